"""Which dissipation law does a run support? Fits under several laws, compared.

Each run is fitted under every law asked for with the single-run model of
:mod:`bayestribo.inference` (the same Π increments, noise model, likelihood and
sampler). A law is a name of :mod:`bayestribo.model.laws` (terms joined with ``+``);
the original three-way comparison's names stay valid:

* ``"viscous"``: ζ free, no friction (μ_k = μ_s = 0);
* ``"coulomb"``: friction free (μ_k, μ_s/μ_k), ζ = 0;
* ``"both"``: ζ and friction free (``viscous+coulomb``, the default fit of a run with
  contact).

Candidates. ``fit(..., law="auto")`` compares :func:`auto_laws`, the laws the rule of
:mod:`bayestribo.model.laws.candidates` builds from the registry of terms: every term
alone, every pair of terms and the paper's law with one more term, but no law holding
a term and one it overlaps (a term's registration says which: power-law drag overlaps
viscous damping, quadratic drag and the friction proportional to amplitude; that
friction overlaps viscous damping). A term a lab registers is a candidate with no edit
here.

The laws are compared by their expected log pointwise predictive density estimated
with Pareto-smoothed importance-sampling leave-one-out cross-validation (PSIS-LOO,
Vehtari, Gelman & Gabry 2017) over the Π increments, through
:func:`arviz.compare`, and each is checked for misfit at its optimum (the χ² of the
residuals and the test for a smooth departure along the decay,
:func:`bayestribo.inference.checks.check`): a law is *adequate* when neither
has a p-value below 1e-3.

Verdict. The law with the highest ``elpd_loo`` is the best. A law is *as good* as
the best when its difference is below 4 or below two standard errors of the
difference (Sivula, Magnusson & Vehtari 2020: smaller differences are not reliably
resolved). The verdict is the simplest adequate law among those as good as the best
(fewest terms, then fewest parameters, then the order of the laws compared, not the
PSIS-LOO rank, which is noise between laws this close). A friction ``η k |X_n|`` and
viscous damping of the same half-cycle ratio make the same turning points, and a decay
sampled one Π increment per half cycle hardly tells them apart (``benchmarks/laws.py``:
elpd differences below 1); their ΔE(A) is the same
(:mod:`bayestribo.inference.dissipation`). Such rivals are compared again on a finer
grid (below), and the verdict names the laws as good as it. When none of them is
adequate, the verdict is the simplest converged law as good as the best, and the
comparison says that no law compared holds: the ΔE(A) measured from the turning points
is then the answer. A Pareto k above 0.7 is reported, since the estimate is then
unreliable for that law.

Optima. The laws are taken to their optima smallest first. A law of one term starts
from the first guesses of :func:`bayestribo.inference.start.maximum_a_posteriori` (a
multi-start), and so does a law of several terms where one of its laws of one term
fewer has no optimum (not compared, or not fitted); otherwise it starts at each of those
laws' optima, the missing term at a small value
(:func:`bayestribo.inference.reduction.nested_starts`), and keeps the best optimum
(:func:`bayestribo.inference.start.maximum_from_starts`). Its optimum lies along one of
them, where one of its terms takes the loss the others leave (the two arms of
``coulomb+power``'s L are ``coulomb`` and ``power``): on the two bundled runs and the 17 real
recordings the speed goals take (the rotary pendulum's on its restoring force), the
seven laws of two or three terms reached an optimum as good as the multi-start's
(within 0.01 of log density) on 128 of the 133 and a better one on 5 (by 0.01 to 3.9),
where the multi-start's first guesses stopped short, in 0.38 of its CPU time over all
(0.03-0.78 a law; ``benchmarks/nested_starts.py``).

Reduction. A law whose extra terms the data put at zero at its optimum (within
:data:`~bayestribo.inference.reduction.REDUCTION_LOSS` of log density) *reduces* to the
largest law it nests that is fitted and converged already: it is not sampled and not
compared by PSIS-LOO (:mod:`bayestribo.inference.reduction`); its table row says
``reduces_to``, ``terms_at_zero``, ``sampled`` False and ``converged`` None, with the
misfit checks at its optimum, and the comparison's text names it. The law-free fit
never reduces. Such a law's second pass (the increments' variances from its motion, and
the optimum again: a third to two fifths of its optimiser's time) waits until it is
judged on its own (:class:`~bayestribo.inference.screening.LawOptimum`): where its
optimum is a law it nests, it stays out of the screen's estimates (it cannot be the
best there: it is the nested law with more parameters) unless that law is screened out
(its second pass is then made and the screen made again with it, as before), and its
second pass is made only where it is not reduced in the end (the nested law settled or
not converged); on air-r1 the three drag laws that reduce (``viscous+quadratic``,
``coulomb+power``, ``viscous+coulomb+quadratic``) never make theirs.

Screening. Every law is first taken to its optimum on the posterior it would be
sampled on; a law whose ΔE(A) cannot follow the turning points', or whose expected log
predictive density estimated at its optimum falls far behind the best one's, is
*screened out*, not sampled and not compared by PSIS-LOO
(:mod:`bayestribo.inference.screening`); so is a law that is, at its optimum, a law
screened out (its extra terms at zero, the rule of Reduction) and whose own estimate
is clearly behind the best's (``screen`` says ``reduces_to``); so is a law with at
least as many sampled parameters as the record has increments
(:func:`~bayestribo.inference.identifiability.too_few_increments`; ``screen`` says
stage ``increments``), where a law with fewer is left: its increments leave the
parameters free to trade along a ridge, which the sampler walks towards its ceiling
(``coulomb+hysteretic`` on the 4 increments of the bicycle wheel's axial gyro, not
converged; ``law="auto"`` there 9.3 s of CPU with it sampled, 2.5 s without,
``benchmarks/results/speed_goals_auto_compare.json``), and PSIS-LOO, leaving out one
of as few increments as parameters, does not estimate how it predicts. Its row says
``screened`` and ``screen``, with the misfit checks at its optimum, and the
comparison's text names it.

Settling. The laws left are sampled, the verdict their optima predict first and the
others smallest first (:func:`bayestribo.inference.settling.sampling_order`), and
before each the verdict and best among the laws sampled so far are known. A law that
misfits at its optimum (or holds there but is not as good as the best, so that its
draws would enter neither the averaged ΔE(A) nor the rivals' comparison), whose
estimated gain over them cannot push the verdict out nor make it the best by more than
noise, whose standing (as good as the best or not) is clear of the tie rule's edge by a
third of its reach, and that cannot be chosen (the verdict adequate, or simpler, or the
law behind) is *settled* there, not sampled (:mod:`bayestribo.inference.settling`); its
row says ``settled`` and ``settle`` (the estimate and its standing), it is in
``as_good`` when the estimate puts it there, and the comparison's text names it. Every
settled law is judged again against the final verdict and best, and sampled where it
could now change the choice. On HarmOsc1 the laws as good as ``quadratic`` by
PSIS-LOO there (``power``, ``quadratic+hysteretic``, ``coulomb+power`` and the law-free
fit, a third of the time ``law="auto"`` took) are settled as good, on HarmOsc3 the
``coulomb+power`` that ran to the step ceiling is settled behind
(``benchmarks/results/auto_speed_real.json``: the same verdicts and laws as good).

Rivals. Simplicity settles a tie between a law and one that nests it; it does not
settle one between laws of different mechanisms: viscous damping and a friction that
grows with amplitude (``hysteretic``) make the same turning points, so one increment
per half cycle cannot tell them apart, and the order of the laws would choose. Within
a half cycle they differ: a friction dissipates in proportion to |ẋ|, viscous damping
to ẋ², and the energy lost by a quarter of a half cycle is 0.146 of the half cycle's
loss against 0.091. When adequate laws as good as the verdict do not nest it (its
*rivals*), they and the verdict are compared again on :data:`TIE_GRID` increments per
half cycle (:func:`bayestribo.inference.preparation.regrid`), each law's optimiser
started at its optimum on the first grid (the same law on the same motion: the finer
grid moves it by about a posterior sd, far less than the first guesses are apart;
:func:`bayestribo.inference.start.maximum_from`, which falls back to the first guesses
where the density there is not finite); that comparison's verdict
replaces the first when it is adequate there, and the laws it rejects leave the laws as
good as the verdict. Otherwise the verdict stands, and the comparison says that the
finer grid did not tell them apart. The finer grid rests on white, independent channel
noise and on the calibration of both channels (:mod:`bayestribo.signal.increments`):
it only breaks the tie, and only with a law that holds on it; the posterior reported is
the verdict's on the half-cycle grid. (``benchmarks/laws.py``: a hysteretic decay at
10x the resolution, viscous misfits at p < 1e-300 on the finer grid and the true law
holds.) When at their optima on the finer grid every law's standing (as good as the
best there or not) is clear of the tie rule's edge by a third of its reach
(:func:`bayestribo.inference.settling.settle`), and the simplest law as good that holds
there is the first grid's verdict, no draws on the finer grid could change the outcome,
and the laws are not sampled there (the rivals' record says ``settled``, with each
law's estimate and misfit checks at its optimum).
"""

