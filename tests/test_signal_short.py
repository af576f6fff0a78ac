"""Short free decays (signal/short.py): two or three oscillations answered, not refused.

The records are independent simulations (scipy's solve_ivp half cycle by half cycle,
nothing from the package) of the paper's rig: m = 0.035 kg, f = 32.6 Hz, N = 0.31 N,
ζ = 0.0236, released from rest at x₀ = 2 mm after 0.1 s of rest.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import RecordingError, ShortAnalysisWarning
from bayestribo.io.run import Rig
from bayestribo.signal.coarse import MIN_COARSE_TURNING_POINTS
from bayestribo.signal.decay import energy_decay

MASS, F_HZ, LOAD, ZETA, X0, G = 0.035, 32.6, 0.31, 0.0236, 2e-3, 9.80665
OMEGA = 2.0 * math.pi * F_HZ
RATE = 10_000.0
REST = 0.1


def _rig_record(
    mu_k: float, *, periods: float | None = None, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t [s], x [m], v [m/s]: rest, release, half cycles until the spring no longer
    overcomes static friction (μ_s = 1.36 μ_k) or ``periods`` after the release."""
    k, c = MASS * OMEGA**2, 2.0 * ZETA * MASS * OMEGA
    until = math.inf if periods is None else periods / F_HZ
    arcs, x, t0 = [], X0, 0.0
    while abs(k * x) > 1.36 * mu_k * LOAD and t0 < until:
        s = -math.copysign(1.0, x)

        def rhs(_t, u, s=s):
            return [u[1], (-c * u[1] - k * u[0] - s * mu_k * LOAD) / MASS]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t0, t0 + 1.0 / F_HZ),
            [x, 0.0],
            events=turned,
            dense_output=True,
            rtol=1e-10,
            atol=1e-14,
        )
        t1, x = float(sol.t_events[0][0]), float(sol.y_events[0][0][0])
        arcs.append((t0, t1, sol.sol))
        t0 = t1
    end = REST + (t0 + REST if periods is None else until)
    t = np.arange(round(end * RATE) + 1) / RATE
    tm = t - REST
    xs, vs = np.full(t.size, X0), np.zeros(t.size)
    for a, b, sol in arcs:
        m = (tm >= a) & (tm < b)
        xs[m], vs[m] = sol(tm[m])
    xs[tm >= t0] = x
    rng = np.random.default_rng(seed)
    return t, xs + 1.5e-6 * rng.standard_normal(t.size), vs + 1.5e-7 * rng.standard_normal(t.size)


RIG = Rig(natural_frequency_Hz=F_HZ, mass_kg=MASS, load_N=LOAD)


def _analysed(t, x, v):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x, v, rig=RIG)
    return decay, [str(w.message) for w in caught if issubclass(w.category, ShortAnalysisWarning)]


@pytest.mark.parametrize("mu_k", [0.5, 0.8])
def test_a_decay_that_sticks_within_three_oscillations_is_analysed_with_a_warning(mu_k):
    """μ_k = 0.5 and 0.8 stop the pin 6 and 4 turning points after the release (main
    refused both: 7 are needed): analysed on what they hold, the first oscillation too
    where it is what they lack, and a ShortAnalysisWarning names the short decay."""
    t, x, v = _rig_record(mu_k)
    decay, said = _analysed(t, x, v)
    assert len(decay.peaks) >= MIN_COARSE_TURNING_POINTS
    assert decay.motion_ended
    assert len(said) == 1 and said[0].startswith("short decay: the motion stops")
    if mu_k == 0.8:  # 4 turning points: the skipped oscillation is analysed too
        assert "skipped after the release analysed too" in said[0]
        assert decay.start_time < REST + 0.75 / F_HZ


def test_a_record_ending_in_motion_after_three_periods_is_analysed_with_a_warning():
    t, x, v = _rig_record(0.0294, periods=3.0)
    decay, said = _analysed(t, x, v)
    assert len(decay.peaks) >= MIN_COARSE_TURNING_POINTS
    assert not decay.motion_ended
    assert len(said) == 1 and said[0].startswith("short decay: the record ends in motion")


def test_a_record_of_two_periods_is_refused_naming_the_count_found_and_needed():
    t, x, v = _rig_record(0.0294, periods=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(
            RecordingError,
            match=r"holds 3 turning points after the release; "
            r"4 are needed at least",
        ):
            energy_decay(t, x, v, rig=RIG)


def test_a_decay_of_many_oscillations_is_not_called_short():
    t, x, v = _rig_record(0.0294)
    decay, said = _analysed(t, x, v)
    assert len(decay.peaks) > 2 * 3 and said == []


def test_a_velocity_alone_whose_rest_wanders_before_the_release_is_answered():
    """The seismometer of ``benchmarks/seismometer.py`` (a viscous oscillator, ζ = 0.08,
    15 s period, velocity alone at 10 Hz, noise 2e-4, released at 10 s), seed 37 cut at
    100 s: its integral's wander over the rest before the release made a turning point
    beside the release's, whose small swing was taken for the fade ("found 1 usable
    extrema"). Analysed on the decay's turning points from the release on."""
    zeta, omega = 0.08, 2.0 * math.pi / 15.0
    t = np.arange(0.0, 100.0, 0.1)
    wd = omega * math.sqrt(1.0 - zeta**2)
    s = np.clip(t - 10.0, 0.0, None)
    # the closed form of x'' + 2ζωx' + ω²x = 0 from (0.02, 0): its velocity, gain 40
    v = np.where(
        t >= 10.0, -40.0 * 0.02 * omega**2 / wd * np.exp(-zeta * omega * s) * np.sin(wd * s), 0.0
    )
    rng = np.random.default_rng(37)
    rng.normal(0.0, 1.0, 3000)  # the benchmark's draws over its 300 s: drift (unused),
    v = v + rng.normal(0.0, 2e-4, 3000)[: t.size]  # then the noise
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = energy_decay(t, None, v)
    assert len(decay.peaks) >= 6
    assert decay.start_time > 10.0
