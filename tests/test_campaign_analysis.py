"""Campaign analysis on stand-in fit results: partition, groups, ζ₀, ζ_k, d_k, trends.

Short population samplings (600 steps): these tests check the bookkeeping and exact
relations, not the sampler (tests/test_population_groups.py does).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from bayestribo.campaign.analysis import analyse_campaign
from bayestribo.errors import BayestriboError

pytestmark = pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")


@dataclass
class _Fit:
    """Stand-in for bayestribo.inference.FitResult with exact normal posteriors."""

    draws: dict[str, np.ndarray]
    metadata: dict[str, Any] = field(default_factory=dict)
    converged: bool = True

    @property
    def run_name(self) -> str:
        return self.metadata["run_id"]

    @property
    def parameter_names(self) -> list[str]:
        return list(self.draws)

    def samples(self, name):
        return self.draws[name]

    def prior_logpdf(self, name, values):
        return np.where((values > 0) & (values < 0.3), -math.log(0.3), -np.inf)


RIG = {"mass_kg": 0.035, "natural_frequency_Hz": 32.6}


def _campaign(rng):
    fits = []
    for load in (0.12, 0.46):
        for r in range(3):
            z, m = rng.normal(0.0236, 0.0012), rng.normal(0.0294, 0.0036)
            meta = {"run_id": f"g-N{load}-r{r}", "lubricant": "glycerol", "load_N": load, **RIG}
            fits.append(
                _Fit({"zeta": rng.normal(z, 2e-5, 400), "mu_k": rng.normal(m, 5e-5, 400)}, meta)
            )
    for r in range(3):
        meta = {"run_id": f"air-r{r}", "lubricant": "none", "load_N": 0.0, **RIG}
        fits.append(_Fit({"zeta": rng.normal(rng.normal(0.0033, 1e-4), 1e-6, 400)}, meta))
    return fits


@pytest.fixture(scope="module")
def analysis():
    return analyse_campaign(_campaign(np.random.default_rng(2)), seed=1, max_steps=2000)


@pytest.fixture(scope="module")
def short_analysis():
    """The campaign analysed with short samplers: the reference of the tests that compare
    two ways to the same analysis, draw for draw, whether or not they converge."""
    return analyse_campaign(_campaign(np.random.default_rng(2)), seed=1, max_steps=300)


def test_runs_are_split_into_contact_groups_and_zeta0(analysis):
    # water_mass_fraction is in no run: left out of the grouping keys.
    assert analysis.by == ("lubricant", "load_N")
    assert list(analysis.contact.groups) == [("glycerol", 0.12), ("glycerol", 0.46)]
    # Pooled over the loads of the series, not over every run with contact.
    assert analysis.contact.pooled is None
    assert list(analysis.series.groups) == ["glycerol"]
    assert analysis.series.groups["glycerol"].runs == tuple(
        f"g-N{n}-r{r}" for n in (0.12, 0.46) for r in range(3)
    )
    assert analysis.zeta0.parameters == ("zeta",)
    assert analysis.zeta0.pooled.runs == ("air-r0", "air-r1", "air-r2")
    z0 = analysis.zeta0.pooled.mean["zeta"]
    assert np.quantile(z0, 0.025) < 0.0033 < np.quantile(z0, 0.975)
    assert list(analysis.trends) == ["lubricant=glycerol"]
    assert {r["parameter"] for r in analysis.trend_rows()} == {"zeta", "mu_k"}
    kinds = [r["kind"] for r in analysis.group_rows()]
    assert kinds == ["contact"] * 4 + ["pooled over loads"] * 2 + ["no contact"]
    assert [r["run_id"] for r in analysis.runs][-1] == "air-r2"
    assert "mu_k" not in analysis.runs[-1]


def test_derived_d_k_is_2_zeta_k_m_omega_over_load(analysis):
    for row in analysis.derived:
        factor = 2 * RIG["mass_kg"] * 2 * math.pi * RIG["natural_frequency_Hz"] / row["load_N"]
        # A positive linear map: medians and interval ends map exactly.
        assert row["d_k_s_per_m"]["median"] == pytest.approx(
            factor * row["zeta_k"]["median"], rel=1e-9
        )
        assert row["d_k_s_per_m"]["interval"] == pytest.approx(
            [factor * v for v in row["zeta_k"]["interval"]], rel=1e-9
        )
        # ζ_k ≈ 0.0236 − 0.0033 within its interval.
        lo, hi = row["zeta_k"]["interval"]
        assert lo < 0.0203 < hi


def test_report_is_json_ready(analysis):
    import json

    text = json.dumps(analysis.to_dict())
    assert '"zeta0"' in text and '"derived"' in text


def test_no_runs_is_an_error():
    with pytest.raises(BayestriboError, match="no fitted runs"):
        analyse_campaign([])


def test_glycerol_water_series_get_a_trend_against_viscosity():
    from bayestribo.campaign.analysis import VISCOSITY_KEY
    from bayestribo.model.viscosity import glycerol_water_viscosity

    rng = np.random.default_rng(4)
    fits = []
    for w in (0.0055, 0.09):
        nu = float(glycerol_water_viscosity(w))
        for r in range(2):
            meta = {
                "run_id": f"w{w}-r{r}",
                "lubricant": "glycerol-water",
                "water_mass_fraction": w,
                "load_N": 0.12,
                **RIG,
            }
            zeta = 0.004 + 2e-5 * nu  # rises with ν
            draws = {"zeta": rng.normal(zeta, 2e-5, 300), "mu_k": rng.normal(0.03, 5e-5, 300)}
            fits.append(_Fit(draws, meta))
    a = analyse_campaign(fits, seed=2, max_steps=1000)  # the labels, not convergence
    label = "viscosity:lubricant=glycerol-water,load_N=0.12"
    assert label in a.trends and a.trends[label].covariate == VISCOSITY_KEY
    # Centre of the covariate = mean ν of the runs, computed with Eq. 43.
    expected = np.mean([glycerol_water_viscosity(w) for w in (0.0055, 0.0055, 0.09, 0.09)])
    assert a.trends[label].center == pytest.approx(expected, rel=1e-12)
    assert a.trends[label].slope_summary("zeta")["prob_positive"] > 0.9


def test_progress_names_each_population_and_trend_before_sampling_it():
    messages: list[str] = []
    fits = _campaign(np.random.default_rng(2))
    # what is said and which runs are used: short samplers do (their answer is not checked)
    got = analyse_campaign(fits, seed=1, max_steps=300, progress=messages.append)
    assert messages[0] == "population of 6 runs with contact, by lubricant, load_N"
    assert "trends against load_N: lubricant=glycerol" in messages
    assert "ζ₀ from 3 runs without contact" in messages
    # then the queue of posteriors (3 groups of contact + pooled, ζ₀ groups + pooled, a
    # trend), with its progress: the last message says all are done
    queued = messages.index("ζ₀ from 3 runs without contact") + 1
    total = int(messages[queued].split()[1])
    assert messages[queued] == f"sampling {total} population and trend posteriors"
    assert messages[-1] == f"sampled {total} of {total} posteriors"
    assert got.excluded == [] and all(r["status"] == "used" for r in got.runs)
    # every run, with and without contact, under the one law they were fitted in
    assert list(got.laws) == ["viscous+coulomb"]
    assert sorted(got.laws["viscous+coulomb"]) == sorted(r["run_id"] for r in got.runs)


def test_a_run_without_a_grouping_key_is_excluded_with_the_reason():
    fits = _campaign(np.random.default_rng(2))
    del fits[0].metadata["lubricant"]
    # which runs enter which population: short samplers do (their answer is not checked)
    got = analyse_campaign(fits, seed=1, max_steps=300)
    assert got.excluded == [
        {
            "run": "g-N0.12-r0",
            "reason": "metadata has no 'lubricant' to group by (the other runs have it); add "
            "it to the run's sidecar",
        }
    ]
    status = {r["run_id"]: r["status"] for r in got.runs}
    assert status["g-N0.12-r0"].startswith("excluded: metadata has no 'lubricant'")
    assert sum(g["n_runs"] for g in got.group_rows() if g["kind"] == "contact") // 2 == 5


def test_an_executor_gives_the_serial_analysis(short_analysis):
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=2) as pool:
        parallel = analyse_campaign(
            _campaign(np.random.default_rng(2)), seed=1, max_steps=300, executor=pool
        )
    assert parallel.group_rows() == short_analysis.group_rows()
    assert parallel.trend_rows() == short_analysis.trend_rows()


def test_a_run_without_a_load_is_not_taken_for_a_run_in_air():
    """A sidecar whose load is missing (a typo the reader did not catch, or left out):
    the fit has a friction displacement, not μ_k; the run is excluded for want of a
    load, and ζ₀ is the air runs' alone."""
    fits = _campaign(np.random.default_rng(2))
    meta = {"run_id": "g-typo", "lubricant": "glycerol", **RIG}
    draws = {"zeta": np.full(400, 0.0242), "friction_displacement": np.full(400, 6e-6)}
    fits.append(_Fit(draws, meta))
    # which runs enter which population: short samplers do (their answer is not checked)
    result = analyse_campaign(fits, seed=1, max_steps=300)
    assert result.zeta0.pooled.runs == ("air-r0", "air-r1", "air-r2")
    reasons = {e["run"]: e["reason"] for e in result.excluded}
    assert "'load_N'" in reasons["g-typo"]


