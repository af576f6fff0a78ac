r"""Coulomb friction beside power-law drag, sampled as the loss, the drag's shape and log α.

In the law's own parameters (μ_k, ζ_α, α) the posterior of a record whose ΔE(A) is
about linear in A is an L: the drag is ~0 and α anything, or α ~ 0 (a drag of
constant magnitude, a friction that does not stick) and ζ_α anything, μ_k carrying
the rest of the loss. The sampler then crosses it in thousands of steps. This
transform (:mod:`bayestribo.model.laws.transforms`) samples

* λ = ΔE(A_r)/E(A_r) = 8μ_k/A_r + 4πζ_α: the energy the two terms dissipate over one
  cycle at the reference amplitude A_r, over the energy there;
* d = ζ_α h(α), h(α) = 1 − ρ^α with ρ the record's smallest amplitude over A_r: how
  much the drag's share of the force changes over the record's amplitudes (the
  drag's ΔE(A)/A goes as (A/A_r)^α, friction's is constant), which the record
  measures whatever α is; the two arms of the L (ζ_α ~ 0, and α ~ 0) are both d ~ 0;
* a = ln α, so that α, spread over decades where d ~ 0, is spread evenly;
* μ_s = μ_k (μ_s/μ_k): the static friction, which the record's end of motion
  measures, where μ_s/μ_k trades against μ_k as the drag at α ~ 0 takes a share of
  the kinetic friction.

Then θ = (μ_k, μ_s/μ_k, ζ_α, α) = (A_r(λ − 4πζ_α)/8, μ_s/μ_k, d/h(α), e^a); ∂θ/∂u is
triangular in the order (α, ζ_α, μ_k, μ_s/μ_k) against (a, d, λ, μ_s), and
log |det ∂θ/∂u| = ln(A_r/8) − ln h(α) + a − ln μ_k.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws.transforms import register_transform

__all__ = ["ALPHA_FLOOR", "LossShare"]

#: The least α mapped to ln α: a θ with α below it (on α's bound 0, where the drag is
#: a friction that does not stick, whatever α is there) starts at it.
ALPHA_FLOOR = 1e-8
#: The range of ρ, the record's smallest amplitude over the reference one.
_RHO = (1e-3, 0.95)


@dataclass(frozen=True)
class LossShare:
    """The sampling transform of ``coulomb`` and ``power`` (see the module notes).

    Parameters
    ----------
    reference : float
        A_r, the reference amplitude of ζ_α (dimensionless, > 0).
    lowest : float
        The record's smallest amplitude (dimensionless); ρ = lowest/reference, held
        within [1e-3, 0.95].
    """

    reference: float
    lowest: float
    law_names: tuple[str, ...] = ("mu_k", "mu_s_ratio", "zeta_alpha", "alpha")
    names: tuple[str, ...] = ("loss_per_cycle", "static_friction", "drag_shape", "log_alpha")

    def __post_init__(self) -> None:
        if not (math.isfinite(self.reference) and self.reference > 0.0):
            raise ValueError(f"reference: expected a positive amplitude, got {self.reference!r}")

    @property
    def log_rho(self) -> float:
        """ln ρ, ρ the record's smallest amplitude over the reference (< 0)."""
        ratio = self.lowest / self.reference if math.isfinite(self.lowest) else _RHO[0]
        return math.log(min(max(ratio, _RHO[0]), _RHO[1]))

    def _shape(self, alpha: NDArray) -> NDArray:
        """h(α) = 1 − ρ^α."""
        return -np.expm1(alpha * self.log_rho)

    def to_law(self, u: NDArray) -> NDArray:
        """(μ_k, μ_s/μ_k, ζ_α, α) of rows ``u`` = (λ, μ_s, d, ln α), shape (n, 4)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        loss, static, shape, log_alpha = u.T
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            alpha = np.exp(log_alpha)
            h = self._shape(alpha)
            # α so small that h underflows: ζ_α is undefined, the row outside the prior
            zeta = np.where(h > 0.0, shape / np.where(h > 0.0, h, 1.0), np.inf)
            mu_k = self.reference * (loss - 4.0 * math.pi * zeta) / 8.0
            # no kinetic friction: μ_s/μ_k undefined, the row outside the prior
            ratio = np.where(mu_k > 0.0, static / np.where(mu_k > 0.0, mu_k, 1.0), np.inf)
        return np.column_stack([mu_k, ratio, zeta, alpha])

    def from_law(self, theta: NDArray) -> NDArray:
        """(λ, μ_s, d, ln α) of rows ``theta`` = (μ_k, μ_s/μ_k, ζ_α, α), shape (n, 4);
        α below :data:`ALPHA_FLOOR` is taken at it."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        mu_k, ratio, zeta = theta[:, 0], theta[:, 1], theta[:, 2]
        alpha = np.maximum(theta[:, 3], ALPHA_FLOOR)
        loss = 8.0 * mu_k / self.reference + 4.0 * math.pi * zeta
        return np.column_stack([loss, mu_k * ratio, zeta * self._shape(alpha), np.log(alpha)])

    def log_jacobian(self, u: NDArray) -> NDArray:
        """ln |det ∂θ/∂u| = ln(A_r/8) − ln h(α) + ln α − ln μ_k, shape (n,)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        mu_k = self.to_law(u)[:, 0]
        log_alpha = u[:, 3]
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            h = self._shape(np.exp(log_alpha))
            return math.log(self.reference / 8.0) - np.log(h) + log_alpha - np.log(mu_k)


register_transform(("coulomb", "power"), LossShare)
