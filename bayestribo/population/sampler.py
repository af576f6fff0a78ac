"""Sampling the population hyperparameters (β, σ) with emcee, seeded.

The sampled vector is (β flattened, log σ): the population-mean coefficients have an
improper flat prior, and each σ_k its prior from :mod:`bayestribo.population.hyperpriors`
(with the Jacobian of σ = exp(log σ)).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import emcee
import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError, ConvergenceWarning
from bayestribo.population.hyperpriors import SigmaPrior
from bayestribo.population.likelihood import MarginalLikelihood

__all__ = ["HyperSamples", "sample_hyperparameters"]

#: Minimum run length in autocorrelation times before a ConvergenceWarning.
MIN_AUTOCORR_TIMES = 50
#: Bound on |log σ| of the sampled hyperparameters.
_LOG_SIGMA_LIMIT = 100.0
#: Median importance-sampling effective sample size below which a run is flagged.
MIN_IS_ESS = 10.0


@dataclass(frozen=True)
class HyperSamples:
    """Posterior samples of the population hyperparameters.

    Attributes
    ----------
    beta : ndarray of shape (n_draws, P, K)
        Population-mean coefficients.
    sigma : ndarray of shape (n_draws, K)
        Between-run standard deviations.
    diagnostics : dict
        ``n_walkers``, ``n_steps``, ``burn``, ``autocorr_time_max``,
        ``acceptance_fraction``, ``converged``, ``is_ess_median_min`` (smallest over
        runs of the median importance-sampling effective sample size).
    """

    beta: NDArray[np.float64]
    sigma: NDArray[np.float64]
    diagnostics: dict[str, Any] = field(default_factory=dict)


def _initial(like: MarginalLikelihood) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Least-squares β and a residual σ from the runs' posterior means (start only)."""
    valid = np.isfinite(like.log_w0)
    counts = valid.sum(axis=1)[:, None]
    means = (like.theta * valid[:, :, None]).sum(axis=1) / counts
    sds = np.sqrt(((like.theta - means[:, None, :]) ** 2 * valid[:, :, None]).sum(axis=1) / counts)
    beta, *_ = np.linalg.lstsq(like.design, means, rcond=None)
    resid = means - like.design @ beta
    dof = max(len(means) - like.n_coefficients, 1)
    spread = np.sqrt((resid**2).sum(axis=0) / dof)
    sigma = np.maximum(spread, np.median(sds, axis=0))
    return beta, sigma


