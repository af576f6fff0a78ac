r"""The colour of the noise at rest below the oscillation: its spectral slope.

Sensor drift, amplifier flicker and seismic background add noise whose power spectral
density grows towards low frequencies, S(f) ∝ f^α with α ≈ -1 (1/f, "pink") or -2
(a random walk, "brown"). The noise model of the increments
(:mod:`bayestribo.signal.spectrum`) spans a few periods of the oscillation; the slow
wander of such noise over the seconds of a decay moves the equilibrium and the energy
of the smallest swings by as much as the noise's whole variance, alike over many
increments: a decay analysed down to a few times that noise is bent by it (a viscous
decay into 2 µm of 1/f noise under a 1 mm release, analysed down to 4 times the noise,
gave ζ 2.5 % high at z = +32).

:func:`noise_colour` measures α on the rest segments (before the release and after the
stop) as the least-squares slope of log S against log f, S a Welch estimate with
segments as long as the rest allows, on its bins from the lowest resolved frequency
to half the oscillation's (mains lines and the oscillation's residue lie
above). :attr:`NoiseColour.low_frequency` is true when the slope is below
:data:`SLOPE_LIMIT` by more than :data:`SLOPE_Z` standard errors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.signal.spectrum import welch

__all__ = ["SLOPE_LIMIT", "SLOPE_Z", "NoiseColour", "noise_colour"]

#: Log-log slope of the rest's PSD below which its noise is called low-frequency
#: (1/f-like): white noise has 0, a filtered white noise 0 below its cutoff, 1/f -1.
#: At -0.5, one 1/f rest in 24 (0.1 % of the release, a quarter of it white) measured
#: -0.76 ± 0.15 and was not called so: its decay misfit at z = 6.7 with no cause named.
SLOPE_LIMIT = -0.25
#: Standard errors by which the slope must lie below :data:`SLOPE_LIMIT`.
SLOPE_Z = 2.0
#: Fewest frequency bins the slope is fitted on.
MIN_BINS = 8


@dataclass(frozen=True)
class NoiseColour:
    """Spectral slope of the noise at rest below the oscillation frequency.

    Attributes
    ----------
    slope : float
        Least-squares slope α of log S(f) against log f (dimensionless): 0 white, -1
        1/f (pink), -2 a random walk (brown).
    slope_se : float
        Its standard error (dimensionless), from the scatter of the bands about the
        line.
    low_Hz, high_Hz : float
        Frequency range of the fit [Hz].
    rms : float
        Standard deviation of the rest samples about each segment's mean [unit]: the
        noise a swing is compared with.
    seconds : float
        Duration of the rest analysed [s].
    """

    slope: float
    slope_se: float
    low_Hz: float
    high_Hz: float
    rms: float
    seconds: float

    @property
    def low_frequency(self) -> bool:
        """True when the PSD rises towards low frequencies beyond white noise's chance."""
        return self.slope + SLOPE_Z * self.slope_se < SLOPE_LIMIT

    @property
    def name(self) -> str:
        """The colour's usual name: ``"1/f (pink)"``, ``"1/f² (brown)"`` or ``"f^α"``."""
        if -1.5 <= self.slope <= -0.5:
            return "1/f (pink)"
        if -2.5 <= self.slope < -1.5:
            return "1/f² (brown)"
        return f"f^{self.slope:.1f}"

    def describe(self) -> str:
        """One phrase: the colour, its slope and where it was measured."""
        return (
            f"{self.name} noise at rest (its spectrum goes as f^{self.slope:.2f} ± "
            f"{self.slope_se:.2f} from {self.low_Hz:.3g} to {self.high_Hz:.3g} Hz, "
            f"{self.seconds:.3g} s of rest, rms {self.rms:.3g})"
        )


