"""``bayestribo laws``: the registered dissipation terms, their parameters and ΔE(A).

Examples::

    bayestribo laws
    bayestribo laws --json

A law is any set of these terms joined with ``+`` (``viscous+coulomb``, the default;
``viscous+quadratic+coulomb``, ...), the value of ``bayestribo fit --law``. The text
ends with the laws ``--law auto`` compares, built from the registry by the rule of
:mod:`bayestribo.model.laws.candidates` (each term's ``overlaps`` and ``compared`` are
in the JSON).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

__all__ = ["add_law_option", "law_table", "register"]

#: Help of ``--law``: the registered terms are listed by ``bayestribo laws`` (the
#: registry is imported only when a law is given).
LAW_HELP = (
    "dissipation law: registered terms joined with '+' (default viscous+coulomb; "
    "'bayestribo laws' lists the terms, their parameters and ΔE(A)), or 'auto': the "
    "simplest adequate law as good as the best, by PSIS-LOO, of the laws the registered "
    "terms make ('bayestribo laws' ends with them)"
)


def law_name(text: str) -> str:
    """argparse type of ``--law``: a known law, written canonically, or ``auto``."""
    from bayestribo.model.laws import get_law

    if text.strip().lower() == "auto":
        return "auto"
    try:
        return get_law(text).name
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_law_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--law NAME`` to a sub-command."""
    parser.add_argument("--law", type=law_name, default=None, metavar="NAME", help=LAW_HELP)


def law_table() -> list[dict[str, Any]]:
    """Every registered term with its kind, description and parameters (with the
    typical value ``bayestribo simulate`` takes where one is not given, or None)."""
    from bayestribo.model.laws import TERMS

    return [
        {
            "term": term.name,
            "kind": term.kind,
            "description": term.description,
            "overlaps": list(term.overlaps),
            "compared": term.compared,
            "parameters": [
                {
                    "name": p.name,
                    "symbol": p.symbol,
                    "unit": p.unit,
                    "support": [p.low, p.high],
                    "label": p.label,
                    "typical": p.typical,
                }
                for p in term.parameters
            ],
        }
        for term in TERMS.values()
    ]


def register(subparsers: Any) -> None:
    """Add the ``laws`` sub-command."""
    p = subparsers.add_parser(
        "laws",
        help="list the dissipation terms a law can be made of (--law of fit)",
        description=(
            "List the registered dissipation terms: each one's force, its parameters "
            "(symbol, unit of the dimensionless value, support) and the energy it "
            "dissipates per cycle ΔE(A). A law is any set of terms joined with '+'; "
            "the laws --law auto compares follow."
        ),
    )
    p.add_argument("--json", action="store_true", help="print one JSON array instead of text")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Print the registered terms."""
    table = law_table()
    if args.json:
        print(json.dumps(table, allow_nan=True))
        return 0
    from bayestribo.inference.quantities import unit_words

    for entry in table:
        print(f"{entry['term']:<12} ({entry['kind']}) {entry['description']}")
        for p in entry["parameters"]:
            low, high = p["support"]
            typical = "" if p["typical"] is None else f" (typical {p['typical']:g})"
            print(
                f"    {p['name']:<12} {p['symbol']:<8} [{low:g}, {high:g}] "
                f"{unit_words(p['unit']):<13} {p['label']}{typical}"
            )
    print("A law is terms joined with '+', e.g. --law viscous+quadratic+coulomb.")
    print(
        "Simulate one: bayestribo simulate OUT.csv --law NAME --param NAME=VALUE ... "
        "(a parameter not given takes its typical value)."
    )
    from bayestribo.model.laws.candidates import CANDIDATE_RULE, candidate_laws

    print(f"--law auto compares {CANDIDATE_RULE}:")
    print("    " + ", ".join(candidate_laws()))
    return 0
