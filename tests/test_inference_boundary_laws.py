"""Every law of several terms averaged over its boundaries (bayestribo/inference/boundary.py):
the boundaries a law declares through its terms, how several nested laws share the
draws, the nested laws' own averaging, and fits of laws other than the default."""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from bayestribo.inference.boundary import MAX_SHARE, THRESHOLD, _shares, boundary_mixture
from bayestribo.inference.priors import Uniform
from bayestribo.inference.sampling import SamplerRun, SamplerSettings
from bayestribo.inference.types import Sampled
from bayestribo.model.laws import Parameter, Term, get_law
from bayestribo.model.laws.viscous import VISCOUS


@pytest.mark.parametrize(
    "law, boundaries",
    [
        ("viscous+coulomb", {"zeta": "coulomb", "mu_k": "viscous"}),
        ("viscous+quadratic", {"zeta": "quadratic", "c2": "viscous"}),
        ("coulomb+quadratic", {"mu_k": "quadratic", "c2": "coulomb"}),
        (
            "viscous+coulomb+quadratic",
            {"zeta": "coulomb+quadratic", "mu_k": "viscous+quadratic", "c2": "viscous+coulomb"},
        ),
        ("coulomb+power", {"mu_k": "power", "zeta_alpha": "coulomb"}),
        # η's null 0 is inside its prior [-0.45, 0.45]: no boundary of its own
        ("coulomb+hysteretic", {"mu_k": "hysteretic"}),
        ("quadratic+hysteretic", {"c2": "hysteretic"}),
        ("viscous", {}),
        ("quadratic", {}),
    ],
)
def test_a_law_nests_the_law_without_each_term_on_its_amount_bound(
    law: str, boundaries: dict[str, str]
) -> None:
    assert get_law(law).boundaries == boundaries


def test_every_amount_is_a_parameter_whose_lower_bound_removes_the_term() -> None:
    """Each registered term's declared amount on its bound dissipates nothing at any
    amplitude (whatever its other parameters), and nothing else of the term does."""
    from bayestribo.model.laws import TERMS

    amplitudes = np.array([1e-3, 0.1, 1.0, 3.0])
    for term in TERMS.values():
        if term.amount is None:
            continue
        values = {
            p.name: np.array([0.7 * p.null + 0.3 + 0.1 * i]) for i, p in enumerate(term.parameters)
        }
        values[term.amount] = np.array([term.parameters[0].low * 0.0])
        assert np.all(term.dissipation(amplitudes, values, 1.0) == 0.0), term.name
        assert term.absent.startswith("no "), term.name


def test_an_amount_inside_its_prior_is_refused() -> None:
    eta = Parameter("eta_test", "η", "-", -1.0, 1.0, "test", lambda a: {}, null=0.0)
    with pytest.raises(ValueError, match="lower bound"):
        Term(
            name="test_signed",
            kind="friction",
            parameters=(eta,),
            n_coefficients=1,
            force=VISCOUS.force,
            coefficients=VISCOUS.coefficients,
            dissipation=VISCOUS.dissipation,
            physical=VISCOUS.physical,
            description="test",
            amount="eta_test",
        )


@pytest.mark.parametrize(
    "probabilities, expected",
    [
        ({"a": 0.3}, {"a": 0.3}),
        ({"a": 0.9, "b": 0.005}, {"a": MAX_SHARE}),
        ({"a": 0.9, "b": 0.97}, {"a": MAX_SHARE, "b": MAX_SHARE}),  # the default law's rule
        ({"a": 0.9, "b": 0.97, "c": 0.99}, {"a": 1 / 3, "b": 1 / 3, "c": 1 / 3}),
        ({"a": 0.9, "b": 0.2, "c": 0.5}, {"a": 0.5 / 1.2, "b": 0.2 / 1.2, "c": 0.5 / 1.2}),
    ],
)
def test_several_nested_laws_share_the_draws(probabilities, expected) -> None:
    shares = _shares({k: {"probability": p} for k, p in probabilities.items()})
    assert shares == pytest.approx(expected)
    assert sum(shares.values()) <= 1.0 + 1e-12
    assert THRESHOLD == 0.01


@dataclass
class _Posterior:
    """The parts of a posterior the averaging reads."""

    law: object
    names: tuple[str, ...]
    priors: dict = field(default_factory=dict)
    fixed: dict = field(default_factory=dict)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        return np.zeros(len(theta))


