"""Tests that sweep simulation settings as flat dictionaries: group them into the
simulator's objects (law, rig, release, sensor) and simulate."""

from __future__ import annotations

from typing import Any

from bayestribo.model.scaling import Rig
from bayestribo.synthetic import PAPER_RIG, DissipationLaw, Release, Sensor, simulate

_LAW = ("zeta", "mu_k", "mu_s")
_RIG = ("natural_frequency_Hz", "mass_kg", "load_N")
_RELEASE = (
    "initial_displacement_m",
    "rest_before_s",
    "motion_duration_s",
    "rest_after_s",
    "magnet_fade_s",
    "offset_m",
    "time_origin_s",
)
_SENSOR = (
    "sample_rate_Hz",
    "displacement_noise_m",
    "velocity_noise_m_per_s",
    "displacement_resolution_m",
    "velocity_resolution_m_per_s",
    "quantise",
    "displacement_range_m",
    "velocity_range_m_per_s",
    "channels",
)


def simulate_flat(**settings: Any) -> Any:
    """``simulate`` with the fields of every object given as one flat set of keywords."""
    unknown = set(settings) - {*_LAW, *_RIG, *_RELEASE, *_SENSOR, "seed", "metadata"}
    if unknown:
        raise TypeError(f"unknown simulation settings {sorted(unknown)}")

    def pick(names: tuple[str, ...]) -> dict[str, Any]:
        return {k: settings[k] for k in names if k in settings}

    rig = {
        "natural_frequency_Hz": PAPER_RIG.natural_frequency_Hz,
        "mass_kg": PAPER_RIG.mass_kg,
        "load_N": PAPER_RIG.load_N,
        **pick(_RIG),
    }
    return simulate(
        DissipationLaw(**pick(_LAW)),
        rig=Rig(**rig),
        release=Release(**pick(_RELEASE)),
        sensor=Sensor(**pick(_SENSOR)),
        seed=settings.get("seed"),
        metadata=settings.get("metadata"),
    )
