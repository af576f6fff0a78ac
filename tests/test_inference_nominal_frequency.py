"""A record whose clock is off against the nominal natural frequency given with it.

A logger whose clock runs 2.4 % slow writes time stamps 1.024 times the true ones: the
record's frequency reads 2.4 % low, the stiffness k = m(2πf)² that takes it 4.7 % low,
and μ_k with it; the fit answered with exit 0 and an interval of μ_k that missed the
truth (the velocity, from its own sensor, said to read 1.024 × dx/dt and rescaled).
Against the nominal ``natural_frequency_Hz`` of the sidecar the disagreement is now
said (exit 1), with both options; the clock's option, followed, covers the truth.

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

import pytest
from _law_recording import law_recording

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.io.run import Run

ZETA, MU_K, LOAD, MASS, F_HZ = 0.0236, 0.0294, 0.31, 0.035, 32.6
#: The logger's time stamps over the true times.
SLOW = 1.024


def _fit(argv: list[str], capsys) -> tuple[int, dict, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main([*argv, "--json"])
    return status, json.loads(buf.getvalue()), capsys.readouterr().err


def _record(stretch: float) -> Run:
    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * ZETA * omega * v, friction=MU_K * LOAD / MASS, duration_s=1.0, seed=1
    )
    meta = {**run.metadata, "natural_frequency_Hz": F_HZ}
    return Run(run.time * stretch, run.displacement, run.velocity, meta)


def _covered(record: dict, name: str, truth: float) -> bool:
    low, high = record["parameters"][name]["interval"]
    return low <= truth <= high


def test_a_clock_off_against_the_nominal_frequency_is_said_and_its_option_answers(
    tmp_path, capsys
) -> None:
    path = write_run(_record(SLOW), tmp_path / "slow_clock.csv")
    status, record, err = _fit(["fit", str(path)], capsys)
    assert status == 1, err
    assert "from the nominal natural_frequency_Hz = 32.6 Hz" in err, err
    assert not _covered(record, "mu_k", MU_K)  # what exit 0 used to report
    option = re.search(r"--scale t=([0-9.]+)", err)
    assert option is not None and float(option[1]) == pytest.approx(1.0 / SLOW, rel=1e-3)
    status, record, err = _fit(["fit", str(path), "--scale", f"t={option[1]}"], capsys)
    assert status == 0, err
    assert _covered(record, "mu_k", MU_K) and _covered(record, "zeta", ZETA)


def test_a_record_at_its_nominal_frequency_is_not_flagged(tmp_path, capsys) -> None:
    path = write_run(_record(1.0), tmp_path / "on_time.csv")
    status, record, err = _fit(["fit", str(path)], capsys)
    assert status == 0 and "nominal natural_frequency_Hz" not in err, err
    assert _covered(record, "mu_k", MU_K)
