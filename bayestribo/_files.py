"""Whole files or none: every file the package writes goes through here.

A file is written to a temporary name in its own folder (created with ``O_EXCL``, the
mode the process's umask gives a new file), flushed, ``fsync``-ed, renamed over the
target with :func:`os.replace` and the folder ``fsync``-ed. A failure at any step (a
full disk, a kill, an exception of the writer) removes the temporary and leaves the
target as it was: its previous content whole, or no file. A reader therefore never sees
a part of a file, and a command that fails says truly what it kept.

Three ways in, by what the writer needs:

- :func:`write_text` / :func:`write_bytes`: the content is at hand.
- :func:`atomic_file`: a file object, for writers that take one (``savefig``,
  ``csv.writer``, ``json.dump``).
- :func:`atomic_path`: a temporary path, for writers that open the file themselves by
  name (the netCDF C library, ``nbformat.write``).

Every byte written through :func:`atomic_file`, :func:`write_text` and
:func:`write_bytes` goes through :func:`os.write`, so a test can simulate a full disk
by patching that one function.

A failure raises the writer's :class:`OSError` with ``filename`` set to the target
(not the temporary), so that the message names the file the user asked for. A writer
that fails with another exception on a device with no space left (the netCDF C library
says ``NetCDF: HDF error``) is reported as the :class:`OSError` ``ENOSPC`` it is, the
writer's exception chained.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "LOW_SPACE_BYTES",
    "atomic_file",
    "atomic_path",
    "fsync_folder",
    "temporary_names",
    "write_bytes",
    "write_text",
]

#: Below this many free bytes on the target's device, a writer's failure that is not an
#: :class:`OSError` is taken for the full disk it most likely is (a library that writes
#: by itself reports it in its own words).
LOW_SPACE_BYTES = 1 << 20

#: How a temporary's name starts and ends: ``.<target name>.<pid>.<n>.tmp<suffix>``
#: (the target's suffix last, for writers that choose a format by it, as ``savefig``).
_PREFIX, _SUFFIX = ".", ".tmp"

_counter = iter(range(1 << 62))


def temporary_names(path: str | os.PathLike[str]) -> str:
    """The glob pattern of the temporaries of ``path`` (to find any left behind).

    Parameters
    ----------
    path : path-like
        A target file.

    Returns
    -------
    str
        A pattern for :meth:`pathlib.Path.glob` in the target's folder.
    """
    return f"{_PREFIX}{Path(path).name}.*{_SUFFIX}*"


def _new_temporary(path: Path) -> tuple[int, Path]:
    """Create a new, empty temporary beside ``path`` (``O_EXCL``): its fd and path."""
    while True:
        name = f"{_PREFIX}{path.name}.{os.getpid()}.{next(_counter)}{_SUFFIX}{path.suffix}"
        tmp = path.with_name(name)
        try:
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
            return os.open(tmp, flags, 0o666), tmp  # the umask applies, as for open()
        except FileExistsError:  # left by a process of the same id: another name
            continue


def fsync_folder(folder: str | os.PathLike[str]) -> None:
    """``fsync`` a folder, so that a rename in it survives a crash of the machine.

    A platform without directory file descriptors (Windows) skips it.
    """
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory fds
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - file systems that refuse it
        pass
    finally:
        os.close(fd)


def _named(exc: OSError, tmp: Path, path: Path) -> OSError:
    """``exc`` naming ``path`` (the target) where it names the temporary or nothing."""
    if exc.filename is None or str(exc.filename) == str(tmp):
        exc.filename = str(path)
    return exc


def _as_disk_full(exc: BaseException, path: Path) -> OSError | None:
    """A writer's non-OSError failure as ``ENOSPC`` when the device is (nearly) full."""
    if isinstance(exc, OSError) or not isinstance(exc, Exception):
        return None
    try:
        free = shutil.disk_usage(path.parent).free
    except OSError:
        return None
    if free >= LOW_SPACE_BYTES:
        return None
    return OSError(
        errno.ENOSPC,
        f"No space left on device ({free} bytes free; the writer said "
        f"{type(exc).__name__}: {str(exc)[:200]})",
        str(path),
    )


