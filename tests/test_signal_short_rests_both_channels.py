"""A slow rig whose rests are shorter than the two-period blocks that find the motion.

A 1 Hz spring with strong Coulomb friction (x_c 5 % of the release, μ_s = 2 μ_k) and
viscous damping, solved half cycle by half cycle in closed form (independent of the
package's model; ``benchmarks/unseen_rigs.py``'s ``coulomb_both`` rig),
held at rest before the release and recorded on past the stop, both channels at 1 kHz:
with rests of 0.2-2 s no two-period block of the record lies wholly in a rest, or the
one that does holds the release's first instants. The noise is then read off the
second differences (``signal/difference_noise.py``); before, the median of the blocks
left out of the motion (its first and last swings) was taken, 48 times the noise, and
the record was refused with "found 0 usable extrema", or a quiet block holding the
release's start gave 7 times the noise. A rest shorter than a block at either end is
found where the first (last) eighth of a period is within the threshold; before, such a
record was taken to start (end) in motion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bayestribo.signal.decay import energy_decay
from bayestribo.signal.motion import motion_span

F, ZETA, X_C, X0, FS = 1.0, 0.01, 2.533e-3, 0.05, 1000.0
X_S = 2.0 * X_C
NX, NV = 5e-5, 5e-4


def _record(seed: int, pre: float, post: float) -> tuple[np.ndarray, ...]:
    """Time [s], displacement [m], velocity [m/s] and the stop [s]."""
    w = 2 * math.pi * F
    wd = w * math.sqrt(1 - ZETA**2)
    half = math.pi / wd
    x, t0, pieces = X0, pre, []
    while abs(x) > X_S:  # sticks where the spring cannot beat static friction
        e = X_C * math.copysign(1.0, x)
        pieces.append((t0, e, x - e))
        x = e - (x - e) * math.exp(-ZETA * w * half)
        t0 += half
    stop = t0
    t = np.arange(round((stop + post) * FS)) / FS
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


CASES = [
    (25, 1.0, 1.5),
    (25, 1.0, 1.2),
    (30, 0.5, 0.5),
    (26, 2.0, 0.2),
    (26, 0.2, 0.2),
    (25, 0.2, 2.0),
    (26, 2.0, 2.0),
]


@pytest.mark.parametrize(("seed", "pre", "post"), CASES)
def test_the_noise_of_rests_shorter_than_a_block_is_the_rests(
    seed: int, pre: float, post: float
) -> None:
    t, _, v, stop = _record(seed, pre, post)
    span = motion_span(t, v, 1.0 / F)
    assert 0.9 * NV < span.noise < 1.2 * NV
    assert span.release_time is not None and abs(span.release_time - pre) < 0.01
    assert span.stop_time is not None and abs(span.stop_time - stop) < 0.03


@pytest.mark.parametrize(("seed", "pre", "post"), [(25, 1.0, 1.5), (26, 1.0, 1.2), (27, 0.2, 1.0)])
def test_such_a_record_is_analysed_not_refused(seed: int, pre: float, post: float) -> None:
    t, x, v, stop = _record(seed, pre, post)
    decay = energy_decay(t, x, v)
    assert decay.motion_ended
    assert decay.peaks.value.size >= 6
    assert abs(decay.release_time - pre) < 0.01
    assert abs(decay.stop_time - stop) < 0.03
