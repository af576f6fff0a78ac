"""numba's cache of a compiled function is discarded when its own file changes, not
when a file whose compiled functions it calls does: each such file is listed with a
digest next to its callers, so that a change of it changes the callers' files too."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from bayestribo.inference import fused, fused_residuals, fused_step

ROOT = Path(fused.__file__).resolve().parents[2]


@pytest.mark.parametrize("module", [fused, fused_residuals, fused_step], ids=lambda m: m.__name__)
def test_the_digests_of_the_compiled_dependencies_are_current(module):
    for path, digest in module.DEPENDS_ON.items():
        current = hashlib.sha256((ROOT / path).read_bytes()).hexdigest()[:16]
        assert current == digest, (
            f"{path} changed: set its digest in {module.__name__}.DEPENDS_ON to "
            f"{current!r} (numba's cache of {module.__name__} would keep the old code)"
        )
