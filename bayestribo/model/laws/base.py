r"""What a dissipation term is, and the one registry of terms.

A dissipation *law* is a sum of *terms* (:mod:`bayestribo.model.laws.law`). In the
dimensionless form of Rigaud et al. (2010), Eq. 6-7 (τ = Ωt, y = x/ℓ with
ℓ = N/k when the load and stiffness are known, one unit of the signal otherwise), a
law's equation of motion is

.. math::

    y'' + y = -\Big[\sum_{\text{drag}} g_i(|y'|) + μ(|Y_n|)\Big]\,\mathrm{sgn}(y'),
    \qquad μ(a) = \sum_{\text{friction}} μ_i(a),

while the contact slides. A term is one of two kinds:

* ``"drag"``: a force that grows with the speed, magnitude ``g(w) >= 0`` at speed
  ``w = |y'|`` (viscous 2ζw, quadratic γw², ...);
* ``"friction"``: a force of constant magnitude within each half cycle, ``μ(a)``,
  which may depend on the magnitude ``a = |Y_n|`` of the turning point where the
  half cycle began (Coulomb friction μ_k, a friction that grows with amplitude).

A term declares its sampled parameters (:class:`Parameter`: name, symbol, unit,
support, default prior, label), maps them to the coefficients its compiled force
uses (:meth:`Term.coefficients`, for example an equivalent damping ratio at a
reference amplitude becomes a force coefficient), gives its compiled force
(:attr:`Term.drag` or :attr:`Term.friction`, numba functions of the speed or amplitude
and a coefficient array) and its energy dissipated over one cycle of the harmonic
motion ``y = A cos τ`` (:meth:`Term.dissipation`, the law-free answer
``ΔE(A) = ∮ F(y') y' dτ``), and says how its parameters read in physical units
(:meth:`Term.physical`).

Adding a term is one module that defines a :class:`Term` and calls
:func:`register_term`; the law parser, the fit's parameters, priors, summaries and the
command line's ``--law`` choices are derived from the registry.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import PluginWarning

__all__ = [
    "PLUGIN_GROUP",
    "TERMS",
    "Parameter",
    "PhysicalScale",
    "Term",
    "available_terms",
    "get_term",
    "register_term",
]

TermKind = Literal["drag", "friction"]


@dataclass(frozen=True)
class PhysicalScale:
    """What the dimensionless quantities of one run are in physical units.

    Attributes
    ----------
    length_scale : float
        ℓ: the length of one unit of y [m when the load and stiffness are known, else
        one unit of the signal].
    omega : float
        Ω: the circular frequency that makes time dimensionless [rad/s].
    length_unit : str
        The unit of ℓ·y (``"m"``, or the signal's unit).
    stiffness : float or None
        k [N/m] where the mass is known (energies then in joules), else None.
    mass : float or None
        m [kg] where known.
    load : float or None
        N [N] where known and positive.
    """

    length_scale: float = 1.0
    omega: float = 1.0
    length_unit: str = "m"
    stiffness: float | None = None
    mass: float | None = None
    load: float | None = None

    @property
    def energy_factor(self) -> float:
        """Physical energy of one dimensionless energy unit: kℓ² [J], or ℓ² when k is
        unknown (then energies are ΔE/k in the signal's unit squared)."""
        k = self.stiffness if self.stiffness is not None else 1.0
        return k * self.length_scale**2

    @property
    def energy_unit(self) -> str:
        """``"J"`` where k is known, else ``"<unit>^2"`` (energy over stiffness)."""
        return "J" if self.stiffness is not None else f"{self.length_unit}^2"


@dataclass(frozen=True)
class Parameter:
    """One sampled parameter of a term.

    Attributes
    ----------
    name : str
        Identifier, unique across registered terms (``"zeta"``, ``"mu_k"``).
    symbol : str
        How it is printed (``"ζ"``, ``"μ_k"``).
    unit : str
        Unit of the sampled (dimensionless) value: ``"-"``, ``"y"`` (one unit of y),
        ``"1/y"``.
    low, high : float
        Support of the parameter (``high`` may be ``inf``).
    label : str
        A short phrase for reports (``"equivalent viscous damping ratio"``).
    null : float, optional
        The value at which the term exerts no force (or, for μ_s/μ_k, no static
        friction beyond the kinetic): what a parameter neither sampled nor fixed takes.
        Default ``low``.
    prior : callable
        ``prior(amplitude) -> dict``: the default prior given the observed initial
        amplitude |y0| (dimensionless), as the plain-data spec of
        :meth:`bayestribo.inference.priors.Prior.from_spec` (``{"type": "Uniform",
        "low": 0, "high": 0.3}``); priors are physical limits, see
        :mod:`bayestribo.inference.priors`.
    typical : float, optional
        A typical value on the paper's rig, in ``unit``: what ``bayestribo simulate``
        takes where it is not given. None (the default) where no value is typical
        (a drag's amount): the simulator then asks for it.
    """

    name: str
    symbol: str
    unit: str
    low: float
    high: float
    label: str
    prior: Callable[[float], Mapping[str, float | str]]
    null: float | None = None
    typical: float | None = None

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(f"Parameter name must be an identifier, got {self.name!r}")
        if not (self.low < self.high):
            raise ValueError(f"Parameter {self.name}: low must be below high")
        if self.typical is not None and not self.low <= self.typical <= self.high:
            raise ValueError(f"Parameter {self.name}: typical must lie in [low, high]")
        if self.null is None:
            object.__setattr__(self, "null", float(self.low))
        elif not self.low <= self.null <= self.high:
            raise ValueError(f"Parameter {self.name}: null must lie in [low, high]")


@dataclass(frozen=True)
class Term:
    """One dissipative force of a law.

    Attributes
    ----------
    name : str
        The term's name in law names (``"viscous"``).
    kind : {"drag", "friction"}
        Speed-dependent drag, or a friction constant within each half cycle.
    parameters : tuple of Parameter
        Its sampled parameters, in order.
    n_coefficients : int
        Number of coefficients its compiled force takes.
    force : numba function
        For ``"drag"``: ``g(w, c) -> float``, the force magnitude at speed ``w >= 0``;
        for ``"friction"``: ``μ(a, c) -> float``, the friction at turning amplitude
        ``a >= 0``, zero at every ``a`` when its coefficients are all zero (the
        integrator then follows the motion as without the term). ``c`` is this
        term's slice of the coefficient array.
    coefficients : callable
        ``coefficients(values, reference) -> list of arrays``: the force's
        coefficients from parameter values by name (arrays of one shape) and the
        reference amplitude (the observed |y0|).
    dissipation : callable
        ``dissipation(A, values, reference) -> array``: energy dissipated over one
        cycle of ``y = A cos τ`` [dimensionless energy, y²], broadcast over A and the
        values.
    physical : callable
        ``physical(values, reference, scale) -> dict``: derived quantities in
        physical units by name, each ``(array, unit, symbol, label)``.
    smooth : bool
        True when ``g`` is smooth at ``w = 0`` (an integer power); the integrator
        then needs no refinement at the turning points.
    description : str
        One line for help texts.
    sticks : bool
        True for the term that carries static friction (``mu_s_ratio``).
    overlaps : tuple of str
        Terms whose ΔE(A) this term makes too, at a value inside its prior or with
        the same power of the amplitude (power-law drag is viscous damping at α = 1;
        a friction proportional to amplitude loses 4ηA² per cycle as viscous damping
        loses 2πζA²). A law holding both trades one for the other along a ridge of its
        posterior: slow to sample, and it says nothing either alone does not, so
        ``law="auto"`` compares no law that holds a term and one it overlaps (either
        way round; :mod:`bayestribo.model.laws.candidates`). Names of terms not
        registered are allowed (a term may name one registered later).
    compared : bool
        False for a term ``law="auto"`` never compares (a building block of the
        law-free fit, not a mechanism); default True, so that a registered term is
        a candidate with no edit elsewhere.
    amount : str, optional
        The parameter whose null, the lower bound of its support, removes the term
        (its force 0 at every speed or amplitude, whatever the others): a drag's
        coefficient, μ_k. A law holding the term and another then nests the law
        without it on that bound (:attr:`bayestribo.model.laws.Law.boundaries`), and a
        fit of the law averages over it (:mod:`bayestribo.inference.boundary`). None
        (the default) for a term without one: a friction that may take either sign
        (η, whose null 0 is inside its prior), or a term that declares none.
    absent : str, optional
        How a report says the term is absent (``"no viscous damping (ζ = 0)"``);
        default ``"no <name> term (<symbol> = 0)"`` from ``amount``.
    """

    name: str
    kind: TermKind
    parameters: tuple[Parameter, ...]
    n_coefficients: int
    force: Any
    coefficients: Callable[[Mapping[str, NDArray], float], list[NDArray]]
    dissipation: Callable[[ArrayLike, Mapping[str, NDArray], float], NDArray]
    physical: Callable[[Mapping[str, NDArray], float, PhysicalScale], dict[str, tuple]]
    description: str
    smooth: bool = True
    sticks: bool = False
    nests: Mapping[str, float] = field(default_factory=dict)
    overlaps: tuple[str, ...] = ()
    compared: bool = True
    amount: str | None = None
    absent: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(f"Term name must be an identifier, got {self.name!r}")
        if self.kind not in ("drag", "friction"):
            raise ValueError(f"Term {self.name}: kind must be 'drag' or 'friction'")
        if self.n_coefficients < 1:
            raise ValueError(f"Term {self.name}: n_coefficients must be >= 1")
        if isinstance(self.overlaps, str):
            raise ValueError(f"Term {self.name}: overlaps must be a tuple of term names")
        object.__setattr__(self, "overlaps", tuple(self.overlaps))
        if self.name in self.overlaps:
            raise ValueError(f"Term {self.name}: a term does not overlap itself")
        if self.amount is not None:
            amount = next((p for p in self.parameters if p.name == self.amount), None)
            if amount is None or amount.null != amount.low:
                raise ValueError(
                    f"Term {self.name}: amount must name a parameter whose null is the "
                    f"lower bound of its support, got {self.amount!r}"
                )
            if not self.absent:
                object.__setattr__(
                    self, "absent", f"no {self.name} term ({amount.symbol} = {amount.null:g})"
                )

    @property
    def parameter_names(self) -> list[str]:
        """Names of the sampled parameters."""
        return [p.name for p in self.parameters]


#: Entry point group of installed packages that offer dissipation terms: each entry
#: point names a module whose import registers its terms (as the built-in modules do),
#: or a :class:`Term`, which is registered. A lab's package declares, in its
#: ``pyproject.toml``::
#:
#:     [project.entry-points."bayestribo.terms"]
#:     lab_quad = "labdrag.term"
PLUGIN_GROUP = "bayestribo.terms"


class _Registry(Mapping[str, Term]):
    """Registered terms by name, in registration order: the built-in ones, then those of
    installed packages (:data:`PLUGIN_GROUP`), loaded once, the first time the registry
    is listed or asked for a name it does not hold."""

    def __init__(self) -> None:
        self._terms: dict[str, Term] = {}
        self._plugins_loaded = False

    def __getitem__(self, name: str) -> Term:
        if name not in self._terms:
            self._load_plugins()
        return self._terms[name]

    def __iter__(self) -> Iterator[str]:
        self._load_plugins()
        return iter(self._terms)

    def __len__(self) -> int:
        self._load_plugins()
        return len(self._terms)

    def _load_plugins(self) -> None:
        """Import each installed package's terms once; one that fails is named in a
        :class:`~bayestribo.errors.PluginWarning` and left out, the others kept."""
        if self._plugins_loaded:
            return
        self._plugins_loaded = True
        from importlib.metadata import entry_points

        for point in entry_points(group=PLUGIN_GROUP):
            origin = f"{point.name} = {point.value}"
            if point.dist is not None:
                origin += f" (package {point.dist.name})"
            try:
                offered = point.load()
                if isinstance(offered, Term) and self._terms.get(offered.name) is not offered:
                    self.add(offered)
            except Exception as exc:  # a lab's package must not stop the built-in laws
                warnings.warn(
                    f"the dissipation term plug-in {origin} could not be loaded "
                    f"({type(exc).__name__}: {exc}); its terms are not available",
                    PluginWarning,
                    stacklevel=3,
                )

    def add(self, term: Term, replace: bool = False) -> None:
        if term.name in self._terms and not replace:
            raise ValueError(f"a term named {term.name!r} is already registered")
        taken = {
            p.name: other.name
            for other in self._terms.values()
            if other.name != term.name
            for p in other.parameters
        }
        for p in term.parameters:
            if p.name in taken:
                raise ValueError(
                    f"term {term.name!r}: parameter {p.name!r} is already a parameter of "
                    f"term {taken[p.name]!r}"
                )
        self._terms[term.name] = term

    def remove(self, name: str) -> None:
        del self._terms[name]


#: Every registered term by name.
TERMS = _Registry()


def register_term(term: Term, *, replace: bool = False) -> Term:
    """Register a term so that law names can use it.

    Parameters
    ----------
    term : Term
        The term.
    replace : bool
        Replace a term of the same name (else that is an error).

    Returns
    -------
    Term
        ``term``, so that a module can write ``VISCOUS = register_term(Term(...))``.

    Raises
    ------
    ValueError
        If the name is taken (without ``replace``) or a parameter name is already
        another term's.
    """
    TERMS.add(term, replace=replace)
    return term


def get_term(name: str) -> Term:
    """The registered term ``name``.

    Raises
    ------
    ValueError
        Naming the registered terms when ``name`` is not one of them.
    """
    try:
        return TERMS[name]
    except KeyError:
        raise ValueError(
            f"unknown dissipation term {name!r}; registered terms: {', '.join(TERMS)}"
        ) from None


def available_terms() -> list[str]:
    """Names of the registered terms, in registration order."""
    return list(TERMS)


def as_column(value: ArrayLike) -> NDArray:
    """A float array (helper for terms' coefficient maps)."""
    return np.asarray(value, dtype=float)


def harmonic_power_integral(exponent: ArrayLike) -> NDArray:
    r"""∫₀^{2π} |sin τ|^{p} dτ = 2√π Γ((p+1)/2)/Γ(p/2 + 1), for p > -1.

    The dissipation of a drag ``c|y'|^α`` over one cycle of ``y = A cos τ`` is
    ``c A^{α+1}`` times this integral with ``p = α + 1``.
    """
    from scipy.special import gammaln

    p = np.asarray(exponent, dtype=float)
    return 2.0 * math.sqrt(math.pi) * np.exp(gammaln(0.5 * (p + 1.0)) - gammaln(0.5 * p + 1.0))
