"""A record's stop that the prior of μ_s/μ_k cannot reach.

The motion sticks at its first turning point Y_n whose spring force the static friction
holds, |Y_n| <= (μ_s/μ_k) μ(|Y_n|) (Rigaud et al. 2010, Sec. 2.2; μ(|Y|) the law's
kinetic friction at that swing, μ_k on the paper's law, in the sampled frame's unit of
y = x/ℓ). A record whose motion ends at the turning point Y_stop therefore asks for

    μ_s/μ_k >= |Y_stop| / μ(|Y_stop|).

Where that is beyond the upper bound of the prior of μ_s/μ_k (10 by default: a belief,
:data:`~bayestribo.inference.priors.BELIEF_BOUNDS`), no draw of the posterior stops
where the record does: every draw moves on past the record's stop, the law misfits the
end of the decay, whatever the law, and the posterior of μ_s/μ_k presses on the bound
without piling on it (a paper rig with μ_s/μ_k = 30: 9.3 [8.7, 10.0], and exit 1 with
``--law auto`` advised, whose comparison misfits too). The bound, not the law, is the
cause: :func:`stop_beyond_prior` says so with the ratio the stop needs, and the misfit's
advice widens the prior to hold it (followed: exit 0, ζ, μ_k and μ_s/μ_k covered;
``tests/test_inference_stop_prior.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import LogUniform, Uniform, widened_prior
from bayestribo.inference.surrogate import CoefficientLayout

__all__ = ["PRESSING", "StopBeyondPrior", "stop_beyond_prior"]

#: The posterior presses on the bound when its 97.5 % quantile of μ_s/μ_k is at least
#: this share of the bound (the paper rig's μ_s/μ_k = 30 record: 9.98 of 10).
PRESSING = 0.9


@dataclass(frozen=True)
class StopBeyondPrior:
    """The ratio a record's stop needs, beyond the prior's bound.

    Attributes
    ----------
    needed : float
        |Y_stop|/μ(|Y_stop|) at the posterior's median [dimensionless].
    bound : float
        The prior's upper bound of μ_s/μ_k.
    option : str
        The ``--prior`` value that holds the stop (``mu_s_ratio=Uniform(1,45)``).
    """

    needed: float
    bound: float
    option: str

    def describe(self) -> str:
        """The cause in a sentence (for the misfit's advice)."""
        return (
            f"the record's motion stops at a turning point {self.needed:.3g} times the "
            "kinetic friction's displacement from the equilibrium (at the posterior's "
            f"median), so its stop needs μ_s/μ_k >= "
            f"{self.needed:.3g}, beyond the prior's upper bound {self.bound:g} (a belief, "
            "not a physical limit): no draw can stop where the record does"
        )


def stop_beyond_prior(
    posterior: Posterior, draws: NDArray, y_stop: float, y_before: float | None = None
) -> StopBeyondPrior | None:
    """Whether the record's stop at ``y_stop`` needs a μ_s/μ_k beyond its prior.

    Parameters
    ----------
    posterior : Posterior
        The sampled posterior (its law, priors and coordinates).
    draws : ndarray
        Its draws, shape (n, d), in sampling coordinates.
    y_stop : float
        The turning point at which the record's motion ends, about the equilibrium,
        in the sampled frame's unit of y [dimensionless].
    y_before : float, optional
        The turning point before it, where the motion did not stick: the ratio is
        below |Y|/μ(|Y|) there, and the prior advised holds 1.2× that (and at least
        1.5× the ratio needed).

    Returns
    -------
    StopBeyondPrior or None
        None where μ_s/μ_k is not sampled, its prior is not one whose bound is a
        belief, the posterior does not press on the bound (:data:`PRESSING`), the law's
        friction at the stop is zero at the median (a stop no friction makes), or the
        ratio needed is within the bound.
    """
    names = posterior.names
    if "mu_s_ratio" not in names or draws.size == 0:
        return None
    prior = posterior.priors["mu_s_ratio"]
    if not isinstance(prior, Uniform | LogUniform):
        return None
    ratio = draws[:, names.index("mu_s_ratio")]
    if float(np.quantile(ratio, 0.975)) < PRESSING * prior.high:
        return None
    params = posterior.physical(np.median(draws, axis=0)[None])["params"]
    law = posterior.law
    values = {n: np.array([float(params[n][0])]) for n in law.parameter_names}
    values["mu_s_ratio"] = np.array([1.0])
    coef = law.coefficients(values, posterior.likelihood.reference_amplitude)[0]
    frictions = CoefficientLayout.of(law).frictions

    def ratio_at(y: float) -> float:
        swing = abs(float(y))
        mu = sum(f.force(swing, coef[f.columns]) for f in frictions)
        return swing / mu if math.isfinite(mu) and mu > 0.0 else math.nan

    needed = ratio_at(y_stop)
    if not math.isfinite(needed) or needed <= prior.high:
        return None
    # the stick the record did not make, at the turning point before, bounds the ratio
    # from above: the prior advised holds it with room
    above = ratio_at(y_before) if y_before is not None else math.nan
    room = max(needed, 1.2 / 1.5 * above) if math.isfinite(above) else needed
    option = widened_prior("mu_s_ratio", prior, needed=room)
    return None if option is None else StopBeyondPrior(needed, float(prior.high), option)
