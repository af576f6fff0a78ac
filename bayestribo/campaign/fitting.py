"""Fit many runs on any executor, with per-run seeds from a campaign seed.

:func:`fit_many` submits one task per run to a :class:`concurrent.futures.Executor`
(a process pool with one worker per core by default; a Dask cluster through
``Client.get_executor()``, see :func:`dask_executor`). Each run's seed is derived from
the campaign seed and the run's *identity* (its ``run_id`` or file stem) with
:class:`numpy.random.SeedSequence`, never from the order of submission or of
completion, so the results do not depend on the executor or on the number of workers.
A failed run is reported with its error and traceback; the others go on.

:func:`fit_catalogued` does the same for run files and records every fit in the
results catalog (:mod:`bayestribo.campaign.catalog`), so that a re-run skips the runs already
fitted with the same data and settings.
"""

from __future__ import annotations

import dataclasses
import hashlib
import multiprocessing
import os
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, Future, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from bayestribo._files import atomic_path
from bayestribo._optional import require
from bayestribo._workers import process_pool
from bayestribo.errors import BayestriboError

__all__ = [
    "RunOutcome",
    "dask_executor",
    "fit_catalogued",
    "fit_many",
    "run_identities",
    "run_identity",
    "run_seed",
]


@dataclass(frozen=True)
class RunOutcome:
    """The outcome of one run's fit.

    Attributes
    ----------
    name : str
        The run's identity (:func:`run_identity`).
    seed : int
        The seed the run was fitted with (:func:`run_seed`).
    result : object or None
        What the fit function returned (a :class:`bayestribo.inference.FitResult` by
        default); None if it failed.
    error : str or None
        ``"ExceptionType: message"`` if the fit failed.
    traceback : str or None
        The formatted traceback of a failure (from the worker).
    elapsed_s : float
        Wall time of the fit in the worker [s] (nan when the worker did not report).
    cached : bool
        True when the result was read back from an earlier fit (:func:`fit_catalogued`).
    """

    name: str
    seed: int
    result: Any = None
    error: str | None = None
    traceback: str | None = None
    elapsed_s: float = float("nan")
    cached: bool = False

    @property
    def ok(self) -> bool:
        """True if the fit returned a result."""
        return self.error is None


def run_identity(run: Any) -> str:
    """The identity of a run: the file stem of a path, else its metadata ``run_id``.

    Raises
    ------
    BayestriboError
        If a run object carries no ``run_id`` (its seed could not be derived from
        what it is).
    """
    if isinstance(run, str | os.PathLike):
        return Path(run).stem
    metadata = getattr(run, "metadata", None)
    run_id = metadata.get("run_id") if isinstance(metadata, Mapping) else None
    if not isinstance(run_id, str) or not run_id:
        raise BayestriboError(
            f"runs: a {type(run).__name__} without metadata 'run_id'; give each run a "
            "run_id (or pass file paths) so that its seed follows from its identity"
        )
    return run_id


def run_identities(
    paths: Sequence[str | os.PathLike[str]], root: str | os.PathLike[str]
) -> list[str]:
    """The identities of a campaign's run files: each file's stem, or, for files whose
    stems clash, their paths in the campaign folder without the suffix.

    ``a/run1.csv`` and ``b/run1.csv`` are two runs, ``a/run1`` and ``b/run1``, with their
    own seeds; a file whose stem is unique keeps it (the bundled campaign's
    ``runs/glycerol-N0.31-r1.csv`` is ``glycerol-N0.31-r1``), so its seed and cached fit do
    not depend on the folder's layout. Two files with one path but another suffix
    (``run1.csv``, ``run1.txt``) keep one identity: :func:`fit_catalogued` leaves both out.

    Raises
    ------
    BayestriboError
        For a file that is not under ``root``.
    """
    stems = [Path(p).stem for p in paths]
    out = []
    for path, stem in zip(paths, stems, strict=True):
        if stems.count(stem) == 1:
            out.append(stem)
            continue
        try:
            # absolute, not resolved: a run file may be a link to a file elsewhere
            relative = Path(os.path.abspath(path)).relative_to(os.path.abspath(root))
        except ValueError:
            raise BayestriboError(f"runs: {path} is not in the campaign folder {root}") from None
        out.append(relative.with_suffix("").as_posix())
    return out


