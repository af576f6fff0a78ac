"""The fit specification: checks naming the field, the JSON round trip, the command
line generated from its fields, and a campaign's catalog keyed on it. Fast: no fit."""

from __future__ import annotations

import inspect
import json
import re
import subprocess
import sys
from typing import ClassVar

import pytest
from _paths import REPO

from bayestribo.cli.main import build_parser
from bayestribo.errors import BayestriboError
from bayestribo.inference.spec import FitSpec, spec_fields

#: The sub-commands that fit, each taking every option of the specification.
FITTING = ("fit", "campaign", "report", "check")


def test_the_field_table_imports_no_numpy():
    code = (
        "import sys; import bayestribo.inference.spec, bayestribo.cli._spec; "
        "print(sorted(m for m in ('numpy', 'scipy') if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True
    )
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"model": "approx"}, r"model: expected one of \('exact', 'averaged'\)"),
        ({"n_walkers": 1}, r"n_walkers: expected an integer >= 2"),
        ({"max_steps": 10}, r"max_steps: expected an integer >= 50"),
        ({"seed": -1}, r"seed: expected a non-negative integer"),
        ({"notch_Hz": "often"}, r"notch_Hz: expected a mains frequency"),
        ({"discrepancy": "yes"}, r"discrepancy: expected True or False"),
        ({"law": "viscous+friction"}, r"law: .*friction"),
        ({"priors": {"zetta": {"type": "Uniform", "low": 0, "high": 1}}}, r"'zetta'.*'zeta'"),
        ({"priors": {"zeta": {"type": "Uniform", "low": 1, "high": 0}}}, r"priors\['zeta'\]"),
        ({"fixed": {"mu_k": "a lot"}}, r"fixed\['mu_k'\]: expected a finite number"),
        ({"law": "auto", "fixed": {"zeta": 0.0}}, r"fixed: .*not law='auto'"),
        ({"colour": 1}, r"unknown field\(s\) 'colour'"),
        ({"restoring": "spring"}, r"restoring: expected one of linear, pendulum, duffing, auto"),
    ],
)
def test_a_bad_value_is_refused_naming_its_field(changes, message):
    with pytest.raises(BayestriboError, match=message):
        FitSpec.of(**changes)


def test_the_json_round_trip_keeps_every_field_in_order():
    spec = FitSpec(
        law="coulomb+viscous",
        priors={"zeta": {"type": "Normal", "mu": 0.02, "sigma": 0.01}},
        fixed={"mu_s_ratio": 1.5},
        seed=None,
        notch_Hz="auto",
        read_options={"columns": ["time_s", "displacement_m"], "metadata": {"load_N": 0.3}},
        restoring="pendulum",
    )
    assert spec.law == "viscous+coulomb"  # canonical
    text = spec.to_json()
    assert list(json.loads(text)) == [f.name for f in spec_fields()]
    assert FitSpec.from_json(text) == spec and FitSpec.from_json(text).to_json() == text
    # the restoring force has one place, whichever way it is given
    lifted = FitSpec(read_options={"metadata": {"restoring": "pendulum"}})
    assert lifted.restoring == "pendulum" and lifted.read_options.metadata is None
    assert lifted.reading().metadata == {"restoring": "pendulum"}


def test_fit_keywords_are_the_specifications_with_its_defaults():
    from bayestribo.inference.fitting import fit
    from bayestribo.inference.likelihood import MODELS
    from bayestribo.inference.spec import MODELS as SPEC_MODELS

    assert SPEC_MODELS == MODELS
    params = inspect.signature(fit).parameters
    for f in spec_fields():
        keyword = f.metadata["keyword"] or f.name
        assert keyword in params, keyword
        if f.default is not __import__("dataclasses").MISSING:
            assert params[keyword].default == f.default, keyword


def _flags(command: str) -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(getattr(a, "choices", None), dict))
    return {flag for action in sub.choices[command]._actions for flag in action.option_strings}


@pytest.mark.parametrize("command", FITTING)
def test_every_fitting_command_takes_every_option_of_the_specification(command):
    from bayestribo.cli._spec import SPEC_FLAGS

    assert set(SPEC_FLAGS) <= _flags(command)


