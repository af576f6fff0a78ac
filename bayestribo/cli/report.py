"""``bayestribo report``: a run or a campaign as one self-contained HTML report.

Runs the single-run notebook (for a run file) or the campaign notebook across loads (for
a folder) and renders it as one HTML page a reader can open offline: no code (unless
``--show-code``), figures embedded, equations rendered, a table of contents. The figures
are also written next to the HTML (``--figure-format pdf`` by default: vector graphics
for a paper).

A folder of recordings without sidecars (another rig's files, read as ``--columns`` and
the other reading options say) gets the real-data report: every recording, the rig as
the folder's ``README.md`` describes it, the fits as ``bayestribo fit`` makes them.

A campaign folder is reported with the fits of ``bayestribo campaign`` when there are any: PATH
itself may be the campaign's ``--out`` folder, or ``--campaign OUTDIR`` names it, or it
is found in ``PATH/bayestribo-campaign`` or ``./bayestribo-campaign``; without one every
run is fitted with the campaign's default seed, and the report says so.

Examples::

    bayestribo report data/runs/glycerol-N0.31-r1.csv --out report.html
    bayestribo report HarmOsc3.txt --columns t x --length-unit arbitrary --out osc3.html
    bayestribo campaign data/ --out results/ && bayestribo report results/ --out campaign.html
    bayestribo report data/ --out campaign.html --param repeats=[1] --figure-format svg
    bayestribo report ../shared/external-data/smorzamento-spring-disc --columns t x v ignore
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["campaign_selection", "fit_reasons", "notebook_for", "parse_params", "register"]

#: The notebooks shipped, each reachable with ``--notebook``.
NOTEBOOKS = ("single_run", "loads", "viscosity", "real_data", "acquisition")

#: File formats of the figures written next to the report.
FIGURE_FORMATS = ("png", "pdf", "svg")


def register(subparsers: Any) -> None:
    """Add the ``report`` sub-command."""
    from bayestribo.cli._common import add_reading_options
    from bayestribo.cli._spec import add_spec_options

    p = subparsers.add_parser(
        "report",
        help="HTML report of a run or a campaign folder, readable offline, figures as PDF",
        description=(
            "Run the report notebook on PATH and write it as one HTML file a reader can open "
            "offline (figures embedded, equations rendered, no code unless --show-code), "
            "with the figures also written next to it. A run file gets the single-run report "
            "(signals, energy decay, classical estimates, Bayesian fit, diagnostics, corner "
            "plot, Π with its predictive band, comparison of estimates, adequacy verdict); a "
            "folder gets the campaign report (per-run fits, forest plot, populations of "
            "repeats, ζ and μ_k against load, ζ_k and d_k), from the fits of `bayestribo "
            "campaign` when its results are found (PATH itself, --campaign, "
            "PATH/bayestribo-campaign or ./bayestribo-campaign); a folder of recordings "
            "without sidecars gets the real-data report (another rig's files, read as "
            "--columns and the other reading options say)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "path",
        metavar="PATH",
        nargs="?",
        help="run file, folder of runs, or a campaign's results folder (not needed by the "
        "acquisition notebook)",
    )
    p.add_argument(
        "--notebook",
        choices=NOTEBOOKS,
        help="the report to run: single_run (a run file), loads (a campaign across loads), "
        "viscosity (glycerol-water series against viscosity), real_data (a folder of "
        "recordings of another rig), acquisition (a simulated instrument, no PATH); "
        "default: single_run for a file, loads for a folder",
    )
    p.add_argument(
        "--out",
        type=Path,
        metavar="FILE.html|DIR",
        help="the report's HTML file, or a folder to write <PATH stem>-report.html into "
        "(default: <PATH stem>-report.html here); figures go beside it",
    )
    add_reading_options(p)
    add_spec_options(
        p,
        helps={
            "seed": "seed of the fits (default: the notebook's; a reused campaign keeps its own)"
        },
        defaults={"seed": None},
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="set a notebook parameter (VALUE a Python literal, e.g. max_steps=5000, "
        "repeats=[1]); checked against the parameter's type before anything runs; repeatable",
    )
    p.add_argument(
        "--figures",
        type=Path,
        metavar="DIR",
        help="folder of the figure files (default: <report stem>-figures next to the HTML)",
    )
    p.add_argument(
        "--figure-format",
        choices=FIGURE_FORMATS,
        default="pdf",
        help="file format of the figures written next to the report (pdf, svg: vector)",
    )
    p.add_argument(
        "--campaign",
        type=Path,
        metavar="OUTDIR",
        help="results of `bayestribo campaign` whose fits a folder's report reuses",
    )
    p.add_argument(
        "--refit",
        action="store_true",
        help="fit a folder's runs for the report even where campaign results exist",
    )
    p.add_argument(
        "--executed", type=Path, metavar="NOTEBOOK", help="also write the executed notebook"
    )
    p.add_argument("--show-code", action="store_true", help="include the notebook's code")
    p.add_argument("--hide-code", action="store_true", help=argparse.SUPPRESS)  # the default now
    p.set_defaults(handler=run)


def parse_params(items: list[str], specs: dict[str, Any] | None = None) -> dict[str, Any]:
    """``KEY=VALUE`` strings to a dict; VALUE a Python literal, else kept as a string.

    Parameters
    ----------
    items : list of str
        The ``--param`` values.
    specs : dict, optional
        The notebook's parameters (:func:`bayestribo.reports.notebooks.notebook_parameter_specs`):
        a VALUE for a ``str`` parameter is kept as written even if it reads as a number
        (``None`` for a ``str | None`` parameter is None).

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
            value = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            value = text
        spec = (specs or {}).get(key)
        keep_none = value is None and spec is not None and spec.type == "str | None"
        if spec is not None and not isinstance(value, str) and spec.type in ("str", "str | None"):
            # a number for a text parameter stays text ("0.0055"); None stays None
            value = None if keep_none else text
        out[key] = value
    return out


