"""``bayestribo report``: a run file or a campaign folder as one HTML report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _paths import REPO

from bayestribo.campaign.results import DEFAULT_SEED
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
        inject_parameters(read_notebook(notebook), parameters)  # names and types valid
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
    argv += ["--figures", str(tmp_path / "figs"), "--figure-format", "svg"]
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
    assert params["figure_format"] == "svg"
    assert kwargs["show_code"] is False and Path(kwargs["html"]) == html
    # the parameters are the notebook's, and the reading options are read_run's
    inject_parameters(read_notebook("single_run"), params)
    run = read_run(params["run_path"], **params["read_kwargs"])
    assert run.length_unit == "arbitrary" and run.velocity is None
    assert str(html.resolve()) in capsys.readouterr().out


def test_by_default_the_figures_are_pdf_next_to_the_report_and_the_code_is_left_out(
    tmp_path, captured
):
    if not RUN.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    assert main(["report", str(RUN), "--out", str(tmp_path / "r.html")]) == 0
    [(_, params, kwargs)] = captured
    assert params["figure_dir"] == str((tmp_path / "r-figures").resolve())
    assert params["figure_format"] == "pdf" and kwargs["show_code"] is False
    assert "seed" not in params  # the notebook's default: the package's default seed
    assert main(["report", str(RUN), "--out", str(tmp_path / "r.html"), "--show-code"]) == 0
    assert captured[-1][2]["show_code"] is True


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_report_of_a_folder_without_campaign_results_fits_with_the_default_seed(
    tmp_path, captured, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)  # no ./bayestribo-campaign here
    assert main(["report", str(RUN.parent.parent), "--out", str(tmp_path / "c.html")]) == 0
    [(notebook, params, _)] = captured
    assert notebook == "loads"
    assert params == {
        "data_dir": str(RUN.parent.parent.resolve()),  # bundled series: the defaults
        "data_label": str(RUN.parent.parent),  # as typed, for the commands the text names
        "campaign_seed": DEFAULT_SEED,
        "figure_dir": str((tmp_path / "c-figures").resolve()),
        "figure_format": "pdf",
    }
    assert "no campaign results found" in capsys.readouterr().err


def _campaign_results(folder: Path, data: Path, seed: int = 3) -> Path:
    """A minimal `bayestribo campaign` results folder for runs under ``data``."""
    from bayestribo.campaign.catalog import register_run

    folder.mkdir(parents=True)
    catalog = folder / "catalog.sqlite"
    run = data / "r1.csv"
    run.write_text("time_s,displacement_m\n0,0\n")
    register_run(catalog, path=run, sha256="0" * 64, metadata={"run_id": "r1", "series": "oil"})
    report = {"settings": {"seed": seed, "fit": {}}, "by": ["load_N"], "catalog": str(catalog)}
    (folder / "population.json").write_text(json.dumps(report))
    return folder


def test_report_of_a_campaign_reuses_its_results(tmp_path, captured, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    data = tmp_path / "data"
    data.mkdir()
    (data / "manifest.csv").write_text("run_id,file,series\nr1,r1.csv,oil\n")
    results = _campaign_results(tmp_path / "bayestribo-campaign", data)
    # the results folder itself, the data folder (found in ./bayestribo-campaign), --campaign
    for argv in (
        ["report", str(results)],
        ["report", str(data)],
        ["report", str(data), "--campaign", str(results)],
    ):
        assert main([*argv, "--out", str(tmp_path / "c.html")]) == 0
        params = captured[-1][1]
        assert params["campaign_dir"] == str(results.resolve())
        assert params["series"] is None and params["air_series"] is None  # no such series
        assert "campaign_seed" not in params  # the campaign's own seed
        # where the runs are, as typed (or from here for the results folder: "data")
        assert (tmp_path / params["data_label"]).resolve() == data.resolve()
        assert argv[1] != str(results) or params["data_label"] == "data"
        assert "reusing the fits of the campaign" in capsys.readouterr().err
    # --refit fits for the report instead
    assert main(["report", str(data), "--refit", "--out", str(tmp_path / "c.html")]) == 0
    assert "campaign_dir" not in captured[-1][1]
    # a seed other than the campaign's is refused rather than silently ignored
    n = len(captured)
    assert main(["report", str(results), "--seed", "5", "--out", str(tmp_path / "c.html")]) == 2
    assert "fitted with seed 3" in capsys.readouterr().err and len(captured) == n


def test_a_parameter_of_the_wrong_type_fails_at_once_naming_it(tmp_path, captured, capsys):
    if not RUN.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    argv = ["report", str(RUN), "--out", str(tmp_path / "r.html"), "--param", "max_steps=5k"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "parameter 'max_steps': expected int, got '5k'" in err
    assert not captured and not (tmp_path / "r.html").exists()


def test_missing_path_is_an_error_naming_it(tmp_path, capsys):
    missing = tmp_path / "nothing.csv"
    assert main(["report", str(missing), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert "nothing.csv" in err and "no such run file or folder" in err
    assert not (tmp_path / "r.html").exists()


def test_folder_without_runs_is_an_error(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("no runs here")
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "manifest.csv or run files" in err and "results of `bayestribo campaign`" in err


def test_run_options_are_refused_for_a_folder(tmp_path, capsys):
    (tmp_path / "manifest.csv").write_text("run_id,file\n")
    assert main(["report", str(tmp_path), "--load", "0.3"]) == 2
    assert "describe one run file" in capsys.readouterr().err


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_unknown_parameter_is_refused_before_running(tmp_path, capsys):
    assert main(["report", str(RUN), "--out", str(tmp_path / "r.html"), "--param", "nope=1"]) == 2
    assert "nope" in capsys.readouterr().err
    assert not (tmp_path / "r.html").exists()


def test_notebook_choice(tmp_path):
    assert notebook_for(RUN.parent.parent) == "loads"
    assert notebook_for(RUN) == "single_run"
    # a folder of recordings without sidecars: another rig's, the real-data report
    (tmp_path / "rec_1.csv").write_text("time;position\n0;1\n")
    (tmp_path / "README.md").write_text("# A rig")
    assert notebook_for(tmp_path) == "real_data"


def test_a_folder_of_recordings_not_read_as_given_is_refused_before_running(tmp_path, capsys):
    """The spring-and-disc files have no units in their header: without --columns the
    report says so at once, naming the file and the options."""
    (tmp_path / "rec_1.csv").write_text("time;position\n0;1\n0.01;2\n")
    assert main(["report", str(tmp_path), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert "rec_1.csv" in err and "--columns" in err
    assert not (tmp_path / "r.html").exists()


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


@pytest.mark.skipif(not RUN.is_file(), reason="the bundled campaign data/ is absent")
def test_out_may_name_a_folder_as_for_every_other_command(tmp_path, captured):
    folder = tmp_path / "reports"
    assert main(["report", str(RUN), "--out", str(folder)]) == 0
    html = Path(captured[-1][2]["html"])
    assert html == folder / "glycerol-N0.31-r1-report.html" and html.is_file()
    assert captured[-1][1]["figure_dir"] == str(
        (folder / "glycerol-N0.31-r1-report-figures").resolve()
    )


def test_a_run_report_takes_the_fit_options_of_the_fit_command(tmp_path, captured):
    """--law, --notch and --discrepancy reach the notebook's fit (one answer per
    question); a campaign folder's report refuses them, naming where they go."""
    if not RUN.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    argv = ["report", str(RUN), "--out", str(tmp_path / "r.html"), "--law", "auto"]
    assert main([*argv, "--notch", "50", "--discrepancy"]) == 0
    [(_, params, _)] = captured
    assert params["law"] == "auto" and params["notch"] == 50.0 and params["discrepancy"]
    assert main(["report", str(RUN.parent.parent), "--law", "auto"]) == 2


