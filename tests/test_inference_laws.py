"""Fits of dissipation laws other than viscous + Coulomb, on independent simulations
(tests/_law_recording.py: solve_ivp with the effect added), and a law defined outside
the package."""

from __future__ import annotations

import json
import math
import re
import warnings

import numpy as np
import pytest
from _law_recording import law_recording, swing_dissipation
from test_model_laws import CUBIC

from bayestribo import fit
from bayestribo.cli import main
from bayestribo.errors import BayestriboError, MisfitWarning
from bayestribo.model.laws import Law, get_law, get_term

OMEGA = 2 * math.pi * 32.6
MASS, LOAD = 0.035, 0.31
ELL = LOAD / (MASS * OMEGA**2)  # length scale N/k [m]
TRUTH = {"zeta": 0.005, "c2": 0.01, "mu_k": 0.02}


@pytest.fixture(scope="module")
def drag_run():
    """Viscous damping, quadratic drag and Coulomb friction (dimensionless γ = c₂ℓ/m)."""
    z, g, mu = TRUTH["zeta"], TRUTH["c2"], TRUTH["mu_k"]
    return law_recording(
        lambda v: 2 * z * OMEGA * v + (g / ELL) * v * abs(v), friction=mu * LOAD / MASS, seed=1
    )


@pytest.fixture(scope="module")
def drag_fit(drag_run):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(drag_run, seed=3, law="viscous+quadratic+coulomb")
    return result, caught


def test_the_law_with_drag_covers_the_truth_and_says_nothing_is_wrong(drag_fit):
    result, caught = drag_fit
    assert result.law == "viscous+coulomb+quadratic"
    assert result.converged
    for name, truth in TRUTH.items():
        lo, hi = result.interval(name, 0.99)
        assert lo < truth < hi, (name, lo, hi)
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    # the physical drag coefficient c₂ = γ m/ℓ [kg/m]
    c2 = result.summary()["c2_SI"]
    assert c2.interval[0] < TRUTH["c2"] * MASS / ELL < c2.interval[1]
    assert result.units()["c2_SI"] == "kg/m"


@pytest.mark.parametrize("unit", ["m", "signal unit"])
def test_the_printed_dissipation_rows_are_aligned(drag_fit, unit, monkeypatch):
    result = drag_fit[0]
    band = dict(result.dissipation, amplitude_unit=unit)  # "signal unit": no length unit
    # swings whose printed digits differ in number, as HarmOsc3's do
    amplitude = list(band["amplitude"])
    amplitude[0], amplitude[len(amplitude) // 2], amplitude[-1] = 0.0928, 0.3847, 1.258
    band["amplitude"] = amplitude
    # and a value at its bound, whose text ("0 (at the bound)") is as wide as the column
    # it is right-aligned in: it ran into the swing ("A = 0.1557 rad0 (at the bound)")
    band["mean"] = [0.0, *list(band["mean"])[1:]]
    band["interval"] = [[0.0, *list(band["interval"][0])[1:]], list(band["interval"][1])]
    monkeypatch.setattr(type(result), "dissipation", property(lambda self: band))
    rows = [line for line in result.to_text().splitlines() if line.startswith("    A = ")]
    assert len(rows) >= 4  # the law's and the turning points', at three swings each
    # every value starts in the same column, whatever the digits of the amplitude
    starts = {line.index("[") for line in rows}
    assert len(starts) == 1
    # two spaces at least between the swing's unit and its value
    assert any("(at the bound)" in line for line in rows)
    assert all(re.match(rf"    A = \S+ {re.escape(unit)}  +\S", line) for line in rows), rows


def test_the_default_law_misfits_the_drag_and_its_dissipation_differs(drag_run, drag_fit):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        default = fit(drag_run, seed=3)
    assert any(issubclass(w.category, MisfitWarning) for w in caught)
    # ΔE(A) from the right law against the truth over the analysed amplitudes [J]
    d = drag_fit[0].dissipation
    assert d["unit"] == "J" and d["law"] == "viscous+coulomb+quadratic"
    z, g, mu = TRUTH["zeta"], TRUTH["c2"], TRUTH["mu_k"]
    truth = swing_dissipation(
        lambda v: 2 * z * OMEGA * v + (g / ELL) * v * abs(v),
        np.asarray(d["amplitude"]),
        friction=mu * LOAD / MASS,
    )
    # within 3.29 posterior sd (99.9 %) at every swing; the swings' errors are
    # nearly one (the band is about 1e-3 wide)
    z = (np.asarray(d["mean"]) - truth) / np.asarray(d["sd"])
    assert np.all(np.abs(z) < 3.29), z
    assert np.asarray(d["amplitude"])[0] < np.asarray(d["amplitude"])[-1]
    assert default.dissipation["law"] == "viscous+coulomb"


def test_the_same_law_by_name_or_object_gives_the_same_default_fit(bundled_run):
    a = fit(bundled_run, seed=5)
    b = fit(bundled_run, seed=5, law=Law((get_term("coulomb"), get_term("viscous"))))
    np.testing.assert_array_equal(a.samples("zeta"), b.samples("zeta"))
    assert a.law == b.law == "viscous+coulomb"
    assert a.dissipation == b.dissipation


def test_a_law_defined_outside_the_package_fits_and_reports(drag_run):
    """A cubic drag term (tests/test_model_laws.py) that is not registered: the fit
    samples its parameter with the term's own default prior and reports ΔE(A)."""
    law = Law((get_term("viscous"), CUBIC, get_term("coulomb")))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MisfitWarning)
        result = fit(drag_run, seed=2, law=law, max_steps=1500)
    assert result.law == "viscous+coulomb+cubic"
    assert "c3" in result.summary()
    assert result.dissipation["by_term"].keys() == {"viscous", "coulomb", "cubic"}


