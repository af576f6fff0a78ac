"""Whole files or none (bayestribo/_files.py)."""

from __future__ import annotations

import errno
import os
from collections import namedtuple
from pathlib import Path

import pytest

from bayestribo import _files
from bayestribo._files import atomic_file, atomic_path, temporary_names, write_bytes, write_text


def _full_after(monkeypatch, budget: int) -> None:
    real = os.write
    written = [0]

    def write(fd: int, data: bytes) -> int:
        room = budget - written[0]
        if room <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        n = real(fd, bytes(memoryview(data)[:room]))
        written[0] += n
        return n

    monkeypatch.setattr(os, "write", write)


def _left(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_new_file_has_the_mode_the_umask_gives(tmp_path: Path) -> None:
    old = os.umask(0o027)
    try:
        path = write_text(tmp_path / "a.txt", "text\n")
    finally:
        os.umask(old)
    assert path.read_text() == "text\n"
    assert path.stat().st_mode & 0o777 == 0o640


@pytest.mark.parametrize("budget", [0, 10, 70_000])
def test_a_full_disk_keeps_the_previous_file_and_names_the_target(
    tmp_path: Path, monkeypatch, budget: int
) -> None:
    path = write_bytes(tmp_path / "a.bin", b"previous")
    _full_after(monkeypatch, budget)
    with pytest.raises(OSError) as caught:
        write_bytes(path, b"x" * 100_000)
    assert caught.value.errno == errno.ENOSPC
    assert caught.value.filename == str(path)
    monkeypatch.undo()
    assert path.read_bytes() == b"previous"
    assert _left(tmp_path) == ["a.bin"]


def test_a_full_disk_leaves_no_file_where_there_was_none(tmp_path: Path, monkeypatch) -> None:
    _full_after(monkeypatch, 5)
    with pytest.raises(OSError, match="No space"):
        write_text(tmp_path / "a.txt", "more than five bytes")
    monkeypatch.undo()
    assert _left(tmp_path) == []


def test_an_error_of_the_writer_leaves_the_previous_file(tmp_path: Path) -> None:
    path = write_text(tmp_path / "t.csv", "old\n")
    with pytest.raises(ValueError, match="half way"):
        with atomic_file(path) as fh:
            fh.write("new, half")
            raise ValueError("half way")
    assert path.read_text() == "old\n"
    assert list(tmp_path.glob(temporary_names(path))) == []


def test_an_interrupt_leaves_the_previous_file(tmp_path: Path) -> None:
    path = write_text(tmp_path / "t.csv", "old\n")
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(path) as partial:
            partial.write_text("new, half")
            raise KeyboardInterrupt
    assert path.read_text() == "old\n"
    assert _left(tmp_path) == ["t.csv"]


def test_a_writer_by_name_gets_a_temporary_with_the_targets_suffix(tmp_path: Path) -> None:
    with atomic_path(tmp_path / "fig.svg") as partial:
        assert partial.parent == tmp_path and partial.suffix == ".svg"
        partial.write_text("<svg/>")
    assert (tmp_path / "fig.svg").read_text() == "<svg/>"
    assert _left(tmp_path) == ["fig.svg"]


def test_a_library_error_on_a_full_device_is_the_full_disk(tmp_path: Path, monkeypatch) -> None:
    """A writer that says the disk is full in its own words (the netCDF library's
    "HDF error") on a device with no room left is reported as ENOSPC, naming the file."""
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(_files.shutil, "disk_usage", lambda p: usage(1 << 30, 1 << 30, 0))
    with pytest.raises(OSError) as caught:
        with atomic_path(tmp_path / "fit.nc"):
            raise RuntimeError("NetCDF: HDF error")
    assert caught.value.errno == errno.ENOSPC
    assert caught.value.filename == str(tmp_path / "fit.nc")
    assert isinstance(caught.value.__cause__, RuntimeError)
    assert _left(tmp_path) == []


def test_a_library_error_with_room_on_the_device_is_its_own(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError, match="a bug"):
        with atomic_path(tmp_path / "fit.nc"):
            raise RuntimeError("a bug")
    assert _left(tmp_path) == []
