"""One writer per output folder, and tables written whole."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from bayestribo.campaign.lock import LOCK_NAME, LOCKING, FolderLock, write_atomic
from bayestribo.cli import main
from bayestribo.errors import BayestriboError


def test_a_second_writer_is_refused_naming_the_first(tmp_path):
    with FolderLock(tmp_path / "out") as first:
        assert (first.path).is_file()
        with pytest.raises(BayestriboError, match=rf"another campaign \(process {os.getpid()}"):
            with FolderLock(tmp_path / "out"):
                pass
    assert not (tmp_path / "out" / LOCK_NAME).exists()  # released


def test_the_lock_of_a_killed_campaign_is_taken_over(tmp_path):
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    pid = int(dead.stdout)  # a process that has ended
    out = tmp_path / "out"
    out.mkdir()
    import socket

    (out / LOCK_NAME).write_text(json.dumps({"pid": pid, "host": socket.gethostname()}))
    with FolderLock(out) as lock:
        assert lock.took_over["pid"] == pid
        assert json.loads(lock.path.read_text())["pid"] == os.getpid()


def test_the_campaign_command_refuses_a_locked_folder(tmp_path, capsys):
    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / "a.csv").write_text("time_s,displacement_m\n")
    (runs / "a.json").write_text("{}")
    with FolderLock(tmp_path / "out"):
        assert main(["campaign", str(runs), "--out", str(tmp_path / "out")]) == 2
    assert "another campaign" in capsys.readouterr().err


def test_a_table_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    path = tmp_path / "population.json"
    write_atomic(path, "old\n")

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", full_disk)
    with pytest.raises(OSError, match="No space"):
        write_atomic(path, "new\n")
    assert path.read_text() == "old\n"  # the old table, whole
    assert [p.name for p in tmp_path.iterdir()] == ["population.json"]  # no temporary left


def _taker(folder, start, tried, counts) -> None:
    """Wait for every taker, try the lock; an owner holds it until all have tried."""
    start.wait(timeout=300)
    try:
        with FolderLock(folder) as lock:
            with counts.get_lock():
                counts[0] += 1
                counts[1] += lock.took_over is not None
            tried.wait(timeout=300)
    except BayestriboError:
        with counts.get_lock():
            counts[2] += 1
        tried.wait(timeout=300)


def _dead_pid() -> int:
    done = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(done.stdout)


@pytest.mark.skipif(LOCKING != "flock", reason="fork and flock (POSIX)")
def test_fifty_simultaneous_takers_of_a_stale_lock_make_one_owner(tmp_path):
    import multiprocessing
    import socket

    (tmp_path / LOCK_NAME).write_text(
        json.dumps({"pid": _dead_pid(), "host": socket.gethostname(), "started": 0.0})
    )
    takers = 50
    context = multiprocessing.get_context("fork")
    start, tried = context.Barrier(takers), context.Barrier(takers)
    counts = context.Array("i", 3)  # owners, of them taking over, refused
    procs = [
        context.Process(target=_taker, args=(tmp_path, start, tried, counts)) for _ in range(takers)
    ]
    for p in procs:
        p.start()
    for p in procs:
        p.join()
    assert [p.exitcode for p in procs] == [0] * takers
    assert list(counts) == [1, 1, takers - 1]
    assert not (tmp_path / LOCK_NAME).exists()  # released by its one owner


def test_a_lock_being_written_is_held_not_stale(tmp_path):
    """An empty lock file whose owner holds it (it has not written its record yet) is
    refused at once: the lock is the operating system's, not the file's content."""
    import fcntl

    path = tmp_path / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(BayestriboError, match="another campaign"):
            with FolderLock(tmp_path):
                pass
        assert path.read_bytes() == b""  # untouched
    finally:
        os.close(fd)
    with FolderLock(tmp_path) as lock:  # its owner gone: taken, said
        assert lock.took_over is None  # an empty file held no record to report
        assert json.loads(path.read_text())["pid"] == os.getpid()


def test_the_lock_of_a_campaign_killed_while_holding_it_is_taken_over(tmp_path):
    import signal

    code = (
        "import sys\n"
        "from bayestribo.campaign.lock import FolderLock\n"
        f"with FolderLock({str(tmp_path)!r}):\n"
        "    print('locked', flush=True)\n"
        "    sys.stdin.read()\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    child = subprocess.Popen(
        [sys.executable, "-c", code],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert child.stdout.readline().strip() == "locked"
        with pytest.raises(BayestriboError, match=rf"process {child.pid}\b"):
            with FolderLock(tmp_path):
                pass
        child.send_signal(signal.SIGKILL)
        child.wait()
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    with FolderLock(tmp_path) as lock:
        assert lock.took_over["pid"] == child.pid


def test_without_file_locking_the_lock_says_so(tmp_path, monkeypatch):
    from bayestribo.campaign import lock as lock_module

    monkeypatch.setattr(lock_module, "LOCKING", None)
    with pytest.raises(BayestriboError, match="no file locking"):
        with FolderLock(tmp_path):
            pass