def test_names_with_dollar_signs_are_drawn_as_written(tmp_path):
    """A lubricant named like mathematics (``glycerol $\\alpha_$``) draws as written in
    the campaign figures instead of failing inside matplotlib."""
    pytest.importorskip("matplotlib")
    from bayestribo.campaign.figures import save_figures

    fits = _campaign(np.random.default_rng(2))
    for f in fits:
        if f.metadata["lubricant"] == "glycerol":
            f.metadata["lubricant"] = "glycerol $\\alpha_$"
            f.metadata["run_id"] = "$" + f.metadata["run_id"]
    result = analyse_campaign(fits, seed=1, max_steps=300)  # the figures, not the samplers
    paths = save_figures(result, tmp_path)
    assert len(paths) == 3 and all(p.stat().st_size > 0 for p in paths)


def test_digests_give_the_analysis_of_the_fits(short_analysis):
    """A campaign keeps digests, not fits: the same runs, groups, trends and ζ₀."""
    from bayestribo.campaign.digest import FitDigest, digest_fit

    fits = _campaign(np.random.default_rng(2))
    digests = [digest_fit(f, prob=0.95, max_samples=300, seed=1) for f in fits]
    assert all(isinstance(d, FitDigest) for d in digests)
    # 400 draws per run, 300 kept: the digest holds less than the fit.
    assert all(d.draws["zeta"].size == 300 for d in digests)
    again = analyse_campaign(digests, seed=1, max_steps=300)
    assert again.runs == short_analysis.runs
    assert again.group_rows() == short_analysis.group_rows()
    assert again.trend_rows() == short_analysis.trend_rows()
    assert again.to_dict() == short_analysis.to_dict()
    with pytest.raises(BayestriboError, match=r"summarises at 0\.95, not at 0\.9"):
        analyse_campaign(digests, seed=1, max_steps=300, prob=0.9)
    with pytest.raises(ValueError, match="at its own draws only"):
        digests[0].prior_logpdf("zeta", [0.02])


