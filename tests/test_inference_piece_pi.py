"""Every piece of μ_s/μ_k from one integration of the longest motion
(inference/piece_pi.py), against each piece integrated directly: on a record whose
motion ends inside it and on one that ends in the motion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo.inference import pipeline, surrogate
from bayestribo.inference.piece_pi import piece_rows, stop_times
from bayestribo.inference.start import maximum_a_posteriori

OMEGA = 2 * math.pi * 32.6
ELL = 0.31 / (0.035 * OMEGA**2)


def _drag_run(duration_s):
    return law_recording(
        lambda v: 2 * 0.01 * OMEGA * v + (0.004 / ELL) * v * abs(v),
        x0=1.5e-3,
        duration_s=duration_s,
        sample_rate_Hz=2000.0,
        seed=4,
    )


def _pieces_both_ways(posterior, theta, cov, n, seed):
    """Each piece's Π at ``n`` points about ``theta`` (ratios 1 to 10), from the
    longest motion and integrated directly; and Π(0)."""
    ratio = "mu_s_ratio"
    names = tuple(x for x in posterior.names if x != ratio)
    index = [posterior.names.index(x) for x in names]
    rng = np.random.default_rng(seed)
    rows = rng.multivariate_normal(theta, cov, size=n)
    rows[0] = theta
    values = posterior.law_draws(rows)
    y0 = posterior.values(rows)["y0"]
    points = np.column_stack([values[x] if x in values else y0 for x in names])
    assert np.allclose(points[0], theta[index]) or "y0" in names
    fixed = {k: float(v[0]) for k, v in values.items() if k not in names}
    if "y0" not in names:
        fixed["y0"] = float(y0[0])
    lik = posterior.likelihood
    turning = [
        surrogate.turning_stops(lik, {**fixed, **dict(zip(names, p, strict=True))}) for p in points
    ]
    piece_ratios = [rng.uniform(1.0, 10.0, size=n) for _ in range(4)]
    shared = surrogate._pieces_from_longest(lik, names, ratio, points, piece_ratios, fixed, turning)
    direct = [
        surrogate._evaluate(lik, (*names, ratio), np.column_stack([points, r]), fixed)
        for r in piece_ratios
    ]
    return shared, direct, float(np.nanmax(np.abs(direct[0])))


@pytest.mark.parametrize(
    ("duration_s", "law"), [(3.0, "coulomb+power"), (1.5, "viscous+coulomb+quadratic")]
)
def test_each_piece_from_the_longest_motion_is_the_piece_integrated(duration_s, law):
    prepared = pipeline.prepare(_drag_run(duration_s), seed=1)
    posterior = pipeline.build_posterior(prepared.data, law=law)
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    shared, direct, scale = _pieces_both_ways(posterior, theta, cov, 40, 3)
    assert shared is not None
    sticks = 0
    for mine, theirs in zip(shared, direct, strict=True):
        moved = np.isfinite(theirs).all(axis=1)  # a row outside the law's domain: NaN
        assert moved.sum() >= 10
        # the same rows NaN, the others within 1e-9 of Π(0)
        np.testing.assert_allclose(mine, theirs, rtol=0.0, atol=1e-9 * scale)
        sticks += int(np.sum(theirs[moved, -1] == 0.0))
    # the ratios cut the motion at different turning points, some inside the record
    assert sticks > 0 or not prepared.data.motion_ended


def test_a_stop_time_is_the_first_turning_point_the_ratio_reaches():
    times = [np.array([0.0, 3.0, 6.0, 9.0])]
    stops = [np.array([9.0, 5.0, 2.0, 0.5])]
    assert stop_times(times, stops, np.array([10.0]))[0] == 0.0
    assert stop_times(times, stops, np.array([4.0]))[0] == 6.0
    assert stop_times(times, stops, np.array([0.1]))[0] == math.inf
    # Π cut at the stop: C(T) - C(τ) before it, 0 at and after it
    at = np.array([0.0, 1.0, 2.0, 6.0, 7.0])
    longest = np.array([[10.0, 8.0, 6.0, 2.0, 1.0]])
    grid = np.array([0.0, 1.0, 2.0, 7.0])
    np.testing.assert_array_equal(
        piece_rows(longest, at, grid, np.array([6.0])), [[8.0, 6.0, 4.0, 0.0]]
    )
    np.testing.assert_array_equal(
        piece_rows(longest, at, grid, np.array([math.inf])), [[10.0, 8.0, 6.0, 1.0]]
    )


def test_pieces_that_disagree_with_the_direct_integration_are_integrated(monkeypatch):
    prepared = pipeline.prepare(_drag_run(3.0), seed=1)
    posterior = pipeline.build_posterior(prepared.data, law="coulomb+power")
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    cut = surrogate.piece_rows

    def off(longest, at, grid, stops):  # 1e-8 of Π(0) off: beyond the tolerance
        pi = cut(longest, at, grid, stops)
        return pi + 1e-8 * np.max(np.abs(pi))

    monkeypatch.setattr(surrogate, "piece_rows", off)
    shared, _, _ = _pieces_both_ways(posterior, theta, cov, 5, 1)
    assert shared is None
