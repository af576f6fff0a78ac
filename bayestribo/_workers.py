"""Worker processes that do not outlive the command that started them.

A campaign fits its runs in a pool of worker processes. Killed (SIGTERM, SIGKILL, the
terminal closed), the command used to leave its workers running, each holding
hundreds of megabytes, for minutes. :func:`process_pool` gives every worker the
order to die with its parent: on Linux the kernel sends the worker SIGTERM when the
process that started it ends (``prctl(PR_SET_PDEATHSIG)``), whatever the way it
ended; elsewhere a thread in the worker watches for its parent's end. SIGTERM of the
command itself is turned into the same clean exit as Ctrl-C (:func:`terminate_as_interrupt`),
so that the pools shut down through their ``with`` blocks.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

__all__ = ["die_with_parent", "process_pool", "stop_workers", "terminate_as_interrupt"]

_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int | None = None) -> None:
    """Make the calling process end when the process ``parent`` (default its own
    parent) ends: the kernel's parent-death signal on Linux when that is the direct
    parent; otherwise (a forkserver's worker, whose parent is the server) a thread that
    looks for it every second."""
    direct = os.getppid()
    parent = direct if parent is None else parent
    if parent == direct and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) == 0:
                if os.getppid() != parent:  # the parent ended before the call
                    os.kill(os.getpid(), signal.SIGTERM)
                return

    def gone() -> bool:
        try:
            os.kill(parent, 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        return False

    def watch() -> None:
        while not gone():
            time.sleep(1.0)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, daemon=True, name="die-with-parent").start()


def _initialise(parent: int, initializer: Any, args: tuple) -> None:
    die_with_parent(parent)
    if initializer is not None:
        initializer(*args)


def process_pool(
    max_workers: int | None = None,
    *,
    method: str | None = None,
    initializer: Any = None,
    initargs: tuple = (),
) -> ProcessPoolExecutor:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` whose workers end with the
    process that made it.

    Parameters
    ----------
    max_workers : int, optional
        Workers (default the number of CPUs).
    method : str, optional
        Start method (``"forkserver"``, ``"spawn"``; default the platform's).
    initializer, initargs
        Run in each worker after the parent-death order, as for the executor.
    """
    context = multiprocessing.get_context(method) if method else None
    return ProcessPoolExecutor(
        max_workers=max_workers,
        mp_context=context,
        initializer=_initialise,
        initargs=(os.getpid(), initializer, tuple(initargs)),
    )


def stop_workers(executor: Any) -> None:
    """End the worker processes of a :class:`~concurrent.futures.ProcessPoolExecutor`
    now (SIGTERM), so that an interrupted command does not wait for the tasks they
    run: their results would be dropped anyway. Other executors are left alone."""
    processes = getattr(executor, "_processes", None) or {}
    for process in list(processes.values()):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            process.terminate()


@contextlib.contextmanager
def terminate_as_interrupt() -> Any:
    """Within the block, SIGTERM raises :class:`KeyboardInterrupt` in the main thread,
    so that a terminated command unwinds as Ctrl-C does (its pools shut down, their
    workers end, partial files are removed); the previous handler is restored after."""

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
