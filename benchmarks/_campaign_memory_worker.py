"""One ``bayestribo campaign`` in this process; its peak resident memory on stderr.

Used by ``benchmarks/campaign_memory.py`` (``PYTHONPATH`` selects the tree). Prints
``MEMORY {"maxrss_kB": ...}`` as the last line of standard error: the peak resident
memory of this process alone (the fitting workers are other processes).
"""

from __future__ import annotations

import json
import resource
import sys

from bayestribo.cli import main

if __name__ == "__main__":
    status = main(["campaign", *sys.argv[1:]])
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print("MEMORY " + json.dumps({"maxrss_kB": peak, "status": status}), file=sys.stderr)
