"""Parameter draws for the predictive checks: posterior draws or a Gaussian stand-in.

The predictive checks (extinction time, peak residuals) need draws of (ζ, μ, Y_0)
that carry the uncertainty of the identified values. The best are posterior draws
of the Bayesian fit (:func:`draws_from_posterior`); without it, draws from the
Gaussian approximation of the least-squares fit of the whole decay
(:func:`draws_from_least_squares`), labelled as such in every report.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.adequacy.segments import SegmentFit
from bayestribo.errors import BayestriboError
from bayestribo.signal.decay import EnergyDecay

__all__ = ["ParameterDraws", "draws_from_least_squares", "draws_from_posterior"]


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
