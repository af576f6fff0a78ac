"""``bayestribo campaign`` end to end on three bundled runs (real fits, short settings).

The fits use a low step ceiling (they need not converge: the test checks the pipeline,
the catalog's skipping and that a Dask cluster gives the same fits as the process
pool, not the posteriors; tests/test_population_groups.py checks those).
"""

from __future__ import annotations

import json
import os

import pytest
from _paths import RUNS

from bayestribo.cli import main

DATA = RUNS
RUNS = ("glycerol-N0.07-r1", "glycerol-N0.59-r1", "air-r1")
FAST = ["--max-steps", "400", "--population-steps", "400", "--quiet", "--json"]

pytestmark = [
    pytest.mark.slow,
    pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning"),
    pytest.mark.skipif(not DATA.is_dir(), reason="bundled data/ folder not present"),
]


@pytest.fixture(scope="module")
def campaign_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs")
    for name in RUNS:
        for suffix in (".csv", ".json"):
            os.symlink(DATA / f"{name}{suffix}", folder / f"{name}{suffix}")
    return folder


def _run(capsys, *argv):
    status = main(["campaign", *map(str, argv)])
    out = capsys.readouterr().out
    return status, json.loads(out)


def _per_run(report):
    return {r["run_id"]: (r.get("zeta"), r.get("mu_k")) for r in report["runs"]}


def test_campaign_fits_reports_and_skips_on_a_rerun(campaign_dir, tmp_path, capsys):
    out = tmp_path / "out"
    status, report = _run(capsys, campaign_dir, "--out", out, "--workers", 2, *FAST)
    assert report["failures"] == [] and report["excluded"] == [] and report["n_cached"] == 0
    # Short fits may not converge: the exit status says whether they all did.
    assert status == (0 if report["converged"] else 1)
    for name in ("population.json", "groups.csv", "trends.csv", "runs.csv", "catalog.sqlite"):
        assert (out / name).is_file(), name
    assert sorted(p.name for p in (out / "fits").iterdir()) == sorted(f"{n}.nc" for n in RUNS)
    assert sorted(p.name for p in (out / "figures").iterdir()) == [
        "forest.png",
        "means_vs_load.png",
        "zeta_k_d_k.png",
    ]
    assert report["zeta0"]["pooled"]["runs"] == ["air-r1"]
    assert [g["value"] for g in report["contact"]["groups"]] == [
        ["glycerol", 0.0055, 0.07],
        ["glycerol", 0.0055, 0.59],
    ]
    assert list(report["trends"]) == ["lubricant=glycerol,water_mass_fraction=0.0055"]
    # A re-run reads every fit back from the catalog.
    status, again = _run(capsys, campaign_dir, "--out", out, *FAST)
    assert status == (0 if again["converged"] else 1) and again["n_cached"] == 3
    assert _per_run(again) == _per_run(report)

    # The same campaign on a Dask cluster gives the same fits as the process pool.
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        status, on_dask = _run(
            capsys,
            campaign_dir,
            "--out",
            tmp_path / "dask",
            "--dask-scheduler",
            cluster.scheduler_address,
            *FAST,
        )
    assert status == (0 if on_dask["converged"] else 1) and on_dask["n_cached"] == 0
    assert _per_run(on_dask) == _per_run(report)


def test_a_campaign_lists_and_excludes_bad_runs_and_analyses_the_rest(tmp_path, capsys):
    import csv

    folder = tmp_path / "runs"
    folder.mkdir()
    good = "glycerol-N0.07-r1"
    for suffix in (".csv", ".json"):
        os.symlink(DATA / f"{good}{suffix}", folder / f"{good}{suffix}")
    # A run whose sidecar lacks the lubricant the other run is grouped by.
    other = "glycerol-N0.59-r1"
    os.symlink(DATA / f"{other}.csv", folder / f"{other}.csv")
    meta = json.loads((DATA / f"{other}.json").read_text())
    del meta["lubricant"]
    (folder / f"{other}.json").write_text(json.dumps(meta))
    # A run whose sidecar cannot be read.
    os.symlink(DATA / "air-r1.csv", folder / "air-r1.csv")
    (folder / "air-r1.json").write_text('{"load_N": 0.0, "mass_kg": ')
    out = tmp_path / "out"
    status, report = _run(capsys, folder, "--out", out, "--no-figures", "--workers", 1, *FAST)
    assert status == 1
    assert [f["run"] for f in report["failures"]] == ["air-r1"]
    assert "air-r1.json" in report["failures"][0]["error"]
    assert [e["run"] for e in report["excluded"]] == [other]
    assert "'lubricant'" in report["excluded"][0]["reason"]
    assert [g["runs"] for g in report["contact"]["groups"]] == [[good]]
    with open(out / "runs.csv", newline="") as f:
        status_by_run = {row["run_id"]: row["status"] for row in csv.DictReader(f)}
    assert status_by_run[good].startswith("used")
    assert status_by_run[other].startswith("excluded: metadata has no 'lubricant'")
    assert status_by_run["air-r1"].startswith("failed: RunFormatError")


