"""HDF5 datasets whose stored chunks decode past what they declare are refused unread.

libhdf5 inflates a chunk whole, whatever its chunk shape says
(:mod:`bayestribo.io.hdf5_storage`): these small files made a reader reach a gigabyte
resident. Each is refused by name, before libhdf5 decodes anything; ordinary filtered
files read exactly as h5py reads them.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import _hostile_hdf5 as hostile
import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import RunFormatError
from bayestribo.io import hdf5_storage
from bayestribo.io.hdf5 import read_hdf5

h5py = pytest.importorskip("h5py", reason="HDF5 files need the hdf5 extra (h5py)")

#: Resident memory a reader may reach on a file under 10 MB [bytes] (the goal).
RESIDENT_GOAL = 500 << 20


def _refused(path: Path) -> str:
    with pytest.raises(RunFormatError) as info:
        read_run(path, **({} if path.suffix == ".mat" else {"group": "run1"}))
    return str(info.value)


@pytest.mark.parametrize("passes", [1, 2])
def test_a_chunk_inflating_past_its_shape_is_refused_naming_the_dataset_and_chunk(tmp_path, passes):
    path = hostile.inflating_chunk(tmp_path / "bomb.h5", 4, passes=passes)
    message = _refused(path)
    filters = ", ".join(["deflate"] * passes)
    assert message.startswith(f"{path}: dataset 'run1/displacement': its chunk at (0,) ")
    assert f"filters {filters}) decodes to more than 80 bytes; expected the 80 bytes" in message
    assert "chunk shape (10,) (float64)" in message


def test_a_matlab_v73_variable_inflating_past_its_chunk_is_refused(tmp_path):
    path = hostile.inflating_chunk(tmp_path / "bomb.mat", 4, passes=2, v73=True)
    assert "dataset 'displacement_m': its chunk at (0,)" in _refused(path)


def test_a_chunk_shape_past_the_read_budget_is_refused_before_any_chunk_is_read(
    tmp_path, monkeypatch
):
    path = hostile.huge_chunk(tmp_path / "chunk.h5", 128)
    read = []
    monkeypatch.setattr(hdf5_storage, "_decode", lambda *a: read.append(a))
    message = _refused(path)
    assert "dataset 'run1/displacement': its chunks (shape (16777216,), float64)" in message
    assert "declare 134 MB each, more than the read budget of 67.1 MB" in message
    assert read == []


def test_a_filter_whose_output_cannot_be_bounded_is_refused_by_name(tmp_path):
    path = hostile.scaleoffset_count(tmp_path / "scaled.h5", 1 << 28)
    message = _refused(path)
    assert "dataset 'run1/displacement' is stored with the filter scaleoffset (filter 6)" in message
    assert "expected only deflate, shuffle, fletcher32" in message


def _lzf_chunk(path: Path, stream: bytes) -> Path:
    """A displacement of ten values in one 80-byte LZF chunk holding ``stream``."""
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        hostile._time(group)
        group.create_dataset(
            "displacement",
            shape=(hostile.SAMPLES,),
            dtype="<f8",
            chunks=(hostile.SAMPLES,),
            compression="lzf",
        )
        group["displacement"].attrs["units"] = "m"
        group["displacement"].id.write_direct_chunk((0,), stream, 0)
    return path


def test_an_lzf_chunk_inflating_past_its_shape_is_refused(tmp_path):
    # one literal byte, then back references of 264 bytes (3 bytes each): 1 MB of zeros
    stream = b"\x00\x00" + b"\xe0\xff\x00" * 4000
    message = _refused(_lzf_chunk(tmp_path / "lzf_bomb.h5", stream))
    assert (
        "its chunk at (0,) (" in message and "filters lzf) decodes to more than 80 bytes" in message
    )


@pytest.mark.parametrize(
    ("stream", "why"),
    [
        (b"\x1f\x00\x01", "a literal run past its end"),
        (b"\x00\x00\x20\x05", "a reference before its start"),
        (b"\x00\x00\xe0", "a reference past its end"),
    ],
)
def test_a_chunk_that_is_not_lzf_data_is_refused(tmp_path, stream, why):
    message = _refused(_lzf_chunk(tmp_path / "noise.h5", stream))
    assert f"filters lzf) is not readable LZF data ({why})" in message


def test_a_chunk_decoding_to_less_than_its_shape_is_refused(tmp_path):
    path = tmp_path / "short.h5"
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        hostile._time(group)
        dsid = hostile._filtered(group, "displacement", hostile.SAMPLES, ["deflate"])
        dsid.write_direct_chunk((0,), __import__("zlib").compress(bytes(40)), 0)
    assert "decodes to 40 bytes; expected the 80 bytes" in _refused(path)


def test_a_chunk_that_is_not_deflate_data_is_refused(tmp_path):
    path = tmp_path / "noise.h5"
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        hostile._time(group)
        dsid = hostile._filtered(group, "displacement", hostile.SAMPLES, ["deflate"])
        dsid.write_direct_chunk((0,), b"not a zlib stream at all", 0)
    message = _refused(path)
    assert "dataset 'run1/displacement': its chunk at (0,) (" in message
    assert "filters deflate) is not readable deflate data (" in message


def _ordinary(path: Path) -> dict[str, np.ndarray]:
    """A file of every layout the reader meets, its values as written."""
    rng = np.random.default_rng(3)
    values = {
        "gzip": rng.normal(size=1003),  # edge chunk partly past the end
        "shuffled": rng.normal(size=1000).astype(">f4"),
        "checked": rng.integers(-(10**6), 10**6, size=777).astype("<i4"),
        "plain_chunks": rng.normal(size=500),
        "contiguous": rng.normal(size=300),
        "matrix": rng.normal(size=(7, 301)),
        "sparse": np.zeros(4000),  # chunks never written: the fill value
        "odd_bytes": rng.integers(-128, 128, size=1000).astype("i1"),  # 33-byte checksums
        "narrow": rng.integers(-(2**23), 2**23, size=500).astype("<i4"),  # stored in 24 bits
        "lzf": np.repeat(rng.normal(size=125), 8),  # runs: back references, some overlapping
        "lzf_shuffled": rng.normal(size=1000).astype("<f4"),
    }
    with h5py.File(path, "w") as handle:
        handle.create_dataset("gzip", data=values["gzip"], chunks=(100,), compression="gzip")
        handle.create_dataset(
            "shuffled", data=values["shuffled"], chunks=(64,), compression=9, shuffle=True
        )
        handle.create_dataset(
            "checked",
            data=values["checked"],
            chunks=(50,),
            compression="gzip",
            shuffle=True,
            fletcher32=True,
        )
        handle.create_dataset("plain_chunks", data=values["plain_chunks"], chunks=(30,))
        handle.create_dataset("contiguous", data=values["contiguous"])
        handle.create_dataset("matrix", data=values["matrix"], chunks=(3, 40), compression="gzip")
        sparse = handle.create_dataset(
            "sparse",
            shape=(4000,),
            dtype="f8",
            chunks=(256,),
            compression="gzip",
            fillvalue=2.5,
            maxshape=(None,),
        )
        sparse[1000:1100] = 0.0
        handle.create_dataset("odd_bytes", data=values["odd_bytes"], chunks=(33,), fletcher32=True)
        narrow = h5py.h5t.STD_I32LE.copy()
        narrow.set_precision(24)
        dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
        dcpl.set_chunk((100,))
        dcpl.set_deflate(4)
        space = h5py.h5s.create_simple((500,))
        h5py.h5d.create(handle.id, b"narrow", narrow, space, dcpl=dcpl).write(
            h5py.h5s.ALL, h5py.h5s.ALL, values["narrow"]
        )
        handle.create_dataset("lzf", data=values["lzf"], chunks=(100,), compression="lzf")
        handle.create_dataset(
            "lzf_shuffled",
            data=values["lzf_shuffled"],
            chunks=(128,),
            compression="lzf",
            shuffle=True,
            fletcher32=True,
        )
        values["sparse"][:] = 2.5
        values["sparse"][1000:1100] = 0.0
    return values


def test_ordinary_datasets_of_every_layout_read_as_h5py_reads_them(tmp_path, monkeypatch):
    path = tmp_path / "ordinary.h5"
    values = _ordinary(path)
    checked = []
    original = hdf5_storage._decode
    monkeypatch.setattr(hdf5_storage, "_decode", lambda *a: checked.append(a) or original(*a))
    from bayestribo.io.arrays import NamedArray
    from bayestribo.io.budget import read_budget
    from bayestribo.io.hdf5 import _datasets, _reader

    with h5py.File(path, "r") as handle:
        datasets = _datasets(h5py, handle)
        load = _reader(datasets, read_budget(path.stat().st_size, str(path)), path.stat().st_size)
        for name, expected in values.items():
            got = load(NamedArray(name, np.empty(0)))
            assert got.dtype == expected.dtype, name
            assert np.array_equal(got, expected), name
            assert np.array_equal(got, handle[name][()]), name
    # every stored filtered chunk was decoded once: gzip 11, shuffled 16, checked 16,
    # matrix 3 x 8, sparse the 2 of its 16 that values 1000-1099 fall in, odd_bytes 31,
    # narrow 5 (then read by libhdf5: its decoded chunks are not its numpy values), lzf 10,
    # lzf_shuffled 8
    assert len(checked) == 11 + 16 + 16 + 24 + 2 + 31 + 5 + 10 + 8


def test_a_damaged_checksum_is_refused_naming_the_chunk(tmp_path):
    path = tmp_path / "checked.h5"
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        hostile._time(group)
        group.create_dataset(
            "displacement",
            data=np.arange(10.0),
            chunks=(10,),
            compression="gzip",
            fletcher32=True,
        ).attrs["units"] = "m"
        offset = group["displacement"].id.get_chunk_info(0).byte_offset
    data = bytearray(path.read_bytes())
    data[offset + 2] ^= 0x01  # inside the deflate stream's data
    path.write_bytes(bytes(data))
    assert "its chunk at (0,) (" in _refused(path)
    assert "fails its Fletcher-32 checksum (damaged data)" in _refused(path)


CHILD = """
import json, sys
from bayestribo import read_run
from bayestribo.errors import RunFormatError
refused = {}
for path in sys.argv[1:]:
    try:
        read_run(path, **({} if path.endswith(".mat") else {"group": "run1"}))
    except RunFormatError as exc:
        refused[path] = str(exc)
