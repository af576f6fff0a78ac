"""Measurement of ``benchmarks/suite_cpu.py`` only: each Python process of a test run
writes, at its exit, its CPU and the CPU numba spent compiling (outermost
``numba:compile`` events) to ``$SUITECUT_LOG/<pid>.json``. Active only where
``SUITECUT_LOG`` is set; numba's event listener is registered when numba is first
imported, so processes that never import numba pay nothing for it."""

import atexit
import importlib.abc
import importlib.machinery
import json
import os
import sys
import time

_OUT = os.environ.get("SUITECUT_LOG")
_MODULES = ("arviz", "matplotlib", "nbclient", "ipykernel", "numba", "bayestribo")
_state = {"compile": 0.0, "n": 0, "depth": 0, "t": 0.0, "funcs": {}, "tests": {}}
#: The test this process was started in (a notebook kernel's, a command's), if any.
_STARTED_IN = os.environ.get("PYTEST_CURRENT_TEST")


def _test() -> str:
    """The test running now (its node id without the phase), or ``""``."""
    return (os.environ.get("PYTEST_CURRENT_TEST") or "").rsplit(" (", 1)[0]


def _register():
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            if _state["depth"] == 0:
                _state["t"] = time.process_time()
                _state["test"] = _test()
            _state["depth"] += 1

        def on_end(self, ev):
            _state["depth"] -= 1
            if _state["depth"] == 0:
                spent = time.process_time() - _state["t"]
                _state["compile"] += spent
                _state["n"] += 1
                function = getattr(ev.data["dispatcher"], "py_func", None)
                module = getattr(function, "__module__", "")
                name = f"{module}.{getattr(function, '__qualname__', '?')}"
                _state["funcs"][name] = _state["funcs"].get(name, 0.0) + spent
                tests = _state["tests"].setdefault(_state["test"], {})
                tests[name] = tests.get(name, 0.0) + spent

    event.register("numba:compile", Listener())


class _Hook(importlib.abc.MetaPathFinder):
    """Registers the listener right after ``numba`` itself is imported."""

    def find_spec(self, name, path, target=None):
        if name != "numba":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None:
            return None
        load = spec.loader.exec_module

        def exec_module(module):
            load(module)
            try:
                _register()
            except Exception as exc:
                _state["err"] = repr(exc)

        spec.loader.exec_module = exec_module
        return spec


def _dump():
    try:
        import resource

        usage = resource.getrusage(resource.RUSAGE_SELF)
        record = {
            "pid": os.getpid(),
            "ppid": os.getppid(),
            "argv": sys.argv[:6],
            "cpu": usage.ru_utime + usage.ru_stime,
            "compile": _state["compile"],
            "ncompile": _state["n"],
            "funcs": _state["funcs"],
            "worker": os.environ.get("PYTEST_XDIST_WORKER"),
            "started_in": _STARTED_IN,
            "compile_by_test": _state["tests"],
            "mods": [m for m in _MODULES if m in sys.modules],
        }
        with open(os.path.join(_OUT, f"{os.getpid()}.json"), "w") as fh:
            json.dump(record, fh)
    except Exception:
        pass


if _OUT:
    sys.meta_path.insert(0, _Hook())
    atexit.register(_dump)
    try:  # multiprocessing's children end with os._exit, after its finalizers
        import multiprocessing.util

        class _Child:
            """Registers the record again in a forked child, whose finalizers the child
            clears first (a forkserver's pool workers)."""

        _CHILD = _Child()
        multiprocessing.util.Finalize(None, _dump, exitpriority=-100)

        def _after_fork(_):
            # a forked child starts with its parent's record: it records only its own
            _state.update(compile=0.0, n=0, funcs={}, tests={})
            multiprocessing.util.Finalize(None, _dump, exitpriority=-100)

        multiprocessing.util.register_after_fork(_CHILD, _after_fork)
    except Exception:
        pass
