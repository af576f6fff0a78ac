"""Peak finding on simulated recordings: noise, offset, drift, skip, rest tail, errors."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_estimators_signals import F_HZ, exact_turning_points, sampled

from bayestribo.errors import RecordingError
from bayestribo.signal.peaks import Peaks, estimate_noise, estimate_offset, find_peaks

OMEGA = 2 * math.pi * F_HZ


def _truth(zeta, mu, y0, n):
    tn, yn, _ = exact_turning_points(y0, zeta, mu)
    return tn[1 : n + 1] / OMEGA, yn[1 : n + 1]


def test_noise_free_turning_points_are_recovered():
    t, x, _ = sampled(0.02, 0.03, 10.0)
    pk = find_peaks(t, x)
    t_true, y_true = _truth(0.02, 0.03, 10.0, len(pk))
    # the first turning point (the release at t = 0) is on the record's edge: not a peak
    assert len(pk) >= 30
    # value: a parabola over ±θ = ±π/6 (1/12 period) biases a sinusoid's extremum by
    # ~2.7e-4 of its amplitude (peaks._refine); the kink between arcs of curvature
    # |Y| ± μ_k adds (9/256)(2μ_k)²θ²/|Y| ≈ 0.04 μ_k²/|Y| (bound 0.05 μ_k²/|Y|)
    bound = 5e-4 * np.abs(y_true) + 0.05 * 0.03**2 / np.abs(y_true)
    assert np.all(np.abs(pk.value - y_true) <= bound)
    # time: the vertex of the symmetric parabola moves by ~(3/8)(μ_k/|Y|)θ where the
    # two arcs differ, and by 2ζθ²/5 from the ζu³/3 tilt of the damped arcs (θ = π/6
    # the half-window in radians); 1.5x margin, converted to seconds with Ω
    theta = math.pi / 6
    tol = 1.5 * (0.375 * 0.03 / np.abs(y_true) * theta + 0.4 * 0.02 * theta**2) / OMEGA
    assert np.all(np.abs(pk.t - t_true) <= tol)
    assert pk.stop_time is not None
    assert pk.offset == pytest.approx(0.0, abs=1e-4)


def test_half_period_gives_damped_frequency():
    t, x, _ = sampled(0.05, 0.01, 10.0)
    pk = find_peaks(t, x)
    expected = math.pi / (OMEGA * math.sqrt(1 - 0.05**2))
    # weighted slope of peak times: timing bias only at the smallest peaks
    assert pk.half_period == pytest.approx(expected, rel=2e-4)


def test_offset_and_noise_are_estimated():
    sigma = 0.01
    t, x, _ = sampled(0.01, 0.02, 10.0, noise_x=sigma, offset=3.0, seed=1)
    pk = find_peaks(t, x)
    # noise from 4th differences: MAD-based, n ≈ 10⁴ samples -> relative SE ~1.3 %
    assert pk.noise == pytest.approx(sigma, rel=0.06)
    # the offset fit averages ~60 mid-points of noise σ_peak ≈ 1.5e-3: SE ~3e-4
    assert pk.offset + pk.drift * t.mean() == pytest.approx(3.0, abs=2e-3)
    _, y_true = _truth(0.01, 0.02, 10.0, len(pk))
    # each peak value: noise of a parabola over ~11 samples (value_noise) + bias
    err = pk.value - y_true
    assert np.std(err) < 3 * pk.value_noise + 1e-3
    assert abs(np.mean(err)) < 4 * pk.value_noise / math.sqrt(len(pk)) + 2e-3


def test_linear_drift_of_equilibrium_is_removed():
    t, x, _ = sampled(0.005, 0.02, 5.0, noise_x=1e-3, seed=2)
    drift = 0.01  # [unit/s]
    pk = find_peaks(t, x + 0.2 + drift * t)
    assert pk.drift == pytest.approx(drift, abs=5e-4)
    assert pk.offset == pytest.approx(0.2, abs=2e-3)
    const = find_peaks(t, x + 0.2 + drift * t, offset="constant")
    assert const.drift == 0.0


def test_skip_drops_leading_extrema():
    t, x, _ = sampled(0.02, 0.03, 10.0)
    full = find_peaks(t, x)
    skipped = find_peaks(t, x, skip=2)
    assert len(skipped) == len(full) - 2
    np.testing.assert_allclose(skipped.t, full.t[2:], atol=1e-9)
    assert full.skip(2).t[0] == skipped.t[0]


def test_rest_before_release_and_rest_tail():
    t, x, _ = sampled(0.01, 0.05, 4.0, lead=0.5, noise_x=1e-4, seed=3)
    pk = find_peaks(t, x)
    tn, yn, stops = exact_turning_points(4.0, 0.01, 0.05)
    assert stops
    # the release is a turning point on a flat lead-in: the first peak found is the
    # next one; the stop is found within one tenth of a period
    assert pk.t[0] == pytest.approx(0.5 + tn[1] / OMEGA, abs=2e-3)
    assert pk.stop_time == pytest.approx(0.5 + tn[-1] / OMEGA, abs=0.1 / F_HZ)
    assert pk.rest_value == pytest.approx(yn[-1], abs=2e-3)
    assert np.all(pk.t < pk.stop_time)


def test_a_given_period_replaces_the_estimate():
    # the dominant period passed in gives the same peaks as the estimate made inside;
    # a period twice as long is used: extrema of one kind must then be 1.2 true
    # periods apart, and half of them are not found
    from bayestribo.signal.period import dominant_period

    t, x, _ = sampled(0.02, 0.03, 10.0, noise_x=1e-3, seed=4)
    estimated = find_peaks(t, x)
    given_period = find_peaks(t, x, period=dominant_period(t, x))
    np.testing.assert_array_equal(given_period.t, estimated.t)
    np.testing.assert_array_equal(given_period.value, estimated.value)
    longer = find_peaks(t, x, period=2.0 * dominant_period(t, x))
    assert len(longer) < 0.75 * len(estimated)


def test_velocity_peaks_follow_minus_y_prime():
    t, _, v = sampled(0.02, 0.03, 10.0)
    pk = find_peaks(t, v, kind="velocity")
    assert pk.kind == "velocity"
    # velocity peaks of consecutive half-cycles alternate; -Y'_k has the sign of Y_k
    assert np.all(np.diff(np.sign(pk.value)) != 0)
    # the velocity is zero at rest: offset from the rest tail
    assert pk.offset == pytest.approx(0.0, abs=1e-9)


@settings(max_examples=50, deadline=None)
@given(
    c=st.floats(-100, 100),
    r=st.floats(0.3, 0.999),
    b=st.floats(0.0, 0.05),
    p0=st.floats(1.0, 10.0),
)
def test_estimate_offset_exact_on_recurrence(c, r, b, p0):
    # P_{n+1} = -r P_n + b sgn(P_n) (Eq. 20 form) while the signs alternate
    p = [p0]
    for _ in range(11):
        nxt = -r * p[-1] + b * math.copysign(1.0, p[-1])
        if nxt * p[-1] >= 0:
            break
        p.append(nxt)
    if len(p) < 4:
        return
    level, slope = estimate_offset(np.array(p) + c)
    # exact model: the mid-point fit is exact up to rounding of values of size |c|
    assert level == pytest.approx(c, abs=1e-7 * (1 + abs(c)))
    assert slope == 0.0


def test_estimate_noise_of_white_noise():
    rng = np.random.default_rng(5)
    # 2e4 samples: relative standard error of the MAD estimate ~1.1 %, 5 SE margin
    assert estimate_noise(0.3 * rng.standard_normal(20000)) == pytest.approx(0.3, rel=0.06)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"t": np.arange(10.0), "signal": np.zeros(10)}, "at least 16"),
        ({"t": np.arange(20.0), "signal": np.zeros(19)}, "shape of t"),
        ({"t": np.r_[np.arange(10.0), np.arange(10.0)], "signal": np.ones(20)}, "increasing"),
        ({"t": np.arange(20.0), "signal": np.r_[np.ones(19), np.nan]}, "NaN"),
        ({"t": np.arange(20.0), "signal": np.ones(20)}, "constant"),
        ({"t": np.arange(20.0), "signal": np.sin(np.arange(20.0)), "kind": "force"}, "kind"),
        ({"t": np.arange(20.0), "signal": np.sin(np.arange(20.0)), "skip": -1}, "skip"),
        ({"t": np.arange(20.0), "signal": np.sin(np.arange(20.0)), "period": 0.0}, "period"),
        ({"t": np.arange(20.0), "signal": np.sin(np.arange(20.0)), "period": np.nan}, "period"),
        ({"t": np.arange(20.0), "signal": np.sin(np.arange(20.0)), "period": "6"}, "period"),
    ],
)
def test_bad_input_raises_recording_error(kwargs, match):
    with pytest.raises(RecordingError, match=match):
        find_peaks(**kwargs)


def test_too_few_peaks_is_reported():
    t, x, _ = sampled(0.02, 0.03, 10.0)
    with pytest.raises(RecordingError, match="usable extrema"):
        find_peaks(t, x, skip=1000)


def test_peaks_container_checks_shapes():
    with pytest.raises(RecordingError, match="one length"):
        Peaks(t=np.arange(3.0), value=np.arange(4.0))


def test_rest_tail_found_block_by_block_is_the_whole_records():
    # the tail's start from blocks read backwards equals the one from the running
    # extremes of the whole record, on decays into noise, pure noise and flat records
    from bayestribo.signal.peaks import _TAIL_BLOCK, _rest_tail_start

    def whole(s, band, min_len):
        hi = np.maximum.accumulate(s[::-1])[::-1]
        lo = np.minimum.accumulate(s[::-1])[::-1]
        inside = (hi - lo) <= 2.0 * band
        if not inside[-1]:
            return None
        start = int(np.argmax(inside))
        return None if s.size - start < min_len else start

    rng = np.random.default_rng(8)
    found = 0
    for trial in range(300):
        n = int(rng.integers(16, 12 * _TAIL_BLOCK))
        tail = int(rng.integers(0, n + 1))
        decay = 10.0 * np.sin(np.arange(n - tail) / 7.0) * np.exp(-np.arange(n - tail) / 4000.0)
        s = [np.r_[decay, rng.uniform(-1.0, 1.0, tail)], rng.standard_normal(n), np.ones(n)]
        s = s[trial % 3]
        band = float(rng.choice([0.0, 0.5, 1.0, 3.0, np.nan]))
        min_len = int(rng.integers(1, 2 * _TAIL_BLOCK))
        expected = whole(s, band, min_len)
        assert _rest_tail_start(s, band, min_len) == expected
        found += expected is not None
    assert found > 50


def test_swings_of_whole_steps_give_the_equilibrium_without_a_rank_warning():
    # a coarse channel's turning points sit on its levels: every peak-to-peak height is
    # the same whole number of steps, so the decay ratio of the heights is not
    # determined by their straight-line fit (numpy's polyfit warned); the equilibrium is
    # the mid-level all the same
    q = 0.77e-3
    levels = np.array([1, -1, 1, -1, 1, -1, 1, -1.0]) * q + 0.25 * q
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        level, slope = estimate_offset(levels, noise=q / np.sqrt(12.0))
    assert level == pytest.approx(0.25 * q, rel=1e-9) and slope == 0.0
