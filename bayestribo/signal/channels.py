"""Do a run's channels and units describe one motion a rig makes?

* :func:`channel_consistency` compares the displacement with the time integral of
  the velocity: their gain ratio, the delay of one against the other (with jackknife
  standard errors over the cycles) and their correlation over the motion.
* :func:`check_channels` refuses channels that are swapped, of different motions, or
  whose gains are a factor of :data:`UNIT_GAIN_TOLERANCE` or more apart (a unit
  mistake), naming the units and scale factors that would fix them.
* :func:`check_plausible_motion` refuses a run in metres whose swing and frequency no
  rig makes (:mod:`bayestribo.model.plausible`), naming the likely units.

:func:`bayestribo.io.validation.validate_run` applies both checks to every file read;
:func:`bayestribo.inference.calibration.calibrate_channels` corrects a velocity whose
gain or delay is off before a fit. The windows of the comparison and the frequency of
a unit hint come from the record's period
(:func:`~bayestribo.signal.period.dominant_period`).

A run is any object with ``time`` [s], ``displacement`` and ``velocity`` (arrays or
``None``), ``signals`` (by canonical column name) and ``length_unit``: a
:class:`bayestribo.io.run.Run`.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.period import MIN_PERIOD_SAMPLES, dominant_period, sample_step

__all__ = [
    "MOTION_FRACTION",
    "UNIT_GAIN_TOLERANCE",
    "ChannelConsistency",
    "channel_consistency",
    "check_channels",
    "check_plausible_motion",
]

#: The canonical column names (:data:`bayestribo.io.run.COLUMNS`) the messages name.
TIME, DISPLACEMENT, VELOCITY = "time_s", "displacement_m", "velocity_m_per_s"


class Recording(Protocol):
    """What the checks read of a run (:class:`bayestribo.io.run.Run` has it)."""

    @property
    def time(self) -> NDArray: ...

    @property
    def displacement(self) -> NDArray | None: ...

    @property
    def velocity(self) -> NDArray | None: ...

    @property
    def signals(self) -> Mapping[str, NDArray | None]: ...

    @property
    def length_unit(self) -> str: ...


#: Accepted range of the gain between displacement and the integral of velocity.
#: Trapezoid integration with 10 samples per period errs by about 3 %, two sensor
#: channels may disagree by some per cent; a unit mistake is a factor of 1000.
UNIT_GAIN_TOLERANCE = 2.0

#: Least correlation of the displacement's changes with the velocity's integral over the
#: same short windows: below it the two columns do not describe one motion.
_UNIT_MIN_CORRELATION = 0.9
#: Windows whose velocity integral exceeds this fraction of its largest are in motion,
#: where the correlation of the channels is measured (:func:`channel_consistency`).
MOTION_FRACTION = 0.01
#: Steps of a quantised displacement a window's motion must exceed to count there.
QUANTISED_WINDOW_STEPS = 1.5
#: Anticorrelation beyond which, with a large negative gain, the columns look swapped
#: (rests at the initial displacement and after the stop weaken it below 1).
_SWAP_MIN_ANTICORRELATION = 0.3


#: Factors a time column in a common unit needs to reach s (ms, µs; minutes, hours, and
#: days: a spreadsheet's date-and-time serial counts days).
_TIME_FACTORS = (1.0, 1e-3, 1e-6, 60.0, 3600.0, 86400.0)
#: Factors a length column needs to reach m or m/s: below 1 a column in mm, cm or µm
#: read as metres; above 1 a column in metres read as mm, cm or µm (a column of metres
#: labelled mm is scaled by 1e-3 on reading and needs 1000 more); 10 and 0.1 for cm and
#: mm mistaken for each other. Tried in this order (the common mistakes first).
_LENGTH_FACTORS = (1.0, 1e-3, 1e-2, 1e-6, 1e3, 1e2, 1e6, 1e-1, 1e1)
_UNIT_WORDS = {
    TIME: {
        1e-3: "time in ms",
        1e-6: "time in µs",
        60.0: "time in minutes",
        3600.0: "time in hours",
        86400.0: "time in days (a spreadsheet's date and time serial)",
    },
    DISPLACEMENT: {
        1e-2: "displacement in cm",
        1e-3: "displacement in mm",
        1e-6: "displacement in µm",
    },
    VELOCITY: {1e-2: "velocity in cm/s", 1e-3: "velocity in mm/s", 1e-6: "velocity in µm/s"},
}
#: The unit a column read too small (factor above 1) or too large (0.1) holds, and the
#: unit its label wrongly states.
_MISLABELLED = {
    1e1: ("cm", "mm"),
    1e2: ("m", "cm"),
    1e3: ("m", "mm"),
    1e6: ("m", "µm"),
    1e-1: ("mm", "cm"),
}
#: Least friction coefficient of a loaded sliding contact [-] (the best-lubricated
#: ones): a decay whose swing and number of half-cycles under the stated load allow
#: less friction than this is read in the wrong length unit. Used only to choose
#: between two readings of channels that disagree, never to refuse a run.
_MU_FLOOR = 1e-3
#: Typical swing of a free-decay rig [m]: of several readings a rig could make, the
#: one whose swing is nearest to it (in ratio) is named first.
_TYPICAL_SWING = 1e-3
#: The sidecar keys that decide between readings, per channel.
_SENSOR_KEYS = {
    DISPLACEMENT: ("displacement_resolution_m", "displacement_range_m"),
    VELOCITY: ("velocity_resolution_m_per_s", "velocity_range_m_per_s"),
}


def _words(name: str, factor: float) -> str:
    """What a column that needs ``factor`` to reach s, m or m/s holds, in words."""
    known = _UNIT_WORDS[name].get(factor)
    if known is not None:
        return known
    word = {TIME: "time", DISPLACEMENT: "displacement", VELOCITY: "velocity"}[name]
    how = f"{factor:.0f} times too small" if factor > 1 else f"{1 / factor:.0f} times too large"
    held_label = _MISLABELLED.get(factor)
    if held_label is None or name == TIME:
        return f"{word} read {how}"
    held, label = held_label
    per = "/s" if name == VELOCITY else ""
    held = "metres" if held == "m" and not per else held + per
    return f"{word} read {how} ({held} in a column labelled {label}{per})"


class _Motion(NamedTuple):
    """A run's motion as read (a run in metres), for the unit hints (a tuple whose
    first two items are the frequency and the swing).

    Attributes
    ----------
    frequency_Hz : float
        Dominant frequency as read [Hz].
    swing : float
        Half the peak-to-peak displacement (or of the velocity, over 2πf) [m as read].
    peak_velocity : float or None
        Largest |velocity| [m/s as read], None without a velocity.
    half_cycles : int
        Half-cycles whose swing is at least a tenth of the largest (:func:`_half_cycles`).
    """

    frequency_Hz: float
    swing: float
    peak_velocity: float | None
    half_cycles: int


def _half_cycles(signal: NDArray) -> int:
    """Lobes of ``signal`` beyond ±10 % of its half range about its mid-range: the
    half-cycles of a decay whose swing is at least a tenth of its largest (noise at rest
    does not cross the band, so it is not counted)."""
    low, high = float(np.min(signal)), float(np.max(signal))
    mid, band = 0.5 * (low + high), 0.05 * (high - low)
    side = np.zeros(signal.size, dtype=np.int8)
    side[signal > mid + band] = 1
    side[signal < mid - band] = -1
    side = side[side != 0]
    if not side.size:
        return 0
    return int(np.count_nonzero(side[1:] != side[:-1])) + 1


def _motion(run: Recording) -> _Motion | None:
    """Frequency, swing, peak velocity and half-cycles of a run's motion as read, for
    :func:`_unit_hint` and :func:`check_plausible_motion`; None for a run not in metres
    or without a period."""
    signal = run.displacement if run.displacement is not None else run.velocity
    if signal is None or run.length_unit != "m":
        return None
    try:
        period = dominant_period(run.time, signal)
    except RecordingError:
        return None
    if not period > 0:
        return None
    frequency = 1.0 / period
    if run.displacement is not None:
        swing = 0.5 * float(np.ptp(run.displacement))
    else:
        swing = 0.5 * float(np.ptp(run.velocity)) / (2.0 * math.pi * frequency)
    peak = float(np.max(np.abs(run.velocity))) if run.velocity is not None else None
    lobes = _half_cycles(run.velocity if run.velocity is not None else run.displacement)
    return _Motion(frequency, swing, peak, lobes)


def _metadata(run: Recording) -> Mapping[str, object]:
    """The run's metadata (sidecar), or nothing for an object without them."""
    found = getattr(run, "metadata", None)
    return found if isinstance(found, Mapping) else {}


