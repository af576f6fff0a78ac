"""A run's metadata for people: "load N: 0.31 N", never ``load_N = 0.31``.

The sidecar's keys (``docs/run-format.md``) carry their unit in their name
(``load_N``, ``velocity_resolution_m_per_s``, ``temperature_C``); a report shows each as
a label in words, with the quantity's symbol where it has one, and the value followed
by its unit. Keys this module does not know are read the same way: a trailing unit
(``_N``, ``_kg``, ``_Hz``, ``_m``, ``_s``, ``_m_per_s``, ``_C``, ``_J``) becomes the
value's unit and the rest of the name words.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["metadata_rows", "value_text"]

#: Known keys: label in words (with the symbol), and the unit of the value.
KNOWN: dict[str, tuple[str, str]] = {
    "load_N": ("load N", "N"),
    "mass_kg": ("mass m", "kg"),
    "natural_frequency_Hz": ("natural frequency f (nominal)", "Hz"),
    "displacement_resolution_m": ("displacement resolution", "m"),
    "velocity_resolution_m_per_s": ("velocity resolution", "m/s"),
    "displacement_range_m": ("displacement range", "m"),
    "velocity_range_m_per_s": ("velocity range", "m/s"),
    "sample_rate_Hz": ("sampling rate", "Hz"),
    "water_mass_fraction": ("water mass fraction", ""),
    "temperature_C": ("temperature", "°C"),
    "length_unit": ("length unit", ""),
    # the simulator's record of a run's true values
    "zeta": ("ζ", ""),
    "mu_k": ("μ_k", ""),
    "mu_s": ("μ_s", ""),
    "initial_displacement_m": ("initial displacement", "m"),
    "offset_m": ("equilibrium offset", "m"),
    "release_time_s": ("release time", "s"),
    "magnet_fade_s": ("magnet fade time", "s"),
    "motion_duration_s": ("motion duration", "s"),
    "displacement_noise_m": ("displacement noise σ_x", "m"),
    "velocity_noise_m_per_s": ("velocity noise σ_v", "m/s"),
}

#: Units written at the end of a key, longest first, and how a reader writes them.
SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_m_per_s", "m/s"),
    ("_N", "N"),
    ("_kg", "kg"),
    ("_Hz", "Hz"),
    ("_m", "m"),
    ("_s", "s"),
    ("_C", "°C"),
    ("_J", "J"),
)


def value_text(value: Any, unit: str = "") -> str:
    """A metadata value as text: a number to four significant digits followed by its
    unit, a boolean as yes or no, a list joined by commas.

    Examples
    --------
    >>> value_text(0.59, "N"), value_text(1.5e-07, "m"), value_text(10000.0, "Hz")
    ('0.59 N', '1.5e-07 m', '10000 Hz')
    >>> value_text(True), value_text([1, 2])
    ('yes', '1, 2')
    """
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e9:
        text = f"{value:.0f}"  # a sampling rate of 10000 Hz, not 1e+04 Hz
    elif isinstance(value, float):
        text = f"{value:.4g}" if math.isfinite(value) else "–"
    elif isinstance(value, (list, tuple)):
        text = ", ".join(value_text(v) for v in value)
    elif value is None:
        text = "–"
    else:
        text = str(value)
    return f"{text} {unit}" if unit and text != "–" else text


def label(key: str) -> tuple[str, str]:
    """A key's label in words and its unit.

    Examples
    --------
    >>> label("load_N"), label("pin_radius_m"), label("operator")
    (('load N', 'N'), ('pin radius', 'm'), ('operator', ''))
    """
    if key in KNOWN:
        return KNOWN[key]
    for suffix, unit in SUFFIXES:
        if key.endswith(suffix) and len(key) > len(suffix):
            return key[: -len(suffix)].replace("_", " "), unit
    return key.replace("_", " "), ""


def metadata_rows(metadata: Mapping[str, Any], *, prefix: str = "") -> dict[str, str]:
    """A run's metadata as label -> value with unit, in the sidecar's order; a nested
    record (the simulator's ``simulation``) gives its own rows, labelled
    ``"<its label>: <key's label>"``; ``run_id`` and None values are left out.

    Examples
    --------
    >>> metadata_rows({"run_id": "r1", "load_N": 0.59, "simulation": {"zeta": 0.024}})
    {'load N': '0.59 N', 'simulation: ζ': '0.024'}
    """
    out: dict[str, str] = {}
    for key, value in metadata.items():
        if key == "run_id" or value is None:
            continue
        name, unit = label(key)
        if isinstance(value, Mapping):
            out.update(metadata_rows(value, prefix=f"{prefix}{name}: "))
        else:
            out[f"{prefix}{name}"] = value_text(value, unit)
    return out
