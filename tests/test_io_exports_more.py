"""Sensor-software exports read with no option, continued: a header of names with blanks
in a blank-separated file, and a preamble that states the sample rate."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.layout import describe_file
from bayestribo.io.sidecar import sidecar_path, write_sidecar
from bayestribo.io.text import PREAMBLE_RATE, read_text, text_layout

N = 2000
META = {"natural_frequency_Hz": 3.0}


def _motion(rate: float) -> tuple[list[float], list[float], list[float]]:
    """Time [s], displacement [m] and velocity [m/s] of a 3 Hz free decay at ``rate``."""
    t = np.arange(N) / rate
    x = 1e-2 * np.exp(-0.4 * t) * np.cos(2 * np.pi * 3.0 * t)
    return t.tolist(), x.tolist(), np.gradient(x, t).tolist()


T, X, V = _motion(1000.0)


def _write(path: Path, head: str, rows: list[str], encoding: str = "utf-8") -> Path:
    path.write_text(head + "\n" + "\n".join(rows) + "\n", encoding=encoding)
    write_sidecar(META, sidecar_path(path))
    return path


# --- A header of names with blanks over blank-separated numbers --------------------------


@pytest.mark.parametrize(
    ("header", "separator"),
    [
        ("Time (s)    Position (mm)", " "),
        ("Time (s)  Position (mm)", "    "),
        ("Time (s)\tPosition (mm)", " "),  # a tab between the names, blanks in the rows
        ("Time (s) Position (mm)", " "),  # one blank: split after the unit's bracket
        ("Time [s]   Position [mm]", "\t "),
    ],
    ids=["runs of blanks", "wide rows", "a tab", "after the bracket", "square brackets"],
)
def test_a_blank_separated_header_of_names_with_units_needs_no_option(
    tmp_path: Path, header: str, separator: str
) -> None:
    rows = [f"{t!r}{separator}{1e3 * x!r}" for t, x in zip(T, X, strict=True)]
    run = read_run(_write(tmp_path / "logger.txt", header, rows))
    np.testing.assert_array_equal(run.time, T)
    # millimetres in the header: metres in the run
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    assert np.max(np.abs(run.displacement)) == pytest.approx(1e-2, rel=1e-12)


def test_three_named_columns_and_a_preamble_above_them(tmp_path: Path) -> None:
    head = "Logger export v2.1\nOperator: A. Smith\n\nTime (ms)   Position (µm)   Velocity (mm/s)"
    rows = [f"{1e3 * t!r}   {1e6 * x!r}   {1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    path = _write(tmp_path / "logger.txt", head, rows)
    run = read_run(path)
    np.testing.assert_allclose(run.time, T, rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)
    layout = describe_file(path)
    assert [c["label"] for c in layout["columns"]] == [
        "Time (ms)",
        "Position (µm)",
        "Velocity (mm/s)",
    ]
    assert "2 preamble line(s) skipped" in layout["reader"]


def test_angles_in_degrees_under_a_blank_separated_header(tmp_path: Path) -> None:
    angle = np.degrees(np.asarray(X) * 10.0).tolist()  # a swing of 0.1 rad
    rows = [f"{t!r} {a!r}" for t, a in zip(T, angle, strict=True)]
    run = read_run(_write(tmp_path / "encoder.txt", "Time (s) Angle (deg)", rows))
    assert run.metadata["length_unit"] == "rad"
    np.testing.assert_allclose(run.displacement, np.radians(angle), rtol=1e-15, atol=0)


def test_velocity_alone_under_a_blank_separated_header(tmp_path: Path) -> None:
    rows = [f"{t!r}  {v!r}" for t, v in zip(T, V, strict=True)]
    run = read_run(_write(tmp_path / "vibrometer.txt", "Time (s)  Velocity (m/s)", rows))
    assert run.displacement is None
    np.testing.assert_array_equal(run.velocity, V)


def test_an_ambiguous_blank_separated_header_is_refused_and_columns_reads_it(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """'Time (s) Angle  Position (mm)' over two numbers a row: is the second column the
    angle or the position? Either split is possible; neither is guessed."""
    header = "Time (s) Angle  Position (mm)"
    rows = [f"{t!r} {1e3 * x!r}" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "rig.txt", header, rows)
    with pytest.raises(
        RunFormatError, match=r"header \(line 1\) 'Time \(s\) Angle  Position"
    ) as info:
        read_run(path)
    message = str(info.value)
    assert "more than one way" in message and "columns=[...]" in message
    assert "['Time (s) Angle', 'Position (mm)']" in message
    assert "['Time (s)', 'Angle  Position (mm)']" in message
    # the fix it names, followed: the header is skipped as one line of two names
    run = read_run(path, columns=["time_s", "displacement_mm"])
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    # and on the command line
    assert main(["inspect", str(path)]) == 2
    assert "--columns" in capsys.readouterr().err
    assert main(["inspect", str(path), "--columns", "t", "displacement_mm", "--json"]) == 0


def test_a_blank_separated_header_that_splits_into_no_column_count_is_refused(
    tmp_path: Path,
) -> None:
    rows = [f"{t!r} {1e3 * x!r}" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "odd.txt", "Time s Position mm", rows)
    with pytest.raises(RunFormatError, match=r"header \(line 1\)"):
        read_run(path)


def test_the_command_line_reads_a_blank_separated_header(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    rows = [f"{t!r}    {1e3 * x!r}" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "logger.txt", "Time (s)    Position (mm)", rows)
    assert main(["inspect", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["samples"]["n"] == N
    assert report["displacement"]["max"] == pytest.approx(max(X), rel=1e-12)


# --- A preamble that states the sample rate ----------------------------------------------


@pytest.mark.parametrize(
    ("statement", "rate"),
    [
        ("Sample rate: 1 kHz", 1000.0),
        ("Sampling rate = 500 Hz", 500.0),
        ("Fs: 2000", 2000.0),
        ("Sample interval: 0.001 s", 1000.0),
        ("dt = 1 ms", 1000.0),
        ("Samples per second: 200", 200.0),
        ("Sample interval: 250 us", 4000.0),
        ("Sample rate (Hz): 1000", 1000.0),
        ("# Sampling rate: 2 kS/s", 2000.0),
        ("Sample rate\t0.5\tkHz", 500.0),
    ],
)
def test_a_preamble_rate_times_a_file_without_a_time_column(
    tmp_path: Path, statement: str, rate: float
) -> None:
    _, x, _ = _motion(rate)
    head = f"Encoder log\nDate: 2024-03-12\n{statement}\nPosition (mm)"
    path = _write(tmp_path / "encoder.txt", head, [repr(1e3 * v) for v in x])
    with pytest.warns(ReadingWarning, match="from the preamble's") as record:
        run = read_run(path)
    said = " ".join(str(w.message) for w in record)
    assert repr(statement.lstrip("# ")) in said and "(line 3)" in said
    np.testing.assert_array_equal(run.time, np.arange(N) / rate)
    np.testing.assert_allclose(run.displacement, x, rtol=1e-15, atol=0)
    assert run.metadata["sample_rate_Hz"] == rate


def test_a_preamble_rate_above_numbers_named_by_columns(tmp_path: Path) -> None:
    """No header: the lines above the numbers are skipped, and the rate among them read."""
    _, x, _ = _motion(2000.0)
    path = tmp_path / "laser.txt"
    path.write_text("Laser sensor\nSample rate: 2 kHz\n" + "\n".join(map(repr, x)) + "\n")
    with pytest.warns(ReadingWarning, match=r"t = i / 2000 Hz.*'Sample rate: 2 kHz' \(line 2\)"):
        run = read_run(path, columns=["displacement_m"], metadata=META)
    np.testing.assert_array_equal(run.time, np.arange(N) / 2000.0)


def test_a_preamble_rate_in_windows_1252_and_with_decimal_commas(tmp_path: Path) -> None:
    """The line-by-line reader (not UTF-8, decimal commas) finds the rate as well."""
    _, x, _ = _motion(10_000.0)
    rows = [repr(1e6 * v).replace(".", ",") for v in x]
    head = "Vibrometer\nSample interval: 100 µs\nDisplacement [µm]"
    path = _write(tmp_path / "psv.txt", head, rows, encoding="cp1252")
    with pytest.warns(ReadingWarning) as record:
        run = read_run(path)
    assert any("'Sample interval: 100 µs' (line 2)" in str(w.message) for w in record)
    np.testing.assert_array_equal(run.time, np.arange(N) / 10_000.0)
    np.testing.assert_allclose(run.displacement, x, rtol=1e-15, atol=0)


def test_a_rate_given_wins_when_it_agrees_and_is_refused_when_it_does_not(
    tmp_path: Path,
) -> None:
    head = "Sample rate: 1 kHz\nPosition (mm)"
    path = _write(tmp_path / "encoder.txt", head, [repr(1e3 * x) for x in X])
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReadingWarning)  # nothing to say: the rate is given
        run = read_run(path, sample_rate_Hz=1000.0)
    np.testing.assert_array_equal(run.time, np.arange(N) / 1000.0)
    with pytest.raises(
        RunFormatError,
        match=r"sample rate given.*500 Hz but the preamble's "
        r"'Sample rate: 1 kHz' \(line 1\) states 1000 Hz.*skip_rows=1",
    ):
        read_run(path, sample_rate_Hz=500.0)
    with pytest.raises(RunFormatError, match=r"metadata's sample_rate_Hz is 500 Hz"):
        read_run(path, metadata={**META, "sample_rate_Hz": 500.0})
    write_sidecar({**META, "sample_rate_Hz": 500.0}, sidecar_path(path))
    with pytest.raises(RunFormatError, match=r"sidecar encoder\.json is 500 Hz.*'Sample rate"):
        read_run(path)
    # the fix it names, followed: the preamble's line left out, the sidecar's rate used
    _, x, _ = _motion(500.0)
    _write(path, head, [repr(1e3 * v) for v in x])
    write_sidecar({**META, "sample_rate_Hz": 500.0}, sidecar_path(path))
    run = read_run(path, skip_rows=1)
    np.testing.assert_array_equal(run.time, np.arange(N) / 500.0)


def test_a_preamble_rate_beside_a_time_column_must_agree_with_it(tmp_path: Path) -> None:
    jitter = np.asarray(T) + 2e-6 * np.sin(np.arange(N))  # a logger's clock, within 1 %
    rows = [f"{t!r}\t{1e3 * x!r}" for t, x in zip(jitter.tolist(), X, strict=True)]
    header = "Time (s)\tPosition (mm)"
    agrees = _write(tmp_path / "agrees.txt", "Sampling rate = 1 kHz\n" + header, rows)
    run = read_run(agrees)
    np.testing.assert_array_equal(run.time, jitter)
    wrong = _write(tmp_path / "wrong.txt", "Device: logger\nSampling rate = 2 kHz\n" + header, rows)
    with pytest.raises(
        RunFormatError,
        match=r"'Sampling rate = 2 kHz' \(line 2\) states a sample rate of 2000 Hz but the "
        r"time column's stamps are 1000 Hz apart",
    ) as info:
        read_run(wrong)
    assert "skip_rows=2" in str(info.value)
    assert read_run(wrong, skip_rows=2).time.size == N
    # a rate 1.5 % off is refused as well; a time column in ms read as s would be 1000x
    off = _write(tmp_path / "off.txt", "Sample rate: 1015 Hz\n" + header, rows)
    with pytest.raises(RunFormatError, match="1015 Hz but the time column"):
        read_run(off)


@pytest.mark.parametrize(
    "statement",
    [
        "Sample rate: 10 mHz",  # millihertz is no megahertz: an unknown unit
        "Sample rate: 1,000 Hz",  # a thousands mark or a decimal comma: not guessed
        "dt = 0.001",  # s or ms? not guessed
        "Sample rate: fast",
        "Sample rate: 1 kHz (nominal)",
        "Sample rate: 1 000 Hz",
    ],
)
def test_a_rate_line_that_cannot_be_read_is_a_preamble_line_and_no_rate(
    tmp_path: Path, statement: str
) -> None:
    untimed = _write(tmp_path / "untimed.txt", f"{statement}\nPosition (mm)", map(repr, X))
    with pytest.raises(RunFormatError, match="no time column: give its sample rate"):
        read_run(untimed)
    assert PREAMBLE_RATE not in read_text(untimed)
    rows = [f"{t!r},{x!r}" for t, x in zip(T, X, strict=True)]
    timed = _write(tmp_path / "timed.csv", f"{statement}\nTime (s),Position (m)", rows)
    np.testing.assert_array_equal(read_run(timed).displacement, X)


def test_two_preamble_lines_that_state_different_rates_are_refused(tmp_path: Path) -> None:
    head = "Sample rate: 1 kHz\nComment: resampled\nSample interval: 2 ms\nPosition (mm)"
    path = _write(tmp_path / "two.txt", head, [repr(1e3 * x) for x in X])
    with pytest.raises(
        RunFormatError,
        match=r"'Sample rate: 1 kHz' \(line 1\) states a sample rate of 1000 Hz but line 3 "
        r"'Sample interval: 2 ms' states 500 Hz",
    ):
        read_run(path)
    # two statements of one rate are one rate
    path = _write(tmp_path / "same.txt", head.replace("2 ms", "1 ms"), [repr(1e3 * x) for x in X])
    with pytest.warns(ReadingWarning, match="'Sample rate: 1 kHz'"):
        assert read_run(path).time[1] == 1e-3


def test_inspect_says_the_rate_came_from_the_preamble(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    head = "Sample rate: 1 kHz\nPosition (mm)"
    path = _write(tmp_path / "encoder.txt", head, [repr(1e3 * x) for x in X])
    layout = text_layout(path.read_text().splitlines()[:200], str(path))
    assert layout.rate is not None and layout.rate.rate_Hz == 1000.0
    assert str(layout.rate) == "the preamble's 'Sample rate: 1 kHz' (line 1)"
    assert main(["inspect", str(path), "--json"]) == 0
    out = capsys.readouterr()
    report = json.loads(out.out)
    assert report["samples"]["sample_rate_Hz"] == pytest.approx(1000.0, rel=1e-12)
    assert "no time column" in report["reading"]["reader"]
    assert "from the preamble's 'Sample rate: 1 kHz' (line 1)" in out.err


def test_a_preamble_rate_wrong_by_a_factor_is_named_by_the_plausibility_check(
    tmp_path: Path,
) -> None:
    """A preamble's rate 1000 times too high: the refusal says where the time came from."""
    from bayestribo.errors import RecordingError

    head = "Sample rate: 1 MHz\nPosition (mm)"
    path = _write(tmp_path / "encoder.txt", head, [repr(1e3 * x) for x in X])
    with (
        pytest.warns(ReadingWarning, match="1 MHz"),
        pytest.raises(
            RecordingError,
            match=r"plausibility.*i / 1e\+06 Hz, from the preamble's 'Sample rate: 1 MHz'",
        ),
    ):
        read_run(path)


