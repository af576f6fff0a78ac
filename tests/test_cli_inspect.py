"""``bayestribo inspect``: how a file is read and what is in it, before any fit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.io.run import Run
from bayestribo.synthetic import simulate


@pytest.fixture(scope="module")
def run():
    return simulate(seed=21)


def _inspect(argv, capsys, status=0):
    assert main(["inspect", *argv, "--json"]) == status
    return json.loads(capsys.readouterr().out)


def test_a_canonical_run_is_described_in_text_and_json(tmp_path, run, capsys):
    path = write_run(run, tmp_path / "r.csv")
    got = _inspect([str(path)], capsys)
    assert got["reading"]["reader"] == "canonical CSV"
    assert got["reading"]["sidecar"].endswith("r.json")
    assert got["samples"]["n"] == run.n_samples
    assert got["samples"]["sample_rate_Hz"] == pytest.approx(1e4, rel=1e-9)
    sim = run.metadata["simulation"]
    assert got["decay"]["release_time_s"] == pytest.approx(sim["release_time_s"], abs=2e-3)
    assert got["decay"]["motion_ended"] is True
    assert got["decay"]["friction_reported_as"] == "mu_k"
    assert got["channels"]["velocity_gain"] == pytest.approx(1.0, abs=1e-3)
    damped = 32.6 * np.sqrt(1 - sim["zeta"] ** 2)
    assert got["oscillation_frequency_Hz"] == pytest.approx(damped, rel=1e-4)
    assert main(["inspect", str(path)]) == 0
    text = capsys.readouterr().out
    for label in ("read as", "samples", "channels", "release", "analysed", "noise at rest"):
        assert label in text


def test_a_velocity_gain_and_a_delay_are_measured(tmp_path, run, capsys):
    t = run.time
    late = np.interp(t - 1e-4, t, run.displacement)  # displacement 100 µs late
    other = Run(t, late, 1.01 * run.velocity, dict(run.metadata))
    got = _inspect([str(write_run(other, tmp_path / "g.csv"))], capsys)
    assert got["channels"]["velocity_gain"] == pytest.approx(1.01, rel=1e-3)
    assert got["channels"]["delay_s"] == pytest.approx(1e-4, rel=0.05)


def test_an_instrument_export_is_named_with_its_columns(tmp_path, run, capsys):
    rows = [
        f"{t:.12e},{x / 2e-4:.12e},{v / 5e-3:.12e}"
        for t, x, v in zip(run.time, run.displacement, run.velocity, strict=True)
    ]
    path = tmp_path / "scope.csv"
    path.write_text("\n".join(["x-axis,1,2", "second,Volt,Volt", *rows]) + "\n", encoding="utf-8")
    argv = [str(path), "--columns", "t", "x", "v", "--scale", "x=2e-4", "--scale", "v=5e-3"]
    argv += ["--frequency", "32.6", "--load", "0.31", "--mass", "0.035"]
    got = _inspect(argv, capsys)
    assert got["reading"]["reader"] == "Keysight/Agilent CSV export"
    assert [c["unit"] for c in got["reading"]["columns"]] == ["second", "Volt", "Volt"]
    assert got["displacement"]["max"] == pytest.approx(run.displacement.max(), rel=1e-9)


def test_a_record_without_motion_says_which_part_failed(tmp_path, capsys):
    t = np.arange(5000) / 1e4
    noise = np.random.default_rng(0).normal(0.0, 1e-7, t.size)
    still = Run(t, noise, None, {"natural_frequency_Hz": 32.6, "length_unit": "arbitrary"})
    got = _inspect([str(write_run(still, tmp_path / "still.csv"))], capsys, status=2)
    assert "error" in got["decay"] and got["decay"]["error"]
    assert main(["inspect", str(tmp_path / "still.csv")]) == 2
    assert "analysis       not possible:" in capsys.readouterr().out


def test_swapped_channels_are_refused_naming_both(tmp_path, run, capsys):
    swapped = tmp_path / "swapped.csv"
    rows = [
        f"{t:.17g},{v:.17g},{x:.17g}"
        for t, x, v in zip(run.time, run.displacement, run.velocity, strict=True)
    ]
    swapped.write_text(
        "time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n", encoding="utf-8"
    )
    assert main(["inspect", str(swapped)]) == 2
    err = capsys.readouterr().err
    assert "'displacement_m' and 'velocity_m_per_s'" in err and "swapped" in err


def test_times_on_a_clock_of_unix_seconds_are_told_apart(tmp_path, run, capsys):
    # a DAQ's time column in Unix seconds: six digits printed every time as 1.40672e+09
    offset = 1_406_722_067.411
    shifted = Run(run.time + offset, run.displacement, run.velocity, dict(run.metadata))
    path = write_run(shifted, tmp_path / "unix.csv")
    got = _inspect([str(path)], capsys)
    release = got["decay"]["release_time_s"]
    assert main(["inspect", str(path)]) == 0
    text = capsys.readouterr().out
    line = next(x for x in text.splitlines() if x.startswith("release"))
    # to a ten-thousandth of the record's duration, and how far into the record
    duration = got["samples"]["duration_s"]
    assert abs(float(line.split("=")[1].split()[0]) - release) <= 1e-4 * duration
    into = float(line.split("(")[1].split()[0])
    assert into == pytest.approx(release - got["samples"]["start_s"], rel=1e-5)
    assert "the pin" not in text


def test_an_angle_record_without_a_rest_is_described_in_its_own_terms(tmp_path, run, capsys):
    # a torsion oscillator's angle in radians, recorded only while it moves
    sim = run.metadata["simulation"]
    moving = (run.time > sim["release_time_s"] + 0.005) & (run.time < run.time[0] + 0.3)
    path = tmp_path / "angle.csv"
    angle = 200.0 * run.displacement[moving]  # about half a radian
    np.savetxt(path, np.column_stack([run.time[moving], angle]), delimiter=",", fmt="%.9g")
    path.write_text("time_s,angle_rad\n" + path.read_text())
    assert main(["inspect", str(path)]) == 0
    text = capsys.readouterr().out
    lines = {line[:14].strip(): line[14:].strip() for line in text.splitlines()}
    assert lines["signals"].startswith("time_s, angle_rad")
    assert lines["friction as"] == "friction angle"
    # no rest: the noise from the signal's differences, said so, no "0 samples"
    assert lines["noise"].startswith("angle ") and "no rest in the record" in lines["noise"]
    assert "0 samples" not in text
    # the oscillation left out after the release is said, with the option that keeps it
    assert "1 oscillation after the release left out" in lines["analysed"]
    assert "--skip 0 keeps it" in lines["analysed"]
