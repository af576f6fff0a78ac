"""Logging that loses nothing: the append-only raw log and the atomic run files.

Every byte received is appended to the raw log as it arrives (written straight to
the operating system, so it survives the death of the process, and synced to disk
at least every :data:`SYNC_INTERVAL_S`). When the run ends, for whatever reason, the
run is written in the canonical format (CSV ``time_s, displacement_m,
velocity_m_per_s`` and a JSON sidecar of the same stem) into a staging directory in
the run folder and moved into place with :func:`os.replace`, so a reader never sees
half a run. The live logger writes the CSV there while the run streams
(:class:`~bayestribo.acquisition.csvstream.StagedRun`), so little is left to do at the
end of a long run; otherwise it is written from the raw log a chunk at a time.
A ``<stem>.sha256`` manifest (``sha256sum -c`` format) lists the raw log and the run
files.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import platform
import re
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from bayestribo import __version__
from bayestribo._files import atomic_file, fsync_folder, write_text
from bayestribo.acquisition.assembly import AssembledRun
from bayestribo.acquisition.csvstream import StagedRun
from bayestribo.acquisition.faults import RunInUseError, StorageError
from bayestribo.errors import AcquisitionError
from bayestribo.io.run import check_metadata
from bayestribo.io.sidecar import RUN_ID_PATTERN, is_run_id, write_sidecar

__all__ = [
    "RUN_ID_PATTERN",
    "SYNC_INTERVAL_S",
    "OperatorInputs",
    "RawLog",
    "RunFiles",
    "check_run_id",
    "claim_raw_log",
    "make_run_id",
    "run_metadata",
    "sha256_file",
    "stage_run",
    "utc_now",
    "write_json_atomic",
    "write_run_files",
]

#: Sync interval of the raw log [s]; with the background thread's period of a quarter
#: of it, a received byte waits at most 0.625 s for ``fsync``.
SYNC_INTERVAL_S = 0.5


def utc_now() -> str:
    """Host time now, ISO 8601 in UTC with microseconds."""
    return datetime.now(UTC).isoformat(timespec="microseconds")


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes, hexadecimal."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


class RawLog:
    """Append-only log of every byte received, synced to disk at least once a second.

    Parameters
    ----------
    path : path-like
        The log file; created if absent, appended to otherwise (never truncated).
    sync_interval_s : float
        Longest time a written byte waits for ``fsync`` [s].
    background : bool
        Sync from a background thread, so the reading loop never waits for the disk
        (a slow ``fsync`` must not let the serial driver's buffer overflow). Without
        it, syncs happen in :meth:`write` and :meth:`tick`, which the caller must call
        often enough.

    Notes
    -----
    Bytes are handed to the operating system at once (``os.write`` on an ``O_APPEND``
    descriptor, no user-space buffer), so they survive the death of the process; the
    periodic ``fsync`` makes them survive a crash of the machine.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        sync_interval_s: float = SYNC_INTERVAL_S,
        *,
        background: bool = False,
    ) -> None:
        self.path = Path(path)
        try:
            self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        except OSError as exc:
            raise AcquisitionError(f"{self.path}: cannot open the raw log ({exc})") from None
        self.sync_interval_s = sync_interval_s
        self.bytes_written = 0
        self._sha = hashlib.sha256()  # of the bytes written, as they are written
        self.syncs = 0
        #: The first storage failure (disk full, I/O error), raised by every later
        #: :meth:`write`: a failure of the background sync is not lost.
        self.error: StorageError | None = None
        self._error_raised = False  # raised to the caller (not only seen by the thread)
        #: The failure of a write, after which nothing more may be appended.
        self._write_failed: StorageError | None = None
        self._dirty_since: float | None = None
        self._lock = threading.Lock()
        self._closing = threading.Event()
        self._thread: threading.Thread | None = None
        if background:
            self._thread = threading.Thread(
                target=self._sync_loop, name="raw-log-sync", daemon=True
            )
            self._thread.start()

    def write(self, data: bytes) -> None:
        """Append bytes (written to the OS immediately; synced per the interval)."""
        if self._fd is None:
            raise AcquisitionError(f"{self.path}: raw log already closed")
        if self._write_failed is not None:
            # bytes after a failed (perhaps partial) write would follow a hole: the log
            # must stay a prefix of the bytes received, so nothing more is appended
            self._error_raised = True
            raise self._write_failed
        failed_before = self.error  # a failed sync: keep what still can be written
        view = memoryview(data)
        try:
            while view:
                written = os.write(self._fd, view)
                self.bytes_written += written
                self._sha.update(view[:written])
                view = view[written:]
        except OSError as exc:
            self._write_failed = StorageError(
                f"{self.path}: cannot append to the raw log ({exc.strerror or exc}); "
                f"{len(view)} bytes just received are not logged, the "
                f"{self.bytes_written} before them are; free space, then "
                f"`bayestribo acquire --recover {self.path}`"
            )
            self.error = failed_before or self._write_failed
            self._error_raised = True
            raise self.error from None
        if failed_before is not None:
            self._error_raised = True
            raise failed_before
        if data:
            with self._lock:
                if self._dirty_since is None:
                    self._dirty_since = time.monotonic()
        if self._thread is None:
            self.tick()

    def sha256(self) -> str | None:
        """SHA-256 of the log's bytes (hexadecimal), if this logger wrote all of them.

        Computed as the bytes are written, so finishing a long run does not read the
        log again; None when the file holds more or fewer bytes than were written here.
        """
        try:
            size = self.path.stat().st_size
        except OSError:
            return None
        return self._sha.hexdigest() if size == self.bytes_written else None

    def tick(self) -> None:
        """Sync to disk if bytes have waited for the sync interval."""
        if (
            self._dirty_since is not None
            and time.monotonic() - self._dirty_since >= self.sync_interval_s
        ):
            self.sync()

    def sync(self) -> None:
        """Force the log to disk now."""
        with self._lock:  # never held during fsync: writes do not wait for the disk
            self._dirty_since = None  # bytes written from now on wait for the next sync
            fd = self._fd
        if fd is not None:
            try:
                os.fsync(fd)
            except OSError as exc:
                if exc.errno == errno.EINVAL:  # a device or pipe, nothing to sync
                    return
                self.error = self.error or StorageError(
                    f"{self.path}: cannot sync the raw log to disk ({exc.strerror or exc}); "
                    f"the {self.bytes_written} bytes received may not all be on disk; "
                    f"check the disk, then `bayestribo acquire --recover {self.path}`"
                )
                if threading.current_thread() is not self._thread:
                    self._error_raised = True
                raise self.error from None
            self.syncs += 1

    def _sync_loop(self) -> None:
        # Wake at a quarter of the interval: a byte waits at most 1.25 intervals. A
        # failed sync is kept in self.error and raised by the next write (the reading
        # loop's thread), never printed from this one.
        while not self._closing.wait(self.sync_interval_s / 4):
            try:
                self.tick()
            except StorageError:
                return

    def close(self) -> None:
        """Sync and close (idempotent).

        Raises
        ------
        StorageError
            If the final sync fails and no storage failure was raised before.
        """
        self._closing.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._fd is None:
            return
        raised_before = self._error_raised
        try:
            self.sync()
        except StorageError:
            pass  # kept in self.error
        finally:
            with self._lock:
                os.close(self._fd)
                self._fd = None
        if self.error is not None and not raised_before:
            self._error_raised = True
            raise self.error

    def __enter__(self) -> RawLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class OperatorInputs(dict[str, Any]):
    """The operator's inputs for a run (a plain dict with checked, canonical keys).

    Parameters
    ----------
    load_N : float
        Normal load N [N], >= 0.
    lubricant : str
        Lubricant name (e.g. ``"glycerol"``, ``"water"``, ``"dry"``).
    repeat : int
        Repeat number of this condition, >= 1.
    water_mass_fraction : float, optional
        Mass fraction of water in the lubricant, in [0, 1].
    temperature_C : float, optional
        Temperature [°C].
    notes : str
        Free text.
    mass_kg : float, optional
        Oscillating mass m [kg].
    natural_frequency_Hz : float, optional
        Natural frequency f [Hz].
    """

    def __init__(
        self,
        *,
        load_N: float,
        lubricant: str,
        repeat: int,
        water_mass_fraction: float | None = None,
        temperature_C: float | None = None,
        notes: str = "",
        mass_kg: float | None = None,
        natural_frequency_Hz: float | None = None,
    ) -> None:
        def check(name: str, value: float | None, lo: float, hi: float) -> float | None:
            if value is None:
                return None
            try:
                value = float(value)
            except (TypeError, ValueError, OverflowError):
                raise AcquisitionError(
                    f"{name}: expected a number in [{lo}, {hi}], got {type(value).__name__}"
                ) from None
            if not (lo <= value <= hi):
                raise AcquisitionError(f"{name}: {value!r} outside the range [{lo}, {hi}]")
            return value

        if not isinstance(lubricant, str) or not lubricant.strip():
            raise AcquisitionError(f"lubricant: expected a non-empty name, got {lubricant!r}")
        if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
            shown = repr(repeat) if isinstance(repeat, int | float | str) else type(repeat)
            raise AcquisitionError(f"repeat: expected an integer >= 1, got {str(shown)[:40]}")
        super().__init__(
            load_N=check("load_N", load_N, 0.0, 1e4),
            lubricant=lubricant.strip(),
            repeat=int(repeat),
            water_mass_fraction=check("water_mass_fraction", water_mass_fraction, 0.0, 1.0),
            temperature_C=check("temperature_C", temperature_C, -273.15, 1e4),
            notes=str(notes),
            mass_kg=check("mass_kg", mass_kg, 1e-9, 1e6),
            natural_frequency_Hz=check("natural_frequency_Hz", natural_frequency_Hz, 1e-6, 1e9),
        )


