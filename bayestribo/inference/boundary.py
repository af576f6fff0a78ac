"""A truth on the boundary of the default law: no friction, or no viscous damping.

The default law ``viscous+coulomb`` samples ζ ≥ 0 and μ_k ≥ 0 (or the friction
displacement x_c ≥ 0). On an oscillator without friction (x_c = 0) or without drag
(ζ = 0) the truth sits on that bound, the two parameters are anticorrelated, and the
posterior's mass inside the bound pulls the other parameter's interval off the truth: ζ's
95 % interval of a linear oscillator ends below its ζ in most runs
(``benchmarks/boundary_truth.py``).

The honest answer gives the nested law (the law without the term) a point mass: a prior
probability of 1/2 that the term is absent. Its posterior probability comes from the
sampled fit by the Savage–Dickey density ratio

    B₀₁ = p(θ = 0 | data) / p(θ = 0),    P(nested | data) = B₀₁ / (1 + B₀₁),

the posterior density of the term's parameter θ at 0 (:func:`boundary_density`, a
boundary-corrected estimate) over its prior density there (the priors are independent,
so the nested law's prior is the full one's at θ = 0). Where that probability is at
least :data:`THRESHOLD`, the nested law is fitted too and the reported draws are a
mixture: that share of the draws, at most :data:`MAX_SHARE`, are the nested fit's
(θ = 0; the parameters the nested law does not have keep the full fit's draws), the
rest the full fit's, so every interval (ζ, x_c or μ_k, μ_s, ΔE(A)) is the average's.
Both boundaries can be probable on one record (one that cannot tell friction from
drag): each nested law then makes half the draws. Where neither is, the fit is the full
law's, unchanged (no draw, no refit).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from bayestribo.inference.types import Sampled

__all__ = [
    "MAX_SHARE",
    "NESTED",
    "THRESHOLD",
    "BoundaryDensity",
    "boundary_density",
    "boundary_mixture",
    "describe",
    "nested_probability",
]

#: The default law's parameters whose 0 drops a term, and the law without it.
NESTED: dict[str, str] = {"mu_k": "viscous", "zeta": "coulomb"}
#: The law whose boundaries are averaged over.
DEFAULT_LAW = "viscous+coulomb"
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


def _candidates(sampled: Sampled) -> dict[str, dict[str, float]]:
    """The nested-law probability of each of the default law's boundary parameters
    that is sampled with a prior of positive density at 0 (none where a parameter of
    the law is fixed, or friction is dropped for a run without contact)."""
    posterior = sampled.posterior
    laws = {p.name for p in posterior.law.parameters}
    if posterior.law.name != DEFAULT_LAW or laws & set(posterior.fixed):
        return {}  # another law, or one of its parameters held at a value
    if not set(NESTED) <= set(posterior.names):
        return {}  # a run without contact: friction dropped, the viscous law alone
    chains = sampled.run.chains
    flat = chains.reshape(-1, chains.shape[-1])
    out = {}
    for name in NESTED:
        if name not in posterior.names:
            continue
        prior_density = float(np.exp(posterior.priors[name].logpdf(0.0)))
        column = flat[:, posterior.names.index(name)]
        if not prior_density > 0.0 or np.any(column < 0):
            continue
        ess = sampled.run.ess[posterior.names.index(name)]
        out[name] = nested_probability(column, prior_density, float(ess))
    return out


def boundary_mixture(
    sampled: Sampled,
    fit_nested: Callable[[str], Sampled],
    rng_of: Callable[[], np.random.Generator],
) -> tuple[Sampled, dict[str, Any] | None]:
    """The draws to report for a fit of the default law, and the record of its
    boundaries.

    Each boundary whose nested law has a posterior probability of at least
    :data:`THRESHOLD` takes that share of the draws, at most :data:`MAX_SHARE`; both
    can (a record that cannot tell friction from viscous damping: half the draws each).

    Parameters
    ----------
    sampled : Sampled
        The full law's checked sample.
    fit_nested : callable
        Called with a nested law's name (:data:`NESTED`), it samples that law on the
        same prepared run and returns its :class:`Sampled`.
    rng_of : callable
        Called once where the draws are mixed: the generator that picks them.

    Returns
    -------
    Sampled, dict or None
        The sample to summarise (``sampled`` itself where the nested laws are
        improbable) and the record: ``parameters``, per boundary parameter (``mu_k``,
        ``zeta``) its density ratio and probability; ``mixed``, the parameters whose
        nested law was mixed in (empty: the full law's draws as sampled); ``nested``,
        per one of those its ``law``, ``share`` of the draws and whether its fit
        ``converged``; ``full_share``. None for a law other than the default, the
        default with one of its parameters fixed, or a run without contact (friction
        dropped).
    """
    candidates = _candidates(sampled)
    if not candidates:
        return sampled, None
    shares = {
        name: min(c["probability"], MAX_SHARE)
        for name, c in candidates.items()
        if c["probability"] >= THRESHOLD
    }
    record: dict[str, Any] = {
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
    nested = {name: fit_nested(NESTED[name]) for name in sorted(shares)}
    record["nested"] = {
        name: {
            "law": NESTED[name],
            "share": shares[name],
            "converged": bool(fit.run.converged),
        }
        for name, fit in nested.items()
    }
    return _mixed(sampled, nested, shares, rng_of()), record


def _mixed(
    full: Sampled,
    nested: Mapping[str, Sampled],
    shares: Mapping[str, float],
    rng: np.random.Generator,
) -> Sampled:
    """``full`` with the share ``shares[name]`` of its draws, picked at random (apart
    for each name), replaced by draws of ``nested[name]`` set in the full law's
    coordinates (``name`` at 0; the coordinates the nested law does not have keep the
    full law's draws)."""
    run = full.run
    names = full.posterior.names
    chains = run.chains.reshape(-1, len(names)).copy()
    n = chains.shape[0]
    order = rng.permutation(n)
    first = 0
    replaced = []
    for name in sorted(shares):
        k = round(shares[name] * n)
        rows = np.sort(order[first : first + k])
        first += k
        replaced.append(rows)
        fit = nested[name]
        source = fit.run.chains.reshape(-1, fit.run.chains.shape[-1])
        picked = source[rng.choice(source.shape[0], size=k, replace=k > source.shape[0])]
        nested_names = fit.posterior.names
        for j, col in enumerate(names):
            if col == name:
                chains[rows, j] = 0.0
            elif col in nested_names:
                chains[rows, j] = picked[:, nested_names.index(col)]
    rows = np.concatenate(replaced)
    log_prob = np.asarray(run.log_prob, dtype=float)
    if log_prob.shape == run.chains.shape[:2] and rows.size:
        log_prob = log_prob.reshape(-1).copy()
        log_prob[rows] = full.posterior(chains[rows])
        log_prob = log_prob.reshape(run.chains.shape[:2])
    new_run = dataclasses.replace(run, chains=chains.reshape(run.chains.shape), log_prob=log_prob)
    return dataclasses.replace(full, run=new_run, pointwise=None)


_WHAT = {"mu_k": "no friction (x_c or μ_k = 0)", "zeta": "no viscous damping (ζ = 0)"}


def describe(record: Mapping[str, Any] | None) -> str | None:
    """One line on what was done at the boundaries (None where nothing was mixed)."""
    if not record or not record.get("mixed"):
        return None
    parts = []
    for name in record["mixed"]:
        nested = record["nested"][name]
        probability = record["parameters"][name]["probability"]
        parts.append(
            f"{_WHAT[name]} has posterior probability {probability:.2f}: the {nested['law']} "
            f"law's fit makes {nested['share']:.0%} of the draws"
            + ("" if nested.get("converged", True) else " (that fit did not converge)")
        )
    return (
        "; ".join(parts)
        + f" (Savage–Dickey ratio, prior 1/2); the intervals average it with {DEFAULT_LAW}'s"
    )
