"""A decay that fades into the noise: its last turning points are the noise's.

A velocity-only record (a seismometer's coil, an integrated accelerometer) leaves a
displacement whose noise wanders: once the swings are within its reach, the wiggles of
the noise stand as turning points off the half period. The analysis ends at the last
turning point before them (a ``FadeWarning`` names it), instead of refusing the record;
an interval off the half period where the swings stand far above the noise is still
refused.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo.errors import FadeWarning, RecordingError
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.motion import regular_turning_points

HALF = 0.25


def _turning_points(tail: list[float], tail_values: float) -> tuple[np.ndarray, np.ndarray]:
    """Twelve turning points half a period apart, swings 1 to 0.05, then ``tail``."""
    times = np.r_[HALF * np.arange(12), HALF * 11 + np.cumsum(tail)]
    values = np.r_[np.geomspace(1.0, 0.05, 12), np.full(len(tail), tail_values)]
    return times, values


def test_turning_points_in_the_noises_reach_that_break_the_spacing_are_left_out():
    times, values = _turning_points([0.12, 0.31, 0.19], 0.01)
    with pytest.raises(RecordingError, match="half a period"):
        regular_turning_points(times, values)
    found = regular_turning_points(times, values, fade_level=0.02)
    assert found.faded == 12 and found.start == 0
    assert found.half_period == pytest.approx(HALF)
    # the spacing kept: the swings within the noise's reach stay where they are regular
    regular = regular_turning_points(*_turning_points([HALF, HALF], 0.01), fade_level=0.02)
    assert regular.faded is None and regular.times.size == 14


def test_an_interval_off_among_swings_above_the_noise_is_still_refused():
    times, values = _turning_points([0.12, 0.31, 0.19], 0.01)
    values = np.r_[values[:12], np.full(3, 0.04)]
    with pytest.raises(RecordingError, match="half a period"):
        regular_turning_points(times, values, fade_level=0.02)


def test_a_velocity_record_that_fades_into_its_noise_is_analysed_to_the_fade():
    # independent: the viscous decay in closed form, its velocity by central
    # differences, white noise on the velocity; its integral wanders (a random walk)
    f, zeta, fs = 2.5, 0.01, 200.0
    omega = 2 * np.pi * f
    t = np.arange(0.0, 60.0, 1 / fs)
    x = 0.01 * np.exp(-zeta * omega * t) * np.cos(omega * np.sqrt(1 - zeta**2) * t)
    rng = np.random.default_rng(0)
    v = np.gradient(x, t) + rng.normal(0.0, 2e-4, t.size)
    time = np.r_[np.arange(-2.0, 0.0, 1 / fs), t]
    velocity = np.r_[rng.normal(0.0, 2e-4, int(2 * fs)), v]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(time, None, velocity)
    said = [w for w in caught if issubclass(w.category, FadeWarning)]
    assert len(said) == 1 and "fades into the noise after turning point" in str(said[0].message)
    # to where the swing is still a few times the wander, in motion at its end
    assert not decay.motion_ended
    swing_at_end = 0.01 * np.exp(-zeta * omega * decay.end_time)
    assert 20 < decay.end_time < 45 and swing_at_end > 1e-5
