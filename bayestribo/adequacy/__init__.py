"""Is the model adequate? Windowed fits, constancy test, extinction time, predictive checks.

Rigaud et al. (2010), section 3.1 and Fig. 8: the friction law must hold along the
whole decay (the same ζ and μ_k in windows moving along the time axis), the
predicted end of motion (Eq. 38) must match the recorded one, and responses
simulated with the identified values must reproduce the recorded peaks.

Modules
-------
segments
    Least-squares fit of one stretch of a decay on its Π increments.
windows
    :func:`windowed_fits`: ζ and μ_k in windows of a few oscillations.
constancy
    :func:`constancy_test`: a trend of ζ and μ_k with amplitude, and a plain statement.
draws
    Parameter draws: posterior, or the labelled Gaussian stand-in.
extinction
    :func:`extinction_check`: predicted against detected end of motion.
predictive
    :func:`predictive_check`: recorded peaks against their predictive intervals.
halves
    :func:`split_halves`: the first and second halves of the motion fitted apart.
report
    :func:`check_adequacy`: all of the above for one run.
plots
    Figures of the windowed estimates, the extinction time and the peak residuals.
"""

from bayestribo.adequacy.check import AdequacyReport, check_adequacy, default_window
from bayestribo.adequacy.constancy import AmplitudeTrend, ConstancyTest, constancy_test
from bayestribo.adequacy.draws import (
    ParameterDraws,
    draws_from_least_squares,
    draws_from_posterior,
)
from bayestribo.adequacy.extinction import ExtinctionCheck, extinction_check
from bayestribo.adequacy.halves import SplitHalves, split_halves
from bayestribo.adequacy.predictive import PeakResiduals, PredictiveCheck, predictive_check
from bayestribo.adequacy.windows import (
    BayesianWindows,
    LeastSquaresWindows,
    WindowedAnalysis,
    WindowEstimate,
    windowed_fits,
)

__all__ = [
    "AdequacyReport",
    "AmplitudeTrend",
    "BayesianWindows",
    "ConstancyTest",
    "ExtinctionCheck",
    "LeastSquaresWindows",
    "ParameterDraws",
    "PeakResiduals",
    "PredictiveCheck",
    "SplitHalves",
    "WindowEstimate",
    "WindowedAnalysis",
    "check_adequacy",
    "constancy_test",
    "default_window",
    "draws_from_least_squares",
    "draws_from_posterior",
    "extinction_check",
    "predictive_check",
    "split_halves",
    "windowed_fits",
]
