"""``bayestribo fit``: the Bayesian fit of one run, as a table or one JSON object.

Examples::

    bayestribo fit data/runs/glycerol-N0.31-r1.csv --seed 1
    bayestribo fit data/runs/glycerol-N0.31-r1.csv --seed 1 --json --out fits/
    bayestribo fit HarmOsc3.txt --columns t x --length-unit arbitrary --frequency 1.1

The exit status is 0 for a converged fit, 1 when the sampler did not converge, a
posterior piles on a physical bound of its prior, or the model misfits the run beyond
what its intervals carry (the result is still printed, with the reason; a frequency
trend is carried into the intervals and leaves it 0), 2 for bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from bayestribo._files import atomic_file
from bayestribo.cli._common import add_run_arguments, read_run_from_args
from bayestribo.cli._spec import add_spec_options, spec_from_args

__all__ = ["json_record", "register", "write_outputs"]

#: Keys of the diagnostics in the JSON record (the issue's shape), in order.
DIAGNOSTICS = (
    "converged",
    "n_walkers",
    "n_steps",
    "autocorr_time_max",
    "ess_min",
    "acceptance_fraction",
)


def register(subparsers: Any) -> None:
    """Add the ``fit`` sub-command."""
    p = subparsers.add_parser(
        "fit",
        help="Bayesian fit of ζ and μ_k of one run (posterior, intervals, diagnostics)",
        description=(
            "Fit the exact (or averaged) model of the retrograde energy integral Π(τ) "
            "to one run with emcee and print the posterior mean, standard deviation, "
            "median and 95 % interval of ζ, μ_k, μ_s and the friction displacement (or "
            "of the parameters of another dissipation law, --law), the energy dissipated "
            "per cycle ΔE(A) with its band, and the sampler's diagnostics. Exit status 1 "
            "when the sampler did not converge or the law misfits the run. Without load "
            "and mass, friction is reported as a friction displacement in the signal's "
            "unit."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_run_arguments(p)
    add_spec_options(p)
    p.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        help="write DIR/<run>.nc (NetCDF) and the corner, trace and Π figures (PNG)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("--progress", action="store_true", help="show a progress bar (stderr)")
    p.add_argument(
        "--quiet",
        action="store_true",
        help="no progress lines (--law auto prints one per law compared on a terminal)",
    )
    p.add_argument(
        "--prob",
        type=float,
        default=0.95,
        help="probability of the reported credible intervals (default 0.95)",
    )
    p.set_defaults(handler=run)


def json_record(result: Any, prob: float = 0.95) -> dict[str, Any]:
    """The JSON object printed by ``--json``.

    ``{"run", "model", "law", "law_comparison" (with ``--law auto``), "restoring" (the
    force, what was measured of it, and with ``--restoring auto`` the choice), "seed",
    "bayestribo_version", "metadata", "noise",
    "parameters": {NAME: {"mean", "sd", "median", "interval", "prob", "kind", "unit",
    "name", "symbol", "label", "sampled", "ess", "r_hat"}} (every quantity of the
    posterior, :meth:`~bayestribo.inference.FitResult.summary`; ``kind`` ``"bound"``
    for a quantity the data do not constrain, its interval from the prior's lower end to
    the bound the table prints; keys are added, never renamed),
    "dissipation": {"amplitude", "mean", "sd", "interval", "prob", "unit", ...},
    "turning_point_dissipation": (the same, measured from the turning points), "diagnostics":
    {"converged", "n_walkers", "n_steps", "autocorr_time_max", "ess_min",
    "acceptance_fraction", ...}, "seconds"}``; the
    diagnostics keep the fit's further entries (R-hat, ESS and τ per parameter, reasons when not
    converged) after the six of the record.
    """
    full = result.to_dict(prob)
    diagnostics = full["diagnostics"]
    ordered = {key: diagnostics.get(key) for key in DIAGNOSTICS}
    ordered.update({k: v for k, v in diagnostics.items() if k not in ordered})
    return {
        "run": full["run"],
        "model": full["model"],
        "law": full["law"],
        "law_comparison": full["law_comparison"],
        "restoring": full["restoring"],
        "seed": full["seed"],
        "bayestribo_version": full["bayestribo_version"],
        "metadata": full["metadata"],
        "noise": full["noise"],
        "channel_calibration": full["channel_calibration"],
        "parameters": full["parameters"],
        "dissipation": full["dissipation"],
        "turning_point_dissipation": full["turning_point_dissipation"],
        "diagnostics": ordered,
        "prior_sensitivity": full.get("prior_sensitivity"),
        "seconds": full["seconds"],
    }


def _save_png(fig: Any, path: Path) -> None:
    """Write a figure as PNG, whole or not at all (:func:`bayestribo._files.atomic_file`)."""
    with atomic_file(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)


def write_outputs(result: Any, out_dir: Path, stem: str) -> list[Path]:
    """Write ``<stem>.nc`` and the corner, trace and Π figures (PNG) into ``out_dir``.

    Raises
    ------
    BayestriboError
        If ``out_dir`` exists and is not a directory, or cannot be created.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from bayestribo.errors import BayestriboError
    from bayestribo.inference.plots import corner_plot, pi_plot, plotted_names, trace_plot

    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError, PermissionError) as exc:
        raise BayestriboError(f"--out: cannot use {out_dir} as an output directory: {exc}") from exc
    paths = [result.save(out_dir / f"{stem}.nc")]

    names = plotted_names(result)
    fig = plt.figure(figsize=(2.2 * len(names) + 1, 2.2 * len(names) + 1))
    corner_plot(result, fig)
    paths.append(out_dir / f"{stem}_corner.png")
    _save_png(fig, paths[-1])
    plt.close(fig)

    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.6 * len(names) + 0.6), sharex=True)
    trace_plot(result, np.atleast_1d(axes))
    fig.tight_layout()
    paths.append(out_dir / f"{stem}_trace.png")
    _save_png(fig, paths[-1])
    plt.close(fig)

    fig, axes = plt.subplots(
        2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    pi_plot(result, axes)
    fig.tight_layout()
    paths.append(out_dir / f"{stem}_pi.png")
    _save_png(fig, paths[-1])
    plt.close(fig)
    return paths


def law_progress(args: argparse.Namespace, law: str | None = None) -> Callable[[str], None] | None:
    """The progress line of ``--law auto``: one line per law compared on stderr, when
    stderr is a terminal and neither ``--quiet`` nor ``--json`` is given; else None."""
    if (law or args.law) != "auto" or args.quiet or args.json or not sys.stderr.isatty():
        return None

    def say(text: str) -> None:
        print(f"bayestribo fit --law auto: {text}", file=sys.stderr, flush=True)

    return say


def tell(
    caught: Sequence[warnings.WarningMessage], told: Sequence[warnings.WarningMessage] = ()
) -> None:
    """Print each warning once: the same message of the same kind, raised again by a
    second pass over the run (``--law auto`` prepares it for the comparison and again
    for its verdict's fit), or already ``told``, is one warning and is printed once.

    Parameters
    ----------
    caught : sequence of warnings.WarningMessage
        Warnings recorded, in the order raised.
    told : sequence of warnings.WarningMessage, optional
        Warnings printed before, not printed again.
    """
    seen = {(w.category, str(w.message)) for w in told}
    for w in caught:
        key = (w.category, str(w.message))
        if key not in seen:
            seen.add(key)
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)


