"""The Run container: structure, typed metadata, value semantics, rig and scaling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bayestribo import Run
from bayestribo.errors import RecordingError, RunFormatError
from bayestribo.io.run import METADATA_KEYS, check_metadata

T = np.arange(100) / 1000.0
X = 1e-3 * np.cos(2 * np.pi * 32.6 * T)


def test_arrays_are_copied_float64_and_read_only() -> None:
    x = X.copy()
    run = Run(T, displacement=x)
    x[0] = 99.0
    assert run.displacement[0] == X[0]
    assert run.time.dtype == np.float64
    with pytest.raises(ValueError):
        run.displacement[0] = 1.0
    assert run.velocity is None
    assert run.n_samples == 100
    assert list(run.signals) == ["time_s", "displacement_m"]


def test_sample_rate_from_time_stamps() -> None:
    assert Run(T, X).sample_rate_Hz == pytest.approx(1000.0, rel=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"displacement": None, "velocity": None}, "displacement_m.*or.*velocity_m_per_s"),
        ({"displacement": X[:-1]}, "'displacement_m' has 99 samples"),
        ({"velocity": np.ones((100, 2))}, "'velocity_m_per_s'.*1-D"),
        ({"displacement": ["a"] * 100}, "'displacement_m': expected numbers"),
    ],
)
def test_bad_structure_raises_run_format_error(kwargs: dict, match: str) -> None:
    with pytest.raises(RunFormatError, match=match):
        Run(T, source="file.csv", **kwargs)
    with pytest.raises(RunFormatError, match=r"file\.csv"):
        Run(T, source="file.csv", **kwargs)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("load_N", "0.31"),
        ("load_N", -0.1),
        ("load_N", True),
        ("load_N", [0.3]),
        ("mass_kg", 0.0),
        ("natural_frequency_Hz", math.nan),
        ("repeat", 1.5),
        ("repeat", -1),
        ("water_mass_fraction", 1.2),
        ("lubricant", 3),
        ("length_unit", "mm"),
        ("temperature_C", -300.0),
    ],
)
def test_known_metadata_keys_are_typed(key: str, value: object) -> None:
    with pytest.raises(RunFormatError, match=rf"metadata '{key}'.*expected"):
        check_metadata({key: value}, "run.json")


def test_known_keys_are_normalised_and_none_means_unknown() -> None:
    meta = check_metadata({"load_N": 1, "repeat": np.int64(2), "mass_kg": None})
    assert meta == {"load_N": 1.0, "repeat": 2, "mass_kg": None}
    assert isinstance(meta["load_N"], float)
    assert isinstance(meta["repeat"], int)


def test_extra_keys_are_kept_as_plain_data() -> None:
    meta = check_metadata(
        {"operator": "A", "n": np.float32(0.5), "tags": ("a", 1), "nested": {"b": [True, None]}}
    )
    assert meta == {"operator": "A", "n": 0.5, "tags": ["a", 1], "nested": {"b": [True, None]}}


@pytest.mark.parametrize("value", [{1, 2}, object(), b"bytes", math.inf, {"k": {1: 2}}])
def test_extra_key_of_unknown_type_raises(value: object) -> None:
    with pytest.raises(RunFormatError, match="metadata 'extra"):
        check_metadata({"extra": value}, "run.json")


def test_every_documented_sidecar_key_is_known() -> None:
    documented = {
        "load_N",
        "mass_kg",
        "natural_frequency_Hz",
        "displacement_resolution_m",
        "velocity_resolution_m_per_s",
        "sample_rate_Hz",
        "lubricant",
        "water_mass_fraction",
        "repeat",
        "temperature_C",
        "run_id",
    }
    assert documented <= set(METADATA_KEYS)


def test_equality_compares_values_not_source() -> None:
    a = Run(T, X, metadata={"load_N": 0.3}, source="a.csv")
    b = Run(T.copy(), X.copy(), metadata={"load_N": 0.3}, source="b.csv")
    assert a == b
    assert a != Run(T, X, metadata={"load_N": 0.31})
    assert a != Run(T, velocity=X, metadata={"load_N": 0.3})
    one_ulp = X.copy()
    one_ulp[5] = np.nextafter(one_ulp[5], 1.0)
    assert a != Run(T, one_ulp, metadata={"load_N": 0.3})


def test_metadata_is_read_only_and_with_metadata_checks_again() -> None:
    run = Run(T, X, metadata={"load_N": 0.3})
    with pytest.raises(TypeError):
        run.metadata["load_N"] = 1.0  # type: ignore[index]
    assert run.with_metadata(load_N=0.5).metadata["load_N"] == 0.5
    with pytest.raises(RunFormatError, match="load_N"):
        run.with_metadata(load_N="heavy")


def test_rig_and_scaling_from_metadata() -> None:
    run = Run(T, X, metadata={"load_N": 0.31, "mass_kg": 0.035, "natural_frequency_Hz": 32.6})
    rig = run.rig()
    assert (rig.natural_frequency_Hz, rig.mass_kg, rig.load_N) == (32.6, 0.035, 0.31)
    scaling = run.scaling()
    assert scaling.friction_defined
    assert scaling.length_scale == pytest.approx(0.31 / (0.035 * (2 * math.pi * 32.6) ** 2))


def test_arbitrary_length_unit_drops_load_and_mass_from_the_rig() -> None:
    run = Run(T, X, metadata={"load_N": 0.31, "mass_kg": 0.035, "length_unit": "arbitrary"})
    assert run.length_unit == "arbitrary"
    assert run.rig() is None  # no natural frequency known
    rig = run.rig(natural_frequency_Hz=1.2)
    assert rig.load_N is None and rig.mass_kg is None
    assert run.scaling(1.2).length_scale == 1.0
    assert not run.scaling(1.2).friction_defined


def test_scaling_without_frequency_raises_recording_error() -> None:
    with pytest.raises(RecordingError, match="natural_frequency_Hz"):
        Run(T, X, source="r.csv").scaling()


def test_a_load_without_a_frequency_uses_the_measured_frequency_and_says_so():
    from bayestribo.errors import MetadataWarning, RunFormatError
    from bayestribo.synthetic import simulate

    recording = simulate(seed=5)
    meta = {k: v for k, v in recording.metadata.items() if k != "natural_frequency_Hz"}
    run = Run(recording.time, recording.displacement, recording.velocity, meta)
    with pytest.warns(MetadataWarning, match=r"turning times \(about 32\.59 Hz"):
        rig = run.rig()
    # The damped frequency of the simulation (ζ = 0.0236), to 1e-5.
    assert rig.natural_frequency_Hz == pytest.approx(32.6 * (1 - 0.0236**2) ** 0.5, rel=1e-5)
    assert rig.load_N == 0.31 and rig.mass_kg == 0.035
    # No motion to measure: refused with the option to give, the load is not dropped.
    still = Run(T, 0.0 * X, metadata={"load_N": 0.31, "mass_kg": 0.035})
    with pytest.raises(RunFormatError, match=r"natural_frequency_Hz is not.*--frequency"):
        still.rig()
    assert Run(T, X, metadata={"load_N": 0.0}).rig() is None  # no contact: nothing lost
    arbitrary = Run(T, X, metadata={"load_N": 0.31, "length_unit": "arbitrary"})
    assert arbitrary.rig() is None
