"""All adequacy checks of one run: :func:`check_adequacy`.

Windowed fits and the constancy test, the extinction time, the peak-by-peak
predictive check and the split-half consistency of the first and second halves of
the motion (:mod:`bayestribo.adequacy.halves`), with one plain verdict: is the linear
law (constant ζ and μ_k, Eq. 7) adequate for this recording? On a nonlinear restoring
force (the run's ``restoring``, or the ``restoring`` option: a pendulum, a Duffing
spring) the same law on that force (:mod:`bayestribo.adequacy.restoring`).

The verdict's level. "Not adequate" when any check fails, so on a record of the law
its false-alarm rate is at most the sum of the checks'. Three checks are tests at a
level: the constancy test, the split halves and the end of motion (the measured end
outside the exact model's central prediction interval); each is made at
``alpha / 3`` (Bonferroni; the constancy test and the halves at p < α/3, the end of
motion against the model's ``1 - α/3`` interval), so the verdict says "not adequate"
on a record of the law at most ``alpha`` of the time (5 % by default). The peaks'
check is a fixed rule (at least :data:`MIN_PEAK_COVERAGE` of the peaks inside their
95 % predictive intervals), not a test at a level; on records of the law it failed
none of 442 (``benchmarks/README.md``, "The adequacy verdict's level").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from bayestribo._plural import count
from bayestribo.adequacy.constancy import MIN_WINDOWS, ConstancyTest, constancy_test
from bayestribo.adequacy.draws import (
    ParameterDraws,
    draws_from_least_squares,
    draws_from_posterior,
    static_friction_at_rest,
)
from bayestribo.adequacy.extinction import ExtinctionCheck, extinction_check
from bayestribo.adequacy.halves import SplitHalves, split_halves
from bayestribo.adequacy.predictive import PredictiveCheck, predictive_check
from bayestribo.adequacy.restoring import chosen_run, force_text, nonlinear
from bayestribo.adequacy.segments import peak_positions, whole_decay_fit
from bayestribo.adequacy.windows import (
    BayesianWindows,
    LeastSquaresWindows,
    WindowedAnalysis,
    analysed_decay,
    windowed_fits,
)
from bayestribo.errors import RecordingError
from bayestribo.signal.decay import EnergyDecay

__all__ = ["AdequacyReport", "check_adequacy", "default_window"]

#: Windows the automatic window length aims at.
TARGET_WINDOWS = 8

#: Checks of the verdict that are tests at a level (the constancy test, the split
#: halves, the end of motion): each is made at ``alpha`` over this (Bonferroni).
TESTS_AT_A_LEVEL = 3


def default_window(decay: EnergyDecay) -> int:
    """Window length [oscillations]: about eight windows of at least two oscillations.

    One oscillation where windows of two would be fewer than the constancy test's three
    (:data:`~bayestribo.adequacy.constancy.MIN_WINDOWS`: a decay of 3-6 oscillations)
    on a recorded displacement, or where the decay holds no window of two (a coarse
    digitiser's record analysed on 4 turning points). A displacement integrated from a
    velocity recorded alone keeps windows of two: fitting its own offset in one
    oscillation, the constancy test on such windows rejected 5-14 of about 40 records of
    the law at α/3, where on a recorded displacement it rejected 1.5-2.5 % of 200
    (``benchmarks/README.md``, "Short records checked, not refused").

    Parameters
    ----------
    decay : EnergyDecay
        The analysed decay.

    Returns
    -------
    int
        The window length [oscillations], at least 1.
    """
    turning_points = peak_positions(decay).size
    oscillations = (turning_points - 1) / 2.0
    window = max(MIN_DEFAULT_WINDOW, round(oscillations / TARGET_WINDOWS))
    windows = (turning_points - 1) // (2 * window)
    recorded = decay.derived_channel != "displacement"
    if windows < 1 or (windows < MIN_WINDOWS and recorded):
        return 1
    return window


#: How the statement of a check that was not run begins.
NOT_RUN = "not run: "

#: The shortest default window [oscillations] on a decay that holds the constancy
#: test's windows of it.
MIN_DEFAULT_WINDOW = 2


def _constancy_not_run(decay: EnergyDecay, windows: WindowedAnalysis, reason: str) -> str:
    """Why the constancy test was not run: the record too short for its windows, or
    the windows' estimates on a bound (``reason``, the test's own message)."""
    if len(windows) >= MIN_WINDOWS:
        return f"{NOT_RUN}{reason}"
    turning_points = peak_positions(decay).size
    each = count(windows.window_oscillations, "oscillation")
    needed = 2 * windows.window_oscillations * MIN_WINDOWS + 1
    return (
        f"{NOT_RUN}the analysed decay holds {turning_points} turning points, "
        f"{count(len(windows), 'window')} of {each}; the constancy test needs "
        f"{MIN_WINDOWS} windows ({needed} turning points at {each} a window)"
    )


@dataclass(frozen=True)
class AdequacyReport:
    """The adequacy checks of one run.

    Attributes
    ----------
    run_name : str or None
    decay : EnergyDecay
    windows : WindowedAnalysis
    constancy : ConstancyTest or None
        None when there are too few windows (``constancy_note`` says why).
    extinction : ExtinctionCheck
    predictive : PredictiveCheck
    draws : ParameterDraws
    adequate : bool
        The law (constant ζ and friction, on the run's restoring force) is
        adequate: every check run and passed (constancy not rejected, the measured
        end of motion inside the exact model's ``1 - alpha/3`` interval, the peak
        coverage not far below 95 % (at least 80 %), and the two halves of the
        motion in agreement). A check the record is too short for is not run
        (:attr:`not_run`), and the law is then not called adequate on the strength
        of the others (:attr:`verdict` names what it rests on). Computed once, from
        :attr:`checks`. On a record of the law long enough for every check it is
        False at most ``alpha`` of the time (:attr:`level_text`).
    halves : SplitHalves or None
        The split-half check (None when the decay is too short for it:
        ``halves_note`` says why).
    halves_note : str
    restoring : str or None
        The run's nonlinear restoring force in words (:func:`~bayestribo.adequacy.
        restoring.force_text`), whose motion every check takes; None for the linear
        spring.
    alpha : float
        The verdict's family-wise false-alarm rate on a record of the law: the
        constancy test, the halves and the end of motion each at ``alpha /
        TESTS_AT_A_LEVEL`` (Bonferroni).
    """

    run_name: str | None
    decay: EnergyDecay
    windows: WindowedAnalysis
    constancy: ConstancyTest | None
    constancy_note: str
    extinction: ExtinctionCheck
    predictive: PredictiveCheck
    draws: ParameterDraws
    adequate: bool
    halves: SplitHalves | None = None
    halves_note: str = ""
    restoring: str | None = None
    alpha: float = 0.05

    @property
    def check_alpha(self) -> float:
        """The level each of the three tests is made at: ``alpha / TESTS_AT_A_LEVEL``."""
        return self.alpha / TESTS_AT_A_LEVEL

    @property
    def level_text(self) -> str:
        """The verdict's false-alarm rate on a record of the law, in one sentence."""
        a = f"{100.0 * self.alpha:.3g} %"
        each = f"{100.0 * self.check_alpha:.3g} %"
        text = (
            f'on a record of the law the verdict says "not adequate" at most {a} of the '
            f"time (the constancy test, the halves and the end of motion each at {each}, "
            f"Bonferroni; the peaks' check a fixed rule of "
            f"{100.0 * MIN_PEAK_COVERAGE:.0f} % coverage)"
        )
        if self.not_run:
            text += (
                "; a record on which a check could not run is never called adequate, the "
                "checks that ran keep their level"
            )
        return text

    @property
    def law_text(self) -> str:
        """The law judged, in words: the linear law, or the law on the run's nonlinear
        restoring force."""
        if self.restoring is None:
            return "the linear law (constant ζ and friction)"
        return f"the law with {self.restoring} (constant ζ and friction)"

    @property
    def checks(self) -> list[dict[str, Any]]:
        """Each check with its outcome: ``name``, ``passed`` (True, False, or None if not
        run) and its one-sentence ``statement``; :attr:`adequate` is True when every
        one is True."""
        return _checks(
            self.constancy,
            self.constancy_note,
            self.extinction,
            self.predictive,
            self.halves,
            self.halves_note,
        )

    @property
    def rests_on(self) -> list[str]:
        """The names of the checks that were run: what the verdict rests on."""
        return [c["name"] for c in self.checks if c["passed"] is not None]

    @property
    def not_run(self) -> list[str]:
        """The names of the checks that could not be run on this record (each
        check's statement says why)."""
        return [c["name"] for c in self.checks if c["passed"] is None]

    @property
    def verdict(self) -> str:
        """The plain conclusion, naming the checks that failed and those not run."""
        return _verdict(self.law_text, self.checks)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``restoring``: the run's nonlinear restoring force in
        words, present only on one)."""
        out = {
            "run": self.run_name,
            "adequate": self.adequate,
            "verdict": self.verdict,
            "rests_on": self.rests_on,
            "not_run": self.not_run,
            "alpha": self.alpha,
            "check_alpha": self.check_alpha,
            "level": self.level_text,
            "checks": [{k: c[k] for k in ("name", "passed", "statement")} for c in self.checks],
            "windows": self.windows.to_dict(),
            "constancy": None if self.constancy is None else self.constancy.to_dict(),
            "constancy_note": self.constancy_note,
            "extinction": self.extinction.to_dict(),
            "predictive": self.predictive.to_dict(),
            "halves": None if self.halves is None else self.halves.to_dict(),
            "halves_note": self.halves_note,
        }
        if self.restoring is not None:
            out["restoring"] = self.restoring
        return out

    def to_text(self) -> str:
        """A report for the terminal."""
        w = self.windows
        unit = w.length_unit
        lines = [f"run: {self.run_name}"] if self.run_name else []
        if self.restoring is not None:
            lines.append(f"restoring force: {self.restoring}")
        lines.append(
            f"windows of {count(w.window_oscillations, 'oscillation')} ({w.method}, friction "
            f"{w.extra.get('friction_mode', 'fit')}); {w.interval_kind}"
        )
        amp = f"amplitude [{unit}]"
        head = f"{'#':>3}  {'t [s]':>15}  {amp:>22}  {'zeta':>22}  {w.friction_name:>24}"
        lines.append(head)
        for x in w.windows:
            flag = "  (on a bound)" if not x.regular else ""
            lines.append(
                f"{x.index:>3}  {x.t_start:7.3f}-{x.t_end:7.3f}  "
                f"{x.amplitude_range[0]:10.4g}-{x.amplitude_range[1]:<10.4g}  "
                f"{x.zeta:10.4g} ± {x.zeta_se:<9.2g}  {x.mu:11.4g} ± {x.mu_se:<9.2g}{flag}"
            )
        if self.halves is not None:
            h = self.halves
            held = ", friction held" if h.friction_mode == "fixed" else ""
            lines.append("")
            lines.append(f"split halves ({h.method}{held}); {h.interval_kind}")
            for label, x in (("1st", h.first), ("2nd", h.second)):
                lines.append(
                    f"{label:>3}  {x.t_start:7.3f}-{x.t_end:7.3f}  "
                    f"{x.amplitude_range[0]:10.4g}-{x.amplitude_range[1]:<10.4g}  "
                    f"{x.zeta:10.4g} ± {x.zeta_se:<9.2g}  {x.mu:11.4g} ± {x.mu_se:<9.2g}"
                )
        lines.append("")
        for check in self.checks:
            mark = {True: "pass", False: "FAIL", None: "not run"}[check["passed"]]
            statement = check["statement"].removeprefix(NOT_RUN)
            lines.append(f"{check['key']}: [{mark}] {statement}")
        lines.append("")
        lines.append("verdict: " + self.verdict)
        lines.append("level: " + self.level_text)
        return "\n".join(lines)


#: Lowest fraction of recorded peaks inside their 95 % predictive intervals that passes.
MIN_PEAK_COVERAGE = 0.8


def _verdict(law: str, checks: list[dict[str, Any]]) -> str:
    """The verdict on ``law`` (in words) from its ``checks`` (:func:`_checks`): adequate
    only when every check was run and passed; otherwise the checks that failed and
    those not run, by name."""
    failed = [c["name"] for c in checks if c["passed"] is False]
    passed = [c["name"] for c in checks if c["passed"] is True]
    not_run = [c["name"] for c in checks if c["passed"] is None]
    if failed:
        return f"{law} is not adequate for this recording (failed: {', '.join(failed)}" + (
            f"; not run: {', '.join(not_run)})" if not_run else ")"
        )
    if not_run:
        rests = f"the checks run pass ({', '.join(passed)})" if passed else "no check could run"
        return (
            f"{law} is not shown adequate for this recording: {rests}; not run: "
            f"{', '.join(not_run)}"
        )
    return f"{law} is adequate for this recording"


def _adequate(checks: list[dict[str, Any]]) -> bool:
    """Every check run and passed: the one place the verdict's outcome is decided."""
    return all(c["passed"] is True for c in checks)


def _checks(
    constancy: ConstancyTest | None,
    constancy_note: str,
    extinction: ExtinctionCheck,
    predictive: PredictiveCheck,
    halves: SplitHalves | None = None,
    halves_note: str = "",
) -> list[dict[str, Any]]:
    """The four checks with their outcomes (``passed`` None: not run, the statement
    says why); :func:`_adequate` decides the verdict from them."""
    return [
        {
            "key": "constancy",
            "name": "constant ζ and friction along the decay",
            "passed": None if constancy is None else bool(constancy.constant),
            "statement": constancy.statement if constancy is not None else constancy_note,
        },
        {
            "key": "extinction",
            "name": "end of motion",
            "passed": extinction.consistent("exact"),
            "statement": extinction.statement,
        },
        {
            "key": "peaks",
            "name": "peak-by-peak predictive check",
            "passed": bool(predictive.coverage >= MIN_PEAK_COVERAGE),
            "statement": predictive.statement,
        },
        {
            "key": "halves",
            "name": "first and second halves agree",
            "passed": None if halves is None else halves.consistent,
            "statement": halves.statement if halves is not None else halves_note,
        },
    ]


#: Periods of the rest after the stop whose displacement gives the record's rest.
REST_PERIODS = 10


def _record_rest(run: Any, decay: EnergyDecay) -> tuple[float, float] | None:
    """The record's rest after its stop [-] and its standard error [-]: the median over
    up to :data:`REST_PERIODS` periods after the decay's end of the displacement about
    the decay's equilibrium (its line), over ℓ; None without a displacement channel or
    samples at rest."""
    t = getattr(run, "time", None)
    x = getattr(run, "displacement", None)
    if t is None or x is None or not decay.motion_ended:
        return None
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    period = 1.0 / decay.damped_frequency_Hz
    tail = (t > decay.end_time) & (t <= decay.end_time + REST_PERIODS * period)
    if np.count_nonzero(tail) < 2:
        return None
    line = decay.equilibrium + decay.equilibrium_drift * (t[tail] - decay.start_time)
    y = (x[tail] - line) / decay.scaling.length_scale
    rest = float(np.median(y))
    # the median's standard error, √(π/2) σ/√n
    se = 1.2533 * float(np.std(y)) / np.sqrt(y.size)
    return (rest, se) if np.isfinite(rest) and np.isfinite(se) else None


def check_adequacy(
    run: Any,
    *,
    window: int | None = None,
    alpha: float = 0.05,
    n_draws: int = 400,
    fit_result: Any | None = None,
    seed: int = 0,
    skip_oscillations: int = 1,
    bayes: bool = False,
    progress: Callable[[str], None] | None = None,
    restoring: str | None = None,
) -> AdequacyReport:
    """Windowed fits, constancy test, extinction time and predictive check of one run.

    Parameters
    ----------
    run : Run, path or EnergyDecay
        The recording.
    window : int, optional
        Window length [oscillations]; default about an eighth of the decay, at
        least 2 (:func:`default_window`).
    alpha : float
        False-alarm rate of the verdict on a record of the law, in (0, 1): the
        constancy test, the split halves and the end of motion are each made at
        ``alpha / 3`` (Bonferroni), so that "not adequate" on a record of the law
        comes at most ``alpha`` of the time (5 % by default; measured in
        ``benchmarks/README.md``, "The adequacy verdict's level"). The peaks' check
        is a fixed rule (coverage at least :data:`MIN_PEAK_COVERAGE`).
    n_draws : int
        Parameter draws for the extinction and predictive checks.
    fit_result : optional
        A Bayesian fit of the run (``samples(name)``): its posterior draws are used;
        without it, draws from the Gaussian approximation of the whole-decay least
        squares (labelled so), their μ_s on the step where each sticks at the
        record's rest (:func:`~bayestribo.adequacy.draws.static_friction_at_rest`; on
        a nonlinear restoring force μ_s = μ_k).
    seed : int
        Seed of the draws and of the noise propagation.
    skip_oscillations : int
        Oscillations after the release left out.
    bayes : bool
        Use the Bayesian fit (:func:`bayestribo.inference.fit`): on each window and
        each half of the motion (posterior intervals) and, unless ``fit_result`` is
        given, on the whole run for the draws. Needs the run itself (not an
        EnergyDecay) and windows of at least 3 oscillations (the default window is
        raised to 3); takes seconds per window.
    progress : callable, optional
        Called with a one-line message before each window fit, each half's fit and
        the whole-run fit.
    restoring : str, optional
        The oscillator's restoring force (a name of
        :func:`bayestribo.model.restoring.restoring_choices`, ``"auto"`` to choose it
        from the record); default the run's own (its metadata's ``restoring``, else
        the linear spring). On a nonlinear force (a pendulum, a Duffing spring) every
        check takes its motion (:mod:`bayestribo.adequacy.restoring`), and the verdict
        names it. Not used with an EnergyDecay (whose own ``restoring`` is taken).

    Returns
    -------
    AdequacyReport

    Raises
    ------
    RecordingError
        ``alpha`` outside (0, 1).
    """
    if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not 0.0 < alpha < 1.0:
        raise RecordingError(f"alpha must be a number in (0, 1), got {alpha!r}")
    level = float(alpha) / TESTS_AT_A_LEVEL
    if isinstance(run, EnergyDecay):
        decay = run
    else:
        recording = chosen_run(run, restoring, skip_oscillations=skip_oscillations)
        if bayes or restoring is not None or nonlinear(recording):
            run = recording
        decay = analysed_decay(recording, skip_oscillations=skip_oscillations)
    if window is None:
        window = default_window(decay)
        if bayes:
            from bayestribo.signal.decay import MIN_OSCILLATIONS

            window = max(window, MIN_OSCILLATIONS)
    if bayes:
        windows = windowed_fits(
            run,
            window=window,
            fitter=BayesianWindows(),
            seed=seed,
            skip_oscillations=skip_oscillations,
            progress=progress,
        )
        if fit_result is None:
            from bayestribo.inference import fit

            if progress is not None:
                progress("whole run (Bayesian fit)")
            fit_result = fit(run, seed=seed, skip_oscillations=skip_oscillations)
    else:
        windows = windowed_fits(decay, window=window, seed=seed)
        stated = getattr(run, "length_unit", None)
        if windows.length_unit != stated and stated in ("m", "rad"):
            # fitted on the decay alone: the recording says its position is in metres,
            # or is a rotation's angle in radians
            windows = replace(windows, length_unit=stated)
    try:
        constancy: ConstancyTest | None = constancy_test(windows, alpha=level)
        note = ""
    except RecordingError as exc:
        constancy, note = None, _constancy_not_run(decay, windows, str(exc))
    if fit_result is not None:
        draws = draws_from_posterior(fit_result, decay, n_draws, seed=seed)
    else:
        draws = draws_from_least_squares(whole_decay_fit(decay, seed=seed), n_draws, seed=seed)
        if decay.restoring is None:
            rest = None if isinstance(run, EnergyDecay) else _record_rest(run, decay)
            draws = static_friction_at_rest(
                draws,
                decay,
                rest=None if rest is None else rest[0],
                rest_sd=None if rest is None else rest[1],
                seed=seed,
            )
    extinction = extinction_check(decay, draws, seed=seed, alpha=level)
    predictive = predictive_check(decay, draws, seed=seed)
    try:
        halves: SplitHalves | None = split_halves(
            run if bayes else decay,
            fitter=BayesianWindows() if bayes else LeastSquaresWindows(),
            alpha=level,
            skip_oscillations=skip_oscillations,
            seed=seed,
            progress=progress,
        )
        if halves is not None and getattr(run, "length_unit", None) == "rad":
            halves = replace(halves, length_unit="rad")  # fitted on the decay alone
        halves_note = ""
    except RecordingError as exc:
        halves, halves_note = None, f"{NOT_RUN}{exc}"
    adequate = _adequate(_checks(constancy, note, extinction, predictive, halves, halves_note))
    name = getattr(run, "source", None) if not isinstance(run, EnergyDecay) else None
    if name is None and isinstance(run, str):
        name = run
    return AdequacyReport(
        run_name=None if name is None else str(name),
        decay=decay,
        windows=windows,
        constancy=constancy,
        constancy_note=note,
        extinction=extinction,
        predictive=predictive,
        draws=draws,
        adequate=adequate,
        halves=halves,
        halves_note=halves_note,
        restoring=None if decay.restoring is None else force_text(decay.restoring),
        alpha=float(alpha),
    )
