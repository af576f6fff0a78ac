"""Text files whose time column holds absolute time stamps (data loggers, Arduino
sketches, phone sensor apps): read with no option as seconds from the first sample,
in every common spelling, the first sample's date and time kept in the metadata; a
pass through midnight, time zones, day-first dates and bad cells; and a free decay
written with ISO stamps fitted with its truth inside the intervals."""

from __future__ import annotations

import contextlib
import datetime as dt
import io
import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from _free_decay import METADATA, X_C, ZETA, free_decay
from hypothesis import given, settings
from hypothesis import strategies as st

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.text import read_text
from bayestribo.io.timestamps import StampError, parse_stamps
from bayestribo.signal.decay import check_time

#: The first sample's date and time, and the seconds written after it: 100 Hz with a
#: microsecond in some stamps (the reading must keep every one).
START = dt.datetime(2026, 11, 30, 9, 15, 2, 120000)
SECONDS = np.round(np.arange(400) / 100.0 + np.where(np.arange(400) % 7 == 3, 1e-6, 0.0), 6)
#: A slowly decaying oscillation [mm], any values: the time is what is tested.
POSITION_MM = 20.0 * np.exp(-0.2 * SECONDS) * np.cos(2.0 * math.pi * 2.0 * SECONDS)


def _stamp(seconds: float, zone: dt.timezone | None = None) -> dt.datetime:
    return (START + dt.timedelta(microseconds=round(seconds * 1e6))).replace(tzinfo=zone)


def _iso(stamp: dt.datetime, sep: str = " ") -> str:
    return stamp.isoformat(sep=sep, timespec="microseconds")


def _day_first(stamp: dt.datetime) -> str:
    return stamp.strftime("%d/%m/%Y %H:%M:%S,%f")


def _toolbox(stamp: dt.datetime) -> str:
    # Physics Toolbox: milliseconds after a third colon (whole milliseconds only)
    return stamp.strftime("%H:%M:%S:") + f"{stamp.microsecond // 1000:03d}"


#: (header of the time column(s), cell writer, delimiter, decimal comma, seconds).
SPELLINGS = {
    "Timestamp, ISO with a blank": ("Timestamp", _iso, ",", False),
    "Time stamp, ISO with T": ("Time stamp", lambda s: _iso(s, "T"), ",", False),
    "Date Time, UTC (Z)": (
        "Date Time",
        lambda s: _iso(s.replace(tzinfo=dt.UTC), "T").replace("+00:00", "Z"),
        ",",
        False,
    ),
    "DateTime, +01:00": (
        "DateTime",
        lambda s: _iso(s.replace(tzinfo=dt.timezone(dt.timedelta(hours=1))), "T"),
        ",",
        False,
    ),
    "Date/Time, day first, decimal comma": ("Date/Time", _day_first, ";", True),
    "Time, a time of day": ("Time", lambda s: s.strftime("%H:%M:%S.%f"), "\t", False),
    "Date and Time columns": (
        "Date,Time",
        lambda s: s.strftime("%Y-%m-%d,%H:%M:%S.%f"),
        ",",
        False,
    ),
}


def _write(path: Path, header: str, cells: list[str], delimiter: str, comma: bool) -> Path:
    values = [f"{x:.6f}".replace(".", ",") if comma else f"{x:.6f}" for x in POSITION_MM]
    rows = [f"{c}{delimiter}{v}" for c, v in zip(cells, values, strict=True)]
    name = "Position (mm)"
    path.write_text(f"{header.replace(',', delimiter)}{delimiter}{name}\n" + "\n".join(rows))
    return path


@pytest.mark.parametrize("spelling", list(SPELLINGS))
def test_each_spelling_reads_as_seconds_from_the_first_sample(tmp_path, spelling) -> None:
    header, cell, delimiter, comma = SPELLINGS[spelling]
    cells = [cell(_stamp(s)) for s in SECONDS]
    path = _write(tmp_path / "stamps.csv", header, cells, delimiter, comma)
    run = read_run(path, metadata={"length_unit": "m"})
    assert run.time.size == SECONDS.size
    assert np.max(np.abs(run.time - SECONDS)) < 1e-6
    np.testing.assert_allclose(run.displacement, POSITION_MM * 1e-3, rtol=0, atol=1e-9)
    written = cell(_stamp(0.0))
    start = run.metadata["start_time"]
    if "Time, a time of day" == spelling:
        assert start == "09:15:02.120000"
    else:
        assert dt.datetime.fromisoformat(start).replace(tzinfo=None) == START, written
    if "+01:00" in spelling:
        assert start.endswith("+01:00")


