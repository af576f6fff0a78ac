"""The single-run pipeline as named stages, each a module of its own.

1. prepare (:mod:`bayestribo.inference.preparation`): :func:`prepare` turns a run into
   a :class:`PreparedRun`, the observed Π increments with their noise variances
   (:func:`reframe`, :func:`regrid` and :func:`prepare_part` prepare it otherwise);
2. build (:mod:`bayestribo.inference.build`): :func:`build_posterior`, default priors
   (or the caller's) × the Π likelihood, with any parameters fixed at a value
   (``fixed={"zeta": 0.0}`` is the Coulomb-only law);
3. start (:mod:`bayestribo.inference.start`): :func:`find_start`, the maximum a
   posteriori (:func:`find_optimum`), the second pass of the increments' variances
   (:mod:`bayestribo.inference.reweight`) and its optimum, giving a :class:`Start`;
4. sample (:mod:`bayestribo.inference.chains`): :func:`sample_from`, walkers about the
   start and the sampler run to convergence, giving a :class:`Sampled` (:func:`sample`
   is the start and sample stages in a row, from a posterior);
5. check (:mod:`bayestribo.inference.checks`): :func:`check`, modes, misfit, prior
   bounds and the frequency trend, giving a :class:`~bayestribo.inference.checks.FitChecks`;
6. summarise (:mod:`bayestribo.inference.summarising`): :func:`summary`, derived
   quantities, ΔE(A), diagnostics: a :class:`Summary` of the fit's typed record
   (:class:`~bayestribo.inference.fit_record.FitRecord`) and draws, whose
   :meth:`~Summary.result` is the :class:`~bayestribo.inference.result.FitResult`
   (:func:`summarise` is the two in a row).

:func:`bayestribo.fit` is these stages in a row (:mod:`bayestribo.inference.fitting`);
``law="auto"`` compares, chooses and refits on top of them
(:mod:`bayestribo.inference.auto`). This module gathers the stages' public names where
they have always been imported from; it defines nothing, and no stage imports it.
"""

from __future__ import annotations

from bayestribo.inference.build import build_posterior
from bayestribo.inference.chains import sample, sample_from
from bayestribo.inference.checks import (
    FREQUENCY_TREND_CHANGE,
    FREQUENCY_TREND_Z,
    FitChecks,
    check,
    frequency_nuisance_sd,
    misfit_p_value,
)
from bayestribo.inference.preparation import (
    law_frequency,
    prepare,
    prepare_part,
    reframe,
    regrid,
)
from bayestribo.inference.start import Start, find_optimum, find_start
from bayestribo.inference.summarising import Summary, summarise, summary
from bayestribo.inference.types import DEFAULT_SETTINGS, MISFIT_P, PreparedRun, Sampled

__all__ = [
    "DEFAULT_SETTINGS",
    "FREQUENCY_TREND_CHANGE",
    "FREQUENCY_TREND_Z",
    "MISFIT_P",
    "FitChecks",
    "PreparedRun",
    "Sampled",
    "Start",
    "Summary",
    "build_posterior",
    "check",
    "find_optimum",
    "find_start",
    "frequency_nuisance_sd",
    "law_frequency",
    "misfit_p_value",
    "prepare",
    "prepare_part",
    "reframe",
    "regrid",
    "sample",
    "sample_from",
    "summarise",
    "summary",
]