def test_the_command_line_gives_the_python_specification(tmp_path):
    from bayestribo.cli._spec import spec_from_args

    python = FitSpec(
        law="viscous+coulomb",
        model="averaged",
        priors={"zeta": {"type": "Uniform", "low": 0.0, "high": 0.1}},
        fixed={"mu_s_ratio": 2.0},
        discrepancy=True,
        seed=5,
        n_walkers=24,
        n_ensembles=3,
        max_steps=5000,
        grid_points=80,
        skip_oscillations=2,
        notch_Hz=50.0,
        correct_channels=False,
        restoring="pendulum",
        read_options={"columns": ["time_s", "displacement_m"], "metadata": {"load_N": 0.3}},
    )
    argv = (
        "--law viscous+coulomb --model averaged --prior zeta=Uniform(0,0.1) "
        "--fix mu_s_ratio=2 --discrepancy --seed 5 --walkers 24 --ensembles 3 "
        "--max-steps 5000 --grid-points 80 --skip 2 --notch 50 --no-channel-correction "
        "--restoring pendulum --columns t x --load 0.3"
    ).split()
    for command in FITTING:
        args = build_parser().parse_args([command, "somewhere", *argv])
        assert spec_from_args(args, command) == python, command
    # the same from a file, and an option given over it
    path = tmp_path / "spec.json"
    path.write_text(python.to_json())
    args = build_parser().parse_args(["fit", "x.csv", "--spec", str(path), "--seed", "7"])
    assert spec_from_args(args, "fit") == python.replace(seed=7)


@pytest.mark.parametrize("command", FITTING)
def test_every_fitting_command_takes_restoring_auto(command):
    from bayestribo.cli._spec import spec_from_args

    args = build_parser().parse_args([command, "somewhere", "--restoring", "auto"])
    spec = spec_from_args(args, command)
    assert spec.restoring == "auto" and spec.reading().metadata == {"restoring": "auto"}
    assert FitSpec.from_json(spec.to_json()) == spec


def test_a_bad_restoring_force_on_the_command_line_names_the_choices(capsys):
    from bayestribo.cli.main import main

    with pytest.raises(SystemExit):
        main(["fit", "x.csv", "--restoring", "spring"])
    err = capsys.readouterr().err
    assert re.search(
        r"invalid choice: .spring. \(choose from .*linear.*pendulum.*duffing.*auto", err
    )


def test_an_option_a_command_cannot_use_is_refused_naming_it(capsys):
    from bayestribo.cli.main import main

    assert main(["check", "x.csv", "--walkers", "8"]) == 2
    assert "--walkers: not used by bayestribo check" in capsys.readouterr().err
    assert main(["fit", "x.csv", "--fix", "zetta=0"]) == 2
    assert "'zetta' is not a parameter" in capsys.readouterr().err


class _Saved:
    """A stand-in fit result the catalog can save and summarise."""

    converged = True
    diagnostics: ClassVar[dict] = {}

    def __init__(self, spec):
        self.spec = spec

    def save(self, path):
        path.write_text(json.dumps(self.spec))
        return path

    def summary(self):
        return {}


def _fit_spec(run, *, seed, spec):
    return _Saved(spec.to_dict())


def test_a_campaign_fit_is_not_reused_under_another_specification(tmp_path):
    from bayestribo.campaign.catalog import list_fits
    from bayestribo.campaign.fitting import fit_catalogued

    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / "r1.csv").write_text("time_s,displacement_m\n0,0\n")
    (runs / "r1.json").write_text(json.dumps({"run_id": "r1"}))
    catalog = tmp_path / "catalog.sqlite"

    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(1) as pool:

        def run(spec):
            [outcome] = fit_catalogued(
                [runs / "r1.csv"],
                catalog,
                tmp_path / "fits",
                pool,
                function=_fit_spec,
                loader=lambda p: p,
                progress=False,
                spec=spec,
            )
            return outcome

        first = run(FitSpec(max_steps=5000))
        again = run(FitSpec(max_steps=5000))
        other = run(FitSpec(max_steps=6000))
    assert not first.cached and again.cached and not other.cached
    specs = [f.settings.get("spec") for f in list_fits(catalog)]
    assert {s["max_steps"] for s in specs} == {5000, 6000}
