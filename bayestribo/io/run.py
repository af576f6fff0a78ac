"""One free-decay recording and what is known about it: the :class:`Run`.

A run holds the sampled time [s], displacement [m] and velocity [m/s] of the
oscillating pin (either signal may be absent) and a metadata mapping. The known
metadata keys (:data:`METADATA_KEYS`) are typed and checked. A run built in Python may
hold further keys (plain data that JSON can store: text, numbers, booleans, ``None``,
lists, mappings), carried into results; a sidecar may not (a key of one's own goes
under ``user``, see :func:`check_metadata`).

Units. The column names carry SI units. When the length unit of a recording is
not known (a file from another rig), the metadata key ``length_unit`` is set to
``"arbitrary"``: the displacement is then in some unknown length unit and the
velocity in that unit per second. :meth:`Run.rig` then leaves out the load and
the mass, so the scaling uses one signal unit as length scale and friction can only
be reported as a friction displacement in the signal's unit.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo._text import shown
from bayestribo.errors import MetadataWarning, RecordingError, RunFormatError
from bayestribo.model.scaling import Rig, Scaling
from bayestribo.signal.frequency import oscillation_frequency
from bayestribo.signal.period import sample_step

__all__ = [
    "ACCELERATION",
    "ACCELERATIONS",
    "ACCELERATION_AXES",
    "ANGLE",
    "ANGULAR",
    "ANGULAR_ACCELERATION",
    "ANGULAR_VELOCITY",
    "COLUMNS",
    "DISPLACEMENT",
    "LENGTH_UNITS",
    "METADATA_KEYS",
    "TIME",
    "VELOCITY",
    "Run",
    "check_metadata",
]

#: Canonical column names: time [s], displacement [m], velocity [m/s].
TIME = "time_s"
DISPLACEMENT = "displacement_m"
VELOCITY = "velocity_m_per_s"
COLUMNS: tuple[str, str, str] = (TIME, DISPLACEMENT, VELOCITY)

#: Canonical column names of a rotational rig: angle [rad], angular velocity [rad/s].
#: A reader returns them for columns named as angles (``angle_deg``, ``Angle (rad)``);
#: :func:`bayestribo.read_run` takes them as the run's displacement and velocity with
#: ``length_unit`` ``"rad"``.
ANGLE = "angle_rad"
ANGULAR_VELOCITY = "angular_velocity_rad_per_s"
ANGULAR: Mapping[str, str] = MappingProxyType({ANGLE: DISPLACEMENT, ANGULAR_VELOCITY: VELOCITY})

#: Canonical column names of an accelerometer's channel: acceleration [m/s²], angular
#: acceleration [rad/s²], and the axes of a three-axis accelerometer (phyphox's
#: ``Acceleration x (m/s^2)``) [m/s²]. A reader returns them; :func:`bayestribo.read_run`
#: integrates the acceleration into the run's velocity
#: (:mod:`bayestribo.io.acceleration`) and records how under the metadata key
#: ``acceleration``.
ACCELERATION = "acceleration_m_per_s2"
ANGULAR_ACCELERATION = "angular_acceleration_rad_per_s2"
ACCELERATION_AXES: Mapping[str, str] = MappingProxyType(
    {axis: f"acceleration_{axis}_m_per_s2" for axis in "xyz"}
)
#: Every acceleration column, and the velocity it is integrated into.
ACCELERATIONS: Mapping[str, str] = MappingProxyType(
    {
        ACCELERATION: VELOCITY,
        ANGULAR_ACCELERATION: ANGULAR_VELOCITY,
        **{name: VELOCITY for name in ACCELERATION_AXES.values()},
    }
)

#: Values of the ``length_unit`` metadata key: metres, an unknown unit, or radians (the
#: displacement an angle, the velocity an angular velocity).
LENGTH_UNITS: tuple[str, ...] = ("m", "arbitrary", "rad")


@dataclass(frozen=True)
class _Key:
    kind: str  # "float", "int", "str" or "plain" (any plain JSON data, checked by `check`)
    description: str
    low: float | None = None  # inclusive lower bound
    low_open: bool = False  # True: the bound is exclusive
    high: float | None = None  # inclusive upper bound
    choices: tuple[str, ...] | None = None
    # for kind "plain": check(value, key, where) -> normalised value, raising RunFormatError
    check: Any = None

    def expected(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        text = {
            "float": "a finite number",
            "int": "an integer",
            "str": "a text string",
            "plain": "plain JSON data",
        }[self.kind]
        if self.low is not None:
            text += f" {'>' if self.low_open else '>='} {self.low:g}"
        if self.high is not None:
            text += f" and <= {self.high:g}"
        return text


#: The typed metadata keys of a run: name -> (type, meaning). ``None`` means unknown.
METADATA_KEYS: Mapping[str, _Key] = MappingProxyType(
    {
        # Every number has a range: a value outside no rig has (a mass of 1e308 kg, a
        # frequency of 1e-320 Hz) is a typo or a unit slip, refused before it reaches a
        # computation that would overflow.
        "load_N": _Key("float", "normal load N [N]; 0 for a test without contact", 0.0, high=1e6),
        "mass_kg": _Key("float", "oscillating mass m [kg]", 1e-9, high=1e4),
        "natural_frequency_Hz": _Key("float", "undamped natural frequency f [Hz]", 1e-4, high=1e6),
        "displacement_resolution_m": _Key(
            "float", "displacement resolution of the sensor [m]", 1e-15, high=1.0
        ),
        "velocity_resolution_m_per_s": _Key(
            "float", "velocity resolution of the sensor [m/s]", 1e-15, high=1e3
        ),
        "displacement_range_m": _Key(
            "float", "largest |displacement| the sensor can record [m]", 1e-12, high=1e3
        ),
        "velocity_range_m_per_s": _Key(
            "float", "largest |velocity| the sensor can record [m/s]", 1e-12, high=1e4
        ),
        "sample_rate_Hz": _Key("float", "sample rate [Hz]", 1e-3, high=1e10),
        "lubricant": _Key("str", "lubricant name"),
        "water_mass_fraction": _Key(
            "float", "mass fraction of water in the lubricant [-]", 0.0, high=1.0
        ),
        "repeat": _Key("int", "repeat number of the test", 0.0),
        "temperature_C": _Key("float", "temperature [°C]", -273.15, low_open=True, high=1e4),
        "run_id": _Key("str", "identifier of the run"),
        "length_unit": _Key(
            "str",
            "'m'; 'rad' for angles (a rotational rig); 'arbitrary' when the unit is unknown",
            choices=LENGTH_UNITS,
        ),
        "restoring": _Key(
            "plain",
            "the oscillator's restoring force: 'linear' (default), 'pendulum' (the angle "
            "in radians), 'duffing' (β measured), or 'auto' (chosen by the fit from how the "
            "half period changes with the swing), see bayestribo.model.restoring",
            check=lambda value, key, where: _restoring(value, key, where),
        ),
        "pendulum_radius_m": _Key(
            "plain",
            "the displacement is x = r sin θ of a pendulum's angle θ, recorded at the distance "
            "r from the pivot [m] (the displacement's unit with length_unit 'arbitrary'), or "
            "'simple' for a simple pendulum's bob (r = g/ω₀², its length): the run is read as "
            "the angle θ = arcsin(x/r) in radians (--pendulum-radius), "
            "see bayestribo.io.pendulum_arm",
            check=lambda value, key, where: _pendulum_radius(value, key, where),
        ),
        "pendulum_arm": _Key(
            "plain",
            "how a length recorded on a pendulum was read as its angle (written by the "
            "package, bayestribo.io.pendulum_arm): the radius, where it came from, the "
            "centre taken off and the largest angle",
        ),
        "inertia_kg_m2": _Key(
            "float",
            "moment of inertia of a rotational oscillator [kg m²]: friction as a torque",
            1e-15,
            high=1e6,
        ),
        "load_uncertainty_N": _Key(
            "float", "standard uncertainty of the normal load [N]", 0.0, high=1e6
        ),
        "mass_uncertainty_kg": _Key(
            "float", "standard uncertainty of the mass [kg]", 0.0, high=1e4
        ),
        "gain_uncertainty": _Key(
            "float",
            "relative standard uncertainty of the sensor's gain (calibration), both channels "
            "[-]; default: the sensor_kind's, else 0.01",
            0.0,
            high=0.5,
        ),
        "displacement_gain_uncertainty": _Key(
            "float",
            "relative standard uncertainty of the displacement channel's gain [-]",
            0.0,
            high=0.5,
        ),
        "velocity_gain_uncertainty": _Key(
            "float",
            "relative standard uncertainty of the velocity channel's gain [-]",
            0.0,
            high=0.5,
        ),
        "sensor_kind": _Key(
            "plain",
            "the kind of sensor ('laser_vibrometer', 'motion_sensor', 'encoder', 'video', "
            "'accelerometer', 'smartphone', 'seismometer', 'displacement_probe', or one "
            "registered): its typical gain uncertainty where gain_uncertainty is not given, "
            "see bayestribo.signal.sensor_kinds",
            check=lambda value, key, where: _sensor_kind(value, key, where),
        ),
        "filter": _Key(
            "plain",
            "the anti-alias filter both channels went through: {'kind': 'butterworth' or "
            "'bessel', 'order': 1 to 10, 'cutoff_Hz': > 0}",
            check=lambda value, key, where: _sensor_filter(value, key, where),
        ),
        "sensor_high_pass": _Key(
            "plain",
            "the analog high-pass every recorded channel went through (an AC-coupled "
            "channel, a geophone, a piezoelectric sensor): {'cutoff_Hz': > 0, 'order': 1 or "
            "2, 'damping': > 0 (two poles; default 0.707)}, or the corner in Hz for one "
            "pole; undone when the run is read (--sensor-high-pass), see "
            "bayestribo.io.high_pass",
            check=lambda value, key, where: _high_pass(value, key, where),
        ),
        "high_pass_undone": _Key(
            "plain",
            "how the sensor's high-pass was undone (written by the package, "
            "bayestribo.io.high_pass): the declaration, the channels and the rests where "
            "its drift was measured",
        ),
        "zeta0": _Key(
            "float", "damping ratio of the oscillator without contact ζ₀ [-]", 0.0, high=1.0
        ),
        "zeta0_sd": _Key("float", "standard uncertainty of ζ₀ [-]", 0.0, high=1.0),
        "window_s": _Key(
            "plain",
            "the part of the record analysed, [t0, t1] in seconds (--window T0:T1)",
            check=lambda value, key, where: _window(value, key, where),
        ),
        "series": _Key("str", "name of the series of runs the run belongs to"),
        "notes": _Key("str", "free text about the run"),
        # Records the package writes itself (simulator, acquisition) and a user's own keys:
        # any plain data, kept as it is.
        "user": _Key("plain", "a mapping of keys of your own (kept, not read)"),
        "simulation": _Key(
            "plain",
            "the simulator's settings and truth (written by the package): for a law of the "
            "registry its name, parameters with their units and the solver of its motion",
        ),
        "acquisition": _Key("plain", "the acquisition's report (written by the package)"),
        "acceleration": _Key(
            "plain",
            "how the velocity was integrated from an acceleration column (written by the "
            "package, bayestribo.io.acceleration): the column, the bias removed and where "
            "it was measured, the high-pass filter and its gain at the oscillation frequency, "
            "and under 'noise' its steps as the fit's noise model puts the sensor's noise "
            "through them",
        ),
        "complete": _Key("plain", "whether the acquisition received every sample"),
        "fault": _Key("plain", "the acquisition's fault, if any"),
        "gaps": _Key("plain", "gaps in the acquisition's samples"),
        "samples_missing": _Key("plain", "samples the acquisition did not receive"),
        "start_time": _Key(
            "plain",
            "date and time of t = 0, ISO 8601 text: a text file's first time stamp (a time "
            "of day alone when the stamps hold no date)",
            check=lambda value, key, where: _start_time(value, key, where),
        ),
        "data_file": _Key(
            "plain",
            "the data file as written (by the package): {'samples': its sample count, "
            "'sha256': its SHA-256}; a file that no longer matches is refused when read",
            check=lambda value, key, where: _data_file(value, key, where),
        ),
    }
)


def _data_file(value: Any, key: str, where: str | None) -> dict[str, Any]:
    """Check a ``data_file`` value: ``samples`` (an integer >= 0) and ``sha256`` (64
    hexadecimal digits), either or both, nothing else."""
    if not isinstance(value, Mapping) or not value:
        raise RunFormatError(
            f"metadata {key!r}: expected {{'samples': N, 'sha256': '64 hex digits'}}, got "
            f"{shown(value)}",
            where,
        )
    extra = sorted(set(value) - {"samples", "sha256"})
    if extra:
        raise RunFormatError(
            f"metadata {key!r}: unknown field(s) {extra}; expected 'samples' and 'sha256'", where
        )
    samples = value.get("samples")
    if samples is not None and (
        isinstance(samples, bool) or not isinstance(samples, int) or samples < 0
    ):
        raise RunFormatError(
            f"metadata '{key}.samples': expected an integer >= 0, got {shown(samples)}", where
        )
    digest = value.get("sha256")
    if digest is not None and not (
        isinstance(digest, str)
        and len(digest) == 64
        and all(c in "0123456789abcdef" for c in digest.lower())
    ):
        raise RunFormatError(
            f"metadata '{key}.sha256': expected 64 hexadecimal digits, got {shown(digest)}",
            where,
        )
    return {k: (v.lower() if k == "sha256" else v) for k, v in value.items() if v is not None}


def _start_time(value: Any, key: str, where: str | None) -> str:
    """Check a ``start_time`` value: a date and time, or a time of day, in ISO 8601."""
    import datetime

    if isinstance(value, str):
        for kind in (datetime.datetime, datetime.time):
            try:
                kind.fromisoformat(value)
            except ValueError:
                continue
            return value
    raise RunFormatError(
        f"metadata {key!r}: expected a date and time in ISO 8601 text, such as "
        f"'2026-11-30T09:15:02.120000', got {shown(value)}",
        where,
    )


def _high_pass(value: Any, key: str, where: str | None) -> dict[str, Any]:
    """Check a ``sensor_high_pass`` value (:func:`bayestribo.signal.high_pass.
    check_high_pass`)."""
    from bayestribo.signal.high_pass import check_high_pass

    try:
        return check_high_pass(value)
    except ValueError as exc:
        raise RunFormatError(f"metadata {key!r}: {exc}", where) from None


def _restoring(value: Any, key: str, where: str | None) -> str:
    """Check a ``restoring`` value: a registered restoring force's name, or ``"auto"``."""
    from bayestribo.model.restoring import AUTO, get_restoring, restoring_choices

    if not isinstance(value, str):
        raise RunFormatError(
            f"metadata {key!r}: expected one of {', '.join(restoring_choices())}, got {value!r}",
            where,
        )
    if value == AUTO:
        return AUTO
    try:
        return get_restoring(value).name
    except ValueError:
        raise RunFormatError(
            f"metadata {key!r}: expected one of {', '.join(restoring_choices())}, got {value!r}",
            where,
        ) from None


