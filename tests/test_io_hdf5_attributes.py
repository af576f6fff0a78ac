"""A variable-length attribute is read only once the lengths it stores fit in the file.

libhdf5 allocates and clears a buffer of a variable-length value's stored length
before it finds the value in the global heap (:mod:`bayestribo.io.hdf5_attributes`): a
``units`` attribute stating 2^31 bytes made the reader take 2 GB.
"""

from __future__ import annotations

from pathlib import Path

import _hostile_hdf5 as hostile
import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import RunFormatError
from bayestribo.io.hdf5_attributes import _CONTINUATION, FileLayout, _messages

h5py = pytest.importorskip("h5py", reason="HDF5 files need the hdf5 extra (h5py)")


def test_a_unit_claiming_more_bytes_than_the_file_is_refused_by_name(tmp_path):
    path = hostile.vlen_unit_length(tmp_path / "unit.h5", 2**31 - 1)
    with pytest.raises(RunFormatError) as info:
        read_run(path, group="run1")
    assert str(info.value) == (
        f"{path}: dataset 'run1/displacement': attribute 'units' claims a value of "
        f"2147483647 bytes, more than the file's {path.stat().st_size}; a damaged or hostile "
        "reference into the global heap"
    )


def _run(path: Path, notes: int, **options) -> Path:
    """A run whose datasets carry ``notes`` string attributes before their units."""
    with h5py.File(path, "w", **options) as handle:
        group = handle.create_group("run1")
        time = group.create_dataset("time", data=np.arange(100) / 1e3)
        x = group.create_dataset("displacement", data=np.arange(100) / 1e3)
        for k in range(notes):
            time.attrs[f"note{k}"] = "t" * (40 * k)
            x.attrs[f"note{k}"] = "x" * 70
        time.attrs["units"] = "s"
        x.attrs["units"] = "mm"
    return path


@pytest.mark.parametrize(
    "options",
    [{}, {"libver": "latest"}, {"track_order": True}],
    ids=["old-style headers", "new-style headers", "creation order"],
)
def test_string_units_are_read_from_every_header_layout(tmp_path, options):
    path = _run(tmp_path / "run.h5", 5, **options)
    run = read_run(path, group="run1", validate=False)
    # mm read as mm (to rounding: 1e-3 x k / 1e3 and k / 1e6 may differ in the last bit)
    np.testing.assert_allclose(run.displacement, np.arange(100) / 1e6, rtol=1e-15, atol=0)


@pytest.mark.parametrize(
    ("notes", "options"),
    [(40, {}), (6, {"libver": "latest"})],
    ids=["old-style headers", "new-style headers"],
)
def test_units_past_a_header_continuation_are_found(tmp_path, notes, options):
    path = _run(tmp_path / "run.h5", notes, **options)
    with h5py.File(path, "r") as handle, open(path, "rb") as fh:
        layout = FileLayout.of(handle, fh, path.stat().st_size)
        address = h5py.h5o.get_info(handle["run1/time"].id).addr
        kinds = [kind for kind, _, _ in _messages(layout, address)]
    assert _CONTINUATION in kinds  # the header was continued: the walk followed it
    run = read_run(path, group="run1", validate=False)
    assert np.array_equal(run.time, np.arange(100) / 1e3)
    np.testing.assert_allclose(run.displacement, np.arange(100) / 1e6, rtol=1e-15, atol=0)


def test_a_variable_length_unit_in_dense_storage_is_refused_by_name(tmp_path):
    path = _run(tmp_path / "dense.h5", 12, libver="latest")
    with pytest.raises(
        RunFormatError,
        match=r"dataset 'run1/displacement': attribute 'units' is of variable length and its "
        r"stored lengths could not be checked \(kept in dense storage\)",
    ):
        read_run(path, group="run1")


def test_a_fixed_length_unit_in_dense_storage_is_read(tmp_path):
    path = tmp_path / "dense.h5"
    with h5py.File(path, "w", libver="latest") as handle:
        group = handle.create_group("run1")
        for name, unit in (("time", b"s"), ("displacement", b"mm")):
            data = group.create_dataset(name, data=np.arange(100) / 1e3)
            for k in range(12):
                data.attrs[f"note{k}"] = np.bytes_(b"n" * 70)
            data.attrs["units"] = np.bytes_(unit)
    run = read_run(path, group="run1", validate=False)
    np.testing.assert_allclose(run.displacement, np.arange(100) / 1e6, rtol=1e-15, atol=0)


def test_a_global_heap_object_running_past_its_collection_is_refused(tmp_path):
    path = hostile.heap_object_size(tmp_path / "heap.h5")
    heap = path.read_bytes().index(b"GCOL")
    with pytest.raises(RunFormatError) as info:
        read_run(path, group="run1")
    assert str(info.value) == (
        f"{path}: dataset 'run1/displacement': attribute 'units': its global heap "
        f"collection at {heap} holds an object of {2**64 - 1} bytes in 4096 bytes; a "
        "damaged global heap"
    )
