"""Exports of sensor software: PASCO Capstone, Vernier, Polytec; read right or refused
with a fix that works when followed."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.sidecar import sidecar_path, write_sidecar

RATE = 1000.0
T = (np.arange(3000) / RATE).tolist()
X = (1e-2 * np.exp(-0.4 * np.asarray(T)) * np.cos(2 * np.pi * 3.0 * np.asarray(T))).tolist()
V = np.gradient(np.asarray(X), np.asarray(T)).tolist()
META = {"natural_frequency_Hz": 3.0}


def _write(path: Path, header: str, rows: list[str], encoding: str = "utf-8") -> Path:
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding=encoding)
    write_sidecar(META, sidecar_path(path))
    return path


def test_pasco_run_labels_are_taken_off_and_acceleration_is_not_read(tmp_path: Path) -> None:
    header = (
        '"Time (s) Run #1","Position (m) Run #1","Velocity (m/s) Run #1",'
        '"Acceleration (m/s²) Run #1"'
    )
    rows = [f"{t!r},{x!r},{v!r},0.5" for t, x, v in zip(T, X, V, strict=True)]
    path = _write(tmp_path / "capstone.csv", header, rows)
    with pytest.warns(ReadingWarning, match=r"\['Acceleration \(m/s²\)'\] not read"):
        run = read_run(path)
    np.testing.assert_array_equal(run.displacement, X)
    np.testing.assert_array_equal(run.velocity, V)


def test_runs_side_by_side_are_refused_with_the_columns_that_read_each(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """Run #2 is shorter: its cells are empty in the last rows."""
    n2 = 2000
    header = (
        "Time (s) Run #1,Position (mm) Run #1,Time (s) Run #2,Position (mm) Run #2,"
        "Velocity (mm/s) Run #2"
    )
    rows = []
    for i, (t, x) in enumerate(zip(T, X, strict=True)):
        second = f"{T[i]!r},{2e3 * X[i]!r},{2e3 * V[i]!r}" if i < n2 else ",,"
        rows.append(f"{t!r},{1e3 * x!r},{second}")
    path = _write(tmp_path / "two.csv", header, rows)
    with pytest.raises(RunFormatError, match=r"2 runs side by side \(Run #1, Run #2\)") as info:
        read_run(path)
    message = str(info.value)
    assert "Run #1: columns=['time_s', 'displacement_mm', 'ignore', 'ignore', 'ignore']" in message
    # Followed in Python ...
    second = read_run(
        path, columns=["ignore", "ignore", "time_s", "displacement_mm", "velocity_mm_per_s"]
    )
    assert second.time.size == n2
    np.testing.assert_allclose(second.displacement, 2 * np.asarray(X[:n2]), rtol=1e-15)
    # ... and on the command line, where the message spells the option.
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Run #2: --columns - - t displacement_mm velocity_mm_per_s" in err
    fix = err.split("Run #2: ")[1].split()[1:]
    assert main(["inspect", str(path), "--columns", *fix, "--json"]) == 0


@pytest.mark.parametrize(
    ("angle", "rate", "scale"),
    [
        ("Angle (rad)", "Angular Velocity (rad/s)", 1.0),
        ("Angle (°)", "Angular Velocity (deg/s)", 180 / np.pi),
    ],
)
def test_rotary_runs_side_by_side_are_read_by_the_advice_followed(
    tmp_path: Path, capsys: pytest.CaptureFixture, angle: str, rate: str, scale: float
) -> None:
    """A rotary motion sensor's runs side by side, with an acceleration in m/s²: every
    column name the refusal gives reads back (an angular velocity is no 'angular_…')."""
    header = ",".join(
        f'"{name} Run #{k}"'
        for k in (1, 2)
        for name in ("Time (s)", angle, rate, "Angular Acceleration (rad/s²)")
    )
    rows = [
        ",".join(f"{value!r}" for value in (t, scale * x, scale * v, 0.0) * 2)
        for t, x, v in zip(T, X, V, strict=True)
    ]
    path = _write(tmp_path / "rotary.csv", header, rows)
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    for run in ("Run #1", "Run #2"):
        fix = err.split(f"{run}: ")[1].split(";")[0].split()[1:]
        assert main(["inspect", str(path), "--columns", *fix, "--json"]) == 0, fix
        assert "unknown column" not in capsys.readouterr().err
    with pytest.raises(RunFormatError) as info:
        read_run(path)
    first = str(info.value).split("Run #1: columns=")[1].split("; Run #2")[0]
    read = read_run(path, columns=ast.literal_eval(first))  # the list the message prints
    np.testing.assert_allclose(read.displacement, X, rtol=1e-13, atol=0)
    np.testing.assert_allclose(read.velocity, V, rtol=1e-13, atol=0)


