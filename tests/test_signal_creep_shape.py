"""A creep seen on one recorded channel (signal/creep_shape.py).

Independent simulation by scipy's solve_ivp of an 8 Hz oscillator with ζ = 0.002 and a
Stribeck friction regularised below 0.05 mm/s,

    ẍ = -ω²x - 2ζωẋ - (0.2 + 0.2 exp(-(ẋ/0.008)²)) tanh(ẋ/(5·10⁻⁵)) m/s²,

held at 4 mm for 0.3 s, released, and recorded for 5 s at 1 kHz with white noise of
3e-7 m and 3e-5 m/s: its swings end near 1.7 s and it then creeps towards the
equilibrium (from 0.13 mm at 2 s to 0.05 mm at 5 s). The same motion with the contact
stuck where its swings end, recorded with an offset that drifts, is the sensor's doing,
not a creep.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import CreepWarning, MisfitWarning
from bayestribo.signal.creep_shape import creep_towards_equilibrium
from bayestribo.signal.decay import energy_decay

OMEGA = 2.0 * math.pi * 8.0
FS = 1000.0
HOLD_S, DURATION_S, X0 = 0.3, 5.0, 4e-3
NOISE_X, NOISE_V = 3e-7, 3e-5


def _rhs(_t: float, s: np.ndarray) -> list[float]:
    v = s[1]
    friction = 0.2 + 0.2 * math.exp(-((v / 0.008) ** 2))
    return [v, -(OMEGA**2) * s[0] - 2.0 * 0.002 * OMEGA * v - friction * math.tanh(v / 5e-5)]


@pytest.fixture(scope="module")
def motion() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t [s], x [m], v [m/s] without noise: held, released at 0.3 s, creeping."""
    t = np.arange(0.0, DURATION_S, 1.0 / FS)
    moving = t >= HOLD_S
    sol = solve_ivp(
        _rhs,
        (0.0, DURATION_S - HOLD_S),
        [X0, 0.0],
        t_eval=t[moving] - HOLD_S,
        method="LSODA",
        rtol=1e-9,
        atol=1e-12,
    )
    x, v = np.full(t.size, X0), np.zeros(t.size)
    x[moving], v[moving] = sol.y[0], sol.y[1]
    return t, x, v


