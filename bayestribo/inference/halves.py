r"""Does the law hold along the decay? The chosen law fitted to each half of the motion.

A law that describes the whole decay by constants must describe each part of it by
the same constants. A law with a free shape (a power of the speed, a friction and a
drag together) can bend to fit a decay whose dissipation changes along the motion
for another reason (a lubricant film that thins, a contact that wears in, a mount
that loosens): fitted to the whole, it passes the misfit tests of
:func:`bayestribo.inference.checks.check`, yet its halves disagree. On the
AppStat2020 HarmOsc2 recording, ``coulomb+power`` fits the whole decay, and the
friction of its first half is 4.7 standard deviations from the second's.

The check. The run is cut at the turning point in the middle of the analysed half
cycles (the cut sample in both halves; a motion that fades into the noise ends an
oscillation after its last turning point found); each half is prepared as the whole was,
with its noise model (:func:`bayestribo.inference.preparation.prepare_part`), and the law
fitted to it (:func:`bayestribo.inference.law_frame.sample_law`,
the same sampler and law). Each half's posterior gives the energy dissipated per cycle
at swings spanning the whole motion, ΔE(A)/k (in the length unit squared, so that the
two halves' own measured frequencies do not enter): each half predicts the other
half's range. With m₁, m₂ the posterior means and s₁, s₂ the standard deviations of
the draws at each swing (the halves share no increment, their noise is independent),

.. math::  z_i = (m_1 - m_2) / \sqrt{s_1^2 + s_2^2},

and the halves disagree when the largest |z_i| is beyond what chance gives at
:data:`HALVES_P` (that of the misfit tests, 1e-3) over the n swings compared:
the Bonferroni p-value ``min(1, 2 n Φ(-max|z_i|))``, which holds whatever the
correlation between the swings (strong: a law has few parameters) and is at most n
times too large (|z| of 3.84 at n = 8, against 3.29 for one swing). A χ² on the
covariance of the differences was tried and set aside: a law's ΔE(A) at many swings
spans a few directions, and where the halves differ most (a friction that the first
half barely sees, extrapolated to the smallest swings) the χ² on those directions
diluted a 5-sd difference to p = 1e-3, on one side of the threshold or the other with
the seed. Swings at which a draw has no half cycle (a friction that holds the
motion, a drag that stops it) are left out.

A run too short to split (fewer than :data:`MIN_HALF_CYCLES` half cycles in a half),
or a half that cannot be prepared or fitted, is not tested; the result says why.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.dissipation import _swing_dissipation
from bayestribo.inference.law_frame import sample_law
from bayestribo.inference.preparation import prepare_part
from bayestribo.inference.records import LawHalves
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.types import MISFIT_P, PreparedRun
from bayestribo.model.laws import Law, get_law

__all__ = ["HALVES_P", "MIN_HALF_CYCLES", "LawHalves", "law_halves"]

#: The p-value below which the halves disagree (that of the misfit tests).
HALVES_P = MISFIT_P
#: The fewest half cycles each half must hold to be fitted apart.
MIN_HALF_CYCLES = 8
#: Swings at which the halves' ΔE(A) are compared, log-spaced over the whole motion.
N_SWINGS = 8
#: Posterior draws of each half evaluated (evenly spaced over every chain).
N_DRAWS = 1000


def _draws(sampled: Any, prepared: PreparedRun, amplitude: NDArray) -> NDArray:
    """ΔE(A)/k [length unit²] of ``N_DRAWS`` of a half's posterior draws at the swings
    ``amplitude`` [length unit], shape (draws, swings)."""
    posterior = sampled.posterior
    flat = sampled.run.chains.reshape(-1, sampled.run.chains.shape[-1])
    flat = flat[np.linspace(0, flat.shape[0] - 1, min(N_DRAWS, flat.shape[0])).astype(int)]
    ell = float(prepared.decay.scaling.length_scale)
    values = posterior.law_draws(flat)
    ref = posterior.likelihood.reference_amplitude
    dimensionless = _swing_dissipation(posterior.law, amplitude / ell, values, ref)
    return np.asarray(dimensionless, dtype=float) * ell**2


def law_halves(
    prepared: PreparedRun,
    law: str | Law,
    *,
    seed: int | np.random.Generator | None = None,
    settings: SamplerSettings | None = None,
    model: str = "exact",
    discrepancy: bool = False,
) -> LawHalves:
    """Fit ``law`` to each half of the analysed motion and compare their ΔE(A).

    Parameters
    ----------
    prepared : PreparedRun
        The whole run, from :func:`bayestribo.inference.preparation.prepare`.
    law : str or Law
        The law fitted to each half.
    seed : int, Generator or None
        Seed of the two fits.
    settings : SamplerSettings, optional
        Sampler size of each half's fit.
    model, discrepancy
        As in :func:`bayestribo.inference.fit`.

    Returns
    -------
    LawHalves
        ``agree`` False when the halves measure different ΔE(A) (module notes).
    """
    the_law = law if isinstance(law, Law) else get_law(law)
    decay = prepared.decay
    times = decay.turning_times
    if times is None:
        times = decay.peaks.time
    times = np.asarray(times, dtype=float)
    n = times.size
    if n < 2 * MIN_HALF_CYCLES + 1:
        return LawHalves(
            the_law.name,
            False,
            note=f"{n} turning points, fewer than the {2 * MIN_HALF_CYCLES + 1} two halves need",
        )
    cut_time = float(times[n // 2])
    run = prepared.run
    k = int(np.argmin(np.abs(run.time - cut_time)))
    turning = np.abs(np.asarray(decay.peaks.value, dtype=float))
    swings = 0.5 * (turning[1:] + turning[:-1])
    amplitude = np.geomspace(swings.min(), swings.max(), N_SWINGS)
    # a motion that fades into the noise ends the second half an oscillation after its
    # last turning point found (the noise after it carries no decay); one that stops
    # keeps its rest (where its end is found)
    stop = run.time.size
    if not decay.motion_ended:
        end = min(decay.end_time, times[-1] + 1.0 / decay.natural_frequency_Hz)
        stop = int(np.searchsorted(run.time, end, side="right"))
    rng = np.random.default_rng(seed)
    halves = []
    for first, last in ((0, k + 1), (k, stop)):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                half = prepare_part(prepared, first, last)
                half, sampled = sample_law(
                    half,
                    the_law,
                    model=model,
                    discrepancy=discrepancy,
                    settings=settings,
                    seed=int(rng.integers(2**31)),
                )
        except BayestriboError as exc:
            which = "first" if not halves else "second"
            return LawHalves(
                the_law.name, False, cut_time, note=f"the {which} half was not fitted: {exc}"
            )
        own = np.abs(np.asarray(half.decay.peaks.value, dtype=float))
        own_swings = 0.5 * (own[1:] + own[:-1]) if own.size > 1 else own
        halves.append((_draws(sampled, half, amplitude), own_swings))
    (d1, r1), (d2, r2) = halves
    usable = np.mean(np.isfinite(d1), axis=0) >= 0.95
    usable &= np.mean(np.isfinite(d2), axis=0) >= 0.95
    if usable.sum() < 1:
        return LawHalves(
            the_law.name,
            False,
            cut_time,
            note="no swing at which both halves' draws have a half cycle",
        )
    amplitude = amplitude[usable]
    d1 = d1[:, usable][np.all(np.isfinite(d1[:, usable]), axis=1)]
    d2 = d2[:, usable][np.all(np.isfinite(d2[:, usable]), axis=1)]
    m1, m2 = d1.mean(axis=0), d2.mean(axis=0)
    z = (m1 - m2) / np.hypot(d1.std(axis=0, ddof=1), d2.std(axis=0, ddof=1))
    z = np.where(np.isfinite(z), z, 0.0)
    largest = float(np.max(np.abs(z)))
    p = float(min(1.0, 2.0 * z.size * scipy.stats.norm.sf(largest)))
    unit = prepared.run.length_unit
    unit = "signal unit" if unit == "arbitrary" else unit

    def side(d: NDArray, own: NDArray) -> dict[str, Any]:
        return {
            "mean": d.mean(axis=0).tolist(),
            "sd": d.std(axis=0, ddof=1).tolist(),
            "range": [float(own.min()), float(own.max())],
        }

    return LawHalves(
        the_law.name,
        True,
        cut_time,
        amplitude.tolist(),
        f"{unit}^2",
        side(d1, r1),
        side(d2, r2),
        largest,
        int(z.size),
        p,
        agree=not (p < HALVES_P),
    )