def noise_colour(
    segments: Sequence[ArrayLike], sample_rate_Hz: float, oscillation_Hz: float
) -> NoiseColour | None:
    """The spectral slope of rest segments below half the oscillation frequency.

    Parameters
    ----------
    segments : sequence of array_like
        Rest segments of one channel [unit], regularly sampled.
    sample_rate_Hz : float
        Sampling rate [Hz].
    oscillation_Hz : float
        Oscillation frequency [Hz]; the slope is fitted up to half of it.

    Returns
    -------
    NoiseColour or None
        None where the rest is too short to resolve :data:`MIN_BINS` bins below half
        the oscillation frequency, or holds no noise.
    """
    fs = float(sample_rate_Hz)
    segs = [np.asarray(s, dtype=float) for s in segments]
    segs = [s for s in segs if s.size >= 16]
    if not segs or not (fs > 0 and oscillation_Hz > 0):
        return None
    longest = max(s.size for s in segs)
    # segments of half the longest rest (three half-overlapping averages there): the
    # lowest frequencies resolved, at a few averages a bin
    nper = 1 << max(4, math.floor(math.log2(max(longest // 2, 16))))
    high = 0.5 * float(oscillation_Hz)
    low = fs / nper
    if math.floor(high / low) < MIN_BINS:
        return None  # too short a rest to resolve the low frequencies: no spectrum
    total = np.zeros(nper // 2 + 1)
    weight = 0
    averages = 0.0
    for s in segs:
        if s.size < nper:
            continue
        total += s.size * welch(s, fs, nper, nper)
        weight += s.size
        averages += 2.0 * s.size / nper - 1.0
    if weight == 0:
        return None
    psd = total / weight
    freq = np.fft.rfftfreq(nper, 1.0 / fs)
    used = (freq >= low * 0.999) & (freq <= high) & (psd > 0)
    if np.count_nonzero(used) < MIN_BINS:
        return None
    xs, ys = np.log10(freq[used]), np.log10(psd[used])
    design = np.column_stack([np.ones(xs.size), xs])
    coef, *_ = np.linalg.lstsq(design, ys, rcond=None)
    resid = ys - design @ coef
    s2 = float(resid @ resid) / max(xs.size - 2, 1)
    # a bin of a Welch average of K periodograms scatters in log10 by about 0.434/√K
    # (K counted for half-overlapping Hann segments): at least that, and the Hann
    # window correlates neighbouring bins (1.5 bins share their noise)
    expected = 0.434**2 / max(averages, 1.0)
    spread = float(np.sum((xs - xs.mean()) ** 2))
    se = math.sqrt(1.5 * max(s2, expected) / spread)
    dev = np.concatenate([s - np.mean(s) for s in segs])
    rms = float(np.sqrt(np.mean(dev * dev)))
    if rms == 0.0:
        return None
    return NoiseColour(
        slope=float(coef[1]),
        slope_se=float(se),
        low_Hz=float(low),
        high_Hz=float(high),
        rms=rms,
        seconds=float(sum(s.size for s in segs) / fs),
    )


#: Smallest swing analysed above low-frequency noise at rest, in its rms: a decay's
#: turning points below it are left out (:func:`wander_end`).
WANDER_FLOOR = 10.0


def wander_end(swings: ArrayLike, colour: NoiseColour | None, least: int) -> int | None:
    """How many of a decay's turning points to keep above low-frequency noise.

    Parameters
    ----------
    swings : array_like
        The analysed turning points' values about the equilibrium [unit], in order.
    colour : NoiseColour or None
        The noise at rest (:func:`noise_colour`).
    least : int
        Fewest turning points the analysis needs.

    Returns
    -------
    int or None
        The count up to the last turning point whose swing is at least
        :data:`WANDER_FLOOR` times the noise's rms, where the noise is low-frequency
        (:attr:`NoiseColour.low_frequency`) and later turning points fall below it;
        None where nothing is to be left out (white noise, every swing above, or fewer
        than ``least`` above).
    """
    if colour is None or not colour.low_frequency:
        return None
    a = np.abs(np.asarray(swings, dtype=float))
    above = np.flatnonzero(a >= WANDER_FLOOR * colour.rms)
    if above.size == 0:
        return None
    kept = int(above[-1]) + 1
    if kept >= a.size or kept < least:
        return None
    return kept


def misfit_note(colour: NoiseColour | None, floor: float | None, swings: ArrayLike) -> str:
    """What a misfit warning says of low-frequency noise at rest ("" for none).

    Parameters
    ----------
    colour : NoiseColour or None
        The noise at rest (:attr:`~bayestribo.signal.decay.EnergyDecay.noise_colour`).
    floor : float or None
        The smallest swing analysed where the analysis ended above the noise
        (:attr:`~bayestribo.signal.decay.EnergyDecay.wander_floor`), else None.
    swings : array_like
        The analysed turning points' values about the equilibrium [unit].

    Returns
    -------
    str
        A sentence naming the noise's colour and what it did to the analysis.
    """
    if colour is None or not colour.low_frequency:
        return ""
    if floor is not None:
        return (
            f" The record's noise is {colour.describe()}; the analysis ended at swings "
            f"of {WANDER_FLOOR:g} times its rms ({floor:.3g}), where its wander is "
            "small against them: the misfit is not that wander's"
        )
    above = int(
        np.count_nonzero(np.abs(np.asarray(swings, dtype=float)) >= WANDER_FLOOR * colour.rms)
    )
    return (
        f" The record's noise is {colour.describe()}: its wander over seconds is not in "
        "the noise model and moves the equilibrium and the energy of the smallest swings "
        f"alike over many increments; only {above} analysed turning point(s) stand "
        f"{WANDER_FLOOR:g} times its rms above it, too few to end the analysis there: "
        "record a larger release, or a quieter signal chain"
    )


#: Amplitude of the oscillation fitted on the first periods after a stop, over the
#: median of those fitted on the rest's last half, beyond which the decay goes on under
#: the noise (a fade, not a stop).
ON_RATIO = 4.0
#: Periods of each block on which that oscillation is fitted.
ON_PERIODS = 8.0
#: Fewest blocks in the rest's last half for the comparison.
ON_BLOCKS = 4


def _amplitude(s: NDArray, x: NDArray, omega: float) -> float:
    """Amplitude [unit] of the sinusoid at ``omega`` fitted with a line to ``x``."""
    design = np.column_stack([np.ones(s.size), s, np.cos(omega * s), np.sin(omega * s)])
    coef, *_ = np.linalg.lstsq(design, x, rcond=None)
    return float(np.hypot(coef[2], coef[3]))


def goes_on(t: NDArray, x: NDArray, stop_s: float | None, period_s: float) -> bool:
    """Whether a decay's oscillation goes on after the stop found in it: a fade into
    the noise, not a stop (a viscous decay never stops).

    A sinusoid at the oscillation's period (with a line) is fitted by least squares to
    the displacement over blocks of :data:`ON_PERIODS` periods of the rest after
    ``stop_s`` (from a quarter period after it). The first block's amplitude beyond
    :data:`ON_RATIO` times the median of the blocks of the rest's last half says the
    motion goes on: the noise's own amplitude at that period is measured there, whatever
    its colour (a white-noise standard error took 1/f noise for an oscillation at 5-11
    of them). A friction's stop leaves the first block as the others (1.2-2.3 times
    their median on the paper's rig in 1/f noise); a viscous decay that fades below a
    threshold of its noise leaves one of several times the noise in it.

    Parameters
    ----------
    t, x : ndarray
        Time stamps [s] and displacement [unit] of the whole record.
    stop_s : float or None
        The stop found [s]; None for a record that ends in motion (True is returned).
    period_s : float
        The oscillation's period [s].

    Returns
    -------
    bool
        False where the rest's last half holds fewer than :data:`ON_BLOCKS` blocks (no
        measure of the noise there: the stop stands).
    """
    if stop_s is None:
        return True
    step = ON_PERIODS * period_s
    first = stop_s + 0.25 * period_s
    blocks = int((float(t[-1]) - first) // step)
    late = range(blocks // 2 + blocks % 2, blocks)
    if len(late) < ON_BLOCKS:
        return False
    omega = 2.0 * math.pi / period_s

    def amplitude(k: int) -> float:
        a = int(np.searchsorted(t, first + k * step, "left"))
        b = int(np.searchsorted(t, first + (k + 1) * step, "left"))
        return _amplitude(t[a:b] - t[a], x[a:b], omega)

    noise = float(np.median([amplitude(k) for k in late]))
    return amplitude(0) > ON_RATIO * noise