def notebook_for(path: Path) -> str:
    """The report a path asks for: ``"single_run"`` for a file, ``"loads"`` for a folder
    holding a campaign (a ``manifest.csv``, runs with sidecars, or the results of
    ``bayestribo campaign``), ``"real_data"`` for a folder of recordings without
    sidecars (another rig's files, read as ``--columns`` and the other reading options
    say).

    Raises
    ------
    ReportError
        If the path does not exist, or a folder holds neither a campaign nor a file of a
        format the package reads.
    """
    from bayestribo.campaign.results import is_campaign_folder
    from bayestribo.reports.notebooks import ReportError

    if path.is_file():
        return "single_run"
    if path.is_dir():
        has_runs = (
            (path / "manifest.csv").is_file()
            or any(f.with_suffix(".json").is_file() for f in path.rglob("*.csv"))
            or is_campaign_folder(path)
        )
        if has_runs:
            return "loads"
        if recordings_in(path):
            return "real_data"
        raise ReportError(
            f"{path}: a campaign folder needs a manifest.csv or run files (.csv) with "
            "their sidecars (.json), or the results of `bayestribo campaign`; a folder of "
            "another rig's recordings needs files of a format read here"
        )
    raise ReportError(f"{path}: no such run file or folder")


def recordings_in(folder: Path) -> list[str]:
    """Names of the files in ``folder`` (not below it) of a format the package reads."""
    from bayestribo.io.registry import registered_formats

    suffixes = {s for f in registered_formats().values() for s in f.suffixes}
    return [
        p.name for p in sorted(folder.iterdir()) if p.is_file() and p.suffix.lower() in suffixes
    ]


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


