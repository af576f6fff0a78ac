"""Reports from notebooks: run a notebook with parameters, render it as one HTML file.

The report notebooks ship inside the package (``bayestribo/reports/ipynb/``, read with
:mod:`importlib.resources`), so ``pip install .`` can make reports; the ``notebooks/``
folder of a source checkout holds identical copies to open in Jupyter (a test keeps
them identical). Each has one cell tagged ``parameters`` holding annotated assignments
(``max_steps: int = 20000``, see :mod:`bayestribo.reports.parameters`).
:func:`inject_parameters` checks new values against those types and replaces that
cell's source (the role papermill plays, without papermill), :func:`execute_notebook`
runs the notebook with :mod:`nbclient`, and :func:`to_html`
(:mod:`bayestribo.reports.html`) renders it as one self-contained page: figures
embedded, equations as SVG, no code unless asked for, nothing loaded from a network.

:func:`run_report` chains the three; ``bayestribo report`` and ``bayestribo demo``
call it.

Where the files are
-------------------
:func:`notebooks_dir` is the packaged folder, or the folder named by
``$BAYESTRIBO_NOTEBOOKS``. The bundled campaign ``data/`` lives next to the package in
a source checkout; :func:`bundled_data_dir` finds it there or in ``$BAYESTRIBO_DATA``.
"""

from __future__ import annotations

import ast
import os
import tempfile
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from bayestribo._files import atomic_file, write_text
from bayestribo._optional import require
from bayestribo.reports import html as _html
from bayestribo.reports._errors import ReportError
from bayestribo.reports.parameters import (
    ParameterSpec,
    check_values,
    parameter_specs,
)

__all__ = [
    "NOTEBOOKS",
    "PARAMETERS_TAG",
    "ReportError",
    "bundled_data_dir",
    "execute_notebook",
    "has_outputs",
    "inject_parameters",
    "notebook_parameter_specs",
    "notebook_parameters",
    "notebook_path",
    "notebooks_dir",
    "read_notebook",
    "run_report",
    "to_html",
]

#: Tag of the cell that holds a notebook's parameters.
PARAMETERS_TAG = "parameters"

#: The report notebooks by short name.
NOTEBOOKS: dict[str, str] = {
    "single_run": "single_run.ipynb",
    "loads": "loads.ipynb",
    "viscosity": "viscosity.ipynb",
    "real_data": "real_data.ipynb",
    "acquisition": "acquisition.ipynb",
}

_REPO_ROOT = Path(__file__).resolve().parents[2]

#: What the kernel prints on its stderr at every start and that is not the reader's
#: concern (the kernel and this process talk over the loopback interface).
_KERNEL_NOISE = ("Kernel is running over TCP",)


def _require(module: str) -> Any:
    """Import a Jupyter package the reports need, or say how to install it."""
    return require(module, "making reports")


def notebooks_dir() -> Path:
    """The folder of the report notebooks.

    ``$BAYESTRIBO_NOTEBOOKS`` if set, else the notebooks shipped in the package
    (``bayestribo/reports/ipynb``).

    Raises
    ------
    ReportError
        If the folder does not exist.
    """
    env = os.environ.get("BAYESTRIBO_NOTEBOOKS")
    folder = Path(env) if env else Path(str(resources.files("bayestribo.reports") / "ipynb"))
    if not folder.is_dir():
        raise ReportError(
            f"notebooks folder {folder} not found: set BAYESTRIBO_NOTEBOOKS to a folder of "
            "report notebooks, or unset it to use the ones shipped with bayestribo"
        )
    return folder


def bundled_data_dir() -> Path | None:
    """The bundled campaign folder (with ``manifest.csv``), or None if absent.

    ``$BAYESTRIBO_DATA`` if set, else ``data/`` next to the package (a source checkout).
    """
    env = os.environ.get("BAYESTRIBO_DATA")
    folder = Path(env) if env else _REPO_ROOT / "data"
    return folder if (folder / "manifest.csv").is_file() else None


