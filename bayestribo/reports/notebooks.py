"""Reports from notebooks: run a notebook with parameters, render it as one HTML file.

The notebooks in ``notebooks/`` are the package's reports and its users' templates.
Each has one cell tagged ``parameters`` holding plain assignments (data path, chain
length, fit settings). :func:`inject_parameters` replaces that cell's source with new
assignments (the role papermill plays, without papermill), :func:`execute_notebook`
runs the notebook with :mod:`nbclient`, and :func:`to_html` renders it with
nbconvert's ``HTMLExporter``, figures embedded as base64 PNG so the HTML file is
self-contained and can be sent by mail.

:func:`run_report` chains the three; ``bayestribo report`` and ``bayestribo demo``
call it.

Where the files are
-------------------
The notebooks and the bundled campaign ``data/`` live next to the package in a
source checkout (an editable install). :func:`notebooks_dir` and
:func:`bundled_data_dir` find them there, or in the folders named by the environment
variables ``BAYESTRIBO_NOTEBOOKS`` and ``BAYESTRIBO_DATA``.
"""

from __future__ import annotations

import ast
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bayestribo._optional import require
from bayestribo.errors import BayestriboError

__all__ = [
    "NOTEBOOKS",
    "PARAMETERS_TAG",
    "ReportError",
    "bundled_data_dir",
    "execute_notebook",
    "has_outputs",
    "inject_parameters",
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


class ReportError(BayestriboError):
    """A report notebook is missing, malformed, or failed while running."""


def _require(module: str) -> Any:
    """Import a Jupyter package the reports need, or say how to install it."""
    return require(module, "making reports")


def notebooks_dir() -> Path:
    """The folder of the report notebooks.

    ``$BAYESTRIBO_NOTEBOOKS`` if set, else ``notebooks/`` next to the package (a
    source checkout).

    Raises
    ------
    ReportError
        If the folder does not exist.
    """
    env = os.environ.get("BAYESTRIBO_NOTEBOOKS")
    folder = Path(env) if env else _REPO_ROOT / "notebooks"
    if not folder.is_dir():
        raise ReportError(
            f"notebooks folder {folder} not found: reports need the notebooks of a source "
            "checkout (pip install -e .) or BAYESTRIBO_NOTEBOOKS naming their folder"
        )
    return folder


def bundled_data_dir() -> Path | None:
    """The bundled campaign folder (with ``manifest.csv``), or None if absent.

    ``$BAYESTRIBO_DATA`` if set, else ``data/`` next to the package.
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


def notebook_parameters(nb: Any) -> dict[str, Any]:
    """The default parameters of a notebook: the literal assignments of its parameters cell.

    Raises
    ------
    ReportError
        If the cell is missing, repeated, or assigns something that is not a literal.
    """
    source = _parameters_cell(nb).source
    out: dict[str, Any] = {}
    for node in ast.parse(source).body:
        if not (isinstance(node, ast.Assign) and len(node.targets) == 1):
            raise ReportError("notebook: the parameters cell must hold plain assignments only")
        target = node.targets[0]
        if not isinstance(target, ast.Name):
            raise ReportError("notebook: the parameters cell must assign plain names")
        try:
            out[target.id] = ast.literal_eval(node.value)
        except ValueError:
            raise ReportError(
                f"notebook: parameter {target.id!r} is not a literal (number, string, list, "
                "dict, None...)"
            ) from None
    return out


def inject_parameters(nb: Any, parameters: Mapping[str, Any]) -> Any:
    """Replace the parameters cell's source with the defaults updated by ``parameters``.

    The notebook is modified in place and returned. Every value must be a Python
    literal (its ``repr`` is written to the cell), and every name must be one of the
    notebook's parameters: a misspelt name would otherwise be silently ignored.

    Raises
    ------
    ReportError
        For an unknown parameter name or a value whose ``repr`` is not a literal.
    """
    defaults = notebook_parameters(nb)
    unknown = sorted(set(parameters) - set(defaults))
    if unknown:
        raise ReportError(
            f"parameters {unknown} are not parameters of this notebook; it has {sorted(defaults)}"
        )
    values = {**defaults, **parameters}
    lines = ["# Parameters (injected)"]
    for key, value in values.items():
        text = repr(value)
        try:
            ast.literal_eval(text)
        except (ValueError, SyntaxError):
            raise ReportError(
                f"parameter {key!r}: {value!r} cannot be written as a Python literal"
            ) from None
        lines.append(f"{key} = {text}")
    _parameters_cell(nb).source = "\n".join(lines) + "\n"
    return nb


def has_outputs(nb: Any) -> bool:
    """True if any code cell holds outputs or an execution count."""
    return any(
        c.cell_type == "code" and (c.get("outputs") or c.get("execution_count") is not None)
        for c in nb.cells
    )


def execute_notebook(
    nb: Any,
    *,
    cwd: str | Path | None = None,
    timeout: float | None = 1800.0,
    kernel_name: str = "python3",
) -> Any:
    """Execute every cell of ``nb`` (in place) with :class:`nbclient.NotebookClient`.

    Parameters
    ----------
    nb : nbformat.NotebookNode
    cwd : path, optional
        Working directory of the kernel (relative paths in the notebook start there);
        default the notebooks folder.
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

    folder = Path(cwd) if cwd is not None else notebooks_dir()
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name=kernel_name,
        resources={"metadata": {"path": str(folder)}},
    )
    try:
        client.execute()
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
    return nb


