"""Damaged files of every kind give the package's error, naming the file, in bounded memory.

Each case is a class of failure the fuzz benchmark (``benchmarks/fuzz.py``) found or
the readers must refuse before reading: a library's own exception on a damaged file,
a header claiming more samples than a record has, data kept in other files.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import RunFormatError
from bayestribo.io import FileFormat, ReadOptions, register_format
from bayestribo.io.arrays import MAX_SAMPLES
from bayestribo.io.layout import describe_file
from bayestribo.synthetic import Sensor, simulate

h5py = pytest.importorskip("h5py", reason="HDF5 files need the hdf5 extra (h5py)")


@pytest.fixture(scope="module")
def run():
    return simulate(seed=3, sensor=Sensor(sample_rate_Hz=2000.0))


def test_an_empty_or_truncated_mat_file_is_refused(tmp_path: Path, run) -> None:
    import scipy.io

    empty = tmp_path / "empty.mat"
    empty.write_bytes(b"")
    with pytest.raises(RunFormatError, match=r"empty\.mat.*MATLAB"):
        read_run(empty)
    whole = tmp_path / "whole.mat"
    scipy.io.savemat(whole, {"time_s": run.time, "displacement_m": run.displacement})
    cut = tmp_path / "cut.mat"
    cut.write_bytes(whole.read_bytes()[:300])
    with pytest.raises(RunFormatError, match=r"cut\.mat"):
        read_run(cut)


def test_a_damaged_hdf5_file_is_refused_with_the_librarys_reason(tmp_path: Path, run) -> None:
    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as handle:
        handle["time_s"] = run.time
        handle["displacement_m"] = run.displacement
    data = bytearray(path.read_bytes())
    # damage the object headers and the symbol table, past the superblock
    for i in range(900, 1400, 7):
        data[i] ^= 0xFF
    bad = tmp_path / "bad.h5"
    bad.write_bytes(bytes(data))
    with pytest.raises(RunFormatError, match=r"bad\.h5.*HDF5"):
        read_run(bad)


def test_an_hdf5_dataset_claiming_too_many_samples_is_refused_before_reading(
    tmp_path: Path,
) -> None:
    path = tmp_path / "huge.h5"
    with h5py.File(path, "w") as handle:
        # no storage is written for an unfilled dataset: a 10 KB file that claims 8 GB
        handle.create_dataset("time_s", shape=(MAX_SAMPLES + 1,), dtype="f8")
        handle.create_dataset("displacement_m", shape=(MAX_SAMPLES + 1,), dtype="f8")
    assert path.stat().st_size < 100_000
    with pytest.raises(RunFormatError, match=rf"claims {MAX_SAMPLES + 1} values"):
        read_run(path)


def test_an_external_hdf5_dataset_is_not_followed(tmp_path: Path, run) -> None:
    raw = tmp_path / "elsewhere.bin"
    raw.write_bytes(np.asarray(run.displacement, dtype="<f8").tobytes())
    path = tmp_path / "links.h5"
    with h5py.File(path, "w") as handle:
        handle["time_s"] = run.time
        handle.create_dataset(
            "displacement_m",
            shape=run.displacement.shape,
            dtype="<f8",
            external=[(str(raw), 0, raw.stat().st_size)],
        )
    with pytest.raises(RunFormatError, match="keeps its data in other files"):
        read_run(path)


def test_a_mat_variable_claiming_too_many_samples_is_refused_from_its_header(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, run
) -> None:
    import scipy.io

    path = tmp_path / "big.mat"
    scipy.io.savemat(path, {"time_s": run.time, "displacement_m": run.displacement})
    monkeypatch.setattr("bayestribo.io.matlab.MAX_SAMPLES", run.time.size - 1)
    with pytest.raises(RunFormatError, match=r"claims .* values .* expected at most"):
        read_run(path)


_CHILD = """
import importlib, sys, warnings
warnings.simplefilter("ignore")
def named(text):
    module, name = text.split(":")
    return getattr(importlib.import_module(module), name)
call, error = named(sys.argv[1]), named(sys.argv[2])
for path in sys.argv[3:]:
    try:
        call(path)
        print("read", path)
    except error as exc:
        print("refused", exc)
