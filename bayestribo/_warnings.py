"""Warnings that point at the user's line, however deep in the package they arise."""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Callable
from typing import Any

__all__ = ["moved", "warn"]


def warn(message: str, category: type[Warning]) -> None:
    """Issue ``message`` as ``category``, attributed to the first caller outside the package.

    A fixed ``stacklevel`` is right for one call path only: a reader's warning reached
    through ``read_run``, ``fit`` or a campaign sits at different depths. This one
    walks the stack past every ``bayestribo`` frame, so the warning names the user's
    script or notebook cell (and the default filter shows it once per line there).
    """
    frame = sys._getframe(1)
    level = 2
    while frame is not None and frame.f_globals.get("__name__", "").startswith("bayestribo"):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level - 1 if frame is None else level)


def moved(old: str, new: str, names: frozenset[str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for public names that moved from module ``old`` to ``new``.

    Each access to a moved name through the old module issues a
    :class:`DeprecationWarning` naming the new module and returns the object itself
    (so ``isinstance`` checks and identities hold); any other name raises
    :class:`AttributeError` as usual.
    """

    def __getattr__(name: str) -> Any:
        if name not in names:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        warnings.warn(
            f"{old}.{name} has moved to {new}.{name}; import it from {new}",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(new), name)

    return __getattr__
