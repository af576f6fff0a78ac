"""A record whose stop needs a μ_s/μ_k beyond the prior: the cause said, the advice works.

On the paper's rig with μ_s/μ_k = 30 (the pin sticks at a turning point 30 friction
displacements from the centre) the default prior's bound 10 lets no draw stop where
the record does: the fit misfits, and its posterior of μ_s/μ_k presses on the bound
without piling on it, so the advice was ``--law auto``, whose comparison misfits too
and ends with the law-free answer. Now the misfit names the stop and the ratio it
needs, and advises the prior that holds it; followed, the default law holds and its
intervals cover the truth.

The record is an independent simulation (``_law_recording.py``: ``solve_ivp`` half
cycle by half cycle with the stick rule), written as a file and fitted through the
command line as a user would.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re

import numpy as np
from _law_recording import law_recording

from bayestribo.cli import main
from bayestribo.inference.priors import Uniform
from bayestribo.inference.stop_prior import StopBeyondPrior
from bayestribo.io import write_run

ZETA, MU_K, RATIO, LOAD, MASS, F_HZ = 0.0236, 0.0294, 30.0, 0.31, 0.035, 32.6
ADVICE = re.compile(r"--law \w+|--restoring \w+|--prior \S+?=\w+\([^()]*\)")


def _fit(argv: list[str], capsys) -> tuple[int, dict, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main([*argv, "--json"])
    return status, json.loads(buf.getvalue()), capsys.readouterr().err


def test_a_stop_beyond_the_prior_is_named_and_its_advice_answers(tmp_path, capsys) -> None:
    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * ZETA * omega * v,
        friction=MU_K * LOAD / MASS,
        static_ratio=RATIO,
        duration_s=1.5,
        seed=2,
    )
    path = write_run(run, tmp_path / "hard_stick.csv")
    status, _, err = _fit(["fit", str(path)], capsys)
    assert status == 1 and "misfits" in err
    assert "its stop needs μ_s/μ_k >=" in err, err
    advice = ADVICE.search(err)
    assert advice is not None and advice[0].startswith("--prior mu_s_ratio=Uniform(1,"), err
    high = float(advice[0].rsplit(",", 1)[1].rstrip(")"))
    assert high > RATIO  # the advised prior holds the truth
    followed = advice[0].split(" ", 1)
    status, record, err = _fit(["fit", str(path), *followed], capsys)
    assert status == 0, err
    for name, truth in (("zeta", ZETA), ("mu_k", MU_K), ("mu_s_ratio", RATIO)):
        low, upper = record["parameters"][name]["interval"]
        assert low <= truth <= upper, (name, truth, low, upper)


def test_the_needed_ratio_is_said_with_the_bound() -> None:
    stop = StopBeyondPrior(28.7, 10.0, "mu_s_ratio=Uniform(1,44)")
    text = stop.describe()
    assert "28.7" in text and "upper bound 10" in text


def test_a_widened_prior_holds_the_needed_ratio_with_room() -> None:
    from bayestribo.inference.priors import widened_prior

    for needed in (11.0, 26.0, 27.0, 31.2, 95.0, 1234.0):
        option = widened_prior("mu_s_ratio", Uniform(1.0, 10.0), needed=needed)
        high = float(option.rsplit(",", 1)[1].rstrip(")"))
        assert high >= max(40.0, 1.5 * needed) and high <= max(40.0, 1.5 * needed) * 1.1
    assert np.isclose(
        float(widened_prior("mu_s_ratio", Uniform(1.0, 10.0)).rsplit(",", 1)[1][:-1]), 40.0
    )
