"""``bayestribo decay``: the energy decay curve Π(τ) of one run.

Examples::

    bayestribo decay data/runs/glycerol-N0.31-r1.csv
    bayestribo decay HarmOsc3.txt --columns t x --length-unit arbitrary --json
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from bayestribo.cli._common import (
    CommandLineError,
    add_notch_option,
    add_run_arguments,
    cli_message,
    read_run_from_args,
)

__all__ = ["register"]


def register(subparsers: Any) -> None:
    """Add the ``decay`` sub-command."""
    p = subparsers.add_parser(
        "decay",
        help="energy decay E(τ) and its retrograde integral Π(τ) of a run",
        description=(
            "Detect the release, skip the first oscillation, estimate the equilibrium, "
            "find the end of motion, measure the noise at rest and the natural frequency, "
            "and print a summary of E(τ) and Π(τ) (Rigaud et al. 2010, Eq. 26, 39)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_run_arguments(p)
    add_notch_option(p)
    p.add_argument("--skip", type=int, default=1, help="oscillations to skip after the release")
    p.add_argument("--points", type=int, default=12, help="rows of Π(τ) to print")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(handler=run)


def summary(decay: Any, run_name: str) -> dict[str, Any]:
    """A JSON-ready summary of an :class:`~bayestribo.signal.decay.EnergyDecay`."""
    return {
        "run": run_name,
        "start_time_s": decay.start_time,
        "end_time_s": decay.end_time,
        "motion_ended": decay.motion_ended,
        "release_time_s": decay.release_time,
        "tau_end": decay.tau_end,
        "y0": decay.y0,
        "pi0": float(decay.pi[0]),
        "length_scale": decay.scaling.length_scale,
        "friction_defined": decay.scaling.friction_defined,
        "equilibrium": decay.equilibrium,
        "natural_frequency_Hz": decay.natural_frequency_Hz,
        "nominal_frequency_Hz": decay.nominal_frequency_Hz,
        "frequency_difference_Hz": decay.frequency_difference_Hz,
        "noise": {
            "displacement": decay.noise.displacement,
            "velocity": decay.noise.velocity,
            "source": decay.noise.source,
            "n_samples": decay.noise.n_samples,
        },
        "derived_channel": decay.derived_channel,
        "n_samples": int(decay.tau.size),
        "notch_Hz": list(decay.notch_Hz),
        "mains_lines_Hz": [] if decay.rest_noise is None else list(decay.rest_noise.lines_Hz),
        "noise_coloured": None if decay.rest_noise is None else bool(decay.rest_noise.coloured),
    }


def mains_note(info: dict[str, Any]) -> str | None:
    """One line on a mains line: removed, or found at rest with the option to remove it."""
    if info["notch_Hz"]:
        lines = ", ".join(f"{f:.2f}" for f in info["notch_Hz"])
        return f"mains line at {lines} Hz measured at rest and subtracted from both channels"
    if info["mains_lines_Hz"]:
        lines = ", ".join(f"{f:.2f}" for f in info["mains_lines_Hz"])
        return f"a mains line at {lines} Hz is in the rest noise; --notch auto subtracts it"
    return None


def run(args: argparse.Namespace) -> int:
    """Read the run, compute its energy decay, print it; exit status 1 when the
    analysis covers less than half of the recorded motion (a ShortAnalysisWarning, said
    on standard error), as ``bayestribo fit`` does."""
    import warnings

    import numpy as np

    from bayestribo.errors import BayestriboError, ShortAnalysisWarning
    from bayestribo.inference.preparation import run_restoring, with_restoring
    from bayestribo.io.acceleration import motion_edges
    from bayestribo.model.restoring import AUTO
    from bayestribo.signal.decay import energy_decay

    recording = read_run_from_args(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(
            recording.time,
            recording.displacement,
            recording.velocity,
            rig=recording.rig(),
            skip_oscillations=args.skip,
            notch=args.notch,
            acceleration_edges=motion_edges(dict(recording.metadata)),
        )
        # E(τ) and Π(τ) with the restoring force's potential, as fit takes them
        # (E = ½y'² + V(y)); "auto" is chosen by fit, from the half periods
        restoring_name = dict(recording.metadata).get("restoring")
        force = None
        if restoring_name not in (None, AUTO):
            try:
                force = run_restoring(recording, decay)
            except BayestriboError as exc:
                raise CommandLineError(cli_message(str(exc))) from None
            decay = with_restoring(decay, force)
    for w in caught:
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    status = int(any(issubclass(w.category, ShortAnalysisWarning) for w in caught))
    info = summary(decay, args.run)
    info["energy"] = (
        "½y'² + V(y), the potential of the " + force.name
        if force is not None
        else "(y² + y'²)/2, the linear spring's"
        + ("; --restoring auto is chosen by fit" if restoring_name == AUTO else "")
    )
    rows = np.linspace(0, decay.tau.size - 1, max(args.points, 2)).astype(int)
    if args.json:
        info["tau"] = decay.tau[rows].tolist()
        info["pi"] = decay.pi[rows].tolist()
        print(json.dumps(info, indent=2))
        return status
    unit = "μ_k (y = kx/N)" if decay.scaling.friction_defined else "friction displacement"
    if not decay.scaling.friction_defined and recording.length_unit == "rad":
        unit = "friction angle"
    print(f"run            {args.run}")
    print(
        f"analysed       {decay.start_time:.6g} s to {decay.end_time:.6g} s "
        f"({'motion ended' if decay.motion_ended else 'record ends first'})"
    )
    nominal = decay.nominal_frequency_Hz
    diff = (
        ""
        if nominal is None
        else f" (nominal {nominal:.4g} Hz, {decay.frequency_difference_Hz:+.3g} Hz)"
    )
    print(f"frequency      {decay.natural_frequency_Hz:.6g} Hz measured{diff}")
    print(
        f"noise          displacement {decay.noise.displacement}, velocity "
        f"{decay.noise.velocity} ({decay.noise.source})"
    )
    print(f"friction unit  {unit}; length scale {decay.scaling.length_scale:.6g}")
    note = mains_note(info)
    if note is not None:
        print(f"mains          {note}")
    print(f"energy         E = {info['energy']}")
    print(f"y0             {decay.y0:.6g}")
    print(f"{'τ':>12} {'E(τ)':>14} {'Π(τ)':>14}")
    for i in rows:
        print(f"{decay.tau[i]:12.4f} {decay.energy[i]:14.6g} {decay.pi[i]:14.6g}")
    return status
