"""HDF5 files of named datasets."""

from __future__ import annotations

from pathlib import Path

from numpy.typing import NDArray

from bayestribo.io.hdf5 import read_hdf5
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_hdf5(path, channels=options.channels, group=options.group, scale=options.scale)


FORMAT = FileFormat.builtin("hdf5", _read)
