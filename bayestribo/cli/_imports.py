"""Import the fitting machinery with the cyclic garbage collector paused.

Importing numba, SciPy, emcee and the package's inference modules allocates some
hundreds of thousands of objects that live as long as the process. Every few
thousand allocations the collector runs, and its oldest generation scans all of them
again: work wasted, since none of them is garbage. :func:`import_module` pauses the
collector for the import (and resumes it after, as it was); in a process the command
line owns (:func:`own_process`), it also moves what exists then to the collector's
permanent generation (:func:`gc.freeze`), which the fit's own collections and the one
at the interpreter's exit never scan. Nothing is changed in a third-party module.
"""

from __future__ import annotations

import gc
import importlib
from types import ModuleType

__all__ = ["import_module", "own_process"]

_state = {"own_process": False}


def own_process(owned: bool = True) -> None:
    """Say whether the command line owns this process (run as ``bayestribo``).

    Only then are the imported objects frozen for the rest of the process: a caller of
    :func:`bayestribo.cli.main.main` in its own process keeps its collector as it was.
    """
    _state["own_process"] = owned


def import_module(name: str) -> ModuleType:
    """Import the module ``name`` with the cyclic collector paused.

    Parameters
    ----------
    name : str
        Dotted module name, e.g. ``"bayestribo.inference"``.

    Returns
    -------
    ModuleType
        The module, as :func:`importlib.import_module` returns it.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        module = importlib.import_module(name)
    finally:
        if enabled:
            gc.enable()
    if _state["own_process"]:
        gc.freeze()
    return module
