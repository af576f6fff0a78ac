r"""Compiled integrator of Π for a law on a nonlinear restoring force.

A pendulum, ``θ'' + sin θ = -F``, or a Duffing spring, ``y'' + y + βy³ = -F``, holds the
energy ``E = ½y'² + V(y)`` with the potential of its restoring force
(:mod:`bayestribo.model.restoring`), and its half period grows (pendulum) or shrinks
(hardening spring) with the swing. The polar coordinates of
:mod:`bayestribo.model.laws.integrator` rest on the linear spring; here the motion

.. math::

    y'' = -V'(y) - \operatorname{sgn}(y')\,\big(g(|y'|) + μ(a)\big),\qquad
    C' = E = ½y'^2 + V(y),

is integrated in τ (classical fourth-order Runge-Kutta, :data:`DEFAULT_STEPS` steps per
π of τ) half cycle by half cycle: within one the direction of motion and the friction
μ(a) (``a`` the magnitude of the turning point it began at) are fixed, so the right
side is smooth. A half cycle ends where y' = 0: the step that crosses it is cut at
the root of the cubic Hermite interpolant of y', and two Newton steps of the
integrator itself put y' within rounding of 0. The motion stops at a turning point
Y where ``|V'(Y)| <= ρ μ(|Y|)`` (static friction; Eq. 8 with the spring's force for
the linear one's |Y|). Π at a grid point τ_j is ``C(T) - C(τ_j)``, C(τ_j) from a
partial step to τ_j. A law without friction summed to the end of motion ends once a
half cycle holds less than 1e-12 of the sum (a geometric tail), or after 20 000 half
cycles past the record.

The step's error grows as h⁴ (h = π/steps): against ``scipy.integrate.solve_ivp`` at
a tolerance of 1e-12, on a pendulum released at 90° with viscous damping, Coulomb
friction and quadratic drag, the turning points agree within 2e-7, their times within
4e-5 after 44 half cycles, and Π within 1.2e-7 of Π(0)
(``tests/test_model_laws_nonlinear.py``). With a linear restoring force the same
integrator reproduces the closed form of viscous damping and Coulomb friction.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

from bayestribo.model.laws import _restoring_core
from bayestribo.model.laws.integrator import _law_source, _load

__all__ = ["DEFAULT_STEPS", "make_nonlinear_integrator"]

DEFAULT_STEPS = _restoring_core.DEFAULT_STEPS


@cache
def make_nonlinear_integrator(
    layout: tuple, spring: Callable, potential: Callable
) -> tuple[Callable, Callable, Callable, Callable]:
    """The compiled Π-grid and turning-point functions of one law on one restoring force.

    Parameters
    ----------
    layout : tuple
        The law's compiled forces and where their coefficients sit (as
        :func:`bayestribo.model.laws.integrator.make_integrator`'s arguments).
    spring, potential : numba functions
        The restoring force's ``V'(y, k)`` and ``V(y, k)`` (dimensionless, ``k`` its
        coefficients).

    Returns
    -------
    grid : callable
        ``grid(tau, y0, coef, k, ratio, yp0, tau_end, steps) -> (Π, status)``, shapes as
        :func:`~bayestribo.model.laws.integrator.make_integrator`'s ``grid``; status 1
        for an overdamped arc (that row NaN).
    turns : callable
        ``turns(y0, coef_row, k, ratio, yp0, tau_max, max_count, steps) -> (τ_n, Y_n)``.
    swing_drops : callable
        ``swing_drops(coef, k, swing, steps) -> drop``: the energy V(a_s) - V(a_e) lost
        over the half cycle whose swing ½(a_s + a_e) is each of ``swing``, (P, S).
    dissipation : callable
        ``dissipation(coef, k, amplitudes) -> ΔE``: the first-order loss per cycle of
        the undamped motion of each swing (docs/restoring.md, Eq. 3), (P, A).
    """
    kernels = {"spring": spring, "potential": potential}
    module = _load(*_law_source(_restoring_core, layout, kernels))
    return module.grid, module.turns, module.swing_drops, module.dissipation