def test_physics_toolbox_milliseconds_after_a_colon(tmp_path) -> None:
    whole_ms = np.arange(300) * 0.01 + np.where(np.arange(300) % 5 == 2, 0.003, 0.0)
    cells = [_toolbox(_stamp(s)) for s in whole_ms]
    path = tmp_path / "toolbox.csv"
    path.write_text(
        "time,x (m)\n"
        + "\n".join(f"{c},{x!r}" for c, x in zip(cells, whole_ms.tolist(), strict=True))
    )
    out = read_text(path)
    assert np.max(np.abs(out["time_s"] - whole_ms)) < 1e-6
    assert out["start_time"] == "09:15:02.120000"


def test_stamps_separated_by_blanks_with_the_date_and_time_split(tmp_path) -> None:
    path = tmp_path / "logger.txt"
    rows = [f"{_iso(_stamp(s))}   {x:.6f}" for s, x in zip(SECONDS, POSITION_MM, strict=True)]
    path.write_text("Date Time   Position (mm)\n" + "\n".join(rows) + "\n")
    out = read_text(path)
    assert np.max(np.abs(out["time_s"] - SECONDS)) < 1e-6
    np.testing.assert_allclose(out["displacement_m"], POSITION_MM * 1e-3, atol=1e-9)


def test_a_pass_through_midnight_adds_a_day_and_says_so(tmp_path) -> None:
    first = dt.datetime(2026, 11, 30, 23, 59, 59, 500000)
    seconds = np.arange(200) * 0.01
    cells = [(first + dt.timedelta(seconds=float(s))).strftime("%H:%M:%S.%f") for s in seconds]
    path = tmp_path / "midnight.csv"
    path.write_text("Time,x (mm)\n" + "\n".join(f"{c},{i % 3}" for i, c in enumerate(cells)) + "\n")
    with pytest.warns(ReadingWarning, match=r"passes midnight at line 52 .*a day is added"):
        out = read_text(path)
    assert np.max(np.abs(out["time_s"] - seconds)) < 1e-6
    assert out["start_time"] == "23:59:59.500000"


def test_dated_stamps_cross_midnight_without_a_warning(tmp_path) -> None:
    first = dt.datetime(2026, 11, 30, 23, 59, 59, 500000)
    seconds = np.arange(200) * 0.01
    cells = [_iso(first + dt.timedelta(seconds=float(s))) for s in seconds]
    path = tmp_path / "dated.csv"
    path.write_text("Timestamp,x (mm)\n" + "\n".join(f"{c},1" for c in cells) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReadingWarning)
        out = read_text(path)
    assert np.max(np.abs(out["time_s"] - seconds)) < 1e-6


def test_zones_are_put_on_one_clock(tmp_path) -> None:
    # the same instants written in two zones (a logger whose clock changes zone)
    zones = [dt.timezone(dt.timedelta(hours=1)), dt.timezone(dt.timedelta(hours=-5, minutes=-30))]
    utc = [_stamp(s).replace(tzinfo=dt.UTC) for s in SECONDS]
    cells = [_iso(u.astimezone(zones[i >= 200]), "T") for i, u in enumerate(utc)]
    assert cells[0].endswith("+01:00") and cells[-1].endswith("-05:30")
    path = tmp_path / "zones.csv"
    path.write_text("Timestamp,x (mm)\n" + "\n".join(f"{c},1" for c in cells) + "\n")
    out = read_text(path)
    assert np.max(np.abs(out["time_s"] - SECONDS)) < 1e-6
    assert dt.datetime.fromisoformat(out["start_time"]) == utc[0]


def test_a_zone_on_some_cells_only_is_refused(tmp_path) -> None:
    cells = [_iso(_stamp(s), "T") for s in SECONDS[:5]]
    cells[3] += "Z"
    path = tmp_path / "mixed.csv"
    path.write_text("Timestamp,x (mm)\n" + "\n".join(f"{c},1" for c in cells) + "\n")
    with pytest.raises(RunFormatError, match=r"line 5, column 'Timestamp'.* two clocks"):
        read_text(path)


@pytest.mark.parametrize("bad", ["12.5", "2026-11-30 09:15:xx", "2026-11-31 09:15:02", ""])
def test_a_cell_that_is_no_date_and_time_is_named(tmp_path, bad) -> None:
    cells = [_iso(_stamp(s)) for s in SECONDS[:40]]
    cells[17] = bad
    path = tmp_path / "bad.csv"
    path.write_text("Timestamp,x (mm)\n" + "\n".join(f"{c},1" for c in cells) + "\n")
    where = "line 19, column 'Timestamp'" if bad else "line 19, column 'time_s'"
    with pytest.raises(RunFormatError, match=re.escape(where)) as caught:
        read_run(path, metadata={"length_unit": "m"})
    if bad:
        assert repr(bad) in str(caught.value)


