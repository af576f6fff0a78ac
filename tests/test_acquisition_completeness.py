"""Complete means complete: a device that contradicts itself, or a header with absurd
numbers or an oversized label, never gives a run marked complete."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bayestribo.acquisition.assembly import assemble_bytes
from bayestribo.acquisition.faults import HeaderError
from bayestribo.acquisition.protocol import (
    MAX_LABEL_BYTES,
    FrameType,
    RunHeader,
    encode_data,
    encode_end,
    encode_frame,
)

HEADER = RunHeader(1000.0, 1e-7, 1e-6, 2e-3, 0.5, 4, "DD-500 2mm")


def _stream(extra: list[bytes] | None = None, header: RunHeader = HEADER) -> bytes:
    counts = np.arange(16, dtype=np.int16).reshape(8, 2)
    frames = [
        encode_frame(FrameType.HEADER, 0, header.to_payload()),
        encode_frame(FrameType.DATA, 1, encode_data(0, counts[:4])),
        encode_frame(FrameType.DATA, 2, encode_data(4, counts[4:])),
    ]
    frames += extra or []
    frames.append(encode_frame(FrameType.END, 3, encode_end(2, 8)))
    return b"".join(frames)


def test_a_clean_stream_and_a_retransmission_are_complete():
    assert assemble_bytes(_stream()).complete
    again = encode_frame(
        FrameType.DATA, 2, encode_data(4, np.arange(8, 16, dtype=np.int16).reshape(4, 2))
    )
    run = assemble_bytes(_stream([again]))
    assert run.complete and run.report["duplicate_frames"] == 1
    assert run.report["conflicting_frames"] == 0


def test_a_sequence_number_repeated_with_other_content_makes_the_run_incomplete():
    other = encode_frame(FrameType.DATA, 2, encode_data(4, np.full((4, 2), 99, dtype=np.int16)))
    run = assemble_bytes(_stream([other]))
    assert not run.complete and run.report["conflicting_frames"] == 1
    assert any("repeated with different content" in a for a in run.report["anomalies"])
    # the first frame's samples are kept, the contradicting ones are not used
    assert run.counts[4, 0] == 8


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("displacement_scale_m", 1e300),
        ("displacement_scale_m", 5e-324),
        ("velocity_scale_m_per_s", 1e9),
        ("sample_rate_Hz", 1e12),
        ("displacement_range_m", 1e6),
    ],
)
def test_absurd_header_numbers_are_refused(field, value):
    header = dataclasses.replace(HEADER, **{field: value})
    with pytest.raises(HeaderError, match=f"{field} = .*expected a finite value in"):
        assemble_bytes(_stream(header=header))


def test_an_oversized_label_is_refused_with_its_size():
    header = dataclasses.replace(HEADER, range_label="x" * (MAX_LABEL_BYTES + 1))
    with pytest.raises(HeaderError, match=f"range label of {MAX_LABEL_BYTES + 1} bytes"):
        assemble_bytes(_stream(header=header))