#: draws near 0 (a boundary the data allow) and far from it, by parameter
_NEAR = {"zeta": 1e-4, "c2": 1e-3}
_FAR = {"mu_k": 0.01, "mu_s_ratio": 2.0, "eta": 0.0, "c3": 0.01, "y0": 1.0}


def _sampled(law: str, seed: int) -> Sampled:
    """A sample of ``law`` whose amounts in _NEAR pile on their bound (half-normal of
    that scale under a prior of width 0.3) and the others sit far from theirs."""
    the_law = get_law(law)
    names = (*the_law.parameter_names, "y0")
    rng = np.random.default_rng(seed)
    columns = [
        np.abs(rng.normal(0.0, _NEAR[n], 4000))
        if n in _NEAR
        else _FAR[n] + rng.normal(0, 1e-4, 4000)
        for n in names
    ]
    chains = np.stack(columns, axis=-1).reshape(2, 2000, len(names))
    priors = {n: Uniform(0.0, 0.3) for n in names}
    run = SamplerRun(
        chains=chains,
        log_prob=np.zeros((2, 2000)),
        autocorr_time=np.ones(len(names)),
        n_steps=2000,
        burn=0,
        thin=1,
        acceptance_fraction=0.3,
        ess=np.full(len(names), 4000.0),
        rhat=np.ones(len(names)),
        converged=True,
        names=names,
    )
    return Sampled(_Posterior(the_law, names, priors), np.zeros(len(names)), run, SamplerSettings())


def test_a_three_term_law_averages_its_nested_laws_over_their_own_boundaries() -> None:
    """viscous+coulomb+quadratic where ζ and c₂ both pile on 0 and μ_k is clear: the
    laws without ζ and without c₂ each take half the draws; each of them is averaged
    over its own remaining boundary (``coulomb``, fitted once, half of theirs). So ζ = 0
    in 3/4 of the draws, c₂ = 0 in 3/4, both in 1/2, μ_k never 0, none the full law's."""
    calls: list[str] = []

    def fit_nested(law: str) -> Sampled:
        calls.append(law)
        return _sampled(law, len(calls))

    full = _sampled("viscous+coulomb+quadratic", 0)
    mixed, record = boundary_mixture(full, fit_nested, lambda: np.random.default_rng(5))
    assert calls == ["viscous+coulomb", "coulomb", "coulomb+quadratic"]
    assert record["law"] == "viscous+coulomb+quadratic"
    assert record["mixed"] == ["c2", "zeta"] and record["full_share"] == pytest.approx(0.0)
    assert record["parameters"]["mu_k"]["probability"] < THRESHOLD
    assert record["nested"]["c2"]["boundary"]["mixed"] == ["zeta"]
    assert record["nested"]["zeta"]["boundary"]["nested"]["c2"]["law"] == "coulomb"
    draws = mixed.run.chains.reshape(-1, len(full.posterior.names))
    zeta, mu_k, c2 = (draws[:, full.posterior.names.index(n)] for n in ("zeta", "mu_k", "c2"))
    # the nested fits' draws are picked at random from theirs: a hypergeometric
    # spread of 0.006 of all the draws around each fraction
    assert np.mean(zeta == 0) == pytest.approx(0.75, abs=0.025)
    assert np.mean(c2 == 0) == pytest.approx(0.75, abs=0.025)
    assert np.mean((zeta == 0) & (c2 == 0)) == pytest.approx(0.5, abs=0.025)
    assert np.all(mu_k > 0)


@dataclass
class _Counting(_Posterior):
    """A posterior that counts the draws it is evaluated at (its density: their sum)."""

    evaluated: list = field(default_factory=list)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        self.evaluated.append(len(theta))
        return np.sum(theta, axis=1)


