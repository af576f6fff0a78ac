"""Never silently wrong: the fit on every effect of a real recording that is not its model.

The one benchmark of "never silently wrong". Each run comes from the independent
simulator of ``benchmarks/_chain.py`` (``scipy.integrate.solve_ivp`` half cycle by half
cycle, nothing from the package) of

    m x'' + c x' + c₂ |x'| x' + k x + k₃ x³ + μ(x) N sgn(x') = 0,

sticking at the first turning point where the spring force is inside ±μ_s N, on the
paper's rig (m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236, μ_k = 0.0294,
μ_s = 0.04, x₀ = 2 mm; 10 kHz and 0.1 s of rest before and after unless said), with
white noise of 10x or 30x the vibrometer's resolution (0.15 µm, 0.015 µm/s) on both
channels and one effect (the sensor's gain exact, ``gain_uncertainty`` 0, unless said):

===========  =========================================================================
clean        the model itself (``--clean-runs`` runs per noise level, default 200)
*the signal chain*
filter       a causal 4th-order Butterworth anti-alias filter at 2 kHz on both channels
hum          50 Hz mains hum of 5x the white noise's rms, fitted as it is
hum-notch    the same, fitted with ``bayestribo.fit(..., notch="auto")``
pink         1/f noise of 5x the white noise's rms
rest-2s      2 s of rest after the stop
rest-30s     30 s of rest after the stop
1kHz         sampled at 1 kHz
100kHz       sampled at 100 kHz, through the anti-alias filter
*the channels*
gain         velocity channel gain +1 %
delay        displacement channel 50 µs late (a band-limited delay)
*the laws*
cubic        k₃ shifting the frequency at 2 mm by +0.1 % (k₃/k = 667 m⁻²)
drag         quadratic damping c₂ carrying 10 % of the viscous loss at 2 mm
track        μ(x) = μ_k (1 + 0.05 sin(2π x / 0.5 mm)): friction ±5 % along the track
*another rig (a first recording)*
jitter-gaps  time stamps jittered by ±0.1 step (uniform), rounded to 1 µs; 2 single
             samples missing in the motion
steps-10     both channels rounded to a tenth of their peak-to-peak swing
spikes       3 single samples of the displacement moved by 30 % of x₀
velocity-10  the velocity channel alone, sampled at 10 samples a period (326 Hz)
one-pole-10f a first-order low-pass at 10 f (326 Hz) on both channels, nothing declared
             (the default 1 % gain uncertainty)
one-pole-5f- the same at 5 f (163 Hz, -1.9 % at f), declared in the sidecar's
declared     ``filter``
duffing-5pc  k₃ shifting the frequency at 2 mm by +5 %
duffing-5pc- the same, declared in the sidecar's ``restoring``: ``duffing`` (the law's
declared     model takes the spring's potential, β measured from the half periods)
pendulum-90  the spring force k L sin(x/L), released at x₀ = L π/2: a pendulum at 90°
duffing-5pc- duffing-5pc and pendulum-90 fitted with ``restoring="auto"`` (the advice of
auto,        the linear fit's ``FrequencyTrendWarning``; ``--restoring auto`` gives it
pendulum-    to every case)
90-auto
pendulum-90- pendulum-90 recorded as the angle x/L [rad] (``length_unit`` ``rad``, no load:
rad-auto     friction as the angle μ_k N/(k L), the fit's friction displacement), fitted
             with ``restoring="auto"``
long-60s     a long, lightly damped record (ζ = 0.0002, μ_k = 0.0002) at 1 kHz, 0.2 s
             of rest before the release and none after: 60 s that end in motion
===========  =========================================================================

Every run is fitted with :func:`bayestribo.fit` (exact model, 16 walkers × 2 ensembles,
at most ``--max-steps`` steps). The truth is ζ = 0.0236 and μ_k = 0.0294 (a case's own
``truth`` where it simulates another rig: ``long-60s``); for the laws
that are not viscous + Coulomb it is the parameters of their linear part, and the fit is
right either to cover them or to say that the law is not adequate. With
z = (posterior mean - truth) / posterior sd for each of ζ and μ_k, a run is

* **refused**: the fit raised an exception (recorded with its message);
* **covered**: the 95 % intervals of ζ and of μ_k both contain the truth;
* **flagged**: not covered, and a bayestribo warning said something is wrong
  (:class:`~bayestribo.errors.MisfitWarning`,
  :class:`~bayestribo.errors.ChannelCalibrationWarning`,
  :class:`~bayestribo.errors.ConvergenceWarning`,
  :class:`~bayestribo.errors.PriorBoundWarning`; a
  :class:`~bayestribo.errors.MetadataWarning` is information, not a flag);
* **missed**: not covered, and no such warning. Expected by chance: a calibrated fit
  leaves each 95 % interval uncovered in 1 run of 20, so about 1 run in 10 misses one of
  the two;
* **silently wrong** (counted among all fitted runs, whatever the coverage): a confident
  wrong answer, the truth outside the 99.9 % interval of ζ or of μ_k (|z| > 3.29) and no
  such warning. A calibrated fit gives this in about 2 runs in 1000; it is the failure
  this benchmark exists to count.

Per case also: coverage of each parameter's 95 % interval with its Clopper-Pearson
95 % interval, the mean of z (± its standard error) and the sd of z (± its standard error
sd/√(2(n-1))): 1 for a calibrated fit, below 1 for conservative intervals, above 1 for
too narrow ones; and the median seconds of one fit. The clean case is the calibration:
coverage should be 93-97 % and sd(z) within 10 % of 1, hence its 200 runs.

The runs are seeded: run ``index`` of ``case`` at ``noise`` draws its noise from
``numpy.random.default_rng([seed, crc32(case), noise, index])`` and fits with the seed
recorded beside it; ``one_run(case, noise, index, seed, max_steps)`` repeats it, and a
sweep made in parts runs the later indices alone (``--first-run 10 --runs 20``: runs
10-19, the same records as in a sweep of 20).

The AppStat2020 recordings' split-half table (``benchmarks/halves.py``: least squares,
the Bayesian fit, the Bayesian fit with the discrepancy term, on HarmOsc1-3) is
recomputed and printed after the simulations (``--no-real`` to skip it).

Run (by hand)::

    nice -n 10 python benchmarks/misspecification.py --runs 20 --clean-runs 200 --workers 2

Writes ``benchmarks/results/misspecification.json`` (``--output NAME``: ``NAME.json``)
with the machine description, the load average at start and end, the table and every run.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
import zlib
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _chain import (  # noqa: E402
    CHAIN_EFFECTS,
    LOAD,
    MU_K,
    OMEGA,
    X0,
    ZETA,
    C,
    K,
    apply_chain,
    clopper_pearson,
    metadata,
    record,
)
from _machine import niced_worker, write_results  # noqa: E402

__all__ = ["CASES", "one_run", "run_indices", "summarise"]

#: k₃/k giving a +0.1 % frequency at amplitude X0 (Duffing: Δf/f = 3/8 k₃/k A²).
K3_OVER_K = 0.001 * 8.0 / (3.0 * X0**2)
#: c₂ whose loss per cycle at X0 is 10 % of the viscous one (8/3 c₂ ω² A³ = 0.1 π c ω A²).
C2 = 0.1 * math.pi * C / ((8.0 / 3.0) * OMEGA * X0)
REST_BEFORE_S = 0.1
#: The pendulum's length [m] (released at 90°: x₀ = L π/2).
PENDULUM_LENGTH = X0 / (math.pi / 2)
#: ζ and μ_k of the long record (``long-60s``): light enough to move for 60 s.
LONG_TRUTH = {"zeta": 0.0002, "mu_k": 0.0002}

#: case -> sample rate [Hz], rest after the stop [s], law (options of ``_chain.record``),
#: chain (options of ``_chain.apply_chain`` but the noise), notch for the fit, kind; and
#: where set, rest before the release [s], the fit's ``restoring``, the truth (ζ, μ_k).
CASES: dict[str, dict[str, Any]] = {
    **{
        name: {"fs": fs, "rest_after": rest, "law": {}, "chain": chain, "notch": notch}
        | {"kind": "clean" if name == "clean" else "chain"}
        for name, (fs, rest, chain, notch) in CHAIN_EFFECTS.items()
    },
    "gain": {"chain": {"velocity_gain": 1.01}, "kind": "channel"},
    "delay": {"chain": {"displacement_delay_s": 50e-6}, "kind": "channel"},
    "cubic": {"law": {"k3": K3_OVER_K * K}, "kind": "law"},
    "drag": {"law": {"c2": C2}, "kind": "law"},
    "track": {"law": {"track": (0.05, 0.5e-3)}, "kind": "law"},
    # a first recording from another rig (the first-contact issue)
    "jitter-gaps": {"time": {"jitter": 0.1, "drop": 2}, "kind": "rig"},
    "steps-10": {"chain": {"steps": 10.0}, "kind": "rig"},
    "spikes": {"chain": {"spikes": 3}, "kind": "rig"},
    "velocity-10": {"fs": 10 * 32.6, "channels": "velocity", "kind": "rig"},
    "one-pole-10f": {"chain": {"one_pole_hz": 326.0}, "meta": {"gain_uncertainty": None}}
    | {"kind": "rig"},
    "one-pole-5f-declared": {
        "chain": {"one_pole_hz": 163.0},
        "meta": {"filter": {"kind": "butterworth", "order": 1, "cutoff_Hz": 163.0}},
        "kind": "rig",
    },
    "duffing-5pc": {"law": {"k3": 50 * K3_OVER_K * K}, "kind": "rig"},
    "duffing-5pc-declared": {
        "law": {"k3": 50 * K3_OVER_K * K},
        "meta": {"restoring": "duffing"},
        "kind": "rig",
    },
    "pendulum-90": {"law": {"pendulum": math.pi / 2}, "kind": "rig"},
    "duffing-5pc-auto": {"law": {"k3": 50 * K3_OVER_K * K}, "restoring": "auto", "kind": "rig"},
    "pendulum-90-auto": {"law": {"pendulum": math.pi / 2}, "restoring": "auto", "kind": "rig"},
    "pendulum-90-rad-auto": {
        "law": {"pendulum": math.pi / 2},
        "angle": PENDULUM_LENGTH,
        "restoring": "auto",
        "truth": {"zeta": ZETA, "mu_k": MU_K * LOAD / (K * PENDULUM_LENGTH)},
        "kind": "rig",
    },
    "long-60s": {
        "fs": 1_000.0,
        "rest_before": 0.2,
        "law": {"zeta": LONG_TRUTH["zeta"], "mu_k": LONG_TRUTH["mu_k"], "duration": 60.0},
        "truth": LONG_TRUTH,
        "kind": "rig",
    },
}
for _case in CASES.values():
    for _key, _default in (
        ("fs", 10_000.0),
        ("rest_after", 0.1),
        ("law", {}),
        ("chain", {}),
        ("notch", None),
        ("time", {}),
        ("channels", "both"),
        ("meta", {}),
        ("rest_before", REST_BEFORE_S),
        ("restoring", None),
        ("truth", {"zeta": ZETA, "mu_k": MU_K}),
        ("angle", None),
    ):
        _case.setdefault(_key, _default)
NOISE_LEVELS = (10.0, 30.0)
PARAMS = ("zeta", "mu_k")
TRUTH = {"zeta": ZETA, "mu_k": MU_K}
Z_CONFIDENT = 3.2905  # two-sided 99.9 % of the normal
#: Warnings that say the result is not to be trusted as it is.
FLAGS = ("MisfitWarning", "ChannelCalibrationWarning", "ConvergenceWarning", "PriorBoundWarning")

NOTES = """\
covered  both 95 % intervals (ζ, μ_k) contain the truth
flagged  not covered, and a warning said something is wrong (Misfit, ChannelCalibration,
         Convergence, PriorBound)
