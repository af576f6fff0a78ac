"""The bundled oil series in a campaign in any law: ``law="auto"`` on one load's repeats.

The oil runs of ``data/`` follow viscous damping, quadratic drag and Coulomb friction
(simulated by solve_ivp, not the fit's integrator). Each run compares the laws; the
group of repeats takes one law from all of them (:mod:`bayestribo.campaign.laws`), and
the population is over that law's own quantities (ζ, μ_k and c₂ [kg/m]), whose true
values the manifest holds under the same names. One load's three repeats (the middle
load, whose comparisons are the shortest: some 4 s of CPU a run) keep the test short.

A statistical check on the bundled files (three law comparisons, some 20 s of CPU), left
out of the default run (``-m validation``: run by hand). The default run covers each of
its steps: the choice of a group's law from its runs' comparisons
(``test_campaign_group_laws.py``), a campaign over a drag law's own quantities ζ and
c₂ [kg/m] with their intervals holding the truth (``test_campaign_laws.py``), the law
comparison's verdict on bundled runs (``test_inference_comparison.py``) and ``law="auto"``
finding a law that holds on a simulated run (``test_inference_fitting.py``).
"""

from __future__ import annotations

import csv

import numpy as np
import pytest
from _paths import DATA

from bayestribo import fit
from bayestribo.campaign.analysis import analyse_campaign
from bayestribo.campaign.laws import group_laws
from bayestribo.synthetic.campaign import OIL_LAW, OIL_LOADS_N

pytestmark = [
    pytest.mark.slow,  # three law comparisons, some 20 s of CPU
    pytest.mark.validation,  # statistical: its steps are checked by default (above)
    pytest.mark.skipif(not (DATA / "manifest.csv").is_file(), reason="bundled data/ absent"),
    # a run's comparison may find no law holding beyond its noise and say so: the
    # choice and the intervals are what is tested here
    pytest.mark.filterwarnings("ignore::bayestribo.errors.MisfitWarning"),
]
BY = ("lubricant", "load_N")


@pytest.fixture(scope="module")
def repeats() -> tuple[list[dict[str, str]], list]:
    """The manifest's rows of the oil runs at the middle load, and their fits with
    ``law="auto"``."""
    with (DATA / "manifest.csv").open(newline="") as fh:
        rows = [
            r
            for r in csv.DictReader(fh)
            if r["series"] == "oil" and float(r["load_N"]) == OIL_LOADS_N[1]
        ]
    assert len(rows) == 3
    return rows, [fit(DATA / r["file"], law="auto", seed=1) for r in rows]


def test_law_auto_gives_the_true_law_and_intervals_over_its_own_quantities(repeats) -> None:
    rows, fits = repeats
    groups, law_of_run = group_laws(fits, BY)
    (group,) = groups.values()
    true_law = rows[0]["law"]
    assert true_law == OIL_LAW
    assert group.law == group.best == true_law and group.decided
    assert group.disagree == () and set(law_of_run.values()) == {true_law}

    analysis = analyse_campaign(fits, BY, seed=1, max_steps=4000)
    assert analysis.laws == {true_law: [r["run_id"] for r in rows]}
    quantities = analysis.contact.parameters
    assert set(quantities) == {"zeta", "mu_k", "c2_SI"}  # c₂ in kg/m, not c₂ℓ/m
    truth = {r["run_id"]: {q: float(r[q]) for q in quantities} for r in rows}
    # each run's estimate of each quantity is within 4 of its posterior standard
    # deviations (the 95 % half width over 1.96) of the true value: 9 checks, each
    # missed by chance with probability 6e-5
    for run in analysis.runs:
        for q in quantities:
            low, high = run[q]["interval"]
            z = (run[q]["median"] - truth[run["run_id"]][q]) / ((high - low) / (2 * 1.96))
            assert abs(z) < 4, (run["run_id"], q, z)
    # the group's population mean holds the mean of its runs' true values
    for row in analysis.group_rows():
        if row["kind"] == "contact" and row["parameter"] in quantities:
            mean = np.mean([t[row["parameter"]] for t in truth.values()])
            assert row["mean_low"] <= mean <= row["mean_high"], row["parameter"]
