"""Reading and writing runs: canonical CSV + JSON sidecar and every registered file format.

See ``docs/run-format.md`` for the canonical format and :mod:`bayestribo.io.registry`
for the formats read.
"""

from bayestribo.io.files import READ_OPTIONS, ReadOptions, as_run, read_run, write_run
from bayestribo.io.registry import FileFormat, register_format, registered_formats
from bayestribo.io.validation import validate_run

__all__ = [
    "READ_OPTIONS",
    "FileFormat",
    "ReadOptions",
    "as_run",
    "read_run",
    "register_format",
    "registered_formats",
    "validate_run",
    "write_run",
]
