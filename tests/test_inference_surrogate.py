"""The quadratic surrogate of Π for laws without a closed form (inference/surrogate.py):
against the exact integrator, the compiled density against its numpy reference, the
surrogate posterior against the exact one, and a surrogate that is wrong is caught."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo import fit
from bayestribo.inference import pipeline, surrogate
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.start import maximum_a_posteriori
from bayestribo.inference.surrogate import (
    MAX_WEIGHT_CV,
    QuadraticPi,
    SurrogateLikelihood,
    check,
    surrogate_posterior,
)

OMEGA = 2 * math.pi * 32.6
MASS, LOAD = 0.035, 0.31
ELL = LOAD / (MASS * OMEGA**2)
LAW = "viscous+quadratic"


@pytest.fixture(scope="module")
def drag_run():
    """Viscous damping and quadratic drag from an independent solve_ivp simulation."""
    zeta, gamma = 0.01, 0.004
    return law_recording(
        lambda v: 2 * zeta * OMEGA * v + (gamma / ELL) * v * abs(v),
        x0=1.5e-3,
        duration_s=1.5,
        sample_rate_Hz=2000.0,
        seed=4,
    )


@pytest.fixture(scope="module")
def exact_posterior(drag_run):
    prepared = pipeline.prepare(drag_run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law=LAW)
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    return prepared, posterior, theta, cov


def _around(theta, cov, width, n, seed):
    """Rows from the Laplace approximation with its covariance times ``width``²."""
    rng = np.random.default_rng(seed)
    rows = rng.multivariate_normal(theta, width**2 * cov, size=n)
    rows[:, 1] = np.abs(rows[:, 1])  # c2 >= 0
    return rows


def test_the_quadratic_follows_the_integrator_across_the_posterior(exact_posterior):
    _, posterior, theta, cov = exact_posterior
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    assert isinstance(sur.likelihood, SurrogateLikelihood)
    rows = _around(theta, cov, 3.0, 40, seed=0)
    exact = posterior.likelihood.model_pi(posterior.physical(rows)["params"])
    approx = sur.likelihood.model_pi(sur.physical(rows)["params"])
    # Π within 1e-8 of Π(0) at three times the Laplace spread: the integrator's own
    # accuracy against solve_ivp (model/laws/integrator.py), whose step counts change
    # with the parameters
    assert np.max(np.abs(exact - approx)) < 1e-8 * np.max(np.abs(exact))
    # and the log posterior within 1e-3 (a weight 1 ± 1e-3)
    assert np.max(np.abs(posterior(rows) - sur(rows))) < 1e-3


def test_the_compiled_surrogate_density_is_its_numpy_reference(exact_posterior):
    _, posterior, theta, cov = exact_posterior
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    assert sur.uses_compiled and sur.grouped_step is not None
    rows = _around(theta, cov, 10.0, 64, seed=1)
    rows[0, 1] = -1e-3  # outside the prior's support
    compiled, reference = sur(rows), sur.reference(rows)
    assert compiled[0] == reference[0] == -np.inf
    scale = np.maximum(1.0, np.abs(reference[1:]))
    assert np.max(np.abs(compiled[1:] - reference[1:]) / scale) < 1e-10
    residuals = sur.standardized_residuals(rows[1:5])
    expected = sur.likelihood.standardized_residuals(sur.physical(rows[1:5])["params"])
    np.testing.assert_allclose(residuals, expected, rtol=1e-9, atol=1e-9)


def test_the_quadratic_fitted_at_draws_follows_the_integrator_where_they_are(exact_posterior):
    """A surrogate fitted again by least squares at draws (regressed_posterior, after a
    failed check) follows the exact Π over the draws' spread, and its compiled
    density is its numpy reference."""
    _, posterior, theta, cov = exact_posterior
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    draws = _around(theta, cov, 3.0, 400, seed=8)
    again = surrogate.regressed_posterior(posterior, sur, draws, np.random.default_rng(0))
    q = again.likelihood.surrogate
    assert isinstance(q, QuadraticPi) and q.n_pieces == 1
    # centred on the draws picked, not on the failed surrogate's centre
    assert not np.allclose(q.centre, sur.likelihood.surrogate.centre)
    rows = _around(theta, cov, 2.0, 40, seed=9)
    exact = posterior.likelihood.model_pi(posterior.physical(rows)["params"])
    approx = again.likelihood.model_pi(again.physical(rows)["params"])
    assert np.max(np.abs(exact - approx)) < 1e-8 * np.max(np.abs(exact))
    assert np.max(np.abs(posterior(rows) - again(rows))) < 1e-3
    assert again.uses_compiled
    np.testing.assert_allclose(again(rows), again.reference(rows), rtol=1e-10)


def test_draws_without_spread_give_no_refitted_surrogate(exact_posterior):
    _, posterior, theta, cov = exact_posterior
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    draws = _around(theta, cov, 1.0, 200, seed=10)
    draws[:, 0] = theta[0]  # one coordinate the same in every draw
    rng = np.random.default_rng(0)
    assert surrogate.regressed_posterior(posterior, sur, draws, rng) is None


@pytest.mark.validation  # two posteriors sampled to convergence side by side
def test_the_surrogate_posterior_is_the_exact_posterior(exact_posterior):
    prepared, posterior, _, _ = exact_posterior
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000)
    fast = pipeline.sample(posterior, prepared.decay, settings=settings, seed=5)
    slow = pipeline.sample(posterior, prepared.decay, settings=settings, seed=6, surrogate=False)
    assert fast.surrogate is not None and fast.surrogate.passed
    assert fast.surrogate.weight_cv < MAX_WEIGHT_CV
    assert fast.surrogate_posterior is not None and slow.surrogate is None
    assert fast.run.converged and slow.run.converged
    a = fast.run.chains.reshape(-1, fast.run.chains.shape[-1])
    b = slow.run.chains.reshape(-1, slow.run.chains.shape[-1])
    sd = b.std(axis=0)
    # two independent chains of the same posterior: means within Monte Carlo error
    # (ESS >= 1000 each: 0.045 sd apart at one standard error), spreads within 10 %
    assert np.all(np.abs(a.mean(axis=0) - b.mean(axis=0)) < 0.25 * sd)
    assert np.all(np.abs(a.std(axis=0) / sd - 1.0) < 0.1)


@pytest.mark.validation  # the exact posterior sampled after three failed surrogates
def test_a_wrong_surrogate_fails_its_check_and_the_exact_posterior_is_sampled(
    exact_posterior, monkeypatch
):
    prepared, posterior, theta, cov = exact_posterior
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    q = sur.likelihood.surrogate
    table = q.table.copy()
    table[0] += 0.5 * table[1]  # the surrogate posterior one sd off in ζ
    wrong = replace(sur, likelihood=replace(sur.likelihood, surrogate=replace(q, table=table)))
    rows = _around(theta, cov, 1.0, 200, seed=2)
    verdict = check(posterior, wrong, rows, np.random.default_rng(0))
    assert not verdict.passed and verdict.weight_cv > MAX_WEIGHT_CV
    assert check(posterior, sur, rows, np.random.default_rng(0)).passed

    def skewing(real):
        def skewed(*args, **kwargs):
            good = real(*args, **kwargs)
            table = good.table.copy()
            table[0] += 0.5 * table[1]
            return QuadraticPi(good.names, good.centre, good.scale, table)

        return skewed

    # every surrogate wrong: those of the design and those fitted again at the draws
    monkeypatch.setattr(surrogate, "quadratic_pi", skewing(surrogate.quadratic_pi))
    monkeypatch.setattr(surrogate, "regressed_pi", skewing(surrogate.regressed_pi))
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=4_000)
    sampled = pipeline.sample(posterior, prepared.decay, settings=settings, seed=5)
    assert sampled.surrogate is not None and not sampled.surrogate.passed
    assert sampled.surrogate.attempt == surrogate.ATTEMPTS
    assert sampled.surrogate_posterior is None
    # the exact posterior (of the second pass) is sampled, not a surrogate
    assert sampled.draws_posterior is sampled.posterior
    assert type(sampled.posterior.likelihood) is type(posterior.likelihood)


def test_the_fit_records_the_check(drag_run):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(drag_run, seed=2, law=LAW)
    record = result.diagnostics["surrogate"]
    assert record["passed"] and record["weight_cv"] < MAX_WEIGHT_CV
    assert record["draws_checked"] == surrogate.CHECK_DRAWS
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the default law misfits the drag
        default = fit(drag_run, seed=2)
    assert default.diagnostics["surrogate"] is None


def test_the_surrogate_of_a_friction_law_follows_the_stop_of_the_motion(bundled_run):
    """Π depends on μ_s/μ_k only through the turning point where the pin sticks: one
    quadratic per piece, the pieces' edges moving with the turning points."""
    prepared = pipeline.prepare(bundled_run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law="viscous+coulomb+quadratic")
    assert prepared.data.motion_ended
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    q = sur.likelihood.surrogate
    assert q.ratio == "mu_s_ratio" and q.n_pieces >= 2
    i = posterior.names.index("mu_s_ratio")
    rng = np.random.default_rng(3)
    rows = rng.multivariate_normal(theta, cov, size=200)
    rows[:, posterior.names.index("c2")] = np.abs(rows[:, posterior.names.index("c2")])
    rows[:, i] = rng.uniform(1.0, 10.0, size=200)
    exact = posterior.likelihood.model_pi(posterior.physical(rows)["params"])
    approx = sur.likelihood.model_pi(sur.physical(rows)["params"])
    error = np.max(np.abs(exact - approx), axis=1) / np.max(np.abs(exact))
    # every row but those within rounding of a piece's edge
    assert np.mean(error < 1e-8) >= 0.99
    # and the compiled density picks the same pieces as the numpy one
    np.testing.assert_allclose(sur(rows), sur.reference(rows), rtol=1e-10, atol=1e-8)
    # fitted again at draws (after a failed check), piece by piece as from the design
    again = surrogate.regressed_posterior(posterior, sur, rows, np.random.default_rng(4))
    q2 = again.likelihood.surrogate
    assert q2.ratio == "mu_s_ratio" and q2.n_pieces >= 2
    approx = again.likelihood.model_pi(again.physical(rows)["params"])
    error = np.max(np.abs(exact - approx), axis=1) / np.max(np.abs(exact))
    assert np.mean(error < 1e-8) >= 0.99
    np.testing.assert_allclose(again(rows), again.reference(rows), rtol=1e-10, atol=1e-8)


