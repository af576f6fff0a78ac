"""The real corpus (``data/real/``): its list, its sources' READMEs, and every file found.

The list and the READMEs are in the repository and checked on every run; the
recordings themselves are kept outside it (``tests/_real_corpus.py`` says where they
are looked for) and each one found is checked against the bytes its source published,
read with the options a user gives, and its decay analysed (``bayestribo inspect``:
read and prepare, no fit). A recording that is absent skips.
"""

from __future__ import annotations

import re

import pytest
from _real_corpus import CORPUS, locate, manifest

from bayestribo.cli.inspect import inspection
from bayestribo.cli.main import build_parser

LISTED = manifest()
RECORDINGS = LISTED["recordings"]
#: Licences that allow the recordings to be passed on, by SPDX id.
REDISTRIBUTABLE = {
    "MIT",
    "BSD-2-Clause",
    "BSD-3-Clause",
    "Apache-2.0",
    "CC0-1.0",
    "CC-BY-4.0",
    "CC-BY-SA-4.0",
    "GPL-3.0-or-later",
    "GPL-3.0-only",
}
#: Fields every source's README gives, as its bullets' bold labels.
FIELDS = ("Source", "Commit", "Licence", "Rig", "Columns and units", "Run")


def _readme(source: str) -> str:
    return (CORPUS / source / "README.md").read_text(encoding="utf-8")


def test_every_recording_names_a_listed_source_once():
    names = [r["name"] for r in RECORDINGS]
    assert len(names) == len(set(names))
    assert {r["source"] for r in RECORDINGS} == set(LISTED["sources"])
    assert len(RECORDINGS) >= 6 and len(LISTED["sources"]) >= 4


@pytest.mark.parametrize("source", sorted(LISTED["sources"]))
def test_source_is_pinned_and_redistributable(source):
    entry = LISTED["sources"][source]
    assert entry["repository"].startswith("https://github.com/")
    assert re.fullmatch(r"[0-9a-f]{40}", entry["commit"])
    assert entry["licence"] in REDISTRIBUTABLE
    assert entry["licence_file"]


@pytest.mark.parametrize("source", sorted(LISTED["sources"]))
def test_source_readme_gives_every_field(source):
    text = _readme(source)
    for field in FIELDS:
        assert f"- **{field}**" in text, f"{source}/README.md lacks '{field}'"
    entry = LISTED["sources"][source]
    assert entry["repository"] in text
    assert entry["commit"] in text
    assert f"SPDX `{entry['licence']}`" in text
    assert "bayestribo fit " in text


@pytest.mark.parametrize("recording", RECORDINGS, ids=lambda r: r["name"])
def test_recording_is_listed_with_its_bytes_and_steps(recording):
    assert re.fullmatch(r"[0-9a-f]{64}", recording["sha256"])
    assert recording["bytes"] > 0
    text = _readme(recording["source"])
    assert f"`{recording['file']}`" in text and recording["sha256"] in text
    assert recording["steps"], "a recording is run by at least one command"
    for step in recording["steps"]:
        assert isinstance(step["options"], list) and step["why"]
    # the options the light test reads with are those of one of the steps
    assert any(
        recording["read"] == step["options"][: len(recording["read"])]
        for step in recording["steps"]
    )


@pytest.mark.parametrize("recording", RECORDINGS, ids=lambda r: r["name"])
def test_recording_reads_and_prepares_as_listed(recording):
    path = locate(recording)  # raises on a file with other bytes than published
    if path is None:
        pytest.skip(
            f"{recording['source']}/{recording['file']} is not on this machine "
            "(set BAYESTRIBO_REAL_CORPUS to the folder that holds it)"
        )
    args = build_parser().parse_args(["inspect", str(path), *recording["read"]])
    report, usable = inspection(args)
    assert report["samples"]["n"] > 100
    assert usable is recording["prepares"], report["decay"]
