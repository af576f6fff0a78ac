"""The report notebooks: committed clean, parameters injected, every notebook executed.

Each notebook runs with nbclient (kernel python3) on short test parameters (a few fits
at most) and must finish without an error output; its HTML rendering must embed its
figures. A notebook whose data or modules are absent is skipped with the reason.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path

import pytest
from _paths import APPSTAT, REPO

nbformat = pytest.importorskip("nbformat")
pytest.importorskip("nbclient")

from bayestribo.errors import MissingDependencyError  # noqa: E402
from bayestribo.reports.notebooks import (  # noqa: E402
    NOTEBOOKS,
    PARAMETERS_TAG,
    ReportError,
    execute_notebook,
    has_outputs,
    inject_parameters,
    notebook_parameters,
    notebook_path,
    read_notebook,
    run_report,
    to_html,
)

EXTERNAL = APPSTAT

#: Modules each notebook imports beyond the core (skip with a reason when absent).
REQUIRES = {
    "single_run": ["bayestribo.inference.plots", "bayestribo.adequacy", "corner"],
    "loads": ["bayestribo.campaign.fitting", "bayestribo.population"],
    "viscosity": ["bayestribo.campaign.fitting", "bayestribo.population"],
    "real_data": ["bayestribo.adequacy"],
    "acquisition": ["bayestribo.acquisition", "bayestribo.inference.plots"],
}


def _test_parameters(name: str, tmp: Path) -> dict:
    """Short runs: one to three fits per notebook, small samplers where it matters."""
    common = {"figure_dir": str(tmp / "figures")}
    if name == "single_run":
        return {**common, "grid_points": 32, "summary_path": str(tmp / "summary.json")}
    if name == "loads":
        return {
            **common,
            "loads": [0.12, 0.31, 0.59],  # three loads: the slope is inferred
            "repeats": [1],
            "air_repeats": [1],
            "fit_kwargs": {"grid_points": 32},
            "population_steps": 600,
            "max_workers": 2,
            "summary_path": str(tmp / "summary.json"),
        }
    if name == "viscosity":
        return {
            **common,
            "loads": [0.46],
            "water_fractions": [0.0055, 0.09],
            "repeats": [1],
            "population_steps": 600,
            "max_workers": 2,
            "summary_path": str(tmp / "summary.json"),
        }
    if name == "real_data":
        return {
            **common,
            "data_dir": str(EXTERNAL),
            "fit_files": ["HarmOsc3.txt"],
            "fit_kwargs": {"grid_points": 24},
            "check_files": ["HarmOsc2.txt"],
            "summary_path": str(tmp / "summary.json"),
        }
    if name == "acquisition":
        return {**common, "duration_s": 0.6, "out_dir": str(tmp / "acquired")}
    raise AssertionError(name)


def _skip_reason(name: str) -> str | None:
    missing = [m for m in REQUIRES[name] if importlib.util.find_spec(m) is None]
    if missing:
        return f"the {name} notebook needs {missing}, not installed or not written yet"
    if name == "real_data" and not EXTERNAL.is_dir():
        return f"real recordings not found at {EXTERNAL}"
    if name in ("loads", "viscosity", "single_run") and not (REPO / "data").is_dir():
        return "the bundled campaign data/ is absent"
    return None


# -- the committed notebooks ------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_notebook_is_committed_without_outputs_and_has_one_parameters_cell(name):
    nb = read_notebook(name)
    nbformat.validate(nb)
    assert not has_outputs(nb), f"{name}: clear the outputs before committing"
    tagged = [c for c in nb.cells if PARAMETERS_TAG in c.metadata.get("tags", [])]
    assert len(tagged) == 1
    params = notebook_parameters(nb)
    assert params, f"{name}: the parameters cell assigns nothing"
    # every notebook can write its figures somewhere the reports collect them
    assert "figure_dir" in params and params["figure_dir"] is None


def test_every_notebook_file_is_listed():
    on_disk = {p.name for p in (REPO / "notebooks").glob("*.ipynb")}
    assert on_disk == set(NOTEBOOKS.values())


# -- parameter injection ----------------------------------------------------------------


def test_inject_parameters_replaces_the_tagged_cell_and_keeps_the_other_defaults():
    nb = read_notebook("single_run")
    defaults = notebook_parameters(nb)
    others = [c.source for c in nb.cells if PARAMETERS_TAG not in c.metadata.get("tags", [])]
    inject_parameters(
        nb, {"max_steps": 123, "read_kwargs": {"metadata": {"length_unit": "arbitrary"}}}
    )
    values = notebook_parameters(nb)
    assert values["max_steps"] == 123
    assert values["read_kwargs"] == {"metadata": {"length_unit": "arbitrary"}}
    assert {k: v for k, v in values.items() if k not in ("max_steps", "read_kwargs")} == {
        k: v for k, v in defaults.items() if k not in ("max_steps", "read_kwargs")
    }
    assert [c.source for c in nb.cells if PARAMETERS_TAG not in c.metadata.get("tags", [])] == (
        others
    )


def test_inject_parameters_refuses_an_unknown_name():
    nb = read_notebook("single_run")
    with pytest.raises(ReportError, match="max_stepz"):
        inject_parameters(nb, {"max_stepz": 10})


def test_inject_parameters_refuses_a_value_that_is_not_a_literal():
    nb = read_notebook("single_run")
    with pytest.raises(ReportError, match="seed"):
        inject_parameters(nb, {"seed": object()})


def test_a_notebook_without_a_parameters_cell_is_refused():
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("x = 1")])
    with pytest.raises(ReportError, match="exactly one cell tagged"):
        notebook_parameters(nb)


def test_unknown_notebook_name_is_a_report_error():
    with pytest.raises(ReportError, match="expected one of"):
        notebook_path("no_such_report")


def test_a_failing_cell_is_a_report_error_naming_the_error(tmp_path):
    cell = nbformat.v4.new_code_cell("x = 1")
    cell.metadata["tags"] = [PARAMETERS_TAG]
    nb = nbformat.v4.new_notebook(
        cells=[cell, nbformat.v4.new_code_cell("raise RuntimeError('boom ' + str(x))")]
    )
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    with pytest.raises(ReportError, match="cell 1: RuntimeError: boom 1") as info:
        execute_notebook(nb, cwd=tmp_path)
    assert info.value.notebook is nb


# -- execution --------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_notebook_executes_with_test_parameters(name, tmp_path):
    reason = _skip_reason(name)
    if reason:
        pytest.skip(reason)
    params = _test_parameters(name, tmp_path)
    # HTML rendering needs nbconvert; without it the notebook is still executed.
    html = tmp_path / f"{name}.html" if importlib.util.find_spec("nbconvert") else None
    nb = run_report(name, params, html=html)
    errors = [
        o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"
    ]
    assert not errors
    images = [
        o
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.outputs
        if "image/png" in o.get("data", {})
    ]
    pngs = sorted((tmp_path / "figures").glob("*.png"))
    assert images and pngs, f"{name}: no figure produced"
    if html is not None:
        text = html.read_text(encoding="utf-8")
        assert text.count("data:image/png;base64") >= len(images)  # figures embedded
        assert "Traceback" not in text

    summary = tmp_path / "summary.json"
    if name == "single_run":
        record = json.loads(summary.read_text())
        assert record["fit"]["diagnostics"]["converged"]
        # The bundled run is simulated: its sidecar holds the truth. At the vibrometer's
        # resolution ζ and μ_k are known to about 1e-5 relative; a wrong scaling or a
        # wrong run would miss the truth by orders of magnitude more than the interval.
        for p in ("zeta", "mu_k"):
            lo, hi = record["fit"]["parameters"][p]["interval"]
            assert lo <= record["true"][p] <= hi, p
    if name in ("loads", "viscosity"):
        record = json.loads(summary.read_text())
        assert not record["failed"]
        assert len(record["runs"]) == {"loads": 4, "viscosity": 2}[name]
    if name == "loads":
        assert record["trend"] is not None and record["contact_damping"]
    if name == "real_data":
        record = json.loads(summary.read_text())
        verdict = {r["recording"]: r["dominated by"] for r in record["verdict"]}
        # HarmOsc3 slides on a metal plate: dry friction dissipates the energy.
        assert verdict == {"HarmOsc3": "friction"}


def test_html_leaves_the_code_out_unless_asked(tmp_path):
    cell = nbformat.v4.new_code_cell("print('visible output')\nsecret_variable_name = 1")
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text="visible output\n")]
    nb = nbformat.v4.new_notebook(cells=[cell])
    pytest.importorskip("nbconvert")
    hidden = to_html(nb)
    assert "secret_variable_name" not in hidden and "visible output" in hidden
    assert "secret_variable_name" in to_html(nb, show_code=True)
    # the former option still leaves the code out
    assert "secret_variable_name" not in to_html(nb, show_code=True, hide_code=True)


@pytest.mark.skipif(os.name != "posix", reason="environment variable handling is POSIX here")
def test_notebooks_folder_from_the_environment(tmp_path, monkeypatch):
    from bayestribo.reports import notebooks as report

    monkeypatch.setenv("BAYESTRIBO_NOTEBOOKS", str(tmp_path / "missing"))
    with pytest.raises(ReportError, match="BAYESTRIBO_NOTEBOOKS"):
        report.notebooks_dir()


def test_a_missing_jupyter_package_is_an_error_saying_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "nbconvert", None)  # import fails as if not installed
    with pytest.raises(MissingDependencyError, match=r"needs nbconvert: .*bayestribo\[report\]"):
        to_html(nbformat.v4.new_notebook())
