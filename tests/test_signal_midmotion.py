"""Recordings that start in the middle of the motion (no rest before a release).

A record cut out of a longer decay starts in motion, with a smaller oscillation than
the whole record. The first difference of the signal, whose spectrum gave the
record's period, multiplies the spectrum by the frequency: in the second half of the
AppStat2020 HarmOsc3 recording (1.47 Hz at 1 kHz) a 150 Hz mains harmonic then
outweighed the oscillation and the front end refused the record ("found 0 usable
extrema"); in the second half of HarmOsc2 (100 Hz) the noise at Nyquist did.
:func:`bayestribo.signal.period.dominant_period` now takes the spectral peak whose
oscillation is strongest in the signal itself. Reading such a record from a file,
the check of its two channels against each other took their correlation over the
rest as well, where it is noise alone; it is now taken over the motion
(:func:`bayestribo.signal.channels.channel_consistency`). These tests check that such
records are analysed from their first turning points and fitted, on the real
recordings and on an independent simulation, and that a record that is not a free
decay, or whose channels are swapped, is still refused.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from _paths import APPSTAT
from scipy.integrate import solve_ivp

import bayestribo
from bayestribo.errors import MisfitWarning, RecordingError
from bayestribo.io import read_run, write_run
from bayestribo.io.run import Run
from bayestribo.io.validation import validate_run
from bayestribo.signal import energy_decay
from bayestribo.signal.channels import channel_consistency
from bayestribo.signal.period import dominant_period

# ---------------------------------------------------------------------------------------
# The AppStat2020 recordings, cut in two
# ---------------------------------------------------------------------------------------


def _appstat(name: str) -> np.ndarray:
    path = APPSTAT / name
    if not path.is_file():
        pytest.skip(f"the recording {name} not found at {path}")
    return np.loadtxt(path)


def _part(data: np.ndarray, keep: np.ndarray) -> Run:
    """A run of the rows ``keep`` of an AppStat2020 recording (position, unknown unit)."""
    return Run(data[keep, 0], displacement=data[keep, 1], metadata={"length_unit": "arbitrary"})


@pytest.mark.parametrize("cut_s", [3.0, 5.75, 8.0])
def test_harmosc3_second_part_is_analysed_from_its_first_turning_points(cut_s):
    data = _appstat("HarmOsc3.txt")
    whole = energy_decay(data[:, 0], data[:, 1])
    run = _part(data, data[:, 0] >= cut_s)
    decay = energy_decay(run.time, run.displacement)
    # the oscillation's frequency (1.48 Hz, within its change along the decay), not
    # the 150 Hz mains harmonic
    assert decay.natural_frequency_Hz == pytest.approx(whole.natural_frequency_Hz, rel=1e-2)
    # starts in motion: its first turning point stands for the release, the whole
    # record's first after the cut (or the second: 40 ms after the cut at 8 s, the
    # part holds too little before a turning point to resolve it)
    following = whole.peaks.t[whole.peaks.t > cut_s][:2]
    assert np.min(np.abs(following - decay.release_time)) < 2e-3
    # one oscillation (two turning points) skipped, then the same turning points
    np.testing.assert_allclose(decay.peaks.t, whole.peaks.t[-len(decay.peaks) :], atol=3e-3)
    assert decay.start_time > decay.release_time
    # the same stop, and the noise measured on the rest after it
    assert decay.stop_time == pytest.approx(whole.stop_time, abs=2e-3)
    assert decay.noise.source == "rest after stop"


def test_harmosc3_halves_are_fitted():
    data = _appstat("HarmOsc3.txt")
    for keep in (data[:, 0] < 5.75, data[:, 0] >= 5.75):
        with warnings.catch_warnings():
            # dry friction of a weight on a plate is not quite the linear law
            warnings.simplefilter("ignore", MisfitWarning)
            result = bayestribo.fit(_part(data, keep), seed=1)
        assert result.converged
        low, high = result.interval("friction_displacement")
        assert 0.0 < low < high < 0.05  # about 0.02 signal units, as for the whole record


@pytest.mark.parametrize(("name", "cut_s"), [("HarmOsc1.txt", 29.025), ("HarmOsc2.txt", 18.075)])
def test_appstat_halves_are_accepted(name, cut_s):
    data = _appstat(name)
    whole = energy_decay(data[:, 0], data[:, 1])
    halves = []
    for keep in (data[:, 0] < cut_s, data[:, 0] >= cut_s):
        decay = energy_decay(data[keep, 0], data[keep, 1])
        halves.append(decay.natural_frequency_Hz)
        assert len(decay.peaks) >= 40
    # the spring's period changes with the swing (HarmOsc2's halves: 1.4287 and
    # 1.4328 Hz): the whole record's frequency lies between its halves', each within
    # the record's own change of it
    f = whole.natural_frequency_Hz
    assert min(halves) * (1 - 2e-4) <= f <= max(halves) * (1 + 2e-4)
    assert all(abs(h / f - 1) < 3e-3 for h in halves)


# ---------------------------------------------------------------------------------------
# An independent simulation that starts in motion
# ---------------------------------------------------------------------------------------

F_HZ = 32.6
OMEGA = 2.0 * math.pi * F_HZ
ZETA = 0.02
FRICTION = 0.2  # μ_k N/m [m/s²]
MASS_KG = 0.035
LOAD_N = 0.31
MU_K = FRICTION * MASS_KG / LOAD_N
X0 = 1e-3  # [m]
FS = 5_000.0
CUT_S = 0.3


def _free_decay(duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x'' + 2ζΩx' + Ω²x = -(μ_k N/m) sgn(x') from rest at X0, half cycle by half cycle.

    Each half cycle is integrated with a constant friction force against the motion,
    up to the velocity's zero (an event); the mass sticks there when the spring force
    Ω²|x| does not exceed the friction (μ_s = μ_k). Sampled at ``FS`` [Hz] over
    ``duration`` [s]; returns t [s], x [m], v [m/s].
    """
    t = np.arange(round(duration * FS)) / FS
    x = np.empty_like(t)
    v = np.empty_like(t)
    t0, state = 0.0, np.array([X0, 0.0])
    filled = 0
    while filled < t.size:
        if OMEGA**2 * abs(state[0]) <= FRICTION:  # stuck for good
            x[filled:], v[filled:] = state[0], 0.0
            break
        direction = -math.copysign(1.0, state[0])  # moves towards the centre

        def rhs(_, y, s=direction):
            return [y[1], -2.0 * ZETA * OMEGA * y[1] - OMEGA**2 * y[0] - FRICTION * s]

        def turn(_, y):
            return y[1]

        turn.terminal, turn.direction = True, -direction
        span = (t0, t0 + 1.0 / F_HZ)  # the turn comes half a period on: a period bounds it
        inside = t[filled:][t[filled:] < span[1]]
        sol = solve_ivp(
            rhs, span, state, method="DOP853", events=turn, dense_output=True, rtol=1e-11,
            atol=1e-15,
        )  # fmt: skip
        t1 = float(sol.t_events[0][0])
        done = inside[inside <= t1]
        if done.size:
            x[filled : filled + done.size], v[filled : filled + done.size] = sol.sol(done)
        filled += done.size
        t0, state = t1, np.array([sol.y_events[0][0][0], 0.0])
    return t, x, v


