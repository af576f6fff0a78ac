"""PSIS-LOO of one sampled law (inference/loo.py): the surrogate's pointwise
log-likelihood where it agrees with the exact one, the exact one otherwise, and each
law's PSIS-LOO computed once for the comparison."""

from __future__ import annotations

import dataclasses
import math
import warnings
from types import SimpleNamespace

import arviz as az
import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo.inference import loo, pipeline
from bayestribo.inference.assemble import pointwise_log_likelihood
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.surrogate import SurrogateLikelihood

OMEGA = 2 * math.pi * 32.6
ELL = 0.31 / (0.035 * OMEGA**2)


@pytest.fixture(scope="module")
def drag_fit():
    """``viscous+quadratic`` (no closed form: sampled on its surrogate) fitted to an
    independent solve_ivp simulation of that law."""
    run = law_recording(
        lambda v: 2 * 0.01 * OMEGA * v + (0.004 / ELL) * v * abs(v),
        x0=1.5e-3,
        duration_s=1.5,
        sample_rate_Hz=2000.0,
        seed=4,
    )
    prepared = pipeline.prepare(run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law="viscous+quadratic")
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=4_000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pipeline.sample(posterior, prepared.decay, settings=settings, seed=3)


def test_the_surrogate_pointwise_stands_for_the_exact_at_every_draw(drag_fit, monkeypatch):
    assert drag_fit.surrogate_posterior is not None  # the chains are the surrogate's
    # every eighth draw of each chain (the exact Π of each costs the integrator)
    drag_fit = dataclasses.replace(
        drag_fit, run=dataclasses.replace(drag_fit.run, chains=drag_fit.run.chains[:, ::8])
    )
    exact = pointwise_log_likelihood(drag_fit.posterior, drag_fit.run.chains)
    evaluated: list[int] = []
    real = PiLikelihood.pointwise

    def counted(self, *args, **kwargs):
        out = real(self, *args, **kwargs)
        if not isinstance(self, SurrogateLikelihood):
            evaluated.append(out.shape[0])
        return out

    monkeypatch.setattr(PiLikelihood, "pointwise", counted)
    got = loo.sampled_pointwise(drag_fit)
    monkeypatch.undo()
    # the exact Π only at the draws compared
    assert sum(evaluated) == loo.CHECK_DRAWS
    assert got.shape == exact.shape
    # at every draw, not only those compared, within the tolerance the check applies
    assert np.max(np.sum(np.abs(got - exact), axis=-1)) <= loo.TOLERANCE
    with_exact = loo.law_loo(drag_fit, exact)
    with_surrogate = loo.law_loo(drag_fit)
    assert abs(float(with_surrogate["elpd_loo"]) - float(with_exact["elpd_loo"])) <= loo.TOLERANCE


def _stub(names, exact_shift: float, surrogate: bool):
    """A sampled law of two chains of 30 draws whose pointwise log-likelihood is a
    function of the draw; the surrogate's is the exact one plus ``exact_shift`` at
    every increment."""
    rng = np.random.default_rng(0)
    chains = rng.normal(size=(2, 30, len(names)))
    m = 12

    def pointwise_of(shift):
        return lambda theta: -0.5 * (theta[:, :1] - np.linspace(-1, 1, m)) ** 2 + shift

    exact = SimpleNamespace(names=names, pointwise=pointwise_of(0.0))
    approx = SimpleNamespace(names=names, pointwise=pointwise_of(exact_shift))
    run = SimpleNamespace(chains=chains)
    return SimpleNamespace(
        posterior=exact, surrogate_posterior=approx if surrogate else None, run=run
    )


