"""Column names with units: ``time_ms``, ``displacement_um``, ``velocity_mm_per_s``, …

A text file's header may name its columns by quantity and unit instead of the
canonical names (``time_s``, ``displacement_m``, ``velocity_m_per_s``). A name is a
quantity word and a unit, joined by ``_`` or written ``quantity [unit]`` or
``quantity (unit)``; the unit gives the factor to the canonical SI unit. A name
without a unit is refused with a message asking for one: a displacement in µm read
as metres is a wrong answer by 10⁶, not an error, so it is never guessed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence

from bayestribo.errors import RunFormatError
from bayestribo.io.run import (
    ACCELERATION,
    ACCELERATION_AXES,
    ANGLE,
    ANGULAR_ACCELERATION,
    ANGULAR_VELOCITY,
    DISPLACEMENT,
    TIME,
    VELOCITY,
)
from bayestribo.io.units import INCH_M, LENGTHS, PER_SECOND, TIMES

__all__ = [
    "IGNORE",
    "MAGNITUDES",
    "OTHER_QUANTITIES",
    "PIXEL_UNITS",
    "QUANTITIES",
    "UNITS",
    "acceleration_label",
    "check_scale",
    "column_name",
    "combine_units_row",
    "motion_label",
    "other_quantity",
    "parse_column",
    "pixel_column",
    "split_run_tag",
]

#: Column name that skips a column of a text file.
IGNORE = "ignore"

#: Words naming each canonical quantity (lower case), in English and in the languages
#: of the labs whose sensor software heads a column in theirs (German, French,
#: Italian, Spanish, Dutch: ``Zeit [s]``, ``Weg [mm]``, ``vitesse (m/s)``). Angular
#: quantities come first: ``angular_velocity_rad_per_s`` is an angular velocity, not a
#: velocity.
QUANTITIES: dict[str, tuple[str, ...]] = {
    ANGULAR_ACCELERATION: ("angular_acceleration", "angular acceleration"),
    ACCELERATION: (
        "acceleration",
        "accel",
        "acc",
        "a",
        "beschleunigung",
        "accélération",
        "accelerazione",
        "aceleración",
        "aceleracion",
        "versnelling",
    ),
    ANGULAR_VELOCITY: (
        "angular_velocity",
        "angular velocity",
        "angular speed",
        "angular rate",
        "omega",
        "ω",
    ),
    ANGLE: (
        "angle",
        "angular position",
        "angular displacement",
        "theta",
        "θ",
        "phi",
        "φ",
        "winkel",
        "angolo",
        "ángulo",
        "angulo",
        "hoek",
    ),
    TIME: ("time", "t", "zeit", "temps", "tempo", "tiempo", "tijd"),
    DISPLACEMENT: (
        "displacement",
        "disp",
        "position",
        "pos",
        "distance",
        "deflection",
        "x",
        "weg",
        "auslenkung",
        "verschiebung",
        "déplacement",
        "deplacement",
        "spostamento",
        "posizione",
        "desplazamiento",
        "posición",
        "posicion",
        "positie",
        "verplaatsing",
        "uitwijking",
    ),
    VELOCITY: (
        "velocity",
        "vel",
        "speed",
        "v",
        "geschwindigkeit",
        "vitesse",
        "velocità",
        "velocita",
        "velocidad",
        "snelheid",
    ),
}

_DEGREE = math.pi / 180.0
#: Standard gravity [m/s²], the unit ``g`` of an accelerometer (CGPM 1901).
STANDARD_GRAVITY = 9.80665

#: Units of each quantity and their factor to the canonical unit.
UNITS: dict[str, dict[str, float]] = {
    TIME: dict(TIMES),
    DISPLACEMENT: dict(LENGTHS),
    VELOCITY: {
        f"{length}{per}": factor
        for length, factor in LENGTHS.items()
        if length not in ("micron", "microns", "inches", "mils")
        for per in PER_SECOND
    }
    | {"ips": INCH_M},
    ANGLE: {
        "rad": 1.0,
        "radian": 1.0,
        "radians": 1.0,
        "mrad": 1e-3,
        "deg": _DEGREE,
        "degree": _DEGREE,
        "degrees": _DEGREE,
        "°": _DEGREE,
    },
    ANGULAR_VELOCITY: {
        **{f"rad{per}": 1.0 for per in PER_SECOND},
        **{f"deg{per}": _DEGREE for per in PER_SECOND},
        "°/s": _DEGREE,
        "°/sec": _DEGREE,
        "rpm": 2.0 * math.pi / 60.0,
    },
    ACCELERATION: {
        **{
            f"{prefix}{form}": factor
            for prefix, factor in (("m", 1.0), ("cm", 1e-2), ("mm", 1e-3))
            for form in ("_per_s2", "/s^2", "/s²", "/s2", "_per_s^2")
        },
        "g": STANDARD_GRAVITY,
    },
    ANGULAR_ACCELERATION: {
        **{
            f"{prefix}{form}": factor
            for prefix, factor in (("rad", 1.0), ("deg", _DEGREE), ("°", _DEGREE))
            for form in ("_per_s2", "/s^2", "/s²", "/s2", "_per_s^2")
        },
    },
}

#: Quantities that sensor software exports beside position and velocity; a header
#: column naming one of these is not read (and said), any other unknown name is an error.
OTHER_QUANTITIES: tuple[str, ...] = (
    "force",
    "voltage",
    "potential",
    "current",
    "temperature",
    "energy",
    "kinetic energy",
    "potential energy",
    "pressure",
    "strain",
    "sound level",
    "light intensity",
    "gyroscope",
    "magnetic field",
    "rotation",
    "illuminance",
    "sound pressure",
    "frequency",
    "tilt",
    "inclination",
    # a sample's or a video frame's number beside the time (video tracking, loggers)
    "frame",
    "frames",
    "frame number",
    "frame no.",
    "frame index",
    "index",
    "sample",
    "sample number",
    "sample no.",
    "sample index",
    "point",
    "no.",
    "#",
)

#: Spellings of the pixel, the unit of a video tracker's position (and of its speed,
#: per second): no length, until a camera's scale makes it one.
PIXEL_UNITS: tuple[str, ...] = ("px", "pix", "pixel", "pixels")

#: Words before or after a quantity that name its axis or its kind, not another
#: quantity (phyphox's ``Acceleration x``, ``Linear Acceleration y``, ``Absolute
#: acceleration``, ``Acceleration with g z``).
_AXIS_SUFFIX = re.compile(r"\s+(?:[xyz]|with\s+g(?:\s+[xyz])?)$")
_KIND_PREFIX = re.compile(r"^(?:absolute|linear|total|resultant|raw)\s+")
#: An acceleration along one axis of a three-axis sensor: ``acceleration x``, ``linear
#: acceleration y``, ``acceleration with g z``, ``accel_x``.
_AXIS = re.compile(
    r"^(?:(?:linear|raw)\s+)?(?P<word>acceleration|accel|acc|a)"
    r"(?:\s+with\s+g)?[\s_](?P<axis>[xyz])$"
)
#: Prefixes that make an acceleration a magnitude (``Absolute acceleration``): never
#: a motion's signed component, so not read.
MAGNITUDES = re.compile(r"^(?:absolute|total|resultant)\s+")

#: Run labels sensor software adds to column names: ``Time (s) Run #1`` (PASCO),
#: ``Run 1: Position (m)`` and ``Latest: Time (s)`` (Vernier), ``Data Set 2: ...``.
_TAG_SUFFIX = re.compile(r"^(?P<label>.*?\S)\s+(?P<tag>Run\s*#?\s*\d+)\s*$", re.IGNORECASE)
_TAG_PREFIX = re.compile(
    r"^\s*(?P<tag>Run\s*#?\s*\d+|Latest|Data\s*Set\s*\d*)\s*:\s*(?P<label>\S.*)$",
    re.IGNORECASE,
)


def split_run_tag(name: str) -> tuple[str, str | None]:
    """A header name without the run label sensor software adds, and that label.

    ``"Position (m) Run #2"`` gives ``("Position (m)", "Run #2")``; ``"Latest: Time (s)"``
    gives ``("Time (s)", "Latest")``; a name without a label is returned with None.
    """
    for pattern in (_TAG_SUFFIX, _TAG_PREFIX):
        m = pattern.match(name)
        if m:
            return m.group("label").strip(), " ".join(m.group("tag").split())
    return name, None


def other_quantity(name: str) -> bool:
    """True for a header name of a quantity that is not read (acceleration, force, ...),
    with an axis or a kind about it (``Acceleration x (m/s^2)``, ``Absolute
    acceleration``)."""
    word, _ = _split(name.replace("\u03bc", "\u00b5"))
    if (
        MAGNITUDES.match(word)
        and _AXIS_SUFFIX.sub("", MAGNITUDES.sub("", word)) in (QUANTITIES[ACCELERATION])
    ):
        return True  # the magnitude of an acceleration: not a signed motion
    word = _KIND_PREFIX.sub("", _AXIS_SUFFIX.sub("", word))
    return word in OTHER_QUANTITIES


def acceleration_label(name: str) -> bool:
    """True for a header name of an acceleration that is read: a signed component
    (``Acceleration (m/s^2)``, ``Acceleration x (m/s^2)``, ``accel_g``, ``angular
    acceleration [rad/s^2]``), not a magnitude (``Absolute acceleration``)."""
    word, _ = _split(name.replace("\u03bc", "\u00b5"))
    return (
        word in QUANTITIES[ACCELERATION]
        or word in QUANTITIES[ANGULAR_ACCELERATION]
        or _AXIS.match(word) is not None
    )


def motion_label(name: str) -> bool:
    """True for a header name of a displacement, a velocity, an angle or an angular
    velocity, with or without its unit (``position``, ``Velocity (m/s)``)."""
    word, _ = _split(name.replace("\u03bc", "\u00b5"))
    return any(word in QUANTITIES[q] for q in (DISPLACEMENT, VELOCITY, ANGLE, ANGULAR_VELOCITY))


def combine_units_row(names: Sequence[str], units: Sequence[str]) -> list[str] | None:
    """A header of names and a row of units below it (``Time``/``s``), as ``Time (s)``.

    Returns None when the second row is not a row of units for these names: a different
    length, or a name that carries its unit already.
    """
    if len(names) != len(units) or not any(u.strip() for u in units):
        return None
    if any(_KEY_VALUE.search(n) for n in names):
        return None  # a preamble's ``Key: value`` line (``Sample rate: 1 kHz``), no names
    if any(_split(n)[1] is not None for n in names):
        return None
    if any(len(u.strip()) > 12 or " " in u.strip() for u in units):
        return None
    return [f"{n} ({u.strip()})" if u.strip() else n for n, u in zip(names, units, strict=True)]


#: A ``Key: value`` or ``key = value`` line of a preamble: a separator, then a number.
_KEY_VALUE = re.compile(r"[:=]\s*[-+]?\.?\d")

_BRACKETED = re.compile(r"^\s*(?P<word>[^\[\(]+?)\s*[\[\(]\s*(?P<unit>[^\]\)]+?)\s*[\]\)]\s*$")


def _split(name: str) -> tuple[str, str | None]:
    """(quantity word, unit or None) of a header name."""
    m = _BRACKETED.match(name)
    if m:
        return m.group("word").strip().lower(), m.group("unit").strip().replace(" ", "")
    text = name.strip()
    low = text.lower()
    for words in QUANTITIES.values():
        for word in words:
            if low == word:
                return word, None
            if low.startswith(word + "_"):
                return word, text[len(word) + 1 :]
    return low, None


def _in_pixels(unit: str | None, canonical: str) -> bool:
    """True for a position in pixels (``px``) or a speed in pixels per second."""
    if unit is None:
        return False
    unit = unit.lower()
    if canonical == VELOCITY:
        for per in ("/s", "_per_s", "/sec"):
            if unit.endswith(per):
                return unit[: -len(per)] in PIXEL_UNITS
        return False
    return unit in PIXEL_UNITS


def pixel_column(name: str) -> str | None:
    """The canonical column of a header name in pixels (``x (px)``: ``displacement_m``,
    ``v (px/s)``: ``velocity_m_per_s``), or None for a name that is not in pixels."""
    word, unit = _split(name.replace("\u03bc", "\u00b5"))
    for canonical in (DISPLACEMENT, VELOCITY):
        if word in QUANTITIES[canonical] and _in_pixels(unit, canonical):
            return canonical
    return None


def parse_column(name: str) -> tuple[str, float] | None:
    """The canonical column and the factor to its unit, for a header name.

    Parameters
    ----------
    name : str
        A header field, e.g. ``"time_ms"``, ``"displacement [µm]"``, ``"velocity_m_per_s"``.

    Returns
    -------
    (canonical name, factor) or None
        None when the name is no known quantity.

    Raises
    ------
    ValueError
        For a known quantity without a unit, or with a unit that is not known; the
        message lists the units accepted.
    """
    # the Greek letter mu (U+03BC) and the micro sign (U+00B5) look alike: one unit
    word, unit = _split(name.replace("\u03bc", "\u00b5"))
    column = None
    axis = _AXIS.match(word)
    if axis is not None:  # Acceleration x (m/s^2)
        word, column = axis.group("word"), ACCELERATION_AXES[axis.group("axis")]
    elif word in QUANTITIES[ACCELERATION] and unit is not None:
        under = re.match(r"^(?P<axis>[xyz])_(?P<unit>.+)$", unit)  # accel_x_g
        if under is not None:
            unit, column = under.group("unit"), ACCELERATION_AXES[under.group("axis")]
    for canonical, words in QUANTITIES.items():
        if word not in words:
            continue
        units = UNITS[canonical]
        if canonical in (DISPLACEMENT, VELOCITY) and _in_pixels(unit, canonical):
            raise ValueError(f"column {name!r} is in pixels, not in a unit of length")
        if unit is None:
            raise ValueError(
                f"column {name!r} has no unit; name it with one, e.g. "
                f"{word}_{next(iter(units))}, or one of {sorted(units)}"
            )
        key = unit if unit in units else unit.lower()
        if key not in units:
            raise ValueError(
                f"column {name!r}: unknown unit {unit!r} for {canonical}; expected one of "
                f"{sorted(units)}"
            )
        return column or canonical, units[key]
    return None


#: A unit spelled as a column name's suffix: letters, digits and underscores only.
_NAME_UNIT = re.compile(r"^[A-Za-z0-9_]+$")


def column_name(label: str, column: str, factor: float) -> str:
    """The column name, with its unit, that reads a header label as it was parsed.

    ``Position (mm)`` parsed as ``("displacement_m", 0.001)`` gives
    ``displacement_mm``; ``Angular Velocity (deg/s)`` gives
    ``angular_velocity_deg_per_s``; ``Acceleration x (m/s²)`` gives
    ``acceleration_x_m_per_s2``. The name is one that :func:`parse_column` reads back
    as the same column and factor; the file's own spelling of the unit is kept where it
    is such a name. Where no name of letters, digits and underscores does, the label
    itself is returned (it reads the same).

    Parameters
    ----------
    label : str
        The header label, without its run tag.
    column : str
        The canonical column :func:`parse_column` gave for it (``time_s``, ...).
    factor : float
        The factor to the canonical column's unit it gave.

    Returns
    -------
    str
        A name for ``columns=`` (``--columns``).
    """
    m = re.search(r"[\[\(]\s*([^\]\)]+?)\s*[\]\)]", label)
    spelled = None if m is None else m.group(1).replace(" ", "").replace("/", "_per_")
    for canonical, units in UNITS.items():
        si = next((u for u, f in units.items() if f == 1.0 and canonical.endswith(f"_{u}")), None)
        if si is None or not column.endswith(f"_{si}"):
            continue
        base = column[: -len(si) - 1]
        if not (column == canonical or base.startswith(canonical[: -len(si) - 1])):
            continue
        keys = [u for u, f in units.items() if _NAME_UNIT.match(u) and math.isclose(f, factor)]
        if spelled in keys:
            keys.insert(0, spelled)
        for key in keys:
            name = f"{base}_{key}"
            try:
                parsed = parse_column(name)
            except ValueError:
                continue
            if parsed is not None and parsed[0] == column and math.isclose(parsed[1], factor):
                return name
    return label


def si_names(labels: Sequence[str]) -> list[str] | None:
    """The column names that read a header's columns in SI units, or None.

    Each label of a quantity that is read (``time``, ``Position``) becomes its canonical
    name (``time_s``, ``displacement_m``), a label of another quantity ``ignore``. None
    when a label is neither: no suggestion can then be made.

    Parameters
    ----------
    labels : sequence of str
        The header's labels in file order.

    Returns
    -------
    list of str or None
        One name per label, for ``columns=`` when the file's units are SI.
    """
    names = []
    motion = any(motion_label(label) for label in labels)  # an acceleration beside it
    for label in labels:  # is not read
        if motion and acceleration_label(label):
            names.append(IGNORE)
            continue
        word, _ = _split(label.replace("\u03bc", "\u00b5"))
        canonical = next((c for c, words in QUANTITIES.items() if word in words), None)
        axis = _AXIS.match(word)
        if axis is not None:
            canonical = ACCELERATION_AXES[axis.group("axis")]
        if canonical is not None:
            names.append(canonical)
        elif word in OTHER_QUANTITIES:
            names.append(IGNORE)
        else:
            return None
    return names


def check_scale(
    scale: Mapping[str, float] | None, present: Sequence[str], where: str
) -> dict[str, float]:
    """Check per-column scale factors: canonical names of present columns -> finite, non-zero."""
    if scale is None:
        return {}
    if not isinstance(scale, Mapping):
        raise RunFormatError(
            "scale: expected a mapping of canonical column name to factor, for instance "
            f"{{'displacement_m': 1e-3}}; got {type(scale).__name__}",
            where,
        )
    out = {}
    for name, factor in scale.items():
        if name not in present:
            raise RunFormatError(
                f"scale: column {name!r} is not read from this file; the columns read are "
                f"{list(present)}",
                where,
            )
        try:
            value = float(factor)
        except (TypeError, ValueError, OverflowError):
            value = math.nan
        if not math.isfinite(value) or value == 0.0 or isinstance(factor, bool):
            raise RunFormatError(
                f"scale[{name!r}]: expected a finite non-zero number, got {factor!r}", where
            )
        out[name] = value
    return out
