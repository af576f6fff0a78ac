"""A length recorded on a pendulum read as its angle: θ = arcsin((x - c)/r).

A video-tracked bob, or a laser or a probe on a pendulum's arm, records ``x = r sin θ``
(plus the sensor's offset c), r the distance from the pivot to the point recorded. No
restoring force of x alone is a pendulum's, so the run is read as the angle itself, in
radians, and fitted with the pendulum's restoring force (``restoring`` ``pendulum``,
unless the metadata name another: a torsion pendulum read by a laser is ``linear`` in
θ). The metadata key ``pendulum_radius_m`` (``--pendulum-radius``) asks for it:

* a number: r [m] (in the displacement's unit when ``length_unit`` is ``arbitrary``);
* ``"simple"``: a simple pendulum's bob, r = g/ω₀² (g = 9.80665 m/s², ω₀ the small
  swings' angular frequency measured from the turning times together with r,
  :func:`bayestribo.signal.pendulum_arm.simple_radius`); an assumption, said in the
  output (a bob of finite size, a heavy rod, a local g up to 0.3 % off the standard
  one move r off its length, and the friction angle by as much).

The centre c (x at θ = 0) is the equilibrium of the displacement's turning points
(:func:`bayestribo.signal.peaks.find_peaks`); the velocity, where recorded, becomes
θ' = v/(r cos θ). The angle's noise is the length's over r cos θ: it grows with the
swing (×1.15 at 30°, ×2 at 60°), and the fit takes the noise measured at rest (θ ≈ 0)
for every sample; the output says by how much it grows (how the intervals fare by
release angle: ``benchmarks/README.md``, ``pendulum_arm.json``). The run's metadata
get ``length_unit`` ``"rad"`` and the record ``pendulum_arm`` (radius, its source,
the centre, the largest angle), which also marks the run as read so: reading it again
changes nothing. Friction is then an angle (a torque with the sidecar's
``inertia_kg_m2``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bayestribo.errors import RecordingError, RunFormatError
from bayestribo.io.run import Run

__all__ = ["ARM", "RADIUS", "SIMPLE", "as_angle", "describe"]

#: The metadata key asking for the conversion, and its value for a simple pendulum.
RADIUS = "pendulum_radius_m"
SIMPLE = "simple"
#: The metadata key recording the conversion (written by the package).
ARM = "pendulum_arm"

#: Resolution keys of the length channels: a step of x is a step of θ of step/r at the
#: centre (the finest; it grows as 1/cos θ with the swing).
_RESOLUTIONS = ("displacement_resolution_m", "velocity_resolution_m_per_s")
#: Range keys of the length channels, taken to the angle they reach (left out when the
#: arm cannot reach them).
_RANGES = ("displacement_range_m", "velocity_range_m_per_s")


def as_angle(run: Run, where: str | None = None) -> Run:
    """The run with its displacement read as a pendulum's angle, if its metadata ask.

    Parameters
    ----------
    run : Run
        A run whose metadata may hold ``pendulum_radius_m``.
    where : str, optional
        Where it came from, for the messages (default: the run's source).

    Returns
    -------
    Run
        The run itself when its metadata hold no ``pendulum_radius_m`` or it was read as
        an angle already (``pendulum_arm``); else the angle θ [rad] as its displacement,
        θ' [rad/s] as its velocity, ``length_unit`` ``"rad"``, ``restoring``
        ``pendulum`` unless given, and the ``pendulum_arm`` record.

    Raises
    ------
    RunFormatError
        For a run in radians already, a ``simple`` radius on a run whose unit is not
        metres, or a run with no displacement.
    RecordingError
        When the swing's centre or (``simple``) the period cannot be measured, or the
        swing reaches the radius (no angle gives it: a radius too short).
    """
    meta = dict(run.metadata)
    given = meta.get(RADIUS)
    where = where or run.source
    if given is None or ARM in meta:
        return run
    if run.length_unit == "rad":
        raise RunFormatError(
            f"metadata {RADIUS!r} reads a length as a pendulum's angle, but the run is in "
            "radians already (length_unit 'rad'); leave one out",
            where,
        )
    if run.displacement is None:
        raise RunFormatError(
            f"metadata {RADIUS!r}: the angle θ = arcsin(x/r) is read from the displacement, "
            "and the run has none",
            where,
        )
    if given == SIMPLE and run.length_unit != "m":
        raise RunFormatError(
            f"metadata {RADIUS!r} {SIMPLE!r} takes r = g/ω₀² in metres, but the run's unit is "
            f"{run.length_unit!r}; give the radius in the displacement's unit instead",
            where,
        )
    from bayestribo.signal.peaks import find_peaks

    t = np.asarray(run.time, dtype=float)
    x = np.asarray(run.displacement, dtype=float)
    try:
        peaks = find_peaks(t, x, kind="displacement", offset="constant")
    except RecordingError as exc:
        raise RecordingError(
            f"{RADIUS}: the centre of the pendulum's swing (x at θ = 0) is measured from the "
            f"displacement's turning points, and {exc.message}",
            where,
        ) from None
    centre = float(peaks.offset)
    record: dict[str, Any] = {"centre_m": centre}
    if given == SIMPLE:
        from bayestribo.signal.pendulum_arm import GRAVITY, simple_radius

        found = simple_radius(peaks.t, peaks.value)
        if found is None:
            raise RecordingError(
                f"{RADIUS} {SIMPLE!r}: the turning times give no simple pendulum's length "
                "r = g/ω₀² (too few turning points, or a swing as large as that length): "
                "give the radius in metres",
                where,
            )
        radius, frequency = found
        record.update(
            radius_m=radius,
            source=(
                f"a simple pendulum: r = g/ω₀² with g = {GRAVITY} m/s² and ω₀/2π = "
                f"{frequency:.6g} Hz from the turning times (an assumption: a bob of finite "
                "size, a heavy rod or the local g move r, and the friction angle with it)"
            ),
            small_swing_frequency_Hz=frequency,
        )
    else:
        radius = float(given)
        record.update(radius_m=radius, source="given")
    s = (x - centre) / radius
    beyond = np.flatnonzero(~(np.abs(s) < 1.0))
    if beyond.size:
        i = int(beyond[0])
        raise RecordingError(
            f"{RADIUS}: the displacement reaches {x[i] - centre:.6g} from the swing's centre "
            f"at t = {t[i]:.6g} s (sample {i}), at or beyond the radius {radius:.6g}: no angle "
            "x = r sin θ gives it; the radius is the distance from the pivot to the point "
            "recorded",
            where,
        )
    theta = np.arcsin(s)
    cos = np.sqrt((1.0 - s) * (1.0 + s))
    omega = None if run.velocity is None else np.asarray(run.velocity, dtype=float) / (radius * cos)
    record["largest_angle_deg"] = float(np.degrees(np.max(np.abs(theta))))
    meta["length_unit"] = "rad"
    meta.setdefault("restoring", "pendulum")
    meta[ARM] = record
    for key in _RESOLUTIONS:
        if meta.get(key) is not None:
            meta[key] = float(meta[key]) / radius
    for key in _RANGES:
        reach = meta.pop(key, None)
        if key.startswith("displacement") and reach is not None and reach < radius:
            meta[key] = math.asin(float(reach) / radius)  # θ' = v/(r cos θ) has no one range
    return Run(t, theta, omega, meta, source=run.source)


def describe(record: dict[str, Any]) -> str:
    """One line for the output: how the length was read as the angle (``pendulum_arm``)."""
    source = record.get("source", "given")
    return (
        f"θ = arcsin((x - c)/r) with r = {record['radius_m']:.6g}"
        + (" (given)" if source == "given" else f", {source}")
        + f", c = {record['centre_m']:.6g} (the swing's centre); largest angle "
        f"{record['largest_angle_deg']:.3g}°; the angle's noise grows as 1/cos θ, "
        f"{1.0 / math.cos(math.radians(record['largest_angle_deg'])):.2f}× its value at "
        "rest there, which the fit takes for every sample"
    )
