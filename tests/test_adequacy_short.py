"""Short records checked, not refused: the checks that fit the record run, those that
cannot are named with the turning points they need, and the verdict is not "adequate"
on the strength of the checks that ran alone."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from _coarse_decay import coarse_record

from bayestribo.adequacy import check_adequacy
from bayestribo.adequacy.check import _adequate, _verdict, default_window
from bayestribo.adequacy.segments import peak_positions
from bayestribo.adequacy.windows import analysed_decay
from bayestribo.cli import main
from bayestribo.inference.records import LawComparison
from bayestribo.io import write_run
from bayestribo.io.run import Run
from bayestribo.synthetic import Release
from bayestribo.synthetic.recording import simulate

RIG = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31}
HALVES = "first and second halves agree"
CONSTANCY = "constant ζ and friction along the decay"


def _coarse_run(steps: float = 3.0, placement: float = 0.45) -> Run:
    """The coarse decay of ``_coarse_decay.coarse_record`` (both channels rounded to
    1/``steps`` of their swing on levels shifted by ``placement`` of a step) as a run of
    the paper's rig; at 3 steps and 0.45 the fit analyses it on 4 turning points (two
    oscillations, the skipped one included)."""
    t, x, v, _, _ = coarse_record(steps, placement)
    return Run(time=t, displacement=x, velocity=v, metadata=dict(RIG))


@pytest.fixture(scope="module")
def coarse():
    """The check of the coarse record analysed on 4 turning points."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return check_adequacy(_coarse_run())


def _by_key(report):
    return {c["key"]: c for c in report.checks}


def test_a_record_of_four_turning_points_is_checked_not_refused(coarse):
    assert peak_positions(coarse.decay).size == 4
    assert coarse.windows.window_oscillations == 1 and len(coarse.windows) == 1
    checks = _by_key(coarse)
    assert checks["constancy"]["passed"] is None
    assert checks["constancy"]["statement"].startswith(
        "not run: the analysed decay holds 4 turning points, 1 window of 1 oscillation"
    )
    assert "needs 3 windows (7 turning points" in checks["constancy"]["statement"]
    assert checks["halves"]["passed"] is None
    assert checks["halves"]["statement"] == (
        "not run: the analysed decay holds 4 turning points (1.5 oscillations); the halves "
        "need 9 (two halves of at least 2 oscillations each)"
    )
    # the end of motion and the peaks need no windows: they run
    assert checks["extinction"]["passed"] is not None
    assert checks["peaks"]["passed"] is not None


def test_an_analysis_cut_before_the_records_end_is_not_called_the_records_end(coarse):
    # the coarse analysis ends at its last resolved turning point (0.18 s), long before
    # the record's 0.9 s: the statement must not say the record ends there
    statement = _by_key(coarse)["extinction"]["statement"]
    assert coarse.decay.end_time < 0.5
    assert "the analysis ends at" in statement and "the record ends at" not in statement


def test_the_checks_not_run_are_named_in_text_and_json(coarse):
    assert not coarse.adequate
    assert f"not run: {CONSTANCY}, {HALVES}" in coarse.verdict
    data = coarse.to_dict()
    assert data["adequate"] is False
    assert data["not_run"] == [CONSTANCY, HALVES]
    assert data["rests_on"] == ["end of motion", "peak-by-peak predictive check"]
    text = coarse.to_text()
    assert "constancy: [not run] the analysed decay holds 4 turning points" in text
    assert "halves: [not run]" in text


def test_a_short_record_of_the_law_is_not_called_adequate_on_the_checks_that_ran():
    """3.5 oscillations of the law: the constancy test runs on windows of one
    oscillation, the halves cannot; the law is not shown adequate."""
    report = check_adequacy(simulate(release=Release(initial_displacement_m=2e-4), seed=33))
    assert peak_positions(report.decay).size == 8
    assert report.windows.window_oscillations == 1 and len(report.windows) == 3
    checks = _by_key(report)
    assert checks["constancy"]["passed"] is not None
    assert checks["halves"]["passed"] is None
    assert "holds 8 turning points" in checks["halves"]["statement"]
    assert not report.adequate
    assert report.verdict.endswith(
        f"is not shown adequate for this recording: the checks run pass ({CONSTANCY}, "
        f"end of motion, peak-by-peak predictive check); not run: {HALVES}"
    )


