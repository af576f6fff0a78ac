"""Moved to :mod:`bayestribo.signal.frequency` (the reading layer only reads).

The names stay importable from here with a :class:`DeprecationWarning`.
"""

from bayestribo._warnings import moved

__all__: list[str] = []

__getattr__ = moved(
    __name__,
    "bayestribo.signal.frequency",
    frozenset(
        {
            "HYSTERESIS",
            "MIN_TREND_TURNING_POINTS",
            "FrequencyTrend",
            "crossing_frequency",
            "frequency_trend",
            "oscillation_frequency",
            "turning_point_trend",
        }
    ),
)
