"""Mains hum on the command line: found at rest and named, subtracted with --notch."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.io.run import Run
from bayestribo.synthetic import Sensor, simulate


@pytest.fixture(scope="module")
def hum_file(tmp_path_factory):
    sensor = Sensor(
        sample_rate_Hz=5000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
    )
    run = simulate(seed=3, sensor=sensor)
    t = run.time
    # 50 Hz hum of 5 times the white noise on both channels (the test's own).
    hum = np.sin(2 * np.pi * 50.0 * t + 0.3)
    x = run.displacement + 5 * np.sqrt(2) * 1.5e-6 * hum
    v = run.velocity + 5 * np.sqrt(2) * 1.5e-7 * hum
    path = tmp_path_factory.mktemp("hum") / "hum.csv"
    return write_run(Run(t, x, v, dict(run.metadata)), path)


def test_a_mains_line_at_rest_is_named_with_the_option_to_remove_it(hum_file, capsys):
    assert main(["decay", str(hum_file), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["notch_Hz"] == []
    assert [round(f) for f in info["mains_lines_Hz"]] == [50]
    assert main(["decay", str(hum_file)]) == 0
    assert "--notch auto subtracts it" in capsys.readouterr().out


@pytest.mark.parametrize("notch", ["auto", "50"])
def test_notch_subtracts_the_line_and_says_so(hum_file, capsys, notch):
    assert main(["inspect", str(hum_file), "--json", "--notch", notch]) == 0
    info = json.loads(capsys.readouterr().out)["decay"]
    assert len(info["notch_Hz"]) == 1 and abs(info["notch_Hz"][0] - 50.0) < 0.5
    assert main(["inspect", str(hum_file), "--notch", notch]) == 0
    assert "measured at rest and subtracted" in capsys.readouterr().out


def test_a_bad_notch_value_is_refused_by_the_parser(hum_file, capsys):
    with pytest.raises(SystemExit):
        main(["decay", str(hum_file), "--notch", "mains"])
    assert "expected a frequency in Hz (50, 60) or auto" in capsys.readouterr().err


def test_fit_records_and_reports_the_line_it_subtracted(hum_file, capsys):
    from bayestribo.inference import fit

    result = fit(hum_file, notch="auto", max_steps=2000)
    assert [round(f) for f in result.settings["notch_Hz"]] == [50]
    status = main(["fit", str(hum_file), "--notch", "auto", "--max-steps", "2000", "--json"])
    out, err = capsys.readouterr()
    record = json.loads(out)
    assert status == (0 if record["diagnostics"]["converged"] else 1)
    assert "mains line at 50" in err
