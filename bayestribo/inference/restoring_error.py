"""The measured restoring force's error in a fit's intervals.

A fitted restoring force (a Duffing spring's β) is measured once from the record's
turning times (:meth:`~bayestribo.model.restoring.RestoringForce.measure`), with a
standard error, and the law is sampled with it held at that value: the chains are draws
of p(θ | data, β̂). Sampling β with θ is not open to the fit, since the observed
increments themselves are of the energy ½y'² + V(y), which β changes; the likelihood is
that of Π for one potential. The error is marginalised instead,

    p(θ | data) = ∫ p(θ | data, β) N(β; β̂, se²) dβ,

to first order in β - β̂: the conditional posterior keeps its shape and its centre moves
as m(β) = m(β̂) + J (β - β̂). For a Gaussian conditional posterior of covariance Σ,
∂/∂β ∇_θ log p(θ | data, β) = Σ⁻¹ J, so

    J = Σ c,        c_j = ∂² log p(θ | data, β) / ∂θ_j ∂β,                    (1)

c from central differences of the log posterior density at the posterior mean, on the
run prepared again with the force at β̂ ± se (:func:`bayestribo.inference.preparation.
reframe`: the energy's potential, and the time scale of the small swings moved by the
ratio of the two forces' small-swing frequencies, the increments' Monte Carlo variances
from the same draws). Each draw θ_i then becomes θ_i + J ε_i with ε_i ~ N(0, se²), drawn
again (up to :data:`REDRAWS` times) where that leaves the priors' support, and kept at
ε_i = 0 where no draw stays inside (counted). The reported quantities and the law's
ΔE(A) band are taken from these draws (:func:`bayestribo.inference.summarising.summary`);
the chains, their diagnostics, the pointwise log-likelihood and the predictive Π remain
those of the sampled p(θ | data, β̂).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.posterior import Posterior
from bayestribo.inference.preparation import data_seed, reframe, small_swing_frequency
from bayestribo.inference.types import PreparedRun
from bayestribo.model.restoring import get_restoring

__all__ = ["REDRAWS", "RestoringError", "restoring_error", "shifted"]

#: Draws of ε for a draw whose shifted value leaves the priors' support, before it is
#: kept at ε = 0.
REDRAWS = 20

#: The step of each coordinate in the central differences of (1), in posterior sds.
_STEP_SD = 0.25


@dataclass(frozen=True)
class RestoringError:
    """A measured restoring force parameter's effect on the fit, and its draws.

    Attributes
    ----------
    parameter : str
        The force's parameter (``"beta"``).
    value, se : float
        Its measured value and standard error [the force's unit].
    shift : dict
        J of Eq. 1 per sampled coordinate: the change of its posterior mean per unit
        of the parameter.
    relative : dict
        ``J se`` over the posterior sd per sampled coordinate: the share of the
        interval the parameter's error adds (its sd in units of the sampled sd).
    eps : ndarray
        ε_i, one per flat draw (0 where kept unshifted).
    unshifted : int
        Draws kept at ε = 0 (every redraw outside the priors' support).
    """

    parameter: str
    value: float
    se: float
    shift: dict[str, float]
    relative: dict[str, float]
    eps: NDArray
    unshifted: int

    def to_dict(self) -> dict[str, Any]:
        """Plain data for the result's ``restoring`` record."""
        return {
            "parameter": self.parameter,
            "marginalised": True,
            "shift_per_unit": dict(self.shift),
            "sd_added_over_sd": dict(self.relative),
            "draws_unshifted": int(self.unshifted),
        }


def _measured(prepared: PreparedRun) -> tuple[Any, dict] | None:
    """The fitted force of the run (its template) and its measurement record, or None
    for a run whose restoring force has no measured parameters."""
    kernel = prepared.decay.restoring
    if kernel is None:
        return None
    force = get_restoring(kernel.name)
    if not force.fitted or force.measure is None or force.with_parameters is None:
        return None
    decay = prepared.decay
    if decay.turning_times is None:
        return None
    try:
        _, record = force.measure(
            decay.turning_times, decay.peaks.value / decay.scaling.length_scale
        )
    except ValueError:
        return None
    return force, record


def _posterior_at(
    prepared: PreparedRun, posterior: Posterior, force: Any, values: dict[str, float]
) -> Posterior:
    """The same posterior on the run prepared again with the force at ``values``."""
    base = prepared.decay.restoring
    kernel = force.with_parameters(values).kernel()
    f_frame = prepared.decay.scaling.omega / (2.0 * math.pi)
    ratio = small_swing_frequency(prepared.decay, kernel) / small_swing_frequency(
        prepared.decay, base
    )
    moved = reframe(prepared, f_frame * ratio, restoring=kernel, seed=data_seed(prepared.decay))
    likelihood = dataclasses.replace(posterior.likelihood, data=moved.data)
    return Posterior(posterior.priors, likelihood, posterior.fixed, posterior.compiled)


def _cross_derivative(
    minus: Posterior, plus: Posterior, center: NDArray, steps: NDArray, h: float
) -> NDArray | None:
    """c of Eq. 1 by central differences (None where a point leaves the support)."""
    d = center.size
    rows = np.repeat(center[None, :], 2 * d, axis=0)
    rows[np.arange(d), np.arange(d)] += steps
    rows[d + np.arange(d), np.arange(d)] -= steps
    lp_plus, lp_minus = plus(rows), minus(rows)
    if not (np.all(np.isfinite(lp_plus)) and np.all(np.isfinite(lp_minus))):
        return None
    up = lp_plus[:d] - lp_minus[:d]
    down = lp_plus[d:] - lp_minus[d:]
    return (up - down) / (4.0 * steps * h)


def restoring_error(
    prepared: PreparedRun,
    posterior: Posterior,
    flat: NDArray,
    rng: np.random.Generator,
) -> RestoringError | None:
    """The measured restoring force's error marginalised into a fit's draws (Eq. 1).

    Parameters
    ----------
    prepared : PreparedRun
        The preparation the posterior was sampled on (the law's frame).
    posterior : Posterior
        The exact posterior that was sampled.
    flat : ndarray
        Its flat draws of the sampled coordinates, shape (n, d).
    rng : numpy.random.Generator
        Source of the draws of ε.

    Returns
    -------
    RestoringError or None
        None for a run whose restoring force has no measured parameter with a finite,
        positive standard error (linear, pendulum), or whose posterior is not smooth
        about its mean.
    """
    measured = _measured(prepared)
    if measured is None:
        return None
    force, record = measured
    names = [n for n in force.kernel_parameters if f"{n}_se" in record]
    if len(names) != 1:
        return None  # one measured parameter (β) is what the forces registered have
    name = names[0]
    value, se = float(record[name]), float(record[f"{name}_se"])
    if not (math.isfinite(se) and se > 0.0):
        return None
    flat = np.atleast_2d(np.asarray(flat, dtype=float))
    center = flat.mean(axis=0)
    cov = np.atleast_2d(np.cov(flat, rowvar=False))
    sd = np.sqrt(np.diag(cov))
    if not np.all(sd > 0.0):
        return None
    minus = _posterior_at(prepared, posterior, force, {name: value - se})
    plus = _posterior_at(prepared, posterior, force, {name: value + se})
    c = _cross_derivative(minus, plus, center, _STEP_SD * sd, se)
    if c is None:
        return None
    jac = cov @ c
    eps, unshifted = _draws_in_support(posterior, flat, jac, se, rng)
    return RestoringError(
        parameter=name,
        value=value,
        se=se,
        shift=dict(zip(posterior.names, jac.tolist(), strict=True)),
        relative=dict(zip(posterior.names, (np.abs(jac) * se / sd).tolist(), strict=True)),
        eps=eps,
        unshifted=unshifted,
    )


def _draws_in_support(
    posterior: Posterior, flat: NDArray, jac: NDArray, se: float, rng: np.random.Generator
) -> tuple[NDArray, int]:
    """ε per draw, drawn again where θ + Jε leaves the priors' support."""
    n = flat.shape[0]
    eps = rng.normal(0.0, se, n)
    todo = ~_in_support(posterior, flat + eps[:, None] * jac[None, :])
    for _ in range(REDRAWS):
        if not todo.any():
            break
        eps[todo] = rng.normal(0.0, se, int(todo.sum()))
        todo[todo] = ~_in_support(posterior, flat[todo] + eps[todo, None] * jac[None, :])
    eps[todo] = 0.0
    return eps, int(todo.sum())


def _in_support(posterior: Posterior, theta: NDArray) -> NDArray:
    """True for rows inside every prior's support."""
    return np.isfinite(posterior.priors.logpdf(theta))


def shifted(flat: NDArray, error: RestoringError | None) -> NDArray:
    """The flat draws θ_i + J ε_i (as they are for None)."""
    if error is None:
        return flat
    jac = np.array(list(error.shift.values()))
    return flat + error.eps[:, None] * jac[None, :]
