"""One fit specification: everything that decides a single-run fit's answer.

:class:`FitSpec` holds the law, the restoring force, the forward model, priors and
fixed values, the sampler's settings, the preparation of the record and how the run
file is read. ``bayestribo.fit`` takes one (or builds one from its keywords),
campaigns record it with every fit and key their catalog on it, and the command line
generates the options of ``fit``, ``campaign``, ``report`` and ``check`` from its
fields (:mod:`bayestribo.cli._spec`), so every entry point takes every option.

Each field is declared once, below, with :func:`_spec_field`: its default, its
meaning and unit, its check and its command-line option. A new fit option is one
field there (and its use in :func:`bayestribo.inference.fitting.fit`).

This module imports no numpy or SciPy: the command line builds its parsers from it.
The checks that need the law registry or the priors import them when a specification
is made.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from bayestribo import DEFAULT_SEED
from bayestribo.errors import BayestriboError
from bayestribo.io.options import ReadOptions

__all__ = ["MODELS", "PRIOR_TYPES", "FitSpec", "SpecOption", "spec_fields"]

#: Forward models of Π (:data:`bayestribo.inference.likelihood.MODELS`).
MODELS: tuple[str, ...] = ("exact", "averaged")
#: Plain-data priors a specification takes (:meth:`bayestribo.inference.priors.Prior.
#: from_spec`): the type and its parameters.
PRIOR_TYPES: dict[str, tuple[str, ...]] = {
    "Uniform": ("low", "high"),
    "Normal": ("mu", "sigma"),
    "LogUniform": ("low", "high"),
}
#: Parameters every law's posterior has besides its terms' (the initial amplitude),
#: and those the discrepancy terms add.
_COMMON = ("y0",)
_DISCREPANCY = ("log10_discrepancy", "log10_shape")


@dataclass(frozen=True)
class SpecOption:
    """How a field is given on the command line.

    Attributes
    ----------
    flag : str
        The option, e.g. ``"--max-steps"``.
    help : str
        Its help text (the default is added from the field).
    kind : {"value", "flag", "off", "pairs", "reading"}
        ``value``: one value parsed by ``parse``; ``flag``: present means True;
        ``off``: present means False; ``pairs``: repeatable ``NAME=VALUE``;
        ``reading``: given by the reading options (:func:`bayestribo.cli._common.
        add_reading_options`), not added again.
    metavar : str, optional
        The value's name in the help.
    parse : str, optional
        Name of the parser of one value in :mod:`bayestribo.cli._spec` (kept as a
        name so that this table imports nothing).
    choices : tuple of str, optional
        The values allowed.
    """

    flag: str
    help: str
    kind: str = "value"
    metavar: str | None = None
    parse: str | None = None
    choices: tuple[str, ...] | None = None

    @property
    def dest(self) -> str:
        """The attribute of the parsed arguments."""
        return self.flag.lstrip("-").replace("-", "_")


def _spec_field(
    default: Any = dataclasses.MISSING,
    *,
    doc: str,
    option: SpecOption,
    check: Callable[[str, Any], Any] | None = None,
    keyword: str | None = None,
    factory: Callable[[], Any] | None = None,
) -> Any:
    """One field of :class:`FitSpec`: its default, meaning (``doc``, with its unit),
    command-line ``option``, ``check`` (``check(name, value)`` returns the value in
    canonical form or raises naming the field) and the keyword of ``fit`` it is given
    as (default: its name)."""
    metadata = {"doc": doc, "option": option, "check": check, "keyword": keyword}
    if factory is not None:
        return field(default_factory=factory, metadata=metadata)
    return field(default=default, metadata=metadata)


def _error(name: str, expected: str, value: Any) -> BayestriboError:
    return BayestriboError(f"{name}: expected {expected}, got {value!r}")


def _integer(low: int, *, optional: bool = False) -> Callable[[str, Any], Any]:
    def check(name: str, value: Any) -> Any:
        if value is None and optional:
            return None
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < low:
            raise _error(name, f"an integer >= {low}" + (" or None" if optional else ""), value)
        return int(value)

    return check


def _boolean(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise _error(name, "True or False", value)
    return value


def _seed(name: str, value: Any) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 0:
        raise _error(name, "a non-negative integer, or None for fresh entropy", value)
    return int(value)


def _model(name: str, value: Any) -> str:
    if value not in MODELS:
        raise _error(name, f"one of {MODELS}", value)
    return str(value)


def _law(name: str, value: Any) -> str | None:
    """A law's canonical name, ``"auto"`` or None (the default law)."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() == "auto":
        return "auto"
    from bayestribo.model.laws import Law, get_law

    if not isinstance(value, str | Law):
        raise _error(name, "a law's name (terms joined with '+'), 'auto' or a Law", value)
    try:
        return get_law(value).name
    except ValueError as exc:
        raise BayestriboError(f"{name}: {exc}") from None


