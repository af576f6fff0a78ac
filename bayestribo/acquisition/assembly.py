"""Assemble the frames of one run into samples, with every gap and anomaly reported.

The same assembler serves the live acquisition and the recovery from a raw log, so a
recovered run is, by construction, what the live logger would have written from the
same bytes. Missing samples are never filled: the run holds the received samples
at their own sample indices and the gaps are listed.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.faults import FrameError
from bayestribo.acquisition.protocol import (
    FRAME_TYPES,
    MAX_FRAME_LENGTH,
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

__all__ = ["AssembledRun", "RunAssembler", "assemble_bytes"]


@dataclass
class AssembledRun:
    """Samples of one run in physical units, with what is known about their gaps.

    Attributes
    ----------
    sample_index : ndarray of int64
        Index of each received sample since ARM.
    time_s, displacement_m, velocity_m_per_s : ndarray of float
        Time ``sample_index / sample_rate`` [s], displacement [m], velocity [m/s].
    counts : ndarray of int16, shape (n, 2)
        The raw counts.
    report : dict
        JSON-ready description: header, frames, gaps, anomalies, completeness.
    """

    sample_index: NDArray[np.int64]
    time_s: NDArray[np.float64]
    displacement_m: NDArray[np.float64]
    velocity_m_per_s: NDArray[np.float64]
    counts: NDArray[np.int16]
    report: dict[str, object]

    @property
    def complete(self) -> bool:
        """True when the END frame arrived and no frame or sample is missing."""
        return bool(self.report["complete"])


def _digest(kind: int, payload: bytes) -> bytes:
    """16-byte digest of a frame's type and payload (to tell a retransmission apart)."""
    return hashlib.blake2b(bytes([kind]) + bytes(payload), digest_size=16).digest()


@dataclass
class RunAssembler:
    """Collect the frames of one run (HEADER, DATA, RELEASE, END) as they arrive."""

    ident: str | None = None
    header: RunHeader | None = None
    release_index: int | None = None
    end: RunEnd | None = None
    data: dict[int, NDArray[np.int16]] = field(default_factory=dict)
    seqs: set[int] = field(default_factory=set)
    messages: list[str] = field(default_factory=list)
    anomalies: list[str] = field(default_factory=list)
    malformed_frames: int = 0
    duplicate_frames: int = 0
    #: Frames whose sequence number (or first sample) was received before with other
    #: content: the device contradicts itself, so the run is not complete.
    conflicting_frames: int = 0
    #: A digest of each accepted frame's type and payload, by sequence number.
    _content: dict[int, bytes] = field(default_factory=dict, init=False, repr=False)
    frames_after_end: int = 0
    samples_received: int = 0
    anomalies_not_listed: int = 0

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

    def add(self, frame: Frame) -> None:
        """Take one frame. Only :class:`HeaderError` (a run header that does not parse) raises."""
        kind = frame.type
        if kind == FrameType.IDENT:
            self.ident = decode_text(frame)
            return
        if kind in (FrameType.ACK, FrameType.ERROR):
            self.messages.append(f"{FRAME_TYPES[kind]} {decode_text(frame)}")
            return
        if kind == FrameType.HEADER:
            header = RunHeader.from_payload(frame.payload)
            if self.header is not None and header != self.header:
                self._note(f"second, different HEADER at byte {frame.offset} ignored")
                return
            self.header = header
            self.seqs.add(frame.seq)
            self._content[frame.seq] = _digest(kind, frame.payload)
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
        if frame.seq in self.seqs:
            if self._content.get(frame.seq) == _digest(kind, frame.payload):
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
                first, counts = decode_data(frame.payload)
                if first in self.data:
                    if np.array_equal(self.data[first], counts):
                        self.duplicate_frames += 1
                        self._note(f"duplicate DATA for sample {first} ignored")
                    else:
                        self.conflicting_frames += 1
                        self._note(
                            f"DATA for sample {first} repeated with different samples; the "
                            "first one is kept"
                        )
                    return
                self.data[first] = counts
                self.samples_received += len(counts)
            elif kind == FrameType.RELEASE:
                self.release_index = decode_release(frame.payload)
            elif kind == FrameType.END:
                self.end = decode_end(frame.payload)
        except FrameError as exc:
            self.malformed_frames += 1
            self._note(f"{exc} (seq {frame.seq}, byte {frame.offset})")
            return
        self.seqs.add(frame.seq)
        self._content[frame.seq] = _digest(kind, frame.payload)

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
        starts = sorted(self.data)
        gaps: list[dict[str, float | int]] = []
        overlaps = 0
        indices: list[NDArray[np.int64]] = []
        chunks: list[NDArray[np.int16]] = []
        expected = 0
        for first in starts:
            counts = self.data[first]
            if first > expected:
                gaps.append(self._gap(expected, first))
            elif first < expected:
                overlaps += 1
                self._note(f"DATA for sample {first} overlaps earlier samples")
                keep = expected - first
                counts = counts[keep:]
                first = expected
                if len(counts) == 0:
                    continue
            indices.append(np.arange(first, first + len(counts), dtype=np.int64))
            chunks.append(counts)
            expected = first + len(counts)
        if self.end is not None and self.end.sample_count > expected:
            gaps.append(self._gap(expected, self.end.sample_count))
        if indices:
            index = np.concatenate(indices)
            counts_all = np.concatenate(chunks).astype(np.int16, copy=False)
        else:
            index = np.zeros(0, dtype=np.int64)
            counts_all = np.zeros((0, 2), dtype=np.int16)
        rate = header.sample_rate_Hz
        missing_seqs: list[int] = []
        if self.seqs:
            last = self.end.frame_count if self.end is not None else max(self.seqs)
            missing_seqs = sorted(set(range(0, last + 1)) - self.seqs)
        if self.end is not None:
            received_before_end = len(self.seqs) - 1  # all but END itself
            frames_missing = max(self.end.frame_count - received_before_end, 0)
        else:
            frames_missing = len(missing_seqs)
        complete = (
            fault is None
            and self.end is not None
            and not gaps
            and not missing_seqs
            and self.malformed_frames == 0
            and self.conflicting_frames == 0
            and len(index) == self.end.sample_count
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
            "frames_received": len(self.seqs) - (1 if self.end is not None else 0),
            "frames_missing": frames_missing,
            "missing_sequence_numbers": missing_seqs,
            "samples_received": len(index),
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
        return AssembledRun(
            sample_index=index,
            time_s=index / rate,
            displacement_m=counts_all[:, 0] * header.displacement_scale_m,
            velocity_m_per_s=counts_all[:, 1] * header.velocity_scale_m_per_s,
            counts=counts_all,
            report=report,
        )

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


def assemble_bytes(data: bytes, *, fault: str | None = None) -> AssembledRun:
    """Parse a whole byte stream (a raw log) and assemble its run.

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
    assembler = RunAssembler()
    for frame in parser.feed(data) + parser.finish():
        assembler.add(frame)
    if fault is None and not assembler.ended:
        fault = "stream ended without an END frame"
    return assembler.build(parser, fault=fault)
