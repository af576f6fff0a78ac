r"""Noise at rest as a spectrum: Welch estimate, mains lines, colour, autocovariance, notch.

A real signal chain does not add white noise. The anti-alias filter of the acquisition
card (a 4th-order Butterworth at 2 kHz, say) keeps only part of the band, the mains add
a line at 50 or 60 Hz, and electronics add 1/f noise. The level of the noise at rest
(:class:`bayestribo.signal.decay.NoiseLevels`) is then not enough: what the Π increments
see is the noise near the oscillation frequency, and noise correlated across samples adds
up differently from white noise. This module measures it:

* :func:`noise_spectrum`: one-sided power spectral density of the noise on the rest
  segment(s) of one channel (Welch, Hann window, the segment's mean removed; segments of
  any length share one frequency grid by zero padding, and are averaged weighted by their
  samples), with the mains line(s) found in it and a flag for noise that is not white
  in the band the increments see;
* :meth:`NoiseSpectrum.autocovariance`: the noise's autocovariance at sample lags, the
  inverse Fourier transform of the PSD (Wiener-Khinchin), from which the variance of a
  weighted sum of noisy samples is ``wᵀ C w`` (:mod:`bayestribo.signal.increments`);
* :func:`notch_filter`: removal of a mains line from both channels, zero phase.

References: P. D. Welch (1967), IEEE Trans. Audio Electroacoust. 15(2), 70-73 (averaged
modified periodograms); Rigaud et al. (2010) for the tribometer.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.period import sample_step

__all__ = [
    "COLOUR_FALSE_ALARM",
    "LINE_FALSE_ALARM",
    "LINE_RATIO",
    "LJUNG_BOX_LAGS",
    "MAINS_HZ",
    "WHITE_P",
    "NoiseSpectrum",
    "RestNoise",
    "band_bounds",
    "colored_noise",
    "fit_line",
    "line_threshold",
    "noise_spectrum",
    "notch_filter",
    "notch_gain",
]

#: Mains frequencies looked for in the rest spectrum [Hz].
MAINS_HZ: tuple[float, ...] = (50.0, 60.0)
#: A line is a peak of the PSD at least this many times the median of its
#: neighbourhood, and more where the PSD is too coarse an estimate for that ratio to be
#: rare in white noise (:func:`line_threshold`).
LINE_RATIO = 10.0
#: Chance that white noise shows a line at one candidate frequency of one channel
#: (:func:`line_threshold`): with six candidates and two channels, about one white
#: record in a thousand, as :data:`WHITE_P`.
LINE_FALSE_ALARM = 1e-4
#: Lags of the Ljung-Box test of whiteness, and the p-value below which it calls the
#: noise coloured (one white record in a thousand is then treated as coloured: its
#: increment variances come from its spectrum, still unbiased).
LJUNG_BOX_LAGS = 10
WHITE_P = 1e-3
#: Noise is called coloured when the PSD in the signal band differs from the flat level
#: of white noise of the same variance by more than this factor, and by more than white
#: noise's band level does with chance :data:`COLOUR_FALSE_ALARM` (:func:`band_bounds`).
COLOUR_FACTOR = 1.25
#: Two-sided chance that white noise's band level falls outside :func:`band_bounds`:
#: that of a normal estimate beyond four standard errors, 2Φ(-4).
COLOUR_FALSE_ALARM = 6.334248366623973e-05


@dataclass(frozen=True)
class NoiseSpectrum:
    """Power spectral density of one channel's noise at rest.

    Attributes
    ----------
    frequency : ndarray
        Frequencies [Hz], 0 to the Nyquist frequency.
    psd : ndarray
        One-sided PSD [unit²/Hz] (``sum(psd) * df`` is the variance).
    sample_rate_Hz : float
        Sampling rate [Hz].
    variance : float
        Variance of the noise, the integral of the PSD [unit²].
    white_level : float
        One-sided PSD [unit²/Hz] that white noise of the same variance, lines
        excluded, would have: ``2 var / fs``.
    band_level : float
        Mean PSD [unit²/Hz] over the signal band (0, ``band_Hz``], lines excluded.
    band_Hz : float
        Upper end of the signal band [Hz]: the frequencies the Π increments see.
    lines_Hz : tuple of float
        Mains lines found (frequency of each peak [Hz]).
    line_rms : tuple of float
        Root-mean-square amplitude of each line [unit].
    coloured : bool
        True when the noise is not white: in the signal band (``band_level`` off
        ``white_level`` by more than :data:`COLOUR_FACTOR` and outside the range white
        noise's estimate keeps with chance 1 - :data:`COLOUR_FALSE_ALARM`,
        :func:`band_bounds` of ``band_rel_se``),
        by the Ljung-Box test (``white_p``), or because it carries a line: its
        samples are then correlated and the increments' variances need the
        autocovariance, not the variance alone.
    n_samples : int
        Samples at rest used.
    n_averages : float
        Equivalent number of independent periodograms averaged (sets the estimate's
        relative standard error, about 1/√(n_averages · bins averaged)).
    white_p : float
        p-value of the Ljung-Box test of whiteness on the first
        :data:`LJUNG_BOX_LAGS` autocorrelations of the rest samples (each segment
        about its mean): below :data:`WHITE_P` the noise is called coloured too. It
        sees a filter or 1/f noise (lag-1 autocorrelation 0.7 for a 2 kHz filter at
        10 kHz) in far fewer samples than the band level does.
    band_rel_se : float
        Relative standard error of ``band_level``, 1/√(n_averages · independent
        bins) (bins closer than 1.5 resolutions of the window counted as one), about that
        of the increments' variances computed from this spectrum: a short rest
        (0.1 s before and after a 32.6 Hz decay) knows them to about ±30 %.
    """

    frequency: NDArray
    psd: NDArray
    sample_rate_Hz: float
    variance: float
    white_level: float
    band_level: float
    band_Hz: float
    lines_Hz: tuple[float, ...]
    line_rms: tuple[float, ...]
    coloured: bool
    n_samples: int
    n_averages: float
    white_p: float = 1.0
    band_rel_se: float = 0.0

    @property
    def sigma(self) -> float:
        """Standard deviation of the noise per sample [unit]."""
        return math.sqrt(self.variance)

    @property
    def colour_ratio(self) -> float:
        """``band_level / white_level``: 1 for white noise, < 1 for filtered noise."""
        return self.band_level / self.white_level if self.white_level > 0 else math.nan

    def autocovariance(self, n_lags: int | None = None) -> NDArray:
        """Autocovariance of the noise at lags of 0, 1, ... samples [unit²].

        The inverse real FFT of the two-sided PSD (Wiener-Khinchin theorem); lag 0 is
        :attr:`variance`. Lags beyond the Welch segment are not resolved by the
        estimate and are returned as 0.

        Parameters
        ----------
        n_lags : int, optional
            Number of lags returned (default: half the FFT length).
        """
        nfft = 2 * (self.psd.size - 1)
        x = self.psd * (self.sample_rate_Hz / 2.0)
        x[0] *= 2.0
        x[-1] *= 2.0
        c = np.fft.irfft(x, nfft)[: nfft // 2]
        if n_lags is None:
            return c
        out = np.zeros(int(n_lags))
        m = min(int(n_lags), c.size)
        out[:m] = c[:m]
        return out


@dataclass(frozen=True)
class RestNoise:
    """Noise spectra of both channels, measured on the same rest segment(s).

    Attributes
    ----------
    displacement, velocity : NoiseSpectrum or None
        Each recorded channel's spectrum (``None`` for a derived channel or without
        rest to measure).
    source : str
        The segments used (``"rest before release"``, ``"rest after stop"`` or both).
    """

    displacement: NoiseSpectrum | None
    velocity: NoiseSpectrum | None
    source: str

    @property
    def coloured(self) -> bool:
        """True when either channel's noise is coloured (see :class:`NoiseSpectrum`)."""
        return any(s is not None and s.coloured for s in (self.displacement, self.velocity))

    @property
    def lines_Hz(self) -> tuple[float, ...]:
        """Mains lines found in either channel [Hz], sorted, duplicates merged."""
        found: list[float] = []
        for s in (self.displacement, self.velocity):
            if s is None:
                continue
            for f in s.lines_Hz:
                if all(abs(f - g) > 1.0 for g in found):
                    found.append(f)
        return tuple(sorted(found))

    def mains_Hz(self) -> float | None:
        """The mains frequency (one of :data:`MAINS_HZ`) of the lines found, or None."""
        for f in self.lines_Hz:
            for mains in MAINS_HZ:
                if abs(f - mains) <= max(1.0, 0.02 * mains):
                    return mains
        return None


