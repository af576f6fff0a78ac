"""The sensor's calibration: an uncertain gain and a known anti-alias filter.

A recording's amplitude is the motion's times the gain of its signal chain: the
sensor's calibration (a laser vibrometer's or a motion sensor's, rarely known better
than 1 %) and any low-pass filter before the digitiser. Damping ratios are ratios of
amplitudes and do not see a constant gain; a friction is a displacement (μ_k N/k) and
sees it whole: a gain of 0.995 gives a μ_k 0.5 % low. A posterior on the Π increments
alone is far narrower than that on a good record, so the gain must enter the reported
intervals:

* the gain's relative standard uncertainty σ_g (the sidecar's ``gain_uncertainty``,
  per channel ``displacement_gain_uncertainty`` and ``velocity_gain_uncertainty``;
  when not stated, the typical uncertainty of the sidecar's ``sensor_kind``
  (:mod:`bayestribo.signal.sensor_kinds`), or of an accelerometer for a run integrated
  from an acceleration, else :data:`DEFAULT_GAIN_UNCERTAINTY`, and the output says
  which) is drawn
  per posterior draw into every length the fit reports
  (:func:`bayestribo.inference.assemble.derived_quantities`);
* a known filter (the sidecar's ``filter``: kind, order, cutoff) multiplies the
  oscillation at the frequency f by ``|H(2πif)|`` (:func:`filter_gain`); the reported
  lengths are divided by it. A first-order filter on a record of both channels is
  undone on them instead (:func:`undo_first_order`), its lag and its smoothing of
  the friction's kinks with it. Both channels are taken through the same filter: their
  common phase lag shifts the record in time and leaves the energy
  ``(y² + y'²)/2`` unchanged.

The energy ``(y² + y'²)/2`` weighs the displacement and the velocity channel equally
over a cycle, so with both channels the amplitude's relative uncertainty is
``√(σ_x² + σ_v²)/2`` (:func:`amplitude_gain_sd`) where the two were calibrated apart
(a kind of sensor whose ``independent_channels`` is true: a vibrometer's two
decoders), and ``(σ_x + σ_v)/2`` where they come from one transducer (every other
kind, and a sensor of unstated kind: a velocity column is most often the software's
derivative of the position); with one channel (the other derived from it) it is that
channel's.

How much of a reported interval is the gain's: the gain is drawn independently of the
posterior's draws, so the fraction of a quantity's posterior variance its draws
explain (:func:`gain_variance_share`) is the gain's part of that quantity's interval.
On a good record it is most of μ_k's: on 96 simulated accelerometer records of dry
friction with a gain uncertainty of 1 % (the unstated kind's default, which these
records took before an acceleration implied an accelerometer's 5 %), a median 89 %
(29-99 %) of μ_k's variance, the data's own part a relative sd of 0.35 %
(0.12-1.5 %); their intervals cover the truth whether the simulated sensor's gain is
exact and stated so or drawn at 1 % and fitted with 1 % (z sd 1.05 and 1.09), and an
exact gain fitted with 1 % gives them z sd 0.39
(``benchmarks/results/acceleration_gain_*.json``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from bayestribo.signal.sensor_kinds import UNKNOWN, SensorKind, get_sensor_kind

__all__ = [
    "DEFAULT_GAIN_UNCERTAINTY",
    "FILTER_KINDS",
    "SensorCalibration",
    "amplitude_gain_sd",
    "check_filter",
    "filter_gain",
    "gain_variance_share",
    "sensor_calibration",
    "undo_first_order",
]

#: Relative standard uncertainty of a sensor's gain where the sidecar states neither one
#: nor a ``sensor_kind``: the calibration accuracy of laser vibrometers and of
#: teaching-lab motion sensors (1 %).
DEFAULT_GAIN_UNCERTAINTY = UNKNOWN.gain_uncertainty

#: Filter kinds a sidecar may name (analog prototypes of :mod:`scipy.signal`).
FILTER_KINDS = ("butterworth", "bessel")


def check_filter(spec: Any) -> dict[str, Any]:
    """Check a filter specification and return it normalised.

    Parameters
    ----------
    spec : mapping
        ``{"kind": "butterworth" | "bessel", "order": 1..10, "cutoff_Hz": > 0}``; a
        one-pole RC filter is ``{"kind": "butterworth", "order": 1, ...}``.

    Returns
    -------
    dict
        ``kind`` (lower case), ``order`` (int), ``cutoff_Hz`` (float).

    Raises
    ------
    ValueError
        Naming the field and what was expected.
    """
    if not isinstance(spec, Mapping):
        raise ValueError(
            f"expected a mapping {{'kind': ..., 'order': ..., 'cutoff_Hz': ...}}, got {spec!r}"
        )
    unknown = set(spec) - {"kind", "order", "cutoff_Hz"}
    if unknown:
        raise ValueError(
            f"unknown field(s) {sorted(unknown)}; expected 'kind', 'order' and 'cutoff_Hz'"
        )
    kind = spec.get("kind")
    if not isinstance(kind, str) or kind.lower() not in FILTER_KINDS:
        raise ValueError(f"'kind' must be one of {', '.join(FILTER_KINDS)}, got {kind!r}")
    order = spec.get("order")
    if isinstance(order, bool) or not isinstance(order, int) or not 1 <= order <= 10:
        raise ValueError(f"'order' must be an integer from 1 to 10, got {order!r}")
    cutoff = spec.get("cutoff_Hz")
    if (
        isinstance(cutoff, bool)
        or not isinstance(cutoff, int | float)
        or not (math.isfinite(cutoff) and cutoff > 0)
    ):
        raise ValueError(f"'cutoff_Hz' must be a positive number [Hz], got {cutoff!r}")
    return {"kind": kind.lower(), "order": int(order), "cutoff_Hz": float(cutoff)}


def filter_gain(spec: Mapping[str, Any], frequency_Hz: float) -> float:
    """Magnitude of an analog low-pass filter at a frequency, ``|H(2πif)|``.

    Parameters
    ----------
    spec : mapping
        A filter (:func:`check_filter`). Butterworth: ``|H| = (1 + (f/f_c)^(2n))^(-1/2)``;
        Bessel: :func:`scipy.signal.bessel` normalised to its -3 dB frequency
        (``norm="mag"``), as filter data sheets state the cutoff.
    frequency_Hz : float
        Oscillation frequency f [Hz].

    Returns
    -------
    float
        The gain, in (0, 1].

    Examples
    --------
    >>> round(filter_gain({"kind": "butterworth", "order": 1, "cutoff_Hz": 10.0}, 1.0), 6)
    0.995037
    """
    spec = check_filter(spec)
    ratio = float(frequency_Hz) / spec["cutoff_Hz"]
    if spec["kind"] == "butterworth":
        return float((1.0 + ratio ** (2 * spec["order"])) ** -0.5)
    from scipy.signal import bessel, freqs

    b, a = bessel(spec["order"], 1.0, analog=True, norm="mag")
    _, h = freqs(b, a, worN=[ratio])
    return float(abs(h[0]))


def amplitude_gain_sd(
    displacement_sd: float | None, velocity_sd: float | None, correlation: float = 0.0
) -> float:
    """Relative standard uncertainty of the energy's amplitude from the channels' gains.

    The energy ``(g_x² y² + g_v² y'²)/2`` of gains ``g = 1 + ε`` has, over a cycle, the
    amplitude ``A √((g_x² + g_v²)/2) ≈ A (1 + (ε_x + ε_v)/2)``.

    Parameters
    ----------
    displacement_sd, velocity_sd : float or None
        Relative gain uncertainty of each recorded channel; None for a channel not
        recorded (derived from the other, it shares that one's gain).
    correlation : float
        Correlation ρ of the two channels' gain errors in [-1, 1]: 0 for channels
        calibrated apart (a vibrometer's two decoders), 1 for two channels of one
        transducer (a velocity differentiated from the position by the sensor's
        software).

    Returns
    -------
    float
        ``√(σ_x² + σ_v² + 2ρσ_xσ_v)/2`` with both channels, else the recorded channel's σ.
    """
    if displacement_sd is None and velocity_sd is None:
        raise ValueError("at least one channel's gain uncertainty is needed")
    if not -1.0 <= correlation <= 1.0:
        raise ValueError(f"correlation: expected a number in [-1, 1], got {correlation!r}")
    if displacement_sd is None or velocity_sd is None:
        return float(displacement_sd if velocity_sd is None else velocity_sd)
    variance = (
        displacement_sd**2 + velocity_sd**2 + 2.0 * correlation * displacement_sd * velocity_sd
    )
    return 0.5 * math.sqrt(max(variance, 0.0))


def gain_variance_share(quantities: Mapping[str, np.ndarray], gain: np.ndarray) -> dict[str, float]:
    """The fraction of each quantity's posterior variance the gain's draws make.

    The gain is drawn independently of the sampled parameters
    (:meth:`SensorCalibration.draws`), so a quantity ``q = f(θ) / g^p`` has the
    variance ``Var f`` plus the gain's part; the squared correlation of ``q`` with ``g``
    over the draws is that part's fraction (to first order in the gain's sd: exact
    for a quantity linear in ``g``, and within ``p σ_g`` of it for ``1/g^p``).

    Parameters
    ----------
    quantities : mapping of str to ndarray
        Draws of each quantity, one per draw of ``gain`` [the quantity's unit].
    gain : ndarray
        Draws of the signal chain's gain [-].

    Returns
    -------
    dict of str to float
        By name, in [0, 1]; empty where the gain does not vary. A quantity that does
        not vary, or whose draws are not all finite, is left out.

    Raises
    ------
    ValueError
        Where a quantity's draws are not as many as the gain's (naming it).
    """
    g = np.asarray(gain, dtype=float).ravel()
    if g.size < 2 or not np.all(np.isfinite(g)) or np.ptp(g) == 0.0:
        return {}
    dg = g - g.mean()
    out: dict[str, float] = {}
    for name, values in quantities.items():
        q = np.asarray(values, dtype=float).ravel()
        if q.size != g.size:
            raise ValueError(
                f"quantities[{name!r}]: expected {g.size} draws (one per gain draw), got {q.size}"
            )
        if not np.all(np.isfinite(q)) or np.ptp(q) == 0.0:
            continue
        dq = q - q.mean()
        corr = float(dq @ dg) / math.sqrt(float(dq @ dq) * float(dg @ dg))
        out[name] = min(corr * corr, 1.0)
    return out


@dataclass(frozen=True)
class SensorCalibration:
    """The gain of a run's signal chain, as the fit uses it.

    Attributes
    ----------
    gain : float
        Known gain at the oscillation frequency (the filter's ``|H|``; 1 without one):
        the reported lengths are divided by it.
    gain_sd : float
        Relative standard uncertainty of the amplitude's gain [-].
    stated : bool
        False where ``gain_sd`` is the default of the sensor's kind for want of a
        sidecar value (the output says so).
    filter : dict or None
        The filter, as the sidecar gives it.
    kind : SensorKind
        The sensor's kind (the sidecar's ``sensor_kind``; an accelerometer for a run
        integrated from an acceleration that names none; :data:`~bayestribo.signal.
        sensor_kinds.UNKNOWN` otherwise), whose gain uncertainty is the default.
    undone : bool
        The filter was undone on the channels before the analysis
        (:func:`undo_first_order`; ``gain`` is then 1).
    implied_by : str or None
        What the kind was taken from where the sidecar names none (``"an
        acceleration"``), for the output; None where it is stated or unknown.
    """

    gain: float = 1.0
    gain_sd: float = 0.0
    stated: bool = True
    filter: dict[str, Any] | None = None
    kind: SensorKind = UNKNOWN
    undone: bool = False
    implied_by: str | None = None

    def draws(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Draws of the chain's gain: ``gain (1 + ε)``, ε ~ N(0, gain_sd²) truncated to
        ``1 + ε > 0.1`` (a sensor off by a factor of ten is a unit error, not a spread)."""
        if self.gain_sd == 0.0:
            return np.full(size, self.gain)
        eps = rng.normal(0.0, self.gain_sd, size)
        bad = eps <= -0.9
        while np.any(bad):
            eps[bad] = rng.normal(0.0, self.gain_sd, int(bad.sum()))
            bad = eps <= -0.9
        return self.gain * (1.0 + eps)

    def describe(self) -> str:
        """One line for the output: the gain uncertainty used and where it came from."""
        text = f"sensor gain uncertainty {self.gain_sd:.2%}"
        if self.stated:
            text += " (stated)"
        elif self.kind is UNKNOWN:
            text += (
                " (the default for a sensor of unstated kind: state yours as "
                "'gain_uncertainty' in the sidecar, or the sensor as 'sensor_kind')"
            )
        elif self.implied_by is not None:
            text += (
                f" (the default for {self.kind.title}, the run being read from "
                f"{self.implied_by}: {self.kind.basis}; state yours as 'gain_uncertainty' in "
                "the sidecar, or the sensor as 'sensor_kind')"
            )
        else:
            text += (
                f" (the default for {self.kind.title}: {self.kind.basis}; state yours as "
                "'gain_uncertainty' in the sidecar)"
            )
        if self.filter is not None:
            f = self.filter
            text += f"; {f['kind']} filter of order {f['order']} at {f['cutoff_Hz']:g} Hz " + (
                "undone on both channels"
                if self.undone
                else f"corrected (gain {self.gain:.5f} at the oscillation frequency)"
            )
        return text


def sensor_calibration(
    metadata: Mapping[str, Any],
    frequency_Hz: float,
    *,
    displacement: bool = True,
    velocity: bool = True,
    filter_undone: bool = False,
) -> SensorCalibration:
    """The signal chain's gain from a run's metadata.

    Parameters
    ----------
    metadata : mapping
        ``gain_uncertainty``, ``displacement_gain_uncertainty``,
        ``velocity_gain_uncertainty`` [-], ``sensor_kind`` (the default uncertainty of
        a channel none of the former covers) and ``filter`` (any may be absent).
    frequency_Hz : float
        The oscillation frequency [Hz] at which the filter's gain is taken.
    displacement, velocity : bool
        Which channels the run recorded.
    filter_undone : bool
        The declared filter was undone on the channels (:func:`undo_first_order`):
        its gain is not divided out again.

    Returns
    -------
    SensorCalibration
    """
    name, implied_by = metadata.get("sensor_kind"), None
    if name is None and metadata.get("acceleration") is not None:
        # the run was integrated from an acceleration: its sensor is an accelerometer
        name, implied_by = "accelerometer", "an acceleration"
    kind = get_sensor_kind(name)
    both = metadata.get("gain_uncertainty")
    stated = both is not None
    sds: dict[str, float | None] = {}
    for channel, recorded in (("displacement", displacement), ("velocity", velocity)):
        own = metadata.get(f"{channel}_gain_uncertainty")
        stated = stated or own is not None
        if not recorded:
            sds[channel] = None
        elif own is not None:
            sds[channel] = float(own)
        else:
            sds[channel] = float(both) if both is not None else kind.gain_uncertainty
    if not (displacement or velocity):
        raise ValueError("a run records a displacement, a velocity or both")
    spec = metadata.get("filter")
    gain = 1.0 if spec is None or filter_undone else filter_gain(spec, frequency_Hz)
    return SensorCalibration(
        gain=gain,
        gain_sd=amplitude_gain_sd(
            sds["displacement"],
            sds["velocity"],
            correlation=0.0 if kind.independent_channels else 1.0,
        ),
        stated=stated,
        filter=None if spec is None else check_filter(spec),
        kind=kind,
        undone=bool(filter_undone and spec is not None),
        implied_by=None if stated else implied_by,
    )


def undo_first_order(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, spec: Mapping[str, Any], period: float
) -> tuple[np.ndarray, np.ndarray]:
    """Both channels before a declared first-order low-pass filter.

    A one-pole filter ``H = 1/(1 + s/ω_c)`` (Butterworth or Bessel of order 1, cutoff
    at -3 dB) gives ``x_f + x_f'/ω_c = x``; the recorded velocity is the filtered
    derivative, ``v_f = x_f'``, so ``x = x_f + v_f/ω_c`` exactly, and
    ``v = v_f + v_f'/ω_c`` with v_f' the velocity's Savitzky-Golay derivative
    (:func:`bayestribo.signal.decay.derive_velocity`, over 1/8 of a period). Its gain
    at f, ``|H(2πif)|``, is then undone too; but not only that: the filter's lag at f
    (11° at f_c = 5f) and the way it smooths the kinks dry friction puts at the
    turning points, which a gain cannot correct (at f_c = 5 f the 95 % intervals of ζ
    and μ_k held the truth in 15 runs of 20, z about ±1).

    Parameters
    ----------
    t : ndarray
        Regular time stamps [s].
    x, v : ndarray
        The recorded displacement [length unit] and velocity [length unit/s].
    spec : mapping
        The filter (:func:`check_filter`), of order 1.
    period : float
        The oscillation's period [s].

    Returns
    -------
    (ndarray, ndarray)
        The displacement and the velocity at the filter's input.
    """
    from bayestribo.signal.decay import derive_velocity

    spec = check_filter(spec)
    if spec["order"] != 1:
        raise ValueError(f"filter: expected a first-order filter, got order {spec['order']}")
    omega_c = 2.0 * math.pi * spec["cutoff_Hz"]
    slope, _ = derive_velocity(t, v, period)
    return x + v / omega_c, v + slope / omega_c
