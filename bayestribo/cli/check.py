"""``bayestribo check``: is the linear law adequate for one run?

Windowed fits along the decay with the constancy test, the predicted end of motion
against the recorded one, and the peak-by-peak predictive check, as a report or JSON.
With ``--restoring pendulum|duffing|auto`` (or the sidecar's ``restoring``) the law of
constant ζ and friction is checked on that restoring force
(:mod:`bayestribo.adequacy.restoring`), and the verdict names it.

Examples::

    bayestribo check runs/glycerol_N0.31_r2.csv
    bayestribo check HarmOsc2.txt --columns t x --length-unit arbitrary --window-length 6 --json

Exit status: 0 when the law is adequate (every check run and passed), 1 when a check
rejects it (the report says which and by how much) or a check could not run on the
record (too few turning points for the constancy test's windows or for the halves: the
report names it and the turning points it needs, and the verdict says what it rests
on), 2 for bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

from bayestribo.cli._common import add_run_arguments, read_run_from_args
from bayestribo.cli._spec import add_spec_options, spec_from_args

__all__ = ["USES", "register"]

#: The fields of the fit specification the check uses: how the run is read and
#: prepared, and the seed; its windowed fits are least squares, or Bayesian fits with
#: settings of their own (``--bayes``).
USES = ("restoring", "read_options", "seed", "skip_oscillations")


def register(subparsers: Any) -> None:
    """Add the ``check`` sub-command."""
    p = subparsers.add_parser(
        "check",
        help="adequacy of the linear law (on the run's restoring force): windowed fits, "
        "extinction time, predictive check",
        description=(
            "Fit ζ and μ_k in windows of a few oscillations along the decay and test whether "
            "they change with amplitude; compare the predicted end of motion (Eq. 38 and the "
            "exact model) with the recorded one; compare the recorded peaks with their "
            "predictive intervals; fit the first and second halves of the motion and test "
            "whether they agree. Without a Bayesian fit the parameter draws come from the "
            "Gaussian approximation of the least-squares fit, and the report says so. With "
            "--restoring (or the sidecar's restoring) every check takes that restoring "
            "force's motion. The verdict is 'not adequate' when any check fails; on a "
            "record of the law it says so at most --alpha of the time (the constancy "
            "test, the halves and the end of motion each at alpha/3, Bonferroni). A check "
            "the record is too short for is not run and named; the law is then not called "
            "adequate on the others alone (exit 1)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_run_arguments(p)
    p.add_argument(
        "--window-length",
        type=int,
        help="length of the windowed fits in oscillations (default: about 1/8 of the decay); "
        "--window T0:T1 crops the record",
    )
    p.add_argument(
        "--alpha",
        type=float,
        default=0.05,
        help="false-alarm rate of the verdict on a record of the law (each of its three "
        "tests at alpha/3)",
    )
    p.add_argument("--draws", type=int, default=400, help="parameter draws for the checks")
    p.add_argument(
        "--bayes",
        action="store_true",
        help="Bayesian fit on each window and on the whole run (posterior draws; slower)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a report")
    p.add_argument("--quiet", action="store_true", help="no progress lines (--bayes)")
    add_spec_options(p, helps={"seed": "seed of the draws and of the fits"})
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Read the run, check, print the report."""
    from bayestribo.adequacy.check import check_adequacy

    spec = spec_from_args(
        args,
        "check",
        uses=USES,
        why="its windowed fits are least squares, or Bayesian fits of their own with "
        "--bayes; give fit options to `bayestribo fit` or `bayestribo report`",
    )
    try:
        recording = read_run_from_args(args, spec.reading())
    except FileNotFoundError as exc:
        print(f"bayestribo check: error: {exc}", file=sys.stderr)
        return 2
    start = time.perf_counter()

    def say(message: str) -> None:
        elapsed = time.perf_counter() - start
        print(f"bayestribo check: [{elapsed:5.0f} s] {message}", file=sys.stderr)

    report = check_adequacy(
        recording,
        window=args.window_length,
        alpha=args.alpha,
        n_draws=args.draws,
        seed=spec.seed,
        bayes=args.bayes,
        skip_oscillations=spec.skip_oscillations,
        progress=None if args.quiet or not args.bayes else say,
    )
    if args.json:
        print(json.dumps(report.to_dict(), indent=2, ensure_ascii=False))
    else:
        print(report.to_text())
    sys.stdout.flush()
    # The exit status rule (README): 1 when the result says something is not right.
    return 0 if report.adequate else 1