def run_seed(campaign_seed: int, identity: str) -> int:
    """The seed of one run: SeedSequence(campaign seed, SHA-256 of its identity).

    Returns a 63-bit non-negative integer, the same on every machine and executor.
    """
    if not isinstance(campaign_seed, int | np.integer) or campaign_seed < 0:
        raise BayestriboError(
            f"campaign_seed: expected a non-negative integer, got {campaign_seed!r}"
        )
    digest = hashlib.sha256(identity.encode("utf-8")).digest()
    words = np.frombuffer(digest, dtype="<u4").tolist()
    state = np.random.SeedSequence([int(campaign_seed), *words]).generate_state(2, np.uint32)
    return (int(state[0]) << 31) ^ int(state[1])


def _default_fit(run: Any, *, seed: int, **kwargs: Any) -> Any:
    from bayestribo.inference import fit  # lazily: the fit pulls in the sampler stack

    if kwargs.get("spec") is not None:
        # the run's own seed in its specification (recorded with the fit)
        from bayestribo.inference.spec import FitSpec

        return fit(run, **{**kwargs, "spec": FitSpec.of(kwargs["spec"]).replace(seed=seed)})
    return fit(run, seed=seed, **kwargs)


def _check_keywords(function: Callable[..., Any], kwargs: Mapping[str, Any]) -> None:
    """Refuse keyword arguments ``function`` does not take, before any run is fitted."""
    import difflib
    import inspect

    params = inspect.signature(function).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return
    known = [n for n, p in params.items() if p.kind is not inspect.Parameter.POSITIONAL_ONLY]
    unknown = sorted(set(kwargs) - set(known))
    if unknown:
        hints = [
            f"{name!r}"
            + "".join(f" (did you mean {c!r}?)" for c in difflib.get_close_matches(name, known, 1))
            for name in unknown
        ]
        raise BayestriboError(
            f"fit options: unknown {', '.join(hints)}; "
            f"{function.__name__} takes {', '.join(known[1:])}"
        )


def _call(
    function: Callable[..., Any], run: Any, seed: int, kwargs: Mapping[str, Any]
) -> tuple[Any, str | None, str | None, float]:
    """Worker side: run one fit, catching its error so that it travels as text."""
    start = time.perf_counter()
    try:
        result = function(run, seed=seed, **kwargs)
    except Exception as exc:  # reported per run; the campaign goes on
        return (
            None,
            f"{type(exc).__name__}: {exc}",
            traceback.format_exc(),
            time.perf_counter() - start,
        )
    return result, None, None, time.perf_counter() - start


class _Progress:
    """A minimal progress line on a stream: done/total, failures, elapsed, remaining."""

    def __init__(self, total: int, stream: IO[str] | None, enabled: bool) -> None:
        self.total, self.done, self.failed = total, 0, 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.start = time.perf_counter()
        self._draw()

    def update(self, ok: bool) -> None:
        self.done += 1
        self.failed += not ok
        self._draw()

    def _draw(self) -> None:
        if not self.enabled:
            return
        width = 30
        filled = width * self.done // max(self.total, 1)
        elapsed = time.perf_counter() - self.start
        left = f"{elapsed / self.done * (self.total - self.done):.0f}s" if self.done else "?"
        failed = f", {self.failed} failed" if self.failed else ""
        self.stream.write(
            f"\rfit runs [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total}"
            f"{failed} {elapsed:.0f}s elapsed, {left} left "
        )
        if self.done == self.total:
            self.stream.write("\n")
        self.stream.flush()