from __future__ import annotations

import os
import time
import warnings
import zlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo import DEFAULT_SEED
from bayestribo.errors import BayestriboError
from bayestribo.inference.build import build_posterior
from bayestribo.inference.chains import sample_from
from bayestribo.inference.checks import misfit, shape_departure
from bayestribo.inference.choice import (
    LAWS,
    SMALL_ELPD_DIFFERENCE,
    choose_law,
    complexity,
    law_of,
    loo_standing,
    tie_key,
    verdict_of,
)
from bayestribo.inference.identifiability import too_few_increments
from bayestribo.inference.loo import law_loo, loo_frame, pareto_k_max
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.preparation import prepare, regrid
from bayestribo.inference.records import LawComparison
from bayestribo.inference.reduction import (
    nested_start,
    nested_starts,
    reduction,
    reduction_among,
)
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.screening import (
    LawOptimum,
    optimum_elpd,
    screen,
    screened_by_reduction,
    turning_point_screen,
)
from bayestribo.inference.settling import sampling_order, settle
from bayestribo.inference.start import find_optimum, find_start
from bayestribo.inference.types import MISFIT_P, PreparedRun, Sampled
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.model.laws import Law, get_law
from bayestribo.model.laws.ahead import AheadCompiler, compile_ahead
from bayestribo.signal.channel_noise import reused_noise
from bayestribo.signal.increments import PiData

__all__ = [
    "LAWS",
    "LawComparison",
    "LawOptimum",
    "auto_laws",
    "compare_dissipation_laws",
    "compare_prepared",
    "optimum_elpd",
    "screen",
]


