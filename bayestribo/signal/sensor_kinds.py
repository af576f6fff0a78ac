"""Kinds of sensor, each with the gain uncertainty to assume when a run states none.

A friction is a length (μ_k N/k) and sees the sensor's gain whole, so the fit draws the
gain's relative standard uncertainty into every reported length
(:mod:`bayestribo.signal.sensor`). A run's sidecar states it (``gain_uncertainty``);
where it does not, the sidecar's ``sensor_kind`` names the kind of sensor and the fit
takes that kind's typical calibration uncertainty, and says so. Without either, it
takes :data:`UNKNOWN` (1 %) and asks for one.

The built-in kinds and their defaults (one relative standard uncertainty of the
amplitude's gain; a calibrated sensor's certificate is better, state it):

=====================  =====  =======================================================
kind                   σ_g    basis
=====================  =====  =======================================================
``laser_vibrometer``   1 %    decoder amplitude accuracy of interferometric
                              vibrometers, ±1 % of reading
``motion_sensor``      2 %    ultrasonic motion sensors (teaching labs): the speed
                              of sound moves 0.17 %/°C; ±1 % of the distance
``encoder``            0.1 %  an encoder's counts per turn are exact; mounting and
                              eccentricity of the disc remain
``video``              2 %    video tracking scaled from a ruler in the frame:
                              the ruler's reading and perspective
``accelerometer``      5 %    nominal sensitivity tolerance of piezoelectric and MEMS
                              accelerometers without their own calibration
``smartphone``         3 %    scale-factor error of phone MEMS gyroscopes and
                              accelerometers
``seismometer``        5 %    a moving-coil sensor's nominal generator constant
``displacement_probe`` 2 %    eddy-current, capacitive and LVDT probes: sensitivity
                              and linearity over the range, on a target not of
                              their calibration's material
=====================  =====  =======================================================

A displacement and a velocity channel share one gain error except for a laser
vibrometer, whose two decoders are calibrated apart (``independent_channels``).

A lab registers its own kind with :func:`register_sensor_kind`; the sidecar key and
the fit take it from then on.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

__all__ = [
    "UNKNOWN",
    "SensorKind",
    "get_sensor_kind",
    "register_sensor_kind",
    "sensor_kind_table",
]


@dataclass(frozen=True)
class SensorKind:
    """A kind of sensor and the gain uncertainty assumed for it.

    Attributes
    ----------
    name : str
        The name a sidecar gives (``sensor_kind``), lower case with underscores.
    title : str
        The kind in words, for the output ("a laser vibrometer").
    gain_uncertainty : float
        Relative standard uncertainty of the gain assumed where a run states none [-].
    basis : str
        Where that number comes from, one line.
    independent_channels : bool
        True where a displacement and a velocity channel are calibrated apart (a
        vibrometer's two decoders): their gain errors are independent. False where
        both come from one transducer (a velocity the software differentiates from
        the position, or both integrated from an acceleration): one gain error for
        both.
    """

    name: str
    title: str
    gain_uncertainty: float
    basis: str
    independent_channels: bool = False

    def __post_init__(self) -> None:
        plain = self.name.replace("_", "")
        if not plain or not plain.isalnum() or self.name.lower() != self.name:
            raise ValueError(
                f"name: expected lower-case letters, digits and underscores, got {self.name!r}"
            )
        if not 0.0 <= self.gain_uncertainty <= 0.5:
            raise ValueError(
                f"gain_uncertainty: expected a relative uncertainty in [0, 0.5], got "
                f"{self.gain_uncertainty!r}"
            )


#: The kind assumed where a run names none: 1 %, the calibration accuracy of laser
#: vibrometers and teaching-lab motion sensors.
UNKNOWN = SensorKind(
    "unknown",
    "a sensor of unstated kind",
    0.01,
    "1 %, the calibration accuracy of laser vibrometers and teaching-lab motion sensors",
)

_KINDS: dict[str, SensorKind] = {}


def register_sensor_kind(kind: SensorKind, *, replace: bool = False) -> SensorKind:
    """Register a kind of sensor under its name.

    Parameters
    ----------
    kind : SensorKind
        The kind.
    replace : bool
        Replace a kind of the same name (otherwise that is an error).

    Returns
    -------
    SensorKind
        ``kind``.

    Raises
    ------
    ValueError
        If the name is taken and ``replace`` is false.
    """
    if not isinstance(kind, SensorKind):
        raise TypeError(f"kind: expected a SensorKind, got {type(kind).__name__}")
    if kind.name in _KINDS and not replace:
        raise ValueError(f"sensor kind {kind.name!r} is registered already (replace=True)")
    _KINDS[kind.name] = kind
    return kind


def sensor_kind_table() -> Mapping[str, SensorKind]:
    """The registered kinds by name (read-only)."""
    return MappingProxyType(dict(_KINDS))


def get_sensor_kind(name: str | None) -> SensorKind:
    """The kind of sensor registered as ``name``; :data:`UNKNOWN` for None.

    Raises
    ------
    ValueError
        If ``name`` is not registered: the message lists the kinds and the nearest.
    """
    if name is None:
        return UNKNOWN
    if not isinstance(name, str):
        raise ValueError(f"sensor_kind: expected a name, got {name!r}")
    key = name.strip().lower().replace("-", "_").replace(" ", "_")
    if key in _KINDS:
        return _KINDS[key]
    if key == UNKNOWN.name:
        return UNKNOWN
    near = difflib.get_close_matches(key, list(_KINDS), n=1)
    hint = f"; did you mean {near[0]!r}?" if near else ""
    raise ValueError(
        f"sensor_kind: expected one of {', '.join(sorted(_KINDS))} or 'unknown', got {name!r}{hint}"
    )


for _kind in (
    SensorKind(
        "laser_vibrometer",
        "a laser vibrometer",
        0.01,
        "decoder amplitude accuracy of interferometric vibrometers, ±1 % of reading",
        independent_channels=True,
    ),
    SensorKind(
        "motion_sensor",
        "an ultrasonic motion sensor",
        0.02,
        "the speed of sound moves 0.17 %/°C; ±1 % of the distance",
    ),
    SensorKind(
        "encoder",
        "an encoder",
        0.001,
        "an encoder's counts per turn are exact; the disc's mounting and eccentricity remain",
    ),
    SensorKind(
        "video",
        "video tracking",
        0.02,
        "the scale from a ruler in the frame: its reading and the perspective",
    ),
    SensorKind(
        "accelerometer",
        "an accelerometer",
        0.05,
        "nominal sensitivity tolerance of accelerometers without their own calibration",
    ),
    SensorKind(
        "smartphone",
        "a smartphone's motion sensors",
        0.03,
        "scale-factor error of phone MEMS gyroscopes and accelerometers",
    ),
    SensorKind(
        "seismometer",
        "a seismometer",
        0.05,
        "a moving-coil sensor's nominal generator constant",
    ),
    SensorKind(
        "displacement_probe",
        "a displacement probe",
        0.02,
        "eddy-current, capacitive and LVDT probes: sensitivity and linearity over the range",
    ),
):
    register_sensor_kind(_kind)
del _kind