def sample_hyperparameters(
    like: MarginalLikelihood,
    priors: Sequence[SigmaPrior],
    *,
    seed: int,
    n_walkers: int = 32,
    n_steps: int = 2500,
    burn: int | None = None,
    progress: bool = False,
) -> HyperSamples:
    """Sample p(β, σ | data) ∝ p(data | β, σ) Π_k p(σ_k).

    Parameters
    ----------
    like : MarginalLikelihood
        The population likelihood.
    priors : sequence of SigmaPrior
        Prior on each σ_k, in the order of ``like.parameters``.
    seed : int
        Seed of the walkers' start and of the sampler.
    n_walkers, n_steps : int
        Ensemble size and steps per walker.
    burn : int, optional
        Steps discarded at the start; default a fifth of ``n_steps``.
    progress : bool
        Show emcee's progress bar.

    Warns
    -----
    ConvergenceWarning
        If the kept steps are fewer than 50 autocorrelation times, or some run's
        importance weights rest on fewer than 10 effective samples (median over draws).
    """
    p, k = like.n_coefficients, len(like.parameters)
    if len(priors) != k:
        raise BayestriboError(f"priors: expected {k} σ priors, got {len(priors)}")
    ndim = p * k + k
    if not (isinstance(n_walkers, int) and n_walkers >= 2 * ndim):
        raise BayestriboError(f"n_walkers: expected an integer >= {2 * ndim}, got {n_walkers!r}")
    if burn is None:
        burn = n_steps // 5
    if not (isinstance(n_steps, int) and 0 <= burn < n_steps):
        raise BayestriboError(
            f"n_steps, burn: expected integers with 0 <= burn < n_steps, got {n_steps}, {burn}"
        )

    def log_prob(x: NDArray[np.float64]) -> NDArray[np.float64]:
        beta = x[:, : p * k].reshape(-1, p, k)
        log_sigma = x[:, p * k :]
        out = np.full(len(x), -np.inf)
        # σ outside e^±100 has no prior mass worth a float: refused before exp overflows.
        ok = np.all(np.abs(log_sigma) < _LOG_SIGMA_LIMIT, axis=1)
        if not ok.any():
            return out
        lp = log_sigma[ok].sum(axis=1)  # Jacobian of σ = exp(log σ)
        for j, prior in enumerate(priors):
            lp = lp + prior.logpdf(np.exp(log_sigma[ok, j]))
        out[ok] = lp + like(beta[ok], log_sigma[ok])
        return np.where(np.isfinite(out), out, -np.inf)

    rng = np.random.default_rng(seed)
    beta0, sigma0 = _initial(like)
    start = np.empty((n_walkers, ndim))
    # Spread of each coefficient as least squares gives it: σ² (XᵀX)⁻¹, per parameter
    # (a slope against a covariate in large units is known far more tightly than a mean).
    coef_sd = np.sqrt(np.diag(np.linalg.pinv(like.design.T @ like.design)))[:, None] * sigma0
    start[:, : p * k] = beta0.ravel() + rng.normal(size=(n_walkers, p * k)) * coef_sd.ravel()
    start[:, p * k :] = np.log(sigma0) + 0.1 * rng.normal(size=(n_walkers, k))
    # Differential-evolution moves: about half the autocorrelation time of the default
    # stretch move on these posteriors (long tail in log σ, correlated means).
    moves = [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    sampler = emcee.EnsembleSampler(n_walkers, ndim, log_prob, moves=moves, vectorize=True)
    sampler.random_state = np.random.RandomState(rng.integers(2**32 - 1)).get_state()
    sampler.run_mcmc(start, n_steps, progress=progress)

    chain = sampler.get_chain(discard=burn)  # (steps, walkers, ndim)
    flat = chain.reshape(-1, ndim)
    with np.errstate(invalid="ignore", divide="ignore"):  # a stuck chain: τ is nan
        tau = sampler.get_autocorr_time(discard=burn, tol=0, quiet=True)
    tau_max = float(np.max(tau)) if np.all(np.isfinite(tau)) else math.inf
    kept = n_steps - burn
    converged = kept >= MIN_AUTOCORR_TIMES * tau_max
    beta = flat[:, : p * k].reshape(-1, p, k)
    log_sigma = flat[:, p * k :]
    pick = rng.choice(len(flat), size=min(200, len(flat)), replace=False)
    ess = like.effective_sample_size(beta[pick], log_sigma[pick])
    ess_median_min = float(np.min(np.nanmedian(ess, axis=0)))
    diagnostics = {
        "n_walkers": n_walkers,
        "n_steps": n_steps,
        "burn": burn,
        "autocorr_time_max": tau_max,
        "acceptance_fraction": float(np.mean(sampler.acceptance_fraction)),
        "converged": bool(converged),
        "is_ess_median_min": ess_median_min,
        "seed": seed,
    }
    if not converged:
        warnings.warn(
            f"population sampler: {kept} kept steps are fewer than {MIN_AUTOCORR_TIMES} "
            f"autocorrelation times ({tau_max:.1f}); increase n_steps",
            ConvergenceWarning,
            stacklevel=3,
        )
    if ess_median_min < MIN_IS_ESS:
        warnings.warn(
            f"population likelihood: a run's importance weights rest on "
            f"{ess_median_min:.1f} effective samples (median over draws); the population "
            "is narrower than the per-run samples resolve: give more samples per run",
            ConvergenceWarning,
            stacklevel=3,
        )
    return HyperSamples(beta, np.exp(log_sigma), diagnostics)