def to_html(nb: Any, *, hide_code: bool = False) -> str:
    """Render an executed notebook as one self-contained HTML page.

    Figures (``image/png`` outputs) are embedded as base64 data, so the file needs
    nothing beside it.

    Parameters
    ----------
    nb : nbformat.NotebookNode
    hide_code : bool
        Leave out the input cells (a report for readers who do not want the code).
    """
    HTMLExporter = _require("nbconvert").HTMLExporter

    exporter = HTMLExporter(
        exclude_input=hide_code, exclude_input_prompt=hide_code, exclude_output_prompt=hide_code
    )
    body, _ = exporter.from_notebook_node(nb)
    return body


def run_report(
    notebook: str | Path,
    parameters: Mapping[str, Any] | None = None,
    *,
    html: str | Path | None = None,
    executed: str | Path | None = None,
    hide_code: bool = False,
    cwd: str | Path | None = None,
    timeout: float | None = 1800.0,
) -> Any:
    """Run a report notebook with parameters and write it as HTML.

    Parameters
    ----------
    notebook : str or Path
        Short name (:data:`NOTEBOOKS`) or ``.ipynb`` path.
    parameters : mapping, optional
        Values replacing the notebook's defaults (:func:`inject_parameters`). Paths
        in them are best absolute: the kernel runs in ``cwd``.
    html : path, optional
        Where to write the HTML report (its folder is created).
    executed : path, optional
        Where to write the executed notebook (``.ipynb``, with outputs).
    hide_code : bool
        Leave the code cells out of the HTML.
    cwd : path, optional
        Working directory of the kernel (default the notebooks folder).
    timeout : float or None
        Longest time a single cell may run [s].

    Returns
    -------
    nbformat.NotebookNode
        The executed notebook.

    Raises
    ------
    ReportError
        For a missing notebook, a bad parameter, or a cell that fails.
    """
    nbformat = _require("nbformat")
    nb = read_notebook(notebook)
    inject_parameters(nb, dict(parameters or {}))
    execute_notebook(nb, cwd=cwd, timeout=timeout)
    if executed is not None:
        Path(executed).parent.mkdir(parents=True, exist_ok=True)
        nbformat.write(nb, str(executed))
    if html is not None:
        out = Path(html)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(to_html(nb, hide_code=hide_code), encoding="utf-8")
    return nb
