"""Recovery: kill the logging process mid-run (SIGKILL) and rebuild the run from its raw log."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from bayestribo.acquisition import OperatorInputs, acquire_run, recover_run
from bayestribo.acquisition.instrument import SimulatedInstrument, SimulationConfig
from bayestribo.errors import AcquisitionError, BayestriboError
from bayestribo.io import read_run

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals and SIGKILL")

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
    """The ``bayestribo`` command (only ``acquire`` if other sub-commands are missing)."""
    try:
        from bayestribo.cli import build_parser

        build_parser()
    except ImportError:
        return [sys.executable, "-c", ACQUIRE_ONLY_CLI]
    return [sys.executable, "-m", "bayestribo.cli"]


def cli_main(argv: list[str]) -> int:
    """In-process ``bayestribo`` (only ``acquire`` if other sub-commands are missing)."""
    try:
        from bayestribo.cli import build_parser, main

        build_parser()
    except ImportError:
        from bayestribo.cli import acquire

        parser = argparse.ArgumentParser(prog="bayestribo")
        acquire.register(parser.add_subparsers(dest="command"))
        args = parser.parse_args(argv)
        try:
            return args.handler(args)
        except BayestriboError:
            return 2
    return main(argv)


def test_sigkill_mid_run_then_recover_gives_what_was_received(tmp_path):
    config = SimulationConfig(sample_rate_Hz=2000.0, duration_s=10.0, samples_per_frame=20)
    sim = SimulatedInstrument(config, realtime=True)
    path = sim.start_pty()
    try:
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
                "--repeat",
                "4",
                "--temperature",
                "23",
                "--out",
                str(tmp_path),
                "--quiet",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        try:
            deadline = time.monotonic() + 15
            raw: Path | None = None
            while time.monotonic() < deadline:
                logs = list(tmp_path.glob("*.raw"))
                if logs and logs[0].stat().st_size > 4000:  # well into the decay
                    raw = logs[0]
                    break
                time.sleep(0.02)
            assert raw is not None, "the logger did not start streaming"
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=10)
        finally:
            proc.kill()
        assert proc.returncode == -signal.SIGKILL
        time.sleep(0.1)
    finally:
        sim.stop()
    assert not list(tmp_path.glob("*.csv")), "the killed logger cannot have written a run"
    # The CSV it was writing while streaming is in its staging directory, never in place.
    [staging] = [p for p in tmp_path.iterdir() if p.name.startswith(f".{raw.stem}.staging-")]
    assert [p.name for p in staging.iterdir()] == [f"{raw.stem}.csv"]
    received = raw.read_bytes()
    # Every byte the logger received is in its raw log, byte for byte and in order.
    assert len(received) > 4000
    assert received == bytes(sim.sent[: len(received)])
    # Expected run, computed independently: the frames wholly inside those bytes.
    kept = [f for f in sim.frames if f.offset is not None and f.offset + f.size <= len(received)]
    index = np.concatenate([np.arange(f.first_index, f.first_index + len(f.counts)) for f in kept])
    counts = np.concatenate([f.counts for f in kept])

    status = cli_main(["acquire", "--recover", str(raw), "--out", str(tmp_path)])
    assert status == 1  # incomplete: no END frame

    assert not staging.exists()  # the recovery removed it
    csv = raw.with_suffix(".csv")
    run = read_run(csv)  # nothing missing before the kill: a regular run
    header = config.header
    assert np.array_equal(run.time, index / header.sample_rate_Hz)
    assert np.array_equal(run.displacement, counts[:, 0] * header.displacement_scale_m)
    assert np.array_equal(run.velocity, counts[:, 1] * header.velocity_scale_m_per_s)
    meta = json.loads(raw.with_suffix(".json").read_text())
    assert meta["complete"] is False
    assert meta["acquisition"]["recovered_from_raw_log"] is True
    assert meta["acquisition"]["release_sample_index"] == sim.release_index
    # The operator's inputs come back from the session file written before the run.
    assert (meta["load_N"], meta["repeat"], meta["temperature_C"]) == (0.31, 4, 23.0)
    assert meta["lubricant"] == "glycerol"


def test_recover_of_a_complete_run_equals_the_live_run(tmp_path):
    config = SimulationConfig(sample_rate_Hz=2000.0, duration_s=0.3, samples_per_frame=32)
    inputs = OperatorInputs(load_N=0.31, lubricant="water", repeat=1, notes="n")
    sim = SimulatedInstrument(config, realtime=False)
    try:
        live = acquire_run(sim.start_pty(), tmp_path / "live", inputs)
    finally:
        sim.stop()
    again = recover_run(live.files.raw, out_dir=tmp_path / "again")
    assert live.complete and again.complete
    assert again.files.csv.read_bytes() == live.files.csv.read_bytes()
    # The sidecars agree but for when they were written and the recovery flag.
    differ = {"host_time_end_utc", "host_time_written_utc", "recovered_from_raw_log"}
    a, b = dict(live.metadata), dict(again.metadata)
    acq_a, acq_b = a.pop("acquisition"), b.pop("acquisition")
    assert a == b
    assert {k: v for k, v in acq_a.items() if k not in differ} == {
        k: v for k, v in acq_b.items() if k not in differ
    }
    assert (acq_a["recovered_from_raw_log"], acq_b["recovered_from_raw_log"]) == (False, True)


def test_recover_refuses_to_overwrite_and_needs_operator_inputs(tmp_path):
    config = SimulationConfig(sample_rate_Hz=2000.0, duration_s=0.2, samples_per_frame=32)
    sim = SimulatedInstrument(config, realtime=False)
    try:
        live = acquire_run(
            sim.start_pty(), tmp_path, OperatorInputs(load_N=0.2, lubricant="dry", repeat=1)
        )
    finally:
        sim.stop()
    with pytest.raises(AcquisitionError, match="run files exist already"):
        recover_run(live.files.raw)
    orphan = tmp_path / "orphan" / "x.raw"
    orphan.parent.mkdir()
    orphan.write_bytes(live.files.raw.read_bytes())
    with pytest.raises(AcquisitionError, match="give load, lubricant and repeat"):
        recover_run(orphan)
    result = recover_run(orphan, inputs={"load_N": 0.2, "lubricant": "dry", "repeat": 1})
    assert result.complete and result.run_id == "x"
    with pytest.raises(AcquisitionError, match="raw log not found"):
        recover_run(tmp_path / "missing.raw")