def test_the_terminal_text_fits_100_columns_aligned_with_its_probability(analysis):
    from bayestribo.cli.campaign import _text

    failures = [{"run": "bad-r9", "error": "RunFormatError: no such run file"}]
    text = _text(analysis, failures)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= 100, max(lines, key=len)
    assert "95 % credible interval" in text and "P(slope > 0) = " in text
    # words, not identifiers: no key=value labels, no Python names
    assert "load_N" not in text and "=" not in text.replace("P(slope > 0) =", "")
    assert "glycerol · 0.12 N, 3 runs" in text and "Trends against load: slope per N" in text
    # the σ column starts at the same place in every parameter line
    columns = {line.index(" σ ") for line in lines if line.startswith("    ") and " σ " in line}
    assert len(columns) == 1
    assert "FAILED bad-r9: RunFormatError: no such run file" in lines
    assert "no contact (ζ₀), 3 runs" in lines


def test_the_contact_damping_figure_has_a_colour_and_a_legend_entry_per_series():
    """ζ_k and d_k of two series (glycerol, glycerol-water) at the same loads: one
    colour per series, named in a legend, not all groups in one colour."""
    import matplotlib

    matplotlib.use("Agg")
    from bayestribo.campaign.figures import plot_derived

    rng = np.random.default_rng(5)
    fits = _campaign(rng)
    for load in (0.12, 0.46):
        for r in range(3):
            meta = {
                "run_id": f"gw-N{load}-r{r}",
                "lubricant": "glycerol-water",
                "water_mass_fraction": 0.03,
                "load_N": load,
                **RIG,
            }
            draws = {"zeta": rng.normal(0.018, 2e-5, 400), "mu_k": rng.normal(0.03, 5e-5, 400)}
            fits.append(_Fit(draws, meta))
    for f in fits:
        f.metadata.setdefault("water_mass_fraction", 0.0055)
    analysis = analyse_campaign(fits, seed=1, max_steps=300)  # the colours, not the samplers
    fig = plot_derived(analysis)
    [legend] = fig.legends
    assert sorted(t.get_text() for t in legend.get_texts()) == [
        "glycerol, water 0.55 % by mass",
        "glycerol-water, water 3 % by mass",
    ]
    colours = {c.lines[0].get_color() for c in fig.axes[0].containers}
    assert len(colours) == 2


