"""A posterior sampled in its law's sampling coordinates, its draws reported in the law's own.

Where the law declares a sampling transform (:mod:`bayestribo.model.laws.transforms`)
and its parameters are all sampled, :class:`Reparameterised` is the same posterior
density in the transform's coordinates u: the columns of the law's parameters it
replaces are u's, the others (μ_s/μ_k, y0, the discrepancy scales, any other term's)
are as they are, and

    log p_u(u) = log p(θ(u)) + log |det ∂θ/∂u|,

the law's own prior carried through the change of variables (the density is −inf
where θ(u) is outside the prior's support). The sampler runs on it as on any
posterior (:func:`~bayestribo.inference.sampling.run_ensembles`); :meth:`law_run`
maps the run back: draws in θ, the log posterior of θ, R-hat of θ, and the
autocorrelation time and effective sample size of each replaced parameter the
longest and the least over the transform's coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.rhat import rhat
from bayestribo.inference.sampling import SamplerRun
from bayestribo.model.laws.transforms import SamplingTransform

__all__ = ["Reparameterised", "lowest_amplitude", "reparameterised"]


def lowest_amplitude(posterior) -> float:
    """The record's smallest amplitude (dimensionless) from its increments: the mean
    energy over each increment D_j/Δτ_j is A²/2; the least over the last tenth of
    them, its square root times √2 (NaN where the increments do not say)."""
    data = posterior.likelihood.data
    tau = np.asarray(data.tau_grid, dtype=float)
    increments = np.asarray(data.increments, dtype=float)
    if increments.size < 2 or tau.size != increments.size + 1:
        return math.nan
    energy = increments / np.diff(tau)
    tail = energy[-max(1, energy.size // 10) :]
    tail = tail[tail > 0.0]
    return float(np.sqrt(2.0 * tail.min())) if tail.size else math.nan


def reparameterised(posterior) -> Reparameterised | None:
    """``posterior`` in its law's sampling coordinates, or None where the law declares
    none (or some parameter it replaces is fixed)."""
    transform = posterior.law.sampling_transform(
        posterior.names,
        posterior.likelihood.reference_amplitude,
        lowest_amplitude(posterior),
        bool(getattr(posterior.likelihood.data, "motion_ended", True)),
    )
    return None if transform is None else Reparameterised(posterior, transform)


@dataclass(frozen=True)
class Reparameterised:
    """A log posterior density in a sampling transform's coordinates.

    Parameters
    ----------
    posterior : callable
        The log posterior density of rows θ (n, d) -> (n,), with ``names``.
    transform : SamplingTransform
        Replaces the columns of ``transform.law_names`` (all in ``posterior.names``).
    """

    posterior: object
    transform: SamplingTransform

    def __post_init__(self) -> None:
        names = list(self.posterior.names)
        missing = [n for n in self.transform.law_names if n not in names]
        if missing:
            raise ValueError(f"transform: {missing} are not sampled coordinates of {names}")
        object.__setattr__(self, "columns", tuple(names.index(n) for n in self.transform.law_names))

    @property
    def names(self) -> list[str]:
        """The sampled coordinates: the posterior's, the transform's in place of the
        parameters it replaces."""
        names = list(self.posterior.names)
        for i, name in zip(self.columns, self.transform.names, strict=True):
            names[i] = name
        return names

    def to_theta(self, u: NDArray) -> NDArray:
        """Rows θ of the posterior from rows ``u`` (..., d)."""
        u = np.asarray(u, dtype=float)
        flat = u.reshape(-1, u.shape[-1]).copy()
        flat[:, self.columns] = self.transform.to_law(flat[:, self.columns])
        return flat.reshape(u.shape)

    def from_theta(self, theta: NDArray) -> NDArray:
        """Rows u from rows ``theta`` (..., d) inside the prior's support."""
        theta = np.asarray(theta, dtype=float)
        flat = theta.reshape(-1, theta.shape[-1]).copy()
        flat[:, self.columns] = self.transform.from_law(flat[:, self.columns])
        return flat.reshape(theta.shape)

    def __call__(self, u: NDArray) -> NDArray:
        """log p(θ(u)) + log |det ∂θ/∂u| of each row of ``u`` (n, d), shape (n,)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        lp = np.full(u.shape[0], -np.inf)
        theta = self.to_theta(u)
        inside = np.all(np.isfinite(theta), axis=1)
        if np.any(inside):
            lp[inside] = self.posterior(theta[inside])
            jac = self.transform.log_jacobian(u[inside][:, self.columns])
            ok = np.isfinite(lp[inside])
            lp[np.flatnonzero(inside)[ok]] += jac[ok]
        return lp

    def initial(self, walkers: NDArray, rng: np.random.Generator) -> NDArray:
        """Starting positions in u of ``walkers`` θ (ensembles, walkers, d): mapped,
        and a coordinate that has one value across an ensemble (θ on a bound, where
        u is taken at the bound's side) spread by a relative 1e-6 where the density
        stays finite, so that the ensemble's moves can move it."""
        u = self.from_theta(walkers)
        for e in range(u.shape[0]):
            for i in self.columns:
                column = u[e, :, i]
                if np.ptp(column) > 0.0:
                    continue
                moved = u[e].copy()
                size = 1e-6 * max(1.0, abs(float(column[0])))
                moved[:, i] = column + size * rng.standard_normal(column.size)
                ok = np.isfinite(self(moved))
                u[e, ok, i] = moved[ok, i]
        return u

    def law_run(self, run: SamplerRun) -> SamplerRun:
        """The run of this density mapped back to the posterior's coordinates.

        Draws θ(u); the log posterior of θ (the sampled one less the log Jacobian);
        R-hat of θ; a run not converged says, after its reasons, which coordinates
        they name; each replaced parameter's autocorrelation time the longest, and
        its effective sample size the least, over the transform's coordinates (each
        θ of them is a function of all); the other coordinates' as sampled.
        """
        chains = self.to_theta(run.chains)
        flat = run.chains.reshape(-1, run.chains.shape[-1])
        jac = self.transform.log_jacobian(flat[:, self.columns]).reshape(run.log_prob.shape)
        cols = list(self.columns)
        tau = np.array(run.autocorr_time, dtype=float)
        ess = np.array(run.ess, dtype=float)
        if tau.size == chains.shape[-1]:
            tau[cols] = np.max(tau[cols])
        if ess.size == chains.shape[-1]:
            ess[cols] = np.min(ess[cols])
        r_hat = rhat(chains) if chains.shape[1] >= 4 else run.rhat
        names = tuple(self.posterior.names) if run.names else run.names
        reasons = list(run.reasons)
        if reasons:
            # the reasons name the sampled coordinates; say what they stand for
            reasons.append(
                f"the sampler ran in the coordinates {', '.join(self.transform.names)} in "
                f"place of {', '.join(self.transform.law_names)} "
                f"({type(self.transform).__module__}); the reasons above name them"
            )
        return replace(
            run,
            reasons=reasons,
            chains=chains,
            log_prob=run.log_prob - jac,
            autocorr_time=tau,
            ess=ess,
            rhat=np.asarray(r_hat, dtype=float),
            names=names,
        )
