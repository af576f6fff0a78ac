"""From chains to reported quantities: derived parameters and the InferenceData.

* :func:`derived_quantities`: ζ, μ_k, μ_s, the friction displacement, ζ_k and d_k from
  the sampled (and fixed) coordinates, with the calibration nuisances (load, mass,
  ζ₀) drawn from their stated uncertainties;
* :func:`pointwise_log_likelihood`: the log-likelihood of each Π increment for each
  draw (for PSIS-LOO);
* :func:`fit_draws`: the groups of a fit (posterior, pointwise log-likelihood,
  posterior predictive Π, observed Π) as numpy arrays, a :class:`FitDraws`, whose
  pointwise log-likelihood (PSIS-LOO's input) and posterior predictive Π (the fit
  plot's) are computed when first read: a fit's summaries use neither, and together
  they cost about a tenth of a default fit;
* :func:`inference_data`: the same as an ArviZ InferenceData
  (:meth:`FitDraws.to_inference_data`), built only when asked for: ArviZ, xarray and
  pandas take longer to import than a fit takes to run.
"""

from __future__ import annotations

import copy
import dataclasses
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.posterior import Posterior
from bayestribo.model.scaling import Scaling
from bayestribo.signal.increments import PiData

__all__ = [
    "FitDraws",
    "derived_quantities",
    "fit_draws",
    "inference_data",
    "pointwise_log_likelihood",
]

#: Draws of the posterior predictive Π kept in a fit's InferenceData.
PREDICTIVE_DRAWS = 400


def derived_quantities(
    posterior: Posterior,
    draws: NDArray,
    scaling: Scaling,
    metadata: Mapping[str, Any],
    rng: np.random.Generator,
    frequency_sd: float = 0.0,
    gain: NDArray | None = None,
) -> dict[str, NDArray]:
    """Sampled and derived quantities by name, from flat draws.

    **Frequency nuisance.** The fit's time τ = Ω̂t and stiffness k = mΩ̂² use the
    frequency Ω̂ measured from the turning points. If the oscillator's own Ω differs
    by a factor 1 + ε (Ω̂ = Ω(1 + ε)), ζ, a rate per radian, is fitted as ζ/(1 + ε)
    and μ_k = x_c k/N as μ_k (1 + ε)²; a frequency that changes with amplitude (a
    cubic spring: :func:`bayestribo.signal.frequency.frequency_trend`) leaves no single Ω
    to use, and the equivalent constant one is known only to within that change.
    ε is drawn per draw from N(0, ``frequency_sd``²) and ζ → ζ(1 + ε), μ_k, μ_s →
    μ/(1 + ε)², k → k/(1 + ε)² in ζ_k and d_k; the friction displacement x_c is
    measured directly and does not change.

    Parameters
    ----------
    posterior : Posterior
        The posterior the draws come from (it names the coordinates and the fixed
        values).
    draws : ndarray
        Flat draws of the sampled coordinates, shape (n, d).
    scaling : Scaling
        Dimensionless scaling of the run (length scale ℓ = N/k [m], Ω [rad/s]).
    metadata : mapping
        The run's metadata: ``load_N``, ``mass_kg`` and their uncertainties
        (``load_uncertainty_N``, ``mass_uncertainty_kg``), ``zeta0`` and ``zeta0_sd``.
    rng : numpy.random.Generator
        Source of the calibration nuisance draws.
    frequency_sd : float
        Relative standard deviation of the frequency nuisance ε [-] (0: none).
    gain : ndarray, optional
        Draws of the signal chain's gain g at the oscillation frequency, one per draw
        (:meth:`bayestribo.signal.sensor.SensorCalibration.draws`): the recorded
        amplitude is g times the motion's, so every length the fit measures (x_c, and
        μ_k = x_c k/N) is divided by it; ζ, a ratio of amplitudes, does not see it.
        None: a gain of exactly 1.

    Returns
    -------
    dict
        ``zeta``; with friction ``mu_s_ratio`` and ``friction_displacement`` [m or the
        run's length unit], and either ``mu_k`` and ``mu_s`` (load and mass known) or
        ``static_friction_displacement`` [same unit] (not known); for a rotation
        (``length_unit`` ``"rad"``, the displacement an angle) with ``inertia_kg_m2``,
        ``friction_torque`` and ``static_friction_torque`` [N m] (κ θ, κ = IΩ²); ``y0``;
        ``log10_discrepancy`` and ``log10_shape`` when sampled; ``zeta_k`` when ζ₀ is given; ``d_k``
        [s/m] (= 2ζ_k √(km)/N, Eq. 42) when ζ₀, the load and the mass are known.
    """
    col = posterior.values(draws)
    size = np.atleast_2d(draws).shape[0]
    if not (np.isfinite(frequency_sd) and frequency_sd >= 0.0):
        raise ValueError(f"frequency_sd must be a number >= 0, got {frequency_sd!r}")
    ratio_w = np.ones(size)  # (1 + ε): the measured over the oscillator's frequency
    if frequency_sd > 0.0:
        ratio_w = 1.0 + rng.normal(0.0, frequency_sd, size)
    out: dict[str, NDArray] = {}
    if "zeta" in col:
        out["zeta"] = col["zeta"] * ratio_w
    n_draw = m_draw = None
    if posterior.friction:
        mu_k = col["mu_k"]
        ratio = col.get("mu_s_ratio", np.ones(size))
        out["mu_s_ratio"] = ratio
        friction_disp = mu_k * scaling.length_scale
        if gain is not None:
            friction_disp = friction_disp / gain
        if scaling.friction_defined:
            # Calibration nuisances: μ_k = x_c k/N with N and m drawn from their
            # stated uncertainties (the data fix x_c, not N or k).
            load = float(metadata["load_N"])
            mass = float(metadata["mass_kg"])
            n_draw = _positive_draws(rng, load, metadata.get("load_uncertainty_N"), size)
            m_draw = _positive_draws(rng, mass, metadata.get("mass_uncertainty_kg"), size)
            mu_k = mu_k if gain is None else mu_k / gain
            out["mu_k"] = mu_k * (load / n_draw) * (m_draw / mass) / ratio_w**2
            out["mu_s"] = out["mu_k"] * ratio
        else:
            # Without the load and stiffness the static friction is a displacement
            # too: it is not μ_s and is not labelled so.
            out["static_friction_displacement"] = friction_disp * ratio
        out["friction_displacement"] = friction_disp
        inertia = metadata.get("inertia_kg_m2")
        if metadata.get("length_unit") == "rad" and inertia is not None:
            # a rotation: the friction angle θ_c times the torsional stiffness
            # κ = IΩ² (Ω the oscillator's own, as k in μ_k) is the friction torque
            kappa = float(inertia) * (scaling.omega / ratio_w) ** 2
            out["friction_torque"] = friction_disp * kappa
            out["static_friction_torque"] = friction_disp * ratio * kappa
    out["y0"] = col["y0"]
    for name in ("log10_discrepancy", "log10_shape"):
        if name in col:
            out[name] = col[name]

    zeta0 = metadata.get("zeta0")
    if zeta0 is not None and posterior.friction and "zeta" in out:
        z0 = _positive_draws(rng, float(zeta0), metadata.get("zeta0_sd"), size)
        out["zeta_k"] = out["zeta"] - z0
        if n_draw is not None and m_draw is not None:
            k_draw = m_draw * (scaling.omega / ratio_w) ** 2
            out["d_k"] = 2.0 * out["zeta_k"] * np.sqrt(k_draw * m_draw) / n_draw
    return out


