"""The ``bayestribo`` command line: a thin dispatcher.

Each sub-command lives in its own module under :mod:`bayestribo.cli` and
exposes ``register(subparsers)``, which adds its parser and sets ``handler`` to a
function ``handler(args) -> int``. This module only parses and dispatches; the
work is done by library functions the command modules call.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import re
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import TextIO

from bayestribo import __version__
from bayestribo.cli._imports import own_process
from bayestribo.errors import BayestriboError

__all__ = ["build_parser", "main", "plain_numbers"]

#: Sub-command modules under ``bayestribo.cli``, in the order of ``--help``.
COMMANDS: tuple[str, ...] = (
    "inspect",
    "decay",
    "acquire",
    "estimate",
    "fit",
    "laws",
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


#: ``np.float64(0.5)``, ``np.int64(3)``: numpy scalar reprs inside a message.
_NUMPY_REPR = re.compile(r"np\.(?:float|int|uint|bool_?|complex)\d*\(([^()]*)\)")


def plain_numbers(text: str) -> str:
    """A message with numpy scalar reprs (``np.float64(0.5)``) written as numbers (0.5)."""
    return _NUMPY_REPR.sub(r"\1", text)


def _one_line_warning(command: str) -> Callable[..., None]:
    """A ``warnings.showwarning`` that prints one line per warning, without the source
    file and line: ``bayestribo fit: warning: …`` (a package warning) or
    ``bayestribo fit: warning (RuntimeWarning): …`` (another library's)."""

    def show(
        message: Warning | str,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: TextIO | None = None,
        line: str | None = None,
    ) -> None:
        text = plain_numbers(" ".join(str(message).split()))
        own = category.__module__.split(".")[0] == "bayestribo"
        if own and category.__name__ == "ReadingWarning":
            from bayestribo.cli._common import cli_message

            text = cli_message(text)  # the fixes it names, as command-line options
        kind = "warning" if own else f"warning ({category.__name__})"
        stream = sys.stderr if file is None else file
        try:
            print(f"bayestribo {command}: {kind}: {text}", file=stream)
        except OSError:
            pass  # as warnings.showwarning: a closed stream loses the warning only

    return show


def disk_full_message(filename: str | os.PathLike[str] | None) -> str:
    """What a command says when the disk is full: the file it was writing, whether that
    file is its previous version or absent, and how to go on.

    Every file the package writes goes through :mod:`bayestribo._files` (a temporary
    name, then a rename), so a file found under the name is its previous version, whole.
    """
    if not filename:
        kept = "the files written before are kept whole"
    elif os.path.exists(filename):
        kept = f"{filename} is its previous version, whole; the files written before are whole"
    else:
        kept = f"no file {filename} was made; the files written before are whole"
    where = f" writing {filename}" if filename else ""
    return (
        f"no space left on the device{where}; {kept} (each file is written to a temporary "
        "name and renamed); free some space and run the command again (a campaign reuses "
        "the fits it finished)"
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the process exit status.

    Errors of the package's own type (bad files, bad arguments) are printed as one
    line on standard error with exit status 2; anything else is a bug and keeps its
    traceback. Called without ``argv`` (as the ``bayestribo`` script and ``python -m
    bayestribo`` call it), the command owns the process: the fitting machinery's
    objects are frozen out of the collector's way once imported (:mod:`._imports`).
    """
    own_process(argv is None)
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning(args.command)
            return int(args.handler(args) or 0)
    except BayestriboError as exc:
        print(f"bayestribo {args.command}: error: {plain_numbers(str(exc))}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader of standard output went away (``| head``): no traceback. Point
        # stdout at devnull so that the interpreter's final flush does not fail too
        # (the recipe of the Python documentation, "Note on SIGPIPE"). Before OSError,
        # of which it is a kind.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:
        if exc.errno not in (errno.ENOSPC, errno.EDQUOT):
            raise
        # a full disk: one line, what was kept, how to go on (no traceback)
        print(
            f"bayestribo {args.command}: error: {disk_full_message(exc.filename)}",
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        # Ctrl-C, or SIGTERM where a command turns it into this: what was finished is
        # kept (a campaign's fits are in its catalog), the rest stops
        print(f"bayestribo {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
