"""Dissipation laws as plug-ins: terms, their registry, and laws that sum them.

A law is named by its terms joined with ``+`` (``"viscous+coulomb"``, the default;
``"viscous+quadratic+coulomb"``, ...). Each term is one module that defines a
:class:`~bayestribo.model.laws.base.Term` and registers it; importing this package
registers the built-in terms, in this order:

* ``viscous``: c v, ζ (Rigaud et al. 2010, Eq. 7);
* ``coulomb``: μ_k N sgn v, sticking at μ_s (Eq. 5, 8);
* ``quadratic``: c₂ v|v|, air and fluid drag;
* ``power``: c_α |v|^α sgn v, α free;
* ``hysteretic``: a friction proportional to amplitude (with ``coulomb``, a friction
  μ_k + ηA that varies with amplitude);
* ``cubic``: c₃ v³, which with the others makes ΔE(A) any polynomial of degree 1-4
  with non-negative coefficients (the law-free fit).
"""

# One import line per built-in term: importing the module registers it.
from bayestribo.model.laws import viscous  # noqa: F401  isort: skip
from bayestribo.model.laws import coulomb  # noqa: F401  isort: skip
from bayestribo.model.laws import quadratic  # noqa: F401  isort: skip
from bayestribo.model.laws import power  # noqa: F401  isort: skip
from bayestribo.model.laws import hysteretic  # noqa: F401  isort: skip
from bayestribo.model.laws import cubic  # noqa: F401  isort: skip

# the sampling transforms of sets of terms (model/laws/transforms.py)
from bayestribo.model.laws import loss_share  # noqa: F401  isort: skip
from bayestribo.model.laws.base import (
    TERMS,
    Parameter,
    PhysicalScale,
    Term,
    available_terms,
    get_term,
    register_term,
)
from bayestribo.model.laws.law import DEFAULT_LAW, Law, get_law

__all__ = [
    "DEFAULT_LAW",
    "TERMS",
    "Law",
    "Parameter",
    "PhysicalScale",
    "Term",
    "available_terms",
    "get_law",
    "get_term",
    "register_term",
]
