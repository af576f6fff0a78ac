"""A campaign that answers as runs land: ``bayestribo campaign DIR --watch``.

:class:`CampaignWatch` keeps warm worker processes (the package, the numba kernels and
the sampler imported and compiled once, by a warm-up fit of a simulated run) and a
loop in the calling thread that looks at the folder (:class:`~.arrivals.Arrivals`) when
the system says something changed there (:class:`~.wakeup.Wakeup`) and at least every
``poll_s``, sends each run file to a worker as soon as it is complete, and with each
answer

* prints one line (:meth:`~.watchpage.Answer.line`) as soon as the fit is back from its
  worker, then rewrites the live page (:mod:`~.watchpage`, milliseconds) and its status
  file;
* records the fit in the catalog (:func:`~.fitting.fit_catalogued`: the same catalog,
  fit files and cache as ``bayestribo campaign``, so a watched run is not fitted again
  by a later campaign with the same settings). A run's identity is its file stem, as
  in a campaign whose stems are unique: a second file of one stem in another
  sub-folder is refused by the catalog, and its line says so. The fit is saved and
  recorded by its fitter thread after its line is printed; where that fails, a second
  line says so and the page shows the run as failed.

The populations of repeats take longer than a fit: they are computed in a background
thread when the fit queue is empty, or at most every ``population_every_s`` while
fits keep coming, and written to ``population.json`` (as ``bayestribo campaign``
writes it, so ``bayestribo report OUTDIR`` reports the watched campaign).

The watch stops after ``max_runs`` answers, after ``timeout_s``, or on Ctrl-C
(SIGINT; SIGTERM likewise): the workers are ended at once
(:func:`bayestribo._workers.stop_workers`); each fit is saved and recorded in one
transaction by the thread that received it, and that thread is waited for, so the
catalog holds every fit that finished and nothing of one cut short.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    InvalidStateError,
    ThreadPoolExecutor,
    wait,
)
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any

from bayestribo.campaign.arrivals import Arrivals
from bayestribo.campaign.lock import write_atomic
from bayestribo.campaign.wakeup import Wakeup
from bayestribo.campaign.watchpage import Answer, PageState, render_page, status
from bayestribo.errors import BayestriboError

__all__ = ["PAGE_NAME", "STATUS_NAME", "CampaignWatch", "WatchOptions", "answer_of"]

#: The live page, in the output folder.
PAGE_NAME = "watch.html"
#: The page's state as JSON, beside it.
STATUS_NAME = "watch.json"
#: Seconds between the reloads of a browser showing the live page.
PAGE_REFRESH_S = 2.0
#: What this process imports before the first run, while the workers warm up.
_HANDLING_IMPORTS = (
    "bayestribo.inference",
    "bayestribo.campaign.digest",
    "bayestribo.campaign.analysis",
    "arviz",
    "netCDF4",
)


@dataclass(frozen=True)
class WatchOptions:
    """How a watch runs.

    Attributes
    ----------
    settle_s : float
        A file without a manifest is complete once its size and modification time
        have not changed for this long [s].
    poll_s : float
        Longest interval between two looks at the folder [s]: it is also looked at as
        soon as the system reports a change there (:mod:`~.wakeup`), and when a file
        waiting to settle is due.
    max_runs : int or None
        Stop after this many answers (failures included; runs already in the folder
        when the watch starts count too).
    timeout_s : float or None
        Stop after this long [s].
    population_every_s : float
        Longest interval between two population updates while fits keep coming [s]
        (they are also updated whenever the fit queue empties).
    page_every_s : float
        Shortest interval between two rewrites of the page while fits keep coming [s]
        (it is rewritten at once whenever the fit queue is empty): a watch started on
        a folder of many runs does not rewrite it for each.
    workers : int
        Warm worker processes fitting side by side.
    warm_up : bool
        Fit a simulated run in each worker before the first file (imports and
        compiles), so that the first run is answered as fast as the others.
    """

    settle_s: float = 2.0
    poll_s: float = 0.2
    max_runs: int | None = None
    timeout_s: float | None = None
    population_every_s: float = 30.0
    page_every_s: float = 2.0
    workers: int = 1
    warm_up: bool = True

    def __post_init__(self) -> None:
        for name in ("settle_s", "poll_s", "population_every_s", "page_every_s"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and value > 0 and math.isfinite(value)):
                raise BayestriboError(
                    f"{name}: expected a positive number of seconds, got {value!r}"
                )
        if self.timeout_s is not None and not self.timeout_s > 0:
            raise BayestriboError(
                f"timeout_s: expected a positive number of seconds, got {self.timeout_s!r}"
            )
        if self.max_runs is not None and (not isinstance(self.max_runs, int) or self.max_runs < 1):
            raise BayestriboError(f"max_runs: expected a positive integer, got {self.max_runs!r}")
        if not isinstance(self.workers, int) or self.workers < 1:
            raise BayestriboError(f"workers: expected a positive integer, got {self.workers!r}")


def answer_of(outcome: Any, path: Path) -> Answer:
    """The :class:`~.watchpage.Answer` of a :class:`~.fitting.RunOutcome` whose result
    is a :class:`~.digest.FitDigest`."""
    if not outcome.ok:
        return Answer(run=outcome.name, path=str(path), error=outcome.error)
    digest = outcome.result
    quantities = {}
    for name, s in digest.summaries.items():
        q = digest.quantities.get(name, {})
        low, high = s["interval"]
        quantities[name] = {
            "symbol": str(q.get("symbol") or name),
            "unit": str(q.get("unit") or "1"),
            "median": float(s["median"]),
            "low": float(low),
            "high": float(high),
            "bound": s.get("kind") == "bound",
        }
    return Answer(
        run=outcome.name,
        path=str(path),
        law=digest.law,
        quantities=quantities,
        converged=digest.converged,
        fit_s=float(outcome.elapsed_s),
        cached=outcome.cached,
    )


def _resolve(future: Future[Any], value: Any) -> None:
    """Resolve ``future`` with ``value`` unless it is resolved already."""
    with contextlib.suppress(InvalidStateError):  # resolved or cancelled
        future.set_result(value)


def _in_background(function: Callable[..., Any], *args: Any) -> Future[Any]:
    """Run ``function(*args)`` in a daemon thread: a Ctrl-C does not wait for it."""
    future: Future[Any] = Future()
    future.set_running_or_notify_cancel()

    def target() -> None:
        try:
            future.set_result(function(*args))
        except BaseException as exc:  # handed to the loop, which says it
            future.set_exception(exc)

    threading.Thread(target=target, daemon=True, name="watch-population").start()
    return future


def _utc() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


class CampaignWatch:
    """Fit the runs of a folder as they land, with warm workers (module notes).

    Parameters
    ----------
    folder : path
        The folder of run files watched (with its sub-folders).
    out : path
        The output folder: ``fits/``, the live page (:data:`PAGE_NAME`), its status
        (:data:`STATUS_NAME`), ``population.json``. Never looked into for runs.
    catalog : path
        The results catalog.
    spec : FitSpec
        The specification of every fit (its seed is the campaign seed).
    options : WatchOptions
    by : sequence of str
        Grouping keys of the populations.
    covariate : str
        Metadata key of the trends.
    prob : float
        Credible-interval probability.
    population_steps : int
        Ceiling on the population sampler's steps.
    dissipation : bool
        Also compare the law-free ΔE across runs.
    suffixes : sequence of str
        File suffixes of run files.
    stream : text stream, optional
        Where the answers are printed, one line each (default standard output).
    say : callable, optional
        Called with progress messages (default: to standard error).
    json_lines : bool
        Print each answer as one JSON object instead of a line of text.
    label : callable, optional
        A group's label (``lubricant=glycerol,load_N=0.31``) in words, for the page;
        default as it is.
    warm_up : callable, optional
        ``warm_up(spec)``, run once in each worker before the first file when
        ``options.warm_up``: a fit of a simulated run (imports and compiles), returning
        its result, which this process then saves, reads back and digests as it does a
        run's (its own imports). A module-level function (it is sent to the workers).
    settings : dict, optional
        Written with the populations in ``population.json`` (``settings``).
    """

    def __init__(
        self,
        folder: str | os.PathLike[str],
        out: str | os.PathLike[str],
        catalog: str | os.PathLike[str],
        spec: Any,
        options: WatchOptions,
        *,
        by: Sequence[str],
        covariate: str = "load_N",
        prob: float = 0.95,
        population_steps: int = 10_000,
        dissipation: bool = False,
        suffixes: Sequence[str],
        stream: IO[str] | None = None,
        say: Callable[[str], None] | None = None,
        json_lines: bool = False,
        label: Callable[[str], str] | None = None,
        warm_up: Callable[[Any], Any] | None = None,
        settings: dict[str, Any] | None = None,
    ) -> None:
        self.folder = Path(folder)
        self.out = Path(out)
        self.catalog = Path(catalog)
        self.spec = spec
        self.options = options
        self.by = tuple(by)
        self.covariate = covariate
        self.prob = prob
        self.population_steps = population_steps
        self.dissipation = dissipation
        self.stream = stream if stream is not None else sys.stdout
        self.say = say or (lambda message: print(message, file=sys.stderr, flush=True))
        self.json_lines = json_lines
        self.warm_up = warm_up if options.warm_up else None
        self.label = label or str
        self.settings = settings or {}
        self.page = self.out / PAGE_NAME
        self.arrivals = Arrivals(self.folder, suffixes, options.settle_s, exclude=[self.out])
        self.answers: dict[str, Answer] = {}  # by run file, latest version
        self.digests: dict[str, Any] = {}  # by run file, the fitted ones
        self.n_answered = 0
        self.stopped_by: str | None = None
        self._state = "warming up"
        self._populations: list[dict[str, Any]] = []
        self._trends: list[dict[str, Any]] = []
        self._population_runs = 0
        self._population_note = "Computed once the first runs are answered."
        # the loop's state
        self._start = 0.0
        self._pool: Any = None
        self._queue: deque[Path] = deque()
        self._running: dict[Future[Any], Path] = {}
        # each running fit's answer, announced before it is saved and recorded
        self._announcing: dict[Path, Future[Any]] = {}
        # the runs answered from their announcement: whether that answer was a fit
        self._announced: dict[Path, bool] = {}
        self._wakeup: Wakeup | None = None
        self._warming: set[Future[Any]] = set()
        self._population: Future[Any] | None = None
        self._population_started = 0
        self._last_population = -math.inf
        self._changed = False
        self._page_stale = False
        self._last_page = -math.inf

    # -- the page ---------------------------------------------------------------------
    def _page_state(self) -> PageState:
        waiting = [*self.arrivals.pending(), *self._queue]
        return PageState(
            folder=str(self.folder),
            state=self._state,
            prob=self.prob,
            answers=list(self.answers.values()),
            waiting=[str(p) for p in waiting],
            fitting=[str(p) for p in self._running.values() if p not in self._announced],
            populations=self._populations,
            trends=self._trends,
            report_command=f"bayestribo report {self.out}",
            population_runs=self._population_runs,
            population_note=self._population_note,
            updated_utc=_utc(),
        )

    def write_page(self, *, final: bool = False) -> None:
        """Rewrite the live page and its status file (atomically); a ``final`` page is
        not reloaded by the browser."""
        state = self._page_state()
        self._page_stale, self._last_page = False, time.monotonic()
        refresh = None if final else PAGE_REFRESH_S
        write_atomic(self.page, render_page(state, refresh_s=refresh))
        write_atomic(self.out / STATUS_NAME, json.dumps(status(state), indent=1) + "\n")

    def _refresh_page(self) -> None:
        """Rewrite the page now if the fit queue is empty or the page is
        ``page_every_s`` old; otherwise later, when one of these holds."""
        self._page_stale = True
        # a fit answered and being saved keeps no answer from the page
        saving = all(p in self._announced for p in self._running.values())
        idle = not self._queue and saving
        if idle or time.monotonic() - self._last_page >= self.options.page_every_s:
            self.write_page()

    # -- fits ---------------------------------------------------------------------------
    def _fit(self, pool: Any, path: Path, announced: Future[Any]) -> Any:
        """Fitter thread: fit one run file on the warm pool, recorded in the catalog;
        ``announced`` is resolved with its outcome as soon as the fit is back, before
        it is saved and recorded."""
        from bayestribo.campaign.digest import digest_fit
        from bayestribo.campaign.fitting import fit_catalogued

        keep = functools.partial(digest_fit, prob=self.prob, seed=self.spec.seed)
        (outcome,) = fit_catalogued(
            [path],
            self.catalog,
            self.out / "fits",
            pool,
            campaign_seed=self.spec.seed,
            progress=False,
            root=self.folder,
            keep=keep,
            announce=functools.partial(_resolve, announced),
            spec=self.spec,
        )
        return outcome

    def _finished(self, path: Path, outcome: Any) -> bool:
        """A fit saved and recorded (or not): answered now unless its announcement
        was, and again where it was answered as a fit and could not be recorded.
        True when a line was printed."""
        self._announcing.pop(path, None)
        announced = self._announced.pop(path, None)
        if announced is None:
            self._answer(path, outcome)
        elif announced and not outcome.ok:
            self._answer(path, outcome, count=False)
        else:
            return False
        return True

    def _answer(self, path: Path, outcome: Any, *, count: bool = True) -> None:
        answer = answer_of(outcome, path)
        key = str(path)
        self.answers.pop(key, None)  # a new version of a run goes to the end
        self.answers[key] = answer
        if outcome.ok:
            self.digests[key] = outcome.result
        else:
            self.digests.pop(key, None)
        self.n_answered += count
        text = json.dumps(answer.to_dict()) if self.json_lines else answer.line()
        print(text, file=self.stream, flush=True)

    def _warm_here(self, result: Any) -> None:
        """What this process does with a fit, once, on the warm-up's result: save it,
        read it back, digest it (the imports of each, before the first run)."""
        from bayestribo.campaign.digest import digest_fit
        from bayestribo.campaign.fitting import _load_fit

        partial = self.out / f".warm-up.{os.getpid()}.nc"
        try:
            result.save(partial)
            digest_fit(_load_fit(str(partial)), prob=self.prob, seed=self.spec.seed)
        finally:
            partial.unlink(missing_ok=True)

    # -- populations --------------------------------------------------------------------
    def _populations_of(self, digests: list[Any]) -> Any:
        """Population thread: the campaign analysis of the runs answered so far."""
        from bayestribo.campaign.analysis import analyse_campaign

        return analyse_campaign(
            digests,
            self.by,
            covariate=self.covariate,
            dissipation=self.dissipation,
            prob=self.prob,
            seed=self.spec.seed,
            max_steps=self.population_steps,
        )

    def _take_populations(self, analysis: Any, n_runs: int) -> None:
        quantities = {**analysis.quantities, **analysis.dissipation_quantities}

        def symbol(name: str) -> str:
            q = quantities.get(name, {})
            unit, text = str(q.get("unit") or "1"), str(q.get("symbol") or name)
            return text if unit in ("1", "-") else f"{text} [{unit}]"

        self._populations = [
            {**r, "symbol": symbol(r["parameter"]), "label": self.label(r["group"])}
            for r in analysis.group_rows()
        ]
        self._trends = [
            {
                **r,
                "symbol": symbol(r["parameter"]),
                "label": self.label(str(r["series"]).split(":", 1)[-1]),
            }
            for r in analysis.trend_rows()
        ]
        self._population_runs = n_runs
        self._population_note = (
            "" if analysis.converged else "A population sampler did not converge."
        )
        failures = [{"run": a.run, "error": a.error} for a in self.answers.values() if not a.ok]
        report = {
            **analysis.to_dict(),
            "failures": failures,
            "n_runs": len(self.answers),
            "n_cached": sum(a.cached for a in self.answers.values()),
            "catalog": str(self.catalog),
            "settings": self.settings,
        }
        write_atomic(self.out / "population.json", json.dumps(report, indent=2, default=str) + "\n")

    # -- the loop -----------------------------------------------------------------------
    def run(self) -> int:
        """Watch until ``max_runs``, ``timeout_s`` or Ctrl-C. After the first two the
        populations take in the last answers before the final page is written; after
        Ctrl-C they are left as they were.

        Returns
        -------
        int
            0 when every run answered was fitted and converged, 1 when one failed or did
            not converge, 130 when stopped by Ctrl-C (or SIGTERM).
        """
        from bayestribo._workers import stop_workers

        self._start = time.monotonic()
        self.out.mkdir(parents=True, exist_ok=True)
        self.write_page()
        self._pool = self._new_pool()
        fitters = ThreadPoolExecutor(self.options.workers, thread_name_prefix="watch-fit")
        interrupted = False
        try:
            self._warm()
            self._watch_events()
            self.say(f"live page: {self.page.resolve().as_uri()}")
            while self.stopped_by is None:
                self._step(fitters)
        except KeyboardInterrupt:
            interrupted = True
            self.stopped_by = "stopped by Ctrl-C"
            # the fits running are dropped: their workers end now, not when they finish,
            # and a fit about to start (its file being registered) is refused
            stop_workers(self._pool)
            self._pool.shutdown(wait=False, cancel_futures=True)
        finally:
            for future in self._running:
                future.cancel()
            # a fit that finished is saved and recorded by its thread: waited for
            fitters.shutdown(wait=True, cancel_futures=True)
            self._pool.shutdown(wait=True, cancel_futures=True)
            if self._wakeup is not None:
                self._wakeup.stop()
            for future, path in self._running.items():
                if not future.done() or future.cancelled() or future.exception() is not None:
                    continue
                if path in self._announced:
                    # answered: a recording that failed is said
                    self._finished(path, future.result())
                elif interrupted and future.result().ok:
                    # the fits that ended as the watch stopped are recorded: said too
                    self._answer(path, future.result())
        if not interrupted:
            # the last answers in the populations too, before the page is final; after
            # Ctrl-C a population under way is not waited for (its daemon thread writes
            # nothing: this thread writes the page and population.json)
            self._last_populations()
        self._state = self.stopped_by or "stopped"
        self.write_page(final=True)
        answers = f"{self.n_answered} answer" + ("" if self.n_answered == 1 else "s")
        self.say(f"{self._state}: {answers}; page {self.page.resolve().as_uri()}")
        if interrupted:
            return 130
        bad = any(not a.ok or not a.converged for a in self.answers.values())
        return 1 if bad else 0

    def _watch_events(self) -> None:
        """Wake on the folder's changes (its output folder and catalog left out); where
        the system gives none, the folder is polled alone, and the user told."""
        catalog = str(self.catalog)
        own = [self.out, *(catalog + end for end in ("", "-journal", "-wal", "-shm"))]
        wakeup = Wakeup(self.folder, exclude=own)
        reason = wakeup.start()
        if reason is None:
            self._wakeup = wakeup
        else:
            self.say(
                f"no change events from {self.folder} ({reason}): looking at it every "
                f"{self.options.poll_s:g} s (--poll)"
            )

    def _new_pool(self) -> Any:
        """The warm workers' pool (forkserver on Linux: workers start clean of this
        process's threads); they end with this process."""
        from bayestribo._workers import process_pool

        method = "forkserver" if sys.platform.startswith("linux") else None
        return process_pool(self.options.workers, method=method)

    def _warm(self) -> None:
        """Send the warm-up to every worker; this process imports meanwhile (what a fit's
        thread needs here is imported before any runs: Ctrl-C stops an import, not a
        thread)."""
        if self.warm_up is None:
            self._state = "watching"
        else:
            if self.options.workers > 1:
                # the laws the fits need compiled once, by as many workers, before each
                # worker's warm-up would compile them all (fitting.compile_laws_first)
                from bayestribo.campaign.fitting import compile_laws_first

                compile_laws_first([{"spec": self.spec}], self.say)
            workers = range(self.options.workers)
            self._warming = {self._pool.submit(self.warm_up, self.spec) for _ in workers}
            self.say("warming up the fit (imports and compiled kernels) ...")
        import importlib

        # what handling a fit needs here: the fit's result and digest, and what saving
        # and reading it back import (ArviZ, xarray, netCDF4: seconds, once)
        for module in _HANDLING_IMPORTS:
            with contextlib.suppress(ImportError):
                importlib.import_module(module)

    def _step(self, fitters: ThreadPoolExecutor) -> None:
        """One turn of the loop: look at the folder, start fits, take what finished."""
        opts = self.options
        if opts.timeout_s is not None and time.monotonic() - self._start >= opts.timeout_s:
            self.stopped_by = f"stopped after --timeout {opts.timeout_s:g} s"
            return
        # armed before the look: a change after it wakes the wait below
        changed = self._wakeup.armed() if self._wakeup is not None else None
        fresh = self.arrivals.poll()
        busy = set(self._running.values())
        self._queue.extend(p for p in fresh if p not in self._queue and p not in busy)
        started = False
        while self._queue and len(self._running) < opts.workers and not self._warming:
            path = self._queue.popleft()
            announced: Future[Any] = Future()
            self._announcing[path] = announced
            self._running[fitters.submit(self._fit, self._pool, path, announced)] = path
            started = True
        if fresh or started:
            self._refresh_page()
        watched = set(self._running) | set(self._announcing.values()) | self._warming
        if self._population is not None:
            watched.add(self._population)
        if changed is not None:
            watched.add(changed)
        # the next look: at a change, when a file waiting to settle is due, at the
        # watch's end, and at the latest after poll_s
        waits = [opts.poll_s, self.arrivals.next_due()]
        if opts.timeout_s is not None:
            waits.append(opts.timeout_s - (time.monotonic() - self._start))
        if self._page_stale:
            waits.append(opts.page_every_s - (time.monotonic() - self._last_page))
        timeout = max(0.0, min(w for w in waits if w is not None))
        if watched:
            done, _ = wait(watched, timeout=timeout, return_when=FIRST_COMPLETED)
        else:
            time.sleep(timeout)
            done = set()
        self._warmed(done & self._warming)
        answered = False
        for path, future in list(self._announcing.items()):
            if self.stopped_by is None and future.done():
                del self._announcing[path]
                outcome = future.result()
                self._answer(path, outcome)
                self._announced[path] = outcome.ok
                answered = True
                self._count_answers()
        for future in [f for f in done if f in self._running]:
            if self.stopped_by is None or self._running[future] in self._announced:
                answered |= self._finished(self._running.pop(future), future.result())
                self._count_answers()
        if answered:
            self._changed = True
            self._refresh_page()
        if answered and getattr(self._pool, "_broken", False) and not self._running:
            # a worker died (killed, out of memory): its run is answered with the
            # error, and the runs after it go to new warm workers
            self.say("a fit's worker process died; starting new workers")
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool()
            self._warm()
        if self._population is not None and self._population.done():
            self._take(self._population)
            self._population = None
            self._refresh_page()
        if self.stopped_by is None:
            self._populations_due()
        if self._page_stale:
            self._refresh_page()

    def _count_answers(self) -> None:
        """Stop once ``max_runs`` runs are answered."""
        most = self.options.max_runs
        if self.stopped_by is None and most is not None and self.n_answered >= most:
            self.stopped_by = f"stopped after --max-runs {most}"

    def _warmed(self, done: set[Future[Any]]) -> None:
        for future in done:
            self._warming.discard(future)
            try:
                self._warm_here(future.result())
            except Exception as exc:  # the runs' own fits say what is wrong
                self.say(f"the warm-up fit failed ({type(exc).__name__}: {exc})")
        if done and not self._warming:
            self.say(f"warm after {time.monotonic() - self._start:.1f} s")
            self._state = "watching"
            self._refresh_page()

    def _populations_due(self) -> None:
        """Start the populations when the fit queue is empty, or when the last ones are
        ``population_every_s`` old, if runs were answered since."""
        if not self._changed or self._population is not None or not self.digests:
            return
        idle = not self._queue and not self._running
        due = time.monotonic() - self._last_population >= self.options.population_every_s
        if idle or due:
            digests = list(self.digests.values())
            self._population = _in_background(self._populations_of, digests)
            self._population_started = len(digests)
            self._last_population = time.monotonic()
            self._changed = False

    def _take(self, population: Future[Any]) -> None:
        """The populations computed, on the page and in ``population.json``; or why not."""
        try:
            self._take_populations(population.result(), self._population_started)
        except BayestriboError as exc:
            self._population_note = f"Not computed: {exc}"
        except Exception as exc:  # the watch goes on; the page says why
            self._population_note = f"Failed: {type(exc).__name__}: {exc}"

    def _last_populations(self) -> None:
        if self._population is not None:
            self._take(self._population)
            self._population = None
        if self._changed and self.digests:
            digests = list(self.digests.values())
            self._population = _in_background(self._populations_of, digests)
            self._population_started = len(digests)
            self._take(self._population)
            self._population = None
