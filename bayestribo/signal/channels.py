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
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.period import dominant_period, sample_step

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
#: Anticorrelation beyond which, with a large negative gain, the columns look swapped
#: (rests at the initial displacement and after the stop weaken it below 1).
_SWAP_MIN_ANTICORRELATION = 0.3


#: Factors a column in a common unit needs to reach s, m or m/s (ms, µs; mm, µm; ...).
_FACTORS = (1.0, 1e-3, 1e-6)
_UNIT_WORDS = {
    TIME: {1e-3: "time in ms", 1e-6: "time in µs"},
    DISPLACEMENT: {1e-3: "displacement in mm", 1e-6: "displacement in µm"},
    VELOCITY: {1e-3: "velocity in mm/s", 1e-6: "velocity in µm/s"},
}


def _unit_hint(gain: float, frequency_Hz: float | None = None, swing: float | None = None) -> str:
    """The likely units of an inconsistent run, and the scale factors that fix them.

    The displacement is ``gain`` times the time integral of the velocity. Every choice
    of ms/µs for the time and mm/µm (mm/s, µm/s) for the signals that brings the gain
    to 1 is tried; those that also make a motion a rig makes
    (:func:`bayestribo.model.plausible.is_plausible` at the measured frequency and
    swing) are named, the fewest columns changed first. A time column in ms with both
    signals in mm reads as a 0.03 Hz oscillation whose channels disagree by 1000: the
    velocity alone "in mm/s" would make them agree and leave the frequency wrong.
    """
    from bayestribo.model.plausible import is_plausible

    if gain < 0:
        return "the velocity has the opposite sign of the rate of change of the displacement"
    fixes = []
    for a_t in _FACTORS:
        for a_x in _FACTORS:
            for a_v in _FACTORS:
                after = gain * a_x / (a_t * a_v)
                if not 0.5 <= after <= 2.0:
                    continue
                if frequency_Hz is not None and swing is not None:
                    if not is_plausible(frequency_Hz / a_t, swing * a_x):
                        continue
                factors = {TIME: a_t, DISPLACEMENT: a_x, VELOCITY: a_v}
                fixes.append({k: v for k, v in factors.items() if v != 1.0})
    fixes.sort(key=len)
    fixes = [f for f in fixes if f and len(f) == len(fixes[0])] if fixes else []
    if not fixes:
        return "the signals are not in units a rig's motion has; give each column its unit"
    described = []
    for fix in fixes:
        words = " and ".join(_UNIT_WORDS[k][v] for k, v in fix.items())
        scale = "{" + ", ".join(f"{k!r}: {v:g}" for k, v in fix.items()) + "}"
        after = ""
        if TIME in fix and frequency_Hz is not None:
            after = f" (then f = {frequency_Hz / fix[TIME]:.4g} Hz)"
        described.append(f"{words}{after}: scale={scale}")
    return "likely " + "; or ".join(described)


def _motion(run: Recording) -> tuple[float | None, float | None]:
    """Frequency [Hz] and amplitude (half the peak-to-peak, in the file's length unit)
    of a run's motion as read, for :func:`_unit_hint`."""
    signal = run.displacement if run.displacement is not None else run.velocity
    if signal is None or run.length_unit != "m":
        return None, None
    try:
        period = dominant_period(run.time, signal)
    except RecordingError:
        return None, None
    if not period > 0:
        return None, None
    frequency = 1.0 / period
    if run.displacement is not None:
        swing = 0.5 * float(np.ptp(run.displacement))
    else:
        swing = 0.5 * float(np.ptp(run.velocity)) / (2.0 * math.pi * frequency)
    return frequency, swing


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


def _moving_correlation(xc: NDArray, ic: NDArray) -> float:
    """Correlation [-] of the displacement's changes ``xc`` with the velocity's integral
    ``ic`` over the windows in motion: ``|ic|`` above :data:`MOTION_FRACTION` of its
    largest.

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
    lag = max(1, round(period / (40.0 * step)))
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
    correlation = _moving_correlation(xc, ic)
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
    gain (:func:`channel_consistency`)."""
    found = channel_consistency(run)
    if found is None:
        return
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
            "(columns=[...])",
            where,
        )
    if not 1.0 / UNIT_GAIN_TOLERANCE <= gain <= UNIT_GAIN_TOLERANCE:
        raise RecordingError(
            f"{both} disagree: the displacement is "
            f"{gain:.4g} times the time integral of the velocity; expected 1 (within a factor "
            f"of {UNIT_GAIN_TOLERANCE:g}): {_unit_hint(gain, *_motion(run))} (or name the "
            "units in the column names, e.g. time_ms, displacement_mm)",
            where,
        )


def check_plausible_motion(run: Recording, where: str | None = None) -> None:
    """Refuse a run in metres whose motion no rig makes (a frequency outside
    :data:`~bayestribo.model.plausible.FREQUENCY_RANGE_HZ` or a peak speed above
    :data:`~bayestribo.model.plausible.MAX_SPEED`), naming the units that would make
    it one and the scale factors that apply them.

    Both channels in mm read as m agree with each other and still give a swing of a
    metre at 32.6 Hz (235 m/s); a time column in ms read as s gives a 0.03 Hz
    oscillation. Only runs in metres are checked (``length_unit: arbitrary`` states
    that the unit is not known).

    Parameters
    ----------
    run : Run
        The run (any object with ``time`` [s], ``displacement`` [m], ``velocity``
        [m/s], ``signals`` and ``length_unit``).
    where : str, optional
        File or origin named in the message.

    Raises
    ------
    RecordingError
        Naming the swing [m], the frequency [Hz], the peak speed [m/s] and the units
        that would make the motion a rig's.
    """
    from bayestribo.model.plausible import FREQUENCY_RANGE_HZ, MAX_SPEED, is_plausible

    frequency, swing = _motion(run)
    if frequency is None or swing is None or not swing > 0:
        return
    if is_plausible(frequency, swing):
        return
    speed = 2.0 * math.pi * frequency * swing
    low, high = FREQUENCY_RANGE_HZ
    fixes = []
    for a_t in _FACTORS:
        for a_x in _FACTORS:
            if (a_t, a_x) != (1.0, 1.0) and is_plausible(frequency / a_t, swing * a_x):
                fixes.append({TIME: a_t, DISPLACEMENT: a_x, VELOCITY: a_x / a_t})
    present = [n for n in (DISPLACEMENT, VELOCITY) if run.signals.get(n) is not None]
    advice = []
    for fix in sorted(fixes, key=lambda f: sum(v != 1.0 for v in f.values()))[:2]:
        factors = {k: v for k, v in fix.items() if v != 1.0 and (k == TIME or k in present)}
        words = " and ".join(_UNIT_WORDS[k].get(v, f"{k} × {v:g}") for k, v in factors.items())
        scale = "{" + ", ".join(f"{k!r}: {v:g}" for k, v in factors.items()) + "}"
        advice.append(f"{words}: scale={scale}")
    said = "; or ".join(advice) if advice else "give each column its unit"
    raise RecordingError(
        f"plausibility: a swing of {swing:.3g} m at {frequency:.4g} Hz (peak speed "
        f"{speed:.3g} m/s) is no free-decay rig's motion (frequencies {low:g} to {high:g} "
        f"Hz, speeds up to {MAX_SPEED:g} m/s): likely {said}; or length_unit 'arbitrary' "
        "when the unit is not known",
        where,
    )
