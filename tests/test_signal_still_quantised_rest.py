"""A quantised channel whose rests sit on one level (a rotary encoder's angle) keeps the
rounding's white noise in the increments' variances, not its rests' spectrum of zero."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run
from bayestribo.signal.quantisation import still_on_its_steps


def _encoder(counts_per_rev: int, seed: int) -> Run:
    """A torsion pendulum (0.8 Hz, ζ = 0.006, friction angle 0.01 rad, static 0.015 rad)
    released from 0.6 rad after 1 s of rest, 3 s kept after the stop, recorded at 200 Hz
    by an encoder of ``counts_per_rev`` (closed form, half cycle by half cycle)."""
    f, zeta, th_c, th_s, th0, fs = 0.8, 0.006, 0.01, 0.015, 0.6 + 0.001 * seed, 200.0
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - zeta**2)
    starts, eqs, amps = [], [], []
    x, t0 = th0, 1.0
    while abs(x) > th_s:
        e = th_c * np.sign(x)
        starts.append(t0)
        eqs.append(e)
        amps.append(x - e)
        x = e - (x - e) * np.exp(-zeta * w * np.pi / wd)
        t0 += np.pi / wd
    t = np.arange(round((t0 + 3.0) * fs)) / fs
    theta = np.full(t.size, th0)
    k = np.searchsorted(starts, t, side="right") - 1
    moving = (k >= 0) & (t < t0)
    tau = t[moving] - np.asarray(starts)[k[moving]]
    theta[moving] = np.asarray(eqs)[k[moving]] + np.asarray(amps)[k[moving]] * np.exp(
        -zeta * w * tau
    ) * (np.cos(wd * tau) + zeta * w / wd * np.sin(wd * tau))
    theta[t >= t0] = x
    step = 2 * np.pi / counts_per_rev
    return Run(
        time=t,
        displacement=np.round(theta / step) * step,
        metadata={"natural_frequency_Hz": f, "length_unit": "rad"},
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_encoders_still_rests_leave_the_rounding_in_the_variances(seed):
    prepared = prepare(_encoder(8192, seed))
    step = 2 * np.pi / 8192
    variance = np.asarray(prepared.data.variance)
    assert np.all(np.isfinite(variance))
    # the smallest increment's variance is of the rounding (q²/12 at the last swing's
    # small amplitude), not the ~1e-35 of a spectrum measured on one level
    assert variance.min() > 1e-6 * step**2
    assert prepared.noise.displacement == pytest.approx(step / np.sqrt(12), rel=0.05)


def test_still_on_its_steps():
    rng = np.random.default_rng(3)
    step = 1e-3
    one_level = [np.full(200, 4 * step), np.full(100, -2 * step)]
    assert still_on_its_steps(one_level, step)
    toggling = [np.where(np.arange(300) == 100, 5 * step, 4 * step)]
    assert still_on_its_steps(toggling, step)
    noisy = [np.round(rng.normal(0, 2 * step, 300) / step) * step]
    assert not still_on_its_steps(noisy, step)
    assert not still_on_its_steps(one_level, None)
