"""Every number of the real-data report is the commands', in the digits the rule gives.

The session's real-data report (``real_data_report`` of ``conftest.py``: the AppStat2020
folder, all three recordings read, HarmOsc3 fitted with 24 Π increments, HarmOsc2's
adequacy checked along its decay), then ``bayestribo fit --json`` of the fitted
recording with the same reading options and settings, and ``bayestribo estimate
--json`` of every recording read. Every table cell of the whole page that is a value
with its interval must be a triple of those JSON outputs (the answer's x_c/A₀ by the
recording's first amplitude) or of the report's record of what no command prints (the
windowed fits of its adequacy check, friction's share of ΔE), written by the digit rule
(:func:`bayestribo.summary.interval_text`). The rendering is the session's (one notebook
kernel for every real-data test), the commands run once for the module.
"""

from __future__ import annotations

import contextlib
import io
import json

import pytest
from _renderings import GROUP
from _report_numbers import interval_cells, table_cells, unmatched

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli.main import main

pytestmark = pytest.mark.xdist_group(GROUP)  # the shared renderings made on one worker

READING = ["--columns", "t", "x", "--length-unit", "arbitrary"]


def _json_of(argv: list[str]) -> dict:
    """What a command prints with ``--json``, whatever its exit status."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        main(argv)
    return json.loads(printed.getvalue())


def _settings(parameters: dict) -> list[str]:
    """The rendering's fit settings as options of ``bayestribo fit``."""
    options = []
    for key, value in parameters.get("fit_kwargs", {}).items():
        options += [f"--{key.replace('_', '-')}", str(value)]
    return options


@pytest.fixture(scope="module")
def reported(real_data_report):
    made = real_data_report
    [recording] = made.parameters["fit_files"]
    folder = made.source
    argv = ["fit", str(folder / recording), *READING, *_settings(made.parameters), "--json"]
    fitted = _json_of(argv)
    record = json.loads(made.summary.read_text())
    estimated = [
        _json_of(["estimate", str(folder / f"{row['recording']}.txt"), *READING, "--json"])
        for row in record["overview"]
    ]
    page = made.html.read_text(encoding="utf-8")
    return page, record, recording, fitted, estimated


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_every_interval_of_the_real_data_report_is_the_commands_in_its_digits(reported):
    page, record, _, fitted, estimated = reported
    cells = interval_cells(page)
    heads = {head for _, _, head in cells}
    # the answer, the classical estimates, the fit and the windows along the decay
    assert len(heads) >= 4 and len(cells) >= 15
    assert record["adequacy"] and record["shares"]  # the check and the shares are tabled
    scales = [1.0, *(1.0 / r["A₀ [signal unit]"] for r in record["overview"])]
    said = (record["adequacy"], record["shares"])
    assert unmatched(page, fitted, *estimated, *said, scales=scales) == []


def test_the_real_data_reports_fit_is_the_commands(reported):
    _, record, recording, fitted, _ = reported
    ours = record["fits"][recording.removesuffix(".txt")]
    assert ours["law"] == fitted["law"]
    assert fitted["parameters"]
    for name, theirs in fitted["parameters"].items():
        mine = ours["parameters"][name]
        assert (mine["mean"], mine["interval"]) == (theirs["mean"], theirs["interval"]), name


def test_the_real_data_report_says_dimensionless_not_a_dash(reported):
    page, *_ = reported
    cells = table_cells(page)
    units = [text for text, column, _ in cells if column == "unit"]
    assert "dimensionless" in units and "-" not in units
    texts = {text for text, _, _ in cells}  # the answer's rows, by their units
    assert "ζ [dimensionless]" in texts and "ζ [-]" not in texts
