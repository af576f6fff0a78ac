"""``bayestribo demo``: the quick start. Fit a bundled run and the bundled campaign.

Fits the bundled (simulated) glycerol run ``glycerol-N0.31-r1`` and a reduced bundled
campaign across the five loads (one repeat per load and one run in air; ``--full`` for
all of them), prints the credible intervals of ζ and μ_k next to the paper's values,
and writes two HTML reports, their figures (PNG) and results (JSON) into an output
folder: ``--out``, by default ``demo/`` in the user's cache folder
(``$XDG_CACHE_HOME/bayestribo/demo``, else ``~/.cache/bayestribo/demo``), never the
current folder, which may be a source checkout. Where it went is printed at the end.

``--full`` also fits the bundled oil series (:data:`DRAG_SERIES`: viscous damping,
quadratic drag and Coulomb friction, three loads, three repeats) with ``law="auto"``:
each run compares the dissipation laws, and the third report gives the populations
and load trends over the chosen law's own quantities (ζ, μ_k and c₂ [kg/m]), printed
next to the values the series was simulated with. It is left out of the default demo:
its nine law comparisons would make the demo half as long again.

The numbers printed are read from the results the reports wrote (``single-run.json``,
``campaign.json``) and shown as the reports show them: a run's posterior mean, a
population's posterior median, each with its 95 % interval in the digits it supports
(:func:`bayestribo.summary.interval_text`).

The exit status is 0 when every sampler converged (the run's, each run's of the
campaign and every population's and trend's), 1 otherwise, with what did not converge
named on stderr. ``--quick`` cuts the population samplers short: its status is 1.

The bundled campaign is ``data/`` of a source checkout; without it the campaign is
simulated again (:func:`bayestribo.synthetic.campaign.write_campaign`, the same fixed seed,
identical files) into a cache folder.

Examples::

    bayestribo demo
    bayestribo demo --out demo-output --full
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from bayestribo._plural import count

__all__ = [
    "DEMO_RUN",
    "DRAG_SERIES",
    "PAPER",
    "campaign_folder",
    "default_out",
    "drag_lines",
    "register",
    "summary_lines",
    "unconverged",
]

#: The bundled run of the single-run report.
DEMO_RUN = "glycerol-N0.31-r1"
#: The paper's glycerol values (section 3.1): mean and standard deviation of repeats.
PAPER = {"zeta": (0.0236, 0.0012), "mu_k": (0.0294, 0.0036)}
#: Ceiling on the population samplers' steps when each load has one repeat (see run).
SINGLE_RUN_GROUP_STEPS = 40_000
#: Ceiling on the population samplers' steps with --quick (they do not converge).
QUICK_STEPS = 600
#: The bundled series whose runs follow a law with drag (fitted with law="auto", --full).
DRAG_SERIES = "oil"


def register(subparsers: Any) -> None:
    """Add the ``demo`` sub-command."""
    p = subparsers.add_parser(
        "demo",
        help="fit a bundled run and the bundled campaign; reports, figures, intervals",
        description=(
            "Fit the bundled simulated run glycerol-N0.31-r1 and the bundled glycerol "
            "campaign across loads (one repeat per load and one run in air, or all runs "
            "with --full), print the 95 % credible intervals of ζ and μ_k next to the "
            "paper's values (--full: and the oil series, whose runs follow a law with drag, "
            "with the law compared per run and its own quantities' populations), and "
            "write HTML reports, figures and JSON results to --out "
            f"(default: {default_out()}, the user's cache folder; printed at the end). "
            "Exit status 1, naming what, when a sampler did not converge (the run's, a "
            "campaign run's, a population's or a trend's)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        default=default_out(),
        help="output folder; by default demo/ in the user's cache folder ($XDG_CACHE_HOME/"
        "bayestribo, else ~/.cache/bayestribo), never the current folder",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--quick",
        action="store_true",
        help="a fast check of the pipeline: two loads, no run in air, no adequacy checks, "
        f"coarser Π grids, population samplers cut at {QUICK_STEPS} steps (they do not "
        "converge: exit status 1)",
    )
    size.add_argument(
        "--full",
        action="store_true",
        help="every glycerol run (3 repeats × 5 loads) and air run, and the oil series "
        "(3 repeats × 3 loads) with the dissipation law chosen per run (law auto)",
    )
    p.add_argument(
        "--show-code", action="store_true", help="include the notebooks' code in the reports"
    )
    p.set_defaults(handler=run)


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "bayestribo"


def default_out() -> Path:
    """Where the demo writes without ``--out``: ``demo/`` in the user's cache folder
    (``$XDG_CACHE_HOME/bayestribo``, else ``~/.cache/bayestribo``)."""
    return _cache_dir() / "demo"


def campaign_folder(cache: Path | None = None) -> tuple[Path, str]:
    """The bundled campaign folder, simulating it into ``cache`` when ``data/`` is absent.

    Returns
    -------
    (Path, str)
        The folder (with ``manifest.csv``) and where it came from.
    """
    from bayestribo.reports.notebooks import bundled_data_dir
    from bayestribo.synthetic.campaign import CAMPAIGN_SEED, write_campaign

    bundled = bundled_data_dir()
    if bundled is not None:
        return bundled, "bundled"
    folder = (cache or _cache_dir()) / f"campaign-{CAMPAIGN_SEED}"
    if not (folder / "manifest.csv").is_file():
        print(f"simulating the bundled campaign into {folder} ...", file=sys.stderr)
        write_campaign(folder)
        return folder, "simulated now"
    return folder, "simulated earlier (cache)"


def _interval(summary: Mapping[str, Any], centre: str = "mean") -> str:
    """``centre [low, high]`` in the digits the interval supports, as the reports write
    it (:func:`bayestribo.summary.interval_text`)."""
    from bayestribo.summary import interval_text

    return interval_text(summary[centre], *summary["interval"])


def summary_lines(single: dict[str, Any], campaign: dict[str, Any]) -> list[str]:
    """The printed comparison: the run, the campaign's population and the paper, each
    number as the reports show it (a run's posterior mean, a population's posterior
    median)."""
    fit = single["fit"]["parameters"]
    # (label, cells) of the table's rows; None for a line of text
    rows: list[tuple[str, list[str] | None]] = [("", ["ζ", "μ_k"])]
    converged = single["fit"]["diagnostics"].get("converged", False)
    rows.append(
        (
            f"run {single['name']}: posterior mean [95 % credible interval]"
            + ("" if converged else "  (SAMPLER NOT CONVERGED: do not use)"),
            None,
        )
    )
    rows.append(("  Bayesian fit", [_interval(fit[p]) if p in fit else "-" for p in PAPER]))
    true = single.get("true") or {}
    if true:
        rows.append(
            (
                "  true value (simulated run)",
                [f"{true[p]:.6g}" if p in true else "-" for p in PAPER],
            )
        )
    runs = campaign.get("runs") or {}
    stuck = sorted(n for n, r in runs.items() if not r["diagnostics"].get("converged", False))
    failed = sorted(campaign.get("failed") or {})
    pooled = (campaign.get("population") or {}).get("pooled")
    if stuck or failed:
        rows.append(
            (f"campaign: left out of the population: not converged {stuck}, failed {failed}", None)
        )
    if pooled:
        params = pooled["parameters"]
        ok = pooled.get("diagnostics", {}).get("converged", True)
        rows.append(
            (
                f"campaign, {count(pooled['n_runs'], 'run')} across loads: population, posterior "
                "median "
                "[95 % credible interval]"
                + ("" if ok else "  (SAMPLER NOT CONVERGED: do not use)"),
                None,
            )
        )
        for label, key in (("  mean", "mean"), ("  between-run σ", "sigma")):
            rows.append((label, [_interval(params[p][key], "median") for p in PAPER]))
    rows.append(("paper, glycerol (mean, σ)", [f"{m} (σ {s})" for m, s in PAPER.values()]))
    w = max(len(c) for _, cells in rows if cells for c in cells) + 2
    first = max(len(label) for label, cells in rows if cells is not None) + 2
    return [
        label
        if cells is None
        else (f"{label:<{first}}" + "".join(f"{c:<{w}}" for c in cells)).rstrip()
        for label, cells in rows
    ]


def drag_lines(drag: Mapping[str, Any]) -> list[str]:
    """The printed summary of the drag series (its report's results): the laws the
    runs chose, and per quantity of the law the population pooled over loads, each as
    the reports show it, next to the values the series was simulated with
    (:data:`bayestribo.synthetic.campaign.OIL_POPULATION`)."""
    from bayestribo.synthetic.campaign import OIL_POPULATION

    runs = drag.get("runs") or {}
    laws: dict[str, int] = {}
    for r in runs.values():
        laws[str(r.get("law"))] = laws.get(str(r.get("law")), 0) + 1
    chosen = ", ".join(f"{law} ({count(n, 'run')})" for law, n in sorted(laws.items()))
    lines = [f"{DRAG_SERIES} series, law auto: each run's law {chosen or 'none'}"]
    pooled = (drag.get("population") or {}).get("pooled")
    if not pooled:
        return [*lines, "  no population pooled over loads (see its report)"]
    params = pooled["parameters"]
    quantities = (drag.get("analysis") or {}).get("quantities") or {}
    names = [p for p in params if p in OIL_POPULATION]

    def heading(p: str) -> str:
        q = quantities.get(p) or {}
        unit = str(q.get("unit") or "1")
        return str(q.get("symbol") or p) + ("" if unit in ("1", "-") else f" [{unit}]")

    ok = pooled.get("diagnostics", {}).get("converged", True)
    rows: list[tuple[str, list[str]]] = [("", [heading(p) for p in names])]
    for label, key in (("  mean", "mean"), ("  between-run σ", "sigma")):
        rows.append((label, [_interval(params[p][key], "median") for p in names]))
    rows.append(
        (
            "  simulated (mean, σ)",
            [f"{OIL_POPULATION[p][0]} (σ {OIL_POPULATION[p][1]})" for p in names],
        )
    )
    w = max(len(c) for _, cells in rows for c in cells) + 2
    first = max(len(label) for label, _ in rows) + 2
    lines.append(
        f"{DRAG_SERIES}, {count(pooled['n_runs'], 'run')} across loads: population, posterior "
        "median [95 % credible interval]" + ("" if ok else "  (SAMPLER NOT CONVERGED: do not use)")
    )
    lines += [
        (f"{label:<{first}}" + "".join(f"{c:<{w}}" for c in cells)).rstrip()
        for label, cells in rows
    ]
    return lines


def _samplers(analysis: Mapping[str, Any], where: str) -> Iterator[tuple[str, Mapping]]:
    """Every population and trend sampler of a campaign analysis (its ``to_dict``), as
    (what it is, its diagnostics)."""
    for kind in ("contact", "zeta0", "series", "dissipation"):
        population = analysis.get(kind) or {}
        for group in population.get("groups") or []:
            yield f"{where}population {kind} {group.get('label')}", group.get("diagnostics", {})
        pooled = population.get("pooled")
        if pooled:
            yield f"{where}population {kind}, pooled", pooled.get("diagnostics", {})
    for kind in ("trends", "dissipation_trends"):
        for label, trend in (analysis.get(kind) or {}).items():
            yield f"{where}trend {label}", trend.get("diagnostics", {})


def unconverged(
    single: Mapping[str, Any],
    campaign: Mapping[str, Any],
    drag: Mapping[str, Any] | None = None,
) -> list[str]:
    """What did not converge, in the results the demo's reports wrote: the run's fit,
    each run of the campaign, each population and trend (the series across water
    fractions too, where analysed, and the drag series' campaign, ``drag``, where
    fitted); each with its reasons. Empty when all converged.
    """
    out = []

    def reasons(diagnostics: Mapping[str, Any]) -> str:
        said = diagnostics.get("reasons") or []
        return f": {'; '.join(map(str, said))}" if said else ""

    diagnostics = single["fit"].get("diagnostics", {})
    if not diagnostics.get("converged", False):
        out.append(f"the fit of {single.get('name', DEMO_RUN)}{reasons(diagnostics)}")
    campaigns = [campaign] if drag is None else [campaign, drag]
    for results in campaigns:
        for name, r in sorted((results.get("runs") or {}).items()):
            if not r.get("diagnostics", {}).get("converged", False):
                out.append(f"the fit of {name}{reasons(r.get('diagnostics', {}))}")
        for name, why in sorted((results.get("failed") or {}).items()):
            out.append(f"the fit of {name} failed: {why}")
    analyses = [("", campaign.get("analysis") or {})]
    water = (campaign.get("water_series") or {}).get("analysis")
    if water:
        analyses.append(("water series: ", water))
    if drag is not None:
        analyses.append((f"{DRAG_SERIES} series: ", drag.get("analysis") or {}))
    for where, analysis in analyses:
        for what, d in _samplers(analysis, where):
            if not d.get("converged", True):
                out.append(f"the {what}{reasons(d)}")
    return out


def run(args: argparse.Namespace) -> int:
    """Fit, report, print where everything is."""
    from bayestribo.reports.notebooks import run_report

    data, origin = campaign_folder()
    out = (args.out if args.out is not None else default_out()).resolve()
    out.mkdir(parents=True, exist_ok=True)
    figures = out / "figures"
    single_params: dict[str, Any] = {
        "run_path": str(data / "runs" / f"{DEMO_RUN}.csv"),
        "figure_dir": str(figures / "single-run"),
        "summary_path": str(out / "single-run.json"),
    }
    campaign_params: dict[str, Any] = {
        "data_dir": str(data),
        "repeats": None if args.full else [1],
        "air_repeats": None if args.full else [1],
        # the demo is the glycerol campaign across loads (section 3.1 of the paper): the
        # glycerol-water series (`bayestribo report RESULTS`, section 6) is left out
        "water_series": None,
        "figure_dir": str(figures / "campaign"),
        "summary_path": str(out / "campaign.json"),
    }
    if not args.full:
        # One repeat per load: each load's population holds one run, whose spread
        # between repeats the data cannot tell (σ keeps its prior), and its sampler's
        # autocorrelation time is some 200-450 steps on the bundled campaign: 50 of them
        # need 10000-23000 steps, more than the default ceiling of 10000.
        campaign_params["population_steps"] = SINGLE_RUN_GROUP_STEPS
    if args.quick:
        single_params.update({"check_model": False, "grid_points": 32})
        campaign_params.update(
            {
                "loads": [0.31, 0.59],
                "fit_air": False,
                # cut short: two runs leave a trend's σ to its prior, a sampler that
                # converges only after some 80000 steps (the exit status says so)
                "population_steps": QUICK_STEPS,
                "fit_kwargs": {"grid_points": 32},
            }
        )
    print(f"campaign data: {data} ({origin}; simulated runs, see its README.md)", file=sys.stderr)
    print(f"fitting {DEMO_RUN} ...", file=sys.stderr)
    run_report(
        "single_run",
        single_params,
        html=out / "single-run-report.html",
        show_code=args.show_code,
    )
    print("fitting the campaign across loads ...", file=sys.stderr)
    run_report(
        "loads",
        campaign_params,
        html=out / "campaign-report.html",
        show_code=args.show_code,
    )
    drag = None
    if args.full:
        print(
            f"fitting the {DRAG_SERIES} series across loads, each run comparing the laws ...",
            file=sys.stderr,
        )
        run_report(
            "loads",
            {
                "data_dir": str(data),
                "series": DRAG_SERIES,
                "fit_air": False,
                "water_series": None,
                "fit_kwargs": {"law": "auto"},
                "figure_dir": str(figures / DRAG_SERIES),
                "summary_path": str(out / f"{DRAG_SERIES}-campaign.json"),
            },
            html=out / f"{DRAG_SERIES}-campaign-report.html",
            show_code=args.show_code,
        )
        drag = json.loads((out / f"{DRAG_SERIES}-campaign.json").read_text(encoding="utf-8"))
    single = json.loads((out / "single-run.json").read_text(encoding="utf-8"))
    campaign = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    print("\n".join(summary_lines(single, campaign)))
    if drag is not None:
        print()
        print("\n".join(drag_lines(drag)))
    names = ["single-run", "campaign"] + ([DRAG_SERIES] if drag is not None else [])
    reports = ["single-run-report.html", "campaign-report.html"]
    results = ["single-run.json", "campaign.json"]
    if drag is not None:
        reports.append(f"{DRAG_SERIES}-campaign-report.html")
        results.append(f"{DRAG_SERIES}-campaign.json")
    print()
    for i, name in enumerate(reports):
        print(f"{'reports:' if i == 0 else '':<10}{out / name}")
    for i, name in enumerate(names):
        n_png = len(list((figures / name).glob("*.png")))
        print(f"{'figures:' if i == 0 else '':<10}{figures / name} ({n_png} PNG)")
    print(f"results:  {', '.join(str(out / name) for name in results)}")
    stuck = unconverged(single, campaign, drag)
    if stuck:
        print(
            f"bayestribo demo: NOT CONVERGED ({len(stuck)}): " + "; ".join(stuck),
            file=sys.stderr,
        )
        return 1
    return 0
