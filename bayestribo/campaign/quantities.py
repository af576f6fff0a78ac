"""The quantities a campaign compares across runs, in any dissipation law.

A law's sampled parameters are dimensionless (:mod:`bayestribo.model.laws.base`): one
unit of y is ℓ = N/k where the load and stiffness are known, one signal unit
otherwise, and time is Ωt. A population of repeats, or a trend against the load,
compares a quantity across runs whose ℓ and Ω differ (ℓ = N/k changes with the load),
so each parameter is taken in a form that means the same in every run:

* a parameter in units of ``"-"`` as sampled (ζ, the exponent α, η);
* a friction term's parameter in units of y where ℓ = N/k, as sampled: a force over
  the load, a friction coefficient (μ_k);
* any other parameter as the physical quantity of its term that is proportional to
  it alone, with the run's constant factor (c₂ as c₂ [kg/m] = c₂ m/ℓ, μ_k of a run
  without a load as the friction displacement x_c = μ_k ℓ): the factor is found by
  evaluating the term's ``physical`` at two values of the parameter and two
  reference amplitudes, so a term registered by a lab needs nothing here;
* a parameter defined at the run's own initial amplitude (power-law drag's ζ_α) is
  compared as sampled and flagged (:attr:`CampaignQuantity.at_own_amplitude`): runs
  released from other swings compare it at other swings;
* a parameter with no such quantity is not compared across runs (it is named, with
  why, in the ``left_out`` of :func:`campaign_quantities`).

The static friction ratio μ_s/μ_k is left out, as the paper's campaign leaves it: it
is rarely measured (its posterior follows its prior where no turning point falls
inside the sticking band).

The conversion uses each run's factor without the sensor's gain draws: a gain error
is common to the runs of one sensor, so it moves every run alike and is not a spread
between repeats (the single-run fit reports it, :mod:`bayestribo.signal.sensor`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws import get_law
from bayestribo.model.laws.base import PhysicalScale, Term

__all__ = ["CampaignQuantity", "campaign_quantities", "quantity_draws"]

#: Parameters a campaign does not compare (see the module notes).
NOT_COMPARED: frozenset[str] = frozenset({"mu_s_ratio"})
#: Relative tolerance of the proportionality checks on a term's physical quantities.
_PROPORTIONAL = 1e-9


@dataclass(frozen=True)
class CampaignQuantity:
    """One quantity a campaign compares across runs.

    Attributes
    ----------
    name : str
        Its name in the campaign's tables (``"zeta"``, ``"mu_k"``, ``"c2_SI"``).
    symbol : str
        How it is printed (``"ζ"``, ``"c₂"``).
    unit : str
        Its unit (``"1"`` for a dimensionless quantity, ``"kg/m"``).
    label : str
        A short phrase for reports.
    parameter : str
        The sampled parameter it is made from.
    factor : float
        The run's factor: quantity = factor × parameter (1 for a parameter taken as
        sampled).
    non_negative : bool
        True when it cannot be negative (the population mean is bounded at zero).
    term : str
        The law term it belongs to.
    at_own_amplitude : bool
        True for a parameter defined at each run's own initial amplitude (power-law
        drag's ζ_α): runs released from other amplitudes compare values at other
        swings, which differ where the law is not linear in the amplitude (α ≠ 1).
    """

    name: str
    symbol: str
    unit: str
    label: str
    parameter: str
    factor: float
    non_negative: bool
    term: str
    at_own_amplitude: bool = False

    def describe(self) -> dict[str, Any]:
        """Plain data: name, symbol, unit, label, term, non_negative (no run factor)."""
        out = asdict(self)
        del out["factor"], out["parameter"]
        return out


def _scale(result: Any) -> PhysicalScale | None:
    """The run's physical scale, from a fit result's attributes and metadata."""
    attrs = getattr(result, "attrs", None)
    if not isinstance(attrs, Mapping) or "length_scale" not in attrs or "omega" not in attrs:
        return None
    from bayestribo.inference.dissipation import physical_scale
    from bayestribo.model.scaling import Scaling

    scaling = Scaling(omega=float(attrs["omega"]), length_scale=float(attrs["length_scale"]))
    return physical_scale(scaling, getattr(result, "metadata", {}) or {})


def _friction_defined(result: Any) -> bool:
    attrs = getattr(result, "attrs", None)
    if isinstance(attrs, Mapping) and "friction_defined" in attrs:
        return bool(attrs["friction_defined"])
    return (getattr(result, "metadata", {}) or {}).get("load_N") not in (None, 0, 0.0)


def _proportional(term: Term, name: str, scale: PhysicalScale) -> tuple[str, float, tuple] | None:
    """The physical quantity of ``term`` proportional to its parameter ``name`` alone:
    (its name, the factor, its (unit, symbol, label)), or None."""
    ones = {p.name: np.array(1.0) for p in term.parameters}

    def physical(values: dict[str, NDArray], reference: float) -> dict[str, tuple]:
        try:
            return term.physical(values, reference, scale)
        except (ArithmeticError, ValueError, KeyError):
            return {}

    base = physical(ones, 1.0)
    doubled = physical({**ones, name: np.array(2.0)}, 1.0)
    moved = physical(ones, 2.0)
    others = {k: (np.array(2.0) if k != name else v) for k, v in ones.items()}
    held = physical(others, 1.0)
    for key, entry in base.items():
        value = float(np.asarray(entry[0], dtype=float))
        if not (math.isfinite(value) and value != 0.0):
            continue
        try:
            twice = float(np.asarray(doubled[key][0], dtype=float))
            same_ref = float(np.asarray(moved[key][0], dtype=float))
            same_others = float(np.asarray(held[key][0], dtype=float))
        except (KeyError, TypeError, ValueError):
            continue
        tol = _PROPORTIONAL * abs(value)
        if (
            abs(twice - 2.0 * value) <= 2.0 * tol
            and abs(same_ref - value) <= tol
            and abs(same_others - value) <= tol
        ):
            return key, value, tuple(entry[1:4])
    return None


def _at_reference(term: Term, name: str) -> bool:
    """Is ``name`` a scale of its term's dissipation (ΔE proportional to it) in a term
    whose dissipation at a given swing depends on the reference amplitude (the run's
    own initial amplitude)? Power-law drag's ζ_α is; its exponent α is not."""
    values = {p.name: np.array(max(p.low, 0.0) + 0.5) for p in term.parameters}
    swings = np.array([0.5, 2.0])
    try:
        one = term.dissipation(swings, values, 1.0)
        two = term.dissipation(swings, values, 2.0)
        doubled = term.dissipation(swings, {**values, name: 2.0 * values[name]}, 1.0)
    except (ArithmeticError, ValueError, KeyError):
        return False
    scale = np.allclose(doubled, 2.0 * one, rtol=1e-12, atol=0.0)
    return bool(scale and not np.allclose(one, two, rtol=1e-12, atol=0.0))


