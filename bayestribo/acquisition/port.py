"""Open a serial link by URL and read from it, with the package's own errors.

Any URL :func:`serial.serial_for_url` understands works: a device path
(``/dev/ttyACM0``, ``COM3``), ``socket://host:port``, ``loop://``. Framing and parsing
live elsewhere (:mod:`bayestribo.acquisition.protocol`); this module only moves bytes.
"""

from __future__ import annotations

import errno
from types import ModuleType
from typing import TYPE_CHECKING

from bayestribo._optional import require
from bayestribo.acquisition.faults import (
    AcquisitionTimeout,
    DisconnectedError,
    PortBusyError,
    PortNotFoundError,
)
from bayestribo.errors import AcquisitionError

if TYPE_CHECKING:
    import serial

__all__ = ["DEFAULT_BAUDRATE", "Link", "open_port"]

#: Default baud rate [bit/s]; USB CDC devices ignore it, UART bridges need ≥ 921600.
DEFAULT_BAUDRATE = 921_600

_NOT_FOUND = {errno.ENOENT, errno.ENODEV, errno.ENXIO, errno.ECONNREFUSED, errno.EHOSTUNREACH}
_BUSY = {errno.EBUSY, errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK}


def _serial() -> ModuleType:
    """pyserial, imported when a link is used (the ``acquire`` extra)."""
    return require("serial", "the acquisition link")


class Link:
    """A byte link to the device: read what is available, write commands.

    Parameters
    ----------
    port : serial.SerialBase
        An open pyserial port.
    url : str
        The URL it was opened with (for messages).
    """

    def __init__(self, port: serial.SerialBase, url: str) -> None:
        self.port = port
        self.url = url

    def read_available(self, max_bytes: int = 65536) -> bytes:
        """Return the bytes available now, waiting at most the port's read timeout.

        Raises
        ------
        DisconnectedError
            If the device went away.
        """
        try:
            waiting = self.port.in_waiting
            return bytes(self.port.read(min(max(waiting, 1), max_bytes)))
        except (_serial().SerialException, OSError) as exc:
            raise DisconnectedError(f"{self.url}: device disconnected ({exc})") from None

    def write_line(self, command: str) -> None:
        """Send one ASCII command line (``\\n`` appended).

        Raises
        ------
        DisconnectedError
            If the device went away.
        AcquisitionTimeout
            If the write does not complete within the write timeout.
        """
        try:
            self.port.write(command.encode("ascii") + b"\n")
            self.port.flush()
        except _serial().SerialTimeoutException:
            raise AcquisitionTimeout(f"{self.url}: timed out sending {command!r}") from None
        except (_serial().SerialException, OSError) as exc:
            raise DisconnectedError(
                f"{self.url}: device disconnected while sending {command!r} ({exc})"
            ) from None

    def close(self) -> None:
        """Close the port, ignoring errors of a port that is already gone."""
        try:
            self.port.close()
        except (_serial().SerialException, OSError):
            pass

    def __enter__(self) -> Link:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_port(
    url: str,
    *,
    baudrate: int = DEFAULT_BAUDRATE,
    read_timeout_s: float = 0.1,
    write_timeout_s: float = 2.0,
) -> Link:
    """Open a serial link by URL, exclusively where the platform allows it.

    Parameters
    ----------
    url : str
        A device path, ``socket://host:port``, ``loop://`` or any pyserial URL.
    baudrate : int
        Baud rate [bit/s] (ignored by USB CDC devices, sockets and ptys).
    read_timeout_s : float
        Longest wait of a single read [s]; the caller keeps its own overall timeout.
    write_timeout_s : float
        Longest wait for a command to be sent [s].

    Returns
    -------
    Link

    Raises
    ------
    PortNotFoundError
        If the port does not exist or nothing listens at the address.
    PortBusyError
        If another program holds the port (exclusive lock on POSIX device paths).
    AcquisitionError
        For any other failure to open, with the port's own message.
    """
    if not isinstance(url, str) or not url:
        raise PortNotFoundError(f"port: expected a device path or URL, got {url!r}")
    try:
        port = _serial().serial_for_url(
            url,
            baudrate=baudrate,
            timeout=read_timeout_s,
            write_timeout=write_timeout_s,
            exclusive=True,
        )
    except (_serial().SerialException, OSError, ValueError) as exc:
        code = getattr(exc, "errno", None)
        text = str(exc)
        if code in _BUSY or "exclusively lock" in text or "busy" in text.lower():
            raise PortBusyError(f"{url}: port is busy, held by another program ({text})") from None
        if code in _NOT_FOUND or "No such file" in text or "refused" in text.lower():
            raise PortNotFoundError(f"{url}: no such port ({text})") from None
        raise AcquisitionError(f"{url}: cannot open port ({text})") from None
    return Link(port, url)