def _pendulum_radius(value: Any, key: str, where: str | None) -> float | str:
    """Check a ``pendulum_radius_m`` value: a radius > 0 (at most 1 km), or ``"simple"``."""
    from bayestribo.io.pendulum_arm import SIMPLE

    if value == SIMPLE:
        return SIMPLE
    radius = math.nan
    if isinstance(value, int | float) and not isinstance(value, bool):
        try:
            radius = float(value)
        except OverflowError:
            radius = math.nan
    if not (math.isfinite(radius) and 0.0 < radius <= 1e3):
        raise RunFormatError(
            f"metadata {key!r}: expected the pendulum's radius at the sensor in metres, "
            f"0 < r <= 1000, or {SIMPLE!r} for a simple pendulum (r = g/ω₀²), got "
            f"{shown(value)}",
            where,
        )
    return radius


def _sensor_kind(value: Any, key: str, where: str | None) -> str:
    """Check a ``sensor_kind`` value: a registered kind of sensor's name."""
    from bayestribo.signal.sensor_kinds import get_sensor_kind

    try:
        return get_sensor_kind(value).name
    except ValueError as exc:
        reason = str(exc).removeprefix("sensor_kind: ")
        raise RunFormatError(f"metadata {key!r}: {reason}", where) from None


def _window(value: Any, key: str, where: str | None) -> list[float]:
    """Check a ``window_s`` value: two finite times t0 < t1 [s]."""
    from bayestribo.errors import BayestriboError
    from bayestribo.io.options import check_window

    if not isinstance(value, list | tuple) or len(value) != 2:
        raise RunFormatError(
            f"metadata {key!r}: expected [t0, t1] in seconds, got {value!r}", where
        )
    try:
        t0, t1 = check_window(value)
        if not (math.isfinite(t0) and math.isfinite(t1)):
            raise BayestriboError(f"expected finite times, got {value!r}")
        return [t0, t1]
    except BayestriboError as exc:
        raise RunFormatError(f"metadata {key!r}: {exc}", where) from None


