"""A run recorded through a sensor's high-pass, read as the motion before it.

The metadata key ``sensor_high_pass`` (``--sensor-high-pass HZ[:ORDER[:DAMPING]]``)
declares the analog high-pass every recorded channel went through (an AC-coupled
channel, a geophone, a piezoelectric sensor): ``{"cutoff_Hz": f_c, "order": 1}``, or
``{"cutoff_Hz": f_c, "order": 2, "damping": ζ_g}`` for a geophone's two poles. The run
is read as the motion at the filter's input (:func:`bayestribo.signal.high_pass.
undo_high_pass`): each channel through the filter's inverse, the drift the inverse
leaves (the filter's state at the first sample, the digitiser's offset, the noise's
random walk) measured at rest and taken off (a velocity is zero at rest, a displacement
constant). The run's metadata get the record ``high_pass_undone`` (the declaration,
the channels undone, the rests the drift was measured in), which also marks the run as
read so: reading it again changes nothing, and the fit's output and provenance say it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io.run import Run
from bayestribo.signal.high_pass import (
    HIGH_PASS_KEY,
    check_high_pass,
    noise_record,
    option_text,
    undo_high_pass,
)

__all__ = ["HIGH_PASS_KEY", "UNDONE", "describe", "undone"]

#: The metadata key recording the inverse (written by the package).
UNDONE = "high_pass_undone"


def _rests(t: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The rest before the release and after the stop of a velocity (or None where the
    record holds no motion the analysis finds)."""
    from bayestribo.signal.motion import motion_span
    from bayestribo.signal.period import dominant_period

    try:
        period = dominant_period(t, velocity)
        span = motion_span(t, velocity, period, velocity_alone=True)
    except BayestriboError:
        return None
    index = np.arange(t.size)
    release = -1 if span.release_index is None else span.release_index
    stop = t.size if span.stop_index is None else span.stop_index
    before = span.quiet & (index <= release)
    after = span.quiet & (index > stop)
    return before, after


def undone(run: Run, where: str | None = None) -> Run:
    """The run before its sensor's high-pass, if its metadata declare one.

    Parameters
    ----------
    run : Run
        A run whose metadata may hold ``sensor_high_pass``.
    where : str, optional
        Where it came from, for the messages (default: the run's source).

    Returns
    -------
    Run
        The run itself when its metadata declare none or it was undone already
        (``high_pass_undone``); else the run with each recorded channel at the
        filter's input and the ``high_pass_undone`` record.

    Raises
    ------
    RunFormatError
        For a declaration that is not valid.
    """
    meta = dict(run.metadata)
    given = meta.get(HIGH_PASS_KEY)
    if given is None or UNDONE in meta:
        return run
    where = where or run.source
    try:
        spec = check_high_pass(given)
    except ValueError as exc:
        raise RunFormatError(f"metadata {HIGH_PASS_KEY!r}: {exc}", where) from None
    t = np.asarray(run.time, dtype=float)
    x = None if run.displacement is None else np.asarray(run.displacement, dtype=float)
    v = None if run.velocity is None else np.asarray(run.velocity, dtype=float)
    # the rests, from the velocity through the inverse (the recorded one relaxes there)
    first = undo_high_pass(t, v, spec, zero_at_rest=True) if v is not None else None
    if first is None and x is not None:
        first = np.gradient(undo_high_pass(t, x, spec, zero_at_rest=False), t)
    rests = None if first is None else _rests(t, first)
    channels = []
    noise = None
    if v is not None:
        if x is None and rests is not None:
            # a velocity alone: the increments' noise drawn through the inverse
            noise = noise_record(t, v, spec, rests)
        v = undo_high_pass(t, v, spec, zero_at_rest=True, rests=rests)
        channels.append("velocity")
    if x is not None:
        x = undo_high_pass(t, x, spec, zero_at_rest=False, rests=rests)
        channels.append("displacement")
    record: dict[str, Any] = {**spec, "channels": channels}
    if rests is None:
        record["rests"] = "none found: the filter's state at the first sample taken as zero"
    else:
        record["rests"] = (
            f"{int(rests[0].sum())} samples before the release, {int(rests[1].sum())} "
            "after the stop"
        )
    if noise is not None:
        record["noise"] = noise
    meta[HIGH_PASS_KEY] = spec
    meta[UNDONE] = record
    return Run(t, x, v, meta, source=run.source)


def describe(record: dict[str, Any]) -> str:
    """One line for the output: the high-pass undone (``high_pass_undone``)."""
    spec = {k: record[k] for k in ("cutoff_Hz", "order", "damping") if k in record}
    poles = "one pole" if spec["order"] == 1 else f"two poles, damping {spec['damping']:.3g}"
    return (
        f"the sensor's high-pass at {spec['cutoff_Hz']:.4g} Hz ({poles}; --sensor-high-pass "
        f"{option_text(spec)}) undone on the {' and '.join(record['channels'])}; its drift "
        f"measured at rest ({record['rests']})"
    )
