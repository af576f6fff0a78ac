"""The answers of ``bayestribo campaign --watch``: each run's line, the live page and its
status, the JSON lines, and the options of a watch (no fit: these are the parts a watch
prints and writes; ``tests/test_campaign_watch.py`` runs whole watches)."""

from __future__ import annotations

import io
import json
import math

import pytest

from bayestribo.campaign.digest import FitDigest
from bayestribo.campaign.fitting import RunOutcome
from bayestribo.campaign.watch import CampaignWatch, WatchOptions
from bayestribo.campaign.watchpage import Answer, PageState, interval_text, render_page, status
from bayestribo.cli import main
from bayestribo.errors import BayestriboError

ZETA = {"symbol": "ζ", "unit": "1", "median": 0.0236, "low": 0.0231, "high": 0.0241}
C2 = {"symbol": "c₂", "unit": "kg/m", "median": 0.5, "low": 0.4, "high": 0.6}


def test_an_answer_line_names_the_run_its_law_and_its_intervals():
    answer = Answer(
        run="r1", path="r1.csv", law="viscous+quadratic", quantities={"zeta": ZETA, "c2": C2}
    )
    answer = Answer(**{**answer.__dict__, "fit_s": 1.25})
    assert answer.line() == (
        "r1  viscous+quadratic  ζ 0.0236 [0.0231, 0.0241]  c₂ 0.5 [0.4, 0.6] kg/m  (fit 1.25 s)"
    )
    cached = Answer(run="r1", path="r1.csv", law="viscous", quantities={"zeta": ZETA}, cached=True)
    assert cached.line().endswith("(from the catalog)")
    unconverged = Answer(run="r1", path="r1.csv", law="viscous", converged=False, fit_s=2.0)
    assert unconverged.line().endswith("(fit 2.00 s, NOT CONVERGED)")
    failed = Answer(run="bad", path="bad.csv", error="RunFormatError: no rows")
    assert failed.line() == "FAILED bad: RunFormatError: no rows"


def test_an_interval_has_the_digits_that_tell_its_ends_apart():
    assert interval_text(0.0236, 0.0231, 0.0241) == "0.0236 [0.0231, 0.0241]"
    # a run's interval is often 1e-4 of its median wide
    assert interval_text(0.0242506, 0.0242499, 0.0242513) == "0.0242506 [0.0242499, 0.0242513]"
    assert interval_text(1.0, 1.0, 1.0) == "1 [1, 1]"
    assert interval_text(math.nan, 0.1, 0.2) == "– [0.1, 0.2]"


def _state(**kwargs) -> PageState:
    answers = [
        Answer(run="a<1>", path="a.csv", law="viscous", quantities={"zeta": ZETA}, fit_s=1.0),
        Answer(run="bad", path="bad.csv", error="RunFormatError: <no rows>"),
    ]
    return PageState(folder="runs", state="watching", prob=0.95, answers=answers, **kwargs)


def test_the_page_reloads_only_while_the_watch_runs_and_escapes_what_it_shows():
    live = render_page(_state(waiting=["runs/c.csv"], fitting=["runs/b.csv"]), refresh_s=2.0)
    assert '<meta http-equiv="refresh" content="2">' in live
    assert "<script" not in live
    assert 'data-run="a&lt;1&gt;"' in live and "RunFormatError: &lt;no rows&gt;" in live
    assert "Fitting: runs/b.csv" in live and "Waiting for: runs/c.csv" in live
    assert "0.0236 [0.0231, 0.0241]" in live
    final = render_page(_state(), refresh_s=None)
    assert "http-equiv" not in final


def test_the_status_file_holds_each_answer_as_json():
    state = _state(fitting=["runs/b.csv"])
    loaded = json.loads(json.dumps(status(state)))
    assert [a["run"] for a in loaded["answers"]] == ["a<1>", "bad"]
    assert loaded["answers"][0]["quantities"]["zeta"] == ZETA
    assert loaded["answers"][1]["fit_s"] is None  # nan is no JSON number
    assert loaded["fitting"] == ["runs/b.csv"] and loaded["state"] == "watching"


def _digest() -> FitDigest:
    return FitDigest(
        run_name="r1",
        metadata={"run_id": "r1"},
        parameter_names=("zeta",),
        converged=True,
        at_prior_bound=[],
        prob=0.95,
        summaries={"zeta": {"median": 0.0236, "interval": (0.0231, 0.0241)}},
        draws={},
        log_prior={},
        law="viscous",
        quantities={"zeta": {"symbol": "ζ", "unit": "1"}},
    )


@pytest.mark.parametrize("json_lines", [False, True])
def test_each_answer_is_printed_once_as_it_lands(tmp_path, json_lines):
    stream = io.StringIO()
    watch = CampaignWatch(
        tmp_path / "runs",
        tmp_path / "out",
        tmp_path / "out" / "catalog.sqlite",
        spec=None,
        options=WatchOptions(),
        by=("load_N",),
        suffixes=[".csv"],
        stream=stream,
        json_lines=json_lines,
    )
    path = tmp_path / "runs" / "r1.csv"
    watch._answer(path, RunOutcome("r1", 1, _digest(), elapsed_s=1.5))
    watch._answer(path.with_name("r2.csv"), RunOutcome("r2", 2, error="RunFormatError: x"))
    lines = stream.getvalue().splitlines()
    if json_lines:
        first, second = map(json.loads, lines)
        assert first["run"] == "r1" and first["quantities"]["zeta"]["median"] == 0.0236
        assert first["fit_s"] == 1.5 and second["error"] == "RunFormatError: x"
    else:
        assert lines == [
            "r1  viscous  ζ 0.0236 [0.0231, 0.0241]  (fit 1.50 s)",
            "FAILED r2: RunFormatError: x",
        ]
    assert watch.n_answered == 2 and list(watch.digests) == [str(path)]