"""


def _read_each_in_a_child(call: str, error: str, paths: list[str]) -> list[str]:
    """``call`` ("module:function") on each of ``paths`` in one child process, a line
    each: "read PATH", or "refused MESSAGE" where it raised ``error``. A crash of the
    child (a library's SIGSEGV) fails the calling test instead of ending the run."""
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", _CHILD, call, error, *paths],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    return done.stdout.splitlines()


@pytest.mark.parametrize("compress", [False, True])
def test_a_mat_array_whose_header_misstates_its_data_is_refused_not_read(
    tmp_path: Path, run, compress: bool
) -> None:
    # scipy.io.loadmat trusts an array's flags: a real array flagged complex (its
    # imaginary part missing) or stated sparse is read past its element's end, which
    # crashed the interpreter (SIGSEGV, scipy 1.17: found by benchmarks/fuzz.py), and a
    # class no MATLAB file has raised UnboundLocalError. Each is read here in a child
    # process, so that a crash fails this test instead of ending the run.
    import zlib

    import scipy.io

    whole = tmp_path / "whole.mat"
    data = {"time_s": run.time, "displacement_m": run.displacement}
    scipy.io.savemat(whole, data, do_compression=False)
    raw = whole.read_bytes()
    assert raw[136:140] == bytes([6, 0, 0, 0])  # the first array's flags (little-endian)
    files = []
    for name, offset, byte in (("complex", 145, 0x08), ("sparse", 144, 5), ("class", 144, 255)):
        damaged = bytearray(raw)
        damaged[offset] = damaged[offset] | byte if name == "complex" else byte
        if compress:  # the first variable as miCOMPRESSED, as MATLAB writes it
            size = 8 + int.from_bytes(damaged[132:136], "little")
            packed = zlib.compress(bytes(damaged[128 : 128 + size]))
            element = (15).to_bytes(4, "little") + len(packed).to_bytes(4, "little") + packed
            damaged = damaged[:128] + element + damaged[128 + size :]
        path = tmp_path / f"{name}.mat"
        path.write_bytes(bytes(damaged))
        files.append(str(path))
    lines = _read_each_in_a_child("bayestribo:read_run", "bayestribo.errors:RunFormatError", files)
    assert len(lines) == 3 and all(line.startswith("refused") for line in lines), lines
    assert "'time_s'" in lines[0] and "MATLAB" in lines[0]
    assert "class 255, not a MATLAB class" in lines[2]


def test_the_mat_header_walk_refuses_no_file_matlab_wrote() -> None:
    # SciPy's own test files, written by MATLAB 4 to 7.4 on several platforms (complex,
    # sparse, cell, structure and object arrays, strings, function handles, big- and
    # little-endian): the header walk refuses only those loadmat cannot read either.
    import scipy.io

    from bayestribo.io.mat_headers import DamagedHeader, declared_bytes, v5_variables

    files = sorted((Path(scipy.io.__file__).parent / "matlab" / "tests" / "data").glob("*.mat"))
    if not files:
        pytest.skip("this SciPy has no test files")
    refused = []
    for path in files:
        with path.open("rb") as fh:
            try:
                for variable in list(v5_variables(fh)):
                    declared_bytes(fh, variable, 1 << 34)
            except DamagedHeader:
                refused.append(str(path))
    assert len(refused) < len(files) // 4  # most of them walked
    lines = _read_each_in_a_child("scipy.io:loadmat", "builtins:Exception", refused)
    assert all(line.startswith("refused") for line in lines), lines


def test_a_broken_workbook_is_refused(tmp_path: Path, run) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    import zipfile

    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Time (s)", "Position (m)"])
    for t, x in zip(run.time[:200], run.displacement[:200], strict=True):
        sheet.append([float(t), float(x)])
    good = tmp_path / "good.xlsx"
    book.save(good)
    bad = tmp_path / "bad.xlsx"
    with zipfile.ZipFile(good) as src, zipfile.ZipFile(bad, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename.endswith("sheet1.xml"):
                data = data.replace(b"<c r=", b'<c r=""', 3)  # damaged cell references
            dst.writestr(item, data)
    with pytest.raises(RunFormatError, match=r"bad\.xlsx.*Excel"):
        read_run(bad)


def test_any_readers_library_error_becomes_the_packages_error(tmp_path: Path) -> None:
    """A registered reader whose library raises on a damaged file: read_run and
    describe_file say which file and which format, the library's message kept."""

    def read(path: Path, options: ReadOptions) -> dict:
        raise KeyError("b'\\x00\\x01' is not a known record")

    fmt = FileFormat(
        "brokenlib", "a lab's binary log", (".blog",), read, describe=lambda p, o: read(p, o)
    )
    register_format(fmt)
    try:
        path = tmp_path / "run.blog"
        path.write_bytes(b"\x00\x01")
        with pytest.raises(RunFormatError, match=r"run\.blog.*a lab's binary log file \(KeyError"):
            read_run(path)
        with pytest.raises(RunFormatError, match=r"not a readable a lab's binary log"):
            describe_file(path)
    finally:
        from bayestribo.io import registry

        registry._REGISTRY.pop("brokenlib")
        registry._READERS.pop("brokenlib")


@pytest.mark.parametrize("mass", [1e308, 1e-320, -1.0])
def test_absurd_sidecar_numbers_are_refused_naming_the_field(tmp_path: Path, run, mass) -> None:
    import json

    from bayestribo.cli import main
    from bayestribo.io import write_run

    path = write_run(run, tmp_path / "run.csv")
    meta = json.loads(path.with_suffix(".json").read_text())
    meta["mass_kg"] = mass
    path.with_suffix(".json").write_text(json.dumps(meta))
    with pytest.raises(RunFormatError, match="mass_kg"):
        read_run(path)
    assert main(["inspect", str(path)]) == 2


@pytest.mark.parametrize("huge", [1e308, -1.7e308])
def test_a_sample_near_the_largest_float_is_refused_or_named(
    tmp_path: Path, run, huge: float
) -> None:
    # the fuzz benchmark's "number" mutation: one displacement sample replaced by a
    # value whose spectrum overflows; the channel check names it (it crashed on a NaN
    # period), and without the velocity the decay analysis names it as a spike, with
    # its time and value, and leaves it out (signal/spikes.py)
    from bayestribo.errors import RecordingError, SpikeWarning
    from bayestribo.inference.pipeline import prepare
    from bayestribo.io.text import write_csv

    x = run.displacement.copy()
    x[x.size // 3] = huge
    both = write_csv(
        {"time_s": run.time, "displacement_m": x, "velocity_m_per_s": run.velocity},
        tmp_path / "both.csv",
    )
    with pytest.raises(RecordingError, match=r"both\.csv.*overflow the arithmetic of the check"):
        read_run(both)
    alone = write_csv({"time_s": run.time, "displacement_m": x}, tmp_path / "alone.csv")
    named = r"1 spike\(s\) in the displacement at t = .* \(" + re.escape(f"{huge:g}") + r"\)"
    with pytest.warns(SpikeWarning, match=named):
        prepare(read_run(alone))
