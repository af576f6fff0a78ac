"""Priors of the single-run fit: small, independent, replaceable objects.

Each prior is a one-dimensional distribution with a vectorised ``logpdf`` (``-inf``
outside its support), a ``sample`` for starting walkers and prior predictive draws,
and a ``describe`` for reports. :class:`PriorSet` holds one per parameter; the
default set is built by :func:`default_priors` and any entry can be replaced.

Defaults (dimensionless, Rigaud et al. 2010 notation), for the default law; every other
term of :mod:`bayestribo.model.laws` declares its own:

* ``zeta`` (ζ): uniform on [0, 0.3]. Underdamped oscillators that ring for several
  cycles have ζ well below 0.3; the rig's ζ₀ = 0.0033 in air and ζ ≈ 0.024 with
  glycerol.
* ``mu_k`` (μ_k, or the friction displacement x_c in signal units when there is no
  load): uniform on [0, y0/4]. A friction larger than a quarter of the initial
  amplitude stops the motion within two half cycles: such a record has no decay to
  analyse.
* ``mu_s_ratio`` (μ_s/μ_k): uniform on [1, 10]. Static friction is at least kinetic
  friction, and dry contacts reach several times it; the ratio mostly decides at
  which turning point the pin sticks.
* ``y0`` (initial amplitude): normal, centred on the observed y(0) with a standard
  deviation of 1 % of it, which is hundreds of times the noise of one sample (or,
  for a coarse displacement, the 1 % and half its step added in quadrature).
* ``log10_discrepancy`` (optional): base-10 logarithm of the relative model
  discrepancy per unit √τ, uniform on [-7, 0] (a log-uniform scale).
* ``log10_shape`` (optional, with the discrepancy): base-10 logarithm of the standard
  deviation s_c of the shape discrepancy's coefficients (a relative departure of the
  increments, smooth along the decay), uniform on [-7, 0].
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws import Law, get_law

__all__ = [
    "BELIEF_BOUNDS",
    "BOUND_FRACTION",
    "BOUND_WIDTH",
    "LogUniform",
    "Normal",
    "Prior",
    "PriorSet",
    "Uniform",
    "default_priors",
    "piled_on_bounds",
    "widened_prior",
]

#: Width of the band below an upper prior bound, as a fraction of the prior range.
BOUND_WIDTH = 0.01
#: Share of posterior draws in that band above which the posterior piles on the bound
#: (a posterior that ignores the bound puts about BOUND_WIDTH there).
BOUND_FRACTION = 0.10


class Prior:
    """A one-dimensional prior distribution."""

    def to_spec(self) -> dict[str, float | str]:
        """Plain-data description, e.g. ``{"type": "Uniform", "low": 0, "high": 1}``."""
        return {"type": type(self).__name__, **self.__dict__}

    @staticmethod
    def from_spec(spec: Mapping[str, float | str]) -> Prior:
        """Rebuild a prior written by :meth:`to_spec`."""
        kinds = {"Uniform": Uniform, "Normal": Normal, "LogUniform": LogUniform}
        args = dict(spec)
        kind = args.pop("type", None)
        if kind not in kinds:
            raise ValueError(f"unknown prior type {kind!r}; expected one of {sorted(kinds)}")
        return kinds[str(kind)](**args)

    def logpdf(self, x: ArrayLike) -> NDArray:  # pragma: no cover - interface
        raise NotImplementedError

    def sample(self, rng: np.random.Generator, size: int) -> NDArray:  # pragma: no cover
        raise NotImplementedError

    def describe(self) -> str:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class Uniform(Prior):
    """Uniform on [low, high]."""

    low: float
    high: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.high > self.low):
            raise ValueError(f"Uniform needs finite low < high, got [{self.low}, {self.high}]")

    def logpdf(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        inside = (x >= self.low) & (x <= self.high)
        return np.where(inside, -math.log(self.high - self.low), -np.inf)

    def sample(self, rng: np.random.Generator, size: int) -> NDArray:
        return rng.uniform(self.low, self.high, size)

    def describe(self) -> str:
        return f"Uniform({self.low:g}, {self.high:g})"


@dataclass(frozen=True)
class Normal(Prior):
    """Normal with mean ``mu`` and standard deviation ``sigma``."""

    mu: float
    sigma: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mu) and math.isfinite(self.sigma) and self.sigma > 0):
            raise ValueError(f"Normal needs a finite mu and sigma > 0, got {self.mu}, {self.sigma}")

    def logpdf(self, x: ArrayLike) -> NDArray:
        z = (np.asarray(x, dtype=float) - self.mu) / self.sigma
        return -0.5 * z * z - math.log(self.sigma * math.sqrt(2.0 * math.pi))

    def sample(self, rng: np.random.Generator, size: int) -> NDArray:
        return rng.normal(self.mu, self.sigma, size)

    def describe(self) -> str:
        return f"Normal({self.mu:g}, {self.sigma:g})"


@dataclass(frozen=True)
class LogUniform(Prior):
    """Log-uniform (density ∝ 1/x) on [low, high], 0 < low < high."""

    low: float
    high: float

    def __post_init__(self) -> None:
        if not (0 < self.low < self.high and math.isfinite(self.high)):
            raise ValueError(f"LogUniform needs 0 < low < high, got [{self.low}, {self.high}]")

    def logpdf(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        inside = (x >= self.low) & (x <= self.high)
        safe = np.where(inside, x, 1.0)
        return np.where(inside, -np.log(safe) - math.log(math.log(self.high / self.low)), -np.inf)

    def sample(self, rng: np.random.Generator, size: int) -> NDArray:
        return np.exp(rng.uniform(math.log(self.low), math.log(self.high), size))

    def describe(self) -> str:
        return f"LogUniform({self.low:g}, {self.high:g})"


@dataclass(frozen=True)
class PriorSet:
    """Independent priors by parameter name, in sampling order."""

    priors: Mapping[str, Prior] = field(default_factory=dict)

    def __iter__(self) -> Iterator[str]:
        return iter(self.priors)

    def __len__(self) -> int:
        return len(self.priors)

    def __getitem__(self, name: str) -> Prior:
        return self.priors[name]

    @property
    def names(self) -> list[str]:
        """Parameter names in sampling order."""
        return list(self.priors)

    def replace(self, **priors: Prior) -> PriorSet:
        """A copy with some priors replaced (names must exist)."""
        unknown = set(priors) - set(self.priors)
        if unknown:
            raise ValueError(f"unknown parameter(s) {sorted(unknown)}; the fit has {self.names}")
        return PriorSet({**self.priors, **priors})

    def logpdf(self, theta: NDArray) -> NDArray:
        """Joint log density of parameter rows ``theta`` (shape (..., n_params))."""
        theta = np.asarray(theta, dtype=float)
        total = np.zeros(theta.shape[:-1])
        for i, prior in enumerate(self.priors.values()):
            total = total + prior.logpdf(theta[..., i])
        return total

    def sample(self, rng: np.random.Generator, size: int) -> NDArray:
        """Draws of shape (size, n_params)."""
        return np.column_stack([p.sample(rng, size) for p in self.priors.values()])

    def describe(self) -> dict[str, str]:
        """Text description of each prior."""
        return {name: p.describe() for name, p in self.priors.items()}

    def to_spec(self) -> dict[str, dict[str, float | str]]:
        """Plain-data description of every prior (JSON, NetCDF attributes)."""
        return {name: p.to_spec() for name, p in self.priors.items()}

    @classmethod
    def from_spec(cls, spec: Mapping[str, Mapping[str, float | str]]) -> PriorSet:
        """Rebuild a prior set written by :meth:`to_spec`."""
        return cls({name: Prior.from_spec(s) for name, s in spec.items()})


def default_priors(
    y0: float,
    *,
    friction: bool = True,
    discrepancy: bool = False,
    law: str | Law | None = None,
    y0_sd: float | None = None,
) -> PriorSet:
    """The documented default priors (see the module notes).

    Parameters
    ----------
    y0 : float
        Observed dimensionless displacement at the start of the analysed window.
    friction : bool
        False for a test without contact: the law's friction terms are dropped (for
        the default law only ζ (= ζ₀) and y0 are fitted).
    discrepancy : bool
        Add the model-discrepancy scales: the white one and the shape one.
    law : str or Law, optional
        The dissipation law whose parameters get their default priors (each term's
        :class:`~bayestribo.model.laws.Parameter` gives its own); default
        ``"viscous+coulomb"``.
    y0_sd : float, optional
        Standard deviation of y0's prior where the observed y(0) is known worse than
        1 % of it (a coarse displacement: :mod:`bayestribo.signal.coarse`); default
        1 % of |y0|.
    """
    amp = abs(float(y0))
    if not amp > 0:
        raise ValueError(f"y0 must be non-zero to set the default priors, got {y0!r}")
    the_law = get_law(law)
    priors: dict[str, Prior] = {}
    for term in the_law.terms:
        if term.kind == "friction" and not friction:
            continue
        for p in term.parameters:
            priors[p.name] = Prior.from_spec(p.prior(amp))
    if y0_sd is not None and not (math.isfinite(y0_sd) and y0_sd > 0):
        raise ValueError(f"y0_sd: expected a positive number, got {y0_sd!r}")
    priors["y0"] = Normal(float(y0), 0.01 * amp if y0_sd is None else float(y0_sd))
    if discrepancy:
        priors["log10_discrepancy"] = Uniform(-7.0, 0.0)
        priors["log10_shape"] = Uniform(-7.0, 0.0)
    return PriorSet(priors)


#: Sampled parameters whose default upper bound is a belief about contacts, not a
#: physical limit, with that bound: a record may ask for more (μ_s/μ_k: a lubricated
#: contact may stick at twenty times its kinetic friction), and a posterior on it is
#: answered by a wider prior.
BELIEF_BOUNDS = {"mu_s_ratio": 10.0}
#: Factor by which the advice widens such a bound.
WIDEN = 4.0


def widened_prior(name: str, prior: Prior, needed: float | None = None) -> str | None:
    """The ``--prior`` value that widens the default upper bound of a parameter of
    :data:`BELIEF_BOUNDS` by :data:`WIDEN` (``mu_s_ratio=Uniform(1,40)``), or to 1.5×
    ``needed`` (rounded up to two significant digits) where that is more (a value the
    record is known to ask for: :mod:`bayestribo.inference.stop_prior`); None for any
    other parameter (its default bound is a physical limit: the data asking for more
    say that a unit, a channel or the record is wrong), another kind of prior, or a
    bound already beyond the default (the advice is given once: a posterior that piles
    on the widened bound too asks for more than sticking).

    Examples
    --------
    >>> widened_prior("mu_s_ratio", Uniform(1.0, 10.0))
    'mu_s_ratio=Uniform(1,40)'
    >>> widened_prior("mu_s_ratio", Uniform(1.0, 10.0), needed=31.2)
    'mu_s_ratio=Uniform(1,47)'
    >>> widened_prior("mu_s_ratio", Uniform(1.0, 40.0)) is None
    True
    >>> widened_prior("zeta", Uniform(0.0, 0.3)) is None
    True
    """
    default = BELIEF_BOUNDS.get(name)
    if default is None or not isinstance(prior, Uniform | LogUniform) or prior.high > default:
        return None
    high = WIDEN * prior.high
    if needed is not None and math.isfinite(needed) and 1.5 * needed > high:
        digits = 10.0 ** (math.floor(math.log10(1.5 * needed)) - 1)
        high = math.ceil(1.5 * needed / digits) * digits
    return f"{name}={type(prior).__name__}({prior.low:g},{high:g})"


def piled_on_bounds(draws: NDArray, priors: PriorSet) -> list[dict[str, float | str]]:
    """Parameters whose posterior piles on the upper bound of a uniform prior.

    The upper bounds of the default priors are physical limits, not beliefs: a
    friction of a quarter of the initial amplitude stops the motion within two half
    cycles, and ζ = 0.3 leaves no decay of several cycles to analyse. A posterior
    held against such a bound is no measurement: the data ask for a value the motion
    cannot have (a unit or a channel wrong, or a recording that is not a free decay).
    A parameter piles on its bound when more than :data:`BOUND_FRACTION` of the draws
    lie within :data:`BOUND_WIDTH` of the prior range below it. Lower bounds (ζ = 0,
    μ_k = 0, μ_s = μ_k) are physical values a posterior may legitimately reach.

    Parameters
    ----------
    draws : ndarray of shape (n, d)
        Posterior draws of the sampled parameters, in ``priors`` order.
    priors : PriorSet
        Their priors.

    Returns
    -------
    list of dict
        One ``{"parameter", "bound", "fraction"}`` per parameter on its bound.
    """
    draws = np.asarray(draws, dtype=float)
    out: list[dict[str, float | str]] = []
    for i, name in enumerate(priors.names):
        prior = priors[name]
        if not isinstance(prior, Uniform | LogUniform):
            continue
        edge = prior.high - BOUND_WIDTH * (prior.high - prior.low)
        fraction = float(np.mean(draws[:, i] >= edge))
        if fraction > BOUND_FRACTION:
            out.append({"parameter": name, "bound": float(prior.high), "fraction": fraction})
    return out
