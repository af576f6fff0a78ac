"""One writer per output folder, and tables written whole."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from bayestribo.campaign.lock import LOCK_NAME, FolderLock, write_atomic
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
