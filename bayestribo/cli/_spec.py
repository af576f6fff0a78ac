"""The fit specification's command-line options, generated from its fields once.

:func:`add_spec_options` adds an option per field of
:class:`~bayestribo.inference.spec.FitSpec` (its :class:`~bayestribo.inference.spec.
SpecOption`), and ``--spec FILE`` (a specification as JSON, ``FitSpec.to_json``), to
a sub-command's parser; :func:`spec_from_args` builds the specification from the
parsed arguments: the file's, then the options given over it. ``fit``, ``campaign``,
``report`` and ``check`` all take every option; a command refuses, naming it, an
option it cannot use. Building the options imports no numpy (``--help`` stays light).
"""

from __future__ import annotations

import argparse
import json
import math
import re
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any

from bayestribo.cli._common import CommandLineError, notch_value, reading_options
from bayestribo.inference.spec import PRIOR_TYPES, FitSpec, SpecOption, spec_fields

__all__ = ["SPEC_FLAGS", "add_spec_options", "given_options", "spec_from_args"]

#: Where the parsed arguments keep the destinations of the options given.
_GIVEN = "_spec_given"


def _law(text: str) -> str:
    from bayestribo.cli.laws import law_name

    return law_name(text)


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


#: Parsers of one option value by the name a field's :class:`SpecOption` gives.
_PARSERS: dict[str, Callable[[str], Any]] = {"law": _law, "int": _int, "notch": notch_value}


class _Given(argparse.Action):
    """Store (or append) a value and remember that the option was given."""

    def __init__(self, *args: Any, const_value: Any = None, append: bool = False, **kw: Any):
        self.const_value, self.append = const_value, append
        super().__init__(*args, **kw)

    def __call__(self, parser: Any, namespace: Any, values: Any, option: Any = None) -> None:
        value = self.const_value if self.nargs == 0 else values
        if self.append:
            value = [*(getattr(namespace, self.dest, None) or []), value]
        setattr(namespace, self.dest, value)
        given = set(getattr(namespace, _GIVEN, set()))
        setattr(namespace, _GIVEN, given | {self.dest})


def _options() -> list[tuple[Any, SpecOption]]:
    return [(f, f.metadata["option"]) for f in spec_fields()]


#: Every option of the specification (the reading options' are added by
#: :func:`bayestribo.cli._common.add_reading_options`), and ``--spec``.
SPEC_FLAGS: tuple[str, ...] = ("--spec", *(option.flag for _, option in _options()))


def add_spec_options(
    parser: argparse.ArgumentParser,
    *,
    helps: Mapping[str, str] | None = None,
    defaults: Mapping[str, Any] | None = None,
) -> None:
    """Add ``--spec FILE`` and an option per field of
    :class:`~bayestribo.inference.spec.FitSpec` (the reading options excepted: the
    command adds them with :func:`~bayestribo.cli._common.add_reading_options`).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser.
    helps : mapping, optional
        Another help text by field name (a campaign's seed is the campaign's).
    defaults : mapping, optional
        Another parsed default by field name (``report``'s seed: None, the notebook's).
    """
    from bayestribo.cli.laws import LAW_HELP

    helps, defaults = dict(helps or {}), dict(defaults or {})
    parser.add_argument(
        "--spec",
        type=Path,
        metavar="FILE",
        action=_Given,
        help="the fit's specification as JSON (FitSpec.to_json, a result's spec); the "
        "options given here replace its fields",
    )
    for f, option in _options():
        if option.kind == "reading":
            continue
        text = helps.get(f.name) or option.help or (LAW_HELP if f.name == "law" else "")
        if option.kind in ("flag", "off"):
            parser.add_argument(
                option.flag,
                dest=option.dest,
                action=_Given,
                nargs=0,
                const_value=True,
                default=False,
                help=text,
            )
            continue
        if option.kind == "pairs":
            parser.add_argument(
                option.flag,
                dest=option.dest,
                action=_Given,
                append=True,
                metavar=option.metavar,
                default=None,
                help=text,
            )
            continue
        parser.add_argument(
            option.flag,
            dest=option.dest,
            action=_Given,
            type=_PARSERS[option.parse] if option.parse else None,
            choices=option.choices,
            metavar=option.metavar,
            default=defaults.get(f.name, f.default),
            help=text,
        )


def given_options(args: argparse.Namespace) -> list[str]:
    """The specification's options given on the command line (``--law``, ...), the
    reading options given counted as ``--columns`` and the like by their own flags."""
    given = getattr(args, _GIVEN, set())
    flags = [flag for flag in SPEC_FLAGS if flag.lstrip("-").replace("-", "_") in given]
    reading = reading_options(args).as_kwargs() if hasattr(args, "columns") else {}
    if reading:
        flags.append("reading options (" + ", ".join(sorted(_reading_flags(reading))) + ")")
    return flags


