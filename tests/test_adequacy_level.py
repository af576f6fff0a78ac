"""The adequacy verdict's level and the least-squares draws' static friction.

The verdict is "not adequate" when any check fails: its three tests at a level (the
constancy test, the split halves, the end of motion) are each made at α/3, so that on a
record of the law it errs at most α of the time (Bonferroni). The least squares do not
estimate μ_s: the draws take it on the step where each sticks at the record's rest.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bayestribo.adequacy import check_adequacy
from bayestribo.adequacy.draws import draws_from_least_squares, static_friction_at_rest
from bayestribo.adequacy.extinction import extinction_check
from bayestribo.adequacy.segments import whole_decay_fit
from bayestribo.adequacy.windows import analysed_decay
from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.io import read_run
from bayestribo.model import rest_position

#: A bundled run (data/manifest.csv: μ_s = 1.2 μ_k) that sticks at a turning point
#: between μ_k and μ_s, half a period before the kinetic friction alone would stop it.
STUCK_ABOVE_MU_K = Path(__file__).resolve().parent.parent / "data/runs/glycerol-N0.46-r3.csv"


@pytest.fixture(scope="module")
def stuck():
    return check_adequacy(str(STUCK_ABOVE_MU_K))


def test_a_record_stuck_between_mu_k_and_mu_s_passes_its_end_of_motion(stuck):
    # with μ_s = μ_k the draws went on one half cycle past the record's stop (0.3835 s
    # predicted, 0.3683 s measured) and the check failed on a record of the law
    ext = stuck.extinction
    assert ext.consistent()
    half_period = 0.5 / stuck.decay.damped_frequency_Hz
    assert abs(np.median(ext.exact) - ext.measured) < 0.25 * half_period
    # nearly every draw sticks a half cycle before the kinetic friction alone would
    # stop it (a few creep on to the same side by 0.15 μ_k, a step of about the same rest
    # within the draws' reach, in proportion to its width)
    assert np.mean(stuck.draws.mu_s > stuck.draws.mu) > 0.9
    assert stuck.adequate
    assert "μ_s on the step" in stuck.draws.label


def test_each_draw_sticks_where_the_record_rests(stuck):
    d, decay = stuck.draws, stuck.decay
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    rest = rest_position(sign * np.abs(d.y0), d.zeta, d.mu, d.mu_s, float(decay.yp[0]))
    # the record's rest, to its noise (a few thousandths of μ_k here), not the next
    # turning point's (about 2 μ_k away)
    assert np.mean(np.abs(rest - decay.y[-1]) < 0.1 * d.mu) > 0.9
    assert np.all(np.abs(rest - decay.y[-1]) < 0.5 * d.mu)


@pytest.mark.parametrize("heavier", [1.2, 1.5, 2.0])
def test_draws_that_stop_before_the_record_still_fail_its_end(stuck, heavier):
    # draws with more kinetic friction stop a half cycle or more before the record's
    # rest whatever their μ_s (μ_s only ever stops the motion earlier): the end of
    # motion fails, so the check's power is not given away
    decay = stuck.decay
    fit = whole_decay_fit(decay)
    heavy = draws_from_least_squares(replace(fit, mu=heavier * fit.mu), 200, seed=1)
    moved = static_friction_at_rest(heavy, decay, seed=1)
    ext = extinction_check(decay, moved)
    assert not ext.consistent()
    half_period = 0.5 / decay.damped_frequency_Hz
    assert np.all(ext.exact < ext.measured - 0.5 * half_period)


def test_a_draw_that_cannot_rest_where_the_record_does_keeps_the_kinetic_stop(stuck):
    decay = stuck.decay
    fit = whole_decay_fit(decay)
    heavy = draws_from_least_squares(replace(fit, mu=2.0 * fit.mu), 200, seed=1)
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    y0 = sign * np.abs(heavy.y0)
    kinetic = rest_position(y0, heavy.zeta, heavy.mu, heavy.mu, float(decay.yp[0]))
    # their kinetic stop (μ_s = μ_k) rests more than half a μ_k from the record's rest
    assert np.all(np.abs(kinetic - decay.y[-1]) > 0.5 * heavy.mu)
    moved = static_friction_at_rest(heavy, decay, seed=1)
    assert np.array_equal(moved.mu_s, moved.mu)


def test_static_friction_is_left_alone_where_the_motion_does_not_stop():
    from bayestribo.synthetic import Release
    from bayestribo.synthetic.recording import simulate

    run = simulate(release=Release(motion_duration_s=0.2, rest_after_s=0.0), seed=3)
    decay = analysed_decay(run)
    assert not decay.motion_ended
    draws = draws_from_least_squares(whole_decay_fit(decay), 50, seed=0)
    assert static_friction_at_rest(draws, decay) is draws


def test_each_test_is_made_at_a_third_of_the_verdicts_level(stuck):
    for alpha in (0.05, 0.1):
        report = stuck if alpha == 0.05 else check_adequacy(str(STUCK_ABOVE_MU_K), alpha=alpha)
        assert report.alpha == alpha
        assert report.constancy.alpha == pytest.approx(alpha / 3)
        assert report.halves.alpha == pytest.approx(alpha / 3)
        assert report.extinction.alpha == pytest.approx(alpha / 3)
        assert report.to_dict()["check_alpha"] == pytest.approx(alpha / 3)
    text = stuck.to_text()
    assert "at most 5 % of the time" in text
    assert "each at 1.67 %" in text
    assert "98.3 % interval" in stuck.extinction.statement


def test_the_constancy_test_decides_at_the_third(stuck):
    # the verdict's constancy check is the test at α/3 on the same windows
    from bayestribo.adequacy.constancy import constancy_test

    test = constancy_test(stuck.windows, alpha=0.05 / 3)
    assert test.p_value == stuck.constancy.p_value
    assert stuck.constancy.constant == (test.p_value >= 0.05 / 3)


def test_the_end_of_motion_interval_follows_alpha(stuck):
    ext = stuck.extinction
    wide = extinction_check(stuck.decay, stuck.draws, alpha=0.5)
    narrow_lo, narrow_hi = np.quantile(wide.exact, [0.25, 0.75])
    lo, hi = np.quantile(ext.exact, [ext.alpha / 2, 1 - ext.alpha / 2])
    assert lo <= narrow_lo <= narrow_hi <= hi
    assert "50 % interval" in wide.statement


@pytest.mark.parametrize("alpha", [0.0, 1.0, -0.1, float("nan"), True, "0.05"])
def test_a_bad_alpha_is_refused(alpha):
    with pytest.raises(RecordingError, match="alpha"):
        check_adequacy(str(STUCK_ABOVE_MU_K), alpha=alpha)


def test_the_static_friction_of_a_nonlinear_force_is_refused():
    decay = analysed_decay(read_run(str(STUCK_ABOVE_MU_K)))
    draws = draws_from_least_squares(whole_decay_fit(decay), 20, seed=0)
    fake = type("Force", (), {"name": "pendulum"})()
    with pytest.raises(BayestriboError, match="linear spring"):
        static_friction_at_rest(draws, replace(decay, restoring=fake))


@pytest.mark.parametrize(("name", "value"), [("rest", float("nan")), ("rest_sd", -1.0)])
def test_a_bad_rest_is_refused(stuck, name, value):
    with pytest.raises(BayestriboError, match=name):
        static_friction_at_rest(stuck.draws, stuck.decay, **{name: value})
