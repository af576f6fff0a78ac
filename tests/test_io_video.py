"""A video tracker's export: frame numbers beside the time, positions in pixels."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError

FPS = 30.0
T = np.arange(600) / FPS
#: A decaying swing of 80 pixels, rounded to whole pixels as a tracker gives it.
X = np.round(80.0 * np.exp(-0.1 * T) * np.cos(2 * np.pi * 0.9 * T))


def _export(path: Path, unit: str) -> Path:
    rows = [f"{i},{t:.4f},{x:.0f},{240 + i % 2}" for i, (t, x) in enumerate(zip(T, X, strict=True))]
    path.write_text(f"frame,t (s),x ({unit}),y ({unit})\n" + "\n".join(rows) + "\n")
    return path


def test_a_frame_number_is_not_read_and_said(tmp_path: Path) -> None:
    path = tmp_path / "tracked.csv"
    rows = [f"{i},{t:.4f},{x / 1000:.3f}" for i, (t, x) in enumerate(zip(T, X, strict=True))]
    path.write_text("frame,t (s),x (m)\n" + "\n".join(rows) + "\n")
    with pytest.warns(ReadingWarning, match=r"\['frame'\] not read"):
        run = read_run(path)
    np.testing.assert_allclose(run.displacement, X / 1000, rtol=0, atol=1e-12)


def test_pixels_are_refused_with_two_readings_that_work_when_followed(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    path = _export(tmp_path / "tracked.csv", "px")
    with pytest.raises(RunFormatError, match=r"column 'x \(px\)' is in pixels") as info:
        read_run(path)
    assert "columns=['ignore', 'time_s', 'displacement_m', 'ignore']" in str(info.value)
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    arbitrary = err.split("in pixels with ")[1].split(" (friction")[0].replace(" and ", " ")
    metres = err.split("in metres with ")[1].split(" for a camera")[0].replace(" and ", " ")
    for fix, unit, factor in ((arbitrary, "arbitrary", 1.0), (metres, "m", 1e-3)):
        argv = ["inspect", str(path), *fix.split(), "--json"]
        assert main(argv) == 0, argv
        said = json.loads(capsys.readouterr().out)
        assert said["metadata"].get("length_unit", "m") == unit, said["metadata"]
        assert said["displacement"]["max"] == pytest.approx(X.max() * factor, rel=1e-12)
