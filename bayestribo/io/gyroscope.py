"""A gyroscope's axes read as the angular velocity of the axis that swings.

A smartphone's or an IMU's gyroscope export (``Gyroscope x (deg/s)``, ``Gyro Z (rad/s)``,
``gyro_z_dps``) holds the angular velocity about three axes. On a torsion oscillator or
a pendulum one of them carries the swing and the others its noise: that axis is the
angular velocity of the rig. :func:`gyroscope_columns` finds it where the file holds
nothing else that is read (no displacement, velocity, angle or acceleration) and one
axis swings at least three times as widely as each other one; axes that swing alike
(a sensor mounted askew) are left to the caller's refusal, whose advice names each
axis's reading.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["GyroscopeReading", "gyroscope_axes", "gyroscope_columns"]

#: A gyroscope axis's header name: ``Gyroscope x (deg/s)``, ``Gyroscope rotation rate
#: z (rad/s)``, ``gyro_z [°/s]``, ``Gyro Z (dps)``, ``gyr_x_rad_per_s``.
_AXIS = re.compile(
    r"^(?:gyroscope|gyro|gyr)(?:[\s_]+(?:rotation[\s_]+rate|rate))?[\s_]*(?P<axis>[xyz])"
    r"(?:\s*[\(\[](?P<bracket>[^\)\]]+)[\)\]]|_(?P<suffix>\w+))\s*$",
    re.IGNORECASE,
)

#: Units of an angular velocity and their factor to rad/s.
_UNITS: dict[str, float] = {
    "rad/s": 1.0,
    "rad_per_s": 1.0,
    "rad/sec": 1.0,
    "rads": 1.0,
    "deg/s": math.pi / 180.0,
    "deg_per_s": math.pi / 180.0,
    "deg/sec": math.pi / 180.0,
    "°/s": math.pi / 180.0,
    "dps": math.pi / 180.0,
}

#: How many times more widely the swinging axis must swing than each other one.
DOMINANCE = 3.0


def gyroscope_axes(names: Sequence[str]) -> dict[int, tuple[str, str]]:
    """The gyroscope axes among a header's names: column -> (axis, unit as
    ``columns=`` names it, ``deg_per_s`` or ``rad_per_s``)."""
    out: dict[int, tuple[str, str]] = {}
    for i, name in enumerate(names):
        match = _AXIS.match(name.strip())
        if match is None:
            continue
        unit = (match.group("bracket") or match.group("suffix") or "").strip().lower()
        factor = _UNITS.get(unit.replace(" ", ""))
        if factor is None:
            continue
        out[i] = (match.group("axis").lower(), "rad_per_s" if factor == 1.0 else "deg_per_s")
    return out


@dataclass(frozen=True)
class GyroscopeReading:
    """Which gyroscope axis is read as the angular velocity, and why.

    Attributes
    ----------
    columns : list of str
        The ``columns=`` that read it, in file order.
    axis : str
        The axis read (``x``, ``y`` or ``z``).
    spreads : dict
        Each axis's standard deviation about its median [the file's unit].
    """

    columns: list[str]
    axis: str
    spreads: dict[str, float]

    def note(self) -> str:
        """One sentence saying which axis is read and how widely the others swing."""
        others = ", ".join(
            f"{a} {s / self.spreads[self.axis]:.2g}×"
            for a, s in self.spreads.items()
            if a != self.axis
        )
        return (
            f"the gyroscope's {self.axis} axis read as the angular velocity (the axis that "
            f"swings; the others' spread: {others}); give --columns to read another"
        )


def gyroscope_columns(names: Sequence[str], rows: np.ndarray) -> GyroscopeReading | None:
    """The reading of a gyroscope export's swinging axis, or None.

    Parameters
    ----------
    names : sequence of str
        The header's column names, as written.
    rows : ndarray
        The file's numbers, shape (samples, columns) (NaN where a cell is not one).

    Returns
    -------
    GyroscopeReading or None
        None where the file holds no gyroscope axis with an angular velocity's unit, a
        motion or an acceleration besides, or no axis that swings :data:`DOMINANCE`
        times as widely as each other one.
    """
    from bayestribo.io.columns import parse_column

    axes = gyroscope_axes(names)
    if not axes or rows.ndim != 2 or rows.shape[1] != len(names) or rows.shape[0] < 16:
        return None
    known: list[str | None] = []
    for i, name in enumerate(names):
        try:
            parsed = None if i in axes else parse_column(name)
        except ValueError:
            parsed = None
        if parsed is not None and parsed[0] != "time_s":
            return None  # a motion or an acceleration is read instead
        known.append(None if parsed is None else name)
    spreads = {}
    for column in axes:
        values = rows[:, column]
        values = values[np.isfinite(values)]
        if values.size < 16:
            return None
        spreads[column] = float(np.std(values - np.median(values)))
    best = max(spreads, key=spreads.__getitem__)
    if any(s * DOMINANCE > spreads[best] for c, s in spreads.items() if c != best):
        return None
    columns = [
        f"angular_velocity_{axes[i][1]}" if i == best else (known[i] or "ignore")
        for i in range(len(names))
    ]
    return GyroscopeReading(
        columns, axes[best][0], {axes[c][0]: s for c, s in sorted(spreads.items())}
    )
