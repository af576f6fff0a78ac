"""Parameter draws for the predictive checks: posterior draws or a Gaussian stand-in.

The predictive checks (extinction time, peak residuals) need draws of (ζ, μ, Y_0)
that carry the uncertainty of the identified values. The best are posterior draws
of the Bayesian fit (:func:`draws_from_posterior`); without it, draws from the
Gaussian approximation of the least-squares fit of the whole decay
(:func:`draws_from_least_squares`), labelled as such in every report.

The least squares do not estimate static friction: the law (Eq. 8) sticks at the first
turning point inside ±μ_s, μ_s ≥ μ_k free, and a record whose motion stopped sets
μ_s only to the step on which the model sticks where the record rests.
:func:`static_friction_at_rest` draws each draw's μ_s on that step, as the Bayesian
fit's posterior does (its prior uniform in μ_s/μ_k, the likelihood constant along
the step); with μ_s = μ_k the model would go on past a record that stuck at a turning
point between μ_k and μ_s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.adequacy.segments import SegmentFit
from bayestribo.errors import BayestriboError
from bayestribo.signal.decay import EnergyDecay

__all__ = [
    "ParameterDraws",
    "draws_from_least_squares",
    "draws_from_posterior",
    "static_friction_at_rest",
]


@dataclass(frozen=True)
class ParameterDraws:
    """Draws of the dimensionless parameters of the exact model.

    Attributes
    ----------
    zeta, mu, y0 : ndarray
        ζ [-], μ [-] (μ_k, or friction displacement / ℓ) and the amplitude Y_0 of
        the first analysed turning point [-], one value per draw.
    mu_s : ndarray
        Static friction per draw (μ_s = μ_k unless the fit sampled it).
    label : str
        Where the draws come from (shown in every report).
    """

    zeta: NDArray
    mu: NDArray
    y0: NDArray
    mu_s: NDArray
    label: str

    def __len__(self) -> int:
        return int(self.zeta.size)


def draws_from_least_squares(
    fit: SegmentFit, n_draws: int = 400, *, seed: int | None = 0
) -> ParameterDraws:
    """Draws from the Gaussian approximation N(estimate, covariance) of a least-squares fit.

    Draws outside the model's domain (ζ < 0, μ < 0, ζ >= 1) are reflected into it
    (|value|), which keeps the mass near a bound where the estimate sits.

    Parameters
    ----------
    fit : SegmentFit
        A whole-decay fit (:func:`bayestribo.adequacy.segments.whole_decay_fit`).
    n_draws : int
        Number of draws (>= 10).
    seed : int, optional
        Seed of the draws.
    """
    if isinstance(n_draws, bool) or not isinstance(n_draws, int) or n_draws < 10:
        raise BayestriboError(f"n_draws must be an integer >= 10, got {n_draws!r}")
    rng = np.random.default_rng(seed)
    cov = np.asarray(fit.covariance, dtype=float)
    # an exactly fixed parameter has a zero row: draws equal the estimate
    x = rng.multivariate_normal(fit.values, cov, size=n_draws, method="eigh")
    zeta = np.minimum(np.abs(x[:, 0]), 0.99)
    mu = np.abs(x[:, 1])
    y0 = np.abs(x[:, 2])
    return ParameterDraws(
        zeta=zeta,
        mu=mu,
        y0=y0,
        mu_s=mu.copy(),
        label="draws from the Gaussian approximation of the least-squares fit (not a posterior)",
    )


def draws_from_posterior(
    result: Any, decay: EnergyDecay, n_draws: int = 400, *, seed: int | None = 0
) -> ParameterDraws:
    """Posterior draws of a Bayesian fit (``result.samples(name)``), thinned to ``n_draws``.

    The model's friction is the sampled friction displacement divided by the decay's
    length scale (``mu_k`` of a fit also carries the load and mass calibration
    uncertainties, which do not change the motion); ``mu_k`` only when no
    displacement is given. μ_s is μ times ``mu_s_ratio`` when sampled, else
    ``mu_s``, else μ.

    Raises
    ------
    BayestriboError
        When the result has no ζ, friction or y0 samples.
    """
    names = list(getattr(result, "parameter_names", []))
    try:
        zeta = np.asarray(result.samples("zeta"), dtype=float)
        y0 = np.abs(np.asarray(result.samples("y0"), dtype=float))
        if "friction_displacement" in names:
            mu = np.asarray(result.samples("friction_displacement"), dtype=float)
            mu = mu / decay.scaling.length_scale
        else:
            mu = np.asarray(result.samples("mu_k"), dtype=float)
        if "mu_s_ratio" in names:
            mu_s = mu * np.asarray(result.samples("mu_s_ratio"), dtype=float)
        elif "mu_s" in names:
            mu_s = np.asarray(result.samples("mu_s"), dtype=float)
        else:
            mu_s = mu
    except (KeyError, ValueError, AttributeError) as exc:
        raise BayestriboError(f"the fit result has no usable samples: {exc}") from exc
    rng = np.random.default_rng(seed)
    idx = rng.choice(zeta.size, size=min(n_draws, zeta.size), replace=False)
    mu = np.abs(mu[idx])
    return ParameterDraws(
        zeta=np.clip(zeta[idx], 0.0, 0.99),
        mu=mu,
        y0=y0[idx],
        mu_s=np.maximum(np.abs(mu_s[idx]), mu),
        label="posterior draws of the Bayesian fit",
    )


#: Values of μ_s per draw scanned by :func:`static_friction_at_rest`.
STATIC_GRID = 200

#: Largest distance [μ_k] of a step's rest from the record's for the draw to stick there.
REST_TOLERANCE = 0.5

#: Label added to least-squares draws whose μ_s :func:`static_friction_at_rest` set.
STATIC_LABEL = ", μ_s on the step where each sticks at the record's rest"


def static_friction_at_rest(
    draws: ParameterDraws, decay: EnergyDecay, *, seed: int | None = 0
) -> ParameterDraws:
    """The draws with μ_s on the step where each one's motion sticks at the record's rest.

    On the linear spring the exact model sticks at the first turning point inside
    ±μ_s (Eq. 8), so its rest moves in steps as μ_s grows from μ_k. For each draw the
    step whose rest is nearest the record's (the decay's last sample, y about the
    equilibrium) is found over :data:`STATIC_GRID` values of μ_s from μ_k to
    1.5 |y_rest| + 3 μ_k, and μ_s is drawn uniformly over that step's grid values: the
    Bayesian fit's posterior of μ_s/μ_k (uniform prior) given the draw's ζ, μ_k and
    y0. Two steps' rests lie more than μ_k apart (successive turning points have
    opposite signs, the earlier beyond μ_k), so a step whose rest is within
    :data:`REST_TOLERANCE` μ_k of the record's is the one it stuck on; a draw with no
    such step cannot rest where the record does (the record moved past its last
    turning point, or rests where none of its turning points is) and keeps μ_s = μ_k,
    the law's latest stop.

    Parameters
    ----------
    draws : ParameterDraws
        Draws of the decay's model (the model starts at ``y0`` with the decay's first
        recorded velocity, as in :func:`bayestribo.adequacy.extinction.extinction_check`).
    decay : EnergyDecay
        The analysed decay on the linear spring (``restoring`` None).
    seed : int, optional
        Seed of the uniform draw within each step.

    Returns
    -------
    ParameterDraws
        ``draws`` unchanged when the motion did not stop inside the record; else with
        ``mu_s`` set and the label saying so.

    Raises
    ------
    BayestriboError
        On a decay with a nonlinear restoring force (its steps are not the linear
        spring's).
    """
    from bayestribo.model import rest_position

    if decay.restoring is not None:
        raise BayestriboError(
            "static_friction_at_rest takes a decay on the linear spring, got one on "
            f"{decay.restoring.name!r}"
        )
    if not decay.motion_ended:
        return draws
    y_rest = float(decay.y[-1])
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    y0 = sign * np.abs(np.asarray(draws.y0, dtype=float))[:, None]
    zeta = np.asarray(draws.zeta, dtype=float)[:, None]
    mu = np.asarray(draws.mu, dtype=float)[:, None]
    top = 1.5 * abs(y_rest) + 3.0 * mu
    grid = mu + (top - mu) * np.linspace(0.0, 1.0, STATIC_GRID)[None, :]
    with np.errstate(invalid="ignore", over="ignore"):
        rest = np.asarray(rest_position(y0, zeta, mu, grid, float(decay.yp[0])), dtype=float)
    miss = np.where(np.isfinite(rest), np.abs(rest - y_rest), np.inf)
    best = np.argmin(miss, axis=1)
    rows = np.arange(grid.shape[0])
    found = miss[rows, best] <= REST_TOLERANCE * mu[:, 0]
    at_best = rest[rows, best][:, None]
    tol = 1e-9 * (np.abs(at_best) + mu)
    same = np.abs(rest - at_best) <= tol
    lo = np.where(same, grid, np.inf).min(axis=1)
    hi = np.where(same, grid, -np.inf).max(axis=1)
    u = np.random.default_rng(seed).uniform(size=lo.size)
    mu_s = np.where(found, lo + u * (hi - lo), draws.mu)
    return replace(
        draws,
        mu_s=np.maximum(mu_s, draws.mu),
        label=draws.label.replace(" (not a posterior)", STATIC_LABEL + " (not a posterior)"),
    )
