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
