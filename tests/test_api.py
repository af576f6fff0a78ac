"""The public surface: names that resolve, one run-or-path helper, one summary type,
unknown keywords refused, and the README's Python examples run as written."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from _paths import APPSTAT, REPO

import bayestribo
from bayestribo import ParameterSummary, as_run, simulate
from bayestribo.errors import BayestriboError

ROOT = REPO
EXTERNAL = APPSTAT


@pytest.mark.parametrize("name", bayestribo.__all__)
def test_every_public_name_resolves(name):
    assert getattr(bayestribo, name) is not None


def test_fit_is_the_function_and_takes_a_run_or_a_path(tmp_path):
    run = simulate(seed=3)
    path = bayestribo.write_run(run, tmp_path / "r.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from_run = bayestribo.fit(run, seed=1, max_steps=400)
        from_path = bayestribo.fit(path, seed=1, max_steps=400)
    np.testing.assert_array_equal(from_run.samples("zeta"), from_path.samples("zeta"))
    with pytest.raises(TypeError):
        bayestribo.fit(run, seeed=1)


def test_summaries_share_one_type_and_honour_prob():
    run = simulate(seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bayestribo.fit(run, seed=1, max_steps=400)
    table = bayestribo.estimate_all(run, methods=["energy_ls_exact"])
    for summaries in (result.summary(prob=0.9), table[0].summary(prob=0.9)):
        s = summaries["zeta"]
        assert isinstance(s, ParameterSummary) and s.prob == 0.9
    wide = result.summary(prob=0.99)["zeta"]
    narrow = result.summary(prob=0.9)["zeta"]
    assert wide.low < narrow.low < narrow.high < wide.high
    with pytest.raises(BayestriboError, match="prob"):
        result.summary(prob=95)


def _leaves(summaries):
    """Every ParameterSummary in a (nested) summary dict."""
    for value in summaries.values():
        if isinstance(value, dict):
            yield from _leaves(value)
        else:
            yield value


def _result_types():
    """One instance of every result type that is not a single-run fit (built directly)."""
    from bayestribo.adequacy import AmplitudeTrend, ConstancyTest
    from bayestribo.adequacy.extinction import ExtinctionCheck
    from bayestribo.adequacy.windows import WindowEstimate
    from bayestribo.estimators import Estimate
    from bayestribo.estimators.result import EstimateTable
    from bayestribo.population import GroupPosterior, Population, Trend

    rng = np.random.default_rng(0)

    def draws(loc, scale):
        return rng.normal(loc, scale, 4000)

    estimate = Estimate("energy_ls_exact", zeta=0.01, zeta_se=1e-3, mu_k=0.05, mu_k_se=4e-3)
    group = GroupPosterior(
        "load_N=0.31", 0.31, ("a", "b"), ("zeta",), {"zeta": draws(0.01, 1e-3)},
        {"zeta": np.abs(draws(2e-3, 5e-4))}, {"zeta": "half-normal"},
    )  # fmt: skip
    pooled = GroupPosterior(
        "all", None, ("a", "b"), ("zeta",), {"zeta": draws(0.01, 1e-3)},
        {"zeta": np.abs(draws(2e-3, 5e-4))}, {"zeta": "half-normal"},
    )  # fmt: skip
    trend = Trend(
        "load_N", 0.3, ("a", "b", "c"), ("zeta",), {"zeta": draws(0.01, 1e-3)},
        {"zeta": draws(0.0, 1e-3)}, {"zeta": np.abs(draws(2e-3, 5e-4))},
    )  # fmt: skip
    amplitude = AmplitudeTrend("zeta", 0.01, 1e-3, 2e-4, 1e-3, (6e-4, 1.4e-3), 0.1, 0.8)
    constancy = ConstancyTest(
        True, 0.5, 0.5, 0.5, 0.05, amplitude,
        AmplitudeTrend("mu_k", 0.05, 0.0, 1e-3, 0.0, (-2e-3, 2e-3), 0.0, 0.8),
        1.0, 4.0, 8, (0.2, 1.0), 6, 0, "",
    )  # fmt: skip
    window = WindowEstimate(
        0, 0.0, 1.0, 2.0, 0.5, (0.4, 0.6), (1.0, 2.0), 0.01, 0.05, (0.008, 0.012),
        (0.04, 0.06), np.diag([1e-6, 2.5e-5]), "least_squares",
    )  # fmt: skip
    extinction = ExtinctionCheck(9.5, 12.0, draws(9.0, 0.5), draws(9.4, 0.4), "posterior")
    return {
        "Estimate": estimate,
        "EstimateTable": EstimateTable([estimate]),
        "GroupPosterior": group,
        "Population": Population("load_N", ("zeta",), {0.31: group}, pooled),
        "Trend": trend,
        "AmplitudeTrend": amplitude,
        "ConstancyTest": constancy,
        "WindowEstimate": window,
        "ExtinctionCheck": extinction,
    }


@pytest.mark.parametrize("kind", sorted(_result_types()))
def test_every_result_type_summarises_with_the_asked_probability(kind):
    result = _result_types()[kind]
    narrow, wide = list(_leaves(result.summary(prob=0.9))), list(_leaves(result.summary(0.99)))
    assert narrow and len(narrow) == len(wide)
    for n, w in zip(narrow, wide, strict=True):
        assert isinstance(n, ParameterSummary) and n.prob == 0.9 and w.prob == 0.99
        assert w.low < n.low < n.high < w.high
    with pytest.raises(BayestriboError, match="prob"):
        result.summary(prob=1.5)


def test_as_run_is_the_one_conversion(tmp_path):
    run = simulate(seed=3)
    assert as_run(run) is run
    path = bayestribo.write_run(run, tmp_path / "r.csv")
    assert as_run(path) == run and as_run(str(path)) == run
    with pytest.raises(BayestriboError, match="run is already a Run"):
        as_run(run, skip_rows=1)
    with pytest.raises(BayestriboError, match="run: expected"):
        as_run(3.0)
    with pytest.raises(BayestriboError, match=r"'delimeter' \(did you mean 'delimiter'\?\)"):
        bayestribo.read_run(path, delimeter=",")


def _readme_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_readme_has_python_examples():
    assert len(_readme_blocks()) >= 2


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(_readme_blocks())))
def test_readme_python_examples_run_as_written(index, monkeypatch, tmp_path):
    block = _readme_blocks()[index]
    for name in re.findall(r"HarmOsc\d\.txt", block):
        if not (EXTERNAL / name).is_file():
            pytest.skip(f"the example reads {name} from {EXTERNAL}, which is not here")
    # The examples name files as a user in the repository (data/...) or beside the
    # AppStat2020 recordings would: run them from a folder holding both.
    for name in re.findall(r"HarmOsc\d\.txt", block):
        (tmp_path / name).symlink_to(EXTERNAL / name)
    (tmp_path / "data").symlink_to(ROOT / "data")
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, f"README.md python block {index}", "exec"), {})
