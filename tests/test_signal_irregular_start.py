"""Records whose first turning points are not the free decay, and periods that change
with the amplitude, against an independent simulator.

The simulator shares nothing with the package: ``scipy.integrate.solve_ivp`` of a
pendulum, θ'' + 2ζω θ' + ω² sin θ = 0, released from rest at 135° or 90° (its period
grows with the amplitude: half as long again at 135° as in small swings), and of a
linear oscillator x'' + 2ζω x' + ω² x = F(t) driven by a sinusoid off its frequency
for its first cycles, then free. The turning times are the solver's events (θ' = 0).
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import RecordingError
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.frequency import turning_point_trend
from bayestribo.signal.motion import (
    SPACING_TOLERANCE,
    IrregularStartWarning,
    regular_turning_points,
)

ZETA = 0.01
REST = 2.0  # [s] held at the release angle before it


@functools.lru_cache(maxsize=8)
def pendulum(theta0_deg: float, f: float, fs: float, cycles: float = 40.0, seed: int = 3):
    """Time [s], angle [°] with 0.05° of white noise, and the true turning times [s]
    (the release included)."""
    w = 2.0 * math.pi * f

    def rhs(_t, u):
        return [u[1], -2.0 * ZETA * w * u[1] - w * w * math.sin(u[0])]

    def turned(_t, u):
        return u[1]

    duration = cycles / f
    sol = solve_ivp(
        rhs,
        (0.0, duration),
        [math.radians(theta0_deg), 0.0],
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        dense_output=True,
        events=turned,
    )
    t = np.arange(round((REST + duration) * fs)) / fs
    theta = np.full(t.size, math.radians(theta0_deg))
    moving = t >= REST
    theta[moving] = sol.sol(t[moving] - REST)[0]
    noise = 0.05 * np.random.default_rng(seed).standard_normal(t.size)
    turns = np.concatenate([[REST], sol.t_events[0][sol.t_events[0] > 0] + REST])
    return t, np.degrees(theta) + noise, turns


@functools.lru_cache(maxsize=8)
def driven(f_drive: float, cycles: float, f: float = 2.0, fs: float = 500.0, seed: int = 5):
    """A linear oscillator at ``f`` [Hz] driven at ``f_drive`` for ``cycles`` of the
    drive from rest, then free for 20 s: time [s], displacement with 1e-3 of white noise
    (swings of about 1), true turning times [s] and the end of the drive [s]."""
    w, wd = 2.0 * math.pi * f, 2.0 * math.pi * f_drive
    t_drive = cycles / f_drive

    def rhs(tt, u, drive):
        force = w * w * math.sin(wd * tt) if drive else 0.0
        return [u[1], -2.0 * ZETA * w * u[1] - w * w * u[0] + force]

    def turned(_t, u, _drive):
        return u[1]

    options = dict(method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True, events=turned)
    first = solve_ivp(rhs, (0.0, t_drive), [0.0, 0.0], args=(True,), **options)
    free = solve_ivp(rhs, (t_drive, 20.0), first.y[:, -1], args=(False,), **options)
    rest = 0.3
    t = np.arange(round((rest + 20.0) * fs)) / fs
    x = np.zeros(t.size)
    tm = t - rest
    on = (tm >= 0.0) & (tm < t_drive)
    off = tm >= t_drive
    x[on] = first.sol(tm[on])[0]
    x[off] = free.sol(tm[off])[0]
    x += 1e-3 * np.random.default_rng(seed).standard_normal(t.size)
    turns = np.concatenate([first.t_events[0], free.t_events[0]]) + rest
    return t, x, turns, t_drive + rest


def analysed(t, x, **kw):
    """The energy decay of a displacement record and the warnings it gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x, None, **kw)
    return decay, [w for w in caught if issubclass(w.category, IrregularStartWarning)]


def true_half_periods(decay, turns):
    """The simulation's half periods between the analysed turning points [s]."""
    tt = decay.turning_times
    k = np.array([int(np.argmin(np.abs(turns - tp))) for tp in tt])
    assert np.all(np.abs(turns[k] - tt) < 0.02 / decay.damped_frequency_Hz)
    assert np.all(np.diff(k) == 1)  # one to one, none missed
    return np.diff(turns[k[0] : k[-1] + 1])