def run(args: argparse.Namespace) -> int:
    """Read the run, fit, print; exit status 1 when the sampler did not converge."""
    from bayestribo.errors import MisfitWarning
    from bayestribo.summary import check_prob

    check_prob(args.prob)  # before the fit, not after it
    spec = spec_from_args(args, "fit")
    with warnings.catch_warnings(record=True) as read:
        warnings.simplefilter("always")
        recording = read_run_from_args(args, spec.reading())
    tell(read)  # told at once; counted with the fit's below (e.g. samples left out)
    # the fitting machinery (numba, emcee, scipy) only once the input is good: a bad
    # option or file is told at once
    from bayestribo.cli._imports import import_module

    import_module("bayestribo.inference.fitting")
    fit = sys.modules["bayestribo.inference"].fit

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # every warning of this fit, none deduplicated
        result = fit(
            recording,
            # the specification as fit's keywords; the run is read: its reading options
            # are not given again
            **spec.replace(read_options=None, restoring=None).fit_kwargs(),
            progress=args.progress,
            law_progress=law_progress(args, spec.law),
        )
    # the run is named by the path the user gave, and read as the specification says
    result.attrs["run_name"] = str(args.run)
    result.attrs["spec_json"] = spec.to_json()
    tell(caught, told=read)
    notched = result.settings.get("notch_Hz") or []
    lines = result.noise.get("lines_Hz") or []
    if notched:
        found = ", ".join(f"{f:.2f}" for f in notched)
        print(
            f"bayestribo fit: mains line at {found} Hz measured at rest and subtracted",
            file=sys.stderr,
        )
    elif lines:
        found = ", ".join(f"{f:.2f}" for f in lines)
        print(
            f"bayestribo fit: a mains line at {found} Hz is in the rest noise; --notch auto "
            "subtracts it",
            file=sys.stderr,
        )
    if args.out is not None:
        paths = write_outputs(result, args.out, Path(args.run).stem)
        if not args.json:
            print("wrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    if args.json:
        print(json.dumps(json_record(result, args.prob), allow_nan=False))
    else:
        print(result.to_text(args.prob))
    sys.stdout.flush()
    # 1 when something is not right: not converged, a posterior on a prior bound, or a
    # misfit the intervals do not carry (the README's exit-status rule).
    misfit = any(issubclass(w.category, MisfitWarning) for w in [*read, *caught])
    return 0 if result.usable and not misfit else 1
