"""Delimited text files with other layouts, and the real recordings of ../shared."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _paths import APPSTAT
from hypothesis import given, settings
from hypothesis import strategies as st

from bayestribo import read_run
from bayestribo.errors import ReadingWarning, RunFormatError

EXTERNAL = APPSTAT

# From the data set's README: rows, sample step and first time stamp of each file.
APPSTAT = [
    ("HarmOsc1.txt", 3806, 0.01, 10.0),
    ("HarmOsc2.txt", 3616, 0.01, 0.0),
    ("HarmOsc3.txt", 13700, 0.001, 0.0),
]


@pytest.mark.parametrize(("name", "rows", "step", "first"), APPSTAT)
def test_real_recordings_read_with_one_documented_call(
    name: str, rows: int, step: float, first: float
) -> None:
    path = EXTERNAL / name
    if not path.is_file():
        pytest.skip(f"external data not present at {path}")
    run = read_run(
        path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
    )
    assert run.n_samples == rows
    assert run.time[0] == first
    assert run.sample_rate_Hz == pytest.approx(1.0 / step, rel=1e-9)
    assert run.velocity is None
    assert run.length_unit == "arbitrary"
    # Same numbers as an independent parser of the same file.
    np.testing.assert_array_equal(run.displacement, np.loadtxt(path)[:, 1])
    # No load, mass or frequency: friction can only be a friction displacement.
    assert run.rig() is None
    assert not run.scaling(natural_frequency_Hz=1.0).friction_defined


def _sine(n: int = 400, rate: float = 2000.0) -> tuple[list[float], list[float]]:
    t = np.arange(n) / rate
    return t.tolist(), (1e-3 * np.sin(2 * np.pi * 32.6 * t + 0.3)).tolist()


def test_headerless_two_columns_whitespace(tmp_path: Path) -> None:
    t, x = _sine()
    path = tmp_path / "pos.txt"
    path.write_text("".join(f"{a!r}   {b!r}\n" for a, b in zip(t, x, strict=True)))
    run = read_run(path, columns=["time_s", "displacement_m"])
    np.testing.assert_array_equal(run.time, t)
    np.testing.assert_array_equal(run.displacement, x)


def test_other_names_units_delimiter_decimal_comma_and_ignored_column(tmp_path: Path) -> None:
    t, x = _sine()
    v = np.gradient(x, t).tolist()
    path = tmp_path / "export.csv"
    lines = ["# exported by some software", "Zeit [ms];Kanal;Weg [mm];v [mm/s]"]
    lines += [
        f"{1e3 * a:.6f};7;{1e3 * b:.9f};{1e3 * c:.9f}".replace(".", ",")
        for a, b, c in zip(t, x, v, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    run = read_run(
        path,
        columns=["time_s", "ignore", "displacement_m", "velocity_m_per_s"],
        scale={"time_s": 1e-3, "displacement_m": 1e-3, "velocity_m_per_s": 1e-3},
        decimal=",",
    )
    # Printed with 6 decimals in ms and 9 in mm: rounding below 1e-9 s and 1e-12 m.
    np.testing.assert_allclose(run.time, t, atol=1e-9)
    np.testing.assert_allclose(run.displacement, x, atol=1e-12)
    np.testing.assert_allclose(run.velocity, v, atol=1e-12)


def test_instrument_preamble_is_skipped(tmp_path: Path) -> None:
    t, x = _sine()
    path = tmp_path / "inst.dat"
    path.write_text(
        "Instrument XYZ v2\nDate: today\n"
        + "".join(f"{a!r}\t{b!r}\n" for a, b in zip(t, x, strict=True))
    )
    run = read_run(path, columns=["time_s", "displacement_m"], skip_rows=2)
    assert run.n_samples == len(t)


def test_preamble_of_another_width_names_the_skip_rows_that_reads_it(tmp_path: Path) -> None:
    """A logger's settings in two lines of three fields above one angle per line (an
    encoder's serial print, no time column): refused when --columns names one column,
    with the skip_rows that reads it; followed, the file is read."""
    angles = 90.0 * np.cos(2 * np.pi * 0.8 * np.arange(2000) / 1000.0)
    path = tmp_path / "swing.txt"
    path.write_text(
        "trigger_start_deg, sample_rate, duration_sec\n90, 1000, 2 \n"
        + "".join(f"{a:.2f}\n" for a in angles)
    )
    with pytest.raises(RunFormatError, match=r"start at line 3: skip_rows=2 "):
        read_run(path, columns=["angle_deg"], sample_rate_Hz=1000.0)
    run = read_run(path, columns=["angle_deg"], sample_rate_Hz=1000.0, skip_rows=2)
    assert run.n_samples == angles.size
    assert run.length_unit == "rad"
    np.testing.assert_allclose(run.displacement, np.deg2rad(np.round(angles, 2)))


def _write(tmp_path: Path, text: str, name: str = "bad.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _good_rows(n: int = 100) -> str:
    t, x = _sine(n)
    return "".join(f"{a!r},{b!r}\n" for a, b in zip(t, x, strict=True))


BAD_TEXT = [
    ("time_s,chan_b\n" + _good_rows(), {}, "unknown column 'chan_b'.*columns="),
    ("time_s,pos\n" + _good_rows(), {}, "column 'pos' has no unit.*pos_m"),
    (_good_rows(), {}, "no header row.*columns="),
    (
        "time_s,displacement_m\n0.0,1.0\n0.001\n" + _good_rows(),
        {},
        "line 3: expected 2 field",
    ),
    (
        "time_s,displacement_m\n0.0,1.0\n0.001,abc\n",
        {},
        "line 3, column 'displacement_m': 'abc' is not a number",
    ),
    (_good_rows(), {"columns": ["time_s", "angle"]}, "column 'angle' has no unit"),
    (_good_rows(), {"columns": ["time_s", "torque_Nm"]}, "unknown column 'torque_Nm'"),
    (_good_rows(), {"columns": ["time_s", "position"]}, "column 'position' has no unit"),
    (_good_rows(), {"columns": ["time_s", "position_ft"]}, "unknown unit 'ft'"),
    (_good_rows(), {"columns": ["time_s", "time_s"]}, "'time_s' is given 2 times"),
    (
        _good_rows(),
        {"columns": ["ignore", "displacement_m"]},
        "no time column: give its sample rate, sample_rate_Hz=HZ",
    ),
    (_good_rows(), {"columns": ["time_s", "ignore"]}, "'displacement_m' or"),
    ("a,b,c\n" + _good_rows(), {"columns": ["time_s", "displacement_m"]}, "header"),
    ("", {}, "no data rows"),
    ("time_s,displacement_m\n", {}, "header but no data"),
    (
        _good_rows(),
        {"columns": ["time_s", "displacement_m"], "scale": {"velocity_m_per_s": 2}},
        "scale: column 'velocity_m_per_s' is not read",
    ),
    (
        _good_rows(),
        {"columns": ["time_s", "displacement_m"], "scale": {"displacement_m": 0}},
        "finite non-zero",
    ),
    (_good_rows(), {"columns": "time_s"}, "one name per column"),
    (_good_rows(), {"columns": ["time_s", "displacement_m"], "decimal": ";"}, "decimal"),
]


@pytest.mark.parametrize(
    ("text", "kwargs", "match"), BAD_TEXT, ids=[case[2][:32] for case in BAD_TEXT]
)
def test_bad_text_raises_naming_file_and_what_was_expected(
    tmp_path: Path, text: str, kwargs: dict, match: str
) -> None:
    path = _write(tmp_path, text)
    with pytest.raises(RunFormatError, match=match) as info:
        read_run(path, **kwargs)
    assert str(path) in str(info.value)


def test_bytes_that_are_no_numbers_are_refused_naming_the_line(tmp_path: Path) -> None:
    from bayestribo.errors import ReadingWarning

    path = tmp_path / "bin.csv"
    path.write_bytes(b"time_s,displacement_m\n\xff\xfe,1\n0.1,2\n")
    with pytest.warns(ReadingWarning, match="not UTF-8"):
        with pytest.raises(RunFormatError, match=r"bin\.csv.*line 2, column 'time_s'"):
            read_run(path)


def test_numpys_reader_and_the_row_by_row_reader_give_the_same_numbers(tmp_path: Path) -> None:
    # read_text parses a block with numpy's C reader and falls back to Python's float
    # row by row; both must give the same float64 for every way of writing a number,
    # and the fallback must take over wherever numpy's reader does not apply.
    from bayestribo.io.text import _parse_block, _parse_rows, read_text

    rng = np.random.default_rng(4)
    values = rng.standard_normal((200, 3)) * 10.0 ** rng.integers(-12, 12, (200, 3))
    values[:3] = [[0.0, -0.0, 1.0], [5e-324, 1.7976931348623157e308, -2.5], [0.5, 5.0, 1e-5]]
    styles = ("{!r}", "{:.17e}", "{:.6g}", " {!r} ", "{:+.17E}")
    lines = [
        ",".join(styles[(r + c) % len(styles)].format(float(v)) for c, v in enumerate(row))
        for r, row in enumerate(values)
    ]
    rows = list(enumerate(lines, start=2))
    keep = [(0, "time_s"), (1, "displacement_m"), (2, "velocity_m_per_s")]
    fast = _parse_block(rows, ",", 3, [0, 1, 2])
    slow = _parse_rows(rows, ",", ".", [n for _, n in keep], keep, "f")
    assert fast is not None
    np.testing.assert_array_equal(fast, slow)
    assert np.array_equal(np.signbit(fast), np.signbit(slow))
    # Python's float reads these, numpy's reader does not: the rows are read anyway.
    path = tmp_path / "odd.csv"
    path.write_text("time_s,displacement_m\n0.0,1_0\n0.001,\u0661.5\n")
    out = read_text(path)
    np.testing.assert_array_equal(out["displacement_m"], [10.0, 1.5])
    # A text column that is ignored (the first row is data, not a header), and a short
    # row that is an error naming its line.
    path.write_text("0.0,a,1.0\n0.001,b,2.0\n")
    out = read_text(path, columns=["time_s", "ignore", "displacement_m"])
    np.testing.assert_array_equal(out["displacement_m"], [1.0, 2.0])
    path.write_text("time_s,displacement_m\n0.0,1.0\n0.001\n0.002,3.0\n")
    with pytest.raises(RunFormatError, match="line 3: expected 2 field"):
        read_text(path)


def test_empty_cells_at_the_end_of_a_channel_leave_those_rows_out_and_say_so(
    tmp_path: Path,
) -> None:
    """A motion sensor's software leaves the derivative's last cells empty (the spring
    and disc recordings): those rows are left out with a warning naming them; an empty
    cell between values is an error naming its line and column."""
    from bayestribo.errors import ReadingWarning

    t, x = _sine(100)
    w = 2 * np.pi * 32.6
    v = [repr(float(1e-3 * w * np.cos(w * a + 0.3))) for a in t]
    v[-2:] = ["", ""]
    body = "".join(f"{a!r};{b!r};{c}\n" for a, b, c in zip(t, x, v, strict=True))
    path = tmp_path / "sensor.csv"
    path.write_text("time;position;velocity\n" + body)
    columns = ["time_s", "displacement_m", "velocity_m_per_s"]
    with pytest.warns(ReadingWarning, match=r"2 row\(s\).*lines 100-101.*velocity_m_per_s"):
        run = read_run(path, columns=columns)
    assert run.n_samples == 98
    np.testing.assert_array_equal(run.displacement, x[:98])
    # without the velocity nothing is left out
    run = read_run(path, columns=["time_s", "displacement_m", "ignore"])
    assert run.n_samples == 100
    v[10] = ""
    body = "".join(f"{a!r};{b!r};{c}\n" for a, b, c in zip(t, x, v, strict=True))
    path.write_text("time;position;velocity\n" + body)
    with pytest.raises(RunFormatError, match="line 12, column 'velocity_m_per_s': an empty cell"):
        read_run(path, columns=columns)


def test_the_spring_and_disc_recordings_read_with_their_velocity() -> None:
    from _paths import SPRING_DISC

    from bayestribo.errors import ReadingWarning

    paths = sorted(SPRING_DISC.glob("*.csv"))
    if not paths:
        pytest.skip(f"external data not present at {SPRING_DISC}")
    for path in paths:
        with pytest.warns(ReadingWarning, match="velocity_m_per_s"):
            run = read_run(path, columns=["time_s", "displacement_m", "velocity_m_per_s", "ignore"])
        rows = np.genfromtxt(path, delimiter=";", skip_header=1)
        full = ~np.isnan(rows[:, 2])
        np.testing.assert_array_equal(run.velocity, rows[full, 2])
        np.testing.assert_array_equal(run.displacement, rows[full, 1])


@pytest.mark.parametrize("mu", ["\u00b5", "\u03bc"], ids=["micro sign", "Greek mu"])
def test_micro_units_read_with_either_mu(tmp_path: Path, mu: str) -> None:
    """``[µm]`` typed with the micro sign or with the Greek letter: the same unit."""
    t, x = _sine()
    path = tmp_path / "um.csv"
    body = "".join(f"{a!r},{b * 1e6!r}\n" for a, b in zip(t, x, strict=True))
    path.write_text(f"time [s],displacement [{mu}m]\n" + body, encoding="utf-8")
    run = read_run(path)
    np.testing.assert_allclose(run.displacement, x, rtol=1e-12)


def test_a_last_line_cut_short_is_left_out_and_said(tmp_path: Path) -> None:
    """A file copied while it was written: its last line is incomplete. The line is
    left out with a warning naming it; a bad line elsewhere is still an error."""
    from bayestribo.errors import ReadingWarning

    t, x = _sine(200)
    body = "".join(f"{a!r},{b!r}\n" for a, b in zip(t, x, strict=True))
    path = tmp_path / "cut.csv"
    path.write_text("time_s,displacement_m\n" + body + "0.1000,1.2e-")
    with pytest.warns(ReadingWarning, match="the last line .line 202. is incomplete"):
        run = read_run(path)
    assert run.n_samples == 200
    path.write_text("time_s,displacement_m\n" + body + "0.1000")
    with pytest.warns(ReadingWarning, match="incomplete"):
        assert read_run(path).n_samples == 200
    lines = body.splitlines()
    lines[50] = lines[50][:6]
    path.write_text("time_s,displacement_m\n" + "\n".join(lines) + "\n")
    with pytest.raises(RunFormatError, match="line 52"):
        read_run(path)


def test_an_8_bit_file_is_read_as_windows_1252_and_said(tmp_path: Path) -> None:
    """A Polytec-style export written in Windows-1252 (µ as the byte 0xB5): read, the
    unit understood, with a warning naming the encoding used; --encoding reads it
    without one; a wrong encoding given is an error naming it."""
    from bayestribo.errors import ReadingWarning

    t, x = _sine()
    body = "".join(f"{a!r};{b * 1e6!r}\n" for a, b in zip(t, x, strict=True))
    path = tmp_path / "polytec.txt"
    path.write_bytes(("time [s];displacement [µm]\n" + body).encode("cp1252"))
    with pytest.warns(ReadingWarning, match="not UTF-8 .byte 0xb5.*Windows-1252.*'µ'"):
        run = read_run(path)
    np.testing.assert_allclose(run.displacement, x, rtol=1e-12)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ReadingWarning)
        assert read_run(path, encoding="cp1252").n_samples == len(t)
    with pytest.raises(RunFormatError, match="unknown text encoding 'klingon'"):
        read_run(path, encoding="klingon")
    with pytest.raises(RunFormatError, match="encoding: expected the name"):
        read_run(path, encoding=1252)


@pytest.mark.parametrize(
    ("header", "delimiter", "newline", "columns"),
    [
        ("time_s,displacement_um,velocity_mm_per_s", ",", "\n", None),
        ("time_ms;displacement_m;velocity_m_per_s", ";", "\r\n", None),
        ("\ufefftime_s\tdisplacement_m\tvelocity_m_per_s", "\t", "\n", None),
        ("", " ", "\n", ["time_s", "ignore", "displacement_m"]),
    ],
    ids=["comma-units", "semicolon-crlf", "tab-bom", "whitespace-columns"],
)
def test_the_streamed_reader_gives_the_line_by_line_numbers(
    tmp_path: Path, header: str, delimiter: str, newline: str, columns: list[str] | None
) -> None:
    """A plain file is read by numpy's C reader straight from the file; the same file
    through the line-by-line reader gives the same arrays, bit for bit."""
    from bayestribo.io.text import parse_lines, read_text

    rng = np.random.default_rng(3)
    width = 3
    rows = [
        delimiter.join(repr(float(v)) for v in rng.normal(size=width) * 10.0 ** rng.integers(-9, 3))
        for _ in range(6000)
    ]
    text = newline.join(([header] if header else []) + rows) + newline
    path = tmp_path / "run.txt"
    path.write_bytes(text.encode("utf-8"))
    streamed = read_text(path, columns=columns)
    lines = text.encode("utf-8").decode("utf-8-sig").splitlines()
    by_line = parse_lines(lines, str(path), columns=columns)
    assert list(streamed) == list(by_line)
    for name in streamed:
        np.testing.assert_array_equal(streamed[name], by_line[name])


def test_a_bad_row_far_beyond_the_head_is_still_named(tmp_path: Path) -> None:
    rows = [f"{i * 1e-4!r},{float(np.sin(i / 50))!r}" for i in range(20000)]
    rows[15000] = "1.5,oops"
    path = tmp_path / "run.csv"
    path.write_text("time_s,displacement_m\n" + "\n".join(rows) + "\n")
    with pytest.raises(RunFormatError, match=r"line 15002, column 'displacement_m': 'oops'"):
        read_run(path, validate=False)


@pytest.mark.parametrize(
    ("header", "delimiter", "decimal"),
    [
        ('"Time (s)","Position (mm)",', ",", "."),
        ("Zeit [s];Weg [mm];", ";", ","),
        ("time_s,displacement_mm,", ",", "."),
        ("Time [s]\tDisplacement [mm]\t", "\t", "."),
    ],
)
@pytest.mark.parametrize("rows", [40, 6000], ids=["short", "long"])
def test_a_delimiter_ending_every_line_ends_no_field(
    tmp_path: Path, header: str, delimiter: str, decimal: str, rows: int
) -> None:
    """A spreadsheet export's delimiter at the end of each line (the header's too) reads
    as the same file without it, through both readers."""
    t = np.arange(rows) * 1e-3
    x = np.round(5.0 * np.cos(t * 40.0), 6)
    body = [
        f"{float(a)!r}{delimiter}{float(b)!r}".replace(".", decimal)
        for a, b in zip(t, x, strict=True)
    ]
    plain = tmp_path / "plain.csv"
    plain.write_text("\r\n".join([header[:-1], *body]) + "\r\n", encoding="utf-8")
    ending = tmp_path / "ending.csv"
    ending.write_text(
        "\r\n".join([header, *(line + delimiter for line in body)]) + "\r\n", encoding="utf-8"
    )
    one, other = read_run(plain, validate=False), read_run(ending, validate=False)
    np.testing.assert_array_equal(one.time, other.time)
    np.testing.assert_array_equal(one.displacement, other.displacement)
    np.testing.assert_allclose(other.displacement, 1e-3 * x, rtol=1e-15)


def test_an_unnamed_last_column_with_values_is_not_dropped(tmp_path: Path) -> None:
    """Rows that hold a value after the header's last name keep it: refused, not cut."""
    path = tmp_path / "run.csv"
    rows = [f"{k * 1e-3!r},{np.cos(k / 9):.6f},{k}" for k in range(50)]
    path.write_text("time_s,displacement_m,\n" + "\n".join(rows) + "\n")
    with pytest.raises(RunFormatError, match=r"unknown column ''"):
        read_run(path, validate=False)


