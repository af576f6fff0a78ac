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
  the kinetic friction; on a record that ends in motion, which holds no stick, the
  ratio μ_s/μ_k itself.

Then θ = (μ_k, μ_s/μ_k, ζ_α, α) = (A_r(λ − 4πζ_α)/8, μ_s/μ_k, d/h(α), e^a); ∂θ/∂u is
triangular in the order (α, ζ_α, μ_k, μ_s/μ_k) against (a, d, λ, μ_s), and
log |det ∂θ/∂u| = ln(A_r/8) − ln h(α) + a − ln μ_k (without − ln μ_k where the ratio
is sampled).

Why the ratio where the record ends in motion: there the end of motion measures
nothing, μ_s/μ_k is its prior's wherever μ_k is small (no stick before the record's
end), and μ_s ranges over [μ_k, 10 μ_k], a wedge that closes as μ_k → 0 (a
seismometer's record, whose magnet's drag holds the whole loss): the exact sampler
walked it at τ 40-90 steps, where in the ratio the same posterior is a product near
μ_k = 0 (τ 11-37, the fits 0.6-0.8 of the time, ``benchmarks/README.md``).
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
    ended : bool
        Whether the record holds the end of the motion: the static friction μ_s is
        sampled where it does, the ratio μ_s/μ_k where it does not.
    """

    reference: float
    lowest: float
    ended: bool = True
    law_names: tuple[str, ...] = ("mu_k", "mu_s_ratio", "zeta_alpha", "alpha")

    @property
    def names(self) -> tuple[str, ...]:
        """The sampling coordinates: the static friction where the record holds its
        end of motion, else the ratio μ_s/μ_k."""
        static = "static_friction" if self.ended else "static_ratio"
        return ("loss_per_cycle", static, "drag_shape", "log_alpha")

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
            if self.ended:
                # no kinetic friction: μ_s/μ_k undefined, the row outside the prior
                ratio = np.where(mu_k > 0.0, static / np.where(mu_k > 0.0, mu_k, 1.0), np.inf)
            else:
                ratio = static
        return np.column_stack([mu_k, ratio, zeta, alpha])

    def from_law(self, theta: NDArray) -> NDArray:
        """(λ, μ_s, d, ln α) of rows ``theta`` = (μ_k, μ_s/μ_k, ζ_α, α), shape (n, 4)
        (μ_s/μ_k in place of μ_s where the record ends in motion); α below
        :data:`ALPHA_FLOOR` is taken at it."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        mu_k, ratio, zeta = theta[:, 0], theta[:, 1], theta[:, 2]
        alpha = np.maximum(theta[:, 3], ALPHA_FLOOR)
        loss = 8.0 * mu_k / self.reference + 4.0 * math.pi * zeta
        static = mu_k * ratio if self.ended else ratio
        return np.column_stack([loss, static, zeta * self._shape(alpha), np.log(alpha)])

    def log_jacobian(self, u: NDArray) -> NDArray:
        """ln |det ∂θ/∂u| = ln(A_r/8) − ln h(α) + ln α − ln μ_k (without − ln μ_k where
        the ratio is sampled), shape (n,)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        log_alpha = u[:, 3]
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            h = self._shape(np.exp(log_alpha))
            out = math.log(self.reference / 8.0) - np.log(h) + log_alpha
            if self.ended:
                out = out - np.log(self.to_law(u)[:, 0])
            return out


register_transform(("coulomb", "power"), LossShare)