def fit_many(
    runs: Iterable[Any],
    executor: Executor | None = None,
    *,
    campaign_seed: int = 0,
    function: Callable[..., Any] | None = None,
    max_workers: int | None = None,
    progress: bool = True,
    progress_stream: IO[str] | None = None,
    callback: Callable[[RunOutcome], None] | None = None,
    names: Sequence[str] | None = None,
    run_kwargs: Sequence[Mapping[str, Any]] | None = None,
    keep: Callable[[Any], Any] | None = None,
    announce: Callable[[RunOutcome], None] | None = None,
    **fit_kwargs: Any,
) -> list[RunOutcome]:
    """Fit every run, in parallel, each with its own seed from the campaign seed.

    Parameters
    ----------
    runs : iterable
        Runs (:class:`bayestribo.io.run.Run` with a ``run_id``) or paths of run files.
    executor : concurrent.futures.Executor, optional
        Where to fit: any executor (a thread or process pool, a Dask
        ``Client.get_executor()``). Default: a process pool with ``max_workers``
        workers, created and shut down here.
    campaign_seed : int
        Seed of the campaign; run i is fitted with ``seed=run_seed(campaign_seed,
        run_identity(run))``.
    function : callable, optional
        ``function(run, seed=..., **fit_kwargs)`` fitting one run; default
        :func:`bayestribo.inference.fit` (imported in the worker). It must be picklable
        (a module-level function) for a process pool or a cluster.
    max_workers : int, optional
        Workers of the default process pool; default one per core. The pool starts
        its workers with the ``forkserver`` method (safe with threads), so a script
        that calls :func:`fit_many` must guard its top level with
        ``if __name__ == "__main__":``. With its own pool of two or more workers and
        the default ``function``, the laws the fits will need that the law cache lacks
        (every law of ``law="auto"``) are compiled first, once each, by as many
        worker processes (:mod:`bayestribo.model.laws.ahead`), not by every fit's
        worker at once.
    progress : bool
        Show a progress line on ``progress_stream`` (default standard error).
    callback : callable, optional
        Called in the calling process with each :class:`RunOutcome` as it completes
        (e.g. to record it in a catalog).
    names : sequence of str, optional
        The runs' identities (one per run, e.g. :func:`run_identities` of a campaign's
        files); default :func:`run_identity` of each.
    run_kwargs : sequence of mappings, optional
        Keyword arguments of ``function`` for each run (one mapping per run, in the
        order of ``runs``), over ``fit_kwargs``.
    keep : callable, optional
        What the outcomes hold of each result: ``keep(result)``, applied in the calling
        process (``callback`` still sees the whole result; e.g.
        :func:`bayestribo.campaign.digest.digest_fit`, so that memory does not grow
        with the number of runs). Default: the result itself.
    announce : callable, optional
        Called in the calling process with each :class:`RunOutcome` as it completes,
        its result as ``keep`` keeps it, before ``callback`` (a caller that shows each
        answer does not wait for its recording).
    **fit_kwargs
        Passed to ``function`` for every run.

    Returns
    -------
    list of RunOutcome
        One per run, in the order of ``runs``. Failed runs have ``error`` set.

    Raises
    ------
    BayestriboError
        If two runs have the same identity, a run has none, or ``campaign_seed`` is
        not a non-negative integer.
    """
    runs = list(runs)
    if names is None:
        names = [run_identity(run) for run in runs]
    elif len(names) != len(runs):
        raise BayestriboError(f"names: expected one per run ({len(runs)}), got {len(names)}")
    names = list(names)
    if run_kwargs is not None and len(run_kwargs) != len(runs):
        raise BayestriboError(
            f"run_kwargs: expected one mapping per run ({len(runs)}), got {len(run_kwargs)}"
        )
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise BayestriboError(f"runs: duplicate run identities {duplicates}")
    seeds = [run_seed(campaign_seed, name) for name in names]
    if function is None:
        from bayestribo.inference import fit

        _check_keywords(fit, fit_kwargs)
        function = _default_fit
    own = executor is None
    workers = max_workers or os.cpu_count() or 1
    if own and function is _default_fit and workers > 1:
        # the laws not yet compiled, compiled once by as many workers before the fits
        # (each fit would otherwise compile each law it needs, in every worker at once)
        compile_laws_first(
            [fit_kwargs, *(run_kwargs or [])],
            (lambda text: print(text, file=progress_stream or sys.stderr, flush=True))
            if progress
            else None,
        )
    if own:
        # forkserver: workers start from a clean process, safe when the caller runs
        # threads (progress bars, a Dask client, a GUI).
        # Workers end with this process, however it ends (bayestribo._workers).
        method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else None
        executor = process_pool(workers, method=method)
    assert executor is not None
    outcomes: list[RunOutcome | None] = [None] * len(runs)
    bar = _Progress(len(runs), progress_stream, progress)
    futures: dict[Future[Any], int] = {}
    try:
        for i, run in enumerate(runs):
            kwargs = {**fit_kwargs, **(run_kwargs[i] if run_kwargs is not None else {})}
            futures[executor.submit(_call, function, run, seeds[i], kwargs)] = i
        for future in as_completed(futures):
            # dropped as it is handled: a done future holds its whole result
            i = futures.pop(future)
            try:
                result, error, tb, elapsed = future.result()
            except Exception as exc:  # the executor lost the task (worker died, ...)
                result, error, tb = None, f"{type(exc).__name__}: {exc}", traceback.format_exc()
                elapsed = float("nan")
            if result is not None:
                _name_by_identity(result, names[i])
            outcome = RunOutcome(names[i], seeds[i], result, error, tb, elapsed)
            bar.update(outcome.ok)
            kept = outcome
            if keep is not None and outcome.ok:
                kept = dataclasses.replace(outcome, result=keep(outcome.result))
            if announce is not None:
                announce(kept)
            if callback is not None:
                callback(outcome)
            outcomes[i] = kept
            del kept
            del result, outcome, future
    except BaseException:
        for future in futures:
            future.cancel()
        if own:
            # interrupted: the fits still running are dropped, so their workers end
            # now rather than when those fits finish (minutes for a first fit that
            # compiles the kernels)
            from bayestribo._workers import stop_workers

            stop_workers(executor)
        raise
    finally:
        if own:
            executor.shutdown(wait=True, cancel_futures=True)
    return [o for o in outcomes if o is not None]


