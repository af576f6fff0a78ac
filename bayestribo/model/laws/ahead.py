"""Laws compiled ahead: the integrators a comparison will need, compiled into the law
cache by worker processes while the command goes on.

``--law auto`` compares a dozen laws. On a fresh machine each law's integrator
(:mod:`.integrator`) is compiled on its first use, some 15 s of CPU each, one after the
other in the command's process: the first ``auto`` on a new install took minutes.
:func:`compile_ahead` hands the laws whose compiled code is not in the law cache to
worker processes (as many as the CPUs, at most :data:`WORKERS_ENV`; 0 none), one law a
worker at a time in the order the command will need them, while the command goes on
with its own work. Where it reaches a law a worker is compiling, it waits for that
worker and loads the law from the cache (:func:`wait_for`, called as a law's module is
loaded); a law no worker has begun it takes back and compiles itself, as without
workers. A worker compiles the law's module from the same generated text with the same
numba, so the code loaded is the code the command would have compiled: the answers are
the same to the bit (``benchmarks/law_ahead.py``; ``tests/test_model_laws_ahead.py``
checks that the command loads what a worker compiled and compiles nothing again).

No workers are started for a law cache that is not usable (every process compiles its
laws then), on one CPU, inside a worker process (a campaign's fits, which are parallel
already), or for laws whose terms cannot be imported by name (defined in ``__main__``:
compiled in the command's process, as before). Workers end with the command
(:func:`bayestribo._workers.die_with_parent`); one still compiling when the comparison
ends is stopped, leaving no partial file numba would load (each cache file is written
whole and checked against its SHA-256 before it is read, :mod:`.cache`).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import subprocess
import sys
import threading
from collections import deque
from collections.abc import Iterator, Sequence
from pathlib import Path

from bayestribo.errors import BayestriboError

__all__ = [
    "WORKERS_ENV",
    "AheadCompiler",
    "compile_ahead",
    "compile_law",
    "entry_points",
    "wait_for",
    "worker_count",
]

#: Environment variable: at most this many worker processes compile laws ahead (0:
#: none, each law compiled by the command as it needs it).
WORKERS_ENV = "BAYESTRIBO_COMPILE_WORKERS"


def worker_count(laws: int) -> int:
    """How many workers compile ``laws`` laws ahead: as many as the CPUs this process
    may use (the command mostly waits for them), at most ``laws`` and at most
    :data:`WORKERS_ENV`; none on one CPU or inside a worker process.

    Raises
    ------
    BayestriboError
        If :data:`WORKERS_ENV` is set to anything but a whole number >= 0.
    """
    text = os.environ.get(WORKERS_ENV, "").strip()
    limit = None
    if text:
        try:
            limit = int(text)
        except ValueError:
            limit = -1
        if limit < 0:
            raise BayestriboError(
                f"{WORKERS_ENV}: expected a whole number of worker processes >= 0, got {text!r}"
            )
    if multiprocessing.parent_process() is not None:
        return 0
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    count = min(cpus, laws) if cpus > 1 else 0
    if limit is not None:
        count = min(count, limit)
    return max(count, 0)


def entry_points(law: object) -> tuple[str, ...]:
    """The compiled functions of a law's module that fits call: the turning points
    (:meth:`~.law.Law.turning_points`), and for a law without a closed form Π
    (:meth:`~.law.Law.pi_grid`) and the swings' dissipation
    (:meth:`~.law.Law.swing_dissipation`) too."""
    if law.closed_form:  # type: ignore[attr-defined]
        return ("turns",)
    return ("grid", "turns", "swing_drops")


def _pending(laws: Sequence[object], folder: Path) -> list[tuple[str, str]]:
    """``(module name, law name)`` of each law whose module may be cached and is not,
    in the order given, each module once."""
    from bayestribo.model.laws.integrator import cached_functions, law_module

    out: dict[str, str] = {}
    compiled = cached_functions(folder)
    for law in laws:
        if getattr(law, "restoring", None) is not None:
            continue  # the laws on a nonlinear spring compile other modules
        name = law_module(law._layout[0])  # type: ignore[attr-defined]
        if name is None or name in out:
            continue
        if all(f"{name}.{entry}" in compiled for entry in entry_points(law)):
            continue
        out[name] = law.name  # type: ignore[attr-defined]
    return list(out.items())


def compile_law(law: str, module: str) -> str:
    """In a worker, its law cache in the environment (``BAYESTRIBO_CACHE_DIR``): compile
    the functions of the law named ``law`` that fits call (:func:`entry_points`) by
    calling each once, with small arguments of the types a fit passes; the module's
    name back. Raises when the law made here is not the module asked for (a term
    registered in the command alone), so that the command compiles it."""
    import numpy as np

    from bayestribo.model.laws import get_law
    from bayestribo.model.laws.integrator import law_module

    the_law = get_law(law)
    made = law_module(the_law._layout[0])
    if made != module:
        raise RuntimeError(f"law {law} is {made} here, not {module}")
    values = {p.name: p.null if p.null is not None else p.low for p in the_law.parameters}
    rows = {k: np.array([v]) for k, v in values.items()}
    tau = np.linspace(0.0, 4.0 * np.pi, 5)
    entries = entry_points(the_law)
    if "grid" in entries:
        the_law.pi_grid(tau, rows, np.array([1.0]), tau_end=float(tau[-1]), method="integrate")
    the_law.turning_points(values, 1.0, tau_max=float(tau[-1]), max_count=4)
    if "swing_drops" in entries:
        the_law.swing_dissipation(np.array([0.5]), rows, 1.0)
    return module


def wait_for(module: str) -> None:
    """Before the law module ``module`` is loaded: where a worker is compiling it, wait
    until it is done (the module then loads from the cache); where no worker has begun
    it, take it back, to be compiled here. A worker that failed leaves it to be
    compiled here too."""
    for ahead in list(_active):
        ahead.wait_for(module)


def _end(process: subprocess.Popen) -> None:
    """End a worker: its input closed (it ends when done), killed if it is not."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        process.stdin.close()  # type: ignore[union-attr]
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(timeout=5)
    if process.poll() is None:
        with contextlib.suppress(OSError):
            process.kill()
        process.wait()


