"""The streamed path of the text reader (numpy's C reader straight from the file, or a
compiled CSV parser for a large file) gives the same arrays and warnings as the
line-by-line reader on every layout, plain or not."""

from __future__ import annotations

import shutil
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from bayestribo.errors import RunFormatError
from bayestribo.io import bulk_text
from bayestribo.io import text as text_module
from bayestribo.io.text import read_text

_rng = np.random.default_rng(7)
_T = np.arange(50) / 1000.0
_X = 1e-4 * np.sin(2.0 * np.pi * 30.0 * _T) + 1e-7 * _rng.standard_normal(_T.size)
_V = np.gradient(_X, _T)


def _body(sep: str, newline: str = "\n") -> str:
    return newline.join(
        sep.join(repr(float(c)) for c in row) for row in zip(_T, _X, _V, strict=True)
    )


#: name -> (file text, read_text options, whether the file is plain)
FILES = {
    "canonical": ("time_s,displacement_m,velocity_m_per_s\n" + _body(",") + "\n", {}, True),
    "no final newline": ("time_s,displacement_m,velocity_m_per_s\n" + _body(","), {}, True),
    "crlf": (
        "time_s,displacement_m,velocity_m_per_s\r\n" + _body(",", "\r\n") + "\r\n",
        {},
        True,
    ),
    "units, semicolons, comments above": (
        "# rig 3\n\n# µm and mm/s\ntime_ms;displacement_um;velocity_mm_per_s\n" + _body(";"),
        {},
        True,
    ),
    "white space, no header": (
        _body("   "),
        {"columns": ["time_s", "ignore", "velocity_m_per_s"]},
        True,
    ),
    "tabs, skip_rows": (
        "preamble line\nanother\ntime_s\tdisplacement_m\tvelocity_m_per_s\n" + _body("\t"),
        {"skip_rows": 2},
        True,
    ),
    "300 comment lines above the header": (
        "# note\n" * 300 + "time_s,displacement_m,velocity_m_per_s\n" + _body(","),
        {},
        True,
    ),
    "comment among rows": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n# pause\n", 1),
        {},
        False,
    ),
    "blank line among rows": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n\n", 3),
        {},
        False,
    ),
    "lone carriage return": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\r", 1),
        {},
        False,
    ),
    "cut-short last line": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",") + "\n0.05,1.2e-",
        {},
        False,
    ),
    "empty cells at the start": (
        "time_s,displacement_m,velocity_m_per_s\n0.0,1e-4,\n" + _body(",").split("\n", 1)[1],
        {},
        False,
    ),
    "decimal commas": (
        "time_s;displacement_m;velocity_m_per_s\n" + _body(";").replace(".", ","),
        {"decimal": ","},
        False,
    ),
}


def _parsing_with(parser: str, taken: list[bool]):
    """The large-file path held to ``parser``, noting in ``taken`` whether it read the
    file (True) or left it to numpy's reader (False)."""

    def large(path, delimiter, skip, width):
        out = bulk_text.read_numbers(path, delimiter, skip, width, parser=parser)
        taken.append(out is not None)
        return out

    return large


def _read(path: Path, options: dict, fast: bool, monkeypatch) -> tuple[dict, list[str]]:
    with monkeypatch.context() as patch:
        if not fast:  # the row-by-row reader alone
            patch.setattr(text_module, "_read_streamed", lambda *a, **k: None)
            patch.setattr(text_module, "_parse_block", lambda *a, **k: None)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = read_text(path, **options)
    return out, [str(w.message) for w in caught]


@pytest.mark.parametrize("name", list(FILES))
def test_the_streamed_and_line_by_line_readers_give_identical_arrays_and_warnings(
    name: str, tmp_path: Path, monkeypatch
) -> None:
    content, options, _ = FILES[name]
    path = tmp_path / "run.csv"
    path.write_bytes(content.encode("utf-8"))
    fast, fast_warnings = _read(path, options, True, monkeypatch)
    slow, slow_warnings = _read(path, options, False, monkeypatch)
    assert list(fast) == list(slow)
    for key in fast:
        assert fast[key].tobytes() == slow[key].tobytes(), key
    assert fast_warnings == slow_warnings


