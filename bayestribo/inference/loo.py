"""PSIS-LOO of one sampled law: its pointwise log-likelihood, reused where it can be.

PSIS-LOO (Vehtari, Gelman & Gabry 2017) needs the log-likelihood of every Π increment
at every draw. For a law with a closed form that is cheap. For a law without one, the
exact Π of a draw is its compiled half-cycle integrator (some 400 µs a draw for a power
drag), and the draws of a comparison's laws then cost more than their sampling did
(``law="auto"`` on the bundled run: 1.3 s of its 4.4 s of CPU). Such a law is sampled
on its quadratic surrogate of Π where the exact posterior confirms it
(:mod:`bayestribo.inference.surrogate`), and the surrogate's pointwise log-likelihood
is what the draws came from: :func:`sampled_pointwise` takes it, after comparing it
with the exact one at :data:`CHECK_DRAWS` draws spread over the chains. PSIS-LOO's
``elpd_loo`` of a law moves by at most the sum over the increments of the largest
change of their log-likelihood over the draws, so the surrogate's stands when that
sum, at the draws compared, is within :data:`TOLERANCE`; otherwise every draw is
evaluated with the exact Π. (On the bundled runs ``glycerol-N0.31-r1`` and
``air-r1``, both grids, the two differ by at most 3e-6 per increment and draw, and the
laws' ``elpd_loo`` agree to 1e-3.)

That sum is a worst case: ``elpd_loo`` moves by the surrogate's error averaged over the
draws with each increment's leave-one-out weights, to first order
``Σ_i Σ_s w_is ε_is`` (the weights sum to one per increment), and errors of either
sign cancel. Where the check fails, that shift is estimated before every draw is
integrated (:func:`surrogate_shift`): the exact log-likelihood at :data:`SHIFT_DRAWS`
draws picked in proportion to their leave-one-out weight (half of them evenly), a
Horvitz-Thompson estimate of the sum with its standard error, and a bound on the second
order term; the surrogate's values stand when the estimate, three standard errors and
that bound stay within :data:`TOLERANCE`. ``coulomb+quadratic`` on HarmOsc2 (2016
draws, 99 increments): the check's sums up to 0.22 at 8 draws (1.1 over all draws),
the shift −0.016 (−0.0162 to first order), estimated at 32 draws within 0.03 of it
in 200 random placements (sd 0.010); every draw integrated there took 0.42 s.

:func:`law_loo` is one law's PSIS-LOO (its pointwise values kept), :func:`loo_frame`
the laws' comparison from them, as :func:`arviz.compare` makes it
(:mod:`bayestribo.inference.loo_compare`, without importing ArviZ): each law's PSIS-LOO
is computed once. :func:`psis_loo` computes it as :func:`arviz.loo` does, to
rounding (``tests/test_inference_loo.py``), with the Pareto smoothing of all increments
at once (:func:`psis`) where ArviZ fits one increment at a time: 3-4 times faster (5
ms against 21 ms for 31 increments and 1800 draws, 72 against 229 ms for 738), which
on a record of several hundred increments per grid was a tenth of ``law="auto"``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.assemble import pointwise_log_likelihood
from bayestribo.inference.loo_compare import LooResult, compare, ess_mean
from bayestribo.inference.types import Sampled

__all__ = [
    "CHECK_DRAWS",
    "SHIFT_DRAWS",
    "TOLERANCE",
    "law_loo",
    "loo_frame",
    "pareto_k_max",
    "psis",
    "psis_loo",
    "relative_efficiency",
    "sampled_pointwise",
    "surrogate_shift",
]

#: Draws, evenly spaced over the flattened chains, at which the surrogate's pointwise
#: log-likelihood is compared with the exact one.
CHECK_DRAWS = 8
#: Largest sum over the increments of |surrogate - exact| pointwise log-likelihood at a
#: draw compared for the surrogate's to stand: a bound on the change of ``elpd_loo``
#: small beside the comparison's tie rule (4) and PSIS-LOO's own Monte Carlo error
#: (some 0.1 with a thousand draws); also the largest estimated shift of ``elpd_loo``
#: (:func:`surrogate_shift`, with three standard errors and the second order) for the
#: surrogate's values to stand where that sum is exceeded.
TOLERANCE = 0.05
#: Draws at which the exact log-likelihood is computed to estimate the shift of
#: ``elpd_loo`` by the surrogate (:func:`surrogate_shift`).
SHIFT_DRAWS = 32


def sampled_pointwise(sampled: Sampled) -> NDArray:
    """Log-likelihood of each Π increment at each draw of a sampled law (module notes).

    Parameters
    ----------
    sampled : Sampled
        A law's fit; its ``surrogate_posterior``, when there is one, is the posterior
        its draws came from.

    Returns
    -------
    ndarray
        Shape (chains, draws, m) for m increments: the exact values the sampler
        computed already where it did (``sampled.pointwise``); else the surrogate's
        values where they agree with the exact ones at the draws compared (within
        :data:`TOLERANCE`), else the exact posterior's
        (:func:`bayestribo.inference.assemble.pointwise_log_likelihood`).
    """
    chains = np.asarray(sampled.run.chains, dtype=float)
    given = getattr(sampled, "pointwise", None)
    if given is not None and np.shape(given)[:2] == chains.shape[:2]:
        return np.asarray(given, dtype=float)
    surrogate = sampled.surrogate_posterior
    if surrogate is None:
        return pointwise_log_likelihood(sampled.posterior, chains)
    approx = pointwise_log_likelihood(surrogate, chains)
    flat = chains.reshape(-1, chains.shape[-1])
    approx_flat = approx.reshape(flat.shape[0], -1)
    pick = np.unique(np.linspace(0, flat.shape[0] - 1, min(CHECK_DRAWS, flat.shape[0])).astype(int))
    exact = np.asarray(sampled.posterior.pointwise(flat[pick]), dtype=float)
    with np.errstate(invalid="ignore"):
        error = np.sum(np.abs(approx_flat[pick] - exact), axis=-1)
    if np.all(np.isfinite(error)) and float(np.max(error)) <= TOLERANCE:
        return approx
    shift, se, second = surrogate_shift(
        approx_flat, flat, sampled.posterior.pointwise, relative_efficiency(chains)
    )
    if abs(shift) + 3.0 * se + second <= TOLERANCE:
        return approx
    return pointwise_log_likelihood(sampled.posterior, chains)


def surrogate_shift(
    approx: NDArray, draws: NDArray, exact: Callable[[NDArray], NDArray], reff: float
) -> tuple[float, float, float]:
    """How far a surrogate's pointwise log-likelihood moves ``elpd_loo`` from the exact
    one's, estimated at :data:`SHIFT_DRAWS` draws (module notes).

    To first order ``elpd_loo(surrogate) - elpd_loo(exact) = Σ_s t_s``, with
    ``t_s = Σ_i w_is ε_is``: ``w_is`` the Pareto-smoothed leave-one-out weights of draw s
    for increment i (from the surrogate's values, each increment's summing to one) and
    ``ε_is`` the surrogate's error. The draws are picked by systematic sampling with
    probability ``q_s``, half in proportion to ``Σ_i w_is`` and half evenly; the
    estimate is the mean of ``t_s / q_s`` over them (Horvitz-Thompson), its standard
    error their sd over √n. The second order term, ``-½ Σ_i Var_w(ε_i)``, is at most
    ``½ Σ_s Σ_i w_is ε_is²`` in size, estimated the same way.

    Parameters
    ----------
    approx : ndarray
        The surrogate's pointwise log-likelihood, shape (S, m): S draws (flattened
        chains), m increments.
    draws : ndarray
        The draws (S, d) whose values ``approx`` holds.
    exact : callable
        ``exact(theta)`` -> the exact pointwise log-likelihood (n, m) at draws
        ``theta`` (n, d); called once, with the draws picked.
    reff : float
        Relative efficiency of the draws (:func:`relative_efficiency`).

    Returns
    -------
    (float, float, float)
        The estimated shift, its standard error and the bound on the second order
        term; (inf, inf, inf) where an exact value picked is not finite.
    """
    approx = np.asarray(approx, dtype=float)
    n_draws = approx.shape[0]
    log_weights, _ = psis(-approx.T, reff)
    weights = np.exp(log_weights)  # (m, S), each row summing to one
    mass = np.sum(weights, axis=0)
    q = 0.5 * mass / np.sum(mass) + 0.5 / n_draws
    n = min(SHIFT_DRAWS, n_draws)
    edges = np.cumsum(q)
    pick = np.minimum(np.searchsorted(edges, (0.5 + np.arange(n)) / n * edges[-1]), n_draws - 1)
    unique, where = np.unique(pick, return_inverse=True)
    with np.errstate(invalid="ignore"):
        error = approx[unique] - np.asarray(exact(np.asarray(draws)[unique]), dtype=float)
    if not np.all(np.isfinite(error)):
        return np.inf, np.inf, np.inf
    error = error[where]
    w = weights[:, pick].T  # (n, m)
    first = np.sum(w * error, axis=1) / q[pick]
    second = np.sum(w * error**2, axis=1) / q[pick]
    se = float(np.std(first, ddof=1) / np.sqrt(n)) if n > 1 else np.inf
    return float(np.mean(first)), se, 0.5 * float(np.mean(second))


def law_loo(sampled: Sampled, pointwise: NDArray | None = None) -> LooResult:
    """PSIS-LOO of one sampled law, its pointwise values kept.

    Parameters
    ----------
    sampled : Sampled
        The law's fit (its chains give the relative efficiency of the draws).
    pointwise : ndarray, optional
        Its pointwise log-likelihood, shape (chains, draws, m); default
        :func:`sampled_pointwise`.

    Returns
    -------
    LooResult
        :func:`psis_loo` of the pointwise log-likelihood with the relative efficiency
        of the chains (:func:`relative_efficiency`). A high Pareto k is reported by the
        comparison, not warned here.
    """
    if pointwise is None:
        pointwise = sampled_pointwise(sampled)
    return psis_loo(pointwise, relative_efficiency(sampled.run.chains))


def relative_efficiency(chains: NDArray) -> float:
    """The draws' mean effective sample size over their number: ArviZ's ``reff`` of
    :func:`arviz.loo` (the "mean" ESS of each coordinate, averaged; 1 for one chain),
    computed without ArviZ (:func:`~bayestribo.inference.loo_compare.ess_mean`).

    Parameters
    ----------
    chains : ndarray
        Draws of shape (chains, draws, d).
    """
    chains = np.asarray(chains, dtype=float)
    n_chains, n_draws, d = chains.shape
    if n_chains == 1:
        return 1.0
    ess = [ess_mean(chains[..., i]) for i in range(d)]
    return float(np.mean(ess)) / (n_chains * n_draws)


def psis_loo(log_likelihood: NDArray, reff: float) -> LooResult:
    """PSIS-LOO from a pointwise log-likelihood, as :func:`arviz.loo` computes it
    (``pointwise=True``, log scale), with the Pareto smoothing of every increment's
    weights at once (:func:`psis`) rather than one increment at a time.

    Parameters
    ----------
    log_likelihood : ndarray
        Shape (chains, draws, m): each increment's log-likelihood at each draw.
    reff : float
        Relative efficiency of the draws (:func:`relative_efficiency`).

    Returns
    -------
    LooResult
        ``elpd_loo``, ``se``, ``p_loo``, ``n_samples``, ``n_data_points``,
        ``warning`` (a Pareto k above ``good_k``), ``loo_i`` and ``pareto_k`` (per
        increment), ``scale`` ("log") and ``good_k``, as :func:`arviz.loo` gives them
        (:class:`~bayestribo.inference.loo_compare.LooResult`, read by key).
    """
    ll = np.asarray(log_likelihood, dtype=float)
    ll = ll.reshape(-1, ll.shape[-1]).T  # (m, samples), samples in chain-major order
    m, n_samples = ll.shape
    log_weights, pareto_k = psis(-ll, reff)
    loo_i = _logsumexp_rows(log_weights + ll)
    elpd = float(np.sum(loo_i))
    se = float((m * np.var(loo_i)) ** 0.5)
    lppd = float(np.sum(_logsumexp_rows(ll) - np.log(n_samples)))
    good_k = min(1.0 - 1.0 / np.log10(n_samples), 0.7)
    return LooResult(
        elpd_loo=elpd,
        se=se,
        p_loo=lppd - elpd,
        n_samples=n_samples,
        n_data_points=m,
        warning=bool(np.any(pareto_k > good_k)),
        loo_i=loo_i,
        pareto_k=pareto_k,
        scale="log",
        good_k=good_k,
    )


def _logsumexp_rows(x: NDArray) -> NDArray:
    """log Σ exp along the last axis, stably (ArviZ's order of operations)."""
    top = np.max(x, axis=-1, keepdims=True)
    return np.log(np.sum(np.exp(x - top), axis=-1)) + top[..., 0]


def psis(log_weights: NDArray, reff: float) -> tuple[NDArray, NDArray]:
    """Pareto-smoothed importance sampling of many rows of log weights at once
    (Vehtari et al. 2024), the algorithm of :func:`arviz.psislw` row by row.

    Each row's largest weights (its tail: ``ceil(min(S/5, 3 sqrt(S/reff)))`` of its S
    samples) are replaced by the quantiles of a generalized Pareto distribution fitted
    to them (Zhang & Stephens 2009, with ArviZ's weakly informative prior on k),
    truncated at the largest raw weight, and the row normalised. Rows whose tail holds
    ties at its cut (a different number of samples beyond it) are smoothed by ArviZ's
    own row function.

    Parameters
    ----------
    log_weights : ndarray
        Shape (rows, S).
    reff : float
        Relative efficiency of the samples.

    Returns
    -------
    smoothed : ndarray
        Shape (rows, S), normalised log weights.
    k : ndarray
        Shape (rows,): each row's Pareto shape k (inf where the tail is too short).
    """
    x = np.array(log_weights, dtype=float)
    rows, n = x.shape
    cutoff_ind = -int(np.ceil(min(n / 5.0, 3 * (n / reff) ** 0.5))) - 1
    cutoffmin = np.log(np.finfo(float).tiny)
    x -= np.max(x, axis=1, keepdims=True)
    tail = -cutoff_ind - 1
    # the tail and the cut below it: the largest tail + 1 of each row, in order
    top = np.argpartition(x, n - tail - 1, axis=1)[:, n - tail - 1 :]
    top = np.take_along_axis(top, np.argsort(np.take_along_axis(x, top, axis=1), axis=1), axis=1)
    ordered = np.take_along_axis(x, top, axis=1)
    cut = np.maximum(ordered[:, 0], cutoffmin)
    in_tail = np.sum(x > cut[:, None], axis=1)
    k = np.full(rows, np.inf)
    regular = in_tail == tail
    if tail > 4 and np.any(regular):
        r = np.flatnonzero(regular)
        exp_cut = np.exp(cut[r])
        sample = np.exp(ordered[r, 1:]) - exp_cut[:, None]
        k_r, sigma = _gpdfit_rows(sample)
        probs = np.arange(0.5, tail) / tail
        smoothed = _gpinv_rows(probs, k_r, sigma)
        smoothed = np.log(smoothed + exp_cut[:, None])
        fitted = np.isfinite(k_r)
        k[r] = k_r
        rows_fitted = r[fitted]
        if rows_fitted.size:
            block = x[rows_fitted]
            np.put_along_axis(block, top[rows_fitted, 1:], smoothed[fitted], axis=1)
            block[block > 0] = 0.0
            x[rows_fitted] = block
    x -= _logsumexp_rows(x)[:, None]
    for i in np.flatnonzero(~regular | (tail <= 4)):
        # ties at the cut (a walker that stayed put repeats its weight), or too short a
        # tail: ArviZ's row function, written out (ArviZ takes seconds to import)
        x[i], k[i] = _psis_row(np.array(log_weights[i], dtype=float), cutoff_ind, cutoffmin)
    return x, k


def _psis_row(x: NDArray, cutoff_ind: int, cutoffmin: float) -> tuple[NDArray, float]:
    """One row smoothed as ArviZ's ``_psislw`` does it (normalised): the tail is every
    weight above the one at ``cutoff_ind`` of the sorted row, however many ties there
    are at that cut. ``x`` is changed in place."""
    x -= np.max(x)
    cut = max(float(x[np.argsort(x)[cutoff_ind]]), cutoffmin)
    exp_cut = np.exp(cut)
    (in_tail,) = np.where(x > cut)
    k = math.inf
    if in_tail.size > 4:
        order = np.argsort(x[in_tail])
        sample = np.exp(x[in_tail][order]) - exp_cut
        k_row, sigma = _gpdfit_rows(sample[None, :])
        k = float(k_row[0])
        if math.isfinite(k):
            probs = np.arange(0.5, in_tail.size) / in_tail.size
            x[in_tail[order]] = np.log(_gpinv_rows(probs, k_row, sigma)[0] + exp_cut)
            x[x > 0] = 0.0
    x -= _logsumexp_rows(x[None, :])[0]
    return x, k


def _gpdfit_rows(sample: NDArray) -> tuple[NDArray, NDArray]:
    """ArviZ's empirical-Bayes fit of a generalized Pareto distribution (Zhang &
    Stephens 2009, prior on k of weight 10 at 0.5), each row of sorted exceedances
    at once: shape k and scale sigma, each (rows,)."""
    n = sample.shape[1]
    prior_bs, prior_k = 3, 10
    m_est = 30 + int(n**0.5)
    b = 1 - np.sqrt(m_est / (np.arange(1, m_est + 1, dtype=float) - 0.5))
    b = b[None, :] / (prior_bs * sample[:, int(n / 4 + 0.5) - 1])[:, None]
    b = b + (1 / sample[:, -1])[:, None]
    k_b = np.log1p(-b[:, :, None] * sample[:, None, :]).mean(axis=2)
    len_scale = n * (np.log(-(b / k_b)) - k_b - 1)
    weights = 1 / np.exp(len_scale[:, None, :] - len_scale[:, :, None]).sum(axis=2)
    weights = np.where(weights >= 10 * np.finfo(float).eps, weights, 0.0)
    weights /= weights.sum(axis=1, keepdims=True)
    b_post = np.sum(b * weights, axis=1)
    k_post = np.log1p(-b_post[:, None] * sample).mean(axis=1)
    sigma = -k_post / b_post
    k_post = (n * k_post + prior_k * 0.5) / (n + prior_k)
    return k_post, sigma


def _gpinv_rows(probs: NDArray, kappa: NDArray, sigma: NDArray) -> NDArray:
    """Quantiles ``probs`` (all inside (0, 1)) of each row's generalized Pareto
    distribution (shape ``kappa``, scale ``sigma``); NaN where sigma <= 0."""
    with np.errstate(all="ignore"):
        small = np.abs(kappa) < np.finfo(float).eps
        safe = np.where(small, 1.0, kappa)
        x = np.where(
            small[:, None],
            -np.log1p(-probs)[None, :],
            np.expm1(-safe[:, None] * np.log1p(-probs)[None, :]) / safe[:, None],
        )
        x = x * sigma[:, None]
    return np.where((sigma > 0)[:, None], x, np.nan)


def pareto_k_max(loo: LooResult) -> float:
    """Largest Pareto k of a law's PSIS-LOO (:func:`law_loo`)."""
    return float(np.max(np.asarray(loo.pareto_k)))


def loo_frame(loos: Mapping[str, LooResult]) -> dict[str, dict[str, float]]:
    """The laws' PSIS-LOO compared, as :func:`arviz.compare` compares them
    (:func:`~bayestribo.inference.loo_compare.compare`); one law alone is its own best.

    Parameters
    ----------
    loos : mapping of str to LooResult
        Each law's PSIS-LOO, pointwise.

    Returns
    -------
    dict
        Law -> its row, best first: ``rank``, ``elpd_loo``, ``p_loo``, ``elpd_diff``,
        ``weight``, ``se``, ``dse``, ``warning``.
    """
    return compare(loos)
