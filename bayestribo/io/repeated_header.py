"""A header repeated among the rows: acquisitions appended to one file."""

from __future__ import annotations

from collections.abc import Sequence

from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning


def without_repeated_header(
    rows: Sequence[tuple[int, str]], header: Sequence[tuple[int, str]], where: str
) -> list[tuple[int, str]]:
    """The rows without the lines that repeat the header.

    A logger that appends each acquisition to one file writes the header again above
    each (``time_s,displacement_m`` at line 1 and again at line 1468, the time starting
    over below it). Those lines hold no numbers; they are left out with a
    :class:`~bayestribo.errors.ReadingWarning` naming them, and the rows after them
    are read as they are (a clock that starts over is then found and handled as any
    restart of the clock).

    Parameters
    ----------
    rows : sequence of (int, str)
        Line numbers and lines below the header.
    header : sequence of (int, str)
        Line numbers and lines of the header (names, and units where a row holds them).
    where : str
        The file, for the warning.

    Returns
    -------
    list of (int, str)
        ``rows`` without the repeated header lines (the same rows when there are none).
    """
    texts = {line.strip() for _, line in header}
    repeated = [n for n, line in rows if line.strip() in texts]
    if not repeated:
        return list(rows)
    lines = ", ".join(str(n) for n in repeated[:5]) + (" ..." if len(repeated) > 5 else "")
    warn(
        f"{where}: line(s) {lines} repeat the header (acquisitions appended to one file): "
        "left out; the rows below them are read as they are (where the time starts over, "
        "the restart of the clock is said); save each acquisition as a file of its own to "
        "fit it",
        ReadingWarning,
    )
    skip = set(repeated)
    return [(n, line) for n, line in rows if n not in skip]