def auto_laws() -> tuple[str, ...]:
    """The laws ``law="auto"`` compares: :func:`bayestribo.model.laws.candidates.
    candidate_laws` of the registry as it is now (module notes, Candidates)."""
    from bayestribo.model.laws.candidates import candidate_laws

    return candidate_laws()


#: Increments per half cycle of the grid that compares rivals (module notes).
TIE_GRID = 4
#: Pareto k above which PSIS-LOO is unreliable.
PARETO_K_LIMIT = 0.7


def _posterior(law: str | Law, data: PiData, model: str, discrepancy: bool) -> Posterior:
    """The posterior of one law."""
    return build_posterior(data, model=model, discrepancy=discrepancy, law=law_of(law))


def _fit_law(
    law: str,
    prepared: PreparedRun,
    settings: SamplerSettings,
    rng: np.random.Generator,
    posterior: Posterior,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None],
) -> tuple[Sampled, Any]:
    """Sample one law's posterior from its optimum; also return its PSIS-LOO
    (:func:`bayestribo.inference.loo.law_loo`, pointwise).

    ``posterior`` and ``optimum`` are the second pass's (:func:`_optimise`), the
    posterior a fit of the law alone samples: it is sampled as it is, not reweighted
    a third time."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        start = find_start(posterior, prepared.decay, optimum=optimum, reweight=False)
        sampled = sample_from(start, settings=settings, seed=rng)
    return sampled, law_loo(sampled)


def _law_seed(root: np.random.SeedSequence, law: str) -> np.random.SeedSequence:
    """Each law's stream from the seed and the law's name alone (not from which other
    laws are compared); the original three keep the streams they had."""
    legacy = list(LAWS)
    if law in legacy:
        # as the original comparison spawned them (a fresh sequence: spawn counts calls)
        return np.random.SeedSequence(root.entropy).spawn(1 + len(legacy))[1 + legacy.index(law)]
    return np.random.SeedSequence(root.entropy, spawn_key=(1000 + zlib.crc32(law.encode()),))


def _optimise(
    law: str,
    prepared: PreparedRun,
    model: str,
    discrepancy: bool,
    optima: Mapping[str, dict[str, float]],
    start: Mapping[str, float] | None = None,
) -> LawOptimum:
    """A law's optimum on both passes and its pointwise log-likelihood there; with
    ``start`` (its optimum on another grid of the run, by coordinate), the optimiser
    starts there rather than from the first guesses (module notes, Rivals); a law of
    several terms whose laws of one term fewer all have their optimum in ``optima``
    starts at each of those optima instead (module notes, Optima). The second pass is
    made when first asked for (:attr:`LawOptimum.pending`)."""
    from bayestribo.inference.start import better_optimum, maximum_from, maximum_from_starts

    # friction terms are fitted without contact too (as a friction displacement): the
    # data, not the metadata, decide whether there is friction to see
    posterior = _posterior(law, prepared.data, model, discrepancy)
    nested = nested_start(law, prepared, optima)
    if start is not None and all(name in start for name in posterior.names):
        theta = np.array([start[name] for name in posterior.names], dtype=float)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            optimum = better_optimum(
                posterior, maximum_from(posterior, theta, prepared.decay), nested
            )
    elif (starts := nested_starts(law, prepared, optima)) is not None and all(
        name in nested_law for nested_law in starts for name in posterior.names
    ):
        optimum = maximum_from_starts(posterior, starts, prepared.decay)
    else:
        optimum = find_optimum(posterior, prepared.decay, also_start_at=nested)
    return LawOptimum(
        law, posterior, optimum, finish=lambda: _second_pass(posterior, prepared, optimum)
    )


def _second_pass(
    posterior: Posterior,
    prepared: PreparedRun,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None],
) -> tuple[Posterior, tuple[NDArray, NDArray, tuple[float, float] | None], NDArray]:
    """The second pass from a law's first-pass optimum, as :func:`bayestribo.inference.
    chains.sample` makes it, so that the law is judged on the posterior it would be
    sampled on: that posterior, its optimum and the pointwise log-likelihood there."""
    from bayestribo.inference.reweight import reweighted_posterior
    from bayestribo.inference.start import maximum_from

    second, second_optimum = posterior, optimum
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        reweighted = reweighted_posterior(posterior, prepared.decay, optimum[0])
        if reweighted is not None:
            second = reweighted
            second_optimum = maximum_from(reweighted, optimum[0], prepared.decay)
        theta = np.asarray(second_optimum[0], dtype=float)
        pointwise = np.asarray(second.pointwise(theta[None]), dtype=float)[0]
    return second, second_optimum, pointwise


def _checks(posterior: Posterior, theta: NDArray) -> dict[str, Any]:
    """The misfit checks at a point: χ², its p-value, the shape test and adequacy."""
    chi2, m, misfit_p = misfit(posterior, theta)
    shape = shape_departure(posterior, theta)
    return {
        "adequate": bool(misfit_p >= MISFIT_P and not shape.p_value < MISFIT_P),
        "chi2_map": chi2,
        "n_increments": m,
        "misfit_p": misfit_p,
        "shape_p": shape.p_value,
    }


@reused_noise()
def compare_prepared(
    prepared: PreparedRun,
    laws: Sequence[str],
    *,
    seed: int | None = DEFAULT_SEED,
    model: str = "exact",
    settings: SamplerSettings | None = None,
    discrepancy: bool = False,
    law_free: bool = False,
    rivals: bool = True,
    screening: bool = True,
    progress: Callable[[str], None] | None = None,
    starts: Mapping[str, Mapping[str, float]] | None = None,
    settle_adequate: bool = False,
    at_optima: dict[str, LawOptimum] | None = None,
) -> tuple[LawComparison, dict[str, Sampled]]:
    """Compare laws on a prepared run; also return each law's sampled posterior.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`bayestribo.inference.prepare`.
    laws : sequence of str
        Two or more laws (names of :mod:`bayestribo.model.laws`, or the original
        ``"viscous"``, ``"coulomb"``, ``"both"``).
    seed : int or None
        Seed; each law's stream depends on it and on the law's name alone.
    model, settings, discrepancy
        As in :func:`bayestribo.inference.fit`.
    law_free : bool
        When no law compared is adequate, also fit the law-free ``"free"`` law
        (:data:`bayestribo.model.laws.law.ALIASES`), a dissipation per cycle that is
        any increasing polynomial of the amplitude of degree 1 to 4.
    rivals : bool
        Compare the verdict's rivals again on a finer grid (module notes).
    screening : bool
        Sample only the laws that can still win, judged at their optima (module
        notes; :func:`screen`); False samples every law that does not reduce.
    progress : callable, optional
        Called with one line of text per law as the comparison goes (its optimum,
        then its sampling or why it is not sampled).
    starts : mapping, optional
        Law -> its optimum on another grid of the same run (values of its sampled
        coordinates by name): that law's optimiser starts there alone
        (:func:`bayestribo.inference.start.maximum_from`) rather than from the first
        guesses of :func:`bayestribo.inference.start.find_optimum` (the rivals'
        comparison on the finer grid, module notes).
    settle_adequate : bool
        Settle adequate laws as good as the best too where they cannot be chosen
        (:mod:`bayestribo.inference.settling`): for a comparison whose draws serve its
        choice alone (the rivals' on the finer grid); False (the default) settles an
        adequate law only when it is not as good as the best (the draws of one that is
        may enter the ΔE(A) averaged over the laws as good, or make it a rival).
    at_optima : dict, optional
        Filled with each law taken to its optimum (:class:`LawOptimum`, by law), for
        a caller that fits a law again on the same preparation (the verdict of
        ``law="auto"``, :mod:`bayestribo.inference.auto`).

    Returns
    -------
    LawComparison, dict of Sampled
    """
    laws = list(dict.fromkeys(laws))
    if len(laws) < 2:
        raise BayestriboError(f"laws: expected two or more laws to compare, got {laws}")
    for law in laws:
        law_of(law)
    # the laws not in the law cache compiled by worker processes while the comparison
    # goes on (model/laws/ahead.py)
    with compile_ahead() as ahead:
        return _compare_prepared(
            ahead,
            prepared,
            laws,
            seed=seed,
            model=model,
            settings=settings,
            discrepancy=discrepancy,
            law_free=law_free,
            rivals=rivals,
            screening=screening,
            progress=progress,
            starts=starts,
            settle_adequate=settle_adequate,
            at_optima=at_optima,
        )


def _compare_prepared(
    ahead: AheadCompiler,
    prepared: PreparedRun,
    laws: list[str],
    *,
    seed: int | None,
    model: str,
    settings: SamplerSettings | None,
    discrepancy: bool,
    law_free: bool,
    rivals: bool,
    screening: bool,
    progress: Callable[[str], None] | None,
    starts: Mapping[str, Mapping[str, float]] | None,
    settle_adequate: bool,
    at_optima: dict[str, LawOptimum] | None,
) -> tuple[LawComparison, dict[str, Sampled]]:
    """:func:`compare_prepared` on its checked arguments, the laws it takes to their
    optima compiled ahead by ``ahead``'s workers."""
    settings = settings or SamplerSettings()
    say = progress or (lambda text: None)
    root = np.random.SeedSequence(seed)
    loos, table, notes, runs = {}, {}, [], {}
    optima: dict[str, dict[str, float]] = {}
    equivalent: dict[str, str] = {}
    found: dict[str, LawOptimum] = {} if at_optima is None else at_optima
    spent: dict[str, tuple[float, float]] = {}
    # laws whose second pass waits, each with the law it nests that its optimum is
    deferred: dict[str, str] = {}

    def failed(law: str, exc: BayestriboError) -> None:
        # a law that cannot be fitted here is reported and left out of the comparison,
        # not a failure of the others
        table[law] = {"law": law_of(law).name, "error": str(exc), "converged": False}
        notes.append(f"{law}: not fitted ({exc})")

    def optimise(law: str, k: int, n: int) -> None:
        start, cpu = time.perf_counter(), time.process_time()
        try:
            at = _optimise(law, prepared, model, discrepancy, optima, start=(starts or {}).get(law))
            # a law whose optimum is a law it nests is that law there: its second pass
            # waits until it is judged on its own (module notes, Reduction)
            inner = [o for o in found if law_of(law).nests(law_of(o)) and o != law]
            nests = (
                reduction_among(law, at.posterior, at.optimum[0], inner, optima) if inner else None
            )
            if not screening or nests is None:
                at.pointwise  # noqa: B018  the second pass, made now
            else:
                deferred[law] = nests[0]
            found[law] = at
        except BayestriboError as exc:
            failed(law, exc)
            say(f"law {k}/{n} {law}: not fitted ({exc})")
            return
        optima[law] = dict(zip(found[law].posterior.names, found[law].optimum[0], strict=True))
        spent[law] = (time.perf_counter() - start, time.process_time() - cpu)
        say(f"law {k}/{n} {law}: optimum found ({spent[law][0]:.1f} s)")

    def elapsed(law: str, start: float, cpu: float) -> dict[str, float]:
        wall, used = spent.get(law, (0.0, 0.0))
        return {
            "seconds": wall + time.perf_counter() - start,
            "cpu_seconds": used + time.process_time() - cpu,
        }

    def at_optimum(law: str) -> dict[str, Any]:
        # the misfit checks at a law's second-pass optimum, computed once
        at = found[law]
        theta = np.asarray(at.second_optimum[0], dtype=float)
        if law not in misfits:
            misfits[law] = _checks(at.second, theta)
        return misfits[law]

    def unsampled(law: str, posterior: Posterior, theta: NDArray, checks: dict) -> dict:
        # the row of a law taken no further than a point of its posterior
        return {
            "law": law_of(law).name,
            "sampled": False,
            "converged": None,
            **checks,
            "map": {n: float(v) for n, v in zip(posterior.names, theta, strict=True)},
        }

    def settling(law: str) -> dict[str, Any] | None:
        # can the law still change the choice? judged at its optimum against the
        # verdict and the best of the laws sampled so far (module notes, Settling)
        at = found[law]
        checks = at_optimum(law)
        if not loos:
            return None
        best, differences = loo_standing(loos)
        sampled_laws = [other for other in rank if other in loos]
        _, _, verdict, adequate = choose_law(sampled_laws, best, differences, table)
        info = settle(
            (at.pointwise, at.n_parameters),
            (found[verdict].pointwise, found[verdict].n_parameters),
            (found[best].pointwise, found[best].n_parameters),
            verdict_adequate=adequate,
            loses_tie=tie_key(law, rank) > tie_key(verdict, rank),
            small=SMALL_ELPD_DIFFERENCE,
            adequate=bool(checks["adequate"]),
        )
        if checks["adequate"] and not settle_adequate and info["as_good"] is not False:
            # an adequate law as good as the best may enter the averaged ΔE(A) or be a
            # rival: its draws are needed
            info["settled"] = False
        return {**info, "verdict": verdict, "best": best}

    def settle_one(law: str, info: dict[str, Any], start: float, cpu: float) -> None:
        at = found[law]
        theta = np.asarray(at.second_optimum[0], dtype=float)
        table[law] = {
            **unsampled(law, at.second, theta, at_optimum(law)),
            "settled": True,
            "settle": info,
            **elapsed(law, start, cpu),
        }
        if screens.get(law):
            table[law]["screen"] = screens[law]
        settled.append(law)

    def sample_one(law: str, k: int, n: int, force: bool = False) -> None:
        start, cpu = time.perf_counter(), time.process_time()
        rng = np.random.default_rng(_law_seed(root, law))
        at = found[law]
        try:
            reduced = reduction(law, at.posterior, at.optimum[0], runs, optima)
            info = settling(law) if screening and not force and reduced is None else None
            if info is not None and info["settled"]:
                settle_one(law, info, start, cpu)
                say(
                    f"{law} ({k}/{n}): not sampled, cannot change the choice at its optimum "
                    f"({'as good as' if info['as_good'] else 'behind'} {info['best']}, "
                    f"verdict {info['verdict']})"
                )
                return
            if reduced is None:
                say(f"sampling {law} ({k}/{n})")
                sampled, loos[law] = _fit_law(
                    law, prepared, settings, rng, at.second, at.second_optimum
                )
        except BayestriboError as exc:
            failed(law, exc)
            return
        if reduced is not None:
            # its optimum is the nested law's: not sampled, not compared (module notes)
            theta = at.optimum[0]
            table[law] = {
                **unsampled(law, at.posterior, theta, _checks(at.posterior, theta)),
                "reduces_to": reduced[0],
                "terms_at_zero": reduced[1],
                **elapsed(law, start, cpu),
            }
            equivalent[law] = reduced[0]
            say(f"{law} ({k}/{n}): reduces to {reduced[0]} at its optimum, not sampled")
            return
        runs[law] = sampled
        s = sampled.run
        names = sampled.posterior.names
        best_row = np.unravel_index(np.argmax(s.log_prob), s.log_prob.shape)
        optima[law] = dict(zip(names, s.chains[best_row], strict=True))
        k_max = pareto_k_max(loos[law])
        table[law] = {
            "law": law_of(law).name,
            "pareto_k_max": k_max,
            "converged": bool(s.converged),
            **_checks(sampled.posterior, sampled.theta_map),
            "median": {n: float(np.median(s.chains[..., i])) for i, n in enumerate(names)},
            "sampled": True,
            **elapsed(law, start, cpu),
        }
        if screens.get(law):
            table[law]["screen"] = screens[law]
        if k_max > PARETO_K_LIMIT:
            notes.append(f"{law}: Pareto k up to {k_max:.2f}; its PSIS-LOO is unreliable")
        if not s.converged:
            notes.append(f"{law}: sampler not converged ({'; '.join(s.reasons)})")
        say(
            f"{law} ({k}/{n}): sampled in {table[law]['seconds']:.1f} s"
            + ("" if s.converged else ", not converged")
        )

    # smallest laws first: their optima are starting points of the laws that nest them
    ordered = sorted(laws, key=complexity)
    # the order of the laws compared, for ties of complexity (the law-free fit last)
    rank = [*ordered, *([] if "free" in ordered else ["free"])]
    misfits: dict[str, dict[str, Any]] = {}
    settled: list[str] = []
    # laws whose ΔE(A) cannot follow the turning points' are not taken to an optimum
    early = turning_point_screen(prepared, ordered) if screening else {}
    for law in ordered:
        if early.get(law, {}).get("screened"):
            table[law] = {
                "law": law_of(law).name,
                "sampled": False,
                "converged": None,
                "screened": True,
                "screen": {"stage": "turning points", **early[law]},
            }
    first = [law for law in ordered if law not in table]
    compiling = ahead.submit([law_of(law) for law in first])
    if compiling:
        say(
            f"compiling {compiling} of the laws on their first use, in {ahead.workers} "
            "worker processes (kept in the law cache for later runs)"
        )
    if len(first) < len(ordered):
        say(
            f"{len(ordered) - len(first)} of {len(ordered)} laws cannot follow the turning "
            "points' ΔE(A) (not fitted): " + ", ".join(law for law in ordered if law not in first)
        )
    for k, law in enumerate(first, 1):
        optimise(law, k, len(first))
    screens: dict[str, dict[str, Any]] = {}
    if screening and len(found) >= 2:
        screens = _screen_optima(found, deferred, failed)
    for law in ordered:
        if law in screens:
            screens[law] = {"stage": "optimum", **screens[law]}
    if screens:
        # a law that is, at its optimum, a law screened out goes with it (screening.py)
        screens.update(
            screened_by_reduction(
                ordered,
                screens,
                lambda law, out: reduction_among(
                    law, found[law].posterior, found[law].optimum[0], out, optima
                ),
            )
        )
    screened = [law for law in ordered if screens.get(law, {}).get("screened")]
    for law in screened:
        at = found[law]
        theta = np.asarray(at.second_optimum[0], dtype=float)
        table[law] = {
            **unsampled(law, at.second, theta, at_optimum(law)),
            "screened": True,
            "screen": screens[law],
            "seconds": spent[law][0],
            "cpu_seconds": spent[law][1],
        }
    if screened:
        say(
            f"{len(screened)} of {len(found)} laws cannot win at their optimum (not sampled): "
            + ", ".join(screened)
        )
    screened = [law for law in ordered if table.get(law, {}).get("screened")]
    survivors = [law for law in ordered if law in found and law not in screened]
    if screening:
        survivors = _outnumbered_out(
            survivors, found, prepared, table, unsampled, at_optimum, spent, say
        )
        screened = [law for law in ordered if table.get(law, {}).get("screened")]
    if screening and len(survivors) > 1:
        # the verdict the optima predict first: the laws after it are judged against it
        survivors = sampling_order(
            survivors,
            {
                law: (found[law].pointwise, found[law].n_parameters)
                for law in survivors
                if not found[law].pending
            },
            lambda law: bool(at_optimum(law)["adequate"]),
            rank,
            small=SMALL_ELPD_DIFFERENCE,
            leads=lambda law: (
                reduction_among(law, found[law].posterior, found[law].optimum[0], survivors, optima)
                is None
            ),
        )
    for k, law in enumerate(survivors, 1):
        sample_one(law, k, len(survivors))
    if law_free and not any(
        row.get("adequate") and (row.get("converged") or row.get("settled"))
        for row in table.values()
    ):
        # no law compared holds: the law-free fit, whose ΔE(A) is any increasing
        # polynomial of degree 1-4, says how much energy the decay loses
        free = get_law("free").name
        if free not in {law_of(law).name for law in laws}:
            laws = [*laws, "free"]
            optimise("free", 1, 1)
            if "free" in found:
                sample_one("free", 1, 1)
    # a law sampled later may have moved the verdict or the best: every settled law is
    # judged again against them, and sampled when it could now change the choice
    while settled:
        reopened = [law for law in settled if not (settling(law) or {}).get("settled")]
        if not reopened:
            break
        law = reopened[0]
        settled.remove(law)
        del table[law]
        say(f"{law}: the verdict moved; sampled after all")
        sample_one(law, 1, 1, force=True)
    for law in settled:
        table[law]["settle"] = {**table[law]["settle"], **(settling(law) or {})}
    loos = {law: loos[law] for law in rank if law in loos}
    if not loos or len(loos) + len(equivalent) + len(screened) + len(settled) < 2:
        raise BayestriboError(
            f"laws: fewer than two of {laws} could be fitted: " + "; ".join(notes)
        )
    frame = loo_frame(loos)
    for law, row in frame.items():
        table[law].update(
            {
                key: float(row[key])
                for key in ("rank", "elpd_loo", "p_loo", "elpd_diff", "weight", "se", "dse")
            }
        )
    best, as_good, verdict, adequate = verdict_of(list(loos), table, frame)
    # the settled laws as good as the best at their optimum stand beside the sampled
    as_good = [
        law
        for law in rank
        if law in as_good or (law in settled and table[law]["settle"]["as_good"])
    ]
    rematch = None
    if rivals and adequate:
        contenders = _rivals(verdict, as_good, table)
        if contenders:
            say(
                f"comparing {verdict} with {', '.join(contenders)} again on {TIE_GRID} "
                "increments per half cycle"
            )
            rematch = _compare_rivals(
                prepared,
                [verdict, *contenders],
                seed,
                model,
                settings,
                discrepancy,
                screening,
                starts={
                    law: dict(zip(at.posterior.names, at.optimum[0], strict=True))
                    for law, at in found.items()
                },
            )
            if rematch["decided"]:
                verdict = rematch["verdict"]
                as_good = [law for law in as_good if law in rematch["as_good"]]
    comparison = LawComparison(
        prepared.name,
        table,
        best,
        verdict,
        as_good,
        notes,
        adequate,
        rivals=rematch,
        equivalent=equivalent,
        screened=screened,
        settled=[law for law in rank if law in settled],
    )
    return comparison, runs


def _outnumbered_out(
    survivors: list[str],
    found: Mapping[str, LawOptimum],
    prepared: PreparedRun,
    table: dict[str, dict[str, Any]],
    unsampled: Callable[[str, Posterior, NDArray, dict], dict],
    at_optimum: Callable[[str], dict[str, Any]],
    spent: Mapping[str, tuple[float, float]],
    say: Callable[[str], None],
) -> list[str]:
    """The laws left to sample once those with at least as many sampled parameters as
    the record's increments are screened out (module notes, Screening): their
    increments leave the parameters free to trade along a ridge, which the sampler
    walks to its ceiling, and PSIS-LOO, leaving out one of as few increments as
    parameters, does not estimate how the law predicts. Their rows say ``screened``
    and ``screen`` (stage ``increments``, with the reason), the misfit checks at their
    optimum. Where every law left is outnumbered they are all sampled, as before."""
    n_increments = int(np.asarray(prepared.data.increments).size)
    if n_increments < 1:
        return survivors
    reasons = {
        law: reason
        for law in survivors
        if (reason := too_few_increments(found[law].posterior.names, n_increments, law))
    }
    if not reasons or len(reasons) == len(survivors):
        return survivors
    for law, reason in reasons.items():
        at = found[law]
        theta = np.asarray(at.second_optimum[0], dtype=float)
        table[law] = {
            **unsampled(law, at.second, theta, at_optimum(law)),
            "screened": True,
            "screen": {"stage": "increments", "reason": reason},
            "seconds": spent[law][0],
            "cpu_seconds": spent[law][1],
        }
    say(
        f"{len(reasons)} of {len(survivors)} laws have as many parameters as the record's "
        f"{n_increments} increments, which do not identify them (not sampled): "
        + ", ".join(reasons)
    )
    return [law for law in survivors if law not in reasons]


def _screen_optima(
    found: dict[str, LawOptimum],
    deferred: Mapping[str, str],
    failed: Callable[[str, BayestriboError], None],
) -> dict[str, dict[str, Any]]:
    """:func:`screen` of the laws taken to their optima whose second pass is made. A
    law whose second pass waits (``deferred``: its optimum is the law it nests there)
    stays out of it, and is later judged by the reduction rule or on its own; where
    the law it nests is screened out, its second pass is made and the screen made
    again with it (the screen as it was before any second pass waited). A law whose
    second pass fails is reported by ``failed`` and left out of ``found``."""
    while True:
        done = {law: at for law, at in found.items() if not at.pending}
        if len(done) < 2:
            return {}
        screens = screen(
            {law: at.pointwise for law, at in done.items()},
            {law: at.n_parameters for law, at in done.items()},
        )
        due = [
            law
            for law, at in found.items()
            if at.pending and screens.get(deferred.get(law, ""), {}).get("screened")
        ]
        if not due:
            return screens
        for law in due:
            try:
                found[law].pointwise  # noqa: B018  the second pass, made now
            except BayestriboError as exc:
                failed(law, exc)
                del found[law]


def _rivals(verdict: str, as_good: Sequence[str], table: Mapping[str, Any]) -> list[str]:
    """Adequate, converged laws as good as the verdict that do not nest it."""
    the_verdict = law_of(verdict)
    return [
        law
        for law in as_good
        if law != verdict
        and table[law].get("adequate")
        and table[law].get("converged")
        and not law_of(law).nests(the_verdict)
    ]


def _compare_rivals(
    prepared: PreparedRun,
    laws: list[str],
    seed: int | None,
    model: str,
    settings: SamplerSettings,
    discrepancy: bool,
    screening: bool = True,
    starts: Mapping[str, Mapping[str, float]] | None = None,
) -> dict[str, Any]:
    """The verdict and its rivals compared on :data:`TIE_GRID` increments per half
    cycle (module notes), each law's optimiser started at ``starts`` (its optimum on
    the first grid) where given."""
    fine = regrid(prepared, TIE_GRID * int(prepared.data.increments.size))
    out: dict[str, Any] = {
        "laws": list(laws),
        "per_half_cycle": TIE_GRID,
        "grid_points": int(fine.data.increments.size),
        "decided": False,
    }
    if screening:
        judged = _judged_at_optimum(fine, laws, model, discrepancy, starts)
        if judged is not None:
            out.update(judged)
            return out
    try:
        comparison, _ = compare_prepared(
            fine,
            laws,
            seed=seed,
            model=model,
            settings=settings,
            discrepancy=discrepancy,
            rivals=False,
            screening=screening,
            starts=starts,
            settle_adequate=True,
        )
    except BayestriboError as exc:
        out["error"] = str(exc)
        return out
    # a law that reduced there to a law as good as the verdict is as good as it too
    as_good = [
        law
        for law in laws
        if law in comparison.as_good or comparison.equivalent.get(law) in comparison.as_good
    ]
    out.update(
        verdict=comparison.verdict,
        as_good=as_good,
        adequate=comparison.adequate,
        table={
            law: {
                k: row.get(k)
                for k in (
                    "elpd_diff",
                    "dse",
                    "adequate",
                    "misfit_p",
                    "shape_p",
                    "reduces_to",
                    "screened",
                    "seconds",
                )
            }
            for law, row in comparison.table.items()
        },
    )
    # decided: the finer grid's verdict holds there, and some law as good as the
    # first verdict is not as good there
    out["decided"] = bool(comparison.adequate and set(as_good) != set(laws))
    return out


def _judged_at_optimum(
    fine: PreparedRun,
    laws: Sequence[str],
    model: str,
    discrepancy: bool,
    starts: Mapping[str, Mapping[str, float]] | None,
) -> dict[str, Any] | None:
    """The rivals' comparison judged at the laws' optima on the finer grid, when that
    settles it (module notes, Rivals): every law's standing (as good as the best there
    or not) clear of the tie rule's edge by a third of its reach
    (:func:`bayestribo.inference.settling.settle`), and the verdict there, the simplest
    law as good that holds at its optimum, the first grid's verdict (``laws[0]``, whose
    posterior is the one reported, sampled and converged on the first grid). Returns the
    comparison's fields (``verdict``, ``as_good``, ``adequate``, ``decided``,
    ``settled`` True and each law's estimate in ``table``), or None when the optima do
    not settle it (the laws are then sampled)."""
    found: dict[str, LawOptimum] = {}
    optima: dict[str, dict[str, float]] = {}
    for law in sorted(laws, key=complexity):
        try:
            found[law] = _optimise(
                law, fine, model, discrepancy, optima, start=(starts or {}).get(law)
            )
            found[law].pointwise  # noqa: B018  the second pass, made now
        except BayestriboError:
            return None
        at = found[law]
        optima[law] = dict(zip(at.posterior.names, at.optimum[0], strict=True))
    elpd = {law: optimum_elpd(at.pointwise, at.n_parameters) for law, at in found.items()}
    if not all(np.isfinite(v) for v in elpd.values()):
        return None
    best = max(laws, key=elpd.__getitem__)
    top = (found[best].pointwise, found[best].n_parameters)
    table: dict[str, dict[str, Any]] = {}
    for law in laws:
        at = found[law]
        info = settle(
            (at.pointwise, at.n_parameters),
            top,
            top,
            verdict_adequate=True,
            loses_tie=True,
            small=SMALL_ELPD_DIFFERENCE,
            adequate=True,
        )
        if info["as_good"] is None:
            return None
        checks = _checks(at.second, np.asarray(at.second_optimum[0], dtype=float))
        table[law] = {
            **{k: info[k] for k in ("elpd_diff", "dse", "reach", "as_good")},
            **{k: checks.get(k) for k in ("adequate", "misfit_p", "shape_p")},
        }
    as_good = [law for law in laws if table[law]["as_good"]]
    holding = [law for law in as_good if table[law]["adequate"]]
    if not holding:
        return None
    verdict = min(holding, key=lambda law: tie_key(law, list(laws)))
    if verdict != laws[0]:
        return None
    return {
        "verdict": verdict,
        "as_good": as_good,
        "adequate": True,
        "decided": set(as_good) != set(laws),
        "settled": True,
        "table": table,
    }


def compare_dissipation_laws(
    run: Run | str | os.PathLike[str],
    *,
    laws: Sequence[str] = ("viscous", "coulomb", "both"),
    seed: int | None = DEFAULT_SEED,
    model: str = "exact",
    n_walkers: int = 16,
    n_ensembles: int = 2,
    max_steps: int = 20_000,
    grid_points: int | None = None,
    skip_oscillations: int = 1,
    discrepancy: bool = False,
    read_options: ReadOptions | Mapping[str, Any] | None = None,
) -> LawComparison:
    """Fit a run under each dissipation law and compare them by PSIS-LOO.

    Parameters
    ----------
    run : Run or path
        The recording, as for :func:`bayestribo.inference.fit`.
    laws : sequence of str
        Laws to compare (at least two): names of :mod:`bayestribo.model.laws` or the
        original ``"viscous"``, ``"coulomb"``, ``"both"``; :func:`auto_laws` is the
        set ``fit(..., law="auto")`` compares.
    seed : int or None
        Seed of every fit (each law gets its own stream from it and its name); default
        :data:`bayestribo.DEFAULT_SEED`.
    model, n_walkers, n_ensembles, max_steps, grid_points, skip_oscillations, discrepancy
        As in :func:`bayestribo.inference.fit`.
    read_options : ReadOptions or mapping, optional
        How to read ``run`` when it is a path (:class:`~bayestribo.io.options.ReadOptions`,
        or a mapping of the options of :func:`bayestribo.read_run`).

    Returns
    -------
    LawComparison

    Raises
    ------
    BayestriboError
        If a law is unknown or fewer than two are given.
    """
    settings = SamplerSettings(n_walkers=n_walkers, n_ensembles=n_ensembles, max_steps=max_steps)
    laws = list(dict.fromkeys(laws))
    if len(laws) < 2:
        raise BayestriboError(f"laws: expected two or more laws to compare, got {laws}")
    for law in laws:
        law_of(law)
    prepared = prepare(
        run,
        skip_oscillations=skip_oscillations,
        grid_points=grid_points,
        read_options=read_options,
    )
    comparison, _ = compare_prepared(
        prepared, laws, seed=seed, model=model, settings=settings, discrepancy=discrepancy
    )
    return comparison
