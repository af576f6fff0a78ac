"""Folder events that wake a watch as soon as something lands.

:class:`Wakeup` runs watchdog's native observer on a folder (inotify on Linux, FSEvents
on macOS, ReadDirectoryChangesW on Windows) and resolves a future at the first change
after it was armed, so a loop waiting with :func:`concurrent.futures.wait` on its fits
and that future looks at the folder the moment a file is created, written, renamed or
removed there. Polling stays the watch's fallback (:class:`~.watch.WatchOptions`
``poll_s``): folders where the system delivers no events (network shares, some
containers' mounts) are still looked at every ``poll_s``, and a folder whose observer
cannot start is watched by polling alone, with the reason.

A file created, closed after writing, renamed or removed wakes the loop; each write
into a file does not (a recording streamed in would wake it thousands of times a
second; its close does, and a file written in place is looked at again when it is due
to have settled), nor does opening or closing a file without writing it (the fits
reading the runs), nor anything under a hidden name (the acquisition's staging
folders, which the watch never looks into; their rename into place wakes it) or under
the excluded paths (the campaign's own output folder and catalog, which the watch
itself writes).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Collection
from concurrent.futures import Future
from pathlib import Path
from typing import Any

__all__ = ["Wakeup"]

#: Event types that do not wake the loop: reads, and each write into a file (its close
#: does).
_QUIET = frozenset({"opened", "closed_no_write", "modified"})


class Wakeup:
    """A future resolved by the next change in a folder.

    Parameters
    ----------
    folder : path
        The folder watched, with its sub-folders.
    exclude : collection of path, optional
        Folders (with everything under them) and files whose events are ignored.
    """

    def __init__(
        self,
        folder: str | os.PathLike[str],
        *,
        exclude: Collection[str | os.PathLike[str]] = (),
    ) -> None:
        self.folder = Path(folder)
        self._root = os.path.abspath(self.folder)
        self._exclude = tuple(os.path.abspath(p) for p in exclude)
        self._lock = threading.Lock()
        self._future: Future[None] = Future()
        self._observer: Any = None

    def start(self) -> str | None:
        """Start the observer; None when it runs, else why not (the watch then polls)."""
        try:
            from watchdog.events import FileSystemEventHandler
            from watchdog.observers import Observer
        except ImportError as exc:  # a trimmed install
            return f"watchdog is not importable ({exc})"
        wakeup = self

        class _Handler(FileSystemEventHandler):
            def on_any_event(self, event: Any) -> None:
                wakeup._event(event)

        observer = Observer()
        observer.daemon = True
        try:
            observer.schedule(_Handler(), str(self.folder), recursive=True)
            observer.start()
        except Exception as exc:  # inotify's watch limit, an unsupported filesystem
            return f"{type(exc).__name__}: {exc}"
        self._observer = observer
        return None

    @property
    def running(self) -> bool:
        """True while the observer delivers events."""
        return self._observer is not None and self._observer.is_alive()

    def armed(self) -> Future[None]:
        """The future the next change resolves: a fresh one once the last was resolved.
        Arm before looking at the folder, so that no change after the look is missed."""
        with self._lock:
            if self._future.done():
                self._future = Future()
            return self._future

    def stop(self) -> None:
        """Stop the observer (idempotent)."""
        observer, self._observer = self._observer, None
        if observer is not None:
            observer.stop()
            observer.join(timeout=5.0)

    def _event(self, event: Any) -> None:
        if event.event_type in _QUIET:
            return
        paths = [event.src_path, getattr(event, "dest_path", "") or ""]
        if all(not p or self._ignored(os.fsdecode(p)) for p in paths):
            return
        with self._lock:
            if not self._future.done():
                self._future.set_result(None)

    def _ignored(self, path: str) -> bool:
        """Under an excluded path, or under a hidden name inside the folder."""
        path = os.path.abspath(path)
        if any(path == p or path.startswith(p + os.sep) for p in self._exclude):
            return True
        try:
            inside = os.path.relpath(path, self._root)
        except ValueError:  # another drive (Windows): not in the folder
            return True
        return any(part.startswith(".") for part in Path(inside).parts if part != "..")
