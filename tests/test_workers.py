"""Worker processes end with the command that started them, however it ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

SCRIPT = textwrap.dedent(
    """
    import sys, time
    from bayestribo._workers import process_pool

    def slow(x):
        time.sleep(600)

    if __name__ == "__main__":
        pool = process_pool(2, method=sys.argv[1])
        futures = [pool.submit(slow, i) for i in range(2)]
        time.sleep(2)  # the workers are running
        print("ready", flush=True)
        time.sleep(600)
    """
)


def _descendants(pid: int) -> set[int]:
    out = subprocess.run(["ps", "-eo", "pid=,ppid="], capture_output=True, text=True, check=True)
    children: dict[int, list[int]] = {}
    for line in out.stdout.split("\n"):
        if line.strip():
            p, pp = (int(v) for v in line.split())
            children.setdefault(pp, []).append(p)
    found, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            found.add(c)
            todo.append(c)
    return found


def _alive(pids: set[int]) -> set[int]:
    alive = set()
    for p in pids:
        try:
            os.kill(p, 0)
        except ProcessLookupError:
            continue
        # a zombie is gone for good: its parent (init) reaps it
        state = subprocess.run(["ps", "-o", "stat=", "-p", str(p)], capture_output=True, text=True)
        if state.stdout.strip() and not state.stdout.strip().startswith("Z"):
            alive.add(p)
    return alive


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ps and signals of Linux")
@pytest.mark.parametrize("method", ["forkserver", "spawn"])
def test_a_killed_command_leaves_no_worker_behind(tmp_path, method):
    script = tmp_path / "pool.py"
    script.write_text(SCRIPT)
    main = subprocess.Popen(
        [sys.executable, str(script), method], stdout=subprocess.PIPE, text=True
    )
    try:
        assert main.stdout.readline().strip() == "ready"
        helpers = _descendants(main.pid)
        assert len(helpers) >= 2  # the workers (and the server, the resource tracker)
        main.send_signal(signal.SIGKILL)
        main.wait(timeout=30)
        deadline = time.monotonic() + 10.0  # the limit: nothing alive after 10 s
        while _alive(helpers) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not _alive(helpers)
    finally:
        if main.poll() is None:
            main.kill()
        for p in _descendants(main.pid):
            with __import__("contextlib").suppress(ProcessLookupError):
                os.kill(p, signal.SIGKILL)


def _group(pgid: int) -> set[int]:
    """Processes of the process group ``pgid`` that are alive (zombies left out)."""
    out = subprocess.run(["ps", "-eo", "pid=,pgid=,stat="], capture_output=True, text=True)
    alive = set()
    for line in out.stdout.splitlines():
        pid, group, stat = line.split(None, 2)
        if int(group) == pgid and not stat.startswith("Z"):
            alive.add(int(pid))
    return alive


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ps and signals of Linux")
def test_a_terminated_campaign_stops_its_workers_and_exits_as_interrupted(tmp_path):
    # `bayestribo campaign` with two workers fitting the bundled runs, in a process group
    # of its own, gets SIGTERM once its workers exist: it unwinds as Ctrl-C does (exit
    # 130, "interrupted", the folder's lock released) and no process of its group is
    # alive 10 s after it ended (the limit).
    from _paths import DATA, REPO

    from bayestribo.campaign.lock import LOCK_NAME

    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    out = tmp_path / "out"
    argv = ["campaign", str(DATA), "--out", str(out), "--workers", "2", "--quiet", "--no-figures"]
    main = subprocess.Popen(
        [sys.executable, "-m", "bayestribo", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
        env=env,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 300.0  # a guard against a hang, not a speed limit
        while len(_descendants(main.pid)) < 2 and main.poll() is None:
            assert time.monotonic() < deadline, "the campaign started no workers"
            time.sleep(0.2)
        assert main.poll() is None, main.communicate()
        main.send_signal(signal.SIGTERM)
        _, err = main.communicate(timeout=120)
        assert main.returncode == 130, err
        # (a worker still starting when the pool shuts down may print the forkserver's
        # traceback of a semaphore already gone: the command's own lines are checked)
        assert "bayestribo campaign: interrupted" in err.splitlines()
        assert not (out / LOCK_NAME).exists()  # released on the way out, not left stale
        deadline = time.monotonic() + 10.0
        while _group(main.pid) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not _group(main.pid)
    finally:
        with __import__("contextlib").suppress(ProcessLookupError):
            os.killpg(main.pid, signal.SIGKILL)
