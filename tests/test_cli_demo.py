"""``bayestribo demo``: the quick start fits, reports and prints the intervals."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from _paths import REPO
from _renderings import GROUP

from bayestribo.cli import demo, main

pytest.importorskip("nbclient")


@pytest.mark.validation  # two reports rendered: run by hand (-m validation)
@pytest.mark.skipif(not (REPO / "data").is_dir(), reason="the bundled campaign data/ is absent")
def test_quick_demo_prints_intervals_beside_the_paper_and_writes_reports(tmp_path, capsys):
    """The quick demo end to end: its two reports rendered, its intervals printed.

    Left out of the default run. By default, the demo's parameters are checked against the
    notebooks and its printing against the records they write (the session's shared
    renderings: the next test), its steps and exit status with stand-in reports (the
    tests below), and each notebook is rendered on parameters like the demo's (the loads
    report without runs in air: ``test_reports_campaign_laws.py``; the single-run report
    without its model checks: ``test_cli_report_vs_fit.py``).
    """
    pytest.importorskip("nbconvert")
    out = tmp_path / "demo"
    # --quick cuts the population samplers short: they do not converge, and it says so
    assert main(["demo", "--quick", "--out", str(out)]) == 1
    captured = capsys.readouterr()
    text = captured.out
    assert "bayestribo demo: NOT CONVERGED" in captured.err
    assert "fewer than 50 autocorrelation times" in captured.err
    assert "paper, glycerol (mean, σ)" in text
    assert "0.0236 (σ 0.0012)" in text and "0.0294 (σ 0.0036)" in text
    fit_line = next(line for line in text.splitlines() if "Bayesian fit" in line)
    intervals = re.findall(r"([\d.]+) \[([\d.]+), ([\d.]+)\]", fit_line)
    assert len(intervals) == 2  # ζ and μ_k
    for mean, lo, hi in intervals:
        assert float(lo) <= float(mean) <= float(hi)
    assert "population" in text and "between-run σ" in text
    for name in ("single-run-report.html", "campaign-report.html"):
        assert (out / name).is_file()
        assert str(out / name) in text  # says where they are
        assert "data:image/png;base64" in (out / name).read_text(encoding="utf-8")
    assert list((out / "figures" / "single-run").glob("*.png"))
    assert list((out / "figures" / "campaign").glob("*.png"))


@pytest.mark.xdist_group(GROUP)  # the shared renderings made on one worker
@pytest.mark.skipif(not (REPO / "data").is_dir(), reason="the bundled campaign data/ is absent")
def test_quick_demo_gives_the_notebooks_their_parameters_and_prints_their_records(
    single_run_report, loads_report, tmp_path, monkeypatch, capsys
):
    """``bayestribo demo --quick`` with its reports standing in: each notebook's parameters
    are checked as a report run checks them (names and types), and what the demo prints
    is read from the records those notebooks wrote for the session's shared single-run and
    campaign reports (``conftest.py``; the campaign's populations sampled 600 steps, too
    few to converge, as the quick demo's)."""
    from bayestribo.reports.notebooks import inject_parameters, read_notebook

    records = {"single_run": single_run_report.summary, "loads": loads_report.summary}
    calls = []

    def report(name, params, html, show_code=False):
        inject_parameters(read_notebook(name), params)  # names and types valid
        calls.append(name)
        Path(params["summary_path"]).write_text(records[name].read_text(encoding="utf-8"))
        Path(html).write_text("<html></html>", encoding="utf-8")
        return Path(html)

    monkeypatch.setattr("bayestribo.reports.notebooks.run_report", report)
    out = tmp_path / "demo"
    assert main(["demo", "--quick", "--out", str(out)]) == 1
    assert calls == ["single_run", "loads"]
    captured = capsys.readouterr()
    text = captured.out
    assert "bayestribo demo: NOT CONVERGED" in captured.err
    assert "fewer than 50 autocorrelation times" in captured.err
    assert "paper, glycerol (mean, σ)" in text
    assert "0.0236 (σ 0.0012)" in text and "0.0294 (σ 0.0036)" in text
    fit_line = next(line for line in text.splitlines() if "Bayesian fit" in line)
    intervals = re.findall(r"([\d.]+) \[([\d.]+), ([\d.]+)\]", fit_line)
    assert len(intervals) == 2  # ζ and μ_k
    for mean, lo, hi in intervals:
        assert float(lo) <= float(mean) <= float(hi)
    assert "population" in text and "between-run σ" in text
    for name in ("single-run-report.html", "campaign-report.html"):
        assert str(out / name) in text  # says where they are


def test_campaign_is_simulated_into_the_cache_when_data_is_absent(tmp_path, monkeypatch):
    calls = []

    def fake_write_campaign(folder):
        calls.append(Path(folder))
        Path(folder).mkdir(parents=True)
        (Path(folder) / "manifest.csv").write_text("run_id,file\n")
        return Path(folder) / "manifest.csv"

    monkeypatch.setenv("BAYESTRIBO_DATA", str(tmp_path / "no-data-here"))
    monkeypatch.setattr("bayestribo.synthetic.campaign.write_campaign", fake_write_campaign)
    folder, origin = demo.campaign_folder(cache=tmp_path / "cache")
    assert origin == "simulated now" and calls == [folder]
    assert folder.parent == tmp_path / "cache"
    again, origin = demo.campaign_folder(cache=tmp_path / "cache")
    assert again == folder and origin.startswith("simulated earlier") and len(calls) == 1


def test_bundled_data_is_used_when_present(monkeypatch):
    if not (REPO / "data" / "manifest.csv").is_file():
        pytest.skip("the bundled campaign data/ is absent")
    monkeypatch.delenv("BAYESTRIBO_DATA", raising=False)
    folder, origin = demo.campaign_folder()
    assert folder == REPO / "data" and origin == "bundled"


def test_quick_and_full_exclude_each_other(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--quick", "--full"])
    assert "not allowed with" in capsys.readouterr().err


def _single(converged=True):
    interval = {"mean": 0.0242507, "median": 0.0242506, "interval": [0.0242501, 0.0242513]}
    return {
        "name": "glycerol-N0.31-r1",
        "fit": {
            "parameters": {
                "zeta": interval,
                "mu_k": {"mean": 0.02854, "median": 0.02854, "interval": [0.0285, 0.0286]},
            },
            "diagnostics": {"converged": converged, "reasons": [] if converged else ["short"]},
        },
        "true": {"zeta": 0.0242508, "mu_k": 0.0285408},
    }


def _campaign(converged=True, population_converged=True):
    mean = {"mean": 0.0238, "median": 0.0237, "interval": [0.0230, 0.0247]}
    # a skewed σ: its mean and median differ in the second digit
    sigma = {"mean": 0.0024, "median": 0.0019, "interval": [0.0010, 0.0060]}
    group = {
        "label": "lubricant=glycerol,load_N=0.07",
        "diagnostics": {
            "converged": population_converged,
            "reasons": [] if population_converged else ["only 9596 steps after burn-in"],
        },
    }
    return {
        "runs": {"glycerol-N0.07-r1": {"diagnostics": {"converged": converged}}},
        "failed": {},
        "population": {
            "pooled": {
                "n_runs": 5,
                "parameters": {p: {"mean": mean, "sigma": sigma} for p in ("zeta", "mu_k")},
            }
        },
        "analysis": {
            "contact": {"groups": [group], "pooled": None},
            "trends": {"all": {"diagnostics": {"converged": True}}},
        },
    }


def test_summary_shows_enough_digits_for_a_narrow_interval_and_the_truth():
    text = "\n".join(demo.summary_lines(_single(), _campaign()))
    # an interval 1.2e-6 wide needs seven decimals to be seen at all; the report writes
    # two significant digits of its half width
    assert "0.02425070 [0.02425010, 0.02425130]" in text
    assert "true value (simulated run)" in text and "0.0242508" in text
    assert "campaign, 5 runs across loads" in text
    assert "NOT CONVERGED" not in text and "left out" not in text


def test_summary_shows_the_population_as_the_report_does():
    from bayestribo.reports import kit

    text = "\n".join(demo.summary_lines(_single(), _campaign()))
    # the report's answer: the posterior median of the draws and their interval
    sigma = _campaign()["population"]["pooled"]["parameters"]["mu_k"]["sigma"]
    line = next(line for line in text.splitlines() if "between-run σ" in line)
    assert kit.interval_text(sigma["median"], *sigma["interval"]) in line
    assert "0.0024" not in line  # not the mean
    assert "posterior median" in text


def test_summary_never_shows_an_unconverged_fit_as_if_it_had_converged():
    text = "\n".join(demo.summary_lines(_single(converged=False), _campaign(converged=False)))
    assert "SAMPLER NOT CONVERGED" in text
    assert "not converged ['glycerol-N0.07-r1']" in text


def test_unconverged_names_every_sampler_that_did_not_converge():
    assert demo.unconverged(_single(), _campaign()) == []
    stuck = demo.unconverged(_single(converged=False), _campaign(population_converged=False))
    assert stuck == [
        "the fit of glycerol-N0.31-r1: short",
        "the population contact lubricant=glycerol,load_N=0.07: only 9596 steps after burn-in",
    ]
    assert demo.unconverged(_single(), _campaign(converged=False)) == [
        "the fit of glycerol-N0.07-r1"
    ]


def _fake_reports(single, campaign, drag=None, calls=None):
    """run_report as the demo calls it, writing the given results (``drag``: the drag
    series' campaign) and an empty page; each call's (name, params) into ``calls``."""

    def fake(name, params, html, show_code=False):
        from pathlib import Path

        if calls is not None:
            calls.append((name, params))
        record = single if name == "single_run" else campaign
        if params.get("series") == demo.DRAG_SERIES:
            record = drag
        Path(params["summary_path"]).write_text(json.dumps(record), encoding="utf-8")
        Path(html).write_text("<html></html>", encoding="utf-8")
        return Path(html)

    return fake


@pytest.mark.parametrize("population_converged", [True, False])
def test_exit_status_follows_convergence_and_output_goes_to_the_cache(
    tmp_path, monkeypatch, capsys, population_converged
):
    cache = tmp_path / "cache"
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
    monkeypatch.chdir(work)
    monkeypatch.setattr(demo, "campaign_folder", lambda: (tmp_path, "bundled"))
    fake = _fake_reports(_single(), _campaign(population_converged=population_converged))
    monkeypatch.setattr("bayestribo.reports.notebooks.run_report", fake)
    status = main(["demo"])
    captured = capsys.readouterr()
    assert status == (0 if population_converged else 1)
    if not population_converged:
        assert "NOT CONVERGED (1)" in captured.err and "load_N=0.07" in captured.err
    out = cache / "bayestribo" / "demo"
    assert (out / "campaign-report.html").is_file() and str(out) in captured.out
    assert list(work.iterdir()) == []  # nothing in the current folder


def _drag(converged=True):
    """The drag series' campaign results, as its report writes them."""
    from bayestribo.synthetic.campaign import OIL_LAW

    mean = {"mean": 0.3371, "median": 0.3368, "interval": [0.3248, 0.3492]}
    sigma = {"mean": 0.018, "median": 0.0167, "interval": [0.0106, 0.0304]}
    return {
        "runs": {
            f"oil-N0.31-r{r}": {"law": OIL_LAW, "diagnostics": {"converged": converged}}
            for r in (1, 2, 3)
        },
        "failed": {},
        "population": {
            "pooled": {
                "n_runs": 3,
                "parameters": {p: {"mean": mean, "sigma": sigma} for p in ("zeta", "c2_SI")},
            }
        },
        "analysis": {
            "quantities": {
                "zeta": {"symbol": "ζ", "unit": "1"},
                "c2_SI": {"symbol": "c₂", "unit": "kg/m"},
            },
            "contact": {"groups": [], "pooled": None},
        },
    }


def test_full_demo_fits_the_drag_series_with_law_auto_and_prints_its_populations(
    tmp_path, monkeypatch, capsys
):
    calls = []
    monkeypatch.setattr(demo, "campaign_folder", lambda: (tmp_path, "bundled"))
    fake = _fake_reports(_single(), _campaign(), _drag(), calls)
    monkeypatch.setattr("bayestribo.reports.notebooks.run_report", fake)
    out = tmp_path / "out"
    assert main(["demo", "--full", "--out", str(out)]) == 0
    (params,) = [p for _, p in calls if p.get("series") == demo.DRAG_SERIES]
    assert params["fit_kwargs"] == {"law": "auto"} and params["fit_air"] is False
    assert params["water_series"] is None and params["data_dir"] == str(tmp_path)
    text = capsys.readouterr().out
    assert "oil series, law auto: each run's law viscous+coulomb+quadratic (3 runs)" in text
    line = next(line for line in text.splitlines() if "  mean" in line and "0.337" in line)
    assert "0.337 [0.325, 0.349]" in line  # the posterior median, as the report shows it
    assert "c₂ [kg/m]" in text and "0.35 (σ 0.0175)" in text  # beside the simulated values
    assert str(out / "oil-campaign-report.html") in text
    # the default demo leaves it out
    calls.clear()
    assert main(["demo", "--out", str(out)]) == 0
    assert [p.get("series") for _, p in calls if "series" in p] == []


def test_unconverged_names_the_drag_series_fits_and_samplers():
    assert demo.unconverged(_single(), _campaign(), _drag()) == []
    stuck = demo.unconverged(_single(), _campaign(), _drag(converged=False))
    assert stuck == [f"the fit of oil-N0.31-r{r}" for r in (1, 2, 3)]
    drag = _drag()
    drag["analysis"]["contact"]["groups"] = [
        {"label": "lubricant=oil,load_N=0.31", "diagnostics": {"converged": False}}
    ]
    assert demo.unconverged(_single(), _campaign(), drag) == [
        "the oil series: population contact lubricant=oil,load_N=0.31"
    ]


def test_help_names_the_default_output_folder(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert demo.default_out() == tmp_path / "bayestribo" / "demo"
    with pytest.raises(SystemExit):
        main(["demo", "--help"])
    assert "cache" in capsys.readouterr().out
