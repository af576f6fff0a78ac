"""Warnings that point at the user's line, however deep in the package they arise."""

from __future__ import annotations

import sys
import warnings

__all__ = ["warn"]


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
