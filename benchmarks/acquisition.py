"""Acquisition benchmark: sustained samples per second through a pseudo-terminal without
loss, and the CPU the logger uses at 20 kS/s of two channels.

The simulated instrument runs in a child process (so its work does not share the
logger's interpreter lock) on a POSIX pseudo-terminal; the logger is
:func:`bayestribo.acquisition.acquire_run` in this process, reading through pyserial.
Every run is checked sample by sample against the decay the instrument streams: a
figure is reported only for a run without loss.

Run: ``python benchmarks/acquisition.py [--quick]``. Prints a table and writes
``benchmarks/results/acquisition.json``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import serial

from bayestribo import __version__
from bayestribo.acquisition import OperatorInputs, acquire_run
from bayestribo.acquisition.instrument import SimulatedInstrument, SimulationConfig

RESULTS = Path(__file__).resolve().parent / "results" / "acquisition.json"
INPUTS = OperatorInputs(
    load_N=0.31, lubricant="benchmark", repeat=1, mass_kg=0.035, natural_frequency_Hz=32.6
)


def _serve(config: SimulationConfig, realtime: bool, conn: mp.connection.Connection) -> None:
    sim = SimulatedInstrument(config, realtime=realtime)
    conn.send(sim.start_pty())
    conn.recv()  # parent says stop
    sim.stop()


def _expected(config: SimulationConfig, release: int, n: int) -> np.ndarray:
    expected = np.empty((n, 2), dtype=np.int16)
    expected[:release] = config.rest_counts()
    expected[release:] = config.decay_counts()[: n - release]
    return expected


def one_run(config: SimulationConfig, realtime: bool, out: Path) -> dict[str, float]:
    """Acquire one run from an instrument in a child process; check it; time it."""
    parent, child = mp.Pipe()
    proc = mp.get_context("fork").Process(target=_serve, args=(config, realtime, child))
    proc.start()
    try:
        path = parent.recv()
        marks: list[tuple[float, float, int]] = []

        def progress(p) -> None:
            marks.append((time.perf_counter(), time.thread_time(), p.samples))

        wall0, cpu0 = time.perf_counter(), time.thread_time()
        result = acquire_run(
            path, out, INPUTS, progress=progress, progress_interval_s=0.01, timeout_s=5.0
        )
        wall1, cpu1 = time.perf_counter(), time.thread_time()
    finally:
        parent.send("stop")
        proc.join(5)
    run = result.run
    release = run.report["release_sample_index"]
    n = len(run.sample_index)
    lossless = bool(
        result.complete
        and np.array_equal(run.sample_index, np.arange(n))
        and np.array_equal(run.counts, _expected(config, release, n))
    )
    # Streaming only: from the first progress report with samples to the last one.
    streaming = [m for m in marks if m[2] > 0]
    if len(streaming) < 3:
        raise RuntimeError(f"run too short to time: {len(streaming)} progress reports")
    (t0, c0, s0), (t1, c1, s1) = streaming[0], streaming[-1]
    return {
        "samples": n,
        "lossless": lossless,
        "stream_samples_per_s": (s1 - s0) / (t1 - t0),
        "stream_cpu_fraction": (c1 - c0) / (t1 - t0),
        "total_wall_s": wall1 - wall0,
        "total_cpu_s": cpu1 - cpu0,
        "raw_log_bytes": result.metadata["acquisition"]["raw_log_bytes"],
    }


def machine() -> dict[str, object]:
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor(),
        "cpu_count": os.cpu_count(),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "pyserial": serial.__version__,
        "bayestribo": __version__,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs")
    args = parser.parse_args()
    scale = 0.25 if args.quick else 1.0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        # 1. Throughput: the instrument sends as fast as the pseudo-terminal takes it.
        for spf in (32, 128, 512, 1024):
            config = SimulationConfig(
                sample_rate_Hz=20_000.0, duration_s=60.0 * scale, samples_per_frame=spf
            )
            r = one_run(config, realtime=False, out=Path(tmp) / f"max{spf}")
            rows.append({"test": "max throughput", "samples_per_frame": spf, **r})
        # 2. CPU of the logger at the target rate: 20 kS/s of two channels, paced.
        for spf in (128, 512):
            config = SimulationConfig(
                sample_rate_Hz=20_000.0, duration_s=10.0 * scale, samples_per_frame=spf
            )
            r = one_run(config, realtime=True, out=Path(tmp) / f"paced{spf}")
            rows.append({"test": "paced 20 kS/s", "samples_per_frame": spf, **r})
    print(
        f"{'test':<16}{'spf':>6}{'samples':>10}{'lossless':>10}{'kS/s':>10}"
        f"{'logger CPU':>12}{'total s':>9}"
    )
    for r in rows:
        print(
            f"{r['test']:<16}{r['samples_per_frame']:>6}{r['samples']:>10}"
            f"{r['lossless']!s:>10}{r['stream_samples_per_s'] / 1e3:>10.1f}"
            f"{r['stream_cpu_fraction']:>11.1%}{r['total_wall_s']:>9.2f}"
        )
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(
        json.dumps(
            {
                "benchmark": "acquisition",
                "description": __doc__.split("\n\n")[0],
                "quick": args.quick,
                "when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                "machine": machine(),
                "notes": (
                    "stream_samples_per_s: sample pairs (two channels) per second between the "
                    "first and last progress report; stream_cpu_fraction: CPU time of the "
                    "logger thread over wall time while streaming; total includes "
                    "identification, arming and writing the run files."
                ),
                "rows": rows,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"written {RESULTS}")


if __name__ == "__main__":
    main()
