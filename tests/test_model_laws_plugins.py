"""A dissipation term offered by an installed package reaches every command.

A lab's package is written here as a folder on the path: its module defines a quadratic
drag term and registers it, and its ``.dist-info`` declares the module under the entry
point group ``bayestribo.terms`` (:data:`bayestribo.model.laws.base.PLUGIN_GROUP`), as
``pip install`` of a package with ``[project.entry-points."bayestribo.terms"]`` in its
``pyproject.toml`` would. Each command runs in a fresh process, as a user's does (and as
a report's kernel does): nothing of this test's process is shared with it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from _paths import REPO, RUNS

LAB_MODULE = '''
"""A lab's quadratic drag, registered on import."""
import math

import numba
import numpy as np

from bayestribo.model.laws import Parameter, Term, register_term


@numba.njit(cache=False)
def force(w, c):
    return c[0] * w * abs(w)


def physical(values, reference, scale):
    return {}


LAB_QUAD = register_term(
    Term(
        name="lab_quad",
        kind="drag",
        parameters=(
            Parameter(
                "lab_g", "g", "1/y", 0.0, math.inf, "a lab's quadratic drag",
                lambda amplitude: {"type": "Uniform", "low": 0.0, "high": 1.0 / amplitude},
            ),
        ),
        n_coefficients=1,
        force=force,
        coefficients=lambda values, reference: [np.asarray(values["lab_g"], dtype=float)],
        dissipation=lambda a, values, reference: (
            (8.0 / 3.0) * np.asarray(values["lab_g"]) * np.asarray(a, dtype=float) ** 3
        ),
        physical=physical,
        description="a lab's quadratic drag",
        overlaps=("quadratic",),
    )
)
'''


def _package(site: Path, module: str, entry: str) -> None:
    """Write the module ``labdrag`` and the metadata that offers ``entry``."""
    (site / "labdrag").mkdir(parents=True)
    (site / "labdrag" / "__init__.py").write_text(textwrap.dedent(module))
    info = site / "labdrag-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: labdrag\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[bayestribo.terms]\nlab_quad = {entry}\n")


def _run(site: Path, *argv: str, cwd: Path) -> subprocess.CompletedProcess:
    path = os.pathsep.join([str(site), str(REPO), os.environ.get("PYTHONPATH", "")])
    env = {**os.environ, "PYTHONPATH": path}
    return subprocess.run(
        [sys.executable, *argv], capture_output=True, text=True, env=env, cwd=cwd, timeout=600
    )


def test_an_installed_packages_term_is_listed_and_compared(tmp_path):
    site = tmp_path / "site"
    _package(site, LAB_MODULE, "labdrag")
    listed = _run(site, "-m", "bayestribo", "laws", "--json", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    terms = {t["term"] for t in json.loads(listed.stdout)}
    assert {"viscous", "coulomb", "lab_quad"} <= terms
    # auto's candidates are built from the registry: the term is compared with no edit
    code = "from bayestribo.model.laws.candidates import candidate_laws; print(candidate_laws())"
    candidates = _run(site, "-c", code, cwd=tmp_path)
    assert candidates.returncode == 0, candidates.stderr
    assert "'lab_quad'" in candidates.stdout and "'viscous+lab_quad'" in candidates.stdout
    assert "quadratic+lab_quad" not in candidates.stdout  # the overlap it declares


@pytest.mark.validation  # a minute: numba compiles the new law's integrator afresh
def test_an_installed_packages_term_is_fitted_by_the_command_line(tmp_path):
    site = tmp_path / "site"
    _package(site, LAB_MODULE, "labdrag")
    if not RUNS.is_dir():
        pytest.skip(f"the bundled runs are absent at {RUNS}")
    argv = ["-m", "bayestribo", "fit", str(RUNS / "air-r1.csv"), "--law", "viscous+lab_quad"]
    fitted = _run(site, *argv, "--max-steps", "400", "--json", cwd=tmp_path)
    assert fitted.returncode in (0, 1), fitted.stderr
    out = json.loads(fitted.stdout)
    assert out["law"] == "viscous+lab_quad"
    assert {"zeta", "lab_g"} <= set(out["parameters"])


def test_a_term_object_as_the_entry_point_is_registered(tmp_path):
    site = tmp_path / "site"
    module = LAB_MODULE.replace("LAB_QUAD = register_term(", "LAB_QUAD = (")
    _package(site, module, "labdrag:LAB_QUAD")
    code = "from bayestribo.model.laws import get_law; print(get_law('coulomb+lab_quad').name)"
    done = _run(site, "-c", code, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "coulomb+lab_quad"


def test_a_broken_plugin_is_named_and_the_built_in_laws_still_work(tmp_path):
    site = tmp_path / "site"
    _package(site, "raise RuntimeError('the lab module is broken')\n", "labdrag")
    code = (
        "import warnings\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        "    from bayestribo.model.laws import TERMS, get_law\n"
        "    print(sorted(TERMS), get_law('viscous+coulomb').name)\n"
        "for w in caught:\n"
        "    print(w.category.__name__, w.message)\n"
    )
    done = _run(site, "-c", code, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "viscous+coulomb" in done.stdout and "lab_quad" not in done.stdout.split("\n")[0]
    assert "PluginWarning the dissipation term plug-in lab_quad = labdrag" in done.stdout
    assert "(package labdrag)" in done.stdout and "the lab module is broken" in done.stdout


LAB_MODULE_SI = LAB_MODULE.replace(
    """def physical(values, reference, scale):
    return {}""",
    """def physical(values, reference, scale):
    g = np.asarray(values["lab_g"], dtype=float)
    if scale.mass is None:
        return {}
    return {"lab_g_SI": (g / scale.length_scale * scale.mass, "kg/m", "g", "a lab's drag")}""",
)


@pytest.mark.validation  # minutes: numba compiles the new law afresh, then a notebook runs
def test_an_installed_packages_term_reaches_a_campaign_and_its_report(tmp_path):
    # runs with quadratic drag simulated by the package's solve_ivp path from the
    # built-in term (not the lab's), fitted and reported in the lab's law by the commands
    # a user types, each in a fresh process with the lab's package installed
    pytest.importorskip("nbclient")
    import math

    from bayestribo.io import write_run
    from bayestribo.model.scaling import Rig
    from bayestribo.synthetic.recording import simulate
    from bayestribo.synthetic.setup import LawParameters, Release

    site = tmp_path / "site"
    _package(site, LAB_MODULE_SI, "labdrag")
    mass, frequency, c2_si = 0.035, 32.6, 0.5
    stiffness = mass * (2 * math.pi * frequency) ** 2
    data, out = tmp_path / "data", tmp_path / "out"
    data.mkdir()
    for load in (0.1, 0.3):
        for repeat in (1, 2):
            gamma = c2_si * (load / stiffness) / mass  # c₂ℓ/m, ℓ = N/k
            run_id = f"oil-N{load}-r{repeat}"
            run = simulate(
                LawParameters("viscous+quadratic", {"zeta": 0.004, "c2": gamma}),
                rig=Rig(frequency, mass, load),
                release=Release(initial_displacement_m=1e-3, motion_duration_s=1.2),
                seed=10 * repeat + int(10 * load),
                metadata={"run_id": run_id, "lubricant": "oil", "series": "oil", "repeat": repeat},
            )
            write_run(run, data / f"{run_id}.csv")
    argv = ["-m", "bayestribo", "campaign", str(data), "--out", str(out), "--json", "--quiet"]
    argv += ["--law", "viscous+lab_quad", "--max-steps", "3000", "--workers", "1"]
    done = _run(site, *argv, cwd=tmp_path)
    assert done.returncode in (0, 1), done.stderr
    campaign = json.loads(done.stdout)
    assert list(campaign["quantities"]) == ["zeta", "lab_g_SI"]
    assert campaign["quantities"]["lab_g_SI"]["unit"] == "kg/m"
    for group in campaign["contact"]["groups"]:
        mean = group["parameters"]["lab_g_SI"]["mean"]
        assert mean["interval"][0] <= c2_si <= mean["interval"][1], group["label"]
    html = tmp_path / "report.html"
    reported = _run(site, "-m", "bayestribo", "report", str(out), "--out", str(html), cwd=tmp_path)
    assert reported.returncode == 0, reported.stderr
    text = html.read_text(encoding="utf-8")
    assert "Traceback" not in text and "KeyError" not in text
    for heading in ("1. One fit per run", "4. Each quantity against load", "7. Energy loss"):
        assert heading in text, heading
    assert "g [kg/m]" in text and "μ_k [" not in text  # the term's own symbol and unit
