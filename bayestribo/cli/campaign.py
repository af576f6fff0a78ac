"""``bayestribo campaign``: fit every run of a folder and report across runs.

Examples::

    bayestribo campaign data/ --out results/
    bayestribo campaign data/runs --by load_N --json
    bayestribo campaign data/ --dask-scheduler tcp://10.0.0.5:8786
    bayestribo campaign data/ --law viscous+quadratic
    bayestribo campaign data/ --law auto        # or --compare-laws

Fits each run (skipping runs the catalog holds a fit of, with the same data and
settings), writes each run's NetCDF, the populations per group with the between-run σ
of the law's quantities (ζ and μ_k in the paper's law), ζ₀ from the runs without
contact, ζ_k and d_k, the load trends (JSON and CSV tables) and figures. With
``--law auto`` (or ``--compare-laws``) every run compares the laws, each group of
repeats takes one law chosen from all its runs (:mod:`bayestribo.campaign.laws`), the
runs whose own verdict differs are named and fitted again in their group's law, and
``laws.csv`` lists each run's verdict and its group's law.
"""

from __future__ import annotations

import argparse
import csv
import functools
import io
import json
import os
import sys
import time
from contextlib import nullcontext
from pathlib import Path
from typing import Any

from bayestribo._plural import count
from bayestribo.cli._common import add_reading_options
from bayestribo.cli._spec import add_spec_options, spec_from_args
from bayestribo.cli._watch import add_watch_options, check_watch_options, run_watch

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add the ``campaign`` sub-command."""
    p = subparsers.add_parser(
        "campaign",
        help="fit every run of a folder; populations, load trends, ζ₀, figures",
        description=(
            "Fit every run (a file of any format read, with its JSON sidecar) under DIR and "
            "its sub-folders in parallel, record the "
            "fits in an SQLite catalog (re-runs skip runs fitted with the same data and "
            "settings), infer the population of repeats per group (mean and between-run "
            "σ of ζ and μ_k), ζ₀ from the runs without contact, ζ_k = ζ - ζ₀, d_k and the "
            "trends against load, and write JSON, CSV and figures to OUTDIR."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("dir", metavar="DIR", help="folder searched recursively for run files")
    p.add_argument(
        "--by",
        default="lubricant,water_mass_fraction,load_N",
        help="comma-separated metadata keys grouping the runs with contact "
        "(keys no run has are left out)",
    )
    p.add_argument(
        "--out",
        default="bayestribo-campaign",
        metavar="OUTDIR",
        help="folder of the results: fits/, catalog, JSON and CSV tables, figures/",
    )
    p.add_argument("--catalog", help="results catalog (default OUTDIR/catalog.sqlite)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--workers", type=int, help="processes (default: one per core)")
    p.add_argument("--dask-scheduler", metavar="ADDRESS", help="fit on this Dask scheduler instead")
    p.add_argument("--refit", action="store_true", help="fit runs already in the catalog")
    p.add_argument(
        "--population-steps",
        type=int,
        default=10_000,
        help="ceiling on the population sampler's steps (it stops earlier once converged)",
    )
    p.add_argument("--prob", type=float, default=0.95, help="credible-interval probability")
    p.add_argument(
        "--law-free",
        action="store_true",
        help="also compare the law-free ΔE at common swings across runs (populations and "
        "trends; on with --law auto)",
    )
    p.add_argument(
        "--against",
        default="load_N",
        metavar="KEY",
        help="numeric sidecar key the trends are inferred against (a series' runs at two "
        "or more values of it; e.g. temperature_C)",
    )
    p.add_argument(
        "--compare-laws",
        action="store_true",
        help="choose one law per group of repeats from the runs' law comparisons "
        "(the same as --law auto; laws.csv)",
    )
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    add_reading_options(p)
    add_spec_options(
        p,
        helps={"seed": "campaign seed: each run's seed derives from it and the run's identity"},
    )
    p.add_argument("--quiet", action="store_true", help="no progress line")
    add_watch_options(p)
    p.set_defaults(handler=run)


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """A table, written whole or not at all (a temporary file renamed into place)."""
    from bayestribo.campaign.lock import write_atomic

    text = io.StringIO(newline="")
    if rows:
        # every column of every row (runs fitted in several laws have other quantities)
        fields = list(dict.fromkeys(key for row in rows for key in row))
        writer = csv.DictWriter(text, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    write_atomic(path, text.getvalue())


def _run_rows(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for r in runs:
        row = {k: v for k, v in r.items() if not isinstance(v, dict)}
        for p, s in r.items():
            if isinstance(s, dict) and "median" in s:
                row[f"{p}_median"] = s["median"]
                row[f"{p}_low"], row[f"{p}_high"] = s["interval"]
        rows.append(row)
    return rows


#: How grouping keys read on the terminal: a value alone, or with its unit.
_KEY_WORDS = {
    "lubricant": "{}",
    "series": "{}",
    "water_mass_fraction": "water {:.3g} %",
    "load_N": "{:g} N",
    "kinematic_viscosity_mm2_per_s": "{:g} mm²/s",
}
_COVARIATES = {"load_N": ("load", "N"), "kinematic_viscosity_mm2_per_s": ("viscosity", "mm²/s")}


def _words(label: Any) -> str:
    """A group label (``lubricant=glycerol,load_N=0.07``) as ``glycerol · 0.07 N``."""
    text = str(label)
    if text in ("all", "pooled", ""):
        return text or "all"
    parts = []
    for item in text.split(","):
        key, sep, value = item.partition("=")
        if not sep:
            parts.append(item)
            continue
        form = _KEY_WORDS.get(key, f"{key} {{}}")
        try:
            if "g}" in form:  # a number, water as a percentage
                number = float(value) * (100.0 if key == "water_mass_fraction" else 1.0)
                parts.append(form.format(number))
            else:
                parts.append(form.format(value))
        except ValueError:
            parts.append(f"{key} {value}")
    return " · ".join(parts)


def _symbol(analysis: Any, name: str) -> str:
    """A quantity as printed: its symbol, with its unit where it has one."""
    q = getattr(analysis, "quantities", {}).get(name) or (
        getattr(analysis, "dissipation_quantities", {}).get(name, {})
    )
    symbol = str(q.get("symbol") or name)
    unit = str(q.get("unit") or "1")
    return symbol if unit in ("1", "-") else f"{symbol} [{unit}]"


def _interval(median: float, low: float, high: float) -> str:
    # the digits the interval supports, as the reports write it (the digit rule)
    from bayestribo.summary import interval_text

    return interval_text(median, low, high)


def _law_lines(groups: dict[str, Any] | None) -> list[str]:
    """The law of each group of repeats, and the runs whose own verdict differs."""
    if not groups:
        return []
    lines = ["Law of each group of repeats (chosen from all its runs' law comparisons):"]
    for label, g in groups.items():
        law = g["law"] or "none"
        how = "" if g["decided"] else " (most runs' verdict: no law compared in every run)"
        holds = "" if g["adequate"] else "; it misfits some runs: see each run's fit"
        lines.append(f"    {_words(label)}: {law}{how}{holds}")
        for run in g["disagree"]:
            lines.append(
                f"        {run} alone chose {g['verdicts'].get(run) or 'no law'}; "
                f"fitted again in {law}"
            )
    lines.append("")
    return lines


def _text(
    analysis: Any, failures: list[dict[str, str]], groups: dict[str, Any] | None = None
) -> str:
    """The campaign's answer on the terminal, in at most 100 columns."""
    from bayestribo.summary import probability_text

    percent = f"{100 * analysis.prob:g} %"
    lines = [
        *_law_lines(groups),
        f"Populations of repeats: the mean and σ (the spread between repeats) of each "
        f"group,\nas posterior median [{percent} credible interval].",
    ]
    laws = getattr(analysis, "laws", {}) or {}
    if len(laws) > 1:
        listing = ", ".join(f"{law} ({count(len(runs), 'run')})" for law, runs in laws.items())
        lines.append(f"Laws fitted: {listing}; runs of different laws are grouped apart.")
    elif laws and next(iter(laws)) != "viscous+coulomb":
        lines.append(f"Law fitted: {next(iter(laws))}.")
    for name, why in (getattr(analysis, "left_out", {}) or {}).items():
        lines.append(f"Not compared across runs: {name}: {why}.")
    for name, q in (getattr(analysis, "quantities", {}) or {}).items():
        if q.get("at_own_amplitude"):
            lines.append(
                f"{q.get('symbol', name)} is at each run's own initial amplitude: runs "
                "released from other swings compare it at other swings."
            )
    titles = {"pooled over loads": " (pooled over loads)", "ΔE (law-free)": ", law-free ΔE"}
    rows = analysis.group_rows()
    trends = analysis.trend_rows()
    width = max([4, *(len(_symbol(analysis, r["parameter"])) for r in [*rows, *trends])])
    current = None
    for r in rows:
        words = _words(r["group"])
        if r["kind"] == "no contact":
            group = "no contact (ζ₀)" + ("" if words == "all" else f": {words}")
        else:
            group = f"{words}{titles.get(r['kind'], '')}"
        group += f", {count(r['n_runs'], 'run')}"
        if group != current:
            lines.append("")
            lines.append(group)
            current = group
        symbol = _symbol(analysis, r["parameter"])
        mean = _interval(r["mean_median"], r["mean_low"], r["mean_high"])
        sigma = _interval(r["sigma_median"], r["sigma_low"], r["sigma_high"])
        lines.append(f"    {symbol:{width}s} mean {mean:34s} σ {sigma}")
    covariates = list(dict.fromkeys(r["covariate"] for r in trends))
    for covariate in covariates:
        name, unit = _COVARIATES.get(covariate, (covariate, "unit"))
        lines.append("")
        lines.append(
            f"Trends against {name}: slope per {unit}, median [{percent} interval], and "
            "the probability that it is positive."
        )
        current = None
        for r in trends:
            if r["covariate"] != covariate:
                continue
            series = _words(str(r["series"]).split(":", 1)[-1])
            if series != current:
                lines.append(series)
                current = series
            symbol = _symbol(analysis, r["parameter"])
            slope = _interval(r["slope_median"], r["slope_low"], r["slope_high"])
            said = probability_text(r["prob_positive"])  # "> 0.999", never "1.000"
            positive = f"P(slope > 0) {said}" if said[0] in "<>" else f"P(slope > 0) = {said}"
            lines.append(f"    {symbol:{width}s} {slope:40s} {positive}")
    unconverged = [r["run_id"] for r in analysis.runs if not r.get("converged", True)]
    if failures or analysis.excluded or unconverged or not analysis.converged:
        lines.append("")
    for f in failures:
        lines.append(f"FAILED {f['run']}: {f['error']}")
    for e in analysis.excluded:
        lines.append(f"EXCLUDED {e['run']}: {e['reason']}")
    if unconverged:
        lines.append(
            f"NOT CONVERGED: the fits of {', '.join(map(str, unconverged))}; raise --max-steps"
        )
    elif not analysis.converged:
        lines.append(
            "NOT CONVERGED: a population sampler did not converge; raise --population-steps"
        )
    return "\n".join(lines)