def _number(metadata: Mapping[str, object], key: str) -> float | None:
    """A positive finite number of the metadata, or None."""
    value = metadata.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    value = float(value)
    return value if math.isfinite(value) and value > 0 else None


def _implausible(
    motion: _Motion,
    factors: Mapping[str, float],
    metadata: Mapping[str, object],
    *,
    soft: bool = True,
) -> str | None:
    """Why the run read with ``factors`` (per canonical name, 1 for a column as read) is
    no motion the rig makes, or None when it is one.

    In turn: a frequency or peak speed no rig has
    (:func:`bayestribo.model.plausible.is_plausible`); a swing or speed beyond the
    sensor's stated range (``displacement_range_m``, ``velocity_range_m_per_s``) or
    below its stated resolution (``displacement_resolution_m``,
    ``velocity_resolution_m_per_s``); and, with ``soft`` (choosing between readings,
    not refusing a run as read), a frequency more than twice from the stated
    ``natural_frequency_Hz``, or a swing too small for the stated load: a contact of
    friction coefficient μ under the load N takes at least
    2μN/k off the amplitude every half-cycle (k = m (2πf)² from ``mass_kg`` and
    ``natural_frequency_Hz``), so a swing A lasting n half-cycles allows
    μ ≤ k·2A/(2N·n) (2A bounds the first amplitude about the centre), and one below
    :data:`_MU_FLOOR` is not a loaded contact's.
    """
    from bayestribo.model.plausible import FREQUENCY_RANGE_HZ, MAX_SPEED, is_plausible

    frequency = motion.frequency_Hz / factors.get(TIME, 1.0)
    swing = motion.swing * factors.get(DISPLACEMENT, 1.0)
    speed = 2.0 * math.pi * frequency * swing
    if motion.peak_velocity is not None:
        speed = motion.peak_velocity * factors.get(VELOCITY, 1.0)
    if not is_plausible(frequency, swing):
        low, high = FREQUENCY_RANGE_HZ
        return (
            f"a swing of {swing:.3g} m at {frequency:.4g} Hz (peak speed "
            f"{2.0 * math.pi * frequency * swing:.3g} m/s) is no free-decay rig's motion "
            f"(frequencies {low:g} to {high:g} Hz, speeds up to {MAX_SPEED:g} m/s)"
        )
    limits = (
        ("displacement_range_m", swing, "a swing of", "m", "beyond"),
        ("velocity_range_m_per_s", speed, "a peak speed of", "m/s", "beyond"),
        ("displacement_resolution_m", swing, "a swing of", "m", "below"),
        ("velocity_resolution_m_per_s", speed, "a peak speed of", "m/s", "below"),
    )
    for key, value, what, unit, side in limits:
        if key.startswith("velocity") and motion.peak_velocity is None:
            continue
        limit = _number(metadata, key)
        if limit is None or (value <= limit if side == "beyond" else value >= limit):
            continue
        return f"{what} {value:.3g} {unit} is {side} the sensor's stated {key} = {limit:g} {unit}"
    if not soft:
        return None
    natural = _number(metadata, "natural_frequency_Hz")
    if natural is not None and not natural / 2.0 <= frequency <= 2.0 * natural:
        return (
            f"the frequency {frequency:.4g} Hz is not the stated natural_frequency_Hz = "
            f"{natural:g} Hz"
        )
    load, mass = _number(metadata, "load_N"), _number(metadata, "mass_kg")
    if load is None or mass is None or motion.half_cycles < 3:
        return None
    natural = natural or frequency
    stiffness = mass * (2.0 * math.pi * natural) ** 2
    most = stiffness * swing / (load * motion.half_cycles)
    if most >= _MU_FLOOR:
        return None
    return (
        f"a swing of {swing:.3g} m lasting {motion.half_cycles} half-cycles under the "
        f"stated load_N = {load:g} N (stiffness {stiffness:.4g} N/m from mass_kg and "
        f"{'natural_frequency_Hz' if natural != frequency else 'the frequency'}) allows a "
        f"friction coefficient of at most {most:.2g}, less than any loaded sliding "
        f"contact's ({_MU_FLOOR:g})"
    )


