"""Campaign figures in any law: panels from the analysis' quantities, groups of several
laws apart, the load trend's band, ΔE(A) per group (stand-in digests, short samplers).

The runs are :class:`~bayestribo.campaign.digest.FitDigest` objects with normal draws
of each law's campaign quantities, described as :mod:`bayestribo.campaign.quantities`
describes them (symbols and units from the law registry): these tests check what the
figures draw, not the populations (tests/test_campaign_laws.py fits real runs).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bayestribo.campaign.analysis import analyse_campaign
from bayestribo.campaign.digest import FitDigest
from bayestribo.model.laws import get_law
from bayestribo.summary import summarize

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

pytestmark = pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")

RIG = {"mass_kg": 0.035, "natural_frequency_Hz": 32.6}
PROB = 0.95


def _described(law: str) -> dict[str, dict]:
    """Each quantity of ``law`` as a digest describes it: a dimensionless parameter as
    sampled, the quadratic drag as c₂ [kg/m] (its physical quantity)."""
    out = {}
    for term in get_law(law).terms:
        for p in term.parameters:
            if p.name == "mu_s_ratio":
                continue
            name, symbol, unit = p.name, p.symbol, "1"
            if p.name == "c2":
                name, symbol, unit = "c2_SI", "c₂", "kg/m"
            out[name] = {
                "name": name,
                "symbol": symbol,
                "unit": unit,
                "label": p.label,
                "term": term.name,
                "non_negative": True,
            }
    return out


def _digest(rng, run_id: str, law: str, load: float, truth: dict[str, float]) -> FitDigest:
    """A run's digest with 200 normal draws (1 % wide) about ``truth`` ± a repeat spread."""
    draws, log_prior, summaries = {}, {}, {}
    for name, value in truth.items():
        centre = value * (1 + 0.03 * rng.standard_normal())
        draws[name] = centre * (1 + 0.01 * rng.standard_normal(200))
        log_prior[name] = np.full(200, -math.log(10 * value))
        summaries[name] = summarize(draws[name], PROB)
    described = _described(law)
    amps = np.geomspace(2e-5, 1e-3, 12) * (1 + 0.2 * rng.random())
    mean = (0.05 + load) * 1e-3 * (amps / 1e-3) ** 1.5
    band = {
        "law": law,
        "amplitude": amps.tolist(),
        "amplitude_unit": "m",
        "mean": mean.tolist(),
        "interval": [(0.95 * mean).tolist(), (1.05 * mean).tolist()],
        "prob": PROB,
        "unit": "J",
    }
    digest = FitDigest(
        run_name=run_id,
        metadata={"run_id": run_id, "lubricant": "oil", "load_N": load, **RIG},
        parameter_names=tuple(truth),
        converged=True,
        at_prior_bound=[],
        prob=PROB,
        summaries=summaries,
        draws=draws,
        log_prior=log_prior,
        law=law,
        quantities={n: described[n] for n in truth},
    )
    return digest, band


DRAG = {"zeta": 0.004, "c2_SI": 0.5}
POWER = {"mu_k": 0.03, "zeta_alpha": 0.01, "alpha": 1.5}


def _campaign(laws: dict[str, dict[str, float]], loads=(0.1, 0.3), repeats=3):
    rng = np.random.default_rng(4)
    digests, bands = [], {}
    for law, truth in laws.items():
        for load in loads:
            for r in range(repeats):
                run_id = f"{law}-N{load}-r{r}"
                d, band = _digest(rng, run_id, law, load, truth)
                digests.append(d)
                bands[run_id] = band
    analysis = analyse_campaign(
        digests, by=("lubricant", "load_N"), seed=1, max_steps=400, max_samples=200, prob=PROB
    )
    return analysis, bands


@pytest.fixture(scope="module")
def drag():
    return _campaign({"viscous+quadratic": DRAG})


@pytest.fixture(scope="module")
def two_laws():
    return _campaign({"viscous+quadratic": DRAG, "coulomb+power": POWER}, repeats=2)


def _axes(fig):
    return [ax for ax in fig.axes if ax.get_visible()]


