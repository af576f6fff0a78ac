"""Acquisition through a real pseudo-terminal with pyserial: one test per fault.

Each test checks that the raw log holds every byte the simulated instrument sent and
that the run holds every frame it sent intact (sample indices and counts equal), with
the missing ones reported, never filled.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from bayestribo.acquisition import (
    AcquisitionTimeout,
    HeaderError,
    OperatorInputs,
    PortBusyError,
    PortNotFoundError,
    acquire_run,
)
from bayestribo.acquisition.instrument import FaultPlan, SimulatedInstrument, SimulationConfig
from bayestribo.acquisition.port import open_port
from bayestribo.campaign.catalog import find_run, list_runs
from bayestribo.errors import AcquisitionError, RecordingError
from bayestribo.io import read_run

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX")

# Small, fast runs: 2 kS/s, 0.5 s after release, 32 sample pairs a frame.
SMALL = SimulationConfig(sample_rate_Hz=2000.0, duration_s=0.5, samples_per_frame=32)
INPUTS = OperatorInputs(
    load_N=0.31,
    lubricant="glycerol",
    repeat=2,
    water_mass_fraction=0.1,
    temperature_C=22.5,
    notes="pty test",
    mass_kg=0.035,
    natural_frequency_Hz=32.6,
)

ACQUIRE_ONLY_CLI = """
import argparse, sys
from bayestribo.cli import acquire
from bayestribo.errors import BayestriboError
parser = argparse.ArgumentParser(prog="bayestribo")
acquire.register(parser.add_subparsers(dest="command"))
args = parser.parse_args(sys.argv[1:])
try:
    sys.exit(args.handler(args))
except BayestriboError as exc:
    print(f"bayestribo acquire: error: {exc}", file=sys.stderr)
    sys.exit(2)
