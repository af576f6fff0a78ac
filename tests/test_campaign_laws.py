"""Campaigns in any law: the quantities of each run's law, populations and trends over them.

Runs of a rig with viscous damping and quadratic drag (c₂ in kg/m) are simulated by an
independent ODE (:mod:`tests._law_recording`), fitted in ``viscous+quadratic``, and
analysed: the campaign compares ζ and c₂ [kg/m] (not the run-dependent dimensionless
c₂ℓ/m, whose ℓ = N/k moves with the load), and runs fitted in another law are grouped
apart.
"""

from __future__ import annotations

import numpy as np
import pytest
from _law_recording import law_recording, swing_dissipation

from bayestribo import fit
from bayestribo.campaign.analysis import analyse_campaign, sigma_scale
from bayestribo.campaign.digest import digest_fit
from bayestribo.campaign.quantities import campaign_quantities, quantity_draws

MASS = 0.035
ZETA = 0.004
C2 = 0.5  # quadratic drag coefficient [kg/m]
OMEGA = 2 * np.pi * 32.6


def _drag(v: float) -> float:
    return 2 * ZETA * OMEGA * v + C2 / MASS * v * abs(v)


def _fit(load: float, repeat: int, law: str = "viscous+quadratic"):
    run = law_recording(
        _drag, load_N=load, x0=1e-3, duration_s=1.2, sample_rate_Hz=4000.0, seed=repeat
    )
    run = run.with_metadata(run_id=f"oil-N{load}-r{repeat}-{law}", lubricant="oil", repeat=repeat)
    return fit(run, law=law, max_steps=3000, seed=repeat)


@pytest.fixture(scope="module")
def fits():
    return [_fit(load, r) for load in (0.1, 0.3) for r in (1, 2)]


def test_the_quantities_of_a_drag_law_are_its_physical_coefficients(fits):
    quantities, left_out = campaign_quantities(fits[0])
    assert [q.name for q in quantities] == ["zeta", "c2_SI"] and left_out == {}
    c2 = quantities[1]
    assert c2.unit == "kg/m" and c2.parameter == "c2" and c2.non_negative
    values, log_prior = quantity_draws(fits[0], c2)
    # the factor is m/ℓ, ℓ = N/k: the c₂ [kg/m] the fit reports, but for the fit's
    # draws of the sensor's gain (1 % by default), common to the runs of one sensor
    np.testing.assert_allclose(values, c2.factor * fits[0].samples("c2"), rtol=1e-12)
    ratio = values / fits[0].samples("c2_SI")
    assert abs(np.median(ratio) - 1) < 2e-3 and 0.002 < np.std(ratio) < 0.05
    # the prior density of c₂ [kg/m] is that of c₂ℓ/m with the factor's Jacobian
    raw = fits[0].samples("c2")
    expected = fits[0].prior_logpdf("c2", raw) - np.log(c2.factor)
    np.testing.assert_allclose(log_prior, expected)
    # the dimensionless c₂ℓ/m differs between loads; c₂ [kg/m] does not
    low, high = fits[0], fits[2]
    assert np.median(high.samples("c2")) / np.median(low.samples("c2")) > 2.0
    a = np.median(quantity_draws(low, campaign_quantities(low)[0][1])[0])
    b = np.median(quantity_draws(high, campaign_quantities(high)[0][1])[0])
    assert abs(a / b - 1) < 0.2


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_campaign_in_a_drag_law_compares_its_quantities_across_loads(fits):
    analysis = analyse_campaign(
        fits,
        by=("lubricant", "load_N"),
        seed=3,
        max_steps=1500,
        max_samples=100,
        dissipation=True,
    )
    assert analysis.laws == {"viscous+quadratic": [f.metadata["run_id"] for f in fits]}
    assert analysis.contact.parameters == ("zeta", "c2_SI")
    assert analysis.quantities["c2_SI"]["unit"] == "kg/m"
    assert analysis.zeta0 is None and analysis.derived == []  # no run in air
    for group in analysis.contact.groups.values():
        for name, truth in (("zeta", ZETA), ("c2_SI", C2)):
            lo, hi = np.quantile(group.mean[name], [0.005, 0.995])
            assert lo < truth < hi, (group.label, name, lo, hi)
    # the trend against the load holds a slope of zero: c₂ [kg/m] is the rig's own
    slope = analysis.trends["lubricant=oil"].slope_summary("c2_SI")
    assert slope["interval"][0] < 0.0 < slope["interval"][1]
    # the between-run σ prior of c₂ is half its typical value, as 0.01 is for ζ
    assert analysis.sigma_scales["zeta"] == 0.01
    assert analysis.sigma_scales["c2_SI"] == pytest.approx(C2 / 2, rel=0.2)
    # the law-free answer: ΔE at three swings every run reaches, per group and against
    # the load, against the true ΔE(A) of the drag by an independent integration
    pop = analysis.dissipation
    assert len(pop.parameters) == 3 and all(n.startswith("ΔE(A=") for n in pop.parameters)
    swings = [float(n.split("=")[1].split()[0]) for n in pop.parameters]
    truth = swing_dissipation(_drag, np.array(swings))
    for group in pop.groups.values():
        for name, true in zip(pop.parameters, truth, strict=True):
            lo, hi = np.quantile(group.mean[name], [0.005, 0.995])
            assert lo < true < hi, (group.label, name, lo, true, hi)
    flat = analysis.dissipation_trends["lubricant=oil"].slope_summary(pop.parameters[1])
    assert flat["interval"][0] < 0.0 < flat["interval"][1]
    rows = analysis.group_rows()
    assert {r["parameter"] for r in rows} == {"zeta", "c2_SI", *pop.parameters}
    assert all(r["law"] == "viscous+quadratic" for r in analysis.runs)
    assert all("c2_SI" in r and "mu_k" not in r for r in analysis.runs)


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_runs_fitted_in_two_laws_are_never_one_population(fits):
    other = [_fit(0.1, 1, law="viscous"), _fit(0.1, 2, law="viscous")]
    digests = [digest_fit(f, seed=3, max_samples=100) for f in [*fits[:2], *other]]
    analysis = analyse_campaign(
        digests, by=("lubricant", "load_N"), seed=3, max_steps=600, max_samples=100
    )
    assert set(analysis.laws) == {"viscous+quadratic", "viscous"}
    assert analysis.contact.by == ("law", "lubricant", "load_N")
    assert analysis.dissipation is None  # the law-free comparison only when asked for
    groups = {g.label: g for g in analysis.contact.groups.values()}
    assert set(groups) == {
        "law=viscous+quadratic,lubricant=oil,load_N=0.1",
        "law=viscous,lubricant=oil,load_N=0.1",
    }
    assert groups["law=viscous,lubricant=oil,load_N=0.1"].parameters == ("zeta",)
    assert len(groups["law=viscous+quadratic,lubricant=oil,load_N=0.1"].runs) == 2
    assert analysis.contact.pooled is None
    # differences only between groups that both model a quantity: ζ in both laws, c₂ in
    # one (the JSON report of such a campaign is whole)
    report = analysis.to_dict()["contact"]["differences"]
    assert len(report["zeta"]) == 1 and report["c2_SI"] == []


