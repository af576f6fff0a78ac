"""UFF 58 (ASCII) and 58b (binary) files written by pyuff itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pyuff

from bayestribo import read_run
from bayestribo.errors import RunFormatError

RATE = 5000.0
T = 0.25 + np.arange(800) / RATE
X = 1.2e-3 * np.exp(-4.8 * T) * np.cos(2 * np.pi * 32.6 * T)
V = np.gradient(X, T)


def _record(data: np.ndarray, spec: int, unit: str, binary: int, start: float = 0.25) -> dict:
    return pyuff.prepare_58(
        binary=binary,
        id1=f"Vib {unit}",
        func_type=1,
        rsp_node=1,
        rsp_dir=1,
        ref_node=1,
        ref_dir=1,
        abscissa_spacing=1,
        data=data,
        x=start + np.arange(data.size) / RATE,
        abscissa_spec_data_type=17,
        abscissa_axis_units_lab="s",
        ordinate_spec_data_type=spec,
        ordinate_axis_units_lab=unit,
        orddenom_spec_data_type=0,
        z_axis_spec_data_type=0,
    )


def _write(path: Path, records: list[dict]) -> Path:
    pyuff.UFF(str(path)).write_sets(records, mode="add")
    return path


@pytest.mark.parametrize("binary", [0, 1], ids=["58-ascii", "58b-binary"])
def test_displacement_and_velocity_records_with_units(tmp_path: Path, binary: int) -> None:
    path = _write(
        tmp_path / "vib.uff",
        [_record(1e3 * X, 8, "mm", binary), _record(V, 11, "m/s", binary)],
    )
    run = read_run(path, metadata={"natural_frequency_Hz": 32.6})
    # pyuff writes the abscissa start and step with 6 significant digits (%13.5e),
    # exact here; ASCII data with 12 significant digits (%20.11e), binary exactly.
    np.testing.assert_allclose(run.time, T, rtol=0, atol=1e-12)
    # Displacement went through x1000 here and x1e-3 in the reader: two roundings, < 1e-15.
    rtol = 1e-11 if binary == 0 else 1e-15
    np.testing.assert_allclose(run.displacement, X, rtol=rtol, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=rtol, atol=0)
    if binary:
        np.testing.assert_array_equal(run.velocity, V)
    assert run.metadata["natural_frequency_Hz"] == 32.6


def test_type_from_unit_label_when_data_type_is_unknown(tmp_path: Path) -> None:
    path = _write(tmp_path / "v.unv", [_record(1e6 * V, 0, "um/s", 1)])
    run = read_run(path)
    assert run.displacement is None
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15)


def test_channels_choose_among_several_records(tmp_path: Path) -> None:
    path = _write(
        tmp_path / "two.uff",
        [_record(X, 8, "m", 1), _record(2 * X, 8, "m", 1), _record(V, 11, "m/s", 1)],
    )
    with pytest.raises(RunFormatError, match="records 0 and 1 are both displacement_m"):
        read_run(path)
    run = read_run(path, channels={"displacement_m": 0, "velocity_m_per_s": 2})
    np.testing.assert_array_equal(run.displacement, X)


def test_unknown_unit_needs_a_scale_factor(tmp_path: Path) -> None:
    path = _write(tmp_path / "volts.uff", [_record(X / 0.002, 8, "V", 1)])
    with pytest.raises(RunFormatError, match=r"volts\.uff.*unit label 'V'.*scale="):
        read_run(path)
    run = read_run(path, scale={"displacement_m": 0.002})
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15)


def test_different_time_axes_are_refused(tmp_path: Path) -> None:
    path = _write(
        tmp_path / "shift.uff", [_record(X, 8, "m", 1), _record(V, 11, "m/s", 1, start=0.5)]
    )
    with pytest.raises(RunFormatError, match="different time axes"):
        read_run(path)


def test_garbage_and_empty_files_raise_format_errors(tmp_path: Path) -> None:
    (tmp_path / "junk.uff").write_bytes(b"    -1\n    58\nnot a data set\n    -1\n")
    with pytest.raises(RunFormatError, match=r"junk\.uff"):
        read_run(tmp_path / "junk.uff")
    (tmp_path / "empty.uff").write_text("")
    with pytest.raises(RunFormatError, match=r"empty\.uff"):
        read_run(tmp_path / "empty.uff")
