"""WAV files: the channels of a sound card, an audio interface or a recorder.

A sound-card DAQ, a piezo pickup or an accelerometer on an audio interface, a
microphone by a tuning fork: the sample rate in the header gives the time (sample i at
t = i / rate [s]) and the channels are numbered from 0 (``"0"``, ``"1"``, ...; in a
stereo file also ``"left"`` and ``"right"``). A WAV file states no quantity and no
unit, so a channel is read only when named with ``channels=``, e.g.
``{"displacement_m": "0"}`` with ``length_unit`` ``"arbitrary"``, or with the sensor's
sensitivity as ``scale``; without it the file is refused, saying so.

Integer PCM (8 to 64 bits, :func:`scipy.io.wavfile.read`) is read as fractions of the
full scale: count / 2**(bits - 1), in [-1, 1) (8-bit samples are unsigned:
(count - 128) / 128). 16-bit, 24-bit and float files of the same signal read the
same, and a sensor's sensitivity in metres (m/s, m/s²) per full scale is the ``scale``
that converts them; reading integer PCM without a ``scale`` or an arbitrary length
unit is said with a :class:`~bayestribo.errors.ReadingWarning`. A float file's values
are read as stored. A sound card driven past its range holds samples at full scale:
the run's clipping check (:func:`bayestribo.io.validation.validate_run`) finds them as
it finds any other flat top.

Most sound cards are AC coupled (a high pass of a few hertz): the offset and the slow
part of a record are lost, and a decay at a few hertz or below is distorted by the
input itself. A DC-coupled input (a DAQ's, some instrumentation interfaces') is needed
for slow oscillators.
"""

from __future__ import annotations

import struct
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.arrays import MAX_SAMPLES, NamedArray, signals_from_arrays
from bayestribo.io.columns import parse_column
from bayestribo.io.run import ACCELERATION, DISPLACEMENT, TIME, VELOCITY

__all__ = ["WavLayout", "describe_wav", "read_wav", "wav_layout"]

#: WAVE format tags (RFC 2361) read: integer PCM and IEEE float.
_PCM, _FLOAT, _EXTENSIBLE = 1, 3, 0xFFFE
#: The names of a stereo file's channels beside their numbers.
_STEREO = {"left": "0", "right": "1"}


@dataclass(frozen=True)
class WavLayout:
    """What a WAV file's header says, none of its samples read.

    Attributes
    ----------
    channels : int
        Number of channels.
    rate_Hz : int
        Sample rate [Hz].
    bits : int
        Bits per sample.
    floating : bool
        IEEE float samples (otherwise integer PCM).
    frames : int
        Samples per channel.
    """

    channels: int
    rate_Hz: int
    bits: int
    floating: bool
    frames: int

    @property
    def encoding(self) -> str:
        """``"16-bit integer PCM"``, ``"32-bit float"``."""
        return f"{self.bits}-bit {'float' if self.floating else 'integer PCM'}"

    @property
    def values(self) -> str:
        """How the samples are read, in words."""
        if self.floating:
            return "values as stored"
        if self.bits <= 8:
            return "values as fractions of full scale, (count - 128) / 128"
        return f"values as fractions of full scale, count / 2^{self.bits - 1}"

    def describe(self) -> str:
        """The file in words, for ``inspect``."""
        plural = "s" if self.channels != 1 else ""
        return (
            f"WAV, {self.encoding}, {self.channels} channel{plural} at {self.rate_Hz} Hz "
            f"({self.values})"
        )


def _chunks(fh: BinaryIO, end: int, order: str) -> Iterator[tuple[bytes, int, int]]:
    """``(id, size, offset of its data)`` of each chunk from the file's position to ``end``."""
    while fh.tell() + 8 <= end:
        head = fh.read(8)
        chunk, size = head[:4], struct.unpack(order + "I", head[4:])[0]
        start = fh.tell()
        yield chunk, size, start
        fh.seek(start + size + (size & 1))  # chunks are padded to an even size


def _fmt(data: bytes, order: str, where: str) -> tuple[int, int, int, int, int]:
    """``(format tag, channels, rate, block align, bits)`` of a ``fmt `` chunk."""
    if len(data) < 16:
        raise RunFormatError(
            f"not a readable WAV file: its fmt chunk holds {len(data)} bytes, expected 16 or more",
            where,
        )
    tag, channels, rate, _, align, bits = struct.unpack(order + "HHIIHH", data[:16])
    if tag == _EXTENSIBLE and len(data) >= 26:
        tag = struct.unpack(order + "H", data[24:26])[0]  # the sub-format GUID's first field
    return tag, channels, rate, align, bits


