"""A slow rig whose rest after the stop is shorter than the motion's blocks, its
displacement written in fine steps: the stop is found, and the advice the fit then
prints works when followed.

The record (``_slow_rig.py``, ``solve_ivp``) is a 0.3 Hz bob at 20 Hz with 1.5 periods
of rest after its stop, written with five decimals of metres. The levels of those
decimals, dithered by a noise of 20 steps, were taken for a coarse digitiser's: their
toggling in the block that holds the last swing and the short rest marked it as
motion, and the record was said to end while the pin still moves (a misfit that
advised ``--law auto``, which does not answer it). Its μ_s/μ_k is 20, beyond the
default prior's 10: the fit says so and advises the wider prior, which covers the
truth when followed.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import warnings

import pytest
from _slow_rig import F_HZ, MU_K, MU_S, ZETA, write_slow_decay

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.inference.preparation import prepare


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    return write_slow_decay(tmp_path_factory.mktemp("slow"))


def test_the_stop_before_a_rest_shorter_than_a_block_is_found(record) -> None:
    path, stop = record
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(read_run(path))
    assert prepared.data.motion_ended
    # the stop is the last turning point, approached quadratically: its last excursion
    # beyond 5 σ of the rest is a few samples before it (0.25 s here), within a tenth of
    # a period
    assert 0.0 <= stop - prepared.decay.peaks.stop_time <= 0.1 / F_HZ


def _fit(argv: list[str], capsys) -> tuple[int, dict, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(["fit", *argv, "--seed", "1", "--json"])
    return status, json.loads(buf.getvalue()), capsys.readouterr().err


def test_the_prior_bound_advice_covers_the_truth_when_followed(record, capsys) -> None:
    path, _ = record
    status, _, err = _fit([str(path)], capsys)
    assert status == 1
    assert "mu_s_ratio piles on the upper bound of its prior" in err
    advised = re.findall(r"--prior (\S+=\w+\([^()]*\))", err)
    # the misfit names the prior before another law, and so does the bound's warning
    assert len(advised) == 2 and len(set(advised)) == 1
    assert err.index("--prior") < err.index("--law auto")
    status, record_, err = _fit([str(path), "--prior", advised[0]], capsys)
    assert status == 0, err
    p = record_["parameters"]
    for name, truth in (("zeta", ZETA), ("mu_k", MU_K), ("mu_s", MU_S)):
        low, high = p[name]["interval"]
        assert low <= truth <= high, (name, low, high)
    # the stop bounds μ_s/μ_k on both sides: a range measured, not a bound
    assert p["mu_s_ratio"]["kind"] == "posterior"
    assert p["mu_s_ratio"]["interval"][0] <= MU_S / MU_K <= p["mu_s_ratio"]["interval"][1]
