"""Dissipation-law comparison by PSIS-LOO: viscous, Coulomb or both.

On the bundled simulated runs the truth is known: the test without contact has no
friction (the verdict must be viscous: "both" may be as good, never better by more
than the noise of the estimate), a glycerol run has both mechanisms (viscous only and
Coulomb only must lose clearly).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from bayestribo.errors import BayestriboError
from bayestribo.inference.comparison import LAWS, _Pinned, compare_dissipation_laws

DATA = Path(__file__).resolve().parents[1] / "data" / "runs"
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason="bundled data/ folder not present")


@needs_data
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_run_without_contact_comes_out_viscous():
    c = compare_dissipation_laws(DATA / "air-r1.csv", seed=3, max_steps=1500)
    assert c.verdict == "viscous"
    assert "coulomb" not in c.as_good
    assert c.table["coulomb"]["elpd_diff"] > 100  # friction alone cannot make an exponential decay
    assert c.to_dict()["verdict"] == "viscous"


@needs_data
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_a_glycerol_run_needs_both_mechanisms():
    c = compare_dissipation_laws(DATA / "glycerol-N0.31-r1.csv", seed=3, max_steps=1500)
    assert c.best == "both" and c.verdict == "both" and c.as_good == ["both"]
    for law in ("viscous", "coulomb"):
        assert c.table[law]["elpd_diff"] > 100
    # The losing laws' PSIS-LOO may be flagged unreliable (Pareto k); the winner's is not.
    assert not any(w.startswith("both") for w in c.warnings)


@dataclass
class _Base:
    names: list
    likelihood: object = None
    priors: object = None
    friction: bool = True


def test_pinned_coordinates_are_inserted_in_place():
    pinned = _Pinned(_Base(["zeta", "mu_k", "mu_s_ratio", "y0"]), {"zeta": 0.0})
    assert pinned.names == ["mu_k", "mu_s_ratio", "y0"] and pinned.friction
    full = pinned._full(np.array([[0.1, 1.2, 3.0], [0.2, 1.5, 4.0]]))
    np.testing.assert_array_equal(full, [[0.0, 0.1, 1.2, 3.0], [0.0, 0.2, 1.5, 4.0]])


def test_unknown_or_single_laws_are_refused():
    assert set(LAWS) == {"viscous", "coulomb", "both"}
    with pytest.raises(BayestriboError, match="laws"):
        compare_dissipation_laws("x.csv", laws=("viscous", "dry"))
    with pytest.raises(BayestriboError, match="two or more"):
        compare_dissipation_laws("x.csv", laws=("both",))
