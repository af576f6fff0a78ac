"""The single-run Bayesian fit: recording → Π increments → posterior of ζ and μ_k.

:func:`fit` chains the steps, each in its own module:

1. :func:`bayestribo.signal.decay.energy_decay`: the analysed window, y, y', E and the
   noise measured at rest;
2. :func:`bayestribo.signal.noise.noise_model`: nominal resolution against measured noise;
3. :func:`bayestribo.signal.increments.pi_data`: Π increments and their exact noise variances;
4. :class:`bayestribo.inference.posterior.Posterior`: priors × likelihood (the equilibrium
   error marginalised);
5. :mod:`bayestribo.inference.start`: maximum a posteriori and starting walkers;
6. :func:`bayestribo.inference.sampling.run_ensembles`: emcee to convergence;
7. derived quantities, pointwise log-likelihood, posterior predictive, prior
   sensitivity, and an :class:`~bayestribo.inference.result.FitResult`.
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from bayestribo import __version__
from bayestribo.errors import ConvergenceWarning, MisfitWarning
from bayestribo.inference.likelihood import MODELS, PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Prior, PriorSet, default_priors
from bayestribo.inference.result import FitResult, _plain
from bayestribo.inference.sampling import SamplerRun, SamplerSettings, run_ensembles
from bayestribo.inference.start import initial_walkers, maximum_a_posteriori
from bayestribo.signal.decay import EnergyDecay, energy_decay
from bayestribo.signal.increments import PiData, pi_data
from bayestribo.signal.noise import NoiseModel, noise_model

__all__ = ["build_posterior", "fit", "prior_sensitivity"]

_PREDICTIVE_DRAWS = 400


def prior_sensitivity(
    draws: NDArray, priors: PriorSet, alphas: tuple[float, float] = (0.5, 2.0)
) -> dict[str, dict[str, float]]:
    """Power-scaling sensitivity of the posterior to its prior (Kallioinen et al. 2023).

    The prior is raised to the power α (weakened for α < 1, strengthened for α > 1)
    by importance-reweighting the posterior draws with p(θ)^(α-1); for each parameter
    the largest shift of the posterior mean over the two α, in posterior standard
    deviations, is reported, with the prior-to-posterior contraction
    1 - var_post/var_prior. Uniform priors give no shift inside their support: the
    shift is then exactly 0, and a shift above 0.1 sd means the prior matters.

    Parameters
    ----------
    draws : ndarray
        Posterior draws of the sampled parameters, shape (n, d), in ``priors`` order.
    priors : PriorSet
    alphas : tuple of float
        Powers applied to the prior.
    """
    log_prior = priors.logpdf(draws)
    log_prior = log_prior - np.max(log_prior)
    out = {}
    sd = np.std(draws, axis=0, ddof=1)
    mean = np.mean(draws, axis=0)
    shifts = []
    for alpha in alphas:
        logw = (alpha - 1.0) * log_prior
        w = np.exp(logw - np.max(logw))
        w /= w.sum()
        shifts.append(np.abs(w @ draws - mean) / np.where(sd > 0, sd, 1.0))
    shift = np.max(shifts, axis=0)
    rng = np.random.default_rng(0)
    for i, name in enumerate(priors.names):
        prior_sd = float(np.std(priors[name].sample(rng, 20_000)))
        contraction = 1.0 - (sd[i] / prior_sd) ** 2 if prior_sd > 0 else float("nan")
        out[name] = {"mean_shift_sd": float(shift[i]), "contraction": float(contraction)}
    return out


def build_posterior(
    data: PiData,
    *,
    model: str = "exact",
    friction: bool = True,
    discrepancy: bool = False,
    priors: Mapping[str, Prior] | None = None,
) -> Posterior:
    """The fit's posterior for observed Π increments: default priors and likelihood.

    The equilibrium nuisance gets prior standard deviations of 1 % of the initial
    amplitude (δ₀) and 1 % of it over the analysed window (δ₁), hundreds of times
    the errors of the equilibrium estimate.

    Parameters
    ----------
    data : PiData
        Observed increments (:func:`bayestribo.signal.increments.pi_data`).
    model : {"exact", "averaged"}
        Forward model.
    friction : bool
        Fit μ_k and μ_s/μ_k (False: viscous damping only).
    discrepancy : bool
        Add the model-discrepancy term.
    priors : mapping, optional
        Replacement priors by parameter name.
    """
    prior_set = default_priors(data.y0, friction=friction, discrepancy=discrepancy)
    if priors:
        prior_set = prior_set.replace(**dict(priors))
    likelihood = PiLikelihood(
        data,
        model=model,  # type: ignore[arg-type]
        offset_sd=max(1e-2 * abs(data.y0), 1e-12),
        drift_sd=max(1e-2 * abs(data.y0) / data.tau_end, 1e-15),
    )
    return Posterior(prior_set, likelihood)


def _read(run: Any, read_kwargs: Mapping[str, Any]) -> tuple[Any, str]:
    from bayestribo.io import read_run

    if isinstance(run, str | Path):
        return read_run(run, **read_kwargs), str(run)
    name = getattr(run, "source", None) or dict(getattr(run, "metadata", {})).get("run_id", "")
    return run, str(name)


def _derived(
    posterior: Posterior,
    draws: NDArray,
    decay: EnergyDecay,
    metadata: Mapping[str, Any],
    rng: np.random.Generator,
) -> dict[str, NDArray]:
    """Sampled and derived quantities by name, from flat draws (n, d)."""
    names = posterior.names
    col = {name: draws[:, i] for i, name in enumerate(names)}
    out: dict[str, NDArray] = {}
    sc = decay.scaling
    out["zeta"] = col["zeta"]
    if posterior.friction:
        mu_k = col["mu_k"]
        out["mu_s_ratio"] = col["mu_s_ratio"]
        friction_disp = mu_k * sc.length_scale
        if sc.friction_defined:
            # Calibration nuisances: μ_k = x_c k/N with N and m drawn from their
            # stated uncertainties (the data fix x_c, not N or k).
            load = float(metadata["load_N"])
            mass = float(metadata["mass_kg"])
            n_draw = _positive_draws(rng, load, metadata.get("load_uncertainty_N"), mu_k.size)
            m_draw = _positive_draws(rng, mass, metadata.get("mass_uncertainty_kg"), mu_k.size)
            out["mu_k"] = mu_k * (load / n_draw) * (m_draw / mass)
            out["mu_s"] = out["mu_k"] * col["mu_s_ratio"]
        else:
            out["mu_s"] = friction_disp * col["mu_s_ratio"]
            n_draw = m_draw = None
        out["friction_displacement"] = friction_disp
    else:
        n_draw = m_draw = None
    out["y0"] = col["y0"]
    if "log10_discrepancy" in col:
        out["log10_discrepancy"] = col["log10_discrepancy"]

    zeta0 = metadata.get("zeta0")
    if zeta0 is not None and posterior.friction:
        z0 = _positive_draws(rng, float(zeta0), metadata.get("zeta0_sd"), draws.shape[0])
        out["zeta_k"] = col["zeta"] - z0
        if n_draw is not None and m_draw is not None:
            k_draw = m_draw * sc.omega**2
            out["d_k"] = 2.0 * out["zeta_k"] * np.sqrt(k_draw * m_draw) / n_draw
    return out


def _positive_draws(rng: np.random.Generator, value: float, sd: float | None, size: int) -> NDArray:
    if sd is None or sd == 0:
        return np.full(size, value)
    draws = rng.normal(value, float(sd), size)
    while np.any(draws <= 0):  # a normal truncated to positive values
        bad = draws <= 0
        draws[bad] = rng.normal(value, float(sd), int(bad.sum()))
    return draws


def _inference_data(
    posterior: Posterior,
    sampler: SamplerRun,
    derived: dict[str, NDArray],
    data: PiData,
    rng: np.random.Generator,
    attrs: dict[str, Any],
) -> Any:
    import arviz as az

    n_chain, n_draw, _ = sampler.chains.shape
    flat = sampler.chains.reshape(-1, sampler.chains.shape[-1])
    pointwise = np.concatenate(
        [posterior.pointwise(block) for block in np.array_split(flat, max(1, flat.shape[0] // 256))]
    )
    # Posterior predictive Π: model increments plus noise (and discrepancy), for a
    # subset of the draws, with the conditional equilibrium offset applied.
    pick = np.sort(
        rng.choice(flat.shape[0], size=min(_PREDICTIVE_DRAWS, flat.shape[0]), replace=False)
    )
    p = posterior.physical(flat[pick])
    lik = posterior.likelihood
    model_inc = lik.model_increments(p["zeta"], p["mu_k"], p["mu_s"], p["y0"])
    delta = lik.offset(p["zeta"], p["mu_k"], p["mu_s"], p["y0"], p["discrepancy"])
    var = np.broadcast_to(lik.variance(p["discrepancy"]), model_inc.shape)
    replicated = model_inc + delta @ data.offset_design.T + rng.normal(0.0, np.sqrt(var))
    pi_rep = np.cumsum(replicated[:, ::-1], axis=1)[:, ::-1]

    def shaped(values: NDArray) -> NDArray:
        return values.reshape(n_chain, n_draw, *values.shape[1:])

    tau = data.tau_grid[:-1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        idata = az.from_dict(
            posterior={k: shaped(v) for k, v in derived.items()},
            log_likelihood={"pi": shaped(pointwise)},
            posterior_predictive={"pi": pi_rep[None, :, :]},
            observed_data={"pi": data.pi},
            coords={"increment": np.arange(data.increments.size), "grid": tau},
            dims={"pi": ["grid"]},
            pred_dims={"pi": ["grid"]},
            log_likelihood_dims={"pi": ["increment"]},
        )
    idata.posterior.attrs.update(attrs)
    return idata


def fit(
    run: Any,
    *,
    model: str = "exact",
    seed: int | None = None,
    n_walkers: int = 16,
    n_ensembles: int = 2,
    max_steps: int = 20_000,
    discrepancy: bool = False,
    priors: Mapping[str, Prior] | None = None,
    grid_points: int | None = None,
    skip_oscillations: int = 1,
    progress: bool = False,
    read_kwargs: Mapping[str, Any] | None = None,
    noise: NoiseModel | None = None,
) -> FitResult:
    """Posterior of ζ and μ_k (or ζ₀, or the friction displacement) for one run.

    Parameters
    ----------
    run : Run or path
        The recording (:class:`bayestribo.io.run.Run`) or a file for
        :func:`bayestribo.read_run` (with ``read_kwargs``).
    model : {"exact", "averaged"}
        Forward model of Π (the exact one by default; the averaged one is biased by
        about 2ζ² of Π, far more than the noise of a good record).
    seed : int, optional
        Seed of everything random in the fit (walkers, moves, predictive draws).
    n_walkers, n_ensembles, max_steps : int
        Sampler size: walkers per ensemble, independent ensembles, step ceiling.
    discrepancy : bool
        Add the model-discrepancy term (a relative error on E with its own prior).
    priors : mapping, optional
        Replacement priors by parameter name (see :func:`default_priors`).
    grid_points : int, optional
        Number of Π increments; default one per half cycle (see
        :mod:`bayestribo.signal.increments`).
    skip_oscillations : int
        Oscillations skipped after the release.
    progress : bool
        Show a progress bar.
    read_kwargs : mapping, optional
        Passed to :func:`bayestribo.read_run` when ``run`` is a path.
    noise : NoiseModel, optional
        Use this noise model instead of the recording's.

    Returns
    -------
    FitResult
        A run that did not converge is returned with ``converged`` False and a
        :class:`~bayestribo.errors.ConvergenceWarning` is raised as a warning.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    start = time.perf_counter()
    recording, name = _read(run, read_kwargs or {})
    metadata = dict(recording.metadata)
    rig = recording.rig()
    decay = energy_decay(
        recording.time,
        recording.displacement,
        recording.velocity,
        rig=rig,
        skip_oscillations=skip_oscillations,
    )
    noise_used = noise or noise_model(decay, metadata)
    rng = np.random.default_rng(seed)
    data = pi_data(decay, noise_used, grid_points=grid_points, seed=int(rng.integers(2**31)))

    contact = not (metadata.get("load_N") == 0)
    posterior = build_posterior(
        data, model=model, friction=contact, discrepancy=discrepancy, priors=priors
    )
    prior_set = posterior.priors
    theta, cov, ratio_range = maximum_a_posteriori(posterior, decay)
    settings = SamplerSettings(n_walkers=n_walkers, n_ensembles=n_ensembles, max_steps=max_steps)
    walkers = initial_walkers(posterior, theta, cov, ratio_range, n_ensembles, n_walkers, rng)
    sampler = run_ensembles(
        posterior, walkers, settings, seed=int(rng.integers(2**31)), progress=progress
    )

    # Goodness of fit at the optimum: χ² of the standardized increment residuals. With
    # the model and noise right it is χ²(m); far above, the intervals are too narrow
    # unless the discrepancy term is on.
    resid = posterior.standardized_residuals(theta[None])[0]
    chi2 = float(np.sum(resid * resid))
    misfit_p = float(scipy.stats.chi2.sf(chi2, resid.size))
    if misfit_p < 1e-3 and not discrepancy:
        warnings.warn(
            f"the model misfits {name or 'the run'} beyond its noise (χ² = {chi2:.0f} for "
            f"{resid.size} increments, p = {misfit_p:.1e}): its intervals are too narrow; "
            "fit with discrepancy=True (--discrepancy) to widen them by the misfit",
            MisfitWarning,
            stacklevel=2,
        )
    flat = sampler.chains.reshape(-1, sampler.chains.shape[-1])
    derived = _derived(posterior, flat, decay, metadata, rng)
    if not decay.scaling.friction_defined and "mu_k" in derived:
        derived.pop("mu_k")
    diagnostics = {
        "converged": sampler.converged,
        "reasons": sampler.reasons,
        "n_walkers": n_walkers,
        "n_ensembles": n_ensembles,
        "n_steps": sampler.n_steps,
        "burn": sampler.burn,
        "thin": sampler.thin,
        "autocorr_time": dict(zip(posterior.names, sampler.autocorr_time.tolist(), strict=True)),
        "autocorr_time_max": float(np.max(sampler.autocorr_time)),
        "ess": dict(zip(posterior.names, sampler.ess.tolist(), strict=True)),
        "ess_min": float(np.min(sampler.ess)),
        "rhat": dict(zip(posterior.names, sampler.rhat.tolist(), strict=True)),
        "rhat_max": float(np.max(sampler.rhat)),
        "acceptance_fraction": sampler.acceptance_fraction,
        "map": dict(zip(posterior.names, theta.tolist(), strict=True)),
        "chi2_map": chi2,
        "n_increments": int(resid.size),
        "misfit_p": misfit_p,
    }
    noise_info = {**noise_used.to_dict(), "description": noise_used.describe()}
    attrs = {
        "run_name": name,
        "model": model,
        "seed": -1 if seed is None else int(seed),
        "package_version": __version__,
        "friction_defined": int(decay.scaling.friction_defined),
        "length_scale": decay.scaling.length_scale,
        "omega": decay.scaling.omega,
        "tau_end": data.tau_end,
        "motion_ended": int(data.motion_ended),
        "metadata_json": json.dumps(_plain(metadata)),
        "noise_json": json.dumps(_plain(noise_info)),
        "priors_json": json.dumps(prior_set.to_spec()),
        "settings_json": json.dumps(
            {
                "grid_points": grid_points,
                "skip_oscillations": skip_oscillations,
                "discrepancy": discrepancy,
                "max_steps": max_steps,
            }
        ),
        "diagnostics_json": json.dumps(_plain(diagnostics)),
        "prior_sensitivity_json": json.dumps(_plain(prior_sensitivity(flat, prior_set))),
    }
    idata = _inference_data(posterior, sampler, derived, data, rng, attrs)
    result = FitResult(idata)
    idata.posterior.attrs["seconds"] = time.perf_counter() - start
    if not sampler.converged:
        warnings.warn(
            f"the sampler did not converge on {name or 'the run'}: " + "; ".join(sampler.reasons),
            ConvergenceWarning,
            stacklevel=2,
        )
    return result