def _group_laws(
    args: argparse.Namespace,
    paths: list[Path],
    outcomes: list[Any],
    catalog: Path,
    out: Path,
    folder: Path,
    fit_kwargs: dict[str, Any],
    executor: Any,
    keep: Any,
) -> tuple[list[Any], dict[str, Any]]:
    """One law per group of repeats (``--law auto``): choose it from the runs' law
    comparisons, fit again in it the runs whose own verdict differs, and return the
    outcomes to analyse with the groups' choices."""
    from bayestribo.campaign.fitting import fit_catalogued
    from bayestribo.campaign.laws import group_laws

    by = tuple(k for k in args.by.split(",") if k)
    fitted = [o.result for o in outcomes if o.ok]
    groups, law_of_run = group_laws(fitted, by)
    index = {o.name: i for i, o in enumerate(outcomes)}
    again: dict[str, list[int]] = {}
    for o in outcomes:
        if o.ok and law_of_run.get(o.name) and law_of_run[o.name] != (o.result.law or ""):
            again.setdefault(law_of_run[o.name], []).append(index[o.name])
    outcomes = list(outcomes)
    for law, rows in again.items():
        if not args.quiet:
            names = ", ".join(outcomes[i].name for i in rows)
            print(f"bayestribo campaign: fitting again in {law}: {names}", file=sys.stderr)
        refits = fit_catalogued(
            [paths[i] for i in rows],
            catalog,
            out / "fits" / "group-law" / law,
            executor,
            campaign_seed=fit_kwargs["spec"].seed,
            refit=args.refit,
            max_workers=args.workers,
            progress=not args.quiet,
            root=folder,
            keep=keep,
            spec=fit_kwargs["spec"].replace(law=law),
        )
        for i, refit in zip(rows, refits, strict=True):
            outcomes[i] = refit
    return outcomes, {label: g.to_dict() for label, g in groups.items()}


