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