def test_reading_options_apply_to_every_run_of_a_campaign(tmp_path, capsys):
    from bayestribo.io import read_run

    folder = tmp_path / "eu"
    folder.mkdir()
    name = "glycerol-N0.07-r1"
    run = read_run(DATA / f"{name}.csv")
    rows = [
        f"{t:.12g};{x:.12g};{v:.12g}".replace(".", ",")
        for t, x, v in zip(run.time, run.displacement, run.velocity, strict=True)
    ]
    (folder / f"{name}.csv").write_text("\n".join(["t;x;v", *rows]) + "\n", encoding="utf-8")
    # the sidecar without the record of the bundled file's bytes: this file is another
    sidecar = json.loads((DATA / f"{name}.json").read_text(encoding="utf-8"))
    sidecar.pop("data_file", None)
    (folder / f"{name}.json").write_text(json.dumps(sidecar), encoding="utf-8")
    reading = ["--delimiter", ";", "--decimal", ",", "--columns", "t", "x", "v"]
    status, report = _run(capsys, folder, "--out", tmp_path / "o", "--no-figures", *reading, *FAST)
    assert report["failures"] == [] and [r["run_id"] for r in report["runs"]] == [name]
    assert status == (0 if report["converged"] else 1)
    assert report["settings"]["fit"]["read_options"]["decimal"] == ","
    # Without the options the run cannot be read, and the campaign says why.
    assert main(["campaign", str(folder), "--out", str(tmp_path / "p"), "--quiet"]) == 2
    assert "could be fitted" in capsys.readouterr().err


def test_a_folder_without_runs_is_a_package_error(tmp_path, capsys):
    assert main(["campaign", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert "no run files" in capsys.readouterr().err
    assert main(["campaign", str(tmp_path / "missing")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_the_group_laws_are_a_table_and_text_naming_the_runs_that_differ(tmp_path, capsys):
    # The choice itself is tested in tests/test_campaign_group_laws.py; a campaign with
    # --law auto (a comparison of laws per run) is too slow for the default suite:
    # benchmarks/campaign_laws.py runs it.
    from bayestribo.campaign.laws import choose_group_law
    from bayestribo.cli.campaign import _law_lines, _law_rows

    def comparison(verdict: str) -> dict:
        rows = {"viscous": (100.0, 0.0), "viscous+quadratic": (100.5, 0.5)}
        table = {
            law: {"elpd_loo": e, "dse": d, "adequate": True, "sampled": True}
            for law, (e, d) in rows.items()
        }
        return {"verdict": verdict, "adequate": True, "table": table}

    group = choose_group_law(
        "lubricant=oil,load_N=0.3",
        {"r1": comparison("viscous"), "r2": comparison("viscous+quadratic")},
    )
    groups = {group.group: group.to_dict()}
    rows = _law_rows(groups)
    assert [(r["run"], r["verdict"], r["group_law"], r["agrees"]) for r in rows] == [
        ("r1", "viscous", "viscous", True),
        ("r2", "viscous+quadratic", "viscous", False),
    ]
    text = "\n".join(_law_lines(groups))
    assert "oil · 0.3 N: viscous" in text
    assert "r2 alone chose viscous+quadratic; fitted again in viscous" in text
    # --compare-laws is the joint choice, --law auto: with another law it is refused
    status = main(
        ["campaign", str(DATA), "--out", str(tmp_path), "--compare-laws", "--law", "viscous"]
    )
    assert status == 2
    assert "--compare-laws chooses the law of each group" in capsys.readouterr().err


def test_equal_names_in_sub_folders_are_two_runs_and_twin_files_are_named(tmp_path, capsys):
    """Runs are identified by their path in the campaign folder: a/run and b/run are two
    runs (own seeds, fit files and rows); two files of one identity are both left out,
    each with the reason, and the campaign goes on."""
    root = tmp_path / "campaign"
    sources = {"a/run": "glycerol-N0.07-r1", "b/run": "glycerol-N0.59-r1", "c/twin": "air-r1"}
    for identity, source in sources.items():
        target = root / f"{identity}.csv"
        target.parent.mkdir(parents=True, exist_ok=True)
        os.symlink(DATA / f"{source}.csv", target)
        metadata = json.loads((DATA / f"{source}.json").read_text())
        metadata["run_id"] = target.stem
        target.with_suffix(".json").write_text(json.dumps(metadata))
    os.symlink(DATA / "air-r1.csv", root / "c" / "twin.txt")
    out = tmp_path / "out"
    status, report = _run(capsys, root, "--out", out, "--workers", 1, *FAST)
    assert status == 1
    assert sorted(r["run_id"] for r in report["runs"]) == ["a/run", "b/run"]
    assert sorted(f["run"] for f in report["failures"]) == ["c/twin", "c/twin"]
    assert all("one run identity 'c/twin'" in f["error"] for f in report["failures"])
    assert sorted(p.relative_to(out / "fits").as_posix() for p in out.rglob("*.nc")) == [
        "a/run.nc",
        "b/run.nc",
    ]
    zeta = {r["run_id"]: r["zeta"]["median"] for r in report["runs"]}
    assert zeta["a/run"] != zeta["b/run"]
