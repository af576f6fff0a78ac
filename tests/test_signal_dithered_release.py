"""A coarse digitiser's record with a little white noise before the rounding (dither).

The rounded noise toggles the record between two levels at rest and at every level
crossing: a spectrum rising to the sampling's Nyquist frequency that once made the
dominant period 2 samples and the record refused ("release: no motion found"). The
records here are simulated independently of the package (``scipy.integrate.solve_ivp``
of a linear oscillator with viscous and quadratic damping), 3 to 5 steps across the
swing, noise of 0.05 to 0.2 step before rounding, levels placed at random.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import RecordingError
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.period import dominant_period

FREQUENCY = 21.3  # Hz
RATE = 5_000.0  # Hz
RELEASE = 0.15  # s


def _record(steps: int, noise: float, seed: int, zeta: float = 0.005, beta: float = 10.0):
    """A decay from 3 mm held until :data:`RELEASE`, both channels rounded to
    ``steps`` levels across their swing after white noise of ``noise`` steps."""
    w = 2 * math.pi * FREQUENCY
    t = np.arange(0.0, 1.4, 1.0 / RATE)
    moving = t >= RELEASE

    def rhs(_: float, s: np.ndarray) -> list[float]:
        return [s[1], -(w**2) * s[0] - 2 * zeta * w * s[1] - beta * abs(s[1]) * s[1]]

    sol = solve_ivp(rhs, (RELEASE, t[-1]), [3e-3, 0.0], t_eval=t[moving], rtol=1e-9, atol=1e-12)
    x = np.full(t.size, 3e-3)
    v = np.zeros(t.size)
    x[moving], v[moving] = sol.y
    rng = np.random.default_rng([39, steps, round(100 * noise), seed])
    out = []
    for s in (x, v):
        q = float(np.ptp(s)) / steps
        u = rng.uniform(-0.5, 0.5)
        out.append((np.round(s / q + noise * rng.standard_normal(s.size) + u) - u) * q)
    return t, out[0], out[1]


@pytest.mark.parametrize("steps", [3, 4, 5])
@pytest.mark.parametrize("noise", [0.05, 0.2])
def test_the_period_of_a_dithered_coarse_record_is_the_oscillations(steps, noise):
    for seed in range(3):
        t, x, v = _record(steps, noise, seed)
        for signal in (x, v):
            assert 1.0 / dominant_period(t, signal) == pytest.approx(FREQUENCY, rel=0.03)


@pytest.mark.parametrize("steps", [3, 4, 5])
@pytest.mark.parametrize("noise", [0.05, 0.2])
def test_a_dithered_coarse_record_is_answered_from_its_release(steps, noise):
    period = 1.0 / FREQUENCY
    for seed in range(3):
        t, x, v = _record(steps, noise, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            decay = energy_decay(t, x, v)
        # the release from the levels: at most the fall by a step from the held swing
        assert RELEASE - 0.02 * period <= decay.release_time <= RELEASE + 0.2 * period
        # from as few as four turning times on the levels at 3 steps: a few percent
        assert 1.0 / decay.natural_frequency_Hz == pytest.approx(period, rel=0.05)
        assert len(decay.peaks) >= 4


@pytest.mark.parametrize("noise", [0.1, 0.3])
def test_dithered_rest_alone_is_still_refused(noise):
    rng = np.random.default_rng(int(10 * noise))
    t = np.arange(0.0, 1.4, 1.0 / RATE)
    u = rng.uniform(-0.5, 0.5, 2)
    x = 1e-3 * (np.round(noise * rng.standard_normal(t.size) + u[0]) - u[0])
    v = 0.1 * (np.round(noise * rng.standard_normal(t.size) + u[1]) - u[1])
    with pytest.raises(RecordingError, match="release: no motion found"):
        energy_decay(t, x, v)


@pytest.mark.parametrize("steps", [3, 4])
def test_a_steady_dithered_coarse_oscillation_is_still_refused(steps):
    # its turning points go on to the record's end: no decay hides under the levels
    t, x, v = _record(steps, 0.1, 0, zeta=0.0, beta=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(RecordingError, match="does not decay"):
            energy_decay(t, x, v)
