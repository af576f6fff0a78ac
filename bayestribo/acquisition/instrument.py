"""A simulated acquisition board that speaks the protocol, with fault injection.

The instrument runs in a background thread on a POSIX pseudo-terminal (the host opens
its device path like a USB serial port) or on a localhost TCP socket (the host opens
``socket://127.0.0.1:PORT``). It streams the free decay of the exact model
(:func:`bayestribo.model.exact_response`, Rigaud et al. 2010, Eq. 12-16) for chosen
parameters, quantised to 16-bit counts, and can drop, corrupt, precede with garbage or
stall chosen DATA frames, send a header that does not parse, stay silent, or
disconnect after a number of frames.

It records every byte it writes (:attr:`SimulatedInstrument.sent`) and every DATA
frame it produced (:attr:`SimulatedInstrument.frames`), so tests can check that the
host kept everything.
"""

from __future__ import annotations

import fcntl
import math
import os
import select
import socket
import struct
import termios
import threading
import time
import tty
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.protocol import (
    FrameType,
    RunHeader,
    encode_data,
    encode_end,
    encode_frame,
    encode_release,
)

__all__ = ["FaultPlan", "SentFrame", "SimulatedInstrument", "SimulationConfig"]

#: Longest time the simulated device streams before FIRE before it ends the run [s].
MAX_PRETRIGGER_S = 10.0
#: Longest command line, without its line ending [characters].
MAX_LINE = 32
#: Configuration commands (refused during a run).
_CONFIGURE = ("RATE", "SPF", "DUR")


@dataclass(frozen=True)
class SimulationConfig:
    """Physics and acquisition settings of the simulated rig.

    Parameters
    ----------
    zeta : float
        Equivalent viscous damping ratio ζ [-] (Eq. 9).
    mu_k, mu_s : float
        Kinetic and static friction coefficients [-] (Eq. 10-11); ``mu_s`` defaults
        to ``mu_k``.
    x0_m : float
        Displacement at release [m] (held by the electromagnet before FIRE).
    load_N, mass_kg, natural_frequency_Hz : float
        Rig: load N [N], mass m [kg], natural frequency f [Hz] (k = m(2πf)², ℓ = N/k).
    sample_rate_Hz : float
        Sample rate [Hz].
    duration_s : float
        Recording time after release [s].
    samples_per_frame : int
        Sample pairs per DATA frame.
    displacement_range_m, velocity_range_m_per_s : float
        Vibrometer full-scale ranges (±) [m], [m/s]; one count is range / 32767.
    noise_counts : float
        Standard deviation of Gaussian noise added before quantisation [counts].
    seed : int
        Seed of the noise and of injected garbage.
    hold_s : float
        Least time the magnet holds the pin after ARM [s]: a FIRE that comes earlier
        releases it at the first frame from that time on, so that the recording does
        not depend on when the host's FIRE arrives (0: at the frame after FIRE, as a
        board does).
    """

    zeta: float = 0.0236
    mu_k: float = 0.0294
    mu_s: float | None = None
    x0_m: float = 5e-4
    load_N: float = 0.31
    mass_kg: float = 0.035
    natural_frequency_Hz: float = 32.6
    sample_rate_Hz: float = 20_000.0
    duration_s: float = 1.0
    samples_per_frame: int = 128
    displacement_range_m: float = 2e-3
    velocity_range_m_per_s: float = 0.5
    noise_counts: float = 0.0
    seed: int = 0
    hold_s: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "x0_m",
            "load_N",
            "mass_kg",
            "natural_frequency_Hz",
            "sample_rate_Hz",
            "duration_s",
            "displacement_range_m",
            "velocity_range_m_per_s",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value!r}")
        if not (math.isfinite(self.hold_s) and 0.0 <= self.hold_s < MAX_PRETRIGGER_S):
            raise ValueError(f"hold_s must be in [0, {MAX_PRETRIGGER_S:g}) s, got {self.hold_s!r}")
        if not 1 <= self.samples_per_frame <= 1024:
            raise ValueError(f"samples_per_frame must be in 1..1024, got {self.samples_per_frame}")
        if self.x0_m > self.displacement_range_m:
            raise ValueError(
                f"x0_m = {self.x0_m} m exceeds displacement_range_m = "
                f"{self.displacement_range_m} m: the signal would be clipped"
            )

    @property
    def header(self) -> RunHeader:
        """The run header the device sends."""
        return RunHeader(
            sample_rate_Hz=self.sample_rate_Hz,
            displacement_scale_m=self.displacement_range_m / 32767,
            velocity_scale_m_per_s=self.velocity_range_m_per_s / 32767,
            displacement_range_m=self.displacement_range_m,
            velocity_range_m_per_s=self.velocity_range_m_per_s,
            samples_per_frame=self.samples_per_frame,
            range_label=(
                f"simulated: displacement ±{self.displacement_range_m * 1e3:g} mm, "
                f"velocity ±{self.velocity_range_m_per_s:g} m/s"
            ),
        )

    def decay_counts(self) -> NDArray[np.int16]:
        """Counts of the free decay after release, shape (n, 2).

        Raises
        ------
        ValueError
            If the decay exceeds the velocity range (it would be clipped).
        """
        from bayestribo.model import exact_response

        omega = 2 * math.pi * self.natural_frequency_Hz
        k = self.mass_kg * omega**2
        ell = self.load_N / k
        n = round(self.duration_s * self.sample_rate_Hz)
        tau = np.arange(n) / self.sample_rate_Hz * omega
        mu_s = self.mu_k if self.mu_s is None else self.mu_s
        y, yp = exact_response(tau, self.x0_m / ell, self.zeta, self.mu_k, mu_s)
        header = self.header
        d = np.asarray(y) * ell / header.displacement_scale_m
        v = np.asarray(yp) * ell * omega / header.velocity_scale_m_per_s
        if self.noise_counts > 0:
            rng = np.random.default_rng(self.seed)
            d = d + rng.normal(0.0, self.noise_counts, n)
            v = v + rng.normal(0.0, self.noise_counts, n)
        counts = np.rint(np.column_stack([d, v]))
        if np.abs(counts).max(initial=0) > 32767:
            raise ValueError(
                "the simulated decay exceeds the velocity or displacement range: raise "
                "velocity_range_m_per_s or displacement_range_m"
            )
        return counts.astype(np.int16)

    def rest_counts(self) -> NDArray[np.int16]:
        """Counts while the pin is held before release, shape (2,)."""
        return np.array([round(self.x0_m / self.header.displacement_scale_m), 0], dtype=np.int16)


