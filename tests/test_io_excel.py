"""Excel workbooks: the worksheet chosen, cells read exactly, bad workbooks refused."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError

openpyxl = pytest.importorskip("openpyxl", reason="Excel files need the formats extra")

RATE = 2000.0
T = np.arange(600) / RATE
X = 1.2e-3 * np.exp(-3.0 * T) * np.cos(2 * np.pi * 32.6 * T)
META = {"natural_frequency_Hz": 32.6, "length_unit": "m"}


def _book(path: Path, sheets: dict[str, list[list[object]]]) -> Path:
    book = openpyxl.Workbook()
    book.remove(book.active)
    for name, rows in sheets.items():
        sheet = book.create_sheet(name)
        for row in rows:
            sheet.append(row)
    book.save(path)
    return path


def _rows(header: list[str] | None = None) -> list[list[object]]:
    body = [[float(t), float(1e3 * x)] for t, x in zip(T, X, strict=True)]
    return ([header] if header else []) + body


def test_header_with_units_in_parentheses_reads_exactly(tmp_path: Path) -> None:
    path = _book(tmp_path / "a.xlsx", {"Run 1": _rows(["Time (s)", "Position (mm)"])})
    run = read_run(path, metadata=META)
    np.testing.assert_array_equal(run.time, T)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)


def test_several_sheets_of_numbers_need_sheet_and_it_is_never_guessed(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    other = [[float(t), 0.5 * float(1e3 * x)] for t, x in zip(T, X, strict=True)]
    path = _book(
        tmp_path / "two.xlsx",
        {
            "Notes": [["operator", "rig B"], ["load", "0.31 N"]],
            "Run 1": _rows(["Time (s)", "Position (mm)"]),
            "Run 2": [["Time (s)", "Position (mm)"], *other],
        },
    )
    with pytest.raises(
        RunFormatError, match=r"several worksheets hold numbers \(\['Run 1', 'Run 2'\]\)"
    ):
        read_run(path, metadata=META)
    by_name = read_run(path, sheet="Run 2", metadata=META)
    by_position = read_run(path, sheet=2, metadata=META)
    np.testing.assert_array_equal(by_name.displacement, by_position.displacement)
    np.testing.assert_allclose(by_name.displacement, 0.5 * X, rtol=1e-15, atol=0)
    with pytest.raises(RunFormatError, match=r"no worksheet 'Run 3'; the sheets are"):
        read_run(path, sheet="Run 3")
    with pytest.raises(RunFormatError, match=r"position 5 is not in 0..2"):
        read_run(path, sheet=5)
    # The command line names its own option, and --sheet picks the run.
    assert main(["inspect", str(path), "--length-unit", "m", "--frequency", "32.6"]) == 2
    said = capsys.readouterr().err
    assert "give --sheet" in said
    # each reading named as it is typed
    assert "`--sheet 'Run 1'` or `--sheet 'Run 2'`" in said
    assert main(["inspect", str(path), "--sheet", "1", "--length-unit", "m", "--json"]) == 0


def test_a_headerless_sheet_reads_with_columns_and_skip_rows(tmp_path: Path) -> None:
    rows = [["Exported by the rig software"], ["sample rate", 2000.0], *_rows()]
    path = _book(tmp_path / "bare.xlsx", {"Sheet1": rows})
    run = read_run(path, columns=["time_s", "displacement_mm"], skip_rows=2, metadata=META)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    with pytest.raises(
        RunFormatError, match=r"sheet 'Sheet1'.*line 2, column 'time_s': 'sample rate'"
    ):
        read_run(path, columns=["time_s", "displacement_mm"], metadata=META)


def test_a_derived_column_empty_in_its_last_rows_is_trimmed_and_said(tmp_path: Path) -> None:
    rows = _rows(["Time (s)", "Position (mm)", "Velocity (mm/s)"])
    v = 1e3 * np.gradient(X, T)
    for i, row in enumerate(rows[1:]):
        if i < len(v) - 2:
            row.append(float(v[i]))
    path = _book(tmp_path / "derived.xlsx", {"Data": rows})
    with pytest.warns(ReadingWarning, match="empty"):
        run = read_run(path, metadata=META)
    assert run.time.size == T.size - 2


def test_cells_that_are_not_numbers_are_refused_naming_the_row(tmp_path: Path) -> None:
    rows = _rows(["Time (s)", "Position (mm)"])
    rows[40][1] = "overload"
    path = _book(tmp_path / "text.xlsx", {"Data": rows})
    with pytest.raises(RunFormatError, match=r"line 41, column 'displacement_m': 'overload'"):
        read_run(path, metadata=META)


@pytest.mark.parametrize(
    "content",
    [b"", b"PK\x03\x04 not really a zip", b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1 old xls"],
    ids=["empty", "broken-zip", "xls-renamed"],
)
def test_a_file_that_is_not_a_workbook_is_refused(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "bad.xlsx"
    path.write_bytes(content)
    with pytest.raises(RunFormatError, match=r"not a readable Excel \.xlsx workbook"):
        read_run(path)


def test_a_workbook_without_numbers_says_where_they_should_be(tmp_path: Path) -> None:
    path = _book(tmp_path / "notes.xlsx", {"Notes": [["nothing", "here"]]})
    with pytest.raises(RunFormatError, match="no worksheet holds columns of numbers"):
        read_run(path)
