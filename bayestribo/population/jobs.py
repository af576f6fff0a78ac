"""Independent samplers side by side on an executor, their warnings carried back.

The groups of a population, the trends of a campaign's series and ζ₀ are independent
posteriors: :func:`run_jobs` samples them on any :class:`concurrent.futures.Executor`
(a process pool, Dask's) or in series without one. Every job's seed follows from what it
is (a group's label), not from the order it runs in, so the results do not depend on the
executor. Warnings a job raises in a worker process would be printed there, unformatted,
or lost: they are recorded in the worker and given again in the caller, in job order.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed
from typing import Any, TypeVar

__all__ = ["run_calls", "run_jobs"]

T = TypeVar("T")


def _recorded(function: Callable[..., T], args: tuple[Any, ...]) -> tuple[T, list[tuple]]:
    """Worker side: run ``function(*args)`` and record its warnings as plain data."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = function(*args)
    return result, [(str(w.message), w.category) for w in caught]


def run_jobs(
    function: Callable[..., T],
    jobs: Sequence[tuple[Any, ...]],
    executor: Executor | None = None,
) -> list[T]:
    """``[function(*job) for job in jobs]``, on ``executor`` when one is given.

    Parameters
    ----------
    function : callable
        A module-level function (picklable for a process pool).
    jobs : sequence of tuple
        Positional arguments of each call.
    executor : Executor, optional
        Where to run the calls; None runs them here, in order.

    Returns
    -------
    list
        The results, in the order of ``jobs``.
    """
    return run_calls([(function, tuple(job)) for job in jobs], executor)


def run_calls(
    calls: Sequence[tuple[Callable[..., Any], tuple[Any, ...]]],
    executor: Executor | None = None,
    costs: Sequence[float] | None = None,
    done: Callable[[int, int], None] | None = None,
) -> list[Any]:
    """``[function(*args) for function, args in calls]``, on ``executor`` when one is given.

    Unlike :func:`run_jobs` the calls may be of different functions, so that every
    independent posterior of a campaign (groups, pooled populations, trends) shares one
    queue and no worker waits for the last job of a phase.

    Parameters
    ----------
    calls : sequence of (callable, tuple)
        Module-level functions (picklable for a process pool) and their positional
        arguments.
    executor : Executor, optional
        Where to run the calls; None runs them here, in order.
    costs : sequence of float, optional
        Relative cost of each call; on an executor the costliest are submitted first
        (longest first keeps the workers busy to the end). The results and the order
        of the warnings given again do not depend on it.
    done : callable, optional
        ``done(finished, total)`` after each call completes (progress of a long queue).

    Returns
    -------
    list
        The results, in the order of ``calls``.
    """
    if costs is not None and len(costs) != len(calls):
        raise ValueError(f"costs: expected {len(calls)} values, one per call, got {len(costs)}")
    total = len(calls)
    if executor is None or total < 2:
        results = []
        for k, (function, args) in enumerate(calls, start=1):
            results.append(function(*args))
            if done is not None:
                done(k, total)
        return results
    order = range(total) if costs is None else sorted(range(total), key=lambda i: -costs[i])
    futures = {i: executor.submit(_recorded, calls[i][0], tuple(calls[i][1])) for i in order}
    if done is not None:
        for k, _ in enumerate(as_completed(futures.values()), start=1):
            done(k, total)
    out = []
    for i in range(len(calls)):
        result, caught = futures[i].result()
        for message, category in caught:
            warnings.warn(message, category, stacklevel=2)
        out.append(result)
    return out
