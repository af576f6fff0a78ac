"""Shared fixtures: the bundled runs and the real recordings in ../shared/external-data.

A test that needs the real recordings asks for ``appstat`` (the folder) or calls
``appstat_file(name)``. Where the folder is absent the test is skipped with the reason
(shown by ``pytest -ra``, the default here); where it is present every real-data test
runs.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from _hostile_names import HOSTILE_FIELD, HOSTILE_FILE_WORD, HOSTILE_SCRIPT, hostile_copy
from _paths import APPSTAT, RUNS

from bayestribo import Run, read_run


def _missing(what: str, path: Path) -> None:
    pytest.skip(f"{what} not found at {path}")


@pytest.fixture(scope="session")
def appstat() -> Path:
    """The AppStat2020 harmonic-oscillator folder (skips where it is absent)."""
    if not APPSTAT.is_dir():
        _missing("the AppStat2020 recordings", APPSTAT)
    return APPSTAT


@pytest.fixture(scope="session")
def appstat_file(appstat: Path) -> Callable[[str], Path]:
    """``appstat_file("HarmOsc3.txt")``: the path of one AppStat2020 recording."""

    def find(name: str) -> Path:
        path = appstat / name
        if not path.is_file():
            _missing(f"the recording {name}", path)
        return path

    return find


@pytest.fixture(scope="session")
def bundled_runs() -> Path:
    """The folder of the bundled simulated runs (``data/runs``)."""
    if not RUNS.is_dir():
        _missing("the bundled runs", RUNS)
    return RUNS


@pytest.fixture(scope="session")
def bundled_run(bundled_runs: Path) -> Run:
    """The bundled glycerol run at 0.31 N (repeat 1), read."""
    return read_run(bundled_runs / "glycerol-N0.31-r1.csv")


@pytest.fixture(scope="session")
def short_fit(tmp_path_factory: pytest.TempPathFactory):
    """A converged fit of a short simulated 2 kHz run (a few seconds), read back from its
    NetCDF file, as the command line and a later session see it; shared by the tests of
    the result and of its figures."""
    from bayestribo.inference import FitResult, fit
    from bayestribo.synthetic import Sensor
    from bayestribo.synthetic.recording import simulate

    run = simulate(sensor=Sensor(sample_rate_Hz=2000.0), seed=11)
    path = tmp_path_factory.mktemp("fit") / "run.nc"
    fit(run, seed=3).save(path)
    return FitResult.load(path)


@pytest.fixture(scope="session")
def single_run_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The single-run report (``bayestribo report RUN``) of the bundled glycerol run at
    0.31 N, made once for every test that reads it, from a copy whose file name (the
    run's label) and sidecar's notes hold markup: ``glycerol <svg onload=...>-r1.csv``."""
    pytest.importorskip("nbclient")
    pytest.importorskip("nbconvert")
    from bayestribo.cli import main

    source = RUNS / "glycerol-N0.31-r1.csv"
    if not source.is_file():
        _missing("the bundled run", source)
    folder = tmp_path_factory.mktemp("report")
    run = hostile_copy(
        source,
        folder,
        f"glycerol {HOSTILE_FILE_WORD}-r1",
        run_id=None,  # the run's label is its file's name (a sidecar's run_id is checked)
        notes=HOSTILE_FIELD,
        user={"operator": HOSTILE_SCRIPT},
    )
    out = folder / "single.html"
    assert main(["report", str(run), "--out", str(out), "--param", "grid_points=32"]) == 0
    return out


@pytest.fixture(scope="session")
def viscosity_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The report against viscosity (``--notebook viscosity``) of two bundled glycerol-water
    runs at 0.46 N (0.55 and 9 % water), made once, from copies whose file names, series
    and sidecars' notes hold markup."""
    pytest.importorskip("nbclient")
    pytest.importorskip("nbconvert")
    from bayestribo.cli import main

    folder = tmp_path_factory.mktemp("viscosity")
    for water in ("0.55", "9.00"):
        source = RUNS / f"water{water}pc-N0.46-r1.csv"
        if not source.is_file():
            _missing("the bundled run", source)
        hostile_copy(
            source,
            folder,
            f"water{water}pc {HOSTILE_FILE_WORD}-r1",
            run_id=None,
            series=HOSTILE_SCRIPT,
            notes=HOSTILE_FIELD,
        )
    out = folder / "viscosity.html"
    argv = ["report", str(folder), "--notebook", "viscosity", "--out", str(out)]
    argv += ["--param", f"series={HOSTILE_SCRIPT!r}", "--param", "loads=[0.46]"]
    argv += ["--param", "population_steps=600", "--param", "fit_kwargs={'grid_points': 32}"]
    main(argv)
    return out


@pytest.fixture(scope="session")
def acquisition_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The simulated instrument's report (``--notebook acquisition``), made once."""
    pytest.importorskip("nbclient")
    pytest.importorskip("nbconvert")
    pytest.importorskip("bayestribo.acquisition")
    from bayestribo.cli import main

    folder = tmp_path_factory.mktemp("acquisition")
    out = folder / "acquisition.html"
    argv = ["report", "--notebook", "acquisition", "--out", str(out)]
    argv += ["--param", "duration_s=0.6", "--param", f"out_dir={str(folder / 'acq')!r}"]
    main(argv)
    return out