def test_the_report_exits_as_fit_would():
    """1 for a record that is not converged, misfits, piles on a bound or fails the
    model checks; 0 for a clean one."""
    from bayestribo.cli.report import fit_reasons

    clean = {
        "fit": {
            "law": "viscous+coulomb",
            "parameters": {"zeta": {}},
            "diagnostics": {
                "converged": True,
                "misfit_p": 0.4,
                "shape_departure": {"p_value": 0.3},
                "at_prior_bound": [],
            },
        },
        "adequacy": {"adequate": True, "verdict": "adequate"},
    }
    assert fit_reasons(clean) == []
    misfit = json.loads(json.dumps(clean))
    misfit["fit"]["diagnostics"]["misfit_p"] = 1e-9
    assert "misfits" in fit_reasons(misfit)[0]
    # a white misfit with the discrepancy terms is carried by them
    misfit["fit"]["parameters"]["log10_discrepancy"] = {}
    assert fit_reasons(misfit) == []
    bad = json.loads(json.dumps(clean))
    bad["fit"]["diagnostics"]["converged"] = False
    bad["adequacy"] = {"adequate": False, "verdict": "not adequate (failed: windows)"}
    assert len(fit_reasons(bad)) == 2


def test_every_shipped_notebook_is_reached_by_report(tmp_path, captured, capsys):
    """``--notebook`` runs each report shipped; each gets parameters of its own."""
    from bayestribo.cli.report import NOTEBOOKS
    from bayestribo.reports import notebooks

    shipped = {p.stem for p in (Path(notebooks.__file__).parent / "ipynb").glob("*.ipynb")}
    assert set(NOTEBOOKS) == set(notebooks.NOTEBOOKS) == shipped
    data = REPO / "data"
    appstat = REPO.parent / "shared" / "external-data" / "appstat2020-harmonic-oscillator"
    recordings = tmp_path / "recordings"
    recordings.mkdir()
    # without the real recordings (a checkout elsewhere), two free decays of a
    # damped pendulum as two-column text stand in for them
    t = np.arange(0.0, 20.0, 0.01)
    for k, name in enumerate(("HarmOsc1.txt", "HarmOsc2.txt")):
        decay = np.exp(-(0.05 + 0.02 * k) * t) * np.cos(2 * np.pi * 1.1 * t)
        stand_in = "".join(f"{a:.2f} {b:.6f}\n" for a, b in zip(t, decay, strict=True))
        (recordings / name).write_bytes(
            (appstat / name).read_bytes() if appstat.is_dir() else stand_in.encode()
        )
    (recordings / "notes.md").write_text("not a recording")
    cases = {
        "single_run": [str(RUN)],
        "loads": [str(data)],
        "viscosity": [str(data), "--seed", "3"],
        "real_data": [str(recordings)],
        "acquisition": [],
    }
    for notebook, argv in cases.items():
        out = tmp_path / f"{notebook}.html"
        assert main(["report", *argv, "--notebook", notebook, "--out", str(out)]) == 0
        name, params, _ = captured[-1]
        assert name == notebook and out.is_file()
    params = {name: p for name, p, _ in captured}
    assert "fit_kwargs" not in params["real_data"]  # the defaults of `bayestribo fit`
    assert "--notebook viscosity`" in capsys.readouterr().err  # the loads report names it
    assert params["viscosity"]["data_dir"] == str(data.resolve())
    assert params["viscosity"]["campaign_seed"] == 3
    assert params["real_data"]["files"] == ["HarmOsc1.txt", "HarmOsc2.txt"]
    # a notebook asked of the wrong kind of path, or without one, is refused in one line
    assert main(["report", str(RUN), "--notebook", "loads"]) == 2
    assert "--notebook loads reports on a folder" in capsys.readouterr().err
    assert main(["report", "--notebook", "viscosity"]) == 2
    assert "PATH: give a run file or a campaign folder" in capsys.readouterr().err


