"""The real corpus: recordings made by others, listed in ``data/real/manifest.json``.

The list, the sources' READMEs and the options a user gives live in the repository;
the recordings themselves are kept outside it, as the two rigs of
``../shared/external-data`` are, and looked up by their names. One definition for the
light test (``tests/test_real_corpus.py``) and the benchmark
(``benchmarks/real_corpus.py``, which loads this file by its path).
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

#: The repository root.
REPO = Path(__file__).resolve().parents[1]
#: The corpus' folder: one README per source, and the manifest.
CORPUS = REPO / "data" / "real"
MANIFEST = CORPUS / "manifest.json"
#: The environment variable naming a folder that holds ``<source>/<file>``.
ROOT_VARIABLE = "BAYESTRIBO_REAL_CORPUS"


def manifest() -> dict[str, Any]:
    """The manifest: ``sources`` (repository, commit, licence) and ``recordings``."""
    return json.loads(MANIFEST.read_text(encoding="utf-8"))


def search_roots() -> list[Path]:
    """Folders searched for ``<source>/<file>``, in order: ``$BAYESTRIBO_REAL_CORPUS``,
    ``data/real`` and ``../shared/external-data/real-corpus`` beside the checkout."""
    roots = [CORPUS, REPO.parent / "shared" / "external-data" / "real-corpus"]
    given = os.environ.get(ROOT_VARIABLE)
    return ([Path(given)] if given else []) + roots


def sha256(path: Path) -> str:
    """The file's SHA-256, in hexadecimal."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def locate(recording: dict[str, Any]) -> Path | None:
    """The recording's file in the first root that holds it, or None where none does.

    Raises
    ------
    ValueError
        When a file of that name is found with other bytes than the source published.
    """
    for root in search_roots():
        path = root / recording["source"] / recording["file"]
        if path.is_file():
            found = sha256(path)
            if found != recording["sha256"]:
                raise ValueError(
                    f"{path}: sha256 {found}, expected {recording['sha256']} (the file as "
                    "its source published it)"
                )
            return path
    return None
