"""Raw log (append-only, synced at least once a second) and atomic run files."""

from __future__ import annotations

import json
import os
import time

import numpy as np
import pytest

from bayestribo.acquisition import logger as logger_module
from bayestribo.acquisition.assembly import assemble_bytes
from bayestribo.acquisition.logger import (
    OperatorInputs,
    RawLog,
    make_run_id,
    run_metadata,
    write_json_atomic,
    write_run_files,
)
from bayestribo.acquisition.protocol import (
    FrameType,
    RunHeader,
    encode_data,
    encode_end,
    encode_frame,
)
from bayestribo.errors import AcquisitionError
from bayestribo.io import read_run

HEADER = RunHeader(2000.0, 1e-7, 1e-5, 3e-3, 0.3, 16, "label")


def stream() -> bytes:
    """A complete run of 80 samples in five DATA frames of 16."""
    counts = np.arange(160, dtype=np.int16).reshape(80, 2)
    frames = [encode_frame(FrameType.HEADER, 0, HEADER.to_payload())]
    for k in range(5):
        frames.append(
            encode_frame(FrameType.DATA, 1 + k, encode_data(16 * k, counts[16 * k : 16 * k + 16]))
        )
    frames.append(encode_frame(FrameType.END, 6, encode_end(6, 80)))
    return b"".join(frames)


def test_raw_log_appends_and_is_on_disk_at_once(tmp_path):
    path = tmp_path / "run.raw"
    with RawLog(path) as log:
        log.write(b"abc")
        # Visible to another reader before any close: it survives the process's death.
        assert path.read_bytes() == b"abc"
    with RawLog(path) as log:
        log.write(b"def")
    assert path.read_bytes() == b"abcdef"  # reopened logs append, never truncate


def test_raw_log_syncs_within_the_interval(tmp_path, monkeypatch):
    clock = [100.0]
    synced = []
    monkeypatch.setattr(logger_module.time, "monotonic", lambda: clock[0])
    real_fsync = os.fsync
    monkeypatch.setattr(logger_module.os, "fsync", lambda fd: synced.append(fd) or real_fsync(fd))
    log = RawLog(tmp_path / "r.raw", sync_interval_s=0.5)
    log.write(b"x")
    assert synced == []
    clock[0] += 0.49
    log.tick()
    assert synced == []
    clock[0] += 0.01
    log.tick()  # 0.5 s after the first unsynced byte
    assert len(synced) == 1
    log.tick()
    assert len(synced) == 1  # nothing new to sync
    log.close()
    assert len(synced) == 2  # closing always syncs
    assert logger_module.SYNC_INTERVAL_S < 1.0  # the promise: at least once a second
    with pytest.raises(AcquisitionError, match="closed"):
        log.write(b"y")


def test_raw_log_unwritable_path_is_a_clear_error(tmp_path):
    with pytest.raises(AcquisitionError, match="cannot open the raw log"):
        RawLog(tmp_path / "no" / "such" / "dir" / "r.raw")


def metadata_for(tmp_path, raw_bytes: bytes):
    raw = tmp_path / "r.raw"
    raw.write_bytes(raw_bytes)
    run = assemble_bytes(raw_bytes)
    inputs = OperatorInputs(load_N=0.31, lubricant="glycerol", repeat=2, water_mass_fraction=0.0)
    meta = run_metadata(
        run, inputs, run_id="r", raw_log=raw, port="loop://", started_utc="s", ended_utc="e"
    )
    return run, meta, raw


def test_run_files_roundtrip_through_the_canonical_reader(tmp_path):
    run, meta, raw = metadata_for(tmp_path, stream())
    files = write_run_files(tmp_path / "out", "r", run, meta, raw)
    # Ramps, not a decay: skip the reader's physical checks (the pty tests read real
    # simulated decays with validation on).
    back = read_run(files.csv, validate=False)
    assert np.array_equal(back.time, np.arange(80) / 2000.0)
    assert np.array_equal(back.displacement, np.arange(0, 160, 2) * 1e-7)
    assert np.array_equal(back.velocity, np.arange(1, 160, 2) * 1e-5)
    side = json.loads(files.json.read_text())
    assert side["displacement_resolution_m"] == 1e-7
    assert side["velocity_range_m_per_s"] == 0.3
    assert side["complete"] is True and side["gaps"] == []
    assert side["acquisition"]["device_header"]["range_label"] == "label"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["r.csv", "r.json", "r.sha256"]