def _reading_flags(reading: Mapping[str, Any]) -> list[str]:
    names = {"file_format": "format", "sample_rate_Hz": "sample-rate", "channels": "channel"}
    flags = [f"--{names.get(k, k).replace('_', '-')}" for k in reading if k != "metadata"]
    metadata = {
        "length_unit": "--length-unit",
        "natural_frequency_Hz": "--frequency",
        "load_N": "--load",
        "mass_kg": "--mass",
        "restoring": "--restoring",
        "pendulum_radius_m": "--pendulum-radius",
        "sensor_high_pass": "--sensor-high-pass",
    }
    flags += [metadata.get(k, k) for k in reading.get("metadata") or {}]
    return flags


def _prior_value(item: str) -> tuple[str, dict[str, Any]]:
    """``NAME=Type(a,b)`` or ``NAME={json}`` as a name and a plain-data prior."""
    name, sep, text = item.partition("=")
    text = text.strip()
    match = re.fullmatch(r"(\w+)\(\s*([^,()]+?)\s*,\s*([^,()]+?)\s*\)", text)
    if sep and name and match and match[1] in PRIOR_TYPES:
        keys = PRIOR_TYPES[match[1]]
        return name.strip(), {"type": match[1], keys[0]: match[2], keys[1]: match[3]}
    if sep and name and text.startswith("{"):
        try:
            return name.strip(), json.loads(text)
        except json.JSONDecodeError:
            pass
    kinds = ", ".join(f"{k}({','.join(v).upper()})" for k, v in PRIOR_TYPES.items())
    raise CommandLineError(f"--prior: expected NAME=PRIOR with PRIOR one of {kinds}, got {item!r}")


def _fixed_value(item: str) -> tuple[str, float]:
    name, sep, text = item.partition("=")
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not sep or not name.strip() or not math.isfinite(value):
        raise CommandLineError(f"--fix: expected NAME=VALUE (e.g. zeta=0), got {item!r}")
    return name.strip(), value


def _pairs(option: SpecOption, items: list[str]) -> dict[str, Any]:
    parse = _prior_value if option.parse == "prior" else _fixed_value
    out: dict[str, Any] = {}
    for item in items:
        name, value = parse(item)
        if name in out:
            raise CommandLineError(f"{option.flag}: {name} given twice")
        out[name] = value
    return out


def spec_from_args(
    args: argparse.Namespace,
    command: str,
    *,
    uses: Collection[str] | None = None,
    why: str = "",
) -> FitSpec:
    """The :class:`~bayestribo.inference.spec.FitSpec` of the parsed options:
    ``--spec FILE``'s, the options given over it.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed by a parser with :func:`add_spec_options` and the reading options.
    command : str
        The sub-command, for the messages.
    uses : collection of str, optional
        The fields the command can use (default: every one); an option of another one
        given is refused.
    why : str
        Why the command cannot use the others (said with the refusal).

    Raises
    ------
    CommandLineError
        For an option the command cannot use, a file that is not a specification, or
        a value the specification refuses, naming the option.
    """
    given = getattr(args, _GIVEN, set())
    base = FitSpec()
    if "spec" in given:
        try:
            base = FitSpec.from_json(Path(args.spec).read_text(encoding="utf-8"))
        except OSError as exc:
            raise CommandLineError(f"--spec: cannot read {args.spec}: {exc}") from None
        except CommandLineError:
            raise
        except Exception as exc:
            raise CommandLineError(f"--spec {args.spec}: {exc}") from None
    changes: dict[str, Any] = {}
    flags: dict[str, str] = {}
    for f, option in _options():
        flags[f.name] = option.flag
        if option.kind == "reading" or option.dest not in given:
            continue
        value = getattr(args, option.dest)
        if option.kind == "off":
            value = not value
        elif option.kind == "pairs":
            value = _pairs(option, value)
        changes[f.name] = value
    given_fields: dict[str, list[str]] = {name: [flags[name]] for name in changes}
    if "spec" in given:
        for name in base.changed():
            given_fields.setdefault(name, []).append(f"--spec ({name})")
    reading = reading_options(args)
    given_reading = reading.as_kwargs()
    if given_reading:
        metadata = {**(base.read_options.metadata or {}), **(reading.metadata or {})}
        if base.restoring is not None and "restoring" not in metadata:
            metadata["restoring"] = base.restoring
        options = base.read_options.replace(**{**given_reading, "metadata": metadata or None})
        changes["read_options"] = options
        changes.setdefault("restoring", None)  # the reading options' metadata say it
        for flag in _reading_flags(given_reading):
            name = "restoring" if flag == "--restoring" else "read_options"
            given_fields.setdefault(name, []).append(flag)
    if uses is not None:
        refused = [flag for name, fl in given_fields.items() if name not in uses for flag in fl]
        if refused:
            listing = ", ".join(dict.fromkeys(refused))
            raise CommandLineError(
                f"{listing}: not used by bayestribo {command}" + (f" ({why})" if why else "")
            )
    try:
        return base.replace(**changes)
    except CommandLineError:
        raise
    except Exception as exc:
        raise CommandLineError(_as_option(str(exc), flags)) from None


def _as_option(message: str, flags: Mapping[str, str]) -> str:
    """A specification's error with its field named as the option that gives it."""
    name = re.match(r"(\w+)", message)
    if name and name[1] in flags and flags[name[1]] != "--columns":
        return f"{flags[name[1]]} ({name[1]}){message[len(name[1]) :]}"
    return message
