"""``bayestribo simulate --law NAME``: any law of the registry, its motion by the
independent solver, and fits of the simulated files that recover the truth."""

from __future__ import annotations

import json
import math
import re
import warnings
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pytest

from bayestribo import fit, read_run
from bayestribo.cli import main
from bayestribo.model.laws import TERMS, Parameter, Term, register_term
from bayestribo.synthetic import LawParameters, Release, simulate

#: 30 times the vibrometer's resolution, 5 kHz: a realistic record, fitted fast.
SENSOR = [
    "--sample-rate",
    "5000",
    "--displacement-noise",
    "4.5e-6",
    "--velocity-noise",
    "4.5e-7",
]
CASES = {
    "viscous+quadratic": (
        ["--param", "zeta=0.01", "--param", "c2=0.005", "--motion-duration", "1.5"],
        ["--x0", "1.5e-3"],
        ("zeta", "c2", "c2_SI"),
    ),
    "coulomb+power": (
        ["--param", "mu_k=0.015", "--param", "mu_s_ratio=1.5"],
        ["--param", "zeta_alpha=0.01", "--param", "alpha=1.5", "--x0", "1.5e-3"],
        # ζ_α is at the simulator's reference amplitude (x₀), the fit's at its observed
        # |y0|: the physical coefficient c_α is the one they share
        ("mu_k", "alpha", "c_alpha_SI"),
    ),
}