def wav_layout(path: str | Path) -> WavLayout:
    """What a WAV file's header says (channels, rate, encoding, samples), no sample read.

    Parameters
    ----------
    path : str or Path
        The ``.wav`` file.

    Returns
    -------
    WavLayout

    Raises
    ------
    RunFormatError
        For an empty file, a file that is not RIFF/WAVE, an encoding other than integer
        PCM and float (a compressed WAV), no samples, a data chunk that runs past the
        end of the file (a file cut short), or more than
        :data:`~bayestribo.io.arrays.MAX_SAMPLES` samples per channel.
    """
    path = Path(path)
    where = str(path)
    try:
        size = path.stat().st_size
        fh = open(path, "rb")
    except OSError as exc:
        raise RunFormatError(f"not a readable WAV file ({exc})", where) from None
    if size == 0:
        fh.close()
        raise RunFormatError("the file is empty (0 bytes); expected a WAV file", where)
    with fh:
        head = fh.read(12)
        kind = head[:4]
        if len(head) < 12 or kind not in (b"RIFF", b"RIFX", b"RF64") or head[8:] != b"WAVE":
            raise RunFormatError(
                f"not a WAV file: it starts with {head[:12]!r}, expected 'RIFF....WAVE'", where
            )
        order = ">" if kind == b"RIFX" else "<"
        fmt = None
        data_size = data_start = None
        big_data = None  # an RF64 file's data size, from its ds64 chunk
        for chunk, length, start in _chunks(fh, size, order):
            if chunk == b"ds64" and length >= 24:
                big_data = struct.unpack("<Q", fh.read(24)[8:16])[0]
            elif chunk == b"fmt ":
                fmt = _fmt(fh.read(min(length, 64)), order, where)
            elif chunk == b"data":
                data_size = big_data if kind == b"RF64" and big_data is not None else length
                data_start = start
                break
    if fmt is None or data_size is None or data_start is None:
        missing = "no 'fmt' chunk before its data" if fmt is None else "no 'data' chunk"
        raise RunFormatError(f"not a readable WAV file: {missing}", where)
    tag, channels, rate, align, bits = fmt
    if tag not in (_PCM, _FLOAT):
        raise RunFormatError(
            f"WAV format tag {tag:#06x} (a compressed encoding) is not read; expected integer "
            "PCM or float: save the recording as uncompressed PCM (16 or 24 bit) or float",
            where,
        )
    if channels < 1 or rate < 1 or align < channels:
        raise RunFormatError(
            f"not a readable WAV file: its header gives {channels} channel(s) at {rate} Hz "
            f"in blocks of {align} bytes",
            where,
        )
    frames = data_size // align
    if data_start + data_size > size:
        raise RunFormatError(
            f"the WAV data chunk declares {data_size} bytes but the file ends "
            f"{size - data_start} bytes after its start: a file cut short (copied while it "
            "was recorded?); save or export it again",
            where,
        )
    if frames == 0:
        raise RunFormatError("the WAV file holds no samples (its data chunk is empty)", where)
    if frames > MAX_SAMPLES:
        raise RunFormatError(
            f"the WAV file holds {frames} samples per channel ({frames / rate:.4g} s at "
            f"{rate} Hz); expected at most {MAX_SAMPLES}: cut the record to the free decay "
            "first",
            where,
        )
    return WavLayout(channels, rate, bits, tag == _FLOAT, frames)


def _fractions(column: NDArray) -> NDArray:
    """One channel as scipy returns it, as float64: integer PCM as fractions of full
    scale (scipy gives samples left-justified in their container: the container's range
    is the full scale), float as stored."""
    values = column.astype(np.float64)
    kind = column.dtype.kind
    if kind == "u":  # 8-bit and fewer: unsigned, 128 is zero
        values -= 128.0
        values /= 128.0
    elif kind == "i":
        values /= float(2 ** (8 * column.dtype.itemsize - 1))
    return values


def _advice(layout: WavLayout) -> str:
    """What to give to read a WAV file's channels, in the reading options' spelling."""
    names = "numbered from 0" + (", or left and right" if layout.channels == 2 else "")
    unit = "the sound card's full scale" if not layout.floating else "the file's unit"
    return (
        f"a WAV file states no quantity and no unit: name what its {layout.channels} "
        f"channel(s) ({names}) hold, e.g. channels={{'{DISPLACEMENT}': '0'}} and "
        f"length_unit='arbitrary' for a displacement in {unit}; {VELOCITY} or "
        f"{ACCELERATION} in place of {DISPLACEMENT} for a velocity or an acceleration "
        f"pickup, and scale={{'{DISPLACEMENT}': 0.002}} for a sensitivity of 2 mm per "
        f"{'full scale' if not layout.floating else 'unit'} in place of the arbitrary unit"
    )


def _sources(channels: Mapping[Any, Any], layout: WavLayout, where: str) -> dict[str, str]:
    """``channels`` with each source as a channel number (``"left"`` as ``"0"``), a time
    among them refused."""
    out: dict[str, str] = {}
    for key, source in channels.items():
        try:
            parsed = parse_column(str(key))
        except ValueError:
            parsed = None  # signals_from_arrays names what is wrong with it
        if parsed is not None and parsed[0] == TIME:
            raise RunFormatError(
                f"channels[{key!r}]: a WAV file's time is its sample rate ({layout.rate_Hz} "
                "Hz, sample i at i / rate); name the channels of the motion only",
                where,
            )
        text = str(source).strip().lower()
        out[str(key)] = _STEREO.get(text, text) if layout.channels == 2 else text
    return out