@dataclass(frozen=True)
class _Reading:
    """One way of reading a run: the factors of the columns it changes, why the motion
    it gives is no rig's (None when it is one) and its rank among the plausible."""

    factors: dict[str, float]
    reason: str | None
    rank: float


def _reading(
    motion: _Motion | None,
    factors: Mapping[str, float],
    changed: Mapping[str, float],
    metadata: Mapping[str, object],
) -> _Reading:
    """The :class:`_Reading` of the columns ``changed`` (``factors`` holds every column's)."""
    if motion is None:
        return _Reading(dict(changed), None, 0.0)
    reason = _implausible(motion, factors, metadata)
    swing = motion.swing * factors.get(DISPLACEMENT, 1.0)
    rank = abs(math.log10(swing / _TYPICAL_SWING)) if swing > 0 else math.inf
    return _Reading(dict(changed), reason, rank)


def _describe(reading: _Reading, frequency_Hz: float | None) -> str:
    """A reading in words with the ``scale=`` that applies it."""
    fix = reading.factors
    words = " and ".join(_words(k, v) for k, v in fix.items())
    scale = "{" + ", ".join(f"{k!r}: {v:g}" for k, v in fix.items()) + "}"
    after = ""
    if TIME in fix and frequency_Hz is not None:
        after = f" (then f = {frequency_Hz / fix[TIME]:.4g} Hz)"
    return f"{words}{after}: scale={scale}"


