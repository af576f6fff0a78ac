"""Measurement noise of a recording: nominal resolution, measured levels, the one used.

The vibrometer's data sheet gives a resolution per measurement range (paper,
section 2.3: 0.15 µm for the 10 mm peak-to-peak displacement range and 0.015 µm/s for
the 1 m/s velocity range). A posterior built on that figure alone is as narrow as the
instrument is fine, and a real recording usually carries more noise (electronics,
vibration of the floor, the flat's own motion). So the noise model starts from the
nominal resolution, measures the noise actually present at rest in the recording
(:class:`bayestribo.signal.decay.NoiseLevels`), and uses, channel by channel, the larger of
the two, saying which it used.

The resolution is taken as a standard deviation. For pure quantisation at step q the
standard deviation would be q/√12; using q is the conservative choice.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

from bayestribo.errors import RecordingError
from bayestribo.signal.decay import EnergyDecay

__all__ = ["RANGE_RESOLUTION", "NoiseModel", "noise_model"]

#: Resolution of the laser vibrometer per measurement range (paper, section 2.3):
#: ``{"displacement": {range peak-to-peak [m]: resolution [m]}, "velocity":
#: {range peak-to-peak [m/s]: resolution [m/s]}}``. The resolution scales with the
#: range (a fixed number of counts); other ranges are scaled from these.
RANGE_RESOLUTION: dict[str, dict[float, float]] = {
    "displacement": {10e-3: 0.15e-6},
    "velocity": {1.0: 0.015e-6},
}


def resolution_for_range(channel: str, range_pp: float) -> float:
    """Nominal resolution of ``channel`` at a peak-to-peak range (scaled from the table)."""
    if channel not in RANGE_RESOLUTION:
        raise ValueError(f"channel must be 'displacement' or 'velocity', got {channel!r}")
    if not (math.isfinite(range_pp) and range_pp > 0):
        raise ValueError(f"range_pp must be a positive number, got {range_pp!r}")
    (ref_range, ref_res), *_ = RANGE_RESOLUTION[channel].items()
    return ref_res * range_pp / ref_range


@dataclass(frozen=True)
class NoiseModel:
    """Per-channel noise standard deviations used by the likelihood, in signal units.

    Attributes
    ----------
    displacement, velocity : float
        Standard deviation used for each channel [length unit], [length unit/s].
    nominal_displacement, nominal_velocity : float or None
        The instrument's resolution, when known.
    measured_displacement, measured_velocity : float or None
        The noise measured at rest in the recording, when there was rest to measure.
    source_displacement, source_velocity : str
        ``"nominal"`` or ``"measured"``: which figure is used.
    measured_in : str
        Where the measured figures come from (quiescent segments or signal differences).
    derived_channel : str or None
        A channel computed from the other (its noise is propagated, not assumed).
    coloured : bool
        The noise measured at rest is not white (filtered, 1/f, or a mains line; see
        :class:`bayestribo.signal.spectrum.RestNoise`): :func:`bayestribo.signal.pi_data`
        then takes the increments' variances from its spectrum.
    lines_Hz : tuple of float
        Mains lines found in the noise at rest [Hz].
    quantisation_steps : tuple
        The step of the displacement and of the velocity when quantised (None when
        not): the measured noise is at least step/√12
        (:mod:`bayestribo.signal.quantisation`).
    spectrum_rel_se : float or None
        For coloured noise, the relative standard error of its level in the signal
        band as measured at rest (:attr:`~bayestribo.signal.spectrum.NoiseSpectrum.band_rel_se`,
        the larger of the channels'): how well the increments' variances are known.
    measured_dof : float or None
        Degrees of freedom of the measured variance where a measured figure is used
        (:attr:`exceeds_nominal`): the quiescent samples less one per segment for white
        noise, ``2/spectrum_rel_se²`` for coloured noise; None where the noise is the
        instrument's resolution, the rounding of a coarse digitiser on every recorded
        channel (:mod:`bayestribo.signal.coarse`), or measured from signal differences
        over the whole record. A misfit test compares the residuals' χ² with this estimate's own
        uncertainty (an F test), so a short rest gives no false alarms
        (:func:`bayestribo.inference.pipeline.misfit_p_value`).
    integrated_velocity : dict or None
        For a velocity integrated from an accelerometer's record (and the displacement
        derived from it), the integration's ``noise`` record
        (:meth:`bayestribo.io.acceleration.Integration.record`): the increments'
        variances then come from the sensor's noise put through the integration
        (:func:`bayestribo.signal.velocity_integral.velocity_noise`), which the velocity's rest
        does not show in the motion.
    """

    displacement: float
    velocity: float
    nominal_displacement: float | None
    nominal_velocity: float | None
    measured_displacement: float | None
    measured_velocity: float | None
    source_displacement: str
    source_velocity: str
    measured_in: str
    derived_channel: str | None
    coloured: bool = False
    lines_Hz: tuple[float, ...] = ()
    spectrum_rel_se: float | None = None
    quantisation_steps: tuple[float | None, float | None] = (None, None)
    measured_dof: float | None = None
    integrated_velocity: dict[str, Any] | None = None

    @property
    def exceeds_nominal(self) -> bool:
        """True when the recording is noisier than the instrument's resolution."""
        return "measured" in (self.source_displacement, self.source_velocity)

    def describe(self) -> str:
        """One sentence for reports."""
        parts = []
        for ch in ("displacement", "velocity"):
            if ch == self.derived_channel:
                parts.append(f"{ch} derived from the other channel")
                continue
            used = getattr(self, ch)
            src = getattr(self, f"source_{ch}")
            nominal = getattr(self, f"nominal_{ch}")
            text = f"{ch} σ = {used:.3g} ({src}"
            if src == "measured" and nominal is not None:
                text += f", {used / nominal:.3g}× the resolution {nominal:.3g}"
            parts.append(text + ")")
        text = "; ".join(parts) + f"; measured in {self.measured_in}"
        if self.coloured:
            text += "; coloured noise at rest (increment variances from its spectrum"
            if self.spectrum_rel_se is not None:
                text += f", known to ±{100 * self.spectrum_rel_se:.0f} %"
            text += ")"
        if self.lines_Hz:
            text += "; mains line(s) at " + ", ".join(f"{f:.2f}" for f in self.lines_Hz) + " Hz"
        for ch, step in zip(("displacement", "velocity"), self.quantisation_steps, strict=True):
            if step is not None:
                text += f"; {ch} quantised in steps of {step:.3g} (σ >= step/√12)"
        return text

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON, NetCDF attributes)."""
        return asdict(self)


def _choose(nominal: float | None, measured: float | None, channel: str) -> tuple[float, str]:
    if nominal is None and measured is None:
        raise RecordingError(
            f"no noise level for the {channel}: give its resolution (sidecar key "
            f"'{channel}_resolution_...') or record a quiescent segment"
        )
    if measured is None or (nominal is not None and nominal >= measured):
        value, source = float(nominal), "nominal"  # type: ignore[arg-type]
    else:
        value, source = float(measured), "measured"
    if not value > 0:
        raise RecordingError(
            f"the {channel} noise is {value!r}: a likelihood needs a positive noise level; "
            f"give the {channel} resolution in the metadata"
        )
    return value, source


def noise_model(
    decay: EnergyDecay,
    metadata: Mapping[str, Any] | None = None,
    *,
    displacement_resolution: float | None = None,
    velocity_resolution: float | None = None,
) -> NoiseModel:
    """The noise model of a recording: nominal resolution, checked against the record.

    Parameters
    ----------
    decay : EnergyDecay
        The recording's energy decay, which carries the measured noise.
    metadata : mapping, optional
        Run metadata; ``displacement_resolution_m`` and ``velocity_resolution_m_per_s``
        give the nominal resolution.
    displacement_resolution, velocity_resolution : float, optional
        Override the metadata's resolutions [length unit], [length unit/s].

    Returns
    -------
    NoiseModel
        With, per channel, the larger of the nominal and the measured noise.
    """
    meta = dict(metadata or {})
    nom_x = displacement_resolution or meta.get("displacement_resolution_m")
    nom_v = velocity_resolution or meta.get("velocity_resolution_m_per_s")
    meas = decay.noise
    rest = getattr(decay, "rest_noise", None)
    derived = decay.derived_channel
    if derived == "displacement":
        sigma_v, src_v = _choose(nom_v, meas.velocity, "velocity")
        sigma_x, src_x = 0.0, "derived"
    elif derived == "velocity":
        sigma_x, src_x = _choose(nom_x, meas.displacement, "displacement")
        sigma_v, src_v = 0.0, "derived"
    else:
        sigma_x, src_x = _choose(nom_x, meas.displacement, "displacement")
        sigma_v, src_v = _choose(nom_v, meas.velocity, "velocity")
    return NoiseModel(
        displacement=sigma_x,
        velocity=sigma_v,
        nominal_displacement=None if nom_x is None else float(nom_x),
        nominal_velocity=None if nom_v is None else float(nom_v),
        measured_displacement=meas.displacement,
        measured_velocity=meas.velocity,
        source_displacement=src_x,
        source_velocity=src_v,
        measured_in=meas.source,
        derived_channel=derived,
        coloured=bool(rest is not None and rest.coloured),
        lines_Hz=() if rest is None else tuple(float(f) for f in rest.lines_Hz),
        spectrum_rel_se=_spectrum_rel_se(rest),
        quantisation_steps=(
            getattr(meas, "displacement_step", None),
            getattr(meas, "velocity_step", None),
        ),
        measured_dof=None
        if _all_coarse(meas, derived)
        else _measured_dof(meas, rest, "measured" in (src_x, src_v)),
        integrated_velocity=_integrated_velocity(meta) if derived == "displacement" else None,
    )


def _integrated_velocity(meta: Mapping[str, Any]) -> dict[str, Any] | None:
    """The accelerometer integration's noise record in a run's metadata, or that of a
    velocity undone of its sensor's high-pass (:mod:`bayestribo.io.high_pass`), or None."""
    record = meta.get("acceleration")
    if not isinstance(record, Mapping):
        record = meta.get("high_pass_undone")
    if not isinstance(record, Mapping):
        return None
    noise = record.get("noise")
    return dict(noise) if isinstance(noise, Mapping) else None


