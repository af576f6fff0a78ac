"""A truth on a boundary of the law: a term the record does not have.

A law of several terms samples each term's amount (its *amount* parameter,
:attr:`bayestribo.model.laws.base.Term.amount`: ζ, μ_k or the friction displacement x_c,
c₂, ζ_α, ...) on a prior bounded below by the value that removes the term. On a record
without that term (an oscillator without friction, without viscous damping, without
quadratic drag) the truth sits on the bound, the amount is anticorrelated with the other
terms', and the posterior's mass inside the bound pulls the others' intervals off the
truth: ζ's 95 % interval of a linear oscillator fitted with ``viscous+coulomb`` ends
below its ζ in most runs (``benchmarks/boundary_truth.py``), and so do ζ's with
``viscous+quadratic`` and x_c's with ``coulomb+quadratic`` (``benchmarks/boundary_laws.py``).

The honest answer gives each nested law (the law without one term,
:attr:`bayestribo.model.laws.Law.boundaries`) a point mass: a prior probability of 1/2
that the term is absent. Its posterior probability comes from the sampled fit by the
Savage–Dickey density ratio

    B₀₁ = p(θ = 0 | data) / p(θ = 0),    P(nested | data) = B₀₁ / (1 + B₀₁),

the posterior density of the term's amount θ at its bound (:func:`boundary_density`, a
boundary-corrected estimate) over its prior density there (the priors are independent,
so the nested law's prior is the full one's at θ = 0). Where that probability is at
least :data:`THRESHOLD`, the nested law is fitted too and the reported draws are a
mixture: that share of the draws, at most :data:`MAX_SHARE`, are the nested fit's
(θ = 0; the parameters the nested law does not have, such as μ_s/μ_k without μ_k or α
without ζ_α, keep the full fit's draws), the rest the full fit's, so every interval is
the average's. Several boundaries can be probable on one record (one that cannot tell
friction from drag): each nested law makes its share; where three or more shares add
up to more than all the draws, each is scaled down in proportion (:func:`_shares`). A
nested law of several terms is averaged over its own boundaries the same way before it
is mixed in (``viscous+coulomb+quadratic`` on a record of viscous damping alone: its
nested ``viscous+coulomb`` and ``viscous+quadratic`` each mix ``viscous`` in), each
nested law fitted once. Where no boundary is probable, the fit is the full law's,
unchanged (no draw, no refit).

Not averaged: a law of one term (without it there is no law), a fit with one of the
law's parameters fixed, the law-free fit (its answer is ΔE(A), not its coefficients),
and ``law="auto"`` (:mod:`bayestribo.inference.comparison`): the laws it compares hold
every law nested in each of them (:mod:`bayestribo.model.laws.candidates`), a law whose
optimum puts a term on its bound reduces to the nested law
(:mod:`bayestribo.inference.reduction`), and the simplest law as good as the best is
kept, so a term on its bound is dropped by the choice; averaging the chosen law again
would count the nested laws twice. A term that declares no amount (η of a friction that
varies with amplitude, whose 0 is inside its prior) has no boundary.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.inference.types import Sampled
from bayestribo.model.laws import TERMS, get_law

__all__ = [
    "MAX_SHARE",
    "THRESHOLD",
    "BoundaryDensity",
    "boundary_density",
    "boundary_mixture",
    "describe",
    "nested_probability",
]

#: Posterior probability of the nested law below which the full law's fit stands.
THRESHOLD = 0.01
#: The largest share of the reported draws a nested law's fit takes: its prior
#: probability. The Savage–Dickey probability of a law nested in one with a wide prior
#: tends to 1 wherever the data cannot tell the two apart (the wider the prior, the
#: nearer), and the nested fit's intervals alone then miss a term that is small but
#: there (x_c's interval [0, 0]). At a half share, a truth on the boundary has the
#: other parameter's interval end at the nested fit's 95 % quantile, and a truth just
#: inside it has the full fit's 95 % quantile bound the other side: each a one-sided 5 %
#: miss (benchmarks/README.md: 18-20 of 20 in every design measured).
MAX_SHARE = 0.5
#: Width of the estimate's first window, as a fraction of the draws' median distance
#: from the bound, times n^(-1/5).
_WIDTH = 1.0


@dataclass(frozen=True)
class BoundaryDensity:
    """A density at a bound estimated from draws.

    Attributes
    ----------
    density : float
        The estimate at the bound [1/unit of the draws], 0 or more.
    se : float
        Its standard error from the counts (independent draws) [1/unit].
    width : float
        The window h: the estimate takes the draws within 2h of the bound [unit].
    """

    density: float
    se: float
    width: float


def boundary_density(draws: ArrayLike, low: float = 0.0) -> BoundaryDensity:
    """Density at ``low`` of draws of a distribution supported on [low, ∞).

    A density linear near the bound, f(x) = a + b(x - low), puts F(h) = ah + bh²/2
    and F(2h) = 2ah + 2bh² of the probability within h and 2h of it, so

        a = (4 F(h) - F(2h)) / (2h),

    exact for a linear density (the reflection estimate is biased by its slope), taken
    with the empirical fractions. The window h is the draws' median distance from the
    bound times n^(-1/5); the estimate is clipped at 0.

    Parameters
    ----------
    draws : array_like
        Draws, every one at or above ``low`` [unit].
    low : float
        The bound [unit].

    Returns
    -------
    BoundaryDensity
        The estimate [1/unit], its standard error and the window.

    Raises
    ------
    ValueError
        With fewer than 10 draws, or a draw below ``low``.
    """
    x = np.asarray(draws, dtype=float).ravel() - low
    n = x.size
    if n < 10:
        raise ValueError(f"draws: at least 10 needed, got {n}")
    if np.any(x < 0):
        raise ValueError("draws: every draw must be at or above the bound")
    median = float(np.median(x))
    if median <= 0.0:  # half the draws on the bound: a point mass, no density
        return BoundaryDensity(math.inf, math.inf, 0.0)
    h = _WIDTH * median * n ** (-0.2)
    first = int(np.count_nonzero(x <= h))
    second = int(np.count_nonzero((x > h) & (x <= 2 * h)))
    density = (3 * first - second) / (2 * h * n)
    se = math.sqrt(9 * first + second) / (2 * h * n)
    return BoundaryDensity(max(density, 0.0), se, h)


def nested_probability(
    draws: ArrayLike, prior_density: float, effective: float | None = None
) -> dict[str, float]:
    """Posterior probability of the nested law (the parameter at 0) at prior odds 1,
    from the Savage–Dickey density ratio.

    Parameters
    ----------
    draws : array_like
        The full law's draws of the parameter (0 or more) [unit].
    prior_density : float
        Its prior density at 0 [1/unit], above 0.
    effective : float, optional
        Effective number of the draws, to scale the standard error (default: all).

    Returns
    -------
    dict
        ``posterior_density``, its ``se`` [1/unit], ``prior_density`` [1/unit],
        ``density_ratio`` B₀₁ [-] and ``probability`` B₀₁/(1 + B₀₁) [-].
    """
    x = np.asarray(draws, dtype=float).ravel()
    est = boundary_density(x)
    se = est.se
    if effective is not None and 0 < effective < x.size:
        se *= math.sqrt(x.size / effective)
    ratio = est.density / prior_density
    probability = 1.0 if math.isinf(ratio) else ratio / (1.0 + ratio)
    return {
        "posterior_density": est.density,
        "se": se,
        "prior_density": prior_density,
        "density_ratio": ratio,
        "probability": probability,
    }


def _candidates(sampled: Sampled) -> dict[str, dict[str, Any]]:
    """The nested law's probability at each boundary of the sampled law
    (:attr:`~bayestribo.model.laws.Law.boundaries`) whose parameter is sampled with a
    prior of positive density at its bound: with the name of the law without the term
    (``law``). None where one of the law's parameters is fixed, the law-free fit, or a
    law that has fewer than two of its terms sampled (a run without contact: friction
    dropped)."""
    posterior = sampled.posterior
    law = posterior.law
    if {p.name for p in law.parameters} & set(posterior.fixed) or law.name == _free():
        return {}  # one of its parameters held at a value, or the law-free fit
    names = posterior.names
    present = [t for t in law.terms if all(p.name in names for p in t.parameters)]
    if len(present) < 2:
        return {}  # a run without contact: friction dropped, one term left
    chains = sampled.run.chains
    flat = chains.reshape(-1, chains.shape[-1])
    out = {}
    for term in present:
        name = term.amount
        if name is None:
            continue
        bound = law.parameter(name).low
        prior_density = float(np.exp(posterior.priors[name].logpdf(bound)))
        column = flat[:, names.index(name)] - bound
        if not prior_density > 0.0 or np.any(column < 0):
            continue
        ess = sampled.run.ess[names.index(name)]
        out[name] = nested_probability(column, prior_density, float(ess))
        out[name]["law"] = law.boundaries[name]
    return out


def _free() -> str:
    """The name of the law-free fit's law."""
    return get_law("free").name


