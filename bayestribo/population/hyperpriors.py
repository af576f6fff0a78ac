"""Hyperpriors of the population of repeats: the prior on a between-run σ.

Three repeats say little about a standard deviation, so the prior on each
between-run σ matters and is stated with the results. The default is a
**half-Cauchy** distribution (Gelman 2006, *Bayesian Analysis* 1, 515-534):

* it is flat near σ = 0, so it does not push the estimate away from "the repeats
  agree" (an inverse-gamma prior does);
* its tail falls off only as σ⁻², so it does not rule out a large spread either: with
  three repeats the posterior of σ keeps a long upper tail, which is the honest answer;
* its scale ``s`` is the σ below which the prior is nearly flat. The defaults
  (:data:`DEFAULT_SIGMA_SCALES`) are 0.01 for the dimensionless ζ and μ_k: about half
  the paper's values (ζ = 0.0236, μ_k = 0.0294), so a run-to-run spread of half the
  mean is still a priori plausible while the paper's spreads (0.0012 and 0.0036) sit
  in the flat part.

A half-normal prior (lighter tail: more informative about large σ) is available for
comparison. Population means get an improper flat prior: each run bounds its own
parameter, so their posterior is proper as soon as a group holds one run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import BayestriboError

__all__ = [
    "DEFAULT_SIGMA_SCALES",
    "HalfCauchy",
    "HalfNormal",
    "SigmaPrior",
    "sigma_priors",
]

#: Default half-Cauchy scales of the between-run σ of the dimensionless parameters.
DEFAULT_SIGMA_SCALES: Mapping[str, float] = {"zeta": 0.01, "mu_k": 0.01, "zeta_k": 0.01}


@dataclass(frozen=True)
class HalfCauchy:
    """Half-Cauchy prior on σ > 0: density 2 / (π s (1 + (σ/s)²)).

    Parameters
    ----------
    scale : float
        Scale s > 0 [units of the parameter]; also the prior median of σ.
    """

    scale: float

    def __post_init__(self) -> None:
        _check_scale(self.scale)

    def logpdf(self, sigma: ArrayLike) -> NDArray[np.float64]:
        """Log density at ``sigma`` (−inf for σ <= 0)."""
        s = np.asarray(sigma, dtype=float)
        # log1p of a square never warns (inf gives inf, NaN stays NaN).
        out = math.log(2.0 / (math.pi * self.scale)) - np.log1p((s / self.scale) ** 2)
        return np.where(s > 0, out, -np.inf)

    def describe(self) -> str:
        """One-line description, for reports."""
        return f"half-Cauchy(scale={self.scale:g})"


@dataclass(frozen=True)
class HalfNormal:
    """Half-normal prior on σ > 0: density 2 N(σ | 0, s²).

    Parameters
    ----------
    scale : float
        Scale s > 0 [units of the parameter].
    """

    scale: float

    def __post_init__(self) -> None:
        _check_scale(self.scale)

    def logpdf(self, sigma: ArrayLike) -> NDArray[np.float64]:
        """Log density at ``sigma`` (−inf for σ <= 0)."""
        s = np.asarray(sigma, dtype=float)
        out = math.log(2.0) - 0.5 * math.log(2 * math.pi) - math.log(self.scale)
        out = out - 0.5 * (s / self.scale) ** 2
        return np.where(s > 0, out, -np.inf)

    def describe(self) -> str:
        """One-line description, for reports."""
        return f"half-normal(scale={self.scale:g})"


SigmaPrior = HalfCauchy | HalfNormal


def _check_scale(scale: float) -> None:
    if not (isinstance(scale, int | float) and math.isfinite(scale) and scale > 0):
        raise BayestriboError(f"scale: expected a finite number > 0, got {scale!r}")


def sigma_priors(
    parameters: tuple[str, ...],
    sigma_prior: Mapping[str, SigmaPrior | float] | None = None,
) -> dict[str, SigmaPrior]:
    """The prior on the between-run σ of each parameter.

    Parameters
    ----------
    parameters : tuple of str
        Parameter names.
    sigma_prior : mapping, optional
        Per parameter, a prior object or a half-Cauchy scale. Parameters not given
        use a half-Cauchy with the scale of :data:`DEFAULT_SIGMA_SCALES`.

    Raises
    ------
    BayestriboError
        If a parameter has no default scale (e.g. a friction displacement in signal
        units) and none is given, or a name is not among ``parameters``.
    """
    given = dict(sigma_prior or {})
    unknown = sorted(set(given) - set(parameters))
    if unknown:
        raise BayestriboError(f"sigma_prior: {unknown} not among the parameters {list(parameters)}")
    out: dict[str, SigmaPrior] = {}
    for name in parameters:
        value = given.get(name, DEFAULT_SIGMA_SCALES.get(name))
        if value is None:
            raise BayestriboError(
                f"sigma_prior: no default scale for the between-run σ of {name!r}; "
                "give one (a half-Cauchy scale in the parameter's units)"
            )
        out[name] = value if isinstance(value, HalfCauchy | HalfNormal) else HalfCauchy(value)
    return out