#: Longest lubricant part of a run id made by :func:`make_run_id` [characters]: the
#: whole id stays within the 128 characters of :data:`RUN_ID_PATTERN`.
_MAX_LUBRICANT_CHARS = 64


def make_run_id(inputs: Mapping[str, Any], when: datetime | None = None) -> str:
    """A file-name-safe run id: UTC time, lubricant, load and repeat.

    Example: ``20261122T061500Z_glycerol_N0.31_r2``.
    """
    when = when or datetime.now(UTC)
    lubricant = re.sub(r"[^A-Za-z0-9.-]+", "-", str(inputs["lubricant"])).strip("-")
    lubricant = re.sub(r"\.{2,}", ".", lubricant)[:_MAX_LUBRICANT_CHARS].strip("-.") or "x"
    return f"{when:%Y%m%dT%H%M%SZ}_{lubricant}_N{inputs['load_N']:g}_r{inputs['repeat']}"


#: Suffixes tried when a generated run id is taken (``<id>_2`` … ``<id>_99``).
_MAX_SUFFIX = 99


def check_run_id(run_id: object, where: str = "run_id") -> str:
    """A run id that is safe as a file name, or an :class:`AcquisitionError`.

    Parameters
    ----------
    run_id : object
        The run id (from the command line or read from a session file).
    where : str
        What to name in the message (the option or the file).
    """
    if not is_run_id(run_id):
        raise AcquisitionError(
            f"{where}: {run_id!r} is not a run id; expected 1 to 128 letters, digits, "
            "'.', '_', '+' or '-', starting with a letter or digit (no path separators)"
        )
    return run_id


