"""``bayestribo acquire``: log a run from the acquisition board, losing nothing.

Examples::

    bayestribo acquire --port /dev/ttyACM0 --load 0.31 --lubricant glycerol --repeat 2 \\
        --out runs/
    bayestribo acquire --simulate --drop 5 --load 0.31 --lubricant glycerol --out runs/
    bayestribo acquire --recover runs/20261122T061500Z_glycerol_N0.31_r2.raw
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from bayestribo.errors import AcquisitionError

__all__ = ["register"]

_EXIT_INCOMPLETE = 1
#: The disk could not take the run (raw log or run files); the raw log is kept.
_EXIT_STORAGE = 3
_EXIT_INTERRUPTED = 130


def _stall(text: str) -> tuple[int, float]:
    frame, sep, seconds = text.partition(":")
    try:
        if not sep:
            raise ValueError
        return int(frame), float(seconds)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected FRAME:SECONDS (e.g. 10:3.0), got {text!r}"
        ) from None


def register(subparsers: Any) -> None:
    """Add the ``acquire`` sub-command."""
    p = subparsers.add_parser(
        "acquire",
        help="log a run from the acquisition board (or a simulated one)",
        description=(
            "Drive the acquisition board over a serial port (any pyserial URL), append "
            "every byte received to a raw log, and write the run in the canonical format "
            "(CSV + JSON sidecar) with the operator's inputs and the device header. Faults "
            "keep everything received: the run is written incomplete with its gaps listed."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--port", help="device path or URL (socket://host:port, loop://)")
    src.add_argument(
        "--simulate",
        action="store_true",
        help="run the whole chain with the simulated instrument on a pseudo-terminal",
    )
    src.add_argument("--recover", metavar="RAWLOG", help="rebuild the run of a raw log")

    op = p.add_argument_group("operator inputs")
    op.add_argument("--load", type=float, help="normal load N [N]")
    op.add_argument("--lubricant", help="lubricant name")
    op.add_argument("--repeat", type=int, default=1, help="repeat number")
    op.add_argument("--water-fraction", type=float, help="water mass fraction [0-1]")
    op.add_argument("--temperature", type=float, help="temperature [°C]")
    op.add_argument("--notes", default="", help="free text")
    op.add_argument("--mass", type=float, help="oscillating mass m [kg]")
    op.add_argument("--frequency", type=float, help="natural frequency f [Hz]")

    io = p.add_argument_group("output")
    io.add_argument(
        "--out",
        help="directory of the run files [default: runs, or the raw log's directory]",
    )
    io.add_argument(
        "--run-id",
        help="run id and file stem [default: UTC time, lubricant, load and repeat]; "
        "refused if a run of that id exists",
    )
    io.add_argument("--catalog", help="results catalog (SQLite) [default: OUT/catalog.sqlite]")
    io.add_argument("--no-catalog", action="store_true", help="do not register the run")
    io.add_argument("--overwrite", action="store_true", help="with --recover: replace files")
    io.add_argument("--quiet", action="store_true", help="no progress display")

    dev = p.add_argument_group("device")
    dev.add_argument("--baudrate", type=int, default=921_600, help="baud rate [bit/s]")
    dev.add_argument("--timeout", type=float, default=2.0, help="longest silence [s]")
    dev.add_argument("--pretrigger", type=float, default=0.05, help="stream before FIRE [s]")
    dev.add_argument("--rate", type=float, help="set the sample rate [Hz] (RATE)")
    dev.add_argument("--samples-per-frame", type=int, help="set samples per frame (SPF)")
    dev.add_argument("--duration", type=float, help="set the recording time after release [s]")

    sim = p.add_argument_group("simulation (--simulate)")
    sim.add_argument("--sim-zeta", type=float, default=0.0236, help="damping ratio ζ")
    sim.add_argument("--sim-mu-k", type=float, default=0.0294, help="kinetic friction μ_k")
    sim.add_argument("--sim-mu-s", type=float, help="static friction μ_s [default: μ_k]")
    sim.add_argument("--sim-x0", type=float, default=5e-4, help="displacement at release [m]")
    sim.add_argument("--sim-noise", type=float, default=0.0, help="noise [counts]")
    sim.add_argument("--sim-seed", type=int, default=0, help="seed of noise and garbage")
    sim.add_argument("--sim-socket", action="store_true", help="serve on a localhost socket")
    sim.add_argument("--drop", type=int, nargs="+", default=[], metavar="N", help="drop frames")
    sim.add_argument(
        "--corrupt",
        type=int,
        nargs="+",
        default=[],
        metavar="N",
        help="flip a payload byte of these frames (checksum fails)",
    )
    sim.add_argument(
        "--garbage",
        type=int,
        nargs="+",
        default=[],
        metavar="N",
        help="send random bytes before these frames",
    )
    sim.add_argument(
        "--stall",
        type=_stall,
        nargs="+",
        default=[],
        metavar="N:S",
        help="pause S seconds before frame N",
    )
    sim.add_argument("--disconnect-after", type=int, metavar="N", help="disconnect after frame N")
    sim.add_argument(
        "--bad-header", action="store_true", help="send a run header that does not parse"
    )
    sim.add_argument("--silent", action="store_true", help="simulated device never answers")
    p.set_defaults(handler=run)


def _inputs(args: argparse.Namespace, *, simulate: bool) -> Any:
    from bayestribo.acquisition.logger import OperatorInputs

    missing = [f"--{n}" for n in ("load", "lubricant") if getattr(args, n) is None]
    if missing:
        raise AcquisitionError(f"acquire: {' and '.join(missing)} required")
    mass, freq = args.mass, args.frequency
    if simulate:
        mass = 0.035 if mass is None else mass
        freq = 32.6 if freq is None else freq
    return OperatorInputs(
        load_N=args.load,
        lubricant=args.lubricant,
        repeat=args.repeat,
        water_mass_fraction=args.water_fraction,
        temperature_C=args.temperature,
        notes=args.notes,
        mass_kg=mass,
        natural_frequency_Hz=freq,
    )


def _progress(info: Any) -> None:
    seconds = info.samples / info.sample_rate_Hz
    sys.stderr.write(
        f"\r  {info.samples:9d} samples ({seconds:6.2f} s of signal), {info.frames:6d} frames, "
        f"{info.bytes_received / 1024:8.1f} KiB, {info.discarded_bytes} bytes discarded"
    )
    sys.stderr.flush()


def _report(result: Any) -> int:
    meta = result.metadata
    print(f"run {result.run_id}: {meta['acquisition']['samples_received']} samples")
    print(f"  run file   {result.files.csv}")
    print(f"  sidecar    {result.files.json}")
    print(f"  raw log    {result.files.raw}")
    if result.catalog_id is not None:
        print(f"  catalog id {result.catalog_id}")
    if result.complete:
        print("  complete: every frame and sample received")
        return 0
    conflicting = meta["acquisition"].get("conflicting_frames", 0)
    reason = result.fault or (
        f"{conflicting} frame(s) repeated with different content (see 'anomalies')"
        if conflicting and not meta["gaps"]
        else "frames or samples missing"
    )
    print(f"  INCOMPLETE: {reason}", file=sys.stderr)
    for gap in meta["gaps"]:
        print(
            f"  gap: samples {gap['start_sample']}..{gap['stop_sample'] - 1} "
            f"({gap['n_samples']} samples at t = {gap['start_time_s']:.6g} s)",
            file=sys.stderr,
        )
    return _EXIT_INTERRUPTED if result.interrupted else _EXIT_INCOMPLETE


def run(args: argparse.Namespace) -> int:
    """Acquire, simulate or recover one run; return 0 if complete, 1 if not, 3 if the disk
    could not take it (raw log kept), 130 on Ctrl-C.

    Other failures (no port, no answer, a refused header, a run id in use, a run with
    the samples of a catalogued run) raise the package's error: exit status 2 from
    :func:`bayestribo.cli.main.main`, with nothing but the raw log written.
    """
    from bayestribo.acquisition.faults import StorageError
    from bayestribo.acquisition.recover import recover_run
    from bayestribo.acquisition.session import acquire_run

    raw = Path(args.recover) if args.recover else None
    out = Path(args.out) if args.out else (raw.parent if raw is not None else Path("runs"))
    catalog = None if args.no_catalog else (args.catalog or out / "catalog.sqlite")
    if raw is not None:
        given = {
            "load_N": args.load,
            "lubricant": args.lubricant,
            "water_mass_fraction": args.water_fraction,
            "temperature_C": args.temperature,
            "mass_kg": args.mass,
            "natural_frequency_Hz": args.frequency,
        }
        try:
            result = recover_run(
                raw, out_dir=out, inputs=given, catalog=catalog, overwrite=args.overwrite
            )
        except StorageError as exc:
            print(f"bayestribo acquire: storage error: {exc}", file=sys.stderr)
            return _EXIT_STORAGE
        return _report(result)

    inputs = _inputs(args, simulate=args.simulate)
    instrument = None
    port = args.port
    if args.simulate:
        from bayestribo.acquisition.instrument import (
            FaultPlan,
            SimulatedInstrument,
            SimulationConfig,
        )

        try:
            config = SimulationConfig(
                zeta=args.sim_zeta,
                mu_k=args.sim_mu_k,
                mu_s=args.sim_mu_s,
                x0_m=args.sim_x0,
                load_N=args.load,
                mass_kg=inputs["mass_kg"],
                natural_frequency_Hz=inputs["natural_frequency_Hz"],
                noise_counts=args.sim_noise,
                seed=args.sim_seed,
                # the simulated magnet holds the pin long after the host's FIRE is due:
                # the same settings give the same recording whatever the machine's load
                hold_s=max(0.5, 10.0 * args.pretrigger),
            )
            faults = FaultPlan(
                drop=frozenset(args.drop),
                corrupt=frozenset(args.corrupt),
                garbage=frozenset(args.garbage),
                stall=dict(args.stall),
                disconnect_after=args.disconnect_after,
                bad_header=args.bad_header,
                silent=args.silent,
            )
            instrument = SimulatedInstrument(config, faults)
        except ValueError as exc:
            raise AcquisitionError(f"acquire --simulate: {exc}") from None
        port = instrument.start_socket() if args.sim_socket else instrument.start_pty()
        print(f"simulated instrument on {port}", file=sys.stderr)
    try:
        result = acquire_run(
            port,
            out,
            inputs,
            baudrate=args.baudrate,
            timeout_s=args.timeout,
            pretrigger_s=args.pretrigger,
            sample_rate_Hz=args.rate,
            samples_per_frame=args.samples_per_frame,
            duration_s=args.duration,
            run_id=args.run_id,
            progress=None if args.quiet else _progress,
            catalog=catalog,
        )
    except KeyboardInterrupt:
        print("\ninterrupted before the run started; raw log kept", file=sys.stderr)
        return _EXIT_INTERRUPTED
    except StorageError as exc:
        end_of_progress = "" if args.quiet else "\n"
        print(f"{end_of_progress}bayestribo acquire: storage error: {exc}", file=sys.stderr)
        return _EXIT_STORAGE
    finally:
        if instrument is not None:
            instrument.stop()
    if not args.quiet:
        sys.stderr.write("\n")
    return _report(result)
