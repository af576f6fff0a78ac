"""A seismometer's velocity alone: a viscous decay that fades into the noise, never stops.

The record (an independent ``solve_ivp`` integration): ζ = 0.08, a 15 s period, held for
10 s and released from rest, its velocity alone at 5 Hz (75 samples a period) with white
noise, 300 s. Its swings sink below 8 times the noise at about 170 s and its oscillation
stays coherent under them for about 50 s more. Taken for a stop, the 8σ crossing ended
the motion (the model's energy after it missing from the data), the tail's oscillation
was counted as rest noise (the velocity's noise 1.9 times the simulated), and ζ came out
2.5 to 4.7 sd low; the 10 s rest, shorter than the motion's two-period blocks, made the
record one that starts in motion, whose integral's wander at rest gave a turning point.
``benchmarks/seismometer.py`` measures the coverage over seeds
(``results/seismometer_fade.json``).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import bayestribo
from bayestribo.errors import (
    FadeWarning,
    FrequencyTrendWarning,
    MisfitWarning,
    OffsetDriftWarning,
)
from bayestribo.signal.decay import energy_decay

ZETA, PERIOD, RELEASE, SIGMA, RATE = 0.08, 15.0, 10.0, 2e-4, 5.0


def _record(seed: int, drift: float = 0.0, cubic: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and velocity [arbitrary] of the seismometer, noise seeded by ``seed``,
    its offset a random walk of ``drift`` per √s, its spring hardening so that the
    frequency at the release swing is higher by the fraction ``cubic`` (Duffing,
    ω(A) ≈ ω(1 + 3/8 β A²))."""
    omega = 2.0 * math.pi / PERIOD
    beta = cubic / (0.375 * 0.02**2)
    t = np.arange(0.0, 300.0, 1.0 / RATE)
    moving = t >= RELEASE
    solution = solve_ivp(
        lambda _t, s: [
            s[1],
            -omega * omega * s[0] * (1.0 + beta * s[0] * s[0]) - 2.0 * ZETA * omega * s[1],
        ],
        (0.0, float(t[-1] - RELEASE)),
        [0.02, 0.0],
        t_eval=t[moving] - RELEASE,
        rtol=1e-10,
        atol=1e-14,
    )
    v = np.zeros(t.size)
    v[moving] = 40.0 * solution.y[1]
    rng = np.random.default_rng(seed)
    v += drift * np.cumsum(rng.normal(0.0, 1.0, t.size)) * math.sqrt(t[1] - t[0])
    return t, v + rng.normal(0.0, SIGMA, t.size)


@pytest.fixture(scope="module")
def decay_and_warnings() -> tuple[object, list[warnings.WarningMessage]]:
    t, v = _record(1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, velocity=v)
    return decay, caught


def test_a_fade_into_the_noise_is_not_an_end_of_motion(decay_and_warnings):
    decay, caught = decay_and_warnings
    assert not decay.motion_ended
    said = [str(w.message) for w in caught if issubclass(w.category, FadeWarning)]
    assert len(said) == 1 and "without stopping" in said[0]
    # the analysis ends at a turning point near where the swings sink below 8σ (the
    # velocity's envelope, 40 ω x₀ e^(-ζω(t - release)), reaches 8σ; the last swing
    # beyond it is the noise's too), not at the record's end
    omega = 2.0 * math.pi / PERIOD
    sinks = RELEASE + math.log(40.0 * 0.02 * omega / (8.0 * SIGMA)) / (ZETA * omega)
    assert abs(decay.end_time - sinks) < PERIOD / 2


def test_the_rest_noise_is_measured_where_the_oscillation_has_ended(decay_and_warnings):
    decay, _ = decay_and_warnings
    # about 700 samples of rest: the sd of their sd is 2.7 %; 10 % is 3.7 of it
    assert decay.noise.velocity == pytest.approx(SIGMA, rel=0.1)
    # white, as simulated: the oscillation left under the noise, a line at the rig's
    # frequency, is taken out of the rest before its spectrum is measured
    assert not decay.rest_noise.coloured


def test_a_rest_shorter_than_a_period_is_found_before_the_release(decay_and_warnings):
    decay, _ = decay_and_warnings
    assert decay.release_time == pytest.approx(RELEASE, abs=2.0 / RATE)
    # the analysis starts a whole oscillation after it (the default skip)
    assert decay.start_time == pytest.approx(RELEASE + PERIOD, abs=2.0 / RATE)


def test_the_default_fit_covers_zeta_without_a_misfit():
    t, v = _record(1)
    run = bayestribo.Run(time=t, velocity=v, metadata={"length_unit": "arbitrary"})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = bayestribo.fit(run, seed=1)
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    lo, hi = result.interval("zeta", 0.95)
    assert lo <= ZETA <= hi


def test_a_stiffening_spring_the_half_periods_cannot_show_is_in_the_interval():
    # A spring 0.5 % stiffer at the release swing: the half period grows by about 0.2 %
    # over the analysed swings, which the last, poorly timed swings measure to about
    # 0.1 % (here 1.2 standard errors, no FrequencyTrendWarning), and the constant
    # frequency moves ζ by about 3 of its own sd (benchmarks/seismometer.py, case
    # cubic). The frequency nuisance ½√(Δ² + σ_Δ²) keeps the linear part's ζ in the
    # interval; a nuisance from the change beyond its noise alone, ½√max(Δ² - σ_Δ², 0),
    # was 0.45 times as wide here and left it 2.1 sd out.
    t, v = _record(5, cubic=0.005)
    run = bayestribo.Run(time=t, velocity=v, metadata={"length_unit": "arbitrary"})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = bayestribo.fit(run, seed=1)
    assert not [w for w in caught if issubclass(w.category, FrequencyTrendWarning)]
    assert abs(result.frequency_trend["z"]) < 2.0
    lo, hi = result.interval("zeta", 0.95)
    assert lo <= ZETA <= hi


def test_an_offset_that_drifts_between_the_rests_is_flagged(decay_and_warnings):
    _, clean = decay_and_warnings
    assert not [w for w in clean if issubclass(w.category, OffsetDriftWarning)]
    t, v = _record(1, drift=1e-4)  # the rests' levels about 7 σ apart
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        energy_decay(t, velocity=v)
    said = [str(w.message) for w in caught if issubclass(w.category, OffsetDriftWarning)]
    assert len(said) == 1 and "its offset drifts" in said[0]
