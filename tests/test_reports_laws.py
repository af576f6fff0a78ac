"""A fit's law as the reports say it: words and symbols from the registry, whether the
law holds, friction's share of the energy per cycle, and the ΔE(A) figure.

The share is checked against the paper's closed form for viscous damping and Coulomb
friction (ΔE = 2πζA² and 4x_cA over one harmonic cycle) computed here from the same
draws; the figure's bands are checked never to reach below zero.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo.model.laws import TERMS
from bayestribo.reports import laws, tables
from bayestribo.reports.figures import half_cycle_losses, plot_dissipation

READ = {"columns": ["time_s", "displacement_m"], "metadata": {"length_unit": "arbitrary"}}


@pytest.fixture(scope="module")
def paper_fit(appstat_file):
    """HarmOsc3 (dry friction on a plate) in the paper's law, a short sampler."""
    from bayestribo import read_run
    from bayestribo.inference import fit

    run = read_run(appstat_file("HarmOsc3.txt"), **READ)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit(run, seed=3, grid_points=24, max_steps=2000)


@pytest.mark.parametrize("name", list(TERMS))
def test_every_registered_term_reads_as_words_and_its_parameters_as_symbols(name):
    words = laws.term_words(name)
    assert words and "_" not in words
    assert laws.law_text(f"{name}+{name}") == f"{words} + {words}"
    # the law's parameters by their registry symbols, through prose
    for p in TERMS[name].parameters:
        assert tables.prose(f"the value of {p.name} is") == f"the value of {p.symbol} is"


def test_physical_quantities_have_their_registry_symbols():
    assert tables.physical_symbols("viscous+quadratic")["c2_per_mass"] == "c₂/m"
    assert tables.physical_symbols("power")["c_alpha_SI"] == "c_α"
    assert tables.physical_symbols("no_such_term") == {}


def test_a_law_of_one_kind_of_term_has_no_share_and_says_why(paper_fit, monkeypatch):
    for law, median, said in (("viscous", 0.0, "no friction term"), ("coulomb", 1.0, "no drag")):
        monkeypatch.setattr(type(paper_fit), "law", property(lambda self, law=law: law))
        share = laws.energy_share(paper_fit)
        assert share.draws is None and said in share.text() and share.median == median


def test_friction_share_per_draw_is_the_papers_closed_form(paper_fit):
    share = laws.energy_share(paper_fit, draws=10**6, seed=None)
    a = share.swing  # the largest swing [signal unit], ℓ = 1
    zeta = paper_fit.samples("zeta")
    x_c = paper_fit.samples("friction_displacement")
    expected = 4 * x_c * a / (4 * x_c * a + 2 * math.pi * zeta * a**2)
    assert share.draws.size == zeta.size  # every draw taken
    assert np.median(share.draws) == pytest.approx(np.median(expected), rel=1e-9)
    # friction's share grows as the swing shrinks: in every draw with a drag, so at the
    # interval's lower end (the median may sit on the share of 1 of the draws with ζ = 0,
    # half of them where the boundary law holds, at both swings)
    rows = laws.share_rows(paper_fit)
    assert rows["smallest swing"].median >= rows["largest swing"].median
    assert rows["smallest swing"].interval()[0] > rows["largest swing"].interval()[0]
    assert rows["largest swing"].dominant in ("friction", "drag (viscous damping)")


def test_the_paper_law_is_checked_by_the_model_checks_and_another_is_not(paper_fit):
    assert laws.adequacy_reason(paper_fit) is None
    assert laws.paper_parameters(paper_fit) == {"zeta": "ζ", "friction_displacement": "x_c"}
    from types import SimpleNamespace

    other = SimpleNamespace(law="coulomb+power")
    assert "Coulomb friction + power-law drag" in laws.adequacy_reason(other)


def test_a_misfit_law_does_not_hold(paper_fit):
    holds, why = laws.law_holds(paper_fit)  # dry friction on a plate: the paper's law misfits
    assert not holds and why


def test_the_dissipation_figure_never_draws_below_zero_on_log_axes(paper_fit):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    measured = dict(paper_fit.turning_point_dissipation)
    low = list(measured["interval"][0])
    low[0] = -abs(measured["mean"][0])  # a Student-t interval reaching below zero
    measured["interval"] = [low, measured["interval"][1]]
    fig, ax = plt.subplots()
    plot_dissipation(
        ax, paper_fit.dissipation, measured, points=half_cycle_losses([1.0, -0.9, 0.8])
    )
    assert ax.get_xscale() == ax.get_yscale() == "log"
    bottom = ax.get_ylim()[0]
    assert bottom > 0
    for collection in ax.collections:  # the law's band and the error bars
        for path in collection.get_paths():
            assert np.all(path.vertices[:, 1] >= 0)
    labels = ax.get_legend_handles_labels()[1]
    assert any("turning points" in label for label in labels)
    plt.close(fig)
    # the tables hold it at zero too
    frame = tables.dissipation_frame(paper_fit)
    assert not any("[-" in str(v) for v in frame.to_numpy().ravel())


def test_a_share_reads_in_the_digits_its_interval_supports_as_its_record_keeps_it(paper_fit):
    """The share with its interval by the digit rule: its ends never print as its median
    ("0.095 [0.095, 0.095]" once did, each number in three digits), and its record (a
    report's summary) holds the numbers the text shows."""
    from bayestribo.summary import interval_text

    for share in laws.share_rows(paper_fit).values():
        record = share.to_dict()
        median, (low, high) = record["median"], record["interval"]
        assert low <= median <= high and record["swing"] == share.swing
        text = share.text()
        assert text == interval_text(median, low, high)
        shown = [t.strip("[],") for t in text.split()]
        # numbers that differ print differently (a median on an end prints as it)
        assert len(set(shown)) == len({median, low, high}), text
