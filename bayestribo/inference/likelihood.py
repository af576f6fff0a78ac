r"""Gaussian likelihood of the observed Π increments under the exact or averaged model.

See :mod:`bayestribo.signal.increments` for why the observation is a set of independent
increments of Π. For parameters θ the model increments are
``M_j = Π_θ(τ_j) - Π_θ(τ_{j+1})`` for all but the last, and the last is
``Π_θ(τ_{m-1})``: when the record holds the end of motion, the model's Π runs to the
model's own end of motion (so a model that stops later or earlier than the record is
penalised by the energy it adds or misses); otherwise it is truncated at the end of the
record like the data.

**Equilibrium nuisance.** The equilibrium of the displacement is estimated from the
turning points with an error δ(τ) = δ₀ + δ₁τ of order 1e-4 of the length scale, which
shifts every observed increment by ``-δ₀∫y - δ₁∫τy`` (an oscillating term, as large as
the noise of a vibrometer-grade record). δ₀ and δ₁ are nuisance parameters with
Gaussian priors (standard deviations ``offset_sd`` and ``drift_sd``); they enter the
residuals linearly and are marginalised analytically (a two-dimensional Gaussian
integral per evaluation):

.. math::

    \log L = -\tfrac12\left[r^\top W r - b^\top A^{-1} b\right]
             - \tfrac12 \sum_j \log 2πV_j - \tfrac12 \log|A| - \tfrac12 \log|P|,

with ``r = D - M``, ``W = diag(1/V)``, design ``X`` (∫y, ∫τy per increment),
``A = XᵀWX + P⁻¹``, ``b = XᵀWr`` and ``P`` the prior covariance. The pointwise
log-likelihood (for PSIS-LOO) is the conditional one at the conditional mean
``δ̂ = A⁻¹b``.

**Correlated increments.** Where the noise of the increments is correlated (a
displacement integrated from the velocity: :attr:`~bayestribo.signal.increments.
PiData.correlation` R, the covariance ``√V_i R_ij √V_j``), the residuals and the
design are whitened once by ``T = L⁻¹``, R = LLᵀ (:attr:`PiLikelihood.whitening`):
``r → T(r/√V)``, ``X → T(X/√V)``, and W above becomes the identity on them, with
``log|R|`` added to ``Σ log V``. The white discrepancy's term is taken with the
same correlation (the variances scaled, R kept), which keeps one whitening for every
parameter set. The pointwise log-likelihood of an increment is then its density
given all the others (:meth:`PiLikelihood.pointwise`).

**Noise-level nuisance.** The noise bias removed from each increment rests on σ²
measured in the recording, known to a relative √(2/n) or so: a third column of the
design, the bias's standard error per increment (:attr:`~bayestribo.signal.
increments.PiData.offset_design`), enters with a standard normal coefficient and is
marginalised with δ₀ and δ₁ (prior precision 1, so ``log|P|`` is unchanged).

**Model discrepancy** (optional), for what the physics leaves out, in two parts:

* a relative, white error on E of intensity s² per unit τ adds ``s² ∫_j E² dτ`` to the
  variance of increment j; like the noise, it does not depend on how finely Π is
  gridded;
* a **shape** discrepancy correlated along the decay, for a law whose decay has another
  shape (drag that grows with amplitude, friction that varies along the track, a
  stiffness that depends on amplitude): a smooth relative departure of the increments,
  ``D_j g(u_j)`` with ``g(u) = Σ_k c_k P_k(u)`` (Legendre polynomials of degree
  < :data:`SHAPE_TERMS` in the position u ∈ [-1, 1] of the increment along the
  record), coefficients ``c_k ~ N(0, s_c²)``. Equivalently a Gaussian process over
  the increments with the low-rank covariance ``s_c² (D∘P)(D∘P)ᵀ``. The coefficients
  enter the residuals linearly and are marginalised with the equilibrium nuisance
  (the design gains the columns ``D_j P_k(u_j)``, the prior covariance ``s_c² I``).
  Its low-order terms overlap with the law's own parameters (a constant with y0, a
  slope with ζ): that is the point. A departure of the decay that a change of ζ could
  also explain widens ζ's interval by as much as the data cannot tell them apart.
  The law's increments at the first pass's optimum stand in for the model's in the
  design (:attr:`~bayestribo.signal.increments.PiData.law_increments`; the
  observed ones when the data do not hold them). The observed ones would not do
  below the noise: in the tail of a record at 30 times the vibrometer's resolution
  they are the noise's energy within ±40 %, and a departure fitted on columns that
  hold the residuals' own noise finds one (+49 % ± 9 % on a record of the law
  itself, p = 5e-6).

:meth:`PiLikelihood.shape_departure` tests the residuals at one parameter set for a
smooth departure of this form (χ² of the coefficients' least squares against their
noise covariance) and says by how much the decay departs from the law.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np
import scipy.linalg
import scipy.stats
from numpy.typing import NDArray

from bayestribo.model import averaged_pi
from bayestribo.model.laws import Law, get_law
from bayestribo.signal.increments import PiData

__all__ = [
    "BASE_NUISANCES",
    "INTEGRATOR_SHARE",
    "MODELS",
    "NEAR_ZERO",
    "SHAPE_TERMS",
    "Params",
    "PiLikelihood",
    "ShapeDeparture",
    "departure_size",
]

#: Parameter values by name: the law's parameters and ``y0``, arrays of shape (n,) or
#: (n, 1) (a parameter of the law that is missing takes its null value,
#: :attr:`~bayestribo.model.laws.Parameter.null`: no force, or μ_s = μ_k).
Params = Mapping[str, NDArray]

MODELS = ("exact", "averaged")
ModelName = Literal["exact", "averaged"]
_LOG_2PI = math.log(2.0 * math.pi)
#: Legendre terms (degrees 0 .. SHAPE_TERMS - 1) of the shape discrepancy.
SHAPE_TERMS = 4
#: The integrator's error allowed in Π (a law without a closed form), as a share of the
#: smallest noise sd of the increments over √m (:attr:`PiLikelihood.integrator_tolerance`).
INTEGRATOR_SHARE = 1e-2
#: Linear nuisances every likelihood has: the equilibrium's offset δ₀ and drift δ₁,
#: and the noise level's error (standard normal).
BASE_NUISANCES = 3


@dataclass(frozen=True)
class PiLikelihood:
    """Likelihood of Π increments with the equilibrium error marginalised.

    Parameters
    ----------
    data : PiData
        Observed increments and their noise variances.
    model : {"exact", "averaged"}
        Forward model: the exact piecewise solution with sticking (default), or the
        averaged closed form (Eq. 40-41; no static friction, amplitude √(y0² + y'0²);
        only for laws of viscous damping and Coulomb friction).
    offset_sd : float
        Prior standard deviation of the equilibrium error δ₀ [units of y].
    drift_sd : float
        Prior standard deviation of its drift δ₁ [units of y per unit τ].
    law : Law
        The dissipation law (:mod:`bayestribo.model.laws`; default viscous damping
        and Coulomb friction).
    steps : int
        Runge-Kutta steps per half cycle of the law's integrator where it has no
        closed form: 0 (the default) chooses them per half cycle for Π within the
        error its increments' noise allows (:attr:`integrator_tolerance`; ~2e-9 of Π(0)
        where the noise allows no more); a small fixed number is the coarse model on
        which the optimiser's multi-start runs
        (:func:`bayestribo.inference.start.maximum_a_posteriori`), its sum past the
        record shortened (:attr:`integrator_steps`).
    """

    data: PiData
    model: ModelName = "exact"
    offset_sd: float = 1e-2
    drift_sd: float = 1e-4
    law: Law = field(default_factory=get_law)
    steps: int = 0

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise ValueError(f"model must be one of {MODELS}, got {self.model!r}")
        # the run's restoring force (its energy's potential) is the law's
        restoring = getattr(self.data, "restoring", None)
        object.__setattr__(self, "law", get_law(self.law).with_restoring(restoring))
        if self.model == "averaged" and not self.law.closed_form:
            raise ValueError(
                f"model='averaged' has no closed form for the law {self.law.name}; use "
                "model='exact'"
            )
        for name in ("offset_sd", "drift_sd"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if not (isinstance(self.steps, int | np.integer) and self.steps >= 0):
            raise ValueError(f"steps must be a non-negative integer, got {self.steps!r}")

    # -- model --------------------------------------------------------------------
    @property
    def integrator_steps(self) -> int:
        """The ``steps`` of :meth:`bayestribo.model.laws.Law.pi_grid`: 0, or -:attr:`steps`
        for a coarse model (that many steps per half cycle, and past the record of a
        motion that ended the sum of those half cycles shortened where they hold
        nothing and taken from their averaged flow, instead of up to 20,000 of them
        one by one)."""
        return -int(self.steps)

    @cached_property
    def integrator_tolerance(self) -> float | None:
        """The error of Π allowed where a law without a closed form is integrated with
        the steps chosen per half cycle (:meth:`bayestribo.model.laws.Law.pi_grid`'s
        ``tolerance``, a fraction of Π(0)): :data:`INTEGRATOR_SHARE` of the smallest
        noise sd of the m increments (with correlated noise, of the covariance's
        smallest eigenvalue's root) over √m, over the observed Π(0).

        An error of the model's increments moves the posterior by at most its length
        in units of the noise (whitened), which a bias common to all m increments makes
        √m times one's: at ε/√m of the smallest sd each (ε the share), less than ε sd
        however the errors line up; the integrator's error is within a few times its
        tolerance and an increment is a difference of two Π, so the posterior moves by
        less than about 6ε = 0.06 sd (on nine real records' laws the increments move
        by less than 1e-4 of their sd together, the 32 steps' floor holding the error
        far below what is allowed: ``benchmarks/results/tolerance_shift.json``). The
        scheme's usual steps hold Π within ~2e-9 of Π(0), 3-6 % of the smallest sd on
        a vibrometer's record and 1e-7 of it on a seismometer's: on a record as noisy
        as most, the steps fall as the fourth root of what the noise allows (to 32 a
        half cycle at least). None (the usual steps) for a coarse model of fixed
        steps, or where the noise or Π(0) is not positive."""
        if self.steps:
            return None
        data = self.data
        variance = np.asarray(data.variance, dtype=float)
        correlation = getattr(data, "correlation", None)
        if variance.size == 0:
            return None
        if correlation is not None:
            sd = np.sqrt(np.clip(variance, 0.0, None))
            smallest = float(np.linalg.eigvalsh(sd[:, None] * correlation * sd[None, :])[0])
        else:
            smallest = float(variance.min())
        pi0 = float(np.sum(data.increments))
        if not (math.isfinite(smallest) and smallest > 0.0 and math.isfinite(pi0) and pi0 > 0):
            return None
        return INTEGRATOR_SHARE * math.sqrt(smallest / variance.size) / pi0

    @property
    def reference_amplitude(self) -> float:
        """The amplitude at which laws parametrised at a reference are (the observed
        |y0| of the analysed window)."""
        return abs(float(self.data.y0))

    def law_values(self, params: Params) -> tuple[dict[str, NDArray], NDArray]:
        """The law's parameter values (each (n,)) and y0 (n,) from ``params``."""
        y0 = np.ravel(np.asarray(params["y0"], dtype=float))
        values = {}
        for p in self.law.parameters:
            v = params.get(p.name)
            values[p.name] = (
                np.full(y0.shape, p.null) if v is None else np.ravel(np.asarray(v, dtype=float))
            )
        return values, y0

    def model_pi(self, params: Params) -> NDArray:
        """Model Π at the grid points τ_0 .. τ_{m-1}, shape (n, m).

        ``params``: the law's parameters and ``y0`` by name (:data:`Params`). A row is
        NaN where the law cannot move (an overdamped arc of a strong drag).
        """
        tau = self.data.tau_grid[:-1]
        end = None if self.data.motion_ended else self.data.tau_end
        values, y0 = self.law_values(params)
        if self.model == "exact":
            # The law's one compiled core: the closed form where it has one (5-10x
            # faster than the numpy implementation, to which it agrees to 1e-12), the
            # half-cycle integrator otherwise.
            return self.law_pi(tau, values, y0)
        amplitude = np.hypot(y0, self.data.yp0)[:, None]
        zeta = values.get("zeta", np.zeros_like(y0))[:, None]
        mu_k = values.get("mu_k", np.zeros_like(y0))[:, None]
        return averaged_pi(tau, amplitude, zeta, mu_k, tau_end=end)

    def law_pi(self, at: NDArray, values: Mapping[str, NDArray], y0: NDArray) -> NDArray:
        """The exact model's Π at the sorted times ``at`` (its law's
        :meth:`~bayestribo.model.laws.Law.pi_grid`), shape (n, len(at)), as the data's Π
        is taken: to the record's end where the record ends in motion, else to the
        model's own end of motion, a creep to rest ending at the record's detected stop
        (τ_end, where the data's Π ends: the creep's ∫E past it is none of the data's);
        a law without a closed form to the error its increments' noise allows
        (:attr:`integrator_tolerance`).

        Parameters
        ----------
        at : ndarray
            Sorted dimensionless times.
        values : mapping
            The law's parameter values by name, each (n,) (:meth:`law_values`).
        y0 : ndarray
            The initial displacement of each set, (n,).

        Returns
        -------
        ndarray
            Π, (n, len(at)); a row is NaN where the law cannot move.
        """
        data = self.data
        return self.law.pi_grid(
            at,
            values,
            y0,
            data.yp0,
            None if data.motion_ended else data.tau_end,
            reference=self.reference_amplitude,
            steps=self.integrator_steps,
            creep_end=data.tau_end,
            tolerance=self.integrator_tolerance,
        )

    def model_increments(self, params: Params) -> NDArray:
        """Model increments M_j, shape (n, m)."""
        pi = self.model_pi(params)
        inc = np.empty_like(pi)
        endless = np.isposinf(pi).any(axis=-1)  # no dissipation: the motion never ends
        with np.errstate(invalid="ignore"):
            inc[..., :-1] = pi[..., :-1] - pi[..., 1:]
        inc[..., -1] = pi[..., -1]
        if np.any(endless):
            # Π is infinite where nothing dissipates (ζ = μ_k = 0 on a closed form): no
            # decay is made, so the increments are infinite, not inf - inf
            inc[endless] = np.inf
        return inc

    @cached_property
    def shape_basis(self) -> NDArray:
        """Legendre polynomials P_k(u_j) of the increments' positions, shape (m, K).

        u runs linearly from -1 at the first increment's middle to +1 at the last's.
        """
        grid = self.data.tau_grid
        mid = 0.5 * (grid[:-1] + grid[1:])
        span = float(mid[-1] - mid[0]) if mid.size > 1 else 1.0
        u = 2.0 * (mid - mid[0]) / span - 1.0
        return np.polynomial.legendre.legvander(u, SHAPE_TERMS - 1)

    @cached_property
    def shape_design(self) -> NDArray:
        """Columns D_j P_k(u_j) of the shape discrepancy, shape (m, K): D_j the law's
        increments at the first pass's optimum where the data hold them
        (:attr:`~bayestribo.signal.increments.PiData.law_increments`), else the
        observed ones."""
        scale = self.data.law_increments
        if scale is None:
            scale = self.data.increments
        return np.asarray(scale)[:, None] * self.shape_basis

    def design(self, shape: bool = False) -> NDArray:
        """Design of the linear nuisances: ∫y, ∫τy, the noise bias's standard error
        (and the shape columns), (m, q)."""
        if not shape:
            return self.data.offset_design
        return np.hstack([self.data.offset_design, self.shape_design])

    @cached_property
    def whitening(self) -> NDArray | None:
        """T = L⁻¹ for the increments' noise correlation R = LLᵀ
        (:attr:`~bayestribo.signal.increments.PiData.correlation`), lower triangular
        (m, m): ``T (r / √V)`` are independent standard normals; None for independent
        increments."""
        correlation = getattr(self.data, "correlation", None)
        if correlation is None:
            return None
        chol = np.linalg.cholesky(np.asarray(correlation, dtype=float))
        return scipy.linalg.solve_triangular(chol, np.eye(chol.shape[0]), lower=True)

    @cached_property
    def log_det_correlation(self) -> float:
        """log|R| of the increments' noise correlation (0 for independent ones)."""
        t = self.whitening
        return 0.0 if t is None else float(-2.0 * np.sum(np.log(np.diag(t))))

    def _whiten(self, standardized: NDArray) -> NDArray:
        """``T x`` along the last axis of increments already divided by √V (x as it is
        for independent increments)."""
        t = self.whitening
        return standardized if t is None else standardized @ t.T

    def variance(self, discrepancy: NDArray | None = None) -> NDArray:
        """Variance of each increment (noise, plus the discrepancy term if given).

        With correlated increments (:attr:`whitening`) the covariance is
        ``√V_i R_ij √V_j``: the white discrepancy's term is taken with the noise's
        correlation (one whitening for all parameters)."""
        if discrepancy is None:
            return self.data.variance
        return self.data.variance + np.asarray(discrepancy) ** 2 * self.data.energy_squared

    # -- nuisance -----------------------------------------------------------------
    def _solve(
        self, resid: NDArray, var: NDArray, shape: NDArray | None = None
    ) -> tuple[NDArray, NDArray, NDArray]:
        """Conditional mean of the linear nuisances, b·A⁻¹b and log|A| per row.

        The nuisances are the equilibrium offset and drift (δ₀, δ₁), the noise level's
        error and, with a shape scale ``shape`` (s_c, shape (n, 1)), the shape
        coefficients c_k; A = XᵀWX +
        P⁻¹ with X = :meth:`design`. Returns δ̂ (n, q), b·δ̂ (n,), log|A| (n,).
        """
        x = self.design(shape is not None)  # (m, q)
        resid = np.atleast_2d(resid)
        n, q = resid.shape[0], x.shape[1]
        if self.whitening is not None:
            a, b = self._whitened_system(resid, var, x)
        else:
            w = 1.0 / var  # (m,) or (n, m)
            if w.ndim == 1:
                a = np.broadcast_to((x.T * w) @ x, (n, q, q)).copy()
            else:
                a = np.einsum("nj,jk,jl->nkl", w, x, x)
            b = (resid * w) @ x
        precision = self._prior_sd(n, shape) ** -2
        a[:, np.arange(q), np.arange(q)] += precision
        delta = np.linalg.solve(a, b[..., None])[..., 0]
        logdet = np.linalg.slogdet(a)[1]
        return delta, np.sum(b * delta, axis=-1), logdet

    def _whitened_system(self, resid: NDArray, var: NDArray, x: NDArray) -> tuple[NDArray, NDArray]:
        """XᵀΣ⁻¹X (n, q, q) and XᵀΣ⁻¹r (n, q) with the increments' correlation."""
        n, q = resid.shape[0], x.shape[1]
        sd = np.sqrt(var)
        z = self._whiten(resid / sd)  # (n, m)
        if sd.ndim == 1:
            xw = self._whiten((x / sd[:, None]).T).T  # (m, q)
            return np.broadcast_to(xw.T @ xw, (n, q, q)).copy(), z @ xw
        xw = np.swapaxes(self._whiten(np.swapaxes(x[None] / sd[..., None], 1, 2)), 1, 2)
        return np.einsum("njk,njl->nkl", xw, xw), np.einsum("nj,njk->nk", z, xw)

    def _prior_sd(self, n: int, shape: NDArray | None = None) -> NDArray:
        """Prior standard deviations of the q linear nuisances for n rows, (n, q):
        δ₀, δ₁, the noise level's error (standard normal) and the shape coefficients
        (s_c of each row)."""
        q = BASE_NUISANCES + (0 if shape is None else SHAPE_TERMS)
        sd = np.empty((n, q))
        sd[:, 0] = self.offset_sd
        sd[:, 1] = self.drift_sd
        sd[:, 2] = 1.0
        if shape is not None:
            sd[:, BASE_NUISANCES:] = np.reshape(np.asarray(shape, dtype=float), (-1, 1))
        return sd

    def _log_prior_det(self, shape: NDArray | None = None) -> NDArray | float:
        """log|P| of the nuisances' prior covariance (per row with a shape scale)."""
        base = float(2.0 * np.sum(np.log(self._prior_sd(1)[0])))
        if shape is None:
            return base
        return base + 2.0 * SHAPE_TERMS * np.log(np.reshape(np.asarray(shape, float), -1))

    def _residuals(self, params: Params) -> NDArray:
        """Observed minus model increments, D_j - M_j, shape (n, m)."""
        return self.data.increments - self.model_increments(params)

    def offset(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
    ) -> NDArray:
        """Conditional mean of (δ₀, δ₁) given the parameters, shape (n, 2)."""
        resid = self._residuals(params)
        return self._solve(resid, self.variance(discrepancy), shape)[0][:, :2]

    def nuisance_mean(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
    ) -> NDArray:
        """Conditional mean of the linear nuisances' part of each increment (equilibrium
        and, with ``shape``, the shape discrepancy), shape (n, m)."""
        resid = self._residuals(params)
        delta = self._solve(resid, self.variance(discrepancy), shape)[0]
        return delta @ self.design(shape is not None).T

    # -- densities ----------------------------------------------------------------
    def log_likelihood(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
    ) -> NDArray:
        """Log-likelihood with the linear nuisances marginalised, shape (n,).

        ``discrepancy`` is the white discrepancy's scale s and ``shape`` the shape
        discrepancy's s_c (each (n, 1), or None without that term). A row where a law
        without a closed form cannot move (an overdamped arc: its Π is NaN) is outside
        the law's domain and has log-likelihood −inf, as has a row of a closed form that
        dissipates nothing (ζ = μ_k = 0: its Π infinite, no decay made); with the closed
        forms a NaN stays NaN (a bug or a broken input, which the posterior reports).
        """
        resid = self._residuals(params)
        if self.law.closed_form:
            # a law that dissipates nothing makes no decay (its increments infinite:
            # :meth:`model_increments`): outside the data's support, not a NaN
            outside = np.any(np.isinf(resid), axis=-1)
        else:
            outside = ~np.all(np.isfinite(resid), axis=-1)
        if np.any(outside):
            resid = np.where(outside[:, None], 0.0, resid)
        var = self.variance(discrepancy)
        _, explained, logdet_a = self._solve(resid, var, shape)
        if self.whitening is None:
            chi2 = np.sum(resid * resid / var, axis=-1) - explained
            norm = np.sum(np.log(var) + _LOG_2PI, axis=-1)
        else:
            z = self._whiten(resid / np.sqrt(var))
            chi2 = np.sum(z * z, axis=-1) - explained
            norm = np.sum(np.log(var) + _LOG_2PI, axis=-1) + self.log_det_correlation
        out = -0.5 * (chi2 + norm + logdet_a + self._log_prior_det(shape))
        if np.any(outside):
            out = np.where(outside, -np.inf, out)
        return out

    def conditional_residuals(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
    ) -> NDArray:
        """D_j - M_j with the nuisances' conditional mean removed, shape (n, m)."""
        resid = self._residuals(params)
        delta = self._solve(resid, self.variance(discrepancy), shape)[0]
        return resid - delta @ self.design(shape is not None).T

    def pointwise(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
    ) -> NDArray:
        """Conditional log-likelihood of each increment, shape (n, m) (for PSIS-LOO).

        With correlated increments (:attr:`whitening`), each increment's density given
        all the others: with u = r/√V, g = R⁻¹u and p = diag(R⁻¹), the increment is
        normal about its value less ``√V g/p`` with variance ``V/p`` (the independent
        formula when R = I)."""
        resid = self.conditional_residuals(params, discrepancy, shape)
        var = self.variance(discrepancy)
        t = self.whitening
        if t is None:
            return -0.5 * (resid * resid / var + np.log(var) + _LOG_2PI)
        g = self._whiten(resid / np.sqrt(var)) @ t
        p = np.sum(t * t, axis=0)
        return -0.5 * (g * g / p + np.log(var / p) + _LOG_2PI)

    def standardized_residuals(
        self,
        params: Params,
        discrepancy: NDArray | None = None,
        shape: NDArray | None = None,
        nuisances: bool = False,
    ) -> NDArray:
        """Conditional residuals over √V_j: standard normals if the model is right,
        shape (n, m); whitened (``T r/√V``, :attr:`whitening`) where the increments
        are correlated.

        With ``nuisances`` the q linear nuisances' conditional means over their prior
        sd follow, shape (n, m + q): the sum of squares of a row is then the χ²
        part of the log-likelihood, ``rᵀWr - bᵀA⁻¹b`` (what a least squares must
        minimise where a nuisance is pulled far into its prior's tail).
        """
        resid = self._residuals(params)
        var = self.variance(discrepancy)
        delta = self._solve(resid, var, shape)[0]
        out = self._whiten((resid - delta @ self.design(shape is not None).T) / np.sqrt(var))
        if not nuisances:
            return out
        return np.hstack([out, delta / self._prior_sd(delta.shape[0], shape)])

    # -- how far the decay departs from the law -----------------------------------
    def shape_departure(self, params: Mapping[str, float]) -> ShapeDeparture:
        """Test the residuals at one parameter set for a smooth departure along the decay.

        The relative departure ``g(u) = Σ_k c_k P_k(u)`` (see the module notes) is fitted
        to the residuals by weighted least squares with the equilibrium nuisance, under
        the noise variances alone; its χ² is ``ĉᵀ Cov(ĉ)⁻¹ ĉ`` with
        :data:`SHAPE_TERMS` degrees of freedom (conservative at a fitted parameter set,
        whose own directions the residuals no longer hold).

        Parameters
        ----------
        params : mapping of str to float
            The parameter set by name, the law's parameters and ``y0`` (usually the
            maximum a posteriori).

        Returns
        -------
        ShapeDeparture
        """
        one = {k: np.array([float(v)]) for k, v in params.items()}
        model = self.model_increments(one)[0]
        resid = self.data.increments - model
        # the law's increments at these parameters scale the departure (module notes)
        x = np.hstack([self.data.offset_design, model[:, None] * self.shape_basis])
        if self.whitening is None:
            w = 1.0 / self.data.variance
            a = (x.T * w) @ x
            b = (resid * w) @ x
        else:
            a, b = (v[0] for v in self._whitened_system(resid[None], self.data.variance, x))
        base = np.arange(BASE_NUISANCES)
        a[base, base] += self._prior_sd(1)[0] ** -2  # the shape coefficients: no prior
        try:
            cov = np.linalg.inv(a)
        except np.linalg.LinAlgError:
            return ShapeDeparture.undetermined(resid.size)
        coef = cov @ b
        base = BASE_NUISANCES
        c, cov_c = coef[base:], cov[base:, base:]
        try:
            chi2 = float(c @ np.linalg.solve(cov_c, c))
        except np.linalg.LinAlgError:
            return ShapeDeparture.undetermined(resid.size)
        basis = self.shape_basis
        g = basis @ c
        sd_g = np.sqrt(np.maximum(np.einsum("jk,kl,jl->j", basis, cov_c, basis), 0.0))
        worst = int(np.argmax(np.abs(g)))
        # the departure in Π itself: largest where the law's increments are, which the
        # relative one need not be (where the law's increment is near zero)
        absolute, sd_absolute = g * model, sd_g * np.abs(model)
        at = int(np.argmax(np.abs(absolute)))
        return ShapeDeparture(
            chi2=chi2,
            dof=SHAPE_TERMS,
            p_value=float(scipy.stats.chi2.sf(chi2, SHAPE_TERMS)),
            max_relative=float(g[worst]),
            max_relative_sd=float(sd_g[worst]),
            at_increment=worst,
            relative=g,
            reference=float(model[worst]),
            largest=float(np.max(np.abs(model))),
            max_absolute=float(absolute[at]),
            max_absolute_sd=float(sd_absolute[at]),
        )


@dataclass(frozen=True)
class ShapeDeparture:
    """A smooth departure of the decay from the law (:meth:`PiLikelihood.shape_departure`).

    Attributes
    ----------
    chi2 : float
        χ² of the fitted shape coefficients against their noise covariance.
    dof : int
        Its degrees of freedom (:data:`SHAPE_TERMS`).
    p_value : float
        Probability of a χ² this large if the law holds and the noise model is right.
    max_relative : float
        The fitted relative departure g at the increment where it is largest in
        magnitude (a fraction of that increment; signed: + the record holds more
        energy than the law).
    max_relative_sd : float
        Its standard error from the noise.
    at_increment : int
        Index of that increment.
    relative : ndarray
        The fitted relative departure at every increment, shape (m,).
    reference : float
        The law's own increment of Π at ``at_increment`` (dimensionless).
    largest : float
        The largest of the law's increments (dimensionless), the scale of Π.
    max_absolute, max_absolute_sd : float
        The departure in Π's increments (g times the law's increment, dimensionless)
        where it is largest in magnitude, and its standard error: the size of a
        departure that the relative one overstates where the law's increment is near
        zero.
    """

    chi2: float
    dof: int
    p_value: float
    max_relative: float
    max_relative_sd: float
    at_increment: int
    relative: NDArray
    reference: float = math.nan
    largest: float = math.nan
    max_absolute: float = math.nan
    max_absolute_sd: float = math.nan

    @classmethod
    def undetermined(cls, m: int) -> ShapeDeparture:
        """No test possible (a singular system: too few increments)."""
        return cls(math.nan, SHAPE_TERMS, math.nan, math.nan, math.nan, -1, np.full(m, math.nan))

    def describe(self) -> str:
        """One sentence: by how much the decay departs from the law."""
        if not math.isfinite(self.chi2):
            return "the shape of the decay could not be tested (too few increments)"
        return (
            f"the increments depart from the law smoothly along the decay by up to "
            f"{departure_size(self.to_dict())} (χ² = {self.chi2:.1f} for {self.dof} shape "
            f"terms, p = {self.p_value:.1e})"
        )

    def to_dict(self) -> dict[str, float | int]:
        """Plain data (without the per-increment curve): ``chi2``, ``dof``,
        ``p_value``, ``max_relative``, ``max_relative_sd``, ``at_increment``,
        ``reference``, ``largest``, ``max_absolute``, ``max_absolute_sd``."""
        return {
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": self.p_value,
            "max_relative": self.max_relative,
            "max_relative_sd": self.max_relative_sd,
            "at_increment": self.at_increment,
            "reference": self.reference,
            "largest": self.largest,
            "max_absolute": self.max_absolute,
            "max_absolute_sd": self.max_absolute_sd,
        }


#: Below this fraction of the largest increment, the law's increment is near zero: a
#: departure relative to it says nothing (+3.7e+03 % of almost nothing).
NEAR_ZERO = 0.01


def departure_size(shape: Mapping[str, Any]) -> str:
    """How far the decay departs from the law (:meth:`ShapeDeparture.to_dict`), in
    words: in percent of the law's own increment where that increment is a fair
    reference, else (the increment near zero, below :data:`NEAR_ZERO` of the largest,
    or the departure larger than the increment itself) the largest absolute departure
    in Π, dimensionless and as a share of the largest increment.

    Examples
    --------
    >>> departure_size({"max_relative": 0.012, "max_relative_sd": 0.002,
    ...                 "reference": 0.5, "largest": 2.0})
    '+1.2 % (± 0.2 %)'
    >>> departure_size({"max_relative": 37.0, "max_relative_sd": 3.2, "reference": 1e-6,
    ...                 "largest": 2.0, "max_absolute": 3.7e-5, "max_absolute_sd": 3.2e-6})
    '+3.7e-05 (± 3.2e-06) in an increment of Π (0.0018 % of the largest)'
    """

    def number(key: str) -> float:
        value = shape.get(key)
        return math.nan if value is None else float(value)

    g, sd_g = number("max_relative"), number("max_relative_sd")
    ref, largest = number("reference"), number("largest")
    near_zero = abs(g) > 1.0 or (math.isfinite(largest) and abs(ref) < NEAR_ZERO * largest)
    if not (near_zero and math.isfinite(ref) and largest > 0):
        error = f" (± {100 * sd_g:.2g} %)" if math.isfinite(sd_g) else ""
        return f"{100 * g:+.3g} %{error}"
    diff, sd = number("max_absolute"), number("max_absolute_sd")
    if not math.isfinite(diff):  # recorded before the absolute departure was
        diff, sd = g * ref, sd_g * abs(ref)
    error = f" (± {sd:.2g})" if math.isfinite(sd) else ""
    share = 100 * abs(diff) / largest
    return f"{diff:+.3g}{error} in an increment of Π ({share:.2g} % of the largest)"
