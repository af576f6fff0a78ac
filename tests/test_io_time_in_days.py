"""A time column in days (a spreadsheet's date-and-time serial), in hours or minutes.

Excel and LibreOffice keep a date and time as a count of days: a record exported with
its time stamps so reads 45678.500002 for 0.2 ms after noon. Read as seconds, the
channels disagree by 86 400 and the motion is a 2.8 MHz oscillation; the refusal said
"give each column its unit", which, followed with ``--columns t x v``, read the same
way. It now names the unit and the scale (``--scale t=86400``), and where the record
does not tell hours from days, the rig's frequency as what decides. The record is an
independent simulation (``_law_recording.py``).
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

ZETA, MU_K = 0.0236, 0.0294


def _file(folder, velocity: bool) -> str:
    omega = 2.0 * math.pi * 32.6
    run = law_recording(
        lambda v: 2.0 * ZETA * omega * v, friction=MU_K * 0.31 / 0.035, duration_s=1.0
    )
    days = 45678.5 + run.time / 86400.0
    columns = [days, run.displacement] + ([run.velocity] if velocity else [])
    path = folder / ("days.csv" if velocity else "days_x.csv")
    header = "Time,displacement_m" + (",velocity_m_per_s" if velocity else "")
    np.savetxt(
        path, np.column_stack(columns), delimiter=",", header=header, comments="", fmt="%.12f"
    )
    path.with_suffix(".json").write_text(json.dumps({"load_N": 0.31, "mass_kg": 0.035}))
    return str(path)


def _run(argv, capsys) -> tuple[int, str, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(argv)
    return status, buf.getvalue(), capsys.readouterr().err


def test_days_are_named_and_the_scale_reads_them(tmp_path, capsys) -> None:
    path = _file(tmp_path, velocity=True)
    status, _, err = _run(["fit", path, "--columns", "t", "x", "v"], capsys)
    assert status == 2 and "time in days" in err, err
    scale = re.search(r"--scale (t=86400)\b", err)
    assert scale is not None, err
    status, out, err = _run(
        ["fit", path, "--columns", "t", "x", "v", "--scale", scale[1], "--json"], capsys
    )
    assert status == 0, err
    record = json.loads(out)
    for name, truth in (("zeta", ZETA), ("mu_k", MU_K)):
        low, high = record["parameters"][name]["interval"]
        assert low <= truth <= high, (name, low, high)


def test_hours_or_days_the_frequency_decides(tmp_path, capsys) -> None:
    path = _file(tmp_path, velocity=False)
    status, _, err = _run(["fit", path, "--columns", "t", "x"], capsys)
    assert status == 2 and "time in hours" in err and "time in days" in err, err
    assert "natural_frequency_Hz (--frequency), which decides the time's unit" in err
    status, _, err = _run(["fit", path, "--columns", "t", "x", "--frequency", "32.6"], capsys)
    assert status == 2 and "not time in hours" in err and "--scale t=86400" in err, err
