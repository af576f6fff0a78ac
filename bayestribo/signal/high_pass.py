"""A sensor's analog high-pass (an AC-coupled channel): undone, and recognised.

Geophones, piezoelectric velocity and acceleration sensors, AC-coupled oscilloscope
channels and some vibrometer outputs pass no DC: the recorded signal y is the motion's
through ``H(s) = s/(s + ω_c)`` (one pole, an RC coupling) or
``H(s) = s²/(s² + 2ζ_g ω_c s + ω_c²)`` (two poles: a geophone's coil on its spring,
ζ_g its damping, about 0.7). At the oscillation frequency f the filter leads the phase
and lowers the gain by ``|H(2πif)|`` (0.986 at f_c = f/6 for one pole); worse, it turns
the release, a step of the swing's centre, into a centre that relaxes over 1/ω_c, and
after the stop the record relaxes as the filter's step response: the energy decay is
no law's, and the fit misfits (ζ 30 sd off on a 3 Hz rig with a 0.5 Hz pole).

**Undone** (:func:`undo_high_pass`): the filter's inverse is exact up to its state at
the record's start. For one pole, ``y' + ω_c y = u'`` gives
``u = y + ω_c ∫y dt + C``; for two poles ``u = y + 2ζ_g ω_c ∫y + ω_c² ∬y + C₀ + C₁t``.
The constants (the filter's state at the first sample), an offset of the digitiser
(``b`` in y: a line ``ω_c b t`` after one integral, a parabola after two) and the
random walk the integral makes of the noise (``ω_c σ √(t Δt)`` after t) are taken off
where the motion is known: at rest (:func:`rest_correction`), a velocity is zero there
and a displacement constant. Between the rests that drift is interpolated linearly (the
best estimate of a random walk known at both ends,
:func:`bayestribo.signal.velocity_integral.rest_drift`).

**Recognised** (:func:`detect_high_pass`): an oscillator's swing is centred on its
equilibrium (shifted by ± x_c alternately by a dry friction, by a fraction of the
decrement by a drag). The centres of a high-passed record are not: its displacement (or
the integral of its velocity) swings about a centre that moves from the release point
toward the rest as ``exp(-ω_c t)``. The midpoints of consecutive turning points are
regressed on the terms the inverse adds (``ω_c ∫y``, a polynomial drift) beside the
friction's alternation; ω_c is linear there and its estimate, with its standard error,
is the sign. A DC-coupled sensor's drift (an offset, a slow thermal wander) is the
polynomial's and does not give it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import cumulative_trapezoid

from bayestribo._text import shown

__all__ = [
    "CALIBRATED_CORNER",
    "DEFAULT_DAMPING",
    "DETECTION_DRIFT",
    "DETECTION_Z",
    "HIGH_PASS_KEY",
    "HighPassSign",
    "check_high_pass",
    "cumulative_integral",
    "detect_high_pass",
    "high_pass_gain",
    "high_pass_noise",
    "noise_record",
    "option_text",
    "rest_correction",
    "undo_high_pass",
]

#: The metadata (sidecar) key declaring a sensor's high-pass.
HIGH_PASS_KEY = "sensor_high_pass"
#: Damping of a two-pole high-pass whose damping is not given: a Butterworth's, about a
#: geophone's coil shunted for a flat response (0.6-0.7 on data sheets).
DEFAULT_DAMPING = 1.0 / math.sqrt(2.0)
#: Standard errors by which the centres' corner frequency must stand out of zero for
#: the sign to be named (the bundled and real recordings reach 3.6 at most, the
#: high-passed records of ``benchmarks/high_pass.py`` 40 and more).
DETECTION_Z = 12.0
#: Smallest move of the centres, as a fraction of the largest swing, that is named (the
#: bundled and real recordings move theirs by 1 % at most).
DETECTION_DRIFT = 0.03
#: The highest declared corner, as a fraction of the oscillation's frequency, at which
#: the undone records' intervals were measured to cover (``benchmarks/high_pass.py``, 8
#: records each: at 0.1 f the z of ζ had sd 0.5 (one pole) and 0.8 (two poles); at 0.3 f
#: sd 1.65, 3 of 8 one-pole records missed at exit 0; at f, 3 of 8). The inverse
#: multiplies by ω_c the integral's error at the release's kink (up to ω_c ω Δt²/8 of
#: the swing's speed) and the noise's random walk. Above it the fit says its intervals
#: may be too narrow.
CALIBRATED_CORNER = 0.1
#: Fewest turning points the regression of the centres takes (six unknowns).
_FEWEST_TURNING_POINTS = 12


def _number(value: Any) -> float:
    """``value`` as a float: NaN for anything but an int or float (a bool included), and
    for an int too large for a float (a sidecar's JSON may hold one of 400 digits)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return math.nan
    try:
        return float(value)
    except OverflowError:
        return math.nan


def check_high_pass(spec: Any) -> dict[str, Any]:
    """Check a high-pass declaration and return it normalised.

    Parameters
    ----------
    spec : mapping or number
        ``{"cutoff_Hz": > 0, "order": 1 or 2, "damping": > 0}`` (``order`` 1 by default,
        ``damping`` for two poles only, :data:`DEFAULT_DAMPING` by default), or the
        corner frequency alone [Hz] for one pole.

    Returns
    -------
    dict
        ``cutoff_Hz`` (float), ``order`` (int) and, for two poles, ``damping`` (float).

    Raises
    ------
    ValueError
        Naming the field and what was expected.
    """
    if isinstance(spec, int | float) and not isinstance(spec, bool):
        spec = {"cutoff_Hz": spec}
    if not isinstance(spec, Mapping):
        raise ValueError(
            "expected a mapping {'cutoff_Hz': HZ, 'order': 1 or 2, 'damping': ζ} or a corner "
            f"frequency in Hz, got {shown(spec)}"
        )
    unknown = set(spec) - {"cutoff_Hz", "order", "damping"}
    if unknown:
        raise ValueError(
            f"unknown field(s) {sorted(unknown)}; expected 'cutoff_Hz', 'order' and 'damping'"
        )
    cutoff = spec.get("cutoff_Hz")
    if not 0 < _number(cutoff) <= 1e6:
        raise ValueError(f"'cutoff_Hz' must be a positive number [Hz], got {shown(cutoff)}")
    order = spec.get("order", 1)
    if isinstance(order, bool) or order not in (1, 2):
        raise ValueError(f"'order' must be 1 or 2 (poles), got {shown(order)}")
    out: dict[str, Any] = {"cutoff_Hz": float(cutoff), "order": int(order)}
    damping = spec.get("damping")
    if damping is not None and order == 1:
        raise ValueError("'damping' is a two-pole high-pass's; give 'order': 2 with it")
    if order == 2:
        damping = DEFAULT_DAMPING if damping is None else damping
        if not 0 < _number(damping) <= 10:
            raise ValueError(f"'damping' must be a number in (0, 10], got {shown(damping)}")
        out["damping"] = float(damping)
    return out


def high_pass_gain(spec: Mapping[str, Any], frequency_Hz: float) -> float:
    """Magnitude of the declared high-pass at a frequency, ``|H(2πif)|``.

    Examples
    --------
    >>> round(high_pass_gain({"cutoff_Hz": 0.5}, 3.0), 6)
    0.986394
    """
    spec = check_high_pass(spec)
    r = float(frequency_Hz) / spec["cutoff_Hz"]
    if spec["order"] == 1:
        return r / math.sqrt(1.0 + r * r)
    z = spec["damping"]
    return r * r / math.sqrt((1.0 - r * r) ** 2 + (2.0 * z * r) ** 2)


def option_text(spec: Mapping[str, Any]) -> str:
    """The command-line value of a declaration: ``HZ``, or ``HZ:2:ζ`` for two poles."""
    spec = check_high_pass(spec)
    if spec["order"] == 1:
        return f"{spec['cutoff_Hz']:.3g}"
    return f"{spec['cutoff_Hz']:.3g}:2:{spec['damping']:.2g}"


def cumulative_integral(t: NDArray, y: NDArray) -> NDArray:
    """∫₀ᵗ y by the trapezoidal rule, 0 at the first sample [unit·s]
    (:func:`scipy.integrate.cumulative_trapezoid`, as the increments' Monte Carlo
    integrates)."""
    return cumulative_trapezoid(y, t, initial=0.0)


def _inverse_terms(t: NDArray, y: NDArray, spec: Mapping[str, Any]) -> NDArray:
    """``y`` through the high-pass's inverse with its state zero at the first sample."""
    w = 2.0 * math.pi * spec["cutoff_Hz"]
    first = cumulative_integral(t, y)
    if spec["order"] == 1:
        return y + w * first
    return y + 2.0 * spec["damping"] * w * first + w * w * cumulative_integral(t, first)


def rest_correction(
    t: NDArray, u: NDArray, before: NDArray, after: NDArray, *, zero: bool
) -> NDArray:
    """The drift an inverse high-pass leaves, measured at rest.

    Parameters
    ----------
    t : ndarray
        Time [s].
    u : ndarray
        The inverse's output [unit].
    before, after : ndarray of bool
        The rest before the release and after the stop.
    zero : bool
        The channel is zero at rest (a velocity): a line through each rest, between
        them the straight line joining them (:func:`~bayestribo.signal.velocity_integral.
        rest_drift`). Else (a displacement) only the rests' common slope is taken off,
        each rest keeping its own level (the release point and the stop differ).

    Returns
    -------
    ndarray
        The drift to subtract [unit].
    """
    if zero:
        from bayestribo.signal.velocity_integral import rest_drift

        return rest_drift(t, u, before, after)
    num = den = 0.0
    for mask in (before, after):
        if int(mask.sum()) >= 8:
            tm = t[mask] - t[mask].mean()
            num += float(tm @ (u[mask] - u[mask].mean()))
            den += float(tm @ tm)
    if den == 0.0:
        return np.zeros_like(u)
    return (num / den) * (t - t[0])


def undo_high_pass(
    t: ArrayLike,
    y: ArrayLike,
    spec: Mapping[str, Any],
    *,
    zero_at_rest: bool,
    rests: tuple[NDArray, NDArray] | None = None,
) -> NDArray:
    """A channel before its sensor's high-pass (see the module notes).

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    y : array_like
        The recorded channel [unit].
    spec : mapping
        The high-pass (:func:`check_high_pass`).
    zero_at_rest : bool
        The channel is a velocity (zero at rest), else a displacement.
    rests : (ndarray of bool, ndarray of bool), optional
        The samples at rest before the release and after the stop, where the drift is
        measured (:func:`rest_correction`); None leaves it (the filter's state at the
        first sample then taken as zero: a record that starts at rest, settled).

    Returns
    -------
    ndarray
        The channel at the high-pass's input [unit].
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    u = _inverse_terms(t, y, check_high_pass(spec))
    if rests is not None:
        u = u - rest_correction(t, u, rests[0], rests[1], zero=zero_at_rest)
    return u


@dataclass(frozen=True)
class HighPassSign:
    """A record's sign of a sensor high-pass (:func:`detect_high_pass`).

    Attributes
    ----------
    cutoff_Hz : float
        The corner frequency the centres' drift gives [Hz].
    cutoff_se_Hz : float
        Its standard error [Hz] (from the centres' scatter; the estimate's error on
        simulated records is within about 2 of them).
    channel : str
        What the centres were read from: ``"velocity's integral"`` or
        ``"displacement"``.
    z : float
        ``cutoff_Hz / cutoff_se_Hz``.
    drift : float
        How far the centres move over the record, as a fraction of the largest swing.
    order : int
        Poles: 1, or 2 where the two-pole inverse explains the centres far better.
    damping : float or None
        The two poles' damping ζ_g [-]; None for one pole.
    rss, dof : float, int
        The regression's residual sum of squares and degrees of freedom.
    """

    cutoff_Hz: float
    cutoff_se_Hz: float
    channel: str
    z: float
    drift: float
    order: int = 1
    damping: float | None = None
    rss: float = math.nan
    dof: int = 0

    @property
    def spec(self) -> dict[str, Any]:
        """The declaration advised, to three significant digits."""
        spec: dict[str, Any] = {"cutoff_Hz": float(f"{self.cutoff_Hz:.3g}"), "order": self.order}
        if self.order == 2 and self.damping is not None:
            spec["damping"] = float(f"{self.damping:.2g}")
        return spec

    def advice(self) -> str:
        """The sentence a warning gives: the sign, the estimate and the option."""
        spec = self.spec
        value = option_text(spec)
        poles = (
            "one pole"
            if self.order == 1
            else f"two poles, damping {spec['damping']:g}, as a geophone's"
        )
        return (
            f"the {self.channel} swings about a centre that relaxes from the release "
            "toward the rest, the sign of a sensor that passes no DC (an AC-coupled "
            "channel, a geophone, a piezoelectric sensor): a high-pass of "
            f"{poles} with its corner at {self.cutoff_Hz:.3g} ± {self.cutoff_se_Hz:.2g} Hz "
            f"from the centres ({self.drift:.0%} of the largest swing moved). Declare it: "
            f"sensor_high_pass={spec} (--sensor-high-pass {value}) undoes it when the run "
            "is read"
            + (
                " (the sensor's data-sheet corner and poles, where known, are better)"
                if self.order == 1
                else "; two poles are estimated to a few per cent only, which can leave a "
                "misfit: the sensor's data-sheet corner and damping answer it"
            )
        )


def _at(times: NDArray, t: NDArray, s: NDArray) -> NDArray:
    return np.interp(times, t, s)


def _centres_fit(
    t: ArrayLike,
    signal: ArrayLike,
    turning_times: ArrayLike,
    *,
    velocity: bool,
    z_min: float,
    ratio: float = 1.0,
    instrument: float | None = None,
    order: int = 1,
    gate: bool = True,
) -> HighPassSign | None:
    """One regression of the centres at the given turning times (see
    :func:`detect_high_pass`): ``(x_{k+1} + r x_k)/(1 + r)`` of consecutive turning
    points, which for a viscous decay of ratio r per half cycle (and a Coulomb
    friction's alternation) is the equilibrium exactly; with r = 1 the midpoints.
    ``instrument``: a corner [rad/s] whose relaxation ``exp(-ω_c t)`` stands for the
    regressor ``∬y`` (an instrumental variable): the regressor holds the noise's double
    integral, which the centres' own noise (its single integral) is correlated with,
    and which put the corner 1-4 % low on a 3 Hz rig with poles at 0.3-0.9 Hz.
    ``order`` 2: the two-pole inverse's terms ``2ζ_g ω_c ∬y`` and ``ω_c² ∭y`` (and a
    cubic of drift), no instrument. ``gate`` False: the regression whatever its corner,
    standard error and drift (its residual for :func:`_two_poles`).

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    signal : array_like
        The recorded velocity (``velocity`` True) or displacement [unit].
    turning_times : array_like
        The motion's turning times [s] (the velocity's zeros).
    velocity : bool
        ``signal`` is a velocity: its integral is the displacement whose centres are
        read, with a parabola of drift (an offset and a linear wander of the velocity
        after the inverse); else a line.
    z_min : float
        Standard errors by which the corner must stand out of zero.

    Returns
    -------
    HighPassSign or None
        None where the turning points are fewer than 12, the corner does not stand
        out, or lies beyond the oscillation's frequency (no sign of a high-pass).
    """
    t = np.asarray(t, dtype=float)
    s = np.asarray(signal, dtype=float)
    tt = np.asarray(turning_times, dtype=float)
    tt = tt[(tt > t[0]) & (tt < t[-1])]
    if tt.size < _FEWEST_TURNING_POINTS or t.size < 16:
        return None
    d = cumulative_integral(t, s) if velocity else s - s[0]
    j = cumulative_integral(t, d)
    dk, jk = _at(tt, t, d), _at(tt, t, j)
    swing = 0.5 * np.abs(np.diff(dk))
    mid = lambda a: (a[1:] + ratio * a[:-1]) / (1.0 + ratio)  # noqa: E731
    tm = mid(tt - tt[0])
    sign = (-1.0) ** np.arange(tm.size)
    scale = float(tt[-1] - tt[0])
    columns = [
        np.ones_like(tm),
        sign,
        sign * swing / swing.max(),
        tm / scale,
    ]
    if velocity:
        columns.append(mid((tt - tt[0]) ** 2) / scale**2)
    terms = [mid(jk)]
    if order == 2:
        terms.append(mid(_at(tt, t, cumulative_integral(t, j))))
        columns.append(
            mid((tt - tt[0]) ** (3 if velocity else 2)) / scale ** (3 if velocity else 2)
        )
    # the centres as the inverse makes them: mid(d) + ω_c mid(j) = polynomial + alternation
    a = np.column_stack([*terms, *columns])
    b = -mid(dk)
    z_ = a.copy()
    if instrument is not None and order == 1:
        z_[:, 0] = np.exp(-instrument * tm)
    # the centres' noise is the integral of the record's: a random walk, whose steps
    # are independent; the regression is on the centres' steps (the constant drops out)
    keep = [i for i in range(a.shape[1]) if i != len(terms)]
    a, z_, b = np.diff(a[:, keep], axis=0), np.diff(z_[:, keep], axis=0), np.diff(b)
    dof = b.size - a.shape[1]
    if dof < 4:
        return None
    try:
        inverse = np.linalg.inv(z_.T @ a)
        coef = inverse @ (z_.T @ b)
        resid = b - a @ coef
        s2 = float(resid @ resid) / dof
        cov = s2 * inverse @ (z_.T @ z_) @ inverse.T
    except np.linalg.LinAlgError:
        return None
    rss = float(resid @ resid)
    if order == 2:
        p1, p2 = float(coef[0]), float(coef[1])
        if not (p1 > 0 and p2 > 0) and gate:
            return None
        w = math.sqrt(abs(p2))
        se = 0.5 * math.sqrt(max(float(cov[1, 1]), 0.0)) / w  # of ω_c from that of ω_c²
        damping = p1 / (2.0 * w) if w > 0 else math.nan
        if not 0.05 <= damping <= 5.0 and gate:
            return None
    else:
        w, se = float(coef[0]), math.sqrt(max(float(cov[0, 0]), 0.0))
        damping = None
    if not (w > 0 and se > 0 and math.isfinite(w)) and gate:
        return None
    z = w / se if se > 0 else math.inf
    period = 2.0 * float(np.median(np.diff(tt)))
    cutoff = w / (2.0 * math.pi)
    least = z_min if order == 1 else max(z_min, TWO_POLE_Z)
    if gate and (z < least or cutoff * period > 2.0):
        return None
    poly = np.column_stack([columns[0], *columns[3:]])
    term = sum(c * q for c, q in zip(coef[: len(terms)], terms, strict=True))
    term = term - poly @ np.linalg.lstsq(poly, term, rcond=None)[0]
    drift = float(np.ptp(term)) / float(swing.max()) if swing.max() > 0 else 0.0
    if gate and not drift >= DETECTION_DRIFT:
        return None
    return HighPassSign(
        cutoff_Hz=cutoff,
        cutoff_se_Hz=se / (2.0 * math.pi),
        channel="velocity's integral" if velocity else "displacement",
        z=z,
        drift=drift,
        order=order,
        damping=damping,
        rss=rss,
        dof=dof,
    )


def _decay_ratio(t: NDArray, s: NDArray, tt: NDArray, w: float, velocity: bool) -> float:
    """The ratio r of consecutive turning points about the equilibrium, ``x_{k+1} - e =
    -r (x_k - e) + c (-1)^k``, of the motion undone at ω_c = ``w`` (in [0.5, 1], 1 where
    it cannot be had)."""
    d = cumulative_integral(t, s) if velocity else s - s[0]
    x = _at(tt, t, d + w * cumulative_integral(t, d))
    sign = (-1.0) ** np.arange(x.size - 1)
    span = max(float(tt[-1] - tt[0]), 1e-12)
    a = np.column_stack([x[:-1], np.ones(x.size - 1), sign, (tt[1:] - tt[0]) / span])
    coef, *_ = np.linalg.lstsq(a, x[1:], rcond=None)
    r = -float(coef[0])
    return r if math.isfinite(r) and 0.5 <= r <= 1.0 else 1.0


def _turning_times(t: NDArray, u: NDArray, near: NDArray, period: float) -> NDArray:
    """The zeros of a velocity ``u`` nearest the times ``near``: a cubic fitted over a
    quarter period each side, its root nearest (the time itself where none is)."""
    out = near.copy()
    for i, c in enumerate(near):
        m = np.abs(t - c) <= 0.25 * period
        if int(m.sum()) < 6:
            continue
        p = np.polynomial.Polynomial.fit(t[m] - c, u[m], 3)
        roots = p.roots()
        roots = roots[np.isreal(roots)].real
        roots = roots[np.abs(roots) <= 0.25 * period]
        if roots.size:
            out[i] = c + roots[np.argmin(np.abs(roots))]
    return out


def detect_high_pass(
    t: ArrayLike,
    signal: ArrayLike,
    turning_times: ArrayLike,
    *,
    velocity: bool,
    z_min: float = DETECTION_Z,
) -> HighPassSign | None:
    """The sign of a one-pole sensor high-pass in a record, or None.

    The centres are read at the turning points of the motion before the filter: the
    recorded ones lead the motion's by the filter's phase (9.5° at f_c = f/6), and read
    there the corner came out 3 % low (on a 3 Hz rig with a 0.5 Hz pole: enough for a
    misfit when the estimate is declared). So the turning times are taken again at the
    zeros of the velocity undone at the estimate, three times (0.2 % off on that rig).

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    signal : array_like
        The recorded velocity (``velocity`` True) or displacement [unit].
    turning_times : array_like
        The recorded motion's turning times [s] (the velocity's zeros).
    velocity : bool
        ``signal`` is a velocity: its integral is the displacement whose centres are
        read, with a parabola of drift (an offset and a linear wander of the velocity
        after the inverse); else a line.
    z_min : float
        Standard errors by which the corner must stand out of zero.

    Returns
    -------
    HighPassSign or None
        None where the turning points are fewer than 12, the corner does not stand
        out, lies beyond twice the oscillation's frequency, or the centres move by less than
        :data:`DETECTION_DRIFT` of the largest swing (no sign of a high-pass).
    """
    t = np.asarray(t, dtype=float)
    s = np.asarray(signal, dtype=float)
    tt = np.asarray(turning_times, dtype=float)
    one = _centres_fit(t, s, tt, velocity=velocity, z_min=z_min)
    two = _centres_fit(t, s, tt, velocity=velocity, z_min=z_min, order=2)
    sign = two if _two_poles(one, two, t, s, tt, velocity) else one
    if sign is None:
        return None
    period = 2.0 * float(np.median(np.diff(tt)))
    for _ in range(3):
        spec = {"cutoff_Hz": sign.cutoff_Hz, "order": sign.order}
        if sign.order == 2:
            spec["damping"] = sign.damping
        u = _inverse_terms(t, s, check_high_pass(spec))
        if not velocity:
            u = np.gradient(u, t)
        times = _turning_times(t, u, tt, period)
        ratio = _decay_ratio(t, s, times, sign.cutoff_Hz * 2.0 * math.pi, velocity)
        again = _centres_fit(
            t,
            s,
            times,
            velocity=velocity,
            z_min=z_min,
            ratio=ratio,
            instrument=sign.cutoff_Hz * 2.0 * math.pi,
            order=sign.order,
        )
        if again is None:
            return None
        sign = again
    return sign


#: Standard errors by which two poles' corner must stand out of zero (two-pole records
#: at corners of 0.1-0.3 f give 180 and more; a pendulum in air read as a length, 19).
TWO_POLE_Z = 50.0
#: How many times the two-pole inverse must explain the centres' steps better than the
#: one-pole inverse (an F statistic) for two poles to be named: on one-pole records up
#: to 22, on a pendulum in air read as a length 91, on two-pole records (ζ_g 0.7) 10⁴
#: and more.
TWO_POLE_F = 300.0


def _two_poles(
    one: HighPassSign | None,
    two: HighPassSign | None,
    t: NDArray,
    s: NDArray,
    tt: NDArray,
    velocity: bool,
) -> bool:
    """Whether the centres ask for two poles (:data:`TWO_POLE_F`)."""
    if two is None:
        return False
    if one is None:
        # the one-pole fit named nothing (a corner of the wrong sign, no drift): its
        # residual all the same
        one = _centres_fit(t, s, tt, velocity=velocity, z_min=-math.inf, gate=False)
        if one is None:
            return False
    return (one.rss - two.rss) / (two.rss / two.dof) > TWO_POLE_F


def _runs(mask: NDArray) -> list[list[int]]:
    """The runs of True in ``mask`` as ``[first, stop)`` index pairs."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return [[int(a), int(b)] for a, b in zip(edges[::2], edges[1::2], strict=True)]


