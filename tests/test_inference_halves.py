"""The chosen law fitted to each half of the motion (bayestribo.inference.halves).

The recordings come from the independent solve_ivp simulator of ``tests/_law_recording.py``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo.errors import MisfitWarning
from bayestribo.inference import halves as halves_module
from bayestribo.inference.auto import _check_halves
from bayestribo.inference.comparison import LawComparison
from bayestribo.inference.halves import HALVES_P, N_DRAWS, N_FIRST_DRAWS, LawHalves, law_halves
from bayestribo.inference.pipeline import prepare
from bayestribo.inference.sampling import SamplerSettings

OMEGA = 2 * math.pi * 32.6
FRICTION = 0.02 * 0.31 / 0.035  # μ_k N/m [m/s²]


def _viscous(zeta: float):
    return lambda v: 2.0 * zeta * OMEGA * v


def _prepared(seed: int = 0, **kw):
    run = law_recording(
        _viscous(0.005), friction=FRICTION, x0=1e-3, duration_s=2.5, seed=seed, **kw
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare(run)


@pytest.fixture(scope="module")
def constant():
    return _prepared(seed=3)


@pytest.fixture(scope="module")
def changing():
    # the friction rises by 30 % a third of the way through the motion
    return _prepared(seed=4, friction_change=(0.25, 1.3 * FRICTION))


@pytest.fixture(scope="module")
def held(constant):
    return law_halves(constant, "viscous+coulomb", seed=1)


def test_a_law_that_holds_gives_halves_that_agree(held):
    h = held
    assert h.tested and h.agree, h.describe()
    assert h.p_value >= HALVES_P
    assert h.n_swings == len(h.amplitude) >= 4
    # each half's own motion lies on its side of the cut
    assert h.first["range"][0] >= h.second["range"][1] * (1 - 1e-9)
    assert h.unit == "m^2"
    # the result's JSON gives the same check back (the fit's text prints it)
    assert LawHalves(**h.to_dict()) == h


def test_a_friction_that_changes_during_the_run_splits_the_halves(changing):
    h = law_halves(changing, "viscous+coulomb", seed=1)
    assert h.tested and not h.agree, h.describe()
    assert h.p_value < HALVES_P and abs(h.largest_z) > 3.84
    a, z = h.most_apart()
    assert a in h.amplitude and abs(z) == pytest.approx(h.largest_z)
    assert "disagree" in h.describe()
    # so far beyond the threshold that the first draws settle it
    assert 2 <= h.first["draws"] <= N_FIRST_DRAWS and 2 <= h.second["draws"] <= N_FIRST_DRAWS


def test_a_verdict_the_first_draws_leave_open_takes_all_of_them(constant, held, monkeypatch):
    monkeypatch.setattr(halves_module, "verdict_is_clear", lambda difference, p: False)
    h = law_halves(constant, "viscous+coulomb", seed=1)
    assert held.first["draws"] <= N_FIRST_DRAWS < h.first["draws"] <= N_DRAWS
    assert N_FIRST_DRAWS < h.second["draws"] <= N_DRAWS
    # the same fits (the same seed), more draws of each: the same verdict, and z
    # within a few of the first draws' Monte Carlo sds (of z, at most ~0.1 here)
    assert h.agree == held.agree and h.amplitude == held.amplitude
    assert abs(h.largest_z - held.largest_z) < 0.5


def test_the_verdict_does_not_depend_on_the_seed(changing, constant):
    assert not any(law_halves(changing, "viscous+coulomb", seed=s).agree for s in (2, 3))
    assert all(law_halves(constant, "viscous+coulomb", seed=s).agree for s in (2, 3))


def test_a_run_too_short_to_split_is_not_tested():
    run = law_recording(_viscous(0.005), friction=4 * FRICTION, x0=3e-4, duration_s=1.0, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(run)
    h = law_halves(prepared, "viscous+coulomb", seed=1)
    assert not h.tested and h.agree
    assert "turning points" in h.note and "halves not compared" in h.describe()
    assert h.to_dict()["p_value"] is None


def _comparison(adequate: bool = True) -> LawComparison:
    return LawComparison(
        "run", {}, "viscous+coulomb", "viscous+coulomb", ["viscous+coulomb"], [], adequate
    )


def test_halves_that_disagree_make_the_comparison_inadequate_and_say_so(changing):
    rng = np.random.default_rng(0)
    with pytest.warns(MisfitWarning, match="not both halves of it alike") as caught:
        checked = _check_halves(_comparison(), changing, rng, SamplerSettings(), "exact", False)
    assert not checked.adequate and checked.halves["agree"] is False
    text = checked.describe()
    assert "law-free" in text and "sd apart" in text
    assert "ΔE/k" in str(caught[0].message)
    assert checked.to_dict()["halves"] == checked.halves


def test_halves_that_agree_leave_the_comparison_adequate(constant):
    rng = np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        checked = _check_halves(_comparison(), constant, rng, SamplerSettings(), "exact", False)
    assert checked.adequate and checked.halves["tested"] and checked.halves["agree"]


def test_an_inadequate_comparison_is_not_checked_again(changing):
    rng = np.random.default_rng(0)
    before = _comparison(adequate=False)
    assert _check_halves(before, changing, rng, SamplerSettings(), "exact", False) is before


def test_halves_not_compared_say_why():
    h = LawHalves("viscous", False, note="the second half was not fitted: too short")
    assert h.describe() == "halves not compared: the second half was not fitted: too short"
    assert math.isnan(h.most_apart()[0])


def test_a_part_is_prepared_as_the_whole_was(constant):
    from bayestribo.errors import BayestriboError
    from bayestribo.inference.pipeline import prepare_part

    n = constant.run.time.size
    part = prepare_part(constant, n // 3, n)
    assert part.noise is constant.noise and part.noise_given
    assert part.run.time[0] == constant.run.time[n // 3] and part.run.time.size == n - n // 3
    assert part.decay.peaks.value.size < constant.decay.peaks.value.size
    assert part.data.increments.size > 4
    for start, stop in ((5, 5), (-1, 10), (0, n + 1)):
        with pytest.raises(BayestriboError, match="start, stop"):
            prepare_part(constant, start, stop)


def test_a_second_half_that_fades_into_the_noise_is_still_compared():
    # a viscous decay of 4 s at 20x the vibrometer's resolution: the second half of the
    # motion, read as a recording of its own, has channels that correlate below the
    # reading check's 0.9 (it would be refused); as a part of the whole it is compared
    from bayestribo.io.run import Run
    from bayestribo.signal.channels import channel_consistency

    run = law_recording(
        _viscous(0.01), load_N=None, x0=1.5e-3, duration_s=4.0, noise_x=3e-6, seed=2
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(run)
    times = prepared.decay.turning_times
    k = int(np.argmin(np.abs(run.time - times[times.size // 2])))
    stop = int(np.searchsorted(run.time, times[-1] + 1 / 32.6))
    alone = Run(
        run.time[k:stop], displacement=run.displacement[k:stop], velocity=run.velocity[k:stop]
    )
    assert channel_consistency(alone).correlation < 0.9
    h = law_halves(prepared, "viscous", seed=1)
    assert h.tested and h.agree, h.describe()


def test_a_half_whose_weights_do_not_hold_is_sampled_as_a_fit_alone(constant, held, monkeypatch):
    # each half's fit returned as a surrogate's run left for the halves to weight
    # (check failed, surrogate posterior given), whose weights never hold: each half is
    # fitted again without weighting, with its own seed, and the check is the one
    # the plain fits give
    import dataclasses

    from bayestribo.inference.surrogate import SurrogateCheck

    calls = []
    plain = halves_module.sample_law

    def sample_law(*args, weighted=0, **kwargs):
        calls.append(weighted)
        prepared, sampled = plain(*args, weighted=weighted, **kwargs)
        if weighted:
            failed = SurrogateCheck(128, 0.2, 0.2, 2)
            sampled = dataclasses.replace(
                sampled, surrogate=failed, surrogate_posterior=sampled.posterior
            )
        return prepared, sampled

    monkeypatch.setattr(halves_module, "sample_law", sample_law)
    monkeypatch.setattr(halves_module, "weights_at", lambda *args: None)
    h = law_halves(constant, "viscous+coulomb", seed=1)
    assert calls == [N_FIRST_DRAWS, N_FIRST_DRAWS, 0, 0]
    assert h == held


def test_a_half_weighted_by_the_sampler_is_not_weighted_again(monkeypatch):
    # the weights the sampler computed at the draws the halves use (check failed, run
    # kept for its weighted draws) are taken as they are: the exact posterior is not
    # evaluated there again; for another number of draws it is
    import types

    from bayestribo.inference.correction import evenly_spaced
    from bayestribo.inference.surrogate import SurrogateCheck

    rng = np.random.default_rng(2)
    chains = rng.normal(size=(2, 150, 2))
    run = types.SimpleNamespace(chains=chains)
    posterior = types.SimpleNamespace(
        law=None,
        law_draws=lambda rows: {"a": rows[:, 0]},
        likelihood=types.SimpleNamespace(reference_amplitude=1.0),
    )
    given = rng.uniform(0.5, 1.0, evenly_spaced(run, 200).size)
    check = SurrogateCheck(128, 0.4, 0.4, 1, weights=given)
    sampled = types.SimpleNamespace(
        run=run, posterior=posterior, surrogate=check, surrogate_posterior=posterior
    )
    prepared = types.SimpleNamespace(
        decay=types.SimpleNamespace(scaling=types.SimpleNamespace(length_scale=2.0))
    )
    asked = []

    def weights_at(run, posterior, picks, max_cv):
        asked.append(picks.size)
        return np.ones(picks.size)

    monkeypatch.setattr(halves_module, "weights_at", weights_at)
    monkeypatch.setattr(
        halves_module, "_swing_dissipation", lambda law, a, values, ref: values["a"][:, None] + a
    )
    amplitude = np.array([1.0, 2.0])
    d, w = halves_module._draws(sampled, prepared, amplitude, 200)
    assert w is given and asked == []
    assert d.shape == (200, 2)
    _, w = halves_module._draws(sampled, prepared, amplitude, 100)
    assert asked == [100] and np.all(w == 1.0)


def test_a_half_whose_weights_still_do_not_hold_is_fitted_again_once_and_named(
    constant, monkeypatch
):
    # the first half's plain fit still returns a surrogate's run whose weights do not
    # hold (a run on a ridge the half does not identify): fitting it again with the
    # same seed gives the same draws, so it is fitted once more at most, and the note
    # says which half and why, not that no swing was left to compare
    import dataclasses

    from bayestribo.inference.surrogate import SurrogateCheck

    calls = []
    plain = halves_module.sample_law

    def sample_law(part, *args, weighted=0, **kwargs):
        first = part.run.time[0] == constant.run.time[0]
        calls.append((first, weighted))
        prepared, sampled = plain(part, *args, weighted=weighted, **kwargs)
        if first:
            failed = SurrogateCheck(128, 0.9, 0.9, 2)
            sampled = dataclasses.replace(
                sampled, surrogate=failed, surrogate_posterior=sampled.posterior
            )
        return prepared, sampled

    monkeypatch.setattr(halves_module, "sample_law", sample_law)
    monkeypatch.setattr(halves_module, "weights_at", lambda *args: None)
    h = law_halves(constant, "viscous+coulomb", seed=1)
    assert calls == [(True, N_FIRST_DRAWS), (False, N_FIRST_DRAWS), (True, 0)]
    assert not h.tested
    assert "first half's draws are not compared" in h.note and "weights" in h.note
    assert "no swing" not in h.note


def test_a_half_stopped_on_a_ridge_ends_the_check_before_the_other_half(constant, monkeypatch):
    # the first half's run stopped on a ridge that half does not identify: its draws
    # measure no ΔE(A) to compare; the second half is not fitted, and the note gives
    # the run's reasons
    import dataclasses

    calls = []
    plain = halves_module.sample_law

    def sample_law(*args, weighted=0, **kwargs):
        calls.append(weighted)
        prepared, sampled = plain(*args, weighted=weighted, **kwargs)
        run = dataclasses.replace(
            sampled.run,
            ridge=True,
            converged=False,
            reasons=[
                "stopped at 900 steps: (why)",
                "μ_k (mu_k) reaches 0 (...), so this record does not identify μ_s/μ_k and "
                "the walkers cross a ridge, not a mode; the coulomb term can be left out: "
                "fit law='viscous' (--law viscous)",
            ],
        )
        return prepared, dataclasses.replace(sampled, run=run)

    monkeypatch.setattr(halves_module, "sample_law", sample_law)
    h = law_halves(constant, "viscous+coulomb", seed=1)
    assert calls == [N_FIRST_DRAWS]
    assert not h.tested
    assert h.note.startswith("the first half's fit stopped on a ridge")
    assert "stopped at 900 steps: (why)" in h.note
    # the half's advice to leave a term out is not the whole record's: not repeated
    assert h.note.endswith("the walkers cross a ridge, not a mode)")
    assert "left out" not in h.note and "--law" not in h.note
    assert "the half does not identify μ_s/μ_k" in h.note and "this record" not in h.note
