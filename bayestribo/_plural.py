"""A count before its noun, in the number the count asks for: ``1 run``, ``2 runs``.

Reports and the command line put counts before nouns everywhere ("4 runs in air",
"2 ensembles", "1 file"): :func:`count` writes each, so that none reads "1 runs".
"""

from __future__ import annotations

__all__ = ["count"]


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and ``noun``, singular for one, plural otherwise.

    Parameters
    ----------
    n : int
        The count (a whole number; ``-1`` and ``0`` take the plural, as in English).
    noun : str
        The noun in the singular ("run", "half cycle": the last word takes the plural).
    plural : str, optional
        The plural where it is not the noun with an "s" ("analyses").

    Examples
    --------
    >>> count(1, "run"), count(2, "run"), count(0, "file"), count(3, "half cycle")
    ('1 run', '2 runs', '0 files', '3 half cycles')
    >>> count(2, "analysis", "analyses")
    '2 analyses'
    """
    word = noun if n == 1 else (plural if plural is not None else f"{noun}s")
    return f"{n} {word}"
