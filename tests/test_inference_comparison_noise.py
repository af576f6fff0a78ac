"""A comparison draws a derived channel's Monte Carlo noise once for all its laws."""

from __future__ import annotations

from pathlib import Path

import pytest
from _comparison_stubs import stub_fits, stub_prepared

from bayestribo.inference import comparison
from bayestribo.inference.comparison import compare_prepared
from bayestribo.signal import channel_noise

RUN = Path(__file__).resolve().parents[1] / "data" / "runs" / "air-r1.csv"


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
    compare_prepared(stub_prepared(), list(shifts), seed=1, rivals=False)
    assert len(seen) == len(shifts)
    assert seen[0] is not None and all(kept is seen[0] for kept in seen)
    # released once the comparison is done
    assert channel_noise._KEPT.get() is None


class _Stop(Exception):
    pass


@pytest.mark.parametrize("law", ["auto", "viscous+coulomb"])
def test_a_fit_keeps_the_first_passes_noise_for_its_second_passes(monkeypatch, law):
    from bayestribo.inference import fitting

    seen = {}

    def prepare(run, **kwargs):
        seen["prepare"] = channel_noise._KEPT.get()
        return stub_prepared()

    def stop(name):
        def record(*args, **kwargs):
            seen[name] = channel_noise._KEPT.get()
            raise _Stop

        return record

    monkeypatch.setattr(fitting, "prepare", prepare)
    monkeypatch.setattr(fitting, "fit_auto", stop("fit_auto"))
    monkeypatch.setattr(fitting, "sample_law", stop("sample_law"))
    with pytest.raises(_Stop):
        fitting.fit(RUN, law=law)
    # nothing is kept once the fit has ended
    assert channel_noise._KEPT.get() is None
    # the comparison's laws, or the default law's boundary laws, find the first pass's
    # noise (and its derivative) made
    stage = "fit_auto" if law == "auto" else "sample_law"
    assert seen["prepare"] is not None and seen[stage] is seen["prepare"]
