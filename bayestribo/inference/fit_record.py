"""What a fit records beside its draws, as one typed record.

:class:`FitRecord` is the provenance, settings, checks and answers of one fit (the
run, the law, the noise model, the diagnostics, ΔE(A), the comparison of
``law="auto"``, ...), each a field with its type. A fit file keeps them as the
attributes of its posterior group, numbers as numbers and records as JSON text
(``dissipation_json``, ...): :meth:`FitRecord.to_attrs` writes those attributes and
:meth:`FitRecord.from_attrs` reads them back, from a file of this version or of an
earlier one (an attribute an earlier version did not write stays unwritten).
:meth:`FitRecord.to_dict` and :meth:`FitRecord.from_dict` are its plain data.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["FitRecord", "plain_data"]


def plain_data(value: Any) -> Any:
    """JSON-compatible copy (numpy scalars and arrays to Python)."""
    if isinstance(value, Mapping):
        return {str(k): plain_data(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain_data(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain_data(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _json(attribute: str, *, plain: bool = True, allow_nan: bool = True) -> dict[str, Any]:
    """The metadata of a field kept as JSON text in the attribute ``attribute``;
    ``plain``: made plain data first (non-finite numbers as null), as the fit has always
    written it."""
    return {"attribute": attribute, "json": True, "plain": plain, "allow_nan": allow_nan}


def _number(attribute: str) -> dict[str, Any]:
    """The metadata of a field kept as a number or text in the attribute ``attribute``."""
    return {"attribute": attribute, "json": False}


@dataclass(frozen=True)
class FitRecord:
    """The record of one fit, in the order of its file's attributes.

    Attributes
    ----------
    run_name : str
        The fitted run's name (file or ``run_id``).
    model : str
        Forward model, ``"exact"`` or ``"averaged"``.
    law : str
        The dissipation law fitted.
    dissipation : dict or None
        ΔE(A) of the law (or averaged over the laws as good, with ``law="auto"``).
    turning_point_dissipation : dict or None
        ΔE(A) from the turning points alone.
    shape_agreement : dict or None
        The law's ΔE(A) against the turning points'.
    restoring : dict or None
        The restoring force and what was measured of it.
    units : dict
        Unit of each of the law's own quantities.
    seed : int
        The fit's seed (-1: none).
    package_version : str
        The bayestribo version that made the fit.
    friction_defined : int
        1 when friction is a coefficient (load and mass known), else 0.
    length_scale, omega, tau_end : float
        The fit's length scale [signal unit], angular frequency [rad/s] and end of Π.
    motion_ended : int
        1 when the record holds the end of the motion.
    metadata, noise, channels : dict
        The run's metadata, the noise model, the channel calibration (None: one signal).
    priors, fixed, settings, diagnostics : dict
        The priors (plain data), fixed values, settings and sampler diagnostics.
    frequency_trend : dict or None
        The half period's trend with amplitude beyond the law's own.
    frequency_nuisance_sd : float
        Relative sd of the frequency nuisance [-].
    sensor : dict
        The sensor's gain and its uncertainty.
    law_frequency_change : float
        The law's own change of the half period over the decay [-].
    prior_sensitivity : dict
        Power-scaling prior sensitivity per parameter.
    law_comparison : dict or None
        How ``law="auto"`` chose the law (None for a named law).
    verdict_dissipation : dict or None
        The verdict's own ΔE(A) where :attr:`dissipation` is averaged.
    spec : dict or None
        The fit's specification (:meth:`~bayestribo.inference.spec.FitSpec.to_dict`).
    seconds : float or None
        Wall time of the fit [s].
    boundary : dict or None
        The law's boundaries (a term absent: no friction, no viscous damping, no
        quadratic drag, ...): each one's posterior probability from the Savage–Dickey
        density ratio, and the nested laws whose fits were mixed into the draws, if any
        (:mod:`bayestribo.inference.boundary`); None for a law not averaged (one term,
        ``law="auto"``, the law-free fit, a parameter fixed).
    unwritten : frozenset of str
        Attributes the record does not write (those a file of an earlier version does
        not hold, and the optional ones left None).
    extra : dict
        Attributes of the file that are not fields (kept as they are).
    """

    run_name: str | None = field(default=None, metadata=_number("run_name"))
    model: str | None = field(default=None, metadata=_number("model"))
    law: str | None = field(default=None, metadata=_number("law"))
    dissipation: dict[str, Any] | None = field(default=None, metadata=_json("dissipation_json"))
    turning_point_dissipation: dict[str, Any] | None = field(
        default=None, metadata=_json("turning_point_dissipation_json")
    )
    shape_agreement: dict[str, Any] | None = field(
        default=None, metadata=_json("shape_agreement_json")
    )
    restoring: dict[str, Any] | None = field(default=None, metadata=_json("restoring_json"))
    units: dict[str, str] | None = field(default=None, metadata=_json("units_json", plain=False))
    seed: int | None = field(default=None, metadata=_number("seed"))
    package_version: str | None = field(default=None, metadata=_number("package_version"))
    friction_defined: int | None = field(default=None, metadata=_number("friction_defined"))
    length_scale: float | None = field(default=None, metadata=_number("length_scale"))
    omega: float | None = field(default=None, metadata=_number("omega"))
    tau_end: float | None = field(default=None, metadata=_number("tau_end"))
    motion_ended: int | None = field(default=None, metadata=_number("motion_ended"))
    metadata: dict[str, Any] | None = field(default=None, metadata=_json("metadata_json"))
    noise: dict[str, Any] | None = field(default=None, metadata=_json("noise_json"))
    channels: dict[str, Any] | None = field(default=None, metadata=_json("channels_json"))
    priors: dict[str, Any] | None = field(default=None, metadata=_json("priors_json", plain=False))
    fixed: dict[str, float] | None = field(default=None, metadata=_json("fixed_json"))
    settings: dict[str, Any] | None = field(
        default=None, metadata=_json("settings_json", plain=False)
    )
    diagnostics: dict[str, Any] | None = field(default=None, metadata=_json("diagnostics_json"))
    frequency_trend: dict[str, Any] | None = field(
        default=None, metadata=_json("frequency_trend_json", plain=False)
    )
    frequency_nuisance_sd: float | None = field(
        default=None, metadata=_number("frequency_nuisance_sd")
    )
    sensor: dict[str, Any] | None = field(default=None, metadata=_json("sensor_json", plain=False))
    law_frequency_change: float | None = field(
        default=None, metadata=_number("law_frequency_change")
    )
    prior_sensitivity: dict[str, Any] | None = field(
        default=None, metadata=_json("prior_sensitivity_json")
    )
    law_comparison: dict[str, Any] | None = field(
        default=None, metadata=_json("law_comparison_json")
    )
    verdict_dissipation: dict[str, Any] | None = field(
        default=None, metadata=_json("verdict_dissipation_json")
    )
    spec: dict[str, Any] | None = field(
        default=None, metadata=_json("spec_json", plain=False, allow_nan=False)
    )
    seconds: float | None = field(default=None, metadata=_number("seconds"))
    boundary: dict[str, Any] | None = field(default=None, metadata=_json("boundary_json"))
    unwritten: frozenset[str] = field(
        default=frozenset({"law_comparison", "verdict_dissipation", "spec", "seconds", "boundary"})
    )
    extra: dict[str, Any] = field(default_factory=dict)

    @staticmethod
    def _fields() -> list[dataclasses.Field]:
        return [f for f in dataclasses.fields(FitRecord) if "attribute" in f.metadata]

    def replace(self, **changes: Any) -> FitRecord:
        """A copy with ``changes``; each field given is written (no longer unwritten)."""
        unwritten = self.unwritten - set(changes)
        return dataclasses.replace(self, **changes, unwritten=frozenset(unwritten))

    def to_attrs(self) -> dict[str, Any]:
        """The attributes of a fit file's posterior group: numbers as they are, the
        records as JSON text, in the fields' order, then :attr:`extra`."""
        out: dict[str, Any] = {}
        for f in self._fields():
            if f.name in self.unwritten:
                continue
            value = getattr(self, f.name)
            key = f.metadata["attribute"]
            if f.metadata["json"]:
                data = plain_data(value) if f.metadata["plain"] else value
                out[key] = json.dumps(data, allow_nan=f.metadata["allow_nan"])
            else:
                out[key] = value
        out.update(self.extra)
        return out

    @classmethod
    def from_attrs(cls, attrs: Mapping[str, Any]) -> FitRecord:
        """The record of a fit file's attributes (:meth:`to_attrs`, of this version or
        an earlier one: an attribute it does not hold is a field left unwritten, None)."""
        values: dict[str, Any] = {}
        unwritten = set()
        known = set()
        for f in cls._fields():
            key = f.metadata["attribute"]
            known.add(key)
            if key not in attrs:
                unwritten.add(f.name)
                continue
            value = attrs[key]
            if f.metadata["json"] and isinstance(value, str):
                value = json.loads(value)
            elif isinstance(value, np.generic):
                value = value.item()
            values[f.name] = value
        extra = {k: v for k, v in attrs.items() if k not in known}
        return cls(**values, unwritten=frozenset(unwritten), extra=extra)

    def to_dict(self) -> dict[str, Any]:
        """Plain data: each written field by name (and ``extra``)."""
        out = {
            f.name: getattr(self, f.name) for f in self._fields() if f.name not in self.unwritten
        }
        if self.extra:
            out["extra"] = dict(self.extra)
        return plain_data(out)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FitRecord:
        """The record of :meth:`to_dict`'s plain data (a field it does not hold is left
        unwritten)."""
        names = {f.name for f in cls._fields()}
        unknown = set(data) - names - {"extra"}
        if unknown:
            raise ValueError(
                f"FitRecord: unknown fields {sorted(unknown)}; expected {sorted(names)}"
            )
        values = {k: v for k, v in data.items() if k in names}
        return cls(
            **values,
            unwritten=frozenset(names - set(values)),
            extra=dict(data.get("extra") or {}),
        )
