"""One rendering per report kind, made by ``bayestribo report`` and shared by the tests.

The notebook tests (``test_reports_notebooks.py``), the browser tests
(``test_reports_browser.py``) and the page tests (``test_reports_pages.py``) each check
the single-run, campaign (loads), real-data, viscosity and acquisition reports (the
acquisition report's numbers too: ``test_reports_numbers_acquisition.py``): each kind
is made once per test session (``conftest.py`` holds the fixtures) on short test
parameters, with the executed notebook and, where the notebook writes one, its summary
JSON beside the HTML, and every test asserts on that one output. The single-run and
viscosity reports are made from runs whose file names and sidecars hold markup (the page
tests check that it shows as text), the others from the bundled runs and the real
recordings as a user reports them.

Under ``pytest -n`` the modules using these renderings are one ``xdist_group``
(:data:`GROUP`), so the renderings are made on one worker only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["ACQUISITION_SETTINGS", "GROUP", "Rendering", "render"]

#: The ``xdist_group`` of the test modules sharing the renderings.
GROUP = "renderings"

#: The acquisition report's fit settings, as options of ``bayestribo report`` (and of
#: ``bayestribo fit``, which ``test_reports_numbers_acquisition.py`` runs on the run the
#: report acquired): a short sampler, whose convergence the tests do not need.
ACQUISITION_SETTINGS = ("--max-steps", "1500", "--grid-points", "32")


@dataclass(frozen=True)
class Rendering:
    """One report made by ``bayestribo report`` for the tests.

    Attributes
    ----------
    html : Path
        The report.
    figures : Path
        The folder of its figure files.
    figure_format : str
        Their format (``"png"``, ``"pdf"`` or ``"svg"``).
    executed : Path
        The executed notebook (``--executed``), with its outputs.
    summary : Path or None
        The summary JSON the notebook wrote (``summary_path``), or None (not asked for).
    parameters : dict
        The notebook parameters given with ``--param``.
    status : int
        The command's exit status.
    source : Path or None
        The run or folder the report was made of.
    """

    html: Path
    figures: Path
    figure_format: str
    executed: Path
    summary: Path | None
    parameters: dict[str, Any] = field(default_factory=dict)
    status: int = 0
    source: Path | None = None


def render(
    folder: Path,
    name: str,
    path: Path | None,
    parameters: dict[str, Any],
    *,
    notebook: str | None = None,
    figure_format: str = "png",
    options: tuple[str, ...] = (),
    summary: bool = True,
) -> Rendering:
    """Make a report with ``bayestribo report`` into ``folder``.

    Parameters
    ----------
    folder : Path
        Where the report (``NAME.html``), its figures (``NAME-figures``), the executed
        notebook (``NAME.ipynb``) and the summary (``NAME-summary.json``) are written.
    name : str
        The stem of those files.
    path : Path or None
        The run file or folder reported on (None: the simulated acquisition).
    parameters : dict
        Notebook parameters, each given as ``--param KEY=repr(VALUE)``.
    notebook : str, optional
        ``--notebook`` (default: the command's choice for ``path``).
    figure_format : str
        ``--figure-format``.
    options : tuple of str
        Further options of the command.
    summary : bool
        Ask the notebook for its summary JSON (``summary_path``).

    Returns
    -------
    Rendering
        The report's files and the command's exit status.
    """
    from bayestribo.cli import main

    html = folder / f"{name}.html"
    executed = folder / f"{name}.ipynb"
    summary_path = folder / f"{name}-summary.json" if summary else None
    given = dict(parameters)
    if summary_path is not None:
        given["summary_path"] = str(summary_path)
    argv = ["report", *([str(path)] if path is not None else [])]
    argv += ["--notebook", notebook] if notebook else []
    argv += ["--out", str(html), "--figure-format", figure_format, "--executed", str(executed)]
    argv += list(options)
    for key, value in given.items():
        argv += ["--param", f"{key}={value!r}"]
    status = main(argv)
    return Rendering(
        html=html,
        figures=folder / f"{name}-figures",
        figure_format=figure_format,
        executed=executed,
        summary=summary_path,
        parameters=given,
        status=status,
        source=path,
    )