@pytest.mark.parametrize("rows", [40, 6000], ids=["short", "long"])
def test_a_header_repeated_among_the_rows_is_left_out_and_said(tmp_path: Path, rows: int) -> None:
    """Two acquisitions appended to one file, each below the same header: the repeated
    header line is named in a ReadingWarning, and the time starting over below it is a
    restart of the clock: the first acquisition is read, the second named as left out."""
    t = np.arange(rows) * 1e-3
    x = np.round(2e-3 * np.cos(t * 40.0), 9)
    header = "time_s,displacement_m"
    body = [f"{float(a)!r},{float(b)!r}" for a, b in zip(t, x, strict=True)]
    path = tmp_path / "appended.csv"
    path.write_text("\n".join([header, *body, header, *body]) + "\n")
    with pytest.warns(ReadingWarning, match=rf"line\(s\) {rows + 2} repeat the header"):
        run = read_run(path, validate=False)
    np.testing.assert_array_equal(run.time, t)
    np.testing.assert_array_equal(run.displacement, x)


@pytest.mark.parametrize("rows", [3000, 12000], ids=["short", "long"])
def test_decimal_commas_with_thousands_points_read_when_the_comma_is_given(
    tmp_path: Path, rows: int
) -> None:
    """A European spreadsheet's numbers grouped in thousands (``1.234,5``) read as the
    numbers they show with ``decimal=","``; guessed, the first such cell is named with
    the option that reads it; a point that groups no thousands is named either way."""
    t = np.arange(rows) * 0.5  # ms, past 1 000
    x = np.round(2500.0 * np.cos(t / 40.0), 2)  # µm, past ±1 000

    def european(value: float, digits: int) -> str:
        return f"{value:,.{digits}f}".replace(",", "_").replace(".", ",").replace("_", ".")

    lines = [f"{european(a, 1)};{european(b, 2)}" for a, b in zip(t, x, strict=True)]
    path = tmp_path / "run.csv"
    path.write_text("Zeit [ms];Weg [µm]\n" + "\n".join(lines) + "\n", encoding="utf-8")
    run = read_run(path, validate=False, decimal=",")
    np.testing.assert_allclose(run.time, t * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(run.displacement, x * 1e-6, rtol=1e-15)
    with pytest.raises(RunFormatError, match=r"'2\.500,00' is not a number \(.*--decimal , "):
        read_run(path, validate=False)
    lines[100] = lines[100].split(";")[0] + ";12.34,5"
    path.write_text("Zeit [ms];Weg [µm]\n" + "\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(RunFormatError, match=r"line 102, column 'displacement_m': '12.34,5'"):
        read_run(path, validate=False, decimal=",")


def test_a_video_trackers_t_x_y_columns_are_named_with_the_columns_that_read_them(
    tmp_path: Path,
) -> None:
    """Tracker's export (``mass A``, then ``t x y`` without units): the refusal names the
    columns= that reads each coordinate, and following it reads that one."""
    t = np.arange(200) / 30.0
    x = np.round(0.12 * np.cos(7.5 * t), 6)
    path = tmp_path / "tracker.txt"
    rows = [f"{a:.6E}\t{b:.6E}\t{0.3:.6E}" for a, b in zip(t, x, strict=True)]
    path.write_text("mass A\nt\tx\ty\n" + "\n".join(rows) + "\n")
    along_x = ["time_s", "displacement_m", "ignore"]
    with pytest.raises(RunFormatError, match="has no unit") as caught:
        read_run(path, validate=False)
    assert f"columns={along_x} if the motion is along x" in str(caught.value)
    assert "columns=['time_s', 'ignore', 'displacement_m'] if along y" in str(caught.value)
    run = read_run(path, columns=along_x, validate=False)
    np.testing.assert_allclose(run.displacement, x, rtol=1e-6)


def _trailing_rule(lines: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """The trailing-delimiter rule written plainly (``without_trailing_delimiter``'s
    docstring): for the first delimiter that at least two lines hold and every line
    holding it ends with, that delimiter taken off the end of each line holding it."""
    from bayestribo.io.text import _TRAILING, _line_end

    for mark in _TRAILING:
        holding = [_line_end(line, mark) for _, line in lines if mark in line]
        if len(holding) >= 2 and all(line.endswith(mark) for line in holding):
            return [(n, _line_end(line, mark)[:-1] if mark in line else line) for n, line in lines]
    return lines


@settings(max_examples=500, deadline=None)
@given(
    st.lists(
        st.text(alphabet=["1", ",", ";", "\t", " ", "a", "\r", ".", '"'], max_size=8),
        max_size=8,
    )
)
def test_the_trailing_delimiter_rule_is_the_plain_one_on_any_lines(texts):
    from bayestribo.io.text import without_trailing_delimiter

    lines = list(enumerate(texts, start=1))
    got, expected = without_trailing_delimiter(lines), _trailing_rule(lines)
    assert got == expected
    assert (got is lines) == (expected is lines)  # unchanged lines: the same list
