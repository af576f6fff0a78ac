r"""The motion of any dissipation law, integrated independently of the fit.

A law of the registry (:mod:`bayestribo.model.laws`) moves, in the dimensionless form
of Rigaud et al. (2010), Eq. 6-7 (τ = Ωt, y = x/ℓ, ℓ = N/k), by

.. math::

    y'' + y = -\Big[\sum_{\text{drag}} g_i(|y'|)\Big]\,\mathrm{sgn}\,y'
              - μ(|Y_n|)\,\mathrm{sgn}\,y' + y_0\,m(τ),
    \qquad μ(a) = \sum_{\text{friction}} μ_i(a),

with ``Y_n`` the turning point the current half cycle started from and ``m(τ)`` the
magnet's pull, which balances the spring at the release displacement ``y₀`` and fades
as ``(1 + cos(πτ/τ_f))/2`` over ``τ_f`` (0 after; ``τ_f = 0``: an ideal release).

It is integrated with :func:`scipy.integrate.solve_ivp` (DOP853, relative tolerance
:data:`RTOL`) half cycle by half cycle: each starts at a turning point (y' = 0) and
ends on the event y' = 0, the friction's sign being that of the half cycle's velocity
and its magnitude μ(|Y_n|) constant within it. At each turning point the pin sticks
when the spring force is within the static friction, ``|Y_n| <= ρ μ(|Y_n|)`` (Eq. 8;
ρ = μ_s/μ_k where the law has a static friction parameter, else 1). During the fade
the pin is held until the unbalanced spring force ``y₀ (1 - m(τ))`` reaches ``ρ μ(y₀)``.

Only the law's definition is taken from the package: each term's force (its compiled
``g(w, c)`` or ``μ(a, c)``, called point by point) and its map from parameters to
coefficients. Neither the closed forms of :mod:`bayestribo.model` nor the fit's
half-cycle integrator (:mod:`bayestribo.model.laws.integrator`) are used, so a fit of a
record made from this motion tests the fit's integrator too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["RTOL", "SOLVER", "LawForces", "LawMotion", "integrate_law"]

#: Relative tolerance of the integration (the absolute one is 1e-13 y₀).
RTOL = 1e-10
#: What made the motion, as the simulator's metadata states it.
SOLVER = (
    f"scipy.integrate.solve_ivp (DOP853, rtol {RTOL:g}, atol 1e-13 y0), half cycle by half "
    "cycle to the event y' = 0; sticks at a turning point Y where |Y| <= (mu_s/mu_k) mu(|Y|); "
    "independent of the fit's half-cycle integrator (bayestribo.synthetic.motion)"
)
#: A half cycle that does not turn within this span of τ is overdamped.
_HALF_CYCLE_SPAN = 6.0 * math.pi


@dataclass(frozen=True)
class LawForces:
    """The forces of one law at one set of parameter values (dimensionless).

    Attributes
    ----------
    name : str
        The law's name.
    drags, frictions : tuple of (force, coefficients)
        Each term's compiled force and its coefficient array.
    ratio : float
        ρ = μ_s/μ_k, the static to kinetic friction (1 without such a parameter).
    """

    name: str
    drags: tuple[tuple[Callable[[float, NDArray], float], NDArray], ...]
    frictions: tuple[tuple[Callable[[float, NDArray], float], NDArray], ...]
    ratio: float

    @classmethod
    def of(cls, law: Any, values: Mapping[str, float], reference: float) -> LawForces:
        """The forces of ``law`` (a :class:`~bayestribo.model.laws.Law`) at ``values``
        (each parameter by name) and the reference amplitude ``reference`` [y]."""
        vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in law.parameter_names}
        drags, frictions = [], []
        for term in law.terms:
            coef = np.array(
                [float(np.ravel(c)[0]) for c in term.coefficients(vals, float(reference))]
            )
            (drags if term.kind == "drag" else frictions).append((term.force, coef))
        ratio = float(law.static_ratio(vals, 1)[0])
        return cls(law.name, tuple(drags), tuple(frictions), ratio)

    def drag(self, w: float) -> float:
        """Total drag magnitude at speed ``w >= 0``."""
        return sum((f(w, c) for f, c in self.drags), 0.0)

    def friction(self, a: float) -> float:
        """Total friction magnitude of a half cycle from the turning point ``|Y| = a``."""
        return sum((f(a, c) for f, c in self.frictions), 0.0)

    def sticks(self, a: float) -> bool:
        """True when the pin sticks at a turning point of magnitude ``a``."""
        if not self.frictions:
            return False
        return a <= self.ratio * self.friction(a)


@dataclass(frozen=True)
class _Arc:
    """One piece of the motion: ``solution(τ) -> (y, y')`` for start <= τ < end."""

    start: float
    end: float
    solution: Any


@dataclass(frozen=True)
class LawMotion:
    """The integrated motion of a law from a release at rest.

    Attributes
    ----------
    y0 : float
        Release displacement [y].
    tau_break : float
        When the pin breaks away from the magnet [τ] (0 for an ideal release).
    turning_times, turning_points : ndarray
        τ_n and Y_n of every turning point, from the release displacement (at τ = 0
        for an ideal release, at the breakaway otherwise) to the last one integrated.
    tau_stop : float
        When the pin sticks for good [τ] (the last turning time), or ``inf`` when the
        motion was still going at ``tau_limit``.
    """

    y0: float
    tau_break: float
    turning_times: NDArray
    turning_points: NDArray
    tau_stop: float
    arcs: tuple[_Arc, ...]

    @property
    def stopped(self) -> bool:
        """True when the pin stuck before the end of the integration."""
        return math.isfinite(self.tau_stop)

    @property
    def half_cycles(self) -> int:
        """Number of half cycles integrated (the magnet's fade not counted apart)."""
        return len(self.turning_times) - 1

    def sample(self, tau: ArrayLike) -> tuple[NDArray, NDArray]:
        """y and y' at the times ``tau`` [τ from the release]: y₀ at rest before the
        breakaway, the rest position after the stop.

        Raises
        ------
        ValueError
            For a time after the last integrated one of a motion that did not stop.
        """
        t = np.asarray(tau, dtype=float)
        y = np.full(t.shape, self.y0)
        yp = np.zeros(t.shape)
        flat = t.ravel()
        order = np.argsort(flat, kind="stable")
        ordered = flat[order]
        for arc in self.arcs:  # each arc's samples by bisection: O(n log n) in all
            lo, hi = np.searchsorted(ordered, [arc.start, arc.end], side="left")
            if hi > lo:
                sel = np.unravel_index(order[lo:hi], t.shape)
                y[sel], yp[sel] = arc.solution(ordered[lo:hi])
        end = self.turning_times[-1]
        if self.stopped:
            y[t >= end] = self.turning_points[-1]
        elif np.any(t >= end):
            raise ValueError(f"the motion was integrated to τ = {end:g} only")
        return y, yp


def _half_cycle(
    forces: LawForces,
    start: float,
    state: tuple[float, float],
    direction: float,
    mu: float,
    *,
    stop: float,
    magnet: Callable[[float], float] | None,
    atol: float,
) -> Any:
    """solve_ivp from ``state`` at ``start`` with the velocity's sign ``direction``
    and the friction ``mu``, until y' = 0 or τ = ``stop``."""
    from scipy.integrate import solve_ivp

    drag = forces.drag

    def rhs(tau: float, u: NDArray) -> list[float]:
        yp = u[1]
        acc = -u[0] - math.copysign(drag(abs(yp)), yp) - direction * mu
        if magnet is not None:
            acc += magnet(tau)
        return [yp, acc]

    def turned(tau: float, u: NDArray) -> float:
        return u[1]

    turned.terminal = True  # type: ignore[attr-defined]
    turned.direction = -direction  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (start, stop),
        list(state),
        method="DOP853",
        rtol=RTOL,
        atol=atol,
        events=turned,
        dense_output=True,
    )
    if not sol.success:  # pragma: no cover - smooth forces, tight tolerance
        raise RuntimeError(f"law {forces.name}: solve_ivp failed: {sol.message}")
    return sol