def _campaign_params(path: Path, args: argparse.Namespace) -> tuple[dict[str, Any], str]:
    """Parameters of the campaign notebook, and a line saying where the fits come from."""
    from bayestribo.campaign.results import (
        DEFAULT_SEED,
        find_campaign,
        is_campaign_folder,
        load_campaign,
    )
    from bayestribo.reports.notebooks import ReportError

    found = None
    if args.campaign is not None:
        if not is_campaign_folder(args.campaign):
            raise ReportError(
                f"--campaign {args.campaign}: no campaign results there (population.json and "
                "catalog.sqlite, as written by `bayestribo campaign DIR --out OUTDIR`)"
            )
        found = args.campaign.resolve()
    elif not args.refit:
        found = find_campaign(path)
    params: dict[str, Any] = {}
    if found is not None and not args.refit:
        campaign = load_campaign(found)
        if args.seed is not None and args.seed != campaign.seed:
            raise ReportError(
                f"--seed {args.seed}: the campaign in {found} was fitted with seed "
                f"{campaign.seed}; leave --seed out to report its fits, or add --refit"
            )
        params["campaign_dir"] = str(found)
        # the folders as typed: the report shows no path the reader did not give
        params["campaign_label"] = str(args.campaign or (args.path if found == path else found))
        if found != path:
            params["data_dir"] = str(path)
        else:
            params["_data_label"] = _runs_folder(list(campaign.paths.values()))
        series = {m.get("series") for m in campaign.metadata.values()}
        params.update({"series": None} if "glycerol" not in series else {})
        params.update({"air_series": None} if "air" not in series else {})
        return params, f"reusing the fits of the campaign in {found}"
    params["data_dir"] = str(path)
    params["campaign_seed"] = DEFAULT_SEED if args.seed is None else args.seed
    params.update(campaign_selection(path))
    return params, (
        f"no campaign results found: fitting every run with seed {params['campaign_seed']}"
        + (" (the default of `bayestribo campaign`)" if args.seed is None else "")
    )


def run(args: argparse.Namespace) -> int:
    """Choose the notebook, check the parameters, execute, write the HTML and figures."""
    from bayestribo.cli._spec import spec_from_args
    from bayestribo.reports.notebooks import (
        ReportError,
        inject_parameters,
        notebook_parameter_specs,
        read_notebook,
        run_report,
    )

    notebook = args.notebook
    if args.path is None:
        if notebook != "acquisition":
            raise ReportError(
                "PATH: give a run file or a campaign folder (only --notebook acquisition "
                "runs without one)"
            )
        path = Path("acquisition")
    else:
        path = Path(args.path).resolve()
        if notebook in (None, "single_run", "loads"):
            found = notebook_for(path)
            notebook = notebook or found
            if notebook == "loads" and found == "real_data":
                raise ReportError(
                    f"--notebook loads reports on a campaign folder; {path} holds recordings "
                    "without sidecars (their report: --notebook real_data)"
                )
            if (notebook == "single_run") != (found == "single_run"):
                wanted = "a run file" if notebook == "single_run" else "a folder"
                raise ReportError(f"--notebook {notebook} reports on {wanted}; {path} is not one")
        elif not path.is_dir():
            raise ReportError(f"--notebook {notebook} reports on a folder; {path} is not one")
    params: dict[str, Any] = {}
    where = ""
    if notebook in ("viscosity", "real_data", "acquisition"):
        params.update(_other_params(notebook, path, args))
    elif notebook == "single_run":
        # the fit's specification, as `bayestribo fit` takes it: one answer per question
        fit_kwargs = spec_from_args(args, "report").fit_kwargs(changed_only=True)
        reading = fit_kwargs.pop("read_options", {})
        params.update({"run_path": str(path), "read_kwargs": reading})
        if args.seed is not None:
            params["seed"] = args.seed
        fit_kwargs.pop("seed", None)
        for name in SINGLE_RUN_FIT:
            if name in fit_kwargs:
                params[name] = fit_kwargs.pop(name)
        if fit_kwargs:
            params["fit_kwargs"] = fit_kwargs
    else:
        if args.columns or args.length_unit or args.frequency or args.load or args.mass:
            raise ReportError(
                "--columns, --length-unit, --frequency, --load and --mass describe one run "
                "file; a campaign folder's runs need sidecars"
            )
        # the campaign's fits are `bayestribo campaign`'s, made with its specification
        spec_from_args(
            args,
            "report",
            uses=("seed",),
            why="a campaign folder's report reuses or makes the fits of `bayestribo "
            "campaign`: give fit options there, then report its results",
        )
        campaign_params, where = _campaign_params(path, args)
        params.update(campaign_params)
        # the data folder as typed (or, for a campaign's results, where its runs are, from
        # here): the commands the text names work as shown
        params["data_label"] = params.pop("_data_label", None) or str(args.path)
        if _has_water_series(path):
            where += (
                f"\nthe campaign also holds glycerol-water runs: section 6 reports them; "
                f"their report of its own against viscosity is "
                f"`bayestribo report {params['data_label']} --notebook viscosity`"
            )
    default_name = f"{path.stem or path.name}-report.html"
    out = args.out or Path(default_name)
    if out.is_dir() or (args.out is not None and out.suffix.lower() not in (".html", ".htm")):
        # --out names a folder, as for every other command
        out = out / default_name
    out.parent.mkdir(parents=True, exist_ok=True)
    figures = args.figures or out.with_name(f"{out.stem}-figures")
    params["figure_dir"] = str(figures.resolve())
    params["figure_format"] = args.figure_format
    nb = read_notebook(notebook)
    params.update(parse_params(args.param, notebook_parameter_specs(nb)))
    inject_parameters(nb, params)  # every name and type checked before anything runs
    print(f"running the {notebook} report on {path} ...", file=sys.stderr)
    if where:
        print(where, file=sys.stderr)
    with tempfile.TemporaryDirectory() as tmp:
        if notebook in ("single_run", "real_data") and not params.get("summary_path"):
            params["summary_path"] = str(Path(tmp) / "summary.json")
        run_report(
            notebook,
            params,
            html=out,
            executed=args.executed,
            show_code=args.show_code,
        )
        reasons = []
        summary = Path(params["summary_path"]) if params.get("summary_path") else None
        if summary is not None and summary.is_file():
            record = json.loads(summary.read_text())
            if notebook == "single_run":
                reasons = fit_reasons(record)
            elif notebook == "real_data":
                reasons = recordings_reasons(record)
    print(f"report written to {out.resolve()}")
    print(f"figures ({args.figure_format}) in {figures.resolve()}")
    for reason in reasons:
        print(f"bayestribo report: {reason}", file=sys.stderr)
    # the exit status of `bayestribo fit` on the same run (README, Exit status)
    return 1 if reasons else 0