def noise_record(
    t: NDArray, y: NDArray, spec: Mapping[str, Any], rests: tuple[NDArray, NDArray]
) -> dict[str, Any] | None:
    """What :func:`high_pass_noise` needs to draw the noise an undone velocity holds:
    the recorded channel's white noise σ at rest (from its first differences, which the
    filter's slow relaxation there does not reach), the sampling, the rests and the
    declaration; None for a record not sampled regularly or without rest."""
    if t.size < 3:
        return None
    step = float(np.median(np.diff(t)))
    if not (step > 0 and np.allclose(np.diff(t), step, rtol=1e-3, atol=0.0)):
        return None
    rest = rests[0] | rests[1]
    pairs = rest[1:] & rest[:-1]
    if int(pairs.sum()) < 8:
        return None
    sigma = float(np.std(np.diff(y)[pairs]) / math.sqrt(2.0))
    if not (math.isfinite(sigma) and sigma > 0):
        return None
    return {
        "kind": "high_pass",
        **check_high_pass(spec),
        "sigma": sigma,
        "samples": int(t.size),
        "start_s": float(t[0]),
        "step_s": step,
        "rest_before": _runs(rests[0]),
        "rest_after": _runs(rests[1]),
    }


def high_pass_noise(noise: Mapping[str, Any], count: int, rng: np.random.Generator) -> NDArray:
    """Draws of the noise a velocity undone of its sensor's high-pass holds: the
    recorded white noise through the inverse and its drift taken off at the same rests
    (:func:`undo_high_pass`). The inverse integrates the noise into a random walk held
    at the rests and free between them, which the rest's own noise does not show (on a
    3 Hz rig with a 0.5 Hz pole, χ² 95 for 31 increments when the increments took the
    rest's white noise).

    Parameters
    ----------
    noise : mapping
        :func:`noise_record`'s record.
    count : int
        Draws.
    rng : numpy.random.Generator
        Their source.

    Returns
    -------
    ndarray
        Shape (count, samples) [the velocity's unit].
    """
    n = int(noise["samples"])
    t = float(noise["start_s"]) + float(noise["step_s"]) * np.arange(n)
    masks = []
    for key in ("rest_before", "rest_after"):
        mask = np.zeros(n, dtype=bool)
        for first, stop in noise[key]:
            mask[first:stop] = True
        masks.append(mask)
    spec = check_high_pass({k: noise[k] for k in ("cutoff_Hz", "order", "damping") if k in noise})
    y = rng.normal(0.0, float(noise["sigma"]), (count, n))
    w = 2.0 * math.pi * spec["cutoff_Hz"]
    dt = float(noise["step_s"])
    first = np.zeros_like(y)
    first[:, 1:] = np.cumsum(0.5 * (y[:, 1:] + y[:, :-1]) * dt, axis=1)
    if spec["order"] == 1:
        u = y + w * first
    else:
        second = np.zeros_like(y)
        second[:, 1:] = np.cumsum(0.5 * (first[:, 1:] + first[:, :-1]) * dt, axis=1)
        u = y + 2.0 * spec["damping"] * w * first + w * w * second
    from bayestribo.signal.velocity_integral import rest_drift

    return u - rest_drift(t, u, masks[0], masks[1])