def claim_raw_log(
    out_dir: str | os.PathLike[str], run_id: str, *, suffix_if_taken: bool
) -> tuple[str, Path]:
    """Create ``<out_dir>/<run_id>.raw`` exclusively: the run belongs to this logger.

    The file is created with ``O_CREAT | O_EXCL``, atomic on a local file system, so
    two loggers started on one folder never append to one raw log.

    Parameters
    ----------
    out_dir : path-like
        The run folder (must exist).
    run_id : str
        The wanted run id.
    suffix_if_taken : bool
        When the run id is taken, try ``<run_id>_2``, ``<run_id>_3``, … (for run ids
        the logger made up from the time, which two loggers may make in the same
        second); otherwise refuse.

    Returns
    -------
    run_id, path
        The run id claimed and its (empty) raw log.

    Raises
    ------
    RunInUseError
        If the run id is taken (and may not be suffixed), or all suffixes are.
    AcquisitionError
        If the file cannot be created for another reason.
    """
    out = Path(out_dir)
    for k in range(1, _MAX_SUFFIX + 1):
        candidate = run_id if k == 1 else f"{run_id}_{k}"
        path = out / f"{candidate}.raw"
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            if not suffix_if_taken:
                raise RunInUseError(
                    f"{path}: run {candidate!r} exists already (another logger may be "
                    "recording it); give another --run-id"
                ) from None
            continue
        except OSError as exc:
            raise AcquisitionError(f"{path}: cannot create the raw log ({exc})") from None
        os.close(fd)
        return candidate, path
    raise RunInUseError(f"{out}: runs {run_id!r} to {run_id}_{_MAX_SUFFIX} exist already")


