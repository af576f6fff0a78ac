"""Where the samples of a run lie in its byte stream: an index instead of the samples.

A run of an hour at 20 kS/s of two channels is 290 MB of counts in the raw log. The
assembler keeps no samples in memory; it records, for every DATA frame it accepts,
the frame's sequence number, first sample index, sample count and the offset of its
counts in the byte stream, and reads the counts back from the stream (the raw log, or
the bytes given to :func:`~bayestribo.acquisition.assembly.assemble_bytes`) when the
run is written.

Frames sent back to back, with consecutive sequence numbers and sample indices, form
one :class:`Block`; an undisturbed run is a handful of blocks whatever its length, so
the index takes memory in proportion to the run's anomalies (lost, repeated or
reordered frames), not to its length.
"""

from __future__ import annotations

import bisect
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.faults import FrameError
from bayestribo.acquisition.protocol import CRC_SIZE, PREFIX_SIZE

__all__ = ["Block", "ByteSource", "BytesSource", "DataIndex", "FileSource", "read_block"]

#: Bytes of a DATA payload before the counts (the u32 index of the first sample).
INDEX_SIZE = 4
#: Bytes of one sample pair on the wire (two int16).
PAIR_SIZE = 4


class ByteSource(Protocol):
    """Random access to the byte stream the frames were parsed from."""

    def read(self, offset: int, size: int) -> bytes:
        """``size`` bytes from stream offset ``offset``."""
        ...


class BytesSource:
    """A byte stream held in memory.

    Parameters
    ----------
    data : bytes
        The whole stream.
    """

    def __init__(self, data: bytes | bytearray | memoryview) -> None:
        self._data = bytes(data)

    def read(self, offset: int, size: int) -> bytes:
        """``size`` bytes from ``offset``."""
        chunk = self._data[offset : offset + size]
        if len(chunk) != size:
            raise FrameError(f"byte stream: {size} bytes at offset {offset} are not there")
        return chunk


class FileSource:
    """A byte stream in a file (the raw log), read with ``pread``; the file may still grow.

    The file is opened for each read and closed again, so a run that is kept (in an
    :class:`~bayestribo.acquisition.session.AcquisitionResult`) holds no descriptor.

    Parameters
    ----------
    path : path-like
        The file.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)

    def read(self, offset: int, size: int) -> bytes:
        """``size`` bytes from ``offset``."""
        fd = os.open(self.path, os.O_RDONLY)
        try:
            parts = []
            got = 0
            while got < size:
                chunk = os.pread(fd, size - got, offset + got)
                if not chunk:
                    raise FrameError(
                        f"{self.path}: {size} bytes at offset {offset} are not in the raw "
                        "log (was it changed after the run?)"
                    )
                parts.append(chunk)
                got += len(chunk)
        finally:
            os.close(fd)
        return b"".join(parts)


@dataclass
class Block:
    """Consecutive DATA frames: ``count`` frames of ``n`` sample pairs, back to back.

    Attributes
    ----------
    seq0 : int
        Sequence number of the first frame; frame k has ``seq0 + k``.
    first0 : int
        Index of the first sample of the first frame; frame k starts at ``first0 + k n``.
    n : int
        Sample pairs per frame.
    offset0 : int
        Stream offset of the first frame's counts [bytes]; frame k's are at
        ``offset0 + k stride``.
    count : int
        Frames in the block.
    """

    seq0: int
    first0: int
    n: int
    offset0: int
    count: int = 1

    @property
    def stride(self) -> int:
        """Size of one DATA frame of ``n`` pairs on the wire [bytes]."""
        return PREFIX_SIZE + INDEX_SIZE + PAIR_SIZE * self.n + CRC_SIZE

    @property
    def end(self) -> int:
        """Index after the block's last sample."""
        return self.first0 + self.n * self.count

    @property
    def samples(self) -> int:
        """Sample pairs in the block."""
        return self.n * self.count

    def frames(self, start: int, stop: int) -> Block:
        """The frames ``start`` to ``stop - 1`` of the block, as a block."""
        return Block(
            self.seq0 + start,
            self.first0 + start * self.n,
            self.n,
            self.offset0 + start * self.stride,
            stop - start,
        )


