"""The default fit on a real ridge: HarmOsc2's first half, whose μ_k lies on a ridge at 0.

The AppStat2020 HarmOsc2 recording (position only, arbitrary unit) up to 18.30 s
(``benchmarks/real.py``'s first half). With the independence move left in the mix, the
default law's seed 1 stopped unconverged there (its ridge's tail left to the DE moves
a quarter of the steps); the move is taken out when τ shows it does not mix
(``SamplerSettings.independence_limit``), and the fit converges as main's sampler did.
Six seeds are fitted: every one converges, and on those where the move was taken out
the draws kept are all of the DE moves. Which seeds take it out is a matter of the
chain's last bits (none of the six on some CPUs, whose SIMD kernels round differently):
that a move past the limit is taken out, and the draws after it sample the target, is
tested where the limit is forced (``tests/test_inference_independence_limit.py``; and on
a synthetic curved ridge among the validation checks).
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


#: Seeds of the default fit tried: the move's failure to mix is a matter of the chain
#: (seeds 1 and 5 took it out at one commit; seed 5 alone after the derived velocity's
#: noise was filtered as the motion's plus the noise's, which moves the last digits;
#: none on an AVX-512 machine).
SEEDS = (1, 2, 3, 4, 5, 6)


def test_on_the_ridge_the_fit_converges_with_or_without_the_move():
    for seed in SEEDS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(_first_half(), seed=seed)
        d = result.diagnostics
        # converged whether or not the move was taken out
        assert result.converged, (seed, d["reasons"])
        assert d["ess_min"] >= 1000
        if d["independence_dropped"] is not None:
            assert d["independence_weight"] == 0.0
            assert d["burn"] >= d["independence_dropped"]