missed   not covered, no such warning: expected by chance in about 1 run in 10 (two
         parameters at 95 %)
SILENT   silently wrong: a confident wrong answer, |z| > 3.29 (truth outside the 99.9 %
         interval) for ζ or μ_k with no such warning, z = (mean - truth)/sd; about 2 in
         1000 by chance
warned   runs with such a warning, covered or not (ChannelCalibration also when it
         measured and corrected the channels)"""


def _entropy(case: str, noise: float, index: int, seed: int) -> list[int]:
    return [seed, zlib.crc32(case.encode()), round(100 * noise), index]


def _clock(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, spec: dict[str, Any], entropy: list[int]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A logger's clock: stamps jittered uniformly by ±``jitter`` steps (rounded to a
    microsecond) and ``drop`` single samples missing in the motion."""
    if not spec:
        return t, x, v
    rng = np.random.default_rng([*entropy, 2])
    step = t[1] - t[0]
    stamps = np.round(t + rng.uniform(-1, 1, t.size) * spec.get("jitter", 0.0) * step, 6)
    drop = int(spec.get("drop", 0))
    lost = rng.choice(np.arange(t.size // 4, t.size // 2), size=drop, replace=False)
    keep = np.setdiff1d(np.arange(t.size), lost)
    return stamps[keep], x[keep], v[keep]


def run_indices(
    cases: list[str], noise: list[float], runs: int, clean_runs: int, first: int = 0
) -> list[tuple[str, float, int]]:
    """The runs (case, noise, index) of a sweep: indices ``first`` to ``runs`` - 1 of
    every case (to ``clean_runs`` - 1 of ``clean``) at every noise level."""
    return [
        (c, n, i)
        for c in cases
        for n in noise
        for i in range(first, clean_runs if c == "clean" else runs)
    ]


def one_run(
    case: str,
    noise: float,
    index: int,
    seed: int,
    max_steps: int,
    restoring: str | None = None,
) -> dict[str, Any]:
    """Simulate run ``index`` of ``case`` at ``noise`` x the resolution, fit it, record
    refusal, intervals, z and warnings; ``restoring`` over the case's own restoring
    force for the fit (``fit(..., restoring=...)``)."""
    from bayestribo.inference import fit
    from bayestribo.io.run import Run

    spec = CASES[case]
    truth = spec["truth"]
    restoring = restoring or spec["restoring"]
    entropy = _entropy(case, noise, index, seed)
    fit_seed = int(np.random.default_rng([*entropy, 1]).integers(2**31))
    out: dict[str, Any] = {
        "case": case,
        "noise": noise,
        "index": index,
        "entropy": entropy,
        "fit_seed": fit_seed,
        "restoring": restoring,
    }
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t, x, v = record(spec["fs"], spec["rest_before"], spec["rest_after"], **spec["law"])
            xs, vs = apply_chain(t, x, v, spec["fs"], seed=entropy, noise=noise, **spec["chain"])
            t, xs, vs = _clock(t, xs, vs, spec["time"], entropy)
            meta = {**metadata(), **spec["meta"]}
            if spec["angle"]:  # the angle x/L of a pendulum of length L, in radians
                length = spec["angle"]
                xs, vs = xs / length, vs / length
                meta |= {"length_unit": "rad", "load_N": None, "mass_kg": None}
                meta["displacement_resolution_m"] /= length
                meta["velocity_resolution_m_per_s"] /= length
            meta = {k: value for k, value in meta.items() if value is not None}
            run = Run(
                time=t,
                displacement=None if spec["channels"] == "velocity" else xs,
                velocity=vs,
                metadata=meta,
            )
            start = time.perf_counter()
            result = fit(
                run, seed=fit_seed, max_steps=max_steps, notch=spec["notch"], restoring=restoring
            )
            out["fit_seconds"] = time.perf_counter() - start
    except Exception as exc:  # recorded and reported, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    ours = [w for w in caught if w.category.__module__.startswith("bayestribo")]
    # a flag is one of FLAGS or a subclass of one (ShortAnalysisWarning and
    # CoarseSignalWarning are MisfitWarnings: the command's exit status is 1)
    flag = [w for w in ours if any(c.__name__ in FLAGS for c in w.category.__mro__)]
    out["warnings"] = sorted({w.category.__name__ for w in flag})
    out["other_warnings"] = sorted({w.category.__name__ for w in caught if w not in flag})
    messages: dict[str, str] = {}
    for w in ours:
        messages.setdefault(w.category.__name__, str(w.message)[:400])
    out["warning_messages"] = messages
    out["converged"] = bool(result.converged)
    diagnostics = result.diagnostics
    if diagnostics.get("chi2_map") is not None and diagnostics.get("n_increments"):
        out["chi2_per_n"] = diagnostics["chi2_map"] / diagnostics["n_increments"]
    out["notch_Hz"] = result.settings.get("notch_Hz")
    chosen = (result.restoring or {}).get("auto")
    if chosen:
        out["restoring_chosen"] = chosen.get("chosen")
    # without a load (an angle), friction is the friction displacement x_c = μ_k N/k
    named = {"zeta": "zeta", "mu_k": "friction_displacement" if spec["angle"] else "mu_k"}
    draws = {n: result.samples(named[n]) for n in PARAMS}
    out["interval"] = {n: [float(b) for b in result.interval(named[n], 0.95)] for n in PARAMS}
    out["mean"] = {n: float(np.mean(draws[n])) for n in PARAMS}
    out["sd"] = {n: float(np.std(draws[n], ddof=1)) for n in PARAMS}
    out["covered"] = {
        n: bool(out["interval"][n][0] <= truth[n] <= out["interval"][n][1]) for n in PARAMS
    }
    out["z"] = {n: (out["mean"][n] - truth[n]) / out["sd"][n] for n in PARAMS}
    return out


def _confident_wrong(r: dict[str, Any]) -> bool:
    return any(abs(r["z"][n]) > Z_CONFIDENT for n in PARAMS)


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per case and noise level: refused, covered, flagged, missed, silently wrong;
    coverage per parameter with its interval; z's mean and sd with their errors."""
    table: dict[str, Any] = {}
    for case in CASES:
        for noise in sorted({r["noise"] for r in records}):
            rows = [r for r in records if r["case"] == case and r["noise"] == noise]
            if not rows:
                continue
            fitted = [r for r in rows if "refused" not in r]
            both = [all(r["covered"].values()) for r in fitted]
            uncovered = [r for r, c in zip(fitted, both, strict=True) if not c]
            silent = [r for r in fitted if _confident_wrong(r) and not r["warnings"]]
            row: dict[str, Any] = {
                "kind": CASES[case]["kind"],
                "runs": len(rows),
                "refused": len(rows) - len(fitted),
                "refusals": [
                    {"index": r["index"], "message": r["refused"]} for r in rows if "refused" in r
                ],
                "covered": sum(both),
                "flagged": sum(bool(r["warnings"]) for r in uncovered),
                "missed": sum(not r["warnings"] for r in uncovered),
                "silently_wrong": len(silent),
                "silently_wrong_runs": [
                    {"index": r["index"], "entropy": r["entropy"], "z": r["z"]} for r in silent
                ],
                "confident_wrong_flagged": sum(
                    _confident_wrong(r) and bool(r["warnings"]) for r in fitted
                ),
                "warned": sum(bool(r["warnings"]) for r in fitted),
                "warnings": {
                    w: sum(w in r["warnings"] for r in fitted)
                    for w in sorted({w for r in fitted for w in r["warnings"]})
                },
                "not_converged": sum(not r["converged"] for r in fitted),
                "restoring_chosen": {
                    f: sum(r.get("restoring_chosen") == f for r in fitted)
                    for f in sorted(
                        {r["restoring_chosen"] for r in fitted if "restoring_chosen" in r}
                    )
                },
                "median_fit_seconds": (
                    float(np.median([r["fit_seconds"] for r in fitted])) if fitted else None
                ),
            }
            chi2 = [r["chi2_per_n"] for r in fitted if r.get("chi2_per_n") is not None]
            row["chi2_per_n_median"] = float(np.median(chi2)) if chi2 else None
            n = len(fitted)
            for p in PARAMS:
                k = sum(r["covered"][p] for r in fitted)
                row[f"coverage_{p}"] = {
                    "covered": k,
                    "of": n,
                    "rate": k / n if n else None,
                    "ci95": clopper_pearson(k, n),
                }
                z = np.array([r["z"][p] for r in fitted])
                row[f"z_{p}"] = (
                    {
                        "mean": float(z.mean()),
                        "mean_se": float(z.std(ddof=1) / math.sqrt(n)),
                        "sd": float(z.std(ddof=1)),
                        "sd_se": float(z.std(ddof=1) / math.sqrt(2 * (n - 1))),
                        "max_abs": float(np.abs(z).max()),
                    }
                    if n > 1
                    else None
                )
            table[f"{case}@{noise:g}x"] = row
    return table


def _print_table(table: dict[str, Any]) -> None:
    print("\nOutcomes per case (runs refused, covered, flagged, missed, silently wrong)")
    print(NOTES)
    print(
        f"\n{'case@noise':15s} {'kind':7s} {'runs':>4s} {'refused':>7s} {'covered':>7s} "
        f"{'flagged':>7s} {'missed':>6s} {'SILENT':>6s} {'warned':>6s}  warnings (runs)"
    )
    for key, r in table.items():
        warned = ", ".join(
            [f"{w.removesuffix('Warning')} {k}" for w, k in r["warnings"].items()]
            + [f"auto→{f} {k}" for f, k in r.get("restoring_chosen", {}).items()]
        )
        print(
            f"{key:15s} {r['kind']:7s} {r['runs']:4d} {r['refused']:7d} {r['covered']:7d} "
            f"{r['flagged']:7d} {r['missed']:6d} {r['silently_wrong']:6d} {r['warned']:6d}  "
            f"{warned}"
        )
    print(
        "\nCalibration per case: coverage of each 95 % interval [Clopper-Pearson 95 %], "
        "z = (mean - truth)/sd: mean ± se, sd ± se (1 if calibrated), median s per fit"
    )
    print(
        f"{'case@noise':15s} {'cov ζ %':>17s} {'cov μk %':>17s} {'z ζ mean':>12s} "
        f"{'sd z ζ':>11s} {'z μk mean':>12s} {'sd z μk':>11s} {'s/fit':>6s}"
    )
    for key, r in table.items():
        cells = []
        for p in PARAMS:
            c = r[f"coverage_{p}"]
            lo, hi = c["ci95"]
            cells.append(
                f"{100 * c['rate']:5.1f} [{100 * lo:3.0f}-{100 * hi:3.0f}]"
                if c["of"]
                else "-".rjust(17)
            )
        zs = []
        for p in PARAMS:
            z = r[f"z_{p}"]
            zs += (
                [f"{z['mean']:+.2f}±{z['mean_se']:.2f}", f"{z['sd']:.2f}±{z['sd_se']:.2f}"]
                if z
                else ["-", "-"]
            )
        sec = r["median_fit_seconds"]
        print(
            f"{key:15s} {cells[0]:>17s} {cells[1]:>17s} {zs[0]:>12s} {zs[1]:>11s} "
            f"{zs[2]:>12s} {zs[3]:>11s} {'-' if sec is None else f'{sec:6.2f}':>6s}"
        )
    refusals = [(k, x) for k, r in table.items() for x in r["refusals"]]
    if refusals:
        print("\nRefused:")
        for key, x in refusals:
            print(f"  {key} run {x['index']}: {x['message']}")
    silent = [(k, x) for k, r in table.items() for x in r["silently_wrong_runs"]]
    if silent:
        print("\nSilently wrong:")
        for key, x in silent:
            z = ", ".join(f"z_{p} {v:+.2f}" for p, v in x["z"].items())
            print(f"  {key} run {x['index']} (entropy {x['entropy']}): {z}")


def _split_halves_real() -> list[dict[str, Any]]:
    """The AppStat2020 split-half table, recomputed with ``benchmarks/halves.py``."""
    from halves import _real

    rows: list[dict[str, Any]] = []
    for name in ("HarmOsc1.txt", "HarmOsc2.txt", "HarmOsc3.txt"):
        rows += _real(name)
    return rows


def _print_halves(rows: list[dict[str, Any]], seconds: float) -> None:
    print(
        "\nReal data: split-half check of the AppStat2020 recordings (benchmarks/halves.py, "
        f"recomputed in {seconds:.0f} s; α = 0.05; agree = one constant law fits both halves)"
    )
    print(f"{'recording':13s} {'method':18s} {'verdict':9s} {'max|z|':>7s} {'p':>8s}  friction")
    for r in rows:
        if "error" in r:
            print(f"{r['recording']:13s} {r['method']:18s} refused: {r['error']}")
        else:
            print(
                f"{r['recording']:13s} {r['method']:18s} "
                f"{'agree' if r['consistent'] else 'DISAGREE':9s} {r['max_abs_z']:7.2f} "
                f"{r['p_value']:8.2g}  {r['friction_mode']}"
            )


def _source_state() -> dict[str, Any]:
    """Where the package was imported from: the repository's commit and the package's
    files changed in its working tree, or another directory (e.g. a snapshot of a commit
    put first on PYTHONPATH while the working tree is being edited)."""
    import subprocess

    import bayestribo

    def git(*a: str) -> str:
        try:
            return subprocess.run(
                ["git", *a], cwd=HERE.parent, capture_output=True, text=True, check=True
            ).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return ""

    package = Path(bayestribo.__file__).resolve().parent
    in_tree = package == (HERE.parent / "bayestribo").resolve()
    return {
        "commit": git("rev-parse", "HEAD"),
        "package_path": str(package),
        "package_version": bayestribo.__version__,
        "package_files_changed": (
            git("status", "--porcelain", "--", "bayestribo").splitlines()
            if in_tree
            else "not used: the package was imported from package_path"
        ),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per case and noise level")
    parser.add_argument(
        "--clean-runs", type=int, default=200, help="runs of the clean case per noise level"
    )
    parser.add_argument(
        "--first-run",
        type=int,
        default=0,
        help="the first run index of every case (runs FIRST to RUNS-1, clean FIRST to "
        "CLEAN_RUNS-1): the later runs of a sweep made in parts",
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--max-steps", type=int, default=6000)
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    parser.add_argument("--noise", nargs="*", type=float, default=list(NOISE_LEVELS))
    parser.add_argument("--no-real", action="store_true", help="skip the split-half table")
    parser.add_argument("--output", default="misspecification", help="results/NAME.json")
    parser.add_argument(
        "--restoring",
        default=None,
        help="the fit's restoring force for every case (linear, pendulum, duffing, auto), "
        "over the case's own",
    )
    args = parser.parse_args(argv)
    if args.first_run < 0:
        parser.error(f"--first-run: expected a run index >= 0, got {args.first_run}")
    load_start = os.getloadavg()
    source = _source_state()
    start = time.perf_counter()
    jobs = run_indices(args.cases, args.noise, args.runs, args.clean_runs, args.first_run)

    # the slow cases first, so that the two workers end together
    def length(case: dict[str, Any]) -> float:
        return case["law"].get("duration") or case["rest_after"] + 0.6

    jobs.sort(key=lambda j: -CASES[j[0]]["fs"] * length(CASES[j[0]]))
    print(
        f"{len(jobs)} fits on {args.workers} workers, load average {load_start[0]:.2f}",
        flush=True,
    )
    records: list[dict[str, Any]] = []
    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        futures = [
            pool.submit(one_run, c, n, i, args.seed, args.max_steps, args.restoring)
            for c, n, i in jobs
        ]
        for k, future in enumerate(as_completed(futures), 1):
            records.append(future.result())
            if k % 25 == 0 or k == len(jobs):
                print(
                    f"{k}/{len(jobs)} runs, {time.perf_counter() - start:.0f} s, "
                    f"load {os.getloadavg()[0]:.2f}",
                    flush=True,
                )
    sim_seconds = time.perf_counter() - start
    records.sort(key=lambda r: (list(CASES).index(r["case"]), r["noise"], r["index"]))
    table = summarise(records)
    _print_table(table)
    halves: dict[str, Any] = {"skipped": True}
    if not args.no_real:
        t0 = time.perf_counter()
        rows = _split_halves_real()
        halves = {
            "source": "recomputed with benchmarks/halves.py (_real) on "
            "../shared/external-data/appstat2020-harmonic-oscillator",
            "seconds": time.perf_counter() - t0,
            "rows": rows,
        }
        _print_halves(rows, halves["seconds"])
    load_end = os.getloadavg()
    wall = time.perf_counter() - start
    print(
        f"\nwall {wall:.0f} s (simulations and fits {sim_seconds:.0f} s); load average "
        f"(1, 5, 15 min) at start {', '.join(f'{x:.2f}' for x in load_start)}, at end "
        f"{', '.join(f'{x:.2f}' for x in load_end)}"
    )
    path = write_results(
        args.output,
        {
            "settings": {
                "runs": args.runs,
                "first_run": args.first_run,
                "clean_runs": args.clean_runs,
                "seed": args.seed,
                "max_steps": args.max_steps,
                "workers": args.workers,
                "n_walkers": 16,
                "n_ensembles": 2,
                "noise_levels_x_resolution": args.noise,
                "resolution": {"displacement_m": 0.15e-6, "velocity_m_per_s": 0.015e-6},
                "truth": TRUTH,
                "rest_before_s": REST_BEFORE_S,
                "restoring": args.restoring,
                "cases": {
                    c: {k: (str(v) if k in ("law", "chain") else v) for k, v in CASES[c].items()}
                    for c in args.cases
                },
                "flags": list(FLAGS),
                "silently_wrong": "|z| > 3.29 for zeta or mu_k and no flag, "
                "z = (posterior mean - truth) / posterior sd",
            },
            "notes": NOTES,
            "source": source,
            "wall_seconds": wall,
            "simulation_and_fit_seconds": sim_seconds,
            "load_average_start": list(load_start),
            "load_average_end": list(load_end),
            "table": table,
            "split_halves_real": halves,
            "runs": records,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
