"""The period of a record's oscillation: the one estimator every part of the package uses.

The readers' checks (the frequency behind a unit hint, the windows of the channel
comparison), the derivative behind a zero-crossing frequency and the energy decay's
search distances and fit windows all take the record's period from
:func:`dominant_period`. It is rough by design (a few parts in 1e4 from the spectral
peak's interpolation); the precise frequency of a decay comes from its turning times
(:func:`bayestribo.signal.frequency.oscillation_frequency`,
:attr:`bayestribo.signal.decay.EnergyDecay.natural_frequency_Hz`).

A run's arrays are read-only: the period of one is computed once and remembered
while the array lives (reading a file, its checks and the preparation of a fit ask
for it three times), and so is the median step of its time stamps
(:func:`sample_step`, asked for a dozen times).
"""

from __future__ import annotations

import math
import weakref

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError

__all__ = [
    "CANDIDATES",
    "CANDIDATE_PERIODS",
    "MIN_PERIOD_SAMPLES",
    "PADDING",
    "POWER_RATIO",
    "dominant_period",
    "sample_step",
]

#: Spectral peaks of each ranking examined as the oscillation by :func:`dominant_period`.
CANDIDATES = 6
#: A candidate replaces the strongest peak of the difference's spectrum only when its
#: oscillation in the signal itself has at least this many times the power (10: the
#: amplitude 3.2 times larger; a mains line or the noise at Nyquist is 1e-3 to 1e-5
#: of a free decay's power, a sidelobe of the decay's own peak a fraction of it).
POWER_RATIO = 10.0
#: Fewest periods a candidate of :func:`dominant_period` must fit in the record.
CANDIDATE_PERIODS = 3.0
#: Fewest samples per period of an oscillation whose turning points can be located
#: (:func:`bayestribo.signal.decay.energy_decay` refuses a shorter dominant period): a
#: shorter peak found first is weighed against the peaks above this floor
#: (:func:`_above_floor`).
MIN_PERIOD_SAMPLES = 6


def _oscillation_power(s: NDArray, period: float, dt: float, block: float | None = None) -> float:
    """Largest power [signal unit²] of a sinusoid at ``period`` [s] in ``s``, over blocks.

    ``s`` is sampled every ``dt`` [s]. Blocks of two periods (at least 16 samples, at
    most the record; the last one ends with the record), each detrended by a line: the
    variance the sinusoid explains beyond the line, about half its squared amplitude.
    A level that differs between the rest and the motion, or a drift, is a line in a
    block and is not counted; a line of the noise is counted at its (small) amplitude
    in the signal, not amplified by a difference. ``block`` [s], when given, sets the
    blocks to two of its periods instead (two candidates weighed on the same blocks).
    """
    size = min(s.size, max(16, round(2.0 * (period if block is None else block) / dt)))
    u = (np.arange(size) - 0.5 * (size - 1)) * dt  # centred: 1 and u are orthogonal
    # rows, each detrended by the line (1, u): an (n, 2) @ (2, 2) product took numpy
    # 60 ms at 250,000 samples, the subtractions below a few. cos is even and sin odd
    # about the centre: half the samples are mirrored, not computed.
    wave = np.empty((2, size))
    half = size // 2
    phase = 2.0 * math.pi * u[half:] / period
    np.cos(phase, out=wave[0, half:])
    np.sin(phase, out=wave[1, half:])
    wave[0, :half] = wave[0, size - 1 : size - 1 - half : -1]
    wave[1, :half] = -wave[1, size - 1 : size - 1 - half : -1]
    wave -= wave.mean(axis=1, keepdims=True)
    # products of two rows, by einsum rather than BLAS: a threaded BLAS waits for a
    # second core that a shared machine gives late (20 ms instead of 2 here)
    slope = np.einsum("ij,j->i", wave, u) / float(np.einsum("i,i->", u, u))
    wave[0] -= slope[0] * u
    wave[1] -= slope[1] * u
    # the explained variance of coefficients c = W⁺b is bᵀW (WᵀW)⁺ Wᵀb; at Nyquist
    # one column of W vanishes and the pseudo-inverse drops it
    gram_inv = np.linalg.pinv(np.einsum("ij,kj->ik", wave, wave), rcond=1e-9)
    m = s.size // size
    projected = [np.einsum("ij,kj->ik", s[: m * size].reshape(m, size), wave)]
    if m * size < s.size:
        projected.append(np.einsum("j,kj->k", s[-size:], wave)[None, :])
    best = 0.0
    (g00, g01), (g10, g11) = gram_inv.tolist()
    for p in projected:
        # the quadratic form pᵀ G p of each block written out: einsum's three-operand
        # form took 2.5 ms for the 62,500 blocks of 16 samples of a 1 MHz record, this
        # 0.3 ms
        a, b = p[:, 0], p[:, 1]
        best = max(best, float(np.max(a * (g00 * a + g01 * b) + b * (g10 * a + g11 * b))))
    return best / size