def test_the_sigma_scale_of_a_quantity_without_a_default():
    assert sigma_scale("mu_k", [0.5], [0.1]) == 0.01
    assert sigma_scale("c2_SI", [0.4, 0.6, 0.5], [0.1, 0.1, 0.1]) == pytest.approx(0.25)
    # every run at zero: the runs' interval width, the spread they can tell apart
    assert sigma_scale("c2_SI", [0.0, 0.0], [0.02, 0.04]) == pytest.approx(0.03)


# -- a term a lab registers in its own module reaches the campaign --------------------


def _lab_term():
    import math

    import numba

    from bayestribo.model.laws import Parameter, Term

    @numba.njit(cache=False)
    def force(w, c):
        return c[0] * w * w

    def physical(values, reference, scale):
        g = np.asarray(values["lab_g"], dtype=float)
        if scale.mass is None:
            return {}
        return {"lab_g_SI": (g / scale.length_scale * scale.mass, "kg/m", "g", "lab drag")}

    return Term(
        name="lab_quad",
        kind="drag",
        parameters=(
            Parameter(
                "lab_g",
                "g",
                "1/y",
                0.0,
                math.inf,
                "a lab's quadratic drag",
                lambda amplitude: {"type": "Uniform", "low": 0.0, "high": 1.0 / amplitude},
            ),
        ),
        n_coefficients=1,
        force=force,
        coefficients=lambda values, reference: [np.asarray(values["lab_g"], dtype=float)],
        dissipation=lambda a, values, reference: (
            (8.0 / 3.0) * np.asarray(values["lab_g"]) * np.asarray(a, dtype=float) ** 3
        ),
        physical=physical,
        description="a lab's quadratic drag",
    )


class _LabFit:
    """A fit-like result of the law viscous+lab_quad: what a FitResult gives a campaign."""

    law = "viscous+lab_quad"

    def __init__(self, name: str, load: float, g_si: float, rng: np.random.Generator) -> None:
        k = MASS * OMEGA**2
        self.attrs = {"length_scale": load / k, "omega": OMEGA, "friction_defined": 1}
        self.metadata = {
            "run_id": name,
            "lubricant": "lab-oil",
            "load_N": load,
            "mass_kg": MASS,
            "natural_frequency_Hz": OMEGA / (2 * np.pi),
        }
        factor = MASS / (load / k)  # g [kg/m] = lab_g m/ℓ
        self.draws = {
            "zeta": rng.normal(0.004, 1e-5, 400),
            "lab_g": rng.normal(g_si / factor, 1e-3 * g_si / factor, 400),
            "y0": rng.normal(5.0, 0.01, 400),
        }
        self.converged = True
        self.at_prior_bound: list = []

    @property
    def parameter_names(self):
        return list(self.draws)

    def samples(self, name):
        return self.draws[name]

    def prior_logpdf(self, name, values):
        return np.zeros_like(values)


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_term_registered_by_a_lab_reaches_the_campaign_without_edits():
    from bayestribo.model.laws import TERMS, register_term

    term = register_term(_lab_term())
    try:
        rng = np.random.default_rng(5)
        fits = [
            _LabFit(f"lab-N{load}-r{r}", load, rng.normal(0.3, 0.01), rng)
            for load in (0.1, 0.3)
            for r in (1, 2)
        ]
        quantities, _ = campaign_quantities(fits[0])
        assert [(q.name, q.unit, q.term) for q in quantities] == [
            ("zeta", "1", "viscous"),
            ("lab_g_SI", "kg/m", term.name),
        ]
        analysis = analyse_campaign(
            fits, by=("lubricant", "load_N"), seed=1, max_steps=600, max_samples=100
        )
        assert analysis.contact.parameters == ("zeta", "lab_g_SI")
        assert analysis.quantities["lab_g_SI"]["unit"] == "kg/m"
        for group in analysis.contact.groups.values():
            assert abs(np.median(group.mean["lab_g_SI"]) - 0.3) < 0.05
    finally:
        TERMS.remove("lab_quad")
