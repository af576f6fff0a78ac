"""A comparison draws a derived channel's Monte Carlo noise once for all its laws."""

from __future__ import annotations

from types import SimpleNamespace

from _comparison_stubs import stub_fits

from bayestribo.inference import comparison
from bayestribo.inference.comparison import compare_prepared
from bayestribo.signal import channel_noise


def test_every_laws_optimum_in_a_comparison_shares_the_kept_noise(monkeypatch):
    shifts = {"viscous": 5000.0, "coulomb": 2.0, "viscous+coulomb": 0.0}
    stub_fits(monkeypatch, shifts)
    stubbed = comparison._optimise
    seen = []

    def optimise(*args, **kwargs):
        # the second pass runs inside this call (reweight.reweighted_posterior)
        seen.append(channel_noise._KEPT.get())
        return stubbed(*args, **kwargs)

    monkeypatch.setattr(comparison, "_optimise", optimise)
    assert channel_noise._KEPT.get() is None
    compare_prepared(SimpleNamespace(name="stub"), list(shifts), seed=1, rivals=False)
    assert len(seen) == len(shifts)
    assert seen[0] is not None and all(kept is seen[0] for kept in seen)
    # released once the comparison is done
    assert channel_noise._KEPT.get() is None
