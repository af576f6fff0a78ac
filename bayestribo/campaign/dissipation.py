"""The law-free answer across runs: ΔE at common swings, from each run's turning points.

Where no law holds, a run's answer is the energy it loses per cycle at each swing,
ΔE(A), measured from its turning points whatever the law
(:func:`bayestribo.inference.dissipation.turning_point_dissipation`: a mean and a
standard deviation at each of its swings). A campaign compares it across runs at
swings every run of a series reaches (:func:`common_amplitudes`: the overlap of the
runs' ranges, three swings spaced evenly in log A within it), each run's ΔE there
interpolated in log-log between its two nearest swings (its sd in proportion).

The population of repeats then takes each run's ΔE at a swing as a normal measurement
N(m_r, s_r) under a flat prior: :func:`dissipation_samples` draws from it, with a log
prior density of zero, so that the population's importance-sampling likelihood
(:mod:`bayestribo.population.likelihood`) is that of the random-effects model
m_r ~ N(β, σ² + s_r²), the meta-analysis of repeats with known errors.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.population.samples import RunSamples

__all__ = [
    "N_SWINGS",
    "common_amplitudes",
    "dissipation_name",
    "dissipation_samples",
    "has_band",
]

#: Swings per series at which ΔE is compared.
N_SWINGS = 3


def _band(run: Any) -> Mapping[str, Any] | None:
    band = getattr(run, "turning_points", None)
    if band is None:
        band = getattr(run, "turning_point_dissipation", None)
    if not band or not band.get("amplitude") or not band.get("mean") or not band.get("sd"):
        return None
    return band


def has_band(run: Any) -> bool:
    """Whether a fit result or digest holds its turning points' ΔE(A)."""
    return _band(run) is not None


def common_amplitudes(runs: Sequence[Any], n: int = N_SWINGS) -> NDArray[np.float64] | None:
    """Swings [the runs' length unit] every run's turning points reach, or None.

    Parameters
    ----------
    runs : sequence of fit results or digests
        Each with its turning points' ΔE(A) band (``turning_point_dissipation`` of a fit,
        ``turning_points`` of a digest).
    n : int
        Number of swings, evenly spaced in log A over the overlap of the runs' ranges
        (one, its geometric middle, when the overlap is a point).

    Returns
    -------
    ndarray or None
        None when a run has no band, the bands' units differ, or the ranges do not
        overlap.
    """
    bands = [_band(r) for r in runs]
    if not bands or any(b is None for b in bands):
        return None
    units = {(b.get("amplitude_unit"), b.get("unit")) for b in bands if b is not None}
    if len(units) != 1:
        return None
    low = max(min(b["amplitude"]) for b in bands if b is not None)
    high = min(max(b["amplitude"]) for b in bands if b is not None)
    if not (low > 0 and high >= low):
        return None
    if math.isclose(low, high, rel_tol=1e-9):
        return np.array([low])
    # inside the ends a little, so no run is extrapolated by rounding
    return np.geomspace(low * (1 + 1e-9), high * (1 - 1e-9), n)


def _at(band: Mapping[str, Any], amplitude: float) -> tuple[float, float]:
    """(mean, sd) of a band at ``amplitude``, log-log between its nearest swings."""
    a = np.asarray(band["amplitude"], dtype=float)
    m = np.asarray(band["mean"], dtype=float)
    s = np.asarray(band["sd"], dtype=float)
    order = np.argsort(a)
    a, m, s = a[order], m[order], s[order]
    ok = (a > 0) & (m > 0) & np.isfinite(s)
    a, m, s = a[ok], m[ok], s[ok]
    mean = float(np.exp(np.interp(math.log(amplitude), np.log(a), np.log(m))))
    relative = float(np.interp(math.log(amplitude), np.log(a), s / m))
    return mean, relative * mean


def dissipation_name(amplitude: float, unit: str) -> str:
    """The quantity's name: ``ΔE(A=1.5e-04 m)``."""
    return f"ΔE(A={amplitude:.3g} {unit})"


def dissipation_samples(
    run: Any,
    amplitudes: Sequence[float],
    *,
    n_samples: int = 300,
    seed: int = 0,
    name: str | None = None,
) -> RunSamples:
    """A run's ΔE at ``amplitudes`` as draws of N(m_r, s_r), log prior zero (module notes).

    Parameters
    ----------
    run : fit result or digest
        With its turning points' band and ``metadata`` (``run_id``).
    amplitudes : sequence of float
        Swings inside the run's range [its length unit] (:func:`common_amplitudes`).
    n_samples : int
        Draws per swing.
    seed : int
        Combined with the run's name: the draws do not depend on the order of the runs.
    name : str, optional
        The run's name; default its ``run_id``.
    """
    band = _band(run)
    if band is None:
        raise ValueError("run: no ΔE(A) from its turning points")
    md = dict(getattr(run, "metadata", {}) or {})
    name = name or str(md.get("run_id") or getattr(run, "run_name", None) or "run")
    rng = np.random.default_rng([int(seed), zlib.crc32(f"dissipation:{name}".encode())])
    unit = str(band.get("amplitude_unit") or "m")
    values = {}
    for amplitude in amplitudes:
        mean, sd = _at(band, float(amplitude))
        values[dissipation_name(float(amplitude), unit)] = rng.normal(mean, max(sd, 0.0), n_samples)
    return RunSamples(name, values, np.zeros(n_samples), md)