def test_each_piece_of_a_misfitting_friction_law_is_fitted_where_it_exists():
    """Coulomb friction and a power law fitted to drag (3 s, so that the law's motion
    stops inside the record): the edges of the μ_s/μ_k pieces move across the nodes, so
    one piece's motion at one node is the next piece's at another. Fitted per piece on
    the nodes where it exists, the surrogate's log posterior (the second pass's, whose
    tail residuals are many noise sd) follows the exact one within 0.01 over ratios 1
    to 3; with every node of a piece at the centre's ratio it was 0.12, and the
    importance check failed three surrogates in a row."""
    from bayestribo.inference.reweight import reweighted_posterior
    from bayestribo.inference.start import maximum_from

    run = law_recording(
        lambda v: 2 * 0.01 * OMEGA * v + (0.004 / ELL) * v * abs(v),
        x0=1.5e-3,
        duration_s=3.0,
        sample_rate_Hz=2000.0,
        seed=4,
    )
    prepared = pipeline.prepare(run, seed=1)
    first = pipeline.build_posterior(prepared.data, law="coulomb+power")
    theta, _, _ = maximum_a_posteriori(first, prepared.decay)
    posterior = reweighted_posterior(first, prepared.decay, theta)
    theta, cov, _ = maximum_from(posterior, theta, prepared.decay)
    sur = surrogate_posterior(posterior, theta, 2.0 * np.sqrt(np.diag(cov)))
    assert sur.likelihood.surrogate.n_pieces >= 3
    rng = np.random.default_rng(3)
    rows = rng.multivariate_normal(theta, cov, size=200)
    rows[:, posterior.names.index("mu_s_ratio")] = rng.uniform(1.0, 3.0, size=200)
    log_w = posterior(rows) - sur(rows)
    assert np.all(np.isfinite(log_w))
    assert np.std(log_w) < 0.01


