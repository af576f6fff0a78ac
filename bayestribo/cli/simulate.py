"""``bayestribo simulate``: write a simulated run, or the whole bundled campaign.

Examples::

    bayestribo simulate run.csv --load 0.31 --zeta 0.0236 --mu-k 0.0294 --seed 1
    bayestribo simulate run.csv --law viscous+quadratic --param zeta=0.01 --param c2=0.005 \
        --motion-duration 3 --seed 1
    bayestribo simulate --campaign data/      # regenerates the bundled campaign

Without ``--law`` the law is viscous damping and Coulomb friction (``--zeta``,
``--mu-k``, ``--mu-s``) on the exact solution. With ``--law NAME`` it is any law of the
registry (``bayestribo laws``: its parameters, in the registry's dimensionless units,
are given as ``--param NAME=VALUE``), and the motion is integrated by ``solve_ivp``
(:mod:`bayestribo.synthetic.motion`), independently of the fit's integrator.
"""

from __future__ import annotations

import argparse
from typing import Any

from bayestribo._plural import count
from bayestribo.errors import BayestriboError

__all__ = ["register"]


class SimulationArgumentError(BayestriboError, ValueError):
    """A simulation argument is out of range (reported by the command line)."""


def register(subparsers: Any) -> None:
    """Add the ``simulate`` sub-command."""
    p = subparsers.add_parser(
        "simulate",
        help="simulate a free-decay run (canonical CSV + JSON), or the bundled campaign",
        description=(
            "Simulate one recording of the dynamic tribometer on the exact model (rest, "
            "magnet release, decay with viscous damping and Coulomb friction, rest tail, "
            "sensor noise) and write it in the canonical format; with --law, of any "
            "registered dissipation law, its motion integrated by solve_ivp (not the fit's "
            "integrator); or, with --campaign, regenerate the whole synthetic campaign "
            "(runs and manifest.csv) with a fixed seed."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("output", nargs="?", metavar="OUT.csv", help="run file to write")
    p.add_argument("--campaign", metavar="DIR", help="write the whole campaign into DIR")
    p.add_argument("--seed", type=int, help="noise seed (campaign: campaign seed)")
    p.add_argument("--load", type=float, default=0.31, help="normal load N [N] (0: no contact)")
    p.add_argument(
        "--law",
        metavar="NAME",
        help="any registered law, terms joined with '+' ('bayestribo laws' lists them), its "
        "motion by solve_ivp; default: --zeta, --mu-k, --mu-s on the exact solution",
    )
    p.add_argument(
        "--param",
        action="append",
        metavar="NAME=VALUE",
        help="a parameter of --law in the registry's units ('bayestribo laws'), repeated; "
        "one not given takes its typical value where it has one",
    )
    p.add_argument("--zeta", type=float, help="viscous damping ζ [-] (default 0.0236)")
    p.add_argument("--mu-k", type=float, help="kinetic friction μ_k [-] (default 0.0294, 0 in air)")
    p.add_argument("--mu-s", type=float, help="static friction μ_s [-] (default μ_k)")
    p.add_argument("--mass", type=float, default=0.035, help="mass m [kg]")
    p.add_argument("--frequency", type=float, default=32.6, help="natural frequency f [Hz]")
    p.add_argument("--x0", type=float, default=1.5e-3, help="initial displacement [m]")
    p.add_argument("--sample-rate", type=float, default=10_000.0, help="sample rate [Hz]")
    p.add_argument("--rest-before", type=float, default=0.05, help="rest before release [s]")
    p.add_argument("--rest-after", type=float, default=0.1, help="rest after the stop [s]")
    p.add_argument(
        "--motion-duration", type=float, help="time recorded after release [s] (default: stop)"
    )
    p.add_argument("--magnet-fade", type=float, help="magnet fade time [s] (default T/4)")
    p.add_argument("--offset", type=float, default=0.0, help="displacement offset [m]")
    p.add_argument("--time-origin", type=float, default=0.0, help="first time stamp [s]")
    p.add_argument("--displacement-noise", type=float, help="noise σ [m] (default resolution)")
    p.add_argument("--velocity-noise", type=float, help="noise σ [m/s] (default resolution)")
    p.add_argument("--quantise", action="store_true", help="round to the sensor resolution")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Simulate and write; print what was written."""
    if (args.campaign is None) == (args.output is None):
        raise SimulationArgumentError("give either OUT.csv or --campaign DIR (one of the two)")
    if args.campaign is not None:
        from bayestribo.synthetic.campaign import CAMPAIGN_SEED, campaign_plan, write_campaign

        seed = CAMPAIGN_SEED if args.seed is None else args.seed
        manifest = write_campaign(args.campaign, seed=seed)
        runs = count(len(campaign_plan(seed)), "run")
        print(f"wrote {runs} and {manifest} (campaign seed {seed})")
        return 0

    from bayestribo.io import write_run
    from bayestribo.model.scaling import Rig
    from bayestribo.synthetic import Release, Sensor
    from bayestribo.synthetic.recording import simulate

    law = _law(args)
    try:
        sim = simulate(
            law,
            rig=Rig(natural_frequency_Hz=args.frequency, mass_kg=args.mass, load_N=args.load),
            release=Release(
                initial_displacement_m=args.x0,
                rest_before_s=args.rest_before,
                motion_duration_s=args.motion_duration,
                rest_after_s=args.rest_after,
                magnet_fade_s=args.magnet_fade,
                offset_m=args.offset,
                time_origin_s=args.time_origin,
            ),
            sensor=Sensor(
                sample_rate_Hz=args.sample_rate,
                displacement_noise_m=args.displacement_noise,
                velocity_noise_m_per_s=args.velocity_noise,
                quantise=args.quantise,
            ),
            seed=args.seed,
        )
    except ValueError as exc:
        if isinstance(exc, BayestriboError):
            raise
        raise SimulationArgumentError(str(exc)) from None
    path = write_run(sim, args.output)
    truth = sim.metadata["simulation"]
    motion = truth["motion_duration_s"]
    if "law" not in truth:
        print(f"wrote {path} ({sim.n_samples} samples, {motion:.3f} s of motion)")
        return 0
    values = ", ".join(
        f"{name} = {p['value']:g} [{p['unit']}]" for name, p in truth["parameters"].items()
    )
    print(
        f"wrote {path} ({sim.n_samples} samples, {motion:.3f} s of motion): law "
        f"{truth['law']}, {values}; motion by solve_ivp (not the fit's integrator)"
    )
    return 0


def _law(args: argparse.Namespace) -> Any:
    """The law to simulate: ``--zeta/--mu-k/--mu-s`` without ``--law``, else the
    registered law with its ``--param`` values (a SimulationArgumentError naming the
    argument otherwise)."""
    from bayestribo.synthetic import DissipationLaw, LawParameters

    if args.law is None:
        if args.param:
            raise SimulationArgumentError(
                f"--param {args.param[0]}: a parameter of a law; give the law with --law NAME"
            )
        zeta = 0.0236 if args.zeta is None else args.zeta
        try:
            return DissipationLaw(zeta=zeta, mu_k=args.mu_k, mu_s=args.mu_s)
        except ValueError as exc:
            raise SimulationArgumentError(str(exc)) from None
    given = [
        flag
        for flag, v in (("--zeta", args.zeta), ("--mu-k", args.mu_k), ("--mu-s", args.mu_s))
        if v is not None
    ]
    if given:
        raise SimulationArgumentError(
            f"{given[0]} sets the default law's parameter; with --law give the law's own as "
            "--param NAME=VALUE (e.g. --param zeta=0.01; 'bayestribo laws' lists them)"
        )
    from bayestribo.model.laws import get_law

    if args.law.strip().lower() == "auto":
        raise SimulationArgumentError(
            "--law auto: a simulation needs one law; expected registered terms joined with "
            "'+' ('bayestribo laws' lists them)"
        )
    try:
        law = get_law(args.law)
    except ValueError as exc:
        raise SimulationArgumentError(f"--law {args.law}: {exc}") from None
    values: dict[str, float] = {}
    for item in args.param or []:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise SimulationArgumentError(f"--param {item!r}: expected NAME=VALUE, e.g. zeta=0.01")
        try:
            value = float(text)
        except ValueError:
            raise SimulationArgumentError(
                f"--param {item}: expected a number after '=', got {text.strip()!r}"
            ) from None
        if name in values:
            raise SimulationArgumentError(f"--param {name} is given twice")
        values[name] = value
    try:
        return LawParameters(law, values)
    except ValueError as exc:
        raise SimulationArgumentError(f"--param: {exc}") from None