def campaign_quantities(result: Any) -> tuple[tuple[CampaignQuantity, ...], dict[str, str]]:
    """The quantities of a fit that a campaign compares across runs (module notes).

    Parameters
    ----------
    result : fit result
        A :class:`bayestribo.inference.FitResult` (its ``law``, ``attrs`` with the
        run's ``length_scale`` ℓ and ``omega`` Ω, ``metadata``, ``parameter_names``).

    Returns
    -------
    quantities : tuple of CampaignQuantity
        In the law's parameter order; only parameters the fit sampled.
    left_out : dict of str to str
        Sampled parameters not compared, with why.
    """
    law = get_law(str(getattr(result, "law", None) or "viscous+coulomb"))
    names = set(getattr(result, "parameter_names", ()) or ())
    scale = _scale(result)
    defined = _friction_defined(result)
    quantities: list[CampaignQuantity] = []
    left_out: dict[str, str] = {}
    for term in law.terms:
        for p in term.parameters:
            if p.name in NOT_COMPARED:
                continue
            sampled = p.name in names or (p.name == "mu_k" and "friction_displacement" in names)
            if not sampled:
                continue  # fixed, or not in this fit
            if p.unit == "-" or (term.kind == "friction" and p.unit == "y" and defined):
                if p.name in names:
                    quantities.append(
                        CampaignQuantity(
                            p.name,
                            p.symbol,
                            "1",
                            p.label,
                            p.name,
                            1.0,
                            p.low >= 0.0,
                            term.name,
                            _at_reference(term, p.name),
                        )
                    )
                    continue
            found = None if scale is None else _proportional(term, p.name, scale)
            if found is None:
                left_out[p.name] = (
                    f"{p.symbol} [{p.unit}] is in the run's own units and no physical "
                    "quantity of its term is proportional to it alone"
                )
                continue
            key, factor, (unit, symbol, label) = found
            quantities.append(
                CampaignQuantity(
                    key,
                    symbol,
                    str(unit),
                    str(label),
                    p.name,
                    float(factor),
                    p.low >= 0.0 and factor > 0,
                    term.name,
                )
            )
    return tuple(quantities), left_out


def quantity_draws(
    result: Any, quantity: CampaignQuantity
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The draws of ``quantity`` and the log prior density at each (with the Jacobian of
    the run's factor).

    Parameters
    ----------
    result : fit result
        ``samples`` and ``prior_logpdf`` (:class:`bayestribo.inference.FitResult`).
    quantity : CampaignQuantity
        From :func:`campaign_quantities` of the same result.

    Returns
    -------
    values, log_prior : ndarray
    """
    parameter = quantity.parameter
    try:
        raw = np.asarray(result.samples(parameter), dtype=float).ravel()
        log_prior = np.asarray(result.prior_logpdf(parameter, raw), dtype=float).ravel()
    except KeyError:
        # a friction parameter sampled as a friction displacement (no load)
        raw = np.asarray(result.samples(quantity.name), dtype=float).ravel()
        log_prior = np.asarray(result.prior_logpdf(quantity.name, raw), dtype=float).ravel()
        return raw, log_prior
    if quantity.factor == 1.0:
        return raw, log_prior
    return quantity.factor * raw, log_prior - math.log(abs(quantity.factor))
