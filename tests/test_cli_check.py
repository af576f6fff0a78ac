"""``bayestribo check`` on the command line."""

from __future__ import annotations

import json

import pytest

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.synthetic.recording import simulate


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("check") / "run.csv"
    write_run(simulate(seed=31), path)
    return path


def test_check_prints_a_report(run_file, capsys):
    assert main(["check", str(run_file), "--window-length", "3"]) == 0
    out = capsys.readouterr().out
    assert "windows of 3 oscillations" in out
    assert "constancy:" in out and "extinction:" in out and "peaks:" in out
    assert "verdict:" in out


def test_check_json(run_file, capsys):
    assert main(["check", str(run_file), "--json", "--draws", "100"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["windows"]["window_oscillations"] == 2
    assert len(data["windows"]["windows"]) >= 3
    assert set(data) >= {"adequate", "constancy", "extinction", "predictive", "verdict"}
    assert data["predictive"]["draws"].endswith("(not a posterior)")


def test_bad_window_is_a_package_error(run_file, capsys):
    assert main(["check", str(run_file), "--window-length", "0"]) == 2
    assert "window must be a whole number" in capsys.readouterr().err


def test_missing_file(tmp_path, capsys):
    assert main(["check", str(tmp_path / "none.csv")]) == 2
    assert "error" in capsys.readouterr().err


def test_an_inadequate_law_exits_1(tmp_path, capsys):
    from bayestribo.synthetic import DissipationLaw, Sensor

    # Damping that grows with amplitude: not the constant law.
    run = simulate(
        DissipationLaw(zeta=lambda a: 0.01 + 20.0 * a, mu_k=0.0294),
        sensor=Sensor(
            sample_rate_Hz=2000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=9,
    )
    path = write_run(run, tmp_path / "quadratic.csv")
    assert main(["check", str(path), "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["adequate"] is False