def _positive_draws(rng: np.random.Generator, value: float, sd: float | None, size: int) -> NDArray:
    """Draws of a normal truncated to positive values (``value`` itself without ``sd``)."""
    if sd is None or sd == 0:
        return np.full(size, value)
    draws = rng.normal(value, float(sd), size)
    while np.any(draws <= 0):
        bad = draws <= 0
        draws[bad] = rng.normal(value, float(sd), int(bad.sum()))
    return draws


def pointwise_log_likelihood(posterior: Posterior, chains: NDArray) -> NDArray:
    """Log-likelihood of each Π increment for each draw.

    Parameters
    ----------
    posterior : Posterior
    chains : ndarray
        Draws of shape (chains, draws, d).

    Returns
    -------
    ndarray
        Shape (chains, draws, m) for m increments, evaluated in blocks of about 256
        draws to bound memory.
    """
    n_chain, n_draw, d = chains.shape
    flat = chains.reshape(-1, d)
    blocks = np.array_split(flat, max(1, flat.shape[0] // 256))
    pointwise = np.concatenate([posterior.pointwise(block) for block in blocks])
    return pointwise.reshape(n_chain, n_draw, -1)


def _predictive_pi(
    posterior: Posterior, flat: NDArray, data: PiData, rng: np.random.Generator
) -> NDArray:
    """Posterior predictive Π: model increments plus noise (and discrepancy), for a
    subset of the draws, with the conditional equilibrium offset applied."""
    pick = np.sort(
        rng.choice(flat.shape[0], size=min(PREDICTIVE_DRAWS, flat.shape[0]), replace=False)
    )
    p = posterior.physical(flat[pick])
    lik = posterior.likelihood
    model_inc = lik.model_increments(p["params"])
    nuisance = lik.nuisance_mean(p["params"], p["discrepancy"], p["shape"])
    var = np.broadcast_to(lik.variance(p["discrepancy"]), model_inc.shape)
    correlation = getattr(data, "correlation", None)
    if correlation is None:
        replicated = model_inc + nuisance + rng.normal(0.0, np.sqrt(var))
    else:  # the increments' noise correlated as the likelihood takes it
        noise = rng.normal(0.0, 1.0, model_inc.shape) @ np.linalg.cholesky(correlation).T
        replicated = model_inc + nuisance + np.sqrt(var) * noise
    return np.cumsum(replicated[:, ::-1], axis=1)[:, ::-1]


#: The fields of :class:`FitDraws` that may be computed when first read.
_DEFERRED = ("log_likelihood", "posterior_predictive", "log_prob")


@dataclass
class FitDraws:
    """The groups of a fit's InferenceData as numpy arrays, before ArviZ is imported.

    Attributes
    ----------
    posterior : dict of str to ndarray
        Draws of each reported quantity, shape (chain, draw), in the order of the
        posterior group.
    attrs : dict
        Attributes of the posterior group (run, settings, diagnostics as JSON).
    log_likelihood : ndarray
        Pointwise log-likelihood of each Π increment, shape (chain, draw, increment).
    posterior_predictive : ndarray
        Replicated Π on the grid, shape (1, draw, grid).
    observed : ndarray
        Observed Π on the grid.
    grid : ndarray
        τ of the grid points (the coordinate ``grid``).
    log_prob : ndarray or None
        Log posterior density of each draw as the sampler saw it, shape (chain,
        draw) (unnormalised; the surrogate's where the fit sampled one; at a draw of a
        nested law mixed in at a boundary, the full law's posterior evaluated there).
    walker_acceptance : ndarray or None
        emcee's acceptance fraction of each walker, shape (chain, walker).

    Notes
    -----
    ``log_likelihood``, ``posterior_predictive`` and ``log_prob`` are each given as an
    array, or as a function of no arguments that computes it (:func:`fit_draws`),
    called when the attribute is first read and its array kept; a FitDraws is pickled
    with the arrays.
    """

    posterior: dict[str, NDArray]
    attrs: dict[str, Any]
    log_likelihood: NDArray
    posterior_predictive: NDArray
    observed: NDArray
    grid: NDArray
    log_prob: NDArray | None = None
    walker_acceptance: NDArray | None = None

    def with_attrs(self, attrs: Mapping[str, Any]) -> FitDraws:
        """These draws with the posterior group's attributes ``attrs``; a field not
        computed yet stays so (``dataclasses.replace`` alone would compute it)."""
        deferred = {k: self.__dict__[f"_{k}"] for k in _DEFERRED}
        new = dataclasses.replace(self, **deferred)
        new.attrs = dict(attrs)
        return new

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        for name in _DEFERRED:
            state[f"_{name}"] = getattr(self, name)  # computed, not the function
        return state

    def sample_stats(self) -> dict[str, NDArray]:
        """The sampler's statistics per draw, shape (chain, draw) each: ``lp`` (log
        posterior density, ArviZ's name for it) and ``walker_index`` (the walker that made
        the draw; draws are step-major); empty where not recorded."""
        if self.log_prob is None:
            return {}
        lp = np.asarray(self.log_prob, dtype=float)
        out = {"lp": lp}
        if self.walker_acceptance is not None:
            n_walkers = np.asarray(self.walker_acceptance).shape[-1]
            walker = np.arange(lp.shape[1]) % n_walkers
            out["walker_index"] = np.broadcast_to(walker, lp.shape).copy()
        return out

    def to_inference_data(self) -> Any:
        """The ArviZ InferenceData of these groups (imports ArviZ).

        Returns
        -------
        arviz.InferenceData
                Groups ``posterior`` (with :attr:`attrs`), ``log_likelihood`` (``pi``, per
            increment), ``posterior_predictive`` and ``observed_data`` (Π on the grid),
            and, where recorded, ``sample_stats``: ``lp`` and ``walker_index`` per draw
            (:meth:`sample_stats`) and ``acceptance_fraction`` per walker (dims
            ``chain, walker``).
        """
        import arviz as az

        stats = self.sample_stats()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            idata = az.from_dict(
                posterior=dict(self.posterior),
                sample_stats=stats or None,
                log_likelihood={"pi": self.log_likelihood},
                posterior_predictive={"pi": self.posterior_predictive},
                observed_data={"pi": self.observed},
                coords={
                    "increment": np.arange(self.log_likelihood.shape[-1]),
                    "grid": self.grid,
                },
                dims={"pi": ["grid"]},
                pred_dims={"pi": ["grid"]},
                log_likelihood_dims={"pi": ["increment"]},
            )
        idata.posterior.attrs.update(self.attrs)
        if stats and self.walker_acceptance is not None:
            fractions = np.asarray(self.walker_acceptance, dtype=float)
            idata.sample_stats["acceptance_fraction"] = (("chain", "walker"), fractions)
            idata.sample_stats = idata.sample_stats.assign_coords(
                walker=np.arange(fractions.shape[1])
            )
        return idata


class _Deferred:
    """A field of :class:`FitDraws` given as an array or as a function of no arguments
    that computes it, called when the field is first read (its array then kept)."""

    def __init__(self, name: str) -> None:
        self.key = f"_{name}"
        self.__doc__ = f"{name} (see the class; computed when first read)."

    def __get__(self, draws: FitDraws | None, owner: type | None = None) -> Any:
        if draws is None:
            return self
        value = draws.__dict__[self.key]
        if callable(value):
            value = draws.__dict__[self.key] = value()
        return value

    def __set__(self, draws: FitDraws, value: NDArray | Callable[[], NDArray]) -> None:
        draws.__dict__[self.key] = value


# set after the dataclass is made (in the class body they would be the fields'
# defaults): its __init__ then stores the array or the function through them
FitDraws.log_likelihood = _Deferred("log_likelihood")  # type: ignore[assignment]
FitDraws.posterior_predictive = _Deferred("posterior_predictive")  # type: ignore[assignment]
FitDraws.log_prob = _Deferred("log_prob")  # type: ignore[assignment]


def fit_draws(
    posterior: Posterior,
    chains: NDArray,
    derived: Mapping[str, NDArray],
    rng: np.random.Generator,
    attrs: Mapping[str, Any],
    *,
    log_prob: NDArray | Callable[[], NDArray] | None = None,
    walker_acceptance: NDArray | None = None,
) -> FitDraws:
    """The groups of a fit's InferenceData, as numpy arrays.

    Parameters
    ----------
    posterior : Posterior
        The posterior that was sampled (its likelihood holds the observed increments).
    chains : ndarray
        Draws of the sampled coordinates, shape (chains, draws, d).
    derived : mapping
        Flat draws of each reported quantity (:func:`derived_quantities`).
    rng : numpy.random.Generator
        Source of the posterior predictive draws: a copy of it as it is at this call
        makes them when they are first read (``rng`` itself is not advanced).
    attrs : mapping
        Attributes of the posterior group (run, settings, diagnostics as JSON).
    log_prob : ndarray or callable, optional
        Log posterior density of each draw, shape (chains, draws); or a function of no
        arguments that gives it, called when first read (draws mixed in after
        sampling, :mod:`bayestribo.inference.boundary`).
    walker_acceptance : ndarray, optional
        Acceptance fraction of each walker, shape (chains, walkers).

    Returns
    -------
    FitDraws
        The posterior draws shaped (chain, draw), the pointwise log-likelihood and
        the posterior predictive (each computed when first read) and the observed Π.
    """
    data = posterior.likelihood.data
    n_chain, n_draw, _ = chains.shape
    # both computed when first read (the summaries use neither), from copies of the
    # chains and of the generator as they are now: the same arrays as if made now
    chains = np.array(chains)
    own = copy.deepcopy(rng)
    pointwise = partial(pointwise_log_likelihood, posterior, chains)

    def predictive() -> NDArray:
        return _predictive_pi(posterior, chains.reshape(n_chain * n_draw, -1), data, own)[None]

    def shaped(values: NDArray) -> NDArray:
        return values.reshape(n_chain, n_draw, *values.shape[1:])

    return FitDraws(
        posterior={k: shaped(v) for k, v in derived.items()},
        attrs=dict(attrs),
        log_likelihood=pointwise,
        posterior_predictive=predictive,
        observed=data.pi,
        grid=data.tau_grid[:-1],
        log_prob=log_prob if log_prob is None or callable(log_prob) else np.asarray(log_prob, "f8"),
        walker_acceptance=walker_acceptance,
    )


def inference_data(
    posterior: Posterior,
    chains: NDArray,
    derived: Mapping[str, NDArray],
    rng: np.random.Generator,
    attrs: Mapping[str, Any],
) -> Any:
    """The ArviZ InferenceData of a fit (:func:`fit_draws`, then ArviZ).

    Parameters
    ----------
    posterior : Posterior
        The posterior that was sampled (its likelihood holds the observed increments).
    chains : ndarray
        Draws of the sampled coordinates, shape (chains, draws, d).
    derived : mapping
        Flat draws of each reported quantity (:func:`derived_quantities`).
    rng : numpy.random.Generator
        Source of the posterior predictive draws.
    attrs : mapping
        Attributes of the posterior group (run, settings, diagnostics as JSON).

    Returns
    -------
    arviz.InferenceData
        Groups ``posterior``, ``log_likelihood`` (``pi``, per increment),
        ``posterior_predictive`` and ``observed_data`` (Π on the grid).
    """
    return fit_draws(posterior, chains, derived, rng, attrs).to_inference_data()
