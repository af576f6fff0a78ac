"""``bayestribo report``: a run file or a campaign folder as one HTML report."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _paths import REPO

from bayestribo.cli import main
from bayestribo.cli.report import campaign_selection, notebook_for, parse_params
from bayestribo.io import read_run
from bayestribo.reports.notebooks import ReportError, inject_parameters, read_notebook

pytest.importorskip("nbclient")

RUN = REPO / "data" / "runs" / "glycerol-N0.31-r1.csv"


@pytest.fixture
def captured(monkeypatch):
    """Replace the notebook run by a recorder: the command's own work is the parameters.

    The notebooks themselves are executed and rendered in tests/test_reports_notebooks.py and,
    through the same ``run_report``, end to end by the demo test.
    """
    calls = []

    def fake_run_report(notebook, parameters, **kwargs):
        calls.append((notebook, dict(parameters), kwargs))
        Path(kwargs["html"]).write_text("<html></html>")

    monkeypatch.setattr("bayestribo.reports.notebooks.run_report", fake_run_report)
    return calls


def test_report_of_a_text_file_passes_the_reading_options_to_the_notebook(
    tmp_path, captured, capsys
):
    t = np.arange(0.0, 5.0, 0.01)
    text = tmp_path / "decay.txt"
    np.savetxt(text, np.column_stack([t, np.exp(-0.1 * t) * np.cos(2 * np.pi * t)]))
    html = tmp_path / "out.html"
    argv = ["report", str(text), "--out", str(html), "--columns", "t", "x"]
    argv += ["--length-unit", "arbitrary", "--seed", "7", "--param", "max_steps=500"]
    argv += ["--figures", str(tmp_path / "figs"), "--hide-code"]
    assert main(argv) == 0
    [(notebook, params, kwargs)] = captured
    assert notebook == "single_run"
    assert params["run_path"] == str(text.resolve())
    assert params["read_kwargs"] == {
        "columns": ["time_s", "displacement_m"],
        "metadata": {"length_unit": "arbitrary"},
    }
    assert params["seed"] == 7 and params["max_steps"] == 500
    assert params["figure_dir"] == str((tmp_path / "figs").resolve())
    assert kwargs["hide_code"] is True and Path(kwargs["html"]) == html
    # the parameters are the notebook's, and the reading options are read_run's
    inject_parameters(read_notebook("single_run"), params)
    run = read_run(params["run_path"], **params["read_kwargs"])
    assert run.length_unit == "arbitrary" and run.velocity is None
    assert str(html.resolve()) in capsys.readouterr().out


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_report_of_a_folder_runs_the_campaign_notebook(tmp_path, captured):
    assert main(["report", str(RUN.parent.parent), "--out", str(tmp_path / "c.html")]) == 0
    [(notebook, params, _)] = captured
    assert notebook == "loads"
    assert params == {"data_dir": str(RUN.parent.parent.resolve())}  # bundled series
    inject_parameters(read_notebook("loads"), params)


def test_missing_path_is_an_error_naming_it(tmp_path, capsys):
    missing = tmp_path / "nothing.csv"
    assert main(["report", str(missing), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert "nothing.csv" in err and "no such run file or folder" in err
    assert not (tmp_path / "r.html").exists()


def test_folder_without_runs_is_an_error(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("no runs here")
    assert main(["report", str(tmp_path)]) == 2
    assert "manifest.csv or run files" in capsys.readouterr().err


def test_run_options_are_refused_for_a_folder(tmp_path, capsys):
    (tmp_path / "manifest.csv").write_text("run_id,file\n")
    assert main(["report", str(tmp_path), "--load", "0.3"]) == 2
    assert "describe one run file" in capsys.readouterr().err


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_unknown_parameter_is_refused_before_running(tmp_path, capsys):
    assert main(["report", str(RUN), "--out", str(tmp_path / "r.html"), "--param", "nope=1"]) == 2
    assert "nope" in capsys.readouterr().err
    assert not (tmp_path / "r.html").exists()


def test_notebook_choice():
    assert notebook_for(RUN.parent.parent) == "loads"
    assert notebook_for(RUN) == "single_run"


def test_parse_params_literals_and_strings():
    assert parse_params(["a=1", "b=[1, 2]", "c=hello", "d={'x': None}"]) == {
        "a": 1,
        "b": [1, 2],
        "c": "hello",
        "d": {"x": None},
    }
    with pytest.raises(ReportError, match="KEY=VALUE"):
        parse_params(["no_equals_sign"])


def test_campaign_selection_follows_the_manifest(tmp_path):
    if RUN.is_file():
        assert campaign_selection(RUN.parent.parent) == {}  # bundled: glycerol and air series
    (tmp_path / "manifest.csv").write_text("run_id,file,series\nr1,runs/r1.csv,oil\n")
    assert campaign_selection(tmp_path) == {"series": None, "air_series": None}
    assert campaign_selection(tmp_path / "no-manifest") == {"series": None, "air_series": None}