def test_the_ratio_scan_of_a_law_without_closed_form_evaluates_once_per_stick(bundled_run):
    """The scan of μ_s/μ_k (start.py) gives the density of every grid point from one
    evaluation per stick, equal to evaluating each."""
    from bayestribo.inference import start

    prepared = pipeline.prepare(bundled_run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law="coulomb+power")
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    rng = np.random.default_rng(5)
    slower = theta.copy()  # less friction: the model moves past the record's end
    slower[posterior.names.index("mu_k")] *= 0.7
    for row in [theta, slower, *rng.multivariate_normal(theta, 4.0 * cov, size=3)]:
        rows, lp, grid = start._scan_ratio(posterior, row)
        np.testing.assert_array_equal(lp, posterior(rows))
        assert np.unique(lp).size < grid.size // 4  # a few sticks, not 81 evaluations


def test_the_interpolated_dissipation_is_the_integrated_one(exact_posterior, monkeypatch):
    """ΔE(A) of a law without a closed form is interpolated over the draws and checked
    against the integrator (inference/dissipation.py)."""
    from bayestribo.inference import dissipation

    _, posterior, theta, cov = exact_posterior
    draws = _around(theta, cov, 1.0, 600, seed=7)
    values = posterior.law_draws(draws)
    law, ref = posterior.law, posterior.likelihood.reference_amplitude
    swings = np.linspace(0.3, 1.0, 12) * ref
    exact = law.swing_dissipation(swings, values, ref)
    fast = dissipation._swing_dissipation(law, swings, values, ref)
    sd = exact.std(axis=0)
    assert np.max(np.abs(fast - exact) / sd) < 1e-2
    # a check that cannot be met integrates every draw
    monkeypatch.setattr(dissipation, "_SWING_TOLERANCE", 0.0)
    calls = []
    real = law.swing_dissipation

    def counted(a, v, r):
        calls.append(np.atleast_1d(next(iter(v.values()))).size)
        return real(a, v, r)

    monkeypatch.setattr(type(law), "swing_dissipation", lambda self, a, v, r: counted(a, v, r))
    again = dissipation._swing_dissipation(law, swings, values, ref)
    np.testing.assert_array_equal(again, exact)
    assert calls[-1] == draws.shape[0]


