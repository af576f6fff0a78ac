"""A closed-form law that dissipates nothing (ζ = μ_k = 0) makes no decay.

Its Π(τ) is infinite (the motion never ends), so a decaying record has no likelihood
there: the log posterior is −∞, not a NaN that the posterior reports as a bug. The
point is inside the default law's prior (both bounds are 0), and the optimiser's check
of its bounds, or a record that cannot tell friction from viscous damping, reaches it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo.inference import build_posterior, prepare


@pytest.mark.parametrize("model", ["exact", "averaged"])
def test_no_dissipation_has_no_likelihood_not_a_nan(bundled_run, model: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(bundled_run)
    posterior = build_posterior(prepared.data, friction=prepared.contact, model=model)
    y0 = float(prepared.data.y0)
    names = posterior.names
    row = {"zeta": 0.0, "mu_k": 0.0, "mu_s_ratio": 2.0, "y0": y0}
    nothing = np.array([[row[n] for n in names]])
    near = nothing.copy()
    near[0, names.index("zeta")] = 1e-3  # some damping: a decay, a finite density
    lp = posterior(np.vstack([nothing, near]))
    assert lp[0] == -np.inf
    assert np.isfinite(lp[1])
    assert posterior.reference(nothing)[0] == -np.inf  # the numpy reference agrees
