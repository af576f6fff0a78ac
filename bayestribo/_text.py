"""Text from the user (run ids, lubricant names, metadata values) on a figure.

Matplotlib reads a pair of ``$`` in any text as mathematics: a lubricant named
``glycerol $\\alpha_$`` then fails to draw (a ParseSyntaxException from deep inside
matplotlib) after every table was written. Such text goes through :func:`literal`,
which escapes the dollar signs so that it is drawn as written.
"""

from __future__ import annotations

__all__ = ["literal"]


def literal(text: object) -> str:
    """``text`` as a string that matplotlib draws as written (no mathtext).

    Examples
    --------
    >>> literal("glycerol $\\\\alpha_$")
    'glycerol \\\\$\\\\alpha_\\\\$'
    """
    return str(text).replace("$", r"\$")
