"""The second pass: the increments' variances from the law's motion at the optimum.

The noise variance of an increment of Π is a sum over its samples of
``w² (y²σ_y² + y'²σ_y'² + ½(σ_y⁴ + σ_y'⁴))`` (:mod:`bayestribo.signal.increments`),
with y and y' the channels *without* their noise. A first pass takes the observed
channels; the fit then finds the optimum, computes the variances again from the law's
motion there (:func:`law_motion`) and finds the optimum of that posterior, from which
it samples (:func:`reweighted_posterior`, run by :func:`bayestribo.inference.sample`;
iteratively reweighted least squares stopped after one step: the optimum moves by a
fraction of a posterior sd, and the variances by a fraction of that).

Why: below the noise the observed y² has the mean y² + σ_y², so the tail's variances
were 3 times too large at 30 times the vibrometer's resolution, and each increment's
variance shared its noise, which leaned the fit to low energies at small amplitude.
On 40 records of ``viscous+quadratic`` at 30 times the resolution
(``benchmarks/noise_weights.py``) ζ's mean z was +0.52 ± 0.17 with the observed
channels, +0.18 ± 0.19 with the noise-free ones. With this second pass (and the noise
level's error marginalised, :func:`bayestribo.signal.increments.noise_bias_sd`) the
package's own fits of those records give ζ's mean z -0.11 ± 0.15, sd(z) 0.97
(``benchmarks/results/laws_calibration_30x_vq_reweight.json``).

The motion is rebuilt from the law's turning points (its compiled integrator, every
law alike): between turning points τ_n, τ_{n+1} at Y_n, Y_{n+1}, a half cosine
``y = c + a cos(π(τ - τ_n)/(τ_{n+1} - τ_n))`` about the centre c = (Y_n + Y_{n+1})/2
with a = (Y_n - Y_{n+1})/2 (exact for Coulomb friction, within the damping's decay
over a half cycle, a few per cent of y², for the others: the variances need no
more), at rest at the last turning point once the motion stops. Before the first
turning point (a record that starts in motion) the first half cosine is continued
backwards.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.model.laws import Law
from bayestribo.signal.increments import pi_data

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior
    from bayestribo.signal.decay import EnergyDecay

__all__ = ["law_motion", "reweighted_posterior"]


def law_motion(
    law: Law,
    values: Mapping[str, float],
    y0: float,
    yp0: float,
    tau: ArrayLike,
    *,
    reference: float | None = None,
) -> tuple[NDArray, NDArray]:
    """The law's motion y(τ), y'(τ) on the samples ``tau``, from its turning points.

    Parameters
    ----------
    law : Law
        The dissipation law.
    values : mapping
        Its parameters by name (scalars, dimensionless).
    y0, yp0 : float
        Initial state (dimensionless).
    tau : array_like
        Sorted sample times τ >= 0.
    reference : float, optional
        Reference amplitude of terms parametrised at it (default |y0|).

    Returns
    -------
    y, yp : ndarray
        Same shape as ``tau``.
    """
    t = np.asarray(tau, dtype=float)
    if t.size == 0:
        return np.empty(0), np.empty(0)
    tau_n, y_n = law.turning_points(
        values, float(y0), float(yp0), tau_max=float(t[-1]) + 2.0 * math.pi, reference=reference
    )
    tau_n, y_n = np.asarray(tau_n, dtype=float), np.asarray(y_n, dtype=float)
    if tau_n.size < 2:
        # no half cycle: at rest where it starts (or stops at once)
        still = float(y_n[-1]) if y_n.size else float(y0)
        return np.full(t.shape, still), np.zeros(t.shape)
    k = np.clip(np.searchsorted(tau_n, t, side="right") - 1, 0, tau_n.size - 2)
    span = tau_n[k + 1] - tau_n[k]
    centre = 0.5 * (y_n[k] + y_n[k + 1])
    half = 0.5 * (y_n[k] - y_n[k + 1])
    phase = math.pi * (t - tau_n[k]) / span
    y = centre + half * np.cos(phase)
    yp = -half * (math.pi / span) * np.sin(phase)
    stopped = t >= tau_n[-1]
    if np.any(stopped):
        y[stopped] = y_n[-1]
        yp[stopped] = 0.0
    return y, yp


def reweighted_posterior(
    posterior: Posterior, decay: EnergyDecay, theta: NDArray
) -> Posterior | None:
    """The same posterior with its increments' variances from the law's motion at
    ``theta``.

    Parameters
    ----------
    posterior : Posterior
        A posterior whose data were made by :func:`bayestribo.signal.pi_data` from
        ``decay`` (their :attr:`~bayestribo.signal.increments.PiData.preparation`).
    decay : EnergyDecay
        The run's energy decay.
    theta : ndarray
        The optimum, in sampling coordinates.

    Returns
    -------
    Posterior or None
        Same priors, fixed values, law and observed increments; the variances (and
        the noise level's column) of the second pass. None when the data do not say
        how they were made, or the law cannot move from ``theta`` (its motion is not
        finite).
    """
    likelihood = posterior.likelihood
    recipe = likelihood.data.preparation
    if recipe is None or type(likelihood) is not PiLikelihood:
        return None
    params = posterior.physical(np.asarray(theta, dtype=float)[None])["params"]
    values = {k: float(v[0]) for k, v in params.items() if k != "y0"}
    y, yp = law_motion(
        posterior.law,
        values,
        float(params["y0"][0]),
        float(likelihood.data.yp0),
        decay.tau,
        reference=likelihood.reference_amplitude,
    )
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(yp))):
        return None
    data = dataclasses.replace(
        pi_data(decay, motion=(y, yp), **recipe),
        law_increments=likelihood.model_increments(params)[0],
    )
    return dataclasses.replace(posterior, likelihood=dataclasses.replace(likelihood, data=data))
