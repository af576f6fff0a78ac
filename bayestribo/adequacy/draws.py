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

#: Standard deviation [μ_k] of the model's rest about the record's, beyond the record's
#: own: the draws' rests are off the record's by 2-4 % of μ_k on the bundled runs (the
#: equilibrium's and the parameters' errors).
REST_SD = 0.1

#: A draw none of whose values of μ_s rests within this many standard deviations of
#: the record's rest cannot stick there: it keeps μ_s = μ_k.
REST_REACH = 4.0

#: Label added to least-squares draws whose μ_s :func:`static_friction_at_rest` set.
STATIC_LABEL = ", μ_s on the step where each sticks at the record's rest"


def static_friction_at_rest(
    draws: ParameterDraws,
    decay: EnergyDecay,
    *,
    rest: float | None = None,
    rest_sd: float | None = None,
    seed: int | None = 0,
) -> ParameterDraws:
    """The draws with μ_s where each one's motion sticks at the record's rest.

    On the linear spring the exact model sticks at the first turning point inside
    ±μ_s (Eq. 8), so its rest moves in steps as μ_s grows from μ_k. For each draw the
    rest is evaluated at :data:`STATIC_GRID` values of μ_s, evenly spaced from μ_k to
    1.5 |y_rest| + 3 μ_k, and μ_s is one of them drawn with weight
    exp(-d²/2s²), d the distance of its rest from the record's and
    s² = (:data:`REST_SD` μ_k)² + ``rest_sd``²: the Bayesian fit's posterior of
    μ_s/μ_k (uniform prior) given the draw's ζ, μ_k and y0, with the record's rest as
    its datum. Steps whose turning points lie on opposite sides rest more than μ_k
    apart, and the nearest holds all the weight; a turning point just beyond μ_k is
    followed by a creep to the same side, and where that moves the rest by less than
    s both steps share the weight in proportion to their widths. A draw none of whose
    values rests within :data:`REST_REACH` s of the record's (the record moved past
    its last turning point, or rests where none of its turning points is) keeps
    μ_s = μ_k, the law's latest stop.

    Parameters
    ----------
    draws : ParameterDraws
        Draws of the decay's model (the model starts at ``y0`` with the decay's first
        recorded velocity, as in :func:`bayestribo.adequacy.extinction.extinction_check`).
    decay : EnergyDecay
        The analysed decay on the linear spring (``restoring`` None).
    rest : float, optional
        The record's rest after its stop [-] (y about the equilibrium); default the
        decay's last sample.
    rest_sd : float, optional
        Its standard error [-]; default the displacement's noise per sample
        (``decay.noise_y``) with the default ``rest``, else 0.
    seed : int, optional
        Seed of the draw of μ_s.

    Returns
    -------
    ParameterDraws
        ``draws`` unchanged when the motion did not stop inside the record; else with
        ``mu_s`` set and the label saying so.

    Raises
    ------
    BayestriboError
        On a decay with a nonlinear restoring force (its steps are not the linear
        spring's), or a ``rest`` or ``rest_sd`` that is not a finite number (``rest_sd``
        at least 0).
    """
    from bayestribo.model import rest_position

    if decay.restoring is not None:
        raise BayestriboError(
            "static_friction_at_rest takes a decay on the linear spring, got one on "
            f"{decay.restoring.name!r}"
        )
    for name, value in (("rest", rest), ("rest_sd", rest_sd)):
        if value is not None and not (
            isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)
        ):
            raise BayestriboError(f"{name} must be a finite number, got {value!r}")
    if rest_sd is not None and rest_sd < 0.0:
        raise BayestriboError(f"rest_sd must be at least 0, got {rest_sd!r}")
    if not decay.motion_ended:
        return draws
    if rest is None:
        y_rest = float(decay.y[-1])
        se = float(decay.noise_y or 0.0) if rest_sd is None else float(rest_sd)
    else:
        y_rest, se = float(rest), float(rest_sd or 0.0)
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    y0 = sign * np.abs(np.asarray(draws.y0, dtype=float))[:, None]
    zeta = np.asarray(draws.zeta, dtype=float)[:, None]
    mu = np.asarray(draws.mu, dtype=float)[:, None]
    top = 1.5 * abs(y_rest) + 3.0 * mu
    grid = mu + (top - mu) * np.linspace(0.0, 1.0, STATIC_GRID)[None, :]
    with np.errstate(invalid="ignore", over="ignore"):
        at = np.asarray(rest_position(y0, zeta, mu, grid, float(decay.yp[0])), dtype=float)
    s = np.sqrt((REST_SD * mu) ** 2 + se * se)
    z = np.where(np.isfinite(at), np.abs(at - y_rest) / np.maximum(s, 1e-300), np.inf)
    nearest = z.min(axis=1)
    weight = np.exp(-0.5 * (z * z - (nearest * nearest)[:, None]))
    weight = np.where(np.isfinite(weight), weight, 0.0)
    cumulative = np.cumsum(weight, axis=1)
    u = np.random.default_rng(seed).uniform(size=nearest.size) * cumulative[:, -1]
    index = np.minimum((cumulative < u[:, None]).sum(axis=1), STATIC_GRID - 1)
    chosen = grid[np.arange(nearest.size), index]
    mu_s = np.where(nearest <= REST_REACH, chosen, draws.mu)
    return replace(
        draws,
        mu_s=np.maximum(mu_s, draws.mu),
        label=draws.label.replace(" (not a posterior)", STATIC_LABEL + " (not a posterior)"),
    )