def _law_rows(groups: dict[str, Any]) -> list[dict[str, Any]]:
    """laws.csv: each run's own verdict and its group's law."""
    rows = []
    for label, g in groups.items():
        for run in g["runs"]:
            rows.append(
                {
                    "run": run,
                    "group": label,
                    "verdict": g["verdicts"].get(run),
                    "group_law": g["law"],
                    "agrees": g["verdicts"].get(run) == g["law"],
                    "group_best": g["best"],
                    "group_law_holds": g["adequate"],
                    "decided": g["decided"],
                }
            )
    return rows


def run_files(
    folder: Path, file_format: str | None = None, exclude: Path | None = None
) -> list[Path]:
    """The run files under ``folder`` and its sub-folders: files of a registered format
    (of ``file_format`` only, when given) with a JSON sidecar beside them, outside
    ``exclude`` (the campaign's own output folder)."""
    from bayestribo.io.registry import get_format, registered_formats

    formats = [get_format(file_format)] if file_format else registered_formats().values()
    suffixes = {s for f in formats for s in f.suffixes}
    skip = None if exclude is None else Path(os.path.abspath(exclude))
    return sorted(
        p
        for p in folder.rglob("*")
        if p.is_file()
        and p.suffix.lower() in suffixes
        and p.with_suffix(".json").is_file()
        and (skip is None or not Path(os.path.abspath(p)).is_relative_to(skip))
    )


