"""The result of a single-run fit: an ArviZ InferenceData and what a report needs.

:class:`FitResult` holds, or makes on first use of :attr:`FitResult.idata`, an
:class:`arviz.InferenceData` with the groups

* ``posterior``: the sampled parameters (``zeta``; with friction ``mu_k`` or, without a
  load, ``friction_displacement``, ``mu_s_ratio``; ``y0``; optionally
  ``log10_discrepancy``) and the derived quantities (``mu_s``,
  ``friction_displacement`` in the displacement's unit, ``zeta_k`` = ζ - ζ₀ when the
  run's metadata give ``zeta0``, ``d_k`` [s/m] when they also give the load and the
  mass); dims ``(chain, draw)``, a chain being one independent ensemble;
* ``log_likelihood``: ``pi``, the pointwise log-likelihood of each Π increment
  (dim ``increment``), so that :func:`arviz.loo` works;
* ``posterior_predictive``: ``pi``, replicated Π on the grid (dim ``grid``);
* ``observed_data``: ``pi``, the observed Π on the grid, with coordinate ``tau``;

and, in its attributes, the run's metadata, the seed, the model, the noise model, the
priors, the sampler settings and the diagnostics (JSON strings), so that a saved
NetCDF file is a complete record of the fit.

A fresh fit holds these groups as numpy arrays
(:class:`~bayestribo.inference.assemble.FitDraws`) and imports ArviZ only when the
InferenceData itself is asked for (saving it, plotting, PSIS-LOO): its summaries,
diagnostics, text and JSON need numpy alone, so ``bayestribo fit`` does not pay for
importing ArviZ, xarray and pandas.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from collections.abc import Mapping
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo._files import atomic_path
from bayestribo.inference.fit_record import FitRecord, plain_data
from bayestribo.inference.priors import PriorSet, widened_prior
from bayestribo.inference.quantities import (
    DERIVED,
    Quantity,
    QuantitySummary,
    describe,
    unit_words,
)
from bayestribo.summary import ParameterSummary, check_prob

if TYPE_CHECKING:
    from bayestribo.inference.assemble import FitDraws

__all__ = ["UNITS", "FitResult", "plain_data"]

#: Backend of the fit files (:meth:`FitResult.save`, :meth:`FitResult.load`).
NETCDF_ENGINE = "netcdf4"

#: The output names the sensor's gain's share of a quantity's posterior variance from
#: this fraction up (:func:`bayestribo.signal.sensor.gain_variance_share`).
GAIN_SHARE_SHOWN = 0.1

#: Quantities reported by :meth:`FitResult.summary` and the command line, in order.
REPORTED = (
    "zeta",
    "mu_k",
    "mu_s",
    "friction_displacement",
    "static_friction_displacement",
    "friction_torque",
    "static_friction_torque",
    "zeta_k",
    "d_k",
    "y0",
    "log10_discrepancy",
    "log10_shape",
)


#: Unit of each reported quantity of the default law ("1" when dimensionless);
#: "length" is the displacement's unit (m, rad for a rotation, or the signal's unit for
#: a run with ``length_unit="arbitrary"``). The same as
#: :func:`bayestribo.inference.quantities.describe` gives (:meth:`FitResult.units`).
UNITS: dict[str, str] = {
    "zeta": "1",
    "mu_k": "1",
    **{name: unit for name, (_, _, unit) in DERIVED.items()},
}


class FitResult:
    """Posterior of one run, with diagnostics and provenance.

    Parameters
    ----------
    idata : arviz.InferenceData, optional
        The posterior and its companions (see the module notes).
    draws : FitDraws, optional
        The same groups as numpy arrays (what a fit makes); the InferenceData is
        then built from them on first use of :attr:`idata`. Give one of the two.

    Raises
    ------
    TypeError
        If neither or both of ``idata`` and ``draws`` are given.
    """

    def __init__(self, idata: Any = None, *, draws: FitDraws | None = None) -> None:
        if (idata is None) == (draws is None):
            raise TypeError("FitResult: give either idata or draws")
        self._idata = idata
        self._draws = draws

    @property
    def idata(self) -> Any:
        """The :class:`arviz.InferenceData` of the fit (see the module notes); for a
        fresh fit, built from its draws on first use (this imports ArviZ)."""
        if self._idata is None:
            assert self._draws is not None
            self._idata = self._draws.to_inference_data()
            self._draws = None  # from now on the InferenceData is the one record
        return self._idata

    @property
    def attrs(self) -> dict[str, Any]:
        """The attributes of the posterior group (run, settings, diagnostics as JSON
        strings), the record :meth:`save` writes; changes are kept (whether or not
        the InferenceData was built yet)."""
        if self._draws is not None:
            return self._draws.attrs
        return self._idata.posterior.attrs

    def _posterior_names(self) -> list[str]:
        if self._draws is not None:
            return list(self._draws.posterior)
        return list(self._idata.posterior.data_vars)

    def _has(self, name: str) -> bool:
        if self._draws is not None:
            return name in self._draws.posterior
        return name in self._idata.posterior

    def _chains(self, name: str) -> NDArray:
        if self._draws is not None:
            return np.asarray(self._draws.posterior[name])
        return np.asarray(self._idata.posterior[name])

    # -- provenance (from the attributes) -----------------------------------------
    @property
    def record(self) -> FitRecord:
        """Everything the fit records beside its draws, typed
        (:class:`~bayestribo.inference.fit_record.FitRecord`, read from :attr:`attrs`)."""
        return FitRecord.from_attrs(self.attrs)

    def _attr(self, key: str, default: Any = None) -> Any:
        value = self.attrs.get(key, default)
        if isinstance(value, str) and key.endswith("_json"):
            return json.loads(value)
        return value

    @property
    def run_name(self) -> str:
        """Name (path or id) of the fitted run."""
        return str(self._attr("run_name", ""))

    @property
    def metadata(self) -> dict[str, Any]:
        """The run's metadata."""
        return self._attr("metadata_json", {})

    @property
    def model(self) -> str:
        """Forward model: ``"exact"`` or ``"averaged"``."""
        return str(self._attr("model"))

    @property
    def law(self) -> str:
        """The dissipation law fitted (terms joined with ``+``; fits saved before laws
        were plug-ins are ``"viscous+coulomb"``)."""
        return str(self._attr("law", "viscous+coulomb"))

    @property
    def dissipation(self) -> dict[str, Any] | None:
        """Energy the law dissipates per cycle, ΔE(A), at the swings of the analysed
        motion (:func:`bayestribo.inference.dissipation.dissipation_band`):
        ``amplitude``, ``mean``, ``sd``, ``interval``, ``prob``, ``unit``, ``by_term``,
        ``harmonic_mean``. With ``law="auto"`` and several adequate laws as good as the
        verdict, their posteriors mixed (``laws`` lists them,
        :func:`~bayestribo.inference.dissipation.averaged_dissipation`; the verdict's own
        band is :attr:`verdict_dissipation`). None for fits saved before it was
        recorded."""
        return self._attr("dissipation_json", None)

    @property
    def verdict_dissipation(self) -> dict[str, Any] | None:
        """The verdict law's own ΔE(A) band when :attr:`dissipation` is averaged over
        several laws, else the same as :attr:`dissipation`."""
        return self._attr("verdict_dissipation_json", None) or self.dissipation

    @property
    def turning_point_dissipation(self) -> dict[str, Any] | None:
        """ΔE(A) measured from the turning points alone, whatever the law, at the same
        swings (:func:`bayestribo.inference.dissipation.turning_point_dissipation`):
        the law-free answer when no law holds; None with too few cycles or for fits
        saved before it was recorded."""
        return self._attr("turning_point_dissipation_json", None)

    @property
    def restoring(self) -> dict[str, Any] | None:
        """The oscillator's restoring force as the fit took it: ``name``, what was
        measured of it (a Duffing spring's ``beta`` and ``beta_se``, their ``error`` in
        the intervals), ``in_model``, and for ``restoring="auto"`` the choice and why
        (``auto``: :meth:`~bayestribo.inference.restoring_choice.RestoringChoice.
        to_dict` with its ``description``); None for fits saved before it was recorded."""
        return self._attr("restoring_json", None)

    @property
    def law_comparison(self) -> dict[str, Any] | None:
        """How ``law="auto"`` chose the law (:class:`~bayestribo.inference.records.
        LawComparison` as plain data: ``verdict``, ``best``, ``as_good``, ``adequate``,
        ``table``), None for a fit of a named law."""
        return self._attr("law_comparison_json", None)

    @property
    def boundary(self) -> dict[str, Any] | None:
        """The law's boundaries (:mod:`bayestribo.inference.boundary`): the ``law``
        averaged; per boundary parameter (``mu_k`` for no friction, ``zeta`` for no
        viscous damping, ``c2`` for no quadratic drag, ...) its Savage–Dickey
        ``density_ratio``, the nested law's posterior ``probability`` and its ``law``
        (``parameters``); ``mixed``, the parameters whose nested law's fit was mixed
        into the draws (empty: the full law's draws as sampled), with each one's
        ``law``, ``share`` of the draws and, where that law was averaged over its own
        boundaries, its ``boundary`` record (``nested``). None for a law of one term,
        ``law="auto"``, the law-free fit, or a fit with one of the law's parameters
        fixed.
        """
        return self._attr("boundary_json", None)

    @property
    def seed(self) -> int | None:
        """Seed of the sampler (``None`` if the run was not seeded)."""
        seed = self._attr("seed")
        return None if seed is None or seed == -1 else int(seed)

    @property
    def noise(self) -> dict[str, Any]:
        """The noise model used (see :class:`bayestribo.signal.noise.NoiseModel`)."""
        return self._attr("noise_json", {})

    @property
    def diagnostics(self) -> dict[str, Any]:
        """Convergence diagnostics: converged, n_walkers, n_steps, autocorr_time_max,
        ess_min, acceptance_fraction, rhat_max, and the reasons when not converged."""
        return self._attr("diagnostics_json", {})

    @property
    def converged(self) -> bool:
        """True when the sampler met every convergence criterion."""
        return bool(self.diagnostics.get("converged", False))

    @property
    def at_prior_bound(self) -> list[dict[str, Any]]:
        """Parameters whose posterior piles on a physical bound of their prior."""
        return list(self.diagnostics.get("at_prior_bound", []))

    @property
    def usable(self) -> bool:
        """Converged, and no posterior piled on a prior bound: a measurement."""
        return self.converged and not self.at_prior_bound

    @property
    def priors(self) -> PriorSet:
        """The priors of the sampled parameters."""
        return PriorSet.from_spec(self._attr("priors_json", {}))

    @property
    def prior_sensitivity(self) -> dict[str, Any]:
        """Power-scaling prior sensitivity per parameter (see :func:`prior_sensitivity`)."""
        return self._attr("prior_sensitivity_json", {})

    @property
    def seconds(self) -> float:
        """Wall time of the fit [s]."""
        return float(self._attr("seconds", float("nan")))

    # -- draws ----------------------------------------------------------------------
    @property
    def parameter_names(self) -> list[str]:
        """Every quantity in the posterior group (sampled and derived)."""
        return self._posterior_names()

    def samples(self, name: str) -> NDArray:
        """All posterior draws of ``name``, chains concatenated (1-D)."""
        if not self._has(name):
            raise KeyError(
                f"{name!r} is not in this fit's posterior; it has {self.parameter_names}"
            )
        return self._chains(name).reshape(-1)

    def prior_logpdf(self, name: str, values: ArrayLike) -> NDArray:
        """Log density of the prior of one sampled parameter at ``values``.

        ``friction_displacement`` is accepted for a run fitted without a load (it is
        the sampled friction parameter there).
        """
        priors = self.priors
        key = name
        sampled_as_mu_k = "mu_k" in priors.names and not self._friction_defined
        if name == "friction_displacement" and sampled_as_mu_k:
            key = "mu_k"
        if key not in priors.names:
            raise KeyError(f"{name!r} has no prior of its own; sampled: {priors.names}")
        return priors[key].logpdf(values)

    @property
    def _friction_defined(self) -> bool:
        return bool(self._attr("friction_defined", 0))

    def interval(self, name: str, prob: float = 0.95) -> tuple[float, float]:
        """Credible interval of ``name`` with probability ``prob``, as :meth:`summary`
        gives it: equal-tailed, or, for a quantity the data do not constrain, from its
        prior's lower end to the one-sided bound
        (:func:`~bayestribo.inference.flatness.bound_interval`)."""
        from bayestribo.inference.flatness import prior_end_interval

        check_prob(prob)
        draws = self.samples(name)
        fit = SimpleNamespace(priors=self.priors, samples=self.samples)
        from_end = prior_end_interval(fit, name, draws, prob)
        if from_end is not None:
            return from_end[0]
        return ParameterSummary.from_samples(draws, prob).interval

    def _summary_names(self) -> list[str]:
        """Every quantity of the posterior group, in the order of the summaries: those
        of the default law (:data:`REPORTED`), the law's own parameters and physical
        quantities, the other sampled ones (μ_s/μ_k), then y₀ and the scales."""
        names = [n for n in REPORTED if self._has(n)]
        own = [n for n in self._attr("units_json", {}) if self._has(n) and n not in names]
        rest = [n for n in self.parameter_names if n not in names and n not in own]
        at = names.index("y0") if "y0" in names else len(names)
        names[at:at] = own + rest
        return names

    def _sampled_names(self) -> set[str]:
        """Quantities of the posterior group that are sampled coordinates."""
        sampled = set(self.priors.names)
        if "mu_k" in sampled and not self._has("mu_k"):
            sampled.add("friction_displacement")  # no load: x_c is the sampled friction
        return sampled

    def quantity_info(self) -> dict[str, Quantity]:
        """What each quantity of the posterior group is: symbol, name in words and unit,
        from the registry of dissipation terms
        (:func:`bayestribo.inference.quantities.describe`), in the order of
        :meth:`summary`.

        Returns
        -------
        dict of str to Quantity
            By name (``"zeta"``, ``"mu_k"``, ``"mu_s_ratio"``, ...).
        """
        return describe(
            self._summary_names(),
            law=self.law,
            metadata=self.metadata,
            units=self._attr("units_json", {}) or {},
            sampled=self._sampled_names(),
            friction_defined=self._friction_defined,
        )

    def summary(self, prob: float = 0.95) -> dict[str, QuantitySummary]:
        """Posterior summary of every quantity of the fit: each sampled parameter
        (the law's, μ_s/μ_k, y₀, the discrepancy scales) and each derived one.

        Parameters
        ----------
        prob : float
            Probability of the equal-tailed credible intervals, in (0, 1).

        Returns
        -------
        dict of str to QuantitySummary
            By name, in the order: the quantities of the default law (ζ, μ_k, μ_s,
            x_c, ...), the other laws' parameters and physical quantities, the other
            sampled ones (μ_s/μ_k), then y₀ and the scales. Each record
            (:class:`~bayestribo.inference.quantities.QuantitySummary`, a
            :class:`~bayestribo.summary.ParameterSummary`) holds ``mean``, ``sd``,
            ``median`` and ``interval`` (low, high) in the quantity's ``unit``,
            ``prob``, ``kind``, ``name``, ``symbol``, ``label`` (the name in words),
            ``unit`` (``"1"`` when dimensionless), ``sampled``, ``ess`` and ``r_hat``.
            A quantity the data do not constrain (its posterior is its prior's up to a
            bound, :func:`~bayestribo.inference.flatness.prior_flatness`: μ_s/μ_k of a
            record that never sticks) has ``kind`` ``"bound"`` and the one-sided
            interval from the prior's lower end to the bound the text table prints
            (:func:`~bayestribo.inference.flatness.bound_interval`).

        Raises
        ------
        BayestriboError
            If ``prob`` is not in (0, 1).
        """
        check_prob(prob)
        from bayestribo.inference.flatness import prior_end_interval

        n_walkers = self.diagnostics.get("n_walkers")
        # the priors read once (each reading parses them), the draws as they are
        fit = SimpleNamespace(priors=self.priors, samples=self.samples)
        out = {}
        for name, q in self.quantity_info().items():
            draws = self._chains(name)
            s = QuantitySummary.of(q, draws, prob, n_walkers)
            # the prior's, up to a bound (never a central interval), or a static
            # friction's from the prior's end where its lowest step starts there
            from_end = prior_end_interval(fit, name, draws, prob)
            if from_end is not None:
                s = dataclasses.replace(s, interval=from_end[0], kind=from_end[1])
            out[name] = s
        return out

    def to_dataframe(self, prob: float = 0.95) -> Any:
        """The posterior summary as a table, one row per quantity (:meth:`summary`).

        Parameters
        ----------
        prob : float
            Probability of the equal-tailed credible interval, in (0, 1).

        Returns
        -------
        pandas.DataFrame
            Index ``name`` (``"zeta"``, ...); columns ``symbol``, ``label`` (the name in
            words), ``unit`` (``"1"`` when dimensionless; ``unit_words`` as a reader
            reads it), ``mean``, ``sd``, ``median``, ``low`` and ``high`` (the ends
            of the ``prob`` interval), all in the quantity's unit, ``prob``, ``kind``
            (``"bound"`` for a quantity the data do not constrain, its interval from
            the prior's lower end), ``ess`` (effective sample size), ``r_hat`` and
            ``sampled``.

        Raises
        ------
        BayestriboError
            If ``prob`` is not in (0, 1).
        """
        import pandas as pd

        rows = [
            {
                "name": name,
                "symbol": s.symbol,
                "label": s.label,
                "unit": s.unit,
                "unit_words": unit_words(s.unit),
                "mean": s.mean,
                "sd": s.sd,
                "median": s.median,
                "low": s.low,
                "high": s.high,
                "prob": s.prob,
                "kind": s.kind,
                "ess": s.ess,
                "r_hat": s.r_hat,
                "sampled": s.sampled,
            }
            for name, s in self.summary(prob).items()
        ]
        return pd.DataFrame(rows).set_index("name")

    def plot(self, kind: str = "pi", fig: Any = None, **kwargs: Any) -> Any:
        """A figure of the fit (:func:`bayestribo.inference.plots.plot_fit`).

        Parameters
        ----------
        kind : {"pi", "decay", "corner", "trace"}
            ``"pi"`` (or ``"decay"``): the observed Π(τ) against the fitted model's
            posterior predictive band, with standardized residuals; ``"corner"``: the
            pairwise marginal posteriors; ``"trace"``: the draws of each ensemble.
        fig : matplotlib.figure.Figure, optional
            An empty figure to draw on; default a new one.
        **kwargs
            Passed on (``prob`` for ``"pi"``; ``names`` for ``"corner"`` and
            ``"trace"``).

        Returns
        -------
        matplotlib.figure.Figure
            The figure (its axes: ``fig.axes``); nothing is shown or saved.

        Raises
        ------
        ValueError
            If ``kind`` is unknown (the kinds are named).
        """
        from bayestribo.inference.plots import plot_fit

        return plot_fit(self, kind, fig, **kwargs)

    @property
    def frequency_trend(self) -> dict[str, Any] | None:
        """The half period's change with amplitude along the decay (``change``, ``z``):
        zero for the linear law (see :func:`bayestribo.signal.frequency.frequency_trend`)."""
        return self._attr("frequency_trend_json", None)

    @property
    def settings(self) -> dict[str, Any]:
        """The fit's settings: grid points, skipped oscillations, discrepancy, step
        ceiling and the mains line subtracted (``notch_Hz``)."""
        return dict(self._attr("settings_json", {}) or {})

    @property
    def spec(self) -> Any:
        """The :class:`~bayestribo.inference.spec.FitSpec` the fit was made with (None
        for a fit saved before specifications were recorded, or made by a pipeline of
        one's own). ``bayestribo.fit(run, spec=result.spec)`` fits it again alike."""
        from bayestribo.inference.spec import FitSpec

        data = self._attr("spec_json", None)
        return None if data is None else FitSpec.from_dict(data)

    @property
    def channel_calibration(self) -> dict[str, Any] | None:
        """The channels' gain ratio and delay measured from the motion, and whether
        the velocity was corrected (None for a run with one signal)."""
        return self._attr("channels_json", None)

    @property
    def sensor(self) -> dict[str, Any] | None:
        """The signal chain's gain as the fit drew it into the reported lengths
        (:mod:`bayestribo.signal.sensor`): ``gain``, its relative sd ``gain_sd``,
        whether it was ``stated``, the sensor's ``kind``, the ``filter``, the
        output's ``description``, and ``variance_share``: for each quantity, the
        fraction of its posterior variance the gain's draws make
        (:func:`bayestribo.signal.sensor.gain_variance_share`; absent in fits made
        before it was recorded). None for a fit that recorded no sensor."""
        return self._attr("sensor_json", None)

    def _gain_share_text(self, sensor: dict[str, Any]) -> str:
        """Where the gain makes a tenth or more of a reported quantity's posterior
        variance, how much (``"; of the posterior variance, the gain makes 93 % of
        μ_k's"``)."""
        shares = sensor.get("variance_share") or {}
        parts = [
            f"{100 * shares[name]:.0f} % of {quantity.symbol}'s"
            for name, quantity in self.quantity_info().items()
            if shares.get(name, 0.0) >= GAIN_SHARE_SHOWN
        ]
        if not parts:
            return ""
        return f"; of the posterior variance, the gain makes {', '.join(parts)}"

    @property
    def symbols(self) -> dict[str, str]:
        """The symbol of each of the law's parameters (``{"zeta": "ζ", ...}``); empty
        for a law this version does not register."""
        from bayestribo.model.laws import get_law

        try:
            return {p.name: p.symbol for p in get_law(self.law).parameters}
        except ValueError:
            return {}

    @property
    def law_departs(self) -> bool:
        """True when the decay departs from the law smoothly beyond its noise (the shape
        test of :meth:`~bayestribo.inference.likelihood.PiLikelihood.shape_departure`,
        p below the misfit threshold :data:`bayestribo.inference.types.MISFIT_P`), or when
        the law's ΔE(A) has another shape than the turning points' (:attr:`shape_agreement`)."""
        from bayestribo.inference.types import MISFIT_P

        p = (self.diagnostics.get("shape_departure") or {}).get("p_value")
        agreement = self.shape_agreement
        other_shape = agreement is not None and not agreement.get("same_shape", True)
        return (p is not None and p < MISFIT_P) or other_shape

    @property
    def shape_agreement(self) -> dict[str, Any] | None:
        """How close the law's ΔE(A) comes to the turning points'
        (:func:`~bayestribo.inference.dissipation.shape_agreement`: departures in
        percent, log-log slopes, ``same_shape``); None without a turning-point answer or
        for fits saved before it was recorded."""
        return self._attr("shape_agreement_json", None)

    @property
    def package_version(self) -> str:
        """The bayestribo version that made the fit."""
        return str(self._attr("package_version", "unknown"))

    def units(self) -> dict[str, str]:
        """Unit of each quantity of :meth:`summary` ("1" for a dimensionless one; the
        displacement's unit ``"m"``, ``"rad"`` or ``"signal length unit"``)."""
        return {name: q.unit for name, q in self.quantity_info().items()}

    def to_dict(self, prob: float = 0.95) -> dict[str, Any]:
        """JSON-ready record: run, model, seed, package version, run metadata, noise,
        parameters (summaries with ``prob`` intervals and units), diagnostics, seconds."""
        units = self.units()
        return plain_data(
            {
                "run": self.run_name,
                "model": self.model,
                "law": self.law,
                "law_comparison": self.law_comparison,
                "boundary": self.boundary,
                "restoring": self.restoring,
                "seed": self.seed,
                "bayestribo_version": self.package_version,
                "metadata": self.metadata,
                "noise": self.noise,
                "channel_calibration": self.channel_calibration,
                "frequency_trend": self.frequency_trend,
                "parameters": {
                    k: {**v.to_dict(), "unit": units.get(k, "")}
                    for k, v in self.summary(prob).items()
                },
                "dissipation": self.dissipation,
                "turning_point_dissipation": self.turning_point_dissipation,
                "diagnostics": self.diagnostics,
                "prior_sensitivity": self.prior_sensitivity,
                "seconds": self.seconds,
            }
        )

    def to_text(self, prob: float = 0.95) -> str:
        """Human-readable table of the posterior, with ``prob`` intervals."""
        lines = [
            f"run       {self.run_name}",
            f"law       {self.law}  (model {self.model}, seed {self.seed})",
            *self._comparison_lines(),
            f"noise     {self.noise.get('description', '')}",
        ]
        from bayestribo.inference.boundary import describe as describe_boundary

        at_boundary = describe_boundary(self.boundary)
        if at_boundary:
            lines.append(f"boundary  {at_boundary}")
        from bayestribo._plural import count

        d = self.diagnostics
        status = (
            "converged"
            if d.get("converged")
            else "NOT CONVERGED: " + "; ".join(d.get("reasons", []))
        )
        lines.append(
            f"sampler   {status}; {count(d.get('n_walkers'), 'walker')} × "
            f"{count(d.get('n_ensembles'), 'ensemble')} × {count(d.get('n_steps'), 'step')}, "
            f"τ_max {_number(d.get('autocorr_time_max'), '.1f')}, "
            f"ESS_min {_number(d.get('ess_min'), '.0f')}, "
            f"R-hat_max {_number(d.get('rhat_max'), '.4f')}"
        )
        shape = d.get("shape_departure") or {}
        if shape.get("p_value") is not None and shape["p_value"] < 1e-3:
            from bayestribo.inference.likelihood import departure_size

            lines.append(
                "NOT ADEQUATE: the decay departs from the constant law by up to "
                f"{departure_size(shape)} along the decay (χ² = {shape['chi2']:.1f} for "
                f"{shape['dof']} shape terms)"
            )
        sd_eps = float(self.attrs.get("frequency_nuisance_sd", 0.0))
        trend = self.frequency_trend
        if trend and sd_eps > 0:
            lines.append(
                f"frequency half period changes by {100 * trend['change']:+.3g} % along the "
                f"decay ({trend['z']:+.1f} SE); the parameters and ΔE(A) carry "
                f"± {100 * sd_eps:.2g} % for it"
            )
        sensor = self._attr("sensor_json", None)
        if sensor:
            lines.append(f"sensor    {sensor['description']}{self._gain_share_text(sensor)}")
        integrated = self.metadata.get("acceleration")
        if integrated:
            from bayestribo.io.acceleration import describe

            lines.append(f"velocity  {describe(integrated)}")
        high_pass = self.metadata.get("high_pass_undone")
        if high_pass:
            from bayestribo.io.high_pass import describe as describe_high_pass

            lines.append(f"sensor    {describe_high_pass(high_pass)}")
        arm = self.metadata.get("pendulum_arm")
        if arm:
            from bayestribo.io.pendulum_arm import describe as describe_arm

            lines.append(f"angle     {describe_arm(arm)}")
        spring = self._attr("restoring_json", None)
        chosen = (spring or {}).get("auto")
        if chosen and spring.get("name") in (None, "linear"):
            lines.append(f"restoring {chosen['description']}")
        elif spring and spring.get("name") not in (None, "linear"):
            text = f"restoring {chosen['description'] if chosen else spring['name']}"
            if "beta" in spring:
                se = spring.get("beta_se")
                # a standard error the half periods do not define (a singular Jacobian)
                # is null in the record
                spread = f" ± {se:.2g}" if se is not None else " (its standard error undefined)"
                text += f", β = {spring['beta']:.4g}{spread} (from the half periods)"
            error = spring.get("error")
            if error:
                shares = [
                    v
                    for k, v in error["sd_added_over_sd"].items()
                    if k != "y0" and not k.startswith("log10_")
                ]
                text += (
                    f", its error marginalised into the intervals (an sd of at most "
                    f"{100 * max(shares, default=0.0):.2g} % of a law parameter's own)"
                )
            if spring.get("in_model"):
                lines.append(
                    text + f"; the law's model ({self.law}) and the law-free ΔE(A) take its "
                    "potential, E = ½y'² + V(y)"
                )
            else:
                lines.append(text + "; the law-free ΔE(A) takes its potential")
        agreement = self._attr("shape_agreement_json", None)
        if agreement:
            lines.append(
                f"shape     ΔE(A) of the law as A^{_number(agreement['law_slope'], '.2f')}, of "
                f"the turning points as A^{_number(agreement['measured_slope'], '.2f')} ± "
                f"{_number(agreement['measured_slope_se'], '.2f')}; the law departs from "
                "them by up to "
                f"{agreement['max_percent']:.3g} %"
                + ("" if agreement["same_shape"] else ": ANOTHER SHAPE")
            )
        for entry in self.at_prior_bound:
            option = None
            if entry["parameter"] in self.priors.names:
                option = widened_prior(entry["parameter"], self.priors[entry["parameter"]])
            lines.append(
                f"NOT A MEASUREMENT: {entry['parameter']} piles on its prior's upper bound "
                f"{entry['bound']:.4g}; "
                + (
                    "check units and channels (bayestribo inspect)"
                    if option is None
                    else f"where the stop is real, widen it (--prior {option})"
                )
            )
        lines.extend(self._table_lines(prob))
        lines.extend(self._dissipation_lines())
        return "\n".join(lines)

    def _table_lines(self, prob: float) -> list[str]:
        """The posterior table: each quantity by its name in words and symbol, its
        unit ("dimensionless" for a number), mean and ``prob`` interval in the digits the
        interval supports, or a bound where the posterior is its prior's
        (:mod:`bayestribo.inference.flatness`), and sd."""
        from bayestribo.summary import interval_text

        header = f"mean [{100 * check_prob(prob):g} % interval]"
        summary = self.summary(prob)
        titles = {name: s.title for name, s in summary.items()}
        units = {name: unit_words(s.unit) for name, s in summary.items()}
        values = {}
        for name, s in summary.items():
            lo, hi = s.interval
            if s.kind == "bound":
                # the data set a range, not a value: a bound, never a measurement
                values[name] = f"< {hi:.2g} (not constrained by the data: its prior up to there)"
            else:  # the digits the interval supports (bayestribo.summary.interval_text)
                values[name] = interval_text(s.mean, lo, hi)
        w = max([len(t) for t in titles.values()] + [10]) + 2
        u = max([len(t) for t in units.values()] + [4]) + 2
        v = max([len(t) for t in values.values()] + [len(header)]) + 2
        lines = [f"{'':{w}}{'unit':<{u}}{header:<{v}}sd"]
        for name, s in summary.items():
            lines.append(f"{titles[name]:<{w}}{units[name]:<{u}}{values[name]:<{v}}{s.sd:.2g}")
        return lines

    def _comparison_lines(self) -> list[str]:
        """How the law was chosen (``law="auto"``)."""
        c = self.law_comparison
        if not c:
            return []
        from bayestribo.inference.records import LawComparison, LawHalves

        text = LawComparison.from_dict(c)
        lines = [f"          {text.describe()}"]
        halves = c.get("halves")
        if halves and halves.get("tested") and halves.get("agree"):
            lines.append(f"          {LawHalves.from_dict(halves).describe()}")
        lines.extend(self._departure_lines(c.get("departures") or {}))
        if not c.get("adequate") and not self.turning_point_dissipation:
            lines.append(
                "          the analysis holds too few half cycles for the law-free ΔE(A) "
                "either: the record holds no measurement of the dissipation"
            )
        return lines

    def _departure_lines(self, departures: Mapping[str, Any]) -> list[str]:
        """How close each compared law came to the turning points' ΔE(A)."""
        rows = {law: d for law, d in departures.items() if d}
        if not rows:
            return []
        first = next(iter(rows.values()))
        out = [
            "          how close each law came to the turning points' ΔE(A) (largest "
            "departure over the swings; log-log slope, the turning points' "
            f"{_number(first['measured_slope'], '.2f')} ± "
            f"{_number(first['measured_slope_se'], '.2f')}):"
        ]
        width = max(len(law) for law in rows)
        for law, d in sorted(rows.items(), key=lambda item: item[1]["max_percent"]):
            shape = "" if d["same_shape"] else "  another shape"
            out.append(
                f"            {law:<{width}}  {d['max_percent']:8.3g} %   slope "
                f"{_number(d['law_slope'], '.2f')}{shape}"
            )
        return out

    def _dissipation_lines(self) -> list[str]:
        """ΔE(A) at the largest, middle and smallest swing of the analysed motion: the
        law's, and the one measured from the turning points."""
        d = self.dissipation
        if not d or not d.get("amplitude"):
            return []
        unit = d["unit"].replace("^2", "²")
        head = (
            f"energy dissipated per cycle ΔE(A) [{unit}], "
            f"{100 * float(d['prob']):g} % interval"
            + ("" if d["unit"] == "J" else " (ΔE/k: the stiffness is not known)")
        )
        out = [head]
        measured = self.turning_point_dissipation
        laws = d.get("laws")
        label = (
            f"laws {', '.join(laws)} (as good as each other: mixed)" if laws else f"law {self.law}"
        )
        rows = [(label, d)]
        if measured and measured.get("amplitude"):
            rows.append(("turning points (law-free)", measured))
        from bayestribo.summary import interval_text

        amp = d["amplitude"]
        picks = sorted({len(amp) - 1, len(amp) // 2, 0}, reverse=True)
        swings = {i: f"A = {amp[i]:.4g} {d['amplitude_unit']}" for i in picks}
        width = max(len(s) for s in swings.values())
        cells: list[tuple[str, list[tuple[str, str, str]]]] = []
        for label, band in rows:
            mean, (lo, hi) = band["mean"], band["interval"]
            row = []
            for i in picks:
                if mean[i] is None or lo[i] is None or hi[i] is None:
                    continue
                centre, _, rest = interval_text(mean[i], lo[i], hi[i]).partition(" [")
                row.append((swings[i], centre, f" [{rest}" if rest else ""))
            cells.append((label, row))
        # the value right-aligned, so every interval starts in one column, two spaces
        # at least from the swing ("0 (at the bound)" fills 16)
        right = max([len(c) for _, row in cells for _, c, _ in row] + [14]) + 2
        for label, row in cells:
            out.append(f"  {label}")
            out.extend(f"    {swing:<{width}}{centre:>{right}}{b}" for swing, centre, b in row)
        return out

    def __repr__(self) -> str:
        summary = self.summary()
        parts = ", ".join(
            f"{name}={s.mean:.4g}±{s.sd:.2g}"
            for name, s in summary.items()
            if name in ("zeta", "mu_k", "friction_displacement")
        )
        state = "converged" if self.converged else "NOT converged"
        if self.at_prior_bound:
            state += ", NOT A MEASUREMENT (prior bound)"
        return f"<FitResult {self.run_name!s}: {parts} ({state}, seed {self.seed})>"

    def _repr_html_(self) -> str:
        """The summary table for Jupyter."""
        import html

        rows = "".join(
            f"<tr><td>{html.escape(s.title)}</td><td>{html.escape(unit_words(s.unit))}</td>"
            f"<td>{s.mean:.6g}</td><td>{s.sd:.3g}</td>"
            f"<td>[{s.interval[0]:.6g}, {s.interval[1]:.6g}]</td></tr>"
            for s in self.summary().values()
        )
        state = "converged" if self.converged else "NOT converged"
        if self.at_prior_bound:
            state += "; NOT A MEASUREMENT: a posterior piles on its prior's bound"
        caption = (
            f"{html.escape(str(self.run_name))}: {html.escape(self.model)} model, "
            f"seed {self.seed}, {html.escape(state)}"
        )
        return (
            f"<table><caption>{caption}</caption><thead><tr><th></th><th>unit</th>"
            "<th>mean</th><th>sd</th><th>95 % interval</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>"
        )

    # -- files ----------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write the InferenceData to NetCDF (``.nc``, netCDF-4/HDF5), whole or not at
        all (:func:`bayestribo._files.atomic_path`: a failure leaves ``path`` as it was).

        Written by the netCDF C library (``netCDF4``), about twice as fast as
        ``h5netcdf`` for a fit's four groups; any netCDF-4 reader (h5netcdf, xarray,
        ArviZ) reads the file.
        """
        path = Path(path)
        with atomic_path(path) as partial:  # whole or not at all
            self.idata.to_netcdf(str(partial), engine=NETCDF_ENGINE)
        return path

    @classmethod
    def load(cls, path: str | Path) -> FitResult:
        """Read a fit written by :meth:`save`."""
        import arviz as az

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            idata = az.from_netcdf(str(path), engine=NETCDF_ENGINE)
        idata.load()
        return cls(idata)


def _number(value: Any, spec: str) -> str:
    """A number for the text: ``value`` formatted, or "undefined" where it is not
    defined (None or NaN: a chain that did not move; the log-log slope of a ΔE(A) that
    is zero at every swing, a law fitted at no loss)."""
    if value is None or not math.isfinite(float(value)):
        return "undefined"
    return format(float(value), spec)
