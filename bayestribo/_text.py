"""Text from the user (run ids, lubricant names, metadata values) on a figure or in a
message.

Matplotlib reads a pair of ``$`` in any text as mathematics: a lubricant named
``glycerol $\\alpha_$`` then fails to draw (a ParseSyntaxException from deep inside
matplotlib) after every table was written. Such text goes through :func:`literal`,
which escapes the dollar signs so that it is drawn as written. A value quoted in an
error message goes through :func:`shown`, which shortens it: a sidecar may hold a
number of 400 digits, or one beyond Python's conversion of integers to text.
"""

from __future__ import annotations

__all__ = ["literal", "shown"]


def literal(text: object) -> str:
    """``text`` as a string that matplotlib draws as written (no mathtext).

    Examples
    --------
    >>> literal("glycerol $\\\\alpha_$")
    'glycerol \\\\$\\\\alpha_\\\\$'
    """
    return str(text).replace("$", r"\$")


def shown(value: object) -> str:
    """``repr(value)`` for a message, shortened to 60 characters.

    Examples
    --------
    >>> shown(0.5)
    '0.5'
    >>> shown(10**5000)
    'a number too long to show'
    """
    try:
        text = repr(value)
    except ValueError:  # an integer beyond Python's string conversion limit
        return "a number too long to show"
    return text if len(text) <= 60 else text[:57] + "..."