def test_the_dissipation_is_integrated_only_at_the_swings_the_interpolation_misses(
    exact_posterior, monkeypatch
):
    """A swing where the interpolation misses its check is integrated at every draw;
    the others keep the interpolation (inference/dissipation.py)."""
    from bayestribo.inference import dissipation

    _, posterior, theta, cov = exact_posterior
    draws = _around(theta, cov, 1.0, 600, seed=7)
    values = posterior.law_draws(draws)
    law, ref = posterior.law, posterior.likelihood.reference_amplitude
    swings = np.linspace(0.3, 1.0, 6) * ref
    name = next(n for n in law.parameter_names if n != "mu_s_ratio" and np.std(values[n]) > 0)
    centre, spread = float(np.mean(values[name])), float(np.std(values[name]))
    real = law.swing_dissipation
    calls = []

    def rough(a, v, r):
        # the largest swing made far from quadratic in one parameter over the draws
        a = np.atleast_1d(np.asarray(a, dtype=float))
        x = np.atleast_1d(np.asarray(v[name], dtype=float))
        calls.append((a.size, x.size))
        bump = 0.3 * np.sin(20.0 * (x - centre) / spread)[:, None] * (a == swings[-1])[None, :]
        return real(a, v, r) * (1.0 + bump)

    monkeypatch.setattr(type(law), "swing_dissipation", lambda self, a, v, r: rough(a, v, r))
    out = dissipation._swing_dissipation(law, swings, values, ref)
    calls_made = list(calls)
    want = rough(swings, values, ref)
    # integrated: the half cycle of each swing is solved to 1e-14 of it, each from the
    # swings solved before on its row (model/laws/_core_shared.py swing_guess), so the
    # swing integrated alone and among the others agree to that, not to the bit
    np.testing.assert_allclose(out[:, -1], want[:, -1], rtol=1e-12, atol=0.0)
    sd = want[:, :-1].std(axis=0)
    assert np.max(np.abs(out[:, :-1] - want[:, :-1]) / sd) < 1e-2
    assert not np.array_equal(out[:, :-1], want[:, :-1])  # interpolated there
    n = draws.shape[0]
    assert (1, n) in calls_made and (swings.size, n) not in calls_made


