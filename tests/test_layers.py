"""The layers of docs/architecture.md hold: a sub-package imports only from below it."""

from __future__ import annotations

import ast
from pathlib import Path

import bayestribo

PACKAGE = Path(bayestribo.__file__).resolve().parent

#: What each part of the package may import (besides itself), as drawn in
#: docs/architecture.md. The shared bottom (errors, summary, _optional, _text, _plural,
#: _clock, _stamps, _workers, ...) is open to all.
BOTTOM = {
    "errors",
    "summary",
    "_optional",
    "_text",
    "_plural",
    "_clock",
    "_stamps",
    "_workers",
    "_warnings",
    "_lazy",
    "_files",
}
#: Every part below the top layer (cli/ and reports/).
_BELOW_THE_TOP = (
    "model",
    "io",
    "synthetic",
    "signal",
    "estimators",
    "inference",
    "population",
    "adequacy",
    "campaign",
    "acquisition",
)
ALLOWED = {
    "model": set(),
    "io": {"model", "signal"},
    "synthetic": {"model", "io"},
    "signal": {"model"},
    "estimators": {"model", "io", "signal"},
    "inference": {"model", "io", "signal", "estimators"},
    "population": {"inference"},
    "adequacy": {"model", "io", "signal", "inference"},
    "campaign": {"model", "io", "inference", "population"},
    "acquisition": {"model", "io", "campaign"},
    # the top layer, beside cli/: a report's helpers speak of laws and fits as the
    # notebooks that import them do
    "reports": set(_BELOW_THE_TOP),
    "cli": {*_BELOW_THE_TOP, "reports"},
}


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        out |= {n.split(".")[1] for n in names if n.startswith("bayestribo.")}
    return out


def test_every_part_is_in_the_picture():
    parts = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert parts == set(ALLOWED)


def test_no_part_imports_from_above_it():
    wrong = []
    for part, allowed in ALLOWED.items():
        for path in (PACKAGE / part).rglob("*.py"):
            extra = _imports(path) - allowed - BOTTOM - {part}
            if extra:
                wrong.append(f"{path.relative_to(PACKAGE)} imports {sorted(extra)}")
    assert not wrong, "\n".join(wrong)
