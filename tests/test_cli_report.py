"""``bayestribo report``: a run file or a campaign folder as one HTML report."""

from __future__ import annotations

from pathlib import Path

import pytest

from bayestribo.cli import main
from bayestribo.commands.report import campaign_selection, notebook_for, parse_params
from bayestribo.report import ReportError

pytest.importorskip("nbclient")

REPO = Path(__file__).resolve().parents[1]
RUN = REPO / "data" / "runs" / "glycerol-N0.31-r1.csv"


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_report_of_a_run_file_is_html_with_embedded_figures(tmp_path, capsys):
    pytest.importorskip("nbconvert")
    html = tmp_path / "out" / "report.html"
    figures = tmp_path / "figures"
    status = main(
        [
            "report",
            str(RUN),
            "--out",
            str(html),
            "--figures",
            str(figures),
            "--seed",
            "3",
            "--param",
            "check_model=False",
            "--param",
            "grid_points=24",
            "--hide-code",
        ]
    )
    assert status == 0
    out = capsys.readouterr().out
    assert str(html.resolve()) in out
    text = html.read_text(encoding="utf-8")
    assert text.count("data:image/png;base64") >= 5  # signals, decay, traces, corner, Π...
    assert "from bayestribo.fit import fit" not in text  # --hide-code
    assert "glycerol-N0.31-r1" in text
    assert "Traceback" not in text
    assert {"signals.png", "corner.png", "pi_band.png"} <= {p.name for p in figures.glob("*")}


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
