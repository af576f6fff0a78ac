"""``bayestribo campaign DIR --watch`` end to end, in a subprocess, as runs land.

One watch (module fixture) finds a malformed run file in its folder and, while it warms
up, two runs of ``bayestribo acquire`` against the simulated instrument land beside it
while a third run file is written slowly, in chunks. It stops by itself after
``--max-runs 4``. Another watch is stopped with SIGINT (Ctrl-C) while its first fit
runs. Short fits
(``--max-steps 400``): the tests check what is answered, recorded and shown, not the
posteriors. Every wait has a deadline far beyond its need and fails the test when
reached; nothing is asserted about time.
"""

from __future__ import annotations

import hashlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from _paths import REPO, RUNS

from bayestribo.campaign.catalog import list_fits, list_runs
from bayestribo.campaign.lock import LOCK_NAME

pytestmark = [
    pytest.mark.skipif(not RUNS.is_dir(), reason="bundled data/ folder not present"),
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pseudo-terminals"),
]

SLOW_SOURCE = RUNS / "glycerol-N0.31-r1.csv"
#: ``--poll 600``: the watch looks at its folder when the system reports a change there
#: (and when a file waiting to settle is due), so every answer here comes by the
#: folder's events; one that waited for a poll would miss its deadline.
FAST = ["--max-steps", "400", "--population-steps", "400", "--poll", "600"]
#: Longest wait for anything (a deadline that fails the test, never a measurement) [s].
DEADLINE = 240.0


def _env() -> dict[str, str]:
    return {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }


class Watch:
    """A ``campaign --watch`` subprocess whose output lines are collected as they come."""

    def __init__(self, folder: Path, out: Path, *options: str) -> None:
        argv = [sys.executable, "-m", "bayestribo", "campaign", str(folder), "--out", str(out)]
        self.proc = subprocess.Popen(
            [*argv, "--watch", *FAST, *options],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=_env(),
        )
        self.lines: list[str] = []
        self._new: queue.Queue[str] = queue.Queue()
        self._said: list[str] = []
        self._readers = [
            threading.Thread(target=self._read, args=(self.proc.stdout, self._new.put)),
            threading.Thread(target=self._read, args=(self.proc.stderr, self._said.append)),
        ]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(stream, keep) -> None:
        for line in stream:
            keep(line.rstrip("\n"))

    @property
    def stderr(self) -> str:
        return "\n".join(self._said)

    def wait_for(self, start: str) -> str:
        """The first line starting with ``start`` (waiting for it)."""
        end = time.monotonic() + DEADLINE
        while True:
            found = [line for line in self.lines if line.startswith(start)]
            if found:
                return found[0]
            try:
                self.lines.append(self._new.get(timeout=max(0.0, end - time.monotonic())))
            except queue.Empty:
                self.proc.kill()
                pytest.fail(f"no line {start!r} from the watch; it printed {self.lines}")

    def finish(self) -> int:
        """Wait for the process to end; its exit status (every line collected)."""
        status = self.proc.wait(timeout=DEADLINE)
        for reader in self._readers:
            reader.join(timeout=DEADLINE)
        while not self._new.empty():
            self.lines.append(self._new.get())
        return status


def _sidecar(run_id: str) -> str:
    """The bundled run's sidecar under another run id, without the water fraction that
    the acquired runs have not: the three runs are one group of repeats."""
    metadata = json.loads(SLOW_SOURCE.with_suffix(".json").read_text(encoding="utf-8"))
    metadata.pop("water_mass_fraction")
    return json.dumps({**metadata, "run_id": run_id})


