"""Restoring forces as plug-ins: the linear spring and the pendulum, and their registry.

A restoring force is one module that defines a
:class:`~bayestribo.model.restoring.base.RestoringForce` and registers it; the built-in
ones are listed, in this order, in
:data:`~bayestribo.model.restoring.base.BUILTIN_RESTORING` and each module is imported
when its force is first asked for (:func:`get_restoring`):

* ``linear``: k x, V = y²/2 (the default);
* ``pendulum``: m g L sin θ, V = 1 - cos θ, θ in radians;
* ``duffing``: k(x + βx³), V = y²/2 + βy⁴/4, β measured from the half periods;

and ``auto`` (:data:`AUTO`) asks a fit to choose one of them from how the half period
changes with the swing (:mod:`bayestribo.inference.restoring_choice`).

A force with compiled kernels (``RestoringForce.kernels``: the pendulum, the Duffing
spring) is taken by every dissipation law's model and by the record's energy
(:mod:`bayestribo.model.laws.nonlinear`, docs/restoring.md).

Importing this package imports no numpy: :func:`restoring_table` names and describes
every registered force without importing them. ``RESTORING`` (every registered force
by name) imports the built-in ones first.
"""

from __future__ import annotations

from typing import Any

from bayestribo.model.restoring.base import (
    AUTO,
    BUILTIN_RESTORING,
    RestoringForce,
    RestoringInfo,
    RestoringKernel,
    available_restoring,
    get_restoring,
    load_builtin_restoring,
    register_restoring,
    rescaled,
    restoring_choices,
    restoring_table,
)

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


def __getattr__(name: str) -> Any:
    if name == "RESTORING":
        return load_builtin_restoring()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
