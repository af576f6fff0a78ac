"""The default fit on a real ridge: HarmOsc2's first half, whose μ_k lies on a ridge at 0.

The AppStat2020 HarmOsc2 recording (position only, arbitrary unit) up to 18.30 s
(``benchmarks/real.py``'s first half). With the independence move left in the mix, the
default law's seed 1 stopped unconverged there (its ridge's tail left to the DE moves
a quarter of the steps); the move is taken out when τ shows it does not mix
(``SamplerSettings.independence_limit``), and the fit converges as main's sampler did.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo import Run, fit, read_run
from tests._paths import APPSTAT

DATA = APPSTAT / "HarmOsc2.txt"
pytestmark = pytest.mark.skipif(not DATA.exists(), reason=f"real recording not found: {DATA}")

#: ``benchmarks/real.py``'s cut of HarmOsc2 [s].
CUT_S = 18.30


def _first_half() -> Run:
    run = read_run(
        DATA, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
    )
    k = int(np.argmin(np.abs(run.time - CUT_S)))
    return Run(
        time=run.time[: k + 1],
        displacement=run.displacement[: k + 1],
        velocity=None,
        metadata=dict(run.metadata),
    )


def test_on_the_ridge_the_move_is_taken_out_and_the_fit_converges():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(_first_half(), seed=1)
    d = result.diagnostics
    assert result.converged, d["reasons"]
    assert d["independence_dropped"] is not None and d["independence_weight"] == 0.0
    assert d["burn"] >= d["independence_dropped"]
    assert d["ess_min"] >= 1000
