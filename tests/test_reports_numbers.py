"""Every number of the campaign report is the campaign's, in the digits the rule gives.

Ten runs of the bundled campaign (glycerol at two loads; the glycerol–water series at
0.46 N at four water fractions, two repeats each) are fitted by ``bayestribo campaign``
with short samplers, then reported by ``bayestribo report`` of its results folder: one
campaign and one rendering for the whole module. Every table cell that is a value
with its interval must be a (median, interval) of the campaign's ``population.json``
written by the digit rule (:func:`bayestribo.summary.interval_text`); every probability
one of its trends' in three decimals or at its end; the glycerol–water series has its σ
between repeats, its forest plot and its μ_k against viscosity tested for a threshold;
the text names no temporary path and no command, and says why a run's numbers depend
on its seed.
"""

from __future__ import annotations

import html
import json
import re
import tempfile

import pytest
from _paths import RUNS
from _report_numbers import interval_cells, section, table_cells, unmatched

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli.main import main
from bayestribo.reports.tables import probability_text

#: The runs: glycerol at two loads (a trend against load), the glycerol–water series at
#: one load, four water fractions (a threshold against viscosity can be told from a line)
#: and two repeats each (a σ between repeats). The runs in air, ζ₀, ζ_k and d_k are
#: checked against their JSON by the loads report's own test (test_reports_notebooks).
RUN_IDS = [
    *(f"glycerol-N{n}-r1" for n in ("0.12", "0.46")),
    *(f"water{w}pc-N0.46-r{r}" for w in ("0.55", "3.00", "6.00", "9.00") for r in (1, 2)),
]


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    if not RUNS.is_dir():
        pytest.skip(f"the bundled runs are absent at {RUNS}")
    tmp = tmp_path_factory.mktemp("numbers")
    data, out = tmp / "data", tmp / "out"
    data.mkdir()
    for run_id in RUN_IDS:  # the bundled files, linked (not copied)
        for suffix in (".csv", ".json"):
            (data / f"{run_id}{suffix}").symlink_to(RUNS / f"{run_id}{suffix}")
    argv = ["campaign", str(data), "--out", str(out), "--max-steps", "1500"]
    argv += ["--grid-points", "32", "--population-steps", "600", "--workers", "1", "--quiet"]
    assert main(argv) in (0, 1)  # short population samplers may not converge
    html, summary = tmp / "report.html", tmp / "summary.json"
    argv = ["report", str(out), "--out", str(html), "--figure-format", "png"]
    assert main([*argv, "--param", f"summary_path={summary}"]) == 0
    page = html.read_text(encoding="utf-8")
    population = json.loads((out / "population.json").read_text())
    return page, population, tmp


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_every_interval_of_the_campaign_report_is_the_campaigns_in_its_digits(campaign):
    page, population, _ = campaign
    cells = interval_cells(page)
    assert len(cells) >= 30  # every run, group, trend and series is tabled
    # the trends' means at the ends of their loads and each run's ΔE at a shared swing
    # are tabled too, and checked with the others (population.json keeps them)
    for table in ("mean at ", "ΔE per cycle"):
        assert any(table in head for _, _, head in cells), table
    assert unmatched(page, population) == []


def test_every_probability_of_the_campaign_report_is_a_trends_in_three_decimals(campaign):
    page, population, _ = campaign
    known = {probability_text(t["prob_positive"]) for t in _trend_rows(population)}
    said = [t for t, column, _ in table_cells(page) if column == "P(slope > 0)" and t]
    prose = html.unescape(re.sub(r"<[^>]+>", " ", page))
    said += re.findall(r"P\(slope > 0\)(?: =|:) ((?:[<>] )?\d\.\d{3})", prose)
    assert len(said) >= 4 and set(said) <= known, set(said) - known
    assert not {"1.000", "0.000"} & set(said)


def _trend_rows(population):
    """Every trend of the campaign with its sign probability, whatever its nesting."""
    if isinstance(population, dict):
        if "prob_positive" in population:
            yield population
        for value in population.values():
            yield from _trend_rows(value)
    elif isinstance(population, list):
        for value in population:
            yield from _trend_rows(value)


def test_the_glycerol_water_series_has_sigma_a_forest_and_a_threshold_test(campaign):
    page, _, tmp = campaign
    water = section(page, "6. The glycerol")
    assert "σ between repeats" in water
    # μ_k against ν: the straight line compared with a threshold, and the comparison said
    assert "a threshold: constant above" in water or "the straight line fits" in water
    assert "straight line or threshold" in water
    figures = {p.name for p in (tmp / "report-figures").iterdir()}
    assert {"forest.png", "forest_water.png"} <= figures


def test_the_campaign_report_names_no_temporary_path_nor_command_and_speaks_of_seeds(campaign):
    page, _, tmp = campaign
    text = re.sub(r"<[^>]+>", " ", re.sub(r"<(style|script)\b.*?</\1>", "", page, flags=re.S))
    assert str(tmp) not in text and tempfile.gettempdir() + "/" not in text
    assert "bayestribo campaign" not in text and "bayestribo report" not in text
    assert not re.search(r"(?<![\w-])--[a-z]", text), re.findall(r".{40}--[a-z].{20}", text)
    assert "seed derived from the campaign seed" in text