#: The compilers of the blocks now open (:func:`compile_ahead`).
_active: list[AheadCompiler] = []


class AheadCompiler:
    """Laws handed to worker processes to compile, one law a worker at a time, in the
    order given; the rest wait here, where the command may take one back
    (:meth:`wait_for`). Made by :func:`compile_ahead`.

    Each worker is a fresh ``python -m bayestribo.model.laws._ahead_worker`` fed law
    names on its standard input by a thread of the command (not :mod:`multiprocessing`,
    whose workers import the command's main script again: a script that calls ``fit``
    without a ``__main__`` guard would run once more in each).
    """

    def __init__(self, folder: Path | None) -> None:
        self.folder = folder
        self.workers = 0
        self._waiting: deque[tuple[str, str]] = deque()  # (module, law) not yet handed out
        self._running: dict[str, threading.Event] = {}
        self._feeders: list[threading.Thread] = []
        self._processes: list[subprocess.Popen] = []
        self._closed = False
        self._lock = threading.Lock()

    def submit(self, laws: Sequence[object]) -> int:
        """Hand the laws ``laws`` (in the order the command needs them) that are not in
        the law cache to workers, starting them where none run; how many of them are
        new to the workers (0 where no worker runs)."""
        if self.folder is None:
            return 0
        with self._lock:
            if self._closed:
                return 0
            known = {m for m, _ in self._waiting} | set(self._running)
            new = [(m, law) for m, law in _pending(laws, self.folder) if m not in known]
            if not new:
                return 0
            if not self.workers:
                self.workers = worker_count(len(new))
            if not self.workers:
                return 0
            self._waiting.extend(new)
            self._feeders = [t for t in self._feeders if t.is_alive()]
            for _ in range(min(self.workers - len(self._feeders), len(self._waiting))):
                # each new worker's first law is marked as begun here, before its thread
                # runs: the command waits for it from now on, never takes it back
                first = self._waiting.popleft()
                self._running[first[0]] = threading.Event()
                feeder = threading.Thread(
                    target=self._feed, args=(first,), daemon=True, name="law-ahead"
                )
                self._feeders.append(feeder)
                feeder.start()
        return len(new)

    def _worker(self) -> subprocess.Popen:
        import bayestribo
        from bayestribo.model.laws.cache import CACHE_ENV

        home = str(Path(bayestribo.__file__).resolve().parent.parent)
        path = os.pathsep.join(p for p in (home, os.environ.get("PYTHONPATH")) if p)
        env = {**os.environ, CACHE_ENV: str(self.folder), "PYTHONPATH": path}
        env[WORKERS_ENV] = "0"
        return subprocess.Popen(
            [sys.executable, "-m", "bayestribo.model.laws._ahead_worker", str(os.getpid())],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            text=True,
        )

    def _feed(self, first: tuple[str, str]) -> None:
        # one worker process: its first law, then the next from the front of the waiting
        # ones, marked as begun before the last one is said to be done (the command,
        # woken by that, then waits for the next rather than taking it back)
        process = None
        module, law = first
        try:
            while module:
                with self._lock:
                    done = self._running[module]
                reply = ""
                try:
                    if process is None:
                        process = self._worker()
                        with self._lock:
                            self._processes.append(process)
                            if self._closed:
                                return
                    assert process.stdin is not None and process.stdout is not None
                    process.stdin.write(f"{law}\t{module}\n")
                    process.stdin.flush()
                    reply = process.stdout.readline()
                except (OSError, ValueError):
                    pass
                finally:
                    with self._lock:
                        self._running.pop(module, None)
                        module, law = "", ""
                        # a worker that ended leaves the laws still waiting to the command
                        if reply and not self._closed and self._waiting:
                            module, law = self._waiting.popleft()
                            self._running[module] = threading.Event()
                    done.set()
        finally:
            if process is not None:
                _end(process)

    def wait_for(self, module: str) -> None:
        """Wait for ``module`` where a worker compiles it; take it back where it waits
        to be handed out."""
        with self._lock:
            self._waiting = deque(item for item in self._waiting if item[0] != module)
            done = self._running.get(module)
        if done is not None:
            done.wait()

    def wait_all(self) -> None:
        """Wait until the workers have compiled every law handed to them (laws a worker
        that ended left waiting are left to whoever needs them)."""
        while True:
            with self._lock:
                done = next(iter(self._running.values()), None)
            if done is None:
                return
            done.wait()

    def close(self) -> None:
        """Stop handing out laws and end the workers (one still compiling is stopped:
        numba writes each file whole, and a file without its record is never loaded)."""
        with self._lock:
            self._closed = True
            self._waiting.clear()
            processes, feeders = list(self._processes), list(self._feeders)
        for process in processes:
            if process.poll() is None:
                with contextlib.suppress(OSError):
                    process.kill()
        for feeder in feeders:
            feeder.join()


@contextlib.contextmanager
def compile_ahead(laws: Sequence[object] = ()) -> Iterator[AheadCompiler]:
    """Within the block, worker processes compile the laws ``laws``
    (:class:`~.law.Law`, in the order the block needs them), and any the block hands
    to :meth:`AheadCompiler.submit`, that are not in the law cache (module notes).
    Yields the :class:`AheadCompiler`."""
    from bayestribo.model.laws.cache import law_cache_dir

    ahead = AheadCompiler(law_cache_dir())
    _active.append(ahead)
    try:
        ahead.submit(laws)
        yield ahead
    finally:
        _active.remove(ahead)
        ahead.close()
