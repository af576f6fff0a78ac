"""fit_many: per-run seeds by identity, any executor, failures reported, progress.

A cheap stand-in replaces the Bayesian fit: it draws from its seed, so equal results
across executors mean equal seeds per run.
"""

from __future__ import annotations

import io
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bayestribo.campaign.fitting import RunOutcome, fit_many, run_identity, run_seed
from bayestribo.errors import BayestriboError, RecordingError


@dataclass(frozen=True)
class FakeRun:
    metadata: dict[str, Any] = field(default_factory=dict)


def cheap_fit(run: Any, *, seed: int, scale: float = 1.0) -> dict[str, Any]:
    """Stand-in fit: a few draws from the run's seed; fails on runs named 'bad*'."""
    name = run_identity(run)
    if name.startswith("bad"):
        raise RecordingError("no oscillation found", where=name)
    return {"name": name, "draws": (scale * np.random.default_rng(seed).normal(size=4)).tolist()}


RUNS = [FakeRun({"run_id": f"glycerol-L{i}-r{r}"}) for i in range(3) for r in range(2)]


def _by_name(outcomes: list[RunOutcome]) -> dict[str, Any]:
    return {o.name: (o.seed, o.result, o.error) for o in outcomes}


@pytest.fixture(scope="module")
def serial():
    with ThreadPoolExecutor(1) as pool:
        return fit_many(RUNS, pool, campaign_seed=7, function=cheap_fit, progress=False)


def test_results_do_not_depend_on_executor_workers_or_order(serial):
    assert [o.name for o in serial] == [r.metadata["run_id"] for r in RUNS]
    assert all(o.ok for o in serial)
    with ThreadPoolExecutor(4) as pool:
        threads = fit_many(RUNS[::-1], pool, campaign_seed=7, function=cheap_fit, progress=False)
    processes = fit_many(
        RUNS, campaign_seed=7, function=cheap_fit, max_workers=2, progress=False
    )  # the default executor: a process pool
    assert _by_name(threads) == _by_name(serial) == _by_name(processes)
    assert [o.name for o in threads] == [r.metadata["run_id"] for r in RUNS[::-1]]


def test_seeds_follow_the_campaign_seed_and_the_identity(serial):
    seeds = [o.seed for o in serial]
    assert len(set(seeds)) == len(seeds)
    assert all(0 <= s < 2**63 for s in seeds)
    assert seeds == [run_seed(7, o.name) for o in serial]
    assert run_seed(8, serial[0].name) != seeds[0]
    # A run keeps its seed when other runs are added or removed.
    with ThreadPoolExecutor(2) as pool:
        one = fit_many(RUNS[2:3], pool, campaign_seed=7, function=cheap_fit, progress=False)
    assert one[0].seed == seeds[2] and one[0].result == serial[2].result


def test_a_failed_run_is_reported_and_the_others_go_on(tmp_path):
    runs = [*RUNS[:2], FakeRun({"run_id": "bad-r1"}), tmp_path / "glycerol-L9-r1.csv"]
    stream = io.StringIO()
    seen: list[str] = []
    outcomes = fit_many(
        runs,
        campaign_seed=3,
        function=cheap_fit,
        max_workers=2,
        progress_stream=stream,
        callback=lambda o: seen.append(o.name),
        scale=2.0,
    )
    assert [o.ok for o in outcomes] == [True, True, False, True]
    bad = outcomes[2]
    assert bad.result is None and bad.error == "RecordingError: bad-r1: no oscillation found"
    assert "Traceback" in bad.traceback and "cheap_fit" in bad.traceback
    assert outcomes[3].name == "glycerol-L9-r1"  # a path's identity is its file stem
    assert sorted(seen) == sorted(o.name for o in outcomes)
    # fit keyword arguments reach the function.
    expected = 2.0 * np.random.default_rng(outcomes[0].seed).normal(size=4)
    np.testing.assert_array_equal(outcomes[0].result["draws"], expected)
    text = stream.getvalue()
    assert "4/4" in text and "1 failed" in text and text.endswith("\n")


def test_no_progress_output_when_disabled():
    stream = io.StringIO()
    with ThreadPoolExecutor(1) as pool:
        fit_many(RUNS[:1], pool, function=cheap_fit, progress=False, progress_stream=stream)
    assert stream.getvalue() == ""