with open("/proc/self/status") as fh:
    peak = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM:"))
print(json.dumps({"refused": refused, "peak": peak}))
"""


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc (Linux)")
def test_hostile_hdf5_files_stay_far_below_half_a_gigabyte_resident(tmp_path):
    # each made libhdf5 allocate a gigabyte (or crash) before its chunks were checked
    files = [
        hostile.inflating_chunk(tmp_path / "once.h5", 1024),
        hostile.inflating_chunk(tmp_path / "twice.h5", 1024, passes=2),
        hostile.inflating_chunk(tmp_path / "twice.mat", 1024, passes=2, v73=True),
        hostile.huge_chunk(tmp_path / "chunk.h5", 1024),
        hostile.scaleoffset_count(tmp_path / "scaled.h5", 1 << 28),
        hostile.vlen_unit_length(tmp_path / "unit.h5", 2**31 - 1),  # 2 GB, its attribute
    ]
    assert all(f.stat().st_size < 10_000_000 for f in files)
    out = subprocess.run(
        [sys.executable, "-c", CHILD, *map(str, files)],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": str(Path(hdf5_storage.__file__).parents[2])},
    )
    result = json.loads(out.stdout)
    assert sorted(result["refused"]) == sorted(map(str, files))
    assert result["peak"] < RESIDENT_GOAL


def test_read_hdf5_reads_the_same_signals_with_the_check(tmp_path, monkeypatch):
    path = tmp_path / "run.h5"
    t = np.arange(2000) / 1000.0
    x = 1e-3 * np.exp(-t) * np.cos(40 * t)
    with h5py.File(path, "w") as handle:
        handle.create_dataset("time", data=t, chunks=(256,), compression="gzip").attrs["units"] = (
            "s"
        )
        handle.create_dataset(
            "displacement", data=1e6 * x, chunks=(256,), compression="gzip", shuffle=True
        ).attrs["units"] = "um"
    checked = read_hdf5(path)
    monkeypatch.setattr("bayestribo.io.hdf5.read_dataset", lambda dataset, *a: dataset[()])
    unchecked = read_hdf5(path)
    assert checked.keys() == unchecked.keys()
    for key in checked:
        assert np.array_equal(checked[key], unchecked[key])


class _WithoutChunkIter:
    """A dataset's id whose libhdf5 cannot iterate over its chunk index."""

    def __init__(self, dsid) -> None:
        self._dsid = dsid

    def chunk_iter(self, visit) -> None:
        raise NotImplementedError("HDF5 1.14 or later")

    def __getattr__(self, name):
        return getattr(self._dsid, name)