def test_a_rate_line_above_a_one_column_header_is_a_preamble_not_names(tmp_path) -> None:
    """``Sample rate: 1 kHz`` over a lone header ``angle_deg``: not a row of names with a
    row of units below it (they combined into one unknown column before)."""
    import math
    import warnings

    import numpy as np

    from bayestribo import read_run

    values = 30 * np.cos(2 * np.pi * 1.5 * np.arange(500) / 1000.0)
    path = tmp_path / "encoder.txt"
    body = "\n".join(f"{v:.6f}" for v in values)
    path.write_text(f"Sample rate: 1 kHz\nangle_deg\n{body}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = read_run(path, validate=False)
    assert run.length_unit == "rad" and run.metadata["sample_rate_Hz"] == 1000.0
    assert run.displacement[0] == pytest.approx(math.radians(30.0), rel=1e-6)


def test_a_software_line_with_a_version_number_above_a_blank_separated_header(tmp_path) -> None:
    """``Logger export 2.1`` above ``time_s displacement_m velocity_m_per_s`` is a
    preamble line (one number among three fields), read past; ``0.01 overload 0.3`` (two
    numbers and a bad cell) is a row of the table, refused naming its line."""
    import numpy as np

    from bayestribo import read_run
    from bayestribo.errors import RunFormatError

    t = np.arange(400) / 200.0
    x = 1e-3 * np.exp(-0.1 * t) * np.cos(2 * np.pi * 1.3 * t)
    v = np.gradient(x, t)
    rows = "\n".join(f"{a:.17g} {b:.17g} {c:.17g}" for a, b, c in zip(t, x, v, strict=True))
    header = "time_s displacement_m velocity_m_per_s"
    path = tmp_path / "logger.txt"
    path.write_text(f"Logger export 2.1\n{header}\n{rows}\n")
    run = read_run(path, validate=False)
    np.testing.assert_array_equal(run.displacement, x)
    path.write_text(f"0.01 overload 0.3\n{header}\n{rows}\n")
    with pytest.raises(RunFormatError, match="line 1"):
        read_run(path, validate=False)
