"""Every reading option on the command line, the same for each command that reads a
run, and errors that give the fix as an option."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bayestribo.cli import main
from bayestribo.synthetic import simulate

F_HZ = 32.6


@pytest.fixture(scope="module")
def run():
    return simulate(seed=4)


def _decay(argv: list[str], capsys) -> dict:
    assert main(["decay", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _write(path: Path, header: str, rows: list[str], preamble: tuple[str, ...] = ()) -> Path:
    path.write_text("\n".join([*preamble, header, *rows]) + "\n", encoding="utf-8")
    return path


def test_units_in_column_names_are_converted(tmp_path, run, capsys):
    rows = [
        f"{1e3 * t:.12g},{1e6 * x:.12g}" for t, x in zip(run.time, run.displacement, strict=True)
    ]
    path = _write(tmp_path / "ms_um.csv", "time_ms,displacement_um", rows)
    reference = _write(
        tmp_path / "s_m.csv",
        "time_s,displacement_m",
        [f"{t:.12g},{x:.12g}" for t, x in zip(run.time, run.displacement, strict=True)],
    )
    options = ["--length-unit", "arbitrary"]
    got = _decay([str(path), *options], capsys)
    want = _decay([str(reference), *options], capsys)
    # read in s and m: the measured frequency is the rig's, not 1000 times lower
    assert got["natural_frequency_Hz"] == pytest.approx(F_HZ, rel=1e-3)
    assert got["natural_frequency_Hz"] == pytest.approx(want["natural_frequency_Hz"], rel=1e-9)
    assert got["equilibrium"] == pytest.approx(want["equilibrium"], rel=1e-9, abs=1e-15)


def test_a_european_export_with_a_preamble_reads_with_options(tmp_path, run, capsys):
    def european(v: float) -> str:
        return f"{v:.9e}".replace(".", ",")

    rows = [
        f"{european(t)};{european(1e3 * x)}"
        for t, x in zip(run.time, run.displacement, strict=True)
    ]
    preamble = ("Model;Scope 1000", "Sample Interval;1,0e-04")
    path = _write(tmp_path / "eu.csv", "t;x", rows, preamble)
    got = _decay(
        [
            str(path),
            *("--skip-rows", "2", "--delimiter", ";", "--decimal", ","),
            *("--columns", "t", "x", "--scale", "x=1e-3", "--length-unit", "arbitrary"),
        ],
        capsys,
    )
    assert got["natural_frequency_Hz"] == pytest.approx(F_HZ, rel=1e-3)


def test_reading_errors_give_the_fix_as_options(tmp_path, run, capsys):
    rows = [f"{t:.12g},{x:.12g}" for t, x in zip(run.time, run.displacement, strict=True)]
    path = _write(tmp_path / "odd.csv", "Model,Amplitude", rows)
    assert main(["decay", str(path)]) == 2
    err = capsys.readouterr().err
    assert "--columns" in err and "columns=[" not in err and "\n" not in err.strip()
    no_header = _write(tmp_path / "bare.csv", rows[0], rows[1:])
    assert main(["estimate", str(no_header)]) == 2
    err = capsys.readouterr().err
    # the advice names units, and how to say that the length unit is not known
    assert "--columns time_s displacement_mm" in err and "--length-unit arbitrary" in err
    assert main(["decay", str(path), "--scale", "x:1e-3"]) == 2
    assert "--scale: expected NAME=FACTOR" in capsys.readouterr().err


@pytest.mark.parametrize(
    "command", ["fit", "estimate", "decay", "check", "report", "inspect", "campaign"]
)
def test_every_reading_command_has_the_same_reading_options(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = capsys.readouterr().out
    for option in ("--columns", "--skip-rows", "--delimiter", "--decimal", "--scale", "--format"):
        assert option in text, (command, option)


def test_a_tab_separated_file_without_header_is_described_as_such(tmp_path, run, capsys):
    rows = [f"{t:.6f}\t{x:.9g}" for t, x in zip(run.time, run.displacement, strict=True)]
    path = _write(tmp_path / "bare.txt", rows[0], rows[1:])
    assert main(["inspect", str(path), "--columns", "t", "x"]) == 0
    out = capsys.readouterr().out
    assert "without a header row" in out and "file columns" not in out


def test_a_header_without_units_is_answered_with_the_columns_that_read_it(tmp_path, run, capsys):
    rows = [
        f"{t:.12g};{x:.12g};{v:.12g};0"
        for t, x, v in zip(run.time, run.displacement, run.velocity, strict=True)
    ]
    path = _write(tmp_path / "sensor.csv", "time;position;velocity;acceleration", rows)
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert "has no unit" in err and "--columns t x v - if the file is in s, m and m/s" in err
    # the advice, followed, reads the run in the units it names
    assert main(["inspect", str(path), "--columns", "t", "x", "v", "-"]) == 0
    assert "time_s, displacement_m, velocity_m_per_s (SI)" in capsys.readouterr().out


def test_an_angle_without_a_unit_is_advised_in_radians_and_in_degrees(tmp_path, capsys):
    # an encoder's log "Time,Angle" in degrees: the advice named angle_rad alone, which
    # read the degrees as radians
    import numpy as np

    from bayestribo.cli import main

    t = np.arange(0.0, 20.0, 0.02)
    angle = 68.0 * np.exp(-0.02 * t) * np.cos(2 * np.pi * 0.72 * t)
    path = tmp_path / "encoder.csv"
    np.savetxt(path, np.column_stack([t, angle]), delimiter=",", header="Time,Angle", comments="")
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert "--columns t angle_rad if the file is in s and radians" in err
    assert "--columns t angle_deg if in degrees" in err


def test_decay_takes_the_named_restoring_forces_potential(tmp_path, capsys):
    # `decay --restoring pendulum` printed E(τ) on the linear spring, y²/2, as without it
    import json

    import numpy as np
    from scipy.integrate import solve_ivp

    from bayestribo.cli import main

    w = 2 * np.pi * 0.72
    t = np.arange(0.0, 20.0, 0.005)
    sol = solve_ivp(
        lambda _t, u: [u[1], -w * w * np.sin(u[0]) - 2 * 0.01 * w * u[1]],
        (0.0, t[-1]),
        [1.1, 0.0],
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
    )
    path = tmp_path / "pendulum.csv"
    np.savetxt(
        path,
        np.column_stack([t, np.degrees(sol.y[0])]),
        delimiter=",",
        header="time_s,angle_deg",
        comments="",
    )
    runs = {}
    for extra in ([], ["--restoring", "pendulum"]):
        assert main(["decay", str(path), "--json", *extra]) in (0, 1)
        runs[bool(extra)] = json.loads(capsys.readouterr().out)
    linear, pendulum = runs[False], runs[True]
    assert linear["energy"].startswith("(y² + y'²)/2")
    assert pendulum["energy"].startswith("½y'² + V(y), the potential of the pendulum")
    # the same y₀, at a turning point; E there the pendulum's 1 - cos y₀, not y₀²/2
    assert pendulum["y0"] == linear["y0"]
    y0 = abs(pendulum["y0"])
    assert main(["decay", str(path), "--restoring", "pendulum"]) in (0, 1)
    rows = capsys.readouterr().out.split("Π(τ)")[1].split()
    energy0 = float(rows[1])  # τ, E(τ), Π(τ) of the first row
    assert energy0 == pytest.approx(1.0 - np.cos(y0), rel=0.01)
    assert abs(energy0 - 0.5 * y0 * y0) > 0.05 * energy0
    assert pendulum["pi0"] < linear["pi0"]
