"""One answer per question: ``bayestribo report`` and ``bayestribo fit`` on a real recording.

HarmOsc3 (AppStat2020: a weight on a spring sliding against a metal plate), read as the
other tests read it, is fitted by both commands at the same seed and options; the
posterior of every quantity must read the same in the digits the report shows, and the
two commands must exit alike. (Once, the report fixed 64 Π increments where the command
took one per half cycle: the friction displacement was 8 sd apart.)
``benchmarks/report_vs_fit.py`` makes the same comparison on every bundled run and
every real recording.
"""

from __future__ import annotations

import json
import re

import pytest

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from _report_numbers import interval_cells, section, unmatched

from bayestribo.cli import main
from bayestribo.summary import interval_text

#: Reading options of the AppStat2020 text files, and a short sampler for a quick test
#: (the same for both commands: whether it converges does not matter here).
READING = ["--columns", "t", "x", "--length-unit", "arbitrary"]
STEPS = 3000
SEED = 11


def test_report_and_fit_give_one_answer_on_a_real_recording(appstat_file, tmp_path, capsys):
    path = appstat_file("HarmOsc3.txt")
    fit_exit = main(
        ["fit", str(path), *READING, "--seed", str(SEED), "--max-steps", str(STEPS), "--json"]
    )
    fitted = json.loads(capsys.readouterr().out)
    summary = tmp_path / "summary.json"
    argv = ["report", str(path), *READING, "--seed", str(SEED), "--out", str(tmp_path / "r.html")]
    argv += ["--param", f"max_steps={STEPS}", "--param", "check_model=False"]
    argv += ["--param", f"summary_path={summary}", "--figure-format", "png"]
    report_exit = main(argv)
    reported = json.loads(summary.read_text())["fit"]
    assert reported["law"] == fitted["law"]
    quantities = [n for n in fitted["parameters"] if not n.startswith("log10_")]
    assert "friction_displacement" in quantities and "zeta" in quantities
    for name in quantities:
        f, r = fitted["parameters"][name], reported["parameters"][name]
        assert interval_text(r["mean"], *r["interval"]) == interval_text(
            f["mean"], *f["interval"]
        ), name
    # every value with its interval that the answer and the fit's section show is one of
    # the command's JSON, in the digits the rule gives
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    for title in ("The answer", "Bayesian fit"):
        assert interval_cells(section(page, title)), title
        assert unmatched(section(page, title), fitted) == [], title
    # every other one (the classical estimates, by ±1.96 standard errors) is one of the
    # report's record, in the same digits
    record = json.loads(summary.read_text())
    assert interval_cells(section(page, "Classical estimates"))
    assert unmatched(page, fitted, record) == []
    # the grid of Π increments and the sampler's run: the same fit, not a near one
    assert reported["diagnostics"]["n_steps"] == fitted["diagnostics"]["n_steps"]
    assert report_exit == fit_exit
    # the law misfits this recording (dry friction on a plate; the fit exits 1): the
    # report's answer does not present ζ and x_c as a measurement, and says what to do
    assert report_exit == 1
    heads = [m.start() for m in re.finditer(r"<h2\b", page)]
    answer = page[heads[0] : heads[1]]
    assert "The answer" in answer and 'class="bt-verdict"' in answer
    assert "The law holds" not in answer
    assert "not a measurement" in answer or "Not a result" in answer
