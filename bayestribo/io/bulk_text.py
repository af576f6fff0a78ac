"""The numbers of a large plain text file, read by a compiled CSV parser.

A 1 MHz record of one second is a million rows (53 MB as the canonical CSV): the
line-by-line reader takes about 5 s, :func:`numpy.loadtxt` 0.4 s, and a compiled CSV
parser a fraction of that. :func:`read_numbers` reads the rows of numbers of a file
whose layout (delimiter, header lines, number of columns) the text reader has already
found in its head, with pyarrow's CSV reader when pyarrow is installed (the ``large``
extra), else with pandas' C parser, and holds either to what numpy's reader accepts
and to the same float64 values (every field a number, correctly rounded; every row
of one width). Anything else gives None and the file is left to numpy's reader, and
then to the line-by-line one, which names the line and column that is wrong.

Measured on the 1 MHz record (1,000,001 rows of 3 columns; two cores shared with
other work, times from import to contiguous float64 columns, median of interleaved
runs): pyarrow on one thread 0.43 to 0.57 s, on two threads 0.67 to 1.05 s (the
second core was busy), pandas' C parser 0.70 to 1.06 s (of which importing pandas,
0.3 s there, is most of the difference; importing pyarrow's CSV module takes 0.04 s),
:func:`numpy.loadtxt` 1.17 s; peak memory 310 MB (pyarrow, one thread), 338 MB (two
threads), 351 MB (pandas), 271 MB (numpy), of which 224 MB is the package's imports.
"""

from __future__ import annotations

import csv
import importlib.util
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["ARROW_THREADS", "arrow_available", "read_numbers", "read_with_text"]

#: Whether pyarrow's reader parses blocks of the file on its thread pool: True, False,
#: or None for "when the machine has a core to spare" (a load average over the last
#: minute at most the cores this process may run on less one). On a machine whose
#: cores are busy the threads wait for each other (see the module notes; reading and
#: checking the 1 MHz record with ``read_run`` took 0.85 to 1.07 s on one thread, 1.10
#: to 1.25 s on two, at a load of 12 on two cores) and take more memory; on a free
#: second core they parse blocks side by side.
ARROW_THREADS: bool | None = None


def _arrow_threads() -> bool:
    """Whether pyarrow's reader runs on its thread pool (:data:`ARROW_THREADS`)."""
    if ARROW_THREADS is not None:
        return bool(ARROW_THREADS)
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):
        return False
    return cores >= 2 and load <= cores - 1


def arrow_available() -> bool:
    """True when pyarrow can be imported (found on the path, without importing it)."""
    if sys.modules.get("pyarrow") is not None:
        return True
    if "pyarrow" in sys.modules:  # None: its import is blocked
        return False
    try:
        return importlib.util.find_spec("pyarrow") is not None
    except (ImportError, ValueError):
        return False


def read_numbers(
    path: Path, delimiter: str | None, skip: int, width: int, *, parser: str = "auto"
) -> list[NDArray] | None:
    """The rows of numbers of a plain text file, or None to leave the file to
    :func:`numpy.loadtxt`.

    Parameters
    ----------
    path : Path
        The file (UTF-8).
    delimiter : str or None
        The column separator; None for white space (pandas only: pyarrow's reader
        takes one character).
    skip : int
        Physical lines before the first row of numbers (header, blank lines).
    width : int
        Fields in every row.
    parser : {"auto", "pyarrow", "pandas"}
        The parser: "auto" takes pyarrow's where it is installed and can read the
        layout, else pandas'.

    Returns
    -------
    list of ndarray or None
        The ``width`` columns, each a contiguous float64 array of its own (made once
        from the parser's buffers), or None when the parser is missing or any row is
        not ``width`` numbers.
    """
    if parser == "auto":
        parser = "pyarrow" if delimiter is not None and arrow_available() else "pandas"
    if parser == "pyarrow":
        return _read_arrow(path, delimiter, skip, width)
    if parser == "pandas":
        return _read_pandas(path, delimiter, skip, width)
    raise ValueError(f"parser: expected 'auto', 'pyarrow' or 'pandas', got {parser!r}")


def _read_arrow(path: Path, delimiter: str | None, skip: int, width: int) -> list[NDArray] | None:
    """pyarrow's CSV reader, held to numpy's: no quoting, no null values (an empty cell,
    "NA" or "null" is an error), each field converted to float64 by its correctly
    rounded parser (the values of Python's ``float``; "nan" and "inf" as there), a row
    of another width an error; its columns copied straight from the parser's buffers
    (``to_numpy`` would import pandas, 0.1 to 0.3 s)."""
    if delimiter is None or len(delimiter) != 1:
        return None
    try:
        import pyarrow
        import pyarrow.csv  # where the CSV module is missing, the file goes to pandas
    except ImportError:
        return None
    names = [f"c{i}" for i in range(width)]
    # the C library's allocator, which numpy uses too: what the parser frees is reused
    # by the analysis (pyarrow's own pool keeps it, 60 MB at 1 MHz, or, released, makes
    # the analysis fault its pages in anew: 0.05 s)
    pool = pyarrow.system_memory_pool()
    try:
        return _parse_arrow(path, delimiter, skip, names, pool)
    finally:
        # what the parser's threads freed, and the allocator keeps in their arenas, goes
        # back to the system (malloc_trim): 1 MHz record, two threads, peak 372 MB
        # instead of 381 MB
        release = getattr(pool, "release_unused", None)
        if release is not None:
            release()


