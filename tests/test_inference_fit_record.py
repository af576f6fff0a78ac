"""The typed record of a fit (inference/fit_record.py) against the attributes of its
file: what a saved fit holds reads back into the record and out again unchanged, so
a file written through the record is the file the previous version wrote and read."""

from __future__ import annotations

import json

import pytest

from bayestribo.inference import FitResult
from bayestribo.inference.fit_record import FitRecord

#: The attributes a fit of a named law has always written (the posterior group's).
WRITTEN = (
    "run_name",
    "model",
    "law",
    "dissipation_json",
    "turning_point_dissipation_json",
    "shape_agreement_json",
    "restoring_json",
    "units_json",
    "seed",
    "package_version",
    "friction_defined",
    "length_scale",
    "omega",
    "tau_end",
    "motion_ended",
    "metadata_json",
    "noise_json",
    "channels_json",
    "priors_json",
    "fixed_json",
    "settings_json",
    "diagnostics_json",
    "frequency_trend_json",
    "frequency_nuisance_sd",
    "sensor_json",
    "law_frequency_change",
    "prior_sensitivity_json",
    "spec_json",
    "seconds",
    "boundary_json",
)


def test_a_saved_fit_reads_into_the_record_and_out_unchanged(short_fit: FitResult) -> None:
    attrs = dict(short_fit.attrs)
    assert set(WRITTEN) <= set(attrs)
    record = FitRecord.from_attrs(attrs)
    assert record.to_attrs() == attrs
    # each JSON attribute's text itself, not only its value
    for key, value in record.to_attrs().items():
        if key.endswith("_json"):
            assert value == attrs[key], key


def test_the_record_is_what_the_result_reads(short_fit: FitResult) -> None:
    record = short_fit.record
    assert record.law == short_fit.law
    assert record.dissipation == short_fit.dissipation
    assert record.diagnostics == short_fit.diagnostics
    assert record.noise == short_fit.noise
    assert record.spec == short_fit.spec.to_dict()
    assert record.seed == short_fit.seed
    assert record.law_comparison is None and "law_comparison" in record.unwritten


def test_an_earlier_fit_keeps_what_it_did_not_write_unwritten(short_fit: FitResult) -> None:
    older = {
        k: v
        for k, v in short_fit.attrs.items()
        if k not in ("shape_agreement_json", "restoring_json", "spec_json")
    }
    older["written_by_someone_else"] = "kept"
    record = FitRecord.from_attrs(older)
    assert record.shape_agreement is None and record.spec is None
    assert {"shape_agreement", "restoring", "spec"} <= record.unwritten
    assert record.extra == {
        k: v for k, v in older.items() if k == "written_by_someone_else" or k not in WRITTEN
    }
    assert record.to_attrs() == older


def test_a_field_set_is_written(short_fit: FitResult) -> None:
    record = FitRecord.from_attrs(short_fit.attrs)
    changed = record.replace(law_comparison={"verdict": "viscous"})
    assert "law_comparison" not in changed.unwritten
    assert json.loads(changed.to_attrs()["law_comparison_json"]) == {"verdict": "viscous"}
    assert "law_comparison_json" not in record.to_attrs()


def test_the_record_round_trips_as_plain_data(short_fit: FitResult) -> None:
    record = FitRecord.from_attrs(short_fit.attrs)
    data = json.loads(json.dumps(record.to_dict()))
    assert FitRecord.from_dict(data).to_attrs() == record.to_attrs()


def test_plain_data_with_an_unknown_field_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown fields \\['lawz'\\]"):
        FitRecord.from_dict({"law": "viscous", "lawz": "viscous"})