def test_dates_that_read_both_ways_are_refused_naming_both(tmp_path) -> None:
    cells = [f"0{d}/11/2026 09:15:0{d},000" for d in range(1, 6)]
    path = tmp_path / "ambiguous.csv"
    path.write_text("Date/Time;x (mm)\n" + "\n".join(f"{c};1,0" for c in cells) + "\n")
    with pytest.raises(
        RunFormatError, match=r"line 2.*'01/11/2026 09:15:01,000'.*2026-11-01\).*2026-01-11\)"
    ):
        read_text(path)


def test_month_first_dates_are_read_where_a_day_above_12_tells(tmp_path) -> None:
    stamps = [dt.datetime(2026, 11, 12, 23, 59, 59) + dt.timedelta(seconds=i) for i in range(4)]
    cells = [s.strftime("%m/%d/%Y %H:%M:%S") for s in stamps]
    assert cells[-1].startswith("11/13/")
    np.testing.assert_array_equal(parse_stamps(cells).offsets_us, [0, 1e6, 2e6, 3e6])


def test_the_fast_and_the_cell_by_cell_readings_agree() -> None:
    # cells of one layout go column-wise, others (no leading zero, a trimmed fraction,
    # a blank before the zone) one by one: both give the same microseconds
    regular = ["2026-11-30 09:15:02.120000+01:00", "2026-11-30 09:15:03.000000+01:00"]
    other = ["2026-11-30 9:15:02.12 +01:00", "2026-11-30 09:15:03+0100"]
    fast, slow = parse_stamps(regular), parse_stamps(other)
    np.testing.assert_array_equal(fast.offsets_us, [0, 880_000])
    np.testing.assert_array_equal(slow.offsets_us, fast.offsets_us)
    assert slow.start == fast.start == "2026-11-30T09:15:02.120000+01:00"


def test_stamps_rounded_to_a_millisecond_read_as_jitter(tmp_path) -> None:
    # 300 Hz written to the millisecond: steps of 3 and 4 ms, the clock's rounding
    exact = np.arange(900) / 300.0
    rounded = np.round(exact, 3)
    cells = [_iso(_stamp(s))[:-3] for s in rounded]
    x = np.exp(-0.3 * exact) * np.cos(2.0 * math.pi * 5.0 * exact)
    path = tmp_path / "rounded.csv"
    path.write_text(
        "Timestamp,x (mm)\n"
        + "\n".join(f"{c},{v!r}" for c, v in zip(cells, x.tolist(), strict=True))
    )
    run = read_run(path, metadata={"length_unit": "m"})
    assert run.time.size == exact.size
    assert np.max(np.abs(run.time - exact)) <= 0.5e-3 + 1e-9  # within the rounding
    # the analysis takes the regular grid the stamps scatter about (least squares):
    # 300 Hz, not the median step's 333 Hz. Rounding errors of sd 1 ms/√12 over 900
    # stamps leave the grid's step an sd of 1.1e-5 of itself (σ √(12/N³) / h) and its
    # origin about 2e-5 s: checked at about 4.5 sd, ten times inside the rounding
    grid = check_time(run.time)
    np.testing.assert_allclose(np.diff(grid), 1.0 / 300.0, rtol=5e-5)
    assert np.max(np.abs(grid - exact)) < 1e-4


def test_numeric_time_columns_are_read_as_before(tmp_path) -> None:
    path = tmp_path / "numbers.csv"
    path.write_text(
        "Recorded: 2026-11-30 09:15:02\nTime (s),x (mm)\n"
        + "\n".join(
            f"{s!r},{x!r}" for s, x in zip(SECONDS.tolist(), POSITION_MM.tolist(), strict=True)
        )
    )
    out = read_text(path)
    np.testing.assert_array_equal(out["time_s"], SECONDS)
    assert "start_time" not in out


