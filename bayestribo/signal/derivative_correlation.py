r"""The correlation of neighbouring increments when the velocity is derived.

With the displacement recorded alone, the velocity is its Savitzky-Golay derivative
(:func:`bayestribo.signal.decay.energy_decay`), y' = S y: the derivative at a sample
takes the displacement's noise from a window of samples about it. To first order in
the noise δy (white, σ_y), the error of the increment ``D_j = Σ_i w_ji E_i`` of
E = ½y'² + V(y) is

.. math::  δD_j = u_j^\top δy,\qquad u_j = w_j ∘ V'(y) + S^\top (w_j ∘ y'),

(w_j the increment's quadrature weights on its samples), so that
``Cov[D_j, D_l] = σ_y² u_j^\top u_l``: neighbouring increments share the samples within
half a window of their boundary. Over an increment ∫ y' δy' dτ is, by parts,
``[y' δy] - ∫ y'' δy dτ``: the boundary term enters the two neighbours with opposite
signs, and their errors are anticorrelated in proportion to the speed at the
boundary.

On the linear spring the default grid (one increment per half cycle of the measured
frequency, :func:`bayestribo.signal.increments.pi_data`) puts every boundary near a
turning point, where y' = 0: neighbours are uncorrelated (+0.015 on
``benchmarks/restoring_coverage.py``'s spring, 2 Hz at 200 Hz). On a nonlinear
restoring force the half period changes with the swing, the boundaries drift through
the phase of the motion, and the correlation of neighbours reaches -0.24 (a pendulum
released at 90°) and -0.26 (a Duffing spring 5 % stiffer at the release): the sum of
all the increments then has 0.54-0.59 of the sum of their variances, and
independent increments left ζ's, c₂'s and μ_k's intervals some 30 % too wide
(z-scores' sd 0.71-0.77; with it 0.94-1.06, ``benchmarks/restoring_coverage.py``).
:func:`derived_velocity_correlation` gives the likelihood that correlation
(:attr:`~bayestribo.signal.increments.PiData.correlation`), with which it whitens the
increments (:mod:`bayestribo.inference.likelihood`); the increments' variances stay
the Monte Carlo's, which holds the second-order terms too. It is given where the force
is not in doubt (:func:`bayestribo.inference.preparation.force_settled`): a force that
is not the record's scatters its estimates more than the noise alone would, and keeps
the independent increments' width.
"""

from __future__ import annotations

import numpy as np
import scipy.signal
from numpy.typing import NDArray

__all__ = ["derived_velocity_correlation", "increment_sensitivity"]

#: Polynomial order of the Savitzky-Golay derivative (that of
#: :func:`bayestribo.signal.increments.increment_draws`' repeated derivation).
POLYORDER = 5


def _window(savgol_window: int | None, n_samples: int) -> int:
    """The derivative's window as the Monte Carlo of the increments takes it."""
    return min(int(savgol_window or 7), n_samples - (1 - n_samples % 2))


def increment_sensitivity(
    force: NDArray,
    yp: NDArray,
    start: int,
    weights: NDArray,
    samples: NDArray,
    coefficients: NDArray,
) -> NDArray:
    """u_j at the given samples: the first-order change of an increment per unit of
    displacement noise at each of them [units of Π per unit of y].

    Parameters
    ----------
    force : ndarray
        V'(y) on every sample (y itself on the linear spring).
    yp : ndarray
        The velocity y' on every sample.
    start : int
        The increment's first sample.
    weights : ndarray
        Its quadrature weights, on samples ``start .. start + len(weights) - 1``.
    samples : ndarray of int
        The samples at which u_j is wanted.
    coefficients : ndarray
        The derivative's coefficients (``savgol_coeffs(..., use="dot")``: the derivative
        at sample i is ``Σ_m c_m y_{i-h+m}``, h the half window).

    Returns
    -------
    ndarray
        u_j at ``samples``. The rows of S are the interior ones: exact for samples
        that lie at least a window from either end of the record.
    """
    stop = start + weights.size
    half = coefficients.size // 2
    k = np.asarray(samples, dtype=int)
    direct = np.where((k >= start) & (k < stop), 1.0, 0.0)
    direct = direct * weights[np.clip(k - start, 0, weights.size - 1)] * force[k]
    lo = max(start, int(k.min()) - half)
    hi = min(stop, int(k.max()) + half + 1)
    if hi <= lo:
        return direct
    rows = np.arange(lo, hi)
    offset = k[None, :] - rows[:, None] + half
    inside = (offset >= 0) & (offset < coefficients.size)
    c = np.where(inside, coefficients[np.clip(offset, 0, coefficients.size - 1)], 0.0)
    speed = weights[rows - start] * yp[rows]
    return direct + speed @ c


def derived_velocity_correlation(
    force: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    variance: NDArray,
    sigma_y: float,
    savgol_window: int | None,
    h: float,
) -> NDArray | None:
    """The correlation of the increments' noise when y' is y's Savitzky-Golay derivative.

    The covariance of increments whose samples lie within a derivative's window of each
    other is the first-order ``σ_y² u_jᵀ u_l`` (module notes); it is divided by the
    increments' own standard deviations (``variance``: the Monte Carlo's,
    :func:`bayestribo.signal.increments.increment_noise`). Where the correlation so made
    is not positive definite (second-order terms left out, at a noise comparable to
    the motion), its off-diagonal part is shrunk until it is.

    Parameters
    ----------
    force : ndarray
        V'(y) on the decay's samples (y on the linear spring), noise-free where known.
    yp : ndarray
        y' on the same samples.
    edges, weights
        The grid (:func:`bayestribo.signal.increments.increment_weights`).
    variance : ndarray
        The increments' noise variances, (m,).
    sigma_y : float
        The displacement's white noise, in units of y.
    savgol_window : int or None
        The derivative's window (:attr:`~bayestribo.signal.decay.EnergyDecay.savgol_window`).
    h : float
        The sample spacing in τ.

    Returns
    -------
    ndarray or None
        (m, m), unit diagonal; None when no two increments share a sample's noise or
        the noise is zero.
    """
    force = np.asarray(force, dtype=float)
    yp = np.asarray(yp, dtype=float)
    n = force.size
    m = len(weights)
    if m < 2 or not sigma_y > 0.0:
        return None
    window = _window(savgol_window, n)
    if window <= POLYORDER:
        return None
    coefficients = scipy.signal.savgol_coeffs(window, POLYORDER, deriv=1, delta=h, use="dot")
    half = window // 2
    covariance = np.zeros((m, m))
    for j in range(m - 1):
        end = int(edges[j + 1])  # the last sample of increment j
        for ell in range(j + 1, m):
            first = int(edges[ell])
            if first - half > end + half:
                break
            samples = np.arange(max(first - half, 0), min(end + half, n - 1) + 1)
            u_j = increment_sensitivity(force, yp, int(edges[j]), weights[j], samples, coefficients)
            u_l = increment_sensitivity(force, yp, first, weights[ell], samples, coefficients)
            covariance[j, ell] = covariance[ell, j] = sigma_y**2 * float(u_j @ u_l)
    if not covariance.any():
        return None
    sd = np.sqrt(np.asarray(variance, dtype=float))
    off = covariance / np.outer(sd, sd)
    for _ in range(50):
        correlation = off + np.eye(m)
        try:
            np.linalg.cholesky(correlation)
        except np.linalg.LinAlgError:
            off = 0.9 * off
            continue
        return correlation
    return None
