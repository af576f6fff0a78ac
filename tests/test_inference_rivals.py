"""Rivals: laws as good as the verdict on the half-cycle grid, of another mechanism,
compared again on a finer grid (bayestribo.inference.comparison, module notes).

Recordings from the independent solve_ivp simulator of ``tests/_law_recording.py``.
"""

from __future__ import annotations

import math
import warnings

import pytest
from _law_recording import law_recording

from bayestribo.errors import BayestriboError
from bayestribo.inference.comparison import TIE_GRID, LawComparison, compare_prepared
from bayestribo.inference.pipeline import prepare, regrid
from bayestribo.inference.sampling import SamplerSettings

OMEGA = 2 * math.pi * 32.6
SETTINGS = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=6000)


def _prepared(**kw):
    run = law_recording(lambda v: 0.0 * v, x0=1.5e-3, duration_s=2.5, noise_x=1.5e-6, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare(run)


@pytest.fixture(scope="module")
def hysteretic():
    # a friction η k |X_n| each half cycle (η = 0.015), no Coulomb part
    return _prepared(friction_slope=0.015 * OMEGA**2, seed=5)


def test_regrid_observes_the_same_decay_on_another_grid(hysteretic):
    n = hysteretic.data.increments.size
    fine = regrid(hysteretic, TIE_GRID * n)
    # the grid is on samples (an even number per increment, for Simpson's rule): about
    # the number asked for
    assert fine.grid_points == TIE_GRID * n
    assert 0.9 * TIE_GRID * n <= fine.data.increments.size <= 1.1 * TIE_GRID * n
    assert fine.decay is hysteretic.decay and fine.noise is hysteretic.noise
    # the same energy over the same span
    assert fine.data.increments.sum() == pytest.approx(hysteretic.data.increments.sum(), rel=1e-9)
    for bad in (1, 2.5, True, "8"):
        with pytest.raises(BayestriboError, match="grid_points"):
            regrid(hysteretic, bad)


def test_a_friction_that_grows_with_amplitude_is_told_from_viscous_damping(hysteretic):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        comparison, _ = compare_prepared(
            hysteretic, ["viscous", "hysteretic"], seed=3, settings=SETTINGS
        )
    rivals = comparison.rivals
    assert rivals is not None and rivals["decided"], comparison.to_dict()
    n = hysteretic.data.increments.size
    assert rivals["grid_points"] == regrid(hysteretic, TIE_GRID * n).data.increments.size
    assert comparison.verdict == "hysteretic" and comparison.adequate
    assert "viscous" not in comparison.as_good
    assert rivals["table"]["viscous"]["adequate"] is False
    assert "chosen over viscous on 4 increments per half cycle" in comparison.describe()


def test_without_rivals_the_order_of_the_laws_decides(hysteretic):
    # the half-cycle grid alone cannot tell them apart: the first law compared wins
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        comparison, _ = compare_prepared(
            hysteretic, ["viscous", "hysteretic"], seed=3, settings=SETTINGS, rivals=False
        )
    assert comparison.rivals is None
    assert comparison.verdict == "viscous" and "hysteretic" in comparison.as_good


def test_viscous_damping_keeps_its_verdict():
    run = law_recording(lambda v: 2 * 0.01 * OMEGA * v, x0=1.5e-3, duration_s=2.5, seed=6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(run)
        comparison, _ = compare_prepared(
            prepared, ["viscous", "hysteretic"], seed=3, settings=SETTINGS
        )
    assert comparison.verdict == "viscous" and comparison.adequate
    rivals = comparison.rivals
    assert rivals is not None
    assert rivals["verdict"] == "viscous"
    assert rivals["table"]["hysteretic"]["adequate"] is False


def test_an_undecided_rematch_is_said():
    c = LawComparison(
        "run",
        {},
        "viscous",
        "viscous",
        ["viscous", "hysteretic"],
        rivals={"laws": ["viscous", "hysteretic"], "per_half_cycle": 4, "decided": False},
    )
    assert "4 increments per half cycle did not tell it from hysteretic" in c.describe()
