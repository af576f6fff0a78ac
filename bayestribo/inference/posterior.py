"""Posterior = priors × likelihood, vectorised over walkers.

The sampled vector holds, in order, the names of the :class:`PriorSet`: the
parameters of the likelihood's dissipation law (:mod:`bayestribo.model.laws`; for the
default law ``zeta``, and with friction ``mu_k`` and ``mu_s_ratio``: μ_s = μ_k × ratio
keeps μ_s >= μ_k without a constraint between coordinates), ``y0``, and optionally
``log10_discrepancy`` and ``log10_shape`` (the white and the shape discrepancy's scales,
:mod:`bayestribo.inference.likelihood`). A parameter may instead be *fixed* at a value (for example
``zeta = 0`` for a Coulomb-only law): it is then not sampled, has no prior, and enters
the likelihood at that value.

One rule for invalid densities: a point outside the prior's support has density 0
(log density −inf) and the likelihood is not evaluated there; a NaN log-likelihood
inside the support is a bug or a broken input, and raises an error that names the
parameters, never a silent −inf.

Two implementations of the same density: :meth:`Posterior.__call__` evaluates all
rows in one compiled call (:class:`~bayestribo.inference.fused.FusedLogPosterior`)
whenever the priors and the likelihood are of the kinds it compiles, and
:meth:`Posterior.reference` with numpy (priors' ``logpdf`` and
:meth:`PiLikelihood.log_likelihood`), the reference the tests hold the compiled one
to (1e-10 of max(1, |log p|)). ``compiled=False`` makes ``__call__`` the reference.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.fused import FusedLogPosterior
from bayestribo.inference.fused_residuals import residual_rows
from bayestribo.inference.fused_step import grouped_step, independence_step
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.priors import PriorSet
from bayestribo.inference.sampling import NaNLogProbabilityError
from bayestribo.model.laws import Law

__all__ = ["PARAMETERS", "Posterior"]

#: Every parameter the single-run posterior of the default law knows, in sampling order.
PARAMETERS = ("zeta", "mu_k", "mu_s_ratio", "y0", "log10_discrepancy", "log10_shape")
#: The parameters of every law besides the law's own.
_COMMON = ("y0", "log10_discrepancy", "log10_shape")


@dataclass(frozen=True)
class Posterior:
    """Log posterior density of the single-run fit.

    Parameters
    ----------
    priors : PriorSet
        Independent priors of the sampled parameters; their names define the sampled
        vector.
    likelihood : PiLikelihood
        Likelihood of the Π increments.
    fixed : mapping of str to float, optional
        Parameters held at a value instead of sampled (the law's parameters, ``y0``
        or a discrepancy scale, not also in ``priors``). A parameter of the law that
        is neither sampled nor fixed takes its null value (no force; μ_s = μ_k).
    compiled : bool
        Evaluate ``__call__`` with the compiled log density where it applies (the
        default); False: always with the numpy reference.
    """

    priors: PriorSet
    likelihood: PiLikelihood
    fixed: Mapping[str, float] = field(default_factory=dict)
    compiled: bool = True

    def __post_init__(self) -> None:
        fixed = {str(k): float(v) for k, v in dict(self.fixed).items()}
        known = self.parameters
        for name, value in fixed.items():
            if name not in known:
                raise BayestriboError(f"fixed: unknown parameter {name!r}; expected {known}")
            if name in self.priors.names:
                raise BayestriboError(f"fixed: {name!r} is also sampled (it has a prior)")
            if not math.isfinite(value):
                raise BayestriboError(f"fixed: {name} must be a finite number, got {value!r}")
        for parameter in getattr(self.likelihood.law, "parameters", ()):
            value = fixed.get(parameter.name)
            if value is not None and not parameter.low <= value <= parameter.high:
                # outside what the law means (a negative friction feeds the motion)
                raise BayestriboError(
                    f"fixed (--fix): {parameter.name} ({parameter.label}) must lie in "
                    f"[{parameter.low:g}, {parameter.high:g}], got {value:g}"
                )
        unknown = [n for n in self.priors.names if n not in known]
        if unknown:
            raise BayestriboError(f"priors: unknown parameter(s) {unknown}; expected {known}")
        if "y0" not in self.priors.names and "y0" not in fixed:
            raise BayestriboError("priors: 'y0' must be sampled or fixed")
        object.__setattr__(self, "fixed", fixed)
        fused = (
            FusedLogPosterior.build(self.priors, self.likelihood, fixed) if self.compiled else None
        )
        object.__setattr__(self, "_fused", fused)

    @property
    def law(self) -> Law:
        """The dissipation law of the likelihood."""
        return self.likelihood.law

    @property
    def parameters(self) -> tuple[str, ...]:
        """Every parameter this posterior knows: the law's, ``y0`` and the discrepancy
        scales."""
        return (*self.law.parameter_names, *_COMMON)

    @property
    def uses_compiled(self) -> bool:
        """True when ``__call__`` evaluates the compiled log density."""
        return self._fused is not None

    @property
    def grouped_step(self) -> Callable[..., int] | None:
        """A whole step of the sampler's grouped moves with the compiled density
        (:func:`bayestribo.inference.fused_step.grouped_step`; the protocol is in
        :mod:`bayestribo.inference.moves`), or None where :attr:`uses_compiled` is
        False."""
        fused: FusedLogPosterior | None = self._fused
        return None if fused is None else partial(grouped_step, fused)

    @property
    def independence_step(self) -> Callable[..., bool] | None:
        """A whole step of the independence move with the compiled density
        (:func:`bayestribo.inference.fused_step.independence_step`), or None where
        :attr:`uses_compiled` is False."""
        fused: FusedLogPosterior | None = self._fused
        return None if fused is None else partial(independence_step, fused)

    @property
    def residual_rows(self) -> Callable[..., NDArray | None] | None:
        """The start stage's least-squares residuals in one compiled call
        (:func:`bayestribo.inference.fused_residuals.residual_rows`, its arguments
        after the tables), or None where :attr:`uses_compiled` is False."""
        fused: FusedLogPosterior | None = self._fused
        return None if fused is None else partial(residual_rows, fused)

    @property
    def names(self) -> list[str]:
        """Names of the sampled coordinates."""
        return self.priors.names

    @property
    def friction(self) -> bool:
        """True when the model has Coulomb friction (μ_k sampled, or fixed above 0)."""
        return "mu_k" in self.names or self.fixed.get("mu_k", 0.0) > 0.0

    def law_draws(self, theta: NDArray) -> dict[str, NDArray]:
        """Every parameter of the law for rows ``theta`` (n, d), each (n,): sampled,
        fixed, or at its null value (no force; μ_s/μ_k = 1)."""
        values = self.values(theta)
        n = np.atleast_2d(theta).shape[0]
        return {
            p.name: values[p.name] if p.name in values else np.full(n, p.null)
            for p in self.law.parameters
        }

    def values(self, theta: NDArray) -> dict[str, NDArray]:
        """Sampled and fixed coordinates of rows ``theta`` (n, d) by name, each (n,)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = {name: np.full(theta.shape[0], value) for name, value in self.fixed.items()}
        out.update({name: theta[:, i] for i, name in enumerate(self.names)})
        return out

    def physical(self, theta: NDArray) -> dict[str, Any]:
        """The likelihood's arguments from sampled rows ``theta`` (n, d).

        Returns
        -------
        dict
            ``params``: the law's parameters and ``y0`` by name, each (n,);
            ``discrepancy`` (white) and ``shape``: the discrepancy scales, each (n, 1),
            or ``None`` without that term.
        """
        col = self.values(theta)
        params = self.law_draws(theta)
        params["y0"] = col["y0"]
        log_s = col.get("log10_discrepancy")
        log_c = col.get("log10_shape")
        return {
            "params": params,
            "discrepancy": None if log_s is None else 10.0 ** log_s[:, None],
            "shape": None if log_c is None else 10.0 ** log_c[:, None],
        }

    def _likelihood_args(self, theta: NDArray) -> tuple:
        p = self.physical(theta)
        return p["params"], p["discrepancy"], p["shape"]

    def log_likelihood(self, theta: NDArray) -> NDArray:
        """Log-likelihood of each row (nuisance offset marginalised), shape (n,)."""
        return self.likelihood.log_likelihood(*self._likelihood_args(theta))

    def pointwise(self, theta: NDArray) -> NDArray:
        """Conditional log-likelihood of each increment for each row, shape (n, m)."""
        return self.likelihood.pointwise(*self._likelihood_args(theta))

    @property
    def residual_size(self) -> int:
        """Columns of :meth:`standardized_residuals` with ``nuisances``: the increments
        and the linear nuisances (the shape coefficients where the shape discrepancy is
        sampled or fixed)."""
        shape = "log10_shape" in self.names or "log10_shape" in self.fixed
        return self.likelihood.data.increments.size + self.likelihood.design(shape).shape[1]

    def log_prior(self, theta: NDArray) -> NDArray:
        """Joint log prior density of each row of ``theta`` (n, d), −inf outside the
        priors' support: compiled where :attr:`uses_compiled` (the optimiser of the
        starting point tests every point it evaluates), else
        :meth:`PriorSet.logpdf <bayestribo.inference.priors.PriorSet.logpdf>`."""
        fused: FusedLogPosterior | None = self._fused
        theta = np.asarray(theta, dtype=float)
        if fused is not None and theta.ndim == 2 and theta.shape[1] == len(self.names):
            return fused.log_prior(theta)
        return self.priors.logpdf(theta)

    def standardized_residuals(self, theta: NDArray, nuisances: bool = False) -> NDArray:
        """Standardized conditional residuals of each increment, shape (n, m); with
        ``nuisances`` the linear nuisances' conditional means over their prior sd
        follow, (n, m + q) (:meth:`PiLikelihood.standardized_residuals`).

        Compiled where :attr:`uses_compiled` (the optimiser of the starting point
        calls it hundreds of times), else
        :meth:`PiLikelihood.standardized_residuals`, the reference.
        """
        fused: FusedLogPosterior | None = self._fused
        theta = np.asarray(theta, dtype=float)
        if fused is not None and theta.ndim == 2 and theta.shape[1] == len(self.names):
            out, flagged = fused.standardized_residuals(theta, nuisances)
            if not flagged:
                return out
        return self.likelihood.standardized_residuals(
            *self._likelihood_args(theta), nuisances=nuisances
        )

    def __call__(self, theta: NDArray) -> NDArray:
        """Log posterior density (up to a constant) of each row, shape (n,).

        The compiled density where it applies (:attr:`uses_compiled`), else
        :meth:`reference`; both give −inf outside the priors' support.

        Raises
        ------
        NaNLogProbabilityError
            If the log-likelihood is NaN inside the prior's support (the message
            names the parameters).
        BayestriboError
            If ``theta`` does not have one column per sampled parameter.
        """
        theta = np.asarray(theta, dtype=float)
        if theta.ndim == 1:
            theta = theta[None]
        if theta.ndim != 2 or theta.shape[1] != len(self.names):
            raise BayestriboError(
                f"theta: expected rows of {len(self.names)} values ({', '.join(self.names)}), "
                f"got shape {theta.shape}"
            )
        fused: FusedLogPosterior | None = self._fused
        if fused is None:
            return self.reference(theta)
        lp, flagged = fused(theta)
        if flagged:
            # Outside the averaged model's domain, or NaN: the reference raises the
            # error that names the cause (or gives the NaN of a NaN prior density).
            return self.reference(theta)
        return lp

    def reference(self, theta: NDArray) -> NDArray:
        """Log posterior density of each row with numpy (the reference), shape (n,).

        Raises
        ------
        NaNLogProbabilityError
            If the log-likelihood is NaN inside the prior's support (the message
            names the parameters).
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        lp = self.priors.logpdf(theta)
        ok = np.isfinite(lp)
        if np.any(ok):
            ll = self.log_likelihood(theta[ok])
            bad = np.isnan(ll)
            if np.any(bad):
                row = theta[ok][bad][0]
                named = ", ".join(f"{n}={float(v)!r}" for n, v in zip(self.names, row, strict=True))
                raise NaNLogProbabilityError(f"the log-likelihood is NaN at {named}")
            lp[ok] = lp[ok] + ll
        return lp