def write_json_atomic(path: str | os.PathLike[str], data: Mapping[str, Any]) -> None:
    """Write JSON whole or not at all (:func:`bayestribo._files.atomic_file`)."""
    with atomic_file(path) as fh:
        json.dump(data, fh, indent=2, sort_keys=False, allow_nan=False)
        fh.write("\n")


def run_metadata(
    run: AssembledRun,
    inputs: Mapping[str, Any],
    *,
    run_id: str,
    raw_log: Path,
    port: str | None,
    started_utc: str | None,
    ended_utc: str | None,
    recovered: bool = False,
    raw_sha256: str | None = None,
) -> dict[str, Any]:
    """The sidecar metadata of a run: canonical keys, operator inputs, device header, host.

    Parameters
    ----------
    run : AssembledRun
        The assembled samples and their report.
    inputs : mapping
        The operator's inputs (:class:`OperatorInputs` keys).
    run_id : str
        The run's id (also the file stem).
    raw_log : Path
        The raw log the run was parsed from (its SHA-256 is recorded).
    port, started_utc, ended_utc : str or None
        Port URL and host times of the acquisition.
    recovered : bool
        True when rebuilt from a raw log after a crash.
    raw_sha256 : str, optional
        SHA-256 of the raw log if known (:meth:`RawLog.sha256`); computed otherwise.
    """
    header = run.report["device_header"]
    assert isinstance(header, dict)
    return {
        "run_id": run_id,
        "load_N": inputs.get("load_N"),
        "mass_kg": inputs.get("mass_kg"),
        "natural_frequency_Hz": inputs.get("natural_frequency_Hz"),
        "displacement_resolution_m": header["displacement_scale_m_per_count"],
        "velocity_resolution_m_per_s": header["velocity_scale_m_per_s_per_count"],
        "displacement_range_m": header["displacement_range_m"],
        "velocity_range_m_per_s": header["velocity_range_m_per_s"],
        "length_unit": "m",
        "sample_rate_Hz": header["sample_rate_Hz"],
        "lubricant": inputs.get("lubricant"),
        "water_mass_fraction": inputs.get("water_mass_fraction"),
        "repeat": inputs.get("repeat"),
        "temperature_C": inputs.get("temperature_C"),
        "notes": inputs.get("notes", ""),
        "complete": run.complete,
        "fault": run.report["fault"],
        "gaps": run.report["gaps"],
        "samples_missing": run.report["samples_missing"],
        "acquisition": {
            **run.report,
            "port": port,
            "host": platform.node(),
            "host_time_start_utc": started_utc,
            "host_time_end_utc": ended_utc,
            "host_time_written_utc": utc_now(),
            "package": "bayestribo",
            "package_version": __version__,
            "raw_log": raw_log.name,
            "raw_log_bytes": raw_log.stat().st_size,
            "raw_log_sha256": raw_sha256 or sha256_file(raw_log),
            "recovered_from_raw_log": recovered,
        },
    }


