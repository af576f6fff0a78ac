"""The command line starts without loading what only a job needs."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("scipy.stats", "scipy.optimize", "arviz", "numba", "emcee", "matplotlib")


def test_help_loads_none_of_the_heavy_modules():
    """``bayestribo --help`` (and each command's ``--help``) lists the commands and
    their choices (the estimators' names, the laws') without SciPy's statistics and
    optimisers, ArviZ, numba, emcee or matplotlib."""
    code = (
        "import json, sys, contextlib, io\n"
        "from bayestribo.cli import main\n"
        "for argv in (['--help'], ['estimate', '--help'], ['fit', '--help']):\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        try:\n"
        "            main(argv)\n"
        "        except SystemExit:\n"
        "            pass\n"
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


def test_the_command_line_lists_every_estimator():
    from bayestribo.cli.estimate import METHOD_NAMES
    from bayestribo.estimators.all import METHODS

    assert METHOD_NAMES == METHODS


def test_a_full_disk_is_one_line_naming_what_to_do(monkeypatch, capsys):
    import errno

    from bayestribo.cli import main

    def full():
        raise OSError(errno.ENOSPC, "No space left on device", "out/population.json")

    monkeypatch.setattr("bayestribo.cli.laws.law_table", full)
    assert main(["laws"]) == 2
    err = capsys.readouterr().err
    assert "no space left on the device writing out/population.json" in err
    assert "Traceback" not in err
