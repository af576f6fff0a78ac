"""What a restoring force is, and the one registry of them.

The dissipation laws (:mod:`bayestribo.model.laws`) act on an oscillator whose restoring
force is linear, ``y'' + y = -F``. A pendulum's is not: ``θ'' + sin θ = -F`` (τ = ω₀t,
θ in radians), and the energy its motion holds at a turning point Y is the potential
``V(Y) = 1 - cos Y``, not ``Y²/2`` (19 % less at 90°, 31 % less at 135°). The energy
lost per cycle measured from the turning points (the law-free answer,
:func:`bayestribo.inference.dissipation.turning_point_dissipation`) takes the
potential of the run's restoring force; and the half period grows with the swing as
``T(A)/T₀`` says, which tells a pendulum from a linear oscillator
(:func:`bayestribo.inference.pipeline` names it when the period changes so).

A restoring force is a :class:`RestoringForce`: its name, the potential ``V(y)``
(dimensionless, ``y²/2`` near 0), the ratio of its half period at swing A to the
small-swing one, and whether y must be an angle in radians. Adding one is one module
that calls :func:`register_restoring` (a built-in one is also named, with its
description, in :data:`BUILTIN_RESTORING`, and its module is imported on first use);
the sidecar's ``restoring`` key and the command line's ``--restoring`` choices come from
the registry. This module imports no numpy: the command line builds ``--restoring``
from :func:`restoring_table` without importing any force.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

__all__ = [
    "AUTO",
    "BUILTIN_RESTORING",
    "RESTORING",
    "RestoringForce",
    "RestoringInfo",
    "RestoringKernel",
    "available_restoring",
    "get_restoring",
    "register_restoring",
    "rescaled",
    "restoring_choices",
    "restoring_table",
]

#: The name that asks a fit to choose the restoring force from the record
#: (:mod:`bayestribo.inference.restoring_choice`): accepted wherever ``restoring`` is
#: (the sidecar, ``--restoring``, ``FitSpec.restoring``), never a registered force.
AUTO = "auto"


@dataclass(frozen=True)
class RestoringForce:
    """A restoring force of the oscillator.

    Attributes
    ----------
    name : str
        Its name in the sidecar's ``restoring`` and ``--restoring``.
    description : str
        One line for help texts.
    potential : callable
        ``V(y) -> array``: the potential energy at displacement y, dimensionless
        (units of the stiffness times y², ``y²/2`` for a linear spring) [-].
    half_period_ratio : callable
        ``T(A)/T₀ -> array``: the half period of the undamped motion of swing A over
        the small-swing one [-] (1 for a linear spring).
    angle : bool
        True when y must be an angle in radians (``length_unit`` ``"rad"``).
    fitted : bool
        True when its parameters are measured from the record (a Duffing spring's β,
        from how the half period changes with the swing): the registered force is a
        template, and ``measure`` gives the run's.
    parameters : mapping
        Its parameters' values, once measured.
    measure : callable, optional
        ``measure(times, values) -> (RestoringForce, dict)``: the force with its
        parameters measured from the turning times [s] and the turning points about the
        equilibrium (the run's unit), and a record of the measurement (values,
        standard errors) for the output.
    spring : callable, optional
        ``V'(y) -> array``: the restoring force per unit stiffness [-]; with
        ``kernels``, what lets the laws' fits use this force
        (:mod:`bayestribo.model.laws.nonlinear`). A force without them is the
        linear spring to the laws.
    kernels : (callable, callable), optional
        The compiled ``V'(y, k)`` and ``V(y, k)`` (numba functions importable by
        name), ``k`` the values of ``kernel_parameters``.
    kernel_parameters : tuple of str
        The names in ``parameters`` the kernels take, in order.
    with_parameters : callable, optional
        ``with_parameters(values) -> RestoringForce``: the force at other values of its
        measured parameters (a mapping by name), for a fitted force: what lets a fit
        carry their standard errors into its intervals
        (:mod:`bayestribo.inference.restoring_error`).
    length_powers : tuple of int
        The power of y's unit in the unit of each of ``kernel_parameters`` (a Duffing
        spring's β is in 1/unit²: -2), so that a kernel measured in one unit of y is
        the same force in another (:func:`rescaled`): the fit's unit of y is N/k, which
        moves with the frequency that scales time.
    """

    name: str
    description: str
    potential: Callable[[ArrayLike], NDArray]
    half_period_ratio: Callable[[ArrayLike], NDArray]
    angle: bool = False
    fitted: bool = False
    parameters: Mapping[str, float] = field(default_factory=dict)
    measure: Callable[[ArrayLike, ArrayLike], tuple[RestoringForce, dict]] | None = None
    spring: Callable[[ArrayLike], NDArray] | None = None
    kernels: tuple[Callable, Callable] | None = None
    kernel_parameters: tuple[str, ...] = ()
    with_parameters: Callable[[Mapping[str, float]], RestoringForce] | None = None
    length_powers: tuple[int, ...] = ()

    def kernel(self) -> RestoringKernel | None:
        """What the laws' integrator takes of this force (None for a force without
        compiled kernels: the linear spring).

        Raises
        ------
        ValueError
            For a fitted force whose parameters were not measured yet.
        """
        if self.kernels is None or self.spring is None:
            return None
        missing = [name for name in self.kernel_parameters if name not in self.parameters]
        if missing:
            raise ValueError(
                f"restoring force {self.name}: its parameters {missing} are measured from "
                "the record first (its 'measure')"
            )
        return RestoringKernel(
            self.name,
            self.kernels[0],
            self.kernels[1],
            tuple(float(self.parameters[name]) for name in self.kernel_parameters),
            self.potential,
            self.spring,
            self.half_period_ratio,
        )

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(f"restoring force name must be an identifier, got {self.name!r}")
        # near zero on the force's own scale, which the run's unit sets: a Duffing
        # spring of β = 0.1 per mm² holds βy² = 0.1 at y = 1e-3 in metres
        if not any(
            math.isclose(float(self.potential(y)), 0.5 * y * y, rel_tol=1e-3)
            for y in (1e-3, 1e-6, 1e-9)
        ):
            raise ValueError(f"restoring force {self.name}: V(y) must be y²/2 near y = 0")


@dataclass(frozen=True)
class RestoringKernel:
    """A nonlinear restoring force as the laws' integrator and the energy take it.

    Two kernels are equal when their force's name and coefficients are.

    Attributes
    ----------
    name : str
        The force's name.
    spring_kernel, potential_kernel : numba functions
        ``V'(y, k)`` and ``V(y, k)``, dimensionless [-].
    coefficients : tuple of float
        ``k``.
    potential, spring : callable
        ``V(y)`` and ``V'(y)`` over arrays (the record's energy and its noise).
    half_period_ratio : callable
        ``T(A)/T₀`` over arrays (:attr:`RestoringForce.half_period_ratio`).
    """

    name: str
    spring_kernel: Callable = field(compare=False)
    potential_kernel: Callable = field(compare=False)
    coefficients: tuple[float, ...] = ()
    potential: Callable[[ArrayLike], NDArray] = field(compare=False, default=None)  # type: ignore[assignment]
    spring: Callable[[ArrayLike], NDArray] = field(compare=False, default=None)  # type: ignore[assignment]
    half_period_ratio: Callable[[ArrayLike], NDArray] = field(compare=False, default=None)  # type: ignore[assignment]

    def describe(self) -> str:
        """Its name and coefficients, for the output."""
        if not self.coefficients:
            return self.name
        return f"{self.name} ({', '.join(f'{c:.4g}' for c in self.coefficients)})"


def rescaled(kernel: RestoringKernel | None, ratio: float) -> RestoringKernel | None:
    """The same restoring force with y in a unit ``ratio`` times as long.

    A kernel's coefficients are in the unit of the y it was measured on: a Duffing
    spring's β y² is the same number for y = x/ℓ and β in 1/ℓ², so that with y in the
    unit ℓ' = ratio ℓ, β' = β ratio² (``RestoringForce.length_powers``). A fit measures
    β on the record scaled by the rig's nominal frequency (ℓ = N/k) and then scales it
    by the small swings' ω₀, or the law's own frequency: k, and ℓ with it, move by the
    square of that frequency's ratio.

    Parameters
    ----------
    kernel : RestoringKernel or None
        The force measured in the unit ℓ (None: the linear spring, returned as None).
    ratio : float
        ℓ'/ℓ [-], positive.

    Returns
    -------
    RestoringKernel or None
        The kernel itself when it has no coefficients or ``ratio`` is 1.

    Raises
    ------
    ValueError
        For a ratio that is not positive and finite, or a force with coefficients that
        declares no ``length_powers`` (or no ``with_parameters``) to rescale them by.
    """
    if kernel is None:
        return None
    if not (math.isfinite(ratio) and ratio > 0.0):
        raise ValueError(f"ratio: expected a positive, finite number, got {ratio!r}")
    if not kernel.coefficients or ratio == 1.0:
        return kernel
    force = get_restoring(kernel.name)
    powers = force.length_powers
    if len(powers) != len(kernel.coefficients) or force.with_parameters is None:
        raise ValueError(
            f"restoring force {kernel.name}: its coefficients cannot be taken to another "
            "unit of y (it declares no length_powers, or no with_parameters)"
        )
    values = {
        name: value * ratio ** (-power)
        for name, value, power in zip(
            force.kernel_parameters, kernel.coefficients, powers, strict=True
        )
    }
    return force.with_parameters(values).kernel()


class RestoringInfo(NamedTuple):
    """A built-in restoring force before its module is imported."""

    #: Its name (:attr:`RestoringForce.name`).
    name: str
    #: One line for help texts (:attr:`RestoringForce.description`).
    description: str
    #: The module that defines and registers it.
    module: str


#: The restoring forces shipped with the package, in the order of ``--restoring``; each
#: module registers its :class:`RestoringForce` (with this description) when imported.
BUILTIN_RESTORING: tuple[RestoringInfo, ...] = (
    RestoringInfo(
        "linear",
        "a linear spring, k x (Rigaud et al. 2010, Eq. 6): V = y²/2",
        "bayestribo.model.restoring.linear",
    ),
    RestoringInfo(
        "pendulum",
        "a pendulum, m g L sin θ (θ in radians): V = 1 - cos θ",
        "bayestribo.model.restoring.pendulum",
    ),
    RestoringInfo(
        "duffing",
        "a Duffing spring, k(x + βx³): V = y²/2 + βy⁴/4, β measured from how the half "
        "period changes with the swing",
        "bayestribo.model.restoring.duffing",
    ),
)
_BUILTIN = {info.name: info for info in BUILTIN_RESTORING}

#: Every registered restoring force by name: those registered at run time, and the
#: built-in ones whose module was imported (:func:`get_restoring` imports it on first
#: use; ``bayestribo.model.restoring.RESTORING`` imports them all first).
RESTORING: dict[str, RestoringForce] = {}


def builtin_description(name: str) -> str:
    """The description of the built-in restoring force ``name`` (for its module)."""
    return _BUILTIN[name].description


def register_builtin(force: RestoringForce) -> RestoringForce:
    """Register a built-in restoring force as its module is imported (a force registered
    under its name before, with ``replace=True``, is kept)."""
    return RESTORING.setdefault(force.name, force)


def register_restoring(force: RestoringForce, *, replace: bool = False) -> RestoringForce:
    """Register a restoring force so that ``restoring`` can name it.

    Raises
    ------
    ValueError
        When the name is taken, by a built-in force too (and ``replace`` is False).
    """
    if force.name == AUTO:
        raise ValueError(f"a restoring force cannot be named {AUTO!r}: it asks a fit to choose")
    if (force.name in RESTORING or force.name in _BUILTIN) and not replace:
        raise ValueError(f"a restoring force named {force.name!r} is already registered")
    RESTORING[force.name] = force
    return force


def restoring_table() -> dict[str, str]:
    """Every registered restoring force's description by name (the built-in ones first),
    without importing any of them: the command line's ``--restoring`` choices."""
    table = {info.name: info.description for info in BUILTIN_RESTORING}
    table.update((name, force.description) for name, force in RESTORING.items())
    return table


