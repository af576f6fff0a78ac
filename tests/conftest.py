"""Shared fixtures: the bundled runs and the real recordings in ../shared/external-data.

A test that needs the real recordings asks for ``appstat`` (the folder) or calls
``appstat_file(name)``. Where the folder is absent the test is skipped with the reason
(shown by ``pytest -ra``, the default here); where it is present every real-data test
runs.

The report tests share one rendering of each report kind (``single_run_report``,
``loads_report``, ``real_data_report``, ``viscosity_report``, ``acquisition_report``:
``bayestribo report`` run once per session, ``_renderings.py``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest
from _hostile_names import HOSTILE_FIELD, HOSTILE_FILE_WORD, HOSTILE_SCRIPT, hostile_copy
from _paths import APPSTAT, DATA, RUNS
from _renderings import ACQUISITION_SETTINGS, Rendering, render

from bayestribo import Run, read_run

# The suite's own workers (pytest -n) use the cores: a comparison in a test compiles its
# laws itself rather than in more processes of its own, which tests with stand-in fits
# would start for laws they never use (tests/test_model_laws_ahead.py sets its own).
os.environ.setdefault("BAYESTRIBO_COMPILE_WORKERS", "0")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object | None:
    """With ``-n`` and ``--dist loadgroup`` (pyproject.toml): the tests of one
    ``xdist_group`` on one worker (the report tests sharing the renderings of
    ``_renderings.py``: each made once), and each other module's tests on one worker, as
    ``--dist loadscope`` sends them (a module's fixtures made once)."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    class GroupOrModule(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            group = super()._split_scope(nodeid)
            return group if group != nodeid else nodeid.split("::", 1)[0]

    return GroupOrModule(config, log)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The tests of the renderings' ``xdist_group`` first: the longest unit of work
    starts on one worker while the other takes the modules one by one, so that neither
    waits for it at the end (longest first, as a scheduler of unequal jobs should)."""
    from _renderings import GROUP

    def first(item: pytest.Item) -> bool:
        return any(m.args == (GROUP,) for m in item.iter_markers("xdist_group"))

    items[:] = [i for i in items if first(i)] + [i for i in items if not first(i)]


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


def _needs_jupyter() -> None:
    pytest.importorskip("nbclient")
    pytest.importorskip("nbconvert")


# -- one rendering per report kind (tests/_renderings.py), shared by the notebook, browser
# -- and page tests: the modules using them are one xdist_group (GROUP)


@pytest.fixture(scope="session")
def single_run_report(tmp_path_factory: pytest.TempPathFactory) -> Rendering:
    """The single-run report (``bayestribo report RUN``) of the bundled glycerol run at
    0.31 N, from a copy whose file name (the run's label) and sidecar's notes hold markup:
    ``glycerol <svg onload=...>-r1.csv``; 32 Π increments, figures as PDF (the command's
    default), its summary JSON beside it."""
    _needs_jupyter()
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
    made = render(folder, "single", run, {"grid_points": 32}, figure_format="pdf")
    assert made.status == 0
    return made


@pytest.fixture(scope="session")
def viscosity_report(tmp_path_factory: pytest.TempPathFactory) -> Rendering:
    """The report against viscosity (``--notebook viscosity``) of two bundled glycerol-water
    runs at 0.46 N (0.55 and 9 % water), from copies whose file names, series and sidecars'
    notes hold markup."""
    _needs_jupyter()
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
    params = {"series": HOSTILE_SCRIPT, "loads": [0.46], "population_steps": 600}
    params.update(fit_kwargs={"grid_points": 32}, max_workers=2)
    return render(folder, "viscosity", folder, params, notebook="viscosity")


@pytest.fixture(scope="session")
def acquisition_report(tmp_path_factory: pytest.TempPathFactory) -> Rendering:
    """The simulated instrument's report (``--notebook acquisition``): 0.6 s recorded,
    fitted with :data:`ACQUISITION_SETTINGS`, its summary JSON beside it."""
    _needs_jupyter()
    pytest.importorskip("bayestribo.acquisition")
    folder = tmp_path_factory.mktemp("acquisition")
    params = {"duration_s": 0.6, "out_dir": str(folder / "acq")}
    made = render(
        folder, "acquisition", None, params, notebook="acquisition", options=ACQUISITION_SETTINGS
    )
    assert made.status == 0
    return made


@pytest.fixture(scope="session")
def loads_report(tmp_path_factory: pytest.TempPathFactory) -> Rendering:
    """The campaign report (``bayestribo report data/ --refit``) of the bundled campaign:
    glycerol at three loads (a slope is inferred) and one run in air, repeat 1, and two
    runs of the glycerol-water series (section 6); 32 Π increments, populations sampled
    600 steps, figures as SVG."""
    _needs_jupyter()
    if not RUNS.is_dir():
        _missing("the bundled runs", RUNS)
    folder = tmp_path_factory.mktemp("loads")
    params = {"loads": [0.12, 0.31, 0.59], "repeats": [1], "air_repeats": [1]}
    params.update(water_fractions=[0.0055, 0.09], fit_kwargs={"grid_points": 32})
    params.update(population_steps=600, max_workers=2)
    return render(folder, "loads", DATA, params, figure_format="svg", options=("--refit",))


@pytest.fixture(scope="session")
def real_data_report(tmp_path_factory: pytest.TempPathFactory, appstat: Path) -> Rendering:
    """The real-data report (``--notebook real_data``) of the AppStat2020 recordings: all
    three read, HarmOsc3 fitted (24 Π increments), HarmOsc2's adequacy checked."""
    _needs_jupyter()
    folder = tmp_path_factory.mktemp("real")
    params = {"fit_files": ["HarmOsc3.txt"], "fit_kwargs": {"grid_points": 24}}
    params["check_files"] = ["HarmOsc2.txt"]
    return render(folder, "real", appstat, params, notebook="real_data")