def read_block(source: ByteSource, block: Block) -> NDArray[np.int16]:
    """The counts of a block, shape ``(block.samples, 2)``, from the byte stream."""
    size = PAIR_SIZE * block.n
    if block.count == 1:
        raw = source.read(block.offset0, size)
        return np.frombuffer(raw, dtype="<i2").reshape(-1, 2).astype(np.int16)
    span = (block.count - 1) * block.stride + size
    buf = np.zeros(block.count * block.stride, dtype=np.uint8)
    buf[:span] = np.frombuffer(source.read(block.offset0, span), dtype=np.uint8)
    pairs = np.ascontiguousarray(buf.reshape(block.count, block.stride)[:, :size])
    return pairs.view("<i2").reshape(-1, 2).astype(np.int16)


class DataIndex:
    """The accepted DATA frames of a run, by sequence number and by first sample.

    Frames that extend the run in order (first sample at or after the end of all
    earlier ones) go to the *main* blocks, sorted by sample index; any other
    accepted frame (a late retransmission filling a gap, an overlapping frame) is a
    *late* block of its own.
    """

    def __init__(self) -> None:
        self.main: list[Block] = []
        self._main_firsts: list[int] = []
        self._seq_starts: list[int] = []  # seq0 of the main blocks, sorted
        self._seq_blocks: list[Block] = []
        self.late_by_first: dict[int, Block] = {}
        self.late_by_seq: dict[int, Block] = {}
        self.main_end = 0
        self.frames = 0

    def add(self, seq: int, first: int, n: int, offset: int) -> bool:
        """Record an accepted DATA frame; True if it extends the run in order.

        Parameters
        ----------
        seq, first, n : int
            Sequence number, first sample index and sample pairs of the frame.
        offset : int
            Stream offset of its counts [bytes].
        """
        self.frames += 1
        if first < self.main_end:
            block = Block(seq, first, n, offset)
            self.late_by_first[first] = block
            self.late_by_seq[seq] = block
            return False
        last = self.main[-1] if self.main else None
        if (
            last is not None
            and seq == last.seq0 + last.count
            and first == last.end
            and n == last.n
            and offset == last.offset0 + last.count * last.stride
        ):
            last.count += 1
        else:
            block = Block(seq, first, n, offset)
            self.main.append(block)
            self._main_firsts.append(first)
            i = bisect.bisect_left(self._seq_starts, seq)
            self._seq_starts.insert(i, seq)
            self._seq_blocks.insert(i, block)
        self.main_end = first + n
        return True

    def by_seq(self, seq: int) -> Block | None:
        """The frame with sequence number ``seq``, as a one-frame block, if accepted."""
        late = self.late_by_seq.get(seq)
        if late is not None:
            return late
        i = bisect.bisect_right(self._seq_starts, seq) - 1
        if i >= 0:
            block = self._seq_blocks[i]
            k = seq - block.seq0
            if k < block.count:
                return block.frames(k, k + 1)
        return None

    def by_first(self, first: int) -> Block | None:
        """The frame whose first sample is ``first``, as a one-frame block, if accepted."""
        late = self.late_by_first.get(first)
        if late is not None:
            return late
        i = bisect.bisect_right(self._main_firsts, first) - 1
        if i >= 0:
            block = self.main[i]
            k, r = divmod(first - block.first0, block.n)
            if r == 0 and k < block.count:
                return block.frames(k, k + 1)
        return None

    def seq_ranges(self) -> Iterator[tuple[int, int]]:
        """Half-open ranges of the accepted frames' sequence numbers (unsorted)."""
        for block in self.main:
            yield block.seq0, block.seq0 + block.count
        for seq in self.late_by_seq:
            yield seq, seq + 1

    def in_order(self) -> Iterator[Block]:
        """All accepted frames as blocks, in the order of their first sample."""
        late = sorted(self.late_by_first.values(), key=lambda b: b.first0)
        j = 0
        for block in self.main:
            done = 0
            while j < len(late) and late[j].first0 < block.end:
                # Frames of the block that start before the late frame come first.
                before = -(-(late[j].first0 - block.first0) // block.n)
                before = min(max(before, done), block.count)
                if before > done:
                    yield block.frames(done, before)
                    done = before
                yield late[j]
                j += 1
            if done < block.count:
                yield block.frames(done, block.count)
        yield from late[j:]
