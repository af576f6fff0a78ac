"""Stubs of compare_prepared's optimiser, sampler and checks (tests of screening and
settling): each law's pointwise log-likelihood is a constant shift below a law at zero."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from bayestribo.inference import comparison
from bayestribo.inference.choice import law_of
from bayestribo.inference.screening import LawOptimum

#: Π increments of a stub.
N = 200


def lpd_shifted(shift: float, spread: float = 0.0, seed: int = 0) -> np.ndarray:
    """N increments' log-likelihood summing to ``-shift``, scattered by ``spread``."""
    rng = np.random.default_rng(seed)
    noise = rng.normal(0.0, spread, N) if spread else np.zeros(N)
    return -shift / N + noise - noise.mean()


class _Posterior:
    def __init__(self, names):
        self.names = list(names)


def stub_fits(
    monkeypatch,
    shifts: dict[str, float],
    adequate: set[str] | None = None,
    spread: dict | None = None,
) -> list[str]:
    """Stub the optimiser, sampler and checks: each law's pointwise log-likelihood sums
    to ``-shift`` at its optimum and in its draws, scattered by ``spread`` (0.01 by
    default); adequate laws are ``adequate`` (every law by default)."""
    import arviz as az

    sampled: list[str] = []
    spread = spread or {}

    def optimise(law, prepared, model, discrepancy, optima, start=None):
        post = _Posterior(law_of(law).parameter_names)
        post.law = law
        theta = np.zeros(len(post.names))
        opt = (theta, np.eye(len(theta)), None)
        pointwise = lpd_shifted(shifts[law], spread.get(law, 0.01), 2)
        return LawOptimum(law, post, opt, post, opt, pointwise)

    def fit_law(law, prepared, settings, rng, posterior, optimum):
        sampled.append(law)
        d = len(posterior.names)
        chains = rng.normal(size=(2, 40, d))
        lpd = lpd_shifted(shifts[law], spread.get(law, 0.01), 2)
        lpd = lpd + 0.001 * rng.normal(size=(2, 40, N))
        run = SimpleNamespace(chains=chains, log_prob=np.zeros((2, 40)), converged=True, reasons=[])
        fit = SimpleNamespace(run=run, posterior=posterior, theta_map=np.zeros(d))
        idata = az.from_dict(
            posterior={n: chains[..., i] for i, n in enumerate(posterior.names)},
            log_likelihood={"pi": lpd},
        )
        return fit, az.loo(idata, pointwise=True)

    monkeypatch.setattr(comparison, "_optimise", optimise)
    monkeypatch.setattr(comparison, "_fit_law", fit_law)
    monkeypatch.setattr(comparison, "reduction", lambda *args: None)
    monkeypatch.setattr(comparison, "reduction_among", lambda *args: None)
    monkeypatch.setattr(comparison, "pareto_k_max", lambda loo: 0.1)
    monkeypatch.setattr(
        comparison,
        "_checks",
        lambda posterior, theta: {"adequate": adequate is None or posterior.law in adequate},
    )
    monkeypatch.setattr(comparison, "turning_point_screen", lambda prepared, laws: {})
    return sampled


def stub_prepared(n: int = N) -> SimpleNamespace:
    """A prepared run as the stubbed comparison reads it: a name and ``n`` increments."""
    return SimpleNamespace(name="stub", data=SimpleNamespace(increments=np.zeros(n)))