def test_vernier_latest_labels_and_centimetres(tmp_path: Path) -> None:
    header = '"Latest: Time (s)","Latest: Position (cm)","Latest: Velocity (cm/s)"'
    rows = [f"{t!r},{100 * x!r},{100 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    run = read_run(_write(tmp_path / "vernier.csv", header, rows))
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)


def test_a_row_of_units_below_the_names(tmp_path: Path) -> None:
    rows = [f"{t!r}\t{1e3 * x!r}\t{1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    run = read_run(_write(tmp_path / "units.txt", "Time\tPosition\tVelocity\ns\tmm\tmm/s", rows))
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    assert run.time.size == len(T)


def test_polytec_brackets_and_micro_sign_in_windows_1252(tmp_path: Path) -> None:
    rows = [f"{t!r}\t{1e6 * x!r}\t{1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    header = "Time [s]\tVib Displacement [µm]\tVib Velocity [mm/s]"
    path = _write(tmp_path / "psv.txt", header.replace("Vib ", ""), rows, encoding="cp1252")
    with pytest.warns(ReadingWarning, match="not UTF-8"):
        run = read_run(path)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    run = read_run(path, encoding="cp1252")
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)


def test_a_column_of_no_known_quantity_is_still_an_error(tmp_path: Path) -> None:
    rows = [f"{t!r},{x!r},1" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "odd.csv", "Time (s),Position (m),Gizmo (V)", rows)
    with pytest.raises(RunFormatError, match="unknown column 'Gizmo"):
        read_run(path)


# --- Exports read with no option: decimal commas, a byte-order mark, a preamble ---------


def _comma(value: float) -> str:
    """A number as a European export writes it: repr with a decimal comma."""
    return repr(value).replace(".", ",")


@pytest.mark.parametrize("delimiter", [";", "\t"])
def test_decimal_commas_a_byte_order_mark_and_quoted_run_labels_need_no_option(
    tmp_path: Path, delimiter: str
) -> None:
    header = delimiter.join(
        ['"Time (s) Run #1"', '"Position (cm) Run #1"', '"Velocity (m/s) Run #1"']
    )
    rows = [
        delimiter.join((_comma(t), _comma(100 * x), _comma(v)))
        for t, x, v in zip(T, X, V, strict=True)
    ]
    path = tmp_path / "capstone.csv"
    path.write_bytes(("\ufeff" + header + "\n" + "\n".join(rows) + "\n").encode("utf-8"))
    write_sidecar(META, sidecar_path(path))
    run = read_run(path)
    np.testing.assert_array_equal(run.time, T)
    np.testing.assert_array_equal(run.velocity, V)
    # the header's centimetres are converted to metres
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    assert np.max(np.abs(run.displacement)) == pytest.approx(1e-2, rel=1e-12)


def test_the_command_line_reads_a_decimal_comma_export_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    rows = [f"{_comma(t)};{_comma(1e3 * x)}" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "logger.csv", "\ufeffTime (s);Position (mm)", rows)
    assert main(["inspect", str(path), "--json"]) == 0
    import json

    report = json.loads(capsys.readouterr().out)
    assert "decimal comma" in report["reading"]["reader"]
    assert report["samples"]["n"] == len(T)
    assert report["displacement"]["max"] == pytest.approx(max(X), rel=1e-12)


def test_a_point_beside_decimal_commas_is_refused_naming_the_cell(tmp_path: Path) -> None:
    rows = [f"{_comma(t)};{_comma(x)}" for t, x in zip(T, X, strict=True)]
    rows[5] = f"{_comma(T[5])};1.234,5"  # a thousands mark: no guess
    path = _write(tmp_path / "mixed.csv", "Time (s);Position (m)", rows)
    with pytest.raises(RunFormatError, match=r"line 7, column 'displacement_m': '1\.234,5'"):
        read_run(path)


def test_empty_trailing_cells_of_a_derivative_in_a_decimal_comma_export(
    tmp_path: Path,
) -> None:
    rows = [
        f"{_comma(t)};{_comma(1e3 * x)};" + ("" if i >= len(T) - 3 else _comma(1e3 * v))
        for i, (t, x, v) in enumerate(zip(T, X, V, strict=True))
    ]
    path = _write(tmp_path / "derived.csv", '"Time (s)";"Position (mm)";"Velocity (mm/s)"', rows)
    with pytest.warns(ReadingWarning, match=r"3 row\(s\).*lines 2999-3001.*velocity_m_per_s"):
        run = read_run(path)
    assert run.time.size == len(T) - 3
    np.testing.assert_allclose(run.displacement, X[:-3], rtol=1e-15, atol=0)
    np.testing.assert_allclose(run.velocity, V[:-3], rtol=1e-15, atol=0)


PREAMBLE = (
    "Vibrometer export 4.2\n"
    "Date: 12.03.2024 10:31\n"
    "Temperature: 21.5 °C\n"
    "Measurement range: 500 µm\n"
    "Sample rate: 1 kHz\n"
    "\n"
)


@pytest.mark.parametrize(
    ("header", "skipped"),
    [
        ("Time [ms]\tDisplacement [µm]\tVelocity [mm/s]", 5),
        ("Time\tDisplacement\tVelocity\nms\tµm\tmm/s", 5),
        # Vernier Format 2: a run name, then names, short names and units
        ("Latest\nTime\tDisplacement\tVelocity\nt\tx\tv\nms\tµm\tmm/s", 7),
    ],
    ids=["units in the names", "a row of units", "Vernier Format 2"],
)
def test_a_vibrometer_preamble_in_windows_1252_is_skipped(
    tmp_path: Path, header: str, skipped: int
) -> None:
    rows = [f"{1e3 * t!r}\t{1e6 * x!r}\t{1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    path = _write(tmp_path / "vib.txt", PREAMBLE + header, rows, encoding="cp1252")
    with pytest.warns(ReadingWarning, match="not UTF-8"):
        run = read_run(path)
    np.testing.assert_allclose(run.time, T, rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)
    from bayestribo.io.layout import describe_file

    layout = describe_file(path, encoding="cp1252")
    assert f"{skipped} preamble line(s) skipped" in layout["reader"]
    assert "µm" in layout["columns"][1]["label"]


def test_a_bad_row_above_the_numbers_is_named_not_skipped_as_a_preamble(tmp_path: Path) -> None:
    rows = [f"{t!r},{x!r}" for t, x in zip(T, X, strict=True)]
    rows[0] = f"{T[0]!r},overload"
    path = _write(tmp_path / "bad.csv", "Time (s),Position (m)", rows)
    with pytest.raises(RunFormatError, match=r"line 2, column 'displacement_m': 'overload'"):
        read_run(path)


def test_phyphox_accelerations_beside_a_position_are_not_read_and_alone_without_a_decay_are_refused(
    tmp_path: Path,
) -> None:
    axes = '"Acceleration x (m/s^2)","Acceleration y (m/s^2)","Absolute acceleration (m/s^2)"'
    rows = [f"{t!r},{x!r},0.1,0.2,9.81" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "phyphox.csv", f'"Time (s)","Position (m)",{axes}', rows)
    with pytest.warns(ReadingWarning, match=r"'Acceleration x \(m/s\^2\)'.*not read"):
        run = read_run(path)
    np.testing.assert_array_equal(run.displacement, X)
    rows = [f"{t!r},0.1,0.2,9.81" for t in T]
    path = _write(tmp_path / "accelerometer.csv", f'"Time (s)",{axes}', rows)
    # constant axes hold no free decay (tests/test_io_acceleration.py reads one that does)
    with pytest.raises(RunFormatError, match="do not move along one line"):
        read_run(path)


# --- Files without a time column: the sample rate gives it -------------------------------


def test_one_column_without_a_header_reads_with_its_sample_rate(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """An encoder's file: one reading per line, no header, no time."""
    path = tmp_path / "encoder.txt"
    path.write_text("\n".join(repr(1e3 * x) for x in X) + "\n")
    options = {"columns": ["displacement_mm"], "metadata": {"natural_frequency_Hz": 3.0}}
    with pytest.raises(RunFormatError, match=r"no time column.*sample_rate_Hz=HZ"):
        read_run(path, **options)
    run = read_run(path, sample_rate_Hz=RATE, **options)
    np.testing.assert_array_equal(run.time, np.arange(len(X)) / RATE)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    assert run.metadata["sample_rate_Hz"] == RATE
    # the command line: no option, the error's fix, then the fix followed
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert "--columns displacement_mm and --sample-rate HZ" in err
    assert main(["inspect", str(path), "--columns", "displacement_mm"]) == 2
    assert '--sample-rate HZ, or "sample_rate_Hz" in the sidecar encoder.json' in (
        capsys.readouterr().err
    )
    cli = ["inspect", str(path), "--columns", "displacement_mm", "--sample-rate", "1000"]
    assert main([*cli, "--frequency", "3", "--json"]) == 0
    import json

    report = json.loads(capsys.readouterr().out)
    assert report["samples"]["sample_rate_Hz"] == pytest.approx(RATE, rel=1e-12)
    assert "no time column" in report["reading"]["reader"]


def test_a_displacement_column_reads_with_the_sidecars_sample_rate(tmp_path: Path) -> None:
    rows = [repr(1e3 * x) for x in X]
    path = tmp_path / "position.csv"
    path.write_text("Position (mm)\n" + "\n".join(rows) + "\n")
    write_sidecar({**META, "sample_rate_Hz": 500.0}, sidecar_path(path))
    run = read_run(path)
    np.testing.assert_array_equal(run.time, np.arange(len(X)) / 500.0)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    # the rate given overrides the sidecar's
    run = read_run(path, sample_rate_Hz=RATE)
    np.testing.assert_array_equal(run.time, np.arange(len(X)) / RATE)


def test_a_sample_rate_that_is_no_rate_or_disagrees_is_refused(tmp_path: Path) -> None:
    from bayestribo.errors import RecordingError

    rows = [f"{t!r},{x!r}" for t, x in zip(T, X, strict=True)]
    timed = _write(tmp_path / "timed.csv", "Time (s),Position (m)", rows)
    with pytest.raises(RecordingError, match=r"'sample_rate_Hz' is 2000\.0 Hz but the time"):
        read_run(timed, sample_rate_Hz=2 * RATE)
    assert read_run(timed, sample_rate_Hz=RATE).time.size == len(T)
    untimed = _write(tmp_path / "untimed.csv", "Position (m)", [repr(x) for x in X])
    for bad in (0, -5.0, float("nan"), "fast", True):
        with pytest.raises(RunFormatError, match=r"sample_rate_Hz: expected a sample rate"):
            read_run(untimed, sample_rate_Hz=bad)
    with pytest.raises(RunFormatError, match=r"sample_rate_Hz is 1000\.0 Hz but metadata gives"):
        read_run(untimed, sample_rate_Hz=RATE, metadata={"sample_rate_Hz": 10.0})
    # a rate 1000 times too high: the refusal says where the time came from
    with pytest.raises(RecordingError, match=r"plausibility.*i / 1e\+06 Hz, from the sample rate"):
        read_run(untimed, sample_rate_Hz=1e3 * RATE)
    with pytest.raises(SystemExit):
        main(["inspect", str(untimed), "--sample-rate", "0"])


def test_a_worksheet_of_one_column_reads_with_its_sample_rate(tmp_path: Path) -> None:
    openpyxl = pytest.importorskip("openpyxl", reason="Excel files need the formats extra")
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Position (mm)"])
    for x in X:
        sheet.append([1e3 * x])
    path = tmp_path / "column.xlsx"
    book.save(path)
    run = read_run(path, sample_rate_Hz=RATE, metadata=META)
    np.testing.assert_array_equal(run.time, np.arange(len(X)) / RATE)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)


def test_matlab_channels_named_without_time_read_with_the_sample_rate(tmp_path: Path) -> None:
    scipy_io = pytest.importorskip("scipy.io")
    path = tmp_path / "laser.mat"
    scipy_io.savemat(path, {"pos": 1e3 * np.asarray(X)})
    run = read_run(path, channels={"displacement_mm": "pos"}, sample_rate_Hz=RATE, metadata=META)
    np.testing.assert_array_equal(run.time, np.arange(len(X)) / RATE)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
