"""The Duffing spring: y'' + y + βy³ = 0, V(y) = y²/2 + βy⁴/4, β fitted to the period.

β is not stated by a rig: it is measured from how the half period changes with the swing
(:func:`fit_beta`). The half period of the undamped swing A over the small-swing one is

    T(A)/T₀ = (2/π) ∫₀^{π/2} dφ / √(1 + (βA²/2)(1 + sin²φ)),

(x = A sin φ in the period integral; ``1 - 3βA²/8`` to first order), computed by
Gauss-Legendre quadrature. Viscous damping and Coulomb friction leave a linear
oscillator's half period constant (Rigaud et al. 2010, Eq. 15), so a change of the half
period with the swing is the spring's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from functools import partial

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.restoring.base import (
    RestoringForce,
    builtin_description,
    register_builtin,
)

__all__ = ["DUFFING", "duffing", "fit_beta", "half_period_ratio", "potential", "spring"]

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(48)
_PHI = 0.25 * math.pi * (_NODES + 1.0)  # [0, π/2]


def half_period_ratio(a: ArrayLike, beta: float) -> NDArray:
    """T(A)/T₀ of the undamped Duffing spring of stiffness ratio β at swings A [-].

    Raises
    ------
    ValueError
        For a softening spring (β < 0) at a swing beyond its turning-over point
        (1 + βA² <= 0: no oscillation there).
    """
    a = np.abs(np.asarray(a, dtype=float))
    inside = 1.0 + 0.5 * beta * (a[..., None] ** 2) * (1.0 + np.sin(_PHI) ** 2)
    if np.any(1.0 + beta * a**2 <= 0.0):
        raise ValueError(f"β = {beta:g}: a softening spring does not oscillate at these swings")
    return (0.5 * _WEIGHTS * (1.0 / np.sqrt(inside))).sum(axis=-1)


def fit_beta(times: ArrayLike, values: ArrayLike) -> tuple[float, float]:
    """β and its standard error from the turning times and the turning points.

    The turning times are fitted by least squares as
    ``t_n = t₀ + T₀ Σ_{m<n} T(A_m)/T₀``, A_m = (|Y_m| + |Y_m+1|)/2 the swing of half
    cycle m (:func:`scipy.optimize.least_squares`, the standard error from the Jacobian
    and the residual scatter). The standard error is the timing scatter's only: on an
    independent simulation (β = 0.6, ζ = 0.004, 200 Hz, noise 1e-4 of the swing) the
    exact turning times gave β = 0.60003, the package's interpolated ones 0.6007, some
    60 of these standard errors (``tests/test_model_restoring.py``).

    Parameters
    ----------
    times : array_like
        Turning times [s], in order.
    values : array_like
        The turning points about the equilibrium, in the run's unit.

    Returns
    -------
    beta, se : float
        β [1/unit²] and its standard error.

    Raises
    ------
    ValueError
        With fewer than five turning points.
    """
    from scipy.optimize import least_squares

    t = np.asarray(times, dtype=float)
    y = np.abs(np.asarray(values, dtype=float))
    if t.size < 5 or t.size != y.size:
        raise ValueError("fit_beta: expected five or more turning times and values")
    # from the first turning time: the least squares' steps are relative to each
    # unknown, and a clock of Unix time (1.4e9 s) made t₀'s step tens of seconds and
    # left β at its start with a singular Jacobian
    t = t - t[0]
    swing = 0.5 * (y[1:] + y[:-1])
    half = float(np.median(np.diff(t)))
    scale = 1.0 / float(np.max(swing)) ** 2  # β in units of 1/A_max²

    def residual(p: NDArray) -> NDArray:
        t0, period, b = p
        steps = period * half_period_ratio(swing, b * scale)
        return t - (t0 + np.concatenate(([0.0], np.cumsum(steps))))

    floor = -0.99  # 1 + βA_max² > 0: the softest spring that still oscillates
    found = least_squares(
        residual, [t[0], half, 0.0], bounds=([-np.inf, 0.0, floor], [np.inf, np.inf, np.inf])
    )
    dof = max(t.size - 3, 1)
    s2 = float(found.fun @ found.fun) / dof
    try:
        cov = s2 * np.linalg.inv(found.jac.T @ found.jac)
        se = math.sqrt(max(float(cov[2, 2]), 0.0)) * scale
    except np.linalg.LinAlgError:
        se = math.inf
    return float(found.x[2]) * scale, se


@numba.njit(cache=True, inline="always")
def spring_kernel(y: float, k: NDArray) -> float:
    """V'(y) = y + βy³, β = k[0]."""
    return y + k[0] * y * y * y


@numba.njit(cache=True, inline="always")
def potential_kernel(y: float, k: NDArray) -> float:
    """V(y) = y²/2 + βy⁴/4, β = k[0]."""
    y2 = y * y
    return 0.5 * y2 + 0.25 * k[0] * y2 * y2


def potential(y: ArrayLike, beta: float) -> NDArray:
    """V(y) = y²/2 + βy⁴/4 at displacements y [unit²]."""
    y = np.asarray(y, dtype=float)
    return 0.5 * y * y + 0.25 * beta * y**4


def spring(y: ArrayLike, beta: float) -> NDArray:
    """V'(y) = y + βy³ at displacements y [unit]."""
    y = np.asarray(y, dtype=float)
    return y + beta * y**3


def duffing(beta: float) -> RestoringForce:
    """The Duffing spring of a given β [1/unit²] (its functions partials of this
    module's, so that it pickles with a law that holds it)."""
    return replace(
        DUFFING,
        description=f"a Duffing spring, k(x + βx³), β = {beta:.4g}",
        potential=partial(potential, beta=beta),
        spring=partial(spring, beta=beta),
        half_period_ratio=partial(half_period_ratio, beta=beta),
        parameters={"beta": beta},
    )


def _with_parameters(values: Mapping[str, float]) -> RestoringForce:
    """The Duffing spring at another β (``values["beta"]``, 1/unit²)."""
    return duffing(float(values["beta"]))


def _measure(times: ArrayLike, values: ArrayLike) -> tuple[RestoringForce, dict]:
    """The Duffing spring of the run: β fitted to its turning times (:func:`fit_beta`)."""
    beta, se = fit_beta(times, values)
    return duffing(beta), {"beta": beta, "beta_se": se}


DUFFING = register_builtin(
    RestoringForce(
        name="duffing",
        description=builtin_description("duffing"),
        potential=partial(potential, beta=0.0),
        half_period_ratio=partial(half_period_ratio, beta=0.0),
        fitted=True,
        measure=_measure,
        spring=partial(spring, beta=0.0),
        kernels=(spring_kernel, potential_kernel),
        kernel_parameters=("beta",),
        with_parameters=_with_parameters,
        length_powers=(-2,),
    )
)
