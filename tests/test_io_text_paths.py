"""The streamed path of the text reader (numpy's C reader straight from the file) gives
the same arrays and warnings as the line-by-line reader on every layout, plain or not."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

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