def test_the_load_figure_draws_the_laws_own_quantities_with_the_trend_band(drag):
    from bayestribo.campaign.figures import plot_against_load

    analysis, _ = drag
    fig = plot_against_load(analysis)
    axes = _axes(fig)
    assert [ax.get_ylabel() for ax in axes] == [
        "population mean of ζ [-]",
        "population mean of c₂ [kg/m]",
    ]
    labels = {t.get_text() for t in fig.legends[0].get_texts()}
    assert "trend against load: median, 95 % band" in labels
    assert "paper, glycerol" not in labels  # oil: no glycerol reference
    # the band spans the loads of the series, about the group means
    from matplotlib.collections import PolyCollection

    [band] = [c for c in axes[1].collections if isinstance(c, PolyCollection)]
    x = band.get_paths()[0].vertices[:, 0]
    assert x.min() == pytest.approx(0.1, abs=0.01) and x.max() == pytest.approx(0.3, abs=0.01)
    [means] = axes[1].containers
    y = means.lines[0].get_ydata()
    assert np.all(np.abs(np.asarray(y) / DRAG["c2_SI"] - 1) < 0.1)


def test_the_forest_has_a_panel_per_quantity_and_the_truth_by_name(drag):
    from bayestribo.campaign.figures import plot_forest

    analysis, _ = drag
    truth = {r["run_id"]: DRAG for r in analysis.runs}
    fig = plot_forest(analysis, truth=truth)
    axes = _axes(fig)
    assert [ax.get_xlabel() for ax in axes[:2]] == ["ζ [-]", "c₂ [kg/m]"]
    assert "(o: ζ, △: c₂)" in axes[2].get_xlabel()
    ticks = [line for line in axes[1].lines if line.get_marker() == "|"]
    assert len(ticks) == len(analysis.runs)


def test_runs_of_two_laws_are_drawn_apart_and_never_read_a_quantity_they_lack(two_laws):
    from bayestribo.campaign.figures import plot_against_load, plot_forest

    analysis, _ = two_laws
    fig = plot_against_load(analysis)
    axes = _axes(fig)
    symbols = [ax.get_ylabel().removeprefix("population mean of ") for ax in axes]
    assert symbols == ["ζ [-]", "c₂ [kg/m]", "μ_k [-]", "ζ_α [-]", "α [-]"]
    labels = {t.get_text() for t in fig.legends[0].get_texts()}
    assert {"law coulomb+power, oil", "law viscous+quadratic, oil"} <= labels
    # each panel holds only its law's series
    for ax, name in zip(axes, ("zeta", "c2_SI", "mu_k", "zeta_alpha", "alpha"), strict=True):
        series = {c.get_label() for c in ax.containers}
        law = "viscous+quadratic" if name in DRAG else "coulomb+power"
        assert series == {f"law {law}, oil"}, name
    fig = plot_forest(analysis)
    assert len(_axes(fig)) == 6


def test_the_dissipation_figures_compare_runs_at_a_shared_swing(two_laws, tmp_path):
    from bayestribo.campaign.bands import (
        at_amplitude,
        dissipation_rows,
        group_runs,
        run_metadata,
    )
    from bayestribo.campaign.figures import (
        plot_dissipation,
        plot_dissipation_against_load,
        save_figures,
    )

    analysis, bands = two_laws
    groups = group_runs(analysis)
    assert len(groups) == 4 and all(len(runs) == 2 for runs in groups.values())
    shared, rows = dissipation_rows(groups, bands, metadata=run_metadata(analysis))
    assert 1e-4 < shared < 1e-3 and len(rows) == 8
    for row in rows:  # the bands are exact power laws: log-log interpolation is exact
        expected = (0.05 + row["load_N"]) * 1e-3 * (shared / 1e-3) ** 1.5
        assert row["mean"] == pytest.approx(expected, rel=1e-9)
        assert row["low"] == pytest.approx(0.95 * expected, rel=1e-9)
    assert at_amplitude(next(iter(bands.values())), 1.0) is None  # beyond the swings
    fig = plot_dissipation(groups, bands)
    axes = _axes(fig)
    assert len(axes) == 4 and all(ax.get_yscale() == "log" for ax in axes)
    assert axes[0].get_ylabel() == "ΔE per cycle [J]"
    fig = plot_dissipation_against_load(analysis, bands)
    assert len(fig.axes[0].containers) == 2  # one series per law
    paths = save_figures(analysis, tmp_path, bands=bands)
    # no run in air: no ζ_k, d_k figure
    assert [p.name for p in paths] == ["means_vs_load.png", "forest.png", "dissipation.png"]