def test_a_surrogate_that_disagrees_gives_way_to_the_exact_pointwise():
    names = ["zeta", "y0"]
    # a shift of the tolerance spread over the 12 increments, and a little more
    close = _stub(names, 0.9 * loo.TOLERANCE / 12, surrogate=True)
    far = _stub(names, 1.1 * loo.TOLERANCE / 12, surrogate=True)
    none = _stub(names, 1.0, surrogate=False)
    exact = pointwise_log_likelihood(close.posterior, close.run.chains)
    assert np.allclose(loo.sampled_pointwise(close), exact + 0.9 * loo.TOLERANCE / 12)
    assert np.array_equal(loo.sampled_pointwise(far), exact)
    assert np.array_equal(loo.sampled_pointwise(none), exact)
    # a surrogate whose value is not finite where the exact one is gives way too
    broken = _stub(names, math.nan, surrogate=True)
    assert np.array_equal(loo.sampled_pointwise(broken), exact)


def test_the_frame_of_precomputed_loos_is_arvizs_comparison():
    laws = {"a": _stub(["zeta", "y0"], 0.0, False), "b": _stub(["mu_k", "y0"], 0.0, False)}
    laws["b"].posterior.pointwise = lambda theta: (
        -0.5 * (theta[:, :1] - 0.3 * np.linspace(-1, 1, 12)) ** 2 - 0.2
    )
    loos = {law: loo.law_loo(s) for law, s in laws.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idatas = {
            law: az.from_dict(
                posterior={n: s.run.chains[..., i] for i, n in enumerate(s.posterior.names)},
                log_likelihood={"pi": pointwise_log_likelihood(s.posterior, s.run.chains)},
            )
            for law, s in laws.items()
        }
        expected = az.compare(idatas, ic="loo")
    frame = loo.loo_frame(loos)
    assert list(frame) == list(expected.index)
    for key in ("rank", "elpd_loo", "p_loo", "elpd_diff", "weight", "se", "dse", "warning"):
        np.testing.assert_allclose(
            [frame[law][key] for law in frame], expected[key].astype(float), rtol=1e-10
        )
    assert loo.pareto_k_max(loos["a"]) == float(np.max(loos["a"].pareto_k))
    alone = loo.loo_frame({"a": loos["a"]})
    assert list(alone) == ["a"] and alone["a"]["elpd_diff"] == 0.0
    assert alone["a"]["elpd_loo"] == float(loos["a"]["elpd_loo"]) and alone["a"]["weight"] == 1


@pytest.mark.parametrize("seed", range(6))
def test_the_comparison_of_several_laws_is_arvizs(seed):
    # three to five laws whose pointwise densities differ by draws of several sizes:
    # the ranks, differences and their errors, and the stacking weights (a constrained
    # optimisation) as arviz.compare gives them
    rng = np.random.default_rng(seed)
    m = int(rng.integers(5, 200))
    laws = [f"law{i}" for i in range(int(rng.integers(3, 6)))]
    loos = {}
    for i, law in enumerate(laws):
        ll = -0.5 * (rng.normal(size=(2, 300, m)) * (1.0 + 0.3 * i)) ** 2 - 0.1 * i
        chains = 0.1 * rng.normal(size=(2, 300, 2)).cumsum(axis=1)
        loos[law] = (ll, chains)
    ours = {law: loo.psis_loo(ll, loo.relative_efficiency(c)) for law, (ll, c) in loos.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ArviZ's own use of pandas
        expected = az.compare({law: _arviz_loo(ll, c) for law, (ll, c) in loos.items()}, ic="loo")
    frame = loo.loo_frame(ours)
    assert list(frame) == list(expected.index)
    for key in ("rank", "elpd_loo", "p_loo", "elpd_diff", "se", "dse"):
        np.testing.assert_allclose(
            [frame[law][key] for law in frame],
            expected[key].astype(float),
            rtol=1e-9,
            atol=1e-9,
            err_msg=key,
        )
    # The stacking weights are SLSQP's optimum to its tolerance (ftol 1e-6 on the log
    # score): weights pressed against a bound (~1e-9) differ between two machines'
    # last bits of loo_i, so they are compared as optima: as good a log score as
    # arviz's, and the same weights to the optimiser's tolerance.
    ours_w = np.array([frame[law]["weight"] for law in frame])
    theirs_w = expected["weight"].astype(float).to_numpy()
    assert np.all(ours_w >= 0.0) and abs(ours_w.sum() - 1.0) < 1e-9
    dens = np.exp(np.column_stack([np.ravel(ours[law]["loo_i"]) for law in frame]))
    score = lambda w: float(np.sum(np.log(dens @ w)))  # noqa: E731
    assert score(ours_w) >= score(theirs_w) - 1e-6
    np.testing.assert_allclose(ours_w, theirs_w, rtol=0, atol=1e-6, err_msg="weight")


@pytest.mark.parametrize("case", ["autocorrelated", "white", "constant", "short", "with a NaN"])
def test_the_effective_sample_size_of_the_mean_is_arvizs(case):
    from bayestribo.inference.loo_compare import ess_mean

    rng = np.random.default_rng(7)
    draws = {
        "autocorrelated": 0.1 * rng.normal(size=(4, 501)).cumsum(axis=1),
        "white": rng.normal(size=(2, 800)),
        "constant": np.full((2, 50), 3.0),
        "short": rng.normal(size=(2, 3)),
        "with a NaN": np.where(np.arange(100) == 7, np.nan, rng.normal(size=(2, 100))),
    }[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        expected = float(az.ess(draws, method="mean"))
    got = ess_mean(draws)
    if np.isnan(expected):
        assert np.isnan(got)
    else:
        assert got == pytest.approx(expected, rel=1e-12)


def _arviz_loo(ll, chains):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idata = az.from_dict(
            posterior={f"p{i}": chains[..., i] for i in range(chains.shape[-1])},
            log_likelihood={"pi": ll},
        )
        return az.loo(idata, pointwise=True)


@pytest.mark.parametrize(
    "case", ["normal", "heavy tails", "tied draws", "misfit and constant rows", "few draws"]
)
def test_psis_loo_is_arvizs_loo(case):
    rng = np.random.default_rng(len(case))
    n_draws, m = (40, 12) if case == "few draws" else (300, 25)
    # autocorrelated chains: a relative efficiency well below 1
    chains = 0.1 * rng.normal(size=(2, n_draws, 3)).cumsum(axis=1)
    if case == "normal":
        ll = -0.5 * rng.normal(size=(2, n_draws, m)) ** 2
    else:
        ll = -0.5 * (3.0 * rng.standard_t(3, size=(2, n_draws, m))) ** 2
    if case == "tied draws":
        ll[:, 100:130, :] = ll[:, 100:101, :]  # a walker stuck: ties in every tail
    if case == "misfit and constant rows":
        ll[0, :, 3] = -1e5
        ll[:, :, 7] = 0.0
    expected = _arviz_loo(ll, chains)
    got = loo.psis_loo(ll, loo.relative_efficiency(chains))
    for key in ("elpd_loo", "se", "p_loo", "good_k"):
        assert float(got[key]) == pytest.approx(float(expected[key]), rel=1e-10, abs=1e-10)
    for key in ("n_samples", "n_data_points", "warning", "scale"):
        assert got[key] == expected[key]
    np.testing.assert_allclose(got["loo_i"], expected["loo_i"].values, rtol=1e-10)
    np.testing.assert_allclose(got["pareto_k"], expected["pareto_k"].values, rtol=1e-10)
    assert loo.relative_efficiency(chains[:1]) == 1.0


def test_psis_does_not_import_arviz():
    """Rows are smoothed without ArviZ, which takes seconds to import (a fit's
    importance correction smooths one row of a surrogate's draws): regular rows, rows
    with ties at the cut (a walker that stayed put repeats its weight: on a seismometer
    record a correction's first such row cost 1.3 s of import) and rows whose tail is
    too short; the smoothing against ArviZ's own is
    :func:`test_psis_loo_is_arvizs_loo`'s and
    :func:`test_a_row_with_ties_at_its_cut_is_smoothed_as_arviz_smooths_it`'s."""
    code = (
        "import numpy as np\n"
        "from bayestribo.inference.loo import psis\n"
        "rows = np.random.default_rng(0).normal(size=(3, 2000))\n"
        "rows[1, 1000:1600] = rows[1, 1000]  # ties at the cut\n"
        "x, k = psis(rows, 1.0)\n"
        "assert np.all(np.isfinite(x)) and np.all(np.isfinite(k))\n"
        "x, k = psis(rows[:, :12], 1.0)  # a tail of 3\n"
        "assert np.all(np.isfinite(x)) and np.all(np.isinf(k))\n"
    )
    assert _heavy_modules_after(code) == []


@pytest.mark.parametrize("seed", range(40))
def test_a_row_with_ties_at_its_cut_is_smoothed_as_arviz_smooths_it(seed):
    from arviz.stats.stats import _psislw

    rng = np.random.default_rng(seed)
    n = int(rng.integers(20, 3000))
    row = rng.standard_t(3, size=n) * rng.uniform(0.1, 5.0)
    for _ in range(int(rng.integers(1, 6))):  # walkers that stayed put
        a = int(rng.integers(0, n))
        row[a : a + int(rng.integers(1, 40))] = row[a]
    if seed % 10 == 0:
        row[:] = row[0]
    cutoff_ind = -int(np.ceil(min(n / 5.0, 3 * (n / rng.uniform(0.2, 1.0)) ** 0.5))) - 1
    cutoffmin = np.log(np.finfo(float).tiny)
    expected, k_expected = _psislw(row.copy(), cutoff_ind, cutoffmin, True)
    got, k = loo._psis_row(row.copy(), cutoff_ind, cutoffmin)
    assert k == pytest.approx(k_expected, rel=1e-12) or (np.isinf(k) and np.isinf(k_expected))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_the_laws_comparison_imports_neither_arviz_nor_pandas():
    """``law="auto"``'s PSIS-LOO, the draws' relative efficiency and the comparison
    (:mod:`bayestribo.inference.loo_compare`) are computed without ArviZ, xarray or
    pandas, which took 2.3 s of a command-line ``--law auto``'s 6.8 s to import; the
    values against ArviZ's are the tests above."""
    code = (
        "import numpy as np\n"
        "import bayestribo.inference.auto, bayestribo.inference.comparison\n"
        "from bayestribo.inference import loo\n"
        "rng = np.random.default_rng(0)\n"
        "chains = 0.1 * rng.normal(size=(2, 300, 3)).cumsum(axis=1)\n"
        "loos = {law: loo.psis_loo(-0.5 * rng.normal(size=(2, 300, 20)) ** 2 - i,\n"
        "                          loo.relative_efficiency(chains))\n"
        "        for i, law in enumerate(['a', 'b', 'c'])}\n"
        "frame = loo.loo_frame(loos)\n"
        "assert list(frame) == ['a', 'b', 'c'], frame\n"
    )
    assert _heavy_modules_after(code) == []


def _heavy_modules_after(code: str) -> list[str]:
    """ArviZ, xarray and pandas, those a fresh interpreter has imported after ``code``
    ran (its assertions hold: the child exits 0)."""
    import subprocess
    import sys

    code += "import sys\nprint(','.join(m for m in HEAVY if m in sys.modules))\n"
    code = "HEAVY = ('arviz', 'xarray', 'pandas')\n" + code
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return [m for m in out.stdout.strip().split(",") if m]


def _scattered(scale: float):
    """A stub whose surrogate errs by ``scale`` times the draw's centred second
    coordinate at every increment: of either sign from draw to draw, the sum over the
    increments at a draw beyond the tolerance, its shift of ``elpd_loo`` small."""
    fit = _stub(["zeta", "y0"], 0.0, surrogate=True)
    centre = float(np.mean(fit.run.chains[..., 1]))
    exact = fit.posterior.pointwise
    fit.surrogate_posterior = SimpleNamespace(
        names=fit.posterior.names,
        pointwise=lambda theta: exact(theta) + scale * (theta[:, 1:2] - centre),
    )
    return fit


def test_a_surrogate_whose_errors_cancel_stands_where_its_shift_of_elpd_is_small():
    fit = _scattered(0.0025)
    chains = fit.run.chains
    flat = chains.reshape(-1, chains.shape[-1])
    approx = pointwise_log_likelihood(fit.surrogate_posterior, chains)
    exact = pointwise_log_likelihood(fit.posterior, chains)
    # the check at CHECK_DRAWS draws fails: its sum over the increments at some draw
    # is beyond the tolerance
    assert np.max(np.sum(np.abs(approx - exact), axis=-1)) > loo.TOLERANCE
    reff = loo.relative_efficiency(chains)
    shift, se, second = loo.surrogate_shift(
        approx.reshape(flat.shape[0], -1), flat, fit.posterior.pointwise, reff
    )
    true = float(loo.psis_loo(approx, reff)["elpd_loo"] - loo.psis_loo(exact, reff)["elpd_loo"])
    assert abs(true) < loo.TOLERANCE / 2
    assert abs(shift - true) <= 3.0 * se + second
    assert np.array_equal(loo.sampled_pointwise(fit), approx)
    # ten times the error: its shift is no longer within the tolerance
    big = _scattered(0.025)
    assert np.array_equal(loo.sampled_pointwise(big), exact)


def test_a_surrogate_shift_with_an_exact_value_outside_the_support_is_infinite():
    fit = _stub(["zeta", "y0"], 0.0, surrogate=True)
    flat = fit.run.chains.reshape(-1, 2)
    approx = fit.surrogate_posterior.pointwise(flat)

    def outside(theta):
        out = fit.posterior.pointwise(theta)
        out[0] = -np.inf
        return out

    assert loo.surrogate_shift(approx, flat, outside, 1.0) == (np.inf, np.inf, np.inf)


def _loo_of(pointwise):
    from bayestribo.inference.loo_compare import LooResult

    loo_i = np.asarray(pointwise, dtype=float)
    return LooResult(
        elpd_loo=float(loo_i.sum()),
        se=float(np.sqrt(loo_i.size * np.var(loo_i))),
        p_loo=1.0,
        n_samples=1000,
        n_data_points=loo_i.size,
        warning=False,
        loo_i=loo_i,
        pareto_k=np.zeros(loo_i.size),
        scale="log",
        good_k=0.7,
    )


def test_stacking_weights_of_laws_that_all_misfit_by_far():
    """Every law misfits a record by thousands of log units an increment (a seismometer
    whose period changes with its swing): exp(loo_i) underflows to 0 for all of them,
    where the stacking took log 0 and 0/0 (numpy's RuntimeWarnings, a NaN gradient).
    The weights do not depend on adding a constant to each increment's row, so they are
    those of the same rows raised into exp's range."""
    import warnings

    from bayestribo.inference.loo_compare import compare

    rng = np.random.default_rng(5)
    base = rng.normal(0.0, 1.0, (45, 3)) + np.array([0.0, -0.3, -1.0])
    offset = -5000.0 - 100.0 * rng.random(45)[:, None]
    far = {f"law{j}": _loo_of(base[:, j] + offset[:, 0]) for j in range(3)}
    near = {f"law{j}": _loo_of(base[:, j]) for j in range(3)}
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        got = compare(far)
    want = compare(near)
    weights = np.array([got[f"law{j}"]["weight"] for j in range(3)])
    assert np.all(np.isfinite(weights)) and weights.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(weights, [want[f"law{j}"]["weight"] for j in range(3)], atol=1e-6)
