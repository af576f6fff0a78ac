"""Reading and writing runs: canonical CSV + JSON sidecar and every registered file format.

See ``docs/run-format.md`` for the canonical format and :mod:`bayestribo.io.registry`
for the formats read. The names below are re-exported lazily: importing the package (or
its light modules :mod:`~bayestribo.io.registry` and :mod:`~bayestribo.io.options`, as
the command line does to build its options) imports no reader, numpy or SciPy.
"""

from __future__ import annotations

from bayestribo._lazy import lazy_exports

_LAZY: dict[str, str] = {
    "READ_OPTIONS": "bayestribo.io.options",
    "FileFormat": "bayestribo.io.registry",
    "ReadOptions": "bayestribo.io.options",
    "as_run": "bayestribo.io.files",
    "read_run": "bayestribo.io.files",
    "register_format": "bayestribo.io.registry",
    "registered_formats": "bayestribo.io.registry",
    "validate_run": "bayestribo.io.validation",
    "write_run": "bayestribo.io.files",
}

__all__ = sorted(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