def available_restoring() -> list[str]:
    """Names of the registered restoring forces."""
    return list(restoring_table())


def restoring_choices() -> list[str]:
    """What ``restoring`` accepts: every registered force's name, then ``"auto"``
    (:data:`AUTO`)."""
    return [*available_restoring(), AUTO]


def load_builtin_restoring() -> dict[str, RestoringForce]:
    """:data:`RESTORING` with every built-in restoring force's module imported."""
    for info in BUILTIN_RESTORING:
        importlib.import_module(info.module)  # registers it, unless replaced
    return RESTORING


def get_restoring(name: str | RestoringForce | None) -> RestoringForce:
    """The restoring force of a name (``None``: linear; a force is returned as it is).

    Raises
    ------
    ValueError
        For a name that is not registered, listing those that are.
    """
    if isinstance(name, RestoringForce):
        return name
    key = "linear" if name is None else str(name)
    if key == AUTO:
        raise ValueError(
            f"restoring force {AUTO!r} is chosen by a fit from how the half period changes "
            "with the swing (bayestribo.inference.restoring_choice), not a force of its own"
        )
    if key not in RESTORING and key in _BUILTIN:
        importlib.import_module(_BUILTIN[key].module)  # registers it
    if key not in RESTORING:
        raise ValueError(
            f"restoring force {name!r} is not known; expected one of {available_restoring()}"
        )
    return RESTORING[key]