#: Layouts only the large-file path meets (pandas' C parser): beyond the 13 above.
LARGE_FILES = {
    **FILES,
    "all lone carriage returns": (
        "time_s,displacement_m,velocity_m_per_s\r" + _body(",", "\r") + "\r",
        {},
        True,
    ),
    "a nan among the rows": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n0.1,nan,0\n", 1),
        {},
        False,
    ),
    "a quoted number": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", '\n0.1,"2",0\n', 1),
        {},
        False,
    ),
    "a row of four fields": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n0.1,2,0,4\n", 1),
        {},
        False,
    ),
    "a row of two fields": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n0.1,2\n", 1),
        {},
        False,
    ),
    "NA in a cell": (
        "time_s,displacement_m,velocity_m_per_s\n" + _body(",").replace("\n", "\n0.1,NA,0\n", 1),
        {},
        False,
    ),
    "numbers of many digits and extremes": (
        "time_s,displacement_m,velocity_m_per_s\n"
        + _body(",")
        + "\n0.06,0.1000000000000000055511151231257827021181583404541015625,4.9e-324"
        + "\n0.07,1e-400,-0.0\n0.08,0.00000000000001953,2.2250738585072011e-308\n",
        {},
        True,
    ),
    "white space with an ignored column": (
        "t x v\n" + _body("  "),
        {"columns": ["time_s", "ignore", "velocity_m_per_s"]},
        True,
    ),
}


@pytest.mark.parametrize("parser", ["pyarrow", "pandas"])
@pytest.mark.parametrize("name", list(LARGE_FILES))
def test_the_large_file_path_gives_numpys_arrays_warnings_and_errors(
    name: str, parser: str, tmp_path: Path, monkeypatch
) -> None:
    """A compiled CSV parser (pyarrow's or pandas') reads a large plain file (here: any
    file longer than a head of 512 bytes) with the arrays, warnings and errors of
    numpy's reader (which the test above holds to the line-by-line reader's), or leaves
    the file to it."""
    pytest.importorskip(parser)
    content, options, _ = LARGE_FILES[name]
    path = tmp_path / "run.csv"
    path.write_bytes(content.encode("utf-8"))
    taken: list[bool] = []
    large = _parsing_with(parser, taken)

    monkeypatch.setattr(text_module, "_HEAD_BYTES", 512)

    def read(large) -> tuple:
        with monkeypatch.context() as patch:
            patch.setattr(text_module, "_read_large", large)
            try:
                return _read(path, options, True, monkeypatch)
            except RunFormatError as refused:  # the line-by-line reader names the line
                return str(refused), []

    with_parser = read(large)
    with_numpy = read(lambda *a, **k: None)
    if isinstance(with_numpy[0], str):
        assert with_parser == with_numpy
    else:
        fast, fast_warnings = with_parser
        slow, slow_warnings = with_numpy
        assert list(fast) == list(slow)
        for key in fast:
            assert fast[key].tobytes() == slow[key].tobytes(), key
        assert fast_warnings == slow_warnings
    if name in READS[parser]:
        assert taken == [True]  # these went through the parser
    if name in REFUSED[parser]:
        assert True not in taken


#: Layouts both parsers read (the plain ones of more than three lines in the head).
_PLAIN = (
    "canonical",
    "no final newline",
    "crlf",
    "units, semicolons, comments above",
    "numbers of many digits and extremes",
)
#: Layouts both parsers must leave to numpy's reader or the line-by-line one.
_NOT_PLAIN = (
    "a quoted number",
    "a row of four fields",
    "a row of two fields",
    "NA in a cell",
    "empty cells at the start",
    "cut-short last line",
)
_WHITE_SPACE = ("white space with an ignored column", "white space, no header")
#: Layouts each parser reads.
READS = {
    "pyarrow": (*_PLAIN, "a nan among the rows"),  # NaN, as numpy reads it
    "pandas": (*_PLAIN, *_WHITE_SPACE),
}
#: Layouts each parser leaves to numpy's reader or the line-by-line one.
REFUSED = {
    "pyarrow": (*_NOT_PLAIN, *_WHITE_SPACE),  # one character separates its fields
    "pandas": (*_NOT_PLAIN, "a nan among the rows"),  # numpy reads it as NaN
}


def _large_record(path: Path) -> None:
    """A file of 300,000 rows (beyond the size from which the compiled parsers read):
    comments, a header with units, and numbers of every magnitude and digit count."""
    rng = np.random.default_rng(11)
    n = 300_000
    t = np.arange(n) * 1e-3  # ms
    x = 1e3 * np.exp(-t / 200.0) * np.sin(t / 5.0) + rng.normal(0.0, 1e-3, n)  # µm
    v = np.gradient(x, t) * 10.0 ** rng.integers(-12, 3, n)  # mm/s, any magnitude
    body = "\n".join(
        f"{a!r};{b:.17g};{c!r}" for a, b, c in zip(t.tolist(), x.tolist(), v.tolist(), strict=True)
    )
    path.write_text(
        "# rig 3, 2026-11-27\n# displacement in µm, velocity in mm/s\n\n"
        "time_ms;displacement_um;velocity_mm_per_s\n" + body + "\n",
        encoding="utf-8",
    )


