"""The Monte Carlo noise of a derived channel, drawn once per record and reused.

When one channel is derived from the other (a Savitzky-Golay derivative of the
displacement, or the integral of the velocity), the increments' noise is found by
drawing noise on the recorded channel and repeating the derivation on it
(:func:`bayestribo.signal.increments.increment_draws`). The derivation is linear, so
the noise it leaves in each channel does not depend on the motion it is added to::

    derived velocity:      y + ε,          SG'(y + ε) = SG'(y) + SG'(ε)
    derived displacement:  y + D(η),       y' + η

(``D`` the integral less its least-squares line,
:func:`bayestribo.signal.increments.detrended``). The noise pairs (ε, SG'(ε)) or
(D(η), η) are therefore a property of the record and of the recipe (replicates, seed,
noise level or spectrum, filter window), not of the motion: the second pass of every
law compared on one record (:mod:`bayestribo.inference.reweight`) draws the same
pairs and adds them to its own motion. :func:`noise_pairs` draws them;
:func:`reused_noise` keeps them for the calls inside a ``with`` block, keyed by every
input that determines them, so that a law's second pass finds them drawn by the first
law's; outside such a block nothing is kept (a record of a million samples would hold
``2 × replicates × 10⁶`` floats).

The draws are those the derivation repeated on the noisy channel gives, up to the
rounding of ``SG'(y) + SG'(ε)`` against ``SG'(y + ε)`` (and of ``(y' + η) - y'``
against ``η``): on HarmOsc3 (10,822 samples, 300 replicates of coloured noise) the
increments' variances moved by 4e-14 to 3e-13 of themselves and the noise bias by
1e-11 of itself against drawing the derivation of the noisy channel; the pairs kept
give the same numbers, to the last bit, as pairs drawn again, and a second pass took
0.02 s with them where drawing them took 0.55-0.6 s.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator

import numpy as np
import scipy.signal
from numpy.typing import NDArray
from scipy.integrate import cumulative_trapezoid

from bayestribo.signal.spectrum import NoiseSpectrum, colored_noise

__all__ = ["noise_carrier", "noise_pairs", "reused_noise", "savgol_derivative"]

#: Monte Carlo replicates drawn at once (memory: block × samples floats).
BLOCK = 25
#: The same for an accelerometer's draws (``velocity_draws``), whose integration costs
#: as much again per block as per draw (its edges' terms, their least squares): 1390
#: draws of a 28 s record at 200 Hz took 2.8 s of CPU in blocks of 25, 1.5 s in
#: blocks of 100 (the draws the same, their variances to 2e-15).
DRAW_BLOCK = 100
#: Largest number of floats :func:`reused_noise` keeps for one recipe (both channels,
#: every replicate): 2²⁴, 134 MB. A larger record's noise is drawn at every call.
KEEP_LIMIT = 2**24


def noise_carrier(
    y: NDArray, yp: NDArray, *, derived: str, savgol_window: int | None, h: float
) -> NDArray:
    """The derived channel of the motion ``(y, y')`` without noise, to which the noise
    of :func:`noise_pairs` is added: ``SG'(y)`` for a derived velocity (the decay's
    filter, :func:`savgol_derivative`), ``y'`` itself for a derived displacement.

    Parameters
    ----------
    y, yp : ndarray
        The motion on the samples (dimensionless).
    derived : {"velocity", "displacement"}
        The channel derived from the other.
    savgol_window : int, optional
        Window of the derivative filter (default 7).
    h : float
        The samples' step in τ.

    Returns
    -------
    ndarray
        Same shape as ``yp``.
    """
    if derived == "velocity":
        return savgol_derivative(y, _window(savgol_window, y.shape[-1]), h)
    return yp


def savgol_derivative(y: NDArray, window: int, h: float) -> NDArray:
    """The Savitzky-Golay derivative the Monte Carlo takes of a displacement
    (polynomial order 5, ``window`` samples, step ``h``, interpolated at the edges),
    along the last axis; linear in ``y``."""
    return scipy.signal.savgol_filter(y, window, 5, deriv=1, delta=h, mode="interp", axis=-1)


def _window(savgol_window: int | None, n_samples: int) -> int:
    """The filter's window on ``n_samples`` samples (odd, at most the samples)."""
    return min(int(savgol_window or 7), n_samples - (1 - n_samples % 2))