def check_within_the_record(decay, turns):
    """The damped frequency lies between those of the first and the last quarter of
    the analysed half periods (the period changes with the swing: no single one)."""
    half = true_half_periods(decay, turns)
    quarter = max(half.size // 4, 2)
    early, late = 0.5 / half[:quarter].mean(), 0.5 / half[-quarter:].mean()
    lo, hi = min(early, late), max(early, late)
    assert lo < decay.damped_frequency_Hz < hi, (decay.damped_frequency_Hz, early, late)


# ---------------------------------------------------------------------------------------
# A pendulum: the period depends on the amplitude
# ---------------------------------------------------------------------------------------

PENDULUMS = [(0.5, 100.0), (1.6, 1000.0)]


@pytest.mark.parametrize(("f", "fs"), [(0.5, 100.0), (1.0, 200.0)], ids=["0.5Hz", "1Hz"])
def test_pendulum_at_135_degrees_starts_where_the_spacing_is_regular(f, fs):
    # 60 cycles, down to swings of a few degrees: without a skip, the first swing (a
    # half period 1.3 times the run's) is left out and named; before, the record was
    # refused (with the default skip too, which now leaves it out without a word).
    t, x, turns = pendulum(135.0, f, fs, cycles=60.0)
    energy_decay(t, x, None)
    decay, said = analysed(t, x, skip_oscillations=0)
    assert len(said) == 1
    message = str(said[0].message)
    assert "turning points 0 and 1" in message
    left = decay.irregular_turning_points
    assert left >= 1
    # the left-out turning points are named with their times
    first = decay.turning_times[0]
    k0 = int(np.argmin(np.abs(turns - first)))
    for tp in turns[k0 - left : k0]:
        assert f"{tp:.3g}"[:3] in message
    assert f"starts at turning point {left}" in message
    # from the start on the spacing is regular; the interval before it is not
    half = true_half_periods(decay, turns)
    reference = 0.5 / decay.damped_frequency_Hz
    assert np.all(np.abs(half / reference - 1.0) < SPACING_TOLERANCE)
    before = turns[k0] - turns[k0 - 1]
    assert abs(before / reference - 1.0) > SPACING_TOLERANCE - 0.02
    check_within_the_record(decay, turns)


@pytest.mark.parametrize("theta0", [135.0, 90.0])
@pytest.mark.parametrize(("f", "fs"), PENDULUMS, ids=["0.5Hz-100Hz", "1.6Hz-1kHz"])
def test_pendulum_frequency_lies_within_the_record(theta0, f, fs):
    # The 1/|Y_n| term of the turning times (a filter's lag) absorbed the period's
    # change with the swing: the frequency fell below that of the largest swings
    # analysed (1.383 Hz against 1.405 to 1.595 Hz at 135°, 1.6 Hz).
    t, x, turns = pendulum(theta0, f, fs)
    decay, _ = analysed(t, x)
    check_within_the_record(decay, turns)


def test_pendulum_frequency_trend_is_still_seen():
    # The half period changes with the swing: the frequency trend the fit reports
    # (FrequencyTrendWarning, the frequency nuisance) sees it on the analysed turning
    # points, shorter at small swings (negative) and far beyond its error.
    t, x, turns = pendulum(135.0, 1.6, 1000.0)
    decay, _ = analysed(t, x)
    trend = turning_point_trend(decay.turning_times, decay.peaks.value)
    half = true_half_periods(decay, turns)
    assert trend is not None and trend.change < -0.1 and trend.z < -10
    assert half[-1] < 0.85 * half[0]  # the simulation's own change


# ---------------------------------------------------------------------------------------
# A linear oscillator driven for its first cycles
# ---------------------------------------------------------------------------------------

DRIVES = [(1.2, 2.0), (0.8, 3.0), (1.0, 1.5), (4.0, 3.0)]


@pytest.mark.parametrize(("f_drive", "cycles"), DRIVES, ids=[f"{a}Hz-x{b}" for a, b in DRIVES])
def test_driven_start_is_left_out_and_the_frequency_is_the_free_one(f_drive, cycles):
    t, x, turns, drive_end = driven(f_drive, cycles)
    decay, said = analysed(t, x)
    assert len(said) == 1
    message = str(said[0].message)
    left = decay.irregular_turning_points
    assert f"the first {left} turning points (0 to {left - 1}" in message
    # the analysis starts at the first turning point of the free decay
    free = turns[turns > drive_end]
    assert decay.turning_times[0] == pytest.approx(free[0], abs=2e-3)
    assert decay.start_time == pytest.approx(free[0], abs=3e-3)  # the sample nearest
    assert abs(decay.natural_frequency_Hz / 2.0 - 1.0) < 1e-4


def test_a_skip_past_the_driven_start_composes():
    # Skipping more than the irregular start leaves nothing more out and says nothing.
    t, x, turns, drive_end = driven(1.2, 2.0)
    decay, said = analysed(t, x, skip_oscillations=4)
    assert said == [] and decay.irregular_turning_points == 0
    k = int(np.argmin(np.abs(turns - decay.turning_times[0])))
    assert turns[k] > drive_end
    assert abs(decay.natural_frequency_Hz / 2.0 - 1.0) < 1e-4


# ---------------------------------------------------------------------------------------
# The spacing itself: a wiggle inside the decay is still refused
# ---------------------------------------------------------------------------------------


def _times(n: int = 30, half: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    values = 10.0 * 0.97 ** np.arange(n) * (-1.0) ** np.arange(n)
    return half * np.arange(n, dtype=float), values


def test_regular_record_is_left_whole():
    times, values = _times()
    found = regular_turning_points(times, values)
    assert found.start == 0 and found.half_period == pytest.approx(0.5)


def test_irregular_start_moves_the_start_past_it():
    times, values = _times()
    times[:3] = [-1.7, -0.9, -0.2]  # 0.8, 0.7 then 0.2 s: a drive, then the decay
    found = regular_turning_points(times, values)
    assert found.start == 3
    assert list(found.off) == [0, 1, 2]
    assert "turning points 0 and 1 (t = -1.7 s and -0.9 s) are 0.8 s apart" in found.describe()


@pytest.mark.parametrize("where", [12, 25])
def test_wiggle_inside_the_decay_is_refused(where):
    times, values = _times()
    wiggle = np.insert(times, where, times[where] - 0.1)  # an extra turning point
    with pytest.raises(RecordingError, match=r"turning points: .*a wiggle of the noise"):
        regular_turning_points(wiggle, np.insert(values, where, 1.0))
    missed = np.delete(times, where)  # a turning point missed: a whole period
    with pytest.raises(RecordingError, match=r"turning points: .*a turning point missed"):
        regular_turning_points(missed, np.delete(values, where))


def test_too_short_a_regular_run_is_refused_naming_the_spacing():
    t, x, _, _ = driven(1.2, 2.0)
    cut = t < 2.9  # two free oscillations after the drive
    with pytest.raises(RecordingError, match=r"turning points 2 and 3 \(t = 1\.2.*regular only"):
        energy_decay(t[cut], x[cut], None)
