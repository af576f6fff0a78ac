"""A mass that creeps on after its last half cycle is not at rest (signal/creep.py).

Independent simulation by scipy's solve_ivp of a 5 Hz oscillator with ζ = 0.003 and a
Stribeck friction regularised below 0.1 mm/s,

    ẍ = -ω²x - 2ζωẋ - (0.15 + 0.25 exp(-(ẋ/0.01)²)) tanh(ẋ/10⁻⁴) m/s²,

released from 6 mm and recorded for 6 s at 500 Hz with white noise of 5e-7 m and
5e-5 m/s: its swings end after 1.7 s and it then creeps towards the spring's
equilibrium at 10⁻⁵-10⁻⁴ m/s for the rest of the record.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import CreepWarning, MisfitWarning
from bayestribo.signal.creep import creeping_rest
from bayestribo.signal.decay import energy_decay

OMEGA = 2.0 * math.pi * 5.0
FS = 500.0
NOISE_X, NOISE_V = 5e-7, 5e-5


def _rhs(_t: float, s: np.ndarray) -> list[float]:
    v = s[1]
    friction = 0.15 + 0.25 * math.exp(-((v / 0.01) ** 2))
    return [v, -(OMEGA**2) * s[0] - 2.0 * 0.003 * OMEGA * v - friction * math.tanh(v / 1e-4)]


@pytest.fixture(scope="module")
def motion() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t [s], x [m], v [m/s] of the motion without noise."""
    t = np.arange(0.0, 6.0, 1.0 / FS)
    sol = solve_ivp(_rhs, (0.0, 6.0), [0.006, 0.0], t_eval=t, method="LSODA", rtol=1e-9, atol=1e-12)
    return t, sol.y[0], sol.y[1]


def _noisy(x: np.ndarray, v: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return x + rng.normal(0.0, NOISE_X, x.size), v + rng.normal(0.0, NOISE_V, v.size)


def _decay(t: np.ndarray, x: np.ndarray, v: np.ndarray) -> tuple[object, list]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x, v)
    return decay, [w for w in caught if issubclass(w.category, CreepWarning)]


def test_a_creep_after_the_stop_is_not_the_noise(motion) -> None:
    t, x, v = motion
    decay, creeps = _decay(t, *_noisy(x, v, 1))
    # the creep (tens of µm over the seconds after the stop) was the "rest" noise:
    # 94 times the recorded one, and the misfit test of a wrong law went blind
    assert len(creeps) == 1
    assert "creeps" in str(creeps[0].message)
    # no law's motion creeps: a misfit of the law at low speed (bayestribo fit exits 1)
    assert issubclass(creeps[0].category, MisfitWarning)
    assert "rest after stop" not in decay.noise.source
    assert decay.noise.displacement == pytest.approx(NOISE_X, rel=0.2)
    assert decay.noise.velocity == pytest.approx(NOISE_V, rel=0.2)


def test_a_still_rest_is_rest_whatever_the_sensor_offsets(motion) -> None:
    t, x, v = motion
    held = x.copy()
    stop = int(np.flatnonzero(np.abs(v) > 1e-3)[-1]) + 1
    held[stop:] = x[stop]  # the contact sticks where the swings end
    still = v.copy()
    still[stop:] = 0.0
    xs, vs = _noisy(held, still, 2)
    # a velocity offset at rest (no displacement moves with it), then a displacement
    # that drifts (no velocity moves with it): neither is a creep
    for xx, vv in ((xs, vs + 3e-4), (xs + 2e-5 * t, vs)):
        decay, creeps = _decay(t, xx, vv)
        assert creeps == []
        assert "rest after stop" in decay.noise.source


def test_the_creep_needs_both_channels_to_agree() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 2.0, 1e-3)
    x = 1e-3 * t + rng.normal(0.0, 1e-6, t.size)
    found = creeping_rest(t, x, np.full(t.size, 1e-3) + rng.normal(0.0, 1e-4, t.size), 0)
    assert found is not None and found.slope == pytest.approx(1e-3, rel=0.01)
    # the velocity says the opposite way, or five times faster: no creep
    for speed in (-1e-3, 5e-3):
        v = np.full(t.size, speed) + rng.normal(0.0, 1e-4, t.size)
        assert creeping_rest(t, x, v, 0) is None
