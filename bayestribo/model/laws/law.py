r"""A dissipation law: a sum of registered terms, named by its terms joined with ``+``.

``Law.from_name("viscous+coulomb")`` is the law of Rigaud et al. (2010), Eq. 7, the
package's default; ``"viscous+quadratic+coulomb"`` adds air or fluid drag, and so on
for every term registered in :mod:`bayestribo.model.laws.base`. The order of the
terms in a name does not matter: a law is printed with its terms in registration
order.

Π on a grid comes from one compiled numeric core: the closed forms of
:mod:`bayestribo.model._kernel` for the laws they cover (viscous damping, Coulomb
friction and both), the half-cycle integrator of
:mod:`bayestribo.model.laws.integrator` for every other law. The two agree to 1e-10
of Π(0) on the laws the closed form covers (tests).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import TERMS, Parameter, PhysicalScale, Term, get_term
from bayestribo.model.laws.integrator import BASE_ERROR, DEFAULT_STEPS, make_integrator
from bayestribo.model.laws.transforms import SamplingTransform, transform_for

if TYPE_CHECKING:
    from bayestribo.model.restoring.base import RestoringKernel

__all__ = ["ALIASES", "DEFAULT_LAW", "Law", "get_law"]

#: The law of a default fit (Rigaud et al. 2010, Eq. 7).
DEFAULT_LAW = "viscous+coulomb"
#: Names that stand for a law. ``free``: the law-free fit, a dissipation per cycle
#: ΔE(A) = 4μ_kA + 2πζA² + (8/3)γA³ + (3π/4)c₃A⁴ with every coefficient >= 0, a
#: smooth increasing function of the amplitude; its parameters are not a measurement
#: of any mechanism, its ΔE(A) is.
ALIASES: dict[str, str] = {"free": "viscous+coulomb+quadratic+cubic"}
#: The terms the closed form of the exact solution covers.
_CLOSED_FORM = frozenset({"viscous", "coulomb"})


@dataclass(frozen=True)
class Law:
    """A dissipation law: the sum of its terms' forces.

    Parameters
    ----------
    terms : sequence of Term
        Distinct terms (see :func:`bayestribo.model.laws.base.register_term`); a
        term need not be registered to be used here, which is how a law defined
        outside the package is fitted.
    restoring : RestoringKernel, optional
        The oscillator's restoring force when it is not the linear spring
        (:meth:`bayestribo.model.restoring.RestoringForce.kernel`): Π then comes from
        :mod:`bayestribo.model.laws.nonlinear`, with the energy ``½y'² + V(y)``.
    """

    terms: tuple[Term, ...]
    restoring: RestoringKernel | None = None

    def __post_init__(self) -> None:
        terms = tuple(self.terms)
        if not terms:
            raise ValueError("a law needs at least one term")
        names = [t.name for t in terms]
        if len(set(names)) != len(names):
            raise ValueError(f"a law names each term once, got {'+'.join(names)!r}")
        params = [p.name for t in terms for p in t.parameters]
        if len(set(params)) != len(params):
            raise ValueError(f"the terms of {'+'.join(names)!r} share a parameter name")
        order = {name: i for i, name in enumerate(TERMS)}
        terms = tuple(sorted(terms, key=lambda t: order.get(t.name, len(order))))
        object.__setattr__(self, "terms", terms)

    # -- names --------------------------------------------------------------------
    @classmethod
    def from_name(cls, name: str) -> Law:
        """The law named by registered terms joined with ``+`` (``"viscous+coulomb"``).

        Raises
        ------
        ValueError
            For an empty name, a repeated term or a term that is not registered (the
            message lists the registered terms).
        """
        if isinstance(name, Law):
            return name
        if not isinstance(name, str) or not name.strip():
            raise ValueError(
                f"law: expected terms joined with '+' (registered terms: "
                f"{', '.join(TERMS)}), got {name!r}"
            )
        name = ALIASES.get(name.strip().lower(), name)
        parts = [p.strip().lower() for p in name.split("+")]
        if any(not p for p in parts):
            raise ValueError(f"law {name!r}: an empty term between '+' signs")
        return cls(tuple(get_term(p) for p in parts))

    @property
    def name(self) -> str:
        """The terms joined with ``+``, in registration order."""
        return "+".join(t.name for t in self.terms)

    def __str__(self) -> str:
        return self.name

    @property
    def term_names(self) -> list[str]:
        """Names of the terms."""
        return [t.name for t in self.terms]

    # -- parameters ---------------------------------------------------------------
    @cached_property
    def parameters(self) -> tuple[Parameter, ...]:
        """Sampled parameters of every term, in order."""
        return tuple(p for t in self.terms for p in t.parameters)

    @cached_property
    def _names(self) -> tuple[str, ...]:
        # read on every evaluation of Π (the sampler's tens of thousands): built once
        return tuple(p.name for p in self.parameters)

    @property
    def parameter_names(self) -> list[str]:
        """Names of the sampled parameters."""
        return list(self._names)

    def parameter(self, name: str) -> Parameter:
        """The parameter ``name`` (ValueError naming the law's parameters otherwise)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise ValueError(
            f"law {self.name} has no parameter {name!r}; it has {self.parameter_names}"
        )

    @property
    def friction(self) -> bool:
        """True when the law has a friction term (the motion can stop)."""
        return any(t.kind == "friction" for t in self.terms)

    @property
    def sticks(self) -> bool:
        """True when a term carries static friction (μ_s/μ_k is a parameter)."""
        return any(t.sticks for t in self.terms)

    def with_restoring(self, restoring: RestoringKernel | None) -> Law:
        """The same law on another restoring force (None: the linear spring)."""
        return self if restoring == self.restoring else replace(self, restoring=restoring)

    def sampling_transform(
        self, sampled: Sequence[str], reference: float, lowest: float, ended: bool = True
    ) -> SamplingTransform | None:
        """The coordinates this law's posterior is sampled in, or None (its own).

        Parameters
        ----------
        sampled : sequence of str
            The sampled coordinates' names (a transform applies where every
            parameter it replaces is sampled).
        reference, lowest : float
            The reference amplitude of the law's parameters and the record's smallest
            amplitude (dimensionless).
        ended : bool
            Whether the record holds the end of the motion.

        Returns
        -------
        SamplingTransform or None
            The registered transform of a set of this law's terms
            (:mod:`bayestribo.model.laws.transforms`).
        """
        return transform_for(self.term_names, sampled, reference, lowest, ended)

    @property
    def closed_form(self) -> bool:
        """True when Π has a closed form (viscous damping, Coulomb friction or both, on
        a linear spring)."""
        return (
            self.restoring is None
            and {t.name for t in self.terms} <= _CLOSED_FORM
            and all(t is TERMS.get(t.name) for t in self.terms)
        )

    def default_priors(self, amplitude: float) -> dict[str, Mapping[str, float | str]]:
        """Each parameter's default prior (a plain-data spec) given the observed initial
        amplitude |y0|."""
        amp = abs(float(amplitude))
        if not (math.isfinite(amp) and amp > 0.0):
            raise ValueError(f"amplitude must be a positive number, got {amplitude!r}")
        return {p.name: p.prior(amp) for p in self.parameters}

    def nests(self, other: Law) -> bool:
        """True when this law contains every term of ``other`` (and so can reproduce
        it with its extra terms at zero)."""
        return set(other.term_names) <= set(self.term_names)

    @property
    def boundaries(self) -> dict[str, str]:
        """The laws this one nests on a bound of its prior: for each term that
        declares an amount (:attr:`~bayestribo.model.laws.base.Term.amount`, the
        parameter whose null, its lower bound, removes the term), that parameter's
        name and the name of the law without the term. Empty for a law of one term
        (without it there is no law).

        Examples
        --------
        >>> Law.from_name("viscous+coulomb").boundaries
        {'zeta': 'coulomb', 'mu_k': 'viscous'}
        """
        if len(self.terms) < 2:
            return {}
        return {
            t.amount: "+".join(o.name for o in self.terms if o is not t)
            for t in self.terms
            if t.amount is not None
        }

    # -- the compiled core --------------------------------------------------------
    @cached_property
    def _layout(self) -> tuple[tuple, tuple]:
        drags = [t for t in self.terms if t.kind == "drag"]
        frictions = [t for t in self.terms if t.kind == "friction"]
        offsets, o = [], 0
        for t in (*drags, *frictions):
            offsets.append(o)
            o += t.n_coefficients
        nd = len(drags)
        return (
            (
                tuple(t.force for t in drags),
                tuple(offsets[:nd]),
                tuple(t.n_coefficients for t in drags),
                tuple(t.force for t in frictions),
                tuple(offsets[nd:]),
                tuple(t.n_coefficients for t in frictions),
            ),
            (*drags, *frictions),
        )

    @property
    def smooth(self) -> bool:
        """True when every drag is smooth at zero speed."""
        return all(t.smooth for t in self.terms)

    def coefficients(self, values: Mapping[str, ArrayLike], reference: float) -> NDArray:
        """Coefficient rows of the compiled forces, shape (P, K), from parameter values
        by name (each of shape (P,)) and the reference amplitude."""
        vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in self._names}
        return self._coefficient_rows(vals, vals[self._names[0]].shape[0], float(reference))

    def _coefficient_rows(
        self, vals: Mapping[str, NDArray], size: int, reference: float
    ) -> NDArray:
        """:meth:`coefficients` from float arrays by name (each broadcast to ``size``)."""
        cols = [c for term in self._layout[1] for c in term.coefficients(vals, reference)]
        out = np.empty((size, len(cols)))
        for k, c in enumerate(cols):
            out[:, k] = c  # each column broadcast to the rows
        return out

    def static_ratio(self, values: Mapping[str, ArrayLike], size: int) -> NDArray:
        """μ_s/μ_k of each row (1 where the law has no static friction parameter)."""
        if "mu_s_ratio" in self._names:
            out = np.empty(size)
            out[:] = np.asarray(values["mu_s_ratio"], dtype=float)
            return out
        return np.ones(size)

    def pi_grid(
        self,
        tau: ArrayLike,
        values: Mapping[str, ArrayLike],
        y0: ArrayLike,
        yp0: float = 0.0,
        tau_end: float | None = None,
        *,
        reference: float | None = None,
        method: str = "auto",
        steps: int = DEFAULT_STEPS,
        creep_end: float | None = None,
        tolerance: float | None = None,
    ) -> NDArray:
        """Π(τ) = ∫_τ^T E on sorted ``tau`` for P parameter sets, shape (P, T).

        Parameters
        ----------
        tau : array_like
            Sorted dimensionless times, ``>= 0``.
        values : mapping
            Each parameter of the law by name, arrays of shape (P,) (or scalars).
        y0 : array_like
            Initial displacement of each set, shape (P,).
        yp0 : float
            Initial velocity y'(0), shared by every set.
        tau_end : float, optional
            End of the record: Π is truncated there (``None``: to the end of motion).
        reference : float, optional
            The reference amplitude of terms parametrised at it (default |y0| of the
            first set).
        method : {"auto", "closed", "integrate"}
            The closed form where the law has one (``"auto"``), or the integrator.
        steps : int
            Runge-Kutta steps per half cycle of the integrator: 0 chosen per half cycle
            (Π within ~2e-9 of Π(0)); positive, that many in every half cycle, every
            one integrated up to the cap past the record (the reference of convergence
            tests); negative, -steps in every half cycle, with the sum past the record
            shortened as with 0 (its rest taken below 1e-12 of the sum, and from the
            averaged flow of those half cycles): the coarse model of the optimiser's
            multi-start, within ~1e-8 of the positive count's tail at a fraction of
            its cost.
        creep_end : float, optional
            Where the overdamped creep that ends a drag's motion (a power law below
            α = 1, :mod:`bayestribo.model.laws._creep`) ends when it starts before
            it: the τ of a record's detected stop of motion, where the data's Π ends
            (its own end for a creep that starts later: that creep adds nothing).
            ``None``: to rest. It shortens only such a creep, and only below
            ``tau_end``: the half cycles run to the end of motion as without it, and
            the closed form and a law on a nonlinear restoring force (no creep) ignore
            it.
        tolerance : float, optional
            The error of Π allowed where the integrator chooses its steps (``steps``
            0), as a fraction of Π(0): the steps fall as its fourth root (the scheme's
            error ∝ ζ_e² h⁴), never below 32 a half cycle inside the record. ``None``
            or anything below :data:`~bayestribo.model.laws.integrator.BASE_ERROR`
            (2e-9): the scheme's usual steps. Measured against fixed steps, the error is
            within a few times the tolerance (``tests/test_model_laws_tolerance.py``).
            A likelihood sets it from its increments' noise
            (:attr:`bayestribo.inference.likelihood.PiLikelihood.integrator_tolerance`).
            The closed forms and the laws on a nonlinear restoring force (fixed steps)
            ignore it.

        Returns
        -------
        ndarray
            Π, shape (P, T); a row is NaN where the drag is too strong for the
            motion to turn (an overdamped arc, outside the law's domain).
        """
        t = np.ascontiguousarray(np.atleast_1d(np.asarray(tau, dtype=float)))
        y = np.ascontiguousarray(np.atleast_1d(np.asarray(y0, dtype=float)).ravel())
        size = y.size
        vals = {n: _rows(values[n], size) for n in self._names}
        end = math.inf if tau_end is None else float(tau_end)
        creep = math.inf if creep_end is None else float(creep_end)
        if math.isnan(creep):
            raise ValueError("creep_end must be a time or None, got NaN")
        weight = 1.0 if tolerance is None else float(tolerance) / BASE_ERROR
        if not weight > 0.0 or math.isinf(weight):
            raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")
        if method not in ("auto", "closed", "integrate"):
            raise ValueError(f"method must be 'auto', 'closed' or 'integrate', got {method!r}")
        if method == "closed" and not self.closed_form:
            raise ValueError(
                f"law {self.name} has no closed form"
                + ("" if self.restoring is None else f" on the {self.restoring.name}")
            )
        if self.restoring is not None:
            return self._nonlinear_grid(t, y, vals, float(yp0), end, reference, steps)
        if method != "integrate" and self.closed_form:
            from bayestribo.model._kernel import exact_pi_grid

            zero = np.zeros(size)
            zeta = vals.get("zeta", zero)
            mu_k = vals.get("mu_k", zero)
            mu_s = mu_k * vals.get("mu_s_ratio", np.ones(size))
            return exact_pi_grid(t, y, zeta, mu_k, mu_s, float(yp0), tau_end)
        ref = abs(float(y[0])) if reference is None else float(reference)
        coef = self._coefficient_rows(vals, size, ref)
        # serial: numba's threads (1.9x on an idle two-core machine) spun against the
        # other processes of a loaded one, 10x slower (tests on two workers, campaigns)
        grid, _, _ = make_integrator(*self._layout[0])
        ratio = self.static_ratio(vals, size)
        pi, _ = grid(t, y, coef, ratio, float(yp0), end, int(steps), creep, max(weight, 1.0))
        return pi

    def turning_points(
        self,
        values: Mapping[str, float],
        y0: float,
        yp0: float = 0.0,
        *,
        tau_max: float = math.inf,
        max_count: int = 100_000,
        reference: float | None = None,
    ) -> tuple[NDArray, NDArray]:
        """Turning times τ_n and positions Y_n of one trajectory (Eq. 20 for the
        closed-form laws), from the compiled integrator.

        Parameters
        ----------
        values : mapping
            The law's parameters by name (scalars).
        y0, yp0 : float
            Initial state; with ``yp0 == 0`` the initial state is the first turning
            point.
        tau_max : float
            Stop after this time.
        max_count : int
            At most this many turning points.
        reference : float, optional
            Reference amplitude (default |y0|).

        Returns
        -------
        tau_n, Y_n : ndarray
            The last one is where the motion stops, when it does before the limits.
        """
        ref = abs(float(y0)) if reference is None else float(reference)
        vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in self.parameter_names}
        coef = self.coefficients(vals, ref)[0]
        ratio = float(self.static_ratio(vals, 1)[0])
        if self.restoring is not None:
            from bayestribo.model.laws.nonlinear import DEFAULT_STEPS as STEPS

            _, turns_nl, _, _ = self._nonlinear
            k = np.asarray(self.restoring.coefficients or (0.0,), dtype=float)
            return turns_nl(
                float(y0), coef, k, ratio, float(yp0), float(tau_max), int(max_count), STEPS
            )
        _, turns, _ = make_integrator(*self._layout[0])
        return turns(float(y0), coef, ratio, float(yp0), float(tau_max), int(max_count))

    @property
    def _nonlinear(self) -> tuple:
        """The compiled Π-grid and turning-point functions on the restoring force."""
        from bayestribo.model.laws.nonlinear import make_nonlinear_integrator

        r = self.restoring
        assert r is not None
        return make_nonlinear_integrator(self._layout[0], r.spring_kernel, r.potential_kernel)

    def _nonlinear_grid(
        self,
        t: NDArray,
        y: NDArray,
        vals: Mapping[str, NDArray],
        yp0: float,
        end: float,
        reference: float | None,
        steps: int,
    ) -> NDArray:
        """Π on the restoring force (:mod:`bayestribo.model.laws.nonlinear`)."""
        from bayestribo.model.laws.nonlinear import DEFAULT_STEPS as STEPS

        ref = abs(float(y[0])) if reference is None else float(reference)
        coef = self.coefficients(vals, ref)
        grid, _, _, _ = self._nonlinear
        k = np.asarray(self.restoring.coefficients or (0.0,), dtype=float)  # type: ignore[union-attr]
        ratio = self.static_ratio(vals, y.size)
        # fixed steps of either sign are that many (no sum past the record to shorten)
        pi, _ = grid(t, y, coef, k, ratio, yp0, end, abs(int(steps)) if steps != 0 else STEPS)
        return pi

    # -- what the law dissipates ---------------------------------------------------
    def dissipation(
        self,
        amplitude: ArrayLike,
        values: Mapping[str, ArrayLike],
        reference: float,
        *,
        by_term: bool = False,
    ) -> NDArray | dict[str, NDArray]:
        """Energy dissipated over one cycle of ``y = A cos τ``, ΔE(A) = ∮F(y')y' dτ
        (on a nonlinear restoring force, over one cycle of its undamped motion of swing
        A: docs/restoring.md, Eq. 3).

        Parameters
        ----------
        amplitude : array_like
            Amplitudes A (dimensionless), shape (n_A,).
        values : mapping
            Parameter values by name, each of shape (P,) (or scalars).
        reference : float
            The reference amplitude of terms parametrised at it.
        by_term : bool
            Return each term's share by term name instead of the sum.

        Returns
        -------
        ndarray of shape (P, n_A), or dict of them
            In dimensionless energy units (y²); multiply by kℓ² for joules
            (:attr:`PhysicalScale.energy_factor`).
        """
        if self.restoring is not None:
            return self._restoring_dissipation(amplitude, values, reference, by_term)
        a = np.atleast_1d(np.asarray(amplitude, dtype=float))[None, :]
        vals = {
            n: np.atleast_1d(np.asarray(values[n], dtype=float))[:, None]
            for n in self.parameter_names
        }
        parts = {t.name: np.asarray(t.dissipation(a, vals, float(reference))) for t in self.terms}
        if by_term:
            return parts
        return sum(parts.values())

    def _restoring_dissipation(
        self,
        amplitude: ArrayLike,
        values: Mapping[str, ArrayLike],
        reference: float,
        by_term: bool,
    ) -> NDArray | dict[str, NDArray]:
        """:meth:`dissipation` on the restoring force: the first-order loss per cycle of
        its undamped motion (docs/restoring.md, Eq. 3); each term's share with the other
        terms' coefficients at zero (a term's force is proportional to them)."""
        a = np.ascontiguousarray(np.atleast_1d(np.asarray(amplitude, dtype=float)))
        vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in self.parameter_names}
        size = max((v.size for v in vals.values()), default=1)
        vals = {n: np.broadcast_to(v, (size,)) for n, v in vals.items()}
        coef = self.coefficients(vals, float(reference))
        k = np.asarray(self.restoring.coefficients or (0.0,), dtype=float)  # type: ignore[union-attr]
        _, _, _, cycle = self._nonlinear
        if not by_term:
            return cycle(coef, k, a)
        parts = {}
        start = 0
        for term in self._layout[1]:
            alone = np.zeros_like(coef)
            alone[:, start : start + term.n_coefficients] = coef[
                :, start : start + term.n_coefficients
            ]
            start += term.n_coefficients
            parts[term.name] = cycle(np.ascontiguousarray(alone), k, a)
        return {t.name: parts[t.name] for t in self.terms}

    def swing_dissipation(
        self, swing: ArrayLike, values: Mapping[str, ArrayLike], reference: float
    ) -> NDArray:
        """Energy the law's own motion dissipates per cycle at the swing A:
        ``ΔE(A) = 2 A (a_s - a_e)``, twice the energy ``(a_s² - a_e²)/2`` lost over the
        half cycle from rest at ``a_s`` to the turning point ``a_e`` whose swing
        ``(a_s + a_e)/2`` is A (static friction ignored: the kinetic law). On a
        nonlinear restoring force (:attr:`restoring`), twice that half cycle's loss of
        its potential, ``2(V(a_s) - V(a_e))``.

        This is what a free decay measures: it is a function of the half-cycle map
        ``a_s -> a_e`` alone, which the turning points pin down, so that two laws that
        describe the same decay give the same ΔE(A). The integral over the harmonic
        motion (:meth:`dissipation`) is its first-order approximation and differs
        between such laws by a relative O(ζ): viscous damping and a friction that grows
        in proportion to the amplitude (``hysteretic``) with the same decay differ there
        by 1.5 % at ζ = 0.01, hundreds of posterior standard deviations at ten times the
        vibrometer's resolution. For Coulomb friction the two agree exactly
        (``4 μ_k A``); for viscous damping ΔE(A) = ``4 A² tanh(πβ/2)``, β = ζ/√(1-ζ²)
        (Eq. 20), against ``2πζA²``.

        Parameters
        ----------
        swing : array_like
            Swings A (dimensionless), shape (n_A,).
        values : mapping
            Parameter values by name, each of shape (P,) (or scalars).
        reference : float
            The reference amplitude of terms parametrised at it.

        Returns
        -------
        ndarray of shape (P, n_A)
            Dimensionless energy (y²), NaN where no half cycle has that swing (the
            drag stops the motion, or the friction holds it).
        """
        a = np.atleast_1d(np.asarray(swing, dtype=float))
        vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in self.parameter_names}
        size = max((v.size for v in vals.values()), default=1)
        if self.restoring is not None:
            # twice the energy V(a_s) - V(a_e) of the half cycle of swing A
            from bayestribo.model.laws.nonlinear import DEFAULT_STEPS as STEPS

            vals = {n: np.broadcast_to(v, (size,)) for n, v in vals.items()}
            coef = self.coefficients(vals, float(reference))
            k = np.asarray(self.restoring.coefficients or (0.0,), dtype=float)
            _, _, drops_nl, _ = self._nonlinear
            return 2.0 * drops_nl(coef, k, np.ascontiguousarray(a), STEPS)
        if self.closed_form:
            zeta = np.broadcast_to(vals.get("zeta", np.zeros(1)), (size,))[:, None]
            mu = np.broadcast_to(vals.get("mu_k", np.zeros(1)), (size,))[:, None]
            with np.errstate(invalid="ignore", divide="ignore"):
                beta = zeta / np.sqrt(1.0 - zeta * zeta)
                drop = 2.0 * mu + 2.0 * a[None, :] * np.tanh(0.5 * math.pi * beta)
            drop = np.where((zeta < 1.0) & (mu >= 0.0), drop, np.nan)
        else:
            coef = self.coefficients(vals, float(reference))
            _, _, drops = make_integrator(*self._layout[0])
            drop = drops(coef, np.ascontiguousarray(a))
        return 2.0 * a[None, :] * drop

    def physical(
        self, values: Mapping[str, ArrayLike], reference: float, scale: PhysicalScale
    ) -> dict[str, tuple]:
        """Derived quantities in physical units by name: ``(values, unit, symbol, label)``."""
        out: dict[str, tuple] = {}
        for t in self.terms:
            out.update(t.physical(values, float(reference), scale))
        return out


def _rows(value: ArrayLike, size: int) -> NDArray:
    """``value`` as float rows of shape (size,): itself where it has that shape already,
    else broadcast (a scalar or one row for every set)."""
    rows = np.asarray(value, dtype=float).ravel()
    return rows if rows.shape[0] == size else np.broadcast_to(rows, (size,))


def get_law(law: str | Law | Sequence[Term] | None = None) -> Law:
    """A :class:`Law` from a name, a law, or a sequence of terms (``None``: the default).

    Raises
    ------
    ValueError
        Naming the registered terms when the name holds an unknown one.
    """
    if law is None:
        return Law.from_name(DEFAULT_LAW)
    if isinstance(law, Law):
        return law
    if isinstance(law, str):
        return Law.from_name(law)
    return Law(tuple(law))
