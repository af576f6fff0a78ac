"""How to read a run file: one settings object shared by every entry point.

:class:`ReadOptions` holds every reading option of :func:`bayestribo.read_run`. The
functions that read a run (``fit``, ``compare_laws``, ``prepare``, campaigns, reports,
``inspect``) take one, or a mapping of the same names, and the command line builds one
from its options (:func:`bayestribo.cli._common.reading_options`), so a file is read
the same way whatever reads it. Which options apply to which file format is said by the
format's registration (:mod:`bayestribo.io.registry`).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bayestribo.errors import BayestriboError

__all__ = ["FORMAT_OPTIONS", "READ_OPTIONS", "ReadOptions"]


@dataclass(frozen=True)
class ReadOptions:
    """Every option of reading a run file (see :func:`bayestribo.read_run`).

    Parameters
    ----------
    columns : sequence of str, optional
        Text and spreadsheet files: one name per column in file order (a canonical name,
        a quantity with its unit such as ``displacement_um``, or ``"ignore"``).
    scale : mapping, optional
        Factor per canonical column name converting the file's unit to s, m or m/s.
    sample_rate_Hz : float, optional
        The sample rate [Hz] of a file without a time column (sample i at t = i / rate);
        for a file with one it is the run's ``sample_rate_Hz``, checked against its time
        stamps.
    delimiter : str, optional
        Text files: the column separator (default: guessed).
    decimal : {".", ","}
        Text files: the decimal mark.
    skip_rows : int
        Text and spreadsheet files: lines (rows) to skip at the top.
    encoding : str, optional
        Text files: the text encoding (default UTF-8, else Windows-1252, said).
    group : str, optional
        TDMS and HDF5 files: the group holding the channels.
    channels : mapping, optional
        Binary formats: the channel, variable, dataset or record per column name.
    sheet : str or int, optional
        Spreadsheets: the worksheet, by name or by position from 0.
    file_format : str, optional
        A registered format name, overriding the choice by suffix.
    sidecar : bool or path
        Read the JSON sidecar beside the file (True), none (False), or this one.
    validate : bool
        Run the data checks of :func:`~bayestribo.io.validation.validate_run`.
    metadata : mapping, optional
        Metadata that fill or override the sidecar's.
    window : (float, float), optional
        Keep the samples with ``t0 <= t <= t1`` [s] (in the file's time, after
        scaling): a part of the record the analysis should see (the rest holds a clock
        restart, a second release, a disturbance). Recorded in the run's metadata
        (``window_s``).
    """

    columns: tuple[str, ...] | None = None
    scale: Mapping[str, float] | None = None
    sample_rate_Hz: float | None = None
    delimiter: str | None = None
    decimal: str = "."
    skip_rows: int = 0
    encoding: str | None = None
    group: str | None = None
    channels: Mapping[str, Any] | None = None
    sheet: str | int | None = None
    file_format: str | None = None
    sidecar: bool | str | Path = True
    validate: bool = True
    metadata: Mapping[str, Any] | None = field(default=None)
    window: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        # A list of columns is kept as a tuple (the options are immutable); every other
        # check is the reader's, which names the file.
        if isinstance(self.columns, list):
            object.__setattr__(self, "columns", tuple(self.columns))
        if self.window is not None:
            object.__setattr__(self, "window", check_window(self.window))

    @classmethod
    def of(cls, value: ReadOptions | Mapping[str, Any] | None = None, **more: Any) -> ReadOptions:
        """The options given as an object, a mapping of option names, or keywords.

        Parameters
        ----------
        value : ReadOptions, mapping or None
            Options, or a mapping of option names (:data:`READ_OPTIONS`) to values.
        **more
            Options that override those in ``value``.

        Returns
        -------
        ReadOptions

        Raises
        ------
        BayestriboError
            For a name that is not a reading option (naming the closest one), or a
            ``value`` that is neither options nor a mapping.
        """
        if value is None:
            base: dict[str, Any] = {}
        elif isinstance(value, ReadOptions):
            if not more:
                return value
            base = value.as_kwargs()
        elif isinstance(value, Mapping):
            base = dict(value)
        else:
            raise BayestriboError(
                f"read_options: expected ReadOptions or a mapping of reading options, got "
                f"{type(value).__name__}"
            )
        base.update(more)
        unknown = {k: v for k, v in base.items() if k not in READ_OPTIONS}
        if unknown:
            raise unknown_options(unknown)
        return cls(**base)

    def replace(self, **changes: Any) -> ReadOptions:
        """A copy with some options changed (names checked as in :meth:`of`)."""
        return ReadOptions.of(self, **changes)

    def as_kwargs(self) -> dict[str, Any]:
        """The options that differ from the defaults, as keyword arguments of ``read_run``.

        Plain lists and dicts, so that the result can be written as JSON (notebook
        parameters) and passed back to :meth:`of`.
        """
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value == f.default:
                continue
            if f.name == "window":
                # an open end as None: JSON holds no infinity
                value = [v if math.isfinite(v) else None for v in value]
            elif isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, Mapping):
                value = dict(value)
            elif isinstance(value, Path):
                value = str(value)
            out[f.name] = value
        return out

    def format_options(self) -> dict[str, Any]:
        """The format-specific options given (:data:`FORMAT_OPTIONS` not at their default)."""
        given = self.as_kwargs()
        return {name: given[name] for name in FORMAT_OPTIONS if name in given}


def check_window(window: Any) -> tuple[float, float]:
    """A time window ``(t0, t1)`` [s] with ``t0 < t1`` (either end may be infinite, or
    None, :meth:`ReadOptions.as_kwargs`'s spelling of it in JSON: open).

    Raises
    ------
    BayestriboError
        Naming the option and what was expected.
    """
    try:
        t0, t1 = window
        t0 = -math.inf if t0 is None else float(t0)
        t1 = math.inf if t1 is None else float(t1)
    except (TypeError, ValueError, OverflowError):
        # an integer beyond a float's range (a JSON sidecar holds any) is no time either
        raise BayestriboError(
            f"window: expected two times (t0, t1) in seconds, got {window!r:.200}"
        ) from None
    if math.isnan(t0) or math.isnan(t1) or not t0 < t1:
        raise BayestriboError(f"window: expected times t0 < t1 in seconds, got ({t0!r}, {t1!r})")
    return t0, t1


#: Names of every reading option, in the order of :func:`bayestribo.read_run`.
READ_OPTIONS: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(ReadOptions))

#: The options that apply to some file formats only; each registered format lists the
#: ones it takes (:attr:`bayestribo.io.registry.FileFormat.options`).
FORMAT_OPTIONS: tuple[str, ...] = (
    "columns",
    "delimiter",
    "decimal",
    "skip_rows",
    "encoding",
    "group",
    "channels",
    "sheet",
)


def unknown_options(unknown: Mapping[str, Any]) -> BayestriboError:
    """The error for names that are not reading options, with the closest one."""
    from bayestribo.io.run import METADATA_KEYS

    parts = []
    for name in sorted(unknown):
        close = difflib.get_close_matches(name, READ_OPTIONS, n=1)
        if close:
            parts.append(f"{name!r} (did you mean {close[0]!r}?)")
        elif name in METADATA_KEYS:
            parts.append(f"{name!r} (a metadata key: pass metadata={{{name!r}: ...}})")
        else:
            parts.append(f"{name!r}")
    return BayestriboError(
        f"unknown reading option(s) {', '.join(parts)}; the options are {', '.join(READ_OPTIONS)}"
    )
