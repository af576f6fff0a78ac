"""Extinction time, predictive check, draws, report and plots (bayestribo.adequacy)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from bayestribo.adequacy import (
    ParameterDraws,
    check_adequacy,
    draws_from_least_squares,
    draws_from_posterior,
    extinction_check,
    predictive_check,
)
from bayestribo.adequacy.plots import plot_extinction, plot_peak_residuals, plot_windows
from bayestribo.adequacy.segments import whole_decay_fit
from bayestribo.adequacy.windows import analysed_decay
from bayestribo.errors import BayestriboError
from bayestribo.model import exact_response, turning_points
from bayestribo.synthetic import Release
from bayestribo.synthetic.recording import simulate


@pytest.fixture(scope="module")
def report():
    return check_adequacy(simulate(seed=21))


def test_constant_law_run_passes_the_checks(report):
    # The extinction and peak checks must pass on a run simulated with the model;
    # the constancy decision, at the verdict's α/3, has a 1.7 % false-alarm rate
    # (this seed's p = 0.048 would be one at 5 %: tested over many runs in
    # test_adequacy_constancy), and the verdict follows it.
    assert report.extinction.consistent()
    assert report.predictive.coverage >= 0.9
    assert "not a posterior" in report.predictive.statement  # stand-in draws labelled
    assert report.constancy is not None
    assert report.halves is not None and report.halves.consistent
    assert report.adequate == report.constancy.constant
    text = report.to_text()
    assert f"verdict: {report.verdict}" in text
    assert report.to_dict()["adequate"] == report.adequate


def test_extinction_matches_the_model_and_the_recording(report):
    ex = report.extinction
    draws = report.draws
    decay = report.decay
    # the exact model's end is where the record would show it: a sample of the record's
    # rate at or before the draw's stop, the last turning point of turning_points from
    # where the fit starts the model (y0 with the recorded velocity), within the
    # resolution of that stop
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    tau_n, _ = turning_points(
        sign * float(draws.y0[0]),
        float(draws.zeta[0]),
        float(draws.mu[0]),
        max(float(draws.mu_s[0]), float(draws.mu[0])),
        float(decay.yp[0]),
    )
    stop = tau_n[-1] / decay.scaling.omega
    assert stop - ex.resolution <= ex.exact[0] <= stop
    dt = float(np.median(np.diff(decay.t)))
    assert ex.exact[0] / dt == pytest.approx(round(ex.exact[0] / dt), abs=1e-6)
    # the recorded end is within two samples (0.2 ms) of the simulated one
    assert abs(np.median(ex.exact) - ex.measured) < 2.5e-4
    # Eq. 38 (averaged) and the exact end differ by less than a half period
    assert abs(np.median(ex.averaged) - np.median(ex.exact)) < 0.5 / 32.6
    d = ex.to_dict()
    assert d["consistent_exact"] is True and d["measured_s"] == pytest.approx(ex.measured)


def test_predictive_peaks_of_the_true_parameters():
    # Draws all equal to the simulated values: predicted peaks are the model's
    # turning points and the recorded peaks must match them within their intervals.
    run = simulate(release=Release(magnet_fade_s=0.0), seed=22)
    decay = analysed_decay(run)
    ell = decay.scaling.length_scale
    y0 = abs(decay.peaks.value[0]) / ell
    n = 50
    draws = ParameterDraws(
        zeta=np.full(n, 0.0236),
        mu=np.full(n, 0.0294),
        y0=np.full(n, y0),
        mu_s=np.full(n, 0.0294),
        label="true values",
    )
    check = predictive_check(decay, draws)
    _, y_n = turning_points(y0, 0.0236, 0.0294, 0.0294, max_count=len(decay.peaks))
    # the predicted displacement peaks equal |Y_n| to the parabola's 3e-4 relative bias
    k = min(y_n.size, check.displacement.predicted.size)
    np.testing.assert_allclose(
        check.displacement.predicted[:k], np.abs(y_n[:k]), rtol=1e-3, atol=1e-3
    )
    assert check.coverage >= 0.9
    # the band's median is the model's response from where the fits start it: y0 at the
    # decay's first sample, with the recorded velocity there
    y, _ = exact_response(
        (check.band_t[:5] - decay.t[0]) * decay.scaling.omega,
        np.sign(decay.peaks.value[0]) * y0,
        0.0236,
        0.0294,
        0.0294,
        float(decay.yp[0]),
    )
    np.testing.assert_allclose(check.y_band[1, :5], y, atol=1e-9)


def test_wrong_parameters_fail_the_predictive_check():
    decay = analysed_decay(simulate(seed=23))
    fit = whole_decay_fit(decay)
    wrong = ParameterDraws(
        zeta=np.full(50, fit.zeta * 1.2),
        mu=np.full(50, fit.mu),
        y0=np.full(50, fit.y0),
        mu_s=np.full(50, fit.mu),
        label="ζ 20 % too large",
    )
    check = predictive_check(decay, wrong)
    assert check.coverage < 0.5 and check.rms_standardized > 3
    assert not extinction_check(decay, wrong).consistent()


def test_least_squares_draws_follow_the_covariance():
    decay = analysed_decay(simulate(seed=24))
    fit = whole_decay_fit(decay)
    d = draws_from_least_squares(fit, 4000, seed=1)
    # sample sd within 5 % of the covariance's (4000 draws: sd of the sd ≈ 1.1 %)
    assert np.std(d.zeta) == pytest.approx(fit.se("zeta"), rel=0.05)
    assert np.mean(d.mu) == pytest.approx(fit.mu, abs=4 * fit.se("mu") / np.sqrt(4000) * 3)
    with pytest.raises(BayestriboError, match="n_draws"):
        draws_from_least_squares(fit, 3)


class _Posterior:
    parameter_names = ("zeta", "mu_k", "mu_s", "y0")

    def __init__(self):
        rng = np.random.default_rng(0)
        self._s = {
            "zeta": 0.0236 + 1e-5 * rng.standard_normal(1000),
            "mu_k": 0.0294 + 1e-5 * rng.standard_normal(1000),
            "mu_s": 0.0300 + 1e-5 * rng.standard_normal(1000),
            "y0": 5.6 + 1e-3 * rng.standard_normal(1000),
        }

    def samples(self, name):
        return self._s[name]


def test_posterior_draws_are_used_and_labelled():
    decay = analysed_decay(simulate(seed=25))
    d = draws_from_posterior(_Posterior(), decay, 200)
    assert len(d) == 200 and d.label.startswith("posterior")
    assert np.all(d.mu_s >= d.mu)

    class Empty:
        parameter_names = ("zeta",)

        def samples(self, name):
            raise KeyError(name)

    with pytest.raises(BayestriboError, match="samples"):
        draws_from_posterior(Empty(), decay)


def test_plots_render(report, tmp_path):
    fig = plot_windows(report.windows, report.constancy, halves=report.halves)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "first half" in legend and "second half" in legend
    assert "halves agree" in fig.axes[0].get_title()
    fig.savefig(tmp_path / "windows.png")
    ax = plot_extinction(report.extinction)
    ax.figure.savefig(tmp_path / "extinction.png")
    fig2 = plot_peak_residuals(report.predictive)
    fig2.savefig(tmp_path / "peaks.png")
    for name in ("windows", "extinction", "peaks"):
        assert (tmp_path / f"{name}.png").stat().st_size > 5000
    assert len(fig.axes) == 2 and fig.axes[0].get_ylabel() == "ζ [-]"
    # given axes are used, not replaced
    _, a = plt.subplots()
    assert plot_extinction(report.extinction, ax=a) is a
    plt.close("all")


def test_the_friction_panel_is_left_out_where_it_has_nothing_to_show(report):
    """Windows that hold the friction at the whole decay's value (a decay without
    measurable friction): only ζ is drawn, and no panel is empty."""
    import dataclasses

    from bayestribo.reports.kit import empty_panels

    held = [
        dataclasses.replace(w, mu=1e-17, mu_interval=(1e-17, 1e-17)) for w in report.windows.windows
    ]
    windows = dataclasses.replace(
        report.windows, windows=held, extra={**report.windows.extra, "friction_mode": "fixed"}
    )
    fig = plot_windows(windows, None, fig=plt.figure(), halves=None)
    assert len(fig.axes) == 1 and empty_panels(fig) == []
    assert "held at the whole decay's value" in fig.axes[0].get_title()
    full = plot_windows(report.windows, report.constancy, halves=report.halves)
    assert len(full.axes) == 2 and empty_panels(full) == []
    plt.close("all")


def test_bad_relative_error_is_refused(report):
    with pytest.raises(BayestriboError, match="relative_error"):
        predictive_check(report.decay, report.draws, relative_error=-0.1)


def test_report_of_a_decay_and_its_json(report):
    again = check_adequacy(report.decay, window=3, n_draws=50)
    assert again.run_name is None and again.windows.window_oscillations == 3
    import json

    data = json.loads(json.dumps(again.to_dict()))
    assert data["predictive"]["displacement"]["n_peaks"] == len(report.decay.peaks)
    assert data["extinction"]["draws"] == again.draws.label