"""


def cli_command() -> list[str]:
    """The ``bayestribo`` command line, or only its ``acquire`` command if other
    sub-commands are not installed yet."""
    try:
        from bayestribo.cli import build_parser

        build_parser()
    except ImportError:
        return [sys.executable, "-c", ACQUIRE_ONLY_CLI]
    return [sys.executable, "-m", "bayestribo.cli"]


@contextmanager
def simulated(faults: FaultPlan | None = None, *, realtime: bool = False, config=SMALL):
    sim = SimulatedInstrument(config, faults, realtime=realtime)
    path = sim.start_pty()
    try:
        yield sim, path
    finally:
        sim.stop()


def assert_kept_everything(sim: SimulatedInstrument, result) -> None:
    """Raw log == bytes sent; run == every intact frame; the files say the same."""
    sim.stop()  # no byte is sent after this
    assert result.files.raw.read_bytes() == bytes(sim.sent)
    index, counts = sim.intact_samples()
    assert len(index) > 0
    assert np.array_equal(result.run.sample_index, index)
    assert np.array_equal(result.run.counts, counts)
    header = sim.config.header
    run = read_run(result.files.csv, validate=False)
    assert np.array_equal(run.time, index / header.sample_rate_Hz)
    assert np.array_equal(run.displacement, counts[:, 0] * header.displacement_scale_m)
    assert np.array_equal(run.velocity, counts[:, 1] * header.velocity_scale_m_per_s)
    lost = [f for f in sim.frames if not f.intact]
    assert result.metadata["samples_missing"] == sum(len(f.counts) for f in lost)
    assert result.metadata["acquisition"]["missing_sequence_numbers"] == [f.seq for f in lost]


def test_clean_run_is_complete_with_full_context(tmp_path):
    progress = []
    with simulated() as (sim, path):
        result = acquire_run(
            path, tmp_path, INPUTS, progress=progress.append, catalog=tmp_path / "c.sqlite"
        )
        assert_kept_everything(sim, result)
    assert result.complete and result.fault is None
    meta = json.loads(result.files.json.read_text())
    for key, value in INPUTS.items():
        assert meta[key] == value
    assert meta["sample_rate_Hz"] == 2000.0
    assert meta["displacement_resolution_m"] == SMALL.header.displacement_scale_m
    assert meta["velocity_resolution_m_per_s"] == SMALL.header.velocity_scale_m_per_s
    acq = meta["acquisition"]
    assert acq["device_header"]["range_label"] == SMALL.header.range_label
    assert acq["device_ident"] == sim.ident
    assert acq["release_sample_index"] == sim.release_index
    assert acq["package_version"] and acq["host_time_start_utc"] and acq["port"] == path
    assert acq["raw_log_sha256"] == hashlib.sha256(bytes(sim.sent)).hexdigest()
    # The manifest lists the true SHA-256 of the raw log and of both run files.
    for line in result.files.manifest.read_text().splitlines():
        digest, name = line.split("  ")
        assert hashlib.sha256((tmp_path / name).read_bytes()).hexdigest() == digest
    # A complete run passes the canonical reader's validation.
    run = read_run(result.files.csv)
    assert run.metadata["run_id"] == result.run_id
    # Registered in the catalog under the CSV's SHA-256.
    record = find_run(tmp_path / "c.sqlite", sha256=result.files.digests[result.files.csv.name])
    assert record is not None and record.id == result.catalog_id
    assert record.metadata["files_sha256"] == result.files.digests
    # Progress was reported while streaming, in non-decreasing sample counts.
    assert progress and all(a.samples <= b.samples for a, b in itertools.pairwise(progress))
    # No temporary file left behind by the atomic writes.
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_no_answer_times_out_and_keeps_the_raw_log(tmp_path):
    with simulated(FaultPlan(silent=True)) as (sim, path):
        with pytest.raises(AcquisitionTimeout, match=r"no answer to 'ID\?' within 0.3 s"):
            acquire_run(path, tmp_path, INPUTS, timeout_s=0.3, run_id="silent")
    assert sim.commands[:1] == ["ID?"]
    assert (tmp_path / "silent.raw").read_bytes() == bytes(sim.sent) == b""
    assert not (tmp_path / "silent.csv").exists()


def test_stall_mid_run_ends_with_timeout_and_keeps_what_came(tmp_path):
    with simulated(FaultPlan(stall={6: 30.0})) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS, timeout_s=0.3)
        assert_kept_everything(sim, result)
    assert "stopped sending for 0.3 s" in result.fault
    assert not result.complete
    assert result.run.report["samples_received"] == 6 * 32
    assert result.metadata["acquisition"]["end_frame_received"] is False


def test_disconnect_mid_run_keeps_every_frame_received(tmp_path):
    with simulated(FaultPlan(disconnect_after=9)) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS, timeout_s=2.0)
        assert sim.disconnected
        assert_kept_everything(sim, result)
    assert "disconnected" in result.fault
    assert not result.complete
    assert result.run.report["samples_received"] == 9 * 32


def test_corrupt_frames_are_reported_as_gaps(tmp_path):
    with simulated(FaultPlan(corrupt=frozenset({3, 7}))) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS)
        assert_kept_everything(sim, result)
    assert not result.complete and result.fault is None
    gaps = result.metadata["gaps"]
    assert [(g["start_sample"], g["n_samples"]) for g in gaps] == [(96, 32), (224, 32)]
    acq = result.metadata["acquisition"]
    # Exactly the bytes of the two damaged frames were discarded.
    assert acq["discarded_bytes"] == sum(f.size for f in sim.frames if f.number in (3, 7))


def test_garbage_between_frames_loses_nothing(tmp_path):
    faults = FaultPlan(garbage=frozenset({0, 2, 5}), garbage_bytes=80)
    with simulated(faults) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS)
        assert_kept_everything(sim, result)
    assert result.complete
    assert result.metadata["acquisition"]["discarded_bytes"] == 3 * 80


def test_sequence_gaps_are_reported_never_filled(tmp_path):
    with simulated(FaultPlan(drop=frozenset({4, 5, 20}))) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS)
        assert_kept_everything(sim, result)
    dropped = [f for f in sim.frames if f.number in (4, 5, 20)]
    assert not result.complete
    assert result.metadata["complete"] is False
    assert result.metadata["acquisition"]["frames_missing"] == 3
    gaps = result.metadata["gaps"]
    assert [(g["start_sample"], g["stop_sample"]) for g in gaps] == [
        (dropped[0].first_index, dropped[1].first_index + 32),
        (dropped[2].first_index, dropped[2].first_index + 32),
    ]
    # No row was invented for the missing samples ...
    assert result.run.report["samples_received"] == len(sim.intact_samples()[0])
    # ... so the canonical reader refuses the run (gaps of whole frames of 32 samples, half
    # a period or more at this rate: too long to bridge) unless told to accept the gaps.
    with pytest.raises(
        RecordingError, match=r"samples are missing after sample .* cannot be bridged"
    ):
        read_run(result.files.csv)


def test_header_that_does_not_parse_is_a_clear_error(tmp_path):
    with simulated(FaultPlan(bad_header=True)) as (sim, path):
        with pytest.raises(HeaderError, match="run header: payload of 20 bytes") as info:
            acquire_run(path, tmp_path, INPUTS, run_id="badheader")
        assert "raw log kept" in str(info.value)
        assert sim.received("STOP")
        sim.stop()
        assert (tmp_path / "badheader.raw").read_bytes() == bytes(sim.sent)
    assert len(sim.sent) > 0
    assert not (tmp_path / "badheader.csv").exists()


def test_lost_header_times_out_even_while_data_streams(tmp_path):
    # The header fails its checksum; DATA keeps coming but cannot be scaled.
    with simulated(FaultPlan(corrupt_header=True), realtime=True) as (sim, path):
        with pytest.raises(AcquisitionTimeout, match=r"no run header after 'ARM' within 0\.4 s"):
            acquire_run(path, tmp_path, INPUTS, timeout_s=0.4, run_id="lost")
        sim.stop()
        assert (tmp_path / "lost.raw").read_bytes() == bytes(sim.sent)
    assert len(sim.frames) > 0  # DATA frames did arrive meanwhile


def test_nonexistent_port_is_a_clear_error_and_writes_nothing(tmp_path):
    with pytest.raises(PortNotFoundError, match="/dev/no-such-port-bt: no such port"):
        acquire_run("/dev/no-such-port-bt", tmp_path / "out", INPUTS)
    assert not (tmp_path / "out").exists()
    with pytest.raises(PortNotFoundError):
        open_port("socket://127.0.0.1:1")  # nothing listens on port 1


def test_busy_port_is_a_clear_error(tmp_path):
    with simulated() as (_, path):
        holder = open_port(path)  # exclusive lock, like another program holding it
        try:
            with pytest.raises(PortBusyError, match="busy"):
                acquire_run(path, tmp_path, INPUTS)
        finally:
            holder.close()
        assert isinstance(PortBusyError("x"), AcquisitionError)


def test_keyboard_interrupt_in_process_keeps_everything(tmp_path):
    def interrupt(progress):
        if progress.samples >= 200:
            raise KeyboardInterrupt

    with simulated(realtime=True) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS, progress=interrupt, progress_interval_s=0.0)
        assert_kept_everything(sim, result)
    assert result.interrupted and "Ctrl-C" in result.fault
    assert "STOP" in sim.commands
    assert result.metadata["acquisition"]["end_frame_received"] is True


def wait_for_raw_log(out: Path, min_bytes: int, deadline_s: float = 15.0) -> Path:
    deadline = time.monotonic() + deadline_s
    while time.monotonic() < deadline:
        logs = list(out.glob("*.raw"))
        if logs and logs[0].stat().st_size >= min_bytes:
            return logs[0]
        time.sleep(0.02)
    raise AssertionError(f"no raw log of {min_bytes} bytes in {out} within {deadline_s} s")


def test_ctrl_c_in_the_command_line_writes_the_run(tmp_path):
    config = SimulationConfig(sample_rate_Hz=2000.0, duration_s=10.0, samples_per_frame=20)
    with simulated(realtime=True, config=config) as (sim, path):
        proc = subprocess.Popen(
            [
                *cli_command(),
                "acquire",
                "--port",
                path,
                "--load",
                "0.31",
                "--lubricant",
                "glycerol",
                "--out",
                str(tmp_path),
                "--no-catalog",
                "--quiet",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            wait_for_raw_log(tmp_path, 3000)
            proc.send_signal(signal.SIGINT)
            _out, err = proc.communicate(timeout=15)
        finally:
            proc.kill()
        assert proc.returncode == 130, err
        assert "INCOMPLETE: interrupted by the operator (Ctrl-C)" in err
        sim.stop()
        (csv,) = tmp_path.glob("*.csv")
        meta = json.loads(csv.with_suffix(".json").read_text())
        assert meta["complete"] is False
        assert csv.with_suffix(".raw").read_bytes() == bytes(sim.sent)
        index, counts = sim.intact_samples()
        run = read_run(csv)
        assert np.array_equal(run.time, index / 2000.0)
        assert np.array_equal(run.displacement, counts[:, 0] * config.header.displacement_scale_m)
        assert meta["acquisition"]["samples_received"] < 10 * 2000  # stopped early


def test_socket_url_and_simulated_chain(tmp_path):
    sim = SimulatedInstrument(SMALL, FaultPlan(drop=frozenset({2})), realtime=False)
    url = sim.start_socket()
    try:
        result = acquire_run(url, tmp_path, INPUTS)
        assert_kept_everything(sim, result)
    finally:
        sim.stop()
    assert url.startswith("socket://127.0.0.1:")
    assert len(result.metadata["gaps"]) == 1


def test_loop_url_moves_bytes_unchanged():
    with open_port("loop://") as link:
        link.write_line("ID?")
        assert link.read_available() == b"ID?\n"


def test_simulate_option_of_the_command_runs_the_whole_chain(tmp_path):
    proc = subprocess.run(
        [
            *cli_command(),
            "acquire",
            "--simulate",
            "--load",
            "0.31",
            "--lubricant",
            "water",
            "--repeat",
            "3",
            "--out",
            str(tmp_path),
            "--drop",
            "3",
            "--quiet",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 1, proc.stderr  # incomplete: one frame dropped
    assert "gap: samples 384..511" in proc.stderr
    (csv,) = tmp_path.glob("*_water_N0.31_r3.csv")
    assert find_run(tmp_path / "catalog.sqlite", run_id=csv.stem) is not None


@pytest.fixture
def full_after_1k(monkeypatch):
    """The raw log's writes fail with ENOSPC once 1 kB is on disk (a run of the small
    simulated board is about 5.5 kB); only the raw log's: the simulated device writes
    to its terminal through the same os.write."""
    import errno

    from bayestribo.acquisition import logger as logger_module

    real_write, real_init = os.write, logger_module.RawLog.__init__
    raw_fds: set[int] = set()
    written = {"n": 0}

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        raw_fds.add(self._fd)

    def write(fd, data):
        if fd not in raw_fds:  # the simulated device's own writes go through
            return real_write(fd, data)
        if written["n"] >= 1024:
            raise OSError(errno.ENOSPC, "No space left on device")
        n = real_write(fd, data)
        written["n"] += n
        return n

    monkeypatch.setattr(logger_module.RawLog, "__init__", init)
    monkeypatch.setattr(logger_module.os, "write", write)
    return written


def test_disk_full_while_streaming_stops_the_device_and_keeps_the_raw_log(tmp_path, full_after_1k):
    from bayestribo.acquisition.faults import StorageError

    written = full_after_1k
    with simulated() as (sim, path):
        with pytest.raises(StorageError, match=r"No space left.*--recover .*\.raw") as caught:
            acquire_run(path, tmp_path, INPUTS, catalog=None)
        assert sim.received("STOP")
        sent = bytes(sim.sent)
    assert "\n" not in str(caught.value)
    [raw] = list(tmp_path.glob("*.raw"))
    kept = raw.read_bytes()
    assert len(kept) == written["n"] >= 1024 and sent.startswith(kept)
    assert not list(tmp_path.glob("*.csv"))  # no run files on a full disk


def test_the_recovery_a_full_disk_names_gives_the_run_received(tmp_path, monkeypatch):
    # the advice of the disk-full error, followed as printed once space is free
    import re

    from bayestribo.acquisition import logger as logger_module
    from bayestribo.acquisition.faults import StorageError
    from bayestribo.cli.main import main

    real_write, real_init = os.write, logger_module.RawLog.__init__
    raw_fds: set[int] = set()

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        raw_fds.add(self._fd)

    def write(fd, data):
        if fd in raw_fds and len(data) and os.fstat(fd).st_size >= 1024:
            raise OSError(28, "No space left on device")
        return real_write(fd, data)

    monkeypatch.setattr(logger_module.RawLog, "__init__", init)
    monkeypatch.setattr(logger_module.os, "write", write)
    with simulated() as (_, path):
        with pytest.raises(StorageError) as caught:
            acquire_run(path, tmp_path, INPUTS, catalog=None)
    monkeypatch.undo()  # space freed
    command = re.search(r"`bayestribo acquire (--recover \S+)`", str(caught.value))
    assert command is not None, str(caught.value)
    argv = ["acquire", *command[1].split(), "--quiet"]  # as printed: beside the raw log
    assert main(argv) == 1  # what was received, short of its end: incomplete
    [csv] = list(tmp_path.glob("*.csv"))
    run = read_run(csv)
    assert run.n_samples > 0 and run.metadata["complete"] is False


def test_disk_full_while_writing_the_run_files_names_the_recovery(tmp_path, monkeypatch):
    import errno

    from bayestribo.acquisition import session as session_module
    from bayestribo.acquisition.faults import StorageError

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(session_module, "write_run_files", full)
    with simulated() as (_, path):
        with pytest.raises(StorageError, match=r"cannot write the run files.*--recover"):
            acquire_run(path, tmp_path, INPUTS, catalog=None)
    [raw] = list(tmp_path.glob("*.raw"))
    assert raw.stat().st_size > 0


def test_the_command_exits_3_on_a_full_disk_with_one_line(tmp_path, full_after_1k, capsys):
    from bayestribo.cli import main

    argv = ["acquire", "--simulate", "--load", "0.31", "--lubricant", "glycerol"]
    assert main([*argv, "--out", str(tmp_path), "--no-catalog", "--quiet"]) == 3
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0].startswith("simulated instrument on")
    assert len(lines) == 2 and "Traceback" not in lines[1]
    assert lines[1].startswith("bayestribo acquire: storage error:") and "--recover" in lines[1]


def test_a_failed_sync_of_the_raw_log_stops_the_run_with_the_packages_error(tmp_path, monkeypatch):
    # fsync fails (EIO) in the background thread: the failure reaches the reading loop
    # as a StorageError, never as a traceback printed by the thread.
    import errno
    import threading

    from bayestribo.acquisition import logger as logger_module
    from bayestribo.acquisition.faults import StorageError

    real_fsync, real_init = os.fsync, logger_module.RawLog.__init__
    raw_fds: set[int] = set()
    hooked: list[object] = []

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        raw_fds.add(self._fd)

    def fsync(fd):
        # the first sync of a raw log holding bytes fails, whenever a loaded machine
        # lets it come: the bytes received before it must stay in the log
        if fd in raw_fds and os.fstat(fd).st_size > 0:
            raise OSError(errno.EIO, "Input/output error")
        return real_fsync(fd)

    monkeypatch.setattr(logger_module.RawLog, "__init__", init)
    monkeypatch.setattr(logger_module.os, "fsync", fsync)
    monkeypatch.setattr(threading, "excepthook", hooked.append)
    # In real time, so that the failing sync falls in the middle of the run.
    with simulated(realtime=True, config=dataclasses.replace(SMALL, duration_s=2.0)) as (
        sim,
        path,
    ):
        with pytest.raises(StorageError, match=r"cannot sync the raw log.*--recover .*\.raw"):
            acquire_run(path, tmp_path, INPUTS, catalog=None)
        assert sim.received("STOP")
    assert hooked == []
    [raw] = list(tmp_path.glob("*.raw"))
    assert bytes(sim.sent).startswith(raw.read_bytes()) and raw.stat().st_size > 0
    assert not list(tmp_path.glob("*.csv"))


def test_a_session_file_that_cannot_be_written_is_a_storage_error(tmp_path, monkeypatch):
    import errno

    from bayestribo.acquisition import session as session_module
    from bayestribo.acquisition.faults import StorageError

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(session_module, "write_json_atomic", full)
    with simulated() as (sim, path):
        with pytest.raises(StorageError, match=r"cannot write the session file.*No space left"):
            acquire_run(path, tmp_path, INPUTS, catalog=None, run_id="r1")
    assert sim.commands == []  # nothing asked of the device, nothing received
    assert list(tmp_path.iterdir()) == []


def test_a_catalog_on_a_full_disk_is_a_storage_error_naming_the_recovery(tmp_path, monkeypatch):
    import sqlite3

    from bayestribo.acquisition.faults import StorageError
    from bayestribo.campaign import catalog as catalog_module

    def full(*args, **kwargs):
        raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(catalog_module, "register_run", full)
    with simulated() as (_, path):
        with pytest.raises(StorageError, match=r"disk is full.*--recover .*\.raw --overwrite"):
            acquire_run(path, tmp_path, INPUTS, catalog=tmp_path / "c.sqlite", run_id="r1")
    assert (tmp_path / "r1.csv").exists() and (tmp_path / "r1.raw").stat().st_size > 0


@pytest.fixture
def tiny_tmpfs(tmp_path):
    """A 64 KiB tmpfs, where root may mount one; skipped otherwise."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    mountpoint = tmp_path / "tiny"
    mountpoint.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mountpoint)],
        capture_output=True,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.decode().strip()}")
    try:
        yield mountpoint
    finally:
        if subprocess.run(["umount", str(mountpoint)], capture_output=True).returncode:
            subprocess.run(["umount", "-l", str(mountpoint)], capture_output=True)


