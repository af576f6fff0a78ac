"""Predicted end of motion against the end detected in the recording.

With Coulomb friction the motion stops in finite time. The averaged model gives the
duration ``T_f = ln(1 + πζa_0/(2μ_k))/ζ`` (Eq. 38,
:func:`bayestribo.model.extinction_time`); the exact model stops at the last turning
point, the first one inside the static-friction band (Eq. 8,
:func:`bayestribo.model.stop_time`). Both are evaluated for every parameter draw
(posterior, or the labelled Gaussian stand-in) and compared with the end of motion
that :func:`bayestribo.signal.decay.energy_decay` detected. Times are in seconds after
the start of the analysed decay (its first sample).

The exact model's end is taken where the record's would be detected
(:func:`bayestribo.signal.motion.motion_span`): the last sample of the record's rate at
which the model's motion, with the record's noise drawn on it, exceeds the record's
threshold of motion (:func:`_linear_stop`). The motion creeps into its stop (its
acceleration there is the spring's force less the friction's, small on a slow
oscillator), so that sample comes before the stop itself, on a linear spring of 0.7 Hz
with 4 mrad/s of noise by 0.1-0.8 s. The detected end is the last excursion's, moved to
the root of the velocity's line before it, so the predicted interval is widened by that
line's reach (or two sample periods, whichever is longer). Where a displacement is
recorded beside the velocity and it is off its rest at that last excursion or at the
turning point after it, the record shows the motion going on, and its end is the end of
the half cycle it sees (:func:`bayestribo.signal.motion._missed_half_cycle`: that
turning point, or the one after it where the velocity's lobe between them stands out of
its noise averaged over an eighth of a period); the model's end moves the same way
(:func:`_moved`). A velocity recorded alone ends one half cycle later where that half
cycle's lobe stands out so (:func:`bayestribo.signal.motion._missed_alone`), as does
a velocity whose displacement beside it does not show that half cycle (its turning
point and rest on one side, within the displacement's threshold of each other), and the
model's end likewise, its lobe judged against the white noise's mean (the record's
against the mean's noise measured at rest, larger for a coloured noise: the prediction
may then run half a cycle past the record's end).

On a nonlinear restoring force (a decay whose ``restoring`` is set) the exact model is
the law's motion on that force (:func:`bayestribo.adequacy.restoring.chains`: the
first turning point inside |V'(Y)| <= μ_s), and its end is taken where the record's
would be detected: the last time the model's motion exceeds the record's threshold of
motion (:func:`_restoring_stop`); Eq. 38 is the linear spring's averaged motion and has
no counterpart there: it is not evaluated, and the statement says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.adequacy.draws import ParameterDraws
from bayestribo.adequacy.restoring import chains, first_turn, force_text, hermite, rest_grid
from bayestribo.errors import BayestriboError
from bayestribo.signal.decay import EnergyDecay
from bayestribo.summary import ParameterSummary, check_prob, interval_text

__all__ = ["ExtinctionCheck", "extinction_check"]


def _summary(values: NDArray) -> dict[str, Any]:
    finite = values[np.isfinite(values)]
    out: dict[str, Any] = {"fraction_finite": float(finite.size / max(values.size, 1))}
    if finite.size:
        lo, med, hi = np.quantile(finite, [0.025, 0.5, 0.975])
        out.update(median=float(med), interval=[float(lo), float(hi)])
    else:
        out.update(median=None, interval=None)
    return out


@dataclass(frozen=True)
class ExtinctionCheck:
    """Predicted and measured duration of the analysed motion.

    Attributes
    ----------
    measured : float or None
        Detected end of motion [s after the analysis start]; None when the record
        ends before the motion does.
    record_end : float
        End of the analysed window [s after the analysis start]: the record's end, or
        where the analysis was cut before it (a fade, a coarse or short record).
    averaged, exact : ndarray
        Predicted durations per draw [s] (``inf`` where the motion never stops):
        Eq. 38, and the exact model's end as the record's is detected.
    label : str
        Origin of the draws.
    resolution : float
        Time resolution of the detected end [s]: the reach of the velocity's line
        through which the end is refined, at least two sample periods (the end is the
        first sample of the rest tail); the prediction interval is widened by it.
    averaged_note : str
        Why Eq. 38 was not evaluated (a nonlinear restoring force: ``averaged`` is then
        NaN); empty when it was.
    alpha : float
        False-alarm rate of :meth:`consistent` on a record of the law: the measured end
        is tested against the central ``1 - alpha`` of the predictions (0.05: their
        95 % interval).
    """

    measured: float | None
    record_end: float
    averaged: NDArray
    exact: NDArray
    label: str
    resolution: float = 0.0
    averaged_note: str = ""
    alpha: float = 0.05

    @property
    def interval_text(self) -> str:
        """The prediction interval tested, in words (``95 %``, ``98.3 %``)."""
        return f"{100.0 * (1.0 - self.alpha):.3g} %"

    def quantile_of_measured(self, which: str = "exact") -> float | None:
        """Fraction of predicted durations below the measured one (None if not measured)."""
        if self.measured is None:
            return None
        pred = self.exact if which == "exact" else self.averaged
        return float(np.mean(pred < self.measured))

    def consistent(self, which: str = "exact") -> bool | None:
        """True when the measured end lies inside the central ``1 - alpha`` of the
        predictions, widened by :attr:`resolution`.

        Without a measured end: True when the predictions allow the motion to last
        beyond the record (at least ``alpha / 2`` of them do).
        """
        pred = self.exact if which == "exact" else self.averaged
        tail = 0.5 * self.alpha
        if self.measured is None:
            return bool(np.mean(pred > self.record_end) >= tail)
        finite = pred[np.isfinite(pred)]
        if finite.size == 0:
            return False
        lo, hi = np.quantile(finite, [tail, 1.0 - tail])
        return bool(lo - self.resolution <= self.measured <= hi + self.resolution)

    @property
    def statement(self) -> str:
        """One plain sentence."""
        ex = _summary(self.exact)
        av = _summary(self.averaged)

        def fmt(s: dict[str, Any]) -> str:
            if s["median"] is None:
                return "never stops"
            lo, hi = s["interval"]
            return f"{interval_text(s['median'], lo, hi)} s (median [95 %])"

        averaged = self.averaged_note or f"averaged Eq. 38 {fmt(av)}"
        pred = f"predicted end of motion: exact model {fmt(ex)}, {averaged}"
        if self.measured is None:
            return (
                f"{pred}; the analysis ends at {self.record_end:.4g} s with the motion going "
                f"on, {'consistent' if self.consistent() else 'not consistent'} with the "
                "prediction (the record ends in motion, or the analysis was cut before its "
                "end: a fade into the noise, a coarse or short record)"
            )
        verdict = "inside" if self.consistent() else "outside"
        return (
            f"{pred}; measured {self.measured:.4g} s, {verdict} the exact model's "
            f"{self.interval_text} interval"
        )

    def summary(self, prob: float = 0.95) -> dict[str, ParameterSummary]:
        """Summaries of the predicted durations [s] over the draws that stop.

        Parameters
        ----------
        prob : float
            Probability of the equal-tailed intervals, in (0, 1).

        Returns
        -------
        dict of str to ParameterSummary
            ``"exact"`` (the exact model's end as the record would show it: its last
            sample beyond the threshold of motion before its stop, Eq. 8) and
            ``"averaged"`` (Eq. 38), each over its finite durations; a model none of
            whose draws stops is left out (``to_dict()`` gives the finite fraction).
            The measured end is :attr:`measured`.
        """
        check_prob(prob)
        out = {}
        pairs = [("exact", self.exact), ("averaged", self.averaged)]
        if self.averaged_note:
            pairs = pairs[:1]
        for name, values in pairs:
            finite = values[np.isfinite(values)]
            if finite.size:
                out[name] = ParameterSummary.from_samples(finite, prob)
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``averaged_note`` only where Eq. 38 was not evaluated, its
        entries then None)."""
        out = {
            "measured_s": self.measured,
            "record_end_s": self.record_end,
            "exact": _summary(self.exact),
            "averaged": _summary(self.averaged),
            "quantile_of_measured_exact": self.quantile_of_measured("exact"),
            "quantile_of_measured_averaged": self.quantile_of_measured("averaged"),
            "consistent_exact": self.consistent("exact"),
            "consistent_averaged": self.consistent("averaged"),
            "resolution_s": self.resolution,
            "alpha": self.alpha,
            "draws": self.label,
            "statement": self.statement,
        }
        if self.averaged_note:
            out.update(
                averaged=None,
                quantile_of_measured_averaged=None,
                consistent_averaged=None,
                averaged_note=self.averaged_note,
            )
        return out


