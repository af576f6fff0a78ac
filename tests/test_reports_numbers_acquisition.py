"""Every number of the acquisition report is the fit's, in the digits the rule gives.

``bayestribo report --notebook acquisition`` logs a run from the simulated board (as
``bayestribo acquire`` logs one from the rig), recovers it from its raw log and fits
it; ``bayestribo fit --json`` then fits the run file the report acquired with the same
seed and settings. Every table cell that is a value with its interval must be a
(mean, interval) of that JSON written by the digit rule
(:func:`bayestribo.summary.interval_text`), and the report's own record of its fit
(``summary_path``) must be the command's: one answer per question. The rendering is the
session's shared one (``acquisition_report`` of ``conftest.py``, short sampler
``ACQUISITION_SETTINGS``), and one fit for the module.
"""

from __future__ import annotations

import contextlib
import io
import json
import re

import pytest
from _renderings import ACQUISITION_SETTINGS, GROUP
from _report_numbers import interval_cells, unmatched

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli.main import main

pytestmark = pytest.mark.xdist_group(GROUP)  # the shared renderings made on one worker

#: The acquisition notebook's default seed (its board's noise and its fit).
SEED = 2010


@pytest.fixture(scope="module")
def acquired(acquisition_report):
    """The shared rendering's page and record, and ``bayestribo fit --json`` of the run it
    acquired with the same seed and settings (a short sampler: whether it converges does
    not matter here, only that the report and the command give the same numbers)."""
    record = json.loads(acquisition_report.summary.read_text())
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        main(["fit", record["run"], "--seed", str(SEED), *ACQUISITION_SETTINGS, "--json"])
    page = acquisition_report.html.read_text(encoding="utf-8")
    return page, record, json.loads(printed.getvalue())


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_every_interval_of_the_acquisition_report_is_the_fits_in_its_digits(acquired):
    page, _, fitted = acquired
    cells = interval_cells(page)
    # ζ and μ_k of the fit beside the board's true values
    assert {column for _, column, _ in cells} == {"posterior mean [95 %]"}
    assert len(cells) == 2
    assert unmatched(page, fitted) == []


def test_the_acquisition_reports_fit_is_the_commands(acquired):
    _, record, fitted = acquired
    assert record["complete"] and record["recovered_same_samples"]
    reported = record["fit"]
    assert reported["law"] == fitted["law"]
    assert reported["diagnostics"]["n_steps"] == fitted["diagnostics"]["n_steps"]
    for name in ("zeta", "mu_k"):
        ours, theirs = reported["parameters"][name], fitted["parameters"][name]
        assert (ours["mean"], ours["interval"]) == (theirs["mean"], theirs["interval"]), name


def test_the_acquisition_report_says_a_misfit_when_the_command_does(acquired):
    from bayestribo.cli.report import fit_reasons

    page, _, fitted = acquired
    misfit = any("misfits" in reason for reason in fit_reasons({"fit": fitted}))
    text = re.sub(r"<[^>]+>", " ", re.sub(r"<(style|script)\b.*?</\1>", "", page, flags=re.S))
    assert ("misfits" in text) == misfit
