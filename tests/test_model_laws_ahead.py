"""Laws compiled ahead by worker processes (bayestribo/model/laws/ahead.py)."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import queue
import subprocess
import sys
import threading
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import pytest

from bayestribo.errors import BayestriboError
from bayestribo.model.laws import ahead, get_law
from bayestribo.model.laws.cache import CACHE_ENV
from bayestribo.model.laws.integrator import law_module

REPO = Path(__file__).resolve().parent.parent

#: In a fresh process with an empty law cache and one worker: two laws handed to the
#: worker, each then used here; numba's counts of the turning-point function's loads
#: from the cache (hits) and compilations here (misses).
END_TO_END = r"""
import json
with open("runs.txt", "a") as mark:  # a script without a __main__ guard: run once
    mark.write("ran\n")
from bayestribo.model.laws import get_law
from bayestribo.model.laws.ahead import compile_ahead
from bayestribo.model.laws.integrator import cached_functions, law_module, make_integrator
from bayestribo.model.laws.cache import law_cache_dir
laws = [get_law("coulomb"), get_law("viscous")]
names = [law_module(law._layout[0]) for law in laws]
before = [f"{n}.turns" in cached_functions(law_cache_dir()) for n in names]
with compile_ahead() as compiler:
    handed = compiler.submit(laws)
    workers = compiler.workers
    rows = []
    for law in laws:
        values = {p.name: 0.01 if p.name != "mu_s_ratio" else 1.0 for p in law.parameters}
        rows.append(law.turning_points(values, 1.0, tau_max=30.0)[1].tolist())
turns = [make_integrator(*law._layout[0])[1] for law in laws]
with compile_ahead() as again:
    handed_again = again.submit(laws)
print(json.dumps({
    "before": before,
    "after": [f"{n}.turns" in cached_functions(law_cache_dir()) for n in names],
    "handed": handed, "workers": workers, "handed_again": handed_again,
    "hits": [sum(t.stats.cache_hits.values()) for t in turns],
    "misses": [sum(t.stats.cache_misses.values()) for t in turns],
    "rows": rows,
}))
"""


def test_laws_compiled_by_a_worker_are_loaded_from_the_cache_not_compiled_again(
    tmp_path: Path,
) -> None:
    env = {
        **os.environ,
        CACHE_ENV: str(tmp_path / "laws"),
        ahead.WORKERS_ENV: "1",
        "PYTHONPATH": str(REPO),
    }
    script = tmp_path / "script.py"
    script.write_text(END_TO_END)
    done = subprocess.run(
        [sys.executable, str(script)],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.splitlines()[-1])
    # the workers did not run the command's script again (multiprocessing's would)
    assert (tmp_path / "runs.txt").read_text() == "ran\n"
    assert out["before"] == [False, False]
    assert out["workers"] == 1 and out["handed"] == 2
    # both compiled by the worker: loaded here, never compiled here
    assert out["hits"] == [1, 1] and out["misses"] == [0, 0]
    assert out["after"] == [True, True]
    assert out["handed_again"] == 0  # in the cache now: nothing for a worker to do
    # the turning points of the code the worker compiled: Coulomb's fall by 2 μ_k a
    # half cycle (Eq. 20), viscous damping's by exp(-πζ/√(1-ζ²))
    coulomb, viscous = out["rows"]
    assert coulomb[:3] == pytest.approx([1.0, -0.98, 0.96], abs=1e-12)
    ratio = -viscous[1] / viscous[0]
    assert ratio == pytest.approx(math.exp(-math.pi * 0.01 / math.sqrt(1 - 1e-4)), rel=1e-8)


class _Worker:
    """A stand-in worker process: records each law it is sent and answers when the test
    says (``answer``), an empty line standing for a worker that ended."""

    def __init__(self) -> None:
        self.sent: list[str] = []
        self.written = threading.Semaphore(0)
        self.answers: queue.Queue[str] = queue.Queue()
        self.stdin = self
        self.stdout = self
        self.killed = False

    def write(self, line: str) -> None:
        self.sent.append(line.split("\t")[0])
        self.written.release()

    def flush(self) -> None:
        pass

    def close(self) -> None:
        pass

    def readline(self) -> str:
        return self.answers.get(timeout=120)  # a hang fails the test, not the suite

    def wait(self, timeout: float | None = None) -> int:
        return 0

    def poll(self) -> int | None:
        return 0

    def kill(self) -> None:
        self.killed = True


@pytest.fixture
def one_worker(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> _Worker:
    """One stand-in worker over an empty law cache."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "laws"))
    monkeypatch.setenv(ahead.WORKERS_ENV, "1")
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    worker = _Worker()
    monkeypatch.setattr(ahead.AheadCompiler, "_worker", lambda self: worker)
    return worker