def extinction_check(
    decay: EnergyDecay, draws: ParameterDraws, *, seed: int | None = 0, alpha: float = 0.05
) -> ExtinctionCheck:
    """Predicted end of motion (Eq. 38 and the exact model) against the detected one.

    Parameters
    ----------
    decay : EnergyDecay
        The analysed decay; its start is the initial turning point of the draws.
    draws : ParameterDraws
        Parameter draws (posterior, or the labelled Gaussian stand-in).
    seed : int, optional
        Seed of the noise (and, on a nonlinear restoring force, the sampling phase)
        drawn on the model's motion before its end.
    alpha : float
        False-alarm rate of the check, in (0, 1): the measured end is tested against the
        central ``1 - alpha`` of the predictions (:meth:`ExtinctionCheck.consistent`).

    Returns
    -------
    ExtinctionCheck

    Raises
    ------
    BayestriboError
        ``alpha`` outside (0, 1).
    """
    from bayestribo.model import extinction_time

    if not (isinstance(alpha, (int, float)) and 0.0 < float(alpha) < 1.0):
        raise BayestriboError(f"alpha must be a number in (0, 1), got {alpha!r}")

    omega = decay.scaling.omega
    measured = decay.tau_end / omega if decay.motion_ended else None
    dt = float(np.median(np.diff(decay.t)))
    resolution = 2.0 * dt
    note = ""
    # the detected end is the last excursion's, moved to the root of the velocity's
    # line before it when that is within a third of the line's samples (motion_span):
    # the prediction, the last excursion, is known to as much
    period = 2.0 * decay.peaks.half_period
    resolution = max(resolution, (max(9, round(period / dt / 8.0)) // 3) * dt)
    if decay.restoring is None:
        tf = np.asarray(extinction_time(draws.y0, draws.zeta, draws.mu), dtype=float)
        ts = _linear_stop(decay, draws, np.random.default_rng(seed))
    else:
        ts = _restoring_stop(decay, draws, np.random.default_rng(seed))
        tf = np.full(ts.shape, np.nan)
        note = (
            f"averaged Eq. 38 not evaluated (the linear spring's averaged motion: it has "
            f"no form on {force_text(decay.restoring)}); the exact model's end is where "
            "its motion last exceeds the record's threshold of motion, or the end of the "
            "half cycle the record would show after it, as the record's is detected"
        )
    return ExtinctionCheck(
        measured=None if measured is None else float(measured),
        record_end=float(decay.tau_end / omega),
        averaged=tf / omega,
        exact=ts / omega,
        label=draws.label,
        resolution=resolution,
        averaged_note=note,
        alpha=float(alpha),
    )


#: How far past the record [record lengths] a draw's motion is followed to its stop.
RECORDS_FOLLOWED = 20.0

#: Half cycles before the stop searched for the last excursion beyond the detection
#: threshold.
LAST_HALF_CYCLES = 3


def _restoring_stop(decay: EnergyDecay, draws: ParameterDraws, rng: np.random.Generator) -> NDArray:
    """Each draw's end of motion [-] on the decay's nonlinear restoring force, as the
    record's is detected (:func:`bayestribo.signal.motion.motion_span`): the last
    sample at which its velocity, with the record's noise drawn on it, exceeds
    :data:`~bayestribo.signal.motion.THRESHOLD` times that noise (a recorded velocity),
    or its displacement departs from its rest by more than
    :data:`~bayestribo.signal.motion.DISPLACEMENT_THRESHOLD` times the displacement
    noise (a derived velocity); the samples at the record's rate, at a phase drawn per
    draw; moved to a turning point after it as the record's end is (:func:`_moved`);
    ``inf`` when the motion goes on past :data:`RECORDS_FOLLOWED` record lengths.

    The motion creeps into its stop (its acceleration there is the spring's force less
    the friction's, small on a slow oscillator): the last sample beyond the threshold
    comes before the stop, on a pendulum of 0.7 Hz with 4 mrad/s of noise by 0.1-0.8 s
    (the last half cycle's swing can stay under the threshold, or the noise lift it
    over), thousands of times the interval of the stop's own time.
    """
    kernel = decay.restoring
    sign0 = 1.0 if decay.peaks.value[0] >= 0.0 else -1.0
    span = float(decay.tau[-1] - decay.tau[0])
    turned, before = first_turn(decay, draws)
    chain = chains(kernel, turned, sign0, RECORDS_FOLLOWED * span, 1_000_000)
    chain = [(tn - b, yn, stopped) for (tn, yn, stopped), b in zip(chain, before, strict=True)]
    by_velocity, noise, level = _detection(decay)
    stopped = np.array([c[2] for c in chain])
    out = np.array([float(c[0][-1]) if c[2] else math.inf for c in chain])
    if not np.any(stopped) or level <= 0.0:
        return out
    dt = float(np.median(np.diff(decay.t))) * decay.scaling.omega  # sample period [-]
    phase = rng.uniform(0.0, dt, len(chain))
    rest = np.array([c[1][-1] for c in chain])
    found = np.zeros(len(chain), dtype=bool)
    at_back = np.zeros(len(chain), dtype=int)
    gate = _beside(decay) if by_velocity else None
    alone = _alone(decay)
    lobe = np.zeros((LAST_HALF_CYCLES, len(chain)), dtype=bool)
    at_out = np.zeros(len(chain))
    for back in range(1, LAST_HALF_CYCLES + 1):
        todo = stopped & ~found & np.array([c[1].size > back for c in chain])
        if not np.any(todo):
            break
        index = np.flatnonzero(todo)
        start = np.array([chain[i][1][-1 - back] for i in index])
        t0 = np.array([chain[i][0][-1 - back] for i in index])
        t1 = np.array([chain[i][0][-back] for i in index])
        h, y, yp, ypp = rest_grid(
            kernel.spring,
            start,
            -np.sign(start),
            draws.zeta[index],
            draws.mu[index],
            float(np.max(t1 - t0)),
        )
        # the record's samples inside this half cycle, and the channel there with noise
        first = np.mod(phase[index] - t0, dt)
        count = int(np.max(t1 - t0) / dt) + 2
        since = first[:, None] + dt * np.arange(count)[None, :]
        inside = since < (t1 - t0)[:, None]
        column = np.broadcast_to(np.arange(index.size)[:, None], since.shape)
        g = y.shape[0]
        if by_velocity:
            value = hermite(h, yp.reshape(g, -1), ypp.reshape(g, -1), since, column)
        else:
            value = hermite(h, y.reshape(g, -1), yp.reshape(g, -1), since, column)
            value = value - rest[index][:, None]
        value = value + noise * rng.standard_normal(value.shape)
        beyond = (np.abs(value) > level) & inside
        hit = beyond.any(axis=1)
        last = count - 1 - np.argmax(beyond[:, ::-1], axis=1)
        out[index[hit]] = (t0 + since[np.arange(index.size), last])[hit]
        found[index[hit]] = True
        at_back[index[hit]] = back
        if alone is not None and by_velocity:
            lobe[back - 1, index] = _lobe(value, inside, noise, alone)
        if gate is not None:
            lobe[back - 1, index] = _lobe(value, inside, noise, gate[1])
            rows = np.arange(index.size)[hit]
            at_last = since[rows, last[hit]][:, None]
            y_last = hermite(h, y.reshape(g, -1), yp.reshape(g, -1), at_last, rows[:, None])
            at_out[index[hit]] = y_last[:, 0] - rest[index[hit]]
    if gate is None:
        if alone is not None:
            # the last half cycle after the last excursion, its lobe seen
            index = np.flatnonzero((at_back == 2) & lobe[0])
            out[index] = np.array([chain[i][0][-1] for i in index])
        return out
    # the end moved from the last excursion to the turning point after it, or to the end
    # of the half cycle after that one, whose velocity the threshold missed
    for back in range(1, LAST_HALF_CYCLES + 1):
        index = np.flatnonzero(at_back == back)
        if index.size == 0:
            continue
        at_turn = np.array([chain[i][1][-back] for i in index]) - rest[index]
        at_next = np.zeros(index.size)
        seen = np.zeros(index.size, dtype=bool)
        if back > 1:
            at_next = np.array([chain[i][1][-back + 1] for i in index]) - rest[index]
            seen = lobe[back - 2, index]
        to_turn, to_next = _moved(at_out[index], at_turn, at_next, seen, gate, rng)
        out[index[to_turn]] = np.array([chain[i][0][-back] for i in index[to_turn]])
        out[index[to_next]] = np.array([chain[i][0][-back + 1] for i in index[to_next]])
    return out


def _detection(decay: EnergyDecay) -> tuple[bool, float, float]:
    """How the record's end of motion is detected: on the velocity (True, a recorded
    velocity) or on the displacement (False, a derived velocity); that channel's noise
    [-] and the threshold of motion [-] (:data:`~bayestribo.signal.motion.THRESHOLD`
    or :data:`~bayestribo.signal.motion.DISPLACEMENT_THRESHOLD` times the noise)."""
    from bayestribo.signal.motion import DISPLACEMENT_THRESHOLD, THRESHOLD

    by_velocity = decay.derived_channel != "velocity"
    noise = float((decay.noise_yp if by_velocity else decay.noise_y) or 0.0)
    return by_velocity, noise, (THRESHOLD if by_velocity else DISPLACEMENT_THRESHOLD) * noise


def _beside(decay: EnergyDecay) -> tuple[float, int] | None:
    """How a last half cycle missed by the velocity's threshold is found in the record
    (:func:`bayestribo.signal.motion._missed_half_cycle`): the displacement's noise [-]
    and the samples in an eighth of a period, where a displacement is recorded beside
    the velocity; None where it is not (a derived channel)."""
    if decay.derived_channel is not None or not decay.noise_y:
        return None
    dt = float(np.median(np.diff(decay.t)))
    size = max(8, round(4.0 * decay.peaks.half_period / dt))
    return float(decay.noise_y), max(3, round(size / 16.0))


def _alone(decay: EnergyDecay) -> int | None:
    """The samples in an eighth of a period where the record is a velocity alone whose
    end is found as :func:`bayestribo.signal.motion._missed_alone` finds it (one more
    half cycle where its lobe stands out of the noise of the velocity's mean); None
    otherwise."""
    if decay.derived_channel != "displacement":
        return None
    dt = float(np.median(np.diff(decay.t)))
    size = max(8, round(4.0 * decay.peaks.half_period / dt))
    return max(3, round(size / 16.0))


def _lobe(value: NDArray, inside: NDArray, noise: float, eighth: int) -> NDArray:
    """Per row: whether the mean of ``value`` (a half cycle's velocity at the record's
    samples, with noise) over ``eighth`` consecutive samples ``inside`` it exceeds
    :data:`~bayestribo.signal.motion.MISSED_THRESHOLD` times that mean's noise, as the
    record's missed half cycle is found."""
    from bayestribo.signal.motion import MISSED_THRESHOLD

    if value.shape[1] < eighth:
        return np.zeros(value.shape[0], dtype=bool)
    total = np.cumsum(np.where(inside, value, 0.0), axis=1)
    total = np.concatenate([np.zeros((value.shape[0], 1)), total], axis=1)
    mean = (total[:, eighth:] - total[:, :-eighth]) / eighth
    return np.any(np.abs(mean) > MISSED_THRESHOLD * noise / math.sqrt(eighth), axis=1)


def _moved(
    at_out: NDArray, at_turn: NDArray, at_next: NDArray, lobe: NDArray, gate: tuple[float, int], rng
) -> tuple[NDArray, NDArray]:
    """Where the record's end moves from its last excursion beyond the threshold, as
    :func:`bayestribo.signal.motion._missed_half_cycle` moves it: where the displacement
    there or at the turning point after it (``at_out``, ``at_turn``, about the rest; a
    median over an eighth of a period, noise drawn) is beyond
    :data:`~bayestribo.signal.motion.DISPLACEMENT_THRESHOLD` times its noise, to that
    turning point, or to the end of the half cycle after that one
    where its velocity lobe is seen (``lobe``); in either case only where the
    displacement at the new end (``at_turn``, ``at_next``) is within the threshold of
    the rest. Returns the masks of the draws moved to the turning point and to the end
    of the half cycle after it."""
    from bayestribo.signal.motion import DISPLACEMENT_THRESHOLD

    noise_y, eighth = gate
    limit = DISPLACEMENT_THRESHOLD * noise_y
    drawn = 1.25 * noise_y / math.sqrt(eighth) * rng.standard_normal(at_out.shape)
    # the displacement's farthest from the rest from the excursion on: there, or at the
    # turning point after it
    farthest = np.where(np.abs(at_out) > np.abs(at_turn), at_out, at_turn)
    off = np.abs(farthest + drawn) > limit
    to_next = off & lobe & (np.abs(at_next) <= limit)
    to_turn = off & ~lobe & (np.abs(at_turn) <= limit)
    return to_turn, to_next


#: At most this many values of the model's motion evaluated at once by
#: :func:`_linear_stop` (draws times samples).
CHUNK_VALUES = 1_000_000


def _linear_stop(decay: EnergyDecay, draws: ParameterDraws, rng: np.random.Generator) -> NDArray:
    """Each draw's end of motion [-] on the linear spring, as the record's is detected
    (:func:`bayestribo.signal.motion.motion_span`): the last of the record's samples
    (τ = k·Δτ from the decay's first one) at which the exact model's velocity, with the
    record's noise drawn on it, exceeds the threshold of motion (a recorded velocity),
    or its displacement departs from its rest by more than the displacement's
    threshold (a derived velocity); searched over the :data:`LAST_HALF_CYCLES` half
    cycles before the stop (the stop itself when none exceeds it there), moved to a
    turning point after it as the record's end is (:func:`_moved`); ``inf`` for a draw
    that never stops.

    The model starts where the fits start it (:func:`~bayestribo.adequacy.segments.
    whole_decay_fit`, the Bayesian likelihood): at the decay's first sample, at ``y0``
    with the recorded velocity there, its turning point before it located by the
    exact model (Eq. 16-17 with y'₀).
    """
    from bayestribo.model import exact_response, rest_position, stop_time

    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    yp0 = float(decay.yp[0])
    y0 = sign * np.abs(np.asarray(draws.y0, dtype=float))
    zeta, mu = np.asarray(draws.zeta, dtype=float), np.asarray(draws.mu, dtype=float)
    mu_s = np.maximum(np.asarray(draws.mu_s, dtype=float), mu)
    out = np.asarray(stop_time(y0, zeta, mu, mu_s, yp0), dtype=float).copy()
    by_velocity, noise, level = _detection(decay)
    stopped = np.flatnonzero(np.isfinite(out))
    if stopped.size == 0 or level <= 0.0:
        return out
    rest = np.asarray(rest_position(y0, zeta, mu, mu_s, yp0), dtype=float)
    dt = float(np.median(np.diff(decay.t))) * decay.scaling.omega  # sample period [-]
    back = LAST_HALF_CYCLES * np.pi / np.sqrt(1.0 - zeta * zeta)
    first = np.maximum(np.ceil((out - back) / dt), 0.0)
    last = np.floor(out / dt)
    count = int(np.max((last - first)[stopped])) + 1
    step = max(1, CHUNK_VALUES // count)
    for lo in range(0, stopped.size, step):
        rows = stopped[lo : lo + step]
        k = first[rows][:, None] + np.arange(count)[None, :]
        inside = k <= last[rows][:, None]
        y, yp = exact_response(
            k * dt,
            y0[rows][:, None],
            zeta[rows][:, None],
            mu[rows][:, None],
            mu_s[rows][:, None],
            yp0,
        )
        value = yp if by_velocity else y - rest[rows][:, None]
        value = value + noise * rng.standard_normal(value.shape)
        beyond = (np.abs(value) > level) & inside
        hit = beyond.any(axis=1)
        at = count - 1 - np.argmax(beyond[:, ::-1], axis=1)
        out[rows[hit]] = k[np.flatnonzero(hit), at[hit]] * dt
    gate = _beside(decay) if by_velocity else None
    alone = _alone(decay)
    if gate is None and alone is None:
        return out
    # a half cycle after the last excursion, missed by the threshold, found in the
    # displacement beside the velocity: the end moves to its end (turning points are
    # half a damped period apart, Eq. 13)
    half = np.pi / np.sqrt(1.0 - zeta * zeta)
    ends = np.asarray(stop_time(y0, zeta, mu, mu_s, yp0), dtype=float)
    rows = np.flatnonzero(np.isfinite(ends) & (out < ends))
    if rows.size == 0:
        return out
    # the turning point after the last excursion, and the half cycle after it
    turn = ends[rows] - np.floor((ends[rows] - out[rows]) / half[rows]) * half[rows]
    after = np.minimum(turn + half[rows], ends[rows])
    args = (y0[rows], zeta[rows], mu[rows], mu_s[rows], yp0)
    at_out = exact_response(out[rows], *args)[0] - rest[rows]
    at_turn = exact_response(turn, *args)[0] - rest[rows]
    at_next = exact_response(after, *args)[0] - rest[rows]
    first = np.ceil(turn / dt)
    count = int(np.max(np.floor(after / dt) - first)) + 1
    k = first[:, None] + np.arange(max(count, 1))[None, :]
    column = tuple(a[:, None] if np.ndim(a) else a for a in args)
    _, yp = exact_response(k * dt, *column)
    inside = k * dt <= after[:, None]
    eighth = gate[1] if gate is not None else int(alone or 3)
    lobe = _lobe(yp + noise * rng.standard_normal(yp.shape), inside, noise, eighth)
    lobe &= turn < ends[rows]
    if gate is None:
        # a velocity alone: its last half cycle, its lobe seen
        last = lobe & (after >= ends[rows])
        out[rows[last]] = after[last]
        return out
    to_turn, to_next = _moved(at_out, at_turn, at_next, lobe, gate, rng)
    # where the displacement does not move it, the velocity's lobe alone does, as it
    # would a velocity recorded alone (the record's end likewise)
    last = ~to_turn & ~to_next & lobe & (after >= ends[rows])
    out[rows[to_turn]] = turn[to_turn]
    out[rows[to_next]] = after[to_next]
    out[rows[last]] = after[last]
    return out
