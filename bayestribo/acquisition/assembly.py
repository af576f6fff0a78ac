"""Assemble the frames of one run into samples, with every gap and anomaly reported.

The same assembler serves the live acquisition and the recovery from a raw log, so a
recovered run is, by construction, what the live logger would have written from the
same bytes. Missing samples are never filled: the run holds the received samples
at their own sample indices and the gaps are listed.

Memory does not grow with the run's length: the assembler keeps an index of where
each accepted DATA frame lies in the byte stream (:mod:`.frameindex`), not its
samples, and an :class:`AssembledRun` reads its samples back from the stream in
chunks (:meth:`AssembledRun.chunks`). Frames that extend the run in order can also be
handed to a *sink* as they arrive (the live logger writes its CSV that way).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.faults import FrameError, HeaderError
from bayestribo.acquisition.frameindex import (
    INDEX_SIZE,
    Block,
    ByteSource,
    BytesSource,
    DataIndex,
    FileSource,
    read_block,
)
from bayestribo.acquisition.protocol import (
    FRAME_TYPES,
    MAX_FRAME_LENGTH,
    PREFIX_SIZE,
    Frame,
    FrameParser,
    FrameType,
    RunEnd,
    RunHeader,
    decode_data,
    decode_end,
    decode_release,
    decode_text,
)

__all__ = ["AssembledRun", "RunAssembler", "assemble_bytes", "assemble_file"]

#: Samples per chunk read back from the byte stream (about 0.5 MB of counts).
CHUNK_SAMPLES = 1 << 17
#: Longest list of missing sequence numbers in a report; further ones are counted.
MAX_MISSING_LISTED = 10_000
#: Bytes read at a time when a raw log is parsed from its file.
READ_SIZE = 1 << 20

#: Called with the first sample index and the counts of every DATA frame that extends
#: the run in order, as it is accepted.
Sink = Callable[[int, NDArray[np.int16]], None]


@dataclass
class AssembledRun:
    """The samples of one run (read back from its byte stream on demand) and its report.

    Attributes
    ----------
    header : RunHeader
        The run header (scale factors, sample rate).
    report : dict
        JSON-ready description: header, frames, gaps, anomalies, completeness.
    pieces : tuple of Block
        The received samples in order, as runs of frames (overlaps trimmed).
    source : ByteSource
        The byte stream the samples are read from (the raw log).
    """

    header: RunHeader
    report: dict[str, object]
    pieces: tuple[Block, ...]
    source: ByteSource

    @property
    def complete(self) -> bool:
        """True when the END frame arrived and no frame or sample is missing."""
        return bool(self.report["complete"])

    @property
    def n_samples(self) -> int:
        """Number of received samples."""
        return sum(piece.samples for piece in self.pieces)

    def chunks(self, max_samples: int = CHUNK_SAMPLES) -> Iterator[tuple[int, NDArray[np.int16]]]:
        """The received samples in order, in runs of consecutive indices.

        Parameters
        ----------
        max_samples : int
            Largest chunk [sample pairs] (a frame longer than this is one chunk).

        Yields
        ------
        first : int
            Index of the chunk's first sample since ARM.
        counts : ndarray of int16, shape (n, 2)
            Raw counts (displacement, velocity) of samples ``first`` to ``first + n - 1``.
        """
        for piece in self.pieces:
            step = max(1, max_samples // piece.n)
            for k in range(0, piece.count, step):
                block = piece.frames(k, min(k + step, piece.count))
                yield block.first0, read_block(self.source, block)

    # -- whole arrays (memory in proportion to the run: for tests and short runs) ------
    @property
    def sample_index(self) -> NDArray[np.int64]:
        """Index of each received sample since ARM."""
        parts = [np.arange(p.first0, p.end, dtype=np.int64) for p in self.pieces]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)

    @property
    def counts(self) -> NDArray[np.int16]:
        """The raw counts, shape (n, 2): displacement, velocity."""
        parts = [counts for _, counts in self.chunks()]
        return np.concatenate(parts) if parts else np.zeros((0, 2), dtype=np.int16)

    @property
    def time_s(self) -> NDArray[np.float64]:
        """Time of each sample, ``sample_index / sample_rate`` [s]."""
        return self.sample_index / self.header.sample_rate_Hz

    @property
    def displacement_m(self) -> NDArray[np.float64]:
        """Displacement, counts times the header's scale [m]."""
        return self.counts[:, 0] * self.header.displacement_scale_m

    @property
    def velocity_m_per_s(self) -> NDArray[np.float64]:
        """Velocity, counts times the header's scale [m/s]."""
        return self.counts[:, 1] * self.header.velocity_scale_m_per_s


