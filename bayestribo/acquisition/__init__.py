"""Acquisition of hardware runs over a serial link, losing nothing.

Modules
-------
protocol
    Frames of the open wire protocol (``docs/protocol.md``) and the streaming parser.
assembly
    Frames of one run to samples, with gaps reported and never filled.
frameindex
    Where each DATA frame lies in the raw log: memory bounded for any run length.
csvstream
    The canonical CSV written a chunk at a time, while the run streams.
port
    Open any port by URL (device path, ``socket://``, ``loop://``).
logger
    Append-only raw log and atomic canonical run files.
session
    The host's conversation with the device: :func:`acquire_run`.
recover
    Rebuild a run from a raw log left by a crash: :func:`recover_run`.
instrument
    A simulated board on a pseudo-terminal or a socket, with fault injection.
"""

from __future__ import annotations

from bayestribo.acquisition.faults import (
    AcquisitionTimeout,
    DeviceError,
    DisconnectedError,
    FrameError,
    HeaderError,
    PortBusyError,
    PortNotFoundError,
)
from bayestribo.acquisition.logger import OperatorInputs
from bayestribo.acquisition.recover import recover_run
from bayestribo.acquisition.session import AcquisitionResult, Progress, acquire_run

__all__ = [
    "AcquisitionResult",
    "AcquisitionTimeout",
    "DeviceError",
    "DisconnectedError",
    "FrameError",
    "HeaderError",
    "OperatorInputs",
    "PortBusyError",
    "PortNotFoundError",
    "Progress",
    "acquire_run",
    "recover_run",
]