def _deciders(metadata: Mapping[str, object], present: list[str], times: bool = False) -> str:
    """The sidecar keys and checks that would decide between readings; ``times``: the
    readings differ in the time's unit, which the rig's stated frequency decides (a
    reading off it by more than a factor of 2 is not plausible)."""
    keys = [k for n in present for k in _SENSOR_KEYS[n] if _number(metadata, k) is None]
    said = []
    if times and _number(metadata, "natural_frequency_Hz") is None:
        said.append(
            "give the rig's natural_frequency_Hz (--frequency), which decides the time's unit"
        )
    if keys:
        said.append("state " + " or ".join(keys) + " in the sidecar")
    missing = [k for k in ("mass_kg", "load_N") if _number(metadata, k) is None]
    if missing:
        said.append(
            "give " + " and ".join(missing) + " (the friction under the load bounds the swing)"
        )
    said.append("check the sensor's output unit and the column labels")
    return ", or ".join(said) + ", then apply that one scale"


def _advice(
    readings: list[_Reading],
    motion: _Motion | None,
    metadata: Mapping[str, object],
    present: list[str],
    explain: bool,
) -> str | None:
    """The plausible readings changing the fewest columns, by rank ("likely ...");
    one alone is named alone, with why the others of as few columns are not (all of
    them with ``explain``, else those the sidecar rules out); several are named all,
    with what decides. None when no reading is plausible."""
    plausible = [r for r in readings if r.reason is None]
    if not plausible:
        return None
    fewest = min(len(r.factors) for r in plausible)
    fixes = sorted((r for r in plausible if len(r.factors) == fewest), key=lambda r: r.rank)
    frequency = motion.frequency_Hz if motion is not None else None
    said = "likely " + "; or ".join(_describe(r, frequency) for r in fixes[:3])
    if len(fixes) > 1:
        times = len({r.factors.get(TIME, 1.0) for r in fixes[:3]}) > 1
        return f"{said}; the record does not tell which: {_deciders(metadata, present, times)}"
    ruled_out = [
        r
        for r in readings
        if r.reason is not None and len(r.factors) == fewest and (explain or "stated" in r.reason)
    ]
    for r in ruled_out[:2]:
        words = " and ".join(_words(k, v) for k, v in r.factors.items())
        said += f"; not {words}: {r.reason}"
    return said


def _unit_hint(gain: float, run: Recording) -> str:
    """The likely units of an inconsistent run, and the scale factors that fix them.

    The displacement is ``gain`` times the time integral of the velocity. Every choice
    of ms/µs for the time and of a length factor (:data:`_LENGTH_FACTORS`) for each
    signal that brings the gain to 1 is a reading of the run; those that also make a
    motion the rig makes (:func:`_implausible`: the frequency and speed a rig has, the
    sensor's stated range and resolution, the friction the stated load allows) are
    named, the fewest columns changed first. Channels a power of ten apart have two
    readings of one column each, the displacement wrong or the velocity: the one the
    rig makes is named alone with why the other is not; when both are, both are named
    with what decides, so that following the advice cannot give a wrong answer. A time
    column in ms with both signals in mm reads as a 0.03 Hz oscillation whose channels
    disagree by 1000: the velocity alone "in mm/s" would make them agree and leave the
    frequency wrong.
    """
    if gain < 0:
        flipped = (
            "the velocity has the opposite sign of the rate of change of the displacement "
            "(one sensor counts the other way): scale={'velocity_m_per_s': -1} reads it "
            "(or the displacement's -1: the friction and damping are the same either way)"
        )
        if 0.5 <= -gain <= 2.0:
            return flipped
        return f"{flipped}; then {_unit_hint(-gain, run)}"
    motion = _motion(run)
    metadata = _metadata(run)
    readings = []
    for a_t in _TIME_FACTORS:
        for a_x in _LENGTH_FACTORS:
            for a_v in _LENGTH_FACTORS:
                if not 0.5 <= gain * a_x / (a_t * a_v) <= 2.0:
                    continue
                factors = {TIME: a_t, DISPLACEMENT: a_x, VELOCITY: a_v}
                changed = {k: v for k, v in factors.items() if v != 1.0}
                if changed:
                    readings.append(_reading(motion, factors, changed, metadata))
    advice = _advice(readings, motion, metadata, [DISPLACEMENT, VELOCITY], explain=True)
    if advice is None:
        return "the signals are not in units a rig's motion has; give each column its unit"
    return advice


