"""Data checks of a run: what makes a recording unusable, with a clear message.

:func:`validate_run` checks, in this order, and raises
:class:`~bayestribo.errors.RecordingError` naming the file, the field and what was
expected at the first problem found:

1. every sample of every field is finite (no NaN, no infinity);
2. there are at least ``min_samples`` samples;
3. the time stamps strictly increase and are regular (each step within
   ``time_rtol`` of the median step), jittered about a regular grid, or on a regular
   grid with samples missing that the analysis can bridge (each gap at most a tenth
   of a period, :func:`bayestribo._clock.on_grid`; a longer one is named with its
   samples and times); a declared ``sample_rate_Hz`` agrees with them, and the
   sampling resolves a declared natural frequency (Nyquist);
4. no signal is clipped: none reaches a declared sensor range
   (``displacement_range_m``, ``velocity_range_m_per_s``), and none is cut flat
   through the record: a flat top is its maximum or minimum value held for
   ``clip_samples`` samples or more and for more than twice what a smooth quantised
   extreme of its swing dwells there, away from the ends of the record, entered and
   left with the signal's slope (:func:`bayestribo.signal.clipping.hard_clips`: the
   rest before release and the rest after the stop touch the ends; the extreme of a
   coarsely quantised sinusoid dwells ``sqrt(2q/A)/π`` of a period and is entered by
   one step). Flat tops followed by at least :data:`CLIP_FREE_PERIODS` periods of
   record pass: the energy decay leaves the clipped cycles out and says so (level,
   cycles, times); otherwise the run is refused naming the level and the cycles;
5. with both signals, the displacement matches the time integral of the velocity
   (gain within a factor of two of 1): this catches a displacement in millimetres
   or micrometres read as metres, a velocity in mm/s, a time in ms, or a velocity
   of the wrong sign (:func:`bayestribo.signal.channels.check_channels`);
6. a run in metres moves as a rig does: its swing and frequency are plausible
   (:func:`bayestribo.signal.channels.check_plausible_motion`).

Nothing is repaired, clipped or dropped: a run either passes unchanged or fails. A
run whose clock restarts within the record is judged as the analysis will see it, on
one clock (:func:`on_one_clock`: continued where the signal goes on smoothly across
the restart, cut where it jumps, and said).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bayestribo._warnings import moved, warn
from bayestribo.errors import RecordingError
from bayestribo.io.run import DISPLACEMENT, TIME, VELOCITY, Run
from bayestribo.signal.channels import check_channels, check_plausible_motion
from bayestribo.signal.clipping import HardClip, hard_clips, quantum
from bayestribo.signal.period import dominant_period, sample_step

__all__ = [
    "CLIP_FREE_PERIODS",
    "CLIP_SAMPLES",
    "MIN_SAMPLES",
    "TIME_RTOL",
    "check_channels",
    "on_one_clock",
    "validate_run",
    "without_repeated_samples",
]

#: Moved to :mod:`bayestribo.signal.channels`: still importable from here, with a
#: DeprecationWarning.
__getattr__ = moved(
    __name__,
    "bayestribo.signal.channels",
    frozenset(
        {"ChannelConsistency", "MOTION_FRACTION", "UNIT_GAIN_TOLERANCE", "channel_consistency"}
    ),
)

#: Fewest samples accepted: a decay analysis needs several oscillation periods of
#: several samples each; 64 is a floor, not a guarantee that a run is long enough.
MIN_SAMPLES = 64

#: Largest relative deviation of a time step from the median step. A dropped or
#: doubled sample deviates by 100 %; time stamps printed with four significant digits
#: of the step deviate by at most 0.05 %, so 1 % separates the two with margin.
TIME_RTOL = 0.01

#: Fewest consecutive samples at an extreme value for a flat top (and more than twice
#: what a smooth quantised extreme of the signal's swing dwells there,
#: :func:`bayestribo.signal.clipping.expected_dwell`). A smooth peak repeats its exact
#: extreme rarely: the real recordings of a spring oscillator (3 decimals at 100 Hz and
#: 6 decimals at 1 kHz) repeat it at most 3 times.
CLIP_SAMPLES = 5
#: Periods of record after the last clipped cycle for the run to pass: the energy
#: decay leaves the clipped cycles out with a ClippingWarning
#: (:func:`bayestribo.signal.decay.energy_decay`) and needs three oscillations after
#: them.
CLIP_FREE_PERIODS = 4


def _fail(message: str, where: str | None) -> RecordingError:
    return RecordingError(message, where)


def _check_finite(run: Run, where: str | None) -> None:
    for name, values in run.signals.items():
        bad = ~np.isfinite(values)
        if bad.any():
            samples = np.flatnonzero(bad)
            first = int(samples[0])
            listed = ", ".join(str(int(i)) for i in samples[:10])
            more = ", ..." if samples.size > 10 else ""
            raise _fail(
                f"field {name!r}: {int(bad.sum())} sample(s) are NaN or infinite, the first "
                f"is sample {first} (counting from 0) with value {values[first]!r} (samples "
                f"{listed}{more}); expected finite numbers: a reading the instrument missed "
                "is a dropped "
                "sample, so delete its row from the file (a short gap it leaves is bridged, "
                "with a GapWarning), or cut the run",
                where,
            )


def _jittered(t: NDArray) -> bool:
    """Stamps that scatter about a regular grid (:mod:`bayestribo._clock`)."""
    from bayestribo._clock import clock

    return clock(t).regular


def _bridgeable(run: Run, where: str | None) -> bool:
    """Stamps on a regular grid with samples missing that the analysis bridges
    (:func:`bayestribo._clock.on_grid`); a gap it cannot bridge is refused here, naming
    its samples and times."""
    from bayestribo._clock import on_grid, timeline

    line = timeline(run.time)
    if not (line.on_grid and line.gaps):
        return False
    try:
        on_grid(run.time, run.displacement, run.velocity)
    except RecordingError as exc:
        raise _fail(exc.message, where) from None
    return True


def _check_restoring(run: Run, where: str | None) -> None:
    """A restoring force whose potential takes an angle (a pendulum's) needs the run in
    radians: its potential at a swing of 2 in another unit means nothing (``"auto"``
    chooses one the run's unit allows)."""
    from bayestribo.model.restoring import AUTO, get_restoring

    name = run.metadata.get("restoring")
    if name == AUTO:
        return
    restoring = get_restoring(name)
    if restoring.angle and run.length_unit != "rad":
        raise _fail(
            f"metadata 'restoring' is {restoring.name!r}, whose potential takes the angle in "
            f"radians, but the run's length unit is {run.length_unit!r}; expected angles "
            "(columns named angle_deg, angle_rad, ..., or length_unit 'rad')",
            where,
        )
    if restoring.angle and run.displacement is not None:
        swing = 0.5 * float(np.ptp(run.displacement))
        if swing >= math.pi:
            # beyond π a pendulum turns over: not a free decay's swing (its potential
            # raised ValueError from deep inside the fit)
            raise _fail(
                f"metadata 'restoring' is {restoring.name!r}, but the angle swings by "
                f"{swing:.3g} rad ({math.degrees(swing):.4g}°), beyond π, where a pendulum "
                "turns over; if the angles are in degrees, name the column angle_deg "
                "(--columns ... angle_deg)",
                where,
            )


def _check_time(run: Run, where: str | None, time_rtol: float) -> float:
    t = run.time
    step = np.diff(t)
    bad = np.flatnonzero(step <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        repeated = ""
        if step[i - 1] == 0.0:
            # a row written twice is read once (without_repeated_samples): this one's
            # values differ from the sample before
            same = int(np.count_nonzero(step == 0.0))
            repeated = (
                f" with other values than sample {i - 1} ({same} stamp"
                f"{'s' if same > 1 else ''} repeated so): two samples at one instant, of which the "
                "record cannot be told; expected one sample a time stamp (a logger's "
                "interleaved or resent rows: export the record again, or --window to a "
                "part without them)"
            )
        raise _fail(
            f"field {TIME!r} is not strictly increasing: sample {i} (t = {float(t[i])!r} s) "
            f"follows t = {float(t[i - 1])!r} s{repeated or '; expected increasing time stamps'}",
            where,
        )
    median = sample_step(t, step)  # remembered for the checks and the fit that follow
    # the largest deviation from the extremes of the steps (no array of deviations)
    largest = max(float(step.max()) - median, median - float(step.min())) / median
    if largest > time_rtol and not _jittered(t) and not _bridgeable(run, where):
        worst = int(np.argmax(np.abs(step - median)))
        raise _fail(
            f"field {TIME!r} is irregular: the step from sample {worst} to {worst + 1} is "
            f"{step[worst]!r} s but the median step is {median!r} s; expected regular "
            f"sampling (every step within {time_rtol:.0%} of the median; a missing sample "
            "or a restart of the clock gives this)",
            where,
        )
    rate = 1.0 / median
    declared = run.metadata.get("sample_rate_Hz")
    if declared is not None and abs(declared - rate) > time_rtol * rate:
        raise _fail(
            f"metadata 'sample_rate_Hz' is {declared!r} Hz but the time stamps give "
            f"{rate:.6g} Hz; expected them to agree within {time_rtol:.0%}",
            where,
        )
    f = run.metadata.get("natural_frequency_Hz")
    if f is not None and rate <= 2.0 * f:
        raise _fail(
            f"field {TIME!r}: sample rate {rate:.6g} Hz does not resolve the natural frequency "
            f"{f!r} Hz (metadata 'natural_frequency_Hz'); expected more than {2.0 * f:.6g} Hz "
            "(two samples per period)" + _time_unit_hint(rate, f),
            where,
        )
    return rate


def _time_unit_hint(rate: float, frequency: float) -> str:
    """For a sample rate too low for the stated frequency: the time unit that fixes it."""
    for factor, unit in ((1e-3, "ms"), (1e-6, "µs")):
        if 2.0 * frequency < rate / factor <= 1e9:
            return (
                f"; a time column in {unit} read as seconds gives this: "
                f"scale={{'time_s': {factor:g}}} (or name it time_{unit.replace('µ', 'u')})"
            )
    return ""


def _quantum(values: NDArray) -> float | None:
    """The smallest non-zero step of a signal (its quantisation step), or None."""
    step = quantum(values)
    return step if step > 0 else None


def _flat_top(values: NDArray, t: NDArray, length: int) -> list[HardClip]:
    """The extremes of ``values`` held flat as a cut is, not as a smooth quantised
    extreme dwells (:func:`bayestribo.signal.clipping.hard_clips`; runs of at least
    ``length`` samples)."""
    try:
        period = dominant_period(t, values)
    except RecordingError:
        return []
    return hard_clips(t, values, period, min_samples=length)


def _check_clipping(run: Run, where: str | None, clip_samples: int) -> None:
    ranges = {
        DISPLACEMENT: ("displacement_range_m", run.displacement),
        VELOCITY: ("velocity_range_m_per_s", run.velocity),
    }
    t = run.time
    for name, (key, values) in ranges.items():
        if values is None:
            continue
        limit = run.metadata.get(key)
        if limit is not None:
            over = np.flatnonzero(np.abs(values) >= limit)
            largest = float(np.max(np.abs(values)))
            if over.size and largest >= 10.0 * limit:
                # far beyond what the sensor can record: a unit, not a clip; the unit
                # checks name the reading that fixes it
                check_channels(run, where)
                check_plausible_motion(run, where)
                raise _fail(
                    f"field {name!r} reaches {largest:.6g}, {largest / limit:.3g} times the "
                    f"sensor range ±{limit!r} (metadata {key!r}): no sensor records beyond "
                    "its range, so the column's unit or the stated range is wrong; check the "
                    "unit in the column's name and the range",
                    where,
                )
            if over.size:
                i = int(over[0])
                raise _fail(
                    f"field {name!r} is clipped: {over.size} sample(s) reach the sensor range "
                    f"±{limit!r} (metadata {key!r}), the first is sample {i} with value "
                    f"{values[i]!r}; expected |{name}| < {limit!r} (choose a larger range on "
                    "the vibrometer or a smaller initial displacement)",
                    where,
                )
        for clip in _flat_top(values, t, clip_samples):
            _, last = clip.times(t)
            period = dominant_period(t, values)
            if float(t[-1]) - last >= CLIP_FREE_PERIODS * period:
                continue  # the analysis starts after the clipped cycles and says so
            raise _fail(
                f"{clip.describe(name, t)}; fewer than {CLIP_FREE_PERIODS} periods "
                f"({CLIP_FREE_PERIODS * period:.4g} s) follow the last clipped cycle, so the "
                "analysis cannot start after them; expected a signal inside the sensor range "
                "(record with a smaller initial displacement or a larger sensor range)",
                where,
            )


def validate_run(
    run: Run,
    *,
    where: str | None = None,
    min_samples: int = MIN_SAMPLES,
    time_rtol: float = TIME_RTOL,
    clip_samples: int = CLIP_SAMPLES,
) -> Run:
    """Check that a run's data can be analysed; return it unchanged.

    Parameters
    ----------
    run : Run
        The run to check.
    where : str, optional
        File or origin named in the messages; default ``run.source``.
    min_samples : int
        Fewest samples accepted (default :data:`MIN_SAMPLES`).
    time_rtol : float
        Largest relative deviation of a time step from the median step, and of a
        declared ``sample_rate_Hz`` from the measured one [-].
    clip_samples : int
        Fewest repeats of an extreme value that can count as a flat top.

    Returns
    -------
    Run
        The same run.

    Raises
    ------
    RecordingError
        At the first failed check (see the module documentation), naming the file,
        the field and what was expected.
    """
    where = where if where is not None else run.source
    _check_finite(run, where)
    if run.n_samples < min_samples:
        raise _fail(
            f"field {TIME!r}: {run.n_samples} sample(s); expected at least {min_samples} "
            "samples for a decay analysis",
            where,
        )
    given = run
    run = on_one_clock(run, say=False)  # the clock the analysis will see
    _check_time(run, where, time_rtol)
    _check_restoring(run, where)
    _check_clipping(run, where, clip_samples)
    check_channels(run, where)
    check_plausible_motion(run, where)
    return given


def without_repeated_samples(run: Run, *, say: bool = True) -> Run:
    """The run without the samples that repeat the one before exactly.

    A logger that writes a row twice gives a sample with the time stamp and every
    channel's value of the one before: it holds nothing the first does not, and each
    such sample is read once. A repeated time stamp with another value in any channel
    is left for :func:`validate_run` to refuse (two samples at one instant: which one
    is the record cannot be told).

    Parameters
    ----------
    run : Run
        The run as read.
    say : bool
        Warn how many samples were read once, and the first of them
        (:class:`~bayestribo.errors.ReadingWarning`).

    Returns
    -------
    Run
        ``run`` itself where no sample repeats the one before.
    """
    from bayestribo._stamps import stamp
    from bayestribo.errors import ReadingWarning

    t = np.asarray(run.time)
    same = np.diff(t) == 0.0
    if not same.any():
        return run
    channels = [c for c in (run.displacement, run.velocity) if c is not None]
    for c in channels:
        c = np.asarray(c)
        same &= (np.diff(c) == 0.0) | (np.isnan(c[1:]) & np.isnan(c[:-1]))
    if not same.any():
        return run
    repeats = np.flatnonzero(same) + 1
    if say:
        where = f"{run.source}: " if run.source else ""
        first = int(repeats[0])
        at = stamp(float(t[first]), float(t[-1] - t[0]), float(t[0]))
        warn(
            f"{where}{repeats.size} sample{'s' if repeats.size > 1 else ''} repeat the one "
            f"before exactly (the same time stamp and value in every channel: a row "
            f"written twice), the first sample {first} at t = {at}; each is read once",
            ReadingWarning,
        )
    keep = np.ones(t.size, dtype=bool)
    keep[repeats] = False
    return Run(
        t[keep],
        None if run.displacement is None else np.asarray(run.displacement)[keep],
        None if run.velocity is None else np.asarray(run.velocity)[keep],
        dict(run.metadata),
        source=run.source,
    )


def on_one_clock(run: Run, *, say: bool = True) -> Run:
    """The run on one clock when its time stamps restart within the record.

    A restart across which the signal goes on smoothly is continued (the stamps after
    it follow the one before by a sample step); at one across which the signal jumps,
    the run is cut and the samples from it on are left out
    (:mod:`bayestribo.signal.restarts`). Every check and analysis of the run then sees
    one clock; a run whose stamps never fall is returned as it is.

    Parameters
    ----------
    run : Run
        The run as recorded.
    say : bool
        Warn what was done: :class:`~bayestribo.errors.ClockRestartWarning` for a
        continued clock, :class:`~bayestribo.signal.coverage.ShortAnalysisWarning` (exit
        status 1) when samples were left out.

    Returns
    -------
    Run
    """
    from bayestribo.errors import ClockRestartWarning
    from bayestribo.signal.coverage import ShortAnalysisWarning
    from bayestribo.signal.restarts import continue_clock

    t, x, v, restarted, cut = continue_clock(run.time, run.displacement, run.velocity)
    if not restarted:
        return run
    where = f"{run.source}: " if run.source else ""
    said = "; ".join(r.describe() for r in restarted)
    if say and cut is not None:
        warn(
            f"{where}{said}: only samples 0 to {cut - 1} (the part holding the release) "
            f"are analysed and samples {cut} to {run.n_samples - 1} were left out (save "
            "them as a record of their own to fit them)",
            ShortAnalysisWarning,
        )
    elif say:
        warn(
            f"{where}{said} (this assumes no sample was lost at the restart; times after "
            "it, --window included, are on the continued clock)",
            ClockRestartWarning,
        )
    return Run(t, x, v, dict(run.metadata), source=run.source)
