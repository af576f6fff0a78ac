"""A short free decay: two or three oscillations, analysed on what they hold.

High friction stops an oscillator within two or three oscillations (the paper's pin at
μ_k = 0.5 or 0.8), and a record may end after two periods in motion. Either is still a
free decay: its turning points shrink from one to the next. The Bayesian fit asks for
three oscillations after the skipped one (:data:`~bayestribo.signal.decay.
MIN_OSCILLATIONS`); a record with fewer is analysed on as few as
:data:`~bayestribo.signal.coarse.MIN_COARSE_TURNING_POINTS` turning points (two
drops of energy from one turning point to the next, at least), with the oscillation
skipped after the release analysed too where it is what the record lacks, by the same
rule as a coarse record (:func:`~bayestribo.signal.coarse.coarse_window`). The total
decay is measured; its split between ζ and μ_k rests on the shape of the decay over a
few turning points, so the intervals are wide, and a
:class:`~bayestribo.errors.ShortAnalysisWarning` (a
:class:`~bayestribo.errors.MisfitWarning`: ``bayestribo fit`` exits 1) names the short
analysis. Fewer turning points than that are refused, with the count found and the
count needed.
"""

from __future__ import annotations

__all__ = ["short_decay_note"]


def short_decay_note(found: int, taken: str, motion_ended: bool) -> str:
    """The warning's text for a free decay analysed on fewer turning points than asked.

    Parameters
    ----------
    found : int
        Turning points found after the release.
    taken : str
        What the analysis takes instead, in words (:attr:`~bayestribo.signal.coarse.
        CoarseWindow.note`).
    motion_ended : bool
        Whether the motion stops inside the record (else the record ends in motion).

    Returns
    -------
    str

    Examples
    --------
    >>> short_decay_note(5, "4 turning points after the skipped ones, where 6 are asked for",
    ...                  True)[:58]
    'short decay: the motion stops 5 turning points after the r'
    """
    why = "the motion stops" if motion_ended else "the record ends in motion"
    return (
        f"short decay: {why} {found} turning points after the release, before the three "
        f"oscillations after the skipped one that a decay is analysed on: the analysis "
        f"takes {taken}; with so short a decay "
        "ζ and μ_k are told apart by little (the total decay is measured, its split "
        "between them is not) and the intervals are wide; a longer record, or a lighter "
        "load, gives a decay that tells them apart"
    )