@pytest.mark.parametrize(
    "field, value",
    [("settle_s", 0.0), ("poll_s", -1.0), ("population_every_s", math.inf), ("max_runs", 0)],
)
def test_the_options_of_a_watch_are_checked(field, value):
    with pytest.raises(BayestriboError, match=field):
        WatchOptions(**{field: value})


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--settle", "1"], "--settle: options of --watch; add --watch"),
        (["--max-runs", "2", "--timeout", "5"], "--max-runs, --timeout: options of --watch"),
        (["--watch", "--refit"], "--refit: a watch fits every new run"),
        (["--watch", "--dask-scheduler", "tcp://x:1"], "--dask-scheduler: a watch fits"),
    ],
)
def test_the_watch_options_are_refused_where_they_mean_nothing(tmp_path, capsys, argv, message):
    assert main(["campaign", str(tmp_path), *argv]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["--settle", "0"], ["--max-runs", "-1"], ["--poll", "nan"]])
def test_a_bad_watch_option_is_an_argument_error(tmp_path, capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(["campaign", str(tmp_path), "--watch", *argv])
    assert exc.value.code == 2
    assert argv[0] in capsys.readouterr().err


def test_the_page_shows_the_populations_and_trends_with_their_labels():
    group = {
        "group": "lubricant=glycerol,load_N=0.31",
        "label": "glycerol · 0.31 N",
        "kind": "contact",
        "n_runs": 3,
        "parameter": "zeta",
        "symbol": "ζ",
        **{f"mean_{k}": v for k, v in (("median", 0.024), ("low", 0.022), ("high", 0.026))},
        **{f"sigma_{k}": v for k, v in (("median", 0.001), ("low", 0.0002), ("high", 0.004))},
    }
    trend = {
        "series": "lubricant=glycerol",
        "label": "glycerol",
        "covariate": "load_N",
        "parameter": "zeta",
        "symbol": "ζ",
        "slope_median": -0.012,
        "slope_low": -0.04,
        "slope_high": 0.02,
        "prob_positive": 0.1284,
        "n_runs": 6,
    }
    state = _state(
        populations=[group],
        trends=[trend],
        population_runs=3,
        report_command="bayestribo report out",
    )
    page = render_page(state, refresh_s=None)
    assert "<td>glycerol · 0.31 N (contact)</td><td>3</td><td>ζ</td>" in page
    assert "0.024 [0.022, 0.026]" in page and "0.001 [0.0002, 0.004]" in page
    assert "Computed from 3 fitted runs" in page
    assert "<td>glycerol</td><td>6</td><td>ζ</td>" in page
    assert "-0.012 [-0.04, 0.02]" in page and ">0.128<" in page
    assert "<code>bayestribo report out</code>" in page
    before = render_page(_state(), refresh_s=None)
    assert '<table id="populations">' not in before and "Not computed yet." in before


def test_the_page_waits_while_fits_keep_coming_and_not_once_the_queue_is_empty(tmp_path):
    watch = CampaignWatch(
        tmp_path / "runs",
        tmp_path / "out",
        tmp_path / "out" / "catalog.sqlite",
        spec=None,
        options=WatchOptions(page_every_s=3600.0),
        by=("load_N",),
        suffixes=[".csv"],
        stream=io.StringIO(),
    )
    (tmp_path / "out").mkdir()
    page = tmp_path / "out" / "watch.html"
    watch._queue.append(tmp_path / "runs" / "next.csv")  # a fit still to come
    watch._answer(tmp_path / "runs" / "r1.csv", RunOutcome("r1", 1, _digest(), elapsed_s=1.0))
    watch._refresh_page()  # the first page: at once
    assert 'data-run="r1"' in page.read_text(encoding="utf-8")
    watch._answer(tmp_path / "runs" / "r2.csv", RunOutcome("r2", 2, _digest(), elapsed_s=1.0))
    watch._refresh_page()  # within the interval, fits to come: later
    assert 'data-run="r2"' not in page.read_text(encoding="utf-8")
    watch._queue.clear()
    watch._refresh_page()  # the queue is empty: at once
    assert 'data-run="r2"' in page.read_text(encoding="utf-8")


def test_a_quantity_the_data_do_not_constrain_is_shown_as_its_bound():
    from bayestribo.campaign.watch import answer_of

    digest = _digest()
    digest.summaries["mu_s_ratio"] = {
        "median": 5.5,
        "interval": [1.0, 9.6],
        "kind": "bound",  # the fit's summary: flat from its prior's end up to 9.6
    }
    digest.quantities["mu_s_ratio"] = {"symbol": "μ_s/μ_k", "unit": "1"}
    answer = answer_of(RunOutcome("r1", 1, digest, elapsed_s=1.0), "r1.csv")
    assert answer.quantities["mu_s_ratio"]["bound"] is True
    assert answer.quantities["zeta"]["bound"] is False
    assert "μ_s/μ_k < 9.6 (not constrained by the data)" in answer.line()
    assert "ζ 0.0236 [0.0231, 0.0241]" in answer.line()
    page = render_page(
        PageState(folder="runs", state="watching", prob=0.95, answers=[answer]), refresh_s=2.0
    )
    assert "&lt; 9.6 (not constrained by the data)" in page and "5.5 [1, 9.6]" not in page
