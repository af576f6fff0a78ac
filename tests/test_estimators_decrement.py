"""Viscous-only decrements (ζ₀): logarithmic decrement and exponential envelope."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_estimators_signals import exact_turning_points, sampled

from bayestribo.errors import RecordingError
from bayestribo.estimators import exponential_envelope, log_decrement
from bayestribo.signal.peaks import Peaks, find_peaks


def _exact_peaks(y0, zeta, mu, count=60):
    tn, yn, _ = exact_turning_points(y0, zeta, mu, max_count=count)
    return Peaks(t=tn, value=yn)


@pytest.mark.parametrize("zeta", [0.001, 0.0033, 0.01, 0.1])
def test_exact_viscous_peaks(zeta):
    pk = _exact_peaks(1.0, zeta, 0.0)
    # |Y_{n+1}| = e^{-βπ}|Y_n| exactly without friction: rounding only
    assert log_decrement(pk).zeta == pytest.approx(zeta, rel=1e-9)
    assert exponential_envelope(pk).zeta == pytest.approx(zeta, rel=1e-6)


@pytest.mark.parametrize("zeta", [0.001, 0.01, 0.1])
@pytest.mark.parametrize("kind", ["displacement", "velocity"])
def test_sampled_viscous_signals(zeta, kind):
    t, x, v = sampled(zeta, 0.0, 10.0)
    pk = find_peaks(t, x if kind == "displacement" else v, kind=kind)
    # peak values carry a common relative bias (~3e-4, cancels in ratios) and the
    # offset fit leaves ~1e-6 Y_0: after ~12/ζ of decay the last peaks are down to
    # ~1e-4 Y_0 (the find_peaks floor), so ~1 % of the decrement for log_decrement
    # (first/last only) and 1e-3 for the least-squares envelope dominated by big peaks
    assert log_decrement(pk).zeta == pytest.approx(zeta, rel=1e-2)
    assert exponential_envelope(pk).zeta == pytest.approx(zeta, rel=1e-3)


def test_friction_is_taken_for_viscous_damping():
    # documented bias: with friction the viscous-only estimators overestimate ζ
    pk = _exact_peaks(10.0, 0.0236, 0.0294)
    pk = Peaks(t=pk.t[:-1], value=pk.value[:-1])
    assert log_decrement(pk).zeta > 0.0236 * 1.5
    assert exponential_envelope(pk).zeta > 0.0236 * 1.2
    assert "assumes no friction" in log_decrement(pk).notes


def test_envelope_standard_error_matches_scatter():
    pk0 = _exact_peaks(1.0, 0.005, 0.0, count=80)
    rng = np.random.default_rng(3)
    sigma = 0.003
    zs, ses, lses = [], [], []
    for _ in range(200):
        pk = Peaks(
            t=pk0.t,
            value=pk0.value + sigma * rng.standard_normal(len(pk0)),
            value_noise=sigma,
        )
        e = exponential_envelope(pk)
        zs.append(e.zeta)
        ses.append(e.zeta_se)
        lses.append(log_decrement(pk).zeta_se)
    # independent peak noise: the Jacobian SE is right; 200 draws -> 5 % on a spread
    assert np.std(zs) == pytest.approx(np.mean(ses), rel=0.2)
    assert abs(np.mean(zs) - 0.005) < 4 * np.std(zs) / math.sqrt(200)
    # the log decrement uses two peaks only: its SE is larger
    assert np.mean(lses) > np.mean(ses)


def test_errors():
    with pytest.raises(RecordingError, match="at least 2 peaks"):
        log_decrement(Peaks(t=[0.0], value=[1.0]))
    with pytest.raises(RecordingError, match="at least 3 peaks"):
        exponential_envelope(Peaks(t=[0.0, 1.0], value=[1.0, -0.9]))
    with pytest.raises(RecordingError, match="peaks must be"):
        log_decrement([1.0, 0.5])