def test_a_real_full_disk_keeps_the_raw_log_and_recover_rebuilds_it(tmp_path, tiny_tmpfs):
    from bayestribo.acquisition.faults import StorageError
    from bayestribo.acquisition.recover import recover_run

    big = dataclasses.replace(SMALL, sample_rate_Hz=20_000.0, duration_s=1.0, samples_per_frame=128)
    with simulated(config=big) as (sim, path):
        with pytest.raises(StorageError, match=r"No space left.*--recover"):
            acquire_run(path, tiny_tmpfs, INPUTS, catalog=None, run_id="full")
        assert sim.received("STOP")
        sent = bytes(sim.sent)
    kept = (tiny_tmpfs / "full.raw").read_bytes()
    assert 0 < len(kept) < len(sent) and sent.startswith(kept)
    assert not list(tiny_tmpfs.glob("*.csv"))
    result = recover_run(tiny_tmpfs / "full.raw", out_dir=tmp_path / "out")
    assert not result.complete  # what the disk held, with the rest listed as missing
    assert result.run.report["samples_received"] > 0


def test_the_same_run_recorded_twice_is_refused_before_any_run_file(tmp_path, capsys):
    # The simulated rig gives the very same samples twice: the second run is refused
    # with one line before its run files are written, not written and then left out.
    from bayestribo.cli import main

    argv = ["acquire", "--simulate", "--load", "0.31", "--lubricant", "glycerol", "--quiet"]
    assert main([*argv, "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "Traceback" not in lines[1]
    assert "are exactly those of run" in lines[1] and "run files not written" in lines[1]
    assert len(list(tmp_path.glob("*.csv"))) == 1 and len(list(tmp_path.glob("*.raw"))) == 2
    assert len(list_runs(tmp_path / "catalog.sqlite")) == 1


def test_a_board_that_sends_only_garbage_times_out_from_its_last_valid_frame(tmp_path):
    """Bytes keep arriving but none is a frame: the run stops after the silence timeout
    counted from the last valid frame (not from the last byte), keeping what came."""
    with simulated(FaultPlan(babble_after=5, garbage_bytes=40)) as (sim, path):
        result = acquire_run(path, tmp_path, INPUTS, timeout_s=0.3)
        sim.stop()
        # every byte received is in the raw log (the board babbles on after the host
        # stopped reading: those bytes were never received)
        raw = result.files.raw.read_bytes()
        assert len(raw) > sum(f.size for f in sim.frames) and bytes(sim.sent).startswith(raw)
        index, counts = sim.intact_samples()
        assert np.array_equal(result.run.sample_index, index)
        assert np.array_equal(result.run.counts, counts)
    assert "no valid frame for 0.3 s" in result.fault
    assert not result.complete
    assert result.run.report["samples_received"] == 5 * 32


def test_the_simulated_magnet_makes_the_recording_independent_of_the_hosts_timing(tmp_path):
    """With a hold time the simulated rig releases at the same sample whenever FIRE
    comes before it (here after 0.01 s and after 0.2 s): the same recording, so a test
    of duplicate runs does not depend on the machine's load."""
    held = dataclasses.replace(SMALL, hold_s=0.3)
    samples = []
    for k, pretrigger in enumerate((0.01, 0.2)):
        with simulated(config=held) as (sim, path):
            result = acquire_run(path, tmp_path / f"r{k}", INPUTS, pretrigger_s=pretrigger)
        assert result.complete
        samples.append((result.run.sample_index, result.run.counts, sim.release_index))
    assert samples[0][2] == samples[1][2] == 608  # 0.3 s at 2 kHz, at a frame of 32
    assert np.array_equal(samples[0][0], samples[1][0])
    assert np.array_equal(samples[0][1], samples[1][1])


def test_a_failed_sync_seen_by_the_reading_loop_loses_no_chunk(tmp_path, monkeypatch):
    # The sync thread never gets to run (a loaded machine): the reading loop's own
    # periodic sync meets the failure while a chunk just read waits to be logged. That
    # chunk is logged first, so the raw log stays a prefix of the bytes sent.
    import errno

    from bayestribo.acquisition import logger as logger_module
    from bayestribo.acquisition.faults import StorageError

    real_fsync, real_init = os.fsync, logger_module.RawLog.__init__
    raw_fds: set[int] = set()

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        self.sync_interval_s = 0.0  # every pump syncs
        raw_fds.add(self._fd)

    def fsync(fd):
        # fails once the run streams (the header and a few frames are in the log)
        if fd in raw_fds and os.fstat(fd).st_size > 1024:
            raise OSError(errno.EIO, "Input/output error")
        return real_fsync(fd)

    monkeypatch.setattr(logger_module.RawLog, "__init__", init)
    monkeypatch.setattr(logger_module.RawLog, "_sync_loop", lambda self: None)
    monkeypatch.setattr(logger_module.os, "fsync", fsync)
    with simulated() as (sim, path):
        with pytest.raises(StorageError, match=r"cannot sync the raw log"):
            acquire_run(path, tmp_path, INPUTS, catalog=None)
    [raw] = list(tmp_path.glob("*.raw"))
    kept = raw.read_bytes()
    assert len(kept) > 1024 and bytes(sim.sent).startswith(kept)
