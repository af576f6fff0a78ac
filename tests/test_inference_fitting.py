"""The single-run fit end to end: convergence, truth recovery, results, grid invariance."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from _paths import RUNS

from bayestribo.errors import BayestriboError, ConvergenceWarning
from bayestribo.inference import FitResult, fit
from bayestribo.io import read_run
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model
from bayestribo.synthetic import DissipationLaw, Release, Sensor
from bayestribo.synthetic.recording import simulate

DATA = RUNS
pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")


@pytest.fixture(scope="module")
def bundled():
    path = DATA / "glycerol-N0.31-r1.csv"
    return read_run(path), fit(path, seed=3)


def test_bundled_run_converges_and_covers_the_truth(bundled):
    run, result = bundled
    sim = run.metadata["simulation"]
    d = result.diagnostics
    assert result.converged, d["reasons"]
    assert d["ess_min"] >= 1000 and d["rhat_max"] < 1.01
    # The fit's stopping rule: an ESS of 1000 (31.25 τ with its 2 × 16 walkers) and
    # at least 20 τ after burn-in.
    walkers = d["n_walkers"] * d["n_ensembles"]
    assert (d["n_steps"] - d["burn"]) * walkers / d["autocorr_time_max"] >= 1000
    assert d["n_steps"] - d["burn"] >= 20 * d["autocorr_time_max"]
    for name in ("zeta", "mu_k"):
        s = result.samples(name)
        # One run: the truth within 4.5 posterior sd (a 1-in-150 000 event if calibrated);
        # calibration over many runs is in tests/test_inference_calibration.py and benchmarks/.
        assert abs(np.mean(s) - sim[name]) < 4.5 * np.std(s), name
    # Friction displacement x_c = μ_k N/k in metres, k = mΩ² with the measured Ω; μ_k
    # carries the frequency nuisance ε (μ_k/(1 + ε)² per draw), whose mean over n
    # draws is within a few σ_ε/√n of 0.
    k = 0.035 * (2 * np.pi * result.idata.posterior.attrs["omega"] / (2 * np.pi)) ** 2
    mu_k = result.samples("mu_k")
    sd_eps = result.idata.posterior.attrs["frequency_nuisance_sd"]
    assert np.mean(result.samples("friction_displacement")) == pytest.approx(
        np.mean(mu_k) * 0.31 / k, rel=1e-9 + 8 * sd_eps / np.sqrt(mu_k.size)
    )


def test_result_contents_and_round_trip(bundled, tmp_path):
    _, result = bundled
    idata = result.idata
    for group in ("posterior", "log_likelihood", "posterior_predictive", "observed_data"):
        assert group in idata.groups()
    assert idata.log_likelihood["pi"].shape[-1] == idata.observed_data["pi"].size
    record = json.loads(json.dumps(result.to_dict()))
    assert set(record["parameters"]) >= {"zeta", "mu_k", "mu_s", "friction_displacement"}
    assert record["noise"]["source_displacement"] in ("nominal", "measured")
    assert record["diagnostics"]["converged"] is True
    lo, hi = result.interval("zeta", 0.9)
    assert lo < np.median(result.samples("zeta")) < hi
    path = result.save(tmp_path / "fit.nc")
    back = FitResult.load(path)
    assert back.summary() == result.summary()
    assert back.metadata == result.metadata and back.seed == 3 and back.model == "exact"
    assert back.prior_logpdf("zeta", [0.02, 0.5]).tolist() == [np.log(1 / 0.3), -np.inf]
    import arviz as az

    # The file is plain netCDF-4: another reader (h5netcdf) gets the same draws.
    other = az.from_netcdf(str(path), engine="h5netcdf")
    np.testing.assert_array_equal(other.posterior["zeta"].values, idata.posterior["zeta"].values)
    assert other.posterior.attrs["model"] == "exact"
    # Fit files written by earlier versions (h5netcdf) still load.
    older = tmp_path / "older.nc"
    idata.to_netcdf(str(older), engine="h5netcdf")
    assert FitResult.load(older).summary() == result.summary()

    loo = az.loo(result.idata)
    assert np.isfinite(loo.elpd_loo)


def test_prior_sensitivity_is_reported(bundled):
    _, result = bundled
    sens = result.prior_sensitivity
    assert set(sens) == {"zeta", "mu_k", "mu_s_ratio", "y0"}
    # Uniform priors: no power-scaling shift; the data dominate ζ and μ_k.
    assert sens["zeta"]["mean_shift_sd"] < 0.01 and sens["zeta"]["contraction"] > 0.99


@pytest.fixture(scope="module")
def short_run():
    return simulate(
        release=Release(initial_displacement_m=1e-3),
        sensor=Sensor(
            sample_rate_Hz=3000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=21,
    )


def test_same_seed_same_posterior(short_run):
    a = fit(short_run, seed=7, grid_points=32)
    b = fit(short_run, seed=7, grid_points=32)
    np.testing.assert_array_equal(a.samples("zeta"), b.samples("zeta"))


def _fisher_sd(data, theta, independent_pi=False):
    """Posterior sd of ζ and μ_k from the Fisher information of a Π likelihood.

    ``independent_pi``: the mistaken model treating Π's grid values as independent,
    each with its marginal variance.
    """
    from bayestribo.inference.likelihood import PiLikelihood

    lik = PiLikelihood(data)
    steps = np.array([1e-7, 1e-7, 1e-6])

    def inc(th):
        col = {"zeta": th[0], "mu_k": th[1], "mu_s_ratio": 1.2, "y0": th[2]}
        return lik.model_increments({k: np.array([v]) for k, v in col.items()})[0]

    jac = np.column_stack(
        [
            (inc(theta + np.eye(3)[i] * steps[i]) - inc(theta - np.eye(3)[i] * steps[i]))
            / (2 * steps[i])
            for i in range(3)
        ]
    )
    jac = np.column_stack([jac, data.offset_design])  # the marginalised linear nuisances
    prior = np.diag([0, 0, 0, lik.offset_sd**-2, lik.drift_sd**-2, 1.0])
    if independent_pi:
        jac = np.cumsum(jac[::-1], axis=0)[::-1]
        fisher = jac.T @ (jac / data.pi_variance[:, None]) + prior
    else:
        fisher = jac.T @ (jac / data.variance[:, None]) + prior
    return np.sqrt(np.diag(np.linalg.inv(fisher)))[:2]


def test_denser_pi_grid_adds_only_the_information_of_finer_increments(short_run):
    """Π sampled 4× denser: the width changes as the increments' information says.

    With the exact (backward random walk) covariance, finer increments add only the
    information genuinely in the finer structure of E, which the Fisher information of
    the increments predicts; the posterior follows that prediction. Treating the 4×
    more Π values as independent would shrink the width by a further factor ~2.
    """
    from bayestribo.signal.decay import energy_decay

    half_cycles = 24  # in the analysed window of this run
    # 2 × 32 walkers: the fit's rule (ESS 1000, at least 20 τ) then gives 2000-3000
    # effective draws a fit, the ratio of two sds known to ±2 % (one sd)
    coarse = fit(short_run, seed=1, grid_points=half_cycles // 4, n_walkers=32)
    fine = fit(short_run, seed=1, grid_points=half_cycles, n_walkers=32)
    decay = energy_decay(
        short_run.time, short_run.displacement, short_run.velocity, rig=short_run.rig()
    )
    assert round(decay.tau[-1] / np.pi) == half_cycles
    noise = noise_model(decay, short_run.metadata)
    theta = np.array(
        [np.mean(fine.samples("zeta")), np.mean(fine.samples("mu_k")), np.mean(fine.samples("y0"))]
    )
    sd = {}
    for m in (half_cycles // 4, half_cycles):
        data = pi_data(decay, noise, grid_points=m)
        sd[m] = (_fisher_sd(data, theta), _fisher_sd(data, theta, independent_pi=True))
    for i, name in enumerate(("zeta", "mu_k")):
        observed = np.std(fine.samples(name)) / np.std(coarse.samples(name))
        predicted = sd[half_cycles][0][i] / sd[half_cycles // 4][0][i]
        independent = sd[half_cycles][1][i] / sd[half_cycles // 4][1][i]
        # The Fisher prediction at the posterior mean is 5-10 % above the sampled ratio
        # of μ_k on this run (over seeds), and the ratio carries ±2 % of Monte Carlo.
        assert observed == pytest.approx(predicted, rel=0.12), (name, observed, predicted)
        assert independent < 0.65 * predicted, (name, independent, predicted)


def test_run_without_contact_fits_zeta0_only():
    run = read_run(DATA / "air-r1.csv")
    result = fit(run, seed=2)
    assert "mu_k" not in result.parameter_names and "mu_s" not in result.parameter_names
    sim = run.metadata["simulation"]
    s = result.samples("zeta")
    assert abs(np.mean(s) - sim["zeta"]) < 4.5 * np.std(s)


def test_run_without_load_reports_friction_displacement(short_run):
    meta = {k: v for k, v in short_run.metadata.items() if k not in ("load_N", "mass_kg")}
    run = type(short_run)(short_run.time, short_run.displacement, short_run.velocity, meta)
    result = fit(run, seed=4, grid_points=32)
    assert "mu_k" not in result.parameter_names
    xc = result.samples("friction_displacement")
    true_xc = 0.0294 * 0.31 / (0.035 * (2 * np.pi * 32.6) ** 2)
    assert abs(np.mean(xc) - true_xc) < 4.5 * np.std(xc)
    assert np.all(np.isfinite(result.prior_logpdf("friction_displacement", xc[:10])))


def test_calibration_uncertainty_reaches_mu_k(short_run):
    run = short_run.with_metadata(load_uncertainty_N=0.31 * 0.02)
    result = fit(run, seed=5, grid_points=32)
    mu = result.samples("mu_k")
    # A 2 % load uncertainty dominates the statistical width: sd ≈ 2 % of μ_k.
    assert np.std(mu) / np.mean(mu) == pytest.approx(0.02, rel=0.15)


def test_non_convergence_is_reported_never_hidden(short_run):
    with pytest.warns(ConvergenceWarning, match="did not converge"):
        result = fit(short_run, seed=6, grid_points=32, max_steps=200)
    assert not result.converged
    assert result.diagnostics["reasons"]


def test_bad_model_name():
    with pytest.raises(BayestriboError, match="model: expected one of"):
        fit(DATA / "air-r1.csv", model="quadratic")


# The truth (0.0496) lies within 1 % of the narrowed bound: the bound warning is right.
@pytest.mark.filterwarnings("ignore::bayestribo.errors.PriorBoundWarning")
def test_narrowed_prior_moves_the_start_inside_it():
    run = simulate(
        DissipationLaw(zeta=0.03798, mu_k=0.04962),
        sensor=Sensor(
            displacement_noise_m=4.5e-6, velocity_noise_m_per_s=4.5e-7, sample_rate_Hz=2000.0
        ),
        seed=5,
    )
    from bayestribo.inference import Uniform

    result = fit(run, seed=1, priors={"mu_k": Uniform(0.01, 0.05)})
    mu = result.samples("mu_k")
    assert result.converged and mu.max() <= 0.05


def test_misfit_is_flagged():
    """Damping that grows with amplitude is not the linear law: χ² says so."""
    from bayestribo.errors import MisfitWarning

    run = simulate(
        DissipationLaw(zeta=lambda a: 0.01 + 20.0 * a, mu_k=0.0294),
        sensor=Sensor(
            sample_rate_Hz=2000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=9,
    )
    with pytest.warns(MisfitWarning, match="law='auto'"):
        result = fit(run, seed=2)
    assert result.diagnostics["misfit_p"] < 1e-3
    # the advice works: law="auto" finds a law that holds (ζ growing with amplitude
    # is a drag growing with speed), says nothing is wrong, and converges
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        followed = fit(run, seed=2, law="auto", max_steps=6000)
    assert followed.law_comparison["adequate"], followed.law_comparison
    assert followed.converged
    # and the law it keeps holds along the decay: fitted to each half, it agrees
    halves = followed.law_comparison["halves"]
    assert halves["tested"] and halves["agree"], halves
    assert "the halves agree" in followed.to_text()
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    # and its answer is that law's own fit, whatever the seed: the same frame (from
    # the optimiser's optimum, not the comparison's best draw) and the same posterior
    from bayestribo.model.laws import get_law

    assert not get_law(followed.law).closed_form
    alone = fit(run, seed=5, law=followed.law, max_steps=6000)
    # the comparison takes a law of several terms to its optimum from its nested laws'
    # optima, the law alone from the first guesses: the optima agree to the least
    # squares' tolerance (1e-8), and so the frames found from them
    assert followed.attrs["omega"] == pytest.approx(alone.attrs["omega"], rel=1e-8, abs=0)
    for name in get_law(followed.law).parameter_names:
        a, b = followed.samples(name), alone.samples(name)
        assert abs(a.mean() - b.mean()) < 0.2 * a.std(), name


def test_without_load_no_quantity_is_labelled_as_a_coefficient():
    # Friction as a displacement: the static one is a displacement too, never "mu_s".
    run = simulate(seed=6).with_metadata(length_unit="arbitrary")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, seed=1, max_steps=600)
    names = set(result.summary())
    assert {"friction_displacement", "static_friction_displacement"} <= names
    assert not names & {"mu_k", "mu_s"}
    ratio = result.samples("mu_s_ratio")
    np.testing.assert_allclose(
        result.samples("static_friction_displacement"),
        result.samples("friction_displacement") * ratio,
        rtol=1e-12,
    )


@pytest.mark.filterwarnings("ignore::bayestribo.errors.MisfitWarning")  # a bound that misfits
def test_a_posterior_piled_on_a_prior_bound_is_no_measurement():
    from bayestribo.errors import PriorBoundWarning
    from bayestribo.inference import Uniform

    run = simulate(
        DissipationLaw(zeta=0.0236, mu_k=0.0294),
        sensor=Sensor(
            displacement_noise_m=4.5e-6, velocity_noise_m_per_s=4.5e-7, sample_rate_Hz=2000.0
        ),
        seed=5,
    )
    # μ_k = 0.0294 cannot fit under a bound of 0.02: the posterior piles on it.
    with pytest.warns(PriorBoundWarning, match=r"mu_k piles on the upper bound"):
        result = fit(run, seed=1, priors={"mu_k": Uniform(0.0, 0.02)}, max_steps=3000)
    piled = {b["parameter"]: b for b in result.at_prior_bound}
    assert piled["mu_k"]["bound"] == 0.02
    # μ_s/μ_k may follow μ_k to its bound (a friction held below the decay's stops
    # the motion later, unless it sticks sooner); nothing else does
    assert set(piled) <= {"mu_k", "mu_s_ratio"}
    assert not result.usable
    assert "NOT A MEASUREMENT: mu_k" in result.to_text()
    # The same run under the default priors is a measurement.
    with warnings.catch_warnings():
        warnings.simplefilter("error", PriorBoundWarning)
        assert fit(run, seed=1, max_steps=3000).at_prior_bound == []


def test_result_repr_and_html_show_the_numbers_with_units(bundled):
    _, result = bundled
    text = repr(result)
    assert text.startswith("<FitResult ") and "zeta=0.02" in text and "converged" in text
    html = result._repr_html_()
    zeta = "<td>equivalent viscous damping ratio ζ</td><td>dimensionless</td>"
    assert html.startswith("<table>") and zeta in html
    d_k = "<td>damping of the contact per unit load d_k</td><td>s/m</td>"
    assert d_k in html or "d_k" not in result.summary()
    assert any(line.split()[:2] == ["unit", "mean"] for line in result.to_text().splitlines())


def test_a_frequency_that_changes_with_amplitude_is_reported():
    from test_signal_frequency import _decay

    from bayestribo.errors import FrequencyTrendWarning, LinearSpringWarning, MisfitWarning
    from bayestribo.io.run import Run

    t, x, v = _decay(10_000.0, k3_over_k=667.0)  # a cubic spring: +0.1 % at 2 mm
    rng = np.random.default_rng(5)
    run = Run(
        t,
        x + rng.normal(0.0, 1.5e-6, t.size),
        v + rng.normal(0.0, 1.5e-7, t.size),
        {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31},
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=1, max_steps=3000)
    trend = [w for w in caught if issubclass(w.category, FrequencyTrendWarning)]
    assert trend and "half period changes by +0.0" in str(trend[0].message)
    # the advice (followed in test_inference_restoring_choice.py)
    assert "--restoring auto chooses the force" in str(trend[0].message)
    # on the linear spring a misfit (exit 1 from the command line), and the only one
    assert trend[0].category is LinearSpringWarning
    misfits = [w for w in caught if issubclass(w.category, MisfitWarning)]
    assert [w.category for w in misfits] == [LinearSpringWarning]
    assert result.frequency_trend["z"] > 4
    # The frequency nuisance (half the span of the frequency) widens ζ and μ_k so that
    # their 95 % intervals hold the linear part's values (ζ, μ_k = k x_c / N of the
    # simulation). Without it this run's ζ is 2.15 sd off (outside its 95 % interval).
    sd_eps = result.idata.posterior.attrs["frequency_nuisance_sd"]
    assert 2e-4 < sd_eps < 5e-4
    mu_k = 0.035 * (2 * np.pi * 32.6) ** 2 * 6.2e-6 / 0.31
    for name, truth in (("zeta", 0.0236), ("mu_k", mu_k)):
        lo, hi = result.interval(name, 0.95)
        assert lo < truth < hi, name
    # A linear oscillator: recorded, no warning.
    t, x, v = _decay(10_000.0)
    plain = Run(
        t,
        x + rng.normal(0.0, 1.5e-6, t.size),
        v + rng.normal(0.0, 1.5e-7, t.size),
        {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31},
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        warnings.simplefilter("error", FrequencyTrendWarning)
        assert abs(fit(plain, seed=1, max_steps=3000).frequency_trend["z"]) < 4


def test_the_pointwise_log_likelihood_and_predictive_are_computed_when_read():
    # A fit's summaries use neither the pointwise log-likelihood (PSIS-LOO's input) nor
    # the posterior predictive Π (the fit plot's): each is computed when first read,
    # from the draws and the generator as the fit left them, so the order they are read
    # in does not change them; a result sent to another process (a campaign's workers)
    # carries them as values.
    import pickle

    run = RUNS / "glycerol-N0.31-r1.csv"
    result, again = fit(run, seed=4), fit(run, seed=4)
    draws, other = result._draws, again._draws
    for name in ("log_likelihood", "posterior_predictive"):
        assert callable(draws.__dict__[f"_{name}"]), name  # not computed by the fit
    sent = pickle.loads(pickle.dumps(draws))
    assert all(
        isinstance(sent.__dict__[f"_{n}"], np.ndarray)
        for n in ("log_likelihood", "posterior_predictive")
    )
    values, predictive = draws.log_likelihood, draws.posterior_predictive
    assert draws.__dict__["_log_likelihood"] is values  # computed once
    n_chain, n_draw = draws.posterior["zeta"].shape
    m = json.loads(draws.attrs["diagnostics_json"])["n_increments"]
    assert values.shape == (n_chain, n_draw, m) and np.all(np.isfinite(values))
    assert predictive.shape == (1, 400, m) == (1, 400, draws.observed.size)
    assert np.all(np.isfinite(predictive))
    # read in the other order on a fit of the same seed: the same arrays
    np.testing.assert_array_equal(other.posterior_predictive, predictive)
    np.testing.assert_array_equal(other.log_likelihood, values)
    np.testing.assert_array_equal(sent.log_likelihood, values)
    np.testing.assert_array_equal(sent.posterior_predictive, predictive)
    idata = result.idata
    np.testing.assert_array_equal(idata.log_likelihood["pi"].values, values)
    np.testing.assert_array_equal(idata.posterior_predictive["pi"].values, predictive)


def test_a_fresh_result_makes_its_inference_data_on_first_use():
    # A fit holds numpy arrays (FitDraws) and builds the ArviZ InferenceData only when
    # asked: the summaries are the same before and after, and attributes set before
    # (the command line's run name) are in the InferenceData and its file.
    from bayestribo.inference.assemble import FitDraws

    rng = np.random.default_rng(5)
    draws = FitDraws(
        posterior={
            "zeta": 0.02 + 1e-4 * rng.standard_normal((2, 50)),
            "mu_k": 0.03 + 1e-4 * rng.standard_normal((2, 50)),
        },
        attrs={"run_name": "a", "model": "exact", "seed": 7, "metadata_json": "{}"},
        log_likelihood=rng.standard_normal((2, 50, 6)),
        posterior_predictive=rng.standard_normal((1, 20, 4)),
        observed=rng.standard_normal(4),
        grid=np.linspace(0.0, 3.0, 4),
    )
    result = FitResult(draws=draws)
    before = result.summary(0.9)
    assert result.parameter_names == ["zeta", "mu_k"] and result.seed == 7
    result.attrs["run_name"] = "runs/a.csv"
    idata = result.idata  # built here
    assert result.idata is idata and idata.posterior.attrs["run_name"] == "runs/a.csv"
    assert result.summary(0.9) == before and result.run_name == "runs/a.csv"
    np.testing.assert_array_equal(idata.posterior["zeta"].values, draws.posterior["zeta"])
    np.testing.assert_array_equal(idata.log_likelihood["pi"].values, draws.log_likelihood)
    np.testing.assert_array_equal(idata.observed_data["grid"].values, draws.grid)
    result.attrs["seconds"] = 1.5  # now in the InferenceData itself
    assert idata.posterior.attrs["seconds"] == 1.5 and result.seconds == 1.5
    with pytest.raises(TypeError, match="either idata or draws"):
        FitResult()


def test_the_verdict_refitted_in_its_frame_keeps_every_term_without_contact(bundled_run):
    """law="auto" fits friction laws on a run without contact too (a friction
    displacement): the verdict fitted again in its own frame keeps its friction terms
    rather than dropping them, so that the answer is the law the comparison chose."""
    from bayestribo.inference.comparison import _posterior
    from bayestribo.inference.law_frame import posterior_like
    from bayestribo.inference.pipeline import prepare
    from bayestribo.io.run import Run

    air = Run(
        time=bundled_run.time,
        displacement=bundled_run.displacement,
        velocity=bundled_run.velocity,
        metadata={**bundled_run.metadata, "load_N": 0.0},
    )
    prepared = prepare(air)
    assert not prepared.contact
    compared = _posterior("coulomb+power", prepared.data, "exact", False)
    again = posterior_like(compared, prepared, "exact", False)
    assert again.names == compared.names and "mu_k" in again.names
    assert again.law.name == compared.law.name
