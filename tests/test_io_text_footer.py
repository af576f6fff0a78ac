"""A footer of labelled values below a text table (a program's summary statistics)."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io import read_run

T = np.arange(400) / 1000.0
X = 1e-3 * np.exp(-2.0 * T) * np.cos(2.0 * np.pi * 20.0 * T)


def _table(path, tail: str, blank: bool = True) -> str:
    lines = ["time_s,displacement_m"] + [f"{a:.4f},{b:.9f}" for a, b in zip(T, X, strict=True)]
    text = "\n".join(lines) + "\n" + ("\n" if blank else "") + tail
    path.write_text(text)
    return str(path)


def test_a_footer_of_statistics_is_left_out_and_said(tmp_path) -> None:
    path = _table(tmp_path / "run.csv", "Mean,0.0000123\nStd,0.00031\nMax,0.001\n")
    with pytest.warns(ReadingWarning, match=r"line\(s\) 403 to 405.*'Mean', 'Std', 'Max'"):
        run = read_run(path, metadata={"length_unit": "m"})
    assert run.time.size == T.size
    np.testing.assert_array_equal(run.displacement, np.round(X, 9))


def test_a_label_inside_the_table_is_still_an_error(tmp_path) -> None:
    lines = ["time_s,displacement_m"] + [f"{a:.4f},{b:.9f}" for a, b in zip(T, X, strict=True)]
    lines.insert(100, "Mean,0.0000123")
    path = tmp_path / "inside.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunFormatError, match=r"'Mean' is not a number"):
        read_run(str(path), metadata={"length_unit": "m"})


def test_labels_not_set_off_by_a_blank_line_are_an_error(tmp_path) -> None:
    path = _table(tmp_path / "run.csv", "Mean,0.0000123\n", blank=False)
    with pytest.raises(RunFormatError, match=r"'Mean' is not a number"):
        read_run(path, metadata={"length_unit": "m"})


def test_numbers_after_a_blank_line_are_rows(tmp_path) -> None:
    path = _table(tmp_path / "run.csv", "0.4000,0.000001\n0.4010,0.000002\n")
    run = read_run(path, metadata={"length_unit": "m"})
    assert run.time.size == T.size + 2