def test_an_iso_stamped_free_decay_is_fitted_with_its_truth_inside_the_intervals(
    tmp_path,
) -> None:
    # the helper's decay (2 kHz) slowed twentyfold: 1 Hz written at 100 Hz with ISO stamps
    slow = 20.0
    decay = free_decay()
    seconds, x = decay.time * slow, decay.displacement
    path = tmp_path / "logger.csv"
    rows = [f"{_iso(_stamp(s), 'T')[:-3]},{v!r}" for s, v in zip(seconds, x.tolist(), strict=True)]
    path.write_text("Timestamp,x (m)\n" + "\n".join(rows) + "\n")
    metadata = {**METADATA, "natural_frequency_Hz": METADATA["natural_frequency_Hz"] / slow}
    path.with_suffix(".json").write_text(json.dumps(metadata))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(["fit", str(path), "--seed", "3", "--grid-points", "32", "--json"])
    assert status == 0
    record = json.loads(out.getvalue())
    assert record["metadata"]["start_time"] == "2026-11-30T09:15:02.120000"
    for name, truth in (("zeta", ZETA), ("friction_displacement", X_C)):
        low, high = record["parameters"][name]["interval"]
        assert low < truth < high, (name, low, high, truth)


def _large(path: Path, rows: int = 4000, bad: int | None = None) -> Path:
    """A file beyond the reader's first 64 kB: read by the columns' parser."""
    seconds = np.arange(rows) * 0.001
    cells = [_iso(_stamp(s)) for s in seconds]
    if bad is not None:
        cells[bad] = "2026-11-30 09:61:00.000000"
    x = np.sin(seconds * 40.0).tolist()
    path.write_text(
        "# logger 2.1\nTimestamp,x (mm),v (mm/s)\n"
        + "\n".join(f"{c},{a!r},{2 * a!r}" for c, a in zip(cells, x, strict=True))
        + "\n"
    )
    assert path.stat().st_size > 1 << 16
    return path


def test_a_large_file_reads_column_wise_as_the_line_reader_reads_it(tmp_path, monkeypatch) -> None:
    from bayestribo.io import bulk_text
    from bayestribo.io.text import parse_lines

    calls = []
    read = bulk_text.read_with_text
    monkeypatch.setattr(bulk_text, "read_with_text", lambda *a: calls.append(a) or read(*a))
    path = _large(tmp_path / "large.csv")
    fast = read_text(path)
    assert len(calls) == 1
    slow = parse_lines(path.read_text().splitlines(), str(path))
    assert (
        fast.keys() == slow.keys() == {"time_s", "displacement_m", "velocity_m_per_s", "start_time"}
    )
    for name in ("time_s", "displacement_m", "velocity_m_per_s"):
        np.testing.assert_array_equal(fast[name], slow[name])
    assert np.max(np.abs(fast["time_s"] - np.arange(4000) * 0.001)) < 1e-6


def test_a_bad_cell_far_in_a_large_file_is_named(tmp_path) -> None:
    path = _large(tmp_path / "large.csv", bad=3500)
    with pytest.raises(RunFormatError, match=r"line 3503, column 'Timestamp': '2026-11-30 09:61"):
        read_text(path)


def test_start_time_in_metadata_is_checked_as_iso_text() -> None:
    from bayestribo.io.run import check_metadata

    for good in ("2026-11-30T09:15:02.120000+01:00", "09:15:02.120000"):
        assert check_metadata({"start_time": good})["start_time"] == good
    for bad in ("30/11/2026 09:15", 12.0):
        with pytest.raises(RunFormatError, match=r"metadata 'start_time': expected a date"):
            check_metadata({"start_time": bad})


def test_inspect_says_the_stamps_are_read_as_seconds(tmp_path, capsys) -> None:
    header, cell, _, _ = SPELLINGS["Date and Time columns"]
    path = _write(tmp_path / "stamps.csv", header, [cell(_stamp(s)) for s in SECONDS], ",", False)
    assert main(["inspect", str(path), "--length-unit", "m"]) == 0
    shown = capsys.readouterr().out
    assert "time stamps in 'Date Time': seconds from the first sample" in shown
    assert "start_time 2026-11-30T09:15:02.120000" in shown


def test_stamps_beside_a_time_column_of_the_files_own_are_not_the_time(tmp_path) -> None:
    # a logger writing both: the seconds column is the time, the first stamp is kept
    path = tmp_path / "both.csv"
    offset = 0.25  # the seconds column's own origin, not the first stamp's
    rows = [
        f"{_iso(_stamp(s))},{s + offset!r},{x!r}"
        for s, x in zip(SECONDS.tolist(), POSITION_MM.tolist(), strict=True)
    ]
    path.write_text("Timestamp,Time (s),Position (mm)\n" + "\n".join(rows) + "\n")
    out = read_text(path)
    np.testing.assert_array_equal(out["time_s"], SECONDS + offset)
    assert out["start_time"] == "2026-11-30T09:15:02.120000"


