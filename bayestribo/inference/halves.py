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
estimated from n₁, n₂ effective draws,

.. math::  z_i = (m_1 - m_2) / \sqrt{s_1^2 (1 + 1/n_1) + s_2^2 (1 + 1/n_2)}

(the terms s²/n: the Monte Carlo error of the estimated means,
:mod:`bayestribo.inference.halves_statistic`),

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

Draws. ΔE(A) of a law without a closed form is integrated draw by draw where its
interpolation misses (some 0.5 ms a draw and swing). :data:`N_FIRST_DRAWS` draws of
each half are evaluated first; where the verdict they give clears the threshold by
four Monte Carlo standard deviations of z (the means' error and the sds' own, from
the draws' kurtosis: :func:`bayestribo.inference.halves_statistic.verdict_is_clear`),
more draws would not change it and it stands; otherwise :data:`N_DRAWS` draws are
evaluated, and the verdict is theirs. On HarmOsc2 under ``coulomb+power`` (halves
6.5-7.2 sd apart) 200 draws settle it, as they do for halves well within their noise.

Weights. A half whose surrogate of Π misses its check by a little would have every
draw of its run resampled to the exact posterior by its importance weights
(:mod:`bayestribo.inference.correction`: the exact Π at some 1,600 draws, 0.5-1 s on
HarmOsc2's second half). The check uses a few hundred draws, so each half is sampled
with ``weighted`` (:func:`bayestribo.inference.law_frame.sample_law`): a surrogate's
run whose check fails is kept as it is where the weights of :data:`N_FIRST_DRAWS` of
its draws hold (cv at most :data:`~bayestribo.inference.correction.MAX_WEIGHTED_CV`,
0.6, Pareto k̂ at most 0.5; the first surrogate's included: on HarmOsc2's second half
its cv is 0.3-0.5, and four further surrogates cost 1-1.5 s), and the draws the check
uses are weighted by exact over surrogate density
(:func:`bayestribo.inference.correction.weights_at`), their effective number Kish's,
which the limits keep the weighted means' Monte Carlo error.
Where the weights of the draws used do not hold, that half is fitted again as a fit of
the law alone is (resampled, or sampled further), with its own seed, once: where its
weights still do not hold (the same seed gives the same draws), the halves are not
compared, and the note says which half and why. A half whose run stopped on a ridge
that half does not identify (:func:`bayestribo.inference.sampling.run_ensembles`'s
``unidentified``: coulomb+power on half of the galileo-encoder-17s pendulum, a friction
at zero and μ_s/μ_k free) measures no ΔE(A) to compare: the check ends there, before
the other half is fitted, its note giving the run's reasons.

A run too short to split (fewer than :data:`MIN_HALF_CYCLES` half cycles in a half),
or a half that cannot be prepared or fitted, is not tested; the result says why.
"""

from __future__ import annotations

import math
import re
import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.correction import MAX_WEIGHTED_CV, evenly_spaced, weights_at
from bayestribo.inference.dissipation import _swing_dissipation
from bayestribo.inference.halves_statistic import (
    SwingDifference,
    swing_difference,
    verdict_is_clear,
    weighted_moments,
)
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
#: Draws of each half evaluated first: where they settle the verdict beyond their
#: Monte Carlo error (:func:`bayestribo.inference.halves_statistic.verdict_is_clear`),
#: the :data:`N_DRAWS` are not evaluated.
N_FIRST_DRAWS = 200


#: The advice of :func:`~bayestribo.inference.identifiability.unidentified_reasons`
#: to fit a law without a term, at the end of a reason.
_LEAVE_OUT = re.compile(r"; the [\w+-]+ term can be left out: .*$")

#: One half's ΔE(A) draws, their importance weights (None: equal) and effective number.
Side = tuple[NDArray, NDArray | None, float]


class _Unweighable(Exception):
    """A half's surrogate draws whose importance weights are not reliable."""


def _draws(
    sampled: Any, prepared: PreparedRun, amplitude: NDArray, count: int
) -> tuple[NDArray, NDArray | None]:
    """ΔE(A)/k [length unit²] of ``count`` of a half's posterior draws (evenly spaced over
    every chain) at the swings ``amplitude`` [length unit], shape (draws, swings), and
    their importance weights (None: equal).

    The draws of a surrogate posterior not corrected (:func:`bayestribo.inference.
    law_frame.sample_law` with ``weighted``) are weighted by the exact posterior's
    density over the surrogate's (:func:`bayestribo.inference.correction.weights_at`);
    :class:`_Unweighable` where those weights are not reliable."""
    posterior = sampled.posterior
    picks = evenly_spaced(sampled.run, count)
    weights = None
    check = sampled.surrogate
    if sampled.surrogate_posterior is not None and check is not None and not check.passed:
        weights = check.weights
        if weights is None or weights.size != picks.size:
            # not those the sampler weighted already (the same draws, the same density)
            weights = weights_at(sampled.run, posterior, picks, MAX_WEIGHTED_CV)
        if weights is None:
            raise _Unweighable("the importance weights of its draws are not reliable")
    flat = sampled.run.chains.reshape(-1, sampled.run.chains.shape[-1])
    ell = float(prepared.decay.scaling.length_scale)
    values = posterior.law_draws(flat[picks])
    ref = posterior.likelihood.reference_amplitude
    dimensionless = _swing_dissipation(posterior.law, amplitude / ell, values, ref)
    return np.asarray(dimensionless, dtype=float) * ell**2, weights


def _effective_fraction(sampled: Any) -> float:
    """The chains' effective sample size over their draws (the smallest over the
    parameters), at most 1: the share of evenly spaced draws that count as independent
    (fewer draws than that are further apart, so this errs on the side of fewer)."""
    run = sampled.run
    total = run.chains.shape[0] * run.chains.shape[1]
    ess = np.asarray(run.ess, dtype=float)
    smallest = float(np.nanmin(ess)) if ess.size and np.isfinite(ess).any() else math.nan
    if not (total > 0 and smallest > 0):
        return 1.0
    return min(1.0, smallest / total)


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
    bounds = ((0, k + 1), (k, stop))
    seeds = [int(rng.integers(2**31)) for _ in bounds]

    def fit_half(i: int, weighted: int) -> tuple[Any, PreparedRun, NDArray]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            half = prepare_part(prepared, *bounds[i])
            half, sampled = sample_law(
                half,
                the_law,
                model=model,
                discrepancy=discrepancy,
                settings=settings,
                seed=seeds[i],
                weighted=weighted,
            )
        own = np.abs(np.asarray(half.decay.peaks.value, dtype=float))
        return sampled, half, 0.5 * (own[1:] + own[:-1]) if own.size > 1 else own

    halves = []
    for i, which in enumerate(("first", "second")):
        try:
            halves.append(fit_half(i, weighted=N_FIRST_DRAWS))
        except BayestriboError as exc:
            return LawHalves(
                the_law.name, False, cut_time, note=f"the {which} half was not fitted: {exc}"
            )
        if halves[i][0].run.ridge:
            # stopped on a ridge the half does not identify (its reasons say which):
            # its draws measure no ΔE(A) to compare, the other half is not fitted
            return LawHalves(the_law.name, False, cut_time, note=_ridge_note(which, halves[i][0]))
    refitted: set[int] = set()
    for count in (N_FIRST_DRAWS, N_DRAWS):
        compared = None
        while compared is None:
            try:
                compared = _compared(halves, amplitude, count)
            except _Unweighable as exc:
                i = exc.args[1]
                which = ("first", "second")[i]
                if i in refitted:
                    # fitted as a fit of the law alone is, its draws still the
                    # surrogate's and their weights not reliable (a run stopped on a
                    # ridge the half does not identify): the same fit again gives the
                    # same draws
                    return LawHalves(
                        the_law.name, False, cut_time, note=_unweighable_note(which, halves[i][0])
                    )
                # that half's surrogate run resampled by its importance weights at every
                # draw, or sampled further, as a fit of the law alone does (same seed)
                refitted.add(i)
                try:
                    halves[i] = fit_half(i, weighted=0)
                except BayestriboError as err:
                    note = f"the {which} half was not fitted: {err}"
                    return LawHalves(the_law.name, False, cut_time, note=note)
                continue
            break
        if compared is None:
            return LawHalves(
                the_law.name,
                False,
                cut_time,
                note="no swing at which both halves' draws have a half cycle",
            )
        used, (d1, w1, n1), (d2, w2, n2), difference = compared
        if verdict_is_clear(difference, HALVES_P):
            break
    (_, _, r1), (_, _, r2) = halves
    unit = prepared.run.length_unit
    unit = "signal unit" if unit == "arbitrary" else unit

    def side(d: NDArray, w: NDArray | None, own: NDArray, draws: float) -> dict[str, Any]:
        mean, var, _ = weighted_moments(d, w)
        return {
            "mean": mean.tolist(),
            "sd": np.sqrt(var).tolist(),
            "range": [float(own.min()), float(own.max())],
            "draws": draws,
        }

    return LawHalves(
        the_law.name,
        True,
        cut_time,
        used.tolist(),
        f"{unit}^2",
        side(d1, w1, r1, n1),
        side(d2, w2, r2, n2),
        difference.largest,
        int(difference.z.size),
        difference.p_value,
        agree=not (difference.p_value < HALVES_P),
    )


def _ridge_note(which: str, sampled: Any) -> str:
    """Why the halves are not compared: the ``which`` half's run stopped on a ridge."""
    # the advice to leave a term out is the half's, not the whole record's (which
    # the law fits with it): it is not repeated here
    reasons = "; ".join(
        _LEAVE_OUT.sub("", reason).replace("this record does not", "the half does not")
        for reason in sampled.run.reasons[:2]
    )
    return f"the {which} half's fit stopped on a ridge that half does not identify ({reasons})"


def _unweighable_note(which: str, sampled: Any) -> str:
    """Why the ``which`` half's draws are not compared: its surrogate posterior's
    importance weights are not reliable, even after a fit of the law alone (and why
    its run stopped, where it did not converge)."""
    note = (
        f"the {which} half's draws are not compared: they are its quadratic surrogate's, "
        "whose importance weights to the exact posterior are not reliable"
    )
    run = sampled.run
    if not run.converged and run.reasons:
        note += f" (its run did not converge: {run.reasons[0]})"
    return note


def _compared(
    halves: list[tuple[Any, PreparedRun, NDArray]], amplitude: NDArray, count: int
) -> tuple[NDArray, Side, Side, SwingDifference] | None:
    """``count`` draws of each half's ΔE(A) at ``amplitude``: the swings at which both
    halves' draws have a half cycle (95 % of them or more; the draws without one left
    out), each half's draws there, their importance weights (None: equal) and their
    effective number, and the difference there; None when no swing (or fewer than two
    draws) is left. Raises :class:`_Unweighable` with the half's index."""
    drawn = []
    for i, (sampled, half, _) in enumerate(halves):
        try:
            drawn.append(_draws(sampled, half, amplitude, count))
        except _Unweighable as exc:
            raise _Unweighable(str(exc), i) from exc
    (d1, w1), (d2, w2) = drawn
    usable = np.mean(np.isfinite(d1), axis=0) >= 0.95
    usable &= np.mean(np.isfinite(d2), axis=0) >= 0.95
    if usable.sum() < 1:
        return None
    sides = []
    for (d, w), (sampled, _, _) in zip(drawn, halves, strict=True):
        keep = np.all(np.isfinite(d[:, usable]), axis=1)
        d, w = d[:, usable][keep], None if w is None else w[keep]
        if d.shape[0] < 2 or (w is not None and not w.sum() > 0):
            return None
        # Kish's number of the weighted draws, of the evenly spaced ones as they are
        kish = d.shape[0] if w is None else float(w.sum() ** 2 / np.sum(w * w))
        sides.append((d, w, max(2.0, kish * _effective_fraction(sampled))))
    (d1, w1, n1), (d2, w2, n2) = sides
    difference = swing_difference(d1, d2, n1, n2, weights=(w1, w2))
    return amplitude[usable], (d1, w1, n1), (d2, w2, n2), difference
