"""The ``bayestribo`` command line: a thin dispatcher.

Each sub-command lives in its own module under :mod:`bayestribo.cli` and
exposes ``register(subparsers)``, which adds its parser and sets ``handler`` to a
function ``handler(args) -> int``. This module only parses and dispatches; the
work is done by library functions the command modules call.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from bayestribo import __version__
from bayestribo.errors import BayestriboError

__all__ = ["build_parser", "main"]

#: Sub-command modules under ``bayestribo.cli``, in the order of ``--help``.
COMMANDS: tuple[str, ...] = (
    "decay",
    "acquire",
    "estimate",
    "fit",
    "simulate",
    "check",
    "campaign",
    "report",
    "demo",
)


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every registered sub-command."""
    parser = argparse.ArgumentParser(
        prog="bayestribo",
        description="Friction and viscous damping from free-decay recordings.",
    )
    parser.add_argument("--version", action="version", version=f"bayestribo {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        module = importlib.import_module(f"bayestribo.cli.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the process exit status.

    Errors of the package's own type (bad files, bad arguments) are printed as one
    line on standard error with exit status 2; anything else is a bug and keeps its
    traceback.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except BayestriboError as exc:
        print(f"bayestribo {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader of standard output went away (``| head``): no traceback. Point
        # stdout at devnull so that the interpreter's final flush does not fail too
        # (the recipe of the Python documentation, "Note on SIGPIPE").
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
