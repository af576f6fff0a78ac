"""Every number of the real-data report is the commands', in the digits the rule gives.

``bayestribo report`` of the AppStat2020 folder (one recording, HarmOsc2: a cardboard
disc adds air drag; fitted and checked along its decay, with a short sampler), then
``bayestribo fit --json`` and ``bayestribo estimate --json`` of the same recording with
the same reading options and settings. Every table cell of the whole page that is a
value with its interval must be a triple of those JSON outputs (the answer's x_c/A₀ by
the recording's first amplitude) or of the report's record of what no command prints
(the windowed fits of its adequacy check, friction's share of ΔE), written by the digit
rule (:func:`bayestribo.summary.interval_text`). One rendering and one fit for the
module.
"""

from __future__ import annotations

import contextlib
import io
import json

import pytest
from _report_numbers import interval_cells, table_cells, unmatched

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli.main import main

READING = ["--columns", "t", "x", "--length-unit", "arbitrary"]
#: A short sampler: the report and the command must agree, converged or not.
SETTINGS = ["--max-steps", "1500", "--grid-points", "32"]
RECORDING = "HarmOsc2.txt"


def _json_of(argv: list[str]) -> dict:
    """What a command prints with ``--json``, whatever its exit status."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        main(argv)
    return json.loads(printed.getvalue())


@pytest.fixture(scope="module")
def reported(appstat_file, tmp_path_factory):
    path = appstat_file(RECORDING)
    tmp = tmp_path_factory.mktemp("real")
    page, summary = tmp / "report.html", tmp / "summary.json"
    argv = ["report", str(path.parent), "--notebook", "real_data", *READING, *SETTINGS]
    argv += ["--out", str(page), "--figure-format", "png"]
    for name in ("files", "fit_files", "check_files"):
        argv += ["--param", f"{name}={[RECORDING]!r}"]
    main([*argv, "--param", f"summary_path={summary}"])  # exits 1: the law misfits
    fitted = _json_of(["fit", str(path), *READING, *SETTINGS, "--json"])
    estimated = _json_of(["estimate", str(path), *READING, "--json"])
    record = json.loads(summary.read_text())
    return page.read_text(encoding="utf-8"), record, fitted, estimated


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_every_interval_of_the_real_data_report_is_the_commands_in_its_digits(reported):
    page, record, fitted, estimated = reported
    cells = interval_cells(page)
    heads = {head for _, _, head in cells}
    # the answer, the classical estimates, the fit and the windows along the decay
    assert len(heads) >= 4 and len(cells) >= 15
    scales = [1.0, *(1.0 / r["A₀ [signal unit]"] for r in record["overview"])]
    said = (record["adequacy"], record["shares"])
    assert unmatched(page, fitted, estimated, *said, scales=scales) == []


def test_the_real_data_reports_fit_is_the_commands(reported):
    _, record, fitted, _ = reported
    ours = record["fits"][RECORDING.removesuffix(".txt")]
    assert ours["law"] == fitted["law"]
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
