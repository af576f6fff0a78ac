"""``bayestribo inspect``: how a file is read and what is found in it, before any fit.

Examples::

    bayestribo inspect data/runs/glycerol-N0.31-r1.csv
    bayestribo inspect scope.csv --columns t x v --scale x=2e-4 --scale v=5e-3 --json

Exit status: 0 when the file reads and its energy decay is found, 2 when it cannot be
read or analysed (the report says which part failed and why).
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from bayestribo.cli._common import (
    CommandLineError,
    add_notch_option,
    add_run_arguments,
    cli_message,
    read_run_from_args,
    reading_options,
)

__all__ = ["inspection", "register"]


def register(subparsers: Any) -> None:
    """Add the ``inspect`` sub-command."""
    p = subparsers.add_parser(
        "inspect",
        help="how a run file is read and what is found in it, before any fit",
        description=(
            "Show how a file is read (format, instrument export, columns and units, "
            "sidecar), the samples (rate, duration, ranges), the metadata, the agreement "
            "of the displacement and velocity channels (gain, delay), and what the "
            "analysis finds: release, analysed window, end of motion, measured frequency "
            "and noise at rest. Nothing is fitted."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_run_arguments(p, optional=True)
    add_notch_option(p)
    p.add_argument(
        "--formats",
        action="store_true",
        help="list the file formats read (suffixes, options, extra to install) and exit",
    )
    p.add_argument(
        "--skip",
        type=int,
        default=1,
        help="oscillations to skip after the release, as for decay and fit",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(handler=run)


def _finite(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


def _signal(values: Any) -> dict[str, float] | None:
    if values is None:
        return None
    return {
        "min": float(values.min()),
        "max": float(values.max()),
        "peak_to_peak": float(values.max() - values.min()),
    }


def inspection(args: argparse.Namespace) -> tuple[dict[str, Any], bool]:
    """What ``inspect`` reports, as JSON-ready data, and whether the run is usable."""
    import numpy as np

    from bayestribo import __version__
    from bayestribo.cli.decay import summary
    from bayestribo.errors import BayestriboError
    from bayestribo.io.acceleration import motion_edges
    from bayestribo.io.layout import describe_file
    from bayestribo.signal.channels import channel_consistency
    from bayestribo.signal.decay import energy_decay
    from bayestribo.signal.frequency import oscillation_frequency

    try:
        layout = describe_file(args.run, reading_options(args))
    except BayestriboError as exc:
        raise CommandLineError(cli_message(str(exc))) from None
    recording = read_run_from_args(args)
    t = recording.time
    steps = np.diff(t)
    units = {"arbitrary": "arbitrary length unit", "rad": "angles: rad, rad/s"}.get(
        recording.length_unit, "SI"
    )
    report: dict[str, Any] = {
        "bayestribo_version": __version__,
        "file": str(args.run),
        "reading": {**layout, "signals": list(recording.signals), "units": units},
        "samples": {
            "n": int(t.size),
            "sample_rate_Hz": float(1.0 / np.median(steps)),
            "start_s": float(t[0]),
            "duration_s": float(t[-1] - t[0]),
        },
        "displacement": _signal(recording.displacement),
        "velocity": _signal(recording.velocity),
        "metadata": dict(recording.metadata),
    }
    consistency = channel_consistency(recording)
    report["channels"] = None if consistency is None else consistency.to_dict()
    report["oscillation_frequency_Hz"] = _finite(
        oscillation_frequency(t, recording.displacement, recording.velocity)
    )
    try:
        decay = energy_decay(
            t,
            recording.displacement,
            recording.velocity,
            rig=recording.rig(),
            skip_oscillations=args.skip,
            notch=args.notch,
            acceleration_edges=motion_edges(dict(recording.metadata)),
        )
    except BayestriboError as exc:
        report["decay"] = {"error": cli_message(str(exc))}
        return report, False
    report["decay"] = summary(decay, str(args.run))
    report["decay"]["friction_reported_as"] = (
        "mu_k"
        if decay.scaling.friction_defined
        else ("friction angle" if recording.length_unit == "rad" else "friction displacement")
    )
    # the oscillations between the release and the analysis: --skip's, and any the
    # analysis left out after them (an irregular or clipped start, said in its warning)
    decay_report = report["decay"]
    keys = ("start_time_s", "release_time_s", "natural_frequency_Hz")
    times = [decay_report.get(k) for k in keys]
    left = (times[0] - times[1]) * times[2] if None not in times else math.nan
    decay_report["skipped_oscillations"] = max(0, round(left)) if math.isfinite(left) else 0
    decay_report["skip_asked"] = int(args.skip)
    return report, True


#: The signals of a record in radians, by the names the text shows them with.
_ANGLE_NAMES = {"displacement_m": "angle_rad", "velocity_m_per_s": "angular_velocity_rad_per_s"}
#: ... and of a record in an arbitrary unit of length.
_UNITLESS_NAMES = {"displacement_m": "displacement", "velocity_m_per_s": "velocity"}


def _number(value: float | None, digits: int = 6) -> str:
    return "—" if value is None else f"{value:.{digits}g}"


def _text(report: dict[str, Any]) -> str:
    from bayestribo._stamps import stamp
    from bayestribo.cli.decay import mains_note

    reading = report["reading"]
    lines = [f"file           {report['file']}"]
    lines.append(f"read as        {reading['reader']} ({reading['format']})")
    if reading["columns"]:
        cols = ", ".join(
            f"{c['label']} [{c['unit']}]" if c["unit"] else c["label"] for c in reading["columns"]
        )
        lines.append(f"file columns   {cols}")
    signals = reading["signals"]
    if reading["units"].startswith("angles"):
        signals = [_ANGLE_NAMES.get(name, name) for name in signals]
    elif reading["units"] != "SI":  # no unit of length: the quantities by name alone
        signals = [_UNITLESS_NAMES.get(name, name) for name in signals]
    lines.append(f"signals        {', '.join(signals)} ({reading['units']})")
    lines.append(f"sidecar        {reading['sidecar'] or 'none'}")
    s = report["samples"]
    lines.append(
        f"samples        {s['n']} at {_number(s['sample_rate_Hz'])} Hz, "
        f"{_number(s['duration_s'])} s from t = {stamp(s['start_s'], s['duration_s'])}"
    )
    start, duration = s["start_s"], s["duration_s"]
    si = reading["units"] == "SI"
    angles = reading["units"].startswith("angles")
    for name, unit in (("displacement", "m"), ("velocity", "m/s")):
        sig = report[name]
        if sig is not None:
            unit = unit if si else unit.replace("m", "rad" if angles else "length unit")
            label = {"displacement": "angle", "velocity": "ang. velocity"}[name] if angles else name
            lines.append(
                f"{label:14s} {_number(sig['min'])} to {_number(sig['max'])} {unit} "
                f"(peak to peak {_number(sig['peak_to_peak'])})"
            )
    meta = ", ".join(
        f"{k} {v}" for k, v in report["metadata"].items() if not isinstance(v, dict | list)
    )
    lines.append(f"metadata       {meta or 'none'}")
    high_pass = report["metadata"].get("high_pass_undone")
    if high_pass:
        from bayestribo.io.high_pass import describe as describe_high_pass

        lines.append(f"sensor         {describe_high_pass(high_pass)}")
    ch = report["channels"]
    if ch is not None:
        gain = ch["gain"]
        gain_se = None if ch["gain_se"] is None or not gain else ch["gain_se"] / gain**2
        delay_se = None if ch["delay_se_s"] is None else 1e6 * ch["delay_se_s"]
        delay = None if ch["delay_s"] is None else 1e6 * ch["delay_s"]
        lines.append(
            f"channels       velocity reads {_number(ch['velocity_gain'], 6)} "
            f"(± {_number(gain_se, 2)}) × dx/dt, displacement delayed "
            f"{_number(delay, 3)} µs (± {_number(delay_se, 2)}), correlation "
            f"{_number(ch['correlation'], 7)}"
        )
    lines.append(
        f"oscillation    {_number(report['oscillation_frequency_Hz'])} Hz (zero crossings)"
    )
    decay = report["decay"]
    if "error" in decay:
        lines.append(f"analysis       not possible: {decay['error']}")
        return "\n".join(lines)
    lines.append(f"release        t = {stamp(decay['release_time_s'], duration, start)}")
    ended = (
        "motion ended" if decay["motion_ended"] else "the record ends while the oscillator moves"
    )
    skipped, asked = decay.get("skipped_oscillations", 0), decay.get("skip_asked", 0)
    if skipped:
        ended += f"; {skipped} oscillation{'s' if skipped > 1 else ''} after the release left out"
        if asked and skipped <= asked:
            them = "them" if skipped > 1 else "it"
            ended += f", the release's transient (--skip 0 keeps {them})"
        elif asked:
            ended += f" ({asked} by --skip, the others by the analysis, as its warning says)"
        else:
            ended += " by the analysis, as its warning says"
    lines.append(
        f"analysed       {stamp(decay['start_time_s'], duration, start)} to "
        f"{stamp(decay['end_time_s'], duration, start)} ({ended})"
    )
    nominal = decay["nominal_frequency_Hz"]
    extra = "" if nominal is None else f" (nominal {_number(nominal, 5)} Hz)"
    lines.append(f"frequency      {_number(decay['natural_frequency_Hz'])} Hz measured{extra}")
    noise = decay["noise"]
    where = (
        f"{noise['source']}, {noise['n_samples']} samples"
        if noise["n_samples"]
        else f"measured in {noise['source']}: no rest in the record"
    )
    lines.append(
        f"{'noise at rest' if noise['n_samples'] else 'noise':14s} "
        f"{'angle' if reading['units'].startswith('angles') else 'displacement'} "
        f"{_number(noise['displacement'], 3)}, velocity {_number(noise['velocity'], 3)} ({where})"
    )
    if decay["derived_channel"]:
        lines.append(f"derived        {decay['derived_channel']} (from the other channel)")
    lines.append(f"friction as    {decay['friction_reported_as']}")
    note = mains_note(decay)
    if note is not None:
        lines.append(f"mains          {note}")
    return "\n".join(lines)


def formats_table() -> tuple[str, list[dict[str, Any]]]:
    """The registered file formats, as text and as JSON-ready rows."""
    import importlib.util

    from bayestribo._optional import EXTRAS
    from bayestribo.io.registry import registered_formats

    rows = []
    for fmt in registered_formats().values():
        needs = [m for m, extra in EXTRAS.items() if extra == fmt.extra] if fmt.extra else []
        missing = [m for m in needs if importlib.util.find_spec(m) is None]
        rows.append(
            {
                "name": fmt.name,
                "title": fmt.title,
                "suffixes": list(fmt.suffixes),
                "options": list(fmt.options),
                "extra": fmt.extra,
                "installed": not missing,
            }
        )
    table = [
        (
            r["name"],
            " ".join(r["suffixes"]),
            ", ".join(r["options"]) or "-",
            "yes" if r["installed"] else f"no: pip install 'bayestribo[{r['extra']}]'",
            r["title"],
        )
        for r in rows
    ]
    head = ("format", "suffixes", "options", "installed", "what")
    widths = [max(len(row[i]) for row in [head, *table]) for i in range(4)]
    lines = [
        "  ".join(f"{cell:{w}s}" for cell, w in zip(row[:4], widths, strict=True)) + "  " + row[4]
        for row in [head, *table]
    ]
    lines.append("every format also takes --scale, the sidecar and the metadata options")
    return "\n".join(lines), rows


def run(args: argparse.Namespace) -> int:
    """Inspect the file; exit 2 when the decay cannot be analysed."""
    if args.formats:
        text, rows = formats_table()
        print(json.dumps(rows, indent=2) if args.json else text)
        return 0
    if args.run is None:
        raise CommandLineError("inspect: give a RUN file to inspect, or --formats")
    report, usable = inspection(args)
    if args.json:
        print(json.dumps(report, indent=2, allow_nan=False, default=str))
    else:
        print(_text(report))
    return 0 if usable else 2
