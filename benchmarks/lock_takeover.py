"""Many processes taking over a stale campaign lock at one instant: how many own it?

A campaign's output folder is locked by :class:`bayestribo.campaign.lock.FolderLock`.
Here the folder holds the lock file of a process that has ended (a killed campaign), and
``--takers`` processes (forked, all started before any goes on) try to take the folder
at the same instant: each waits at a barrier, tries the lock, and a process that got it
holds it until every process has tried (a second barrier), so that all owners are
counted at once. Exactly one must own it; ``double_owners`` (owners beyond the first)
must be 0. Several rounds, each with a fresh stale lock.

``--old COMMIT`` runs the same on the lock of another commit (its
``bayestribo/campaign/lock.py``, read with ``git show``) for comparison.

Run: ``PYTHONPATH=. python benchmarks/lock_takeover.py [--takers 1000] [--rounds 1]``;
prints the counts and writes ``benchmarks/results/lock_takeover.json``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import socket
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results


def dead_pid() -> int:
    """The id of a process that has ended."""
    done = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(done.stdout)


def _taker(lock_class: Any, folder: Path, start: Any, tried: Any, counts: Any) -> None:
    """One process: wait for all, try the lock, hold it (if got) until all have tried."""
    from bayestribo.errors import BayestriboError

    start.wait(timeout=600)
    try:
        with lock_class(folder) as lock:
            with counts.get_lock():
                counts[0] += 1
                counts[1] += lock.took_over is not None
            tried.wait(timeout=600)
    except BayestriboError as exc:
        with counts.get_lock():
            counts[2 if "another" in str(exc) else 3] += 1
        tried.wait(timeout=600)


def one_round(lock_module: types.ModuleType, takers: int) -> dict[str, int]:
    """``takers`` processes on a folder with a stale lock: the counts."""
    context = multiprocessing.get_context("fork")
    with tempfile.TemporaryDirectory(prefix="lock-takeover-") as tmp:
        folder = Path(tmp)
        stale = {"pid": dead_pid(), "host": socket.gethostname(), "started": time.time()}
        (folder / lock_module.LOCK_NAME).write_text(json.dumps(stale))
        start, tried = context.Barrier(takers), context.Barrier(takers)
        # owners, of them taking over a stale lock, refused naming the owner, other errors
        counts = context.Array("i", 4)
        procs = [
            context.Process(
                target=_taker, args=(lock_module.FolderLock, folder, start, tried, counts)
            )
            for _ in range(takers)
        ]
        for p in procs:
            p.start()
        for p in procs:
            p.join()
        crashed = sum(p.exitcode != 0 for p in procs)
        owners, took_over, refused, errors = list(counts)
    return {
        "owners": owners,
        "double_owners": max(owners - 1, 0),
        "took_over": took_over,
        "refused": refused,
        "other_errors": errors,
        "crashed": crashed,
    }


def old_module(revision: str) -> types.ModuleType:
    """The lock module of another commit."""
    source = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{revision}:bayestribo/campaign/lock.py"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    module = types.ModuleType(f"lock_{revision}")
    exec(compile(source, f"{revision}:bayestribo/campaign/lock.py", "exec"), module.__dict__)
    return module


def run(lock_module: types.ModuleType, takers: int, rounds: int) -> dict[str, Any]:
    start = time.perf_counter()
    each = [one_round(lock_module, takers) for _ in range(rounds)]
    total = {key: sum(r[key] for r in each) for key in each[0]}
    return {
        **total,
        "rounds_with_double_owners": sum(r["double_owners"] > 0 for r in each),
        "per_round": each,
        "seconds": round(time.perf_counter() - start, 2),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--takers", type=int, default=1000, help="processes per round")
    parser.add_argument("--rounds", type=int, default=1, help="rounds, each a fresh stale lock")
    parser.add_argument("--old", metavar="COMMIT", help="also run the lock of this commit")
    args = parser.parse_args()

    from bayestribo.campaign import lock

    load_start = os.getloadavg()
    results: dict[str, Any] = {
        "settings": {"takers": args.takers, "rounds": args.rounds, "locking": lock.LOCKING},
        "commit": commit(),
        "load_average_start": load_start,
    }
    runs = {"current": lock}
    if args.old:
        runs[f"old ({args.old})"] = old_module(args.old)
    for name, module in runs.items():
        results[name] = run(module, args.takers, args.rounds)
        shown = {k: v for k, v in results[name].items() if k != "per_round"}
        print(f"{name}: {json.dumps(shown)}")
    results["load_average_end"] = os.getloadavg()
    print(write_results("lock_takeover", results))


if __name__ == "__main__":
    main()
