"""One result type for every classical estimator, and the table of several results."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.integrate

from bayestribo.summary import ParameterSummary, check_prob

__all__ = ["Estimate", "EstimateTable", "friction_fraction"]


def _num(value: Any) -> float | None:
    """A finite float, or None (for JSON: null where a method gives no value)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class Estimate:
    """A point estimate of the damping of one free decay.

    Parameters
    ----------
    method : str
        Estimator name (``"log_decrement"``, ``"feeny_liang"``, ...).
    zeta : float or None
        Equivalent viscous damping ζ (Eq. 6) [-]; None when the method failed.
    zeta_se : float or None
        Standard error of ζ where the method gives one [-].
    mu_k : float or None
        Kinetic friction coefficient μ_k [-] when the load and stiffness are known;
        otherwise None and see ``friction_displacement``.
    mu_k_se : float or None
        Standard error of μ_k [-].
    friction_displacement : float or None
        x_c = μ_k N/k [signal length unit]: the Coulomb force over the stiffness.
        Always given when the method estimates friction.
    friction_displacement_se : float or None
        Standard error of x_c [signal length unit].
    data : str
        What the method used (signal, number of peaks or samples, window).
    notes : str
        Assumptions, corrections, or why no value was produced.
    delta_pi : float or None
        Δ_Π of Eq. 42 at the optimum (energy least squares only) [dimensionless Π].
    covariance : ndarray or None
        Covariance of the fitted parameters ``parameters`` (energy least squares).
    parameters : tuple of str
        Names of the rows/columns of ``covariance``.
    friction_fraction : float or None
        Fraction of the energy dissipated by Coulomb friction over the analysed
        window, from the averaged law (see :func:`friction_fraction`) [-].
    details : mapping
        Method-specific values (β, p and q, initial amplitude, ...).
    """

    method: str
    zeta: float | None = None
    zeta_se: float | None = None
    mu_k: float | None = None
    mu_k_se: float | None = None
    friction_displacement: float | None = None
    friction_displacement_se: float | None = None
    data: str = ""
    notes: str = ""
    delta_pi: float | None = None
    covariance: np.ndarray | None = None
    parameters: tuple[str, ...] = ()
    friction_fraction: float | None = None
    details: Mapping[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when the method produced a damping value."""
        return self.zeta is not None

    def summary(self, prob: float = 0.95) -> dict[str, ParameterSummary]:
        """Normal-approximation summaries (estimate ± z·SE) of each quantity with a
        standard error: ``zeta``, ``mu_k``, ``friction_displacement``.

        Quantities without a value or without a standard error are left out (a point
        value alone has no interval).
        """
        check_prob(prob)
        out = {}
        for name in ("zeta", "mu_k", "friction_displacement"):
            value, se = getattr(self, name), getattr(self, f"{name}_se")
            if _num(value) is not None and _num(se) is not None:
                out[name] = ParameterSummary.from_normal(float(value), float(se), prob)
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping: numbers or None (null)."""
        out: dict[str, Any] = {
            "method": self.method,
            "zeta": _num(self.zeta),
            "zeta_se": _num(self.zeta_se),
            "mu_k": _num(self.mu_k),
            "mu_k_se": _num(self.mu_k_se),
            "friction_displacement": _num(self.friction_displacement),
            "friction_displacement_se": _num(self.friction_displacement_se),
            "friction_fraction": _num(self.friction_fraction),
            "delta_pi": _num(self.delta_pi),
            "data": self.data,
            "notes": self.notes,
        }
        if self.covariance is not None:
            out["covariance"] = {
                "parameters": list(self.parameters),
                "matrix": [[_num(v) for v in row] for row in np.asarray(self.covariance)],
            }
        return out


def _fmt(value: float | None, se: float | None = None) -> str:
    if value is None:
        return "-"
    if se is None:
        return f"{value:.4g}"
    return f"{value:.4g} ± {se:.2g}"


@dataclass
class EstimateTable:
    """The estimates of several methods on one recording.

    Parameters
    ----------
    estimates : list of Estimate
    run : str or None
        Name of the recording.
    """

    estimates: list[Estimate]
    run: str | None = None

    def __iter__(self) -> Iterator[Estimate]:
        return iter(self.estimates)

    def __len__(self) -> int:
        return len(self.estimates)

    def __getitem__(self, key: int | str) -> Estimate:
        if isinstance(key, str):
            for est in self.estimates:
                if est.method == key:
                    return est
            raise KeyError(f"no estimate from method {key!r}")
        return self.estimates[key]

    def summary(self, prob: float = 0.95) -> dict[str, dict[str, ParameterSummary]]:
        """:meth:`Estimate.summary` of each method, by method name.

        Parameters
        ----------
        prob : float
            Probability of the normal-approximation intervals, in (0, 1).

        Returns
        -------
        dict of str to dict of str to ParameterSummary
            ``{method: {"zeta": ..., "mu_k": ..., "friction_displacement": ...}}``; a
            method without any value with a standard error maps to an empty dict.
        """
        check_prob(prob)
        return {e.method: e.summary(prob) for e in self.estimates}

    def to_dict(self) -> dict[str, Any]:
        """``{"run": ..., "estimates": [Estimate.to_dict(), ...]}``."""
        return {"run": self.run, "estimates": [e.to_dict() for e in self.estimates]}

    def to_json(self, indent: int | None = 2) -> str:
        """The table as JSON text (``null`` where a method gives no value)."""
        return json.dumps(self.to_dict(), indent=indent, ensure_ascii=False)

    def to_text(self) -> str:
        """A fixed-width table for the terminal."""
        head = ("method", "data", "zeta", "mu_k", "x_c", "friction share")
        rows = [head]
        for e in self.estimates:
            rows.append(
                (
                    e.method,
                    e.data,
                    _fmt(e.zeta, e.zeta_se),
                    _fmt(e.mu_k, e.mu_k_se),
                    _fmt(e.friction_displacement, e.friction_displacement_se),
                    _fmt(e.friction_fraction),
                )
            )
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
        lines.insert(1, "  ".join("-" * w for w in widths))
        if self.run:
            lines.insert(0, f"run: {self.run}")
        notes = [f"  {e.method} [{e.data}]: {e.notes}" for e in self.estimates if e.notes]
        if notes:
            lines += ["", "notes:", *notes]
        return "\n".join(lines)


def friction_fraction(zeta: float, mu_k: float, a0: float, a_end: float = 0.0) -> float:
    """Share of the dissipated energy due to Coulomb friction, from the averaged law.

    With the averaged amplitude law a' = -ζa - 2μ_k/π (Eq. 32) the energy E = a²/2
    (Eq. 28) decreases at the rate ζa² (viscous) + 2μ_k a/π (friction). Integrating
    the friction part over a from a0 down to a_end, with Γ = 2μ_k/(πζ) (Eq. 36):
    F = ∫ aΓ/(a + Γ) da = Γ(a0 - a_end) - Γ² ln((a0 + Γ)/(a_end + Γ)); the share is
    F/((a0² - a_end²)/2).

    Parameters
    ----------
    zeta, mu_k : float
        Damping ζ [-] and friction (μ_k, or x_c when a0 is in signal units). A
        negative estimate (noise on a negligible term) counts as zero here.
    a0, a_end : float
        Initial and final amplitude, a0 > a_end >= 0 (same unit as ``mu_k``).

    Returns
    -------
    float
        Between 0 (purely viscous) and 1 (purely Coulomb).
    """
    if not (a0 > a_end >= 0.0):
        raise ValueError(f"need a0 > a_end >= 0, got a0={a0!r}, a_end={a_end!r}")
    zeta = max(float(zeta), 0.0)
    mu_k = max(float(mu_k), 0.0)
    if mu_k == 0.0:
        return 0.0
    if zeta == 0.0:
        return 1.0
    g = 2.0 * mu_k / (math.pi * zeta)
    # friction power over total power at amplitude a is Γ/(a + Γ); quadrature is
    # stable for any Γ (the closed form cancels catastrophically when Γ >> a0)
    f = scipy.integrate.quad(lambda a: a * g / (a + g), a_end, a0)[0]
    return float(f / (0.5 * (a0 * a0 - a_end * a_end)))
