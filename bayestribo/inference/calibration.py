"""Channel calibration from the recording itself: v must equal dx/dt.

A displacement channel and a velocity channel of one vibrometer are calibrated
separately; their gains can differ by a percent and a filter can delay one against the
other. E = ½kx² + ½mv² then ripples within each cycle, and the fit reads the ripple as
damping (a 1 % velocity gain moved μ_k by 0.5 %, twelve posterior standard deviations,
with no warning). :func:`calibrate_channels` measures the gain ratio and the relative
delay from the motion (:func:`bayestribo.signal.channels.channel_consistency`, with
jackknife standard errors over the cycles), reports them, and where they differ from
1 and 0 by more than :data:`CALIBRATION_Z` standard errors (and by more than
:data:`MIN_RIPPLE` of E), warns with a
:class:`~bayestribo.errors.ChannelCalibrationWarning` and corrects the **velocity** to
the displacement: the displacement sets the length scale of the friction (x_c = μ_k
N/k), so it is the channel the results are calibrated to. The velocity is rescaled by
the gain ratio and shifted by the delay (a Fourier shift, exact for a band-limited
signal).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import ChannelCalibrationWarning
from bayestribo.io.run import Run
from bayestribo.signal.channels import channel_consistency, check_channels

__all__ = ["CALIBRATION_Z", "MIN_RIPPLE", "calibrate_channels", "fractional_delay"]

#: Standard errors beyond which a gain ratio or a delay is reported and corrected.
#: The jackknife standard errors are conservative (the gain's z-scores of consistent
#: simulated channels scatter with a standard deviation of 0.3-0.6, the delay's of
#: about 1), so 4 keeps false alarms rare while a 1 % gain (z ≈ 20-80) or a 50 µs delay
#: (z ≈ 100) is always caught.
CALIBRATION_Z = 4.0

#: Smallest mismatch acted upon, as the relative ripple it puts on E: |g − 1| for a
#: gain ratio, ω|δ| for a delay (2.4 µs at 32.6 Hz). Below it the effect on ζ and μ_k
#: is a few parts in 10⁴ at most, and a misfitting law (damping that changes with
#: amplitude) can bias the first-order delay estimate by that much: the misfit check,
#: not the channels, should speak then.
MIN_RIPPLE = 5e-4


def fractional_delay(t: NDArray, signal: NDArray, delay_s: float) -> NDArray:
    """``signal`` delayed by ``delay_s`` [s], any fraction of a sample.

    The signal is extended by its last value to twice its length (no wrap-around of
    the end onto the start) and multiplied by exp(-iωd) in the Fourier domain.

    Parameters
    ----------
    t : ndarray
        Regular sample times [s].
    signal : ndarray
        Samples.
    delay_s : float
        Delay [s]; positive moves the signal later.

    Returns
    -------
    ndarray
        The delayed signal, same length.
    """
    n = signal.size
    step = float(t[1] - t[0])
    padded = np.concatenate((signal, np.full(n, signal[-1])))
    freq = np.fft.rfftfreq(2 * n, step)
    spectrum = np.fft.rfft(padded) * np.exp(-2j * np.pi * freq * delay_s)
    return np.fft.irfft(spectrum, 2 * n)[:n]


def calibrate_channels(run: Run, *, correct: bool = True) -> tuple[Run, dict[str, Any] | None]:
    """Measure the channels' gain ratio and delay; correct the velocity when they are off.

    Parameters
    ----------
    run : Run
        A recording; runs with one signal are returned as they are.
    correct : bool
        Rescale and shift the velocity when the gain ratio or the delay is off by more
        than :data:`CALIBRATION_Z` standard errors and :data:`MIN_RIPPLE` (the warning
        is given either way).

    Returns
    -------
    (Run, dict or None)
        The run (corrected or not) and the calibration: the values of
        :class:`~bayestribo.signal.channels.ChannelConsistency` with ``gain_off``,
        ``delay_off`` and ``corrected``; None without both signals or without enough
        cycles to estimate the standard errors.

    Warns
    -----
    ChannelCalibrationWarning
        When the gain ratio or the delay is off, with the values and what was done.

    Raises
    ------
    RecordingError
        When the channels are swapped, unrelated or their gains a factor of 2 or more
        apart (:func:`bayestribo.signal.channels.check_channels`).
    """
    # A run built in memory has not been through read_run's checks: swapped or
    # unrelated channels are refused here too, never "corrected" by a gain of -1/Ω².
    check_channels(run, run.source)
    found = channel_consistency(run)
    if found is None or not (math.isfinite(found.gain_se) and math.isfinite(found.delay_se_s)):
        return run, None
    omega = 2.0 * math.pi / (40.0 * found.window_s)  # the windows are a 40th of a period
    gain_off = abs(found.gain - 1.0) > max(CALIBRATION_Z * found.gain_se, MIN_RIPPLE)
    delay_off = abs(found.delay_s) > max(CALIBRATION_Z * found.delay_se_s, MIN_RIPPLE / omega)
    info: dict[str, Any] = {
        **found.to_dict(),
        "gain_off": bool(gain_off),
        "delay_off": bool(delay_off),
        "corrected": False,
    }
    if not (gain_off or delay_off):
        return run, info
    parts = []
    if gain_off:
        parts.append(
            f"the velocity channel reads {found.velocity_gain:.5f} × dx/dt "
            f"(± {found.gain_se / found.gain**2:.1g})"
        )
    if delay_off:
        parts.append(
            f"the displacement lags the velocity by {1e6 * found.delay_s:.3g} µs "
            f"(± {1e6 * found.delay_se_s:.2g} µs)"
        )
    action = (
        "the velocity is rescaled and shifted to the displacement's calibration"
        if correct
        else "left as recorded (correct_channels=False): E ripples within each cycle"
    )
    warnings.warn(
        f"{run.source or 'the run'}: {' and '.join(parts)}; {action}",
        ChannelCalibrationWarning,
        stacklevel=3,
    )
    if not correct:
        return run, info
    velocity = np.asarray(run.velocity, dtype=float)
    if gain_off:
        velocity = velocity * found.gain
    if delay_off:
        velocity = fractional_delay(run.time, velocity, found.delay_s)
    info["corrected"] = True
    corrected = Run(run.time, run.displacement, velocity, dict(run.metadata), source=run.source)
    return corrected, info
