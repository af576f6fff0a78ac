"""A viscous + Coulomb decay on a coarse digitiser, in closed form half cycle by half
cycle (independent of the package's models): the record the coarse-signal and short-check
tests share."""

from __future__ import annotations

import math

import numpy as np


def coarse_record(steps: float = 10.0, placement: float = 0.0):
    """A viscous + Coulomb decay at 10 kHz (32.6 Hz, from 2 mm, sticking), both channels
    rounded to 1/``steps`` of their swing on levels shifted by ``placement`` of a step
    from the zero, with 0.1 s of rest before and after."""
    f, zeta, xc = 32.6, 0.0236, 6.2e-6
    w = 2 * math.pi * f
    wd = w * math.sqrt(1 - zeta**2)
    fs = 10_000.0
    t = np.arange(0, 0.9, 1 / fs)
    x = np.full(t.size, 2e-3)
    v = np.zeros(t.size)
    t0, amp = 0.1, 2e-3
    direction = -1.0
    while abs(amp) > 2 * xc:
        centre = -direction * xc
        m = (t >= t0) & (t < t0 + math.pi / wd)
        s = t[m] - t0
        env = (amp - centre) * np.exp(-zeta * w * s)
        x[m] = centre + env * (np.cos(wd * s) + zeta * w / wd * np.sin(wd * s))
        v[m] = -env * w * w / wd * np.sin(wd * s)
        amp = centre + (amp - centre) * -math.exp(-zeta * w * math.pi / wd)
        t0 += math.pi / wd
        direction = -direction
    x[t >= t0] = amp
    qx, qv = np.ptp(x) / steps, np.ptp(v) / steps
    u = placement
    return t, (np.round(x / qx + u) - u) * qx, (np.round(v / qv + u) - u) * qv, (qx, qv), t0