@dataclass(frozen=True)
class ChannelConsistency:
    """How the displacement and velocity channels of a run agree (v = dx/dt).

    Attributes
    ----------
    correlation : float
        Correlation of the displacement's changes with the velocity's integral over
        windows of about a fortieth of a period, those in motion [-]; +1 for one
        motion.
    gain : float
        Displacement change per unit of the velocity's integral [-]: the ratio of the
        displacement channel's gain to the velocity channel's; 1 for consistent
        channels, -Ω² for swapped ones.
    delay_s : float
        Delay of the displacement channel behind the velocity channel [s].
    window_s : float
        Length of the comparison windows [s].
    gain_se, delay_se_s : float
        Standard errors of ``gain`` [-] and ``delay_s`` [s], by the delete-one-block
        jackknife over blocks of one period (nan with fewer than 4 blocks in
        motion): residual errors correlated within a cycle are counted once per
        block.
    n_blocks : int
        Blocks of one period that carry motion (the jackknife's blocks).
    """

    correlation: float
    gain: float
    delay_s: float
    window_s: float
    gain_se: float = math.nan
    delay_se_s: float = math.nan
    n_blocks: int = 0

    @property
    def velocity_gain(self) -> float:
        """The velocity channel's reading per unit of dx/dt [-] (1/gain)."""
        return 1.0 / self.gain if self.gain != 0.0 else math.inf

    def to_dict(self) -> dict[str, float | None]:
        """JSON-ready values (None for a standard error that could not be estimated)."""
        values = {
            "correlation": self.correlation,
            "gain": self.gain,
            "gain_se": self.gain_se,
            "velocity_gain": self.velocity_gain,
            "delay_s": self.delay_s,
            "delay_se_s": self.delay_se_s,
            "window_s": self.window_s,
            "n_blocks": self.n_blocks,
        }
        return {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in values.items()}


def _dot(a: NDArray, b: NDArray) -> float:
    """Σ aᵢbᵢ, by einsum: a threaded BLAS waits for a second core that a shared machine
    gives late (these sums are bound by memory, one core reads them as fast)."""
    return float(np.einsum("i,i->", a, b))


def _solve(gram: NDArray, moment: NDArray) -> tuple[float, float] | None:
    """(gain, delay) of Δx ≈ g ΔI − g δ Δv from its normal equations (ΔI and Δv are
    nearly orthogonal: in quadrature over a cycle), or None when degenerate."""
    if gram[0, 0] == 0.0 or gram[1, 1] == 0.0 or not np.all(np.isfinite(gram)):
        return None
    try:
        a, b = np.linalg.solve(gram, moment)
    except np.linalg.LinAlgError:
        return None
    if a == 0.0 or not (math.isfinite(a) and math.isfinite(b)):
        return None
    return float(a), float(-b / a)


def _moving_correlation(xc: NDArray, ic: NDArray, step: float = 0.0) -> float:
    """Correlation [-] of the displacement's changes ``xc`` with the velocity's integral
    ``ic`` over the windows in motion: ``|ic|`` above :data:`MOTION_FRACTION` of its
    largest, and above :data:`QUANTISED_WINDOW_STEPS` of a quantised displacement's
    ``step`` (a change of a step or so is its rounding: at 5 steps across the swing
    the small swings at the end of a decay, rounded on both channels, brought the
    correlation of one motion to 0.88).

    At rest the displacement's change is its noise alone, and the velocity's integral
    almost nothing. Taken over every window, the correlation of one motion fell with
    the share of rest in the record and with the amplitude against the noise: a record
    that starts in motion (cut out of a longer decay, smaller than at a release) with
    its rest after the stop fell below 0.9 and was refused as two motions (measured:
    0.893 for a simulated decay at 32.6 Hz, 5 kHz, 1.5 µm and 0.15 µm/s noise, started
    at 0.18 mm of amplitude, stopped 0.19 s later, 1.1 s of rest; 0.99 over its motion).
    The windows are chosen on the velocity alone, so channels of different motions
    still do not correlate, and swapped ones still anticorrelate.
    """
    size = np.abs(ic)
    moving = size > max(MOTION_FRACTION * float(np.max(size)), QUANTISED_WINDOW_STEPS * step)
    if not np.any(moving):
        moving = size > MOTION_FRACTION * float(np.max(size))
    del size
    xm = xc[moving]
    xm -= xm.mean()
    im = ic[moving]
    im -= im.mean()
    sxx, sii = _dot(xm, xm), _dot(im, im)
    if sxx == 0.0 or sii == 0.0:
        return _dot(xc, ic) / math.sqrt(_dot(xc, xc) * _dot(ic, ic))
    return _dot(xm, im) / math.sqrt(sxx * sii)


#: Results of :func:`channel_consistency` by run (its id, while it lives): a run's arrays
#: are read-only, so the check that read_run, the fit's calibration and ``inspect`` each
#: ask for is made once.
_CONSISTENCY: dict[int, tuple[weakref.ref[Recording], ChannelConsistency | None]] = {}