def test_the_load_figure_draws_each_run_and_the_paper_only_beside_glycerol(analysis):
    import matplotlib

    matplotlib.use("Agg")
    from bayestribo.campaign.figures import plot_against_load

    fig = plot_against_load(analysis)
    labels = {t.get_text() for t in fig.legends[0].get_texts()}
    assert {"a run (median)", "paper, glycerol"} <= labels
    dots = [line for line in fig.axes[0].lines if line.get_label() == "a run (median)"]
    assert len(dots[0].get_xdata()) == 6  # the six runs with contact
    # a campaign of another lubricant, or of the glycerol-water solutions, gets no
    # glycerol reference
    for lubricant in ("oil", "glycerol-water"):
        fits = _campaign(np.random.default_rng(4))
        for f in fits:
            f.metadata["lubricant"] = lubricant if f.metadata["load_N"] else "none"
        other = analyse_campaign(fits, seed=1, max_steps=300)  # the legend only
        labels = {t.get_text() for t in plot_against_load(other).legends[0].get_texts()}
        assert "paper, glycerol" not in labels, lubricant


def test_group_labels_read_as_words_with_units():
    from bayestribo.population.groups import POOLED, group_words

    label = "lubricant=glycerol,water_mass_fraction=0.0055,load_N=0.12"
    assert group_words(label) == "glycerol, water 0.55 % by mass, N = 0.12 N"
    assert group_words("lubricant=oil,temperature_C=40") == "oil, temperature_C=40"
    assert group_words("water_mass_fraction=n/a") == "water n/a"
    assert group_words(POOLED) == "all runs"


def test_the_viscosity_figure_draws_each_load_beside_the_paper_and_reads_in_print():
    """A glycerol–water series at two water fractions and one load: the group means
    against ν (Eq. 43) in one colour for the load, each run's median, the paper's
    glycerol values and the 6 % water line; no text below 8 pt, no labels overlapping."""
    import matplotlib

    matplotlib.use("Agg")
    from bayestribo.campaign.figures import plot_against_viscosity
    from bayestribo.model.viscosity import glycerol_water_viscosity
    from bayestribo.reports.kit import overlapping_labels, setup, small_texts

    setup(None)  # the reports' look
    rng = np.random.default_rng(9)
    fits = []
    for water, zeta in ((0.0055, 0.0236), (0.09, 0.013)):
        for r in range(2):
            meta = {
                "run_id": f"gw{water}-r{r}",
                "lubricant": "glycerol-water",
                "water_mass_fraction": water,
                "load_N": 0.12,
                **RIG,
            }
            draws = {
                "zeta": rng.normal(zeta + 1e-4 * r, 2e-5, 400),
                "mu_k": rng.normal(0.03, 5e-5, 400),
            }
            fits.append(_Fit(draws, meta))
    analysis = analyse_campaign(fits, seed=1, max_steps=300)  # the figure, not the samplers
    fig = plot_against_viscosity(analysis)
    labels = {t.get_text() for t in fig.legends[0].get_texts()}
    assert {"N = 0.12 N", "a run (median)", "paper, glycerol (mean ± σ)", "6 % water"} <= labels
    means = [c for c in fig.axes[0].containers if c.get_label() == "N = 0.12 N"]
    x = np.sort(means[0].lines[0].get_xdata())
    np.testing.assert_allclose(x, glycerol_water_viscosity(np.array([0.09, 0.0055])), rtol=0.03)
    assert small_texts(fig) == [] and overlapping_labels(fig) == []


