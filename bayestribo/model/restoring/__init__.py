"""Restoring forces as plug-ins: the linear spring and the pendulum, and their registry.

A restoring force is one module that defines a
:class:`~bayestribo.model.restoring.base.RestoringForce` and registers it; importing
this package registers the built-in ones, in this order:

* ``linear``: k x, V = y²/2 (the default, every dissipation law's);
* ``pendulum``: m g L sin θ, V = 1 - cos θ, θ in radians;
* ``duffing``: k(x + βx³), V = y²/2 + βy⁴/4, β measured from the half periods.
"""

# One import line per built-in restoring force: importing the module registers it.
from bayestribo.model.restoring import linear  # noqa: F401  isort: skip
from bayestribo.model.restoring import pendulum  # noqa: F401  isort: skip
from bayestribo.model.restoring import duffing  # noqa: F401  isort: skip
from bayestribo.model.restoring.base import (
    RESTORING,
    RestoringForce,
    available_restoring,
    get_restoring,
    register_restoring,
)

__all__ = [
    "RESTORING",
    "RestoringForce",
    "available_restoring",
    "get_restoring",
    "register_restoring",
]
