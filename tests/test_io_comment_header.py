"""A whitespace ``.dat`` whose column names are its last comment line (a byte-order mark,
CRLF line ends) is read by them and said; comment lines that name no columns are not."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.comment_header import comment_header

T = np.arange(800) / 2000.0
X = 2e-3 * np.exp(-4.0 * T) * np.cos(2 * np.pi * 32.6 * T)
V = np.gradient(X, T)


def _dat(path, comments, bom=True, crlf=True):
    rows = [f"{a:10.6f}  {b * 1e6:10.4f}  {c * 1e3:9.4f}" for a, b, c in zip(T, X, V, strict=True)]
    text = ("\r\n" if crlf else "\n").join([*comments, *rows]) + "\n"
    path.write_bytes((("\ufeff" if bom else "") + text).encode("utf-8"))
    return path


@pytest.mark.parametrize("bom", [True, False])
@pytest.mark.parametrize("crlf", [True, False])
def test_names_in_the_last_comment_line_are_the_header(tmp_path, bom, crlf):
    path = _dat(
        tmp_path / "rig.dat",
        ["# free decay, rig B", "#", "# t_s      x_um      v_mm_per_s"],
        bom=bom,
        crlf=crlf,
    )
    with pytest.warns(ReadingWarning, match=r"comment line 3: \['t_s', 'x_um', 'v_mm_per_s'\]"):
        run = read_run(path, metadata={"natural_frequency_Hz": 32.6})
    np.testing.assert_allclose(run.time, T, atol=1e-6)
    np.testing.assert_allclose(run.displacement, X, atol=1e-10)
    np.testing.assert_allclose(run.velocity, V, atol=1e-7)


def test_a_comment_that_names_no_columns_leaves_the_refusal(tmp_path):
    path = _dat(tmp_path / "rig.dat", ["# free decay, rig B", "# three columns"])
    with pytest.raises(RunFormatError, match="no header row"):
        read_run(path)


def test_comment_header():
    assert comment_header(["# t_s x_m", "0 1"], None) == (["t_s", "x_m"], 1)
    assert comment_header(["# t_s x_m v_m_per_s", "0 1"], None) is None  # widths differ
    assert comment_header(["# time x", "0 1"], None) is None  # no units
    assert comment_header(["# t_s x_m", "t_s,x_m", "0,1"], None) is None  # a header row