def test_none_for_an_optional_text_parameter_is_none():
    from bayestribo.reports.notebooks import notebook_parameter_specs

    specs = notebook_parameter_specs(read_notebook("loads"))
    got = parse_params(["series=None", "air_series=air", "lubricant_tag=0.0055"], specs)
    assert got["series"] is None and got["air_series"] == "air"
    assert got["lubricant_tag"] == 0.0055  # not a parameter of the notebook: a literal


def test_a_folder_of_recordings_takes_the_fit_options(tmp_path, captured):
    """--law, --notch and --discrepancy reach the real-data report's fits, as `fit` takes
    them; a campaign folder's report still refuses them."""
    recordings = tmp_path / "rig"
    recordings.mkdir()
    t = np.arange(0.0, 5.0, 0.01)
    np.savetxt(recordings / "a.txt", np.column_stack([t, np.cos(2 * np.pi * t)]))
    argv = ["report", str(recordings), "--out", str(tmp_path / "r.html"), "--law", "auto"]
    assert main([*argv, "--notch", "50", "--discrepancy"]) == 0
    name, params, _ = captured[-1]
    assert name == "real_data"
    assert params["fit_kwargs"] == {"law": "auto", "notch": 50.0, "discrepancy": True}


def test_a_folder_report_exits_as_fit_would_for_each_recording():
    """The real-data report's record gives the reasons `bayestribo fit` would exit 1 for,
    recording by recording: not converged, a misfit, a law comparison with no law
    adequate; none for a recording whose fit is right."""
    from bayestribo.cli.report import recordings_reasons

    good = {"diagnostics": {"converged": True, "misfit_p": 0.4}, "law_comparison": None}
    misfit = {"diagnostics": {"converged": True, "misfit_p": 1e-9}, "parameters": {}}
    stuck = {"diagnostics": {"converged": False, "reasons": ["R-hat 1.2"], "misfit_p": 0.3}}
    no_law = {
        "diagnostics": {"converged": True, "misfit_p": 0.3},
        "law_comparison": {"adequate": False},
    }
    assert recordings_reasons({"fits": {"a.csv": good}}) == []
    reasons = recordings_reasons(
        {"fits": {"a.csv": good, "b.csv": misfit, "c.csv": stuck, "d.csv": no_law}}
    )
    assert [r.split(":")[0] for r in reasons] == ["b.csv", "c.csv", "d.csv"]
    assert "misfits" in reasons[0] and "R-hat 1.2" in reasons[1] and "no law" in reasons[2]
    inadequate = {"fits": {"a.csv": good}, "adequacy": {"a.csv": {"adequate": False}}}
    assert recordings_reasons(inadequate)[0].startswith("a.csv: ")
