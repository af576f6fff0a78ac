"""Never silently wrong: the fit on laws and channels that are not its model.

Each run comes from this file's own simulator (``scipy.integrate.solve_ivp`` half cycle
by half cycle, independent of the package's), of

    m x'' + c x' + c₂ |x'| x' + k x + k₃ x³ + μ(x) N sgn(x') = 0,

sticking at the first turning point where the spring force is inside ±μ_s N, on the
paper's rig (m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236, μ_k = 0.0294,
μ_s = 0.04, x₀ = 2 mm, 10 kHz, 0.1 s of rest before and after), with white noise of
10× or 30× the vibrometer's resolution and one departure from the model:

===========  =========================================================================
clean        the model itself
gain         velocity channel gain +1 %
delay        displacement channel 50 µs late (a band-limited delay)
cubic        k₃ shifting the frequency at 2 mm by +0.1 % (k₃/k = 667 m⁻²)
drag         quadratic damping c₂ carrying 10 % of the viscous loss at 2 mm
track        μ(x) = μ_k (1 + 0.05 sin(2π x / 0.5 mm)): friction varying ±5 % along
             the track
===========  =========================================================================

(The signal chain's effects, anti-alias filter, hum, 1/f noise and long rests, are in
``benchmarks/frontend.py``.) Every run is fitted with :func:`bayestribo.fit` (exact
model, 16 walkers × 2 ensembles). A run is **refused** (an exception), **covered** (the
95 % intervals of ζ and μ_k both contain the nominal values), **flagged** (not covered,
and a package warning says something is wrong: misfit, channels, convergence, prior
bound) or **silently wrong** (not covered, no warning). For the laws that are not
viscous + Coulomb the nominal ζ and μ_k are the parameters of the linear part; the fit
is right to cover them or to say the law is not adequate. At 95 % a clean case leaves
about 1 run in 20 uncovered by chance: "silently wrong" counts are read against that.

Run (by hand)::

    nice -n 10 python benchmarks/misspecification.py --runs 20 --workers 2

Writes ``benchmarks/results/misspecification.json`` with the machine description.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import niced_worker, write_results  # noqa: E402

__all__ = ["EFFECTS", "one_run", "simulate_law", "summarise"]

MASS, F_HZ, LOAD = 0.035, 32.6, 0.31
ZETA, MU_K, MU_S, X0 = 0.0236, 0.0294, 0.04, 2e-3
RESOLUTION_X, RESOLUTION_V = 0.15e-6, 0.015e-6
RATE_HZ, REST_S = 10_000.0, 0.1
OMEGA = 2 * math.pi * F_HZ
K, C = MASS * OMEGA**2, 2 * ZETA * MASS * OMEGA

#: k₃/k giving a +0.1 % frequency at amplitude X0 (Duffing: Δf/f = 3/8 k₃/k A²).
K3_OVER_K = 0.001 * 8.0 / (3.0 * X0**2)
#: c₂ whose loss per cycle at X0 is 10 % of the viscous one (8/3 c₂ ω² A³ = 0.1 π c ω A²).
C2 = 0.1 * math.pi * C / ((8.0 / 3.0) * OMEGA * X0)

#: effect -> simulator options and channel errors
EFFECTS: dict[str, dict[str, Any]] = {
    "clean": {},
    "gain": {"velocity_gain": 1.01},
    "delay": {"displacement_delay_s": 50e-6},
    "cubic": {"k3": K3_OVER_K * K},
    "drag": {"c2": C2},
    "track": {"track": (0.05, 0.5e-3)},
}
NOISE_LEVELS = (10.0, 30.0)
PARAMS = ("zeta", "mu_k")


def simulate_law(
    *, k3: float = 0.0, c2: float = 0.0, track: tuple[float, float] = (0.0, 1.0)
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Noise-free t [s], x [m], v [m/s] of the free decay, solve_ivp half cycle by half
    cycle (the friction's sign is constant between velocity zeros)."""
    amplitude, wavelength = track

    def mu(x: float) -> float:
        return MU_K * (1.0 + amplitude * math.sin(2 * math.pi * x / wavelength))

    arcs, x, t0 = [], X0, 0.0
    while abs(K * x + k3 * x**3) > MU_S * LOAD:
        s = -math.copysign(1.0, x)

        def rhs(_t, u, s=s):
            friction = mu(u[0]) * LOAD * s
            force = -C * u[1] - c2 * abs(u[1]) * u[1] - K * u[0] - k3 * u[0] ** 3 - friction
            return [u[1], force / MASS]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t0, t0 + 1.0 / F_HZ),
            [x, 0.0],
            method="DOP853",
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-15,
        )
        t1, x = float(sol.t_events[0][0]), float(sol.y_events[0][0][0])
        arcs.append((t0, t1, sol.sol))
        t0 = t1
    t = np.arange(round((2 * REST_S + t0) * RATE_HZ) + 1) / RATE_HZ
    tm = t - REST_S
    xs, vs = np.full(t.size, X0), np.zeros(t.size)
    for a, b, sol in arcs:
        m = (tm >= a) & (tm < b)
        if m.any():
            xs[m], vs[m] = sol(tm[m])
    xs[tm >= t0] = x
    return t, xs, vs


def _delayed(t: np.ndarray, signal: np.ndarray, delay: float) -> np.ndarray:
    n = signal.size
    padded = np.concatenate((signal, np.full(n, signal[-1])))
    f = np.fft.rfftfreq(2 * n, t[1] - t[0])
    return np.fft.irfft(np.fft.rfft(padded) * np.exp(-2j * np.pi * f * delay), 2 * n)[:n]