#: How much of the quarter squared range of a signal :func:`_unbeatable` allows a
#: candidate's computed power beyond the exact bound (rounding: none measurable).
_CEILING_MARGIN = 2.0
#: Largest ratio of a signal's magnitude to its range for which :func:`_unbeatable`
#: holds (a larger offset would make the rounding of the blocks' sums count).
_OFFSET_RATIO = 1e3


def _unbeatable(s: NDArray, power_k: float) -> bool:
    """Whether no candidate of :func:`_strongest_oscillation` can have
    :data:`POWER_RATIO` times the power ``power_k`` of the strongest peak.

    The power of any sinusoid in a block (:func:`_oscillation_power`: the variance its
    fit explains beyond the block's line) is at most the block's variance about its
    mid-range, a quarter of its squared range, so at most a quarter of the signal's
    squared range. When :data:`_CEILING_MARGIN` times that is within the ratio of
    ``power_k``, the strongest peak stands whatever the candidates' powers are: they
    are not computed (a free decay's: its largest swing is the record's range).
    """
    hi, lo = float(np.max(s)), float(np.min(s))
    spread = hi - lo
    ceiling = 0.25 * spread * spread
    return (
        math.isfinite(ceiling)
        and max(abs(hi), abs(lo)) <= _OFFSET_RATIO * spread
        and _CEILING_MARGIN * ceiling <= POWER_RATIO * power_k
    )


def _strongest_oscillation(t: NDArray, s: NDArray, spec: NDArray, k: int, n: int, dt: float) -> int:
    """Bin of the candidate peak of ``spec`` (the difference's spectrum, padded to
    ``n``) whose oscillation is strongest in ``s`` (see :func:`dominant_period`);
    ``k`` is the spectrum's highest bin."""
    inner = spec[1:-1]
    local = np.flatnonzero((inner >= spec[:-2]) & (inner > spec[2:])) + 1
    # only periods of which the record holds three, the fewest oscillations a fit
    # needs (in the signal's own spectrum a step leaks in below them)
    short = local[n * dt / local <= float(t[-1] - t[0]) / CANDIDATE_PERIODS]
    gain = np.abs(2.0 * np.sin(math.pi * short / n))  # of the difference, at each bin
    candidates = {k}
    for ranked, pool in (
        (spec[short], short),
        (spec[short] / np.sqrt(gain), short),
        (spec[short] / gain, short),
    ):
        if pool.size > CANDIDATES:
            pool = pool[np.argpartition(ranked, -CANDIDATES)[-CANDIDATES:]]
        candidates.update(pool.tolist())
    power = {k: _oscillation_power(s, n * dt / k, dt)}
    if _unbeatable(s, power[k]):
        return _above_floor(s, spec, k, short, n, dt)
    power.update({c: _oscillation_power(s, n * dt / c, dt) for c in candidates - {k}})
    strongest = max(power.values())
    if strongest <= POWER_RATIO * power[k]:
        return _above_floor(s, spec, k, short, n, dt)
    kept = [c for c in candidates if POWER_RATIO * power[c] >= strongest]
    return _above_floor(s, spec, int(max(kept, key=lambda c: spec[c])), short, n, dt)


