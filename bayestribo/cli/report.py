"""``bayestribo report``: a run or a campaign folder as one self-contained HTML report.

Runs the single-run notebook (for a run file) or the campaign notebook across loads (for
a folder) on the user's data, and renders it as HTML with the figures embedded, so a
report can be sent without opening Jupyter.

Examples::

    bayestribo report data/runs/glycerol-N0.31-r1.csv --out report.html
    bayestribo report HarmOsc3.txt --columns t x --length-unit arbitrary --out osc3.html
    bayestribo report data/ --out campaign.html --param repeats=[1] --hide-code
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path
from typing import Any

__all__ = ["campaign_selection", "notebook_for", "parse_params", "register"]


def register(subparsers: Any) -> None:
    """Add the ``report`` sub-command."""
    from bayestribo.cli._common import add_reading_options

    p = subparsers.add_parser(
        "report",
        help="HTML report of a run (single-run notebook) or a campaign folder (loads notebook)",
        description=(
            "Run the report notebook on PATH and write it as one HTML file with the figures "
            "embedded. A run file gets the single-run report (signals, energy decay, "
            "classical estimates, Bayesian fit, diagnostics, corner plot, Π with its "
            "predictive band, comparison table, adequacy checks); a folder gets the "
            "campaign report across loads (per-run fits, forest plot, population of "
            "repeats, ζ and μ_k against load, ζ_k and d_k)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("path", metavar="PATH", help="run file, or campaign folder")
    p.add_argument("--out", type=Path, help="HTML file to write (default: <PATH stem>-report.html)")
    add_reading_options(p)
    p.add_argument("--seed", type=int, help="seed of the fits (the notebook's default otherwise)")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="set a notebook parameter (VALUE a Python literal, e.g. max_steps=5000, "
        "repeats=[1]); repeatable",
    )
    p.add_argument("--figures", type=Path, metavar="DIR", help="also write the figures (PNG)")
    p.add_argument(
        "--executed", type=Path, metavar="NOTEBOOK", help="also write the executed notebook"
    )
    p.add_argument("--hide-code", action="store_true", help="leave the code cells out")
    p.set_defaults(handler=run)


def parse_params(items: list[str]) -> dict[str, Any]:
    """``KEY=VALUE`` strings to a dict; VALUE a Python literal, else kept as a string.

    Raises
    ------
    ReportError
        For an item without ``=`` or with an empty key.
    """
    from bayestribo.reports.notebooks import ReportError

    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key.isidentifier():
            raise ReportError(f"--param {item!r}: expected KEY=VALUE with KEY a parameter name")
        try:
            out[key] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            out[key] = text
    return out


def notebook_for(path: Path) -> str:
    """``"single_run"`` for a file, ``"loads"`` for a folder holding runs.

    Raises
    ------
    ReportError
        If the path does not exist, or a folder holds neither a ``manifest.csv`` nor a
        run file with a sidecar.
    """
    from bayestribo.reports.notebooks import ReportError

    if path.is_file():
        return "single_run"
    if path.is_dir():
        has_runs = (path / "manifest.csv").is_file() or any(
            f.with_suffix(".json").is_file() for f in path.rglob("*.csv")
        )
        if not has_runs:
            raise ReportError(
                f"{path}: a campaign folder needs a manifest.csv or run files (.csv) with "
                "their sidecars (.json)"
            )
        return "loads"
    raise ReportError(f"{path}: no such run file or folder")


def campaign_selection(folder: Path) -> dict[str, Any]:
    """Series parameters of the campaign notebook for ``folder``.

    The notebook's defaults select the series ``glycerol`` (runs with contact) and
    ``air`` (runs without) of a manifest like the bundled one; a folder without those
    series is selected by load instead (load_N > 0: contact, load_N = 0: air).
    """
    import csv

    manifest = folder / "manifest.csv"
    series: set[str | None] = set()
    if manifest.is_file():
        with manifest.open(newline="", encoding="utf-8") as fh:
            series = {row.get("series") for row in csv.DictReader(fh)}
    out: dict[str, Any] = {}
    if "glycerol" not in series:
        out["series"] = None
    if "air" not in series:
        out["air_series"] = None
    return out


def run(args: argparse.Namespace) -> int:
    """Choose the notebook, inject the parameters, execute, write the HTML."""
    from bayestribo.cli._common import reading_kwargs
    from bayestribo.reports.notebooks import ReportError, run_report

    path = Path(args.path).resolve()
    notebook = notebook_for(path)
    params: dict[str, Any] = {}
    if notebook == "single_run":
        read_kwargs = reading_kwargs(args)
        params.update({"run_path": str(path), "read_kwargs": read_kwargs})
        if args.seed is not None:
            params["seed"] = args.seed
    else:
        if args.columns or args.length_unit or args.frequency or args.load or args.mass:
            raise ReportError(
                "--columns, --length-unit, --frequency, --load and --mass describe one run "
                "file; a campaign folder's runs need sidecars"
            )
        params["data_dir"] = str(path)
        params.update(campaign_selection(path))
        if args.seed is not None:
            params["campaign_seed"] = args.seed
    if args.figures is not None:
        params["figure_dir"] = str(args.figures.resolve())
    params.update(parse_params(args.param))
    out = args.out or Path(f"{path.stem or path.name}-report.html")
    print(f"running the {notebook} report on {path} ...", file=sys.stderr)
    run_report(notebook, params, html=out, executed=args.executed, hide_code=args.hide_code)
    print(f"report written to {out.resolve()}")
    if args.figures is not None:
        print(f"figures in {args.figures.resolve()}")
    return 0