def _shares(candidates: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """Each probable nested law's share of the draws: its probability, at most
    :data:`MAX_SHARE`; where those add up to more than 1 (three or more probable
    boundaries), each scaled down in proportion so that they make all the draws."""
    shares = {
        name: min(c["probability"], MAX_SHARE)
        for name, c in candidates.items()
        if c["probability"] >= THRESHOLD
    }
    total = sum(shares.values())
    if total > 1.0:
        shares = {name: share / total for name, share in shares.items()}
    return shares


def boundary_mixture(
    sampled: Sampled,
    fit_nested: Callable[[str], Sampled],
    rng_of: Callable[[], np.random.Generator],
) -> tuple[Sampled, dict[str, Any] | None]:
    """The draws to report for a fit of a law of several terms, and the record of its
    boundaries.

    Each boundary whose nested law has a posterior probability of at least
    :data:`THRESHOLD` takes that share of the draws, at most :data:`MAX_SHARE`
    (several can: :func:`_shares`). A nested law of several terms is averaged over its
    own boundaries the same way before it is mixed in (each nested law is fitted once,
    however many laws nest it).

    Parameters
    ----------
    sampled : Sampled
        The full law's checked sample.
    fit_nested : callable
        Called with a nested law's name (:attr:`~bayestribo.model.laws.Law.boundaries`),
        it samples that law on the same prepared run and returns its :class:`Sampled`.
    rng_of : callable
        Called once for each mixture made: the generator that picks its draws.

    Returns
    -------
    Sampled, dict or None
        The sample to summarise (``sampled`` itself where the nested laws are
        improbable) and the record: ``law``, the law averaged; ``parameters``, per
        boundary parameter (``mu_k``, ``zeta``, ``c2``, ...) its density ratio,
        probability and nested ``law``; ``mixed``, the parameters whose nested law was
        mixed in (empty: the full law's draws as sampled); ``nested``, per one of those
        its ``law``, ``share`` of the draws, whether its fit ``converged`` and, where it
        was averaged over its own boundaries, its ``boundary`` record; ``full_share``.
        None for a law of one term, a law with one of its parameters fixed, the
        law-free fit, or a run without contact where friction dropped leaves one term.
    """
    return _average(sampled, fit_nested, rng_of, {})


def _average(
    sampled: Sampled,
    fit_nested: Callable[[str], Sampled],
    rng_of: Callable[[], np.random.Generator],
    done: dict[str, _Nested],
) -> tuple[Sampled, dict[str, Any] | None]:
    """:func:`boundary_mixture`, with the nested laws already fitted (and averaged)
    by name in ``done``."""
    candidates = _candidates(sampled)
    if not candidates:
        return sampled, None
    shares = _shares(candidates)
    record: dict[str, Any] = {
        "law": sampled.posterior.law.name,
        "prior_probability": 0.5,
        "threshold": THRESHOLD,
        "max_share": MAX_SHARE,
        "parameters": candidates,
        "mixed": sorted(shares),
        "nested": {},
        "full_share": 1.0 - sum(shares.values()),
    }
    if not shares:
        return sampled, record
    for name in sorted(shares):
        law = candidates[name]["law"]
        if law not in done:
            fit = fit_nested(law)
            averaged, inner = _average(fit, fit_nested, rng_of, done)
            done[law] = _Nested(averaged, inner, bool(fit.run.converged))
        nested = done[law]
        record["nested"][name] = {
            "law": law,
            "share": shares[name],
            "converged": nested.converged,
            **({"boundary": nested.record} if nested.record is not None else {}),
        }
    draws = {name: done[candidates[name]["law"]].sampled for name in shares}
    return _mixed(sampled, draws, shares, rng_of()), record


@dataclass(frozen=True)
class _Nested:
    """A nested law's fit as mixed in: its draws (averaged over its own boundaries),
    that averaging's record, and whether its sampler converged."""

    sampled: Sampled
    record: dict[str, Any] | None
    converged: bool


def _mixed(
    full: Sampled,
    nested: Mapping[str, Sampled],
    shares: Mapping[str, float],
    rng: np.random.Generator,
) -> Sampled:
    """``full`` with the share ``shares[name]`` of its draws, picked at random (apart
    for each name), replaced by draws of ``nested[name]`` set in the full law's
    coordinates (``name`` on its bound, 0; the coordinates the nested law does not have keep the
    full law's draws).

    The full posterior's log density at the draws replaced is left to
    ``log_prob_deferred`` (:class:`~bayestribo.inference.types.Sampled`), computed
    where it is read (the InferenceData's ``sample_stats``): no answer uses it, and for
    a law without a closed form it is the exact integration of every such draw (0.27 s
    of a 0.6 s fit of ``viscous+coulomb+quadratic`` on the bundled run in air)."""
    run = full.run
    names = full.posterior.names
    law = full.posterior.law
    chains = run.chains.reshape(-1, len(names)).copy()
    n = chains.shape[0]
    order = rng.permutation(n)
    first = 0
    replaced = []
    for name in sorted(shares):
        k = min(round(shares[name] * n), n - first)
        rows = np.sort(order[first : first + k])
        first += k
        replaced.append(rows)
        fit = nested[name]
        source = fit.run.chains.reshape(-1, fit.run.chains.shape[-1])
        picked = source[rng.choice(source.shape[0], size=k, replace=k > source.shape[0])]
        nested_names = fit.posterior.names
        for j, col in enumerate(names):
            if col == name:
                chains[rows, j] = law.parameter(name).low
            elif col in nested_names:
                chains[rows, j] = picked[:, nested_names.index(col)]
    rows = np.concatenate(replaced)
    log_prob = np.asarray(run.log_prob, dtype=float)
    deferred = None
    if log_prob.shape == run.chains.shape[:2] and rows.size:
        log_prob = log_prob.reshape(-1).copy()
        log_prob[rows] = np.nan
        log_prob = log_prob.reshape(run.chains.shape[:2])
        deferred = _LogProb(full.posterior, log_prob.copy(), rows, chains[rows].copy())
    new_run = dataclasses.replace(run, chains=chains.reshape(run.chains.shape), log_prob=log_prob)
    return dataclasses.replace(full, run=new_run, pointwise=None, log_prob_deferred=deferred)


@dataclass(frozen=True)
class _LogProb:
    """The log posterior density of every draw of a mixture (:func:`_mixed`): the
    sampler's where it kept the full law's draw, ``posterior`` evaluated at the
    ``points`` set in the rows ``rows`` (of the flattened draws) when called."""

    posterior: Callable[[NDArray], NDArray]
    known: NDArray
    rows: NDArray
    points: NDArray

    def __call__(self) -> NDArray:
        lp = self.known.reshape(-1).copy()
        lp[self.rows] = self.posterior(self.points)
        return lp.reshape(self.known.shape)


def describe(record: Mapping[str, Any] | None) -> str | None:
    """One line on what was done at the boundaries (None where nothing was mixed)."""
    if not record or not record.get("mixed"):
        return None
    # a record saved before other laws were averaged has no "law": the default law's
    law = record.get("law", "viscous+coulomb")
    return (
        _described(record)
        + f" (Savage–Dickey ratio, prior 1/2); the intervals average it with {law}'s"
    )


def _described(record: Mapping[str, Any]) -> str:
    """What :func:`describe` says of one averaging (and of the nested laws' own)."""
    parts = []
    for name in record["mixed"]:
        nested = record["nested"][name]
        probability = record["parameters"][name]["probability"]
        part = (
            f"{_absent(name)} has posterior probability {probability:.2f}: the "
            f"{nested['law']} law's fit makes {nested['share']:.0%} of the draws"
            + ("" if nested.get("converged", True) else " (that fit did not converge)")
        )
        inner = nested.get("boundary")
        if inner and inner.get("mixed"):
            part += f" (itself averaged: {_described(inner)}; with {inner['law']}'s)"
        parts.append(part)
    return "; ".join(parts)


def _absent(name: str) -> str:
    """How a report says the term whose amount is ``name`` is absent."""
    for term in TERMS.values():
        if term.amount == name:
            return term.absent
    return f"{name} = 0"