def _sensor_filter(value: Any, key: str, where: str | None) -> Any:
    """Check a ``filter`` sidecar value (:func:`bayestribo.signal.sensor.filter_gain`)."""
    from bayestribo.signal.sensor import check_filter

    try:
        return check_filter(value)
    except ValueError as exc:
        raise RunFormatError(f"metadata {key!r}: {exc}", where) from None


def _plain(value: Any, key: str, where: str | None) -> Any:
    """Check that an extra metadata value is plain JSON data; return a normalised copy."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        if not math.isfinite(float(value)):
            raise RunFormatError(
                f"metadata {key!r}: expected a finite number, got {value!r}", where
            )
        return float(value)
    if isinstance(value, list | tuple):
        return [_plain(v, f"{key}[{i}]", where) for i, v in enumerate(value)]
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise RunFormatError(
                    f"metadata {key!r}: mapping keys must be text strings, got {k!r}", where
                )
            out[k] = _plain(v, f"{key}.{k}", where)
        return out
    raise RunFormatError(
        f"metadata {key!r}: unknown value type {type(value).__name__}; expected text, a "
        "number, a boolean, null, a list or a mapping (plain JSON data)",
        where,
    )


def _typed(key: str, spec: _Key, value: Any, where: str | None) -> Any:
    """Check and normalise the value of a known metadata key."""
    if value is None:
        return None
    bad = RunFormatError(
        f"metadata {key!r} ({spec.description}): expected {spec.expected()}, "
        f"got {type(value).__name__} {shown(value)}",
        where,
    )
    if spec.kind == "plain":
        plain = _plain(value, key, where)
        return plain if spec.check is None else spec.check(plain, key, where)
    if spec.kind == "str":
        if not isinstance(value, str):
            raise bad
        if spec.choices is not None and value not in spec.choices:
            raise bad
        return value
    if isinstance(value, bool | np.bool_):
        raise bad
    if spec.kind == "int":
        if not isinstance(value, int | np.integer):
            raise bad
        value = int(value)
    else:
        if not isinstance(value, int | float | np.integer | np.floating):
            raise bad
        try:
            value = float(value)
        except OverflowError:
            raise bad from None
        if not math.isfinite(value):
            raise bad
    if spec.low is not None and (value < spec.low or (spec.low_open and value == spec.low)):
        raise bad
    if spec.high is not None and value > spec.high:
        raise bad
    return value


def check_metadata(
    metadata: Mapping[str, Any] | None, where: str | None = None, *, strict: bool = False
) -> dict:
    """Check a run's metadata and return a normalised copy.

    Known keys (:data:`METADATA_KEYS`) must have their type and range (numbers become
    ``float``, ``repeat`` stays ``int``; ``None`` means unknown). Any other key is kept
    if its value is plain JSON data (tuples become lists, NumPy scalars become Python
    numbers).

    Parameters
    ----------
    metadata : mapping or None
        Metadata with text keys.
    where : str, optional
        The file or origin named in error messages.
    strict : bool
        Refuse every key that is not a known key, naming the nearest known one (a
        sidecar: ``normal_load_N`` kept as free metadata would leave the load unknown
        and the friction unreported). A key of one's own goes under ``user``. Without
        ``strict`` (metadata a program builds), only near misses of a known key
        (``laod_N``, ``Load_N``) are refused.

    Raises
    ------
    RunFormatError
        Naming the key, its meaning and the expected type, for a value of the wrong
        type or range, a non-text key or a value JSON cannot store; and for an unknown
        key (see ``strict``), with the known key it most resembles.
    """
    if metadata is None:
        return {}
    if not isinstance(metadata, Mapping):
        raise RunFormatError(
            f"metadata: expected a mapping of names to values, got {type(metadata).__name__}",
            where,
        )
    out: dict[str, Any] = {}
    for key, value in metadata.items():
        if not isinstance(key, str):
            raise RunFormatError(f"metadata keys must be text strings, got {key!r}", where)
        spec = METADATA_KEYS.get(key)
        if spec is None:
            _check_unknown_key(key, where, strict, value)
        out[key] = _typed(key, spec, value, where) if spec else _plain(value, key, where)
    return out


def _nearest_key(key: str) -> str | None:
    """The known key that ``key`` most resembles: shared words (``normal_load_N`` and
    ``load_N`` share ``load`` and the unit ``N``) first, then spelling; None when no
    known key shares a word with it or half its spelling (``operator``)."""
    import difflib

    words = set(key.lower().replace("-", "_").split("_")) - {""}

    def score(known: str) -> tuple[int, float]:
        shared = len(words & set(known.lower().split("_")))
        return shared, difflib.SequenceMatcher(None, key.lower(), known.lower()).ratio()

    best = max(METADATA_KEYS, key=score)
    shared, ratio = score(best)
    return best if shared or ratio >= 0.6 else None


#: Words of a key that holds a channel's calibration (a factor to SI units).
_CALIBRATION = re.compile(
    r"(?:^|_)(?:scale|scaling|per_count|per_counts|per_lsb|per_v|per_mv|sensitivity|"
    r"calibration|cal|factor|counts_per)(?:_|$)",
    re.IGNORECASE,
)


def _calibration_advice(key: str, value: Any = None) -> str:
    """The refusal of a sidecar key that holds a channel's calibration, naming how a
    calibration is given (with the key's number, where it is one, as the scale of the
    channel its name says); "" for another key."""
    if not _CALIBRATION.search(key):
        return ""
    channel = "velocity_m_per_s" if re.search(r"per_s(?:ec)?(?:_|$)", key) else "displacement_m"
    number = (
        repr(float(value))
        if isinstance(value, int | float) and not isinstance(value, bool)
        else "FACTOR"
    )
    return (
        f"metadata key {key!r} looks like a channel's calibration (a factor to SI units), "
        "which the sidecar does not hold: move the key under 'user' "
        f'({{"user": {{{json.dumps(key)}: ...}}}}) or leave it out, and give the factor '
        f"when the file is read, scale={{'{channel}': {number}}} where it is in SI units "
        "(m, m/s) per unit of the file"
    )


def _check_unknown_key(key: str, where: str | None, strict: bool, value: Any = None) -> None:
    """Refuse a key that is not a known key: always when ``strict``, else when it is a
    known key misspelt (``laod_N``, ``Load_N``, ``load``): kept as free metadata it
    would leave the known key missing, and a missing load would make a run with contact
    look like one without."""
    import difflib

    calibration = _calibration_advice(key, value)
    if calibration and strict:
        raise RunFormatError(calibration, where)
    folded = {k.lower(): k for k in METADATA_KEYS}
    close = folded.get(key.lower()) or next(
        iter(difflib.get_close_matches(key, list(METADATA_KEYS), n=1, cutoff=0.8)), None
    )
    if close is None and strict:
        close = _nearest_key(key)
        if close is None:
            raise RunFormatError(
                f"metadata key {key!r} is not a known key; put a key of your own under "
                f"'user' ({{\"user\": {{{json.dumps(key)}: ...}}}}); the known keys are "
                + ", ".join(METADATA_KEYS),
                where,
            )
    if close is not None and close != key:
        raise RunFormatError(
            f"metadata key {key!r} is not a known key; did you mean {close!r} "
            f"({METADATA_KEYS[close].description})? Rename it, or put a key of your own "
            f"under 'user' ({{\"user\": {{{json.dumps(key)}: ...}}}}); the known keys are "
            + ", ".join(METADATA_KEYS),
            where,
        )


def _signal(name: str, values: ArrayLike | None, where: str | None) -> NDArray | None:
    if values is None:
        return None
    if (
        isinstance(values, np.ndarray)
        and values.dtype == np.float64
        and values.ndim == 1
        and not values.flags.writeable
        and values.flags.owndata
    ):
        # frozen (read-only, owning its data: no view can change it, as a reader's
        # columns or another run's arrays): shared, not copied (8 MB a channel at 1 MHz)
        return values
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise RunFormatError(f"field {name!r}: expected numbers, got {exc}", where) from None
    if array.ndim != 1:
        raise RunFormatError(
            f"field {name!r}: expected a 1-D array of samples, got shape {array.shape}", where
        )
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Run:
    """One free-decay recording: sampled signals and metadata.

    The constructor checks the structure (1-D arrays of equal length, at least one
    signal, typed metadata); the data checks (finite samples, regular time stamps,
    clipping, units...) are :func:`bayestribo.io.validation.validate_run`, which
    :func:`bayestribo.read_run` applies to every file it reads. The arrays are
    copied and made read-only (a float64 array that is read-only already and owns its
    data, as a reader's columns or another run's arrays, is shared: nothing can change
    it).

    Parameters
    ----------
    time : array_like
        Sample times t [s], 1-D.
    displacement : array_like, optional
        Displacement x [m] (or arbitrary length unit, see ``length_unit``).
    velocity : array_like, optional
        Velocity v [m/s] (or arbitrary length unit per second).
    metadata : mapping, optional
        Known keys (:data:`METADATA_KEYS`) and any further plain-data keys.
    source : str, optional
        Where the run came from (a file path), named in error messages; not part of
        the run's value (ignored by ``==``).

    Raises
    ------
    RunFormatError
        For arrays of the wrong shape or length, no signal at all, or bad metadata.

    Examples
    --------
    >>> run = Run([0.0, 0.001, 0.002], displacement=[1e-3, 0.9e-3, 0.7e-3],
    ...           metadata={"load_N": 0.31, "natural_frequency_Hz": 32.6})
    >>> run.n_samples, run.metadata["load_N"]
    (3, 0.31)
    """

    time: NDArray
    displacement: NDArray | None = None
    velocity: NDArray | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)
    source: str | None = None

    def __post_init__(self) -> None:
        where = self.source
        time = _signal(TIME, self.time, where)
        disp = _signal(DISPLACEMENT, self.displacement, where)
        vel = _signal(VELOCITY, self.velocity, where)
        if disp is None and vel is None:
            raise RunFormatError(
                f"a run needs a {DISPLACEMENT!r} or a {VELOCITY!r} signal; got neither", where
            )
        for name, array in ((DISPLACEMENT, disp), (VELOCITY, vel)):
            if array is not None and array.shape != time.shape:
                raise RunFormatError(
                    f"field {name!r} has {array.size} samples but {TIME!r} has {time.size}; "
                    "expected one value per time stamp",
                    where,
                )
        meta = MappingProxyType(check_metadata(self.metadata, where))
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "displacement", disp)
        object.__setattr__(self, "velocity", vel)
        object.__setattr__(self, "metadata", meta)

    # -- value semantics ----------------------------------------------------------
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Run):
            return NotImplemented

        def same(a: NDArray | None, b: NDArray | None) -> bool:
            if a is None or b is None:
                return a is None and b is None
            return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))

        return (
            same(self.time, other.time)
            and same(self.displacement, other.displacement)
            and same(self.velocity, other.velocity)
            and dict(self.metadata) == dict(other.metadata)
        )

    __hash__ = None  # type: ignore[assignment]

    # -- derived quantities -------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.time.size)

    @property
    def signals(self) -> dict[str, NDArray]:
        """The present signals by canonical column name, time first."""
        out = {TIME: self.time}
        if self.displacement is not None:
            out[DISPLACEMENT] = self.displacement
        if self.velocity is not None:
            out[VELOCITY] = self.velocity
        return out

    @property
    def length_unit(self) -> str:
        """``"m"`` (the default), ``"rad"`` (angles) or ``"arbitrary"`` (unknown)."""
        return self.metadata.get("length_unit") or "m"

    @property
    def sample_rate_Hz(self) -> float:
        """Sample rate from the time stamps, 1/median(Δt) [Hz].

        Raises
        ------
        RecordingError
            With fewer than two samples or a non-positive median step.
        """
        if self.time.size < 2:
            raise RecordingError(f"{TIME!r}: a sample rate needs at least two samples", self.source)
        step = sample_step(self.time)
        if not step > 0.0:
            raise RecordingError(
                f"{TIME!r}: the median time step is {step!r}; expected a positive step",
                self.source,
            )
        return 1.0 / step

    def with_metadata(self, **updates: Any) -> Run:
        """A copy of the run with metadata keys added or replaced (checked again)."""
        return Run(
            self.time,
            self.displacement,
            self.velocity,
            {**self.metadata, **updates},
            source=self.source,
        )

    def rig(self, natural_frequency_Hz: float | None = None) -> Rig | None:
        """The rig of this run, or ``None`` when the natural frequency is unknown.

        Parameters
        ----------
        natural_frequency_Hz : float, optional
            Natural frequency f [Hz] to use instead of the metadata's (for instance
            one measured from the recording).

        Returns
        -------
        Rig or None
            ``Rig(f, mass_kg, load_N)`` from the metadata. When the load is given
            but the frequency is not, f is measured from the recording
            (:func:`bayestribo.signal.frequency.oscillation_frequency`) with a
            :class:`~bayestribo.errors.MetadataWarning`. With
            ``length_unit`` ``"arbitrary"`` or ``"rad"`` the mass and load are left out, so that the
            rig's scaling uses one signal unit as length scale (N/k in metres would
            not match a signal in another unit).
        """
        f = natural_frequency_Hz
        if f is None:
            f = self.metadata.get("natural_frequency_Hz")
        measured = f is None
        if f is None:
            load = self.metadata.get("load_N")
            if load is None or not load > 0 or self.length_unit != "m":
                return None
            # Without f the stiffness k = m(2πf)² is unknown, so μ_k = x_c k/N could
            # not be formed: take f from the recording and say so, never drop the load.
            f = oscillation_frequency(self.time, self.displacement, self.velocity)
            if f is None:
                raise RunFormatError(
                    f"load_N = {float(load):g} is given but natural_frequency_Hz is not, and "
                    "no two full cycles were found to measure it: friction as μ_k needs the "
                    "stiffness k = m(2πf)²; give natural_frequency_Hz (--frequency)",
                    self.source,
                )
            # the stiffness takes the natural frequency the energy decay measures from
            # the turning times (signal/decay.py), not this estimate: said as such
            warnings.warn(
                "natural_frequency_Hz is not given: the stiffness k = m(2πf)² uses the "
                "natural frequency measured from the recording's turning times (about "
                f"{f:.4g} Hz; give natural_frequency_Hz, --frequency, to use a nominal value)",
                MetadataWarning,
                stacklevel=2,
            )
        try:
            if self.length_unit != "m":  # N/k in metres would not match the signal
                return Rig(natural_frequency_Hz=f, frequency_measured=measured)
            return Rig(
                natural_frequency_Hz=f,
                mass_kg=self.metadata.get("mass_kg"),
                load_N=self.metadata.get("load_N"),
                frequency_measured=measured,
            )
        except ValueError as exc:
            raise RecordingError(str(exc), self.source) from None

    def scaling(self, natural_frequency_Hz: float | None = None) -> Scaling:
        """The dimensionless scaling of this run (see :meth:`Rig.scaling`).

        Raises
        ------
        RecordingError
            If the natural frequency is neither in the metadata nor given.
        """
        rig = self.rig(natural_frequency_Hz)
        if rig is None:
            raise RecordingError(
                "metadata 'natural_frequency_Hz' is unknown; the scaling needs it "
                "(give it, or measure it from the recording)",
                self.source,
            )
        return rig.scaling()