def one_run(effect: str, noise: float, index: int, seed: int, max_steps: int) -> dict[str, Any]:
    """Simulate one run, fit it, record refusal, coverage and warnings."""
    from bayestribo.inference import fit
    from bayestribo.io.run import Run

    options = EFFECTS[effect]
    law = {k: options[k] for k in ("k3", "c2", "track") if k in options}
    out: dict[str, Any] = {"effect": effect, "noise": noise, "index": index}
    rng = np.random.default_rng([seed, index, int(noise)])
    start = time.perf_counter()
    try:
        t, x, v = simulate_law(**law)
        if "displacement_delay_s" in options:
            x = _delayed(t, x, options["displacement_delay_s"])
        v = v * options.get("velocity_gain", 1.0)
        x = x + noise * RESOLUTION_X * rng.standard_normal(t.size)
        v = v + noise * RESOLUTION_V * rng.standard_normal(t.size)
        run = Run(
            t,
            x,
            v,
            {
                "natural_frequency_Hz": F_HZ,
                "mass_kg": MASS,
                "load_N": LOAD,
                "displacement_resolution_m": RESOLUTION_X,
                "velocity_resolution_m_per_s": RESOLUTION_V,
            },
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(run, seed=int(rng.integers(2**31)), max_steps=max_steps)
    except Exception as exc:  # recorded and reported, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    out["seconds"] = time.perf_counter() - start
    out["converged"] = bool(result.converged)
    out["warnings"] = sorted(
        {w.category.__name__ for w in caught if w.category.__module__.startswith("bayestribo")}
    )
    truth = {"zeta": ZETA, "mu_k": MU_K}
    out["interval"] = {n: [float(b) for b in result.interval(n, 0.95)] for n in PARAMS}
    out["mean"] = {n: float(np.mean(result.samples(n))) for n in PARAMS}
    out["sd"] = {n: float(np.std(result.samples(n), ddof=1)) for n in PARAMS}
    out["covered"] = {
        n: bool(out["interval"][n][0] <= truth[n] <= out["interval"][n][1]) for n in PARAMS
    }
    out["z"] = {n: (out["mean"][n] - truth[n]) / out["sd"][n] for n in PARAMS}
    return out


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per effect and noise level: refused, covered, flagged, silently wrong, z."""
    table: dict[str, Any] = {}
    for effect in EFFECTS:
        for noise in NOISE_LEVELS:
            rows = [r for r in records if r["effect"] == effect and r["noise"] == noise]
            if not rows:
                continue
            fitted = [r for r in rows if "covered" in r]
            covered = [r for r in fitted if all(r["covered"].values())]
            missed = [r for r in fitted if not all(r["covered"].values())]
            row: dict[str, Any] = {
                "runs": len(rows),
                "refused": len(rows) - len(fitted),
                "refusals": sorted({r["refused"] for r in rows if "refused" in r}),
                "covered": len(covered),
                "flagged": sum(bool(r["warnings"]) for r in missed),
                "silently_wrong": sum(not r["warnings"] for r in missed),
                "warned_total": sum(bool(r["warnings"]) for r in fitted),
                "warnings": sorted({w for r in fitted for w in r["warnings"]}),
            }
            for n in PARAMS:
                z = np.array([r["z"][n] for r in fitted])
                row[f"z_{n}"] = (
                    {"mean": float(z.mean()), "sd": float(z.std(ddof=1))} if z.size > 1 else None
                )
            table[f"{effect}@{noise:g}x"] = row
    return table


def _print_table(table: dict[str, Any]) -> None:
    print(
        f"{'effect@noise':14s} {'runs':>4s} {'refused':>7s} {'covered':>7s} {'flagged':>7s} "
        f"{'silent':>6s} {'z ζ (mean±sd)':>15s} {'z μk (mean±sd)':>15s}  warnings"
    )
    for key, r in table.items():

        def z(name: str, r: dict = r) -> str:
            v = r[f"z_{name}"]
            return f"{v['mean']:+.2f}±{v['sd']:.2f}" if v else "-"

        print(
            f"{key:14s} {r['runs']:4d} {r['refused']:7d} {r['covered']:7d} {r['flagged']:7d} "
            f"{r['silently_wrong']:6d} {z('zeta'):>15s} {z('mu_k'):>15s}  "
            f"{', '.join(r['warnings'])}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per effect and noise level")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--max-steps", type=int, default=6000)
    parser.add_argument("--effects", nargs="*", default=list(EFFECTS), choices=list(EFFECTS))
    parser.add_argument("--noise", nargs="*", type=float, default=list(NOISE_LEVELS))
    args = parser.parse_args(argv)
    start = time.perf_counter()
    jobs = [(e, n, i) for e in args.effects for n in args.noise for i in range(args.runs)]
    records: list[dict[str, Any]] = []
    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        futures = [pool.submit(one_run, e, n, i, args.seed, args.max_steps) for e, n, i in jobs]
        for k, future in enumerate(as_completed(futures), 1):
            records.append(future.result())
            if k % 20 == 0:
                print(f"{k}/{len(jobs)} runs, {time.perf_counter() - start:.0f} s", flush=True)
    table = summarise(records)
    _print_table(table)
    path = write_results(
        "misspecification",
        {
            "settings": {
                "runs": args.runs,
                "seed": args.seed,
                "max_steps": args.max_steps,
                "noise_levels_x_resolution": args.noise,
                "effects": {e: {k: str(v) for k, v in EFFECTS[e].items()} for e in args.effects},
                "sample_rate_Hz": RATE_HZ,
                "rest_s": REST_S,
            },
            "wall_seconds": time.perf_counter() - start,
            "table": table,
            "runs": records,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