def _module(name: str) -> str:
    module = law_module(get_law(name)._layout[0])
    assert module is not None
    return module


def test_a_law_no_worker_has_begun_is_taken_back_and_one_begun_is_waited_for(
    one_worker: _Worker,
) -> None:
    laws = [get_law("quadratic"), get_law("power"), get_law("hysteretic")]
    with ahead.compile_ahead() as compiler:
        assert compiler.submit(laws) == 3
        # one worker: the first law sent, the others waiting, in order
        assert one_worker.written.acquire(timeout=120)
        assert one_worker.sent == ["quadratic"]
        ahead.wait_for(_module("hysteretic"))  # taken back: compiled by the command
        assert [law for _, law in compiler._waiting] == ["power"]
        one_worker.answers.put(f"ok {_module('quadratic')}\n")  # the worker is done
        ahead.wait_for(_module("quadratic"))  # returns once it is
        assert one_worker.written.acquire(timeout=120)
        assert one_worker.sent == ["quadratic", "power"]
        one_worker.answers.put("")  # the worker ended: power is left to the command
        ahead.wait_for(_module("power"))
        assert compiler._running == {} and not compiler._waiting
    assert one_worker.sent == ["quadratic", "power"]
    assert ahead._active == []


def test_nothing_is_handed_out_without_workers(
    one_worker: _Worker, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(ahead.WORKERS_ENV, "0")
    with ahead.compile_ahead([get_law("quadratic")]) as compiler:
        assert compiler.workers == 0
    assert one_worker.sent == []


@pytest.mark.parametrize("value", ["two", "-1", "1.5"])
def test_a_bad_worker_count_is_named(monkeypatch: pytest.MonkeyPatch, value: str) -> None:
    monkeypatch.setenv(ahead.WORKERS_ENV, value)
    with pytest.raises(BayestriboError, match=ahead.WORKERS_ENV):
        ahead.worker_count(5)


def test_no_workers_on_one_cpu_or_inside_a_worker(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ahead.WORKERS_ENV, raising=False)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2, 3}, raising=False)
    assert ahead.worker_count(9) == 4
    assert ahead.worker_count(2) == 2
    monkeypatch.setenv(ahead.WORKERS_ENV, "3")
    assert ahead.worker_count(9) == 3
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    assert ahead.worker_count(9) == 0
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    monkeypatch.setattr("multiprocessing.parent_process", lambda: object())
    assert ahead.worker_count(9) == 0


def test_a_law_with_a_force_defined_in_main_is_left_to_the_command(
    one_worker: _Worker,
) -> None:
    import numba

    from bayestribo.model.laws import Law
    from bayestribo.model.laws.quadratic import QUADRATIC

    @numba.njit(cache=False)
    def force(w: float, c: object) -> float:  # pragma: no cover - not compiled here
        return 0.0

    local = Law((dataclasses.replace(QUADRATIC, force=force),))
    assert law_module(local._layout[0]) is None
    with ahead.compile_ahead([local]) as compiler:
        assert compiler.workers == 0
    assert one_worker.sent == []


def test_wait_all_returns_when_the_workers_have_compiled_every_law(one_worker: _Worker) -> None:
    laws = [get_law("quadratic"), get_law("power")]
    for law in laws:
        one_worker.answers.put(f"ok {_module(law.name)}\n")
    with ahead.compile_ahead() as compiler:
        assert compiler.submit(laws) == 2
        compiler.wait_all()
        assert one_worker.sent == ["quadratic", "power"]
        assert compiler._running == {} and not compiler._waiting


