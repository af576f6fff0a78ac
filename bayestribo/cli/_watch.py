"""``bayestribo campaign DIR --watch``: the options, and the hand-off to the watch.

Examples::

    bayestribo campaign runs/ --watch                    # Ctrl-C to stop
    bayestribo campaign runs/ --watch --settle 5 --population-every 60
    bayestribo campaign runs/ --watch --max-runs 4 --timeout 600 --json

The loop itself is :class:`bayestribo.campaign.watch.CampaignWatch`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

__all__ = ["add_watch_options", "check_watch_options", "run_watch", "warm_up_fit"]


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


class _Given(argparse.Action):
    """Store the value, and note that the option was given (``args._watch_given``): an
    option of a watch without ``--watch`` is refused, not ignored."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, True if self.nargs == 0 else values)
        given = getattr(namespace, "_watch_given", [])
        namespace._watch_given = [*given, option_string]


def add_watch_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--watch`` and the options of a watch to the campaign's parser (their
    defaults are :class:`~bayestribo.campaign.watch.WatchOptions`')."""
    from bayestribo.campaign.watch import WatchOptions

    default = WatchOptions()
    g = parser.add_argument_group(
        "watching (--watch)",
        "keep one warm process that fits each run as its file is complete, prints its "
        "answer as one line and updates the catalog, the populations and a live page "
        "(OUTDIR/watch.html, which a browser reloads; OUTDIR/watch.json for scripts); "
        "with --json each answer is one JSON object on its line; Ctrl-C stops it",
    )
    g.add_argument("--watch", action="store_true", help="watch DIR for runs as they land")
    g.add_argument(
        "--settle",
        action=_Given,
        type=_seconds,
        default=default.settle_s,
        metavar="SECONDS",
        help="a file (and its sidecar) is complete once its size and modification time "
        "have not changed for this long; files of `bayestribo acquire` (renamed into "
        "place, listed in their .sha256 manifest) are complete at once",
    )
    g.add_argument(
        "--poll",
        action=_Given,
        type=_seconds,
        default=default.poll_s,
        metavar="SECONDS",
        help="longest interval between looks at DIR (it is looked at as soon as the "
        "system reports a change there; this is the fallback where it reports none, "
        "e.g. a network share)",
    )
    g.add_argument(
        "--max-runs",
        action=_Given,
        type=_count,
        default=argparse.SUPPRESS,
        metavar="N",
        help="stop after N answers (failures and the runs already in DIR count)",
    )
    g.add_argument(
        "--timeout",
        action=_Given,
        type=_seconds,
        default=argparse.SUPPRESS,
        metavar="SECONDS",
        help="stop after this long (from the start, warm-up included)",
    )
    g.add_argument(
        "--population-every",
        action=_Given,
        type=_seconds,
        default=default.population_every_s,
        metavar="SECONDS",
        help="update the populations at most this often while fits keep coming (they "
        "are updated whenever the fit queue empties)",
    )
    g.add_argument(
        "--no-warm-up",
        action=_Given,
        nargs=0,
        default=not default.warm_up,
        help="do not fit a simulated run first (the first run then waits for the imports "
        "and compiling)",
    )


def warm_up_fit(spec: Any) -> Any:
    """Fit a simulated run (the paper's rig at 0.31 N) with ``spec``, in the worker that
    runs it: imports the fit and compiles its kernels there; the fit result."""
    import warnings
    from dataclasses import replace

    from bayestribo.inference import fit
    from bayestribo.inference.spec import FitSpec
    from bayestribo.synthetic import PAPER_RIG, simulate

    run = simulate(rig=replace(PAPER_RIG, load_N=0.31), seed=0, metadata={"run_id": "warm-up"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its answer is not shown: its warnings neither
        return fit(run, spec=FitSpec.of(spec).replace(seed=0))


def check_watch_options(args: argparse.Namespace) -> None:
    """Refuse the options of a watch without ``--watch``, and those a watch cannot use.

    Raises
    ------
    CommandLineError
        Naming the option.
    """
    from bayestribo.cli._common import CommandLineError

    if not args.watch:
        given = list(dict.fromkeys(getattr(args, "_watch_given", [])))
        if given:
            raise CommandLineError(f"{', '.join(given)}: options of --watch; add --watch")
        return
    if args.dask_scheduler:
        raise CommandLineError("--dask-scheduler: a watch fits in its own warm processes")
    if args.refit:
        raise CommandLineError("--refit: a watch fits every new run; refit with a campaign")


def run_watch(args: argparse.Namespace) -> int:
    """Watch DIR with the parsed options (``bayestribo campaign DIR --watch``)."""
    from bayestribo._workers import terminate_as_interrupt
    from bayestribo.campaign.lock import FolderLock
    from bayestribo.campaign.watch import CampaignWatch, WatchOptions
    from bayestribo.cli._spec import spec_from_args
    from bayestribo.cli.campaign import _words
    from bayestribo.errors import BayestriboError
    from bayestribo.io.registry import get_format, registered_formats

    folder = Path(args.dir)
    if not folder.is_dir():
        raise BayestriboError(f"DIR: {folder} is not a folder")
    spec = spec_from_args(args, "campaign")
    if args.compare_laws:
        if spec.law not in (None, "auto"):
            raise BayestriboError(
                f"--compare-laws chooses the law of each run (it is --law auto); it cannot "
                f"be given with --law {spec.law}"
            )
        spec = spec.replace(law="auto")
    file_format = getattr(args, "format", None)
    formats = [get_format(file_format)] if file_format else registered_formats().values()
    options = WatchOptions(
        settle_s=args.settle,
        poll_s=args.poll,
        max_runs=getattr(args, "max_runs", None),
        timeout_s=getattr(args, "timeout", None),
        population_every_s=args.population_every,
        workers=args.workers or 1,
        warm_up=not args.no_warm_up,
    )
    out = Path(args.out)
    catalog = Path(args.catalog) if args.catalog else out / "catalog.sqlite"
    say = (lambda message: None) if args.quiet else _say
    watch = CampaignWatch(
        folder,
        out,
        catalog,
        spec,
        options,
        by=tuple(k for k in args.by.split(",") if k),
        covariate=args.against,
        prob=args.prob,
        population_steps=args.population_steps,
        dissipation=args.law_free or spec.law == "auto",
        suffixes=sorted({s for f in formats for s in f.suffixes}),
        say=say,
        json_lines=args.json,
        label=_words,
        warm_up=warm_up_fit,
        settings={
            "seed": spec.seed,
            "fit": spec.changed(),
            "spec": spec.to_dict(),
            "population_steps": args.population_steps,
            "against": args.against,
        },
    )
    out.mkdir(parents=True, exist_ok=True)
    with terminate_as_interrupt(), FolderLock(out) as lock:
        if lock.took_over is not None:
            say(
                f"{out}: took over the lock of a campaign that no longer runs "
                f"(process {lock.took_over.get('pid')})"
            )
        return watch.run()


def _say(message: str) -> None:
    print(f"bayestribo campaign --watch: {message}", file=sys.stderr, flush=True)
