"""What the command line imports: building any parser imports no numpy or SciPy, ``--help``
and bad arguments stay light, ``fit`` skips ArviZ.

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

from bayestribo.cli.main import COMMANDS

#: Libraries that take longer to import than a fit takes to run.
HEAVY = ("scipy.stats", "arviz", "numba", "emcee", "xarray", "pandas", "matplotlib")
#: What building a parser (``--help`` of every command, an argument error) must not
#: import: the heavy libraries, and numpy and SciPy, whose import alone would take more
#: than the start-up a ``--help`` is allowed (1.3× ``import numpy``).
NOT_FOR_PARSING = ("numpy", "scipy", *HEAVY)
#: The package's modules that a fit does not need: the classical estimators other than
#: its starting point's (Feeny-Liang) and the simulator of recordings.
UNUSED_BY_FIT = (
    "bayestribo.estimators.all",
    "bayestribo.estimators.decrement",
    "bayestribo.estimators.energy_ls",
    "bayestribo.estimators.nonsuccessive",
    "bayestribo.synthetic",
)

#: Runs ``bayestribo.cli.main.main(argv)`` and prints the exit status and the heavy
#: modules imported, as one JSON line on standard error (stdout is the command's own).
#: With ``--as-script`` first, ``main()`` is called as the console script calls it (no
#: arguments, the command line in ``sys.argv``). Also reported: the package's modules
#: of :data:`UNUSED_BY_FIT` imported, and the collector's state after the command.
_PROBE = f"""
import gc, json, sys
from bayestribo.cli.main import main
as_script = sys.argv[1:2] == ["--as-script"]
argv = sys.argv[2:] if as_script else sys.argv[1:]
try:
    if as_script:
        sys.argv[1:] = argv
        rc = main()
    else:
        rc = main(argv)
except SystemExit as exc:
    rc = exc.code
heavy = sorted(m for m in {HEAVY!r} if m in sys.modules)
parsing = sorted(m for m in {NOT_FOR_PARSING!r} if m in sys.modules)
unused = sorted(m for m in {UNUSED_BY_FIT!r} if m in sys.modules)
probe = {{"rc": rc, "heavy": heavy, "parsing": parsing, "unused": unused,
          "gc_enabled": gc.isenabled(), "frozen": gc.get_freeze_count()}}
sys.stderr.write("\\nPROBE " + json.dumps(probe) + "\\n")
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
    assert "bayestribo.synthetic" not in probe["unused"]


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("how", ["--help", "--no-such-option"])
def test_building_every_commands_parser_imports_no_numpy_scipy_or_heavy_library(
    command, how, tmp_path
):
    # bayestribo COMMAND --help prints the help; an unknown option is an argument error:
    # either way every parser was built (the format, restoring-force and law choices
    # from their registries' light tables), nothing run
    probe, out = _probe(command, how, cwd=str(tmp_path))
    assert probe["rc"] == (0 if how == "--help" else 2)
    assert probe["parsing"] == [], f"bayestribo {command} {how} imported {probe['parsing']}"
    if how == "--help":
        assert f"bayestribo {command}" in out


def test_a_format_and_a_restoring_force_registered_at_run_time_are_choices_of_the_parser():
    # register_format and register_restoring before the parser is built: --format and
    # --restoring offer them, and still no reader, no force and no numpy is imported
    code = (
        "import sys\n"
        "from bayestribo.cli.main import build_parser\n"
        "from bayestribo.io.registry import BUILTIN_MODULES, FileFormat, register_format\n"
        "from bayestribo.model.restoring import RestoringForce, register_restoring\n"
        "register_format(FileFormat('labrig', 'our rig', ('.rig',), lambda p, o: {}))\n"
        "register_restoring(RestoringForce('softspring', 'our spring', lambda y: 0.5 * y * y,"
        " lambda a: 1.0 + 0.0 * a))\n"
        "parser = build_parser()\n"
        "sub = parser._subparsers._group_actions[0].choices['fit']\n"
        "actions = {a.dest: a for a in sub._actions}\n"
        "assert actions['format'].choices[-1] == 'labrig', actions['format'].choices\n"
        "assert 'softspring' in actions['restoring'].choices, actions['restoring'].choices\n"
        "assert 'labrig: our rig' in actions['format'].help\n"
        "loaded = [m for m in (*BUILTIN_MODULES, 'numpy', 'scipy') if m in sys.modules]\n"
        "assert not loaded, loaded\n"
    )
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr


def test_fit_imports_no_arviz_xarray_pandas_or_matplotlib(tmp_path):
    probe, out = _probe("fit", str(RUNS / "air-r1.csv"), "--json", "--seed", "2", cwd=str(tmp_path))
    assert probe["rc"] == 0
    record = json.loads(out)
    assert record["diagnostics"]["converged"] is True and record["seed"] == 2
    assert not {"arviz", "xarray", "pandas", "matplotlib"} & set(probe["heavy"])
    assert probe["unused"] == [], f"a fit imported {probe['unused']}"
    # called in a process of its caller: the collector is left as it was, nothing frozen
    assert probe["gc_enabled"] is True and probe["frozen"] == 0


def test_the_fit_command_freezes_its_imports_only_in_a_process_it_owns(tmp_path):
    # As the console script: the fitting machinery is imported with the collector
    # paused, which runs again after it, and what the imports made is frozen
    # (hundreds of thousands of objects no collection of the fit scans again).
    probe, out = _probe(
        "--as-script", "fit", str(RUNS / "air-r1.csv"), "--json", "--seed", "2", cwd=str(tmp_path)
    )
    assert probe["rc"] == 0 and json.loads(out)["seed"] == 2
    assert probe["gc_enabled"] is True
    assert probe["frozen"] > 100_000
    assert probe["unused"] == []


def test_the_estimators_reexports_are_the_functions_whatever_was_imported_first():
    # Lazily re-exported names, and feeny_liang whose module has its name, after each
    # method's module was imported directly (a fresh interpreter: nothing imported
    # before the probe).
    code = (
        "import inspect, importlib\n"
        "for m in ('all', 'decrement', 'energy_ls', 'feeny_liang', 'nonsuccessive', 'result'):\n"
        "    importlib.import_module('bayestribo.estimators.' + m)\n"
        "import bayestribo.estimators as e\n"
        "from bayestribo.estimators import feeny_liang\n"
        "bad = [n for n in e.__all__ if inspect.ismodule(getattr(e, n))]\n"
        "assert callable(feeny_liang) and not inspect.ismodule(feeny_liang), feeny_liang\n"
        "assert not bad, bad\n"
    )
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
    }
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
