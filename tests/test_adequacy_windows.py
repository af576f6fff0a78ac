"""Windowed fits along the decay (bayestribo.adequacy.windows, segments)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bayestribo.adequacy.segments import fit_segment, peak_positions, whole_decay_fit
from bayestribo.adequacy.windows import (
    BayesianWindows,
    WindowFit,
    analysed_decay,
    window_bounds,
    windowed_fits,
)
from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.synthetic import Sensor
from bayestribo.synthetic.recording import simulate

ZETA, MU = 0.0236, 0.0294


@pytest.fixture(scope="module")
def decay():
    return analysed_decay(simulate(seed=11))


def test_windows_cover_the_decay_without_gaps(decay):
    bounds = window_bounds(decay, 2)
    pos = peak_positions(decay)
    assert bounds[0][0] == 0
    assert bounds[-1][1] == decay.t.size  # the rest of the decay joins the last window
    for (_a0, b0, f0, l0), (a1, _, f1, _) in itertools.pairwise(bounds):
        assert l0 == f1 and a1 == b0 - 1 == pos[l0]  # consecutive windows share a turning point
        assert l0 - f0 == 4  # 2 oscillations = 4 half cycles
    assert bounds[-1][3] == pos.size - 1


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_bad_window_is_refused(decay, bad):
    with pytest.raises(RecordingError, match="window"):
        windowed_fits(decay, window=bad)


def test_window_longer_than_the_decay_is_refused(decay):
    with pytest.raises(RecordingError, match="fewer than one window"):
        window_bounds(decay, 50)


def test_whole_decay_fit_recovers_the_simulated_values(decay):
    fit = whole_decay_fit(decay)
    # tolerance: 4 standard errors of the fit itself (plus 1e-6 for the sub-sample start)
    assert abs(fit.zeta - ZETA) < 4 * fit.se("zeta") + 1e-6
    assert abs(fit.mu - MU) < 4 * fit.se("mu") + 1e-6
    assert fit.chi2_reduced < 3.0  # the noise model describes the increments


def test_window_intervals_are_calibrated():
    # Statistical: over 5 seeded runs x 6 windows, the Gaussian 95 % intervals of ζ
    # and μ_k must hold the true values about 95 % of the time; with 30 windows,
    # P(fewer than 24 inside | 95 %) < 0.2 %.
    inside_z = inside_m = total = 0
    for seed in range(5):
        w = windowed_fits(simulate(seed=100 + seed), window=2, seed=seed)
        assert w.extra["friction_mode"] == "fit"
        for x in w.windows:
            inside_z += x.zeta_interval[0] <= ZETA <= x.zeta_interval[1]
            inside_m += x.mu_interval[0] <= MU <= x.mu_interval[1]
            total += 1
    assert total >= 25
    assert inside_z >= 0.8 * total
    assert inside_m >= 0.8 * total


def test_window_ranges_in_signal_units(decay):
    w = windowed_fits(decay, window=3)
    amps = [x.amplitude for x in w.windows]
    assert all(a > b for a, b in itertools.pairwise(amps))  # a decay
    x0 = w.windows[0]
    assert x0.amplitude_range[0] <= x0.amplitude <= x0.amplitude_range[1]
    # peak velocity ≈ Ω × amplitude for a lightly damped oscillator (within 15 %)
    omega = decay.scaling.omega
    assert x0.velocity_range[1] == pytest.approx(omega * x0.amplitude_range[1], rel=0.15)
    d = w.to_dict()
    assert d["friction"] == "mu_k" and len(d["windows"]) == len(w)


def test_fixed_friction_fits_only_zeta(decay):
    w = windowed_fits(decay, window=2, friction="fixed")
    assert all(x.mu_se == 0.0 for x in w.windows)
    assert w.extra["fixed_friction"] == pytest.approx(w.extra["whole_decay"]["mu"])
    with pytest.raises(RecordingError, match="friction"):
        windowed_fits(decay, window=2, friction="none")


def test_fixed_mu_out_of_range_is_refused(decay):
    pa = np.abs(decay.peaks.value) / decay.scaling.length_scale
    with pytest.raises(RecordingError, match="fixed_mu"):
        fit_segment(decay, 0, decay.t.size, pa, fixed_mu=-1.0)


class _StandIn:
    """A Bayesian-fit stand-in: Gaussian samples about given values."""

    parameter_names = ("zeta", "mu_k")

    def __init__(self, zeta: float, mu: float) -> None:
        rng = np.random.default_rng(0)
        self._s = {"zeta": zeta + 1e-4 * rng.standard_normal(2000)}
        self._s["mu_k"] = mu + 1e-4 * rng.standard_normal(2000)
        self.converged = True

    def samples(self, name: str) -> np.ndarray:
        return self._s[name]


def test_bayes_method_cuts_each_window_as_a_run():
    run = simulate(seed=5)
    seen = []

    def fitter(sub):
        seen.append((sub.time[0], sub.time[-1]))
        return _StandIn(ZETA, MU)

    w = windowed_fits(run, window=3, fitter=BayesianWindows(fitter))
    assert len(seen) == len(w) >= 3
    for (t0, t1), x in zip(seen, w.windows, strict=True):
        assert t0 < x.t_start and t1 == pytest.approx(x.t_end)  # a quarter period before
        assert x.zeta_interval[0] < ZETA < x.zeta_interval[1]
    assert w.interval_kind.startswith("posterior")
    with pytest.raises(BayestriboError, match="EnergyDecay"):
        windowed_fits(analysed_decay(run), window=3, fitter=BayesianWindows(fitter))
    # a window run must be analysable on its own: at least 3 oscillations
    with pytest.raises(RecordingError, match="at least 3 oscillations"):
        windowed_fits(run, window=2, fitter=BayesianWindows(fitter))


def test_not_a_run_is_refused():
    with pytest.raises(RecordingError, match="run must be"):
        windowed_fits(42)


def test_position_only_window_intervals_are_calibrated():
    # The velocity derived from the displacement carries correlated noise, which the
    # fit propagates by Monte Carlo through the same derivative filter. Statistical,
    # seeded: 4 position-only runs at 10x the resolution noise, about 24 windows;
    # P(fewer than 19 inside | 95 %) < 0.5 %.
    inside = total = 0
    for seed in range(4):
        run = simulate(
            sensor=Sensor(channels=("displacement",), displacement_noise_m=1.5e-6), seed=500 + seed
        )
        w = windowed_fits(run, window=2, seed=seed)
        for x in w.windows:
            inside += x.zeta_interval[0] <= ZETA <= x.zeta_interval[1]
            total += 1
            assert x.chi2_reduced < 4.0  # the propagated noise describes the increments
    assert total >= 20
    assert inside >= 0.8 * total


def test_a_users_own_window_fitter_is_used_as_it_is():
    # Any object with the fitter attributes and methods: here one that reports the
    # window's own index as ζ and holds no friction.
    class IndexFitter:
        method = "index"
        interval_kind = "none"
        holds_friction = False

        def check(self, context, window):
            assert context.run is not None and window == 2

        def fit_window(self, context, index, bounds, fixed_mu):
            assert fixed_mu is None and bounds[0] < bounds[1]
            return WindowFit(
                zeta=float(index),
                mu=0.5,
                covariance=np.eye(2),
                zeta_interval=(index - 1.0, index + 1.0),
                mu_interval=(0.0, 1.0),
            )

    w = windowed_fits(simulate(seed=5), window=2, fitter=IndexFitter())
    assert w.method == "index" and w.to_dict()["friction_mode"] == "fit"
    np.testing.assert_array_equal(w.column("zeta"), np.arange(len(w)))


def test_progress_names_each_window_before_it_is_fitted():
    messages: list[str] = []
    w = windowed_fits(simulate(seed=101), window=2, progress=messages.append)
    n = len(w.windows)
    # The last n messages name the windows of the result (a re-run with the friction
    # held would come after a first pass, and say so).
    held = ", friction held" if w.extra["friction_mode"] == "fixed" else ""
    expected = [f"window {k}/{n} (least_squares{held})" for k in range(1, n + 1)]
    assert messages[-n:] == expected