def _simulate(path: Path, law: str, *extra: str, seed: int = 1) -> dict:
    argv = ["simulate", str(path), "--law", law, *extra, *SENSOR, "--seed", str(seed)]
    assert main(argv) == 0
    return json.loads(path.with_suffix(".json").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def simulated(
    tmp_path_factory: pytest.TempPathFactory,
) -> Callable[[str], tuple[Path, dict]]:
    """``simulated(law)``: the file of a law of :data:`CASES` and its sidecar, each
    simulated once, by the command line, when first asked for."""
    folder = tmp_path_factory.mktemp("laws")
    made: dict[str, tuple[Path, dict]] = {}

    def get(law: str) -> tuple[Path, dict]:
        if law not in made:
            first, second, _ = CASES[law]
            path = folder / f"{law.replace('+', '_')}.csv"
            made[law] = (path, _simulate(path, law, *first, *second))
        return made[law]

    return get


@pytest.mark.parametrize("law", list(CASES))
def test_a_fit_of_the_simulated_file_recovers_the_truth(law: str, simulated) -> None:
    path, sidecar = simulated(law)
    truth = sidecar["simulation"]
    values = {name: p["value"] for name, p in truth["parameters"].items()}
    values.update({name: p["value"] for name, p in truth["physical"].items()})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(path, law=law, seed=1, max_steps=3000)
    assert result.converged
    assert not [w for w in caught if "Misfit" in w.category.__name__]
    summary = result.summary()
    for name in CASES[law][2]:
        lo, hi = summary[name].interval  # 95 %
        assert lo < values[name] < hi, (name, values[name], lo, hi)


def test_the_sidecar_says_which_solver_made_the_motion_and_the_law_with_units(
    simulated,
) -> None:
    path, sidecar = simulated("coulomb+power")
    truth = sidecar["simulation"]
    assert truth["law"] == "coulomb+power"
    assert truth["solver"].startswith("scipy.integrate.solve_ivp")
    assert "independent of the fit" in truth["solver"]
    assert truth["parameters"]["mu_k"] == {"value": 0.015, "unit": "y", "symbol": "μ_k"}
    assert truth["parameters"]["alpha"]["value"] == 1.5
    assert truth["reference_amplitude_m"] == 1.5e-3
    # the law's own quantities in SI: x_c = μ_k ℓ with ℓ = N/k
    assert truth["physical"]["friction_displacement"]["unit"] == "m"
    x_c = truth["physical"]["friction_displacement"]["value"]
    assert x_c == pytest.approx(0.015 * truth["length_scale_m"])
    assert truth["stopped"] and truth["half_cycles"] > 50
    # the run reads back, its sidecar accepted as it is
    run = read_run(path)
    assert run.metadata["simulation"] == truth


def test_a_default_parameter_takes_its_typical_value(capsys: pytest.CaptureFixture) -> None:
    law = LawParameters("viscous+coulomb", {"zeta": 0.01})
    assert dict(law.values) == {"zeta": 0.01, "mu_k": 0.0294, "mu_s_ratio": 1.0}
    # which the registry's listing shows (None: none is typical, it must be given)
    assert main(["laws", "--json"]) == 0
    typical = {
        p["name"]: p["typical"]
        for term in json.loads(capsys.readouterr().out)
        for p in term["parameters"]
    }
    assert typical["zeta"] == 0.0236 and typical["c2"] is None


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (
            ["--law", "viscous+quadratic", "--param", "zeta=0.01"],
            r"--param: .*needs a value of c2 \[1/y\]",
        ),
        (["--law", "viscous+quadratic", "--param", "c2=abc"], r"--param c2=abc: expected a number"),
        (["--law", "viscous+quadratic", "--param", "c2"], r"--param 'c2': expected NAME=VALUE"),
        (
            ["--law", "viscous+quadratic", "--param", "c=1"],
            r"no parameter 'c'; its parameters: zeta \[-\]",
        ),
        (["--law", "viscous+quadratic", "--param", "c2=-1"], r"c2 \[1/y\].* in \[0, inf\], got -1"),
        (
            ["--law", "viscous", "--param", "zeta=1", "--param", "zeta=2"],
            r"--param zeta is given twice",
        ),
        (["--law", "viscous+drag"], r"--law viscous\+drag: unknown dissipation term 'drag'"),
        (["--law", "auto"], r"--law auto: a simulation needs one law"),
        (["--law", "coulomb", "--mu-k", "0.02"], r"--mu-k sets the default law's parameter"),
        (["--param", "zeta=0.01"], r"--param zeta=0.01: .*give the law with --law"),
        (["--law", "coulomb", "--load", "0"], r"friction, which needs a load: load_N"),
        (["--law", "viscous"], r"never stops .*motion_duration_s"),
    ],
)
def test_bad_law_arguments_name_the_argument_and_what_was_expected(
    argv: list[str], match: str, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    assert main(["simulate", str(tmp_path / "x.csv"), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bayestribo simulate: error: ")
    assert re.search(match, err), err
    assert not (tmp_path / "x.csv").exists()


# -- a term a lab registers in its own module ---------------------------------------------


@numba.njit(cache=True)
def _lab_force(w: float, c: np.ndarray) -> float:
    return c[0] * w * w


LAB_DRAG = Term(
    name="lab_drag",
    kind="drag",
    parameters=(
        Parameter(
            "lab_gamma",
            "γ_lab",
            "1/y",
            0.0,
            math.inf,
            "a lab's quadratic drag",
            lambda amplitude: {"type": "Uniform", "low": 0.0, "high": 1.0 / amplitude},
        ),
        Parameter(
            "lab_scale",
            "s_lab",
            "-",
            0.0,
            10.0,
            "a factor on it",
            lambda amplitude: {"type": "Uniform", "low": 0.0, "high": 10.0},
            typical=1.0,
        ),
    ),
    n_coefficients=1,
    force=_lab_force,
    coefficients=lambda values, reference: [
        np.asarray(values["lab_gamma"], dtype=float) * np.asarray(values["lab_scale"])
    ],
    dissipation=lambda a, values, reference: (
        (8.0 / 3.0)
        * np.asarray(values["lab_gamma"])
        * np.asarray(values["lab_scale"])
        * np.asarray(a, dtype=float) ** 3
    ),
    physical=lambda values, reference, scale: {},
    description="a lab's quadratic drag",
)


@pytest.fixture
def lab_term():
    register_term(LAB_DRAG)
    try:
        yield LAB_DRAG
    finally:
        TERMS.remove(LAB_DRAG.name)


def test_a_law_registered_in_a_lab_module_simulates_without_edits(lab_term, tmp_path) -> None:
    common = ["--param", "zeta=0.01", "--motion-duration", "0.3", "--sample-rate", "2000"]
    lab = _simulate(tmp_path / "lab.csv", "viscous+lab_drag", *common, "--param", "lab_gamma=0.005")
    assert lab["simulation"]["law"] == "viscous+lab_drag"
    assert lab["simulation"]["parameters"]["lab_gamma"]["unit"] == "1/y"
    assert lab["simulation"]["parameters"]["lab_scale"]["value"] == 1.0  # its typical value
    # the same force as the built-in quadratic drag: the same file
    _simulate(tmp_path / "builtin.csv", "viscous+quadratic", *common, "--param", "c2=0.005")
    assert (tmp_path / "lab.csv").read_bytes() == (tmp_path / "builtin.csv").read_bytes()
    # and from Python, with the parameter it has no typical value for named
    with pytest.raises(ValueError, match=r"needs a value of lab_gamma \[1/y\]"):
        simulate(LawParameters("lab_drag", {}), release=Release(motion_duration_s=0.1))
