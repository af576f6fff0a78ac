"""The campaign report of a campaign fitted in another law than the paper's.

Two loads × two repeats of a rig with viscous damping and quadratic drag (c₂ = 0.5 kg/m
at both loads), simulated by ``solve_ivp`` (:class:`bayestribo.synthetic.LawParameters`),
fitted by ``bayestribo campaign --law viscous+quadratic`` with short samplers, then
reported by ``bayestribo report``: every section renders, in ζ and c₂ [kg/m] from the
law registry, never reading μ_k; ζ₀, ζ_k and d_k are said not to apply (no run in air);
the load trends have their band; ΔE(A) is drawn per group. One notebook run (about half
a minute) on top of the campaign's four short fits.
"""

from __future__ import annotations

import json
import math

import pytest

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli.main import main
from bayestribo.reports.kit import FIGURE_PROBLEMS

MASS, FREQUENCY = 0.035, 32.6
C2_SI = 0.5  # quadratic drag [kg/m]


def _simulate(folder):
    from bayestribo.io import write_run
    from bayestribo.model.scaling import Rig
    from bayestribo.synthetic.recording import simulate
    from bayestribo.synthetic.setup import LawParameters, Release

    stiffness = MASS * (2 * math.pi * FREQUENCY) ** 2
    for load in (0.1, 0.3):
        for repeat in (1, 2):
            # c₂ in the registry's units is c₂ℓ/m, ℓ = N/k: the same c₂ [kg/m] at both loads
            gamma = C2_SI * (load / stiffness) / MASS
            law = LawParameters(
                "viscous+quadratic", {"zeta": 0.004 * (1 + 0.03 * repeat), "c2": gamma}
            )
            run_id = f"oil-N{load}-r{repeat}"
            run = simulate(
                law,
                rig=Rig(FREQUENCY, MASS, load),
                release=Release(initial_displacement_m=1e-3, motion_duration_s=1.2),
                seed=10 * repeat + int(10 * load),
                metadata={"run_id": run_id, "lubricant": "oil", "series": "oil", "repeat": repeat},
            )
            write_run(run, folder / f"{run_id}.csv")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("drag-campaign")
    data, out = tmp / "data", tmp / "out"
    data.mkdir()
    _simulate(data)
    argv = ["campaign", str(data), "--out", str(out), "--law", "viscous+quadratic"]
    argv += ["--max-steps", "1500", "--population-steps", "600", "--workers", "1", "--quiet"]
    assert main(argv) in (0, 1)  # short population samplers may not converge
    html, summary = tmp / "report.html", tmp / "summary.json"
    argv = ["report", str(out), "--out", str(html), "--figure-format", "png"]
    assert main([*argv, "--param", f"summary_path={summary}"]) == 0
    return html.read_text(encoding="utf-8"), json.loads(summary.read_text()), tmp


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_drag_law_campaign_report_renders_every_section_in_its_own_quantities(report):
    text, record, tmp = report
    analysis = record["analysis"]
    assert analysis["laws"] == {
        "viscous+quadratic": [f"oil-N{n}-r{r}" for n in (0.1, 0.3) for r in (1, 2)]
    }
    assert list(analysis["quantities"]) == ["zeta", "c2_SI"]
    assert "Traceback" not in text and "KeyError" not in text
    for heading in ("1. One fit per run", "4. Each quantity against load", "7. Energy loss"):
        assert heading in text, heading
    assert "c₂ [kg/m]" in text and "μ_k [" not in text
    # no run in air: ζ₀, ζ_k and d_k said not to apply, their figure left out
    assert "No converged run without contact is analysed" in text
    assert "paper, glycerol" not in text.lower()
    # the trend's band at the ends of the loads, for each quantity
    assert "mean at 0.1 N" in text and "mean at 0.3 N" in text
    figures = sorted(p.name for p in (tmp / "report-figures").iterdir())
    assert figures == [
        "against_load.png",
        "dissipation.png",
        "dissipation_against_load.png",
        "forest.png",
    ]
    for problem in FIGURE_PROBLEMS:  # every figure legible, no empty panel
        assert f": {problem}: " not in text, problem
    # ΔE at one swing every run reaches: the same rig at both loads, within 5 %
    energy = record["dissipation"]
    assert len(energy) == 4
    values = [float(row[next(k for k in row if k.startswith("ΔE"))].split()[0]) for row in energy]
    assert max(values) / min(values) < 1.05
    # the populations cover the truth: c₂ [kg/m] at each load
    for group in analysis["contact"]["groups"]:
        lo, hi = group["parameters"]["c2_SI"]["mean"]["interval"]
        assert lo < C2_SI < hi, group["label"]


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_every_interval_of_a_drag_law_campaign_report_is_the_campaigns_in_its_digits(report):
    from _report_numbers import interval_cells, unmatched

    text, _, tmp = report
    population = json.loads((tmp / "out" / "population.json").read_text())
    cells = interval_cells(text)
    assert len(cells) >= 8
    # the trend's means at the ends of its loads and each run's ΔE at a shared swing are
    # population.json's too
    for table in ("mean at ", "ΔE per cycle"):
        assert any(table in head for _, _, head in cells), table
    assert unmatched(text, population) == []