def _above_floor(s: NDArray, spec: NDArray, k: int, peaks: NDArray, n: int, dt: float) -> int:
    """Bin ``k``, or the peak above :data:`MIN_PERIOD_SAMPLES` samples per period whose
    oscillation in ``s`` carries :data:`POWER_RATIO` times the power of ``k``'s.

    A peak of fewer samples per period than that is no free decay's, but the noise of
    a coarse digitiser can make it: white noise of a fraction of a step before the
    rounding (dither) toggles the record between two levels at rest and at every level
    crossing, a spectrum rising to Nyquist that the difference gains further. Its
    power in the signal, over blocks of 16 samples (:func:`_oscillation_power`), comes
    from the few blocks at a crossing, within ten of the oscillation's over its blocks
    of two periods at 3 to 5 steps across the swing. Here the two are weighed on the
    same blocks, the floor peak's: measured on simulated 3- to 5-step records (noise
    0.05 to 0.2 step), the oscillation 100 to 3,000 times the toggling's power; on
    white or dithered noise alone the best floor peak 0.7 to 1.8 times the short
    one's, which then stays (and the record is refused as holding no oscillation).
    The floor peaks are the strongest :data:`CANDIDATES` of each ranking of
    :func:`_strongest_oscillation` among ``peaks`` (the spectrum's local maxima of
    periods the record holds three of) and are chosen among as there.
    """
    if n / k >= MIN_PERIOD_SAMPLES:
        return k
    floor = peaks[n / peaks >= MIN_PERIOD_SAMPLES]
    if not floor.size:
        return k
    gain = np.abs(2.0 * np.sin(math.pi * floor / n))
    candidates: set[int] = set()
    for ranked in (spec[floor], spec[floor] / np.sqrt(gain), spec[floor] / gain):
        pool = floor
        if pool.size > CANDIDATES:
            pool = pool[np.argpartition(ranked, -CANDIDATES)[-CANDIDATES:]]
        candidates.update(pool.tolist())
    power = {c: _oscillation_power(s, n * dt / c, dt) for c in candidates}
    best = max(power, key=power.__getitem__)
    # every peak weighed on the strongest one's blocks: on blocks of 16 samples the
    # toggling near a level crossing scores within ten of the oscillation
    block = n * dt / best
    if power[best] <= POWER_RATIO * _oscillation_power(s, n * dt / k, dt, block=block):
        return k
    same = {c: _oscillation_power(s, n * dt / c, dt, block=block) for c in candidates}
    kept = [c for c in candidates if POWER_RATIO * same[c] >= same[best]]
    return int(max(kept, key=lambda c: spec[c]))


def dominant_period(time: ArrayLike, values: ArrayLike) -> float:
    """Period [s] of a record's oscillation, from the spectrum of its first difference.

    Among the strongest spectral peaks of the difference, the one whose oscillation
    carries the most power in the signal itself (see :func:`_spectral_period`: a mains
    line or the noise at Nyquist, gained by the difference, is not taken for the
    oscillation; a rest before the release or a drift is not either).

    Parameters
    ----------
    time : array_like
        Sample times [s], increasing and (near) regular.
    values : array_like
        Displacement, velocity or any signal of the motion (any unit).

    Returns
    -------
    float
        The period [s].

    Raises
    ------
    RecordingError
        When the signal does not oscillate (a flat spectrum: constant or linear).

    Notes
    -----
    The result for two read-only arrays that own their data (a
    :class:`~bayestribo.io.run.Run`'s) is remembered while they live.
    """
    t = np.asarray(time, dtype=np.float64)
    s = np.asarray(values, dtype=np.float64)
    if t.shape != s.shape or t.ndim != 1 or t.size < 4:
        raise RecordingError(
            f"the period needs two 1-D arrays of the same length (at least 4 samples), got "
            f"shapes {t.shape} and {s.shape}"
        )
    return _remembered("period", (t, s), _spectral_period)


def sample_step(time: ArrayLike, steps: NDArray | None = None) -> float:
    """Median spacing of sample times [s].

    Parameters
    ----------
    time : array_like
        Sample times [s], at least two.
    steps : ndarray, optional
        ``np.diff(time)`` when the caller has it already (not computed again).

    Returns
    -------
    float
        ``median(diff(time))`` [s]; remembered for a read-only array that owns its
        data (a :class:`~bayestribo.io.run.Run`'s time stamps, which the checks of a
        file and the preparation of a fit ask for a dozen times).
    """
    t = np.asarray(time, dtype=np.float64)
    if steps is not None and steps.shape != (max(t.size - 1, 0),):
        raise RecordingError(f"steps: expected np.diff(time), got shape {steps.shape}")
    return _remembered(
        "step", (t,), lambda t: float(np.median(np.diff(t) if steps is None else steps))
    )


