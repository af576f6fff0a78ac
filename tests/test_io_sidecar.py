"""Sidecars of any shape are read or refused with the package's error, naming the key."""

from __future__ import annotations

import json

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from bayestribo.errors import RunFormatError
from bayestribo.io.run import METADATA_KEYS
from bayestribo.io.sidecar import read_sidecar


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('{"load_N": 1' + "0" * 400 + "}", "metadata 'load_N'"),
        ('{"mass_kg": ' + "1" * 5000 + "}", "not valid JSON: Exceeds the limit"),
        ('{"notes": ' + "[" * 100_000 + "]" * 100_000 + "}", "nested too deeply"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ('{"load_N": "heavy"}', "metadata 'load_N'"),
        ("[1, 2]", "one JSON object"),
        ('{"laod_N": 0.59}', "'laod_N' is not a known key; did you mean 'load_N'"),
        ('{"Mass_kg": 0.035}', "did you mean 'mass_kg'"),
        ('{"normal_load_N": 0.31}', "'normal_load_N' is not a known key; did you mean 'load_N'"),
        ('{"mas_kg": 0.035}', "did you mean 'mass_kg'"),
        (
            '{"operator": "B. Smith"}',
            r"'operator' is not a known key; put a key of your own under 'user'",
        ),
        ('{"filter": {"kind": "rc", "order": 1, "cutoff_Hz": 300}}', "metadata 'filter': 'kind'"),
        (
            '{"gain_uncertainty": 2}',
            "metadata 'gain_uncertainty'.*expected a finite number >= 0 and <= 0.5",
        ),
        (
            '{"restoring": "spring"}',
            "metadata 'restoring': expected one of linear, pendulum, duffing, auto, got 'spring'",
        ),
    ],
    ids=[
        "400 digits",
        "5000 digits",
        "deep value",
        "deep array",
        "text load",
        "array",
        "typo",
        "case",
        "another name for a known key",
        "missing letter",
        "a key of ones own",
        "impossible filter",
        "gain beyond its range",
        "unknown restoring force",
    ],
)
def test_absurd_sidecars_are_refused_naming_what_is_wrong(tmp_path, text, match):
    path = tmp_path / "r.json"
    path.write_text(text)
    with pytest.raises(RunFormatError, match=match):
        read_sidecar(path)


@pytest.mark.parametrize("name", ["linear", "pendulum", "duffing", "auto"])
def test_every_restoring_choice_is_read_from_the_sidecar(tmp_path, name):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({"length_unit": "rad", "restoring": name}))
    assert read_sidecar(path)["restoring"] == name


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(), inner, max_size=4),
    max_leaves=20,
)


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.sampled_from(["load_N", "mass_kg", "repeat", "lubricant", "user"]), JSON))
def test_any_json_object_is_read_or_refused_with_the_packages_error(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("s") / "r.json"
    path.write_text(json.dumps(data))
    try:
        read_sidecar(path)
    except RunFormatError:
        pass


@pytest.mark.parametrize(
    "run_id",
    ["../escaped/evil", "/etc/passwd", "a/b", "a\\b", "..", ".hidden", "a..b", "", "x" * 129],
)
def test_a_run_id_that_could_name_another_path_is_refused(tmp_path, run_id):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({"run_id": run_id}))
    with pytest.raises(RunFormatError, match=r"metadata 'run_id': .* is not a run id"):
        read_sidecar(path)


@pytest.mark.parametrize("run_id", ["r1", "water9.00pc-N0.46-r3", "20261122T061500Z_g_N1e+20_r2_2"])
def test_the_run_ids_the_package_makes_are_read(tmp_path, run_id):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({"run_id": run_id}))
    assert read_sidecar(path)["run_id"] == run_id


# Any JSON text: huge integers, deep nesting, every type at the top level and at the
# known keys. Reading gives metadata or the package's error, never another exception.
ANY_JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**500), max_value=10**500)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=200),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.sampled_from([*METADATA_KEYS, "x", "acquisition"]) | st.text(max_size=8),
            inner,
            max_size=4,
        )
    ),
    max_leaves=30,
)


@settings(max_examples=300, deadline=None)
@given(value=ANY_JSON, depth=st.integers(min_value=0, max_value=3000))
# found by this test: a high-pass corner no float holds raised OverflowError
@example(value={"sensor_high_pass": 10**400}, depth=0)
@example(value={"sensor_high_pass": {"cutoff_Hz": 1, "order": 2, "damping": 10**400}}, depth=0)
def test_any_json_value_is_read_or_refused_with_the_packages_error(tmp_path_factory, value, depth):
    text = "[" * depth + json.dumps(value) + "]" * depth
    if depth % 2:  # under a known key, as deep as it goes
        text = '{"notes": ' + text + "}"
    path = tmp_path_factory.mktemp("s") / "r.json"
    path.write_text(text)
    try:
        metadata = read_sidecar(path)
    except RunFormatError as exc:
        assert str(exc)  # a message, one of the package's
    else:
        assert isinstance(metadata, dict)


@pytest.mark.parametrize("key", sorted(METADATA_KEYS))
def test_every_known_key_refuses_numbers_no_float_holds_with_the_packages_error(tmp_path, key):
    # an integer of 400 or 5000 digits (JSON allows any), bare, in a list, in a mapping
    # under the high-pass's field and under another: read, or refused naming the file,
    # never an OverflowError or ValueError from a conversion
    import sys

    limit = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(0)  # to write 10**5000 as JSON
    try:
        for value in (10**400, -(10**400), 10**5000, [10**400], {"cutoff_Hz": 10**400}):
            path = tmp_path / "r.json"
            path.write_text(json.dumps({key: value}))
            sys.set_int_max_str_digits(limit)
            try:
                metadata = read_sidecar(path)
            except RunFormatError as exc:
                assert len(str(exc)) < 2000  # the number shortened in the message
            else:
                assert isinstance(metadata, dict)
            sys.set_int_max_str_digits(0)
    finally:
        sys.set_int_max_str_digits(limit)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("mass_kg", 1e308),
        ("mass_kg", 1e-320),
        ("natural_frequency_Hz", 1e-320),
        ("load_N", 1e300),
        ("sample_rate_Hz", 1e300),
        ("displacement_resolution_m", 5.0),
    ],
)
def test_a_number_no_rig_has_is_refused_naming_its_range(tmp_path, key, value):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({key: value}))
    with pytest.raises(RunFormatError, match=rf"metadata '{key}'.*expected a finite number >="):
        read_sidecar(path)
