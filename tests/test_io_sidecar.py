"""Sidecars of any shape are read or refused with the package's error, naming the key."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bayestribo.errors import RunFormatError
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
    ],
    ids=["400 digits", "5000 digits", "deep value", "deep array", "text load", "array"],
)
def test_absurd_sidecars_are_refused_naming_what_is_wrong(tmp_path, text, match):
    path = tmp_path / "r.json"
    path.write_text(text)
    with pytest.raises(RunFormatError, match=match):
        read_sidecar(path)


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(), inner, max_size=4),
    max_leaves=20,
)


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.sampled_from(["load_N", "mass_kg", "repeat", "lubricant", "x"]), JSON))
def test_any_json_object_is_read_or_refused_with_the_packages_error(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("s") / "r.json"
    path.write_text(json.dumps(data))
    try:
        read_sidecar(path)
    except RunFormatError:
        pass