def _fit_laws(kwargs_list: Sequence[Mapping[str, Any]]) -> list[Any]:
    """The laws the fits with these keyword arguments compile (:class:`~bayestribo.
    model.laws.Law`, smallest first): every law ``law="auto"`` compares, or the law
    given (the default law where none is); none for fits on a nonlinear spring (other
    modules) or where a law or specification is not understood (the fit says why)."""
    from bayestribo.inference.choice import complexity, law_of
    from bayestribo.inference.comparison import auto_laws
    from bayestribo.inference.spec import FitSpec
    from bayestribo.model.laws.law import DEFAULT_LAW

    names: dict[str, None] = {}
    for kwargs in kwargs_list:
        try:
            spec = FitSpec.of(kwargs["spec"]) if kwargs.get("spec") is not None else None
        except Exception:
            continue
        # a keyword at its default (None) leaves the specification's field, as in fit
        law = kwargs.get("law")
        law = spec.law if law is None and spec is not None else law
        restoring = kwargs.get("restoring")
        restoring = spec.restoring if restoring is None and spec is not None else restoring
        if restoring is not None or not (law is None or isinstance(law, str)):
            continue
        for name in auto_laws() if law == "auto" else [law or DEFAULT_LAW]:
            names.setdefault(name)
    laws = []
    for name in names:
        try:
            laws.append(law_of(name))
        except BayestriboError:
            continue
    return sorted(laws, key=lambda law: complexity(law.name))


def compile_laws_first(
    kwargs_list: Sequence[Mapping[str, Any]], say: Callable[[str], None] | None = None
) -> int:
    """Compile the laws that fits with these keyword arguments of
    :func:`bayestribo.inference.fit` need and the law cache lacks, in worker processes,
    as many as the CPUs (:mod:`bayestribo.model.laws.ahead`), and wait for them:
    before a pool's workers fit, each of which would otherwise compile every law it
    needs, all of them the same laws at once.

    Parameters
    ----------
    kwargs_list : sequence of mappings
        The fits' keyword arguments (``law``, ``restoring`` or ``spec``).
    say : callable, optional
        Called with one line when laws are compiled.

    Returns
    -------
    int
        The number of laws compiled by the workers (0: none missing, or no workers).
    """
    from bayestribo.model.laws.ahead import compile_ahead

    laws = _fit_laws(kwargs_list)
    if not laws:
        return 0
    with compile_ahead() as ahead:
        count = ahead.submit(laws)
        if count and say is not None:
            say(
                f"compiling {count} laws on their first use, in {ahead.workers} worker "
                "processes (kept in the law cache for later runs)"
            )
        ahead.wait_all()
    return count