def _digest(kind: int, payload: bytes) -> bytes:
    """16-byte digest of a frame's type and payload (to tell a retransmission apart)."""
    return hashlib.blake2b(bytes([kind]) + bytes(payload), digest_size=16).digest()


@dataclass
class RunAssembler:
    """Collect the frames of one run (HEADER, DATA, RELEASE, END) as they arrive.

    Parameters
    ----------
    source : ByteSource
        The byte stream the frames are parsed from, with the parser's offsets: the
        counts of accepted DATA frames are read back from it (to compare a repeated
        frame with the first one, and to write the run).
    sink : callable, optional
        Called with ``(first, counts)`` for each DATA frame that extends the run in
        order when it is accepted. :attr:`in_order` stays True as long as these are all
        the run's samples.
    on_header : callable, optional
        Called with the run header when it is accepted, before any DATA frame (it may
        set :attr:`sink`).
    """

    source: ByteSource
    sink: Sink | None = None
    on_header: Callable[[RunHeader], None] | None = None
    ident: str | None = None
    header: RunHeader | None = None
    release_index: int | None = None
    end: RunEnd | None = None
    messages: list[str] = field(default_factory=list)
    anomalies: list[str] = field(default_factory=list)
    malformed_frames: int = 0
    duplicate_frames: int = 0
    #: Frames whose sequence number (or first sample) was received before with other
    #: content: the device contradicts itself, so the run is not complete.
    conflicting_frames: int = 0
    frames_after_end: int = 0
    #: Sample pairs of the accepted DATA frames (overlaps counted twice).
    samples_received: int = 0
    anomalies_not_listed: int = 0
    #: False once a DATA frame is accepted that does not extend the run in order (it
    #: went to no sink).
    in_order: bool = True
    index: DataIndex = field(default_factory=DataIndex)
    #: Type and content digest of the accepted frames other than DATA, by sequence number.
    _other: dict[int, tuple[int, bytes]] = field(default_factory=dict, repr=False)

    #: Longest list of anomalies kept; further ones are only counted.
    MAX_LISTED = 100

    def _note(self, message: str) -> None:
        if len(self.anomalies) < self.MAX_LISTED:
            self.anomalies.append(message)
        else:
            self.anomalies_not_listed += 1

    @property
    def ended(self) -> bool:
        """True once the END frame has been received."""
        return self.end is not None

    @property
    def started(self) -> bool:
        """True once the run header has been received."""
        return self.header is not None

    @property
    def frames_received(self) -> int:
        """Frames of the run accepted so far (HEADER, DATA, RELEASE, END)."""
        return self.index.frames + len(self._other)

    def _seen(self, seq: int) -> bytes | None:
        """Content digest of the accepted frame with sequence number ``seq``, if any."""
        other = self._other.get(seq)
        if other is not None:
            return other[1]
        block = self.index.by_seq(seq)
        if block is None:
            return None
        payload = self.source.read(block.offset0 - INDEX_SIZE, INDEX_SIZE + 4 * block.n)
        return _digest(FrameType.DATA, payload)

    def add(self, frame: Frame) -> None:
        """Take one frame.

        Raises
        ------
        HeaderError
            If the first run header does not parse (a later one that does not is an
            anomaly of the run).
        """
        kind = frame.type
        if kind == FrameType.IDENT:
            self.ident = decode_text(frame)
            return
        if kind in (FrameType.ACK, FrameType.ERROR):
            self.messages.append(f"{FRAME_TYPES[kind]} {decode_text(frame)}")
            return
        if kind == FrameType.HEADER:
            self._add_header(frame)
            return
        if self.header is None:
            self._note(
                f"{FRAME_TYPES[kind]} frame before the run header at byte {frame.offset} ignored"
            )
            return
        if self.end is not None:
            self.frames_after_end += 1
            self._note(f"{FRAME_TYPES[kind]} frame after END at byte {frame.offset}")
            return
        seen = self._seen(frame.seq)
        if seen is not None:
            if seen == _digest(kind, frame.payload):
                self.duplicate_frames += 1
                self._note(f"retransmitted frame {frame.seq} at byte {frame.offset} ignored")
            else:
                self.conflicting_frames += 1
                self._note(
                    f"sequence number {frame.seq} repeated with different content at byte "
                    f"{frame.offset}; the first one is kept"
                )
            return
        try:
            if kind == FrameType.DATA:
                self._add_data(frame)
                return
            if kind == FrameType.RELEASE:
                self.release_index = decode_release(frame.payload)
            elif kind == FrameType.END:
                self.end = decode_end(frame.payload)
        except FrameError as exc:
            self.malformed_frames += 1
            self._note(f"{exc} (seq {frame.seq}, byte {frame.offset})")
            return
        self._other[frame.seq] = (kind, _digest(kind, frame.payload))

    def _add_header(self, frame: Frame) -> None:
        if self.header is not None:
            try:
                header = RunHeader.from_payload(frame.payload)
            except HeaderError as exc:
                self._note(f"second HEADER at byte {frame.offset} ignored: {exc}")
                return
            if header != self.header:
                self._note(f"second, different HEADER at byte {frame.offset} ignored")
                return
        else:
            header = RunHeader.from_payload(frame.payload)
            if self.on_header is not None:
                self.on_header(header)
        self.header = header
        self._other[frame.seq] = (FrameType.HEADER, _digest(FrameType.HEADER, frame.payload))

    def _add_data(self, frame: Frame) -> None:
        first, counts = decode_data(frame.payload)
        earlier = self.index.by_first(first)
        if earlier is not None:
            if np.array_equal(read_block(self.source, earlier), counts):
                self.duplicate_frames += 1
                self._note(f"duplicate DATA for sample {first} ignored")
            else:
                self.conflicting_frames += 1
                self._note(
                    f"DATA for sample {first} repeated with different samples; the first one "
                    "is kept"
                )
            return
        offset = frame.offset + PREFIX_SIZE + INDEX_SIZE
        extends = self.index.add(frame.seq, first, len(counts), offset)
        self.samples_received += len(counts)
        if not extends:
            self.in_order = False
        elif self.sink is not None:
            self.sink(first, counts)

    def build(self, parser: FrameParser | None = None, *, fault: str | None = None) -> AssembledRun:
        """Assemble the samples received so far.

        Parameters
        ----------
        parser : FrameParser, optional
            The parser that produced the frames; its discard counters are reported.
        fault : str, optional
            Why the run ended early (timeout, disconnect, interrupt), if it did.

        Raises
        ------
        FrameError
            If no run header was received: counts cannot be converted to metres.
        """
        if self.header is None:
            raise FrameError("no valid run header received: counts cannot be scaled to metres")
        header = self.header
        gaps: list[dict[str, float | int]] = []
        pieces: list[Block] = []
        overlaps = 0
        expected = 0
        for block in self.index.in_order():
            for k in range(block.count):
                first = block.first0 + k * block.n
                if first > expected:
                    gaps.append(self._gap(expected, first))
                elif first < expected:
                    overlaps += 1
                    self._note(f"DATA for sample {first} overlaps earlier samples")
                    keep = expected - first
                    if keep < block.n:
                        frame = block.frames(k, k + 1)
                        pieces.append(
                            Block(frame.seq0, expected, block.n - keep, frame.offset0 + 4 * keep)
                        )
                        expected += block.n - keep
                    continue
                # This frame and the rest of the block are consecutive samples.
                pieces.append(block.frames(k, block.count))
                expected = block.end
                break
        received = sum(piece.samples for piece in pieces)
        if self.end is not None and self.end.sample_count > expected:
            gaps.append(self._gap(expected, self.end.sample_count))
        rate = header.sample_rate_Hz
        seqs = _merged(list(self.index.seq_ranges()) + [(s, s + 1) for s in self._other])
        n_seqs = sum(stop - start for start, stop in seqs)
        missing_seqs: list[int] = []
        missing_count = 0
        if seqs:
            last = self.end.frame_count if self.end is not None else seqs[-1][1] - 1
            missing_seqs, missing_count = _missing(seqs, last)
        if self.end is not None:
            received_before_end = n_seqs - 1  # all but END itself
            frames_missing = max(self.end.frame_count - received_before_end, 0)
        else:
            frames_missing = missing_count
        complete = (
            fault is None
            and self.end is not None
            and not gaps
            and missing_count == 0
            and self.malformed_frames == 0
            and self.conflicting_frames == 0
            and received == self.end.sample_count
        )
        release_time = None if self.release_index is None else self.release_index / rate
        report: dict[str, object] = {
            "complete": bool(complete),
            "fault": fault,
            "device_ident": self.ident,
            "device_header": header.as_metadata(),
            "device_messages": list(self.messages),
            "release_sample_index": self.release_index,
            "release_time_s": release_time,
            "end_frame_received": self.end is not None,
            # Frames of the run before END (HEADER, DATA, RELEASE), as sent and as received.
            "frames_reported_by_device": None if self.end is None else self.end.frame_count,
            "samples_reported_by_device": None if self.end is None else self.end.sample_count,
            "frames_received": n_seqs - (1 if self.end is not None else 0),
            "frames_missing": frames_missing,
            "missing_sequence_numbers": missing_seqs,
            "missing_sequence_numbers_not_listed": missing_count - len(missing_seqs),
            "samples_received": received,
            "samples_missing": int(sum(int(g["n_samples"]) for g in gaps)),
            "gaps": gaps,
            "malformed_frames": self.malformed_frames,
            "duplicate_frames": self.duplicate_frames,
            "conflicting_frames": self.conflicting_frames,
            "overlapping_frames": overlaps,
            "anomalies": list(self.anomalies),
            "anomalies_not_listed": self.anomalies_not_listed,
            "discarded_bytes": None if parser is None else parser.discarded_bytes,
            "rejected_frame_candidates": None if parser is None else parser.rejected_candidates,
        }
        return AssembledRun(header=header, report=report, pieces=tuple(pieces), source=self.source)

    def _gap(self, start: int, stop: int) -> dict[str, float | int]:
        assert self.header is not None
        rate = self.header.sample_rate_Hz
        return {
            "start_sample": int(start),
            "stop_sample": int(stop),
            "n_samples": int(stop - start),
            "start_time_s": start / rate,
            "stop_time_s": stop / rate,
        }