def _stuck(t: np.ndarray, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The motion with the contact stuck at its last turning point (no creep)."""
    last = int(np.flatnonzero(np.abs(v) > 2e-3)[-1])
    stop = last + int(np.flatnonzero(np.sign(v[last:]) != np.sign(v[last]))[0])
    held, still = x.copy(), v.copy()
    held[stop:], still[stop:] = x[stop], 0.0
    return held, still


def _decay(t, x, v) -> tuple[object, list]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x, v)
    return decay, [w for w in caught if issubclass(w.category, CreepWarning)]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_displacement_alone_that_creeps_is_not_the_noise(motion, seed: int) -> None:
    t, x, _ = motion
    rng = np.random.default_rng([39, seed])
    decay, creeps = _decay(t, x + rng.normal(0.0, NOISE_X, t.size), None)
    assert len(creeps) == 1
    assert issubclass(creeps[0].category, MisfitWarning)  # bayestribo fit exits 1
    text = str(creeps[0].message)
    assert "displacement is recorded alone" in text and "creeps" in text
    # the noise comes from the rest before the release, not from the creep (which
    # measured tens of times the recorded noise there)
    assert "rest after stop" not in decay.noise.source
    assert decay.noise.displacement == pytest.approx(NOISE_X, rel=0.2)


def test_a_velocity_alone_that_creeps_is_not_the_noise(motion) -> None:
    t, _, v = motion
    rest = t >= HOLD_S  # recorded from the release on: no rest before it
    found = 0
    for seed in (1, 2, 3):
        rng = np.random.default_rng([39, seed, 1])
        vs = v + rng.normal(0.0, NOISE_V, t.size)
        decay, creeps = _decay(t[rest] - HOLD_S, None, vs[rest])
        if creeps:
            found += 1
            assert "velocity is recorded alone" in str(creeps[0].message)
            assert "rest after stop" not in decay.noise.source
    assert found >= 2


def test_a_stuck_contact_under_a_drifting_sensor_is_rest(motion) -> None:
    t, x, v = motion
    held, still = _stuck(t, x, v)
    towards = -math.copysign(1.0, held[-1])  # the way to the equilibrium
    rng = np.random.default_rng(39)
    xs = held + rng.normal(0.0, NOISE_X, t.size)
    vs = still + rng.normal(0.0, NOISE_V, t.size)
    walk = np.cumsum(rng.normal(0.0, 1.0, t.size))
    hum = np.sin(2.0 * math.pi * 50.0 * t + 0.3)
    cases = {
        # an offset drifting towards the equilibrium, over the whole record
        "linear x": (xs + towards * 2e-5 * t / DURATION_S, None),
        "walk x": (xs + 3e-6 * walk / walk.std(), None),
        "hum x": (xs + 3e-6 * hum, None),
        "linear v": (None, vs + towards * 3e-5 * t / DURATION_S),
        "walk v": (None, vs + 3e-5 * walk / walk.std()),
        "hum v": (None, vs + 6e-5 * hum),
    }
    for name, (xx, vv) in cases.items():
        decay, creeps = _decay(t, xx, vv)
        assert creeps == [], name
        assert "rest after stop" in decay.noise.source, name
    # a velocity recorded from the release on (no rest before it to measure its offset)
    # whose offset drifts: its integral at rest curves, but not towards the equilibrium
    moving = t >= HOLD_S
    for size in (1e-5, 3e-5, -3e-5):
        ramp = vs + towards * size * t / DURATION_S
        _, creeps = _decay(t[moving] - HOLD_S, None, ramp[moving])
        assert creeps == [], size


def _path(r: np.ndarray, t: np.ndarray, **kw) -> object:
    options = dict(
        recorded="displacement",
        sigma=1e-6,
        stop_time=-0.05,
        last_swing=2e-4,
        omega=2.0 * math.pi * 10.0,
    )
    options.update(kw)
    return creep_towards_equilibrium(t, r, np.zeros(t.size), 0, **options)


def test_a_creep_approaches_the_equilibrium_and_slows_down() -> None:
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 3.0, 1e-3)
    noise = rng.normal(0.0, 1e-6, t.size)
    creep = _path(1e-4 * np.exp(-t / 1.0) + noise, t)
    assert creep is not None and creep.time_constant == pytest.approx(1.0, rel=0.2)
    # a steady pace towards the equilibrium (a drift's), away from it, past it, or an
    # approach to another level: no creep
    for path in (
        1e-4 * (1.0 - 0.3 * t),
        1e-4 * (2.0 - np.exp(-t / 1.0)),
        1e-4 * (2.0 * np.exp(-t / 1.0) - 1.0),
        1e-4 * (0.5 + 0.5 * np.exp(-t / 1.0)),
    ):
        assert _path(path + noise, t) is None


def test_a_creep_needs_a_still_rest_before_the_release() -> None:
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 4.0, 1e-3)
    before = 1000  # the first second held, the motion between, the rest from 2 s
    r = np.where(t < 2.0, 1e-4, 1e-4 * np.exp(-(t - 2.0) / 1.0)) + rng.normal(0, 1e-6, t.size)
    kw = dict(stop_time=1.95, before=before)
    start = 2000
    args = (t, r, np.zeros(t.size), start)
    common = dict(recorded="displacement", sigma=1e-6, last_swing=2e-4, omega=60.0)
    assert creep_towards_equilibrium(*args, **common, **kw) is not None
    # the held rest moves at the creep's pace: an offset that drifts
    drifting = r.copy()
    drifting[:before] += 4e-5 * t[:before]
    args = (t, drifting, np.zeros(t.size), start)
    assert creep_towards_equilibrium(*args, **common, **kw) is None