def channel_consistency(run: Recording) -> ChannelConsistency | None:
    """Compare the displacement with the time integral of the velocity, in gain and time.

    Over short windows (a fortieth of the dominant period) the change of the
    displacement Δx is regressed on the integral of the velocity over the same window
    ΔI and on the change of the velocity Δv: Δx ≈ g ΔI − g δ Δv for a displacement
    channel of gain g relative to the velocity channel, delayed by δ (a first-order
    expansion of g I(t − δ)). Offsets of either channel cancel, and noise averages
    out. The trapezoidal integral of a sampled oscillation at angular frequency ω
    carries the factor (ω dt/2)/tan(ω dt/2) (0.35 % at 1 kHz for 32.6 Hz), which is
    divided out with the dominant frequency. A displacement and a velocity of one
    motion correlate near +1 with a gain near 1. Swapped columns correlate near -1
    with a gain near -Ω² (the change of a velocity is an acceleration, in antiphase
    with the displacement); channels of different motions do not correlate. The
    correlation is taken over the windows in motion (:func:`_moving_correlation`), the
    gain and delay over all of them.

    Parameters
    ----------
    run : Run
        A run with both signals.

    Returns
    -------
    ChannelConsistency or None
        None when the run lacks a signal, is too short, or a signal is constant.
    """
    key = id(run)
    cached = _CONSISTENCY.get(key)
    if cached is not None and cached[0]() is run:
        return cached[1]
    found = _channel_consistency(run)
    _CONSISTENCY[key] = (weakref.ref(run, lambda _, key=key: _CONSISTENCY.pop(key, None)), found)
    return found


def _quantised_lag(x: NDArray, v: NDArray, step: float, period: float) -> int:
    """Samples over which the largest swing moves a coarsely quantised displacement by
    four of its steps (0 when it is not quantised), at most a quarter period.

    Over a fortieth of a period a displacement rounded to a fifth of its swing changes by
    one step or none: its changes are the rounding, and they correlate with the
    velocity's integral at 0.46 where the motion is one (a record of 5 steps across the
    swing was refused as two motions). Over windows long enough for four steps the
    rounding is a small part of each change."""
    from bayestribo.signal.quantisation import quantisation_step

    q = quantisation_step(x)
    speed = float(np.max(np.abs(v)))
    if q is None or not speed > 0:
        return 0
    return min(round(4.0 * q / (speed * step)), round(period / (4.0 * step)))


def _channel_consistency(run: Recording) -> ChannelConsistency | None:
    x, v, t = run.displacement, run.velocity, run.time
    if x is None or v is None:
        return None
    try:
        period = dominant_period(t, x)  # the run's one period (remembered for its arrays)
    except RecordingError:
        if not (math.isfinite(_dot(x, x)) and math.isfinite(_dot(v, v))):
            # values whose squares overflow: not comparable, which the check says
            return ChannelConsistency(math.nan, math.nan, math.nan, math.nan)
        return None
    # the trapezoids' cumulative sum, in place (six arrays of the record's length before);
    # the time steps are taken in the integral's place before it is summed there, and
    # the trapezoids' array then holds the windows' integrals
    integral = np.empty(x.size)
    integral[0] = 0.0
    area = v[1:] + v[:-1]
    area *= 0.5
    area *= np.subtract(t[1:], t[:-1], out=integral[1:])
    np.cumsum(area, out=integral[1:])
    step = sample_step(t)
    lag = max(1, round(period / (40.0 * step)), _quantised_lag(x, v, step, period))
    from bayestribo.signal.quantisation import quantisation_step

    x_step = quantisation_step(x) or 0.0
    if 2 * lag >= x.size:
        return None
    xc = x[lag:] - x[:-lag]
    ic = np.subtract(integral[lag:], integral[:-lag], out=area[: x.size - lag])
    del integral, area
    vc = v[lag:] - v[:-lag]
    xc -= xc.mean()
    ic -= ic.mean()
    vc -= vc.mean()
    sxx, sii = _dot(xc, xc), _dot(ic, ic)
    if sxx == 0.0 or sii == 0.0:
        return None
    correlation = _moving_correlation(xc, ic, x_step)
    half = math.pi * step / period  # ω dt / 2
    trapezoid = half / math.tan(half) if 0.0 < half < 1.0 else 1.0
    # Δx ≈ g ΔI − g δ Δv by least squares, from the normal equations summed over
    # blocks of one period, which the delete-one-block jackknife then reuses: residual
    # errors correlated within a cycle (the model's first-order expansion, a filter's
    # ringing) are counted once per block.
    width = max(2, round(period / step))
    blocks = []
    for first in range(0, xc.size, width):
        part = slice(first, first + width)
        i_p, v_p, x_p = ic[part], vc[part], xc[part]
        ii, iv, vv = _dot(i_p, i_p), _dot(i_p, v_p), _dot(v_p, v_p)
        blocks.append(
            (np.array([[ii, iv], [iv, vv]]), np.array([_dot(i_p, x_p), _dot(v_p, x_p)]), ii)
        )
    total_a = sum(b[0] for b in blocks)
    total_b = sum(b[1] for b in blocks)
    fitted = _solve(total_a, total_b)
    if fitted is None:
        gain, delay = _dot(xc, ic) / sii, 0.0
    else:
        gain, delay = fitted
    gain *= trapezoid
    largest = max(b[2] for b in blocks)
    gains, delays = [], []
    for a_i, b_i, energy in blocks:
        if energy <= 1e-3 * largest:
            continue  # at rest: deleting it changes nothing
        found = _solve(total_a - a_i, total_b - b_i)
        if found is not None:
            gains.append(found[0] * trapezoid)
            delays.append(found[1])
    gain_se = delay_se = math.nan
    k = len(gains)
    if k >= 4:
        spread = (k - 1) / k
        gain_se = math.sqrt(spread * float(np.sum((np.asarray(gains) - np.mean(gains)) ** 2)))
        delay_se = math.sqrt(spread * float(np.sum((np.asarray(delays) - np.mean(delays)) ** 2)))
    return ChannelConsistency(correlation, gain, delay, lag * step, gain_se, delay_se, k)