def test_each_trend_keeps_its_population_mean_at_the_ends_of_its_loads(analysis):
    """population.json holds the trend's mean at the lightest and heaviest load of its
    runs, the median and equal-tailed 95 % interval of its draws there (the campaign
    report's table of them reads these numbers)."""
    record = analysis.to_dict()["trends"]["lubricant=glycerol"]
    t = analysis.trends["lubricant=glycerol"]
    assert record["span"] == [0.12, 0.46]
    assert set(record["mean_at_ends"]) == {"zeta", "mu_k"}
    for p, ends in record["mean_at_ends"].items():
        assert [e["at"] for e in ends] == [0.12, 0.46]
        for end in ends:
            draws = t.intercept[p] + t.slope[p] * end["at"]
            lo, mid, hi = np.quantile(draws, [0.025, 0.5, 0.975])
            assert end["median"] == pytest.approx(mid, rel=1e-12)
            assert end["interval"] == pytest.approx([lo, hi], rel=1e-12)


@dataclass
class _BandFit(_Fit):
    """A fit with a law's ΔE(A) band: ΔE = c A² [J], its interval 0.9 c A² to 1.1 c A²."""

    swings: tuple[float, float] = (1e-4, 1e-3)
    c: float = 1.0

    @property
    def dissipation(self):
        a = np.geomspace(*self.swings, 12)
        return {
            "law": "viscous+coulomb",
            "amplitude": a.tolist(),
            "amplitude_unit": "m",
            "mean": (self.c * a**2).tolist(),
            "interval": [(0.9 * self.c * a**2).tolist(), (1.1 * self.c * a**2).tolist()],
            "unit": "J",
            "prob": 0.95,
        }


def test_each_runs_energy_loss_at_a_swing_every_run_reaches_is_kept():
    """population.json holds each run's ΔE from its law's band at one swing inside every
    run's range (the geometric middle of the range they share), read off its band on
    log-log axes: exact for ΔE ∝ A²."""
    fits = [
        _BandFit(f.draws, f.metadata, swings=(1e-4 * (1 + i / 10), 1e-3 * (1 - i / 20)), c=i + 1)
        for i, f in enumerate(_campaign(np.random.default_rng(3)))
    ]
    got = analyse_campaign(fits, seed=1, max_steps=300).to_dict()["dissipation_at_swing"]
    a = got["amplitude"]
    assert a == pytest.approx(np.sqrt(1e-4 * 1.8 * 1e-3 * 0.6), rel=1e-12)
    assert [r["run"] for r in got["rows"]] == [f.metadata["run_id"] for f in fits]
    for row, fit in zip(got["rows"], fits, strict=True):
        assert row["amplitude"] == a and row["unit"] == "J" and row["amplitude_unit"] == "m"
        assert row["mean"] == pytest.approx(fit.c * a**2, rel=1e-9)
        assert row["interval"] == pytest.approx([0.9 * fit.c * a**2, 1.1 * fit.c * a**2])
    # fits without a band keep none
    assert (
        analyse_campaign(_campaign(np.random.default_rng(3)), seed=1, max_steps=300).to_dict()[
            "dissipation_at_swing"
        ]
        is None
    )
