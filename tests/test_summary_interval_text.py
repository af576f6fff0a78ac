"""``interval_text``: a value and its interval in the digits the interval supports."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from bayestribo.summary import NUMERICAL_ZERO, interval_text

_FIG = r"(-?[\d.]+(?:e[-+]\d+)?)"
_NUMBER = re.compile(rf"^{_FIG} \[{_FIG}, {_FIG}\]$")


def _parts(text: str) -> tuple[str, str, str]:
    found = _NUMBER.match(text)
    assert found is not None, text
    return found.group(1), found.group(2), found.group(3)


def _last_digit(text: str) -> float:
    """The place value of the last digit shown (0.001 for "0.0243", 1e-9 for "1.52e-07")."""
    mantissa, _, exponent = text.partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (-decimals + (int(exponent) if exponent else 0))


@pytest.mark.parametrize(
    ("center", "low", "high"),
    [
        (0.0236012, 0.0236003, 0.0236021),  # a posterior 1e-4 of its value wide
        (0.0194461, 0.0194365, 0.0194557),
        (12.3, 11.2, 13.9),
        (-0.00063, -0.00075, -0.00051),
        (1.5158e-07, 1.2e-07, 1.8e-07),
        (2.0e5, 1.9e5, 2.1e5),
    ],
)
def test_the_digits_follow_the_uncertainty(center, low, high):
    """The last digit shown is the second significant digit of the half width."""
    text = interval_text(center, low, high)
    shown = _parts(text)
    half = 0.5 * (high - low)
    second = 10.0 ** (math.floor(math.log10(half)) - 1)
    assert all(math.isclose(_last_digit(s), second, rel_tol=1e-9) for s in shown), text
    # and every shown number is the true one rounded at that digit
    for s, v in zip(shown, (center, low, high), strict=True):
        assert abs(float(s) - v) <= 0.5 * second * (1 + 1e-9), (s, v)


def test_an_interval_never_collapses_at_the_precision_shown():
    """Over many asymmetric intervals, the three shown numbers stay apart and ordered
    ("0.024251 [0.02425, 0.024251]" is the failure)."""
    rng = np.random.default_rng(5)
    for _ in range(2000):
        scale = 10.0 ** rng.uniform(-3, 3)
        center = scale * rng.uniform(0.5, 2)
        above = scale * 10.0 ** rng.uniform(-5, -1)
        below = above * 10.0 ** rng.uniform(-2.7, 2.7)  # one side up to 500 times the other
        below, above = rng.permutation([below, above])
        below, above = min(below, 0.5 * center), min(above, 0.5 * center)  # clear of zero
        text = interval_text(center, center - below, center + above)
        c, lo, hi = (float(s) for s in _parts(text))
        assert lo < c < hi, (text, center, below, above)
    assert interval_text(0.024251, 0.0242509, 0.0243) == "0.0242510 [0.0242509, 0.0243000]"


def test_a_numerical_zero_says_so():
    assert interval_text(4.83e-30, 0.0, 1.3397e-28) == "< 1e-9"
    assert interval_text(1e-12, -1e-13, 5e-10) == "< 1e-9"
    assert NUMERICAL_ZERO == 1e-9


def test_a_value_piled_on_its_bound_at_zero_says_so():
    assert interval_text(1.1e-4, 0.0, 3.1e-4) == "0 (at the bound) [0, 0.00031]"
    assert interval_text(3.97e-19, 0.0, 8.2e-05) == "0 (at the bound) [0, 8.2e-05]"
    # a lower end above zero but zero at the precision shown is at the bound too, and so
    # is one spread over decades down to zero
    assert interval_text(0.12, 0.0004, 0.31) == "0 (at the bound) [0, 0.31]"
    assert interval_text(2.5e-07, 6.9e-09, 9.0e-07) == "0 (at the bound) [0, 9.0e-07]"


def test_a_numerical_zero_in_an_interval_across_zero_is_zero():
    """A windowed least-squares ζ on its bound: 5.2e-27 ± 3.5e-4 reads "0", in the
    interval's notation."""
    assert interval_text(5.2e-27, -6.9e-04, 6.9e-04) == "0 [-0.00069, 0.00069]"
    assert interval_text(1.0e-25, -1.5e-04, 1.5e-04) == "0 [-0.00015, 0.00015]"


def test_a_value_clear_of_zero_is_not_called_zero():
    assert "bound" not in interval_text(0.2, 0.0004, 0.31)  # the centre is far above zero
    assert "bound" not in interval_text(-0.1, -0.3, 0.1)  # an interval across zero
    assert interval_text(5e-10, 4e-10, 6e-10) == "5.0e-10 [4.0e-10, 6.0e-10]"  # measured


def test_missing_and_degenerate_values():
    assert interval_text(float("nan"), 0.0, 1.0) == "–"
    assert interval_text(0.5, float("nan"), 1.0) == "0.5"
    assert interval_text(0.5, 0.5, 0.5) == "0.5 [0.5, 0.5]"
