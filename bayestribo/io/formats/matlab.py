"""MATLAB .mat files, version 4 to 7.3."""

from __future__ import annotations

from pathlib import Path

from numpy.typing import NDArray

from bayestribo.io.matlab import read_mat
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_mat(path, channels=options.channels, scale=options.scale)


FORMAT = FileFormat.builtin("mat", _read)
