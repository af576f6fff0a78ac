"""``bayestribo estimate``: the classical estimators on one run, as a table or JSON.

Examples::

    bayestribo estimate runs/glycerol_N0.31_r2.csv
    bayestribo estimate HarmOsc3.txt --columns t x --length-unit arbitrary --json
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from bayestribo.cli._common import add_run_arguments, read_run_from_args

__all__ = ["METHOD_NAMES", "register"]

#: The estimators' names, as :data:`bayestribo.estimators.all.METHODS` (a test keeps
#: them equal): listed here so that ``--help`` does not import the estimators.
METHOD_NAMES: tuple[str, ...] = (
    "log_decrement",
    "exponential_envelope",
    "feeny_liang",
    "nonsuccessive",
    "energy_ls_averaged",
    "energy_ls_exact",
)


def register(subparsers: Any) -> None:
    """Add the ``estimate`` sub-command."""
    p = subparsers.add_parser(
        "estimate",
        help="classical estimates of ζ and μ_k (peak decrements, energy least squares)",
        description=(
            "Run the classical estimators (logarithmic decrement, exponential envelope, "
            "Feeny-Liang, non-successive peaks, least squares on the energy integral with "
            "the averaged and the exact model) on one run and print a table, or JSON "
            "with null where a method gives no value. Without load and mass, friction is "
            "reported as a friction displacement in the signal's unit."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_run_arguments(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument(
        "--skip",
        type=int,
        default=1,
        help="oscillations to skip after the release, as for fit and decay (the estimators "
        "analyse the fit's window)",
    )
    p.add_argument(
        "--methods", nargs="+", choices=METHOD_NAMES, metavar="METHOD", help="subset of methods"
    )
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Read the run, estimate, print."""
    from bayestribo.estimators.all import estimate_all

    recording = read_run_from_args(args)
    table = estimate_all(
        recording, skip_oscillations=args.skip, methods=args.methods, name=args.run
    )
    if args.json:
        print(table.to_json())
    else:
        print(table.to_text())
    sys.stdout.flush()
    return 0