def test_crash_while_writing_leaves_no_partial_run(tmp_path, monkeypatch):
    run, meta, raw = metadata_for(tmp_path, stream())
    out = tmp_path / "out"

    def crash(*args, **kwargs):
        raise OSError("disk full")

    # The CSV is written, then the sidecar fails.
    monkeypatch.setattr(logger_module, "write_sidecar", crash)
    with pytest.raises(OSError, match="disk full"):
        write_run_files(out, "r", run, meta, raw)
    assert list(out.iterdir()) == []  # neither a half CSV nor a temporary directory


def test_write_json_atomic_keeps_old_content_on_failure(tmp_path):
    path = tmp_path / "s.json"
    write_json_atomic(path, {"a": 1})
    with pytest.raises(TypeError):
        write_json_atomic(path, {"a": object()})
    assert json.loads(path.read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["s.json"]


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"water_mass_fraction": 1.5}, "water_mass_fraction"),
        ({"load_N": -1.0}, "load_N"),
        ({"repeat": 0}, "repeat"),
        ({"lubricant": "  "}, "lubricant"),
        ({"temperature_C": -300.0}, "temperature_C"),
    ],
)
def test_operator_inputs_are_checked(kwargs, field):
    base = {"load_N": 0.31, "lubricant": "glycerol", "repeat": 1}
    with pytest.raises(AcquisitionError, match=field):
        OperatorInputs(**{**base, **kwargs})


def test_run_id_is_file_name_safe():
    from datetime import UTC, datetime

    inputs = OperatorInputs(load_N=0.31, lubricant="glycerol / water 50%", repeat=2)
    when = datetime(2026, 11, 22, 6, 15, tzinfo=UTC)
    assert make_run_id(inputs, when) == "20261122T061500Z_glycerol-water-50_N0.31_r2"


def test_background_sync_needs_no_calls_from_the_reader(tmp_path, monkeypatch):
    synced = []
    real_fsync = os.fsync
    monkeypatch.setattr(logger_module.os, "fsync", lambda fd: synced.append(fd) or real_fsync(fd))
    log = RawLog(tmp_path / "r.raw", sync_interval_s=0.05, background=True)
    log.write(b"x")  # and then no tick() at all
    deadline = time.monotonic() + 5.0  # generous: only that it happens, not how fast
    while not synced and time.monotonic() < deadline:
        time.sleep(0.01)
    assert len(synced) == 1
    log.close()
    assert (tmp_path / "r.raw").read_bytes() == b"x"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
def test_full_disk_is_a_clear_error():
    log = RawLog("/dev/full")
    with pytest.raises(AcquisitionError, match="cannot append to the raw log"):
        log.write(b"abc")
    log.close()


def test_nothing_is_appended_after_a_failed_write(tmp_path, monkeypatch):
    # A write that fails partway leaves a hole after the bytes it did write: a later
    # write (the disk has room again) must not append after the hole.
    import errno

    from bayestribo.acquisition.faults import StorageError

    real_write = os.write
    fail = [True]

    def write(fd, data):
        if fail[0]:
            fail[0] = False
            real_write(fd, bytes(data[:2]))
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    log = RawLog(tmp_path / "r.raw")
    log.write(b"abc")
    monkeypatch.setattr(logger_module.os, "write", write)
    with pytest.raises(StorageError, match="cannot append"):
        log.write(b"defg")
    with pytest.raises(StorageError, match="cannot append"):
        log.write(b"hij")
    log.close()  # the failure was raised already
    assert (tmp_path / "r.raw").read_bytes() == b"abcde"  # a prefix of what came


def test_bytes_after_a_failed_sync_are_still_logged(tmp_path, monkeypatch):
    # A failed sync leaves the log whole: what comes after it is appended, then the
    # failure is raised.
    import errno

    from bayestribo.acquisition.faults import StorageError

    def fsync(fd):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(logger_module.os, "fsync", fsync)
    log = RawLog(tmp_path / "r.raw", sync_interval_s=0.0)
    with pytest.raises(StorageError, match="cannot sync"):
        log.write(b"abc")
    with pytest.raises(StorageError, match="cannot sync"):
        log.write(b"def")
    log.close()
    assert (tmp_path / "r.raw").read_bytes() == b"abcdef"
