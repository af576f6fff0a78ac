"""All adequacy checks of one run: :func:`check_adequacy`.

Windowed fits and the constancy test, the extinction time and the peak-by-peak
predictive check, with one plain verdict: is the linear law (constant ζ and μ_k,
Eq. 7) adequate for this recording?
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bayestribo.adequacy.constancy import ConstancyTest, constancy_test
from bayestribo.adequacy.draws import (
    ParameterDraws,
    draws_from_least_squares,
    draws_from_posterior,
)
from bayestribo.adequacy.extinction import ExtinctionCheck, extinction_check
from bayestribo.adequacy.predictive import PredictiveCheck, predictive_check
from bayestribo.adequacy.segments import peak_positions, whole_decay_fit
from bayestribo.adequacy.windows import (
    BayesianWindows,
    WindowedAnalysis,
    analysed_decay,
    windowed_fits,
)
from bayestribo.errors import RecordingError
from bayestribo.signal.decay import EnergyDecay

__all__ = ["AdequacyReport", "check_adequacy", "default_window"]

#: Windows the automatic window length aims at.
TARGET_WINDOWS = 8


def default_window(decay: EnergyDecay) -> int:
    """Window length [oscillations] giving about eight windows, at least two oscillations."""
    oscillations = (peak_positions(decay).size - 1) / 2.0
    return max(2, round(oscillations / TARGET_WINDOWS))


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
        The linear law is adequate: constancy not rejected and the peak coverage
        not far below 95 % (at least 80 %).
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

    @property
    def verdict(self) -> str:
        """The plain conclusion."""
        if self.adequate:
            return "the linear law (constant ζ and friction) is adequate for this recording"
        return "the linear law (constant ζ and friction) is not adequate for this recording"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "run": self.run_name,
            "adequate": self.adequate,
            "verdict": self.verdict,
            "windows": self.windows.to_dict(),
            "constancy": None if self.constancy is None else self.constancy.to_dict(),
            "constancy_note": self.constancy_note,
            "extinction": self.extinction.to_dict(),
            "predictive": self.predictive.to_dict(),
        }

    def to_text(self) -> str:
        """A report for the terminal."""
        w = self.windows
        unit = w.length_unit
        lines = [f"run: {self.run_name}"] if self.run_name else []
        lines.append(
            f"windows of {w.window_oscillations} oscillations ({w.method}, friction "
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
        lines.append("")
        lines.append(
            "constancy: " + (self.constancy.statement if self.constancy else self.constancy_note)
        )
        lines.append("extinction: " + self.extinction.statement)
        lines.append("peaks: " + self.predictive.statement)
        lines.append("")
        lines.append("verdict: " + self.verdict)
        return "\n".join(lines)


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
        False-alarm rate of the constancy test.
    n_draws : int
        Parameter draws for the extinction and predictive checks.
    fit_result : optional
        A Bayesian fit of the run (``samples(name)``): its posterior draws are used;
        without it, draws from the Gaussian approximation of the whole-decay least
        squares (labelled so).
    seed : int
        Seed of the draws and of the noise propagation.
    skip_oscillations : int
        Oscillations after the release left out.
    bayes : bool
        Use the Bayesian fit (:func:`bayestribo.inference.fit`): on each window (posterior
        intervals) and, unless ``fit_result`` is given, on the whole run for the
        draws. Needs the run itself (not an EnergyDecay) and windows of at least 3
        oscillations (the default window is raised to 3); takes seconds per window.

    Returns
    -------
    AdequacyReport
    """
    decay = analysed_decay(run, skip_oscillations=skip_oscillations)
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
        )
        if fit_result is None:
            from bayestribo.inference import fit

            fit_result = fit(run, seed=seed, skip_oscillations=skip_oscillations)
    else:
        windows = windowed_fits(decay, window=window, seed=seed)
    try:
        constancy: ConstancyTest | None = constancy_test(windows, alpha=alpha)
        note = ""
    except RecordingError as exc:
        constancy, note = None, f"not tested: {exc}"
    if fit_result is not None:
        draws = draws_from_posterior(fit_result, decay, n_draws, seed=seed)
    else:
        draws = draws_from_least_squares(whole_decay_fit(decay, seed=seed), n_draws, seed=seed)
    extinction = extinction_check(decay, draws)
    predictive = predictive_check(decay, draws, seed=seed)
    adequate = (constancy is None or constancy.constant) and predictive.coverage >= 0.8
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
    )