def read_wav(
    path: str | Path,
    *,
    channels: Mapping[str, Any] | None = None,
    scale: Mapping[str, float] | None = None,
    length_unit: str | None = None,
) -> dict[str, NDArray]:
    """Read the signals of a run from a WAV file.

    Parameters
    ----------
    path : str or Path
        The ``.wav`` file.
    channels : mapping
        Column name -> channel number from 0 (``"left"``/``"right"`` in a stereo file),
        e.g. ``{"displacement_m": "0"}`` or ``{"velocity_mm_per_s": 1}`` (a unit in the
        name scales the values read). Required: a WAV file does not say what it holds.
    scale : mapping, optional
        Extra factor per canonical column: the sensor's sensitivity per full scale
        (integer PCM) or per unit stored (float), e.g. ``{"displacement_m": 2e-3}``.
    length_unit : str, optional
        The run's length unit, if given (``"arbitrary"``: the values read are the
        length unit, and no warning is given about integer PCM's full scale).

    Returns
    -------
    dict
        ``time_s`` (i / rate [s]) and the named channels, as fractions of full scale
        (integer PCM) or as stored (float), times their unit's factor and ``scale``.

    Raises
    ------
    RunFormatError
        For a file that is not a readable uncompressed WAV (:func:`wav_layout`),
        ``channels`` not given (saying what to give), a channel that does not exist, or
        a time channel named.

    Warns
    -----
    ReadingWarning
        When integer PCM is read without a ``scale`` for each channel named and without
        an arbitrary length unit: the values are fractions of full scale, not metres.
    """
    import scipy.io.wavfile  # on first use, as the other binary readers

    path = Path(path)
    where = str(path)
    layout = wav_layout(path)
    if channels is None:
        raise RunFormatError(_advice(layout), where)
    if not isinstance(channels, Mapping):
        raise RunFormatError(
            f"channels: expected a mapping of column name to channel number, e.g. "
            f"{{'{DISPLACEMENT}': '0'}}; got {type(channels).__name__}",
            where,
        )
    sources = _sources(channels, layout, where)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", scipy.io.wavfile.WavFileWarning)
        _, data = scipy.io.wavfile.read(path)
    for note in caught:
        if issubclass(note.category, scipy.io.wavfile.WavFileWarning):
            warn(f"{where}: {note.message}", ReadingWarning)
        else:
            warnings.warn_explicit(note.message, note.category, note.filename, note.lineno)
    data = data.reshape(data.shape[0], -1)  # one column per channel
    arrays = [NamedArray(str(k), data[:, k]) for k in range(data.shape[1])]
    signals = signals_from_arrays(
        arrays,
        channels=sources,
        scale=scale,
        where=where,
        kind="channel",
        load=lambda item: _fractions(item.values),
    )
    if not layout.floating and length_unit != "arbitrary":
        unscaled = [name for name in signals if name not in (scale or {})]
        if unscaled:
            picked = ", ".join(f"{name} (channel {_source_of(sources, name)})" for name in unscaled)
            warn(
                f"{where}: {picked} read from {layout.encoding} as fractions of the sound "
                f"card's full scale, not in the unit the name says: give the sensor's "
                f"sensitivity per full scale, e.g. scale={{'{unscaled[0]}': 0.002}}, or "
                "length_unit='arbitrary' for a run in fractions of full scale",
                ReadingWarning,
            )
    n = next(iter(signals.values())).size
    return {TIME: np.arange(n, dtype=np.float64) / float(layout.rate_Hz), **signals}


def _source_of(sources: Mapping[str, str], role: str) -> str:
    """The channel a canonical column was read from (for messages)."""
    for key, source in sources.items():
        try:
            parsed = parse_column(key)
        except ValueError:
            continue
        if parsed is not None and parsed[0] == role:
            return source
    return "?"


def describe_wav(path: str | Path) -> dict[str, Any]:
    """How a WAV file is read, from its header: ``{"reader", "columns"}`` for ``inspect``.

    Parameters
    ----------
    path : str or Path
        The ``.wav`` file.

    Returns
    -------
    dict
        ``reader``: the encoding, channels, rate and how the values are read;
        ``columns``: one ``{"label", "unit"}`` per channel (unit ``"full scale"`` for
        integer PCM, none for float).
    """
    layout = wav_layout(path)
    names = ["left", "right"] if layout.channels == 2 else []
    unit = None if layout.floating else "full scale"
    columns = [
        {"label": f"{k} ({names[k]})" if names else str(k), "unit": unit}
        for k in range(layout.channels)
    ]
    return {
        "reader": f"{layout.describe()}, {layout.frames} samples per channel",
        "columns": columns,
    }