def check_channels(run: Recording, where: str | None = None) -> None:
    """Refuse channels that do not describe one motion: swapped, unrelated, or with
    gains a factor of :data:`UNIT_GAIN_TOLERANCE` or more apart (the check
    :func:`bayestribo.io.validation.validate_run` applies to every file read; a run
    built in memory gets it before its fit).

    Parameters
    ----------
    run : Run
        A run; one without both signals passes.
    where : str, optional
        File or origin named in the message.

    Raises
    ------
    RecordingError
        Naming the fields and what was found.
    """
    _check_units(run, where)


def _check_units(run: Recording, where: str | None) -> None:
    """The displacement must follow the time integral of the velocity, in phase and
    gain (:func:`channel_consistency`); a record sampled too slowly for its oscillation
    is said to be so first (its integral over a sample is no measure of the channels'
    units: 2.45 samples a period read as a gain of 2.3)."""
    found = channel_consistency(run)
    if found is None:
        return
    try:
        per_period = dominant_period(run.time, run.displacement) / sample_step(run.time)
    except RecordingError:
        per_period = math.inf
    if per_period < MIN_PERIOD_SAMPLES:
        raise RecordingError(
            f"the record's dominant period is {per_period:.1f} samples long: its channels "
            "cannot be compared, nor its turning points located (a free decay needs at "
            f"least {MIN_PERIOD_SAMPLES} samples per period); record it at a higher sample "
            "rate, or check that the time column is in the unit its name says",
            where,
        )
    correlation, gain = found.correlation, found.gain
    both = f"fields {DISPLACEMENT!r} and {VELOCITY!r}"
    if not (math.isfinite(correlation) and math.isfinite(gain)):
        largest = max(float(np.max(np.abs(run.displacement))), float(np.max(np.abs(run.velocity))))
        raise RecordingError(
            f"{both} cannot be compared: their values (up to {largest:.3g}) overflow the "
            "arithmetic of the check; expected the magnitudes of a motion in the stated "
            "units",
            where,
        )
    if correlation < -_SWAP_MIN_ANTICORRELATION and -gain > UNIT_GAIN_TOLERANCE:
        raise RecordingError(
            f"{both} look swapped: the changes of the displacement column follow "
            f"{gain:.4g} times the integral of the velocity column (correlation "
            f"{correlation:.3f}), as an acceleration against a displacement does; expected "
            "the displacement to follow the integral of the velocity; check the order of "
            "the columns (columns=[...])",
            where,
        )
    if abs(correlation) < _UNIT_MIN_CORRELATION:
        raise RecordingError(
            f"{both} do not describe one motion: the changes of the displacement and the "
            f"integral of the velocity correlate at {correlation:.3f}; expected close to 1 (above "
            f"{_UNIT_MIN_CORRELATION:g}); check which column holds which signal "
            "(columns=[...]); where each holds what its name says (a channel disturbed, "
            "spiked or too coarse for the other), read one alone: 'ignore' in the other's "
            "place in columns=[...]",
            where,
        )
    if not 1.0 / UNIT_GAIN_TOLERANCE <= gain <= UNIT_GAIN_TOLERANCE:
        raise RecordingError(
            f"{both} disagree: the displacement is "
            f"{gain:.4g} times the time integral of the velocity; expected 1 (within a factor "
            f"of {UNIT_GAIN_TOLERANCE:g}): {_unit_hint(gain, run)} (or name the "
            "units in the column names, e.g. time_ms, displacement_mm)",
            where,
        )


