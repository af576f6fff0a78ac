"""Reading is bounded: a small file that declares huge arrays is refused before allocation.

The budget of a file is ``min(CAP, max(FLOOR, PER_FILE_BYTE x file size))``
(:mod:`bayestribo.io.budget`); the MATLAB reader counts what the variables' headers
declare, the HDF5 reader what the picked datasets' shapes and types declare, before
either decompresses anything.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import _hostile as hostile
import numpy as np
import pytest
import scipy.io

from bayestribo import read_run
from bayestribo.errors import RunFormatError
from bayestribo.io import budget as budget_module
from bayestribo.io.budget import (
    BUDGET_VARIABLE,
    CAP_BYTES,
    FLOAT_BYTES,
    FLOOR_BYTES,
    PER_FILE_BYTE,
    read_budget,
)
from bayestribo.io.budget import _mb as shown

#: Resident memory a reader may reach on a file under 10 MB [bytes] (the goal).
RESIDENT_GOAL = 500 << 20


def test_the_budget_grows_with_the_file_between_its_floor_and_its_cap(monkeypatch):
    monkeypatch.delenv(BUDGET_VARIABLE, raising=False)
    assert read_budget(1000, "f").limit == FLOOR_BYTES
    middle = 2 * FLOOR_BYTES // PER_FILE_BYTE
    assert read_budget(middle, "f").limit == PER_FILE_BYTE * middle
    assert read_budget(10 * CAP_BYTES, "f").limit == CAP_BYTES
    monkeypatch.setenv(BUDGET_VARIABLE, "2.5")
    assert read_budget(1000, "f").limit == 2_500_000
    for bad in ("lots", "-1", "0", "inf", "nan"):
        monkeypatch.setenv(BUDGET_VARIABLE, bad)
        with pytest.raises(RunFormatError, match=f"{BUDGET_VARIABLE}: expected a positive"):
            read_budget(1000, "f")


def test_a_compressed_variable_declaring_more_than_the_budget_is_refused_by_name(tmp_path):
    # 152 MB of zeros as doubles in 150 KB: the reviewer's file held 12 of them
    zero_mb = 152
    path = hostile.write_mat(
        tmp_path / "zeros.mat", *(hostile.zeros_variable(f"v{k}", zero_mb) for k in range(12))
    )
    assert path.stat().st_size < 2_000_000
    limit = read_budget(path.stat().st_size, str(path)).limit
    expected = (
        rf"zeros\.mat: variable 'v0' \(\d+ bytes in the file\) declares at least "
        rf"{shown(zero_mb << 20)} in memory, more than the read budget of {shown(limit)} .*"
        rf"set the environment variable {BUDGET_VARIABLE}"
    )
    with pytest.raises(RunFormatError, match=expected):
        read_run(path)


def test_variables_within_the_budget_each_are_refused_together(tmp_path):
    # each 6 MB, twelve of them past the 64 MB floor: counted together
    path = hostile.write_mat(
        tmp_path / "many.mat", *(hostile.zeros_variable(f"v{k}", 6) for k in range(12))
    )
    assert read_budget(path.stat().st_size, "").limit == FLOOR_BYTES
    first_refused = FLOOR_BYTES // (6 << 20)  # the one that pushes the count past the floor
    with pytest.raises(RunFormatError, match=rf"variable 'v{first_refused}' .* after 6\d.\d MB"):
        read_run(path)


def test_doubles_stored_as_bytes_count_as_the_doubles_they_declare(tmp_path):
    # MATLAB stores small whole numbers as bytes: 10 MB inflated, 80 MB declared
    path = hostile.write_mat(
        tmp_path / "bytes.mat", hostile.zeros_variable("x", 10, stored_as=hostile.MI_UINT8)
    )
    assert (10 << 20) < FLOOR_BYTES < (80 << 20)
    with pytest.raises(RunFormatError, match=rf"variable 'x' .* at least {shown(80 << 20)}"):
        read_run(path)


def test_a_structure_field_counts_in_its_variable(tmp_path):
    path = hostile.write_mat(tmp_path / "struct.mat", hostile.struct_variable("data", "x", 96))
    with pytest.raises(RunFormatError, match=r"variable 'data' .* read budget"):
        read_run(path, channels={"time_s": "data.t", "displacement_m": "data.x"})


def _genuine(rate_Hz: float, duration_s: float) -> dict[str, np.ndarray]:
    """A quantised free decay with noise, as a board records it."""
    t = np.arange(int(rate_Hz * duration_s)) / rate_Hz
    rng = np.random.default_rng(1)
    counts = np.round(
        3000 * np.exp(-t / 0.3) * np.sin(2 * np.pi * 32.6 * t) + rng.normal(0, 2, t.size)
    )
    return {"time_s": t, "displacement_m": counts * 1e-7}


def test_a_genuine_record_reads_and_only_the_named_variables_are_loaded(tmp_path, monkeypatch):
    # a 1 MHz record (0.4 s of it: the budget is proportional to the file, so 10 s read
    # the same way), compressed, beside a variable declaring far more than the budget
    monkeypatch.delenv(BUDGET_VARIABLE, raising=False)
    base = tmp_path / "base.mat"
    signals = _genuine(1e6, 0.4)
    scipy.io.savemat(
        base, {"t": signals["time_s"], "x": signals["displacement_m"]}, do_compression=True
    )
    declared = sum(v.size for v in signals.values()) * FLOAT_BYTES
    path = hostile.write_mat(
        tmp_path / "record.mat", hostile.zeros_variable("junk", 2000), base=base
    )
    assert read_budget(path.stat().st_size, "").limit >= declared  # the record itself fits
    run = read_run(path, channels={"time_s": "t", "displacement_m": "x"}, validate=False)
    assert np.array_equal(run.displacement, signals["displacement_m"])
    with pytest.raises(RunFormatError, match=r"variable 'junk'"):
        read_run(path, validate=False)  # without channels every variable is loaded


def _hdf5_files(h5py, tmp_path: Path) -> tuple[Path, Path]:
    """A file declaring 120 MB in a chunked, compressed, unwritten dataset, and a
    genuine record beside such a dataset."""
    empty = tmp_path / "empty.h5"
    with h5py.File(empty, "w") as handle:
        handle.create_dataset(
            "time_s", shape=(15_000_000,), dtype="f8", chunks=(4096,), compression="gzip"
        )
        handle.create_dataset(
            "displacement_m", shape=(15_000_000,), dtype="f8", chunks=(4096,), compression="gzip"
        )
    beside = tmp_path / "beside.h5"
    signals = _genuine(2000.0, 2.0)
    with h5py.File(beside, "w") as handle:
        for name, values in signals.items():
            handle[name] = values
        handle.create_dataset(
            "junk", shape=(15_000_000,), dtype="f8", chunks=(4096,), compression="gzip"
        )
    return empty, beside


def test_an_hdf5_dataset_declaring_more_than_the_budget_is_refused_by_name(tmp_path):
    h5py = pytest.importorskip("h5py", reason="HDF5 files need the hdf5 extra (h5py)")
    empty, beside = _hdf5_files(h5py, tmp_path)
    assert empty.stat().st_size < 100_000
    limit = read_budget(empty.stat().st_size, "").limit
    with pytest.raises(
        RunFormatError,
        match=rf"dataset '(time_s|displacement_m)' \(shape \(15000000,\), float64\) "
        rf"declares {shown(120e6)} in memory, more than the read budget of {shown(limit)}",
    ):
        read_run(empty)
    run = read_run(beside, validate=False)  # the dataset not picked is never read
    assert run.time.size == 4000


def test_no_library_code_limits_the_processs_address_space():
    # RLIMIT_AS is the whole process's: a notebook kernel or a Dask worker reading a file
    # would get MemoryError in its other threads
    package = Path(budget_module.__file__).parents[1]
    users = [p.name for p in package.rglob("*.py") if "setrlimit" in p.read_text("utf-8")]
    assert users == []


CHILD = """
import json, sys
from bayestribo import read_run
from bayestribo.errors import RunFormatError
refused = {}
for path in sys.argv[1:]:
    try:
        read_run(path)
    except RunFormatError as exc:
        refused[path] = str(exc)
