"""Acquisition benchmark: memory, time to finish after END, and CPU of the logger.

A simulated board (:class:`bayestribo.acquisition.instrument.SimulatedInstrument`) runs
in one process on a POSIX pseudo-terminal; the logger, :func:`bayestribo.acquisition.
acquire_run` exactly as ``bayestribo acquire`` calls it (raw log, CSV written while
streaming, sidecar, manifest, catalog), runs in a fresh Python process of its own, so
its peak resident memory (``ru_maxrss``) is the logger's alone. Every run is then
checked sample for sample against what the board sent; a figure is reported only for
a run without loss.

Runs (20 kS/s of two channels, 128 sample pairs a frame unless said otherwise):

* **paced 10 min**: the board streams at the sample rate for 10 minutes, as a real
  one does. Gives the CPU share of the logger while streaming (process CPU time over
  wall time, the raw-log sync thread included), the resident memory over time and the
  seconds from the END frame leaving the board to the run files being on disk (the
  call returned: files renamed into place, folder synced, run catalogued).
* **unpaced 1 h**: one hour of samples (72 million pairs, 4 GB of CSV) sent as fast as
  the pseudo-terminal takes them: the hour-long run measured directly, not only
  extrapolated.
* **throughput** (60 s of samples, unpaced) for 32, 128 and 1024 pairs a frame.

Extrapolation to one hour from the paced run: memory as the peak plus the growth of
the resident set over the second half of the stream (least-squares slope) times the
50 minutes more; time after END as measured, since the work left at END does not grow
with the run (the CSV and both digests are written while streaming; at END remain the
last megabyte of rows, the sidecar, the manifest and a sync of what the kernel has not
yet written back).

The board sends a 60-s damped oscillation of the exact model (with 2 counts of noise,
so the CSV text varies like a real one's) repeated for as long as the run lasts; each
pair is ``count × scale`` as the header says.

Run: ``python benchmarks/acquisition.py [--quick]`` (``--quick``: 1 min paced, 10 min
unpaced). Prints a table and writes ``benchmarks/results/acquisition.json``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import resource
import subprocess
import sys
import tempfile
import time
from multiprocessing.connection import Connection
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine, write_results

HERE = Path(__file__).resolve()
TABLE_S = 60.0  # length of the decay the board repeats [s]


def _config(duration_s: float, spf: int = 128):
    from bayestribo.acquisition.instrument import SimulationConfig

    return SimulationConfig(
        sample_rate_Hz=20_000.0, duration_s=duration_s, samples_per_frame=spf, noise_counts=2.0
    )


class _Repeated:
    """A decay of ``TABLE_S`` seconds repeated to ``n`` samples (indexable like an array)."""

    def __init__(self, table: np.ndarray, n: int) -> None:
        self.table = table
        self.n = n

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, index: np.ndarray) -> np.ndarray:
        return self.table[np.asarray(index) % len(self.table)]


def _serve(duration_s: float, spf: int, realtime: bool, conn: Connection) -> None:
    """The board: a simulated instrument that reports when its END frame left."""
    from dataclasses import replace

    from bayestribo.acquisition.instrument import SimulatedInstrument
    from bayestribo.acquisition.protocol import SYNC, FrameType

    config = _config(duration_s, spf)
    table = replace(config, duration_s=TABLE_S).decay_counts()

    class Board(SimulatedInstrument):
        end_sent: float | None = None

        def _send(self, data: bytes) -> None:
            super()._send(data)
            if data[:2] == SYNC and data[2] == FrameType.END and self.end_sent is None:
                self.end_sent = time.monotonic()

    board = Board(replace(config, duration_s=1.0), realtime=realtime)
    board._decay = _Repeated(table, round(duration_s * config.sample_rate_Hz))
    board.sent = _Counter()  # do not keep an hour of bytes in memory
    conn.send(board.start_pty())
    conn.recv()  # the logger is done
    conn.send(board.end_sent)
    board.stop()


class _Counter:
    """Stands in for the instrument's record of the bytes it sent: counts them only."""

    def __init__(self) -> None:
        self.n = 0

    def __iadd__(self, data: memoryview) -> _Counter:
        self.n += len(data)
        return self

    def __len__(self) -> int:
        return self.n


