"""The correlation of neighbouring increments with a velocity derived from the
displacement (bayestribo.signal.derivative_correlation)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run
from bayestribo.model.restoring.duffing import duffing
from bayestribo.signal.derivative_correlation import derived_velocity_correlation
from bayestribo.signal.increments import increment_draws, increment_weights
from tests._pendulum_decay import Swing, swing


def _motion(frequency: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A slowly decaying oscillation at ``frequency`` (per unit τ), 100 samples a
    period of the grid's half cycles (π in τ)."""
    h = 2.0 * math.pi / 100.0
    tau = np.arange(0.0, 24.0 * math.pi, h)
    amplitude = np.exp(-0.01 * tau)
    y = amplitude * np.cos(frequency * tau)
    yp = -amplitude * (frequency * np.sin(frequency * tau) + 0.01 * np.cos(frequency * tau))
    return tau, y, yp, h


@pytest.mark.parametrize("frequency", [1.0, 1.06])
def test_first_order_correlation_is_the_monte_carlos(frequency: float) -> None:
    """The first-order covariance σ² u_jᵀu_l against the Monte Carlo of the increments'
    noise through the derivative (2000 draws): every neighbour's correlation within
    4 of the Monte Carlo's standard errors. At frequency 1 the boundaries sit at the
    turning points (neighbours uncorrelated); at 1.06 they drift through the phase
    and reach the zero crossings (strongly anticorrelated)."""
    tau, y, yp, h = _motion(frequency)
    force = duffing(0.2)
    edges, weights = increment_weights(tau.size, h, round(tau[-1] / math.pi))
    sigma, window, count = 1e-3, 13, 2000
    draws = increment_draws(
        tau,
        y,
        yp,
        edges,
        weights,
        sigma,
        0.0,
        derived="velocity",
        savgol_window=window,
        n_replicates=count,
        seed=4,
        potential=force.potential,
    )
    variance = draws.var(axis=0, ddof=1)
    found = derived_velocity_correlation(
        np.asarray(force.spring(y)), yp, edges, weights, variance, sigma, window, h
    )
    assert found is not None
    assert np.allclose(np.diag(found), 1.0)
    measured = np.corrcoef(draws.T)
    lag1 = np.diag(found, 1)
    mc = np.diag(measured, 1)
    se = (1.0 - mc**2) / math.sqrt(count)
    assert np.all(np.abs(lag1 - mc) < 4.0 * se + 1e-3)
    # beyond the derivative's window nothing is shared
    assert np.all(np.triu(found, 2) == 0.0)
    if frequency == 1.0:
        assert np.max(np.abs(lag1)) < 0.1
    else:
        assert np.min(lag1) < -0.2
        # a run of all the increments has less variance than their sum, as measured
        sd = np.sqrt(variance)
        ratio = float(sd @ found @ sd / variance.sum())
        measured_ratio = float(draws.sum(axis=1).var(ddof=1) / variance.sum())
        assert ratio < 0.9
        assert ratio == pytest.approx(measured_ratio, rel=0.1)


def _record(beta: float | None, restoring: str) -> Run:
    """A Duffing spring (or a linear one, β = 0) with the displacement alone."""
    case = Swing(f0=2.0, zeta=0.005, friction=0.002, x0=2.0, beta=beta, rate=200.0, duration=12.0)
    t, x, _ = swing(case, seed=3)
    return Run(t, x, metadata={"length_unit": "arbitrary", "restoring": restoring})


def test_a_nonlinear_force_with_a_derived_velocity_correlates_its_increments() -> None:
    """prepare() gives the likelihood the neighbours' anticorrelation on a Duffing
    spring whose half period changes with the swing, and none on the linear spring
    (its analysis, and every default fit, as before)."""
    nonlinear = prepare(_record(0.033, "duffing")).data
    assert nonlinear.correlation is not None
    assert np.mean(np.diag(nonlinear.correlation, 1)) < -0.1
    linear = prepare(_record(0.0, "linear")).data
    assert linear.correlation is None


@pytest.mark.parametrize("restoring", ["auto", "duffing"])
def test_a_force_in_doubt_keeps_independent_increments(restoring: str) -> None:
    """A pendulum recorded as a length (not radians): ``auto`` takes the Duffing spring
    and warns that a pendulum is fitted in radians, and a Duffing spring named for it is
    the force auto would take with that warning. The increments stay independent, the
    width that covered that force; the same pendulum in radians, named, is correlated."""
    case = Swing(f0=0.5, zeta=0.005, friction=0.002, x0=0.5 * math.pi, rate=100.0, duration=30.0)
    t, x, _ = swing(case, seed=5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # auto's FrequencyTrendWarning
        doubtful = prepare(Run(t, x, metadata={"length_unit": "arbitrary", "restoring": restoring}))
    assert doubtful.run.metadata["restoring"] == "duffing"
    assert doubtful.data.correlation is None
    assert doubtful.data.preparation["derivative_correlation"] is False
    settled = prepare(Run(t, x, metadata={"length_unit": "rad", "restoring": "pendulum"}))
    assert settled.data.correlation is not None
    assert np.mean(np.diag(settled.data.correlation, 1)) < -0.1