def test_bad_input_is_a_package_error():
    with pytest.raises(BayestriboError, match="duplicate run identities"):
        fit_many([RUNS[0], RUNS[0]], function=cheap_fit, progress=False)
    with pytest.raises(BayestriboError, match="without metadata 'run_id'"):
        fit_many([FakeRun({})], function=cheap_fit, progress=False)
    with pytest.raises(BayestriboError, match="campaign_seed"):
        fit_many(RUNS, campaign_seed=-1, function=cheap_fit, progress=False)


def test_dask_cluster_gives_the_same_results_as_the_process_pool(serial):
    distributed = pytest.importorskip("dask.distributed", reason="dask.distributed not installed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert len(client.scheduler_info()["workers"]) == 2
        outcomes = fit_many(
            RUNS, client.get_executor(), campaign_seed=7, function=cheap_fit, progress=False
        )
    processes = fit_many(RUNS, campaign_seed=7, function=cheap_fit, max_workers=2, progress=False)
    assert _by_name(outcomes) == _by_name(processes) == _by_name(serial)


@dataclass
class SavedFit:
    """Stand-in fit result with what fit_catalogued needs."""

    name: str
    draws: list[float]
    converged: bool = True
    diagnostics: dict[str, Any] = field(default_factory=lambda: {"autocorr_time_max": np.inf})

    def summary(self) -> dict[str, Any]:
        return {"zeta": {"mean": float(np.mean(self.draws))}}

    def save(self, path) -> None:
        import json

        Path(path).write_text(json.dumps({"name": self.name, "draws": self.draws}))


def load_saved(path: str) -> SavedFit:
    import json

    return SavedFit(**json.loads(Path(path).read_text()))


def saved_fit(run: Any, *, seed: int, scale: float = 1.0) -> SavedFit:
    out = cheap_fit(run, seed=seed, scale=scale)
    return SavedFit(out["name"], out["draws"])


def _write_run_files(folder: Path, names: list[str]) -> list[Path]:
    import json

    paths = []
    for i, name in enumerate(names):
        csv = folder / f"{name}.csv"
        csv.write_text(f"time_s,displacement_m\n0,{i + 1}e-6\n")  # distinct contents
        (folder / f"{name}.json").write_text(json.dumps({"run_id": name, "load_N": 0.12}))
        paths.append(csv)
    return paths


def test_fit_catalogued_records_fits_and_skips_them_on_a_rerun(tmp_path):
    from bayestribo.campaign.catalog import find_fit, list_fits, list_runs
    from bayestribo.campaign.fitting import fit_catalogued

    paths = _write_run_files(tmp_path, ["a-r1", "a-r2", "bad-r3"])
    db, out = tmp_path / "cat.sqlite", tmp_path / "fits"
    kwargs = {"function": saved_fit, "loader": load_saved, "progress": False, "scale": 2.0}
    with ThreadPoolExecutor(2) as pool:
        first = fit_catalogued(paths, db, out, pool, campaign_seed=4, **kwargs)
    assert [(o.ok, o.cached) for o in first] == [(True, False), (True, False), (False, False)]
    assert [r.run_id for r in list_runs(db)] == ["a-r1", "a-r2", "bad-r3"]
    fits = list_fits(db)
    assert len(fits) == 2 and all(f.summary["converged"] for f in fits)
    assert fits[0].diagnostics["autocorr_time_max"] == np.inf
    assert Path(fits[0].summary["result_path"]).parent == out.resolve()
    # Re-run: the two fitted runs are read back; the failed one is tried again.
    with ThreadPoolExecutor(2) as pool:
        again = fit_catalogued(paths, db, out, pool, campaign_seed=4, **kwargs)
    assert [(o.ok, o.cached) for o in again] == [(True, True), (True, True), (False, False)]
    assert again[0].result == first[0].result and again[0].seed == first[0].seed
    assert len(list_fits(db)) == 2
    # Other settings (campaign seed, fit keyword arguments) are fitted anew.
    with ThreadPoolExecutor(2) as pool:
        other = fit_catalogued(paths[:1], db, out, pool, campaign_seed=5, **kwargs)
    assert not other[0].cached and other[0].result != first[0].result
    settings = {
        "fit_kwargs": {"scale": 2.0},
        "function": f"{__name__}.saved_fit",
        "campaign_seed": 4,
        "seed": run_seed(4, "a-r2"),
        "sidecar_sha256": __import__("hashlib")
        .sha256(paths[1].with_suffix(".json").read_bytes())
        .hexdigest(),
    }
    assert find_fit(db, run="a-r2", settings=settings) is not None
    assert find_fit(db, run="a-r2", settings={**settings, "seed": 1}) is None
    assert find_fit(db, run="nope", settings=settings) is None


def test_fit_records_are_refused_for_unknown_runs_and_non_json(tmp_path):
    from bayestribo.campaign.catalog import CatalogError, record_fit, register_run

    db = tmp_path / "c.sqlite"
    with pytest.raises(CatalogError, match="not registered"):
        record_fit(db, run="r1", settings={}, summary={}, diagnostics={})
    register_run(db, path="x.csv", sha256="a" * 64, metadata={"run_id": "r1"})
    with pytest.raises(CatalogError, match="settings: not JSON"):
        record_fit(db, run="r1", settings={"x": object()}, summary={}, diagnostics={})
    with pytest.raises(CatalogError, match="summary: not JSON"):
        record_fit(db, run=1, settings={}, summary={"x": object()}, diagnostics={})


def test_a_saved_fit_that_cannot_be_read_is_fitted_again(tmp_path, capsys):
    """A truncated result file (a kill, a full disk, another writer) is a cache miss:
    the run is fitted again and the campaign goes on, saying so."""
    from bayestribo.campaign.fitting import fit_catalogued

    paths = _write_run_files(tmp_path, ["a-r1", "a-r2"])
    db, out = tmp_path / "cat.sqlite", tmp_path / "fits"
    kwargs = {"function": saved_fit, "loader": load_saved, "progress": True}
    first = fit_catalogued(paths, db, out, None, campaign_seed=4, **kwargs)
    saved = out / "a-r1.nc"
    saved.write_text(saved.read_text()[:5])  # truncated
    again = fit_catalogued(paths, db, out, None, campaign_seed=4, **kwargs)
    assert [(o.ok, o.cached) for o in again] == [(True, False), (True, True)]
    assert again[0].result == first[0].result
    assert "the saved fit of a-r1 cannot be read" in capsys.readouterr().err
    assert not [p for p in out.iterdir() if ".tmp" in p.name]


def test_a_fit_saved_over_by_other_settings_is_never_read_for_the_first(tmp_path, capsys):
    """Two campaigns with other settings in one output folder write the same run's file:
    the catalog's record of the first settings then points at the second's fit. Its
    checksum tells them apart: the first settings' run is fitted again, never answered
    with the other fit."""
    from bayestribo.campaign.fitting import fit_catalogued

    paths = _write_run_files(tmp_path, ["a-r1"])
    db, out = tmp_path / "cat.sqlite", tmp_path / "fits"
    kwargs = {"function": saved_fit, "loader": load_saved, "progress": True}
    one = fit_catalogued(paths, db, out, None, campaign_seed=4, scale=1.0, **kwargs)
    two = fit_catalogued(paths, db, out, None, campaign_seed=4, scale=2.0, **kwargs)
    assert one[0].result != two[0].result
    again = fit_catalogued(paths, db, out, None, campaign_seed=4, scale=1.0, **kwargs)
    assert not again[0].cached and again[0].result == one[0].result
    assert "cannot be read as recorded" in capsys.readouterr().err
    # the same settings twice in a row: a cache hit, as before
    last = fit_catalogued(paths, db, out, None, campaign_seed=4, scale=1.0, **kwargs)
    assert last[0].cached and last[0].result == one[0].result


class _Whole:
    """A stand-in fit result that can be watched with a weak reference."""

    def __init__(self, name: str) -> None:
        self.name = name


def _fit_digested(function: Any, **hooks: Any) -> list[RunOutcome]:
    """``fit_many`` of RUNS on one thread, each result kept as ``digest of <name>``."""
    with ThreadPoolExecutor(1) as pool:
        return fit_many(
            RUNS,
            pool,
            function=function,
            progress=False,
            keep=lambda result: f"digest of {result.name}",
            **hooks,
        )


def test_fit_many_holds_only_what_keep_returns_while_it_runs():
    """A campaign's memory does not grow with its runs: once a result has been seen by
    the callback and digested, nothing in fit_many holds it any more."""
    import gc
    import weakref

    refs: dict[str, weakref.ref] = {}
    handled: list[str] = []
    alive_at_callbacks: list[list[str]] = []

    def whole_fit(run: Any, *, seed: int) -> _Whole:
        result = _Whole(run_identity(run))
        refs[result.name] = weakref.ref(result)
        return result

    def callback(outcome: RunOutcome) -> None:
        gc.collect()
        alive_at_callbacks.append([name for name in handled if refs[name]() is not None])
        handled.append(outcome.name)

    outcomes = _fit_digested(whole_fit, callback=callback)
    assert [o.result for o in outcomes] == [f"digest of {run_identity(r)}" for r in RUNS]
    # no result handled before is alive when the next one arrives
    assert alive_at_callbacks == [[]] * len(RUNS), alive_at_callbacks


def test_run_identities_are_stems_unless_they_clash(tmp_path):
    from bayestribo.campaign.fitting import run_identities

    paths = [
        tmp_path / "runs" / "glycerol-N0.31-r1.csv",
        tmp_path / "a" / "run1.csv",
        tmp_path / "b" / "run1.tdms",
        tmp_path / "c" / "twin.csv",
        tmp_path / "c" / "twin.txt",
    ]
    assert run_identities(paths, tmp_path) == [
        "glycerol-N0.31-r1",  # unique: the stem, whatever the sub-folder
        "a/run1",
        "b/run1",
        "c/twin",  # one path, two suffixes: one identity (both left out by a campaign)
        "c/twin",
    ]
    with pytest.raises(BayestriboError, match="is not in the campaign folder"):
        run_identities([tmp_path / "x.csv", Path("/elsewhere/x.csv")], tmp_path)


class _Named:
    """A fit result's face as the campaign sees it: metadata and attributes."""

    def __init__(self, path: str, run_id: str | None) -> None:
        self.metadata = {} if run_id is None else {"run_id": run_id}
        self.attrs = {"run_name": path}


def _named_fit(run, *, seed):
    return _Named(str(run), None if "with-id" not in str(run) else "given-id")


def test_a_fit_whose_run_has_no_run_id_is_named_by_its_identity(tmp_path):
    # Named by its file's path, the fit was not found among the runs of its identity
    # (the report's ΔE(A) panels came out empty); a run_id of its own is kept.
    from concurrent.futures import ThreadPoolExecutor

    from bayestribo.campaign.fitting import fit_many

    paths = [tmp_path / "a" / "run7.csv", tmp_path / "with-id.csv"]
    with ThreadPoolExecutor(1) as pool:
        outcomes = fit_many(paths, pool, function=_named_fit, progress=False)
    assert [o.name for o in outcomes] == ["run7", "with-id"]
    assert outcomes[0].result.attrs["run_name"] == "run7"
    assert outcomes[1].result.attrs["run_name"] == str(paths[1])


def test_each_outcome_is_announced_as_kept_before_it_is_recorded():
    """``announce`` sees each outcome with its result as ``keep`` keeps it, before the
    callback sees the whole result (a watch prints the answer, then saves the fit)."""
    events: list[tuple[str, str, object]] = []

    def whole_fit(run: Any, *, seed: int) -> _Whole:
        return _Whole(run_identity(run))

    outcomes = _fit_digested(
        whole_fit,
        announce=lambda o: events.append(("announce", o.name, o.result)),
        callback=lambda o: events.append(("callback", o.name, o.result)),
    )
    names = [run_identity(r) for r in RUNS]
    for name, outcome in zip(names, outcomes, strict=True):
        mine = [(what, result) for what, n, result in events if n == name]
        assert [what for what, _ in mine] == ["announce", "callback"]
        assert mine[0][1] == f"digest of {name}" == outcome.result
        assert isinstance(mine[1][1], _Whole) and mine[1][1].name == name
