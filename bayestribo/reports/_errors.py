"""The reports' exception (its own module so every report module can raise it)."""

from __future__ import annotations

from bayestribo.errors import BayestriboError

__all__ = ["ReportError"]


class ReportError(BayestriboError):
    """A report notebook is missing, malformed, given a bad parameter, or failed while running."""