def test_a_swing_the_quadratic_misses_is_fitted_at_draws_not_integrated_at_every_one(
    exact_posterior, monkeypatch
):
    """Where the quadratic through the nodes misses its check (ΔE cubic in a parameter
    over the draws), a cubic fitted by least squares at a few draws takes its place
    when it meets the same check, instead of the integrator at every draw
    (inference/dissipation.py)."""
    from bayestribo.inference import dissipation

    _, posterior, theta, cov = exact_posterior
    draws = _around(theta, cov, 1.0, 600, seed=7)
    values = posterior.law_draws(draws)
    law, ref = posterior.law, posterior.likelihood.reference_amplitude
    swings = np.linspace(0.3, 1.0, 6) * ref
    name = next(n for n in law.parameter_names if n != "mu_s_ratio" and np.std(values[n]) > 0)
    centre, spread = float(np.mean(values[name])), float(np.std(values[name]))
    real = law.swing_dissipation
    level = float(np.mean(real(swings, values, ref)))
    calls = []

    def curved(a, v, r):
        a = np.atleast_1d(np.asarray(a, dtype=float))
        x = np.atleast_1d(np.asarray(v[name], dtype=float))
        calls.append((a.size, x.size))
        return real(a, v, r) + 0.05 * level * ((x - centre) / spread)[:, None] ** 3

    monkeypatch.setattr(type(law), "swing_dissipation", lambda self, a, v, r: curved(a, v, r))
    out = dissipation._swing_dissipation(law, swings, values, ref)
    calls_made = list(calls)
    want = curved(swings, values, ref)
    sd = want.std(axis=0)
    assert np.max(np.abs(out - want) / sd) < 1e-2
    n = draws.shape[0]
    assert all(size < n for _, size in calls_made)  # never every draw
    # the quadratic through the nodes alone misses it: every draw integrated there

    def nothing(law, amplitudes, *rest):
        return np.zeros((n, amplitudes.size)), np.zeros(amplitudes.size, dtype=bool)

    monkeypatch.setattr(dissipation, "_refit_at_draws", nothing)
    calls.clear()
    dissipation._swing_dissipation(law, swings, values, ref)
    assert any(size == n for _, size in calls)


def test_a_motion_no_friction_stops_has_its_stop_ratios_within_the_record(bundled_run):
    """A friction law at μ_k = 0 (a start of the optimiser on its bound) never sticks:
    its stop ratios are all infinite, found over the record's turning points, not over
    the 100,000 half cycles its drag alone takes to bring the motion to rest; with
    friction the motion is still followed past the record to where it sticks."""
    prepared = pipeline.prepare(bundled_run, seed=1)
    data = prepared.data
    assert data.motion_ended
    posterior = pipeline.build_posterior(data, law="viscous+coulomb+quadratic")
    likelihood = posterior.likelihood
    law = likelihood.law
    values = {"zeta": 0.07, "mu_k": 0.0, "mu_s_ratio": 1.0, "c2": 0.0, "y0": float(data.y0)}
    ratios = surrogate.stop_ratios(likelihood, values)
    within, _ = law.turning_points(
        values,
        float(data.y0),
        float(data.yp0),
        tau_max=float(data.tau_end),
        reference=likelihood.reference_amplitude,
    )
    assert ratios.size == within.size
    assert np.all(np.isinf(ratios))
    # the density's scan over μ_s/μ_k there is still the density at every grid point
    from bayestribo.inference import start

    rows, lp, _ = start._scan_ratio(posterior, start._vector(posterior, values))
    assert np.all(np.isfinite(lp))
    np.testing.assert_array_equal(lp, posterior(rows))
    # with friction the motion sticks past the record's end, and is followed there
    sticking = {**values, "zeta": 0.0, "mu_k": 0.002}
    ratios = surrogate.stop_ratios(likelihood, sticking)
    _, to_rest = law.turning_points(
        sticking,
        float(data.y0),
        float(data.yp0),
        reference=likelihood.reference_amplitude,
    )
    assert ratios.size == to_rest.size > within.size
    assert np.all(np.isfinite(ratios))