def run(args: argparse.Namespace) -> int:
    """Find the runs, fit them, analyse, write the outputs (one writer per --out)."""
    from bayestribo.campaign.lock import FolderLock
    from bayestribo.errors import BayestriboError

    check_watch_options(args)
    if args.watch:
        return run_watch(args)
    folder = Path(args.dir)
    if not folder.is_dir():
        raise BayestriboError(f"DIR: {folder} is not a folder")
    paths = run_files(folder, getattr(args, "format", None), exclude=Path(args.out))
    if not paths:
        raise BayestriboError(
            f"DIR: no run files (a file of a format read, with its JSON sidecar) under {folder}"
        )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from bayestribo._workers import terminate_as_interrupt

    with terminate_as_interrupt(), FolderLock(out) as lock:
        if lock.took_over is not None and not args.quiet:
            print(
                f"bayestribo campaign: {out}: took over the lock of a campaign that no longer "
                f"runs (process {lock.took_over.get('pid')})",
                file=sys.stderr,
            )
        return _run_locked(args, folder, paths, out)


def _run_locked(args: argparse.Namespace, folder: Path, paths: list[Path], out: Path) -> int:
    """:func:`run` with the output folder locked."""
    from bayestribo._workers import process_pool
    from bayestribo.campaign.analysis import analyse_campaign
    from bayestribo.campaign.digest import digest_fit
    from bayestribo.campaign.fitting import dask_executor, fit_catalogued
    from bayestribo.campaign.lock import write_atomic
    from bayestribo.errors import BayestriboError

    catalog = Path(args.catalog) if args.catalog else out / "catalog.sqlite"
    spec = spec_from_args(args, "campaign")
    if args.compare_laws:
        if spec.law not in (None, "auto"):
            raise BayestriboError(
                f"--compare-laws chooses the law of each group (it is --law auto); "
                f"it cannot be given with --law {spec.law}"
            )
        spec = spec.replace(law="auto")
    # every run fitted as the specification says (recorded with each fit); the run's own
    # seed derives from the campaign seed, the specification's
    fit_kwargs: dict[str, Any] = {"spec": spec}
    keep = functools.partial(digest_fit, prob=args.prob, seed=spec.seed)
    context = dask_executor(args.dask_scheduler) if args.dask_scheduler else nullcontext(None)
    with context as executor:
        outcomes = fit_catalogued(
            paths,
            catalog,
            out / "fits",
            executor,
            campaign_seed=spec.seed,
            refit=args.refit,
            max_workers=args.workers,
            progress=not args.quiet,
            root=folder,
            # the analysis needs a digest of each fit; the fits stay on disk
            keep=keep,
            **fit_kwargs,
        )
        laws = None
        if spec.law == "auto":
            outcomes, laws = _group_laws(
                args, paths, outcomes, catalog, out, folder, fit_kwargs, executor, keep
            )
    failures = [{"run": o.name, "error": str(o.error)} for o in outcomes if not o.ok]
    fitted = [o.result for o in outcomes if o.ok]
    if not fitted:
        listing = "; ".join(f"{f['run']}: {f['error']}" for f in failures)
        raise BayestriboError(f"no run of {folder} could be fitted ({listing})")
    by = tuple(k for k in args.by.split(",") if k)
    start = time.perf_counter()

    def say(message: str) -> None:
        if not args.quiet:
            elapsed = time.perf_counter() - start
            print(f"bayestribo campaign: [{elapsed:5.0f} s] {message}", file=sys.stderr)

    workers = args.workers or os.cpu_count() or 1
    pool = process_pool(workers) if workers > 1 else nullcontext(None)
    with pool as executor:  # the populations' groups and the trends side by side
        analysis = analyse_campaign(
            fitted,
            by,
            covariate=args.against,
            dissipation=args.law_free or spec.law == "auto",
            prob=args.prob,
            seed=spec.seed,
            max_steps=args.population_steps,
            progress=say,
            executor=executor,
        )
    report = {
        **analysis.to_dict(),
        "failures": failures,
        "n_runs": len(paths),
        "n_cached": sum(o.cached for o in outcomes),
        "catalog": str(catalog),
        "settings": {
            "seed": spec.seed,
            "fit": spec.changed(),
            "spec": spec.to_dict(),
            "population_steps": args.population_steps,
            "against": args.against,
        },
    }
    if laws is not None:
        report["group_laws"] = laws
        _write_csv(out / "laws.csv", _law_rows(laws))
    write_atomic(out / "population.json", json.dumps(report, indent=2, default=str) + "\n")
    _write_csv(out / "groups.csv", analysis.group_rows())
    _write_csv(out / "trends.csv", analysis.trend_rows())
    failed_rows = [{"run_id": f["run"], "status": f"failed: {f['error']}"} for f in failures]
    _write_csv(out / "runs.csv", _run_rows(analysis.runs) + failed_rows)
    if not args.no_figures:
        from bayestribo.campaign.figures import save_figures

        save_figures(analysis, out / "figures")
    if args.json:
        json.dump(report, sys.stdout, indent=2, default=str)
        sys.stdout.write("\n")
    else:
        print(_text(analysis, failures, laws))
    # The exit status rule of every command (README): 0 all good, 1 something
    # unconverged, failed or excluded, 2 nothing usable (raised above).
    clean = not failures and not analysis.excluded and analysis.converged
    return 0 if clean else 1
