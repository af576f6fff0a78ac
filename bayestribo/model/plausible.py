"""What a free-decay rig can make: the bounds behind the package's unit checks.

A file read in the wrong units is still a decaying oscillation; what gives it away is a
combination no rig makes. These bounds are wide (a tribometer's blade at 32.6 Hz, a
spring and mass at 1 Hz, a stiff rig at a kilohertz all sit far inside them) and are
used only to refuse a record or to rank the explanations of an inconsistency, never
to change data.
"""

from __future__ import annotations

__all__ = ["FREQUENCY_RANGE_HZ", "MAX_SPEED", "is_plausible"]

#: Largest peak speed 2πfA of a free-decay rig [m/s]: laser vibrometers stop near
#: 10-30 m/s, and a swing of millimetres at a kilohertz is a few m/s. Beyond it the
#: displacement is not in metres.
MAX_SPEED = 20.0

#: Natural frequencies [Hz] of free-decay rigs: a period of 20 s to a 20 kHz resonator.
FREQUENCY_RANGE_HZ = (0.05, 20_000.0)


def is_plausible(frequency_Hz: float, swing_m: float) -> bool:
    """True when an oscillation at ``frequency_Hz`` with amplitude ``swing_m`` [m] is one a
    rig makes: its frequency within :data:`FREQUENCY_RANGE_HZ` and its peak speed
    2πfA at most :data:`MAX_SPEED`."""
    import math

    low, high = FREQUENCY_RANGE_HZ
    return low <= frequency_Hz <= high and 2.0 * math.pi * frequency_Hz * swing_m <= MAX_SPEED
