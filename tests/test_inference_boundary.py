"""The default law's boundaries (bayestribo/inference/boundary.py): the density at a
bound, the nested law's probability, and the mixture a fit reports."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo.inference.boundary import (
    MAX_SHARE,
    THRESHOLD,
    boundary_density,
    describe,
    nested_probability,
)

#: distributions on [0, ∞) and their density at 0
KNOWN = {
    "half-normal": (lambda rng, n: np.abs(rng.normal(0.0, 2.0, n)), math.sqrt(2 / math.pi) / 2),
    "exponential": (lambda rng, n: rng.exponential(0.5, n), 2.0),
    "uniform": (lambda rng, n: rng.uniform(0.0, 3.0, n), 1 / 3),
    "shifted": (lambda rng, n: 1e-3 + rng.exponential(1e-3, n), 0.0),
}


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_the_density_at_the_bound_is_its_known_value(name: str) -> None:
    """Over 60 seeded samples of 3000 draws, the estimate's mean is the density at the
    bound within 3 standard errors of that mean, and its reported se is its spread."""
    draw, true = KNOWN[name]
    rng = np.random.default_rng(7)
    estimates = [boundary_density(draw(rng, 3000)) for _ in range(60)]
    values = np.array([e.density for e in estimates])
    spread = values.std(ddof=1)
    if true == 0.0:  # no draw near the bound: nothing there
        assert np.all(values == 0.0)
        return
    assert abs(values.mean() - true) < 3 * spread / math.sqrt(values.size)
    reported = np.mean([e.se for e in estimates])
    assert 0.7 < reported / spread < 1.4


def test_the_density_is_scale_free() -> None:
    x = np.random.default_rng(3).exponential(1.0, 2000)
    one, small = boundary_density(x), boundary_density(1e-6 * x)
    assert small.density == pytest.approx(1e6 * one.density, rel=1e-9)
    shifted = boundary_density(5.0 + x, low=5.0)
    assert shifted.density == pytest.approx(one.density, rel=1e-9)


def test_draws_below_the_bound_or_too_few_are_refused() -> None:
    with pytest.raises(ValueError, match="at or above"):
        boundary_density(np.array([-1.0] + [1.0] * 20))
    with pytest.raises(ValueError, match="at least 10"):
        boundary_density(np.ones(5))


def test_the_nested_probability_is_the_savage_dickey_ratio() -> None:
    """Half-normal draws of sd s have density √(2/π)/s at 0: over a prior density p
    there, B₀₁ = √(2/π)/(s p) and the probability B₀₁/(1 + B₀₁)."""
    s = 0.01
    x = np.abs(np.random.default_rng(11).normal(0.0, s, 20_000))
    p = 1 / 0.3  # the default ζ prior, uniform on [0, 0.3]
    out = nested_probability(x, p)
    ratio = math.sqrt(2 / math.pi) / s / p
    assert out["density_ratio"] == pytest.approx(
        ratio, rel=4 * out["se"] / out["posterior_density"]
    )
    assert out["probability"] == pytest.approx(out["density_ratio"] / (1 + out["density_ratio"]))
    # draws far from the bound: the nested law is ruled out
    far = nested_probability(0.5 + 0.01 * np.random.default_rng(1).normal(size=4000), p)
    assert far["probability"] == 0.0


def test_nothing_is_described_where_nothing_was_mixed() -> None:
    assert describe(None) is None
    assert describe({"mixed": []}) is None
    text = describe(
        {
            "mixed": ["zeta"],
            "nested": {"zeta": {"law": "coulomb", "share": 0.5, "converged": True}},
            "parameters": {"zeta": {"probability": 0.97}},
        }
    )
    assert "no viscous damping" in text and "0.97" in text and "coulomb" in text
    assert 0 < THRESHOLD < MAX_SHARE <= 0.5


def _record(tmp_path, share: float, seed: int, design: str = "mid"):
    """A displacement record in metres without load or mass, simulated in closed form
    by benchmarks/boundary_truth.py (its design, ``share`` of the loss to friction)."""
    from boundary_truth import record

    import bayestribo as bt

    truth, path = record(design, share, seed, tmp_path)
    return truth, bt.read_run(path)


@pytest.fixture(autouse=True)
def _benchmarks_on_path(monkeypatch: pytest.MonkeyPatch) -> None:
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parent.parent / "benchmarks"))


def _fit(run):
    import bayestribo as bt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bt.fit(run, seed=1)


def test_a_linear_oscillator_reports_the_viscous_law_mixed_in(tmp_path) -> None:
    """No friction at all: the nested law is probable, half the draws are the viscous
    law's (x_c = 0 in them), the record and the report say so, and ζ's interval holds
    the truth."""
    (zeta, _), run = _record(tmp_path, 0.0, 0)
    result = _fit(run)
    b = result.boundary
    assert b["mixed"] == ["mu_k"] and b["nested"]["mu_k"]["law"] == "viscous"
    assert b["parameters"]["mu_k"]["probability"] > 0.9
    assert b["parameters"]["zeta"]["probability"] < THRESHOLD
    assert b["nested"]["mu_k"]["share"] == MAX_SHARE == b["full_share"]
    assert np.mean(result.samples("friction_displacement") == 0.0) == pytest.approx(
        MAX_SHARE, abs=1e-3
    )
    # one record: its 99 % interval holds the truth (the full law's alone ends below it)
    lo, hi = result.interval("zeta", 0.99)
    assert lo <= zeta <= hi
    assert "boundary  no friction" in result.to_text()
    assert result.to_dict()["boundary"]["mixed"] == ["mu_k"]
    # the log density of every draw, those mixed in included, computed when read
    assert np.all(np.isfinite(result.idata.sample_stats["lp"].values))


def test_a_record_that_cannot_tell_the_two_apart_mixes_both(tmp_path) -> None:
    """20 % of the amplitude lost at an SNR of 50, no friction: both nested laws are
    probable, each makes half the draws (none the full law's), and the intervals
    hold the truth on either boundary (ζ from 0, x_c from 0)."""
    (zeta, _), run = _record(tmp_path, 0.0, 0, "low")
    result = _fit(run)
    b = result.boundary
    assert b["mixed"] == ["mu_k", "zeta"]
    assert b["nested"]["zeta"]["law"] == "coulomb"
    assert b["full_share"] == pytest.approx(0.0)
    assert np.mean(result.samples("zeta") == 0.0) == pytest.approx(MAX_SHARE, abs=1e-3)
    summary = result.summary()
    assert summary["zeta"].interval[0] == 0.0 and summary["zeta"].interval[1] > zeta
    assert summary["friction_displacement"].interval[0] == 0.0


def test_clear_friction_leaves_the_bundled_run_alone(bundled_run) -> None:
    """The bundled glycerol run at 0.31 N: both nested laws ruled out, nothing mixed."""
    b = _fit(bundled_run).boundary
    assert b["mixed"] == [] and b["full_share"] == 1.0
    assert all(p["probability"] == 0.0 for p in b["parameters"].values())


def test_clear_friction_leaves_the_fit_alone(tmp_path) -> None:
    """Half the loss to friction: the nested laws are ruled out, nothing is mixed in
    (the draws are the full law's: none at x_c = 0)."""
    _, run = _record(tmp_path, 0.5, 0)
    result = _fit(run)
    b = result.boundary
    assert b["mixed"] == [] and b["full_share"] == 1.0
    assert all(p["probability"] < THRESHOLD for p in b["parameters"].values())
    assert np.all(result.samples("friction_displacement") > 0.0)
    assert not any(line.startswith("boundary") for line in result.to_text().splitlines())


@pytest.mark.validation
@pytest.mark.parametrize("share, name", [(0.0, "zeta"), (1.0, "friction_displacement")])
def test_intervals_cover_a_truth_on_the_boundary(tmp_path, share: float, name: str) -> None:
    """20 seeded records of the low design (20 % of the amplitude lost, SNR 50, 20
    samples a period) on each boundary: the other parameter's 95 % interval holds its
    truth in at least 17 (P(≤ 16 of 20) = 1.6 % at 95 %); before, the viscous
    oscillator's ζ was covered in 3 of 12 probe runs."""
    covered = 0
    for seed in range(20):
        (zeta, xc), run = _record(tmp_path, share, seed, "low")
        lo, hi = _fit(run).summary()[name].interval
        covered += lo <= (zeta if name == "zeta" else xc) <= hi
    assert covered >= 17


def test_a_run_without_contact_has_no_boundary_to_average(bundled_runs) -> None:
    """A bundled air run (load 0): friction is dropped, the law is viscous alone."""
    import bayestribo as bt

    result = _fit(bt.read_run(bundled_runs / "air-r1.csv"))
    assert result.boundary is None
    assert not any(line.startswith("boundary") for line in result.to_text().splitlines())
