"""PSIS-LOO of one sampled law: its pointwise log-likelihood, reused where it can be.

PSIS-LOO (Vehtari, Gelman & Gabry 2017) needs the log-likelihood of every Π increment
at every draw. For a law with a closed form that is cheap. For a law without one, the
exact Π of a draw is its compiled half-cycle integrator (some 400 µs a draw for a power
drag), and the draws of a comparison's laws then cost more than their sampling did
(``law="auto"`` on the bundled run: 1.3 s of its 4.4 s of CPU). Such a law is sampled
on its quadratic surrogate of Π where the exact posterior confirms it
(:mod:`bayestribo.inference.surrogate`), and the surrogate's pointwise log-likelihood
is what the draws came from: :func:`sampled_pointwise` takes it, after comparing it
with the exact one at :data:`CHECK_DRAWS` draws spread over the chains. PSIS-LOO's
``elpd_loo`` of a law moves by at most the sum over the increments of the largest
change of their log-likelihood over the draws, so the surrogate's stands when that
sum, at the draws compared, is within :data:`TOLERANCE`; otherwise every draw is
evaluated with the exact Π. (On the bundled runs and the real recordings of
``benchmarks/auto_screening.py`` the two differ by at most 3e-6 per increment and
draw, and the laws' ``elpd_loo`` agree to 1e-3.)

:func:`law_loo` is one law's PSIS-LOO (its pointwise values kept, for
:func:`arviz.compare`), :func:`loo_frame` the laws' comparison from them: each law's
PSIS-LOO is computed once.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.assemble import pointwise_log_likelihood
from bayestribo.inference.types import Sampled

__all__ = ["CHECK_DRAWS", "TOLERANCE", "law_loo", "loo_frame", "pareto_k_max", "sampled_pointwise"]

#: Draws, evenly spaced over the flattened chains, at which the surrogate's pointwise
#: log-likelihood is compared with the exact one.
CHECK_DRAWS = 8
#: Largest sum over the increments of |surrogate - exact| pointwise log-likelihood at a
#: draw compared for the surrogate's to stand: a bound on the change of ``elpd_loo``
#: small beside the comparison's tie rule (4) and PSIS-LOO's own Monte Carlo error
#: (some 0.1 with a thousand draws).
TOLERANCE = 0.05


def sampled_pointwise(sampled: Sampled) -> NDArray:
    """Log-likelihood of each Π increment at each draw of a sampled law (module notes).

    Parameters
    ----------
    sampled : Sampled
        A law's fit; its ``surrogate_posterior``, when there is one, is the posterior
        its draws came from.

    Returns
    -------
    ndarray
        Shape (chains, draws, m) for m increments: the surrogate's values where they
        agree with the exact ones at the draws compared (within :data:`TOLERANCE`),
        else the exact posterior's (:func:`bayestribo.inference.assemble.
        pointwise_log_likelihood`).
    """
    chains = np.asarray(sampled.run.chains, dtype=float)
    surrogate = sampled.surrogate_posterior
    if surrogate is None:
        return pointwise_log_likelihood(sampled.posterior, chains)
    approx = pointwise_log_likelihood(surrogate, chains)
    flat = chains.reshape(-1, chains.shape[-1])
    approx_flat = approx.reshape(flat.shape[0], -1)
    pick = np.unique(np.linspace(0, flat.shape[0] - 1, min(CHECK_DRAWS, flat.shape[0])).astype(int))
    exact = np.asarray(sampled.posterior.pointwise(flat[pick]), dtype=float)
    with np.errstate(invalid="ignore"):
        error = np.sum(np.abs(approx_flat[pick] - exact), axis=-1)
    if np.all(np.isfinite(error)) and float(np.max(error)) <= TOLERANCE:
        return approx
    return pointwise_log_likelihood(sampled.posterior, chains)


def law_loo(sampled: Sampled, pointwise: NDArray | None = None) -> Any:
    """PSIS-LOO of one sampled law, its pointwise values kept (an ArviZ ``ELPDData``).

    Parameters
    ----------
    sampled : Sampled
        The law's fit (its chains give the relative efficiency of the draws).
    pointwise : ndarray, optional
        Its pointwise log-likelihood, shape (chains, draws, m); default
        :func:`sampled_pointwise`.

    Returns
    -------
    ELPDData
        With ``loo_i`` and ``pareto_k`` per increment. A high Pareto k is reported by
        the comparison, not warned here.
    """
    import arviz as az

    chains = np.asarray(sampled.run.chains, dtype=float)
    if pointwise is None:
        pointwise = sampled_pointwise(sampled)
    names = sampled.posterior.names
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        idata = az.from_dict(
            posterior={name: chains[..., i] for i, name in enumerate(names)},
            log_likelihood={"pi": pointwise},
        )
        return az.loo(idata, pointwise=True)


def pareto_k_max(loo: Any) -> float:
    """Largest Pareto k of a law's PSIS-LOO (:func:`law_loo`)."""
    return float(np.max(np.asarray(loo.pareto_k)))


def loo_frame(loos: Mapping[str, Any]) -> Any:
    """The laws' PSIS-LOO compared (:func:`arviz.compare` of :func:`law_loo`'s
    results); one law alone is its own best.

    Parameters
    ----------
    loos : mapping of str to ELPDData
        Each law's PSIS-LOO, pointwise.

    Returns
    -------
    pandas.DataFrame
        One row per law, best first: ``rank``, ``elpd_loo``, ``p_loo``, ``elpd_diff``,
        ``weight``, ``se``, ``dse``.
    """
    import arviz as az
    import pandas as pd

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if len(loos) >= 2:
            return az.compare(dict(loos), ic="loo")
    ((law, loo),) = loos.items()
    row = {
        "rank": 0.0,
        "elpd_loo": float(loo["elpd_loo"]),
        "p_loo": float(loo["p_loo"]),
        "elpd_diff": 0.0,
        "weight": 1.0,
        "se": float(loo["se"]),
        "dse": 0.0,
    }
    return pd.DataFrame([row], index=[law])
