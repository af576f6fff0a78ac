"""NumPy files: ``.npz`` archives of named arrays, ``.npy`` arrays of columns."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo.io.numpy_files import describe_numpy, read_numpy
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_numpy(path, channels=options.channels, columns=options.columns, scale=options.scale)


def _describe(path: Path, options: ReadOptions) -> dict[str, Any]:
    return describe_numpy(path)


FORMAT = FileFormat.builtin("npz", _read, describe=_describe)
