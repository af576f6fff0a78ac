"""Hyperpriors of the population of repeats: the prior on a between-run σ.

Three repeats say little about a standard deviation, so the prior on each
between-run σ matters and is stated with the results. The default is **scale-free**,
p(σ) ∝ 1/σ (:class:`ScaleFree`, resolved per group into a :class:`LogUniform`):

* under it, the posterior of a normal population's mean and σ from n repeats that
  each measure their value exactly is the classical answer: Student's t with n − 1
  degrees of freedom for the mean, χ²ₙ₋₁ for σ (Jeffreys 1961, *Theory of
  Probability*, §3.4). Those intervals cover at their nominal rate whatever the true
  σ, which is what a lab quoting "the spread of three repeats" needs;
* it is bounded below at a tenth of the runs' own posterior sd, where the repeats can
  no longer tell σ from zero (the likelihood is flat below), and above at 10 × the
  quantity's scale (:data:`DEFAULT_SIGMA_SCALES`: 0.01 for the dimensionless ζ and
  μ_k, about half the paper's values), so it is proper;
* a group of a single run, which says nothing of σ, keeps a half-Cauchy prior of that
  scale instead (σ's posterior is then its prior, and the bounds of a prior ∝ 1/σ
  would be all the answer).

The half-Cauchy (Gelman 2006, *Bayesian Analysis* 1, 515-534), the package's default
before, is nearly flat in σ below its scale; with three repeats its mean intervals
have Cauchy-like tails and over-cover (all of 240 group means in 20 simulated
campaigns; ``benchmarks/population_prior.py`` compares the two). It and a half-normal
prior stay available by name. Population means get an improper flat prior: each run
bounds its own parameter, so their posterior is proper as soon as a group holds one
run.
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
    "LogUniform",
    "ScaleFree",
    "SigmaPrior",
    "SigmaPriorSpec",
    "resolve",
    "sigma_priors",
]

#: Default scales (typical between-run σ) of the dimensionless parameters.
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


@dataclass(frozen=True)
class LogUniform:
    """Log-uniform prior on σ: density 1 / (σ ln(high/low)) on [low, high], else 0.

    Within its bounds this is the scale-invariant prior p(σ) ∝ 1/σ under which the
    posterior of a normal population's mean and σ from n repeats measured exactly
    is the classical one (Student's t with n − 1 degrees of freedom for the mean,
    χ² for σ), so its intervals cover at their nominal rate whatever the true σ
    (Jeffreys 1961, *Theory of Probability*, §3.4). The bounds keep it proper: below
    ``low`` and above ``high`` it is zero.

    Parameters
    ----------
    low, high : float
        Bounds 0 < low < high [units of the parameter].
    """

    low: float
    high: float

    def __post_init__(self) -> None:
        _check_scale(self.low)
        _check_scale(self.high)
        if not self.high > self.low:
            raise BayestriboError(
                f"high: expected a bound above low = {self.low:g}, got {self.high!r}"
            )

    def logpdf(self, sigma: ArrayLike) -> NDArray[np.float64]:
        """Log density at ``sigma`` (−inf outside [low, high])."""
        s = np.asarray(sigma, dtype=float)
        inside = (s >= self.low) & (s <= self.high)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = -np.log(s) - math.log(math.log(self.high / self.low))
        return np.where(inside, out, -np.inf)

    def describe(self) -> str:
        """One-line description, for reports."""
        return f"log-uniform(σ in [{self.low:.3g}, {self.high:.3g}])"


@dataclass(frozen=True)
class ScaleFree:
    """The default: p(σ) ∝ 1/σ from a tenth of the runs' own precision to 10 × a scale.

    Resolved per group of runs (:meth:`for_runs`) into a :class:`LogUniform` whose
    lower bound is ``floor`` × the median over the group's runs of their posterior
    standard deviation: below it the repeats cannot tell σ from zero (the likelihood
    is flat there), so a prior ∝ 1/σ reaching further down would only pile mass where
    the data say nothing, and the per-run samples could not resolve it (importance
    weights on a handful of samples). The upper bound is ``span`` × ``scale`` (the
    quantity's typical between-run σ, :data:`DEFAULT_SIGMA_SCALES` or the campaign's
    :func:`bayestribo.campaign.analysis.sigma_scale`), and at least 100 × the lower one.

    With three repeats this prior gives the classical Student-t interval of the mean
    and χ² interval of σ, which cover at their nominal rate; the half-Cauchy, nearly
    flat in σ, gives intervals with Cauchy-like tails that over-cover (measured:
    ``benchmarks/population_prior.py``).

    Parameters
    ----------
    scale : float
        Typical between-run σ [units of the parameter].
    floor : float
        Lower bound as a multiple of the runs' median posterior sd (default 0.1).
    span : float
        Upper bound as a multiple of ``scale`` (default 10).
    """

    scale: float
    floor: float = 0.1
    span: float = 10.0

    def __post_init__(self) -> None:
        _check_scale(self.scale)
        _check_scale(self.floor)
        _check_scale(self.span)

    def for_runs(self, run_sds: ArrayLike) -> LogUniform | HalfCauchy:
        """The prior of a group whose runs have these posterior sds [parameter units].

        A group of one run says nothing of σ: its posterior is its prior, and under
        p(σ) ∝ 1/σ that would be the arbitrary bounds' answer. Such a group gets
        ``HalfCauchy(scale)``, which states the typical spread and nothing more.
        """
        if np.size(run_sds) < 2:
            return HalfCauchy(self.scale)
        sds = np.asarray(run_sds, dtype=float)
        sds = sds[np.isfinite(sds) & (sds > 0)]
        low = self.floor * float(np.median(sds)) if sds.size else self.scale * 1e-4
        return LogUniform(low, max(self.span * self.scale, 100.0 * low))

    def describe(self) -> str:
        """One-line description, for reports (before it is resolved for a group)."""
        return f"log-uniform(σ from {self.floor:g} × the runs' sd to {self.span * self.scale:.3g})"


SigmaPrior = HalfCauchy | HalfNormal | LogUniform
#: What :func:`sigma_priors` returns: a prior, or the default resolved per group.
SigmaPriorSpec = SigmaPrior | ScaleFree


def resolve(prior: SigmaPriorSpec, run_sds: ArrayLike) -> SigmaPrior:
    """The prior of one group: :class:`ScaleFree` resolved on its runs' sds, others as given."""
    return prior.for_runs(run_sds) if isinstance(prior, ScaleFree) else prior


