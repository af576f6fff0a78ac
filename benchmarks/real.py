"""Real recordings made by others: the law ``law="auto"`` keeps, its ΔE(A), across seeds and halves.

Every recording in ``../shared/external-data`` (read from there, never copied):

* ``appstat2020-harmonic-oscillator/HarmOsc1-3.txt``: two whitespace columns, t [s] and
  position in an unknown unit; read with :func:`bayestribo.read_run` as the tests read
  them (``columns=["time_s", "displacement_m"]``, ``length_unit="arbitrary"``): no
  load, no mass, so ΔE(A) is ΔE/k in the signal's unit squared;
* ``smorzamento-spring-disc/*.csv``: ``time;position;velocity;acceleration`` in s, m,
  m/s, m/s², read with numpy; rows with an empty position are dropped, and, when the
  velocity is used, rows with an empty velocity (the last one). The velocity is used
  when the package accepts it (:func:`bayestribo.signal.channels.check_channels`; its
  :func:`~bayestribo.signal.channels.channel_consistency` is recorded); ``mass_kg`` from
  the file name (``..._<stiffness N/m>_<mass kg>_<n>.csv``), so ΔE(A) is in joules with
  k = mΩ² at the frequency the package measures (the stated stiffness and the
  frequency k/m would give are recorded beside it: the spring's own mass makes the
  measured period longer). No load: friction is a friction displacement.

Each recording is fitted whole and as two halves, cut at the turning point in the
middle of the analysed decay's half cycles (of :func:`bayestribo.inference.prepare` on
the whole; the first half ends there, the second starts there, each is then analysed
as the package analyses any recording, its first oscillation skipped). Each of the
three is fitted with ``law="auto"`` and with the default law for ``--seeds`` seeds
(16 walkers x 2 ensembles, at most ``--max-steps`` steps). Recorded per fit: the law
chosen, the comparison's verdict and whether it is adequate, its notes, the bayestribo
warnings, convergence, seconds, the law's own parameters, and ΔE(A) (mean, sd, 95 %
interval) at the fit's 12 reported amplitudes and at three amplitudes of the segment:
its largest swing, its median swing and its smallest swing (a swing is a half cycle's
mean turning-point distance). ΔE(A) at amplitudes other than the reported ones is
computed from the posterior draws with the chosen law's ``swing_dissipation`` (the
draws reproduce the reported band at the reported amplitudes: the
largest relative difference of the means is recorded).

Across seeds: the spread of the means, (max - min)/mean posterior sd, of ΔE at the
three amplitudes and of each parameter of the default law (goal: < 0.2), and whether
every seed chose the same law. The answer's spread is that of what each fit gives as
its answer: its law's ΔE(A) when the law holds, the turning points' ΔE(A) (law-free,
no random numbers) when the fit says that no law holds.

Halves: whether the law fitted to one half predicts the other half's ΔE(A). The
halves' amplitude ranges abut (the first ends at the cut, the second skips one
oscillation after it), so they share no amplitude: each half's law is compared with
the other half's band (a) at the cut, i.e. at the first half's smallest reported
amplitude and the second half's largest (each law extrapolated by at most one
oscillation), and (b) over the other half's 12 reported amplitudes (the law
extrapolated over the other half). At each amplitude z = (m₁ - m₂)/√(s₁² + s₂²) and
whether the predicted mean lies in the other half's 95 % interval. ``agree`` means
|z| <= 1.96 at every amplitude compared. These halves are each fitted with law="auto",
so each may choose its own law. The goal's form ("the law fitted to each half predicts
the other half's ΔE within the intervals, or the fit says that the law does not hold")
is the package's own check since law="auto" fits its verdict to each half of the
segment (:mod:`bayestribo.inference.halves`): per auto fit, ``package_halves`` and
``halves_goal_met`` (the comparison is not adequate, or the verdict's halves agree).

Issue 39's goal, per recording and segment over the seeds of its ``law="auto"`` fits
(``table[name]["goal"]``, printed last but one): the exit status each seed would give (0
when the law holds, 1 with the turning points' ΔE(A)), every seed converged, the
answer's, the law's band's and its parameters' seed spreads below 0.2 sd, the same law
on every seed, the halves agreeing or the law flagged, and never exit 0 with a law
whose ΔE(A) has another shape: the log-log slopes of the fit's ΔE(A) and of the
turning points' ΔE(A) (least squares of their means over the 12 reported amplitudes,
computed here, ``slopes`` per fit) may differ by at most 0.5 where the law holds. The
package's own shape test (:func:`bayestribo.inference.dissipation.shape_agreement`,
which also asks for three standard errors of the turning points' slope) is recorded
beside it (``shape_agreement``).

A recording or segment the package refuses is recorded with its error message (a
finding, not a failure of the benchmark).

Run (by hand)::

    timeout 5400 nice -n 10 python benchmarks/real.py --seeds 5 --workers 2

Writes ``benchmarks/results/real.json`` (``--output NAME``: ``NAME.json``, or a path
ending in .json) after every fit (``"complete": false`` until the end; ``--resume``
keeps the fits of an interrupted file with the same settings, and so adds seeds to a
finished one; ``--summarise`` summarises a file's fits again with this version's
summary, without fitting).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import traceback
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import RESULTS, commit, machine, niced_worker  # noqa: E402
from _tree import require_this_tree  # noqa: E402

__all__ = ["load", "one_fit", "recordings"]

EXTERNAL = HERE.parent.parent / "shared" / "external-data"
APPSTAT = EXTERNAL / "appstat2020-harmonic-oscillator"
SMORZAMENTO = EXTERNAL / "smorzamento-spring-disc"
SEGMENTS = ("whole", "first half", "second half")
FITS = ("auto", "default")
FLAGS = (
    "MisfitWarning",
    "ChannelCalibrationWarning",
    "ConvergenceWarning",
    "PriorBoundWarning",
    "FrequencyTrendWarning",
)
Z_AGREE = 1.959964
SPREAD_GOAL = 0.2
#: The goal's largest difference of log-log slopes of ΔE(A), the law's against the
#: turning points', for a fit that says the law holds (exit 0).
SLOPE_GOAL = 0.5


def recordings() -> dict[str, Path]:
    """Every recording of the external data, by a short name."""
    out = {p.stem: p for p in sorted(APPSTAT.glob("HarmOsc*.txt"))}
    for p in sorted(SMORZAMENTO.glob("*.csv")):
        out["smorzamento-" + p.stem.rsplit("_", 1)[-1]] = p
    return out


def _tail(exc: BaseException) -> str:
    text = "".join(traceback.format_exception(exc)).strip().splitlines()
    return "\n".join(text[-6:])


def load(name: str) -> tuple[Any, dict[str, Any]]:
    """The recording ``name`` as a Run, and how it was read."""
    from bayestribo import read_run
    from bayestribo.signal.channels import channel_consistency, check_channels

    path = recordings()[name]
    info: dict[str, Any] = {"path": str(path.relative_to(EXTERNAL.parent.parent))}
    if path.suffix == ".txt":
        run = read_run(
            path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
        )
        info["read"] = (
            'read_run(path, columns=["time_s", "displacement_m"], '
            'metadata={"length_unit": "arbitrary"})'
        )
        info["velocity"] = "none in the file"
        return run, info
    # smorzamento: time;position;velocity;acceleration, the last rows without velocity
    stiffness, mass = (float(v) for v in path.stem.split("_")[-3:-1])
    meta = {"mass_kg": mass}
    columns = ["time_s", "displacement_m", "velocity_m_per_s", "ignore"]
    info.update(
        stated_stiffness_N_per_m=stiffness,
        mass_kg=mass,
        frequency_from_stated_k_and_m_Hz=math.sqrt(stiffness / mass) / (2 * math.pi),
        metadata=meta,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            run = read_run(path, columns=columns, metadata=meta)
            consistency = channel_consistency(run)
            info["channel_consistency"] = None if consistency is None else asdict(consistency)
            check_channels(run)
            info["read"] = f"read_run(path, columns={columns}, metadata={meta})"
            info["velocity"] = "used"
        except Exception as exc:  # the package refuses the velocity: position only
            info["velocity"] = (
                f"refused by the package ({type(exc).__name__}: {exc}); position only"
            )
            columns = ["time_s", "displacement_m", "ignore", "ignore"]
            run = read_run(path, columns=columns, metadata=meta)
            info["read"] = f"read_run(path, columns={columns}, metadata={meta})"
    info["reading_warnings"] = sorted({str(w.message)[:300] for w in caught})
    info["rows_used"] = int(run.time.size)
    return run, info


def segment(run: Any, which: str, cut_s: float | None) -> Any:
    """The whole run, or the half before or after ``cut_s`` (the cut sample in both)."""
    from bayestribo import Run

    if which == "whole":
        return run
    t = run.time
    k = int(np.argmin(np.abs(t - cut_s)))
    keep = slice(0, k + 1) if which == "first half" else slice(k, t.size)
    return Run(
        time=t[keep],
        displacement=None if run.displacement is None else run.displacement[keep],
        velocity=None if run.velocity is None else run.velocity[keep],
        metadata=dict(run.metadata),
    )


def _prepared(run: Any) -> dict[str, Any]:
    """What the package makes of a segment before any fit: its reported amplitudes,
    three amplitudes, reference amplitude, turning points; or its refusal."""
    from bayestribo.inference import prepare
    from bayestribo.inference.dissipation import dissipation_amplitudes

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            p = prepare(run)
        except Exception as exc:
            return {"error": f"{type(exc).__name__}: {exc}", "traceback": _tail(exc)}
    d = p.decay
    ell = float(d.scaling.length_scale)
    turning = np.abs(np.asarray(d.peaks.value, dtype=float))
    swings = 0.5 * (turning[1:] + turning[:-1])  # each half cycle's swing
    reported = dissipation_amplitudes(turning / ell) * ell
    return {
        "length_scale": ell,
        "reference_amplitude": abs(float(p.data.y0)),
        "reported_amplitudes": reported.tolist(),
        "three_amplitudes": {
            "largest": float(swings.max()),
            "median": float(np.median(swings)),
            "smallest": float(swings.min()),
        },
        "turning_times": np.asarray(d.turning_times, dtype=float).tolist(),
        "n_turning_points": int(turning.size),
        "motion_ended": bool(d.motion_ended),
        "release_time_s": float(d.release_time),
        "natural_frequency_Hz": float(d.natural_frequency_Hz),
        "derived_channel": d.derived_channel,
        "prepare_warnings": sorted({f"{w.category.__name__}: {w.message}"[:300] for w in caught}),
    }


def _law_band(result: Any, amplitudes: list[float], reference: float) -> dict[str, Any]:
    """ΔE(A) of the fitted law at any swings (same unit and definition as the reported
    band, :meth:`~bayestribo.model.laws.Law.swing_dissipation`), from 1000 of its
    posterior draws, evenly spaced."""
    from bayestribo.model.laws import get_law

    law = get_law(result.law)
    attrs = result.idata.posterior.attrs
    ell = float(attrs["length_scale"])
    omega = float(attrs["omega"])
    meta = result.metadata
    mass = meta.get("mass_kg")
    k = mass * omega**2 if mass and meta.get("length_unit", "m") == "m" else 1.0
    values = {}
    for name in law.parameter_names:
        if name in result.idata.posterior:
            values[name] = result.samples(name)
        elif name == "mu_k" and "friction_displacement" in result.idata.posterior:
            values[name] = result.samples("friction_displacement") / ell
        else:
            values[name] = np.full(result.samples("y0").size, law.parameter(name).null)
    amps = np.asarray(amplitudes, dtype=float)
    size = next(iter(values.values())).size
    pick = np.linspace(0, size - 1, min(size, 1000)).astype(int)
    values = {n: np.asarray(v)[pick] for n, v in values.items()}
    draws = np.asarray(law.swing_dissipation(amps / ell, values, reference)) * k * ell**2
    draws = draws[np.all(np.isfinite(draws), axis=1)]
    lo, hi = np.quantile(draws, [0.025, 0.975], axis=0)
    return {
        "amplitude": amps.tolist(),
        "mean": draws.mean(axis=0).tolist(),
        "sd": draws.std(axis=0, ddof=1).tolist(),
        "interval": [lo.tolist(), hi.tolist()],
    }


def one_fit(
    name: str,
    which: str,
    cut_s: float | None,
    seed: int,
    probes: list[float],
    max_steps: int,
    kinds: tuple[str, ...] = FITS,
) -> dict[str, Any]:
    """Fit one segment of one recording with law="auto" and the default law (those of
    ``kinds``)."""
    from bayestribo import fit

    out: dict[str, Any] = {"recording": name, "segment": which, "seed": seed}
    run = segment(load(name)[0], which, cut_s)
    reference = None
    for kind in kinds:
        rec: dict[str, Any] = {}
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            start = time.perf_counter()
            try:
                result = fit(
                    run, law="auto" if kind == "auto" else None, seed=seed, max_steps=max_steps
                )
            except Exception as exc:  # recorded: a refusal is a finding
                rec["seconds"] = time.perf_counter() - start
                rec["error"] = f"{type(exc).__name__}: {exc}"
                rec["traceback"] = _tail(exc)
                out[kind] = rec
                continue
            rec["seconds"] = time.perf_counter() - start
        ours = [w for w in caught if w.category.__module__.startswith("bayestribo")]
        rec["warnings"] = sorted(
            {w.category.__name__ for w in ours if w.category.__name__ in FLAGS}
        )
        messages: dict[str, str] = {}
        for w in ours:
            messages.setdefault(w.category.__name__, str(w.message)[:400])
        rec["warning_messages"] = messages
        rec["law"] = result.law
        rec["converged"] = bool(result.converged)
        diag = result.diagnostics
        rec["diagnostics"] = {
            k: diag.get(k) for k in ("n_steps", "rhat_max", "ess_min", "misfit_p", "reasons")
        }
        rec["at_prior_bound"] = result.at_prior_bound
        comparison = result.law_comparison
        if comparison is not None:
            rec["verdict"] = comparison["verdict"]
            rec["best"] = comparison["best"]
            rec["as_good"] = comparison["as_good"]
            rec["adequate"] = bool(comparison["adequate"])
            # the package's own check: the verdict fitted to each half of this segment
            rec["halves"] = comparison.get("halves")
            rec["comparison_notes"] = comparison.get("warnings", [])
            rec["comparison_table"] = {
                law: {
                    k: row.get(k)
                    for k in ("elpd_diff", "dse", "adequate", "converged", "misfit_p", "error")
                    if k in row
                }
                for law, row in comparison["table"].items()
            }
        else:
            rec["adequate"] = "MisfitWarning" not in rec["warnings"]
        rec["parameters"] = {
            n: {"mean": s.mean, "sd": s.sd, "interval": list(s.interval)}
            for n, s in result.summary().items()
        }
        band = result.dissipation
        rec["dissipation"] = {
            # a verdict that mixes laws has no split by term
            k: band.get(k)
            for k in ("amplitude", "mean", "sd", "interval", "unit", "by_term")
        }
        rec["turning_point_dissipation"] = result.turning_point_dissipation
        rec["shape_agreement"] = result.shape_agreement
        rec["slopes"] = slope_check(band, result.turning_point_dissipation)
        if reference is None:
            from bayestribo.inference import prepare

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                reference = abs(float(prepare(run).data.y0))
        own = _law_band(result, band["amplitude"], reference)
        rec["draws_reproduce_band"] = float(
            np.max(
                np.abs(np.array(own["mean"]) - np.array(band["mean"]))
                / np.maximum(np.abs(band["mean"]), 1e-300)
            )
        )
        rec["probes"] = _law_band(result, probes, reference)
        out[kind] = rec
    return out


def _slope(amplitude: np.ndarray, energy: np.ndarray) -> float:
    """Least-squares slope of ln ΔE against ln A (nan with fewer than two usable points)."""
    ok = np.isfinite(amplitude) & np.isfinite(energy) & (amplitude > 0) & (energy > 0)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(amplitude[ok]), np.log(energy[ok]), 1)[0])


def slope_check(band: dict[str, Any], measured: dict[str, Any] | None) -> dict[str, Any] | None:
    """The goal's shape test, computed here from the two means: the log-log slopes of
    the fit's ΔE(A) and of the turning points' ΔE(A) over the analysed (reported)
    amplitudes, their difference, and whether it is within :data:`SLOPE_GOAL`. None
    without a turning-point answer at the same amplitudes."""
    if not measured or not measured.get("amplitude") or not band.get("amplitude"):
        return None
    amp = np.asarray(band["amplitude"], dtype=float)
    if amp.shape != np.shape(measured["amplitude"]) or not np.allclose(
        amp, measured["amplitude"], rtol=1e-9
    ):
        return {"error": "the fit's band and the turning points' are at other amplitudes"}
    law = _slope(amp, np.asarray(band["mean"], dtype=float))
    tp = _slope(amp, np.asarray(measured["mean"], dtype=float))
    difference = abs(law - tp)
    return {
        "amplitude_range": [float(amp.min()), float(amp.max())],
        "law_slope": law,
        "turning_point_slope": tp,
        "difference": difference,
        "within_goal": bool(difference <= SLOPE_GOAL),
    }


# -- analysis --------------------------------------------------------------------------
def _at(probes: dict[str, Any], amplitude: float) -> tuple[float, float, float, float]:
    i = int(np.argmin(np.abs(np.asarray(probes["amplitude"]) - amplitude)))
    return (
        probes["mean"][i],
        probes["sd"][i],
        probes["interval"][0][i],
        probes["interval"][1][i],
    )


def _compare(pred: dict[str, Any], other: dict[str, Any], amplitudes: list[float]) -> dict:
    """The law of one half (its probes) against the other half's own band at
    ``amplitudes`` (amplitudes of the other half's band)."""
    rows = []
    for a in amplitudes:
        m1, s1, _, _ = _at(pred, a)
        m2, s2, lo2, hi2 = _at(other, a)
        z = (m1 - m2) / math.hypot(s1, s2) if (s1 or s2) else math.inf
        rows.append({"amplitude": a, "z": z, "in_interval": bool(lo2 <= m1 <= hi2)})
    zs = [abs(r["z"]) for r in rows]
    return {
        "max_abs_z": max(zs) if zs else None,
        "agree": all(z <= Z_AGREE for z in zs),
        "in_interval": sum(r["in_interval"] for r in rows),
        "of": len(rows),
        "rows": rows,
    }


def _spread(means: list[float], sds: list[float]) -> float | None:
    if len(means) < 2 or not np.all(np.isfinite(means)):
        return None
    sd = float(np.mean(sds))
    return (max(means) - min(means)) / sd if sd > 0 else math.inf


def summarise(records: list[dict[str, Any]], prepared: dict[str, Any]) -> dict[str, Any]:
    """Per recording and segment: laws, adequacy, ΔE at three amplitudes, seed spread;
    per recording: the halves' cross-predictions."""
    table: dict[str, Any] = {}
    for name, prep in prepared.items():
        entry: dict[str, Any] = {"recording": name, "segments": {}, "halves": {}}
        for which in SEGMENTS:
            seg = prep["segments"].get(which, {})
            if "error" in seg:
                entry["segments"][which] = {"refused": seg["error"]}
                continue
            rows = sorted(
                (r for r in records if r["recording"] == name and r["segment"] == which),
                key=lambda r: r["seed"],
            )
            out: dict[str, Any] = {"seeds": [r["seed"] for r in rows]}
            three = seg.get("three_amplitudes", {})
            for kind in FITS:
                fits = [r[kind] for r in rows if kind in r]
                ok = [f for f in fits if "error" not in f]
                s: dict[str, Any] = {
                    "errors": sorted({f["error"] for f in fits if "error" in f}),
                    "laws": [f["law"] for f in ok],
                    "same_law": len({f["law"] for f in ok}) <= 1,
                    "adequate": [f["adequate"] for f in ok],
                    "converged": [f["converged"] for f in ok],
                    "warnings": sorted({w for f in ok for w in f["warnings"]}),
                    "median_seconds": float(np.median([f["seconds"] for f in ok])) if ok else None,
                    "unit": ok[0]["dissipation"]["unit"] if ok else None,
                }
                de: dict[str, Any] = {}
                worst = 0.0
                for label, a in three.items():
                    vals = [_at(f["probes"], a) for f in ok]
                    spread = _spread([v[0] for v in vals], [v[1] for v in vals])
                    de[label] = {
                        "amplitude": a,
                        "mean": [v[0] for v in vals],
                        "sd": [v[1] for v in vals],
                        "interval": [[v[2], v[3]] for v in vals],
                        "seed_spread_in_sd": spread,
                    }
                    if spread is not None:
                        worst = max(worst, spread)
                s["dissipation"] = de
                # the goal's shape test per seed: never "the law holds" (exit 0) with a
                # ΔE(A) whose log-log slope is more than SLOPE_GOAL off the turning points'
                slopes = [f.get("slopes") or {} for f in ok]
                s["slope_difference"] = [sl.get("difference") for sl in slopes]
                # the package's standard error of the turning points' slope (from the
                # relative sds at the two ends of the amplitudes)
                s["turning_point_slope_se"] = [
                    (f.get("shape_agreement") or {}).get("measured_slope_se") for f in ok
                ]
                s["shape_goal_met"] = [
                    (not f["adequate"]) or bool(sl.get("within_goal"))
                    for f, sl in zip(ok, slopes, strict=True)
                ]
                if kind == "auto":
                    # the goal: the law fitted to each half predicts the other's ΔE(A),
                    # or the fit says that no law holds (and gives the law-free ΔE(A))
                    checks = [f.get("halves") or {} for f in ok]
                    s["package_halves"] = [
                        {
                            "tested": h.get("tested"),
                            "agree": h.get("agree"),
                            "largest_z": h.get("largest_z"),
                            "p_value": h.get("p_value"),
                        }
                        for h in checks
                    ]
                    s["halves_goal_met"] = [
                        (not f["adequate"]) or bool(h.get("tested") and h.get("agree"))
                        for f, h in zip(ok, checks, strict=True)
                    ]
                s["max_seed_spread_dissipation"] = worst if len(ok) > 1 else None
                # the answer each fit gives: its law's ΔE(A) when the law holds, the
                # turning points' (law-free) when it says that no law holds
                answers = [
                    f["probes"] if f["adequate"] else f["turning_point_dissipation"] for f in ok
                ]
                adequate = [bool(f["adequate"]) for f in ok]
                s["answer"] = (
                    "law" if all(adequate) else "turning points" if not any(adequate) else "mixed"
                )
                spreads = [
                    _spread([_at(a, amp)[0] for a in answers], [_at(a, amp)[1] for a in answers])
                    for amp in three.values()
                ]
                spreads = [x for x in spreads if x is not None]
                s["max_seed_spread_answer"] = max(spreads) if len(ok) > 1 and spreads else None
                if s["same_law"] and len(ok) > 1:
                    spreads = {}
                    for p in ok[0]["parameters"]:
                        ms = [f["parameters"][p]["mean"] for f in ok if p in f["parameters"]]
                        sds = [f["parameters"][p]["sd"] for f in ok if p in f["parameters"]]
                        spreads[p] = _spread(ms, sds)
                    s["seed_spread_parameters_in_sd"] = spreads
                out[kind] = s
            entry["segments"][which] = out
        # halves: each half's law against the other half's band
        firsts = {
            r["seed"]: r for r in records if r["recording"] == name and r["segment"] == "first half"
        }
        seconds = {
            r["seed"]: r
            for r in records
            if r["recording"] == name and r["segment"] == "second half"
        }
        s1 = prep["segments"].get("first half", {})
        s2 = prep["segments"].get("second half", {})
        if "reported_amplitudes" in s1 and "reported_amplitudes" in s2:
            a1, a2 = s1["reported_amplitudes"], s2["reported_amplitudes"]
            cut = [min(a1), max(a2)]
            shared = [a for a in a2 if min(a1) <= a <= max(a1)] + [
                a for a in a1 if min(a2) <= a <= max(a2)
            ]
            for kind in FITS:
                per_seed = []
                for seed in sorted(set(firsts) & set(seconds)):
                    f1, f2 = firsts[seed].get(kind, {}), seconds[seed].get(kind, {})
                    if "probes" not in f1 or "probes" not in f2:
                        continue
                    per_seed.append(
                        {
                            "seed": seed,
                            "laws": [f1["law"], f2["law"]],
                            "at_cut": _compare(f1["probes"], f2["probes"], cut),
                            "first_predicts_second": _compare(f1["probes"], f2["probes"], a2),
                            "second_predicts_first": _compare(f2["probes"], f1["probes"], a1),
                            "shared_amplitudes": (
                                _compare(f1["probes"], f2["probes"], shared) if shared else None
                            ),
                        }
                    )
                entry["halves"][kind] = {
                    "cut_amplitudes": cut,
                    "shared_amplitudes": shared,
                    "per_seed": per_seed,
                    "agree_at_cut": sum(p["at_cut"]["agree"] for p in per_seed),
                    "first_predicts_second": sum(
                        p["first_predicts_second"]["agree"] for p in per_seed
                    ),
                    "second_predicts_first": sum(
                        p["second_predicts_first"]["agree"] for p in per_seed
                    ),
                    "seeds": len(per_seed),
                }
        entry["goal"] = {
            which: goal(seg["auto"])
            for which, seg in entry["segments"].items()
            if seg.get("auto") and seg["auto"]["laws"]
        }
        table[name] = entry
    return table


def goal(s: dict[str, Any]) -> dict[str, Any]:
    """Issue 39's goal on one segment's ``law="auto"`` fits over the seeds (a summary of
    :func:`summarise`): each seed's exit status (0 when the law holds, 1 with the
    turning points' ΔE(A)), every seed converged, the answer's and the laws' seed spread
    below :data:`SPREAD_GOAL` (the law's band when every seed chose the same law), the
    halves agreeing or the law flagged, and never exit 0 with a law whose log-log slope
    of ΔE(A) is more than :data:`SLOPE_GOAL` off the turning points'. ``met`` lists the
    criteria met; ``failed`` the others."""
    answer = s.get("max_seed_spread_answer")
    laws = s.get("max_seed_spread_dissipation")
    params = s.get("seed_spread_parameters_in_sd") or {}
    criteria = {
        "answer with ΔE(A)": not s["errors"],
        "converged": all(s["converged"]),
        "seed-stable answer": answer is None or answer < SPREAD_GOAL,
        "same law on every seed": s["same_law"],
        # the band of one law over the seeds (apart across two laws, it says nothing more)
        "seed-stable law band": not s["same_law"] or laws is None or laws < SPREAD_GOAL,
        "seed-stable parameters": all(v is None or v < SPREAD_GOAL for v in params.values()),
        "halves agree or law flagged": all(s.get("halves_goal_met") or [False]),
        "no exit 0 with another shape": all(s.get("shape_goal_met") or [True]),
    }
    diffs = [d for d in s.get("slope_difference", []) if d is not None]
    return {
        "exit": [0 if a else 1 for a in s["adequate"]],
        "laws": s["laws"],
        "answer_seed_spread_sd": answer,
        "law_band_seed_spread_sd": laws,
        "parameters_seed_spread_sd": max(
            (v for v in params.values() if v is not None), default=None
        ),
        "largest_slope_difference": max(diffs) if diffs else None,
        "turning_point_slope_se": s.get("turning_point_slope_se"),
        "met": [k for k, v in criteria.items() if v],
        "failed": [k for k, v in criteria.items() if not v],
    }


def _fmt(x: float | None, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def _laws_text(laws: list[str]) -> str:
    counts: dict[str, int] = {}
    for law in laws:
        counts[law] = counts.get(law, 0) + 1
    return ", ".join(f"{k}×{v}" for k, v in counts.items()) or "-"


def _print_table(table: dict[str, Any], prepared: dict[str, Any]) -> None:
    print(
        "\nPer recording and segment: the laws chosen (auto) and the default law; adequate "
        "and converged seeds; ΔE(A) at the largest, median and smallest swing (mean over "
        "seeds); seed spread = (max - min of the means)/posterior sd (goal < 0.2)"
    )
    for name, entry in table.items():
        info = prepared[name]
        if "error" in info:
            print(f"\n{name}: REFUSED {info['error']}")
            continue
        print(f"\n{name}  ({info['read_info'].get('velocity')})")
        for which, s in entry["segments"].items():
            if "refused" in s:
                print(f"  {which:12s} REFUSED: {s['refused'][:200]}")
                continue
            for kind in FITS:
                k = s.get(kind)
                if not k:
                    continue
                if k["errors"] and not k["laws"]:
                    print(f"  {which:12s} {kind:7s} ERROR: {k['errors'][0][:200]}")
                    continue
                de = k["dissipation"]
                cells = " ".join(
                    f"{lab[0]}:{_fmt(float(np.mean(d['mean'])) if d['mean'] else None)}"
                    for lab, d in de.items()
                )
                spread = k["max_seed_spread_dissipation"]
                flag = "" if spread is None or spread < SPREAD_GOAL else " (>0.2)"
                answer = k.get("max_seed_spread_answer")
                answer_text = f"  answer ({k.get('answer')}) spread {_fmt(answer, '.2f')}"
                goal = k.get("halves_goal_met")
                halves = f"  halves-or-no-law {sum(goal)}/{len(goal)}" if goal is not None else ""
                diffs = [d for d in k.get("slope_difference", []) if d is not None]
                shape = k.get("shape_goal_met", [])
                halves += (
                    f"  |Δslope| ≤ {_fmt(max(diffs), '.2f')} shape-goal {sum(shape)}/{len(shape)}"
                    if diffs
                    else ""
                )
                print(
                    f"  {which:12s} {kind:7s} {_laws_text(k['laws']):42s} "
                    f"adeq {sum(map(bool, k['adequate']))}/{len(k['adequate'])} "
                    f"conv {sum(k['converged'])}/{len(k['converged'])}  ΔE [{k['unit']}] {cells}"
                    f"  spread {_fmt(spread, '.2f')}{flag}{answer_text}{halves}  "
                    f"{_fmt(k['median_seconds'], '.0f')} s"
                    + (
                        f"  warn {','.join(w.removesuffix('Warning') for w in k['warnings'])}"
                        if k["warnings"]
                        else ""
                    )
                    + (f"  errors {len(k['errors'])}" if k["errors"] else "")
                )
    print(
        "\nIssue 39's goal per recording and segment (law='auto' over the seeds): exit "
        "status per seed, the criteria failed"
    )
    for name, entry in table.items():
        for which, g in entry.get("goal", {}).items():
            failed = "; ".join(g["failed"]) or "every criterion met"
            print(
                f"{name:16s} {which:12s} exit {g['exit']} {_laws_text(g['laws']):30s} "
                f"answer spread {_fmt(g['answer_seed_spread_sd'], '.2f')} sd, law band "
                f"{_fmt(g['law_band_seed_spread_sd'], '.2f')} sd, |Δslope| "
                f"{_fmt(g['largest_slope_difference'], '.2f')}: {failed}"
            )
    print(
        "\nHalves: seeds whose law of one half agrees with the other half's ΔE(A) band "
        "(|z| <= 1.96 at every amplitude): at the cut, and over the other half's amplitudes"
    )
    print(f"{'recording':16s} {'fit':7s} {'at cut':>7s} {'1st→2nd':>8s} {'2nd→1st':>8s}  max|z|")
    for name, entry in table.items():
        for kind, h in entry["halves"].items():
            n = h["seeds"]
            zs = [
                (
                    p["at_cut"]["max_abs_z"],
                    p["first_predicts_second"]["max_abs_z"],
                    p["second_predicts_first"]["max_abs_z"],
                )
                for p in h["per_seed"]
            ]
            worst = " / ".join(_fmt(max(z[i] for z in zs), ".1f") for i in range(3)) if zs else "-"
            print(
                f"{name:16s} {kind:7s} {h['agree_at_cut']:3d}/{n:<3d} "
                f"{h['first_predicts_second']:4d}/{n:<3d} {h['second_predicts_first']:4d}/{n:<3d}"
                f"  {worst}"
            )


def output_path(name: str) -> Path:
    """``results/NAME.json``, or ``name`` itself when it is a path ending in .json."""
    return Path(name) if name.endswith(".json") else RESULTS / f"{name}.json"


def write_json(path: Path, results: dict[str, Any]) -> Path:
    """Write ``results`` with the machine description (atomically)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps({"machine": machine(), **results}, indent=2) + "\n")
    tmp.replace(path)
    return path


def resummarise(path: Path) -> int:
    """Summarise the fits of ``path`` again with this version's :func:`summarise`
    (the fits, their settings and source kept; ``summarised_at`` records the commit of
    the summary) and print the table."""
    old = json.loads(path.read_text())  # its "machine" kept: the one the fits ran on
    old["table"] = summarise(old["fits"], old["prepared"])
    old["summarised_at"] = commit()
    write_json(path, old)
    _print_table(old["table"], old["prepared"])
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    names = list(recordings())
    parser.add_argument("--seeds", type=int, default=5, help="seeds per segment (1, 2, ...)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--max-steps", type=int, default=20_000)
    parser.add_argument("--recordings", nargs="*", default=names, choices=names)
    parser.add_argument("--segments", nargs="*", default=list(SEGMENTS), choices=list(SEGMENTS))
    parser.add_argument("--fits", nargs="*", default=list(FITS), choices=list(FITS))
    parser.add_argument(
        "--output", default="real", help="results/NAME.json, or a path ending in .json"
    )
    parser.add_argument(
        "--resume", action="store_true", help="keep the fits of an interrupted output file"
    )
    parser.add_argument(
        "--summarise",
        action="store_true",
        help="summarise the fits of the output file again (no fit) and print its table",
    )
    args = parser.parse_args(argv)
    if args.summarise:
        return resummarise(output_path(args.output))
    import bayestribo

    start = time.perf_counter()
    load_start = os.getloadavg()
    source = {
        "commit": commit(),
        "package_version": bayestribo.__version__,
        "module": require_this_tree(),
    }
    seeds = list(range(1, args.seeds + 1))
    settings = {
        "seeds": seeds,
        "max_steps": args.max_steps,
        "workers": args.workers,
        "n_walkers": 16,
        "n_ensembles": 2,
        "segments": args.segments,
        "fits": args.fits,
        "recordings": {
            n: str(recordings()[n].relative_to(EXTERNAL.parent.parent)) for n in args.recordings
        },
        "halves": "cut at the middle turning point of the whole's analysed decay",
        "agree": "|z| <= 1.96 at every amplitude compared",
        "spread_goal_sd": SPREAD_GOAL,
    }
    # -- what the package makes of each recording and segment, before any fit --
    prepared: dict[str, Any] = {}
    jobs = []
    for name in args.recordings:
        try:
            run, info = load(name)
        except Exception as exc:
            prepared[name] = {"error": f"{type(exc).__name__}: {exc}", "traceback": _tail(exc)}
            continue
        whole = _prepared(run)
        entry = {"read_info": info, "segments": {"whole": whole}, "cut_s": None}
        if "error" not in whole:
            times = whole["turning_times"]
            entry["cut_s"] = float(times[(len(times) - 1) // 2])
            for which in SEGMENTS[1:]:
                entry["segments"][which] = _prepared(segment(run, which, entry["cut_s"]))
        probes = sorted(
            {
                a
                for seg in entry["segments"].values()
                if "error" not in seg
                for a in [*seg["reported_amplitudes"], *seg["three_amplitudes"].values()]
            }
        )
        entry["probe_amplitudes"] = probes
        prepared[name] = entry
        for which in args.segments:
            if "error" in entry["segments"].get(which, {"error": "not prepared"}):
                continue
            for seed in seeds:
                jobs.append((name, which, entry["cut_s"], seed, probes))
        seg_text = ", ".join(
            f"{w}: {'REFUSED' if 'error' in s else str(s['n_turning_points']) + ' swings'}"
            for w, s in entry["segments"].items()
        )
        print(f"{name}: {info.get('velocity')}; {seg_text}", flush=True)
    output = output_path(args.output)
    records: list[dict[str, Any]] = []
    if args.resume and output.is_file():
        old = json.loads(output.read_text())
        if old.get("settings", {}).get("max_steps") == args.max_steps:
            wanted = {(j[0], j[1], j[3]) for j in jobs}
            records = [
                r
                for r in old.get("fits", [])
                if (r["recording"], r["segment"], r["seed"]) in wanted
            ]
            done = {(r["recording"], r["segment"], r["seed"]) for r in records}
            jobs = [j for j in jobs if (j[0], j[1], j[3]) not in done]
            print(f"resumed {len(records)} fits from {output}", flush=True)
    # seeds in turn, so that an interrupted file holds every recording; long ones first
    jobs.sort(key=lambda j: (j[3], -len(prepared[j[0]]["segments"]["whole"]["turning_times"])))
    print(
        f"{len(jobs)} segment fits (auto and default) on {args.workers} workers, "
        f"load average {load_start[0]:.2f}",
        flush=True,
    )

    def write(complete: bool) -> Path:
        records.sort(key=lambda r: (r["recording"], SEGMENTS.index(r["segment"]), r["seed"]))
        return write_json(
            output,
            {
                "complete": complete,
                "settings": settings,
                "source": source,
                "wall_seconds": time.perf_counter() - start,
                "load_average_start": list(load_start),
                "load_average_now": list(os.getloadavg()),
                "prepared": prepared,
                "table": summarise(records, prepared),
                "fits": records,
            },
        )

    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        futures = {
            pool.submit(one_fit, n, w, c, s, p, args.max_steps, tuple(args.fits)): (n, w, s)
            for n, w, c, s, p in jobs
        }
        for k, future in enumerate(as_completed(futures), 1):
            n, w, s = futures[future]
            try:
                rec = future.result()
            except Exception as exc:  # a worker that died: recorded, the others go on
                err = {"error": f"worker died: {_tail(exc)}"}
                rec = {"recording": n, "segment": w, "seed": s, "auto": err, "default": err}
            records.append(rec)
            a = rec.get("auto", {})
            print(
                f"{k}/{len(jobs)} {n} {w} seed {s}: auto {a.get('law', a.get('error', '?'))[:80]}"
                f" ({a.get('seconds', 0):.0f} s), {time.perf_counter() - start:.0f} s, "
                f"load {os.getloadavg()[0]:.2f}",
                flush=True,
            )
            write(False)
    path = write(True)
    _print_table(summarise(records, prepared), prepared)
    print(f"\nwall {time.perf_counter() - start:.0f} s; wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