@contextmanager
def dask_executor(address: str | None = None, **cluster_kwargs: Any) -> Iterator[Executor]:
    """A Dask executor: on the scheduler at ``address``, or on a new local cluster.

    Parameters
    ----------
    address : str, optional
        Scheduler address (``tcp://host:8786``); None starts a
        ``dask.distributed.LocalCluster(**cluster_kwargs)`` for the duration.

    Raises
    ------
    MissingDependencyError
        If ``dask.distributed`` is not installed (the ``dask`` extra).
    """
    distributed = require("dask.distributed", "fitting on Dask")
    Client, LocalCluster = distributed.Client, distributed.LocalCluster
    if address is None:
        with LocalCluster(**cluster_kwargs) as cluster, Client(cluster) as client:
            yield client.get_executor()
    else:
        with Client(address) as client:
            yield client.get_executor()


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _function_name(function: Callable[..., Any] | None) -> str:
    if function is None:
        return "bayestribo.inference.fit"
    return f"{getattr(function, '__module__', '?')}.{getattr(function, '__qualname__', '?')}"


def _load_fit(path: str) -> Any:
    from bayestribo.inference import FitResult

    return FitResult.load(path)


def fit_catalogued(
    paths: Iterable[str | os.PathLike[str]],
    catalog: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    executor: Executor | None = None,
    *,
    campaign_seed: int = 0,
    function: Callable[..., Any] | None = None,
    loader: Callable[[str], Any] | None = None,
    refit: bool = False,
    max_workers: int | None = None,
    progress: bool = True,
    progress_stream: IO[str] | None = None,
    root: str | os.PathLike[str] | None = None,
    keep: Callable[[Any], Any] | None = None,
    announce: Callable[[RunOutcome], None] | None = None,
    **fit_kwargs: Any,
) -> list[RunOutcome]:
    """Fit run files with :func:`fit_many`, recording each fit in a results catalog.

    Each run file is registered in the catalog (SHA-256 and sidecar metadata). A run
    with a recorded fit of the same data, sidecar, settings (fit keyword arguments,
    seed, fit function) and package version whose result file still exists is not
    fitted again: its result is read back (``cached`` True). New fits are saved as
    ``<out_dir>/<identity>.nc`` and recorded as they complete, each in its own
    transaction, so an interrupted campaign keeps the fits it finished.

    A run's identity is its stem, or its path relative to ``root`` without the suffix
    where stems clash (:func:`run_identities`): ``a/run1.csv`` and ``b/run1.csv`` are two
    runs, ``a/run1`` and ``b/run1``, with their own seeds, catalog entries and fit files,
    and their fits carry that identity as ``run_id``. Two files with one identity
    (``run1.csv`` and ``run1.tdms`` side by side) are both left out, each with the
    reason.

    Parameters
    ----------
    paths : iterable of path-like
        Run files (each with its ``.json`` sidecar).
    catalog : path-like
        SQLite results catalog (:mod:`bayestribo.campaign.catalog`), created if absent.
    out_dir : path-like
        Folder of the per-run result files (created if absent).
    executor, campaign_seed, function, max_workers, progress, progress_stream, keep
        As in :func:`fit_many` (``keep`` applies to results read back too).
    root : path-like, optional
        The campaign folder (default: the files' common folder), for the identities of
        files whose stems clash.
    announce : callable, optional
        As in :func:`fit_many`: each new fit's outcome as soon as it is fitted, before
        it is saved and recorded (its final outcome says when that failed).
    **fit_kwargs
        As in :func:`fit_many`: with the default fit, a ``spec``
        (:class:`~bayestribo.inference.spec.FitSpec`) and keywords of
        :func:`bayestribo.fit` over it make one specification, recorded whole with each
        fit (a fit under another specification is another catalog entry, never read
        back for this one). The results must have ``save(path)``, ``summary()``,
        ``converged`` and ``diagnostics`` (as :class:`bayestribo.inference.FitResult`).
    loader : callable, optional
        Reads a saved result back; default :meth:`bayestribo.inference.FitResult.load`.
    refit : bool
        Fit every run even if a matching fit is recorded.

    Returns
    -------
    list of RunOutcome
        One per path, in order.

    A run whose sidecar cannot be read, whose ``run_id`` differs from its file's
    stem, or that the catalog refuses (another file registered under the same run
    id) is not fitted: its outcome carries the reason as ``error``.
    """
    from bayestribo import __version__
    from bayestribo.campaign.catalog import find_fit, record_fit, register_run
    from bayestribo.io.sidecar import read_sidecar, sidecar_path

    paths = [Path(p) for p in paths]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    loader = loader or _load_fit
    if root is None:
        root = os.path.commonpath([os.path.abspath(p.parent) for p in paths]) if paths else "."
    names = run_identities(paths, root)
    spec = None
    if function is None or fit_kwargs.get("spec") is not None:
        # the default fit: one specification of every run's fit, recorded with each
        spec, fit_kwargs = _campaign_spec(fit_kwargs)
    run_kwargs = [
        _identity_kwargs(path, name, fit_kwargs, spec)
        for path, name in zip(paths, names, strict=True)
    ]
    settings: list[dict[str, Any]] = []
    rows: list[int] = []
    outcomes: dict[int, RunOutcome] = {}
    for i, (path, name) in enumerate(zip(paths, names, strict=True)):
        side = sidecar_path(path)
        try:
            twins = [str(p) for p, n in zip(paths, names, strict=True) if n == name]
            if len(twins) > 1:
                raise BayestriboError(
                    f"files {twins} have one run identity {name!r}; rename one of them"
                )
            metadata = read_sidecar(side) if side.exists() else {}
            if metadata.get("run_id", path.stem) != path.stem:
                raise BayestriboError(
                    f"{side}: run_id {metadata['run_id']!r} differs from the file name "
                    f"{path.stem!r}"
                )
            metadata = {**metadata, "run_id": name}
            row = register_run(catalog, path=path, sha256=_sha256(path), metadata=metadata)
        except (BayestriboError, OSError) as exc:
            # This run is listed with its reason and left out; the others go on.
            seed = run_seed(campaign_seed, name)
            outcomes[i] = RunOutcome(name, seed, None, f"{type(exc).__name__}: {exc}")
            row = -1
        rows.append(row)
        settings.append(
            {
                # the whole specification: a fit under another one is another entry
                **({} if spec is None else {"spec": spec.to_dict()}),
                "fit_kwargs": _plain(
                    {k: v for k, v in {**fit_kwargs, **run_kwargs[i]}.items() if k != "spec"}
                ),
                "function": _function_name(function),
                "campaign_seed": int(campaign_seed),
                "seed": run_seed(campaign_seed, name),
                "sidecar_sha256": _sha256(side) if side.exists() else None,
            }
        )
    todo: list[int] = []
    for i, name in enumerate(names):
        if i in outcomes:
            continue
        record = (
            None
            if refit
            else find_fit(catalog, run=rows[i], settings=settings[i], package_version=__version__)
        )
        result_path = None if record is None else record.summary.get("result_path")
        recorded_sha = None if record is None else record.summary.get("result_sha256")
        if (
            result_path
            and Path(result_path).exists()
            and recorded_sha not in (None, _sha256(Path(result_path)))
        ):
            # the file is not the one recorded (a campaign with other settings wrote the
            # same run's file since, or it was cut short): a cache miss, fitted again
            if progress:
                print(
                    f"bayestribo campaign: the saved fit of {name} cannot be read as "
                    "recorded (the file changed since: a fit with other settings in the "
                    "same folder, or a file cut short); fitting it again",
                    file=progress_stream or sys.stderr,
                )
            todo.append(i)
            continue
        if result_path and Path(result_path).exists():
            seed = settings[i]["seed"]
            try:
                cached = loader(result_path)
            except Exception as exc:  # truncated, corrupt: a cache miss, fitted again
                if progress:
                    print(
                        f"bayestribo campaign: the saved fit of {name} cannot be read "
                        f"({type(exc).__name__}: {exc}); fitting it again",
                        file=progress_stream or sys.stderr,
                    )
                todo.append(i)
                continue
            outcomes[i] = RunOutcome(
                name, seed, cached if keep is None else keep(cached), cached=True
            )
            del cached
        else:
            todo.append(i)

    unrecorded: dict[str, str] = {}

    def record(outcome: RunOutcome) -> None:
        if not outcome.ok:
            return
        try:
            save_and_record(outcome)
        except Exception as exc:  # the fit stands; the run is reported as not recorded
            unrecorded[outcome.name] = f"{type(exc).__name__}: {exc}"

    def save_and_record(outcome: RunOutcome) -> None:
        i = names.index(outcome.name)
        target = out / f"{outcome.name}.nc"
        target.parent.mkdir(parents=True, exist_ok=True)
        # written under a temporary name and renamed: the catalog never records a
        # file that is not whole, and a kill or a full disk leaves no half-written fit
        with atomic_path(target) as partial:
            outcome.result.save(partial)
        record_fit(
            catalog,
            run=rows[i],
            settings=settings[i],
            summary={
                "result_path": str(target.resolve()),
                "result_sha256": _sha256(target),
                "converged": bool(outcome.result.converged),
                "posterior": {
                    k: v.to_dict() if hasattr(v, "to_dict") else v
                    for k, v in outcome.result.summary().items()
                },
                "elapsed_s": outcome.elapsed_s,
            },
            diagnostics=outcome.result.diagnostics,
            package_version=__version__,
        )

    fitted = (
        fit_many(
            [paths[i] for i in todo],
            executor,
            campaign_seed=campaign_seed,
            function=function,
            max_workers=max_workers,
            progress=progress,
            progress_stream=progress_stream,
            callback=record,
            names=[names[i] for i in todo],
            run_kwargs=[run_kwargs[i] for i in todo],
            keep=keep,
            announce=announce,
            **fit_kwargs,
        )
        if todo
        else []
    )
    for i, o in zip(todo, fitted, strict=True):
        if o.name in unrecorded:
            error = f"fitted but not saved or recorded: {unrecorded[o.name]}"
            o = RunOutcome(o.name, o.seed, o.result, error, None, o.elapsed_s)
        outcomes[i] = o
    return [outcomes[i] for i in range(len(paths))]