def _written(stamp: dt.datetime, layout: tuple[str, int, bool, bool]) -> str:
    """A stamp as a logger may write it: date order, fraction digits, zone, padding."""
    order, digits, zone, padded = layout
    date = {"iso": "%Y-%m-%d %H:%M:%S", "T": "%Y-%m-%dT%H:%M:%S", "dmy": "%d/%m/%Y %H:%M:%S"}
    text = stamp.strftime(date[order])
    if digits:
        text += "." + f"{stamp.microsecond:06d}"[:digits]
    if not padded:  # an hour without its leading zero: read cell by cell
        text = re.sub(r"([ T])0(\d):", r"\g<1>\2:", text)
    return text + ("+02:00" if zone else "")


@settings(max_examples=60, deadline=None)
@given(
    first=st.datetimes(dt.datetime(1990, 1, 13), dt.datetime(2090, 1, 1)),
    steps=st.lists(st.integers(1, 10**10), min_size=1, max_size=30),
    order=st.sampled_from(["iso", "T", "dmy"]),
    digits=st.integers(0, 6),
    zone=st.booleans(),
    padded=st.lists(st.booleans(), min_size=31, max_size=31),
)
def test_any_layout_reads_the_microseconds_written(
    first, steps, order, digits, zone, padded
) -> None:
    unit = 10 ** (6 - digits)  # the stamps hold whole units of the last digit written
    first = first.replace(microsecond=first.microsecond // unit * unit)
    offsets = np.cumsum([0, *[s // unit * unit or unit for s in steps]])
    stamps = [first + dt.timedelta(microseconds=int(o)) for o in offsets]
    if order == "dmy":
        stamps[0] = stamps[0].replace(day=13)  # a day above 12 tells the order
        offsets = np.array([int((s - stamps[0]) / dt.timedelta(microseconds=1)) for s in stamps])
    cells = [_written(s, (order, digits, zone, p)) for s, p in zip(stamps, padded, strict=False)]
    read = parse_stamps(cells)
    np.testing.assert_array_equal(read.offsets_us, offsets)
    expected = stamps[0].replace(tzinfo=dt.timezone(dt.timedelta(hours=2)) if zone else None)
    assert dt.datetime.fromisoformat(read.start) == expected


def test_an_excel_column_of_dates_and_times_reads_as_seconds(tmp_path) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Date/Time", "Position (mm)"])
    # a workbook keeps a time to the millisecond (a fraction of a day, which openpyxl
    # rounds there): the stamps written hold whole milliseconds
    seconds = np.arange(400) * 0.01 + np.where(np.arange(400) % 7 == 3, 0.001, 0.0)
    for s, x in zip(seconds.tolist(), POSITION_MM.tolist(), strict=True):
        sheet.append([_stamp(s), x])
    path = tmp_path / "logger.xlsx"
    book.save(path)
    run = read_run(path, metadata={"length_unit": "m"})
    assert np.max(np.abs(run.time - seconds)) < 1e-6
    assert run.metadata["start_time"] == "2026-11-30T09:15:02.120000"


@pytest.mark.parametrize(
    ("cells", "said"),
    [
        (["2026-11-30T09:15:02+01:75", "2026-11-30T09:15:03+01:00"], "no time zone"),
        (["2026-11-30T09:15:02+25:00", "2026-11-30T09:15:03+25:00"], "no time zone"),
        (["0000-01-01 00:00:00", "0000-01-01 00:00:01"], "no date of the calendar"),
        (["00/05/2026 09:15:02", "01/05/2026 09:15:02"], "no date of the calendar"),
        (["2026-11-30 24:00:00", "2026-11-30 23:00:01"], "no time of day"),
    ],
)
def test_impossible_stamps_are_refused_naming_the_cell(cells, said) -> None:
    with pytest.raises(StampError, match=said) as caught:
        parse_stamps(cells)
    assert repr(cells[caught.value.row].strip()) in str(caught.value)


@settings(max_examples=150, deadline=None)
@given(
    st.lists(
        st.text(alphabet="0123456789-/.:T Z+,", min_size=0, max_size=30)
        | st.sampled_from(["2026-11-30 09:15:02.120", "09:15:02:120", "31/12/2026 23:59:59"]),
        min_size=1,
        max_size=8,
    )
)
def test_any_text_is_read_or_refused_as_a_stamp_error(cells) -> None:
    try:
        parse_stamps(cells)
    except StampError as exc:
        assert 0 <= exc.row < len(cells)
