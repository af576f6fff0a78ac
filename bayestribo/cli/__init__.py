"""The ``bayestribo`` command line: :func:`main` dispatches to one module per sub-command.

Each sub-command module (``fit``, ``estimate``, ``decay``, …) parses its own options
and hands off to library functions; ``_common`` holds the options shared by the
commands that read a run.
"""

from bayestribo.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
