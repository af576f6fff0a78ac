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
from concurrent.futures import Executor
from typing import Any, TypeVar

__all__ = ["run_jobs"]

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
    if executor is None or len(jobs) < 2:
        return [function(*job) for job in jobs]
    futures = [executor.submit(_recorded, function, tuple(job)) for job in jobs]
    out = []
    for future in futures:
        result, caught = future.result()
        for message, category in caught:
            warnings.warn(message, category, stacklevel=2)
        out.append(result)
    return out