def _runs_folder(paths: list[Any]) -> str | None:
    """The folder of a campaign's runs as a reader types it: the runs' common folder, or
    the one above it holding the manifest, relative to here when below here."""
    import os

    if not paths:
        return None
    folder = Path(os.path.commonpath([str(Path(p).resolve().parent) for p in paths]))
    for candidate in (folder, *list(folder.parents)[:2]):
        if (candidate / "manifest.csv").is_file():
            folder = candidate
            break
    here = Path.cwd().resolve()
    return str(folder.relative_to(here)) if folder.is_relative_to(here) else str(folder)


def _has_water_series(folder: Path) -> bool:
    """Whether a campaign folder's manifest lists runs with a water fraction."""
    import csv

    manifest = folder / "manifest.csv"
    if not manifest.is_file():
        return False
    with manifest.open(newline="", encoding="utf-8") as fh:
        return any(row.get("series") == "glycerol-water" for row in csv.DictReader(fh))


def _other_params(notebook: str, path: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Parameters of the viscosity, real-data and acquisition notebooks from the options."""
    from bayestribo.cli._spec import spec_from_args
    from bayestribo.reports.notebooks import ReportError

    real = notebook == "real_data"
    if args.campaign is not None:
        raise ReportError(
            f"--campaign: not an option of the {notebook} report; give its parameters with "
            "--param KEY=VALUE"
        )
    if real:
        # a folder of recordings is read and fitted as `bayestribo fit` reads and fits one
        fit_kwargs = spec_from_args(args, "report").fit_kwargs(changed_only=True)
        reading = fit_kwargs.pop("read_options", {})
        fit_kwargs.pop("seed", None)
    else:
        fit_kwargs = _folder_fit_kwargs(args, notebook)
    params: dict[str, Any] = {}
    if notebook == "viscosity":
        params["data_dir"] = str(path)
        if args.seed is not None:
            params["campaign_seed"] = args.seed
    elif notebook == "real_data":
        files = recordings_in(path)
        if not files:
            raise ReportError(f"{path}: no recordings of a format read in this folder")
        _check_reading(path / files[0], reading, guessed=args.notebook is None)
        params.update({"data_dir": str(path), "files": files, "fit_files": files})
        if reading:  # how this rig's files are read (default: the AppStat text files)
            params["read_kwargs"] = reading
        params["check_files"] = files[:1]
        if args.seed is not None:
            params["seed"] = args.seed
    elif args.seed is not None:
        params["seed"] = args.seed
    if fit_kwargs:
        params["fit_kwargs"] = fit_kwargs
    return params


#: The single-run notebook's parameters that are keywords of ``fit`` (the others of a
#: specification go in its ``fit_kwargs``).
SINGLE_RUN_FIT = (
    "model",
    "n_walkers",
    "n_ensembles",
    "max_steps",
    "grid_points",
    "law",
    "discrepancy",
    "notch",
    "skip_oscillations",
)


def _folder_fit_kwargs(args: argparse.Namespace, notebook: str) -> dict[str, Any]:
    """The fit specification's options given to a report whose runs have sidecars
    (viscosity, acquisition), as the notebook's ``fit_kwargs`` (the seed is the
    notebook's own parameter); reading options are refused: the runs' sidecars say how
    they are read."""
    from bayestribo.cli._spec import spec_from_args
    from bayestribo.inference.spec import spec_fields

    uses = [f.name for f in spec_fields() if f.name not in ("read_options", "restoring")]
    why = f"the {notebook} report's runs are read as their sidecars say"
    fit_kwargs = spec_from_args(args, "report", uses=uses, why=why).fit_kwargs(changed_only=True)
    fit_kwargs.pop("seed", None)
    return fit_kwargs


def _check_reading(path: Path, reading: dict[str, Any], *, guessed: bool = False) -> None:
    """Read one recording of a folder as the report will, before any kernel starts;
    ``guessed``: the folder was taken for recordings because it holds no campaign.

    Raises
    ------
    ReportError
        Naming the file and what the reader said, with the options that tell it how.
    """
    import warnings

    from bayestribo.errors import BayestriboError
    from bayestribo.io import read_run
    from bayestribo.reports.notebooks import ReportError

    options = reading or {
        "columns": ["time_s", "displacement_m"],
        "metadata": {"length_unit": "arbitrary"},
    }
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the report says them, once per file
            read_run(path, **options)
    except BayestriboError as exc:
        campaign = (
            f"{path.parent} holds no campaign (a manifest.csv or run files (.csv) with their "
            "sidecars (.json), or the results of `bayestribo campaign`), and its recordings "
            "do not read as given: "
            if guessed
            else ""
        )
        raise ReportError(
            f"{campaign}{exc}; say how this rig's files are read with --columns (e.g. "
            "--columns t x v ignore), --length-unit and the other reading options"
        ) from None


def recordings_reasons(record: dict[str, Any]) -> list[str]:
    """What is not right in a folder of recordings' report record (``summary_path`` of
    the real-data report), recording by recording, as `bayestribo fit` would exit 1 for
    each: :func:`fit_reasons` of each fit, and a law comparison (``--law auto``) that
    finds no law adequate; empty when all is right."""
    out = []
    adequacy = record.get("adequacy") or {}
    for name, fit in (record.get("fits") or {}).items():
        reasons = fit_reasons({"fit": fit, "adequacy": adequacy.get(name)})
        comparison = (fit or {}).get("law_comparison") or {}
        if comparison.get("adequate") is False:
            reasons.append("no law compared describes the recording (law_comparison)")
        out += [f"{name}: {reason}" for reason in reasons]
    return out


def fit_reasons(record: dict[str, Any]) -> list[str]:
    """What is not right in a single run's report record (``summary_path``), as
    `bayestribo fit` would exit 1 for it: not converged, a posterior on a prior bound,
    a misfit the intervals do not carry, or a model check that finds the law not
    adequate; empty when all is right."""
    from bayestribo.inference.pipeline import MISFIT_P

    fit = record.get("fit") or {}
    diag = fit.get("diagnostics") or {}
    out = []
    if not diag.get("converged", False):
        out.append("the sampler did not converge: " + "; ".join(diag.get("reasons", [])))
    for entry in diag.get("at_prior_bound") or []:
        out.append(f"{entry.get('parameter')} piles on its prior's bound: not a measurement")
    shape = (diag.get("shape_departure") or {}).get("p_value")
    white = diag.get("misfit_p")
    discrepancy = bool({"log10_discrepancy", "log10_shape"} & set(fit.get("parameters") or {}))
    if (shape is not None and shape < MISFIT_P) or (
        not discrepancy and white is not None and white < MISFIT_P
    ):
        out.append(f"the law {fit.get('law')} misfits the run beyond its noise")
    adequacy = record.get("adequacy")
    if adequacy is not None and adequacy.get("adequate") is False:
        out.append(adequacy.get("verdict", "the model checks find the law not adequate"))
    return out
