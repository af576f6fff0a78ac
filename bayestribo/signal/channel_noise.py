"""The recorded channel's Monte Carlo noise, drawn once per record and recipe.

When one channel is derived from the other (a Savitzky-Golay derivative of the
displacement, or the integral of the velocity), the increments' noise is found by
drawing noise on the recorded channel, adding it to the motion and repeating the
derivation (:func:`bayestribo.signal.increments.increment_draws`). The noise drawn
depends on the record and the recipe alone (samples, replicates, seed, noise level or
spectrum), not on the motion it is added to: the second pass of every law compared on
one record (:mod:`bayestribo.inference.reweight`) draws the same numbers.
:func:`recorded_noise` gives them; inside :func:`reused_noise` (a comparison of laws,
:func:`bayestribo.inference.comparison.compare_prepared`, and any ``fit`` from its first
pass on: each law's second pass under ``law="auto"``, each boundary law's of the default
law) it keeps them, keyed by every input that determines them, so that each second pass
finds them drawn by the first pass. Every increment variance is the same, to the last
bit, as drawing the noise again; what is saved is the drawing, the larger part for
coloured noise (300 replicates of 10,822 samples shaped in frequency on HarmOsc3: 0.39
of the 0.59 s a second pass took; the rest was the derivative filter, 85 samples wide).
Inside one, at most :data:`KEEP_LIMIT` floats are kept in all, the recipes used longest
ago let go first (a comparison's laws use one recipe in a row, the verdict's frame and
each half of the motion theirs after it); outside, nothing is kept.

A derivation that is linear in its input (the Savitzky-Golay derivative, whose edges
are least-squares fits too) gives the noisy motion's derivative as the motion's plus the
noise's: :func:`derived_noise` keeps the noise's derivative beside the noise, so that a
second pass filters one row, the motion, instead of every replicate (on the recordings
of ``benchmarks/auto_ratio.py`` the filter made 14 % of ``law="auto"``'s time).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Hashable, Iterator

import numpy as np
from numpy.typing import NDArray

from bayestribo.signal.spectrum import NoiseSpectrum, colored_noise

__all__ = ["KEEP_LIMIT", "derived_noise", "recorded_noise", "reused_noise"]

#: Largest number of floats :func:`reused_noise` keeps in all (every replicate's
#: samples of every recipe kept): 2²⁴, 134 MB. The recipes used longest ago are let go
#: to keep a new one within it; a recipe larger than it is drawn at every call.
KEEP_LIMIT = 2**24

_KEPT: contextvars.ContextVar[dict | None] = contextvars.ContextVar(
    "bayestribo_kept_noise", default=None
)


def recorded_noise(
    n_samples: int,
    sigma: float,
    *,
    n_replicates: int,
    seed: int,
    block: int,
    spectrum: NoiseSpectrum | None = None,
    spectrum_scale: float = 1.0,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None = None,
) -> Iterator[NDArray]:
    """The recorded channel's noise, ``block`` replicates at a time.

    From one stream seeded with ``seed``: ``velocity_draws(count, rng)`` when given
    (an accelerometer's velocity, :func:`bayestribo.signal.increments.
    accelerometer_draws`), else noise with ``spectrum`` times ``spectrum_scale``
    (:func:`bayestribo.signal.spectrum.colored_noise`), else white noise of ``sigma``.
    Inside :func:`reused_noise` the blocks of a recipe drawn before are given again
    (not for ``velocity_draws``, a function whose draws its identity does not fix).

    Parameters
    ----------
    n_samples : int
        Samples of each replicate.
    sigma : float
        Standard deviation of white noise (units of the recorded channel, y or y').
    n_replicates : int
        Replicates in all.
    seed : int
        Seed of the stream (a generator instead is drawn from, never kept).
    block : int
        Replicates drawn at once (memory: block × samples floats).
    spectrum : NoiseSpectrum, optional
        The recorded channel's noise spectrum.
    spectrum_scale : float
        Factor from the spectrum's units to y (or y') units.
    velocity_draws : callable, optional
        ``velocity_draws(count, rng)``: ``count`` draws of the noise on the samples.

    Yields
    ------
    ndarray
        Shape (count, n_samples), count = ``block`` but for the last; ``n_replicates``
        rows in all.
    """
    key = _recipe(n_samples, sigma, n_replicates, seed, block, spectrum, spectrum_scale)
    if velocity_draws is not None:
        key = None  # a function whose draws its identity does not fix
    found = _found(key)
    if found is not None:
        yield from found
        return
    drawn = _draw(
        n_samples, sigma, n_replicates, seed, block, spectrum, spectrum_scale, velocity_draws
    )
    if key is None:
        yield from drawn
        return
    yield from _keep(key, spectrum, tuple(drawn), n_replicates * n_samples)


def derived_noise(
    n_samples: int,
    sigma: float,
    *,
    n_replicates: int,
    seed: int,
    block: int,
    derive: Callable[[NDArray], NDArray],
    derive_key: Hashable,
    spectrum: NoiseSpectrum | None = None,
    spectrum_scale: float = 1.0,
) -> Iterator[tuple[NDArray, NDArray]]:
    """The recorded channel's noise and a linear derivation of it, ``block``
    replicates at a time (module notes).

    Parameters
    ----------
    n_samples, sigma, n_replicates, seed, block, spectrum, spectrum_scale
        The noise's recipe, as for :func:`recorded_noise` (whose noise this is, to the
        bit).
    derive : callable
        A derivation linear in its input, applied along the last axis: rows (count,
        n_samples) -> rows (count, n_samples) (the Savitzky-Golay derivative of the
        displacement's noise, in y' units).
    derive_key : hashable
        Every setting of ``derive`` (its kind, window, order, step): inside
        :func:`reused_noise` the derived blocks are kept under the recipe and it, an
        entry of as many floats as the noise's own (twice the recipe's in all).

    Yields
    ------
    tuple of ndarray
        The noise and its derivation, each of shape (count, n_samples).
    """
    noise = recorded_noise(
        n_samples,
        sigma,
        n_replicates=n_replicates,
        seed=seed,
        block=block,
        spectrum=spectrum,
        spectrum_scale=spectrum_scale,
    )
    key = _recipe(n_samples, sigma, n_replicates, seed, block, spectrum, spectrum_scale)
    if key is None:
        for draw in noise:
            yield draw, derive(draw)
        return
    # the derivation kept beside the noise (which recorded_noise keeps as its own
    # entry, the same numbers for a recipe of either channel)
    derived_key = (*key, "derived", derive_key)
    found = _found(derived_key)
    if found is not None:
        yield from zip(noise, found, strict=True)
        return
    blocks = tuple(noise)
    derived = _keep(
        derived_key, spectrum, tuple(derive(b) for b in blocks), n_replicates * n_samples
    )
    yield from zip(blocks, derived, strict=True)


def _recipe(
    n_samples: int,
    sigma: float,
    n_replicates: int,
    seed: int,
    block: int,
    spectrum: NoiseSpectrum | None,
    spectrum_scale: float,
) -> tuple | None:
    """The key of a recipe's draws inside :func:`reused_noise`: every input the draws
    depend on, the spectrum by identity (kept alive by the entry, so that its id is not
    reused); None outside it, for a seed that is not an integer, or above the limit."""
    if (
        _KEPT.get() is None
        or not isinstance(seed, int | np.integer)
        or n_replicates * n_samples > KEEP_LIMIT
    ):
        return None
    return (
        int(n_samples),
        float(sigma),
        int(n_replicates),
        int(seed),
        int(block),
        None if spectrum is None else id(spectrum),
        float(spectrum_scale),
    )


def _found(key: tuple | None) -> tuple[NDArray, ...] | None:
    """The blocks kept under ``key``, made the most recently used (the first to be let
    go is the oldest), or None."""
    kept = _KEPT.get()
    if key is None or kept is None or key not in kept:
        return None
    kept[key] = entry = kept.pop(key)
    return entry[1]


def _keep(
    key: tuple, spectrum: NoiseSpectrum | None, blocks: tuple[NDArray, ...], size: int
) -> tuple[NDArray, ...]:
    """Keep ``blocks`` (``size`` floats in all) under ``key``, read-only, letting go of
    the oldest entries to stay within :data:`KEEP_LIMIT`."""
    kept = _KEPT.get()
    assert kept is not None
    for b in blocks:
        b.flags.writeable = False
    while kept and sum(entry[2] for entry in kept.values()) + size > KEEP_LIMIT:
        del kept[next(iter(kept))]
    kept[key] = (spectrum, blocks, size)
    return blocks


def _draw(
    n_samples: int,
    sigma: float,
    n_replicates: int,
    seed: int,
    block: int,
    spectrum: NoiseSpectrum | None,
    spectrum_scale: float,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None,
) -> Iterator[NDArray]:
    """The blocks of :func:`recorded_noise`, drawn."""
    rng = np.random.default_rng(seed)
    for first in range(0, n_replicates, block):
        count = min(block, n_replicates - first)
        # one (count, samples) draw is the same stream as ``count`` draws of a row
        if velocity_draws is not None:
            yield velocity_draws(count, rng)
        elif spectrum is not None:
            yield spectrum_scale * colored_noise(spectrum, n_samples, rng, count)
        else:
            yield rng.normal(0.0, sigma, (count, n_samples))


@contextlib.contextmanager
def reused_noise() -> Iterator[None]:
    """Keep the noise :func:`recorded_noise` draws inside the block for the calls
    that follow in it.

    Every call with the same recipe inside the block gives the blocks the first drew
    (the same numbers: they depend on those inputs alone). Nested blocks share the
    outer one's; what was kept is released when the outermost block ends. Usable as
    a decorator too.

    Examples
    --------
    >>> from bayestribo.signal.channel_noise import recorded_noise, reused_noise
    >>> with reused_noise():
    ...     a = next(recorded_noise(4, 1.0, n_replicates=2, seed=1, block=2))
    ...     b = next(recorded_noise(4, 1.0, n_replicates=2, seed=1, block=2))
    >>> a is b
    True
    """
    if _KEPT.get() is not None:
        yield
        return
    token = _KEPT.set({})
    try:
        yield
    finally:
        _KEPT.reset(token)
