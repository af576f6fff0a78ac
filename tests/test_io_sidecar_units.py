"""A sidecar's load in kgf or grams and its mass in grams are read in SI, and said."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import ReadingWarning, RunFormatError

G = 9.80665


def _record(tmp_path, meta):
    """A closed-form viscous decay (32 Hz, 2 mm) as a canonical CSV with ``meta`` beside it."""
    t = np.arange(2000) / 2000.0
    w = 2 * np.pi * 32.0
    x = 2e-3 * np.exp(-0.02 * w * t) * np.cos(w * t)
    path = tmp_path / "run.csv"
    rows = "\n".join(f"{a:.6f},{b:.6e}" for a, b in zip(t, x, strict=True))
    path.write_text("time_s,displacement_m\n" + rows + "\n")
    (tmp_path / "run.json").write_text(json.dumps(meta))
    return path


@pytest.mark.parametrize(
    ("meta", "load", "mass"),
    [
        ({"load_kgf": 0.3 / G, "mass_g": 35.0}, 0.3, 0.035),
        ({"load_g": 30.0, "mass_kg": 0.035}, 0.030 * G, 0.035),
        ({"load_mN": 300.0, "mass_mg": 35000.0}, 0.3, 0.035),
        ({"load_N": "30 gf", "mass": "35 g"}, 0.030 * G, 0.035),
        ({"load": "0.3 N", "mass_kg": "0.035kg"}, 0.3, 0.035),
        ({"load_lbf": 1.0, "mass_oz": 1.0}, 0.45359237 * G, 0.028349523125),
    ],
    ids=[
        "kgf and grams",
        "grams of a dead weight",
        "mN and mg",
        "units in values",
        "bare names",
        "US",
    ],
)
def test_a_load_or_mass_in_another_unit_is_read_in_si_and_said(tmp_path, meta, load, mass):
    path = _record(tmp_path, {**meta, "natural_frequency_Hz": 32.0})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = read_run(path)
    assert run.metadata["load_N"] == pytest.approx(load, rel=1e-12)
    assert run.metadata["mass_kg"] == pytest.approx(mass, rel=1e-12)
    said = [str(w.message) for w in caught if issubclass(w.category, ReadingWarning)]
    converted = [k for k in meta if k not in ("load_N", "mass_kg") or isinstance(meta[k], str)]
    for key in converted:
        assert any(repr(key) in s and "read as" in s for s in said), (key, said)
    # numbers said to six figures, as the units they were written in
    assert not any("0.030591486" in s for s in said), said


@pytest.mark.parametrize(
    ("meta", "match"),
    [
        ({"load_N": 0.3, "load_kgf": 0.03}, "'load_kgf' and 'load_N' both give the load"),
        ({"load_stone": 0.3}, "'load_stone' is not a known key"),
        ({"mass_kg": "35 gf"}, "metadata 'mass_kg'"),
    ],
    ids=["twice", "unknown unit", "a force for a mass"],
)
def test_a_unit_that_cannot_be_read_is_refused(tmp_path, meta, match):
    path = _record(tmp_path, meta)
    with pytest.raises(RunFormatError, match=match):
        read_run(path)


def test_a_calibration_key_is_refused_naming_the_scale_that_reads_the_file(tmp_path):
    t = np.arange(2000) / 2000.0
    x = 2e-3 * np.exp(-0.02 * 2 * np.pi * 32.0 * t) * np.cos(2 * np.pi * 32.0 * t)
    lsb = 2.5e-6 / 2**12
    path = tmp_path / "adc.txt"
    path.write_text("\n".join(str(int(c)) for c in np.round(x / lsb)) + "\n")
    meta = {"natural_frequency_Hz": 32.0, "sample_rate_Hz": 2000.0}
    (tmp_path / "adc.json").write_text(json.dumps({**meta, "scale_m_per_count": lsb}))
    with pytest.raises(RunFormatError) as err:
        read_run(path)
    message = str(err.value)
    assert "looks like a channel's calibration" in message
    assert f"scale={{'displacement_m': {lsb!r}}}" in message
    assert "did you mean" not in message
    # followed: the key under 'user', the factor given as the scale
    (tmp_path / "adc.json").write_text(json.dumps({**meta, "user": {"scale_m_per_count": lsb}}))
    run = read_run(path, columns=["displacement_m"], scale={"displacement_m": lsb})
    np.testing.assert_allclose(run.displacement, x, atol=lsb)