def _parse_arrow(
    path: Path, delimiter: str, skip: int, names: list[str], pool: Any
) -> list[NDArray] | None:
    """:func:`_read_arrow`'s parse into columns (named ``names``), in ``pool``'s memory:
    the parser's table is freed when this returns."""
    import pyarrow
    import pyarrow.csv as arrow_csv

    width = len(names)
    try:
        table = arrow_csv.read_csv(
            path,
            read_options=arrow_csv.ReadOptions(
                skip_rows=skip, column_names=names, use_threads=_arrow_threads()
            ),
            parse_options=arrow_csv.ParseOptions(
                delimiter=delimiter, quote_char=False, escape_char=False, newlines_in_values=False
            ),
            convert_options=arrow_csv.ConvertOptions(
                column_types=dict.fromkeys(names, pyarrow.float64()),
                null_values=[],
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
                check_utf8=True,
            ),
            memory_pool=pool,
        )
    except (pyarrow.ArrowException, UnicodeDecodeError, OSError):
        return None
    if table.num_columns != width or table.num_rows < 1:
        return None
    columns = []
    for j in range(width):
        column = np.empty(table.num_rows, dtype=np.float64)
        row = 0
        for chunk in table.column(j).chunks:
            if chunk.null_count or chunk.type != pyarrow.float64():
                return None
            values = np.frombuffer(
                chunk.buffers()[1], dtype=np.float64, count=len(chunk), offset=8 * chunk.offset
            )
            column[row : row + values.size] = values
            row += values.size
        columns.append(column)
    return columns


def _pandas_frame(
    path: Path, delimiter: str | None, skip: int, width: int, dtype: Any
) -> Any | None:
    """pandas' C parser, held to numpy's reader: every field of a float64 column a
    number (no quotes; an empty cell, "NA" or "nan" is an error here, and numpy reads
    the file: "nan" as NaN, the others refused), every row ``width`` fields, each
    number correctly rounded (pandas 3.1's one converter; "round_trip", Python's
    conversion, before it). The frame, or None to leave the file to another reader."""
    try:
        import pandas
    except ImportError:  # a core dependency, but numpy's reader does without
        return None
    options: dict = {}
    if tuple(int(p) for p in re.findall(r"\d+", pandas.__version__)[:2]) < (3, 1):
        options["float_precision"] = "round_trip"  # Python's correctly rounded strtod
    try:
        # from an open file, not its path: pandas then parses serially instead of
        # mapping the file into memory for threads (twice the memory, 1.5 times the
        # speed on two free cores)
        with path.open("rb") as handle:
            frame = pandas.read_csv(
                handle,
                sep=r"\s+" if delimiter is None else delimiter,
                header=None,
                skiprows=skip,
                dtype=dtype,
                engine="c",
                comment=None,
                quoting=csv.QUOTE_NONE,
                na_filter=False,
                skip_blank_lines=True,
                encoding="utf-8",
                **options,
            )
    except (ValueError, UnicodeDecodeError, OverflowError, pandas.errors.ParserError):
        return None
    if frame.shape[1] != width or frame.shape[0] < 1:
        return None
    return frame


def _read_pandas(path: Path, delimiter: str | None, skip: int, width: int) -> list[NDArray] | None:
    """Every column a float64 array, by :func:`_pandas_frame`, or None."""
    frame = _pandas_frame(path, delimiter, skip, width, np.float64)
    if frame is None:
        return None
    # column by column: to_numpy() of the frame interleaves the rows (50 ms at
    # 1,000,001 rows), and each column is read whole afterwards
    return [frame.iloc[:, j].to_numpy(dtype=np.float64, copy=True) for j in range(width)]


def read_with_text(
    path: Path, delimiter: str | None, skip: int, width: int, text: Sequence[int]
) -> tuple[list[NDArray | None], dict[int, list[str]]] | None:
    """The rows of a plain text file whose columns ``text`` hold text (time stamps) and
    every other column numbers, read by pandas' C parser, or None to leave the file to
    the line-by-line reader (any empty cell, any field of a number column that is not
    a number, any row of another width).

    Parameters
    ----------
    path : Path
        The file (UTF-8).
    delimiter : str or None
        The column separator; None for white space.
    skip : int
        Physical lines before the first row (header, blank lines).
    width : int
        Fields in every row.
    text : sequence of int
        The columns read as text.

    Returns
    -------
    (list, dict) or None
        The ``width`` columns, each a contiguous float64 array (None for a text
        column), and the cells of each text column by its index.
    """
    dtype = {j: (str if j in text else np.float64) for j in range(width)}
    frame = _pandas_frame(path, delimiter, skip, width, dtype)
    if frame is None:
        return None
    numbers: list[NDArray | None] = [
        None if j in text else frame.iloc[:, j].to_numpy(dtype=np.float64, copy=True)
        for j in range(width)
    ]
    cells = {j: frame.iloc[:, j].tolist() for j in text}
    return numbers, cells