#: The largest swing of an angle a free decay makes [rad]: a turn each way (a pendulum
#: turns over at π; a balance wheel swings to about 270°).
MAX_ANGLE_SWING = 2.0 * math.pi


def _check_angle_swing(run: Recording, where: str | None) -> None:
    """Refuse a run in radians whose angle swings by more than :data:`MAX_ANGLE_SWING`
    (from the angle, or from an angular velocity alone over 2πf): degrees read as radians
    (an encoder's 68° read as 68 rad, fitted as 11 turns each way without a word), naming
    the column name and the scale that read them as degrees."""
    if run.length_unit != "rad":
        return
    recorded = run.displacement if run.displacement is not None else run.velocity
    if recorded is None:
        return
    values = np.asarray(recorded, dtype=float)
    finite = values[np.isfinite(values)]
    if finite.size < 2:
        return
    swing = 0.5 * float(np.ptp(finite))
    if run.displacement is None:
        # an angular velocity alone: its swing over 2πf is the angle's
        try:
            period = dominant_period(run.time, values)
        except RecordingError:
            return
        if not period > 0:
            return
        swing *= period / (2.0 * math.pi)
    if swing <= MAX_ANGLE_SWING:
        return
    raise RecordingError(
        f"plausibility: the angle swings by {swing:.3g} rad ({swing / (2 * math.pi):.3g} "
        f"turns each way), more than a free decay's {MAX_ANGLE_SWING:.3g} rad (a turn): "
        f"likely degrees ({math.radians(swing):.3g} rad): name the column angle_deg "
        f"(--columns ... angle_deg), or --scale x={math.pi / 180:.10g}; a swing of more "
        "than a turn in radians is read with --length-unit arbitrary",
        where,
    )


def check_plausible_motion(run: Recording, where: str | None = None) -> None:
    """Refuse a run in metres whose motion no rig makes (a frequency outside
    :data:`~bayestribo.model.plausible.FREQUENCY_RANGE_HZ`, a peak speed above
    :data:`~bayestribo.model.plausible.MAX_SPEED`, or a swing or speed below the
    sensor's stated resolution or beyond its stated range), naming the units that
    would make it one and the scale factors that apply them.

    Both channels in mm read as m agree with each other and still give a swing of a
    metre at 32.6 Hz (235 m/s); a time column in ms read as s gives a 0.03 Hz
    oscillation; both in metres labelled mm give a swing below a stated
    ``displacement_resolution_m``. Every factor of :data:`_LENGTH_FACTORS` (cm, mm,
    µm read as m and m read as them) and of the time is tried; the readings the rig
    makes (:func:`_implausible`, with the friction the stated load allows) are named,
    and where several are (a swing in cm or in mm), all of them with what decides.
    Only runs in metres are checked (``length_unit: arbitrary`` states that the unit
    is not known).

    Parameters
    ----------
    run : Run
        The run (any object with ``time`` [s], ``displacement`` [m], ``velocity``
        [m/s], ``signals``, ``length_unit`` and, optionally, ``metadata``).
    where : str, optional
        File or origin named in the message.

    Raises
    ------
    RecordingError
        Naming the swing [m], the frequency [Hz], the peak speed [m/s] (or the stated
        range or resolution it violates) and the units that would make the motion a
        rig's.
    """
    _check_angle_swing(run, where)
    motion = _motion(run)
    if motion is None or not motion.swing > 0:
        return
    metadata = _metadata(run)
    as_read = {TIME: 1.0, DISPLACEMENT: 1.0, VELOCITY: 1.0}
    reason = _implausible(motion, as_read, metadata, soft=False)
    if reason is None:
        return
    present = [n for n in (DISPLACEMENT, VELOCITY) if run.signals.get(n) is not None]
    readings = []
    for a_t in _TIME_FACTORS:
        for a_x in _LENGTH_FACTORS:
            # both signals in one length unit (their agreement is check_channels')
            factors = {TIME: a_t, DISPLACEMENT: a_x, VELOCITY: float(f"{a_x / a_t:.12g}")}
            changed = {k: v for k, v in factors.items() if v != 1.0 and (k == TIME or k in present)}
            if changed:
                readings.append(_reading(motion, factors, changed, metadata))
    advice = _advice(readings, motion, metadata, present, explain=False)
    raise RecordingError(
        f"plausibility: {reason}: {advice or 'give each column its unit'}; or length_unit "
        "'arbitrary' when the unit is not known (pixels of a video track not calibrated "
        "to a length, counts of an uncalibrated sensor)",
        where,
    )
