"""Universal File Format data-set 58 (and 58b): modal-analysis and DAQ software exports."""

from __future__ import annotations

from pathlib import Path

from numpy.typing import NDArray

from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.uff import read_uff

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_uff(path, channels=options.channels, scale=options.scale)


FORMAT = FileFormat.builtin("uff", _read)
