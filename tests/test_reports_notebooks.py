"""The report notebooks: shipped in the package, committed clean, typed parameters
checked before running, every notebook executed.

Each notebook runs with nbclient (kernel python3) on short test parameters (a few fits
at most) and must finish without an error output; its HTML rendering must embed its
figures, show no code, load nothing from a network, and its figure files must be in
the format asked for. A notebook whose data or modules are absent is skipped with the
reason.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import sys

import pytest
from _paths import APPSTAT, REPO
from _renderings import GROUP
from _report_numbers import interval_cells, unmatched

from bayestribo import DEFAULT_SEED

nbformat = pytest.importorskip("nbformat")
pytest.importorskip("nbclient")

from bayestribo.errors import MissingDependencyError  # noqa: E402
from bayestribo.reports.html import external_references  # noqa: E402
from bayestribo.reports.kit import FIGURE_PROBLEMS  # noqa: E402
from bayestribo.reports.notebooks import (  # noqa: E402
    NOTEBOOKS,
    PARAMETERS_TAG,
    ReportError,
    execute_notebook,
    has_outputs,
    inject_parameters,
    notebook_parameter_specs,
    notebook_parameters,
    notebook_path,
    notebooks_dir,
    read_notebook,
    run_report,
    to_html,
)

EXTERNAL = APPSTAT

pytestmark = pytest.mark.xdist_group(GROUP)  # the shared renderings made on one worker

#: Modules each notebook imports beyond the core (skip with a reason when absent).
REQUIRES = {
    "single_run": ["bayestribo.inference.plots", "bayestribo.adequacy", "corner"],
    "loads": ["bayestribo.campaign.fitting", "bayestribo.population"],
    "viscosity": ["bayestribo.campaign.fitting", "bayestribo.population"],
    "real_data": ["bayestribo.adequacy"],
    "acquisition": ["bayestribo.acquisition", "bayestribo.inference.plots"],
}


#: The shared rendering of each notebook (conftest.py, tests/_renderings.py): short runs,
#: one to six fits per notebook, small samplers where it matters; every figure format
#: is tried (single_run: pdf, loads: svg, the others png).
RENDERINGS = {name: f"{name}_report" for name in NOTEBOOKS}


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
    shipped = {p.name for p in notebooks_dir().glob("*.ipynb")}
    assert shipped == set(NOTEBOOKS.values())


def test_the_notebooks_are_shipped_in_the_package():
    # read through importlib.resources: what `pip install .` installs, not the checkout
    assert notebooks_dir() == REPO / "bayestribo" / "reports" / "ipynb"
    pyproject = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    assert '"reports/ipynb/*.ipynb"' in pyproject and '"reports/template/*/*"' in pyproject


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_the_notebooks_folder_holds_the_shipped_notebooks(name):
    copy = REPO / "notebooks" / NOTEBOOKS[name]
    if not copy.parent.is_dir():
        pytest.skip("no notebooks/ folder (not a source checkout)")
    shipped = notebooks_dir() / NOTEBOOKS[name]
    assert copy.read_bytes() == shipped.read_bytes(), (
        f"notebooks/{copy.name} differs from the shipped one: copy the edited one over the other"
    )


@pytest.mark.parametrize("name", sorted(NOTEBOOKS))
def test_every_parameter_has_a_type_and_a_meaning(name):
    specs = notebook_parameter_specs(read_notebook(name))
    untyped = [k for k, s in specs.items() if s.annotation is None]
    unexplained = [k for k, s in specs.items() if not s.comment]
    assert not untyped and not unexplained
    assert specs["figure_format"].default == "png"


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


@pytest.mark.parametrize(
    ("value", "expected"),
    [("5k", "expected int"), (True, "expected int"), (2.5, "expected int")],
)
def test_a_value_of_the_wrong_type_is_refused_naming_the_parameter_and_the_type(value, expected):
    nb = read_notebook("single_run")
    with pytest.raises(ReportError, match=f"parameter 'max_steps': {expected}"):
        inject_parameters(nb, {"max_steps": value})


def test_typed_values_are_accepted():
    nb = read_notebook("loads")
    inject_parameters(nb, {"loads": [0.12, 1], "repeats": None, "fit_kwargs": {"max_steps": 9}})
    assert notebook_parameters(nb)["loads"] == [0.12, 1]
    with pytest.raises(ReportError, match=r"parameter 'loads': expected list\[float\] \| None"):
        inject_parameters(read_notebook("loads"), {"loads": ["heavy"]})


def test_a_wrong_type_fails_before_any_cell_runs(tmp_path):
    cell = nbformat.v4.new_code_cell("steps: int = 10  # steps")
    cell.metadata["tags"] = [PARAMETERS_TAG]
    marker = tmp_path / "ran"
    nb = nbformat.v4.new_notebook(
        cells=[cell, nbformat.v4.new_code_cell(f"open({str(marker)!r}, 'w').close()")]
    )
    path = tmp_path / "nb.ipynb"
    nbformat.write(nb, str(path))
    with pytest.raises(ReportError, match="parameter 'steps': expected int"):
        run_report(str(path), {"steps": "5k"}, cwd=tmp_path)
    assert not marker.exists()


def test_inject_parameters_refuses_a_value_that_is_not_a_literal():
    nb = read_notebook("single_run")
    with pytest.raises(ReportError, match="read_kwargs"):
        inject_parameters(nb, {"read_kwargs": {"x": object()}})


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
def test_notebook_executes_with_test_parameters(name, request):
    reason = _skip_reason(name)
    if reason:
        pytest.skip(reason)
    made = request.getfixturevalue(RENDERINGS[name])
    params = made.parameters
    nb = nbformat.read(made.executed, as_version=4)
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
    fmt = made.figure_format
    files = sorted(made.figures.glob(f"*.{fmt}"))
    assert images and files, f"{name}: no figure produced"
    # every report draws the energy lost per cycle against the swing, ΔE(A)
    assert (made.figures / f"dissipation.{fmt}").is_file(), name
    assert len(files) == len(list(made.figures.iterdir()))  # all in that format
    if fmt == "pdf":
        assert all(f.read_bytes().startswith(b"%PDF") for f in files)
    if fmt == "svg":
        assert all(b"<svg" in f.read_bytes()[:2000] for f in files)
    text = made.html.read_text(encoding="utf-8")
    assert text.count("data:image/png;base64") >= len(images)  # figures embedded
    assert "Traceback" not in text
    assert external_references(text) == []  # readable offline
    assert "$$" not in text  # equations rendered, not left as TeX
    assert not re.search(r'class="[^"]*jp-InputArea-editor', text)  # no code
    assert 'data-mime-type="application/vnd.jupyter.stderr"' not in text
    assert 'class="bt-toc"' in text and "bayestribo version" in text
    for problem in FIGURE_PROBLEMS:  # every figure legible, no empty panel (kit.save)
        assert f": {problem}: " not in text, problem
    # nbconvert's "word-break: break-all" is overridden: numbers stay whole
    assert "word-break: normal" in text

    summary = made.summary
    if name == "single_run":
        record = json.loads(summary.read_text())
        assert record["fit"]["diagnostics"]["converged"]
        # one answer per question: the report's fit is the command's, same run, seed
        # and settings (one Π increment per half cycle unless told otherwise)
        from bayestribo import fit

        direct = fit(record["run"], seed=DEFAULT_SEED, grid_points=params.get("grid_points"))
        for p, s in direct.summary().items():
            assert record["fit"]["parameters"][p]["mean"] == pytest.approx(s.mean, rel=1e-12), p
        # The bundled run is simulated: its sidecar holds the truth. At the vibrometer's
        # resolution ζ and μ_k are known to about 1e-5 relative; a wrong scaling or a
        # wrong run would miss the truth by orders of magnitude more than the interval.
        for p in ("zeta", "mu_k"):
            lo, hi = record["fit"]["parameters"][p]["interval"]
            assert lo <= record["true"][p] <= hi, p
        # one verdict, decided from the checks it lists, and the same in the text
        adequacy = record["adequacy"]
        assert adequacy["adequate"] == all(c["passed"] is not False for c in adequacy["checks"])
        assert f"Verdict: {adequacy['verdict']}." in text
        # and its false-alarm rate on a record of the law, stated under it
        assert "verdict says" in adequacy["level"] and "at most 5 % of the time" in text
    if name in ("loads", "viscosity"):
        record = json.loads(summary.read_text())
        # every value with its interval is one of the fits' or the populations', the
        # trends' means at the ends of their loads and each run's ΔE at a shared swing
        # included (the record keeps them)
        assert len(interval_cells(text)) >= 8
        assert unmatched(text, record["runs"], record) == []
        assert not record["failed"]
        assert len(record["runs"]) == {"loads": 4, "viscosity": 2}[name]
    if name == "loads":
        assert record["trends"] and record["contact_damping"]
        assert record["campaign_dir"] is None and record["seed"] == 0  # fitted here
        assert "No campaign results were given" in text
        # the glycerol-water series has its own section: its runs, populations by water
        # fraction and its trend against viscosity
        water = record["water_series"]
        assert water["series"] == "glycerol-water" and len(water["runs"]) == 2
        assert any(k.startswith("viscosity:") for k in water["analysis"]["trends"])
        assert "6. The glycerol–water series" in text and "against viscosity" in text
    if name == "real_data":
        record = json.loads(summary.read_text())
        # every value with its interval in the answer and the fits' section is the fit's
        # own (as `fit --json` writes it), x_c/A₀ by the recording's first amplitude
        scales = [1.0, *(1.0 / r["A₀ [signal unit]"] for r in record["overview"])]
        not_fitted = {r["recording"] for r in record["overview"]} - set(record["fits"])
        for title in ("The answer", "3. Bayesian fits"):
            part = _section(text, title)
            assert unmatched(part, record["fits"], scales=scales, skip_columns=not_fitted) == []
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


#: A law other than the paper's, on HarmOsc3 (dry friction on a plate), where it misfits:
#: its parameters are no ζ, and no law holds (the answer is the turning points' ΔE(A)).
#: A short sampler: the sections' text is checked, and the misfit (χ² p about 1e-13) is
#: as plain after 1000 steps as after 3000.
OTHER_LAW = {"law": "coulomb+power", "grid_points": 24, "max_steps": 1000}


def _section(text: str, title: str) -> str:
    """The HTML of the section whose heading holds ``title``, to the next heading."""
    heads = [m.start() for m in re.finditer(r"<h2\b", text)]
    start = next(i for i, h in enumerate(heads) if title in text[h : h + 400])
    return text[heads[start] : heads[start + 1] if start + 1 < len(heads) else len(text)]


@pytest.mark.parametrize("name", ["single_run", "real_data"])
def test_notebook_renders_every_section_for_another_law_where_no_law_holds(name, tmp_path):
    if importlib.util.find_spec("nbconvert") is None:
        pytest.skip("nbconvert (the report extra) is not installed")
    if not EXTERNAL.is_dir():
        pytest.skip(f"real recordings not found at {EXTERNAL}")
    reading = {"columns": ["time_s", "displacement_m"], "metadata": {"length_unit": "arbitrary"}}
    common = {"figure_dir": str(tmp_path / "figures"), "figure_format": "png"}
    common["summary_path"] = str(tmp_path / "summary.json")
    if name == "single_run":
        params = {**common, "run_path": str(EXTERNAL / "HarmOsc3.txt"), "read_kwargs": reading}
        params.update(OTHER_LAW)
    else:
        params = {**common, "data_dir": str(EXTERNAL), "files": ["HarmOsc3.txt"]}
        params.update(fit_files=["HarmOsc3.txt"], check_files=["HarmOsc3.txt"])
        params["fit_kwargs"] = OTHER_LAW
    html = tmp_path / f"{name}.html"
    nb = run_report(name, params, html=html)
    errors = [
        o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"
    ]
    assert not errors
    text = html.read_text(encoding="utf-8")
    for problem in FIGURE_PROBLEMS:
        assert f": {problem}: " not in text, problem
    assert (tmp_path / "figures" / "dissipation.png").is_file()  # the ΔE(A) figure
    answer = _section(text, "The answer")
    assert "Coulomb friction + power-law drag" in answer
    assert "turning points (law-free)" in answer and "friction" in answer
    assert "The law holds" not in answer and "holds: its parameters" not in answer
    # the law has no ζ: neither the answer nor the fit's section says one in what they
    # show (ζ_α is its own; the sections' fixed introductions name ζ "where it has one")
    for title in ("The answer", "Bayesian fit"):
        part = _section(text, title)
        part = part[part.find('<div class="jp-Cell ') :]
        part = re.sub(
            r'<div class="jp-Cell jp-MarkdownCell.*?(?=<div class="jp-Cell |\Z)',
            "",
            part,
            flags=re.S,
        )
        assert not re.search(r"ζ(?!<sub>|_|α)", part), re.findall(r".{80}ζ(?!<sub>|_|α).{40}", part)
    record = json.loads((tmp_path / "summary.json").read_text())
    fit = record["fit"] if name == "single_run" else record["fits"]["HarmOsc3"]
    assert fit["law"] == "coulomb+power" and "zeta" not in fit["parameters"]
    if name == "real_data":
        # dry friction on a plate: friction dominates in any law that has it
        assert {r["recording"]: r["dominated by"] for r in record["verdict"]} == {
            "HarmOsc3": "friction"
        }


def test_every_interval_of_the_single_run_report_is_the_fits_or_its_records(single_run_report):
    # the whole page of the bundled run's report (answer, classical estimates, fit, model
    # checks with their windowed fits, friction's share): every value with its interval
    # is one of `bayestribo fit --json` of the same run and settings, or of the report's
    # record of what no command prints, in the digits the rule gives
    import contextlib
    import io

    from bayestribo.cli.main import main

    made = single_run_report
    record = json.loads(made.summary.read_text())
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        main(["fit", str(made.source), "--grid-points", "32", "--json"])
    fitted = json.loads(printed.getvalue())
    page = made.html.read_text(encoding="utf-8")
    heads = {head for _, _, head in interval_cells(page)}
    assert len(heads) >= 4 and len(interval_cells(page)) >= 30
    assert unmatched(page, fitted, record) == []