def _wait_for_text(path: Path, text: str) -> str:
    """The content of ``path`` once it holds ``text`` (waiting for it)."""
    end = time.monotonic() + DEADLINE
    while time.monotonic() < end:
        content = path.read_text(encoding="utf-8") if path.is_file() else ""
        if text in content:
            return content
        time.sleep(0.05)
    pytest.fail(f"{path} never held {text!r}")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _write_slowly(path: Path, chunks: int = 8, pause_s: float = 0.2) -> None:
    """The bundled run's rows written in chunks into a file held open, a pause after
    each (well within the watch's settle interval): the watch hears of the file's
    creation and of its close, not of each write, and must look again when it is due
    to have settled."""
    path.with_suffix(".json").write_text(_sidecar(path.stem), encoding="utf-8")
    data = SLOW_SOURCE.read_bytes()
    step = len(data) // chunks + 1
    with open(path, "wb") as fh:
        for i in range(0, len(data), step):
            fh.write(data[i : i + step])
            fh.flush()
            time.sleep(pause_s)


def _acquire(folder: Path, run_id: str, zeta: float) -> subprocess.Popen:
    """``bayestribo acquire`` of a simulated run into ``folder``, started."""
    argv = [sys.executable, "-m", "bayestribo", "acquire", "--simulate", "--load", "0.31"]
    argv += ["--lubricant", "glycerol", "--run-id", run_id, "--out", str(folder)]
    argv += ["--duration", "0.6", "--sim-zeta", str(zeta), "--quiet", "--no-catalog"]
    return subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())


@dataclass
class Watched:
    folder: Path
    out: Path
    lines: list[str]
    stderr: str
    status: int
    live_page: str
    slow_sha256: str


ACQUIRED = ("acq-r1", "acq-r2")


@pytest.fixture(scope="module")
def watched(tmp_path_factory) -> Watched:
    folder = tmp_path_factory.mktemp("runs")
    out = tmp_path_factory.mktemp("results")
    # a malformed run, in the folder from the start
    (folder / "bad.json").write_text(_sidecar("bad"), encoding="utf-8")
    (folder / "bad.csv").write_text("this is not a recording\n", encoding="utf-8")
    watch = Watch(folder, out, "--max-runs", "4", "--settle", "2", "--timeout", str(DEADLINE))
    try:
        # the page of a watch under way (it cannot stop before the runs below land)
        live_page = _wait_for_text(out / "watch.html", "<table")
        slow = folder / "slow.csv"
        writer = threading.Thread(target=_write_slowly, args=(slow,))
        writer.start()
        # two rigs at once, each with its simulated instrument, while the watch warms up
        acquiring = [
            _acquire(folder, run_id, zeta)
            for zeta, run_id in zip((0.0236, 0.0241), ACQUIRED, strict=True)
        ]
        for proc in acquiring:
            _, said = proc.communicate(timeout=DEADLINE)
            assert proc.returncode == 0, said
        writer.join()
        status = watch.finish()
    finally:
        if watch.proc.poll() is None:
            watch.proc.kill()
    return Watched(folder, out, watch.lines, watch.stderr, status, live_page, _sha256(slow))


def _answers(watched: Watched, run: str) -> list[str]:
    return [line for line in watched.lines if line.startswith((f"{run}  ", f"FAILED {run}:"))]


def _catalogued(out: Path) -> dict[str, tuple[str, int]]:
    """Run id -> (SHA-256 registered, number of fits recorded)."""
    catalog = out / "catalog.sqlite"
    return {r.run_id: (r.sha256, len(list_fits(catalog, run=r.id))) for r in list_runs(catalog)}


def test_each_acquired_run_is_answered_once_and_is_in_the_catalog(watched):
    assert "stopped after --max-runs 4" in watched.stderr
    catalogued = _catalogued(watched.out)
    for run in ACQUIRED:
        (line,) = _answers(watched, run)
        assert line.startswith(f"{run}  viscous+coulomb  ζ ") and " μ_k " in line
        assert catalogued[run] == (_sha256(watched.folder / f"{run}.csv"), 1)
        fit = list_fits(watched.out / "catalog.sqlite", run=run)[0]
        assert Path(fit.summary["result_path"]).is_file()