def _merged(ranges: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Sorted, disjoint half-open ranges covering the same integers."""
    out: list[tuple[int, int]] = []
    for start, stop in sorted(ranges):
        if out and start <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], stop))
        else:
            out.append((start, stop))
    return out


def _missing(ranges: list[tuple[int, int]], last: int) -> tuple[list[int], int]:
    """Integers 0..last not in the merged ``ranges``: the first ones listed, and how many."""
    listed: list[int] = []
    count = 0
    position = 0
    for start, stop in [*ranges, (last + 1, last + 1)]:
        stop_gap = min(start, last + 1)
        if stop_gap > position:
            count += stop_gap - position
            room = MAX_MISSING_LISTED - len(listed)
            listed.extend(range(position, min(stop_gap, position + max(room, 0))))
        position = max(position, stop)
        if position > last:
            break
    return listed, count


def _finish(parser: FrameParser, assembler: RunAssembler, fault: str | None) -> AssembledRun:
    for frame in parser.finish():
        assembler.add(frame)
    if fault is None and not assembler.ended:
        fault = "stream ended without an END frame"
    return assembler.build(parser, fault=fault)


def assemble_bytes(data: bytes, *, fault: str | None = None) -> AssembledRun:
    """Parse a whole byte stream held in memory and assemble its run.

    Raises
    ------
    HeaderError
        If the run header does not parse.
    FrameError
        If no run header is found.
    """
    # All bytes are at hand: a long candidate delays nothing, so a run header of any
    # length is found (and one with an oversized label refused with its reason).
    parser = FrameParser(max_header_payload=MAX_FRAME_LENGTH)
    assembler = RunAssembler(BytesSource(data))
    for frame in parser.feed(data):
        assembler.add(frame)
    return _finish(parser, assembler, fault)


def assemble_file(
    path: str | os.PathLike[str], *, fault: str | None = None, sink: Sink | None = None
) -> tuple[AssembledRun, RunAssembler]:
    """Parse a raw log from its file, a megabyte at a time, and assemble its run.

    Memory does not grow with the log's size: the samples stay in the file.

    Parameters
    ----------
    path : path-like
        The raw log.
    fault : str, optional
        Why the run ended early, if known.
    sink : callable, optional
        Given the DATA frames that extend the run in order (see :class:`RunAssembler`).

    Returns
    -------
    run : AssembledRun
    assembler : RunAssembler
        The assembler (its :attr:`~RunAssembler.in_order` tells whether the sink saw
        every sample).

    Raises
    ------
    HeaderError
        If the run header does not parse.
    FrameError
        If no run header is found.
    OSError
        If the file cannot be read.
    """
    parser = FrameParser(max_header_payload=MAX_FRAME_LENGTH)
    assembler = RunAssembler(FileSource(path), sink=sink)
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(READ_SIZE), b""):
            for frame in parser.feed(chunk):
                assembler.add(frame)
    return _finish(parser, assembler, fault), assembler
