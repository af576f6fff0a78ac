"""What the command line imports: ``--help`` and bad arguments stay light, ``fit`` skips
ArviZ.

Each case runs in a fresh interpreter (``python -c``) and reads ``sys.modules`` after
the command: deterministic, unlike a timing. The speed itself is measured side by side
by ``benchmarks/cli_startup.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from _paths import REPO, RUNS

#: Libraries that take longer to import than a fit takes to run.
HEAVY = ("scipy.stats", "arviz", "numba", "emcee", "xarray", "pandas", "matplotlib")

#: Runs ``bayestribo.cli.main.main(argv)`` and prints the exit status and the heavy
#: modules imported, as one JSON line on standard error (stdout is the command's own).
_PROBE = f"""
import json, sys
from bayestribo.cli.main import main
try:
    rc = main(sys.argv[1:])
except SystemExit as exc:
    rc = exc.code
heavy = sorted(m for m in {HEAVY!r} if m in sys.modules)
sys.stderr.write("\\nPROBE " + json.dumps({{"rc": rc, "heavy": heavy}}) + "\\n")
"""


def _probe(*argv: str, cwd: str) -> tuple[dict, str]:
    """Exit status and heavy modules of one command in a fresh interpreter, and its
    standard output."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=600,
    )
    line = [x for x in done.stderr.splitlines() if x.startswith("PROBE ")]
    assert line, done.stderr
    return json.loads(line[-1][len("PROBE ") :]), done.stdout


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["--version"],
        ["fit", "--help"],
        ["campaign", "--help"],
        ["fit"],  # RUN missing
        ["fit", "RUN", "--model", "bogus"],
        ["fit", "RUN", "--prob", "2"],
        ["fit", "no-such-run.csv"],
        ["bogus-command"],
    ],
)
def test_help_and_argument_errors_import_no_heavy_library(argv, tmp_path):
    argv = [str(RUNS / "air-r1.csv") if a == "RUN" else a for a in argv]
    probe, _ = _probe(*argv, cwd=str(tmp_path))
    assert probe["rc"] in (0, 2)
    assert probe["heavy"] == [], f"bayestribo {' '.join(argv)} imported {probe['heavy']}"


def test_fit_imports_no_arviz_xarray_pandas_or_matplotlib(tmp_path):
    probe, out = _probe("fit", str(RUNS / "air-r1.csv"), "--json", "--seed", "2", cwd=str(tmp_path))
    assert probe["rc"] == 0
    record = json.loads(out)
    assert record["diagnostics"]["converged"] is True and record["seed"] == 2
    assert not {"arviz", "xarray", "pandas", "matplotlib"} & set(probe["heavy"])
