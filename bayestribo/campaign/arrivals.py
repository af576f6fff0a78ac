"""Run files as they become complete in a folder that is being written: polling.

``bayestribo campaign DIR --watch`` fits each run as soon as its file is whole.
:class:`Arrivals` walks the folder with :func:`os.scandir` at every :meth:`~Arrivals.poll`
and says which run files became complete since the last one. A run file is a file of a
registered format with its JSON sidecar beside it (as for ``bayestribo campaign``);
hidden files and folders (names starting with ``.``: the staging folders of
``bayestribo acquire``, temporary files of atomic writers) are never looked at. A file
is complete when either

* a ``<stem>.sha256`` manifest beside it (``sha256sum -c`` format, moved into place
  last by ``bayestribo acquire``, whose run files appear by rename) lists the file and
  its sidecar with the digests of their present contents: complete at once; or
* the file and its sidecar have kept the same size and modification time for the
  settle interval: a writer that appends in chunks is waited for until it stops.

A file already given is given again only when it changes (its size or modification
time moves, then settles); the campaign's catalog then says whether it can take it (a
run id holds one file's content: a run rewritten with other samples is refused, naming
both digests). The clock is injected, so the rule is tested without waiting.
"""

from __future__ import annotations

import hashlib
import os
import time
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Arrivals", "FileState", "manifest_digests"]


@dataclass(frozen=True)
class FileState:
    """What a poll sees of a file: its size [bytes] and modification time [ns]."""

    size: int
    mtime_ns: int

    @classmethod
    def of(cls, entry: os.DirEntry[str] | Path) -> FileState:
        """The state of a directory entry or path (following links)."""
        st = entry.stat()
        return cls(int(st.st_size), int(st.st_mtime_ns))


def manifest_digests(path: Path) -> dict[str, str]:
    """The SHA-256 digests a ``sha256sum`` manifest lists, by file name (empty if the
    manifest cannot be read)."""
    out: dict[str, str] = {}
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return out
    for line in text.splitlines():
        digest, sep, name = line.strip().partition("  ")
        if sep and len(digest) == 64:
            out[name.lstrip("*")] = digest.lower()
    return out


def _sha256(path: Path) -> str | None:
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return None
    return digest.hexdigest()


class Arrivals:
    """The run files of a folder that became complete since the last poll.

    Parameters
    ----------
    folder : path
        The folder watched, with its sub-folders.
    suffixes : collection of str
        File suffixes of run files (lower case, with the dot: ``".csv"``).
    settle_s : float
        How long a file without a manifest must keep its size and modification time
        before it counts as complete [s]; must be positive.
    exclude : collection of path, optional
        Folders never looked into (the campaign's own output folder).
    clock : callable, optional
        Monotonic time [s]; default :func:`time.monotonic`.

    Raises
    ------
    ValueError
        For a ``settle_s`` that is not a positive number.
    """

    def __init__(
        self,
        folder: str | os.PathLike[str],
        suffixes: Collection[str],
        settle_s: float,
        *,
        exclude: Collection[str | os.PathLike[str]] = (),
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not settle_s > 0:  # also refuses nan
            raise ValueError(f"settle_s: expected a positive number of seconds, got {settle_s!r}")
        self.folder = Path(folder)
        self.suffixes = {s.lower() for s in suffixes} - {".json"}
        self.settle_s = float(settle_s)
        self._exclude = {os.path.abspath(p) for p in exclude}
        self._clock = clock
        #: path -> (state of the file and its sidecar, when that state was first seen)
        self._seen: dict[Path, tuple[tuple[FileState, FileState | None], float]] = {}
        #: path -> the state answered (the file is given again only when it moves)
        self._given: dict[Path, tuple[FileState, FileState | None]] = {}
        #: path -> the states of the file, its sidecar and its manifest whose digests
        #: did not match (not hashed again)
        self._hashed: dict[Path, tuple[FileState | None, ...]] = {}

    def _walk(self, folder: str) -> Iterator[os.DirEntry[str]]:
        try:
            entries = list(os.scandir(folder))
        except OSError:  # removed or unreadable while being walked
            return
        for entry in entries:
            if entry.name.startswith("."):
                continue
            try:
                if entry.is_dir(follow_symlinks=False):  # as ``rglob``: no loop of links
                    if os.path.abspath(entry.path) not in self._exclude:
                        yield from self._walk(entry.path)
                elif entry.is_file() and os.path.splitext(entry.name)[1].lower() in self.suffixes:
                    yield entry
            except OSError:
                continue

    def pending(self) -> list[Path]:
        """Run files seen and not complete yet (with their sidecar, waiting to settle);
        a file without a sidecar is no run file, and not listed."""
        return sorted(
            p for p, (state, _) in self._seen.items() if p not in self._given and state[1]
        )

    def next_due(self) -> float | None:
        """Seconds until the soonest run file seen and not complete has kept its state
        for ``settle_s`` (0 when one has already); None when none is waiting."""
        now = self._clock()
        waits = [
            first + self.settle_s - now
            for p, (state, first) in self._seen.items()
            if p not in self._given and state[1]
        ]
        return max(0.0, min(waits)) if waits else None

    def poll(self) -> list[Path]:
        """Walk the folder once; the run files that became complete, in name order."""
        now = self._clock()
        present: set[Path] = set()
        ready: list[Path] = []
        for entry in self._walk(str(self.folder)):
            path = Path(entry.path)
            present.add(path)
            side = path.with_suffix(".json")
            try:
                state = (FileState.of(entry), FileState.of(side) if side.is_file() else None)
            except OSError:  # removed between the listing and the look
                continue
            if self._given.get(path) == state:
                continue
            seen = self._seen.get(path)
            if seen is None or seen[0] != state:
                self._seen[path] = (state, now)
                seen = (state, now)
            if state[1] is None:
                continue  # no sidecar (yet): not a run file
            if now - seen[1] >= self.settle_s or self._manifested(path, state):
                self._given[path] = state
                ready.append(path)
        for gone in set(self._seen) - present:
            # deleted or moved away: forgotten, so a file put back is a new arrival
            self._seen.pop(gone, None)
            self._given.pop(gone, None)
            self._hashed.pop(gone, None)
        return sorted(ready)

    def _manifested(self, path: Path, state: tuple[FileState, FileState | None]) -> bool:
        """True when the file's ``.sha256`` manifest lists it and its sidecar with the
        digests of their contents (each state is hashed once)."""
        manifest = path.with_suffix(".sha256")
        try:
            key = (*state, FileState.of(manifest))
        except OSError:  # no manifest (yet)
            return False
        if self._hashed.get(path) == key:
            return False
        listed = manifest_digests(manifest)
        side = path.with_suffix(".json")
        ok = (
            listed.get(path.name) is not None
            and listed.get(side.name) is not None
            and listed[path.name] == _sha256(path)
            and listed[side.name] == _sha256(side)
        )
        if not ok:
            self._hashed[path] = key
        return ok