def integrate_law(
    law: Any,
    values: Mapping[str, float],
    y0: float,
    *,
    reference: float | None = None,
    tau_fade: float = 0.0,
    tau_limit: float = math.inf,
    max_half_cycles: int = 20_000,
) -> LawMotion:
    """Integrate the motion of ``law`` from rest at ``y0`` (see the module notes).

    Parameters
    ----------
    law : Law
        The dissipation law (:func:`bayestribo.model.laws.get_law`).
    values : mapping
        Each of its parameters by name, in the units of the registry (dimensionless).
    y0 : float
        Release displacement y₀ > 0 [y = x/ℓ].
    reference : float, optional
        The reference amplitude of terms parametrised at it [y] (default y₀).
    tau_fade : float
        Duration of the magnet's fade [τ] (0: an ideal release).
    tau_limit : float
        Integrate at least to this time [τ] (the half cycle holding it is finished),
        unless the pin sticks before; ``inf`` until it sticks.
    max_half_cycles : int
        At most this many half cycles.

    Returns
    -------
    LawMotion

    Raises
    ------
    ValueError
        When y₀ is within the static friction (the pin would not move), a friction is
        below zero, the magnet's fade outlasts the first half cycle, a drag is too
        strong for the motion to turn (overdamped), or the motion does not stop within
        ``max_half_cycles`` (a law without friction needs a finite ``tau_limit``).
    """
    y0 = float(y0)
    if not (math.isfinite(y0) and y0 > 0.0):
        raise ValueError(f"y0 must be a finite number > 0, got {y0!r}")
    forces = LawForces.of(law, values, y0 if reference is None else float(reference))
    if not forces.frictions and not math.isfinite(tau_limit):
        raise ValueError(
            f"law {forces.name} has no friction, so the motion never stops: give a finite "
            "duration to integrate"
        )
    atol = 1e-13 * y0

    def friction_at(a: float) -> float:
        mu = forces.friction(a)
        if not (math.isfinite(mu) and mu >= 0.0):
            raise ValueError(
                f"law {forces.name}: the friction at the turning point |Y| = {a:g} is "
                f"{mu!r}; expected a finite value >= 0 (outside the law's domain)"
            )
        return mu

    mu0 = friction_at(y0)
    if forces.sticks(y0):
        raise ValueError(
            f"the release displacement y0 = {y0!r} is within the static friction "
            f"±{forces.ratio * mu0!r} (in units of ℓ = N/k): the pin would not move"
        )
    arcs: list[_Arc] = []
    times, points = [0.0], [y0]
    tau, state, direction = 0.0, (y0, 0.0), -1.0
    tau_break = 0.0
    if tau_fade > 0.0:
        # held until the spring's unbalanced force y0 (1 - m) reaches ρ μ(y0)
        hold = forces.ratio * mu0 if forces.frictions else 0.0
        tau_break = tau_fade / math.pi * math.acos(1.0 - 2.0 * hold / y0)

        def magnet(t: float) -> float:
            return 0.5 * y0 * (1.0 + math.cos(math.pi * min(t, tau_fade) / tau_fade))

        sol = _half_cycle(
            forces, tau_break, state, -1.0, mu0, stop=tau_fade, magnet=magnet, atol=atol
        )
        if sol.t_events[0].size:
            raise ValueError(
                "magnet_fade_s is too long: the pin turns back before the magnet force has "
                "faded; expected a fade within the first oscillation (the default is a "
                "quarter period)"
            )
        arcs.append(_Arc(tau_break, tau_fade, sol.sol))
        times[0] = tau_break
        tau, state = tau_fade, (float(sol.y[0, -1]), float(sol.y[1, -1]))
    mu, tau_stop = mu0, math.inf
    while True:
        sol = _half_cycle(
            forces,
            tau,
            state,
            direction,
            mu,
            stop=tau + _HALF_CYCLE_SPAN,
            magnet=None,
            atol=atol,
        )
        if not sol.t_events[0].size:
            raise ValueError(
                f"law {forces.name}: the drag stops the motion before it turns (an "
                f"overdamped half cycle from τ = {tau:g}): outside the law's domain"
            )
        end = float(sol.t_events[0][0])
        y_end = float(sol.y_events[0][0][0])
        arcs.append(_Arc(tau, end, sol.sol))
        times.append(end)
        points.append(y_end)
        tau, state, direction = end, (y_end, 0.0), -math.copysign(1.0, y_end)
        a = abs(y_end)
        mu = friction_at(a)
        if forces.sticks(a):
            tau_stop = end
            break
        if tau >= tau_limit:
            break
        if len(arcs) >= max_half_cycles:
            raise ValueError(
                f"law {forces.name}: the motion does not stop within {max_half_cycles} half "
                "cycles: give the duration to record after the release (motion_duration_s)"
            )
    return LawMotion(y0, tau_break, np.array(times), np.array(points), tau_stop, tuple(arcs))