def _segments(signal: NDArray, mask: NDArray) -> list[NDArray]:
    """Contiguous runs of ``signal`` where ``mask`` is True."""
    m = np.asarray(mask, bool)
    edges = np.flatnonzero(np.diff(np.r_[0, m.astype(np.int8), 0]))
    return [signal[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _around(freq: NDArray, centre: float, reach: float) -> slice:
    """The bins of the increasing grid ``freq`` that can lie within ``reach`` of
    ``centre``, and one more on each side: a test ``|freq - centre| <= r`` (r at most
    ``reach``) gives on them what it gives on the whole grid, False elsewhere."""
    lo = int(np.searchsorted(freq, centre - reach, side="left")) - 1
    hi = int(np.searchsorted(freq, centre + reach, side="right")) + 1
    return slice(max(lo, 0), min(hi, freq.size))


@functools.lru_cache(maxsize=256)
def line_threshold(
    averages: float, n_near: int, n_hood: int, false_alarm: float = LINE_FALSE_ALARM
) -> float:
    """The ratio of a PSD peak to its neighbourhood's median that white noise exceeds
    with probability ``false_alarm``, and at least :data:`LINE_RATIO`.

    A Welch PSD of white noise that averages K independent periodograms has bins
    distributed as Gamma(K, 1/K) times the level. The peak is the largest of ``n_near``
    bins about a candidate frequency, the background the median of ``n_hood`` bins of
    its neighbourhood (the lower middle order statistic, j = ⌈n/2⌉, when n is even: a
    smaller background, a conservative threshold). The chance of a ratio above T is

        P(T) = ∫ [1 - (1 - S(T x))^n_near] f_(j:n)(x) dx,

    S the Gamma survival function, f_(j:n) the density of the j-th order statistic of
    ``n_hood`` bins; T solves P(T) = ``false_alarm`` (quadrature on a grid of the
    order statistic's quantiles, root by bisection in log T). A single periodogram
    (K = 1) with a neighbourhood of 8 bins needs T ≈ 56-72, not 10: with 10, 12 % of 0.1 s
    white rests at 5 kHz showed a "line" (measured, 2000 records).

    Parameters
    ----------
    averages : float
        Equivalent number K of independent periodograms averaged (at least 1).
    n_near : int
        Bins searched for the peak.
    n_hood : int
        Bins of the neighbourhood whose median is the background (counted as
        independent: bins closer than a resolution would make the median noisier, see
        the caller).
    false_alarm : float
        Chance of a line in white noise at one candidate.

    Returns
    -------
    float
        The threshold ratio, at least :data:`LINE_RATIO`.
    """
    import scipy.optimize
    import scipy.stats

    k = max(float(averages), 1.0)
    n = max(int(n_hood), 1)
    m = max(int(n_near), 1)
    j = (n + 1) // 2
    bins = scipy.stats.gamma(k, scale=1.0 / k)
    # the median's distribution through the Beta law of the j-th uniform order statistic
    u = (np.arange(2000) + 0.5) / 2000
    x = bins.ppf(scipy.stats.beta(j, n - j + 1).ppf(u))

    def excess(log_t: float) -> float:
        single = bins.sf(math.exp(log_t) * x)
        return float(np.mean(-np.expm1(m * np.log1p(-np.minimum(single, 1.0 - 1e-16)))))

    lo, hi = math.log(LINE_RATIO), math.log(1e6)
    if excess(lo) <= false_alarm:
        return LINE_RATIO
    if excess(hi) > false_alarm:
        return 1e6
    return math.exp(scipy.optimize.brentq(lambda v: excess(v) - false_alarm, lo, hi, xtol=1e-3))


def _fft_length(n_longest: int, samples_per_period: float | None) -> int:
    """FFT length: a power of two covering 8 periods (when known), at most the longest
    segment rounded up, at least 64."""
    want = 64 if samples_per_period is None else 8.0 * samples_per_period
    cap = 1 << max(6, math.ceil(math.log2(max(n_longest, 2))))
    return min(max(64, 1 << math.ceil(math.log2(want))), cap)


#: Correlation of the periodograms of two Hann segments overlapping by half.
_HANN_OVERLAP_RHO = 0.167

#: Samples of the segments of :func:`welch` transformed together (8 MB of float64).
_WELCH_CHUNK = 1 << 20


def welch(s: NDArray, fs: float, nper: int, nfft: int) -> NDArray:
    """One-sided power spectral density [unit²/Hz] of ``s`` by Welch's method: Hann
    segments of ``nper`` samples overlapping by half, each less its mean, transformed
    at ``nfft`` points, their periodograms averaged.

    ``scipy.signal.welch(s, fs, window="hann", nperseg=nper, nfft=nfft,
    detrend="constant")`` to rounding (P. D. Welch (1967), IEEE Trans. Audio
    Electroacoust. 15(2), 70-73), with the segments taken as views of ``s`` and
    transformed a few at a time: scipy's sums the window's squares in a Python loop
    (7 ms a call at 65,536 samples) and copies every segment twice.
    """
    x = np.asarray(s, dtype=float)
    step = nper - nper // 2
    count = (x.size - nper) // step + 1
    window = 0.5 - 0.5 * np.cos(2.0 * math.pi * np.arange(nper) / nper)  # periodic Hann
    frames = np.lib.stride_tricks.sliding_window_view(x, nper)[::step][:count]
    total = np.zeros(nfft // 2 + 1)
    batch = max(1, _WELCH_CHUNK // nper)
    for first in range(0, count, batch):
        part = frames[first : first + batch]
        part = part - part.mean(axis=1, keepdims=True)
        part *= window
        spectrum = np.fft.rfft(part, nfft, axis=1)
        total += np.einsum("ij,ij->j", spectrum.real, spectrum.real)
        total += np.einsum("ij,ij->j", spectrum.imag, spectrum.imag)
    psd = total / (count * fs * float(np.einsum("i,i->", window, window)))
    psd[1 : None if nfft % 2 else -1] *= 2.0
    return psd


def band_bounds(rel_se: float, false_alarm: float = COLOUR_FALSE_ALARM) -> tuple[float, float]:
    """The range of ``band_level / white_level`` that white noise keeps.

    The band level of white noise averages periodogram bins, each a scaled χ² of two
    degrees of freedom: with relative standard error ``rel_se`` it is a χ² of
    ν = 2/rel_se² degrees of freedom over ν, skewed towards low values when ν is small.
    A symmetric bound of four standard errors in log(level) (the earlier test) called
    1 in 700 white rests of 0.1 s at 5 kHz coloured (ratio below 0.24, ν ≈ 16), and the
    increment variances computed from their spectrum were then 3-4 times too small.

    Parameters
    ----------
    rel_se : float
        Relative standard error of the band level (dimensionless, > 0).
    false_alarm : float
        Two-sided chance that white noise falls outside the range (in (0, 1)).

    Returns
    -------
    lower, upper : float
        The ratio's quantiles ``false_alarm / 2`` and ``1 - false_alarm / 2``
        (dimensionless).

    Raises
    ------
    ValueError
        If ``rel_se`` is not positive and finite or ``false_alarm`` not in (0, 1).
    """
    from scipy.stats import chi2

    if not (math.isfinite(rel_se) and rel_se > 0):
        raise ValueError(f"rel_se must be a positive number, got {rel_se!r}")
    if not 0.0 < false_alarm < 1.0:
        raise ValueError(f"false_alarm must be in (0, 1), got {false_alarm!r}")
    nu = 2.0 / rel_se**2
    return (
        float(chi2.ppf(0.5 * false_alarm, nu) / nu),
        float(chi2.isf(0.5 * false_alarm, nu) / nu),
    )


def _ljung_box(segments: Sequence[NDArray], lags: int) -> float:
    """p-value of the Ljung-Box statistic n(n+2) Σ ρ_k²/(n-k) over pooled segments.

    G. M. Ljung and G. E. P. Box (1978), Biometrika 65(2), 297-303.
    """
    from scipy.stats import chi2

    dev = [s - np.mean(s) for s in segments if s.size > lags + 2]
    n = sum(d.size for d in dev)
    if n <= lags + 2:
        return 1.0
    # sums by einsum, not a threaded BLAS (:func:`~bayestribo.signal.increments.
    # integrate_increments`)
    c0 = sum(float(np.einsum("i,i->", d, d)) for d in dev)
    if c0 == 0.0:
        return 1.0
    q = 0.0
    for k in range(1, lags + 1):
        rho = sum(float(np.einsum("i,i->", d[:-k], d[k:])) for d in dev) / c0
        q += rho * rho / (n - k)
    return float(chi2.sf(n * (n + 2.0) * q, lags))


def noise_spectrum(
    segments: Sequence[ArrayLike],
    sample_rate_Hz: float,
    *,
    period_s: float | None = None,
    band_Hz: float | None = None,
    mains_Hz: Sequence[float] = MAINS_HZ,
) -> NoiseSpectrum:
    """Welch PSD of the noise on rest segments of one channel, with lines and colour.

    Parameters
    ----------
    segments : sequence of array_like
        Rest segments of one channel [unit], each regularly sampled; each needs at
        least 16 samples.
    sample_rate_Hz : float
        Sampling rate [Hz].
    period_s : float, optional
        Period of the oscillation [s]: the FFT covers 8 of them (frequency resolution
        about an eighth of the oscillation frequency, lags to 8 periods), capped by the
        longest segment.
    band_Hz : float, optional
        Signal band [Hz] in which colour is judged; default 4 oscillation frequencies
        (or the Nyquist frequency without ``period_s``).
    mains_Hz : sequence of float
        Frequencies [Hz] where lines are looked for (and at their 2nd and 3rd harmonics).

    Returns
    -------
    NoiseSpectrum

    Raises
    ------
    RecordingError
        No segment of at least 16 samples, or a non-positive sample rate.
    """
    fs = float(sample_rate_Hz)
    if not (math.isfinite(fs) and fs > 0):
        raise RecordingError(f"sample_rate_Hz must be a positive number, got {sample_rate_Hz!r}")
    segs = [np.asarray(s, dtype=float) for s in segments]
    segs = [s for s in segs if s.size >= 16]
    if not segs:
        raise RecordingError("noise spectrum: no rest segment of at least 16 samples")
    per = None if period_s is None else period_s * fs
    nfft = _fft_length(max(s.size for s in segs), per)
    total = np.zeros(nfft // 2 + 1)
    weight = 0.0
    averages = 0.0
    freq = np.fft.rfftfreq(nfft, 1.0 / fs)
    resolution = 0.0
    spread = 0.0
    for s in segs:
        nper = min(nfft, s.size)
        resolution = max(resolution, fs / nper)
        p = welch(s, fs, nper, nfft)
        total += s.size * p
        weight += s.size
        # Hann with 50 % overlap: each further half segment adds ~1 independent average
        averages += max(1.0, 2.0 * s.size / nper - 1.0) * (nper / nfft)
        # the segment's periodograms actually averaged, overlapping ones correlated
        # (Hann at 50 %: ρ = 0.167, Percival & Walden 1993, Eq. 292b)
        count = (s.size - nper) // (nper - nper // 2) + 1
        spread += s.size**2 * (1.0 + 2.0 * _HANN_OVERLAP_RHO * (count - 1) / count) / count
    psd = total / weight
    # equivalent number of independent periodograms in a bin of the size-weighted
    # average: 1 / Σ wᵢ² / Kᵢ (the line test's statistics)
    line_averages = weight**2 / spread
    df = fs / nfft
    nyquist = fs / 2.0
    band = min(nyquist, 4.0 / period_s) if band_Hz is None and period_s else (band_Hz or nyquist)

    # Lines: a peak near a mains frequency (or its 2nd, 3rd harmonic) standing
    # LINE_RATIO above the median PSD of its neighbourhood.
    line_bins = np.zeros(psd.size, bool)
    lines: list[float] = []
    rms: list[float] = []
    reach = max(1.0, 1.5 * df)
    candidates = [b * h for b in mains_Hz for h in (1, 2, 3)]
    for base in mains_Hz:
        for harmonic in (1, 2, 3):
            f0 = base * harmonic
            if f0 + reach >= nyquist:
                continue
            # the bins about f0 only (a few hundred of the grid's): the same tests
            outer = max(0.5 * f0, 8 * resolution)
            around = _around(freq, f0, max(reach, outer))
            distance = np.abs(freq[around] - f0)
            near = np.flatnonzero(distance <= reach) + around.start
            hood = distance <= outer
            hood &= distance > 3 * resolution
            if around.start == 0:
                hood[0] = False
            if near.size == 0 or np.count_nonzero(hood) < 4:
                continue
            k = int(near[np.argmax(psd[near])])
            if min(candidates, key=lambda c: abs(c - freq[k])) != f0 or line_bins[k]:
                continue  # the peak belongs to another candidate line
            span = _around(freq, float(freq[k]), 2.0 * resolution)
            wide = np.abs(freq[span] - freq[k]) <= 2.0 * resolution
            if psd[k] < np.max(psd[span][wide]):
                continue  # the shoulder of a stronger peak (window leakage), not a line
            background = float(np.median(psd[around][hood]))
            # bins of a zero-padded grid closer than the window's resolution share
            # their noise: count the independent ones (Hann: 1.5 resolutions)
            per = df / (1.5 * resolution)
            ratio = line_threshold(
                round(line_averages, 1),
                max(1, math.ceil(near.size * min(per, 1.0))),
                max(1, int(np.count_nonzero(hood) * min(per, 1.0))),
            )
            if not psd[k] > ratio * background:
                continue
            power = float(np.sum(psd[span][wide] - background) * df)
            f_peak = float(freq[k])
            if 0 < k < psd.size - 1:
                a, b, c = np.log(psd[k - 1 : k + 2])
                den = a - 2 * b + c
                if den != 0:
                    f_peak += 0.5 * (a - c) / den * df
            lines.append(f_peak)
            rms.append(math.sqrt(max(power, 0.0)))
            line_bins[span] |= wide
    variance = float(np.sum(psd) * df)
    smooth = psd.copy()
    if line_bins.any():
        # the variance of the noise without its lines, for the white reference level
        smooth[line_bins] = np.interp(freq[line_bins], freq[~line_bins], psd[~line_bins])
    white = 2.0 * float(np.sum(smooth) * df) / fs
    in_band = (freq > 0) & (freq <= band) & ~line_bins
    if np.count_nonzero(in_band) == 0:
        in_band = (freq > 0) & (freq <= max(band, 2 * df)) & ~line_bins
    band_level = float(np.mean(psd[in_band]))
    # independent estimates in the band: bins closer than the window's resolution are
    # correlated (a Hann window's equivalent noise bandwidth is 1.5 resolutions)
    independent = max(1.0, np.count_nonzero(in_band) * df / (1.5 * resolution))
    rel_se = 1.0 / math.sqrt(max(averages, 1.0) * independent)
    ratio = band_level / white if band_level > 0 and white > 0 else math.nan
    lower, upper = band_bounds(rel_se)
    off_band = not (
        min(lower, 1.0 / COLOUR_FACTOR) <= ratio <= max(upper, COLOUR_FACTOR)
    )  # NaN: off
    p_white = _ljung_box(segs, LJUNG_BOX_LAGS)
    coloured = variance > 0 and (bool(lines) or off_band or p_white < WHITE_P)
    return NoiseSpectrum(
        frequency=freq,
        psd=psd,
        sample_rate_Hz=fs,
        variance=variance,
        white_level=white,
        band_level=band_level,
        band_Hz=float(band),
        lines_Hz=tuple(lines),
        line_rms=tuple(rms),
        coloured=coloured,
        n_samples=int(sum(s.size for s in segs)),
        n_averages=float(averages),
        white_p=float(p_white),
        band_rel_se=float(rel_se),
    )


def notch_gain(
    frequency_Hz: float, notch_Hz: float, sample_rate_Hz: float, quality: float
) -> float:
    """Amplitude gain of the zero-phase notch of :func:`notch_filter` at a frequency.

    ``|H(f)|²`` of the ``scipy.signal.iirnotch`` filter, squared because it is
    applied forwards and backwards.
    """
    b, a = scipy.signal.iirnotch(notch_Hz, quality, fs=sample_rate_Hz)
    _, h = scipy.signal.freqz(b, a, worN=[frequency_Hz], fs=sample_rate_Hz)
    return float(np.abs(h[0]) ** 2)


def _pad(s: NDArray, length: int, period: float, rest: int) -> NDArray:
    """``length`` samples to put before ``s``: whole line periods of its first ``rest``
    samples repeated, or, with less than one period of rest, its odd reflection."""
    periods = int(rest // period) if period > 0 else 0
    if periods >= 1:
        # the whole number of periods whose length in samples is nearest an integer
        k = min(range(1, periods + 1), key=lambda j: abs(j * period - round(j * period)))
        block = s[: round(k * period)]
        reps = -(-length // block.size)
        return np.tile(block, reps)[-length:]
    m = min(length, s.size - 1)
    return 2.0 * s[0] - s[m:0:-1]


def _line_residual(t: NDArray, s: NDArray, labels: NDArray, n_groups: int, f: float):
    """Least squares of s on a constant per segment and a sinusoid at f."""
    w = 2.0 * math.pi * f
    cols = [np.cos(w * t), np.sin(w * t)]
    cols += [(labels == g).astype(float) for g in range(n_groups)]
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a, s, rcond=None)
    r = s - a @ coef
    return float(r @ r), coef


def fit_line(
    t: ArrayLike,
    signal: ArrayLike,
    rest: ArrayLike,
    frequency_Hz: float,
    *,
    search_Hz: float = 0.5,
) -> tuple[float, float, float]:
    """A mains line measured at rest: frequency, amplitude and phase of a sinusoid.

    Least squares on the samples at rest (``rest`` mask, any number of segments, each
    with its own constant level) of ``A cos(2πf t + φ)``, with f refined within
    ``frequency_Hz ± search_Hz`` (mains frequency drifts by a few hundredths of a Hz).

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    signal : array_like
        One channel [unit].
    rest : array_like of bool
        Samples at rest.
    frequency_Hz : float
        Nominal frequency of the line [Hz].
    search_Hz : float
        Half-width of the frequency search [Hz].

    Returns
    -------
    frequency_Hz, amplitude, phase : float
        f [Hz], A [unit] and φ [rad] of ``A cos(2πf t + φ)``.

    Raises
    ------
    RecordingError
        Fewer than two periods of the line at rest.
    """
    from scipy.optimize import minimize_scalar

    t = np.asarray(t, dtype=float)
    s = np.asarray(signal, dtype=float)
    m = np.asarray(rest, bool)
    if np.count_nonzero(m) * sample_step(t) * frequency_Hz < 2.0:
        raise RecordingError(
            f"notch: fewer than two periods of the {frequency_Hz:g} Hz line at rest to measure it"
        )
    edges = np.flatnonzero(np.diff(np.r_[0, m.astype(np.int8), 0]))
    labels = np.zeros(t.size, int)
    for g, (a, b) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        labels[a:b] = g
    tt, ss, ll = t[m] - t[0], s[m], labels[m]
    groups = int(edges.size // 2)
    # a grid first (the residual is multimodal on the scale of 1/T), then refine
    grid = np.linspace(frequency_Hz - search_Hz, frequency_Hz + search_Hz, 41)
    res = [_line_residual(tt, ss, ll, groups, f)[0] for f in grid]
    k = int(np.argmin(res))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = minimize_scalar(
        lambda f: _line_residual(tt, ss, ll, groups, f)[0],
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-6},
    )
    f = float(best.x)
    _, coef = _line_residual(tt, ss, ll, groups, f)
    amplitude = float(math.hypot(coef[0], coef[1]))
    phase = float(math.atan2(-coef[1], coef[0]) - 2.0 * math.pi * f * t[0])
    return f, amplitude, phase


def notch_filter(
    signal: ArrayLike,
    notch_Hz: float,
    sample_rate_Hz: float,
    *,
    quality: float = 30.0,
    oscillation_Hz: float | None = None,
    rest_head: int = 0,
    rest_tail: int = 0,
) -> NDArray:
    """Remove a mains line from a channel with a zero-phase notch.

    A second-order IIR notch (``scipy.signal.iirnotch``, -3 dB width
    ``notch_Hz / quality``) run forwards and backwards (``scipy.signal.filtfilt``,
    padded at both ends): **zero phase, so it adds no delay**, and applied to both
    channels alike it leaves E = ½(y² + y'²) consistent sample by sample. A notch rings
    for about ``quality / (π notch_Hz)`` seconds (0.2 s at 50 Hz, quality 30), so the
    record is padded with six times that: where the record is known to be at rest
    (``rest_head``, ``rest_tail`` samples) by repeating a whole number of the line's
    periods of that rest (the line runs on without a jump, and the rest is notched to its
    edges); elsewhere by an odd reflection (as ``filtfilt`` does). Its
    gain at the oscillation frequency, ``|H(f)|²`` (1 - 2.9e-3 for a 50 Hz notch of
    quality 30 at 32.6 Hz), is divided out when ``oscillation_Hz`` is given, so E is
    not scaled (the gain varies by less than 1e-5 across the ζf-wide spectrum of the
    decay).

    Parameters
    ----------
    signal : array_like
        One channel, regularly sampled [unit].
    notch_Hz : float
        Frequency of the line [Hz], below the Nyquist frequency.
    sample_rate_Hz : float
        Sampling rate [Hz].
    quality : float
        Quality factor of the notch (width ``notch_Hz / quality``).
    oscillation_Hz : float, optional
        Frequency of the oscillation [Hz] at which to restore unit gain.
    rest_head, rest_tail : int
        Samples at the start and at the end of the record known to be at rest (noise
        and the line only), used for the padding.

    Returns
    -------
    ndarray
        The filtered channel [unit].

    Raises
    ------
    RecordingError
        A notch frequency outside (0, fs/2), a quality that is not positive, or too
        few samples.
    """
    s = np.asarray(signal, dtype=float)
    fs = float(sample_rate_Hz)
    f0 = float(notch_Hz)
    if not (math.isfinite(f0) and 0.0 < f0 < fs / 2.0):
        raise RecordingError(
            f"notch must be a frequency between 0 and the Nyquist frequency {fs / 2:g} Hz, "
            f"got {notch_Hz!r}"
        )
    if not (math.isfinite(quality) and quality > 0):
        raise RecordingError(f"notch_quality must be a positive number, got {quality!r}")
    b, a = scipy.signal.iirnotch(f0, quality, fs=fs)
    if s.size < 16:
        raise RecordingError(f"notch: {s.size} samples are too few to filter")
    pad = max(1, math.ceil(6.0 * quality / (math.pi * f0) * fs))
    period = fs / f0
    head = _pad(s, pad, period, int(rest_head))
    tail = _pad(s[::-1], pad, period, int(rest_tail))[::-1]
    padded = np.concatenate([head, s, tail])
    out = scipy.signal.filtfilt(b, a, padded, padlen=0)[head.size : head.size + s.size]
    if oscillation_Hz is not None:
        out = out / notch_gain(oscillation_Hz, f0, fs, quality)
    return out


def colored_noise(
    spectrum: NoiseSpectrum, n_samples: int, rng: np.random.Generator, size: int = 1
) -> NDArray:
    """Gaussian noise with a measured spectrum, by shaping white noise in frequency.

    Parameters
    ----------
    spectrum : NoiseSpectrum
        The PSD to reproduce (interpolated onto the draw's frequency grid).
    n_samples : int
        Length of each draw.
    rng : numpy.random.Generator
        Source of randomness.
    size : int
        Number of independent draws (rows).

    Returns
    -------
    ndarray
        Shape ``(size, n_samples)`` [unit]; variance ≈ ``spectrum.variance``.
    """
    n = int(n_samples)
    m = 2 * n  # circular draws, half kept: no wrap-around correlation
    fs = spectrum.sample_rate_Hz
    f = np.fft.rfftfreq(m, 1.0 / fs)
    p = np.interp(f, spectrum.frequency, spectrum.psd)
    amp = np.sqrt(p * fs * m / 4.0)
    amp[0] = 0.0
    z = rng.standard_normal((size, f.size)) + 1j * rng.standard_normal((size, f.size))
    return np.fft.irfft(z * amp, m, axis=-1)[:, :n]
