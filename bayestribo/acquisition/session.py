"""The host side of one acquisition: identify, configure, arm, release, stream, write.

:func:`acquire_run` talks to a device speaking the protocol of ``docs/protocol.md``
on any port URL, appends every byte received to the raw log, and writes the run
when it ends, completely or not:

* a fault before the run header (no port, no answer, header that does not parse)
  raises the package's own error; the raw log keeps the bytes received;
* a fault during the run (stall, disconnect, Ctrl-C) ends the run: everything
  received is written as an incomplete run with the fault and the gaps in its
  metadata, and the result says why.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from bayestribo import __version__
from bayestribo.acquisition.assembly import AssembledRun, RunAssembler
from bayestribo.acquisition.csvstream import StagedRun
from bayestribo.acquisition.faults import (
    AcquisitionTimeout,
    DeviceError,
    DuplicateRunError,
    HeaderError,
    StorageError,
)
from bayestribo.acquisition.frameindex import BytesSource, FileSource
from bayestribo.acquisition.logger import (
    OperatorInputs,
    RawLog,
    RunFiles,
    check_run_id,
    claim_raw_log,
    make_run_id,
    run_metadata,
    utc_now,
    write_json_atomic,
    write_run_files,
)
from bayestribo.acquisition.port import DEFAULT_BAUDRATE, Link, open_port
from bayestribo.acquisition.protocol import MAX_FRAME_LENGTH, FrameParser, FrameType, RunHeader
from bayestribo.errors import AcquisitionError

__all__ = ["AcquisitionResult", "Progress", "acquire_run", "finish_run"]


class Progress(NamedTuple):
    """Progress of a streaming run, passed to the progress callback."""

    samples: int
    frames: int
    bytes_received: int
    discarded_bytes: int
    elapsed_s: float
    sample_rate_Hz: float


@dataclass(frozen=True)
class AcquisitionResult:
    """What an acquisition (or a recovery) produced.

    Attributes
    ----------
    run_id : str
        Run id and file stem.
    files : RunFiles
        The written files and their SHA-256.
    run : AssembledRun
        The samples and the report.
    metadata : dict
        The sidecar content.
    fault : str or None
        Why the run ended early, if it did.
    interrupted : bool
        True when the operator pressed Ctrl-C.
    catalog_id : int or None
        Id of the run in the results catalog, if registered.
    """

    run_id: str
    files: RunFiles
    run: AssembledRun
    metadata: dict[str, Any]
    fault: str | None
    interrupted: bool = False
    catalog_id: int | None = None

    @property
    def complete(self) -> bool:
        """True when every frame and sample of the run arrived."""
        return self.run.complete


class _DeferredInterrupt:
    """Turn Ctrl-C into a flag checked at safe points (main thread only).

    A KeyboardInterrupt raised between reading bytes from the port and appending them
    to the raw log would lose them; with the flag, the loop stops between two reads.
    """

    def __init__(self) -> None:
        self.pending = False
        self._previous: Any = None
        self._installed = False

    def __enter__(self) -> _DeferredInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._installed = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False

    def _handle(self, signum: int, frame: object) -> None:
        self.pending = True

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed since the last check."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt


class _Conversation:
    """Pump bytes from the link into the raw log, the parser and the assembler.

    When the run header arrives, the run's CSV is started in a staging directory of
    ``out`` and every DATA frame that extends the run in order is written to it as it
    is accepted: at the END frame only the last rows and the sidecar are left to write.
    """

    def __init__(
        self,
        link: Link,
        raw: RawLog,
        timeout_s: float,
        interrupt: _DeferredInterrupt,
        *,
        out: Path,
        run_id: str,
    ) -> None:
        self.link = link
        self.raw = raw
        self.timeout_s = timeout_s
        self.interrupt = interrupt
        self.out = out
        self.run_id = run_id
        self.staged: StagedRun | None = None
        self.parser = FrameParser()
        self.assembler = RunAssembler(FileSource(raw.path), sink=None)
        self.assembler.on_header = self._start_csv
        self.last_byte = time.monotonic()
        self.last_frame = self.last_byte
        self.bytes_at_last_frame = 0

    def _start_csv(self, header: RunHeader) -> None:
        try:
            self.staged = StagedRun(self.out, self.run_id, header)
        except OSError:
            return  # the CSV is written from the raw log at the end (or the disk fails)
        self.assembler.sink = self.staged.csv.append

    def discard_staged(self) -> None:
        """Remove the CSV being written (no run files are written after all)."""
        if self.staged is not None:
            self.staged.discard()
            self.staged = None

    def pump_once(self) -> int:
        self.interrupt.check()
        data = self.link.read_available()
        if data:
            # logged before anything else can raise (a failed sync in tick below): a
            # chunk read from the link and not logged would leave a hole in the raw log
            self.raw.write(data)
            self.last_byte = time.monotonic()
            frames = 0
            for frame in self.parser.feed(data):
                self.assembler.add(frame)
                frames += 1
            if frames:
                self.last_frame = self.last_byte
                self.bytes_at_last_frame = self.raw.bytes_written
        self.raw.tick()
        return len(data)

    def wait_for(self, done: Callable[[], bool], what: str, timeout_s: float | None = None) -> None:
        """Pump until ``done()``; raise :class:`AcquisitionTimeout` after ``timeout_s``.

        The limit counts from the call, not from the last byte: a device that streams
        but never sends the awaited frame (a run header lost to corruption) times out.
        """
        limit = self.timeout_s if timeout_s is None else timeout_s
        start = time.monotonic()
        while not done():
            self.pump_once()
            if time.monotonic() - start > limit:
                raise AcquisitionTimeout(
                    f"{self.link.url}: no {what} within {limit:g} s "
                    f"({self.raw.bytes_written} bytes received in all, "
                    f"{self.parser.frames_parsed} valid frames)"
                )

    def command(self, line: str, answer: str) -> None:
        """Send a configuration command and wait for its ACK (ERROR raises)."""
        before = len(self.assembler.messages)
        self.link.write_line(line)
        self.wait_for(lambda: len(self.assembler.messages) > before, f"{answer} to {line!r}")
        reply = self.assembler.messages[before]
        if reply.startswith("ERROR"):
            raise DeviceError(f"{self.link.url}: device refused {line!r}: {reply[6:]}")


def _session_path(raw_path: Path) -> Path:
    return raw_path.with_name(raw_path.stem + ".session.json")


def acquire_run(
    port: str,
    out_dir: str | os.PathLike[str],
    inputs: OperatorInputs,
    *,
    baudrate: int = DEFAULT_BAUDRATE,
    timeout_s: float = 2.0,
    pretrigger_s: float = 0.05,
    sample_rate_Hz: float | None = None,
    samples_per_frame: int | None = None,
    duration_s: float | None = None,
    run_id: str | None = None,
    progress: Callable[[Progress], None] | None = None,
    progress_interval_s: float = 0.25,
    catalog: str | os.PathLike[str] | None = None,
) -> AcquisitionResult:
    """Acquire one run from a device on ``port`` and write it to ``out_dir``.

    Parameters
    ----------
    port : str
        Device path or pyserial URL (``socket://host:port``, ``loop://``...).
    out_dir : path-like
        Directory of the raw log, the session file and the run files.
    inputs : OperatorInputs
        Load, lubricant, repeat, water fraction, temperature, notes, rig constants.
    baudrate : int
        Serial baud rate [bit/s].
    timeout_s : float
        Longest silence accepted from the device, for answers and while streaming [s].
    pretrigger_s : float
        Time streamed after ARM before FIRE releases the pin [s].
    sample_rate_Hz, samples_per_frame, duration_s : optional
        Configuration sent before ARM (``RATE``, ``SPF``, ``DUR``); the device's
        own settings otherwise.
    run_id : str, optional
        Run id and file stem; from time, lubricant, load and repeat by default.
    progress : callable, optional
        Called with a :class:`Progress` about every ``progress_interval_s`` seconds.
    progress_interval_s : float
        Interval of the progress calls [s].
    catalog : path-like, optional
        SQLite results catalog in which to register the run.

    Returns
    -------
    AcquisitionResult

    Raises
    ------
    RunInUseError
        If ``run_id`` is given and its raw log exists (another logger's run). A run id
        made up from the time is suffixed (``_2``, ``_3``, …) instead, so two loggers
        started in the same second into one folder both record.
    AcquisitionError
        If ``run_id`` is not a valid run id or the folder cannot be created.
    PortNotFoundError, PortBusyError
        If the port cannot be opened.
    AcquisitionTimeout
        If the device does not answer before the run header.
    HeaderError
        If the run header does not parse.
    DeviceError
        If the device refuses a configuration command.
    KeyboardInterrupt
        If Ctrl-C is pressed before the run header (after it, the run is written).
    """
    out = Path(out_dir)
    started = utc_now()
    if catalog is not None:
        # Imported now, not at the END frame: the package behind it takes a second.
        import bayestribo.campaign.catalog  # noqa: F401
    generated = run_id is None
    run_id = check_run_id(
        make_run_id(inputs) if generated else run_id,
        "run id made from the inputs" if generated else "--run-id",
    )
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AcquisitionError(f"{out}: cannot create the output directory ({exc})") from None
    run_id, raw_path = claim_raw_log(out, run_id, suffix_if_taken=generated)
    try:
        link = open_port(port, baudrate=baudrate)
    except BaseException:
        # Nothing was received: give the run id back and leave no trace.
        raw_path.unlink(missing_ok=True)
        if created:
            with contextlib.suppress(OSError):
                out.rmdir()
        raise
    with _DeferredInterrupt() as interrupt:
        return _acquire(
            link,
            out,
            inputs,
            raw_path=raw_path,
            run_id=run_id,
            started=started,
            interrupt=interrupt,
            timeout_s=timeout_s,
            pretrigger_s=pretrigger_s,
            config=(
                ("RATE", sample_rate_Hz),
                ("SPF", samples_per_frame),
                ("DUR", duration_s),
            ),
            progress=progress,
            progress_interval_s=progress_interval_s,
            catalog=catalog,
        )


def _acquire(
    link: Link,
    out: Path,
    inputs: OperatorInputs,
    *,
    raw_path: Path,
    run_id: str,
    started: str,
    interrupt: _DeferredInterrupt,
    timeout_s: float,
    pretrigger_s: float,
    config: tuple[tuple[str, float | None], ...],
    progress: Callable[[Progress], None] | None,
    progress_interval_s: float,
    catalog: str | os.PathLike[str] | None,
) -> AcquisitionResult:
    port = link.url
    try:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise AcquisitionError(f"{out}: cannot create the output directory ({exc})") from None
        try:
            write_json_atomic(
                _session_path(raw_path),
                {
                    "run_id": run_id,
                    "port": port,
                    "host_time_start_utc": started,
                    "package_version": __version__,
                    "operator_inputs": dict(inputs),
                },
            )
        except OSError as exc:
            raw_path.unlink(missing_ok=True)  # nothing was received: leave no trace
            raise StorageError(
                f"{_session_path(raw_path)}: cannot write the session file "
                f"({exc.strerror or exc}); nothing was received, so there is nothing "
                "for `bayestribo acquire --recover` to rebuild: free space and start the "
                "run again"
            ) from None
        raw = RawLog(raw_path, background=True)
        talk = _Conversation(link, raw, timeout_s, interrupt, out=out, run_id=run_id)
        try:
            talk.link.write_line("ID?")
            talk.wait_for(lambda: talk.assembler.ident is not None, "answer to 'ID?'")
            for name, value in config:
                if value is not None:
                    talk.command(f"{name} {value:g}", "ACK")
            talk.link.write_line("ARM")
            talk.wait_for(lambda: talk.assembler.started, "run header after 'ARM'")
        except BaseException as exc:
            _stop_quietly(talk)
            talk.discard_staged()
            raw.close()
            if isinstance(exc, AcquisitionTimeout) and not talk.assembler.started:
                _refused_header(raw_path)  # a header too long for the live parser?
            if isinstance(exc, AcquisitionError) and not isinstance(exc, StorageError):
                exc.args = (f"{exc}; raw log kept in {raw_path}",)
            raise
        fault: str | None = None
        interrupted = False
        try:
            _stream(talk, pretrigger_s, progress, progress_interval_s)
        except AcquisitionTimeout as exc:
            fault = str(exc)
            _stop_quietly(talk)  # a stalled device may come back: end its run
        except StorageError:
            # The disk cannot take more: end the device's run, keep the raw log as it
            # is (every byte that could be written), and write no run files there.
            _stop_quietly(talk)
            talk.discard_staged()
            raise
        except AcquisitionError as exc:
            fault = str(exc)
        except KeyboardInterrupt:
            interrupted = True
            fault = "interrupted by the operator (Ctrl-C)"
            _stop_quietly(talk)
        except BaseException:
            talk.discard_staged()
            raise
        finally:
            raw.close()
    finally:
        link.close()
    # Every byte received went to the raw log, then to the parser: the run is what a
    # recovery from the raw log gives, and its samples are read back from there.
    try:
        for frame in talk.parser.finish():
            talk.assembler.add(frame)
        if fault is None and not talk.assembler.ended:
            fault = "stream ended without an END frame"
        run = talk.assembler.build(talk.parser, fault=fault)
    except BaseException:
        talk.discard_staged()
        raise
    staged = talk.staged if talk.assembler.in_order else None
    if staged is None:
        talk.discard_staged()  # a frame came out of order: the CSV is made from the raw log
    return finish_run(
        run,
        inputs,
        out_dir=out,
        run_id=run_id,
        raw_log=raw_path,
        port=port,
        started_utc=started,
        catalog=catalog,
        fault=fault,
        interrupted=interrupted,
        staged=staged,
        raw_sha256=raw.sha256(),
    )


def _refused_header(raw_path: Path) -> None:
    """Raise the :class:`HeaderError` of a run header the live parser could not see.

    The live parser bounds every frame by
    :data:`~bayestribo.acquisition.protocol.MAX_PAYLOAD`, so that a false candidate never
    holds back the stream for long; a run header with a range label of more than 4056
    bytes is longer and never reaches it. The raw log is parsed again without that
    bound: a run header found there is refused with its own reason (its label's size).
    """
    parser = FrameParser(max_header_payload=MAX_FRAME_LENGTH)
    data = raw_path.read_bytes()  # before the run header: a few bytes
    assembler = RunAssembler(BytesSource(data))
    try:
        for frame in parser.feed(data) + parser.finish():
            if frame.type == FrameType.HEADER:
                assembler.add(frame)
    except HeaderError as exc:  # before OSError: the package's errors are OSErrors too
        exc.args = (f"{exc}; raw log kept in {raw_path}",)
        raise exc from None
    except OSError:
        return


def _stream(
    talk: _Conversation,
    pretrigger_s: float,
    progress: Callable[[Progress], None] | None,
    interval_s: float,
) -> None:
    start = time.monotonic()
    fired = False
    next_report = start
    assert talk.assembler.header is not None
    rate = talk.assembler.header.sample_rate_Hz
    while not talk.assembler.ended:
        now = time.monotonic()
        if not fired and now - start >= pretrigger_s:
            talk.link.write_line("FIRE")
            fired = True
        talk.pump_once()
        now = time.monotonic()
        if now - talk.last_byte > talk.timeout_s:
            raise AcquisitionTimeout(
                f"{talk.link.url}: device stopped sending for {talk.timeout_s:g} s "
                f"in the middle of the run"
            )
        if now - talk.last_frame > talk.timeout_s:
            # bytes arrive but none makes a frame: the silence timeout counts from the
            # last valid frame, not the last byte
            noise = talk.raw.bytes_written - talk.bytes_at_last_frame
            raise AcquisitionTimeout(
                f"{talk.link.url}: no valid frame for {talk.timeout_s:g} s in the middle of "
                f"the run ({noise} bytes since the last one, none of them a frame: check the "
                "baud rate and the device's firmware)"
            )
        if progress is not None and now >= next_report:
            next_report = now + interval_s
            progress(
                Progress(
                    samples=talk.assembler.samples_received,
                    frames=talk.assembler.frames_received,
                    bytes_received=talk.raw.bytes_written,
                    discarded_bytes=talk.parser.discarded_bytes,
                    elapsed_s=now - start,
                    sample_rate_Hz=rate,
                )
            )


def _stop_quietly(talk: _Conversation) -> None:
    """Ask the device to stop and collect what it still sends (best effort, 0.3 s)."""
    try:
        talk.link.write_line("STOP")
        deadline = time.monotonic() + 0.3
        while time.monotonic() < deadline and not talk.assembler.ended:
            talk.pump_once()
    except (AcquisitionError, KeyboardInterrupt):
        pass


def _check_catalog(
    catalog: str | os.PathLike[str], run_id: str, sha256: str, raw_log: Path
) -> None:
    """Refuse a run the catalog would refuse, before any of its run files is written.

    Raises
    ------
    DuplicateRunError
        If the catalog holds a run with the same samples under another run id, or
        this run id with other samples.
    """
    from bayestribo.campaign.catalog import find_run

    same_id = find_run(catalog, run_id=run_id)
    if same_id is not None and same_id.sha256 != sha256:
        raise DuplicateRunError(
            f"{catalog}: run id {run_id!r} is catalogued already (id {same_id.id}) with "
            f"other samples; run files not written, raw log kept in {raw_log}"
        )
    same_samples = find_run(catalog, sha256=sha256)
    if same_samples is not None and same_samples.run_id != run_id:
        raise DuplicateRunError(
            f"{catalog}: the samples of run {run_id!r} are exactly those of run "
            f"{same_samples.run_id!r} (catalog id {same_samples.id}): a repeat is a new "
            f"recording, not the same one again; run files not written, raw log kept in "
            f"{raw_log}"
        )


def finish_run(
    run: AssembledRun,
    inputs: Mapping[str, Any],
    *,
    out_dir: Path,
    run_id: str,
    raw_log: Path,
    port: str | None,
    started_utc: str | None,
    catalog: str | os.PathLike[str] | None,
    fault: str | None,
    interrupted: bool = False,
    recovered: bool = False,
    staged: StagedRun | None = None,
    raw_sha256: str | None = None,
) -> AcquisitionResult:
    """Write an assembled run atomically and register it in the catalog.

    ``staged`` is the run's CSV written while streaming, if any (see
    :func:`~bayestribo.acquisition.logger.write_run_files`); ``raw_sha256`` the raw
    log's digest if known.

    Raises
    ------
    DuplicateRunError
        If the catalog holds the same samples under another run id (or this run id
        with other samples): no run file is written, the raw log is kept.
    StorageError
        If the run files cannot be written, or the catalog cannot be updated (disk
        full, I/O error); the message names the ``--recover`` command.
    """
    try:
        metadata = run_metadata(
            run,
            inputs,
            run_id=run_id,
            raw_log=raw_log,
            port=port,
            started_utc=started_utc,
            ended_utc=utc_now(),
            recovered=recovered,
            raw_sha256=raw_sha256,
        )
    except BaseException:
        if staged is not None:
            staged.discard()
        raise
    csv_name = f"{run_id}.csv"

    def check_catalog(digests: dict[str, str]) -> None:
        if catalog is not None:
            _check_catalog(catalog, run_id, digests[csv_name], raw_log)

    try:
        files = write_run_files(
            out_dir,
            run_id,
            run,
            metadata,
            raw_log,
            before_move=check_catalog,
            staged=staged,
            raw_sha256=raw_sha256,
        )
    except AcquisitionError:  # an OSError too: the catalog's refusal, not the disk's
        raise
    except OSError as exc:
        raise StorageError(
            f"{out_dir}: cannot write the run files of {run_id} ({exc.strerror or exc}); "
            f"the raw log {raw_log} holds every byte received: free space, then "
            f"`bayestribo acquire --recover {raw_log}`"
        ) from None
    catalog_id = None
    if catalog is not None:
        import sqlite3

        from bayestribo.campaign.catalog import register_run

        try:
            catalog_id = register_run(
                catalog,
                path=files.csv,
                sha256=files.digests[files.csv.name],
                metadata={**metadata, "files_sha256": files.digests},
            )
        except sqlite3.Error as exc:
            raise StorageError(
                f"{catalog}: cannot register run {run_id} ({exc}); its run files are "
                f"written: free space, then `bayestribo acquire --recover {raw_log} "
                "--overwrite` registers it"
            ) from None
    return AcquisitionResult(
        run_id=run_id,
        files=files,
        run=run,
        metadata=metadata,
        fault=fault,
        interrupted=interrupted,
        catalog_id=catalog_id,
    )
