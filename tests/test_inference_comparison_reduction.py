"""A law whose extra terms the data put at zero reduces to the law it nests.

On a record of Coulomb friction alone, ``coulomb+power`` has its drag at zero at the
optimum, which leaves the exponent α to its prior: sampled, it ran to the step ceiling
(10 to 13 minutes of ``law="auto"``, ``benchmarks/auto_speed.py``). The comparison
recognises it as ``coulomb`` with the power drag at 0, does not sample it, and says
so, never calling it converged. A law whose extra term the data do need is sampled as
before.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bayestribo import simulate
from bayestribo.inference import prepare
from bayestribo.inference.comparison import LawComparison, compare_prepared
from bayestribo.inference.pipeline import build_posterior, find_optimum
from bayestribo.inference.reduction import REDUCTION_LOSS, reduction, reduction_among
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.synthetic import DissipationLaw

SETTINGS = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=3000)


@pytest.fixture(scope="module")
def coulomb_run():
    """Coulomb friction alone (μ_k = 0.02, μ_s = 0.03), no viscous damping."""
    run = simulate(DissipationLaw(zeta=0.0, mu_k=0.02, mu_s=0.03), seed=11)
    return prepare(run, seed=1)


@pytest.fixture(scope="module")
def both_run():
    """Viscous damping and Coulomb friction (ζ = 0.01, μ_k = 0.02)."""
    run = simulate(DissipationLaw(zeta=0.01, mu_k=0.02, mu_s=0.03), seed=12)
    return prepare(run, seed=1)


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_drag_at_zero_on_a_coulomb_record_reduces_to_coulomb_unsampled(coulomb_run):
    laws = ["coulomb", "coulomb+power", "viscous+coulomb"]
    c, runs = compare_prepared(coulomb_run, laws, seed=3, settings=SETTINGS, rivals=False)
    assert c.verdict == "coulomb" and c.adequate
    assert c.equivalent == {"coulomb+power": "coulomb", "viscous+coulomb": "coulomb"}
    assert set(runs) == {"coulomb"}  # only the nested law was sampled
    row = c.table["coulomb+power"]
    assert row["reduces_to"] == "coulomb" and row["terms_at_zero"] == ["power"]
    # not sampled is not "converged": the row says neither True nor False
    assert row["sampled"] is False and row["converged"] is None
    assert "elpd_loo" not in row and row["adequate"] is True
    assert c.table["viscous+coulomb"]["terms_at_zero"] == ["viscous"]
    assert c.table["coulomb"]["sampled"] is True and c.table["coulomb"]["converged"] is True
    # the laws reduced are not among those as good as the verdict (they are it)
    assert c.as_good == ["coulomb"]
    text = c.describe()
    assert text.startswith("coulomb chosen from 3 laws")
    assert "coulomb+power to coulomb (power at 0)" in text
    assert "viscous+coulomb to coulomb (viscous at 0)" in text
    assert c.to_dict()["equivalent"] == c.equivalent


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_an_extra_term_the_data_need_is_sampled(both_run):
    # without screening, which would leave coulomb alone unsampled on this record
    c, runs = compare_prepared(
        both_run,
        ["coulomb", "viscous+coulomb"],
        seed=3,
        settings=SETTINGS,
        rivals=False,
        screening=False,
    )
    assert c.equivalent == {}
    assert set(runs) == {"coulomb", "viscous+coulomb"}
    assert c.table["viscous+coulomb"]["sampled"] is True
    assert "reduces_to" not in c.table["viscous+coulomb"]
    assert c.verdict == "viscous+coulomb"


def _optima(prepared, law: str, nested: str):
    """The nested law's optimum, and the posterior and optimum of ``law`` started there
    too (as the comparison finds them)."""
    small = build_posterior(prepared.data, law=nested)
    theta_small = find_optimum(small, prepared.decay)[0]
    optima = {nested: dict(zip(small.names, theta_small, strict=True))}
    bigger = build_posterior(prepared.data, law=law)
    start = {**optima[nested], "zeta_alpha": 1e-6, "alpha": 1.0}
    theta = find_optimum(bigger, prepared.decay, also_start_at=start)[0]
    return bigger, theta, optima


def _fitted(converged: bool) -> dict:
    return {"coulomb": SimpleNamespace(run=SimpleNamespace(converged=converged))}


def test_a_law_reduces_only_to_a_converged_nested_law(coulomb_run):
    bigger, theta, optima = _optima(coulomb_run, "coulomb+power", "coulomb")
    names = bigger.names
    # the optimum's drag (tiny, α where the prior leaves it) gains less than half a
    # unit of log density over the nested law's optimum with no drag
    nested = np.array(theta, dtype=float)
    for name, value in optima["coulomb"].items():
        nested[names.index(name)] = value
    nested[names.index("zeta_alpha")] = 0.0
    assert theta[names.index("zeta_alpha")] < 1e-6
    assert bigger(nested[None])[0] >= bigger(theta[None])[0] - REDUCTION_LOSS
    assert reduction("coulomb+power", bigger, theta, _fitted(True), optima) == (
        "coulomb",
        ["power"],
    )
    # a nested law that did not converge is no answer to reduce to: sampled instead
    assert reduction("coulomb+power", bigger, theta, _fitted(False), optima) is None


def test_a_law_reduces_by_the_optima_alone_to_any_law_named(coulomb_run):
    # the screening's use: the law reduced to need not be sampled, only optimised
    bigger, theta, optima = _optima(coulomb_run, "coulomb+power", "coulomb")
    assert reduction_among("coulomb+power", bigger, theta, ["coulomb"], optima) == (
        "coulomb",
        ["power"],
    )
    # a law not named, or named without an optimum, is not reduced to
    assert reduction_among("coulomb+power", bigger, theta, [], optima) is None
    assert reduction_among("coulomb+power", bigger, theta, ["coulomb"], {}) is None
    assert reduction_among("coulomb+power", bigger, theta, ["viscous"], optima) is None


def test_a_drag_the_data_need_does_not_reduce(both_run):
    # viscous damping in the record: coulomb+power's drag stands for it (α near 1),
    # and removing it costs far more than half a unit
    bigger, theta, optima = _optima(both_run, "coulomb+power", "coulomb")
    names = bigger.names
    assert theta[names.index("zeta_alpha")] > 1e-3
    assert reduction("coulomb+power", bigger, theta, _fitted(True), optima) is None
    assert reduction_among("coulomb+power", bigger, theta, ["coulomb"], optima) is None


def test_the_comparison_text_names_the_laws_reduced_as_a_result_reads_it_back():
    table = {
        "coulomb": {"converged": True, "adequate": True},
        "coulomb+power": {"reduces_to": "coulomb", "terms_at_zero": ["power"]},
        "viscous+coulomb+quadratic": {
            "reduces_to": "coulomb",
            "terms_at_zero": ["viscous", "quadratic"],
        },
    }
    c = LawComparison(
        "run",
        table,
        "coulomb",
        "coulomb",
        ["coulomb"],
        equivalent={"coulomb+power": "coulomb", "viscous+coulomb+quadratic": "coulomb"},
    )
    assert c.describe().endswith(
        "not sampled, equivalent at the optimum to a nested law compared: coulomb+power to "
        "coulomb (power at 0), viscous+coulomb+quadratic to coulomb (viscous, quadratic at 0)"
    )
    # as FitResult rebuilds it from its JSON
    back = c.to_dict()
    fields = {k: back[k] for k in ("best", "verdict", "as_good", "table", "warnings")}
    again = LawComparison(
        back["run_name"], **fields, adequate=back["adequate"], equivalent=back["equivalent"]
    )
    assert again.describe() == c.describe()