class _SerialPool:
    """Runs each task as it is submitted, recording the order of events."""

    def __init__(self, events: list[str]) -> None:
        self.events = events

    def submit(self, fn: Any, *args: Any) -> Future:
        self.events.append("fit")
        future: Future = Future()
        future.set_result(fn(*args))
        return future

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        pass


@pytest.mark.parametrize(
    ("workers", "given", "first"), [(2, False, True), (1, False, False), (2, True, False)]
)
def test_a_campaigns_laws_are_compiled_before_its_fits_where_its_own_pool_runs_them(
    monkeypatch: pytest.MonkeyPatch, workers: int, given: bool, first: bool
) -> None:
    from bayestribo.campaign import fitting

    events: list[str] = []
    asked: list[list] = []

    def compile_first(kwargs_list: list, say: Any) -> int:
        events.append("compile")
        asked.append(kwargs_list)
        return 0

    pool = _SerialPool(events)
    monkeypatch.setattr(fitting, "compile_laws_first", compile_first)
    monkeypatch.setattr(fitting, "process_pool", lambda *a, **k: pool)
    run = REPO / "data" / "runs" / "glycerol-N0.31-r1.csv"
    (outcome,) = fitting.fit_many(
        [run], pool if given else None, max_workers=workers, progress=False, law="coulomb"
    )
    assert outcome.ok
    assert events == (["compile", "fit"] if first else ["fit"])
    if first:
        assert asked == [[{"law": "coulomb"}]]


def test_the_laws_a_campaigns_fits_compile() -> None:
    from bayestribo.campaign.fitting import _fit_laws
    from bayestribo.inference.comparison import auto_laws
    from bayestribo.inference.spec import FitSpec

    names = [law.name for law in _fit_laws([{"spec": FitSpec.of({"law": "auto"})}])]
    assert sorted(names) == sorted(auto_laws()) and names[0] == "viscous"
    assert [law.name for law in _fit_laws([{"spec": FitSpec.of({})}])] == ["viscous+coulomb"]
    # a keyword at its default leaves the specification's law, as fit does
    spec = FitSpec.of({"law": "quadratic"})
    assert [law.name for law in _fit_laws([{"spec": spec, "law": None}])] == ["quadratic"]
    two = _fit_laws([{"law": "power"}, {"law": "quadratic"}, {"law": "power"}])
    assert [law.name for law in two] == ["quadratic", "power"]  # smallest first, once each
    # on a nonlinear spring (other modules), or a law not understood (the fit says why)
    assert _fit_laws([{"spec": FitSpec.of({"law": "auto", "restoring": "duffing"})}]) == []
    assert _fit_laws([{"law": "no-such-term"}, {"spec": {"law": 3}}]) == []


@pytest.mark.parametrize(("workers", "first"), [(2, True), (1, False)])
def test_a_watch_has_its_laws_compiled_before_its_workers_warm_up(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, workers: int, first: bool
) -> None:
    import io

    from bayestribo.campaign import fitting
    from bayestribo.campaign.watch import CampaignWatch, WatchOptions
    from bayestribo.inference.spec import FitSpec

    events: list[str] = []
    spec = FitSpec.of({"law": "auto"})

    def compile_first(kwargs_list: list, say: Any) -> int:
        assert kwargs_list == [{"spec": spec}]
        events.append("compile")
        return 0

    class Pool:
        def submit(self, fn: Any, *args: Any) -> Future:
            events.append("warm-up")
            return Future()

    monkeypatch.setattr(fitting, "compile_laws_first", compile_first)
    watch = CampaignWatch(
        tmp_path,
        tmp_path / "out",
        tmp_path / "out" / "catalog.sqlite",
        spec,
        WatchOptions(workers=workers),
        by=("load_N",),
        suffixes=[".csv"],
        stream=io.StringIO(),
        say=lambda message: None,
        warm_up=lambda spec: None,
    )
    watch._pool = Pool()
    watch._warm()
    assert events == (["compile"] if first else []) + ["warm-up"] * workers
