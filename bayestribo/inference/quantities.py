"""What each quantity of a fit is: its symbol, its name in words and its unit.

A fit's posterior group holds the law's sampled parameters, the physical quantities
its terms derive (:meth:`bayestribo.model.laws.Term.physical`) and the quantities
every friction fit derives (μ_s, the friction displacement x_c, ζ_k, d_k, ...).
:func:`describe` says what one of them is, from the registry of dissipation terms
first (a law's parameter: its ``symbol``, ``label`` and ``unit``), then from
:data:`DERIVED` (the quantities :func:`bayestribo.inference.assemble.derived_quantities`
makes), then from the registry again (a term's physical quantity); the command line,
:meth:`bayestribo.inference.FitResult.to_dataframe` and the summaries read it, so that
a new term's parameters are named in words with no edit here.

Units are written as the registry writes them: ``"1"`` for a dimensionless number,
``"y"``, ``"1/y"``, ``"1/y²"`` for a coefficient of the dimensionless equation of
motion (y = x/ℓ, Rigaud et al. 2010, Eq. 6), an SI unit, or the displacement's unit
(``"m"``, ``"rad"``, ``"signal length unit"`` for a recording in an unstated unit).
:func:`unit_words` gives what a reader reads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from bayestribo.summary import ParameterSummary

__all__ = [
    "DERIVED",
    "Quantity",
    "QuantitySummary",
    "chain_diagnostics",
    "describe",
    "law_quantities",
    "unit_words",
]

#: Symbol, name in words and unit of each quantity a friction fit derives beyond the
#: law's own; ``"length"`` is the displacement's unit (:func:`describe` resolves it).
DERIVED: dict[str, tuple[str, str, str]] = {
    "mu_s": ("μ_s", "static friction coefficient", "1"),
    "friction_displacement": ("x_c", "friction as displacement", "length"),
    "static_friction_displacement": ("x_s", "static friction as displacement", "length"),
    "friction_torque": ("T_c", "friction torque", "N m"),
    "static_friction_torque": ("T_s", "static friction torque", "N m"),
    "zeta_k": ("ζ_k", "viscous damping ratio of the contact (ζ − ζ₀)", "1"),
    "d_k": ("d_k", "damping of the contact per unit load", "s/m"),
    "y0": ("y₀", "scaled displacement at the window's start (x₀/ℓ)", "1"),
    "log10_discrepancy": ("log₁₀ σ_d", "model discrepancy scale", "1"),
    "log10_shape": ("log₁₀ σ_s", "shape discrepancy scale", "1"),
}

#: Units of a law's parameters as a fit reports them, where they differ from the
#: registry's: the reported μ_k is the coefficient x_c k/N, a number (the sampled one
#: is in units of y, which is the same number where ℓ = N/k).
_REPORTED_UNITS = {"mu_k": "1"}

#: The same friction quantities for a rotation (the displacement an angle).
_ANGLES: dict[str, tuple[str, str]] = {
    "friction_displacement": ("θ_c", "friction as angle"),
    "static_friction_displacement": ("θ_s", "static friction as angle"),
}

#: Units that are numbers without a dimension.
_DIMENSIONLESS = ("", "1", "-", "y")


@dataclass(frozen=True)
class Quantity:
    """What one quantity of a fit is.

    Attributes
    ----------
    name : str
        Its name in the posterior group and in ``--json`` (``"zeta"``).
    symbol : str
        How it is printed (``"ζ"``), the subscript after ``_``.
    label : str
        Its name in words (``"equivalent viscous damping ratio"``).
    unit : str
        Its unit, as the registry writes it (``"1"`` when dimensionless; see the
        module notes).
    sampled : bool
        True for a coordinate the sampler moved, False for one derived from them.
    """

    name: str
    symbol: str
    label: str
    unit: str
    sampled: bool = False

    @property
    def dimensionless(self) -> bool:
        """True for a number without a dimension."""
        return self.unit in _DIMENSIONLESS

    @property
    def title(self) -> str:
        """Name in words and symbol: ``"equivalent viscous damping ratio ζ"``."""
        return f"{self.label} {self.symbol}" if self.label else self.symbol


def unit_words(unit: str | None) -> str:
    """A unit as a reader reads it: ``"dimensionless"`` for a number without a
    dimension, the displacement's unstated unit as ``"signal unit"``, the coefficients
    of the dimensionless equation of motion with ``y = x/ℓ`` said.

    Examples
    --------
    >>> unit_words("1"), unit_words("m"), unit_words("signal length unit")
    ('dimensionless', 'm', 'signal unit')
    >>> unit_words("1/y")
    '1/y (y = x/ℓ)'
    """
    if unit is None or unit in _DIMENSIONLESS:
        return "dimensionless"
    text = str(unit).replace("signal length unit", "signal unit").replace("^2", "²")
    return f"{text} (y = x/ℓ)" if text.startswith("1/y") else text


def _length_unit(metadata: dict[str, Any]) -> str:
    unit = metadata.get("length_unit", "m") or "m"
    return {"m": "m", "rad": "rad"}.get(unit, "signal length unit")


def law_quantities(
    law: str,
) -> tuple[dict[str, tuple[str, str, str]], dict[str, tuple[str, str, str]]]:
    """Symbol, label and unit of every parameter, and of every physical quantity, the
    terms of ``law`` name (each term's :meth:`~bayestribo.model.laws.Term.physical`,
    with and without a known stiffness); empty for a law this version does not
    register."""
    from bayestribo.model.laws import PhysicalScale, get_law

    try:
        terms = get_law(law).terms
    except ValueError:
        return {}, {}
    parameters: dict[str, tuple[str, str, str]] = {}
    physical: dict[str, tuple[str, str, str]] = {}
    scales = (PhysicalScale(), PhysicalScale(stiffness=1.0, mass=1.0, load=1.0))
    for term in terms:
        for p in term.parameters:
            parameters[p.name] = (p.symbol, p.label, "1" if p.unit == "-" else p.unit)
        values = {
            p.name: np.array([0.5 * (p.low + min(p.high, p.low + 1.0))]) for p in term.parameters
        }
        for scale in scales:
            try:
                quantities = term.physical(values, 1.0, scale)
            except (KeyError, ValueError, ZeroDivisionError):  # a term needing more
                continue
            for name, (_, unit, symbol, label) in quantities.items():
                physical.setdefault(name, (symbol, label, "1" if unit == "-" else unit))
    return parameters, physical


def describe(
    names: list[str],
    *,
    law: str,
    metadata: dict[str, Any] | None = None,
    units: dict[str, str] | None = None,
    sampled: set[str] | frozenset[str] = frozenset(),
    friction_defined: bool = False,
) -> dict[str, Quantity]:
    """What each of ``names`` is, for a fit of ``law``.

    Parameters
    ----------
    names : list of str
        Quantities of a fit's posterior group.
    law : str
        The fitted law (terms joined with ``+``).
    metadata : dict, optional
        The run's metadata (its ``length_unit`` gives the displacement's unit).
    units : dict, optional
        Units the fit recorded for the law's own physical quantities (they depend on
        what the run's metadata gave); these win over the registry's.
    sampled : set of str
        Names of the sampled coordinates.
    friction_defined : bool
        Whether the fit scaled y = x/ℓ by ℓ = N/k (its rig's load and mass,
        :meth:`bayestribo.model.scaling.Rig.scaling`); else ℓ is one unit of the signal
        and y₀ is the displacement (an angle in radians) in the signal's unit.

    Returns
    -------
    dict of str to Quantity
        By name, in the order of ``names``; a quantity known nowhere keeps its name
        as symbol, no label and the unit recorded for it (else ``""``).
    """
    metadata = metadata or {}
    length = _length_unit(metadata)
    parameters, physical = law_quantities(law)
    recorded = {**_REPORTED_UNITS, **(units or {})}
    out: dict[str, Quantity] = {}
    for name in names:
        if name in parameters:
            symbol, label, unit = parameters[name]
        elif name in DERIVED:
            symbol, label, unit = DERIVED[name]
            if length == "rad" and name in _ANGLES:
                symbol, label = _ANGLES[name]
        elif name in physical:
            symbol, label, unit = physical[name]
        else:
            symbol, label, unit = name, "", ""
        unit = recorded.get(name, unit)
        if unit == "length":
            unit = length
        if name == "y0" and not friction_defined:
            # ℓ is one unit of the signal (no load and mass to make N/k): y₀ is the
            # displacement (an angle in radians) itself, in the signal's unit
            what = "angle" if length == "rad" else "displacement"
            label, unit = f"{what} at the window's start", length
        out[name] = Quantity(name, symbol, label, unit, name in sampled)
    return out


@dataclass(frozen=True)
class QuantitySummary(ParameterSummary):
    """The posterior summary of one quantity of a fit, with what the quantity is.

    A :class:`~bayestribo.summary.ParameterSummary` (``mean``, ``sd``, ``median``,
    ``interval``, ``prob``, ``kind``, in the quantity's unit) with the fields of its
    :class:`Quantity` and two sampler diagnostics.

    Attributes
    ----------
    name, symbol, label, unit : str
        As :class:`Quantity` (``unit`` ``"1"`` when dimensionless).
    sampled : bool
        True for a coordinate the sampler moved.
    ess : float
        Effective sample size of the draws kept: draws / τ, τ the integrated
        autocorrelation time of the walkers' thinned chains (as the sampler measures
        it, :func:`~bayestribo.inference.sampling.effective_sample_size`), summed over
        the ensembles; NaN for draws that do not move.
    r_hat : float
        Rank-normalised split R-hat over the ensembles
        (:func:`~bayestribo.inference.sampling.rhat`, ArviZ's to the last bit); NaN
        with one ensemble.
    """

    name: str = ""
    symbol: str = ""
    label: str = ""
    unit: str = ""
    sampled: bool = False
    ess: float = math.nan
    r_hat: float = math.nan

    @classmethod
    def of(
        cls, quantity: Quantity, draws: ArrayLike, prob: float = 0.95, n_walkers: int | None = None
    ) -> QuantitySummary:
        """Summarise the draws of ``quantity``, shape (chain, draw), draws step-major
        over ``n_walkers`` walkers (None: one sequence per chain).

        Raises
        ------
        BayestriboError
            If the draws are empty or not finite, or ``prob`` is not in (0, 1).
        """
        x = np.asarray(draws, dtype=float)
        if x.ndim == 1:
            x = x[None, :]
        base = ParameterSummary.from_samples(x, prob)
        ess, r_hat = chain_diagnostics(x, n_walkers)
        return cls(
            **{f.name: getattr(base, f.name) for f in fields(ParameterSummary)},
            name=quantity.name,
            symbol=quantity.symbol,
            label=quantity.label,
            unit=quantity.unit,
            sampled=quantity.sampled,
            ess=ess,
            r_hat=r_hat,
        )

    @property
    def quantity(self) -> Quantity:
        """What the quantity is (without the numbers)."""
        return Quantity(self.name, self.symbol, self.label, self.unit, self.sampled)

    @property
    def title(self) -> str:
        """Name in words and symbol (:attr:`Quantity.title`)."""
        return self.quantity.title

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict: the fields of :meth:`ParameterSummary.to_dict`, then
        ``name, symbol, label, unit, sampled, ess, r_hat`` (None where not finite)."""
        d = super().to_dict()
        for key in ("ess", "r_hat"):
            d[key] = d[key] if math.isfinite(d[key]) else None
        return d


def chain_diagnostics(draws: ArrayLike, n_walkers: int | None = None) -> tuple[float, float]:
    """Effective sample size and R-hat of one quantity's draws.

    Parameters
    ----------
    draws : array_like
        Shape (chain, draw), each chain's draws step-major over ``n_walkers``.
    n_walkers : int, optional
        Walkers per ensemble; None (or a number that does not divide the draws): each
        chain is one sequence.

    Returns
    -------
    (float, float)
        ESS (summed over chains; NaN for draws that do not move) and R-hat (NaN with
        fewer than two chains).
    """
    from bayestribo.inference.sampling import effective_sample_size, rhat

    x = np.asarray(draws, dtype=float)
    n_chain, n_draw = x.shape
    walkers = n_walkers if n_walkers and n_draw % n_walkers == 0 else 1
    steps = n_draw // walkers
    ess = math.nan
    if steps >= 2:
        with np.errstate(invalid="ignore", divide="ignore"):
            per_chain = [
                float(effective_sample_size(x[c].reshape(steps, walkers, 1))[0])
                for c in range(n_chain)
            ]
        ess = float(np.sum(per_chain)) if all(math.isfinite(v) for v in per_chain) else math.nan
    r_hat = float(rhat(x[:, :, None])[0])
    return ess, r_hat