def _campaign_spec(fit_kwargs: Mapping[str, Any]) -> tuple[Any, dict[str, Any]]:
    """The :class:`~bayestribo.inference.spec.FitSpec` of ``fit_kwargs`` (its ``spec``,
    with the keywords of :func:`bayestribo.fit` that are fields of one over it), and the
    keywords left (``progress``, ``noise``, ...)."""
    from bayestribo.inference.spec import FitSpec, spec_fields

    keywords = {f.metadata["keyword"] or f.name for f in spec_fields()}
    rest = {k: v for k, v in fit_kwargs.items() if k != "spec" and k not in keywords}
    given = {k: v for k, v in fit_kwargs.items() if k in keywords}
    try:
        spec = FitSpec.of(fit_kwargs.get("spec"), **given)
    except ValueError as exc:  # BayestriboError: naming the field
        raise BayestriboError(f"fit options: {exc}") from None
    return spec, rest


def _plain(value: Any) -> Any:
    """Keyword arguments as plain data for the catalog's settings (a specification as
    its dict)."""
    if hasattr(value, "to_dict") and hasattr(value, "fit_kwargs"):
        return value.to_dict()
    if hasattr(value, "as_kwargs"):
        return value.as_kwargs()
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _name_by_identity(result: Any, name: str) -> None:
    """Name a fit by its run's identity in the campaign (the outcome's, the catalog's and
    the seed's: :func:`run_identity`) where its run carries no ``run_id``: else it keeps
    its file's path as its name, and the analysis, which names runs by ``run_id`` or
    name, would not find it among the runs of the same identity (a report's ΔE(A)
    panels came out empty)."""
    metadata = getattr(result, "metadata", None) or {}
    attrs = getattr(result, "attrs", None)
    if not metadata.get("run_id") and isinstance(attrs, dict):
        attrs["run_name"] = name


def _identity_kwargs(
    path: Path, name: str, fit_kwargs: Mapping[str, Any], spec: Any = None
) -> dict[str, Any]:
    """The keywords that give a run in a sub-folder its identity as ``run_id`` (the
    reading options of ``fit_kwargs``, or the ``spec``'s, with it in their metadata);
    with a ``spec``, that run's specification (``{"spec": ...}``) in any case."""
    from bayestribo.io.options import ReadOptions

    if spec is not None and name == path.stem:
        return {"spec": spec}
    if name == path.stem:
        return {}
    options = ReadOptions.of(fit_kwargs.get("read_options") if spec is None else spec.read_options)
    metadata = {**(options.metadata or {}), "run_id": name}
    if spec is not None:
        return {"spec": spec.replace(read_options=options.replace(metadata=metadata))}
    return {"read_options": options.replace(metadata=metadata).as_kwargs()}