def notebook_path(name: str) -> Path:
    """Path of a report notebook by short name (:data:`NOTEBOOKS`) or file path.

    Raises
    ------
    ReportError
        If the name is unknown or the file does not exist.
    """
    if name in NOTEBOOKS:
        path = notebooks_dir() / NOTEBOOKS[name]
    else:
        path = Path(name)
        if path.suffix != ".ipynb":
            raise ReportError(
                f"notebook {name!r}: expected one of {sorted(NOTEBOOKS)} or an .ipynb path"
            )
    if not path.is_file():
        raise ReportError(f"notebook {path} not found")
    return path


def read_notebook(name: str | Path) -> Any:
    """Read a notebook (short name or path) as an nbformat v4 node."""
    nbformat = _require("nbformat")
    path = notebook_path(str(name))
    return nbformat.read(path, as_version=4)


def _parameters_cell(nb: Any) -> Any:
    cells = [c for c in nb.cells if PARAMETERS_TAG in c.get("metadata", {}).get("tags", [])]
    if len(cells) != 1:
        raise ReportError(
            f"notebook: expected exactly one cell tagged {PARAMETERS_TAG!r}, found {len(cells)}"
        )
    if cells[0].cell_type != "code":
        raise ReportError(f"notebook: the cell tagged {PARAMETERS_TAG!r} must be a code cell")
    return cells[0]


def notebook_parameter_specs(nb: Any) -> dict[str, ParameterSpec]:
    """Name, type, default and meaning of every parameter of a notebook.

    Raises
    ------
    ReportError
        If the parameters cell is missing, repeated, or holds anything but
        (annotated) assignments of literals
        (:func:`bayestribo.reports.parameters.parameter_specs`).
    """
    return parameter_specs(_parameters_cell(nb).source)


def notebook_parameters(nb: Any) -> dict[str, Any]:
    """The default parameters of a notebook: the literal assignments of its parameters cell.

    Raises
    ------
    ReportError
        If the cell is missing, repeated, or assigns something that is not a literal.
    """
    return {name: spec.default for name, spec in notebook_parameter_specs(nb).items()}


def inject_parameters(nb: Any, parameters: Mapping[str, Any]) -> Any:
    """Replace the parameters cell's source with the defaults updated by ``parameters``.

    The notebook is modified in place and returned. Every name must be one of the
    notebook's parameters (a misspelt name would otherwise be silently ignored) and
    every value of the parameter's type; both are checked before anything runs.

    Raises
    ------
    ReportError
        For an unknown parameter name, a value of the wrong type (the message names
        the parameter and the type expected) or a value whose ``repr`` is not a literal.
    """
    specs = notebook_parameter_specs(nb)
    check_values(specs, parameters)
    lines = ["# Parameters (injected)"]
    for key, spec in specs.items():
        value = parameters.get(key, spec.default)
        text = repr(value)
        try:
            ast.literal_eval(text)
        except (ValueError, SyntaxError):
            raise ReportError(
                f"parameter {key!r}: {value!r} cannot be written as a Python literal"
            ) from None
        annotation = "" if spec.annotation is None else f": {spec.type}"
        lines.append(f"{key}{annotation} = {text}")
    _parameters_cell(nb).source = "\n".join(lines) + "\n"
    return nb


def has_outputs(nb: Any) -> bool:
    """True if any code cell holds outputs or an execution count."""
    return any(
        c.cell_type == "code" and (c.get("outputs") or c.get("execution_count") is not None)
        for c in nb.cells
    )


