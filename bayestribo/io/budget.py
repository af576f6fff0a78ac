"""How much memory reading one binary file may take: a budget checked before allocation.

A compressed file states the sizes of its arrays in headers it does not have to honour:
a MATLAB variable or an HDF5 dataset of zeros compresses about a thousandfold, so a
small file can ask for gigabytes. The readers add up what a file declares for the
arrays they will load, counted as float64 (what the signals become), and refuse a file
that declares more than its budget before any of it is decompressed.

The budget grows with the file: ``min(CAP, max(FLOOR, PER_FILE_BYTE x file size))``.
A genuine record is at most a few times smaller than its arrays (a 1 MHz x 10 s
record of a time and a displacement, 160 MB as float64, compresses to about 55 MB:
the time vector 1.7 times, a quantised decay 9 times), well within
:data:`PER_FILE_BYTE`; a file of zeros that declares gigabytes is not. A file whose
arrays do compress further (a long flat record) can be read with a larger budget set
in the environment variable :data:`BUDGET_VARIABLE` [MB].
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from bayestribo.errors import RunFormatError

__all__ = [
    "BUDGET_VARIABLE",
    "CAP_BYTES",
    "FLOOR_BYTES",
    "PER_FILE_BYTE",
    "ReadBudget",
    "read_budget",
]

#: Smallest budget [bytes] (64 MB): any small file may hold a few channels.
FLOOR_BYTES = 64 << 20
#: Budget per byte of the file [-]: arrays may declare 16 times the file's size.
PER_FILE_BYTE = 16
#: Largest budget [bytes] (1 GB): three channels of
#: :data:`~bayestribo.io.arrays.MAX_SAMPLES` float64 values and room to spare.
CAP_BYTES = 1 << 30
#: Environment variable that sets the budget [MB], overriding the rule above.
BUDGET_VARIABLE = "BAYESTRIBO_READ_BUDGET_MB"

#: Bytes an array element is counted as [bytes]: its values become float64.
FLOAT_BYTES = 8


def _mb(n: float) -> str:
    """Bytes for a message: ``"67.1 MB"``, ``"1.07 GB"``, ``"1.67 kB"``."""
    for scale, unit in ((1e9, "GB"), (1e6, "MB"), (1e3, "kB")):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} bytes"


@dataclass
class ReadBudget:
    """What one file's arrays may take in memory, and what they have claimed so far.

    Parameters
    ----------
    limit : int
        The budget [bytes].
    where : str
        The file, for messages.
    rule : str
        How the budget was set, for messages.
    used : int
        Bytes claimed so far [bytes].
    """

    limit: int
    where: str
    rule: str
    used: int = 0

    def claim(self, what: str, declared: int, detail: str = "", *, at_least: bool = False) -> None:
        """Add what an array declares to the bytes claimed; refuse it past the budget.

        Parameters
        ----------
        what : str
            The array, e.g. ``"variable 'x'"`` or ``"dataset 'run/x'"``.
        declared : int
            The bytes it declares (element count x :data:`FLOAT_BYTES`, or more).
        detail : str
            Its declared shape and type, for the message.
        at_least : bool
            ``declared`` is a lower bound (the count stopped past the budget).

        Raises
        ------
        RunFormatError
            When the arrays claimed so far and this one exceed the budget.
        """
        if self.used + declared <= self.limit:
            self.used += declared
            return
        before = f" after {_mb(self.used)} for the arrays before it" if self.used else ""
        raise RunFormatError(
            f"{what}{f' ({detail})' if detail else ''} declares "
            f"{'at least ' if at_least else ''}{_mb(declared)} in memory"
            f"{before}, more than the read budget of {_mb(self.limit)} ({self.rule}); a "
            f"damaged or hostile header, or a record that compresses unusually well: to "
            f"read it, set the environment variable {BUDGET_VARIABLE} to a larger budget "
            "in MB",
            self.where,
        )


def read_budget(file_size: int, where: str, *, per_file_byte: int = PER_FILE_BYTE) -> ReadBudget:
    """The memory budget of reading a file of ``file_size`` bytes.

    Parameters
    ----------
    file_size : int
        The file's size [bytes].
    where : str
        The file, for messages.
    per_file_byte : int
        Bytes of memory per byte of the file [-]; a reader whose genuine files expand
        more (a workbook's cells, as text) states its own.

    Returns
    -------
    ReadBudget
        ``min(CAP_BYTES, max(FLOOR_BYTES, per_file_byte * file_size))``, or the budget
        set in :data:`BUDGET_VARIABLE` [MB].

    Raises
    ------
    RunFormatError
        When :data:`BUDGET_VARIABLE` is set to something other than a positive number.
    """
    text = os.environ.get(BUDGET_VARIABLE, "").strip()
    if text:
        try:
            mb = float(text)
        except ValueError:
            mb = float("nan")
        if not mb > 0 or mb == float("inf"):
            raise RunFormatError(
                f"environment variable {BUDGET_VARIABLE}: expected a positive number of MB, "
                f"got {text[:40]!r}",
                where,
            )
        return ReadBudget(int(mb * 1e6), where, f"set by {BUDGET_VARIABLE}")
    limit = min(CAP_BYTES, max(FLOOR_BYTES, per_file_byte * int(file_size)))
    rule = (
        f"{per_file_byte} x the file's {_mb(file_size)}, at least {_mb(FLOOR_BYTES)} and at "
        f"most {_mb(CAP_BYTES)}"
    )
    return ReadBudget(limit, where, rule)
