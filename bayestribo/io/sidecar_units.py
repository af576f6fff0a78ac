"""A sidecar's load and mass in another unit, named in the key or in the value.

Labs write the load of a dead weight in kilograms-force or grams (``"load_kgf": 0.03``,
``"load_g": 30``) and a mass in grams (``"mass_g": 35``), or put the unit in the value
(``"load_N": "30 gf"``, ``"mass": "35 g"``). Taken for the SI key by its nearest name
(``load_kgf`` renamed ``load_N`` with its number kept), such a load is 9.8 times too
small and μ_k 9.8 times too large, with nothing to show it. :func:`si_quantities`
converts these keys to ``load_N``, ``mass_kg`` and their uncertainties, and says each
conversion; a unit it does not know is left for the sidecar's check to refuse.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

__all__ = ["FORCES", "MASSES", "si_quantities"]

#: Standard gravity [m/s²] (CGPM 1901): one kilogram-force is 9.80665 N.
STANDARD_GRAVITY = 9.80665

#: Force units a load is written in and their factor to newtons. A load written in a
#: mass unit (``g``, ``kg``, ``lb``) is the weight of that mass (a dead weight).
FORCES: dict[str, float] = {
    "N": 1.0,
    "mN": 1e-3,
    "kN": 1e3,
    "kgf": STANDARD_GRAVITY,
    "kp": STANDARD_GRAVITY,
    "gf": 1e-3 * STANDARD_GRAVITY,
    "lbf": 0.45359237 * STANDARD_GRAVITY,
    "ozf": 0.028349523125 * STANDARD_GRAVITY,
    "kg": STANDARD_GRAVITY,
    "g": 1e-3 * STANDARD_GRAVITY,
    "lb": 0.45359237 * STANDARD_GRAVITY,
}

#: Mass units and their factor to kilograms.
MASSES: dict[str, float] = {
    "kg": 1.0,
    "g": 1e-3,
    "mg": 1e-6,
    "lb": 0.45359237,
    "oz": 0.028349523125,
}

#: The SI key of each quantity, its units and its names (a key is ``<name>_<unit>`` or
#: ``<name>`` with the unit in the value).
_QUANTITIES: tuple[tuple[str, str, dict[str, float]], ...] = (
    ("load_N", "load", FORCES),
    ("load_uncertainty_N", "load_uncertainty", FORCES),
    ("mass_kg", "mass", MASSES),
    ("mass_uncertainty_kg", "mass_uncertainty", MASSES),
)

#: A number followed by its unit: ``"30 gf"``, ``"0.035kg"``, ``"1.2e-2 kgf"``.
_VALUE_WITH_UNIT = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z]+)\s*$")


def _unit(table: Mapping[str, float], unit: str) -> str | None:
    """``unit`` as spelt in ``table`` (exact, else the one spelling that matches in any
    case), None if unknown or ambiguous."""
    if unit in table:
        return unit
    folded = [u for u in table if u.lower() == unit.lower()]
    return folded[0] if len(folded) == 1 else None


def _converted(
    key: str, value: Any, unit: str, table: Mapping[str, float]
) -> tuple[float, str] | None:
    """The value in SI and its unit as spelt, or None when it is not one of ``table``'s."""
    if isinstance(value, str):
        match = _VALUE_WITH_UNIT.match(value)
        if match is None:
            return None
        number, written = float(match.group(1)), match.group(2)
        spelt = _unit(table, written)
        if spelt is None:
            return None
        return number * table[spelt], spelt
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not unit:
        return None
    spelt = _unit(table, unit)
    if spelt is None:
        return None
    return float(value) * table[spelt], spelt


def si_quantities(metadata: Mapping[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """A sidecar's load and mass keys in other units, converted to the SI keys.

    Parameters
    ----------
    metadata : mapping
        The sidecar's object as read, before it is checked.

    Returns
    -------
    metadata : dict
        The same keys, except that ``load_<unit>`` (``load_kgf``, ``load_g``,
        ``load_mN``...), ``mass_<unit>`` (``mass_g``...), their uncertainties, and
        the SI keys or bare names holding a number with its unit (``"load_N": "30 gf"``,
        ``"mass": "35 g"``) are replaced by ``load_N`` [N], ``mass_kg`` [kg],
        ``load_uncertainty_N`` [N] and ``mass_uncertainty_kg`` [kg]. A load in a mass
        unit is that mass's weight (standard gravity).
    notes : list of str
        One sentence per key converted: the key, its value and unit, and the SI value.

    Raises
    ------
    ValueError
        When a quantity is given twice (``load_N`` and ``load_kgf``), naming both keys.
    """
    out = dict(metadata)
    notes: list[str] = []
    for si_key, name, table in _QUANTITIES:
        for key in list(out):
            value = out[key]
            if key == si_key and not isinstance(value, str):
                continue
            if key == si_key or key == name:
                unit = ""
            elif key.startswith(name + "_") and key.count("_") == name.count("_") + 1:
                unit = key[len(name) + 1 :]
            else:
                continue
            found = _converted(key, value, unit, table)
            if found is None:
                continue
            si, spelt = found
            other = [k for k in out if k == si_key and k != key]
            if other:
                raise ValueError(
                    f"metadata: {key!r} and {si_key!r} both give the {name.replace('_', ' ')}; "
                    "keep one"
                )
            del out[key]
            out[si_key] = si
            shown = repr(value) if isinstance(value, str) else f"{value:.6g} {spelt}"
            weight = (
                " (its weight, standard gravity)" if table is FORCES and spelt in MASSES else ""
            )
            notes.append(f"{key!r} = {shown} read as {si_key} = {si:.6g}{weight}")
    return out, notes
