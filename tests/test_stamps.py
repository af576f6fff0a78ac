"""Time stamps in messages (``bayestribo/_stamps.py``)."""

from __future__ import annotations

import doctest

import bayestribo._stamps as stamps
from bayestribo._stamps import stamp


def test_the_examples_hold():
    assert doctest.testmod(stamps).failed == 0


def test_instants_of_a_unix_clock_are_told_apart():
    start, span = 1_406_722_067.411, 49.1
    release, window = start + 0.277, start + 2.396
    assert stamp(release, span, start) != stamp(window, span, start)
    # to a ten-thousandth of the span
    assert abs(float(stamp(release, span, start).split()[0]) - release) <= 1e-4 * span
    assert "(0.277 s into the record)" in stamp(release, span, start)


def test_a_clock_from_zero_is_printed_as_before():
    assert stamp(1.25, 10.0, 0.0) == "1.25 s"
    assert stamp(None, 10.0) == "— s"
