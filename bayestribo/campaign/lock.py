"""One writer per output folder: a lock on a campaign's ``--out``.

Two campaigns writing the same folder interleave their fits, catalog rows and tables:
each sees the other's half-written files (three of twelve fits unreadable, eighteen
catalog rows for twelve runs, measured). :class:`FolderLock` makes the folder's writer
one process: a lock file created exclusively (``O_CREAT | O_EXCL``) holding the
owner's process id, host and start time. A second campaign on the folder is refused,
naming the first. A lock left by a process that no longer runs (killed, or the machine
restarted) is taken over, and said; a lock of another host cannot be checked and is
refused with the command that removes it.

Every table of the folder is written through :func:`write_atomic`: to a temporary
name in the folder, then renamed over the old file, so that a reader, a kill or a
full disk never leaves a half-written table.
"""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path
from types import TracebackType

from bayestribo.errors import BayestriboError

__all__ = ["LOCK_NAME", "FolderLock", "write_atomic"]

#: The lock file's name in the output folder.
LOCK_NAME = ".bayestribo-campaign.lock"


def _alive(pid: int) -> bool:
    """True when a process with this id runs on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # it runs, as another user
        return True
    return True


class FolderLock:
    """An exclusive lock on an output folder, for a ``with`` block.

    Parameters
    ----------
    folder : path
        The output folder (created if missing).
    what : str
        The command, named in the refusal (``"campaign"``).

    Raises
    ------
    BayestriboError
        On entering, when another live process holds the folder (its id, host and
        start time are named).
    """

    def __init__(self, folder: str | os.PathLike[str], what: str = "campaign") -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_NAME
        self.what = what
        self.took_over: dict | None = None
        self._held = False

    def _owner(self) -> dict:
        try:
            return json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}

    def __enter__(self) -> FolderLock:
        self.folder.mkdir(parents=True, exist_ok=True)
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": time.time()}
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                owner = self._owner()
                if "pid" not in owner:  # being written this instant: look again
                    time.sleep(0.2)
                    owner = self._owner()
                pid, host = owner.get("pid"), owner.get("host")
                if isinstance(pid, int) and host != me["host"]:
                    raise BayestriboError(
                        f"{self.folder}: another {self.what} (process {pid} on host {host}) "
                        "writes to this folder; wait for it, or give another --out (if it no "
                        f"longer runs: rm {self.path})"
                    ) from None
                if isinstance(pid, int) and _alive(pid):
                    since = time.strftime(
                        "%Y-%m-%d %H:%M:%S", time.localtime(float(owner.get("started", 0)))
                    )
                    raise BayestriboError(
                        f"{self.folder}: another {self.what} (process {pid}, since {since}) "
                        "writes to this folder; wait for it to end, or give another --out"
                    ) from None
                # its process no longer runs (killed), or the file is no lock: taken over
                self.took_over = owner or {"unreadable": True}
                self.path.unlink(missing_ok=True)
                continue
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                json.dump(me, f)
            self._held = True
            return self
        raise BayestriboError(f"{self.folder}: could not take the lock {self.path}")

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._held and self._owner().get("pid") == os.getpid():
            self.path.unlink(missing_ok=True)
        self._held = False


def write_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder and a
    rename: the old file or the new one, never a part of either.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path
