"""Complete means complete: a device that contradicts itself, or a header with absurd
numbers or an oversized label, never gives a run marked complete."""

from __future__ import annotations

import dataclasses
import struct
import zlib

import numpy as np
import pytest

from bayestribo.acquisition.assembly import assemble_bytes
from bayestribo.acquisition.faults import DuplicateRunError, HeaderError
from bayestribo.acquisition.instrument import SimulatedInstrument, SimulationConfig
from bayestribo.acquisition.logger import OperatorInputs, run_metadata, write_run_files
from bayestribo.acquisition.protocol import (
    HEADER_LIMITS,
    MAX_LABEL_BYTES,
    FrameType,
    RunHeader,
    encode_data,
    encode_end,
    encode_frame,
)
from bayestribo.acquisition.session import acquire_run, finish_run
from bayestribo.campaign.catalog import list_runs
from bayestribo.io import read_run
from bayestribo.io.sidecar import read_sidecar

HEADER = RunHeader(1000.0, 1e-7, 1e-6, 2e-3, 0.5, 4, "DD-500 2mm")
INPUTS = OperatorInputs(load_N=0.31, lubricant="glycerol", repeat=1)


def _stream(
    extra: list[bytes] | None = None,
    header: RunHeader = HEADER,
    *,
    first: int = 0,
    header_frame: bytes | None = None,
) -> bytes:
    counts = np.arange(first, first + 16, dtype=np.int16).reshape(8, 2)
    frames = [
        header_frame or encode_frame(FrameType.HEADER, 0, header.to_payload()),
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


def _frame_of_any_length(kind: int, seq: int, payload: bytes) -> bytes:
    """A frame as a device would send it, even beyond the largest payload allowed."""
    body = b"\xa5\x5a" + struct.pack("<BHI", kind, len(payload), seq) + payload
    return body + struct.pack("<I", zlib.crc32(body[2:]))


@pytest.mark.parametrize("label_bytes", [MAX_LABEL_BYTES + 1, 4057, 20_000])
def test_a_label_too_long_for_any_frame_is_refused_with_its_size_too(label_bytes):
    # Beyond 4056 bytes the header frame exceeds MAX_PAYLOAD; it is still found and
    # refused for its label, not taken for a missing header.
    payload = HEADER.to_payload()[:44] + b"x" * label_bytes
    data = _stream(header_frame=_frame_of_any_length(FrameType.HEADER, 0, payload))
    with pytest.raises(HeaderError, match=f"range label of {label_bytes} bytes, at most 256"):
        assemble_bytes(data)


@pytest.mark.parametrize(
    "corner",
    [
        {name: low for name, (low, _) in HEADER_LIMITS.items()},
        {name: high for name, (_, high) in HEADER_LIMITS.items()},
    ],
    ids=["lowest", "highest"],
)
def test_any_accepted_header_gives_files_the_package_reads_back(tmp_path, corner):
    # The header bounds keep every number the run files hold within what the
    # package's reader accepts: the sidecar passes read_sidecar, and the samples read
    # back bit for bit (validate=False: the physics of made-up counts is not at stake).
    header = dataclasses.replace(
        HEADER,
        sample_rate_Hz=corner["sample_rate_Hz"],
        displacement_scale_m=corner["displacement_scale_m"],
        velocity_scale_m_per_s=corner["velocity_scale_m_per_s"],
        displacement_range_m=corner["displacement_range_m"],
        velocity_range_m_per_s=corner["velocity_range_m_per_s"],
        range_label="é" * (MAX_LABEL_BYTES // 2),
    )
    run = assemble_bytes(_stream(header=header))
    assert run.complete
    raw = tmp_path / "r1.raw"
    raw.write_bytes(_stream(header=header))
    meta = run_metadata(
        run, INPUTS, run_id="r1", raw_log=raw, port=None, started_utc=None, ended_utc=None
    )
    files = write_run_files(tmp_path, "r1", run, meta, raw)
    assert read_sidecar(files.json)["displacement_resolution_m"] == header.displacement_scale_m
    back = read_run(files.csv, validate=False)
    assert np.array_equal(back.displacement, run.displacement_m)
    assert np.array_equal(back.velocity, run.velocity_m_per_s)
    assert np.array_equal(back.time, run.time_s)


def _finish(tmp_path, run_id: str, data: bytes, catalog):
    raw = tmp_path / f"{run_id}.raw"
    raw.write_bytes(data)
    return finish_run(
        assemble_bytes(data),
        INPUTS,
        out_dir=tmp_path,
        run_id=run_id,
        raw_log=raw,
        port=None,
        started_utc=None,
        catalog=catalog,
        fault=None,
    )


def test_a_run_with_the_samples_of_a_catalogued_one_is_refused_before_writing(tmp_path):
    catalog = tmp_path / "catalog.sqlite"
    first = _finish(tmp_path, "r1", _stream(), catalog)
    assert first.catalog_id == 1
    with pytest.raises(DuplicateRunError, match=r"exactly those of run 'r1' \(catalog id 1\)"):
        _finish(tmp_path, "r2", _stream(), catalog)
    assert sorted(p.name for p in tmp_path.glob("r2.*")) == ["r2.raw"]  # no run files
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert [r.run_id for r in list_runs(catalog)] == ["r1"]
    # Writing the same run again (a recovery) is not a duplicate of itself.
    assert _finish(tmp_path, "r1", _stream(), catalog).catalog_id == 1


def test_a_run_id_catalogued_with_other_samples_is_refused_before_writing(tmp_path):
    # One catalog for two folders: run id r1 is taken there by other samples.
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    catalog = tmp_path / "catalog.sqlite"
    _finish(elsewhere, "r1", _stream(), catalog)
    with pytest.raises(DuplicateRunError, match=r"'r1' is catalogued already .* other samples"):
        _finish(tmp_path, "r1", _stream(first=100), catalog)
    assert not (tmp_path / "r1.csv").exists() and (tmp_path / "r1.raw").exists()


class _LongLabel(SimulationConfig):
    @property
    def header(self) -> RunHeader:
        return dataclasses.replace(super().header, range_label="x" * 5000)


def test_a_live_header_with_a_label_too_long_for_a_frame_is_refused_for_its_label(
    tmp_path, monkeypatch
):
    from bayestribo.acquisition import instrument

    def any_length(kind: int, seq: int, payload: bytes = b"") -> bytes:
        return _frame_of_any_length(kind, seq, bytes(payload))

    monkeypatch.setattr(instrument, "encode_frame", any_length)
    sim = SimulatedInstrument(
        _LongLabel(sample_rate_Hz=2000.0, duration_s=0.5, samples_per_frame=32)
    )
    path = sim.start_pty()
    try:
        with pytest.raises(HeaderError, match="range label of 5000 bytes, at most 256"):
            acquire_run(path, tmp_path, INPUTS, timeout_s=0.5, run_id="long")
        assert sim.received("STOP")  # the device's run is ended
    finally:
        sim.stop()
    assert (tmp_path / "long.raw").stat().st_size > 5000  # and what it sent is kept