def test_a_file_written_slowly_is_fitted_once_and_whole(watched):
    (line,) = _answers(watched, "slow")
    assert line.startswith("slow  viscous+coulomb  ζ ")
    # the fit recorded is that of the whole file, not of a part of it
    assert _catalogued(watched.out)["slow"] == (watched.slow_sha256, 1)


def test_a_malformed_file_is_reported_and_the_watch_goes_on(watched):
    (line,) = _answers(watched, "bad")
    assert "bad.csv" in line
    # the slow run lands after the malformed one (it settles later, or with it and
    # after it in name order): its answer came after the failure
    (slow,) = _answers(watched, "slow")
    assert watched.lines.index(line) < watched.lines.index(slow)
    assert len(watched.lines) == 4
    assert watched.status == 1  # a run failed
    status = json.loads((watched.out / "watch.json").read_text(encoding="utf-8"))
    (failed,) = [a for a in status["answers"] if a["run"] == "bad"]
    assert failed["error"] == line.removeprefix("FAILED bad: ")


def test_the_page_reloads_while_watching_and_not_once_stopped(watched):
    refresh = '<meta http-equiv="refresh"'
    assert refresh in watched.live_page
    final = (watched.out / "watch.html").read_text(encoding="utf-8")
    assert refresh not in final
    assert "stopped after --max-runs 4" in final


def test_the_page_in_a_browser_shows_every_run(watched):
    from bayestribo.reports.browser import find_chromium

    chromium = find_chromium()
    if chromium is None:
        pytest.skip("no headless Chromium on PATH (apt-get install chromium)")
    page = watched.out / "watch.html"
    with tempfile.TemporaryDirectory(prefix="bayestribo-chromium-") as profile:
        done = subprocess.run(
            [
                chromium,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
                f"--user-data-dir={profile}",
                "--dump-dom",
                page.as_uri(),
            ],
            capture_output=True,
            text=True,
            timeout=DEADLINE,
        )
    dom = done.stdout
    assert '<table id="runs">' in dom, done.stderr[-500:]
    for run in ("bad", "slow", *ACQUIRED):
        assert f'<tr data-run="{run}"' in dom or f'data-run="{run}"' in dom
    assert dom.count("<tr data-run=") == 3 and dom.count('<tr class="failed"') == 1
    assert '<table id="populations">' in dom  # the populations of the three runs


def test_ctrl_c_stops_the_watch_with_the_catalog_consistent(tmp_path):
    folder = tmp_path / "runs"
    folder.mkdir()
    run = "glycerol-N0.07-r1"
    for suffix in (".csv", ".json"):
        shutil.copy(RUNS / f"{run}{suffix}", folder / f"{run}{suffix}")
    out = tmp_path / "results"
    # no warm-up: the first fit imports and compiles, and Ctrl-C comes while it runs
    watch = Watch(folder, out, "--settle", "0.5", "--no-warm-up", "--timeout", str(DEADLINE))
    try:
        _wait_for_text(out / "watch.json", '"fitting": [\n  "')
        watch.proc.send_signal(signal.SIGINT)
        status = watch.finish()
    finally:
        if watch.proc.poll() is None:
            watch.proc.kill()
    assert status == 130, watch.stderr
    assert "stopped by Ctrl-C" in watch.stderr
    # consistent: each fit file is a whole fit the catalog records, and each fit
    # recorded has its file (the fit cut short left nothing; one that ended is in both)
    fits = list_fits(out / "catalog.sqlite", run=run)
    recorded = {Path(f.summary["result_path"]): f.summary["result_sha256"] for f in fits}
    assert {p.resolve() for p in (out / "fits").iterdir()} == set(recorded)
    assert all(_sha256(path) == sha for path, sha in recorded.items())
    assert [line for line in watch.lines if not line.startswith(f"{run}  ")] == []
    assert len(watch.lines) == len(fits)  # an answer printed is a fit recorded
    assert not (out / LOCK_NAME).exists()
    final = (out / "watch.html").read_text(encoding="utf-8")
    assert "stopped by Ctrl-C" in final and 'http-equiv="refresh"' not in final
