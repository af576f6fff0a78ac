"""A rotary encoder's raw counts read as an angle with the counts per revolution the
file states, or refused naming the options that read them."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.encoder_counts import counts_per_rev


def _write(path, statement, header="time_s,counts"):
    t = np.arange(400) / 200.0
    counts = np.round(0.5 * np.cos(2 * np.pi * 0.8 * t) / (2 * np.pi) * 8192).astype(int)
    lines = ["# torsion pendulum, rotary encoder"]
    if statement:
        lines.append(statement)
    lines.append(header)
    lines += [f"{a:.3f},{c}" for a, c in zip(t, counts, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return t, counts


@pytest.mark.parametrize(
    ("statement", "n"),
    [
        ("# counts_per_rev: 8192", 8192),
        ("# CPR = 8192", 8192),
        ("# Resolution: 8192 counts/rev", 8192),
        ("# Counts per revolution (x4): 8192", 8192),
    ],
)
def test_counts_are_read_as_an_angle_with_the_stated_resolution(tmp_path, statement, n):
    path = tmp_path / "encoder.csv"
    t, counts = _write(path, statement)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = read_run(path)
    np.testing.assert_allclose(run.time, t)
    np.testing.assert_allclose(run.displacement, counts * 2 * math.pi / n, rtol=1e-12)
    assert run.metadata["length_unit"] == "rad"
    said = [str(w.message) for w in caught if issubclass(w.category, ReadingWarning)]
    assert any("encoder's angle" in s and f"2π/{n}" in s for s in said), said


def test_counts_without_a_resolution_are_refused_with_the_reading(tmp_path):
    path = tmp_path / "encoder.csv"
    _write(path, None)
    with pytest.raises(RunFormatError) as err:
        read_run(path)
    message = str(err.value)
    assert "'--columns time_s angle_rad --scale angle_rad=X'" in message
    # the advice followed, with X = 2π/N for the encoder's N, reads it
    run = read_run(path, columns=["time_s", "angle_rad"], scale={"angle_rad": 2 * math.pi / 8192})
    assert run.metadata["length_unit"] == "rad"
    assert abs(run.displacement).max() == pytest.approx(0.5, abs=1e-3)


def test_two_resolutions_that_differ_state_none():
    lines = [(1, "# counts_per_rev: 8192"), (2, "# CPR: 4096")]
    assert counts_per_rev(lines) is None
    assert counts_per_rev([(3, "# sample rate: 200 Hz")]) is None