def _finish(fd: int, tmp: Path, path: Path) -> None:
    """fsync the temporary's fd, close it, rename it over ``path``, fsync the folder."""
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)
    fsync_folder(path.parent)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path`` for a writer that opens the file by name; on
    leaving the block without error, the file written there replaces ``path``.

    Parameters
    ----------
    path : path-like
        The target file. Its folder must exist.

    Yields
    ------
    Path
        The temporary (created empty; the writer may overwrite or replace it).

    Raises
    ------
    OSError
        When writing fails (``filename`` the target); ``path`` is then as it was.
    """
    path = Path(path)
    fd, tmp = _new_temporary(path)
    os.close(fd)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY | getattr(os, "O_BINARY", 0))
        _finish(fd, tmp, path)
    except OSError as exc:
        _remove(tmp)
        _named(exc, tmp, path)
        raise
    except BaseException as exc:
        _remove(tmp)
        full = _as_disk_full(exc, path)
        if full is not None:
            raise full from exc
        raise


class _Raw(io.RawIOBase):
    """Unbuffered writes to a file descriptor, each through :func:`os.write`.

    Closing it leaves the descriptor open (:func:`atomic_file` closes it). Once
    ``abandoned`` (the write failed), what is still buffered is dropped, never written
    to a descriptor that may by then be another file's.
    """

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.abandoned = False

    def writable(self) -> bool:
        return True

    def write(self, data: Any) -> int:
        if self.abandoned:
            return len(memoryview(data))
        return os.write(self.fd, data)

    def fileno(self) -> int:
        return self.fd


@contextlib.contextmanager
def atomic_file(
    path: str | os.PathLike[str],
    mode: str = "w",
    *,
    encoding: str = "utf-8",
    newline: str | None = "",
) -> Iterator[IO[Any]]:
    """A file object writing a temporary beside ``path``; on leaving the block without
    error, the file replaces ``path`` whole.

    Parameters
    ----------
    path : path-like
        The target file. Its folder must exist.
    mode : {"w", "wb"}
        Text or binary.
    encoding : str
        Text mode: the encoding (UTF-8 by default).
    newline : str or None
        Text mode: as :func:`open`'s ``newline`` (default ``""``: line ends written as
        given).

    Yields
    ------
    file object
        Text (``"w"``) or binary (``"wb"``).

    Raises
    ------
    ValueError
        For another ``mode``.
    OSError
        When writing fails (``filename`` the target); ``path`` is then as it was.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode: expected 'w' or 'wb', got {mode!r}")
    path = Path(path)
    fd, tmp = _new_temporary(path)
    raw = _Raw(fd)
    buffered = io.BufferedWriter(raw, buffer_size=1 << 16)
    handle: IO[Any] = (
        io.TextIOWrapper(buffered, encoding=encoding, newline=newline) if mode == "w" else buffered
    )
    try:
        yield handle
        handle.close()  # flushes; the descriptor stays open for fsync
        raw.fd = -1  # closed by _finish, whatever happens there
        _finish(fd, tmp, path)
    except OSError as exc:
        _abandon(raw, handle)
        _remove(tmp)
        _named(exc, tmp, path)
        raise
    except BaseException as exc:
        _abandon(raw, handle)
        _remove(tmp)
        full = _as_disk_full(exc, path)
        if full is not None:
            raise full from exc
        raise


def _abandon(raw: _Raw, handle: IO[Any]) -> None:
    """Drop what is buffered, close the handle and the descriptor (if still open)."""
    raw.abandoned = True
    fd, raw.fd = raw.fd, -1
    with contextlib.suppress(Exception):
        handle.close()
    if fd >= 0:
        with contextlib.suppress(OSError):
            os.close(fd)


def _remove(tmp: Path) -> None:
    with contextlib.suppress(OSError):
        tmp.unlink()


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` whole, or leave ``path`` as it was.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OSError
        When writing fails (``filename`` the target).
    """
    with atomic_file(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def write_text(path: str | os.PathLike[str], text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` whole (line ends as given), or leave ``path`` as it was.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OSError
        When writing fails (``filename`` the target).
    """
    with atomic_file(path, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)
