"""How much of the recorded motion an energy decay analyses.

The analysis runs from the start turning point (after the skipped oscillations and any
clipped cycles) to the end of motion, or to the last turning point that stands out of
the noise and the quantisation steps. When that is less than half of the motion the
record holds (from the release, or the record's start, to the end of motion or of the
record), a fit of it may look adequate while the law is wrong over the rest: the
energy decay says so with a :class:`ShortAnalysisWarning` naming both spans, which
makes ``bayestribo fit`` exit with status 1 (a
:class:`~bayestribo.errors.MisfitWarning`).
"""

from __future__ import annotations

from bayestribo.errors import ShortAnalysisWarning

__all__ = ["MIN_COVERAGE", "ShortAnalysisWarning", "coverage_note"]

#: Least fraction of the recorded motion the analysis must cover without a warning.
MIN_COVERAGE = 0.5


def coverage_note(
    start: float, end: float, motion_start: float, motion_end: float, why: str
) -> str | None:
    """The warning's text when ``[start, end]`` [s] covers less than
    :data:`MIN_COVERAGE` of ``[motion_start, motion_end]`` [s], else None.

    ``why`` says what ended or started the analysis where it did.
    """
    motion = motion_end - motion_start
    if not motion > 0 or (end - start) >= MIN_COVERAGE * motion:
        return None
    return (
        f"the analysis covers {start:.6g} s to {end:.6g} s, {100 * (end - start) / motion:.0f} % "
        f"of the motion recorded from {motion_start:.6g} s to {motion_end:.6g} s: {why}; "
        "a fit of it says nothing about the rest (crop the record to the motion you mean "
        "with --window T0:T1, or check the signal there)"
    )
