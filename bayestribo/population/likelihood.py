"""The population likelihood from per-run posterior samples, per-run priors divided out.

Model. Run i has parameters θ_i = (θ_i1, ..., θ_iK) (e.g. ζ and μ_k), drawn from a
population of independent normals whose means are linear in the run's covariates::

    θ_ik ~ Normal(x_i · β_k, σ_k²)

(a group mean: x_i = 1; a load trend: x_i = (1, N_i − N̄)). The run was fitted alone
with a prior π_i(θ) and gave posterior samples θ_is, s = 1..S. Since
p(θ | data_i) = p(data_i | θ) π_i(θ) / Z_i,

    p(data_i | β, σ) = ∫ p(data_i | θ) N(θ | x_i β, σ²) dθ
                     = Z_i E_{θ ~ p(θ | data_i)}[ N(θ | x_i β, σ²) / π_i(θ) ]
                     ≈ Z_i (1/S) Σ_s N(θ_is | x_i β, σ²) / π_i(θ_is),

with Z_i a constant. This is the usual reuse of per-run samples (e.g. Hogg, Myers &
Bovy 2010, ApJ 725, 2166). The ratio is taken jointly over the K parameters, so the
correlation of ζ and μ_k within a run is kept.

Evaluation. :meth:`MarginalLikelihood.__call__` computes the sum for every walker in
one compiled (numba) call, one pass over each run's samples with a running
log-sum-exp; :meth:`MarginalLikelihood.reference` is the numpy computation it is
tested against (agreement to 1e-10).

Accuracy. The sum is a kernel estimate of the ratio posterior/prior with bandwidth σ:
it is good while σ is not much smaller than the spread of the samples divided by
about √S, and the per-run effective sample size of the weights
(:meth:`MarginalLikelihood.effective_sample_size`) says when it is not.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.population.samples import RunSamples

__all__ = ["MarginalLikelihood"]

_LOG_2PI = math.log(2.0 * math.pi)


@numba.njit(cache=True, error_model="numpy")
def _shifted_log_weights(
    theta: NDArray,
    log_w0: NDArray,
    counts: NDArray,
    design: NDArray,
    beta: NDArray,
    log_sigma: NDArray,
    out: NDArray,
    top: NDArray,
) -> None:  # pragma: no cover - compiled; tested against the numpy reference
    """Log weights of every walker, run and sample, less their maximum over samples.

    theta (n, K, S) (samples last, for contiguous inner loops), log_w0 (n, S),
    counts (n,) valid samples per run (the padding after them is -inf), design
    (n, P), beta (W, P, K), log_sigma (W, K). Writes
    out (W, n, S) = log w − top and top (W, n) = max_s log w, with log w the log
    weight without the normal's constant (added by the caller).
    """
    n, k = theta.shape[:2]
    p = design.shape[1]
    for w in range(beta.shape[0]):
        for i in range(n):
            row = out[w, i]
            m_i = counts[i]
            row[:m_i] = log_w0[i, :m_i]
            row[m_i:] = -math.inf
            for j in range(k):
                m = 0.0
                for c in range(p):
                    m += design[i, c] * beta[w, c, j]
                h = -0.5 * math.exp(-2.0 * log_sigma[w, j])
                values = theta[i, j]
                for s in range(m_i):
                    d = values[s] - m
                    row[s] += h * d * d
            best = -math.inf
            for s in range(m_i):
                best = max(best, row[s])
            top[w, i] = best
            if best > -math.inf:
                for s in range(m_i):
                    row[s] -= best


class MarginalLikelihood:
    """log p(data | β, σ) up to a constant, for many hyperparameter values at once.

    Parameters
    ----------
    runs : sequence of RunSamples
        The runs (each with samples of every name in ``parameters``).
    parameters : sequence of str
        Parameter names (K of them).
    design : array of shape (n_runs, P), optional
        Covariates x_i of each run; default a column of ones (one common mean).
    """

    def __init__(
        self,
        runs: Sequence[RunSamples],
        parameters: Sequence[str],
        design: NDArray[np.float64] | None = None,
    ) -> None:
        if not runs:
            raise BayestriboError("runs: expected at least one run, got none")
        self.parameters = tuple(parameters)
        n = len(runs)
        s_max = max(r.n_samples for r in runs)
        k = len(self.parameters)
        # Runs are padded to a common sample count; padded samples get weight 0.
        theta = np.zeros((n, s_max, k))
        log_w0 = np.full((n, s_max), -np.inf)
        for i, run in enumerate(runs):
            m = run.n_samples
            for j, name in enumerate(self.parameters):
                theta[i, :m, j] = run.values[name]
            log_w0[i, :m] = -run.log_prior - math.log(m)
        self.theta = theta
        self.log_w0 = log_w0
        # Runs' samples come first, padding after: the compiled sum stops at the count.
        self._counts = np.array([r.n_samples for r in runs], dtype=np.int64)
        self._theta_by_parameter = np.ascontiguousarray(np.moveaxis(theta, 2, 1))
        if design is None:
            design = np.ones((n, 1))
        design = np.asarray(design, dtype=float)
        if design.ndim != 2 or design.shape[0] != n or not np.all(np.isfinite(design)):
            raise BayestriboError(
                f"design: expected a finite array of shape ({n}, P), got {design.shape}"
            )
        self.design = design
        # Features (θ − c)², θ − c, 1 of every sample for the expanded quadratic form.
        self._center = theta.reshape(-1, k)[np.isfinite(log_w0).ravel()].mean(axis=0)
        centred = theta - self._center
        self._features = np.concatenate([centred**2, centred, np.ones((n, s_max, 1))], axis=2)

    @property
    def n_coefficients(self) -> int:
        """P, the number of covariates (columns of the design)."""
        return self.design.shape[1]

    def _log_weights(
        self, beta: NDArray[np.float64], log_sigma: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Log importance weights, shape (n_runs, S, W).

        The quadratic form Σ_k (θ_k − m_k)²/σ_k² is expanded in powers of θ so that all
        walkers are evaluated by one batched matrix product per run (θ is centred first
        to keep the expansion free of cancellation).
        """
        mean = np.einsum("np,wpk->nkw", self.design, beta) - self._center[None, :, None]
        inv_var = np.exp(-2.0 * log_sigma).T  # (K, W)
        n, k = mean.shape[0], mean.shape[1]
        coef = np.empty((n, 2 * k + 1, mean.shape[2]))
        coef[:, :k] = -0.5 * inv_var[None]
        coef[:, k : 2 * k] = mean * inv_var[None]
        const = -0.5 * (mean**2 * inv_var[None]).sum(axis=1)
        const -= log_sigma.sum(axis=1)[None] + 0.5 * k * _LOG_2PI
        coef[:, 2 * k] = const
        return np.matmul(self._features, coef) + self.log_w0[:, :, None]

    def log_weights(
        self, beta: NDArray[np.float64], log_sigma: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Log importance weights, shape (W, n_runs, S).

        Parameters
        ----------
        beta : array of shape (W, P, K)
            Coefficients of the population means.
        log_sigma : array of shape (W, K)
            Log between-run standard deviations.
        """
        return np.moveaxis(self._log_weights(beta, log_sigma), 2, 0)

    def __call__(
        self, beta: NDArray[np.float64], log_sigma: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Log marginal likelihood (up to a constant), shape (W,), in one compiled call.

        Parameters
        ----------
        beta : array of shape (W, P, K)
            Coefficients of the population means.
        log_sigma : array of shape (W, K)
            Log between-run standard deviations.
        """
        beta = np.ascontiguousarray(beta, dtype=np.float64)
        log_sigma = np.ascontiguousarray(log_sigma, dtype=np.float64)
        if beta.ndim != 3 or beta.shape[1:] != (self.n_coefficients, len(self.parameters)):
            raise BayestriboError(
                f"beta: expected shape (W, {self.n_coefficients}, {len(self.parameters)}), "
                f"got {beta.shape}"
            )
        if log_sigma.shape != (beta.shape[0], len(self.parameters)):
            raise BayestriboError(
                f"log_sigma: expected shape ({beta.shape[0]}, {len(self.parameters)}), "
                f"got {log_sigma.shape}"
            )
        n_w, k = log_sigma.shape
        n, n_s = self.log_w0.shape
        shifted = np.empty((n_w, n, n_s))
        top = np.empty((n_w, n))
        _shifted_log_weights(
            self._theta_by_parameter,
            self.log_w0,
            self._counts,
            self.design,
            beta,
            log_sigma,
            shifted,
            top,
        )
        # The exponentials by numpy (its SIMD exp is several times faster than a
        # compiled scalar loop's); the padding contributes exp(-inf) = 0.
        np.exp(shifted, out=shifted)
        with np.errstate(divide="ignore"):
            per_run = np.log(shifted.sum(axis=2)) + top  # (W, n); -inf if a run has no mass
        const = -log_sigma.sum(axis=1) - 0.5 * k * _LOG_2PI
        return per_run.sum(axis=1) + n * const

    def reference(
        self, beta: NDArray[np.float64], log_sigma: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """:meth:`__call__` by numpy (batched matrix products), the tested reference."""
        lw = self._log_weights(beta, log_sigma)  # (n, S, W)
        top = lw.max(axis=1)
        safe = np.where(np.isfinite(top), top, 0.0)
        with np.errstate(divide="ignore"):
            per_run = np.log(np.exp(lw - safe[:, None, :]).sum(axis=1)) + safe
        return per_run.sum(axis=0)

    def effective_sample_size(
        self, beta: NDArray[np.float64], log_sigma: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Kish effective sample size of each run's weights, shape (W, n_runs).

        (Σ w)² / Σ w²: about S when the population is wide compared with a run's
        posterior, small when the kernel estimate rests on few samples.
        """
        lw = self.log_weights(beta, log_sigma)
        lw = lw - lw.max(axis=2, keepdims=True)
        w = np.exp(lw)
        return w.sum(axis=2) ** 2 / (w**2).sum(axis=2)