def test_the_chunks_are_listed_alike_with_and_without_the_index_iterator(tmp_path):
    path = tmp_path / "ordinary.h5"
    _ordinary(path)
    with h5py.File(path, "r") as handle:
        for name in ("gzip", "matrix", "sparse"):
            data = handle[name]
            args = (data.chunks, data.shape, name, str(path))
            iterated = hdf5_storage._stored_chunks(data.id, *args)
            looked_up = hdf5_storage._stored_chunks(_WithoutChunkIter(data.id), *args)
            assert len(iterated) == data.id.get_num_chunks() > 0
            assert sorted(iterated) == sorted(looked_up), name


def test_a_damaged_fill_value_is_not_asked_for_when_every_chunk_is_stored(tmp_path):
    # libhdf5 crashed (SIGSEGV) asked for a fill value whose message claims 2 GB
    path = tmp_path / "fill.h5"
    values = np.arange(200.0)
    with h5py.File(path, "w", libver="earliest") as handle:
        handle.create_dataset("time", data=values / 1e3).attrs["units"] = np.bytes_(b"s")
        handle.create_dataset("displacement", data=values, chunks=(50,), compression="gzip")
        handle["displacement"].attrs["units"] = np.bytes_(b"m")
    data = bytearray(path.read_bytes())
    # the fill value message: type 5, 8 bytes, constant; version 2, times, defined, size 0
    message = bytes.fromhex("0500080001000000020302010000000000")[:16]
    at = data.index(message)
    data[at + 12 : at + 16] = b"\x00\x00\x00\x80"
    path.write_bytes(bytes(data))
    run = read_run(path, validate=False)
    assert np.array_equal(run.displacement, values)
