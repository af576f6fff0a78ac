"""A clean terminal: one line per warning, numbers as numbers, help on every option,
no traceback when the reader of the output goes away."""

from __future__ import annotations

import argparse
import subprocess
import sys

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.cli.main import build_parser, plain_numbers
from bayestribo.io import write_run
from bayestribo.io.run import Run
from bayestribo.synthetic import simulate


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    run = simulate(seed=8)
    meta = {k: v for k, v in run.metadata.items() if k != "natural_frequency_Hz"}
    path = tmp_path_factory.mktemp("runs") / "nofreq.csv"
    return write_run(Run(run.time, run.displacement, run.velocity, meta), path)


def test_a_warning_is_one_line_without_source(run_file, capsys):
    assert main(["decay", str(run_file), "--json"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("bayestribo decay: warning: natural_frequency_Hz is not given")
    assert ".py:" not in err[0] and "warnings.warn" not in err[0]


def test_numpy_scalars_in_messages_print_as_numbers():
    assert plain_numbers("t = np.float64(0.25) s, n = np.int64(3)") == "t = 0.25 s, n = 3"
    assert plain_numbers("np.float64(nan) and np.float32(-1e-05)") == "nan and -1e-05"


def test_an_error_with_numbers_prints_them_as_numbers(tmp_path, capsys):
    t = np.arange(2000) / 1e4
    x = 1e-3 * np.cos(2 * np.pi * 32.6 * t) * np.exp(-t)
    t[1000] = t[999]  # a repeated time stamp with another value (a row written twice is read once)
    path = tmp_path / "bad.csv"
    rows = "\n".join(f"{a:.17g},{b:.17g}" for a, b in zip(t, x, strict=True))
    path.write_text("time_s,displacement_m\n" + rows + "\n", encoding="utf-8")
    assert main(["decay", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bayestribo decay: error:") and "np." not in err


def _options():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, command in sub.choices.items():
        for action in command._actions:
            if not isinstance(action, argparse._HelpAction):
                yield name, action


@pytest.mark.parametrize(
    ("command", "action"), list(_options()), ids=lambda v: getattr(v, "dest", v)
)
def test_every_option_has_help(command, action):
    assert action.help, f"{command} {action.option_strings or action.dest}"


def test_a_closed_pipe_is_no_traceback(run_file):
    # `bayestribo inspect RUN | head -1`: the reader stops after one line.
    proc = subprocess.run(
        f"{sys.executable} -m bayestribo inspect {run_file} | head -1",
        shell=True,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.stdout.startswith("file")
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr


def test_a_reader_gone_at_the_first_write_is_exit_1_without_traceback(
    run_file, monkeypatch, tmp_path
):
    """Deterministic form of ``| head``: the first write to standard output fails with
    BrokenPipeError (a kind of OSError, which must not take it for a disk error)."""

    sink = (tmp_path / "sink").open("w")

    class GoneReader:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            pass

        def fileno(self):
            return sink.fileno()

    monkeypatch.setattr(sys, "stdout", GoneReader())
    try:
        assert main(["inspect", str(run_file)]) == 1
    finally:
        sink.close()
