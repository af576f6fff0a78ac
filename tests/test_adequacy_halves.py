"""Split-half consistency (bayestribo.adequacy.halves): false alarms, detection, real data.

* false-alarm rate: 40 clean simulated runs (seeded) with the least-squares halves at
  α = 5 %: at most 6 rejections (P(X ≥ 7) = 0.34 % for a binomial(40, 0.05); the
  least-squares covariance is widened by the reduced χ², so the test is conservative
  at the resolution: ``benchmarks/halves.py`` measures 1.3 % [0.4, 2.9] over 400 runs,
  and 6.2 % [4.1, 9.1] at 10x the noise), and the z of the differences centred on 0;
* detection: damping that grows with amplitude (ζ = 0.01 + 20·a), the case of
  tests/test_inference_fitting.py::test_misfit_is_flagged, over three seeds;
* the real HarmOsc3 recording, whose halves disagree (4.3 sd in the Bayesian fit
  even with the discrepancy term, issue 13): the check must say so;
* the check in :func:`check_adequacy`: in ``checks``, the verdict, ``to_dict`` and
  ``to_text``.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from bayestribo.adequacy import check_adequacy
from bayestribo.adequacy.halves import SplitHalves, split_halves
from bayestribo.adequacy.windows import BayesianWindows, analysed_decay
from bayestribo.errors import RecordingError
from bayestribo.synthetic import DissipationLaw, Release, Sensor
from bayestribo.synthetic.recording import simulate

ALPHA = 0.05


@pytest.fixture(scope="module")
def clean_halves() -> list[SplitHalves]:
    return [split_halves(simulate(seed=500 + s), alpha=ALPHA) for s in range(40)]


def test_false_alarm_rate_on_clean_runs(clean_halves):
    rejected = sum(not h.consistent for h in clean_halves)
    assert rejected <= 6, rejected
    # both parameters compared on the default rig (friction resolved in each half)
    assert all(h.parameters == ("zeta", "mu") for h in clean_halves)
    z = np.array([h.z["zeta"] for h in clean_halves])
    # mean of 40 z of sd ≤ 1: 4 standard errors is 0.63
    assert abs(z.mean()) < 4 / np.sqrt(40)
    # p-values in [0, 1] and the statement matches the decision
    for h in clean_halves:
        assert 0.0 <= h.p_value <= 1.0
        assert ("the two halves agree" in h.statement) is h.consistent


def _amplitude_dependent_run(seed: int):
    return simulate(
        DissipationLaw(zeta=lambda a: 0.01 + 20.0 * a, mu_k=0.0294),
        sensor=Sensor(
            sample_rate_Hz=2000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=seed,
    )


@pytest.mark.parametrize("seed", [9, 10, 11])
def test_a_damping_that_grows_with_amplitude_is_detected(seed):
    h = split_halves(_amplitude_dependent_run(seed))
    assert not h.consistent
    assert h.p_value < 1e-3
    assert h.max_abs_z > 3.0
    assert "disagree" in h.statement and "does not hold" in h.statement


def test_harmosc3_halves_disagree(appstat_file):
    from bayestribo import read_run

    run = read_run(
        appstat_file("HarmOsc3.txt"),
        columns=["time_s", "displacement_m"],
        metadata={"length_unit": "arbitrary"},
    )
    h = split_halves(run)
    assert not h.consistent
    assert h.max_abs_z > 4.0  # at least the 4.3 sd of the Bayesian fit
    assert h.friction_name == "friction_displacement"
    d = h.to_dict()
    assert json.loads(json.dumps(d))["consistent"] is False
    assert len(d["halves"]) == 2


def test_bayesian_halves_agree_on_a_clean_run():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = split_halves(simulate(seed=31), fitter=BayesianWindows(), seed=1)
    assert h.method == "bayes" and h.parameters == ("zeta", "mu")
    assert h.consistent, h.statement
    # the halves cover the simulated values
    for half in (h.first, h.second):
        assert half.zeta_interval[0] < 0.0236 < half.zeta_interval[1]
        assert half.mu_interval[0] < 0.0294 < half.mu_interval[1]


def test_halves_split_at_the_middle_turning_point():
    run = simulate(seed=32)
    decay = analysed_decay(run)
    h = split_halves(decay)
    n_half_cycles = decay.peaks.value.size - 1
    assert h.first.n_oscillations == (n_half_cycles // 2) / 2
    assert h.first.n_oscillations + h.second.n_oscillations == n_half_cycles / 2
    assert h.first.t_end == h.second.t_start  # they share the middle turning point


def test_too_short_a_decay_and_bad_arguments_are_refused():
    short = simulate(release=Release(initial_displacement_m=2e-4), seed=33)  # 3.5 osc.
    with pytest.raises(RecordingError, match="the halves need 9"):
        split_halves(short)
    with pytest.raises(RecordingError, match="alpha"):
        split_halves(simulate(seed=34), alpha=1.5)


def test_check_adequacy_reports_the_halves():
    report = check_adequacy(_amplitude_dependent_run(9))
    keys = [c["key"] for c in report.checks]
    assert "halves" in keys
    halves = next(c for c in report.checks if c["key"] == "halves")
    assert halves["passed"] is False
    assert not report.adequate
    assert "first and second halves agree" in report.verdict
    text = report.to_text()
    assert "split halves (least_squares" in text and "halves: [FAIL]" in text
    d = report.to_dict()
    assert d["halves"]["consistent"] is False
    assert any(c["name"] == "first and second halves agree" for c in d["checks"])
