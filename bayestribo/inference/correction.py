r"""Draws of a surrogate posterior corrected to the exact one by importance resampling.

A quadratic surrogate of Π (:mod:`bayestribo.inference.surrogate`) whose check fails
by a little still puts its draws where the exact posterior's mass is: on the AppStat
HarmOsc2 recording, ``coulomb+power``'s surrogate misfits Π by 0.05 noise sd on the
three increments before the motion sticks, where the stop crosses a grid point and Π
has a kink, and its importance weights vary by 8 % (against the check's limit of 5 %)
however often it is fitted again. Sampling the exact posterior instead cost 15 s of
CPU a time, three times in ``law="auto"``.

The correction (Vihola, Helske & Franks 2020, *Scand. J. Stat.* 47, 1339: the
importance-sampling correction of approximate Markov chain Monte Carlo is consistent
for the exact posterior): the exact log posterior is evaluated at every draw of the
surrogate's run, the weights ``w = p(θ)/p̃(θ)`` formed, and each ensemble's draws
resampled in their order by systematic resampling (a draw of weight above the
ensemble's mean kept once or twice, one below kept or dropped), so that the chains
stay chains (R-hat, the effective sample size and PSIS-LOO read them as before) and
their draws are of the exact posterior to the resampling's Monte Carlo error. The
correction is kept only when it is reliable:

* every weight finite (the surrogate covers the exact posterior's support);
* the weights' coefficient of variation over all draws at most
  :data:`MAX_CORRECTED_CV` (Kish's effective sample size at least 1/(1 + 0.3²) = 92 %
  of the draws): the resampled ensembles' effective sample size is the run's times
  that fraction;
* the Pareto k̂ of the weights' upper tail (:func:`bayestribo.inference.loo.psis`)
  at most :data:`MAX_PARETO_K`: the weights have a finite variance, so the cv measured
  is the cv there is (a surrogate that misses a region of the exact mass shows there
  as a heavy tail of the weights before it shows in their cv);
* the resampled chains' R-hat no larger than the run's limit where the run's was.

Otherwise the surrogate is fitted again or the exact posterior sampled, as before. A
surrogate fitted again whose check came near the correction's reach (cv at most
:data:`NEAR_CORRECTED_CV`) is given up to :data:`CORRECTING_ATTEMPTS` surrogates in all
rather than :data:`bayestribo.inference.surrogate.ATTEMPTS`: on the second half of
HarmOsc2 under ``coulomb+power`` the regressed surrogates' cv goes 0.13-0.51 from one
to the next (each fitted to 128 draws of the one before, at a kink of Π), so that one
seed in a few met a correction refused (cv 0.32 and k̂ 0.54, a little over their
limits) or checks just beyond the reach (cv 0.35, then 0.37), and sampled the exact
posterior: 9.5 s of CPU, where each further surrogate costs 0.2 s and its correction
1.1 s.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.likelihood import Params, PiLikelihood
from bayestribo.inference.sampling import SamplerRun, rhat

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior

__all__ = [
    "CORRECTING_ATTEMPTS",
    "MAX_CORRECTED_CV",
    "MAX_PARETO_K",
    "MAX_WEIGHTED_CV",
    "NEAR_CORRECTED_CV",
    "Correction",
    "evenly_spaced",
    "exact_density",
    "importance_corrected",
    "resample_in_order",
    "weights_at",
]

#: Largest coefficient of variation of the importance weights over all draws at which
#: the resampled draws are kept (at least 92 % of the draws' effective size).
MAX_CORRECTED_CV = 0.3
#: Largest Pareto k̂ of the weights' tail (finite variance below 1/2).
MAX_PARETO_K = 0.5
#: Surrogates built and checked, once one built again has come near the correction's
#: reach (weights' cv at most :data:`NEAR_CORRECTED_CV`), before the exact posterior is
#: sampled instead (:data:`bayestribo.inference.surrogate.ATTEMPTS` otherwise).
CORRECTING_ATTEMPTS = 5
#: Weights' cv of a surrogate built again within one refit of the correction's reach:
#: from one regressed surrogate to the next the cv varies by a factor of about two
#: (0.13-0.51 on HarmOsc2's second half under ``coulomb+power``).
NEAR_CORRECTED_CV = 2.0 * MAX_CORRECTED_CV
#: Largest coefficient of variation of the importance weights of draws that a caller
#: uses weighted and counts by Kish's effective number (:func:`weights_at` with
#: ``max_cv``; the halves' ΔE(A), :mod:`bayestribo.inference.halves`): at least
#: 1/(1 + 0.6²) = 74 % of the draws count, and the weights' Pareto k̂ of at most
#: :data:`MAX_PARETO_K` keeps their variance finite, so that Kish's number gives the
#: weighted means' Monte Carlo error to within some 15 % of its sd (the halves' z over
#: fresh weighted draws at this cv: tests/test_inference_halves_statistic.py).
MAX_WEIGHTED_CV = 2.0 * MAX_CORRECTED_CV


@dataclasses.dataclass(frozen=True)
class Correction:
    """An importance-resampled run and the weights' statistics.

    Attributes
    ----------
    run : SamplerRun
        The resampled chains, their exact log posterior, the effective sample size
        scaled by Kish's fraction and R-hat recomputed.
    weight_cv : float
        Coefficient of variation of the weights over all draws.
    log_weight_sd : float
        Standard deviation of the log weights.
    pareto_k : float
        Pareto k̂ of the weights' upper tail.
    draws : int
        Draws weighted.
    pointwise : ndarray or None
        The exact pointwise log-likelihood of the resampled draws, (chains, draws, m),
        where the density gave it.
    """

    run: SamplerRun
    weight_cv: float
    log_weight_sd: float
    pareto_k: float
    draws: int
    pointwise: NDArray | None = dataclasses.field(default=None, repr=False)


def resample_in_order(weights: NDArray, u: float) -> NDArray:
    """Systematic resampling that keeps the draws' order.

    Parameters
    ----------
    weights : ndarray
        Non-negative weights of n draws, (n,), not all zero.
    u : float
        The one uniform offset in [0, 1).

    Returns
    -------
    ndarray
        n indices, non-decreasing: draw i appears ``floor`` or ``ceil`` of
        ``n w_i / Σw`` times.
    """
    w = np.asarray(weights, dtype=float)
    n = w.size
    edges = np.cumsum(w) * (n / float(np.sum(w)))
    return np.minimum(np.searchsorted(edges, np.arange(n) + u, side="right"), n - 1)


def importance_corrected(
    run: SamplerRun,
    exact: Callable[[NDArray], tuple[NDArray, NDArray | None]],
    rng: np.random.Generator,
    rhat_max: float,
) -> Correction | None:
    """The surrogate's run resampled to the exact posterior (module notes).

    Parameters
    ----------
    run : SamplerRun
        The surrogate posterior's run; its ``log_prob`` the surrogate's log density of
        each draw.
    exact : callable
        Rows (k, d) -> the exact log posterior of each, (k,), and the exact pointwise
        log-likelihood of each row's increments, (k, m), or None
        (:func:`exact_density`).
    rng : Generator
        The resampling's offsets (one per ensemble).
    rhat_max : float
        The run's R-hat limit.

    Returns
    -------
    Correction or None
        None when the correction is not reliable (module notes).
    """
    from bayestribo.inference.loo import psis

    chains = np.asarray(run.chains, dtype=float)
    surrogate_lp = np.asarray(run.log_prob, dtype=float)
    if chains.ndim != 3 or surrogate_lp.shape != chains.shape[:2] or chains.shape[1] < 4:
        return None
    flat = chains.reshape(-1, chains.shape[-1])
    exact_lp, exact_pointwise = exact(flat)
    exact_lp = np.asarray(exact_lp, dtype=float).reshape(surrogate_lp.shape)
    log_w = exact_lp - surrogate_lp
    if not np.all(np.isfinite(log_w)):
        return None
    w = np.exp(log_w - log_w.max())
    cv = float(np.std(w) / np.mean(w))
    _, k = psis(log_w.reshape(1, -1), 1.0)
    pareto_k = float(np.ravel(k)[0])
    if not (cv <= MAX_CORRECTED_CV and pareto_k <= MAX_PARETO_K):
        return None
    picks = [resample_in_order(w[e], float(rng.uniform())) for e in range(chains.shape[0])]
    new_chains = np.stack([chains[e, p] for e, p in enumerate(picks)])
    new_lp = np.stack([exact_lp[e, p] for e, p in enumerate(picks)])
    pointwise = None
    if exact_pointwise is not None:
        table = np.asarray(exact_pointwise, dtype=float).reshape(*chains.shape[:2], -1)
        pointwise = np.stack([table[e, p] for e, p in enumerate(picks)])
    new_rhat = rhat(new_chains)
    old_ok = np.asarray(run.rhat) <= rhat_max
    if np.any(old_ok & ~(np.asarray(new_rhat) <= rhat_max)):
        return None
    corrected = dataclasses.replace(
        run,
        chains=new_chains,
        log_prob=new_lp,
        ess=np.asarray(run.ess, dtype=float) / (1.0 + cv * cv),
        rhat=new_rhat,
    )
    return Correction(corrected, cv, float(np.std(log_w)), pareto_k, int(flat.shape[0]), pointwise)


def evenly_spaced(run: SamplerRun, count: int) -> NDArray:
    """Flat indices of ``count`` draws of ``run`` evenly spaced over every chain (all of
    them when it has fewer), in the order of ``run.chains.reshape(-1, d)``."""
    total = run.chains.shape[0] * run.chains.shape[1]
    return np.linspace(0, total - 1, min(count, total)).astype(int)


def weights_at(
    run: SamplerRun, posterior: Posterior, picks: NDArray, max_cv: float = MAX_CORRECTED_CV
) -> NDArray | None:
    """Importance weights exact/surrogate of the draws ``picks`` (flat indices) of a
    surrogate's run, for a caller that uses those draws alone, weighted, rather than
    every draw resampled (:func:`importance_corrected`).

    Parameters
    ----------
    run : SamplerRun
        The surrogate posterior's run; its ``log_prob`` the surrogate's log density.
    posterior : Posterior
        The exact posterior.
    picks : ndarray
        Flat indices of the draws weighted (:func:`evenly_spaced`).
    max_cv : float
        The largest coefficient of variation of the weights kept:
        :data:`MAX_CORRECTED_CV` (the correction's own), or :data:`MAX_WEIGHTED_CV` for
        a caller that counts the draws by Kish's effective number.

    Returns
    -------
    ndarray or None
        The weights (largest 1), shape (len(picks),); None when they are not reliable:
        a weight not finite, their cv above ``max_cv`` or their Pareto k̂ above
        :data:`MAX_PARETO_K`.
    """
    from bayestribo.inference.loo import psis

    picks = np.asarray(picks, dtype=int)
    flat = np.asarray(run.chains, dtype=float).reshape(-1, run.chains.shape[-1])[picks]
    log_w = np.asarray(posterior(flat), dtype=float)
    log_w = log_w - np.asarray(run.log_prob, dtype=float).reshape(-1)[picks]
    if picks.size < 4 or not np.all(np.isfinite(log_w)):
        return None
    w = np.exp(log_w - log_w.max())
    cv = float(np.std(w) / np.mean(w))
    _, k = psis(log_w.reshape(1, -1), 1.0)
    if not (cv <= max_cv and float(np.ravel(k)[0]) <= MAX_PARETO_K):
        return None
    return w


def exact_density(
    posterior: Posterior,
) -> Callable[[NDArray], tuple[NDArray, NDArray]]:
    """Rows -> the exact log posterior of each and the pointwise log-likelihood of
    its increments (:meth:`~bayestribo.inference.posterior.Posterior.pointwise`, for
    PSIS-LOO), both from one evaluation of the law's Π (the integrator is the cost:
    the comparison's PSIS-LOO then needs no second pass over the draws).

    Parameters
    ----------
    posterior : Posterior
        The exact posterior.

    Returns
    -------
    callable
        ``rows (k, d) -> (log posterior (k,), pointwise (k, m))``; −inf (and a
        pointwise row of NaN) outside the priors' support.
    """

    def density(rows: NDArray) -> tuple[NDArray, NDArray]:
        rows = np.atleast_2d(np.asarray(rows, dtype=float))
        lp = np.asarray(posterior.priors.logpdf(rows), dtype=float)
        m = posterior.likelihood.data.increments.size
        pointwise = np.full((rows.shape[0], m), np.nan)
        ok = np.isfinite(lp)
        if np.any(ok):
            args = posterior.physical(rows[ok])
            exact = posterior.likelihood
            given = _GivenPi(
                **{f.name: getattr(exact, f.name) for f in dataclasses.fields(PiLikelihood)},
                table=exact.model_pi(args["params"]),
            )
            lp[ok] += given.log_likelihood(args["params"], args["discrepancy"], args["shape"])
            pointwise[ok] = given.pointwise(args["params"], args["discrepancy"], args["shape"])
        return lp, pointwise

    return density


@dataclasses.dataclass(frozen=True)
class _GivenPi(PiLikelihood):
    """A :class:`~bayestribo.inference.likelihood.PiLikelihood` whose model Π is
    given, computed once for the rows its densities are asked of."""

    table: NDArray | None = dataclasses.field(default=None, repr=False)

    def model_pi(self, params: Params) -> NDArray:
        """The given Π, shape (n, m) (the rows of ``params``, in their order)."""
        table = np.asarray(self.table, dtype=float)
        n = np.ravel(np.asarray(params["y0"])).size
        if table.shape[0] != n:
            raise ValueError(f"params: expected the {table.shape[0]} rows of Π given, got {n}")
        return table
