"""Sampling the population hyperparameters (β, σ), seeded.

The sampled vector is (β flattened, log σ): the population-mean coefficients have an
improper flat prior, bounded below by zero for the intercept (the mean at the centre
of the covariates) of a parameter that cannot be negative (:data:`NON_NEGATIVE`:
viscous damping ζ, ζ₀ in air, and friction μ_k), and each σ_k its prior from
:mod:`bayestribo.population.hyperpriors` (with the Jacobian of σ = exp(log σ)).
Sampling is the package's one driver, :func:`bayestribo.inference.sampling.run_ensembles`:
independent ensembles run until
50 autocorrelation times and R-hat say so, with the same moves and NaN rule as the
single-run fit, and the independence Metropolis-Hastings move in the mix after an
adaptation phase (:data:`POPULATION_INDEPENDENCE`;
:mod:`bayestribo.inference.independence`): the hyperparameters' posterior is near
Gaussian in (β, log σ), the move is accepted about half the time, and the 50 τ the
rule asks for take about half the steps (``benchmarks/README.md``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError, ConvergenceWarning
from bayestribo.inference.sampling import SamplerSettings, run_ensembles
from bayestribo.population.hyperpriors import SigmaPrior
from bayestribo.population.likelihood import MarginalLikelihood

__all__ = ["NON_NEGATIVE", "POPULATION_INDEPENDENCE", "HyperSamples", "sample_hyperparameters"]

#: Parameters whose population mean (the intercept at the covariates' centre) is >= 0.
NON_NEGATIVE = frozenset({"zeta", "mu_k"})

#: Weight of the independence move in the population sampler's mix
#: (:class:`~bayestribo.inference.sampling.SamplerSettings` ``independence``), where
#: the step ceiling leaves room for its adaptation phase.
POPULATION_INDEPENDENCE = 0.75

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
        As the single-run fit's: ``converged``, ``reasons``, ``n_walkers`` (per
        ensemble), ``n_ensembles``, ``n_steps``, ``burn``, ``thin``,
        ``autocorr_time`` [steps], ``ess`` and ``rhat`` (dicts by sampled
        hyperparameter, ``beta[i,name]`` and ``log_sigma[name]``), their extremes
        ``autocorr_time_max``, ``ess_min``, ``rhat_max``, ``acceptance_fraction``;
        then ``is_ess_median_min`` (smallest over runs of the median
        importance-sampling effective sample size) and ``seed``.
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
    n_walkers: int | None = 16,
    n_ensembles: int = 2,
    max_steps: int = 10_000,
    progress: bool = False,
    non_negative: Collection[str] | None = None,
) -> HyperSamples:
    """Sample p(β, σ | data) ∝ p(data | β, σ) Π_k p(σ_k) to convergence.

    Parameters
    ----------
    like : MarginalLikelihood
        The population likelihood.
    priors : sequence of SigmaPrior
        Prior on each σ_k, in the order of ``like.parameters``.
    seed : int
        Seed of the walkers' start and of the sampler.
    n_walkers, n_ensembles : int
        Walkers per ensemble (at least twice the number of hyperparameters; None: 16,
        or twice the number of hyperparameters where that is more) and independent
        ensembles.
    max_steps : int
        Ceiling on the steps per ensemble; sampling stops earlier once converged
        (:func:`bayestribo.inference.sampling.run_ensembles`).
    progress : bool
        Show a progress bar.
    non_negative : collection of str, optional
        Parameters whose population mean (the intercept at the covariates' centre) is
        bounded below by zero; default :data:`NON_NEGATIVE`.

    Raises
    ------
    BayestriboError
        If ``priors`` or ``n_walkers`` do not fit the likelihood.
    bayestribo.inference.sampling.NaNLogProbabilityError
        If the log posterior is NaN somewhere (e.g. a NaN per-run sample); the message
        names the hyperparameter values, as the single-run fit's NaN error does.

    Warns
    -----
    ConvergenceWarning
        If the run is not converged by ``max_steps`` (with the reasons), or some run's
        importance weights rest on fewer than 10 effective samples (median over draws).
    """
    p, k = like.n_coefficients, len(like.parameters)
    if len(priors) != k:
        raise BayestriboError(f"priors: expected {k} σ priors, got {len(priors)}")
    ndim = p * k + k
    if n_walkers is None:
        n_walkers = max(16, 2 * ndim)
    if not (isinstance(n_walkers, int) and n_walkers >= 2 * ndim):
        raise BayestriboError(f"n_walkers: expected an integer >= {2 * ndim}, got {n_walkers!r}")
    adapt = SamplerSettings.adapt_steps
    settings = SamplerSettings(
        n_walkers=n_walkers,
        n_ensembles=n_ensembles,
        max_steps=max_steps,
        independence=POPULATION_INDEPENDENCE if max_steps > 2 * adapt else 0.0,
    )
    positive = NON_NEGATIVE if non_negative is None else frozenset(non_negative)
    bounded = [j for j, name in enumerate(like.parameters) if name in positive]

    def inside(beta: NDArray[np.float64], log_sigma: NDArray[np.float64]) -> NDArray[np.float64]:
        lp = log_sigma.sum(axis=1)  # Jacobian of σ = exp(log σ)
        sigma = np.exp(log_sigma)
        for j, prior in enumerate(priors):
            lp += prior.logpdf(sigma[:, j])
        return lp + like(beta, log_sigma)

    def log_prob(x: NDArray[np.float64]) -> NDArray[np.float64]:
        beta = x[:, : p * k].reshape(-1, p, k)
        log_sigma = x[:, p * k :]
        # σ outside e^±100 has no prior mass worth a float: refused before exp overflows.
        ok = np.all(np.abs(log_sigma) < _LOG_SIGMA_LIMIT, axis=1)
        if bounded:
            ok &= np.all(beta[:, 0, bounded] >= 0.0, axis=1)
        if ok.all():
            return inside(beta, log_sigma)
        out = np.full(len(x), -np.inf)
        if ok.any():
            out[ok] = inside(beta[ok], log_sigma[ok])
        return out

    rng = np.random.default_rng(seed)
    beta0, sigma0 = _initial(like)
    n_start = n_ensembles * n_walkers
    start = np.empty((n_start, ndim))
    # Spread of each coefficient as least squares gives it: σ² (XᵀX)⁻¹, per parameter
    # (a slope against a covariate in large units is known far more tightly than a mean).
    coef_sd = np.sqrt(np.diag(np.linalg.pinv(like.design.T @ like.design)))[:, None] * sigma0
    start[:, : p * k] = beta0.ravel() + rng.normal(size=(n_start, p * k)) * coef_sd.ravel()
    if bounded:
        # Walkers start inside the support: a negative intercept is reflected.
        view = start[:, : p * k].reshape(n_start, p, k)
        view[:, 0, bounded] = np.abs(view[:, 0, bounded])
    start[:, p * k :] = np.log(sigma0) + 0.1 * rng.normal(size=(n_start, k))
    names = [f"beta[{i},{name}]" for i in range(p) for name in like.parameters]
    names += [f"log_sigma[{name}]" for name in like.parameters]
    sampled = run_ensembles(
        log_prob,
        start.reshape(n_ensembles, n_walkers, ndim),
        settings,
        seed=int(rng.integers(2**31)),
        progress=progress,
        names=names,
    )

    flat = sampled.chains.reshape(-1, ndim)
    beta = flat[:, : p * k].reshape(-1, p, k)
    log_sigma = flat[:, p * k :]
    pick = rng.choice(len(flat), size=min(200, len(flat)), replace=False)
    ess = like.effective_sample_size(beta[pick], log_sigma[pick])
    ess_median_min = float(np.min(np.nanmedian(ess, axis=0)))
    tau = sampled.autocorr_time

    def by_name(values: NDArray[np.float64]) -> dict[str, float]:
        return dict(zip(sampled.names, np.asarray(values, dtype=float).tolist(), strict=True))

    diagnostics = {
        "converged": bool(sampled.converged),
        "reasons": list(sampled.reasons),
        "n_walkers": n_walkers,
        "n_ensembles": n_ensembles,
        "n_steps": sampled.n_steps,
        "burn": sampled.burn,
        "thin": sampled.thin,
        "autocorr_time": by_name(tau),
        "autocorr_time_max": float(np.max(tau)) if np.all(np.isfinite(tau)) else math.inf,
        "ess": by_name(sampled.ess),
        "ess_min": float(np.min(sampled.ess)),
        "rhat": by_name(sampled.rhat),
        "rhat_max": float(np.max(sampled.rhat)),
        "acceptance_fraction": sampled.acceptance_fraction,
        "independence_weight": sampled.independence,
        "independence_acceptance": sampled.independence_acceptance,
        "is_ess_median_min": ess_median_min,
        "seed": seed,
    }
    if not sampled.converged:
        warnings.warn(
            "population sampler not converged: " + "; ".join(sampled.reasons) + "; increase "
            "max_steps",
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
