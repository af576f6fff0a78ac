"""A slow rig whose rests are shorter than the two-period blocks that find the motion.

A 1 Hz spring with strong Coulomb friction (x_c 5 % of the release) and viscous damping,
solved half cycle by half cycle in closed form (independent of the package's model),
held 1 s at rest before the release and recorded 1.5 s past the stop, both channels at
1 kHz: no two-period block of the record lies wholly in a rest.
"""

from __future__ import annotations

import math

import numpy as np

from bayestribo.signal.decay import energy_decay
from bayestribo.signal.motion import motion_span

F, ZETA, X_C, X0, FS = 1.0, 0.01, 2.533e-3, 0.05, 1000.0
T_PRE, T_POST, NX, NV = 1.0, 1.5, 5e-5, 5e-4


def _record(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    w = 2 * math.pi * F
    wd = w * math.sqrt(1 - ZETA**2)
    half = math.pi / wd
    x, t0, pieces = X0, T_PRE, []
    while abs(x) > X_C:  # sticks where the spring cannot beat friction (μ_s = μ_k)
        e = X_C * math.copysign(1.0, x)
        pieces.append((t0, e, x - e))
        x = e - (x - e) * math.exp(-ZETA * w * half)
        t0 += half
    stop = t0
    t = np.arange(round((stop + T_POST) * FS)) / FS
    xs, vs = np.full(t.size, X0), np.zeros(t.size)
    for start, e, u0 in pieces:
        m = (t >= start) & (t < start + half)
        tau = t[m] - start
        env = np.exp(-ZETA * w * tau)
        xs[m] = e + u0 * env * (np.cos(wd * tau) + ZETA * w / wd * np.sin(wd * tau))
        vs[m] = -u0 * env * (w**2 / wd) * np.sin(wd * tau)
    xs[t >= stop] = x
    rng = np.random.default_rng(seed)
    return t, xs + rng.normal(0, NX, t.size), vs + rng.normal(0, NV, t.size), stop


def test_the_noise_comes_from_the_quietest_block_when_no_block_is_all_rest() -> None:
    t, _, v, stop = _record(25)
    span = motion_span(t, v, 1.0 / F)
    # the median of the blocks left out of the motion holds the first and last swings
    # (48 times the noise here before): the quietest is of the rest's noise
    assert 0.7 * NV < span.noise < 3.0 * NV
    assert span.release_time is not None and abs(span.release_time - T_PRE) < 0.05
    # the last half cycle may swing less than the noise (its start is then the stop)
    assert span.stop_time is not None and stop - 0.5 / F - 0.1 < span.stop_time < stop + 0.1


def test_such_a_record_is_analysed_not_refused() -> None:
    t, x, v, stop = _record(26)
    decay = energy_decay(t, x, v)
    assert decay.peaks.value.size >= 6
    assert stop - 0.5 / F - 0.1 < decay.stop_time < stop + 0.1
