"""One writer per output folder: a lock on a campaign's ``--out``.

Two campaigns writing the same folder interleave their fits, catalog rows and tables:
each sees the other's half-written files (three of twelve fits unreadable, eighteen
catalog rows for twelve runs, measured). :class:`FolderLock` makes the folder's writer
one process: a lock file held open with an exclusive lock of the operating system
(``fcntl.flock``; ``msvcrt.locking`` on Windows) for the lock's whole life, which holds
the owner's process id, host and start time for the messages. A second campaign on the
folder is refused, naming the first.

The operating system drops the lock when its process ends, however it ends (killed,
crashed), so there is no guessing whether a lock is stale: a lock file nobody holds is
free, and the next campaign takes it (and says whose it was). Many processes taking it
at one instant get it one at a time: exactly one of them holds it. The owner removes the
file while it still holds the lock; a process that took the lock of a file removed
meanwhile sees that (the path names another file, or none) and tries again (on Windows,
where an open file cannot be removed, the owner empties it instead). A lock file
naming another host is refused with the command that removes it, as that host's process
cannot be seen from here (and a network file system may not share its locks).

Every table of the folder is written through :func:`write_atomic`
(:func:`bayestribo._files.write_text`): to a temporary name in the folder, then renamed
over the old file, so that a reader, a kill or a full disk never leaves a half-written
table.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import time
from pathlib import Path
from types import TracebackType
from typing import Any

from bayestribo._files import write_text
from bayestribo.errors import BayestriboError

__all__ = ["LOCKING", "LOCK_NAME", "FolderLock", "write_atomic"]

#: The lock file's name in the output folder.
LOCK_NAME = ".bayestribo-campaign.lock"

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]
try:  # Windows
    import msvcrt
except ImportError:
    msvcrt = None  # type: ignore[assignment]

#: How this platform locks: ``"flock"`` (POSIX), ``"msvcrt"`` (Windows) or None.
LOCKING: str | None = "flock" if fcntl is not None else ("msvcrt" if msvcrt is not None else None)

#: Windows: the byte locked, beyond any owner record (Windows' locks keep other
#: processes from reading the bytes they cover).
_WINDOWS_BYTE = 1 << 30


def _try_lock(fd: int) -> bool:
    """Take the operating system's exclusive lock on ``fd`` without waiting."""
    if LOCKING == "flock":
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
    if LOCKING == "msvcrt":  # pragma: no cover - Windows
        os.lseek(fd, _WINDOWS_BYTE, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    raise BayestriboError(
        "this platform has no file locking (neither fcntl nor msvcrt): a campaign's "
        "output folder cannot be locked; run one campaign per --out at a time"
    )


def _unlock(fd: int) -> None:
    if LOCKING == "flock":
        fcntl.flock(fd, fcntl.LOCK_UN)
    elif LOCKING == "msvcrt":  # pragma: no cover - Windows
        os.lseek(fd, _WINDOWS_BYTE, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)


def _same_file(fd: int, path: Path) -> bool:
    """True while ``path`` names the file open as ``fd`` (not removed, not replaced)."""
    try:
        here = os.stat(path)
    except FileNotFoundError:
        return False
    there = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


def _record(fd: int) -> dict[str, Any]:
    """The owner record in the lock file open as ``fd`` ({} if none or unreadable)."""
    try:
        data = os.pread(fd, 4096, 0) if hasattr(os, "pread") else _read_start(fd)
        owner = json.loads(data.decode("utf-8"))
    except (OSError, ValueError):
        return {}
    return owner if isinstance(owner, dict) else {}


def _read_start(fd: int) -> bytes:  # pragma: no cover - Windows
    os.lseek(fd, 0, os.SEEK_SET)
    return os.read(fd, 4096)


class FolderLock:
    """An exclusive lock on an output folder, for a ``with`` block.

    Parameters
    ----------
    folder : path
        The output folder (created if missing).
    what : str
        The command, named in the refusal (``"campaign"``).

    Attributes
    ----------
    took_over : dict or None
        The record of a lock left by a process that had ended (its ``pid``, ``host``
        and ``started``, or ``{"unreadable": True}``), when this lock took its place.

    Raises
    ------
    BayestriboError
        On entering, when another live process holds the folder (its id, host and
        start time are named), or the lock file names another host.
    """

    def __init__(self, folder: str | os.PathLike[str], what: str = "campaign") -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_NAME
        self.what = what
        self.took_over: dict | None = None
        self._fd: int | None = None

    def _owner(self) -> dict:
        try:
            owner = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        return owner if isinstance(owner, dict) else {}

    def _refusal(self) -> BayestriboError:
        """The refusal naming the holder (its record may be a moment from written)."""
        owner = self._owner()
        for _ in range(20):  # for the message only: the holder writes it just after
            if "pid" in owner:
                break
            time.sleep(0.01)
            owner = self._owner()
        pid = owner.get("pid", "unknown")
        host = owner.get("host")
        since = time.strftime(
            "%Y-%m-%d %H:%M:%S", time.localtime(float(owner.get("started", time.time())))
        )
        where = "" if host in (None, socket.gethostname()) else f" on host {host}"
        return BayestriboError(
            f"{self.folder}: another {self.what} (process {pid}{where}, since {since}) "
            "writes to this folder; wait for it to end, or give another --out"
        )

    def __enter__(self) -> FolderLock:
        self.folder.mkdir(parents=True, exist_ok=True)
        me = {"pid": os.getpid(), "host": socket.gethostname(), "started": time.time()}
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | getattr(os, "O_BINARY", 0), 0o644)
            try:
                if not _try_lock(fd):
                    raise self._refusal()
                if not _same_file(fd, self.path):
                    # its owner removed it after this process opened it: another file
                    # is (or will be) the lock; try that one
                    os.close(fd)
                    continue
                before = _record(fd)
            except BaseException:
                with contextlib.suppress(OSError):
                    os.close(fd)
                raise
            break
        host = before.get("host")
        if isinstance(before.get("pid"), int) and host not in (None, me["host"]):
            self._fd = fd
            self._release(remove=False)
            raise BayestriboError(
                f"{self.folder}: another {self.what} (process {before['pid']} on host {host}) "
                "writes to this folder; wait for it, or give another --out (if it no "
                f"longer runs: rm {self.path})"
            )
        if os.fstat(fd).st_size or before:
            # a lock file nobody holds: its process ended without removing it
            self.took_over = before or {"unreadable": True}
        text = json.dumps(me).encode("utf-8")
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, text)
        self._fd = fd
        return self

    def _release(self, *, remove: bool) -> None:
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            if remove and LOCKING == "msvcrt":  # pragma: no cover - Windows
                # an open file cannot be removed there: left empty (no owner), unlocked
                os.ftruncate(fd, 0)
            elif remove and _same_file(fd, self.path):
                # removed while still held: a process waiting on this file sees that
                self.path.unlink(missing_ok=True)
            _unlock(fd)
        finally:
            os.close(fd)

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self._release(remove=True)


def write_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder and a
    rename: the old file or the new one, never a part of either
    (:func:`bayestribo._files.write_text`).

    Returns
    -------
    Path
        ``path``.
    """
    return write_text(path, text)
