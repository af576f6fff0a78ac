"""How a file is read, described before anything is computed from it.

:func:`describe_file` says which reader a file goes to and what it found there (from
the format's registration, :mod:`bayestribo.io.registry`): the recognised instrument
export and its columns with their units, the header row of a plain text file or a
worksheet, and the sidecar read beside it. ``bayestribo inspect`` prints it.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bayestribo.errors import RunFormatError
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import check_content, format_for
from bayestribo.io.sidecar import sidecar_path

__all__ = ["describe_file"]


def describe_file(
    path: str | Path,
    options: ReadOptions | Mapping[str, Any] | None = None,
    **read_options: Any,
) -> dict[str, Any]:
    """Which reader a run file goes to, and the layout it has there.

    Parameters
    ----------
    path : str or Path
        The run file.
    options : ReadOptions or mapping, optional
        How the file is read (as for :func:`bayestribo.read_run`); ``file_format``,
        ``skip_rows``, ``encoding`` and ``sheet`` matter here.
    **read_options
        Reading options overriding ``options``.

    Returns
    -------
    dict
        ``format`` (a registered format name), ``reader`` (in words), ``columns`` (a
        list of ``{"label", "unit"}`` as the file gives them, for a recognised export or
        a header row; empty otherwise) and ``sidecar`` (the path of the JSON sidecar
        read with the file, or None).

    Raises
    ------
    RunFormatError
        For a file that does not exist or whose format is unknown.
    """
    opts = ReadOptions.of(options, **read_options)
    path = Path(path)
    if not path.is_file():
        raise RunFormatError("no such run file; expected an existing file", str(path))
    fmt = format_for(path, opts.file_format)
    if opts.file_format is None:
        check_content(path, fmt)
    out = fmt.describe_file(path, opts)
    side = sidecar_path(path)
    out["sidecar"] = str(side) if side.is_file() and side != path else None
    return out