def _rss_bytes() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def logger_worker(port: str, out: str, duration_s: float, spf: int) -> dict[str, object]:
    """Run in a fresh process: acquire, measure, then check the run against the board."""
    from bayestribo.acquisition import OperatorInputs, acquire_run

    inputs = OperatorInputs(
        load_N=0.31, lubricant="benchmark", repeat=1, mass_kg=0.035, natural_frequency_Hz=32.6
    )
    # Kept small, so that the benchmark's own records do not show as the logger's
    # memory: the first and the latest progress report while streaming, and the
    # resident set once a second (10 kB for a 10-minute run).
    first: list[tuple[float, float, int]] = []
    last: list[tuple[float, float, int]] = []
    rss: list[tuple[float, int]] = []
    next_rss = [0.0]

    def progress(p) -> None:
        now = time.monotonic()
        if p.samples == 0:
            return
        mark = (now, time.process_time(), p.samples)
        if not first:
            first.append(mark)
        last[:] = [mark]
        if now >= next_rss[0]:
            next_rss[0] = now + 1.0
            rss.append((now, _rss_bytes()))

    rss_start = _rss_bytes()
    wall0 = time.monotonic()
    result = acquire_run(
        port,
        out,
        inputs,
        progress=progress,
        progress_interval_s=0.05,
        timeout_s=10.0,
        catalog=Path(out) / "catalog.sqlite",
    )
    done = time.monotonic()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # kB on Linux
    (t0, c0, s0), (t1, c1, s1) = first[0], last[0]
    over_time = [(t - t0, r) for t, r in rss]
    half = [(t, r) for t, r in over_time if t >= (t1 - t0) / 2]
    slope = float(np.polyfit(*zip(*half, strict=True), 1)[0]) if len(half) >= 3 else 0.0
    # The check, after the measurement: every sample against what the board sent.
    from dataclasses import replace

    config = _config(duration_s, spf)
    table = replace(config, duration_s=TABLE_S).decay_counts()
    run = result.run
    release = run.report["release_sample_index"]
    rest = config.rest_counts()
    expected_next = 0
    lossless = result.complete
    for first, counts in run.chunks():
        i = np.arange(first, first + len(counts))
        expected = np.where((i < release)[:, None], rest, table[(i - release) % len(table)])
        lossless = lossless and first == expected_next and np.array_equal(counts, expected)
        expected_next = first + len(counts)
    return {
        "samples": run.n_samples,
        "lossless": bool(lossless and expected_next == run.report["samples_reported_by_device"]),
        "stream_samples_per_s": (s1 - s0) / (t1 - t0),
        "stream_cpu_fraction": (c1 - c0) / (t1 - t0),
        "peak_rss_MB": peak / 1e6,
        "rss_at_start_MB": rss_start / 1e6,
        "rss_growth_MB_per_min": slope * 60 / 1e6,
        "rss_over_time_s_MB": [
            (round(t, 1), round(r / 1e6, 2)) for t, r in over_time[:: max(1, len(over_time) // 40)]
        ],
        "total_wall_s": done - wall0,
        "done_monotonic": done,
        "raw_log_bytes": result.metadata["acquisition"]["raw_log_bytes"],
        "csv_bytes": result.files.csv.stat().st_size,
    }


def one_run(duration_s: float, spf: int, realtime: bool, out: Path) -> dict[str, object]:
    """Board in a child process, logger in a fresh interpreter; the seconds after END."""
    parent, child = mp.Pipe()
    board = mp.get_context("fork").Process(target=_serve, args=(duration_s, spf, realtime, child))
    board.start()
    try:
        port = parent.recv()
        worker = subprocess.run(
            [sys.executable, str(HERE), "--logger", port, str(out), str(duration_s), str(spf)],
            capture_output=True,
            text=True,
            check=False,
        )
        parent.send("done")
        end_sent = parent.recv()
    finally:
        board.join(10)
        if board.is_alive():
            board.terminate()
    if worker.returncode != 0:
        raise RuntimeError(f"logger failed: {worker.stderr.strip()[-2000:]}")
    row = json.loads(worker.stdout.strip().splitlines()[-1])
    row["seconds_after_END"] = row.pop("done_monotonic") - end_sent
    row.update(duration_s=duration_s, samples_per_frame=spf, paced=realtime)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 min paced, 10 min unpaced")
    parser.add_argument("--logger", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.logger:
        port, out, duration, spf = args.logger
        print(json.dumps(logger_worker(port, out, float(duration), int(spf))))
        return
    paced_s = 60.0 if args.quick else 600.0
    unpaced_s = 600.0 if args.quick else 3600.0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        plan = [("paced", paced_s, 128, True), ("unpaced", unpaced_s, 128, False)]
        plan += [("throughput", 60.0, spf, False) for spf in (32, 128, 1024)]
        for k, (test, duration, spf, paced) in enumerate(plan):
            row = one_run(duration, spf, paced, Path(tmp) / f"run{k}")
            rows.append({"test": test, **row})
            print(f"done: {test} {duration:g} s spf {spf}", file=sys.stderr)
    paced = rows[0]
    hour = {
        "peak_rss_MB": paced["peak_rss_MB"]
        + max(paced["rss_growth_MB_per_min"], 0.0) * (3600 - paced_s) / 60,
        "seconds_after_END": paced["seconds_after_END"],
        "method": (
            "peak RSS of the paced run plus its RSS growth over the second half of the "
            "stream (least-squares slope, clipped at 0) times the remaining minutes; "
            "seconds after END as measured (the work left at END does not grow with the "
            "run); the unpaced 1-h row measures an hour of samples directly"
        ),
    }
    header = (
        f"{'test':<11}{'length':>8}{'spf':>6}{'samples':>11}{'lossless':>9}{'kS/s':>8}"
        f"{'CPU':>7}{'peak RSS':>10}{'RSS/min':>9}{'s after END':>12}"
    )
    print(header)
    for r in rows:
        print(
            f"{r['test']:<11}{r['duration_s'] / 60:>6.0f}mn{r['samples_per_frame']:>6}"
            f"{r['samples']:>11}{r['lossless']!s:>9}{r['stream_samples_per_s'] / 1e3:>8.1f}"
            f"{r['stream_cpu_fraction']:>7.1%}{r['peak_rss_MB']:>8.0f}MB"
            f"{r['rss_growth_MB_per_min']:>7.2f}MB{r['seconds_after_END']:>12.2f}"
        )
    print(
        f"1 h extrapolated from the paced run: peak RSS {hour['peak_rss_MB']:.0f} MB, "
        f"{hour['seconds_after_END']:.2f} s after END"
    )
    import serial

    path = write_results(
        "acquisition",
        {
            "benchmark": "acquisition",
            "description": __doc__.split("\n\n")[0],
            "quick": args.quick,
            "machine_extra": {**machine(), "pyserial": serial.__version__},
            "goal": "a 1-hour run at 20 kS/s x 2 finishes under 300 MB and under 10 s after END",
            "notes": (
                "stream_samples_per_s: sample pairs per second between the first and last "
                "progress report; stream_cpu_fraction: logger process CPU time over wall "
                "time while streaming (one core = 100 %); peak_rss_MB: ru_maxrss of the "
                "logger process (a fresh interpreter with bayestribo imported, ~"
                f"{rows[0]['rss_at_start_MB']:.0f} MB before the run); seconds_after_END: "
                "from the board writing END to acquire_run returning with the files on disk "
                "and catalogued (CLOCK_MONOTONIC in both processes)"
            ),
            "one_hour_extrapolated": hour,
            "rows": rows,
        },
    )
    print(f"written {path}")


if __name__ == "__main__":
    main()
