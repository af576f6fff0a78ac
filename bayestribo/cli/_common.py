"""Arguments shared by the commands that read one run."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = [
    "COLUMN_ALIASES",
    "add_reading_options",
    "add_run_arguments",
    "read_run_from_args",
    "reading_kwargs",
]

#: Short names accepted by ``--columns``.
COLUMN_ALIASES = {"t": "time_s", "x": "displacement_m", "v": "velocity_m_per_s", "-": "ignore"}


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """Add RUN and the options that describe a file without a canonical header."""
    parser.add_argument("run", metavar="RUN", help="run file (canonical CSV, text, UFF, TDMS)")
    add_reading_options(parser)


def add_reading_options(parser: argparse.ArgumentParser) -> None:
    """Add the options that describe a run file without a canonical header."""
    parser.add_argument(
        "--columns",
        nargs="+",
        metavar="NAME",
        help="text files: the role of each column in file order, comma or space separated: "
        "time_s, displacement_m, velocity_m_per_s or ignore (short: t, x, v, -)",
    )
    parser.add_argument(
        "--length-unit",
        choices=("m", "arbitrary"),
        help="length unit of the signals (arbitrary: friction as a displacement only)",
    )
    parser.add_argument("--frequency", type=float, help="nominal natural frequency f [Hz]")
    parser.add_argument("--load", type=float, help="normal load N [N]")
    parser.add_argument("--mass", type=float, help="oscillating mass m [kg]")


def columns_from_args(values: list[str] | None) -> list[str] | None:
    """Expand ``--columns`` values (aliases, comma lists) to canonical names."""
    if values is None:
        return None
    names = [c for v in values for c in v.split(",") if c]
    return [COLUMN_ALIASES.get(c, c) for c in names]


def reading_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of :func:`bayestribo.read_run` from :func:`add_reading_options`."""
    kwargs: dict[str, Any] = {}
    columns = columns_from_args(args.columns)
    if columns is not None:
        kwargs["columns"] = columns
    metadata = {
        key: value
        for key, value in (
            ("length_unit", args.length_unit),
            ("natural_frequency_Hz", args.frequency),
            ("load_N", args.load),
            ("mass_kg", args.mass),
        )
        if value is not None
    }
    if metadata:
        kwargs["metadata"] = metadata
    return kwargs


def read_run_from_args(args: argparse.Namespace) -> Any:
    """Read the run named by :func:`add_run_arguments` options."""
    from bayestribo.io import as_run

    return as_run(args.run, **reading_kwargs(args))