def _restoring(name: str, value: Any) -> str | None:
    if value is None:
        return None
    from bayestribo.model.restoring import restoring_choices

    known = restoring_choices()
    if value not in known:
        raise _error(name, f"one of {', '.join(known)}", value)
    return str(value)


def _notch(name: str, value: Any) -> float | str | None:
    if value is None or value == "auto":
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if isinstance(value, bool) or not math.isfinite(number) or number <= 0.0:
        raise _error(name, "a mains frequency in Hz > 0 (50, 60), 'auto' or None", value)
    return number


def _prior(name: str, value: Any) -> dict[str, Any]:
    """A prior as plain data ``{"type": ..., its parameters}``, checked by building it."""
    if hasattr(value, "to_spec"):
        value = value.to_spec()
    if not isinstance(value, Mapping) or value.get("type") not in PRIOR_TYPES:
        raise _error(
            name, f"a prior {{'type': one of {tuple(PRIOR_TYPES)}, its parameters}}", value
        )
    kind = str(value["type"])
    keys = PRIOR_TYPES[kind]
    if set(value) != {"type", *keys}:
        raise _error(name, f"a {kind} prior with {', '.join(keys)}", dict(value))
    spec: dict[str, Any] = {"type": kind}
    for key in keys:
        try:
            spec[key] = float(value[key])
        except (TypeError, ValueError):
            raise _error(f"{name}.{key}", "a number", value[key]) from None
    from bayestribo.inference.priors import Prior

    try:
        Prior.from_spec(spec)
    except ValueError as exc:
        raise BayestriboError(f"{name}: {exc}") from None
    return spec


def _priors(name: str, value: Any) -> dict[str, dict[str, Any]]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise _error(name, "a mapping of parameter names to priors", value)
    return {str(k): _prior(f"{name}[{k!r}]", value[k]) for k in sorted(value)}


def _fixed(name: str, value: Any) -> dict[str, float]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise _error(name, "a mapping of parameter names to values", value)
    out = {}
    for key in sorted(value):
        try:
            number = float(value[key])
        except (TypeError, ValueError):
            number = math.nan
        if isinstance(value[key], bool) or not math.isfinite(number):
            raise _error(f"{name}[{key!r}]", "a finite number", value[key])
        out[str(key)] = number
    return out


def _read_options(name: str, value: Any) -> ReadOptions:
    if isinstance(value, ReadOptions):
        return value
    if value is None or isinstance(value, Mapping):
        return ReadOptions.of(value)
    raise _error(name, "ReadOptions or a mapping of reading options", value)


