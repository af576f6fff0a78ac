"""The campaign report reads back the results of `bayestribo campaign`."""

from __future__ import annotations

import copy
import json

import pytest

from bayestribo.campaign.catalog import CatalogError, record_fit, register_run
from bayestribo.campaign.results import (
    DEFAULT_SEED,
    compare_populations,
    find_campaign,
    is_campaign_folder,
    load_campaign,
)
from bayestribo.cli.main import build_parser

SETTINGS = {"seed": 7, "fit": {"grid_points": 32}}


def _fit_settings(seed: int, fit_kwargs: dict) -> dict:
    return {
        "fit_kwargs": fit_kwargs,
        "function": "bayestribo.inference.fit",
        "campaign_seed": seed,
        "seed": 123,
        "sidecar_sha256": None,
    }


@pytest.fixture
def campaign(tmp_path, monkeypatch):
    """A data folder of three runs and a campaign folder: one run fitted with the
    campaign's settings (twice: the latest counts), one only with other settings, one
    whose result file is gone."""
    data, out = tmp_path / "data", tmp_path / "results"
    data.mkdir()
    (out / "fits").mkdir(parents=True)
    catalog = out / "catalog.sqlite"
    for i, run_id in enumerate(("r1", "r2", "r3")):
        (data / f"{run_id}.csv").write_text(f"time_s,displacement_m\n0,{i}\n")
        register_run(
            catalog,
            path=data / f"{run_id}.csv",
            sha256=f"{i:064x}",
            metadata={"run_id": run_id, "load_N": 0.3},
        )
    for name, run_id, seed, kwargs in (
        ("old", "r1", 7, {"grid_points": 32}),
        ("new", "r1", 7, {"grid_points": 32}),
        ("other", "r2", 0, {}),
        ("gone", "r3", 7, {"grid_points": 32}),
    ):
        result = out / "fits" / f"{name}.nc"
        if name != "gone":
            result.write_text(name)
        record_fit(
            catalog,
            run=run_id,
            settings=_fit_settings(seed, kwargs),
            summary={"result_path": str(result)},
            diagnostics={},
        )
    report = {"by": ["load_N"], "prob": 0.9, "settings": SETTINGS, "catalog": str(catalog)}
    (out / "population.json").write_text(json.dumps(report))
    monkeypatch.setattr(
        "bayestribo.inference.FitResult.load", classmethod(lambda cls, p: open(p).read())
    )
    return data, out


def test_the_fits_made_with_the_campaigns_settings_are_read_back(campaign):
    data, out = campaign
    results = load_campaign(out)
    assert results.seed == 7 and results.fit_kwargs == {"grid_points": 32}
    assert results.by == ("load_N",) and results.prob == 0.9
    assert results.fits == {"r1": "new"}  # the latest fit with the campaign's settings
    assert set(results.missing) == {"r2", "r3"}
    assert "gone" in results.missing["r3"] and "settings" in results.missing["r2"]
    assert results.paths["r2"] == (data / "r2.csv").resolve()


def test_a_campaign_is_found_for_its_data_folder(campaign, tmp_path, monkeypatch):
    data, out = campaign
    assert is_campaign_folder(out) and not is_campaign_folder(data)
    assert find_campaign(out) == out  # the results folder itself
    assert find_campaign(data, search=[out]) == out
    assert find_campaign(tmp_path / "elsewhere", search=[out]) is None  # runs not under it
    monkeypatch.chdir(tmp_path)
    assert find_campaign(data) is None  # not in the default places
    out.rename(tmp_path / "bayestribo-campaign")
    assert find_campaign(data) == tmp_path / "bayestribo-campaign"


def test_a_folder_without_results_is_refused(tmp_path):
    with pytest.raises(CatalogError, match=r"campaign_dir: .* holds no campaign results"):
        load_campaign(tmp_path)


def test_the_default_seed_is_the_campaigns():
    args = build_parser().parse_args(["campaign", "somewhere"])
    assert args.seed == DEFAULT_SEED


def test_populations_are_compared_group_by_group():
    group = {
        "label": "load_N=0.3",
        "parameters": {
            "zeta": {
                "mean": {"median": 0.02, "interval": [0.01, 0.03]},
                "sigma": {"median": 0.001, "interval": [0.0, 0.002]},
            }
        },
    }
    report = {"contact": {"groups": [group], "pooled": None}, "zeta0": None, "series": None}
    assert compare_populations(report, copy.deepcopy(report)) == []
    other = copy.deepcopy(report)
    other["contact"]["groups"][0]["parameters"]["zeta"]["mean"]["median"] = 0.021
    [line] = compare_populations(report, other)
    assert "load_N=0.3 zeta mean" in line