# the peak of this process's own memory (VmHWM, reset by exec; ru_maxrss is not: it
# would count the pages of the test process this one was forked from)
with open("/proc/self/status") as fh:
    peak = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM:"))
print(json.dumps({"refused": refused, "peak": peak}))
"""


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc (Linux)")
def test_hostile_small_files_stay_far_below_half_a_gigabyte_resident(tmp_path):
    files = [
        hostile.write_mat(
            tmp_path / "zeros.mat", *(hostile.zeros_variable(f"v{k}", 152) for k in range(12))
        ),
        hostile.write_mat(
            tmp_path / "bytes.mat", hostile.zeros_variable("x", 19, stored_as=hostile.MI_UINT8)
        ),
    ]
    try:
        import h5py

        files.append(_hdf5_files(h5py, tmp_path)[0])
    except ImportError:
        pass
    assert all(f.stat().st_size < 10_000_000 for f in files)
    out = subprocess.run(
        [sys.executable, "-c", CHILD, *map(str, files)],
        capture_output=True,
        text=True,
        check=True,
        env={
            **__import__("os").environ,
            "PYTHONPATH": str(Path(budget_module.__file__).parents[2]),
        },
    )
    result = json.loads(out.stdout)
    assert sorted(result["refused"]) == sorted(map(str, files))
    assert all("read budget" in message for message in result["refused"].values())
    assert result["peak"] < RESIDENT_GOAL


def _workbook(path: Path, rows: str) -> Path:
    """A workbook of one worksheet whose rows are the XML ``rows`` after a header row."""
    import zipfile

    openpyxl = pytest.importorskip("openpyxl", reason="Excel files need the formats extra")
    seed = path.with_name("seed.xlsx")
    book = openpyxl.Workbook()
    book.active.append(["time_s", "displacement_m"])
    book.save(seed)
    with zipfile.ZipFile(seed) as source, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as out:
        for name in source.namelist():
            data = source.read(name)
            if name == "xl/worksheets/sheet1.xml":
                text = data.decode()
                end = text.index("</sheetData>")
                text = text[:end].replace('<dimension ref="A1:B1" />', "") + rows + text[end:]
                data = text.encode()
            out.writestr(name, data)
    return path


def test_a_workbook_whose_parts_declare_more_than_the_budget_is_refused_unparsed(tmp_path):
    # 2 million rows of repeated XML: 82 MB declared in a file of well under 1 MB
    row = "<row><c><v>0</v></c><c><v>0</v></c></row>"
    path = _workbook(tmp_path / "bomb.xlsx", row * 2_000_000)
    assert path.stat().st_size < 1_000_000
    with pytest.raises(
        RunFormatError,
        match=r"bomb\.xlsx: the workbook's \d+ parts \(largest part 'xl/worksheets/sheet1\.xml'\)"
        rf" declares .* more than the read budget of {shown(FLOOR_BYTES)}",
    ):
        read_run(path)


def test_a_worksheets_cells_are_counted_as_they_are_read(tmp_path, monkeypatch):
    from bayestribo.io.formats.excel import CELL_BYTES

    rows = "".join(f'<row r="{i}"><c><v>{i}</v></c><c><v>0</v></c></row>' for i in range(2, 3000))
    path = _workbook(tmp_path / "cells.xlsx", rows)
    assert read_run(path, validate=False).time.size == 2998
    monkeypatch.setenv(BUDGET_VARIABLE, str(1000 * CELL_BYTES / 1e6))  # 1000 cells
    with pytest.raises(RunFormatError, match=r"the worksheet \(1002 cells to row 501\) declares"):
        read_run(path, validate=False)


def test_a_tdms_channel_is_counted_before_its_data_are_read(tmp_path, monkeypatch):
    nptdms = pytest.importorskip("nptdms", reason="TDMS files need the formats extra")
    path = tmp_path / "run.tdms"
    with nptdms.TdmsWriter(str(path)) as writer:
        writer.write_segment(
            [
                nptdms.ChannelObject("g", "t", np.arange(4000) / 2000.0),
                nptdms.ChannelObject("g", "x", np.zeros(4000)),
            ]
        )
    channels = {"time_s": "t", "displacement_m": "x"}
    assert read_run(path, channels=channels, validate=False).time.size == 4000
    monkeypatch.setenv(BUDGET_VARIABLE, str(6000 * FLOAT_BYTES / 1e6))  # 1.5 channels
    with pytest.raises(
        RunFormatError, match=r"TDMS channel 'g/x' \(4000 values of float64\) declares 32 kB"
    ):
        read_run(path, channels=channels, validate=False)