def _check_scale(scale: float) -> None:
    if not (isinstance(scale, int | float) and math.isfinite(scale) and scale > 0):
        raise BayestriboError(f"scale: expected a finite number > 0, got {scale!r}")


def sigma_priors(
    parameters: tuple[str, ...],
    sigma_prior: Mapping[str, SigmaPriorSpec | float] | None = None,
) -> dict[str, SigmaPriorSpec]:
    """The prior on the between-run σ of each parameter.

    Parameters
    ----------
    parameters : tuple of str
        Parameter names.
    sigma_prior : mapping, optional
        Per parameter, a prior object or a scale. A scale (and a parameter not given,
        with the scale of :data:`DEFAULT_SIGMA_SCALES`) means the default,
        :class:`ScaleFree` with that scale, resolved per group of runs.

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
    out: dict[str, SigmaPriorSpec] = {}
    for name in parameters:
        value = given.get(name, DEFAULT_SIGMA_SCALES.get(name))
        if value is None:
            raise BayestriboError(
                f"sigma_prior: no default scale for the between-run σ of {name!r}; "
                "give one (a typical between-run σ in the parameter's units)"
            )
        out[name] = (
            value
            if isinstance(value, HalfCauchy | HalfNormal | LogUniform | ScaleFree)
            else ScaleFree(value)
        )
    return out
