"""WAV files: a sound card's, an audio interface's or a recorder's channels."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.wav import describe_wav, read_wav

__all__ = ["FORMAT"]


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    length_unit = (options.metadata or {}).get("length_unit")
    return read_wav(path, channels=options.channels, scale=options.scale, length_unit=length_unit)


def _describe(path: Path, options: ReadOptions) -> dict[str, Any]:
    return describe_wav(path)


FORMAT = FileFormat.builtin("wav", _read, describe=_describe)
