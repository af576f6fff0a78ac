"""Wire protocol: frame layout, checksum, header checks, and the resynchronising parser."""

from __future__ import annotations

import itertools
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bayestribo.acquisition.assembly import assemble_bytes
from bayestribo.acquisition.faults import FrameError, HeaderError
from bayestribo.acquisition.protocol import (
    MAX_PAYLOAD,
    SYNC,
    FrameParser,
    FrameType,
    RunHeader,
    decode_data,
    decode_end,
    decode_release,
    encode_data,
    encode_end,
    encode_frame,
    encode_release,
)
from bayestribo.errors import AcquisitionError

HEADER = RunHeader(
    sample_rate_Hz=20_000.0,
    displacement_scale_m=2e-3 / 32767,
    velocity_scale_m_per_s=0.5 / 32767,
    displacement_range_m=2e-3,
    velocity_range_m_per_s=0.5,
    samples_per_frame=4,
    range_label="DD-500 ±2 mm; VD-06 ±0.5 m/s",
)


def crc32_bitwise(data: bytes) -> int:
    """CRC-32/IEEE as a firmware would compute it: reflected, poly 0xEDB88320, no table."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ (0xEDB88320 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


def test_crc_check_value_and_firmware_algorithm():
    # The standard check value of CRC-32/ISO-HDLC over "123456789" is 0xCBF43926.
    assert crc32_bitwise(b"123456789") == 0xCBF43926
    frame = encode_frame(FrameType.ACK, 7, b"RATE 20000")
    (crc,) = struct.unpack("<I", frame[-4:])
    assert crc == crc32_bitwise(frame[2:-4])


def test_frame_layout_is_the_documented_one():
    frame = encode_frame(FrameType.DATA, 0x01020304, encode_data(9, np.array([[1, -2]])))
    # sync, type, length (u16 LE), seq (u32 LE), payload, crc
    assert frame[:2] == SYNC
    assert frame[2] == 0x10
    assert frame[3:5] == (8).to_bytes(2, "little")
    assert frame[5:9] == bytes([4, 3, 2, 1])
    assert frame[9:13] == (9).to_bytes(4, "little")
    assert frame[13:17] == struct.pack("<hh", 1, -2)
    assert len(frame) == 9 + 8 + 4


def test_data_frame_of_128_pairs_fits_20_kS_per_s_at_921600_baud():
    # 20 kS/s of two channels in frames of 128 pairs, 10 bits per byte on a UART (8N1).
    frame = encode_frame(FrameType.DATA, 0, encode_data(0, np.zeros((128, 2), np.int16)))
    bytes_per_s = 20_000 / 128 * len(frame)
    assert bytes_per_s * 10 < 921_600


def test_roundtrip_of_every_payload():
    counts = np.array([[32767, -32768], [0, 1], [-5, 5]], dtype=np.int16)
    first, back = decode_data(encode_data(123456, counts))
    assert first == 123456 and np.array_equal(back, counts)
    assert decode_release(encode_release(77)) == 77
    assert decode_end(encode_end(10, 1280)) == (10, 1280)
    assert RunHeader.from_payload(HEADER.to_payload()) == HEADER


@pytest.mark.parametrize(
    ("payload", "field"),
    [
        (HEADER.to_payload()[:20], "expected at least 44"),
        (b"\x02" + HEADER.to_payload()[1:], "protocol version 2"),
        (HEADER.to_payload()[:1] + b"\x03" + HEADER.to_payload()[2:], "3 channels"),
    ],
)
def test_header_that_does_not_parse_names_the_problem(payload, field):
    with pytest.raises(HeaderError, match=field):
        RunHeader.from_payload(payload)


@pytest.mark.parametrize(
    "name",
    [
        "sample_rate_Hz",
        "displacement_scale_m",
        "velocity_scale_m_per_s",
        "displacement_range_m",
        "velocity_range_m_per_s",
    ],
)
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf")])
def test_header_rejects_non_positive_or_non_finite_values(name, value):
    bad = RunHeader(**{**HEADER.__dict__, name: value})
    with pytest.raises(HeaderError, match=name):
        RunHeader.from_payload(bad.to_payload())


def test_bad_payloads_raise_frame_error_not_anything_else():
    with pytest.raises(FrameError, match="4 \\+ 4n"):
        decode_data(b"\x00" * 6)
    with pytest.raises(FrameError, match="expected 4"):
        decode_release(b"\x00")
    with pytest.raises(FrameError, match="expected 8"):
        decode_end(b"\x00" * 9)
    with pytest.raises(FrameError, match="at most"):
        encode_frame(FrameType.DATA, 0, b"\x00" * (MAX_PAYLOAD + 1))
    with pytest.raises(FrameError, match="unknown frame type"):
        encode_frame(0x7F, 0)
    assert issubclass(FrameError, AcquisitionError)


def sample_frames() -> list[bytes]:
    return [
        encode_frame(FrameType.IDENT, 0, b"bayestribo,sim"),
        encode_frame(FrameType.HEADER, 0, HEADER.to_payload()),
        encode_frame(FrameType.DATA, 1, encode_data(0, np.arange(8).reshape(4, 2))),
        encode_frame(FrameType.RELEASE, 2, encode_release(4)),
        encode_frame(FrameType.DATA, 3, encode_data(4, -np.arange(8).reshape(4, 2))),
        encode_frame(FrameType.END, 4, encode_end(4, 8)),
    ]


def test_parser_byte_by_byte_equals_whole():
    stream = b"".join(sample_frames())
    whole = FrameParser().feed(stream)
    parser = FrameParser()
    pieces = [f for i in range(len(stream)) for f in parser.feed(stream[i : i + 1])]
    assert pieces == whole
    assert [f.type for f in whole] == [1, 2, 0x10, 0x11, 0x10, 0x1F]
    assert parser.discarded_bytes == 0


def test_parser_skips_corrupted_frame_and_keeps_the_next():
    frames = sample_frames()
    damaged = bytearray(frames[2])
    damaged[12] ^= 0x01
    stream = frames[1] + bytes(damaged) + frames[3]
    parser = FrameParser()
    out = parser.feed(stream) + parser.finish()
    assert [f.type for f in out] == [FrameType.HEADER, FrameType.RELEASE]
    assert parser.rejected_candidates == 1
    # Every byte of the damaged frame is discarded, nothing else.
    assert parser.discarded_bytes == len(damaged)


def test_false_candidate_with_long_length_delays_but_never_drops():
    # A false sync announcing a long payload: the parser waits for it, then rescans.
    fake = SYNC + bytes([FrameType.DATA]) + (4000).to_bytes(2, "little") + b"\x00" * 4
    real = sample_frames()[2]
    parser = FrameParser()
    assert parser.feed(fake + real) == []  # waits: the false candidate might complete
    assert parser.finish() == [parser_frame(real, offset=len(fake))]


def parser_frame(frame: bytes, offset: int):
    (out,) = FrameParser().feed(frame)
    return out._replace(offset=offset)


def test_assembled_run_reports_gaps_and_never_fills_them():
    frames = sample_frames()
    run = assemble_bytes(b"".join(frames[:2] + frames[3:]))  # first DATA frame lost
    assert not run.complete
    assert run.report["gaps"] == [
        {
            "start_sample": 0,
            "stop_sample": 4,
            "n_samples": 4,
            "start_time_s": 0.0,
            "stop_time_s": 4 / 20_000,
        }
    ]
    assert run.report["missing_sequence_numbers"] == [1]
    assert run.report["frames_missing"] == 1
    assert list(run.sample_index) == [4, 5, 6, 7]
    assert np.array_equal(run.counts, -np.arange(8).reshape(4, 2))
    assert np.allclose(run.time_s, np.arange(4, 8) / 20_000, rtol=0, atol=0)


def test_assembled_run_complete_and_scaled():
    run = assemble_bytes(b"".join(sample_frames()))
    assert run.complete
    assert run.report["release_sample_index"] == 4
    assert run.report["device_ident"] == "bayestribo,sim"
    counts = np.concatenate([np.arange(8).reshape(4, 2), -np.arange(8).reshape(4, 2)])
    assert np.array_equal(run.displacement_m, counts[:, 0] * HEADER.displacement_scale_m)
    assert np.array_equal(run.velocity_m_per_s, counts[:, 1] * HEADER.velocity_scale_m_per_s)


def test_missing_end_frame_marks_the_run_incomplete():
    run = assemble_bytes(b"".join(sample_frames()[:-1]))
    assert not run.complete
    assert run.report["fault"] == "stream ended without an END frame"
    assert run.report["samples_received"] == 8


def test_no_header_is_a_clear_error():
    with pytest.raises(FrameError, match="no valid run header"):
        assemble_bytes(sample_frames()[2])


# -- property tests ---------------------------------------------------------------------

frames_strategy = st.lists(
    st.tuples(
        st.integers(0, 2**32 - 1),
        st.integers(0, 2**32 - 1 - 64),
        st.lists(st.integers(-32768, 32767), min_size=2, max_size=64).filter(
            lambda v: len(v) % 2 == 0
        ),
    ),
    min_size=1,
    max_size=4,
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.binary(max_size=600), cuts=st.lists(st.integers(0, 600), max_size=6))
def test_arbitrary_bytes_only_ever_raise_the_package_error(data, cuts):
    # Any chunking of any bytes: the parser never raises; assembling raises only the
    # package's AcquisitionError subclasses.
    parser = FrameParser()
    bounds = sorted({0, len(data), *(c for c in cuts if c <= len(data))})
    frames = []
    for a, b in itertools.pairwise(bounds):
        frames += parser.feed(data[a:b])
    frames += parser.finish()
    assert parser.discarded_bytes + sum(f.size for f in frames) == len(data)
    try:
        assemble_bytes(data)
    except AcquisitionError:
        pass


@settings(max_examples=300, deadline=None)
@given(
    garbage=st.binary(max_size=300)
    | st.lists(
        st.sampled_from([SYNC, b"\xa5", b"\x5a", b"\x10", b"\x00", b"\xff", b"\x04\x10"]),
        max_size=40,
    ).map(b"".join),
    frames=frames_strategy,
    chunk=st.integers(1, 64),
)
def test_valid_frames_after_garbage_are_never_lost(garbage, frames, chunk):
    encoded = [
        encode_frame(FrameType.DATA, seq, encode_data(first, np.array(v).reshape(-1, 2)))
        for seq, first, v in frames
    ]
    stream = garbage + b"".join(encoded)
    parser = FrameParser()
    out = []
    for i in range(0, len(stream), chunk):
        out += parser.feed(stream[i : i + chunk])
    out += parser.finish()
    # Every valid frame appended after the garbage is found, unchanged, at its offset.
    expected_offsets = np.cumsum([len(garbage)] + [len(e) for e in encoded[:-1]])
    found = {(f.offset, f.seq, f.payload) for f in out}
    for offset, frame in zip(expected_offsets, encoded, strict=True):
        (reference,) = FrameParser().feed(frame)
        assert (int(offset), reference.seq, reference.payload) in found
