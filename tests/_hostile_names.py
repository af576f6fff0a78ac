"""Names that hold markup, for the report tests (``test_reports_pages.py``).

Every payload sets the page's title to ``PWNED`` if a page ever shows it as markup.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

PAYLOAD = "document.title='PWNED'"
#: A lubricant, a series or a sidecar's field.
HOSTILE_SCRIPT = f"<script>{PAYLOAD}</script>"
#: A word of a file name (no "/": a file name cannot hold one).
HOSTILE_FILE_WORD = f"<svg onload={PAYLOAD}>"
#: A sidecar's field or a README's text.
HOSTILE_FIELD = f"<img src=x onerror={PAYLOAD}>"


def hostile_copy(source: Path, folder: Path, stem: str, **fields: object) -> Path:
    """A copy of a bundled run and its sidecar named ``stem``, with ``fields`` set in the
    sidecar (a field set to None is removed)."""
    csv = folder / f"{stem}.csv"
    shutil.copyfile(source, csv)
    meta = json.loads(source.with_suffix(".json").read_text())
    meta.update(fields)
    meta = {k: v for k, v in meta.items() if v is not None}
    csv.with_suffix(".json").write_text(json.dumps(meta))
    return csv
