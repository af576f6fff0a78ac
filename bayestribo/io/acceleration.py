r"""An accelerometer's record as a velocity: bias removed, integrated, drift filtered.

A free-decay record made with an accelerometer (a cantilever's, a spring-mass rig's, a
smartphone's: phyphox exports ``Acceleration x (m/s^2)``) holds a = ẍ. The fit takes a
velocity (a run with a velocity only derives its displacement), so the acceleration is
integrated once, at read time (:func:`integrate_acceleration`):

1. **Bias.** A sensor's offset (and a smartphone's share of gravity along the axis) is
   a constant b under the motion. Where the record is at rest (before the release and
   after the stop, found as the stretches where no oscillation at the record's own
   frequency stands out of the noise, :func:`bayestribo.signal.motion.motion_span`,
   half a period away from either), the true acceleration is 0, so b is the mean
   acceleration there, with standard error σ_a/√n. A record with no rest has its mean
   taken for b, and the output says so (the mean of a over a record is
   (v_end − v_start)/T, 0 only when it starts and ends at the same speed).
2. **Integration**, in the frequency domain: V(f) = A(f) / (i 2π f) on the record padded
   with as many zeros (after step 1 the rest's mean is 0, so the padding is rest too).
   Unlike the trapezoid rule, whose gain at 20 samples a period is 0.992, this is exact
   below Nyquist for an acceleration sampled through an anti-alias filter. (A jump of
   the acceleration, at the release or where dry friction turns, sampled at one instant
   without such a filter, leaves an error of up to the jump times half a sample step.)
3. **Drift.** What is left of the bias integrates into a ramp and the sensor's white
   noise into a random walk, a noise whose variance grows without bound. The velocity
   at rest is 0: a line through the integral over each rest, and between them the
   straight line from the one to the other, is taken off (the best estimate of a random
   walk between two points where it is known). Then a zero-phase high-pass,
   H(f) = r / (1 + r) with r = (f / f_c)⁴ (the squared magnitude of a second-order
   Butterworth: that filter run forwards and backwards), f_c = 0.15 f, leaves the
   integrated noise stationary, the same at rest as in the motion, so that the fit's
   noise model, measured at rest as a spectrum (:mod:`bayestribo.signal.spectrum`),
   is the motion's (its correlation time, about a period, is well inside a rest of a
   few periods). Its gain at f, 1 / (1 + 0.15⁴) = 0.9995, is divided out. The cut-off
   is a compromise: the filter's slope across the decay's band lowers the ζ fitted to
   a dry-friction decay (with no noise: by 0.3 % of ζ at f_c = 0.1 f, 1 % at 0.2 f,
   2.6 % at 0.3 f), and a lower cut-off leaves a noise correlated over longer than the
   rest shows.
   A free decay's velocity has almost nothing below f_c but the steps of the
   displacement at the release (from the held position to the centre of the
   oscillation) and at the stop: what the high-pass would remove is fitted there by
   least squares with a step at each edge and its first two derivatives (the edge's
   shape, smoothed above 16 f_c: unsmoothed, a step between two samples rang over the
   whole record and the high-pass took part of the edge's content, so that a decay
   that loses much per cycle at the release, quadratic drag at a large swing, kept its
   first swings after the first period 0.2 % low, noise-free; a fit then moved its
   loss from c₂ to ζ: ζ +1.5 %, c₂ -0.9 % with almost no noise, c₂'s z -0.76 ± 0.40 in
   the benchmark; now within 4e-4, ``tests/test_io_acceleration.py``), and that part
   is kept; the rest is the drift. A decay that fades into the noise ends at its last
   excursion beyond 5σ of the rest, a period later. Without a rest on a side (a record
   that starts or ends in motion) the step there cannot be told from the drift: the
   high-pass takes it, at f_c = 0.3 f to confine what it does there to fewer cycles
   (its gain 0.992 at f divided out), and the record says so.

**The release and the stop** are the acceleration's (:attr:`Integration.release_s`,
``stop_s``, :func:`motion_edges`): its noise is white, while the integral's wanders next
to the stop beyond its rest noise, so that the velocity seemed to move on after it (its
last turning points the noise's), or its levels next to the edges were taken for an
offset that drifts. Last swings whose acceleration peaks under the threshold of motion
(a few friction displacements at a slow rig's frequency) are found as lobes of its mean
over an eighth of a period (:func:`bayestribo.signal.motion.lobes_after_stop`): the
stop is never put before the turning point where the oscillator sticks.

**Its noise.** The velocity's noise is the sensor's through these steps: a random walk
held at the rests by the drift's line and free between them, of which the high-pass
keeps a part near its cut-off, so that in the motion it is larger than at rest (2.7
times in sd over 3 s of motion between 2 s and 3 s of rest). The rest's spectrum does
not show it; the integration records its linear steps (``noise`` in
:meth:`Integration.record`: the sensor's noise at rest, the rests, the edges, the
cut-off and the gain) and :func:`velocity_noise` draws the noise they leave, from
which the fit takes the increments' variances
(:func:`bayestribo.signal.increments.accelerometer_draws`).

Without noise the velocity so made is within 2e-3 of the swing of the true one after
the first period (``tests/test_io_acceleration.py``). Fits of simulated accelerometer
records (an independent ``solve_ivp`` integration, 100 to 300 µg/√Hz of noise, 20 runs
a case, ``benchmarks/acceleration.py``, ``benchmarks/results/acceleration.json``):
dry friction, μ_k 13 covered and 7 flagged (misfit, all 7 covered), none silently
wrong (z −0.05 ± 0.57), ζ 12 covered, 7 flagged, 1 silently wrong (z 0.23 ± 1.53);
viscous drag, ζ₀ 18 covered, 1 flagged, 1 silently wrong (z 0.48 ± 1.12); quadratic
drag with ``law="auto"``, ``viscous+quadratic`` chosen in 16 of 20 and
``quadratic+hysteretic`` in 2, c₂ 14 covered, 4 flagged, none silently wrong (z −0.25 ±
0.69); ``coulomb+power`` in 2, each flagged. Before the edge's terms were smoothed
(``acceleration_a480aea.json``) the quadratic drag's law was ``viscous+quadratic`` in
11 of 20 and c₂ silently wrong in 2; the dry-friction records were flagged less often
(4 of 20), because the terms' ringing in the rest before the release inflated the
noise measured there (noise-free: 2e-4 of the swing against 3e-5 now), hiding a misfit
the noise now shows. What is left is a bias of ζ that grows as the noise squared
(``benchmarks/README.md``).

Several axes of one sensor (phyphox's x, y and z) are projected on the principal axis
of the oscillation (:func:`principal_axis`): the direction of the largest variance of
the de-meaned axes, its sign that of its largest component. A motion along one line
gives that line, with the noise of one axis; axes that do not move along one line (the
second principal axis holding over a quarter of the first's variance) are refused
naming the ``columns=`` that picks one axis.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RecordingError, RunFormatError
from bayestribo.io.run import (
    ACCELERATION,
    ACCELERATION_AXES,
    ACCELERATIONS,
    ANGULAR_ACCELERATION,
    ANGULAR_VELOCITY,
    TIME,
    VELOCITY,
    Run,
)
from bayestribo.signal.velocity_integral import (
    ORDER,
    REST_SAMPLES,
    highpass_gain,
    integrated_velocity,
    velocity_noise,
)

__all__ = [
    "CUTOFF_RATIO",
    "CUTOFF_RATIO_OPEN",
    "SPREAD_LIMIT",
    "Integration",
    "PrincipalAxis",
    "describe",
    "from_acceleration",
    "integrate_acceleration",
    "integrated_signals",
    "motion_edges",
    "principal_axis",
    "velocity_noise",
]

#: Cut-off of the high-pass over the oscillation frequency, f_c / f, for a record with
#: rest before the release and after the stop.
CUTOFF_RATIO = 0.15
#: The same for a record that starts or ends in motion: the edge there is not modelled,
#: and a higher cut-off confines what the filter does to it to fewer cycles.
CUTOFF_RATIO_OPEN = 0.3
#: Largest share of the first principal axis's variance the second may hold for axes to
#: be projected on one line.
SPREAD_LIMIT = 0.25
#: Excursion of the acceleration from its rest level, in rest noise standard deviations,
#: beyond which a decay that fades into the noise is still moving.
_FADED = 5.0
#: Samples left out on each side of the release and of the stop when the bias is
#: measured, in periods: the motion starts and ends within a block of the motion span.
_MARGIN_PERIODS = 0.5


@dataclass(frozen=True)
class Integration:
    """A velocity integrated from an acceleration, and how.

    Attributes
    ----------
    velocity : ndarray
        The velocity [m/s or rad/s].
    column : str
        The acceleration column integrated (canonical name, or the axes' projection).
    bias : float
        The bias removed [m/s² or rad/s²].
    bias_se : float
        Its standard error [m/s² or rad/s²] (rest noise / √n).
    bias_from : str
        Where the bias was measured, in words.
    rest_samples : int
        Samples of rest the bias is the mean of (0: none, the record's mean taken).
    frequency_Hz : float
        The oscillation frequency measured from the acceleration [Hz].
    cutoff_Hz : float
        The high-pass's cut-off [Hz].
    gain_at_frequency : float
        The high-pass's gain at ``frequency_Hz`` (divided out).
    drift_from : str
        How the drift was removed, in words.
    noise : dict or None
        The integration's linear steps, for its noise (:func:`bayestribo.signal.
        velocity_integral.velocity_noise`); None without rest enough to measure it.
    release_s, stop_s : float or None
        The release and the end of motion [s] as the acceleration shows them (its noise
        is white: :func:`bayestribo.signal.motion.motion_span` on it); None where the
        record starts or ends in motion, or fades into the noise. The integral's
        noise, a random walk held at the rests, wanders well beyond its rest noise
        next to them, so that the velocity would show motion where the acceleration
        shows none (:func:`motion_edges`).
    """

    velocity: NDArray
    column: str
    bias: float
    bias_se: float
    bias_from: str
    rest_samples: int
    frequency_Hz: float
    cutoff_Hz: float
    gain_at_frequency: float
    drift_from: str
    noise: dict[str, Any] | None = None
    release_s: float | None = None
    stop_s: float | None = None

    def record(self) -> dict[str, Any]:
        """The metadata record (plain data) of the integration."""
        return {
            "column": self.column,
            "bias": self.bias,
            "bias_se": self.bias_se,
            "bias_from": self.bias_from,
            "rest_samples": self.rest_samples,
            "frequency_Hz": self.frequency_Hz,
            "filter": {
                "kind": "zero-phase high-pass, |H|^2 of a Butterworth",
                "order": ORDER,
                "cutoff_Hz": self.cutoff_Hz,
                "gain_at_frequency": self.gain_at_frequency,
                "gain_divided_out": True,
            },
            "drift": self.drift_from,
            "method": "frequency-domain integral V = A / (i 2 pi f), zero-padded",
            **({} if self.noise is None else {"noise": self.noise}),
            "release_s": self.release_s,
            "stop_s": self.stop_s,
        }

    def note(self, unit: str) -> str:
        """One sentence saying what was done, for a warning."""
        return (
            f"the velocity is integrated from the acceleration {self.column!r}: bias "
            f"{self.bias:.4g} ± {self.bias_se:.2g} {unit} removed ({self.bias_from}); "
            f"{self.drift_from}; then a zero-phase high-pass at {self.cutoff_Hz:.3g} Hz "
            f"(order-{ORDER} Butterworth, forwards and backwards; its gain "
            f"{self.gain_at_frequency:.4f} at the oscillation's {self.frequency_Hz:.4g} Hz "
            "divided out)"
        )


def describe(record: Mapping[str, Any]) -> str:
    """One line for a fit's report: where its velocity came from, from the metadata
    record of :meth:`Integration.record` (``run.metadata["acceleration"]``)."""
    filt = record.get("filter", {})
    text = (
        f"integrated from the acceleration {record.get('column')!r}: bias "
        f"{record.get('bias', float('nan')):.4g} ± {record.get('bias_se', float('nan')):.2g} "
        f"removed ({record.get('bias_from')}); zero-phase high-pass at "
        f"{filt.get('cutoff_Hz', float('nan')):.3g} Hz (gain "
        f"{filt.get('gain_at_frequency', float('nan')):.4f} at f, divided out)"
    )
    axes = record.get("axes")
    if axes:
        weights = ", ".join(
            f"{_axis_name(c)} {w:.3f}" for c, w in (axes.get("weights") or {}).items()
        )
        text += f"; the axes projected on their principal axis ({weights})"
    return text


def _rest(
    t: NDArray, a: NDArray, period: float
) -> tuple[NDArray, NDArray, float | None, float | None, bool]:
    """Samples at rest before the release and after the stop (two masks), half a period
    away from the motion, the times of the release and of the stop (None where the
    record starts or ends in motion), and whether that stop is the motion's end. A decay
    that fades into the noise has no sharp stop: a period after its last excursion
    beyond 5σ of the rest is taken (not an end: False), when the record goes on four
    periods beyond it."""
    from bayestribo.signal.motion import lobes_after_stop, motion_span

    span = motion_span(t, a - np.median(a), period)
    quiet = np.array(span.quiet, dtype=bool)
    moving = np.flatnonzero(~quiet)
    release, stop = span.release_time, span.stop_time
    if stop is not None:
        # last swings whose acceleration peaks under the threshold: lobes of the white
        # noise's mean over an eighth of a period (signal.motion.lobes_after_stop)
        stop = lobes_after_stop(t, a, stop, span.noise, period)
        quiet = quiet & ~((t >= span.stop_time) & (t <= stop + 0.125 * period))
    if moving.size and release is None and quiet[0]:
        release = float(t[moving[0]])
    if stop is None and release is not None:
        # a decay that fades into the noise: its last excursion beyond 5σ of the rest
        # (white noise there: a chance of 6e-7 a sample), a period before the rest
        level = float(np.median(a[t < release]))
        out = np.flatnonzero(np.abs(a - level) > _FADED * span.noise)
        if out.size and t[-1] - t[out[-1]] > 4.0 * period:
            stop = float(t[out[-1]]) + period
    margin = _MARGIN_PERIODS * period
    none = np.zeros_like(quiet)
    before = quiet & (t < release - margin) if release is not None else none
    after = none
    if stop is not None:
        after = (t > stop + margin) & (quiet if span.stop_time is not None else True)
    return before, after, release, stop, span.stop_time is not None


def integrate_acceleration(
    time: ArrayLike, acceleration: ArrayLike, *, column: str = ACCELERATION
) -> Integration:
    """The velocity of a free-decay record from its acceleration (see the module notes).

    Parameters
    ----------
    time : array_like
        Sample times t [s], regular.
    acceleration : array_like
        Acceleration a [m/s²] (or rad/s²), with the sensor's bias.
    column : str
        The acceleration's column name, for the record and messages.

    Returns
    -------
    Integration

    Raises
    ------
    RecordingError
        When the acceleration holds no oscillation standing out of its noise (no free
        decay), or is not finite.
    """

    from bayestribo.signal.period import dominant_period, sample_step

    t = np.asarray(time, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    if t.shape != a.shape or t.ndim != 1 or t.size < 16:
        raise RecordingError(
            f"{column}: expected 1-D time and acceleration of the same length (16 samples "
            f"or more), got shapes {t.shape} and {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.isfinite(a))
        raise RecordingError(
            f"{column}: {bad.size} sample(s) not finite, the first at t = {t[bad[0]]:g} s; "
            "an acceleration is integrated over the whole record"
        )
    dt = sample_step(t)
    rough = np.cumsum(a - a.mean()) * dt  # a velocity with a drift: the period only
    try:
        period = dominant_period(t, rough)
        before, after, release, stop, stopped = _rest(t, a, period)
    except RecordingError as exc:
        raise RecordingError(
            f"{column}: {exc.message}; no free decay in the acceleration"
        ) from None
    rest = before | after
    n_rest = int(rest.sum())
    if n_rest >= 2:
        bias = float(a[rest].mean())
        bias_se = float(a[rest].std(ddof=1) / math.sqrt(n_rest))
        bias_from = f"the mean of {n_rest} samples at rest, where the acceleration is 0"
    else:
        n_rest = 0
        bias = float(a.mean())
        bias_se = float(a.std(ddof=1) / math.sqrt(a.size))
        bias_from = (
            "no rest in the record: its mean acceleration was taken for the bias, assuming "
            "the velocity is the same at its start and end"
        )
    frequency = 1.0 / period
    edges = [
        (name, float(edge))
        for name, edge, mask in (
            ("the release", release, before),
            ("the stop", stop, after),
        )
        if edge is not None and int(mask.sum()) >= REST_SAMPLES
    ]
    cutoff = (CUTOFF_RATIO if len(edges) == 2 else CUTOFF_RATIO_OPEN) * frequency
    velocity, sizes = integrated_velocity(t, a - bias, before, after, cutoff, [e for _, e in edges])
    where = " and ".join(name for name, _ in edges)
    rests = {2: "before the release and after the stop", 1: f"at {where} only", 0: ""}
    if edges:
        steps = ", ".join(
            f"{size:.4g} at {name}" for (name, _), size in zip(edges, sizes, strict=True)
        )
        drift_from = (
            f"the drift measured at rest {rests[len(edges)]} taken off (the displacement's "
            f"steps, {steps}, kept out of the high-pass)"
        )
    else:
        drift_from = "no rest before the release or after the stop to measure the drift at"
    if len(edges) < 2:
        drift_from += (
            "; where the record starts or ends in motion, the high-pass takes the "
            "displacement's step there with the drift (the first or last cycles are "
            "distorted)"
        )
    at_frequency = float(highpass_gain(frequency, cutoff))
    velocity /= at_frequency  # the oscillation's amplitude as recorded
    velocity.setflags(write=False)
    noise = None
    if n_rest >= REST_SAMPLES:
        noise = {
            "sigma": bias_se * math.sqrt(n_rest),
            "start_s": float(t[0]),
            "step_s": dt,
            "samples": int(t.size),
            "rest_before": _runs(before),
            "rest_after": _runs(after),
            "edges_s": [e for _, e in edges],
            "cutoff_Hz": cutoff,
            "gain": at_frequency,
        }
    return Integration(
        velocity=velocity,
        column=column,
        bias=bias,
        bias_se=bias_se,
        bias_from=bias_from,
        rest_samples=n_rest,
        frequency_Hz=frequency,
        cutoff_Hz=cutoff,
        gain_at_frequency=at_frequency,
        drift_from=drift_from,
        noise=noise,
        release_s=release if any(name == "the release" for name, _ in edges) else None,
        stop_s=stop if stopped and any(name == "the stop" for name, _ in edges) else None,
    )


def motion_edges(metadata: Mapping[str, Any]) -> tuple[float | None, float | None] | None:
    """The release and the end of motion [s] of a run integrated from an acceleration,
    as its acceleration shows them (:attr:`Integration.release_s`, ``stop_s``; either
    None where the record has none); None for a run not integrated so, or recorded
    before these were kept.

    Parameters
    ----------
    metadata : mapping
        The run's metadata (its ``acceleration`` record).

    Raises
    ------
    RunFormatError
        ``acceleration.release_s`` or ``stop_s`` present but not a finite number (a
        hand-edited or foreign sidecar).
    """
    record = metadata.get("acceleration") if metadata else None
    if not isinstance(record, Mapping) or ("release_s" not in record and "stop_s" not in record):
        return None
    edges: list[float | None] = []
    for key in ("release_s", "stop_s"):
        value = record.get(key)
        if value is None:
            edges.append(None)
            continue
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise RunFormatError(
                f"metadata 'acceleration.{key}' (the {key[:-2]} time the acceleration "
                f"shows [s]): expected a finite number or null, got {value!r}"
            )
        edges.append(float(value))
    return None if edges == [None, None] else (edges[0], edges[1])


def _runs(mask: NDArray) -> list[list[int]]:
    """The runs of true samples of ``mask`` as [first, stop) index pairs."""
    change = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return [[int(a), int(b)] for a, b in zip(change[::2], change[1::2], strict=True)]


@dataclass(frozen=True)
class PrincipalAxis:
    """The projection of a sensor's axes on the principal axis of the oscillation.

    Attributes
    ----------
    values : ndarray
        The projection Σ w_i a_i [m/s²].
    weights : dict
        The unit vector w by axis column.
    spread : float
        The second principal variance over the first (0 for a motion along one line).
    """

    values: NDArray
    weights: dict[str, float]
    spread: float

    def describe(self) -> str:
        """The projection in words: ``0.12 x + 0.99 z``."""
        return " + ".join(f"{w:.3f}·{_axis_name(c)}" for c, w in self.weights.items())


def _axis_name(column: str) -> str:
    return next((axis for axis, name in ACCELERATION_AXES.items() if name == column), column)


def principal_axis(axes: Mapping[str, ArrayLike]) -> PrincipalAxis:
    """Several acceleration axes projected on the direction of their largest variance.

    Parameters
    ----------
    axes : mapping
        Acceleration [m/s²] by axis column, of equal lengths.

    Returns
    -------
    PrincipalAxis
        The projection of the axes as recorded (their bias projected with them), the
        axis (sign: its largest component positive) and the spread.
    """
    names = list(axes)
    data = np.vstack([np.asarray(axes[name], dtype=np.float64) for name in names])
    centred = data - data.mean(axis=1, keepdims=True)
    variances, vectors = np.linalg.eigh(np.cov(centred))
    order = np.argsort(variances)[::-1]
    variances, vectors = variances[order], vectors[:, order]
    w = vectors[:, 0]
    if w[np.argmax(np.abs(w))] < 0:
        w = -w
    spread = float(variances[1] / variances[0]) if variances[0] > 0 else 1.0
    return PrincipalAxis(
        values=w @ data,
        weights={name: float(x) for name, x in zip(names, w, strict=True)},
        spread=spread,
    )


def _pick(axis: str, file_columns: list[str] | None) -> str:
    """The ``columns=`` that reads one axis of a file whose names are ``file_columns``."""
    if file_columns is None:
        return f"{_axis_name(axis)}: columns=[...] naming {axis!r} and 'ignore' for the other axes"
    names = [
        name if name not in ACCELERATIONS else (ACCELERATION if name == axis else "ignore")
        for name in file_columns
    ]
    return f"{_axis_name(axis)}: columns={names} (--columns {' '.join(names)})"


def _one_column(
    signals: Mapping[str, Any], where: str, file_columns: list[str] | None = None
) -> tuple[str, NDArray, dict[str, Any] | None]:
    """The acceleration to integrate: the one column, or the axes' principal projection
    (with its record)."""
    present = [name for name in ACCELERATIONS if signals.get(name) is not None]
    axes = [name for name in ACCELERATION_AXES.values() if name in present]
    others = [name for name in present if name not in axes]
    if len(others) > 1 or (others and axes):
        raise RunFormatError(
            f"the file holds the accelerations {present}; read one (columns=[...], 'ignore' "
            "for the others)",
            where,
        )
    if len(axes) == 1:
        return axes[0], signals[axes[0]], None
    if not axes:
        return present[0], signals[present[0]], None
    projection = principal_axis({name: signals[name] for name in axes})
    pick = [_pick(name, file_columns) for name in axes]
    if projection.spread > SPREAD_LIMIT:
        raise RunFormatError(
            f"the acceleration's axes {[_axis_name(a) for a in axes]} do not move along one "
            f"line (the second principal axis holds {projection.spread:.0%} of the first's "
            f"variance, over {SPREAD_LIMIT:.0%}): the motion is not one oscillation along "
            f"one direction, or it is buried in the noise; pick the axis of the motion, "
            f"{'; '.join(pick)}",
            where,
        )
    record = {"weights": projection.weights, "spread": projection.spread}
    warn(
        f"{where}: the acceleration's axes {[_axis_name(a) for a in axes]} are projected on "
        f"the principal axis of the oscillation, {projection.describe()} (the second axis "
        f"holds {projection.spread:.1%} of its variance); to read one axis instead, "
        f"{'; '.join(pick)}",
        ReadingWarning,
    )
    return "projection " + projection.describe(), projection.values, record


def integrated_signals(
    signals: Mapping[str, Any],
    meta: dict[str, Any],
    where: str,
    file_columns: list[str] | None = None,
) -> dict[str, Any]:
    """A reader's columns with an acceleration integrated into the velocity.

    An acceleration beside a displacement or a velocity is not read (said with a
    :class:`~bayestribo.errors.ReadingWarning`): the recorded motion is used. Otherwise
    the acceleration (or its axes' projection, :func:`principal_axis`) is integrated
    (:func:`integrate_acceleration`), said with a ``ReadingWarning``, and recorded in
    ``meta`` under ``acceleration``.

    Parameters
    ----------
    signals : mapping
        The reader's columns by canonical name, time [s] among them.
    meta : dict
        The run's metadata, updated with the integration's record.
    where : str
        The file, for messages.
    file_columns : list of str, optional
        The file's column names in file order (canonical, ``ignore``), to name the
        ``columns=`` that reads one axis.

    Returns
    -------
    dict
        The columns, accelerations replaced by the velocity (or an angular velocity).
    """
    present = [name for name in ACCELERATIONS if signals.get(name) is not None]
    if not present:
        return dict(signals)
    out = {name: value for name, value in signals.items() if name not in ACCELERATIONS}
    motion = [name for name in out if name != TIME and out[name] is not None]
    if motion:
        warn(
            f"{where}: column(s) {present} not read: the run is read from {motion}, the "
            "motion recorded",
            ReadingWarning,
        )
        return out
    time = out.get(TIME)
    if time is None:
        raise RunFormatError(
            "an acceleration is integrated over time: the file needs a time column or a "
            "sample rate (sample_rate_Hz=HZ)",
            where,
        )
    column, values, axes = _one_column(signals, where, file_columns)
    try:
        integration = integrate_acceleration(time, values, column=column)
    except RecordingError as exc:
        raise RecordingError(exc.message, where) from None
    angular = column == ANGULAR_ACCELERATION
    unit = "rad/s²" if angular else "m/s²"
    meta["acceleration"] = integration.record()
    if axes is not None:
        meta["acceleration"]["axes"] = axes
    warn(f"{where}: {integration.note(unit)}", ReadingWarning)
    out[ANGULAR_VELOCITY if angular else VELOCITY] = integration.velocity
    return out


def from_acceleration(
    time: ArrayLike,
    acceleration: ArrayLike,
    metadata: Mapping[str, Any] | None = None,
    *,
    angular: bool = False,
    source: str | None = None,
) -> Run:
    """A run whose velocity is integrated from an acceleration (see the module notes).

    Parameters
    ----------
    time : array_like
        Sample times t [s], regular.
    acceleration : array_like
        Acceleration a [m/s²] (``angular``: angular acceleration [rad/s²]), bias and
        all.
    metadata : mapping, optional
        The run's metadata; the integration's record is added under ``acceleration``
        (and ``length_unit`` ``"rad"`` for an angular acceleration).
    angular : bool
        The acceleration is an angular one.
    source : str, optional
        Where the record came from, for messages.

    Returns
    -------
    Run
        With the time and the velocity (the fit derives the displacement).
    """
    meta = dict(metadata or {})
    name = ANGULAR_ACCELERATION if angular else ACCELERATION
    signals = integrated_signals(
        {TIME: np.asarray(time, dtype=float), name: np.asarray(acceleration, dtype=float)},
        meta,
        source or "acceleration",
    )
    if angular:
        meta["length_unit"] = "rad"
    velocity = signals.get(ANGULAR_VELOCITY if angular else VELOCITY)
    return Run(signals[TIME], velocity=velocity, metadata=meta, source=source)