#: Values computed from read-only arrays, by what and the arrays' ids, while they live.
_REMEMBERED: dict[tuple, tuple[tuple[weakref.ref, ...], float]] = {}


def _remembered(what: str, arrays: tuple[NDArray, ...], compute) -> float:
    """``compute(*arrays)``, remembered while the arrays live when all are frozen."""
    if not all(_frozen(a) for a in arrays):
        return compute(*arrays)
    key = (what, *map(id, arrays))
    cached = _REMEMBERED.get(key)
    if cached is not None and all(r() is a for r, a in zip(cached[0], arrays, strict=True)):
        return cached[1]
    value = compute(*arrays)

    def forget(_: object, key: tuple = key) -> None:
        _REMEMBERED.pop(key, None)

    _REMEMBERED[key] = (tuple(weakref.ref(a, forget) for a in arrays), value)
    return value


def _frozen(a: NDArray) -> bool:
    """A read-only array that owns its data: no view of it can change it."""
    return not a.flags.writeable and a.flags.owndata


#: Zero padding of the difference's spectrum (the fine grid of :func:`_spectral_period`):
#: its bins are 1/4 of the record's spectral resolution apart.
PADDING = 4
#: Samples per row of the tables of :func:`_fine_spectrum` (a record of n samples is
#: summed as about n/ROW rows of ROW samples).
_ROW = 1024


def _fine_spectrum(x: NDArray, bins: NDArray, n: int) -> NDArray:
    """``|rfft(x, n)[bins]|``, only at ``bins``, by direct sums with tables of e^{-iφ}.

    With ``x[j]`` at ``j = c·R + r`` (R = :data:`_ROW`), e^{-2πi k j/n} is the product of
    a row phase e^{-2πi k c R/n} and a column phase e^{-2πi k r/n}: two small tables
    per bin (phases reduced modulo n in integers, so they are exact for any record
    length), and the sum is a real matrix product of the rows with the column table.
    At 1,000,000 samples and 5 bins: about 10 ms, against 170 ms for the whole padded
    transform (4,194,304 points) whose bins they are.
    """
    rows = x.size // _ROW
    k = bins.astype(np.int64)[:, None]
    column = np.exp((-2j * math.pi / n) * ((k * np.arange(_ROW)) % n))
    row = np.exp((-2j * math.pi / n) * ((k * (_ROW * np.arange(rows + 1))) % n))
    block = x[: rows * _ROW].reshape(rows, _ROW)
    # one real product with the tables' real and imaginary parts stacked, by einsum:
    # a threaded BLAS waiting for a busy second core took 3 to 5 times as long
    parts = np.einsum("ij,kj->ik", block, np.concatenate([column.real, column.imag]))
    inner = parts[:, : bins.size] + 1j * parts[:, bins.size :]  # (rows, bins)
    total = np.einsum("kc,ck->k", row[:, :rows], inner)
    rest = x[rows * _ROW :]
    if rest.size:
        total += row[:, rows] * (column[:, : rest.size] @ rest)
    return np.abs(total)


