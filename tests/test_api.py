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


def test_as_run_is_the_one_conversion(tmp_path):
    run = simulate(seed=3)
    assert as_run(run) is run
    with pytest.raises(BayestriboError, match="run: expected"):
        as_run(3.0)


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
