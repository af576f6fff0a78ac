"""A record whose natural frequency is not the nominal one given with it.

The stiffness is k = mΩ² (Rigaud et al. 2010, Eq. 6) with Ω the natural frequency the
energy decay measures from the record's turning times
(:func:`bayestribo.signal.decay.energy_decay`), not the nominal ``natural_frequency_Hz``
of the metadata; μ_k = x_c k/N, the viscous coefficient c = 2ζmΩ and ΔE(A) in joules
follow it (μ_k ∝ Ω²; ζ and μ_s/μ_k are dimensionless and do not). The two agree on a
rig that is what its sidecar says. Where they do not, one of them is wrong:

* the rig's frequency is not the nominal one (another blade, another mass, a stale
  value): the measured one is right, and the sidecar should say it;
* the record's clock is off (a sample rate that is not the one stated, time stamps
  from a drifting clock, a logger that does not clock its samples): every frequency in
  the record is off by the clock's factor, and so is the stiffness, twice over in μ_k
  (a clock 2.4 % slow: μ_k 4.7 % low, its interval missing the truth with exit 0, the
  velocity said to read 1.024 × dx/dt and rescaled).

The record cannot tell which; a relative difference beyond :data:`NOMINAL_TOLERANCE`
is said (:class:`~bayestribo.errors.NominalFrequencyWarning`, exit 1), with the
frequency-dependent quantities' change against the nominal and the option for each
case: the measured frequency given as the nominal, or the time read at the clock that
makes the record's frequency the nominal (``--scale t=F``), which, followed, gives μ_k
its value at the nominal frequency (``tests/test_inference_nominal_frequency.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from bayestribo._warnings import warn
from bayestribo.errors import NominalFrequencyWarning
from bayestribo.signal.decay import EnergyDecay

__all__ = ["NOMINAL_TOLERANCE", "nominal_frequency_mismatch", "warn_nominal_frequency"]

#: Relative difference between the measured and the nominal natural frequency beyond
#: which they are said to disagree: 1 %, a change of 2 % in μ_k (twice the default
#: sensor gain uncertainty of 1 % that μ_k's interval carries), well beyond a nominal
#: value given to three digits (32.6 Hz: ± 0.15 %).
NOMINAL_TOLERANCE = 0.01


def nominal_frequency_mismatch(
    decay: EnergyDecay, metadata: Mapping[str, Any], name: str | None = None
) -> str | None:
    """What the warning says when the record's natural frequency is not the nominal
    one, or None.

    Parameters
    ----------
    decay : EnergyDecay
        The run's energy decay (its measured and nominal natural frequencies [Hz]).
    metadata : mapping
        The run's metadata: the check applies where ``mass_kg`` is given (the
        stiffness k = m(2πf)² then enters the reported quantities).
    name : str, optional
        The run's name in the message.

    Returns
    -------
    str or None
        The message; None without a nominal frequency, without a mass, or within
        :data:`NOMINAL_TOLERANCE`.
    """
    nominal = decay.nominal_frequency_Hz
    measured = decay.natural_frequency_Hz
    if nominal is None or metadata.get("mass_kg") is None:
        return None
    if not (math.isfinite(measured) and measured > 0.0 and nominal > 0.0):
        return None
    ratio = measured / nominal
    if abs(ratio - 1.0) <= NOMINAL_TOLERANCE:
        return None
    change = 100.0 * (ratio - 1.0)
    stiffness = 100.0 * (1.0 / ratio**2 - 1.0)
    return (
        f"{name or 'the run'}: its natural frequency measured from the turning times, "
        f"{measured:.5g} Hz, is {change:+.2f} % from the nominal natural_frequency_Hz = "
        f"{nominal:g} Hz given with it; the stiffness k = m(2πf)² takes the measured one, "
        f"so μ_k (∝ f²), the viscous coefficient and ΔE(A) in joules would be "
        f"{stiffness:+.1f} % (μ_k) at the nominal one (ζ and μ_s/μ_k are the same either "
        "way). One of the two is wrong: if the rig's frequency is the record's, give it "
        f"as the nominal (natural_frequency_Hz {measured:.5g}, --frequency {measured:.5g}); "
        "if the record's clock is off (a sample rate that is not the one stated, a "
        "logger that does not clock its samples), read its time at the clock that makes "
        f"its frequency the nominal (--scale t={ratio:.6g})"
    )


def warn_nominal_frequency(
    name: str | None, decay: EnergyDecay, metadata: Mapping[str, Any]
) -> None:
    """Warn (:class:`~bayestribo.errors.NominalFrequencyWarning`) where
    :func:`nominal_frequency_mismatch` finds the record's frequency is not the
    nominal one."""
    text = nominal_frequency_mismatch(decay, metadata, name)
    if text is not None:
        warn(text, NominalFrequencyWarning)