@pytest.fixture(scope="module")
def midmotion_run() -> Run:
    t, x, v = _free_decay(1.6)
    keep = t >= CUT_S
    assert abs(v[keep][0]) > 0.03  # the record starts in motion (0.037 m/s)
    assert np.all(v[t > 0.6] == 0.0)  # and holds the stop (0.49 s) and a rest after it
    rng = np.random.default_rng(20260101)
    x = x + 1.5e-6 * rng.standard_normal(t.size)
    v = v + 1.5e-7 * rng.standard_normal(t.size)
    return Run(
        t[keep],
        displacement=x[keep],
        velocity=v[keep],
        metadata={"natural_frequency_Hz": F_HZ, "mass_kg": MASS_KG, "load_N": LOAD_N},
    )


def test_simulation_starting_in_motion_is_analysed(midmotion_run):
    run = midmotion_run
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    assert decay.release_time < CUT_S + 0.5 / F_HZ  # the first turning point
    assert decay.noise.source == "rest after stop"
    assert decay.motion_ended
    assert decay.natural_frequency_Hz == pytest.approx(F_HZ, rel=1e-3)


def test_simulation_starting_in_motion_is_fitted(midmotion_run):
    result = bayestribo.fit(midmotion_run, seed=1)
    assert result.converged
    lo, hi = result.interval("zeta", 0.95)
    assert lo < ZETA < hi
    lo, hi = result.interval("mu_k", 0.95)
    assert lo < MU_K < hi


def test_simulation_starting_in_motion_is_read_from_a_file(midmotion_run, tmp_path):
    # read_run checks the channels against each other: over the whole record, its
    # rest after the stop pulled their correlation to 0.89 (refused as two motions)
    path = tmp_path / "midmotion.csv"
    write_run(midmotion_run, path)
    run = read_run(path)
    consistency = channel_consistency(run)
    assert consistency is not None and consistency.correlation > 0.95
    assert consistency.gain == pytest.approx(1.0, abs=1e-3)


# ---------------------------------------------------------------------------------------
# What is not a free decay is still refused
# ---------------------------------------------------------------------------------------


def test_period_of_a_record_in_motion_is_not_a_line_of_the_noise():
    """The oscillation wins over a mains harmonic that the difference gains 100-fold."""
    rng = np.random.default_rng(3)
    t = np.arange(8_000) / 1_000.0
    x = 0.3 * np.exp(-0.2 * t) * np.cos(2 * math.pi * 1.5 * t) + 0.004 * np.cos(
        2 * math.pi * 150.0 * t
    )
    x += 0.004 * rng.standard_normal(t.size)
    assert 1.0 / dominant_period(t, x) == pytest.approx(1.5, rel=0.02)


def test_a_line_without_a_decay_is_still_refused():
    rng = np.random.default_rng(4)
    t = np.arange(8_000) / 1_000.0
    x = 0.004 * np.cos(2 * math.pi * 150.0 * t) + 0.004 * rng.standard_normal(t.size)
    with pytest.raises(RecordingError, match=r"release: no motion found|turning points: "):
        energy_decay(t, x)
    with pytest.raises(RecordingError, match="release: no motion found"):
        energy_decay(t, 0.004 * rng.standard_normal(t.size))


def test_swapped_channels_starting_in_motion_are_still_refused(midmotion_run):
    run = midmotion_run
    swapped = Run(
        run.time,
        displacement=run.velocity,
        velocity=run.displacement,
        metadata=dict(run.metadata),
    )
    validate_run(run)
    with pytest.raises(RecordingError, match="look swapped"):
        validate_run(swapped)


def test_an_oscillation_that_does_not_decay_is_still_refused():
    rng = np.random.default_rng(5)
    t = np.arange(8_000) / 1_000.0
    x = 0.3 * np.cos(2 * math.pi * 1.5 * t) + 0.004 * np.cos(2 * math.pi * 150.0 * t)
    x += 0.004 * rng.standard_normal(t.size)
    with pytest.raises(RecordingError, match="does not decay"):
        energy_decay(t, x)