@dataclass(frozen=True)
class FaultPlan:
    """Faults to inject, by DATA frame number (0 = first DATA frame after ARM).

    Attributes
    ----------
    drop : frozenset of int
        Frames not sent; their sequence numbers are skipped, as if lost on the link.
    corrupt : frozenset of int
        Frames sent with one payload byte flipped (the checksum fails).
    garbage : frozenset of int
        Frames preceded by ``garbage_bytes`` random bytes containing false sync pairs.
    stall : mapping of int to float
        Pause before the frame [s] (interrupted by :meth:`SimulatedInstrument.stop`).
    disconnect_after : int or None
        Close the link after this many DATA frames (after the host has read them).
    bad_header : bool
        Send a run header whose payload does not parse (valid checksum).
    corrupt_header : bool
        Send the run header with one byte flipped (the checksum fails: header lost).
    silent : bool
        Never answer anything.
    garbage_bytes : int
        Length of each garbage burst.
    babble_after : int or None
        After this many DATA frames send nothing but garbage bursts, every 10 ms, until
        stopped (a board whose firmware went astray).
    """

    drop: frozenset[int] = frozenset()
    corrupt: frozenset[int] = frozenset()
    garbage: frozenset[int] = frozenset()
    stall: Mapping[int, float] = field(default_factory=dict)
    disconnect_after: int | None = None
    bad_header: bool = False
    corrupt_header: bool = False
    silent: bool = False
    garbage_bytes: int = 64
    babble_after: int | None = None


class SentFrame(NamedTuple):
    """A DATA frame the instrument produced.

    ``intact`` is True when it went on the wire unmodified (not dropped or corrupted);
    ``offset`` is where it starts in :attr:`SimulatedInstrument.sent` (None if dropped
    or not completely written) and ``size`` its length on the wire [bytes].
    """

    number: int
    seq: int
    first_index: int
    counts: NDArray[np.int16]
    intact: bool
    offset: int | None
    size: int