def _check(key: str, passed: bool | None) -> dict:
    return {"key": key, "name": key, "passed": passed, "statement": ""}


@pytest.mark.parametrize(
    ("outcomes", "adequate", "says"),
    [
        ((True, True), True, "law is adequate for this recording"),
        ((True, None), False, "not shown adequate for this recording: the checks run pass (a)"),
        ((None, None), False, "not shown adequate for this recording: no check could run"),
        ((False, None), False, "is not adequate for this recording (failed: a; not run: b)"),
        ((False, True), False, "is not adequate for this recording (failed: a)"),
    ],
)
def test_the_verdict_is_adequate_only_when_every_check_ran_and_passed(outcomes, adequate, says):
    checks = [_check(k, p) for k, p in zip("ab", outcomes, strict=True)]
    assert _adequate(checks) is adequate
    assert says in _verdict("the law", checks)


def test_the_default_window_of_a_long_decay_is_unchanged():
    decay = analysed_decay(simulate(seed=31))
    n = peak_positions(decay).size
    assert n > 13
    assert default_window(decay) == max(2, round((n - 1) / 2 / 8))


def test_a_velocity_recorded_alone_keeps_windows_of_two():
    """Its windows fit their own offset: on one oscillation the constancy test was not
    calibrated (``benchmarks/short_checks.py --level``), so a short one has fewer than
    three windows of two, and the constancy test is named as not run."""
    run = simulate(release=Release(initial_displacement_m=2e-4), seed=33)
    alone = Run(time=run.time, velocity=run.velocity, metadata=dict(run.metadata))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = analysed_decay(alone)
    assert decay.derived_channel == "displacement"
    assert peak_positions(decay).size < 13
    assert default_window(decay) == 2
    assert default_window(analysed_decay(run)) == 1


def test_check_answers_a_coarse_record_with_exit_1(tmp_path, capsys):
    """Before, ``bayestribo check`` refused it (exit 2: fewer than one window of 2)."""
    path = write_run(_coarse_run(), tmp_path / "coarse.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["check", str(path), "--json", "--draws", "100"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["not_run"] == [CONSTANCY, HALVES]
    assert "not run" in data["verdict"]


def test_auto_says_its_verdict_rests_on_the_misfit_tests_when_the_halves_cannot_run():
    note = "8 turning points, fewer than the 17 two halves need"
    c = LawComparison(
        "stub",
        {},
        "viscous",
        "viscous",
        ["viscous"],
        halves={"tested": False, "agree": True, "note": note},
    )
    assert c.describe().endswith(
        f"adequate on its misfit tests alone, the halves not compared: {note}"
    )
    tested = LawComparison(
        "stub", {}, "viscous", "viscous", ["viscous"], halves={"tested": True, "agree": True}
    )
    assert "halves not compared" not in tested.describe()


def _seismometer_run(seed: int = 0) -> Run:
    """A seismometer's coil: the velocity alone (arbitrary units, 0.3 at the largest)
    of a viscous oscillator (ζ = 0.08, 15 s period, closed form) released at 10 s,
    300 s at 10 Hz with white noise 2e-4: it fades into the noise after about ten half
    cycles (``benchmarks/seismometer.py``)."""
    zeta, omega = 0.08, 2.0 * math.pi / 15.0
    wd = omega * math.sqrt(1.0 - zeta**2)
    t = np.arange(0.0, 300.0, 0.1)
    s = np.maximum(t - 10.0, 0.0)
    v = -0.3 * omega / wd * np.exp(-zeta * omega * s) * np.sin(wd * s)
    v += np.random.default_rng(seed).normal(0.0, 2e-4, t.size)
    return Run(time=t, velocity=v, metadata={"length_unit": "arbitrary"})


def test_a_velocity_alone_counts_its_own_peaks_not_its_integrals():
    """The integrated displacement's turning points carry the integral's wander, which
    their predictive intervals do not: shown, not counted (before, 9 of 10 such
    records of the law failed the peaks' check on them)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = check_adequacy(_seismometer_run())
    p = report.predictive
    assert p.integrated and p.coverage == p.velocity.coverage
    assert p.to_dict()["counted"] == ["velocity"]
    assert "integrated from the velocity, not counted" in p.statement
    assert _by_key(report)["peaks"]["passed"] is True
