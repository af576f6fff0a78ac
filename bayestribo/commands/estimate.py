"""``bayestribo estimate``: the classical estimators on one run, as a table or JSON.

Examples::

    bayestribo estimate runs/glycerol_N0.31_r2.csv
    bayestribo estimate HarmOsc3.txt --columns t x --length-unit arbitrary --json
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["register"]

_ALIASES = {
    "t": "time_s",
    "x": "displacement_m",
    "v": "velocity_m_per_s",
    "-": "ignore",
}


def _columns(values: list[str] | None) -> list[str] | None:
    if values is None:
        return None
    names = [c for v in values for c in v.split(",") if c]
    return [_ALIASES.get(c, c) for c in names]


def register(subparsers: Any) -> None:
    """Add the ``estimate`` sub-command."""
    from bayestribo.estimators.all import METHODS

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
    p.add_argument("run", metavar="RUN", help="run file (canonical CSV, text, UFF, TDMS)")
    p.add_argument(
        "--columns",
        nargs="+",
        metavar="NAME",
        help="text files: the role of each column in file order: time_s, displacement_m, "
        "velocity_m_per_s or ignore (short: t, x, v, -)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument(
        "--skip", type=int, default=0, help="leading extrema to skip (2 = first oscillation)"
    )
    p.add_argument(
        "--methods", nargs="+", choices=METHODS, metavar="METHOD", help="subset of methods"
    )
    p.add_argument(
        "--length-unit",
        choices=("m", "arbitrary"),
        help="length unit of the signals (arbitrary: friction as a displacement only)",
    )
    p.add_argument("--frequency", type=float, help="natural frequency f [Hz]")
    p.add_argument("--load", type=float, help="normal load N [N]")
    p.add_argument("--mass", type=float, help="oscillating mass m [kg]")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Read the run, estimate, print."""
    from bayestribo.estimators.all import estimate_all
    from bayestribo.io import read_run

    meta: dict[str, Any] = {}
    for key, value in (
        ("length_unit", args.length_unit),
        ("natural_frequency_Hz", args.frequency),
        ("load_N", args.load),
        ("mass_kg", args.mass),
    ):
        if value is not None:
            meta[key] = value
    try:
        recording = read_run(args.run, columns=_columns(args.columns), **meta)
    except FileNotFoundError as exc:
        print(f"bayestribo estimate: error: {exc}", file=sys.stderr)
        return 2
    table = estimate_all(recording, skip=args.skip, methods=args.methods, name=args.run)
    if args.json:
        print(table.to_json())
    else:
        print(table.to_text())
    sys.stdout.flush()
    return 0
