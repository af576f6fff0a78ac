"""The recorded channel's Monte Carlo noise, drawn once per record and recipe.

When one channel is derived from the other (a Savitzky-Golay derivative of the
displacement, or the integral of the velocity), the increments' noise is found by
drawing noise on the recorded channel, adding it to the motion and repeating the
derivation (:func:`bayestribo.signal.increments.increment_draws`). The noise drawn
depends on the record and the recipe alone (samples, replicates, seed, noise level or
spectrum), not on the motion it is added to: the second pass of every law compared on
one record (:mod:`bayestribo.inference.reweight`) draws the same numbers.
:func:`recorded_noise` gives them; inside :func:`reused_noise` (a comparison of laws,
:func:`bayestribo.inference.comparison.compare_prepared`, and ``fit(..., law="auto")``
from its first pass on) it keeps them, keyed by every input that determines them, so
that each law's second pass finds them drawn by the first pass. The derivation is
repeated on each motion as before, so every increment variance is the same, to the
last bit, as drawing the noise again; what is saved is the drawing, the larger part for
coloured noise (300 replicates of 10,822 samples shaped in frequency on HarmOsc3: 0.39
of the 0.59 s a second pass took; the rest is the derivative filter, 85 samples wide).
Inside one, at most :data:`KEEP_LIMIT` floats are kept in all, the recipes used longest
ago let go first (a comparison's laws use one recipe in a row, the verdict's frame and
each half of the motion theirs after it); outside, nothing is kept.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Callable, Iterator

import numpy as np
from numpy.typing import NDArray

from bayestribo.signal.spectrum import NoiseSpectrum, colored_noise

__all__ = ["KEEP_LIMIT", "recorded_noise", "reused_noise"]

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
    kept = _KEPT.get()
    key = None
    if (
        kept is not None
        and velocity_draws is None
        and isinstance(seed, int | np.integer)
        and n_replicates * n_samples <= KEEP_LIMIT
    ):
        # every input the draws depend on; the spectrum by identity (kept alive by
        # the entry, so that its id is not reused)
        key = (
            int(n_samples),
            float(sigma),
            int(n_replicates),
            int(seed),
            int(block),
            None if spectrum is None else id(spectrum),
            float(spectrum_scale),
        )
        if key in kept:
            # the most recently used last: the first to be let go is the oldest
            kept[key] = entry = kept.pop(key)
            yield from entry[1]
            return
    drawn = _draw(
        n_samples, sigma, n_replicates, seed, block, spectrum, spectrum_scale, velocity_draws
    )
    if key is None:
        yield from drawn
        return
    blocks = tuple(drawn)
    for b in blocks:
        b.flags.writeable = False
    size = n_replicates * n_samples
    while kept and sum(entry[2] for entry in kept.values()) + size > KEEP_LIMIT:
        del kept[next(iter(kept))]
    kept[key] = (spectrum, blocks, size)
    yield from blocks


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
