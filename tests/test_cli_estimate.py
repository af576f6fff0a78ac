"""``bayestribo estimate``: table and JSON output, errors."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from bayestribo.cli import estimate
from bayestribo.errors import BayestriboError
from bayestribo.estimators.all import METHODS
from bayestribo.synthetic import PAPER_RIG


def _cli(argv: list[str]) -> int:
    # the command's own parser, as the dispatcher in bayestribo.cli builds it
    parser = argparse.ArgumentParser(prog="bayestribo")
    sub = parser.add_subparsers(dest="command")
    estimate.register(sub)
    args = parser.parse_args(argv)
    return args.handler(args)


@pytest.fixture(scope="module")
def run_file(tmp_path_factory) -> Path:
    from bayestribo.io import write_run
    from bayestribo.synthetic.recording import simulate

    path = tmp_path_factory.mktemp("runs") / "glycerol.csv"
    write_run(simulate(rig=PAPER_RIG, seed=5), path)
    return path


def test_json_output(run_file: Path, capsys) -> None:
    assert _cli(["estimate", str(run_file), "--json", "--skip", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["run"] == str(run_file)
    assert {e["method"] for e in out["estimates"]} == set(METHODS)
    exact = next(e for e in out["estimates"] if e["method"] == "energy_ls_exact")
    # the run's sidecar has load and mass: μ_k is given (resolution noise: 2 %)
    assert exact["mu_k"] == pytest.approx(0.0294, rel=0.02)
    assert exact["zeta"] == pytest.approx(0.0236, rel=0.01)
    log = next(e for e in out["estimates"] if e["method"] == "log_decrement")
    assert log["mu_k"] is None and log["friction_displacement"] is None


def test_table_output_and_method_subset(run_file: Path, capsys) -> None:
    assert _cli(["estimate", str(run_file), "--methods", "feeny_liang"]) == 0
    out = capsys.readouterr().out
    assert "feeny_liang" in out and "energy_ls_exact" not in out


def test_text_file_with_columns_and_arbitrary_unit(appstat_file, capsys) -> None:
    path = appstat_file("HarmOsc3.txt")
    code = _cli(["estimate", str(path), "--columns", "t,x", "--length-unit", "arbitrary", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    exact = next(e for e in out["estimates"] if e["method"] == "energy_ls_exact")
    assert exact["mu_k"] is None and exact["friction_displacement"] > 0


def test_missing_file_is_an_error(tmp_path: Path, capsys) -> None:
    from bayestribo.cli import main

    # through the dispatcher: one line on standard error, exit status 2
    assert main(["estimate", str(tmp_path / "nope.csv")]) == 2
    err = capsys.readouterr().err
    assert "bayestribo estimate: error:" in err and "nope.csv" in err


def test_unreadable_text_is_a_package_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.txt"
    path.write_text("0 1\n1 2\n")
    with pytest.raises(BayestriboError):
        _cli(["estimate", str(path), "--columns", "t", "x"])