def _spectral_period(t: NDArray, s: NDArray) -> float:
    """Period [s] of the record's oscillation: a spectral peak of the signal's first
    difference, the one carrying the most power in the signal itself.

    The difference turns a step (rest before the release, a drift) into a spike with a
    flat spectrum, so the oscillation's peak dominates. No taper: a free decay is
    concentrated at the start of the record, which a taper would suppress. The period
    only sets search distances and fit windows.

    The difference also multiplies the spectrum by the frequency, so a record sampled
    far faster than it oscillates can have a higher peak elsewhere. Measured on the
    AppStat2020 HarmOsc3 recording (1.47 Hz at 1 kHz), a 150 Hz mains harmonic of
    about 3e-3 signal units gained a hundredfold: in the whole record the oscillation
    peak still stood out, but in the half after t = 5.75 s (amplitude 0.5 to 0.06)
    the line did, the analysis ran at a 6.7 ms period, and the turning points were
    refused ("found 0 usable extrema"); in the second half of HarmOsc2 (100 Hz) the
    white noise at Nyquist did ("dominant period is 2.0 samples"). A record that
    starts in motion has no rest before it to make up for this: its oscillation is
    the smaller, the later it starts.

    So the strongest peaks of three rankings are candidates: the difference's spectrum
    (the velocity), its spectrum divided by the difference's gain ``|2 sin(πf dt)|``
    (the signal's own spectrum, where a step leaks in at low frequency) and by the
    gain's square root; each candidate is scored by the power of its oscillation in the
    signal itself (:func:`_oscillation_power`, blocks of two periods each detrended by
    a line, so neither a step nor a drift counts). The strongest peak of the
    difference stands, as before, unless a candidate has :data:`POWER_RATIO` times its
    power; then the strongest peak of the difference among the candidates within
    that ratio of the best power is taken (a sidelobe of the oscillation's own peak
    scores nearly as high but is weaker in the spectrum).

    The peaks are looked for in the spectrum at the record's own resolution (a
    transform at a fast length at least the record's); the chosen peak is then
    located on the grid of the transform zero-padded to :data:`PADDING` times the
    power of two at least the record's length (its bins computed only around the
    peak by :func:`_fine_spectrum`) and interpolated there by a parabola through the
    logarithms of three bins. At 1 MHz × 1 s: 40 ms instead of 170 ms for the
    padded transform, and the same period to about 1e-12 whenever the peak chosen
    is the same one.
    """
    dt = sample_step(t)
    x = np.diff(s)
    x -= np.mean(x)
    # the record's own spectrum at a fast transform length (1,000,000 points for a
    # 1 MHz record: 12 ms, against 19 ms padded to 2^20), the fine grid as before
    m = scipy.fft.next_fast_len(x.size, real=True)
    n = PADDING * (1 << math.ceil(math.log2(s.size)))
    spec = np.abs(np.fft.rfft(x, m))
    spec[0] = 0.0
    k = int(np.argmax(spec))
    if not math.isfinite(spec[k]):  # the largest bin, or the first NaN
        raise _overflow(s)
    if k == 0 or spec[k] == 0.0:
        raise RecordingError("the signal does not oscillate (flat spectrum)")
    k = _strongest_oscillation(t, s, spec, k, m, dt)
    # the fine bins around the peak, climbing to a local maximum of the fine grid
    top = n // 2
    centre = float(k)
    if 0 < k < spec.size - 1:  # where the coarse bins' parabola puts the peak
        a, b, c = np.log(spec[k - 1 : k + 2] + 1e-300)
        den = a - 2 * b + c
        centre += 0.5 * (a - c) / den if den < 0 else 0.0
    fine = min(top, round(centre * n / m))
    for _ in range(16):
        # five bins about it, the window shifted while the maximum is at its edge
        bins = np.arange(max(0, fine - PADDING // 2), min(top, fine + PADDING // 2) + 1)
        values = _fine_spectrum(x, bins, n)
        values[bins == 0] = 0.0  # as the record's mean, left out
        best = int(np.argmax(values))
        fine = int(bins[best])
        if 0 < best < bins.size - 1 or fine in (0, top):
            break
    kf = float(fine)
    if 0 < fine < top and 0 < best < bins.size - 1:
        a, b, c = np.log(values[best - 1 : best + 2] + 1e-300)
        den = a - 2 * b + c
        kf = fine + (0.5 * (a - c) / den if den != 0 else 0.0)
    period = float(n * dt / kf)
    if not (math.isfinite(period) and period > 0):
        raise _overflow(s)
    return period


def _overflow(s: NDArray) -> RecordingError:
    """The error of a signal whose spectrum overflows (values near the largest float)."""
    largest = float(np.max(np.abs(s)))
    return RecordingError(
        f"the signal's values (up to {largest:.3g}) overflow the arithmetic of its spectrum; "
        "expected the magnitudes of a motion in the stated units"
    )
