"""LabVIEW TDMS files."""

from __future__ import annotations

from pathlib import Path

from numpy.typing import NDArray

from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.tdms import read_tdms

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_tdms(path, channels=options.channels, group=options.group, scale=options.scale)


FORMAT = FileFormat.builtin("tdms", _read)
