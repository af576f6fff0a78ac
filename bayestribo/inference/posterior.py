"""Posterior = priors × likelihood, vectorised over walkers.

The sampled vector holds, in order, the names of the :class:`PriorSet`: ``zeta``,
and with friction ``mu_k`` and ``mu_s_ratio`` (μ_s = μ_k × ratio keeps μ_s >= μ_k
without a constraint between coordinates), ``y0``, and optionally
``log10_discrepancy``.
The likelihood is evaluated only for walkers whose prior density is positive.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.priors import PriorSet

__all__ = ["Posterior"]


@dataclass(frozen=True)
class Posterior:
    """Log posterior density of the single-run fit.

    Parameters
    ----------
    priors : PriorSet
        Independent priors; their names define the sampled vector.
    likelihood : PiLikelihood
        Likelihood of the Π increments.
    """

    priors: PriorSet
    likelihood: PiLikelihood

    @property
    def names(self) -> list[str]:
        """Names of the sampled coordinates."""
        return self.priors.names

    @property
    def friction(self) -> bool:
        """True when μ_k and μ_s are fitted."""
        return "mu_k" in self.priors.names

    def physical(self, theta: NDArray) -> dict[str, NDArray]:
        """Model parameters from sampled rows ``theta`` (n, d): each of shape (n, 1)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        col = {name: theta[:, i : i + 1] for i, name in enumerate(self.names)}
        zero = np.zeros_like(col["zeta"])
        mu_k = col.get("mu_k", zero)
        mu_s = mu_k * col["mu_s_ratio"] if "mu_s_ratio" in col else zero
        out = {"zeta": col["zeta"], "mu_k": mu_k, "mu_s": mu_s, "y0": col["y0"]}
        log_s = col.get("log10_discrepancy")
        out["discrepancy"] = None if log_s is None else 10.0**log_s
        return out

    def _args(self, theta: NDArray) -> tuple:
        p = self.physical(theta)
        return p["zeta"], p["mu_k"], p["mu_s"], p["y0"], p["discrepancy"]

    def log_likelihood(self, theta: NDArray) -> NDArray:
        """Log-likelihood of each row (nuisance offset marginalised), shape (n,)."""
        return self.likelihood.log_likelihood(*self._args(theta))

    def pointwise(self, theta: NDArray) -> NDArray:
        """Conditional log-likelihood of each increment for each row, shape (n, m)."""
        return self.likelihood.pointwise(*self._args(theta))

    def standardized_residuals(self, theta: NDArray) -> NDArray:
        """Standardized conditional residuals of each increment, shape (n, m)."""
        return self.likelihood.standardized_residuals(*self._args(theta))

    def __call__(self, theta: NDArray) -> NDArray:
        """Log posterior density (up to a constant) of each row, shape (n,)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = self.priors.logpdf(theta)
        ok = np.isfinite(lp)
        if np.any(ok):
            ll = self.log_likelihood(theta[ok])
            bad = np.isnan(ll)
            if np.any(bad):
                row = theta[ok][bad][0]
                named = ", ".join(f"{n}={float(v)!r}" for n, v in zip(self.names, row, strict=True))
                raise FloatingPointError(f"the log-likelihood is NaN at {named}")
            lp[ok] = lp[ok] + ll
        return lp