def noise_pairs(
    tau: NDArray,
    sigma_y: float,
    sigma_yp: float,
    *,
    derived: str,
    savgol_window: int | None = None,
    n_replicates: int = 300,
    seed: int = 0,
    spectrum: NoiseSpectrum | None = None,
    spectrum_scale: float = 1.0,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None = None,
) -> Iterator[tuple[NDArray, NDArray]]:
    """The noise of y and y' when one is derived from the other, block by block.

    Noise is drawn on the recorded channel (white at ``sigma_y`` or ``sigma_yp``, with
    ``spectrum`` times ``spectrum_scale``, or from ``velocity_draws``) and the
    derivation repeated on it; inside :func:`reused_noise` the blocks of a recipe
    drawn before are given again. The arguments are those of
    :func:`bayestribo.signal.increments.increment_noise`.

    Yields
    ------
    (ndarray, ndarray)
        The noise of y and of y' of one block of replicates (dimensionless, shape
        (count, samples)); the blocks hold ``n_replicates`` rows in all.
    """
    if derived not in ("velocity", "displacement"):
        raise ValueError(f"derived must be 'velocity' or 'displacement', got {derived!r}")
    tau = np.asarray(tau, dtype=float)
    kept = _KEPT.get()
    key = None
    if kept is not None and velocity_draws is None and 2 * n_replicates * tau.size <= KEEP_LIMIT:
        # every input the draws depend on; the spectrum by identity (kept alive by
        # the entry, so that its id is not reused)
        key = (
            derived,
            _window(savgol_window, tau.size) if derived == "velocity" else None,
            int(n_replicates),
            seed,
            tau.size,
            float(tau[1] - tau[0]),
            float(tau[0]),
            float(sigma_y),
            float(sigma_yp),
            None if spectrum is None else id(spectrum),
            float(spectrum_scale),
        )
        if key in kept:
            yield from kept[key][1]
            return
    pairs = _draw(
        tau,
        sigma_y,
        sigma_yp,
        derived,
        savgol_window,
        n_replicates,
        seed,
        spectrum,
        spectrum_scale,
        velocity_draws,
    )
    if key is None:
        yield from pairs
        return
    blocks = tuple(pairs)
    kept[key] = (spectrum, blocks)
    yield from blocks


def _draw(
    tau: NDArray,
    sigma_y: float,
    sigma_yp: float,
    derived: str,
    savgol_window: int | None,
    n_replicates: int,
    seed: int,
    spectrum: NoiseSpectrum | None,
    spectrum_scale: float,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None,
) -> Iterator[tuple[NDArray, NDArray]]:
    """The blocks of :func:`noise_pairs`, drawn."""
    from bayestribo.signal.increments import detrended

    rng = np.random.default_rng(seed)
    h = float(tau[1] - tau[0])
    window = _window(savgol_window, tau.size)
    block = DRAW_BLOCK if velocity_draws is not None and derived == "displacement" else BLOCK
    for first in range(0, n_replicates, block):
        count = min(block, n_replicates - first)
        # one (count, samples) draw is the same stream as ``count`` draws of a row
        if velocity_draws is not None and derived == "displacement":
            draw = velocity_draws(count, rng)
        elif spectrum is not None:
            draw = spectrum_scale * colored_noise(spectrum, tau.size, rng, count)
        else:
            sigma = sigma_y if derived == "velocity" else sigma_yp
            draw = rng.normal(0.0, sigma, (count, tau.size))
        if derived == "velocity":
            yield draw, savgol_derivative(draw, window, h)
        else:
            # the equilibrium and its drift (a line in τ) are estimated from the
            # record's own turning points, so the line the noise's integral holds goes
            # with them and only its departure from a line remains
            walk = cumulative_trapezoid(draw, tau, initial=0.0, axis=-1)
            yield detrended(walk, tau), draw


_KEPT: contextvars.ContextVar[dict | None] = contextvars.ContextVar(
    "bayestribo_kept_noise", default=None
)


@contextlib.contextmanager
def reused_noise() -> Iterator[None]:
    """Keep the noise pairs drawn inside the block for the calls that follow in it.

    Every call of :func:`noise_pairs` with the same record and recipe inside the
    block gives the blocks the first drew (the same numbers: the draws depend on
    those inputs alone). Nested blocks share the outer one's; what was kept is
    released when the outermost block ends.

    Examples
    --------
    >>> from bayestribo.signal.channel_noise import reused_noise
    >>> with reused_noise():
    ...     pass
    """
    if _KEPT.get() is not None:
        yield
        return
    token = _KEPT.set({})
    try:
        yield
    finally:
        _KEPT.reset(token)
