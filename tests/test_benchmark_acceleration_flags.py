"""``benchmarks/acceleration.py``: a fit is flagged by a MisfitWarning or a
ConvergenceWarning, or by any kind of either (the command's exit 1), never by a warning
that is information."""

from __future__ import annotations

import importlib.util
import sys
import warnings
from pathlib import Path

import pytest

from bayestribo.errors import (
    ConvergenceWarning,
    FadeWarning,
    MisfitWarning,
    OffsetDriftWarning,
    ReadingWarning,
    ShortAnalysisWarning,
)

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def acceleration():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        path = ROOT / "benchmarks" / "acceleration.py"
        spec = importlib.util.spec_from_file_location("acceleration", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return module


def _caught(*categories):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for category in categories:
            warnings.warn("a message", category, stacklevel=1)
    return caught


def test_a_kind_of_misfit_flags_the_fit(acceleration):
    assert acceleration.flags(_caught(ShortAnalysisWarning)) == ["ShortAnalysisWarning"]
    assert acceleration.flags(_caught(OffsetDriftWarning, FadeWarning)) == ["OffsetDriftWarning"]


def test_the_two_classes_flag_and_information_does_not(acceleration):
    caught = _caught(MisfitWarning, ConvergenceWarning, ReadingWarning, FadeWarning)
    assert acceleration.flags(caught) == ["ConvergenceWarning", "MisfitWarning"]
    assert acceleration.flags(_caught(ReadingWarning, FadeWarning)) == []