@dataclass(frozen=True)
class RunFiles:
    """Paths of a written run and the SHA-256 of each file, by file name."""

    csv: Path
    json: Path
    raw: Path
    manifest: Path
    digests: dict[str, str]


def stage_run(out_dir: Path, stem: str, run: AssembledRun) -> StagedRun:
    """Write the canonical CSV of a run, a chunk at a time, into a new staging directory.

    Rows are the received samples only, at their own times: gaps show as jumps in
    ``time_s`` (which :func:`bayestribo.io.read_run` refuses unless ``validate=False``)
    and are listed in the sidecar, never filled.

    Raises
    ------
    OSError
        If the CSV cannot be written; no staging directory is left then.
    """
    staged = StagedRun(out_dir, stem, run.header)
    try:
        for first, counts in run.chunks():
            staged.csv.append(first, counts)
            if staged.csv.error is not None:
                raise staged.csv.error
    except BaseException:
        staged.discard()
        raise
    return staged


def write_run_files(
    out_dir: str | os.PathLike[str],
    stem: str,
    run: AssembledRun,
    metadata: Mapping[str, Any],
    raw_log: Path,
    *,
    before_move: Callable[[dict[str, str]], None] | None = None,
    staged: StagedRun | None = None,
    raw_sha256: str | None = None,
) -> RunFiles:
    """Write a run atomically: staging directory in ``out_dir``, fsync, :func:`os.replace`.

    Parameters
    ----------
    out_dir : path-like
        Directory of the run files (same file system as the staging directory).
    stem : str
        File stem (the run id).
    run : AssembledRun
        The samples.
    metadata : mapping
        The sidecar content (:func:`run_metadata`).
    raw_log : Path
        The raw log, listed in the ``.sha256`` manifest.
    before_move : callable, optional
        Called with the SHA-256 of each file (by file name) once they are written in
        the staging directory, before any is moved into place; if it raises, no run
        file is written (e.g. a run the catalog would refuse).
    staged : StagedRun, optional
        The run's CSV written while streaming (:class:`~.csvstream.StagedRun`), used
        when it holds exactly the run's samples; otherwise (or if not given) the CSV is
        written from ``run``, a chunk at a time. Removed in every case.
    raw_sha256 : str, optional
        SHA-256 of the raw log if known; computed otherwise.

    Returns
    -------
    RunFiles
        Paths of the CSV, JSON, raw log and manifest, and their digests.

    Raises
    ------
    OSError
        If a file cannot be written (disk full, I/O error); no run file is moved into
        place then.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        whole = staged is not None and staged.csv.rows == run.n_samples
        if staged is not None and (staged.csv.error is not None or not whole):
            staged.discard()
            staged = None
        if staged is None:
            staged = stage_run(out, stem, run)
    except BaseException:
        if staged is not None:
            staged.discard()
        raise
    tmp = staged.directory
    try:
        csv_tmp = staged.csv.path
        digests = {csv_tmp.name: staged.csv.close()}
        json_tmp = write_sidecar(
            check_metadata(metadata),
            tmp / f"{stem}.json",
            data={"samples": run.n_samples, "sha256": digests[csv_tmp.name]},
        )
        digests[json_tmp.name] = sha256_file(json_tmp)
        digests[raw_log.name] = raw_sha256 or sha256_file(raw_log)
        manifest_tmp = tmp / f"{stem}.sha256"
        # each written whole and fsync-ed (bayestribo._files)
        write_text(manifest_tmp, "".join(f"{digest}  {name}\n" for name, digest in digests.items()))
        if before_move is not None:
            before_move(dict(digests))
        for path in (csv_tmp, json_tmp, manifest_tmp):
            os.replace(path, out / path.name)
    finally:
        staged.discard()
    _fsync_dir(out)
    return RunFiles(
        csv=out / csv_tmp.name,
        json=out / json_tmp.name,
        raw=raw_log,
        manifest=out / manifest_tmp.name,
        digests=digests,
    )


def _fsync_dir(directory: Path) -> None:
    fsync_folder(directory)