@dataclass(frozen=True)
class FitSpec:
    """Everything that decides a single-run fit's answer (see the module notes).

    The parameters are listed under :func:`spec_fields` and in
    ``bayestribo fit --help``; ``FitSpec.__doc__`` is completed from the fields below.
    """

    law: str | None = _spec_field(
        None,
        doc="The dissipation law: registered terms joined with '+' (canonical name), "
        "'auto' (the simplest adequate law as good as the best, of the laws the registry "
        "makes), or None, the default law viscous+coulomb.",
        option=SpecOption("--law", "", metavar="NAME", parse="law"),
        check=_law,
    )
    restoring: str | None = _spec_field(
        None,
        doc="The oscillator's restoring force (a registered one, the sidecar's "
        "'restoring'); None: the sidecar's, else linear; 'auto': chosen from how the half "
        "period changes with the swing (bayestribo.inference.restoring_choice). A "
        "nonlinear one's potential is the law's model's and the record's energy's "
        "(docs/restoring.md).",
        option=SpecOption("--restoring", "", kind="reading"),
        check=_restoring,
    )
    model: str = _spec_field(
        "exact",
        doc="Forward model of Π: 'exact' (piecewise, with sticking) or 'averaged' (closed "
        "form, biased by about 2ζ² of Π).",
        option=SpecOption("--model", "forward model of Π", choices=MODELS),
        check=_model,
    )
    priors: Mapping[str, Mapping[str, Any]] = _spec_field(
        doc="Replacement priors by parameter name, as plain data "
        "({'type': 'Uniform', 'low': 0, 'high': 0.1}; Normal: mu, sigma; LogUniform: low, "
        "high), in the parameter's own (dimensionless) unit; the others keep their "
        "defaults.",
        option=SpecOption(
            "--prior",
            "replace a parameter's prior, e.g. zeta=Uniform(0,0.1), y0=Normal(1,0.01), "
            "mu_k=LogUniform(1e-4,0.5) (repeatable; names as in 'bayestribo laws')",
            kind="pairs",
            metavar="NAME=PRIOR",
            parse="prior",
        ),
        check=_priors,
        factory=dict,
    )
    fixed: Mapping[str, float] = _spec_field(
        doc="Parameters held at a value instead of sampled, by name, in the parameter's "
        "own (dimensionless) unit, e.g. {'zeta': 0.0}.",
        option=SpecOption(
            "--fix",
            "hold a parameter at a value instead of sampling it, e.g. zeta=0 (repeatable)",
            kind="pairs",
            metavar="NAME=VALUE",
            parse="number",
        ),
        check=_fixed,
        factory=dict,
    )
    discrepancy: bool = _spec_field(
        False,
        doc="Add the model-discrepancy terms: a white relative error on E and a departure "
        "of the decay's shape smooth along it, each with its scale sampled.",
        option=SpecOption(
            "--discrepancy",
            "add the model-discrepancy terms: a white relative error on E and a departure "
            "of the decay's shape, smooth along the decay (for a small misfit; for a law "
            "that does not hold, --law auto)",
            kind="flag",
        ),
        check=_boolean,
    )
    seed: int | None = _spec_field(
        DEFAULT_SEED,
        doc="Seed of everything random in the fit (walkers, moves, predictive draws); "
        "None draws fresh entropy (recorded as -1). A campaign's seed, from which each "
        "run's derives.",
        option=SpecOption("--seed", "seed of the fit, recorded in the result", parse="int"),
        check=_seed,
    )
    n_walkers: int = _spec_field(
        16,
        doc="Walkers per ensemble (a multiple of 4 uses the grouped moves).",
        option=SpecOption("--walkers", "walkers per ensemble", metavar="N", parse="int"),
        check=_integer(2),
    )
    n_ensembles: int = _spec_field(
        2,
        doc="Independent ensembles (>= 2, for R-hat).",
        option=SpecOption(
            "--ensembles", "independent ensembles (for R-hat)", metavar="N", parse="int"
        ),
        check=_integer(2),
    )
    max_steps: int = _spec_field(
        20_000,
        doc="Ceiling on the sampler's steps per ensemble (it stops earlier once converged).",
        option=SpecOption(
            "--max-steps", "ceiling on the sampler's steps per ensemble", metavar="N", parse="int"
        ),
        check=_integer(50),
    )
    grid_points: int | None = _spec_field(
        None,
        doc="Number of Π increments; None: one per half cycle.",
        option=SpecOption(
            "--grid-points",
            "Π increments (default: one per half cycle)",
            metavar="N",
            parse="int",
        ),
        check=_integer(2, optional=True),
    )
    skip_oscillations: int = _spec_field(
        1,
        doc="Oscillations skipped after the release (the magnet's).",
        option=SpecOption(
            "--skip", "oscillations to skip after the release", metavar="N", parse="int"
        ),
        check=_integer(0),
    )
    notch_Hz: float | str | None = _spec_field(
        None,
        doc="Mains line [Hz] measured at rest and subtracted from both channels, 'auto' "
        "(the line found in the rest spectrum), or None.",
        option=SpecOption(
            "--notch",
            "subtract the mains line (50, 60) measured at rest from both channels, or the "
            "line found in the rest spectrum (auto); zero-phase, no delay",
            metavar="HZ|auto",
            parse="notch",
        ),
        check=_notch,
        keyword="notch",
    )
    correct_channels: bool = _spec_field(
        True,
        doc="Correct the velocity channel to the displacement when their gain ratio or "
        "delay is off by more than the recording's own uncertainty.",
        option=SpecOption(
            "--no-channel-correction",
            "leave the velocity channel as recorded when its gain or delay is off",
            kind="off",
        ),
        check=_boolean,
    )
    # _spec_field returns dataclasses.field(default_factory=ReadOptions, ...)
    read_options: ReadOptions = _spec_field(  # noqa: RUF009
        doc="How the run file is read (:class:`~bayestribo.io.options.ReadOptions`); "
        "its metadata's 'restoring' is kept in ``restoring``.",
        option=SpecOption("--columns", "", kind="reading"),
        check=_read_options,
        factory=ReadOptions,
    )

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            check = f.metadata["check"]
            object.__setattr__(self, f.name, check(f.name, getattr(self, f.name)))
        metadata = dict(self.read_options.metadata or {})
        if "restoring" in metadata:
            # one place for the restoring force: the field, not the reading metadata
            given = _restoring("read_options.metadata['restoring']", metadata.pop("restoring"))
            if self.restoring not in (None, given):
                raise BayestriboError(
                    f"restoring: {self.restoring!r} and read_options.metadata['restoring'] "
                    f"{given!r} differ; give one"
                )
            object.__setattr__(self, "restoring", given)
            options = self.read_options.replace(metadata=metadata or None)
            object.__setattr__(self, "read_options", options)
        self._check_names()

    def _check_names(self) -> None:
        """Priors and fixed values name parameters of the law (the errors name them)."""
        if not (self.priors or self.fixed):
            return
        if self.law == "auto":
            given = "priors" if self.priors else "fixed"
            raise BayestriboError(
                f"{given}: priors and fixed values name the parameters of one law: give "
                "law=NAME with them, not law='auto'"
            )
        from bayestribo.model.laws import get_law

        law = get_law(self.law)
        known = [*law.parameter_names, *_COMMON, *(_DISCREPANCY if self.discrepancy else ())]
        for which in ("priors", "fixed"):
            for name in getattr(self, which):
                if name not in known:
                    close = difflib.get_close_matches(name, known, n=1)
                    hint = f" (did you mean {close[0]!r}?)" if close else ""
                    extra = (
                        "; log10_discrepancy and log10_shape come with discrepancy=True"
                        if name in _DISCREPANCY
                        else ""
                    )
                    raise BayestriboError(
                        f"{which}: {name!r} is not a parameter of the law {law.name}{hint}; "
                        f"its parameters are {', '.join(known)}{extra}"
                    )

    # -- building ------------------------------------------------------------------

    @classmethod
    def of(cls, value: FitSpec | Mapping[str, Any] | None = None, **changes: Any) -> FitSpec:
        """A specification from another, a mapping of fields (:meth:`from_dict`), or
        None (the defaults), with ``changes`` (field names, or ``fit``'s keywords such
        as ``notch``) over it.

        Raises
        ------
        BayestriboError
            For a name that is not a field (naming the closest), or a bad value
            (naming the field and what was expected).
        """
        if value is None:
            base = cls()
        elif isinstance(value, FitSpec):
            base = value
        elif isinstance(value, Mapping):
            base = cls.from_dict(value)
        else:
            raise _error("spec", "a FitSpec or a mapping of its fields", type(value).__name__)
        return base.replace(**changes) if changes else base

    def replace(self, **changes: Any) -> FitSpec:
        """A copy with some fields changed (field names or ``fit``'s keywords)."""
        by_keyword = {_keyword(f): f.name for f in dataclasses.fields(self)}
        fields = {by_keyword.get(k, k): v for k, v in changes.items()}
        _refuse_unknown(fields)
        if "read_options" in fields and "restoring" not in fields:
            if _names_restoring(fields["read_options"]):
                fields["restoring"] = None  # the new reading options name it
        return dataclasses.replace(self, **fields)

    # -- plain data ----------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain data, in the fields' order (JSON-ready; the reading
        options as :meth:`~bayestribo.io.options.ReadOptions.as_kwargs`, the options
        that differ from their defaults)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, ReadOptions):
                value = value.as_kwargs()
            elif isinstance(value, Mapping):
                value = {k: dict(v) if isinstance(v, Mapping) else v for k, v in value.items()}
            out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FitSpec:
        """A specification from :meth:`to_dict`'s mapping (fields left out keep their
        defaults).

        Raises
        ------
        BayestriboError
            For a key that is not a field, or a bad value.
        """
        if not isinstance(data, Mapping):
            raise _error("spec", "a mapping of FitSpec fields", type(data).__name__)
        _refuse_unknown(data)
        return cls(**dict(data))

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON, keys in the fields' order."""
        return json.dumps(self.to_dict(), allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> FitSpec:
        """A specification from :meth:`to_json`'s text."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise BayestriboError(f"spec: not JSON ({exc})") from None
        return cls.from_dict(data)

    def changed(self) -> dict[str, Any]:
        """The fields that differ from their defaults, as in :meth:`to_dict`."""
        default = FitSpec().to_dict()
        return {k: v for k, v in self.to_dict().items() if v != default[k]}

    # -- what the fit takes ----------------------------------------------------------

    def reading(self) -> ReadOptions:
        """The reading options with the restoring force in their metadata (as
        :func:`bayestribo.read_run` takes it)."""
        if self.restoring is None:
            return self.read_options
        metadata = {**(self.read_options.metadata or {}), "restoring": self.restoring}
        return self.read_options.replace(metadata=metadata)

    def fit_kwargs(self, *, changed_only: bool = False) -> dict[str, Any]:
        """The keywords of :func:`bayestribo.fit` that give this specification (the
        restoring force inside ``read_options``); with ``changed_only``, those that
        differ from the defaults, as plain data (a notebook's ``fit_kwargs``)."""
        changed = self.changed()
        out: dict[str, Any] = {}
        for f in spec_fields():
            if f.name == "restoring":
                continue  # given inside read_options
            if f.name == "read_options":
                if changed_only and not {"read_options", "restoring"} & set(changed):
                    continue
                options = self.reading()
                out["read_options"] = options.as_kwargs() if changed_only else options
            elif not changed_only or f.name in changed:
                out[_keyword(f)] = getattr(self, f.name)
        return out

    def sampler_settings(self) -> Any:
        """The sampler's :class:`~bayestribo.inference.sampling.SamplerSettings`: the
        walkers, ensembles and ceiling given, and the fit's stopping rule (an effective
        sample size of :data:`~bayestribo.inference.sampling.FIT_MIN_ESS` and at least
        :data:`~bayestribo.inference.sampling.FIT_AUTOCORR_MULTIPLE` τ)."""
        from bayestribo.inference.sampling import (
            FIT_AUTOCORR_MULTIPLE,
            FIT_INDEPENDENCE,
            FIT_INDEPENDENCE_LIMIT,
            FIT_MAX_DRAWS,
            FIT_MIN_ESS,
            SamplerSettings,
        )

        return SamplerSettings(
            n_walkers=self.n_walkers,
            n_ensembles=self.n_ensembles,
            max_steps=self.max_steps,
            autocorr_multiple=FIT_AUTOCORR_MULTIPLE,
            min_ess=FIT_MIN_ESS,
            # the move's adaptation phase (100 steps) needs room after it
            independence=FIT_INDEPENDENCE if self.max_steps >= 300 else 0.0,
            max_draws=max(FIT_MAX_DRAWS, self.n_walkers * self.n_ensembles),
            independence_limit=FIT_INDEPENDENCE_LIMIT,
            debias=True,
        )


def spec_fields() -> tuple[dataclasses.Field, ...]:
    """The fields of :class:`FitSpec` in order, each with ``metadata`` ``doc``,
    ``option`` (:class:`SpecOption`), ``check`` and ``keyword``."""
    return dataclasses.fields(FitSpec)


def _keyword(f: dataclasses.Field) -> str:
    return f.metadata["keyword"] or f.name


def _names_restoring(options: Any) -> bool:
    metadata = getattr(options, "metadata", None)
    if metadata is None and isinstance(options, Mapping):
        metadata = options.get("metadata")
    return isinstance(metadata, Mapping) and "restoring" in metadata


def _refuse_unknown(names: Mapping[str, Any]) -> None:
    known = [f.name for f in spec_fields()]
    unknown = [n for n in names if n not in known]
    if unknown:
        parts = []
        for name in unknown:
            close = difflib.get_close_matches(str(name), known, n=1)
            parts.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise BayestriboError(
            f"spec: unknown field(s) {', '.join(parts)}; the fields are {', '.join(known)}"
        )


def _document() -> None:
    """Complete :class:`FitSpec`'s docstring from its fields (numpydoc Parameters)."""
    lines = ["", "    Parameters", "    ----------"]
    for f in spec_fields():
        default = (
            "ReadOptions()"
            if f.name == "read_options"
            else repr(f.default if f.default is not dataclasses.MISSING else f.default_factory())
        )
        lines.append(f"    {f.name} : {f.type}, default {default}")
        lines.append(f"        {f.metadata['doc']}")
    FitSpec.__doc__ = (FitSpec.__doc__ or "").rstrip() + "\n" + "\n".join(lines) + "\n"


_document()