def test_the_density_at_the_draws_mixed_in_is_computed_where_it_is_read() -> None:
    """The mixture does not evaluate the full posterior at the nested laws' draws (the
    exact integration of each, for a law without a closed form); ``run.log_prob`` is
    NaN exactly there and the sampler's elsewhere, and ``log_prob_deferred`` fills them
    with the full posterior's density at the mixture's own draws."""
    full = _sampled("viscous+quadratic", 0)
    counting = _Counting(full.posterior.law, full.posterior.names, full.posterior.priors)
    known = np.arange(4000.0).reshape(2, 2000)
    full = dataclasses.replace(
        full, posterior=counting, run=dataclasses.replace(full.run, log_prob=known)
    )
    mixed, record = boundary_mixture(
        full, lambda law: _sampled(law, 7), lambda: np.random.default_rng(5)
    )
    assert record["mixed"] and counting.evaluated == []
    names = full.posterior.names
    flat = mixed.run.chains.reshape(-1, len(names))
    changed = np.any(flat != full.run.chains.reshape(-1, len(names)), axis=1)
    lp = mixed.run.log_prob.reshape(-1)
    np.testing.assert_array_equal(np.isnan(lp), changed)
    np.testing.assert_array_equal(lp[~changed], known.reshape(-1)[~changed])
    filled = mixed.log_prob_deferred().reshape(-1)
    assert counting.evaluated == [int(changed.sum())]
    np.testing.assert_array_equal(filled[changed], flat[changed].sum(axis=1))
    np.testing.assert_array_equal(filled[~changed], known.reshape(-1)[~changed])


def test_a_law_whose_amounts_are_clear_is_left_alone() -> None:
    """Nothing near a bound: no nested fit, the sample itself returned."""
    full = _sampled("coulomb+hysteretic", 0)

    def refuse(law: str) -> Sampled:
        raise AssertionError(f"{law} fitted")

    mixed, record = boundary_mixture(full, refuse, refuse)
    assert mixed is full
    assert record["mixed"] == [] and list(record["parameters"]) == ["mu_k"]


def test_the_law_free_fit_and_one_term_are_not_averaged() -> None:
    for law in ("free", "quadratic"):
        full = _sampled(law, 0)
        assert boundary_mixture(full, None, None) == (full, None)


@pytest.fixture
def _benchmarks_on_path(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parent.parent / "benchmarks"))


def _fit(path: Path, law: str):
    import bayestribo as bt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bt.fit(bt.read_run(path), seed=1, law=law)


@pytest.mark.usefixtures("_benchmarks_on_path")
def test_viscous_quadratic_on_a_linear_oscillator_mixes_the_viscous_law_in(tmp_path) -> None:
    """A linear oscillator (no quadratic drag, benchmarks/boundary_laws.py's mid design)
    fitted with viscous+quadratic: the law without quadratic drag is probable and makes
    half the draws (c₂ = 0 in them), the report says so, and ζ's interval holds the
    truth."""
    from boundary_laws import DESIGNS, record

    truth, path = record("mid", "viscous", 0, tmp_path)
    assert truth["c2"] == 0.0 and DESIGNS["mid"]["snr"] == 500.0
    result = _fit(path, "viscous+quadratic")
    b = result.boundary
    assert "c2" in b["mixed"] and b["nested"]["c2"]["law"] == "viscous"
    assert b["parameters"]["c2"]["probability"] > 0.5
    assert b["parameters"]["zeta"]["probability"] < THRESHOLD
    assert np.mean(result.samples("c2") == 0.0) == pytest.approx(
        b["nested"]["c2"]["share"], abs=1e-3
    )
    lo, hi = result.interval("zeta", 0.99)
    assert lo <= truth["zeta"] <= hi
    assert result.summary()["c2_per_mass"].interval[0] == 0.0
    assert "boundary  no quadratic drag" in result.to_text()


@pytest.mark.validation
@pytest.mark.usefixtures("_benchmarks_on_path")
@pytest.mark.parametrize(
    "kind, law, key",
    [("coulomb", "coulomb+quadratic", "xc"), ("viscous", "viscous+quadratic", "zeta")],
)
def test_intervals_cover_a_truth_without_quadratic_drag(tmp_path, kind, law, key) -> None:
    """20 seeded records of the low design with no quadratic drag: the other term's
    95 % interval holds its truth in at least 17 (P(<= 16 of 20) = 1.6 % at 95 %)."""
    from boundary_laws import QUANTITIES, record

    covered = 0
    for seed in range(20):
        truth, path = record("low", kind, seed, tmp_path)
        lo, hi = _fit(path, law).summary()[QUANTITIES[key]].interval
        covered += lo <= truth[key] <= hi
    assert covered >= 17
