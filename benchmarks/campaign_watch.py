"""Latency of ``bayestribo campaign DIR --watch``: from a run file closing to its answer.

One watch runs (a subprocess, the command's default fit settings, one warm worker) on
an empty folder. Once it says it is warm, runs of the bundled campaign are delivered
into the folder one at a time, each when the previous one is answered and on the page:

* ``atomic``: as ``bayestribo acquire`` writes a run: the CSV, its sidecar and a
  ``.sha256`` manifest written in a hidden staging folder in the watched folder, then
  renamed into place (the manifest last). The file is closed (complete) at the last
  rename;
* ``settled``: the CSV written in place in one go (opened, written, closed) after its
  sidecar, no manifest: the watch waits for the settle interval (``--settle``) before it
  counts the file complete, so its latency is at least that interval.

For each run the benchmark times, from the file's close (the rename, or the close of the
written file) on its monotonic clock,

* ``printed``: its answer line read on the watch's standard output;
* ``page``: the live page (``watch.html``) showing its row (the page read every 10 ms);

and takes the warm fit's wall time measured side by side by the watch's own worker in
the same run (``fit_s`` of ``watch.json``). Reported: each run's figures, their medians,
and the medians of the ratios latency / warm fit. The machine is shared with other
users: medians, and the load averages at the start and the end.

Run: ``python benchmarks/campaign_watch.py``; writes
``benchmarks/results/campaign_watch.json`` (``--output NAME``: ``NAME.json``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, provenance, write_results

RUNS = ROOT / "data" / "runs"
ATOMIC = [f"glycerol-N{load}-r{r}" for load in ("0.12", "0.31", "0.46") for r in (1, 2, 3)]
SETTLED = ["glycerol-N0.59-r1", "glycerol-N0.59-r2", "glycerol-N0.59-r3"]
#: Longest wait for any one thing before the benchmark gives up [s].
DEADLINE = 600.0


class Watch:
    """The watch subprocess, its output lines timestamped on arrival."""

    def __init__(self, folder: Path, out: Path, settle: float) -> None:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        argv = [sys.executable, "-m", "bayestribo", "campaign", str(folder), "--out", str(out)]
        argv += ["--watch", "--settle", str(settle)]
        self.proc = subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
        self.out: list[tuple[float, str]] = []
        self.err: list[tuple[float, str]] = []
        self._lock = threading.Condition()
        for stream, keep in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._read, args=(stream, keep), daemon=True).start()

    def _read(self, stream: Any, keep: list[tuple[float, str]]) -> None:
        for line in stream:
            with self._lock:
                keep.append((time.monotonic(), line.rstrip("\n")))
                self._lock.notify_all()

    def wait_line(self, lines: list[tuple[float, str]], start: str) -> float:
        """When the first line starting with ``start`` arrived."""
        end = time.monotonic() + DEADLINE
        with self._lock:
            while True:
                for when, line in lines:
                    if line.startswith(start):
                        return when
                if not self._lock.wait(timeout=max(0.0, end - time.monotonic())):
                    raise TimeoutError(f"no line {start!r}; stderr: {self.err[-5:]}")


def _wait_page(page: Path, run: str) -> float:
    """When the page first showed the run's row (read every 10 ms)."""
    mark = f'data-run="{run}"'
    end = time.monotonic() + DEADLINE
    while time.monotonic() < end:
        try:
            if mark in page.read_text(encoding="utf-8"):
                return time.monotonic()
        except OSError:
            pass
        time.sleep(0.01)
    raise TimeoutError(f"{page} never showed {run}")


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def deliver_atomic(folder: Path, run: str) -> float:
    """The run written as ``bayestribo acquire`` writes one; the time of the last rename."""
    staging = Path(tempfile.mkdtemp(prefix=f".{run}.staging-", dir=folder))
    files = []
    for suffix in (".csv", ".json"):
        shutil.copyfile(RUNS / f"{run}{suffix}", staging / f"{run}{suffix}")
        files.append(staging / f"{run}{suffix}")
    manifest = staging / f"{run}.sha256"
    manifest.write_text("".join(f"{_sha(p)}  {p.name}\n" for p in files), encoding="utf-8")
    for path in [*files, manifest]:
        os.replace(path, folder / path.name)
    closed = time.monotonic()
    staging.rmdir()
    return closed


def deliver_settled(folder: Path, run: str) -> float:
    """The sidecar, then the CSV written in place in one go; the time of its close."""
    shutil.copyfile(RUNS / f"{run}.json", folder / f"{run}.json")
    data = (RUNS / f"{run}.csv").read_bytes()
    with open(folder / f"{run}.csv", "wb") as fh:
        fh.write(data)
    return time.monotonic()


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settle", type=float, default=1.0, help="--settle of the watch [s]")
    parser.add_argument("--no-write", action="store_true", help="print, do not write results")
    parser.add_argument("--output", default="campaign_watch", help="results/<OUTPUT>.json")
    args = parser.parse_args(argv)
    load_start = os.getloadavg()
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="bayestribo-watch-bench-") as tmp:
        folder, out = Path(tmp) / "runs", Path(tmp) / "out"
        folder.mkdir()
        started = time.monotonic()
        watch = Watch(folder, out, args.settle)
        try:
            warm = watch.wait_line(watch.err, "bayestribo campaign --watch: warm after")
            page = out / "watch.html"
            plan = [("atomic", r) for r in ATOMIC] + [("settled", r) for r in SETTLED]
            for how, run in plan:
                deliver = deliver_atomic if how == "atomic" else deliver_settled
                closed = deliver(folder, run)
                printed = watch.wait_line(watch.out, f"{run}  ")
                shown = _wait_page(page, run)
                line = next(text for when, text in watch.out if text.startswith(f"{run}  "))
                rows.append(
                    {
                        "run": run,
                        "delivery": how,
                        "printed_s": printed - closed,
                        "page_s": shown - closed,
                        "line": line,
                    }
                )
                print(
                    f"{how:8s} {run}: printed {printed - closed:.3f} s, page {shown - closed:.3f} s"
                )
                time.sleep(0.5)  # the page's own refresh settles; not timed
        finally:
            watch.proc.terminate()  # SIGTERM: the same clean stop as Ctrl-C
            status = watch.proc.wait(timeout=DEADLINE)
        answers = {a["run"]: a for a in json.loads((out / "watch.json").read_text())["answers"]}
    for row in rows:
        fit_s = answers[row["run"]]["fit_s"]
        row["fit_s"] = fit_s
        row["printed_over_fit"] = row["printed_s"] / fit_s
        row["page_over_fit"] = row["page_s"] / fit_s
    summary: dict[str, Any] = {}
    for how in ("atomic", "settled"):
        mine = [r for r in rows if r["delivery"] == how]
        summary[how] = {
            key: _median([r[key] for r in mine])
            for key in ("fit_s", "printed_s", "page_s", "printed_over_fit", "page_over_fit")
        }
        summary[how]["n_runs"] = len(mine)
    settle = args.settle
    summary["settled"]["printed_minus_settle_over_fit"] = _median(
        [(r["printed_s"] - settle) / r["fit_s"] for r in rows if r["delivery"] == "settled"]
    )
    result = {
        **provenance("bayestribo.campaign.watch", {"settle_s": settle}, load_start),
        "warm_up_s": warm - started,
        "exit_status_on_sigterm": status,
        "goal": "file closed -> answer printed and on the page <= 2x the warm fit (atomic)",
        "summary": summary,
        "runs": rows,
    }
    print(json.dumps(summary, indent=2))
    if not args.no_write:
        print(f"written to {write_results(args.output, result)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
