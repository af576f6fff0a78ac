"""Figures of a fit: each renders with Agg, on the axes given, with the paper's labels."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.figure
import matplotlib.pyplot as plt

from bayestribo.inference import FitResult
from bayestribo.inference.plots import corner_plot, pi_plot, plotted_names, trace_plot


@pytest.fixture(scope="module")
def result(short_fit) -> FitResult:
    # a short 2 kHz run (conftest.py): the plots are drawn from the NetCDF copy
    return short_fit


def _png(fig, tmp_path: Path, name: str) -> Path:
    path = tmp_path / name
    fig.savefig(path, dpi=60)
    plt.close(fig)
    assert path.stat().st_size > 5000  # a drawn figure, not an empty canvas
    return path


def test_default_names_have_the_fitted_quantities(result: FitResult) -> None:
    names = plotted_names(result)
    assert names == ["zeta", "mu_k", "mu_s_ratio", "y0"]
    with pytest.raises(KeyError, match="zeta_k"):
        plotted_names(result, ["zeta", "zeta_k"])


def test_corner_draws_on_the_given_figure(result: FitResult, tmp_path: Path) -> None:
    fig = plt.figure(figsize=(6, 6))
    out = corner_plot(result, fig)
    assert out is fig
    d = len(plotted_names(result))
    assert len(fig.axes) == d * d
    labels = {ax.get_xlabel() for ax in fig.axes}
    assert {"ζ [-]", "μ_k [-]", "μ_s/μ_k [-]"} <= labels
    # each title gives the median and 95 % interval in the digits the interval supports
    # (corner's own format rounds a ζ of 0.0242506 ± 4e-7 to 0.0243)
    from bayestribo.summary import interval_text

    diagonal = np.asarray(fig.axes).reshape(d, d).diagonal()
    for ax, name in zip(diagonal, plotted_names(result), strict=True):
        low, median, high = np.quantile(result.samples(name), [0.025, 0.5, 0.975])
        assert ax.get_title().splitlines()[1] == interval_text(median, low, high), name
    _png(fig, tmp_path, "corner.png")


def test_trace_one_line_per_ensemble(result: FitResult, tmp_path: Path) -> None:
    fig, axes = plt.subplots(4, 1, sharex=True)
    out = trace_plot(result, axes)
    assert out is axes
    n_chain = np.asarray(result.idata.posterior["zeta"]).shape[0]
    for ax, name in zip(axes, plotted_names(result), strict=True):
        assert len(ax.lines) == n_chain
        np.testing.assert_array_equal(
            ax.lines[0].get_ydata(), np.asarray(result.idata.posterior[name])[0]
        )
    assert axes[0].get_ylabel() == "ζ [-]"
    _png(fig, tmp_path, "trace.png")
    fig, axes = plt.subplots(3, 1)
    with pytest.raises(ValueError, match="need 4 axes"):
        trace_plot(result, axes)
    plt.close(fig)


def test_pi_band_and_residuals(result: FitResult, tmp_path: Path) -> None:
    fig, axes = plt.subplots(2, 1, sharex=True)
    out = pi_plot(result, axes)
    assert out is axes
    ax_pi, ax_res = axes
    assert ax_pi.get_yscale() == "log"
    assert "Π" in ax_pi.get_ylabel() and "τ" in ax_res.get_xlabel()
    observed = np.asarray(result.idata.observed_data["pi"])
    np.testing.assert_array_equal(ax_pi.lines[-1].get_ydata(), observed)
    z = ax_res.lines[-1].get_ydata()
    assert z.size == observed.size
    # the increments' residuals of a correctly specified simulated run are standard
    # normals (within the sampling error of the predictive moments, 400 draws): a
    # mean within 4 standard errors of 0 and a spread between 0.6 and 1.5 (the
    # 99.9 % range of the sample sd of ~64 normals is about 0.7-1.3)
    assert abs(np.mean(z)) < 4.0 / np.sqrt(z.size)
    assert 0.6 < np.std(z) < 1.5
    _png(fig, tmp_path, "pi.png")
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match="two axes"):
        pi_plot(result, [ax])
    with pytest.raises(ValueError, match="prob"):
        pi_plot(result, axes, prob=1.5)
    plt.close("all")


@pytest.mark.parametrize("kind", ["pi", "decay"])
def test_result_plot_of_the_decay_is_the_data_against_the_fit(result: FitResult, kind) -> None:
    fig = result.plot(kind)
    assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 2
    ax_pi = fig.axes[0]
    observed = np.asarray(result.idata.observed_data["pi"])
    np.testing.assert_array_equal(ax_pi.lines[-1].get_ydata(), observed)  # the data
    # the fitted model: the predictive median of Π, beside the data
    replicated = np.asarray(result.idata.posterior_predictive["pi"]).reshape(-1, observed.size)
    np.testing.assert_allclose(ax_pi.lines[0].get_ydata(), np.median(replicated, axis=0))
    plt.close(fig)


def test_result_plot_draws_a_corner_and_a_trace_on_the_figure_given(result: FitResult) -> None:
    d = len(plotted_names(result))
    fig = plt.figure()
    assert result.plot("corner", fig) is fig and len(fig.axes) == d * d
    plt.close(fig)
    fig = result.plot("trace", names=["zeta", "mu_k"])
    assert [ax.get_ylabel() for ax in fig.axes] == ["ζ [-]", "μ_k [-]"]
    plt.close(fig)


def test_result_plot_names_the_kinds_it_knows(result: FitResult) -> None:
    with pytest.raises(ValueError, match=r"kind: expected one of \['corner', 'decay', 'pi'"):
        result.plot("histogram")
