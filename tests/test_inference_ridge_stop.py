"""A run on a ridge stops as soon as the draws show it cannot converge by the ceiling.

Where the record does not identify a parameter (a term whose force the draws put at
zero), the walkers random-walk along the ridge: τ grows with the chain, or the two
ensembles keep disagreeing. Before, such a run went on to the ceiling of 20,000 steps
(the halves check of a pendulum encoder's record: 20,000 then 16,800 steps, 40 % of
``--law auto``'s time) before it said so; it now stops where τ has grown in proportion
to the chain over a doubling of the steps, or R-hat has not shrunk over a doubling since
the rule was met (``bayestribo.inference.sampling``). A target that converges is not
stopped, the reasons given or not.
"""

from __future__ import annotations

import numpy as np

from bayestribo.inference.sampling import (
    SamplerSettings,
    _rhat_stalled,
    _ridge_growth,
    run_ensembles,
)
from bayestribo.inference.tau_bias import TauCheck


def _check(steps: int, tau: float) -> TauCheck:
    return TauCheck(steps, np.array([tau]), np.array([tau]), True)


def test_tau_that_grows_with_the_chain_is_a_ridge_and_one_that_settles_is_not():
    # the encoder record's ridge: 72.6 at 1250 steps, 219 at 3750 (power 1.0)
    ridge = [_check(1250, 72.6), _check(2450, 117.5), _check(3750, 219.1)]
    why = _ridge_growth(ridge, 31.25, 20_000)
    assert why is not None and "grows with the chain" in why
    # the same record's other run settling (132 at 2300, 171 at 4000: power 0.6)
    settling = [_check(1100, 76.5), _check(2300, 132.4), _check(4000, 171.1)]
    assert _ridge_growth(settling, 31.25, 20_000) is None
    # growing, but the rule met at the ceiling all the same: τ 30 at 2000 steps
    small = [_check(1000, 15.0), _check(2000, 30.0)]
    assert _ridge_growth(small, 31.25, 20_000) is None
    # too early to tell a ridge from a start's transient
    assert _ridge_growth([_check(500, 20.0), _check(1000, 60.0)], 31.25, 20_000) is None


def test_rhat_that_does_not_shrink_over_a_doubling_has_stalled():
    first = (5900, 200, 177, np.array([1.02, 1.0, 1.21]))
    assert _rhat_stalled(first, (8000, 400, 190, np.array([1.02, 1.0, 1.20])), "abc") is None
    why = _rhat_stalled(first, (11800, 400, 200, np.array([1.02, 1.0, 1.20])), "abc")
    assert why is not None and "R-hat of c 1.200" in why
    assert _rhat_stalled(first, (11800, 400, 200, np.array([1.02, 1.0, 1.05])), "abc") is None


def _ridge(theta: np.ndarray) -> np.ndarray:
    # a thin ring: the walkers creep along it (a ridge of one parameter, not a mode)
    radius = np.hypot(theta[:, 0], theta[:, 1])
    return -0.5 * ((radius - 1.0) / 1e-3) ** 2


def _normal(theta: np.ndarray) -> np.ndarray:
    return -0.5 * np.sum(theta * theta, axis=1)


def test_a_run_on_a_ridge_stops_long_before_the_ceiling_and_says_why():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2)
    rng = np.random.default_rng(4)
    angle = rng.uniform(0.0, 0.3, size=(2, 16))
    initial = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    run = run_ensembles(
        _ridge, initial, settings, seed=4, unidentified=lambda draws: ["y is not identified"]
    )
    assert not run.converged and run.ridge
    assert run.n_steps < settings.max_steps / 2
    assert any("y is not identified" in r for r in run.reasons)
    # without the reasons the run walks on to the ceiling, as before
    run = run_ensembles(_ridge, initial, settings, seed=4)
    assert not run.converged and run.n_steps == settings.max_steps


def test_a_target_that_converges_is_not_stopped_by_the_reasons():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2)
    initial = np.random.default_rng(5).normal(size=(2, 16, 3))
    run = run_ensembles(
        _normal, initial, settings, seed=5, unidentified=lambda draws: ["never true here"]
    )
    assert run.converged and not run.ridge