@pytest.fixture(scope="module")
def large_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The large record, written once for the module (tests that alter it copy it)."""
    path = tmp_path_factory.mktemp("large") / "run.csv"
    _large_record(path)
    return path


@pytest.fixture(scope="module")
def large_read_row_by_row(large_file: Path) -> tuple[dict, list[str]]:
    """The large record as the row-by-row reader alone reads it, with its warnings."""
    with pytest.MonkeyPatch.context() as patch:
        return _read(large_file, {}, False, patch)


def _copy(path: Path, folder: Path) -> Path:
    copy = folder / path.name
    shutil.copyfile(path, copy)
    return copy


@pytest.mark.parametrize(
    ("parser", "threads"), [("pyarrow", False), ("pyarrow", True), ("pandas", None)]
)
def test_a_large_file_with_comments_and_units_reads_as_the_row_by_row_reader_reads_it(
    parser: str, threads: bool | None, large_file: Path, large_read_row_by_row, monkeypatch
) -> None:
    """The whole fast path (the head laid out, the rows parsed by a compiled parser, on
    one thread or several) against the row-by-row reader alone, on a file of the size
    the fast path is for: the same arrays bit for bit and the same warnings."""
    pytest.importorskip(parser)
    monkeypatch.setattr(bulk_text, "ARROW_THREADS", threads)
    path = large_file
    assert path.stat().st_size > text_module._ARROW_BYTES
    taken: list[bool] = []
    large = _parsing_with(parser, taken)

    monkeypatch.setattr(text_module, "_LARGE_BYTES", 0)
    monkeypatch.setattr(text_module, "_read_large", large)
    fast, fast_warnings = _read(path, {}, True, monkeypatch)
    assert taken == [True]
    slow, slow_warnings = large_read_row_by_row
    assert list(fast) == list(slow) == ["time_s", "displacement_m", "velocity_m_per_s"]
    for key in fast:
        assert fast[key].tobytes() == slow[key].tobytes(), key
        assert fast[key].dtype == np.float64 and fast[key].flags.c_contiguous
    assert fast_warnings == slow_warnings


def test_a_bad_row_of_a_large_file_is_named_by_the_row_by_row_reader(
    large_file: Path, tmp_path: Path
) -> None:
    """The compiled parser refuses the file; the line-by-line reader names the line."""
    path = _copy(large_file, tmp_path)
    lines = path.read_text(encoding="utf-8").splitlines()
    lines[200_004] = lines[200_004].replace(";", ";x", 1)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(RunFormatError, match=r"line 200005, column 'displacement_m'"):
        read_text(path)


def test_a_pyarrow_that_does_not_import_leaves_the_file_to_pandas(
    large_file: Path, large_read_row_by_row, monkeypatch
) -> None:
    """A broken pyarrow install (found on the path, failing to import) costs speed, not
    the reading: pandas' parser reads the file, with the row-by-row reader's numbers."""
    pytest.importorskip("pandas")
    path = large_file
    used = []
    read_numbers = bulk_text.read_numbers

    def spy(*args, parser="auto", **kwargs):
        out = read_numbers(*args, parser=parser, **kwargs)
        used.append((parser, out is not None))
        return out

    monkeypatch.setattr(bulk_text, "arrow_available", lambda: True)
    monkeypatch.setattr(bulk_text, "read_numbers", spy)
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow raises ImportError
    monkeypatch.setattr(text_module, "_LARGE_BYTES", 0)
    fast, _ = _read(path, {}, True, monkeypatch)
    assert used == [("pyarrow", False), ("pandas", True)]
    slow, _ = large_read_row_by_row
    for key in fast:
        assert fast[key].tobytes() == slow[key].tobytes(), key


@pytest.mark.parametrize("bad", [False, True])
def test_pyarrows_pool_keeps_nothing_of_a_read(
    bad: bool, large_file: Path, tmp_path: Path, monkeypatch
) -> None:
    """The columns are the reader's own arrays: once a file is read (or refused), no
    memory of pyarrow's pool is left allocated for the parser's table."""
    pyarrow = pytest.importorskip("pyarrow")
    path = _copy(large_file, tmp_path) if bad else large_file
    if bad:
        with path.open("a", encoding="utf-8") as handle:
            handle.write("1.0;x;2.0\n")
    # the reader's pool, seen through a proxy that counts this read's allocations
    # alone (the system pool's count also holds whatever another thread of the test
    # process has allocated meanwhile)
    pool = pyarrow.proxy_memory_pool(pyarrow.system_memory_pool())
    monkeypatch.setattr(pyarrow, "system_memory_pool", lambda: pool)
    out = bulk_text.read_numbers(path, ";", 4, 3, parser="pyarrow")
    assert (out is None) == bad
    if out is not None:
        assert all(column.flags.owndata for column in out)
    assert pool.max_memory() > 0  # the parser worked in this pool
    assert pool.bytes_allocated() == 0
