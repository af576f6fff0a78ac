"""Errors of the acquisition link, all :class:`bayestribo.errors.AcquisitionError`.

Each names the port or file concerned and what was expected, so the command line
can print it as one clear line.
"""

from __future__ import annotations

from bayestribo.errors import AcquisitionError

__all__ = [
    "AcquisitionTimeout",
    "DeviceError",
    "DisconnectedError",
    "DuplicateRunError",
    "FrameError",
    "HeaderError",
    "PortBusyError",
    "PortNotFoundError",
    "RunInUseError",
    "StorageError",
]


class StorageError(AcquisitionError):
    """The raw log or the run files cannot be written (disk full, I/O error).

    The message names the cause and the ``bayestribo acquire --recover`` command that
    rebuilds the run from the raw log once the disk has room again.
    """


class RunInUseError(AcquisitionError):
    """Another logger holds this run (its raw log exists): two loggers never share one."""


class DuplicateRunError(AcquisitionError):
    """A run's samples are those of a run in the catalog already, or its run id is
    catalogued with other samples: its run files are not written (the raw log is kept).

    The catalog identifies a run by the SHA-256 of its run file, so a second recording
    with the very same samples cannot be catalogued beside the first; it is refused
    before any run file is written rather than written and then left out.
    """


class PortNotFoundError(AcquisitionError):
    """The serial port (device path or URL) does not exist or cannot be reached."""


class PortBusyError(AcquisitionError):
    """The serial port is held by another program."""


class AcquisitionTimeout(AcquisitionError):
    """The device did not answer, or stopped sending, within the timeout."""


class DisconnectedError(AcquisitionError):
    """The device went away in the middle of a conversation (cable pulled, reset)."""


class FrameError(AcquisitionError):
    """A frame passed its checksum but its payload does not follow the protocol."""


class HeaderError(FrameError):
    """The run header does not parse (bad length, unsupported version, bad values)."""


class DeviceError(AcquisitionError):
    """The device answered a command with an ERROR frame."""