class _Channel:
    """Byte channel of the instrument: a pty master or a connected socket."""

    def __init__(
        self, fd: int, sock: socket.socket | None = None, slave_fd: int | None = None
    ) -> None:
        self.fd = fd
        self.sock = sock
        self.slave_fd = slave_fd

    def read(self) -> bytes:
        if self.sock is not None:
            return self.sock.recv(4096)
        return os.read(self.fd, 4096)

    def write(self, data: memoryview) -> int:
        if self.sock is not None:
            return self.sock.send(data)
        return os.write(self.fd, data)

    def pending_for_host(self) -> int:
        """Bytes written but not yet read by the host (pty only; 0 for sockets)."""
        if self.slave_fd is None:
            return 0
        buf = bytearray(4)
        fcntl.ioctl(self.slave_fd, termios.FIONREAD, buf)
        return struct.unpack("i", buf)[0]

    def close(self) -> None:
        if self.sock is not None:
            try:
                self.sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            self.sock.close()
        else:
            os.close(self.fd)
        if self.slave_fd is not None:
            os.close(self.slave_fd)
            self.slave_fd = None


class SimulatedInstrument:
    """A simulated acquisition board in a background thread.

    Parameters
    ----------
    config : SimulationConfig
        Physics and acquisition settings.
    faults : FaultPlan
        Faults to inject.
    realtime : bool
        Pace DATA frames after release at the sample rate (True) or send them as
        fast as the link takes them (False). Before release the stream is always
        paced at the sample rate.
    ident : str
        Identification string answered to ``ID?``.

    Examples
    --------
    >>> with SimulatedInstrument(SimulationConfig(duration_s=0.1)) as sim:  # doctest: +SKIP
    ...     path = sim.start_pty()
    ...     # acquire_run(path, "runs", inputs)
    """

    def __init__(
        self,
        config: SimulationConfig | None = None,
        faults: FaultPlan | None = None,
        *,
        realtime: bool = True,
        ident: str = "bayestribo,simulated-board,0001,fw1",
    ) -> None:
        self.config = config or SimulationConfig()
        self.faults = faults or FaultPlan()
        self.realtime = realtime
        self.ident = ident
        self.sent = bytearray()
        self.frames: list[SentFrame] = []
        self.commands: list[str] = []
        self.release_index: int | None = None
        self.disconnected = False
        self._decay = self.config.decay_counts()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._channel: _Channel | None = None
        self._listener: socket.socket | None = None
        self._rng = np.random.default_rng(self.config.seed + 1)
        self.error: BaseException | None = None

    # -- starting and stopping ---------------------------------------------------------
    def start_pty(self) -> str:
        """Serve on a new pseudo-terminal; return the device path for the host."""
        master, slave = os.openpty()
        tty.setraw(slave)
        tty.setraw(master)
        self._channel = _Channel(master, slave_fd=slave)
        self._start(self._serve)
        return os.ttyname(slave)

    def start_socket(self, host: str = "127.0.0.1") -> str:
        """Serve on a localhost TCP socket; return the ``socket://`` URL for the host."""
        listener = socket.create_server((host, 0))
        listener.settimeout(0.1)
        self._listener = listener
        self._start(self._accept_then_serve)
        return f"socket://{host}:{listener.getsockname()[1]}"

    def _start(self, target: object) -> None:
        self._thread = threading.Thread(target=target, name="simulated-instrument", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the thread and close the link."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        self._close()

    def join(self, timeout_s: float) -> bool:
        """Wait for the thread to end by itself; True if it did."""
        if self._thread is None:
            return True
        self._thread.join(timeout_s)
        return not self._thread.is_alive()

    def received(self, command: str, timeout_s: float = 30.0) -> bool:
        """Wait until the instrument has read ``command``; True if it did.

        The host's write returns once the bytes are in the link; the instrument's
        thread reads them when it next runs, which a loaded machine may delay past the
        host's return (after a STOP sent on the way out of a failed run).

        Parameters
        ----------
        command : str
            The command line, without its line end (``"STOP"``).
        timeout_s : float
            Longest wait [s].
        """
        deadline = time.monotonic() + timeout_s
        while command not in self.commands:
            alive = self._thread is not None and self._thread.is_alive()
            if not alive or time.monotonic() > deadline:
                return command in self.commands
            time.sleep(0.005)
        return True

    def __enter__(self) -> SimulatedInstrument:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _close(self) -> None:
        if self._channel is not None:
            channel, self._channel = self._channel, None
            try:
                channel.close()
            except OSError:
                pass
        if self._listener is not None:
            self._listener.close()
            self._listener = None

    # -- expected content ------------------------------------------------------------
    def intact_samples(self) -> tuple[NDArray[np.int64], NDArray[np.int16]]:
        """Sample indices and counts of the DATA frames sent unmodified, in order."""
        frames = [f for f in self.frames if f.intact]
        if not frames:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 2), dtype=np.int16)
        index = np.concatenate(
            [np.arange(f.first_index, f.first_index + len(f.counts)) for f in frames]
        )
        return index, np.concatenate([f.counts for f in frames])

    # -- the device ------------------------------------------------------------------
    def _accept_then_serve(self) -> None:
        assert self._listener is not None
        while not self._stop.is_set():
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.setblocking(True)
            self._channel = _Channel(conn.fileno(), sock=conn)
            self._serve()
            return

    def _serve(self) -> None:
        try:
            self._serve_loop()
        except OSError as exc:  # host went away
            self.error = exc
        except BaseException as exc:  # pragma: no cover - reported to tests
            self.error = exc
            raise

    def _serve_loop(self) -> None:
        channel = self._channel
        assert channel is not None
        cfg = self.config
        line = bytearray()
        streaming = False
        seq = 0
        number = 0  # DATA frames produced
        index = 0  # next sample index
        release: int | None = None
        fire_pending = False
        t0 = 0.0
        while not self._stop.is_set():
            rate = cfg.sample_rate_Hz
            spf = cfg.samples_per_frame
            wait = 0.05
            if streaming:
                paced = release is None or self.realtime
                due = t0 + index / rate if paced else time.monotonic()
                wait = max(0.0, min(wait, due - time.monotonic()))
            readable, _, _ = select.select([channel.fd], [], [], wait)
            if readable:
                data = channel.read()
                if not data:
                    return
                line += data
                while b"\n" in line:
                    raw, _, rest = line.partition(b"\n")
                    line = bytearray(rest)
                    command = raw.decode("ascii", errors="replace").strip()
                    if not command:
                        continue  # an empty line is ignored
                    self.commands.append(command)
                    if self.faults.silent:
                        continue
                    name = command.split(" ")[0]
                    if len(raw.rstrip(b"\r")) > MAX_LINE:
                        self._error("line too long")
                    elif command == "ID?":
                        self._send(encode_frame(FrameType.IDENT, 0, self.ident.encode()))
                    elif streaming and (command in ("CFG?", "ARM") or name in _CONFIGURE):
                        self._error("busy: a run is in progress")
                    elif command == "CFG?":
                        self._send(encode_frame(FrameType.HEADER, 0, cfg.header.to_payload()))
                    elif name in _CONFIGURE and " " in command:
                        cfg = self._configure(command, cfg)
                    elif command == "ARM":
                        payload = cfg.header.to_payload()
                        if self.faults.bad_header:
                            payload = payload[:20]
                        frame = encode_frame(FrameType.HEADER, 0, payload)
                        if self.faults.corrupt_header:
                            frame = frame[:12] + bytes([frame[12] ^ 0xFF]) + frame[13:]
                        self._send(frame)
                        seq, number, index, release = 1, 0, 0, None
                        fire_pending = False
                        streaming, t0 = True, time.monotonic()
                    elif command == "FIRE":
                        if not streaming:
                            self._error("no run: ARM first")
                        elif release is not None or fire_pending:
                            self._error("released already")
                        else:
                            fire_pending = True  # released at the next frame, see below

                    elif command == "STOP":
                        if not streaming:
                            self._error("no run")
                        else:
                            self._send(encode_frame(FrameType.END, seq, encode_end(seq, index)))
                            streaming = False
                    else:
                        self._error("unknown command")
                continue
            if not streaming:
                continue
            if fire_pending and index >= math.ceil(cfg.hold_s * rate):
                fire_pending = False
                release = index
                self.release_index = index
                self._send(encode_frame(FrameType.RELEASE, seq, encode_release(index)))
                seq += 1
            if release is not None:
                remaining = release + len(self._decay) - index
            else:
                remaining = int(MAX_PRETRIGGER_S * rate) - index
            if remaining <= 0:
                self._send(encode_frame(FrameType.END, seq, encode_end(seq, index)))
                streaming = False
                continue
            n = min(spf, remaining)
            counts = self._samples(index, n, release)
            if self.faults.babble_after is not None and number >= self.faults.babble_after:
                while not self._stop.wait(0.01):
                    self._send(self._garbage())
                return
            if number in self.faults.stall:
                if self._stop.wait(self.faults.stall[number]):
                    return
                t0 += self.faults.stall[number]
            if number in self.faults.garbage:
                self._send(self._garbage())
            frame = encode_frame(FrameType.DATA, seq, encode_data(index, counts))
            intact = number not in self.faults.drop and number not in self.faults.corrupt
            if number in self.faults.corrupt:
                damaged = bytearray(frame)
                damaged[13] ^= 0xFF
                frame = bytes(damaged)
            offset = None
            if number not in self.faults.drop:
                offset = len(self.sent)
                self._send(frame)
            self.frames.append(SentFrame(number, seq, index, counts, intact, offset, len(frame)))
            seq += 1
            number += 1
            index += n
            if self.faults.disconnect_after is not None and number >= self.faults.disconnect_after:
                self._disconnect()
                return

    def _samples(self, start: int, n: int, release: int | None) -> NDArray[np.int16]:
        counts = np.empty((n, 2), dtype=np.int16)
        counts[:] = self.config.rest_counts()
        if release is not None:
            i = np.arange(start, start + n)
            after = i >= release
            counts[after] = self._decay[i[after] - release]
        return counts

    def _configure(self, command: str, cfg: SimulationConfig) -> SimulationConfig:
        name, _, value = command.partition(" ")
        try:
            number = float(value)
            if name == "RATE":
                new = replace(cfg, sample_rate_Hz=number)
            elif name == "SPF":
                if number != int(number):
                    raise ValueError(f"samples_per_frame must be a whole number, got {value}")
                new = replace(cfg, samples_per_frame=int(number))
            else:
                new = replace(cfg, duration_s=number)
            self._decay = new.decay_counts()
        except (ValueError, OverflowError) as exc:
            self._send(encode_frame(FrameType.ERROR, 0, f"{command}: {exc}".encode()))
            return cfg
        self.config = new
        self._send(encode_frame(FrameType.ACK, 0, command.encode()))
        return new

    def _error(self, text: str) -> None:
        """Send an ERROR frame (sequence number 0, outside the run's numbering)."""
        self._send(encode_frame(FrameType.ERROR, 0, text.encode()))

    def _garbage(self) -> bytes:
        junk = bytearray(self._rng.integers(0, 256, self.faults.garbage_bytes, dtype=np.uint8))
        # False sync pairs, one followed by a plausible DATA prefix with a long length.
        junk[0:2] = b"\xa5\x5a"
        if len(junk) >= 12:
            junk[5:12] = b"\xa5\x5a\x10\x00\x01\x07\x00"
        return bytes(junk)

    def _send(self, data: bytes) -> None:
        channel = self._channel
        assert channel is not None
        view = memoryview(data)
        while view:
            _, writable, _ = select.select([], [channel.fd], [], 0.1)
            if self._stop.is_set():
                raise OSError("instrument stopped while writing")
            if not writable:
                continue
            written = channel.write(view)
            self.sent += view[:written]
            view = view[written:]

    def _disconnect(self) -> None:
        """Close the link once the host has read everything (a pty loses unread bytes)."""
        channel = self._channel
        assert channel is not None
        # Bytes written to a pty master reach the slave's queue asynchronously: wait
        # until the queue has stayed empty for 60 ms (or 2 s in all).
        deadline = time.monotonic() + 2.0
        empty_since: float | None = None
        while time.monotonic() < deadline:
            now = time.monotonic()
            if channel.pending_for_host():
                empty_since = None
            elif empty_since is None:
                empty_since = now
            elif now - empty_since >= 0.06:
                break
            if self._stop.wait(0.005):
                break
        self.disconnected = True
        self._close()
