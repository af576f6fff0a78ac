"""Reading and writing runs: canonical CSV + JSON sidecar, delimited text, UFF 58, TDMS.

See ``docs/run-format.md`` for the canonical format.
"""

from bayestribo.io.files import FORMATS, READ_OPTIONS, as_run, read_run, write_run
from bayestribo.io.validation import validate_run

__all__ = ["FORMATS", "READ_OPTIONS", "as_run", "read_run", "validate_run", "write_run"]
