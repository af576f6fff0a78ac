"""The canonical run CSV written a chunk at a time, as the samples arrive.

Rows are written exactly as :func:`bayestribo.io.text.write_csv` writes them (header
``time_s,displacement_m,velocity_m_per_s``, then one row per sample, every value the
shortest text that reads back to the same 64-bit float), so
:func:`bayestribo.io.read_run` gives bit-identical samples. Displacement and velocity
are ``count × scale`` with 16-bit counts: the text of each count is made once, the
first time it is seen, so a row costs one float formatting (its time), not three.

The file's SHA-256 is computed as it is written; nothing of the run is held in memory
beyond a buffer of about a megabyte.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.protocol import RunHeader
from bayestribo.io.run import COLUMNS

__all__ = ["CsvStream", "StagedRun", "is_staging_of"]

#: What follows ``.<run_id>`` in the name of a staging directory, before the random part.
STAGING_MARK = ".staging-"
#: Bytes of rows gathered before they are written to the file.
BUFFER_BYTES = 1 << 20
_OFFSET = 32768  # count -32768 is row 0 of the text tables


class _Texts:
    """Text of ``count × scale`` by 16-bit count, made the first time a count is seen."""

    def __init__(self, scale: float) -> None:
        self.scale = scale
        self._texts = np.empty(2 * _OFFSET, dtype=object)
        self._made = np.zeros(2 * _OFFSET, dtype=bool)

    def __call__(self, counts: NDArray[np.int16]) -> list[str]:
        rows = counts.astype(np.intp) + _OFFSET
        new = rows[~self._made[rows]]
        if new.size:
            new = np.unique(new)
            # float64(count) * scale, as numpy multiplies int16 counts by a scale.
            values = (new - _OFFSET).astype(np.float64) * self.scale
            self._texts[new] = [repr(v) for v in values.tolist()]
            self._made[new] = True
        return self._texts[rows].tolist()


class CsvStream:
    """Append the samples of a run, in increasing sample index, to a canonical CSV.

    Parameters
    ----------
    path : path-like
        The CSV to create (it must not exist).
    header : RunHeader
        Sample rate and scale factors of the run.

    Attributes
    ----------
    rows : int
        Rows appended so far.
    next_index : int
        Smallest sample index the next :meth:`append` may start at.
    error : OSError or None
        The first failure to write (disk full, I/O error): later appends are dropped.
        The raw log still holds every byte, so the CSV can be made again from it.
    """

    def __init__(self, path: str | os.PathLike[str], header: RunHeader) -> None:
        self.path = Path(path)
        self._rate = header.sample_rate_Hz
        self._displacement = _Texts(header.displacement_scale_m)
        self._velocity = _Texts(header.velocity_scale_m_per_s)
        self._sha = hashlib.sha256()
        self._pending: list[bytes] = []
        self._pending_bytes = 0
        self.rows = 0
        self.next_index = 0
        self.error: OSError | None = None
        self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        self._queue((",".join(COLUMNS) + "\n").encode())

    def append(self, first: int, counts: NDArray[np.int16]) -> None:
        """Add the rows of samples ``first`` to ``first + len(counts) - 1``.

        Parameters
        ----------
        first : int
            Sample index of the first row since ARM (not below :attr:`next_index`).
        counts : ndarray of int16, shape (n, 2)
            Raw counts: displacement, velocity.

        Raises
        ------
        ValueError
            If ``first`` is below :attr:`next_index` (rows must be in order).
        """
        if first < self.next_index:
            raise ValueError(f"first: sample {first} is before sample {self.next_index}")
        n = len(counts)
        self.next_index = first + n
        self.rows += n
        if self.error is not None or n == 0:
            return
        time = (np.arange(first, first + n, dtype=np.int64) / self._rate).tolist()
        disp = self._displacement(counts[:, 0])
        vel = self._velocity(counts[:, 1])
        text = "".join([f"{t!r},{d},{v}\n" for t, d, v in zip(time, disp, vel, strict=True)])
        self._queue(text.encode())

    def _queue(self, data: bytes) -> None:
        self._pending.append(data)
        self._pending_bytes += len(data)
        if self._pending_bytes >= BUFFER_BYTES:
            self.flush()

    def flush(self) -> None:
        """Write the buffered rows to the file (a failure is kept in :attr:`error`)."""
        data = b"".join(self._pending)
        self._pending.clear()
        self._pending_bytes = 0
        if self.error is not None or self._fd is None or not data:
            return
        view = memoryview(data)
        try:
            while view:
                written = os.write(self._fd, view)
                self._sha.update(view[:written])
                view = view[written:]
        except OSError as exc:
            self.error = exc

    def close(self) -> str:
        """Write what is left, sync to disk, close; return the file's SHA-256.

        Raises
        ------
        OSError
            If any write, the sync or the close failed.
        """
        if self.rows == 0:
            self._queue(b"\n")  # as write_csv: the header, then an empty body line
        self.flush()
        fd, self._fd = self._fd, None
        if fd is not None:
            try:
                if self.error is None:
                    os.fsync(fd)
            except OSError as exc:
                self.error = exc
            finally:
                os.close(fd)
        if self.error is not None:
            raise self.error
        return self._sha.hexdigest()

    def abort(self) -> None:
        """Close without writing what is buffered (the file is left as it is)."""
        self._pending.clear()
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)


class StagedRun:
    """A temporary directory in the run folder, with the run's CSV being written into it.

    The run files are made in it and moved into place with :func:`os.replace` (same
    file system), so a reader never sees half a run; :meth:`discard` removes it.

    Parameters
    ----------
    out_dir : path-like
        The run folder.
    stem : str
        The run id (file stem).
    header : RunHeader
        Sample rate and scale factors of the run.

    Raises
    ------
    OSError
        If the directory or the CSV cannot be created.
    """

    def __init__(self, out_dir: str | os.PathLike[str], stem: str, header: RunHeader) -> None:
        prefix = f".{stem}{STAGING_MARK}"
        self.directory = Path(tempfile.mkdtemp(prefix=prefix, dir=out_dir))
        try:
            self.csv = CsvStream(self.directory / f"{stem}.csv", header)
        except BaseException:
            shutil.rmtree(self.directory, ignore_errors=True)
            raise

    def discard(self) -> None:
        """Close the CSV and remove the directory with everything in it."""
        self.csv.abort()
        shutil.rmtree(self.directory, ignore_errors=True)


def is_staging_of(path: Path, run_id: str) -> bool:
    """True if ``path`` is a staging directory of ``run_id`` (not of another run id).

    Its name is ``.<run_id>.staging-`` and the eight random characters of
    :func:`tempfile.mkdtemp`, so the run ``r`` never claims the staging of ``r.2``.
    """
    pattern = re.escape(f".{run_id}{STAGING_MARK}") + r"[a-z0-9_]{8}"
    return re.fullmatch(pattern, path.name) is not None and path.is_dir()
