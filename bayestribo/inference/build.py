"""Building a law's posterior for prepared increments: priors × the Π likelihood.

:func:`build_posterior` takes the increments of the prepare stage
(:attr:`~bayestribo.inference.types.PreparedRun.data`) and gives the
:class:`~bayestribo.inference.posterior.Posterior` the start and sample stages take.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from bayestribo.errors import BayestriboError
from bayestribo.inference.likelihood import MODELS, PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Normal, Prior, PriorSet, default_priors
from bayestribo.model.laws import Law, get_law
from bayestribo.signal.increments import PiData

__all__ = ["build_posterior"]


def build_posterior(
    data: PiData,
    *,
    model: str = "exact",
    friction: bool = True,
    discrepancy: bool = False,
    priors: Mapping[str, Prior] | None = None,
    fixed: Mapping[str, float] | None = None,
    law: str | Law | None = None,
) -> Posterior:
    """Step 2: the posterior for observed Π increments.

    The equilibrium nuisance gets prior standard deviations of 1 % of the initial
    amplitude (δ₀) and 1 % of it over the analysed window (δ₁), hundreds of times
    the errors of the equilibrium estimate.

    Parameters
    ----------
    data : PiData
        Observed increments (:func:`bayestribo.signal.pi_data`).
    model : {"exact", "averaged"}
        Forward model.
    friction : bool
        Fit μ_k and μ_s/μ_k (False: viscous damping only).
    discrepancy : bool
        Add the model-discrepancy terms: white (``log10_discrepancy``) and shape
        (``log10_shape``).
    priors : mapping, optional
        Replacement priors by parameter name (see
        :func:`bayestribo.inference.priors.default_priors`).
    fixed : mapping, optional
        Parameters held at a value instead of sampled, e.g. ``{"zeta": 0.0}`` for
        friction alone; their priors are dropped.
    law : str or Law, optional
        The dissipation law (:mod:`bayestribo.model.laws`): a name such as
        ``"viscous+quadratic+coulomb"``, or a :class:`~bayestribo.model.laws.Law`
        (one of terms defined outside the package too); default
        ``"viscous+coulomb"``.

    Returns
    -------
    Posterior

    Raises
    ------
    BayestriboError
        If a parameter is both given a prior and fixed, a fixed name is unknown, the
        law is unknown, or a prior names a parameter the law does not have.
    """
    if model not in MODELS:
        raise BayestriboError(f"model: expected one of {MODELS}, got {model!r}")
    try:
        the_law = get_law(law)
    except ValueError as exc:
        raise BayestriboError(str(exc)) from None
    if model == "averaged" and data.restoring is not None:
        raise BayestriboError(
            f"model='averaged' has no form on the {data.restoring.name}'s restoring force: "
            "use model='exact'"
        )
    if model == "averaged" and not the_law.closed_form:
        raise BayestriboError(
            f"model='averaged' has no closed form for the law {the_law.name}: use model='exact'"
        )
    fixed = dict(fixed or {})
    both = sorted(set(fixed) & set(priors or {}))
    if both:
        raise BayestriboError(f"priors and fixed both name {both}: give one or the other")
    # a coarse displacement reads y0 and the equilibrium to about half a step
    half_step = 0.5 * float(getattr(data, "rounding", 0.0))
    prior_set = default_priors(
        data.y0,
        friction=friction,
        discrepancy=discrepancy,
        law=the_law,
        y0_sd=math.hypot(0.01 * data.y0, half_step) if half_step > 0 else None,
    )
    if priors:
        try:
            prior_set = prior_set.replace(**dict(priors))
        except ValueError as exc:
            raise BayestriboError(f"priors: {exc} (law {the_law.name})") from None
        _check_support(prior_set, the_law)
    if fixed:
        prior_set = PriorSet({n: p for n, p in prior_set.priors.items() if n not in fixed})
    likelihood = PiLikelihood(
        data,
        model=model,  # type: ignore[arg-type]
        offset_sd=max(math.hypot(1e-2 * data.y0, half_step), 1e-12),
        drift_sd=max(math.hypot(1e-2 * data.y0, half_step) / data.tau_end, 1e-15),
        law=the_law,
    )
    return Posterior(prior_set, likelihood, fixed)


#: Prior mass a Normal prior may put outside its parameter's support (where the law
#: is not defined: a negative friction, an overdamped ζ above 1).
OUTSIDE_MASS = 1e-6


def _check_support(prior_set: PriorSet, law: Law) -> None:
    """Refuse a prior given for a law's parameter that reaches beyond the parameter's
    support: a uniform one whose bounds do, or a normal one with more than
    :data:`OUTSIDE_MASS` of its mass there."""
    from scipy.special import ndtr

    for parameter in law.parameters:
        prior = prior_set.priors.get(parameter.name)
        if prior is None:
            continue
        low, high = parameter.low, parameter.high
        if isinstance(prior, Normal):
            below = ndtr((low - prior.mu) / prior.sigma) if math.isfinite(low) else 0.0
            above = ndtr((prior.mu - high) / prior.sigma) if math.isfinite(high) else 0.0
            beyond = below + above > OUTSIDE_MASS
        else:
            beyond = getattr(prior, "low", low) < low or getattr(prior, "high", high) > high
        if beyond:
            raise BayestriboError(
                f"priors (--prior): {parameter.name}={prior.describe()} reaches beyond "
                f"[{low:g}, {high:g}], where the law {law.name} defines {parameter.name} "
                f"({parameter.label}); give a prior within it"
            )