def test_bad_laws_and_priors_are_refused_by_name(bundled_run):
    with pytest.raises(BayestriboError, match="unknown dissipation term 'drag'"):
        fit(bundled_run, law="viscous+drag")
    from bayestribo.inference.priors import Uniform

    with pytest.raises(BayestriboError, match=r"priors: 'c2' is not a parameter of the law"):
        fit(bundled_run, priors={"c2": Uniform(0, 1)})


def test_fit_command_takes_the_law_and_prints_it_with_the_dissipation(bundled_runs, capsys):
    path = str(bundled_runs / "glycerol-N0.31-r1.csv")
    assert main(["fit", path, "--seed", "1", "--json", "--law", "coulomb+viscous"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["law"] == "viscous+coulomb"
    assert record["dissipation"]["unit"] == "J"
    assert len(record["dissipation"]["amplitude"]) == len(record["dissipation"]["mean"])
    with pytest.raises(SystemExit) as exc:
        main(["fit", path, "--law", "viscous+drag"])
    assert exc.value.code == 2
    assert "registered terms: viscous, coulomb" in capsys.readouterr().err


def test_laws_command_lists_every_registered_term(capsys):
    assert main(["laws", "--json"]) == 0
    table = json.loads(capsys.readouterr().out)
    assert [t["term"] for t in table][:5] == [
        "viscous",
        "coulomb",
        "quadratic",
        "power",
        "hysteretic",
    ]


def test_the_comparison_keeps_the_simplest_adequate_law_as_good_as_the_best(drag_run):
    """On the drag recording: the paper's law and viscous damping alone misfit, the law
    with drag is adequate and chosen."""
    from bayestribo.inference import prepare
    from bayestribo.inference.comparison import compare_prepared

    prepared = prepare(drag_run)
    comparison, runs = compare_prepared(
        prepared, ["viscous", "viscous+coulomb", "viscous+coulomb+quadratic"], seed=4
    )
    table = comparison.table
    assert not table["viscous"]["adequate"] and not table["viscous+coulomb"]["adequate"]
    assert table["viscous+coulomb+quadratic"]["adequate"]
    assert comparison.verdict == "viscous+coulomb+quadratic" and comparison.adequate
    assert comparison.as_good == ["viscous+coulomb+quadratic"]
    # the verdict the optima predict is sampled first; the paper's law, clearly behind
    # it at its optimum, is settled there (its estimate), not sampled
    assert comparison.settled == ["viscous+coulomb"]
    assert table["viscous+coulomb"]["settle"]["elpd_diff"] > 1000
    assert "chosen from 3 laws" in comparison.describe()
    assert set(runs) == {law for law, row in table.items() if row.get("sampled")}


def test_a_friction_that_falls_with_amplitude_is_measured():
    """Coulomb friction μ(A) = μ_k + ηA with η < 0 (an independent solve_ivp recording:
    the friction of each half cycle set by the turning point it starts from): the
    law coulomb+hysteretic covers μ_k and η, and the paper's law misfits."""
    mu_k, eta = 0.025, -0.002  # dimensionless: μ(A) 38 % lower at y0 ≈ 4.7
    run = law_recording(
        lambda v: 0.0 * v,
        friction=mu_k * LOAD / MASS,
        friction_slope=eta * OMEGA**2,  # η ℓ k/m per ℓ of amplitude
        seed=5,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=1, law="coulomb+hysteretic")
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    for name, truth in (("mu_k", mu_k), ("eta", eta)):
        lo, hi = result.interval(name, 0.99)
        assert lo < truth < hi, (name, lo, hi)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit(run, seed=1)
    assert any(issubclass(w.category, MisfitWarning) for w in caught)


def test_a_friction_below_zero_at_some_amplitude_is_outside_the_law():
    law = get_law("coulomb+hysteretic")
    pi = law.pi_grid(
        np.linspace(0.0, 20.0, 5),
        {"mu_k": [0.02, 0.02], "mu_s_ratio": [1.5, 1.5], "eta": [-0.002, -0.05]},
        [1.0, 1.0],
    )
    assert np.all(np.isfinite(pi[0])) and np.all(np.isnan(pi[1]))


def test_a_nonlinear_law_is_fitted_in_the_frame_of_its_own_turning_times():
    """Quadratic drag alone (ζ_e about 0.02 at the release, solve_ivp): the record's
    frequency from the decrement is off by about 1e-4; the fit's frequency is the one
    at which the law's turning times keep step with the record's, the drag's own
    change of the half period (about -2.5e-4) is not taken for a stiffness, and ΔE(A)
    covers the truth."""
    q = 23.56  # c₂/m [1/m]
    drag = lambda v: q * v * abs(v)  # noqa: E731
    run = law_recording(drag, x0=2e-3, duration_s=4.0, noise_x=1.5e-6, noise_v=1.5e-7, seed=4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=1, law="quadratic")
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    attrs = result.idata.posterior.attrs
    assert abs(attrs["omega"] / OMEGA - 1) < 1e-7
    trend = json.loads(attrs["frequency_trend_json"])
    assert abs(trend["change"]) < 2e-6
    assert -3e-4 < attrs["law_frequency_change"] < -1.5e-4
    # c₂ is reported in that frame: γ = qℓ with ℓ = N/(mω²), ω = attrs["omega"] (the
    # record's frequency, about 6e-4 off here, would put the truth 30 sd away)
    gamma = result.samples("c2")
    truth_gamma = q * LOAD / (MASS * attrs["omega"] ** 2)
    assert abs(gamma.mean() - truth_gamma) < 3.29 * gamma.std(ddof=1)
    d = result.dissipation
    truth = swing_dissipation(drag, np.asarray(d["amplitude"]))
    z = (np.asarray(d["mean"]) - truth) / np.asarray(d["sd"])
    assert np.all(np.abs(z) < 3.29), z


def test_an_unregistered_friction_law_is_flagged_and_the_turning_points_give_its_dissipation():
    """Friction that weakens with speed (Stribeck, μ_s = 0.03 falling to μ_k = 0.02
    over 0.05 m/s; no registered law has it; solve_ivp): the default fit says it
    misfits, and the ΔE(A) measured from the turning points covers the truth that the
    law's band misses."""
    mu_k, mu_s, v_s = 0.02, 0.03, 0.05
    weakening = (mu_s - mu_k) * LOAD / MASS

    def drag(v: float) -> float:  # the speed-dependent part of the friction, odd in v
        return 2 * 0.005 * OMEGA * v + math.copysign(weakening * math.exp(-abs(v) / v_s), v)

    run = law_recording(drag, friction=mu_k * LOAD / MASS, static_ratio=1.5, x0=2e-3, seed=7)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=1)
    assert [w for w in caught if issubclass(w.category, MisfitWarning)]
    measured = result.turning_point_dissipation
    truth = swing_dissipation(drag, np.asarray(measured["amplitude"]), friction=mu_k * LOAD / MASS)
    lo, hi = (np.asarray(x) for x in measured["interval"])
    assert np.all((lo < truth) & (truth < hi)), (lo / truth - 1, hi / truth - 1)
    law_z = (np.asarray(result.dissipation["mean"]) - truth) / np.asarray(result.dissipation["sd"])
    assert np.max(np.abs(law_z)) > 10


def test_laws_the_decay_cannot_split_give_one_averaged_dissipation():
    """A friction that grows with amplitude (η > 0, no viscous damping; solve_ivp):
    viscous + Coulomb describes the decay as well, and the comparison's ΔE(A), the
    two laws' posteriors mixed, covers the true ΔE(A) of the motion."""
    from bayestribo.inference import prepare
    from bayestribo.inference.comparison import compare_prepared
    from bayestribo.inference.dissipation import (
        averaged_dissipation,
        dissipation_amplitudes,
        physical_scale,
    )

    mu_k, eta = 0.02, 0.004
    run = law_recording(
        lambda v: 0.0 * v,
        friction=mu_k * LOAD / MASS,
        friction_slope=eta * OMEGA**2,
        seed=8,
    )
    prepared = prepare(run)
    # on the half-cycle grid alone (no rivals' rematch on a finer one,
    # tests/test_inference_rivals.py), the two laws are as good as each other
    comparison, runs = compare_prepared(
        prepared, ("viscous+coulomb", "coulomb+hysteretic"), seed=2, rivals=False
    )
    assert set(comparison.as_good) == {"viscous+coulomb", "coulomb+hysteretic"}
    assert comparison.verdict == "viscous+coulomb"  # the order compared breaks the tie
    scale = physical_scale(prepared.decay.scaling, prepared.metadata)
    members = [
        (law, s.posterior, s.run.chains.reshape(-1, s.run.chains.shape[-1]), scale)
        for law, s in runs.items()
    ]
    swings = dissipation_amplitudes(prepared.decay.peaks.value / scale.length_scale)
    band = averaged_dissipation(members, swings * scale.length_scale)
    truth = swing_dissipation(
        lambda v: 0.0 * v,
        np.asarray(band["amplitude"]),
        friction=mu_k * LOAD / MASS,
        friction_slope=eta * OMEGA**2,
    )
    lo, hi = (np.asarray(x) for x in band["interval"])
    assert np.all((lo < truth) & (truth < hi)), (lo / truth - 1, hi / truth - 1)
    assert band["laws"] == list(runs)
    # as fit(law="auto") assembles it: the verdict's final posterior and the others'
    from bayestribo.inference.auto import _averaged_band
    from bayestribo.inference.pipeline import summarise

    verdict = runs[comparison.verdict]
    result = summarise(prepared, verdict, seed=1)
    wired = _averaged_band(prepared, runs, comparison, result.record, (prepared, verdict))
    assert wired["laws"] == comparison.as_good and wired["left_out"] == []
    assert wired["amplitude"] == result.dissipation["amplitude"]
    np.testing.assert_allclose(wired["mean"], band["mean"], rtol=1e-6)
