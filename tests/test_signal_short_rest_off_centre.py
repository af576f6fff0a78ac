"""A stop far off centre followed by a rest of a period or two: the end of motion is the stop.

An independent closed-form simulation of a viscous + Coulomb oscillator (half cycle by
half cycle, each a damped oscillation about the equilibrium the friction shifts,
sticking at the first turning point within the static friction's reach): f = 1 Hz,
ζ = 0.01, a friction displacement 5 % of the 50 mm release and a static one 10 %, 100 Hz,
the displacement alone with 50 µm of noise, 1 s of rest before the release and 2 s
after the stop, which is some 3 mm off centre (the unseen-rig probe's ``ms_wrap``).
When the rest after the last moving block was shorter than a block, its noise was
taken as zero, every sample of it stood out, and the end of motion was put at the
record's last sample: the data's last Π increment then held two seconds of the rest's
energy, ½y_stop², which the law's own end of motion leaves out, and the fit misfit the
law that made the record (p < 1e-50).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo.inference.build import build_posterior
from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run

F, ZETA, X0, XC, XS, FS = 1.0, 0.01, 0.05, 0.05 * 0.05, 0.1 * 0.05, 100.0
PRE, POST = 1.0, 2.0


def _record(seed: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Time [s], displacement [m] and the time of the stop [s]."""
    w = 2 * math.pi * F
    wd = w * math.sqrt(1 - ZETA**2)
    half = math.pi / wd
    starts, centres, sizes = [], [], []
    x, t0 = X0, PRE
    while abs(x) > XS:
        c = XC * math.copysign(1.0, x)
        starts.append(t0)
        centres.append(c)
        sizes.append(x - c)
        x = c - (x - c) * math.exp(-ZETA * w * half)
        t0 += half
    t = np.arange(round((t0 + POST) * FS)) / FS
    out = np.full(t.size, X0)
    k = np.searchsorted(np.asarray(starts), t, side="right") - 1
    moving = (k >= 0) & (t < t0)
    s = t[moving] - np.asarray(starts)[k[moving]]
    envelope = np.exp(-ZETA * w * s)
    out[moving] = np.asarray(centres)[k[moving]] + np.asarray(sizes)[k[moving]] * envelope * (
        np.cos(wd * s) + ZETA * w / wd * np.sin(wd * s)
    )
    out[t >= t0] = x
    return t, out + np.random.default_rng(seed).normal(0.0, 5e-5, t.size), t0


@pytest.mark.parametrize("seed", [11, 12])
def test_the_motion_ends_at_the_stop_and_the_law_that_made_it_fits(seed):
    t, x, stop = _record(seed)
    k = 0.2 * (2 * math.pi * F) ** 2
    run = Run(t, x, metadata={"load_N": 1.0, "mass_kg": 0.2, "natural_frequency_Hz": F})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(run)
    decay = prepared.decay
    assert abs(decay.peaks.stop_time - stop) < 0.25 / F, (decay.peaks.stop_time, stop)
    assert "rest after stop" in decay.noise.source
    # the law that made the record, at its true values: χ² of the order of the increments
    posterior = build_posterior(prepared.data)
    truth = {"zeta": ZETA, "mu_k": XC * k / 1.0, "mu_s_ratio": XS / XC}
    y0 = np.linspace(-0.5, 0.5, 2001)
    theta = np.array([[truth.get(n, v) for n in posterior.names] for v in y0])
    residuals = posterior.standardized_residuals(theta)
    chi2 = np.min(np.sum(residuals**2, axis=1))
    assert chi2 < 3.0 * residuals.shape[1] + 10.0, chi2