def _kernel_messages(path: Path) -> list[str]:
    """What the kernel wrote on its stderr, without its start-up noise."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return []
    lines = [line for line in text.splitlines() if line.strip()]
    return [line for line in lines if not any(n in line for n in _KERNEL_NOISE)]


def execute_notebook(
    nb: Any,
    *,
    cwd: str | Path | None = None,
    timeout: float | None = 1800.0,
    kernel_name: str = "python3",
) -> Any:
    """Execute every cell of ``nb`` (in place) with :class:`nbclient.NotebookClient`.

    The kernel's own stderr (its start-up messages) is kept off the terminal; what it
    says there besides its transport notice is added to the error if a cell fails.

    Parameters
    ----------
    nb : nbformat.NotebookNode
    cwd : path, optional
        Working directory of the kernel (relative paths in the notebook start there);
        default the current directory.
    timeout : float or None
        Longest time a single cell may run [s].
    kernel_name : str
        Jupyter kernel.

    Returns
    -------
    nbformat.NotebookNode
        ``nb`` with its outputs.

    Raises
    ------
    ReportError
        If a cell raises: the message names the cell and the error, and the
        partially executed notebook is in the exception's ``notebook`` attribute.
    """
    NotebookClient = _require("nbclient").NotebookClient
    CellExecutionError = _require("nbclient.exceptions").CellExecutionError

    folder = Path(cwd) if cwd is not None else Path.cwd()
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name=kernel_name,
        resources={"metadata": {"path": str(folder)}},
    )
    with tempfile.TemporaryDirectory(prefix="bayestribo-kernel-") as tmp:
        log = Path(tmp) / "kernel-stderr.txt"
        try:
            with open(log, "w", encoding="utf-8") as stderr:
                client.execute(stderr=stderr)
        except CellExecutionError as exc:
            failed = next(
                (
                    i
                    for i, c in enumerate(nb.cells)
                    if c.cell_type == "code"
                    and any(o.get("output_type") == "error" for o in c.get("outputs", []))
                ),
                None,
            )
            where = f"cell {failed}" if failed is not None else "a cell"
            error = ReportError(f"the notebook failed in {where}: {exc.ename}: {exc.evalue}")
            error.notebook = nb  # type: ignore[attr-defined]
            raise error from None
        except Exception as exc:  # the kernel died or could not start
            said = "; ".join(_kernel_messages(log)[-5:])
            raise ReportError(
                f"the notebook's kernel failed: {type(exc).__name__}: {exc}"
                + (f" (kernel said: {said})" if said else "")
            ) from None
    return nb


def to_html(nb: Any, *, show_code: bool = False, hide_code: bool | None = None) -> str:
    """Render an executed notebook as one self-contained HTML page.

    See :func:`bayestribo.reports.html.to_html`: figures embedded, equations as SVG,
    warnings as notes, a table of contents, nothing fetched from a network.

    Parameters
    ----------
    nb : nbformat.NotebookNode
    show_code : bool
        Include the code cells (default: a report without code).
    hide_code : bool, optional
        Former option (the code is now left out by default): ``True`` leaves the code
        out whatever ``show_code`` says; ``False`` changes nothing.
    """
    return _html.to_html(nb, show_code=show_code and not hide_code)


def run_report(
    notebook: str | Path,
    parameters: Mapping[str, Any] | None = None,
    *,
    html: str | Path | None = None,
    executed: str | Path | None = None,
    show_code: bool = False,
    hide_code: bool | None = None,
    cwd: str | Path | None = None,
    timeout: float | None = 1800.0,
) -> Any:
    """Run a report notebook with parameters and write it as HTML.

    Parameters
    ----------
    notebook : str or Path
        Short name (:data:`NOTEBOOKS`) or ``.ipynb`` path.
    parameters : mapping, optional
        Values replacing the notebook's defaults (:func:`inject_parameters`), checked
        against the parameters' types before anything runs. Paths in them are best
        absolute: the kernel runs in ``cwd``.
    html : path, optional
        Where to write the HTML report (its folder is created).
    executed : path, optional
        Where to write the executed notebook (``.ipynb``, with outputs and code).
    show_code : bool
        Include the code cells in the HTML (default: a report without code).
    hide_code : bool, optional
        Former option, see :func:`to_html`.
    cwd : path, optional
        Working directory of the kernel (default the current directory).
    timeout : float or None
        Longest time a single cell may run [s].

    Returns
    -------
    nbformat.NotebookNode
        The executed notebook.

    Raises
    ------
    ReportError
        For a missing notebook, a bad parameter (before any cell runs), or a cell
        that fails.
    """
    nbformat = _require("nbformat")
    nb = read_notebook(notebook)
    inject_parameters(nb, dict(parameters or {}))
    execute_notebook(nb, cwd=cwd, timeout=timeout)
    if executed is not None:
        Path(executed).parent.mkdir(parents=True, exist_ok=True)
        with atomic_file(executed) as fh:
            nbformat.write(nb, fh)
    if html is not None:
        out = Path(html)
        out.parent.mkdir(parents=True, exist_ok=True)
        write_text(out, to_html(nb, show_code=show_code, hide_code=hide_code))
    return nb
