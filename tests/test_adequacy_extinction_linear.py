"""The end-of-motion and peak checks of the law on the linear spring, on records the law
describes.

Independent records (``tests/_pendulum_decay.py``, ``solve_ivp`` half cycle by half
cycle with sticking) of a linear spring with viscous damping and Coulomb friction, slow
(0.7 Hz) and fast (3 Hz), angle and velocity with 1 mrad and 4 mrad/s of noise. The
slow motion creeps into its stop: its last sample beyond the threshold of motion comes
a few tenths of a second before the closed-form stop, and the model's end is predicted
the same way (moved to the stop where the displacement there is seen off its rest).
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from _pendulum_decay import Swing, swing

from bayestribo.adequacy import check_adequacy
from bayestribo.io.run import Run

#: (frequency [Hz], duration [s], release, noise seed): records whose end of motion
#: (both) and peaks (the slow one) the checks once rejected.
RECORDS = {
    "slow": (0.7, 40.0, 1.0902474095456514, 1005),
    "fast": (3.0, 15.0, 1.3, 1001),
}


@functools.cache
def _run(name: str) -> Run:
    f0, duration, x0, seed = RECORDS[name]
    case = Swing(f0=f0, zeta=0.003, friction=0.012, x0=x0, beta=0.0, duration=duration)
    t, x, v = swing(case, seed)
    return Run(t, x, v, metadata={"length_unit": "arbitrary"}, source=f"{name}.csv")


@functools.cache
def _report(name: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return check_adequacy(_run(name), restoring="linear")


@pytest.mark.parametrize("name", list(RECORDS))
def test_the_law_on_a_linear_spring_passes_its_end_of_motion_and_peaks(name):
    report = _report(name)
    passed = {c["key"]: c["passed"] for c in report.checks}
    assert passed["extinction"] is True, report.extinction.statement
    assert passed["peaks"] is True, report.predictive.statement
    assert report.adequate, report.verdict


def test_the_slow_springs_predicted_end_comes_before_its_stop():
    # the closed-form stop of the same draws (Eq. 8, from where the fit starts them)
    # lies past the predicted end by more than the end's resolution where the draw's
    # motion creeps into it under the threshold of motion, its displacement there
    # within 5 σ of its rest: the prediction is where the record would show its end,
    # not the stop. A draw whose displacement at its last excursion is farther from
    # the rest is seen moving on to its stop (signal.motion._missed_half_cycle): its
    # end is the stop itself
    from bayestribo.adequacy import draws_from_least_squares, extinction_check
    from bayestribo.adequacy.segments import whole_decay_fit
    from bayestribo.adequacy.windows import analysed_decay
    from bayestribo.model import stop_time

    decay = analysed_decay(_run("slow"))
    draws = draws_from_least_squares(whole_decay_fit(decay), 100)
    extinction = extinction_check(decay, draws)
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    stop = stop_time(sign * draws.y0, draws.zeta, draws.mu, draws.mu, float(decay.yp[0]))
    stop = np.asarray(stop) / decay.scaling.omega
    assert np.all(np.isfinite(extinction.exact))
    creeps = np.abs(stop - extinction.exact) > 1e-9
    assert np.mean(creeps) > 0.5
    assert np.all(extinction.exact[creeps] + extinction.resolution < stop[creeps])
    assert float(np.median(stop - extinction.exact)) > 0.1
    assert extinction.consistent()