def _all_coarse(meas: Any, derived: str | None) -> bool:
    """Every recorded channel is coarse (:mod:`bayestribo.signal.coarse`): its noise is
    its rounding, q/√12 exactly, and the increments' variances come from the rounding
    itself, not from a level measured at rest (whose spectrum, of a rest on one level,
    says nothing)."""
    from bayestribo.signal.coarse import coarse_steps

    steps = (getattr(meas, "displacement_step", None), getattr(meas, "velocity_step", None))
    coarse = coarse_steps(steps, (meas.displacement, meas.velocity))
    recorded = [i for i, ch in enumerate(("displacement", "velocity")) if ch != derived]
    return all(coarse[i] is not None for i in recorded)


def _measured_dof(meas: Any, rest: Any, used: bool) -> float | None:
    """Degrees of freedom of the measured noise variance (see :class:`NoiseModel`)."""
    if not used or meas.n_samples <= 0:
        return None
    rel_se = _spectrum_rel_se(rest)
    if rel_se is not None and rel_se > 0:
        return 2.0 / rel_se**2
    segments = max(1, str(meas.source).count(" and ") + 1)
    return float(max(meas.n_samples - segments, 1))


def _spectrum_rel_se(rest: Any) -> float | None:
    """The larger band-level standard error of the coloured channels, or None."""
    if rest is None or not rest.coloured:
        return None
    ses = [
        s.band_rel_se for s in (rest.displacement, rest.velocity) if s is not None and s.coloured
    ]
    return max(ses) if ses else None
