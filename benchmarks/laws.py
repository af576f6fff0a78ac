"""Every dissipation law, simulated independently: coverage of its fit, and what law="auto" chooses.

Each run comes from the independent simulator of ``benchmarks/_laws_sim.py``
(``scipy.integrate.solve_ivp`` half cycle by half cycle, nothing from the package) on
the paper's rig (m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, so ℓ = N/k = 0.211 mm),
released from x₀ at rest after 0.1 s of rest, sampled at 5 kHz, with white noise of
10x or 30x the vibrometer's resolution (0.15 µm, 0.015 µm/s) on both channels. A law
with friction is recorded until 0.2 s after it stops; one without friction for 4 s
after the release. The cases (γ "s %": the quadratic drag dissipates s % of the
viscous loss at x₀; ζ_α at x₀; η: μ(A) = μ_k + ηA grows 30 % from the end of the decay
to x₀):

=========================  ===============================================================
viscous                    ζ = 0.01, x₀ = 2 mm
coulomb                    μ_k = 0.02, μ_s/μ_k = 1.5, x₀ = 1.5 mm
quadratic                  γ with the loss of ζ = 0.02 at x₀ = 2 mm (γ = 0.0050)
power                      ζ_α = 0.01 at x₀ = 2 mm, α = 1.5
hysteretic                 η = 0.015 (alone: a friction η|X_n|, no Coulomb), x₀ = 2 mm
viscous+coulomb            ζ = 0.005, μ_k = 0.02, μ_s/μ_k = 1.5, x₀ = 2 mm
viscous+coulomb+quadratic  ζ = 0.01, μ_k = 0.015, μ_s/μ_k = 1.3, γ 50 %, x₀ = 2 mm
coulomb+hysteretic         μ_k = 0.02, μ_s/μ_k = 1.5, η 30 %, x₀ = 2 mm
coulomb+power              μ_k = 0.01, μ_s/μ_k = 1.5, ζ_α = 0.01, α = 1.5, x₀ = 2 mm
viscous+quadratic          ζ = 0.01, γ 100 %, x₀ = 1.5 mm
stribeck (not registered)  ζ = 0.005 and μ(v) = μ_k + (μ_s - μ_k) exp(-|v|/v_s), μ_k = 0.02,
                           μ_s = 0.03, v_s = 0.05 m/s (the peak speed at x₀ = 2 mm is 0.41 m/s)
=========================  ===============================================================

Each run is fitted (16 walkers x 2 ensembles, at most ``--max-steps`` steps):

* with the true law (not for ``stribeck``, which has none; it gets the default law
  instead): the 95 % interval of each sampled parameter against the truth (ζ_α at the
  fit's reference amplitude, the observed |y0| of ``bayestribo.inference.prepare``),
  z = (mean - truth)/sd. The dimensionless ζ, γ = qℓ, η and ζ_α depend on the frame
  (τ = Ωt, ℓ = N/(mΩ²)): the truth is in the true frame (Ω = 2π 32.6 Hz); the package
  measures the natural frequency from the record, and a nonlinear law's fit moves to
  the frequency at which the law's own turning times keep step with the record's
  (``law_frequency``; the record's is 3e-4 off for quadratic drag), so coverage and z
  are also given against the truth in the frame the fit ends in (its ``omega``: what a
  fit with an exact frequency would cover); and the 95 % band of ΔE(A) at each of its 12 reported
  amplitudes against the true ΔE(A) = ``get_law(law).dissipation`` of the true
  parameters times kℓ² [J] (for ``stribeck``: the quadrature of the true force over a
  harmonic cycle), z likewise;
* with ``law="auto"``: the chosen law. It is *right* when it is the true law, or a law
  nesting it whose extra terms hold zero: the 95 % highest-density interval of each
  extra term's amount (ζ, μ_k, γ, ζ_α, η, c₃) contains 0 (for a parameter bounded at
  0: the interval starts within the lowest 1 % of the draws). The chosen law's ΔE(A)
  band is checked against the truth as above; a run is **silently wrong** when that
  band misses the true ΔE(A) at one amplitude or more while the comparison says the
  law is adequate, the fit converged and no bayestribo warning (Misfit, Convergence,
  PriorBound, ChannelCalibration) was raised. A calibrated band misses somewhere among
  its 12 (strongly correlated) amplitudes in well over 5 % of runs by chance; the
  stricter *confidently* silently wrong count asks |z| > 3.29 at some amplitude.

Coverage rates carry Clopper-Pearson 95 % intervals; sd(z) its standard error
sd/√(2(n-1)). Exceptions from bayestribo are recorded with their traceback's last lines.

``--true-law-only`` leaves out the auto fit (minutes a run; the true-law fit takes
seconds), so that a law gets the tens of runs its calibration needs: the per-law table
of ``benchmarks/_laws_calibration.py`` has one z per run and quantity (each parameter,
ΔE at the smallest, middle and largest reported swing), never an sd over a run's
strongly correlated swings.

The runs are seeded: run ``index`` of ``case`` at ``noise`` draws its noise from
``numpy.random.default_rng([seed, crc32(case), 100 noise, index])``;
``one_run(case, noise, index, seed, max_steps)`` repeats it.

Run (by hand)::

    timeout 5400 nice -n 10 python benchmarks/laws.py --runs 6 --workers 2
    timeout 5000 nice -n 10 python benchmarks/laws.py --true-law-only --runs 60 \
        --levels 10 --workers 1 --seed 2012 --resume      # laws_calibration.json

Writes ``benchmarks/results/laws.json`` (``--output NAME``: ``NAME.json``) after every
run (``"complete": false`` until the end; ``--resume`` keeps the runs of an
interrupted file with the same settings; with ``--true-law-only``, ``laws_calibration.json``),
with the machine description, the package's commit, the settings, the table, the
confusion matrix, the per-law calibration and every run. ``--retable NAME`` rewrites
a finished file's tables from its runs with this code; ``--pool`` pools files of
distinct seeds.
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
import zlib
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _laws_calibration import calibration, print_calibration  # noqa: E402
from _laws_calibration import rate as _rate  # noqa: E402
from _laws_calibration import z_stats as _z_stats  # noqa: E402
from _laws_sim import (  # noqa: E402
    ELL,
    LOAD,
    MASS,
    OMEGA,
    RESOLUTION_V,
    RESOLUTION_X,
    Truth,
    harmonic_power_integral,
    metadata,
    simulate,
    true_dissipation,
)
from _machine import RESULTS, commit, machine, niced_worker  # noqa: E402
from _tree import require_this_tree  # noqa: E402

__all__ = ["CASES", "one_run", "summarise"]

NOISE_LEVELS = (10.0, 30.0)
FS = 5000.0
REST_BEFORE_S = 0.1
REST_AFTER_S = 0.2
DURATION_S = 4.0  # a law without friction: seconds recorded after the release
Z_CONFIDENT = 3.2905  # two-sided 99.9 % of the normal
#: Warnings that say the result is not to be trusted as it is.
FLAGS = ("MisfitWarning", "ChannelCalibrationWarning", "ConvergenceWarning", "PriorBoundWarning")
#: Each term's amount: the parameter whose null (0) removes the term.
AMOUNT = {
    "viscous": "zeta",
    "coulomb": "mu_k",
    "quadratic": "c2",
    "power": "zeta_alpha",
    "hysteretic": "eta",
    "cubic": "c3",
}
#: Parameters that may take either sign (the others are bounded below by their null).
SIGNED = frozenset({"eta"})
DEFAULT_LAW = "viscous+coulomb"


def _gamma_share(share: float, zeta: float, x0: float) -> float:
    """q [1/m] whose quadratic loss at x₀ is ``share`` of the viscous loss of ζ:
    (8/3) γ A³ = share 2πζA² with γ = qℓ, A = x₀/ℓ."""
    a0 = x0 / ELL
    return share * 2.0 * math.pi * zeta * 3.0 / (8.0 * a0) / ELL


def _power_b(zeta_alpha: float, alpha: float, x0: float) -> float:
    """b [m^(1-α) s^(α-2)] of a power drag whose ΔE at x₀ equals that of ζ_α."""
    a0 = x0 / ELL
    c = 2.0 * math.pi * zeta_alpha * a0 ** (1.0 - alpha) / harmonic_power_integral(alpha + 1.0)
    return c * ELL * OMEGA**2 / (ELL * OMEGA) ** alpha


def _eta_growth(growth: float, mu_k: float, x0: float) -> float:
    """η for μ(A) = μ_k + ηA growing by ``growth`` from A → 0 to x₀."""
    return growth * mu_k / (x0 / ELL)


#: case -> (true law or None, Truth, x₀ [m], kind).
CASES: dict[str, tuple[str | None, Truth, float, str]] = {
    "viscous": ("viscous", Truth(zeta=0.01), 2e-3, "single"),
    "coulomb": ("coulomb", Truth(mu_k=0.02, static_ratio=1.5), 1.5e-3, "single"),
    "quadratic": ("quadratic", Truth(q=_gamma_share(1.0, 0.02, 2e-3)), 2e-3, "single"),
    "power": ("power", Truth(b=_power_b(0.01, 1.5, 2e-3), alpha=1.5), 2e-3, "single"),
    "hysteretic": ("hysteretic", Truth(eta=0.015), 2e-3, "single"),
    # a power drag below α = 1: six turning points, then an overdamped creep from
    # ~85 µm towards the centre, recorded to the end of the record
    "power-creep": ("power", Truth(b=_power_b(0.1, 0.5, 2e-3), alpha=0.5), 2e-3, "single"),
    # the same at α = 0.7: a longer decay, a creep that holds less of the energy
    "power-creep-0.7": ("power", Truth(b=_power_b(0.1, 0.7, 2e-3), alpha=0.7), 2e-3, "single"),
    "viscous+coulomb": (
        "viscous+coulomb",
        Truth(zeta=0.005, mu_k=0.02, static_ratio=1.5),
        2e-3,
        "combination",
    ),
    "viscous+coulomb+quadratic": (
        "viscous+coulomb+quadratic",
        Truth(zeta=0.01, mu_k=0.015, static_ratio=1.3, q=_gamma_share(0.5, 0.01, 2e-3)),
        2e-3,
        "combination",
    ),
    "coulomb+hysteretic": (
        "coulomb+hysteretic",
        Truth(mu_k=0.02, static_ratio=1.5, eta=_eta_growth(0.3, 0.02, 2e-3)),
        2e-3,
        "combination",
    ),
    "coulomb+power": (
        "coulomb+power",
        Truth(mu_k=0.01, static_ratio=1.5, b=_power_b(0.01, 1.5, 2e-3), alpha=1.5),
        2e-3,
        "combination",
    ),
    "viscous+quadratic": (
        "viscous+quadratic",
        Truth(zeta=0.01, q=_gamma_share(1.0, 0.01, 1.5e-3)),
        1.5e-3,
        "combination",
    ),
    "stribeck": (
        None,
        Truth(zeta=0.005, mu_k=0.02, mu_s_stribeck=0.03, v_s=0.05),
        2e-3,
        "unregistered",
    ),
}

NOTES = """\
true-law fit: coverage of each sampled parameter's 95 % interval and of the 95 % ΔE(A)
  band at the middle of the 12 reported swings [Clopper-Pearson 95 %]; sd(z) ± se (1 if
  calibrated), one z per run (a run's swings are strongly correlated: an sd over them
  is no calibration statistic); all-A = runs covered at every swing; the per-law table
  (calibration) adds the smallest and largest swings; stribeck has no true law: its
  row is the default law
auto: right = the true law, or a law nesting it whose extra terms' 95 % HDI hold 0;
  ΔE cov = the chosen law's band against the true ΔE(A) (the energy the true motion
  loses per cycle at each swing, solve_ivp); TP cov = the ΔE(A) measured from the
  turning points; eqv = not right, but the true law (or one nesting it) is among the
  laws as good as the verdict (the data do not tell them apart); SILENT = band misses
  the truth at some amplitude while adequate, converged and no warning (CONF: |z| >
  3.29 there)"""


def case_record(case: str, noise: float, seed: Any) -> tuple[Any, dict[str, Any]]:
    """The run of ``case`` simulated independently (:func:`_laws_sim.simulate` at the
    benchmark's rate, rests and duration) with ``noise`` times the resolution, and the
    simulation's facts.

    Parameters
    ----------
    case : str
        A key of :data:`CASES`.
    noise : float
        Noise level, in multiples of the vibrometer's resolution.
    seed : int or sequence of int
        The simulation's entropy (:func:`_entropy` for the benchmark's runs).

    Returns
    -------
    (Run, dict)
    """
    from bayestribo.io.run import Run

    _law, truth, x0, _kind = CASES[case]
    t, xs, vs, facts = simulate(
        truth,
        x0=x0,
        fs=FS,
        rest_before=REST_BEFORE_S,
        rest_after=REST_AFTER_S,
        duration=DURATION_S,
        noise=noise,
        seed=seed,
    )
    return Run(time=t, displacement=xs, velocity=vs, metadata=metadata()), facts


def _entropy(case: str, noise: float, index: int, seed: int) -> list[int]:
    return [seed, zlib.crc32(case.encode()), round(100 * noise), index]


def _tail(exc: BaseException) -> str:
    lines = traceback.format_exception(exc)
    text = "".join(lines).strip().splitlines()
    return "\n".join(text[-6:])


def _flags(caught: list) -> tuple[list[str], dict[str, str]]:
    ours = [w for w in caught if w.category.__module__.startswith("bayestribo")]
    names = sorted({w.category.__name__ for w in ours if w.category.__name__ in FLAGS})
    messages: dict[str, str] = {}
    for w in ours:
        messages.setdefault(w.category.__name__, str(w.message)[:300])
    return names, messages


def _hdi(draws: np.ndarray, prob: float = 0.95) -> tuple[float, float, int]:
    """Shortest interval holding ``prob`` of the draws, and the rank of its lower end."""
    s = np.sort(draws)
    n = s.size
    m = math.ceil(prob * n)
    widths = s[m - 1 :] - s[: n - m + 1]
    i = int(np.argmin(widths))
    return float(s[i]), float(s[i + m - 1]), i


def _holds_zero(name: str, draws: np.ndarray) -> dict[str, Any]:
    lo, hi, rank = _hdi(draws)
    if name in SIGNED:
        holds = lo <= 0.0 <= hi
    else:
        holds = rank <= 0.01 * draws.size
    return {"hdi95": [lo, hi], "lower_rank_fraction": rank / draws.size, "holds_zero": holds}


def _dissipation_check(result: Any, truth_fn: Any) -> dict[str, Any]:
    """The fit's ΔE(A) band against the true ΔE(A) at its reported amplitudes."""
    d = result.dissipation
    amps = np.asarray(d["amplitude"], dtype=float)
    true = np.asarray(truth_fn(amps), dtype=float)
    mean = np.asarray(d["mean"], dtype=float)
    sd = np.asarray(d["sd"], dtype=float)
    lo, hi = (np.asarray(b, dtype=float) for b in d["interval"])
    z = (mean - true) / sd
    measured = getattr(result, "turning_point_dissipation", None)
    tp = None
    if measured:
        m_mean = np.array([np.nan if v is None else v for v in measured["mean"]], dtype=float)
        m_sd = np.array([np.nan if v is None else v for v in measured["sd"]], dtype=float)
        m_lo, m_hi = (
            np.array([np.nan if v is None else v for v in b], dtype=float)
            for b in measured["interval"]
        )
        tp = {
            "mean": m_mean.tolist(),
            "sd": m_sd.tolist(),
            "covered": [bool(a <= t <= b) for a, t, b in zip(m_lo, true, m_hi, strict=True)],
            "z": ((m_mean - true) / m_sd).tolist(),
        }
    return {
        "turning_points": tp,
        "unit": d["unit"],
        "amplitude_m": amps.tolist(),
        "truth": true.tolist(),
        "mean": mean.tolist(),
        "sd": sd.tolist(),
        "interval": [lo.tolist(), hi.tolist()],
        "covered": [bool(a <= t <= b) for a, t, b in zip(lo, true, hi, strict=True)],
        "z": z.tolist(),
        "max_abs_z": float(np.max(np.abs(z))),
    }


def _fit(run: Any, law: str, seed: int, max_steps: int) -> tuple[Any, dict[str, Any]]:
    """One fit, timed, its flags recorded; (result or None, record)."""
    from bayestribo import fit

    out: dict[str, Any] = {"law_asked": law, "seed": seed}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        start = time.perf_counter()
        try:
            result = fit(run, law=law, seed=seed, max_steps=max_steps)
        except Exception as exc:  # recorded and reported, never silently dropped
            out["seconds"] = time.perf_counter() - start
            out["error"] = f"{type(exc).__name__}: {exc}"
            out["traceback"] = _tail(exc)
            return None, out
        out["seconds"] = time.perf_counter() - start
    out["warnings"], out["warning_messages"] = _flags(caught)
    out["law"] = result.law
    out["converged"] = bool(result.converged)
    out["at_prior_bound"] = result.at_prior_bound
    attrs = result.idata.posterior.attrs
    out["omega"] = float(attrs["omega"])
    out["frequency_trend"] = json.loads(attrs.get("frequency_trend_json", "null"))
    out["law_frequency_change"] = float(attrs.get("law_frequency_change", math.nan))
    out["frequency_nuisance_sd"] = float(attrs.get("frequency_nuisance_sd", math.nan))
    return result, out


def _truth_function(case: str, reference_m: float) -> Any:
    """True ΔE(A) [J] at swings in metres, from the independent simulator: the energy
    the true motion loses per cycle at each swing (solve_ivp through the half cycle,
    :func:`_laws_sim.true_dissipation`), for registered laws and others alike."""
    _law, truth, _x0, _kind = CASES[case]
    return lambda amps: true_dissipation(truth, amps)


def one_run(
    case: str, noise: float, index: int, seed: int, max_steps: int, auto: bool = True
) -> dict[str, Any]:
    """Simulate run ``index`` of ``case`` at ``noise`` x the resolution; fit it with the
    true law (or the default one) and, unless ``auto`` is False, with law="auto"; check
    both against the truth."""
    from bayestribo.inference import prepare
    from bayestribo.model.laws import get_law

    law, truth, x0, kind = CASES[case]
    entropy = _entropy(case, noise, index, seed)
    fit_seeds = np.random.default_rng([*entropy, 1]).integers(2**31, size=2)
    out: dict[str, Any] = {
        "case": case,
        "kind": kind,
        "noise": noise,
        "index": index,
        "entropy": entropy,
    }
    start = time.perf_counter()
    run, facts = case_record(case, noise, entropy)
    out["simulation"] = {**facts, "seconds": time.perf_counter() - start}
    omega = OMEGA
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prepared = prepare(run)
        omega = float(prepared.decay.scaling.omega)
        reference_m = abs(float(prepared.data.y0)) * float(prepared.decay.scaling.length_scale)
    except Exception as exc:
        out["prepare_error"] = f"{type(exc).__name__}: {exc}"
        out["prepare_traceback"] = _tail(exc)
        reference_m = x0
    # the record's frame: its Ω is the natural frequency measured from the record,
    # ℓ = N/(mΩ²); a nonlinear law's fit moves to the frame of the law's own turning
    # times (bayestribo.inference.pipeline.law_frequency, attrs["omega"]): the package
    # frame of its parameters is that one, taken from the fit below
    out["package_frame"] = {
        "record_omega_over_true": omega / OMEGA,
        "reference_amplitude_m": reference_m,
    }
    truth_fn = _truth_function(case, reference_m)
    values = truth.dimensionless(reference_m)

    # -- the true law (the default law for a law that is not registered) --
    asked = law or DEFAULT_LAW
    result, rec = _fit(run, asked, int(fit_seeds[0]), max_steps)
    if result is not None:
        if law is not None:
            params = {}
            for name in get_law(law).parameter_names:
                draws = result.samples(name)
                mean, sd = float(np.mean(draws)), float(np.std(draws, ddof=1))
                lo, hi = result.interval(name, 0.95)
                params[name] = {
                    "truth": values[name],
                    "mean": mean,
                    "sd": sd,
                    "interval": [float(lo), float(hi)],
                    "covered": bool(lo <= values[name] <= hi),
                    "z": (mean - values[name]) / sd,
                }
            rec["parameters"] = params
        rec["dissipation"] = _dissipation_check(result, truth_fn)
    out["true_fit" if law is not None else "default_fit"] = rec
    # the truth in the package's frame, the Ω the fit ends in: what the fit would
    # cover if that frequency were exact
    in_fit_frame(out)
    if not auto:
        out["seconds"] = time.perf_counter() - start
        return out

    # -- law="auto" --
    result, rec = _fit(run, "auto", int(fit_seeds[1]), max_steps)
    if result is not None:
        comparison = result.law_comparison or {}
        rec["verdict"] = comparison.get("verdict")
        rec["best"] = comparison.get("best")
        rec["as_good"] = comparison.get("as_good")
        rec["adequate"] = bool(comparison.get("adequate"))
        rec["comparison_notes"] = comparison.get("warnings", [])
        rec["comparison_table"] = {
            name: {
                k: row.get(k)
                for k in ("law", "elpd_diff", "dse", "adequate", "converged", "misfit_p", "error")
                if k in row
            }
            for name, row in (comparison.get("table") or {}).items()
        }
        chosen = get_law(result.law)
        rec["dissipation"] = _dissipation_check(result, truth_fn)
        if law is not None:
            true_law = get_law(law)
            extra = [t for t in chosen.term_names if t not in true_law.term_names]
            rec["extra_terms"] = {
                term: _holds_zero(AMOUNT[term], result.samples(AMOUNT[term])) for term in extra
            }
            if chosen.name == true_law.name:
                rec["right"], rec["how"] = True, "true law"
            elif chosen.nests(true_law) and all(
                e["holds_zero"] for e in rec["extra_terms"].values()
            ):
                rec["right"], rec["how"] = True, "nesting, extra terms hold 0"
            elif chosen.nests(true_law):
                rec["right"], rec["how"] = False, "nesting, an extra term away from 0"
            else:
                rec["right"], rec["how"] = False, "does not nest the truth"
            # the true law (or one nesting it) among the laws as good as the verdict:
            # the data do not tell them apart, and the verdict named it
            rec["true_law_as_good"] = any(
                get_law(g).nests(true_law) for g in (rec["as_good"] or []) if g != "free"
            )
        d = rec["dissipation"]
        quiet = rec["adequate"] and rec["converged"] and not rec["warnings"]
        rec["silently_wrong"] = bool(quiet and not all(d["covered"]))
        rec["confidently_silently_wrong"] = bool(quiet and d["max_abs_z"] > Z_CONFIDENT)
    out["auto_fit"] = rec
    out["seconds"] = time.perf_counter() - start
    return out


# -- the table -------------------------------------------------------------------------
def _band_stats(recs: list[dict[str, Any]]) -> dict[str, Any]:
    fitted = [r["dissipation"] for r in recs if "dissipation" in r]
    if not fitted:
        return {}
    cov = [c for d in fitted for c in d["covered"]]
    # one z per run, at the middle swing: a run's 12 swings are strongly correlated
    # (viscous: the same z at every swing), so an sd over them is no calibration
    middle = [int(np.argsort(d["amplitude_m"])[len(d["z"]) // 2]) for d in fitted]
    n_amp = min(len(d["covered"]) for d in fitted)
    by_amp = [_rate(sum(d["covered"][i] for d in fitted), len(fitted)) for i in range(n_amp)]
    tps = [d["turning_points"] for d in fitted if d.get("turning_points")]
    tp_cov = [c for d in tps for c in d["covered"]]
    return {
        "turning_points": {
            "coverage": _rate(sum(tp_cov), len(tp_cov)),
            "z": _z_stats([v for d in tps for v in d["z"]]),
        },
        "coverage_over_swings": _rate(sum(cov), len(cov)),
        "coverage": _rate(
            sum(d["covered"][i] for d, i in zip(fitted, middle, strict=True)), len(fitted)
        ),
        "all_amplitudes_covered": sum(all(d["covered"]) for d in fitted),
        "runs": len(fitted),
        "coverage_by_amplitude_index": by_amp,
        "z": _z_stats([d["z"][i] for d, i in zip(fitted, middle, strict=True)]),
    }


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per case and noise level: the true-law fit's coverage and z, the auto fit's
    chosen laws, rightness, ΔE coverage and silently wrong runs."""
    table: dict[str, Any] = {}
    for case in CASES:
        for noise in sorted({r["noise"] for r in records}):
            rows = [r for r in records if r["case"] == case and r["noise"] == noise]
            if not rows:
                continue
            row: dict[str, Any] = {"kind": CASES[case][3], "runs": len(rows)}
            key = "true_fit" if CASES[case][0] else "default_fit"
            fits = [r[key] for r in rows]
            ok = [f for f in fits if "error" not in f]
            row[key] = {
                "law": CASES[case][0] or DEFAULT_LAW,
                "errors": [
                    {"index": r["index"], "error": r[key]["error"]}
                    for r in rows
                    if "error" in r[key]
                ],
                "not_converged": sum(not f["converged"] for f in ok),
                "warned": {
                    w: sum(w in f["warnings"] for f in ok)
                    for w in sorted({w for f in ok for w in f["warnings"]})
                },
                "median_seconds": float(np.median([f["seconds"] for f in ok])) if ok else None,
                "dissipation": _band_stats(ok),
            }
            if CASES[case][0]:
                params = {}
                for name in ok[0]["parameters"] if ok else []:
                    ps = [f["parameters"][name] for f in ok]
                    in_frame = [
                        p["interval"][0] <= p["truth_in_package_frame"] <= p["interval"][1]
                        for p in ps
                    ]
                    params[name] = {
                        "truth": ps[0]["truth"] if name != "zeta_alpha" else None,
                        "coverage": _rate(sum(p["covered"] for p in ps), len(ps)),
                        "z": _z_stats([p["z"] for p in ps]),
                        "coverage_in_package_frame": _rate(sum(in_frame), len(ps)),
                        "z_in_package_frame": _z_stats([p["z_in_package_frame"] for p in ps]),
                    }
                row[key]["parameters"] = params
            table[f"{case}@{noise:g}x"] = row
            if not all("auto_fit" in r for r in rows):  # --true-law-only
                continue
            autos = [r["auto_fit"] for r in rows]
            aok = [a for a in autos if "error" not in a]
            chosen: dict[str, int] = {}
            for a in aok:
                chosen[a["law"]] = chosen.get(a["law"], 0) + 1
            row["auto"] = {
                "errors": [
                    {"index": r["index"], "error": r["auto_fit"]["error"]}
                    for r in rows
                    if "error" in r["auto_fit"]
                ],
                "chosen": chosen,
                "right": sum(bool(a.get("right")) for a in aok) if CASES[case][0] else None,
                "right_as_nesting": sum(a.get("how") == "nesting, extra terms hold 0" for a in aok),
                "wrong_but_true_law_as_good": sum(
                    (not a.get("right")) and bool(a.get("true_law_as_good")) for a in aok
                ),
                "adequate": sum(a["adequate"] for a in aok),
                "not_converged": sum(not a["converged"] for a in aok),
                "warned": {
                    w: sum(w in a["warnings"] for a in aok)
                    for w in sorted({w for a in aok for w in a["warnings"]})
                },
                "silently_wrong": sum(a["silently_wrong"] for a in aok),
                "confidently_silently_wrong": sum(a["confidently_silently_wrong"] for a in aok),
                "silently_wrong_runs": [
                    {
                        "index": r["index"],
                        "law": r["auto_fit"]["law"],
                        "max_abs_z": r["auto_fit"]["dissipation"]["max_abs_z"],
                    }
                    for r in rows
                    if r["auto_fit"].get("silently_wrong")
                ],
                "median_seconds": float(np.median([a["seconds"] for a in aok])) if aok else None,
                "dissipation": _band_stats(aok),
            }
    return table


def pooled(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Calibration of the true-law fits over every case together, and the auto rates.

    One z per run and quantity: each sampled parameter except μ_s/μ_k (its posterior is
    its prior's wherever the decay does not end on a stick), and ΔE(A) at the middle of
    the reported swings only (the 12 swings of a run are strongly correlated: pooling
    them would count one run 12 times). The auto rates leave out the case no registered
    law describes.
    """
    z_par, z_frame, z_de, cov_par, cov_de = [], [], [], [], []
    right = runs = silent = confident = 0
    for r in records:
        law = CASES[r["case"]][0]
        fit = r.get("true_fit", {})
        if law and "error" not in fit:
            for name, par in fit.get("parameters", {}).items():
                if name == "mu_s_ratio" or not math.isfinite(par.get("z", math.nan)):
                    continue
                z_par.append(par["z"])
                z_frame.append(par.get("z_in_package_frame", math.nan))
                cov_par.append(bool(par["covered"]))
            d = fit.get("dissipation")
            if d and d.get("z"):
                i = len(d["z"]) // 2
                z_de.append(d["z"][i])
                cov_de.append(bool(d["covered"][i]))
        auto = r.get("auto_fit")
        if law and auto and "error" not in auto:
            runs += 1
            right += bool(auto.get("right"))
            silent += bool(auto.get("silently_wrong"))
            confident += bool(auto.get("confidently_silently_wrong"))
    return {
        "parameters": {
            "coverage": _rate(sum(cov_par), len(cov_par)),
            "z": _z_stats(z_par),
            "z_in_package_frame": _z_stats(z_frame),
        },
        "dissipation_middle_swing": {
            "coverage": _rate(sum(cov_de), len(cov_de)),
            "z": _z_stats(z_de),
        },
        "auto": {
            "runs": runs,
            "right": _rate(right, runs) if runs else None,
            "silently_wrong": silent,
            "confidently_silently_wrong": confident,
        },
    }


def confusion(records: list[dict[str, Any]]) -> dict[str, Any]:
    """True law x chosen law (counts over every noise level), and the rightness."""
    laws: list[str] = []
    matrix: dict[str, dict[str, int]] = {}
    for case in CASES:
        rows = [r for r in records if r["case"] == case]
        if not rows:
            continue
        counts: dict[str, int] = {}
        for r in rows:
            a = r.get("auto_fit")
            if a is None:  # --true-law-only
                continue
            name = "error" if "error" in a else a["law"]
            counts[name] = counts.get(name, 0) + 1
            if name not in laws:
                laws.append(name)
        if counts:
            matrix[case] = counts
    return {"columns": laws, "rows": matrix}


def _cell(rate: dict[str, Any]) -> str:
    if not rate or not rate["of"]:
        return "-"
    lo, hi = rate["ci95"]
    return f"{100 * rate['rate']:3.0f} [{100 * lo:2.0f}-{100 * hi:3.0f}]"


def _zcell(z: dict[str, Any] | None) -> str:
    return "-" if not z else f"{z['sd']:.2f}±{z['sd_se']:.2f}"


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def _print_table(table: dict[str, Any], conf: dict[str, Any]) -> None:
    print("\n" + NOTES)
    print(
        "\nTrue-law fit: coverage % [CP 95 %] and sd(z) per parameter; ΔE(A) band at the "
        "middle swing (one z per run); all-A: runs whose band covers every swing"
    )
    for key, r in table.items():
        f = r.get("true_fit") or r.get("default_fit")
        errs = f"  errors {len(f['errors'])}" if f["errors"] else ""
        d = f["dissipation"]
        cells = [
            f"{n:10s} {_cell(p['coverage']):>15s} sd(z) {_zcell(p['z']):>11s}   in the "
            f"package's frame {_cell(p['coverage_in_package_frame']):>15s} sd(z) "
            f"{_zcell(p['z_in_package_frame'])}"
            for n, p in f.get("parameters", {}).items()
        ]
        print(
            f"{key:32s} law {f['law']:26s} ΔE(A_mid) {_cell(d.get('coverage'))} "
            f"sd(z) {_zcell(d.get('z'))} all-A {d.get('all_amplitudes_covered', 0)}/"
            f"{d.get('runs', 0)}  unconv {f['not_converged']}  "
            f"{_seconds(f['median_seconds'])} s{errs}"
        )
        for c in cells:
            print(f"{'':34s}{c}")
    if any("auto" in r for r in table.values()):
        _print_auto(table, conf)
    errors = [
        (k, which, e)
        for k, r in table.items()
        for which, f in (
            ("fit", r.get("true_fit") or r.get("default_fit")),
            ("auto", r.get("auto")),
        )
        if f
        for e in f["errors"]
    ]
    if errors:
        print("\nPackage errors:")
        for key, which, e in errors:
            print(f"  {key} {which} run {e['index']}: {e['error'][:300]}")


def _print_auto(table: dict[str, Any], conf: dict[str, Any]) -> None:
    print("\nlaw='auto'")
    print(
        f"{'case@noise':32s} {'runs':>4s} {'right':>5s} {'nest':>4s} {'adeq':>4s} "
        f"{'unconv':>6s} {'SILENT':>6s} {'CONF':>4s} {'ΔE cov %':>15s} {'TP cov %':>15s} "
        f"{'eqv':>3s} {'s/fit':>6s}  chosen"
    )
    for key, r in table.items():
        if "auto" not in r:
            continue
        a = r["auto"]
        right = "-" if a["right"] is None else str(a["right"])
        chosen = ", ".join(f"{k} {v}" for k, v in a["chosen"].items())
        if a["errors"]:
            chosen += f", ERROR {len(a['errors'])}"
        sec = a["median_seconds"]
        print(
            f"{key:32s} {r['runs']:4d} {right:>5s} {a['right_as_nesting']:4d} "
            f"{a['adequate']:4d} {a['not_converged']:6d} {a['silently_wrong']:6d} "
            f"{a['confidently_silently_wrong']:4d} {_cell(a['dissipation'].get('coverage')):>15s} "
            f"{_cell(a['dissipation'].get('turning_points', {}).get('coverage')):>15s} "
            f"{a.get('wrong_but_true_law_as_good', 0):3d} "
            f"{'-' if sec is None else f'{sec:6.1f}':>6s}  {chosen}"
        )
    print("\nConfusion matrix (rows: true law; columns: law chosen by auto; all noise levels)")
    cols = conf["columns"]
    short = {
        c: c.replace("viscous", "v")
        .replace("coulomb", "c")
        .replace("quadratic", "q")
        .replace("hysteretic", "h")
        .replace("power", "p")
        .replace("cubic", "cu")
        for c in cols
    }
    print(f"{'true law':26s} " + " ".join(f"{short[c]:>8s}" for c in cols))
    for case, counts in conf["rows"].items():
        print(f"{case:26s} " + " ".join(f"{counts.get(c, 0):8d}" for c in cols))


def output_path(name: str) -> Path:
    """``results/NAME.json``, or ``name`` itself when it is a path ending in .json."""
    return Path(name) if name.endswith(".json") else RESULTS / f"{name}.json"


def write_json(path: Path, results: dict[str, Any]) -> Path:
    """Write ``results`` with the machine description (atomically: a file that is read
    or interrupted while it is written is never half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps({"machine": machine(), **results}, indent=2) + "\n")
    tmp.replace(path)
    return path


def _settings(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "runs": args.runs,
        "seed": args.seed,
        "max_steps": args.max_steps,
        "workers": args.workers,
        "auto": not args.true_law_only,
        "n_walkers": 16,
        "n_ensembles": 2,
        "noise_levels_x_resolution": args.levels,
        "resolution": {"displacement_m": RESOLUTION_X, "velocity_m_per_s": RESOLUTION_V},
        "rig": {
            "mass_kg": MASS,
            "natural_frequency_Hz": OMEGA / (2 * math.pi),
            "load_N": LOAD,
            "length_scale_m": ELL,
        },
        "sample_rate_Hz": FS,
        "rest_before_s": REST_BEFORE_S,
        "rest_after_stop_s": REST_AFTER_S,
        "duration_without_friction_s": DURATION_S,
        "cases": {
            c: {
                "law": CASES[c][0],
                "truth": vars(CASES[c][1]),
                "x0_m": CASES[c][2],
                "kind": CASES[c][3],
            }
            for c in args.cases
        },
        "flags": list(FLAGS),
    }


def in_fit_frame(record: dict[str, Any]) -> dict[str, Any]:
    """``record`` with the truth of its true-law fit's parameters in the package's frame
    (``truth_in_package_frame``, ``z_in_package_frame``): the frame the fit ended in
    (its ``omega``, :func:`bayestribo.inference.pipeline.law_frequency` for a nonlinear
    law; ℓ = N/(mΩ²) follows it), not the record's (``record_omega_over_true``).

    Runs written before that fix measured z_in_package_frame against the record's
    frequency, which a nonlinear law's fit leaves for its own (quadratic drag: 3e-4
    off, 19 posterior sd of c₂); the fit's frame is in the run, so the correction
    needs no refit."""
    fit = record.get("true_fit", {})
    law, truth, _x0, _kind = CASES[record["case"]]
    if law is None or "parameters" not in fit or "omega" not in fit:
        return record
    frame = record.setdefault("package_frame", {})
    if "record_omega_over_true" not in frame:
        frame["record_omega_over_true"] = frame.get("omega_over_true")
    frame["omega_over_true"] = fit["omega"] / OMEGA
    in_frame = truth.dimensionless(frame["reference_amplitude_m"], fit["omega"])
    for name, par in fit["parameters"].items():
        par["truth_in_package_frame"] = in_frame[name]
        par["z_in_package_frame"] = (par["mean"] - in_frame[name]) / par["sd"]
    return record


def _retable_files(names: list[str]) -> int:
    """Rewrite the tables of finished result files from their runs with this summary
    code (the package-frame truth in the fit's frame, :func:`in_fit_frame`; one z per
    run); nothing is fitted, the runs' fits are kept."""
    for name in names:
        path = output_path(name)
        old = json.loads(path.read_text())
        records = [in_fit_frame(r) for r in old["runs"]]
        old.update(
            {
                "retabled": {
                    "commit": commit(),
                    "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                },
                "notes": NOTES,
                "table": summarise(records),
                "confusion": confusion(records),
                "pooled": pooled(records),
                "calibration": calibration(records, CASES),
                "runs": records,
            }
        )
        write_json(path, old)
        print(f"rewrote the tables of {path}")
    return 0


def _pool_files(names: list[str], output: Path) -> int:
    """Pool the runs of complete result files, no run twice (a run is its case, noise
    level and entropy: files of one seed may pool when they hold other cases):
    :func:`pooled` over them all."""
    files = [output_path(n) for n in names]
    results = [json.loads(f.read_text()) for f in files]
    if not all(r.get("complete") for r in results):
        raise SystemExit(f"--pool: expected complete result files, got {names}")
    records = [run for r in results for run in r["runs"]]
    keys = [(run["case"], run["noise"], tuple(run["entropy"])) for run in records]
    if len(set(keys)) != len(keys):
        raise SystemExit(f"--pool: a run stands in more than one of {names}")
    pooled_all = pooled(records)
    write_json(
        output,
        {
            "pooled_from": {
                f.name: {"seed": r["settings"]["seed"], "commit": r["source"]["commit"]}
                for f, r in zip(files, results, strict=True)
            },
            "runs": len(records),
            "pooled": pooled_all,
            "calibration": calibration(records, CASES),
        },
    )
    print(json.dumps(pooled_all, indent=1))
    print_calibration(calibration(records, CASES))
    print(f"wrote {output}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="runs per case and noise level")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--max-steps", type=int, default=6000)
    parser.add_argument(
        "--cases",
        nargs="*",
        default=None,
        choices=list(CASES),
        help="default: every case (with --true-law-only: every case with a registered law)",
    )
    parser.add_argument("--levels", nargs="*", type=float, default=list(NOISE_LEVELS))
    parser.add_argument(
        "--output",
        default=None,
        help="results/NAME.json, or a path ending in .json (default: laws, or "
        "laws_calibration with --true-law-only)",
    )
    parser.add_argument(
        "--true-law-only",
        action="store_true",
        help="fit each run with its true law only (no law='auto', which takes minutes a "
        "run): for the per-law calibration with many runs",
    )
    parser.add_argument(
        "--resume", action="store_true", help="keep the runs of an interrupted output file"
    )
    parser.add_argument(
        "--pool",
        nargs="+",
        metavar="NAME",
        help="pool the runs of finished result files (results/NAME.json, at different "
        "--seed) into --output, calibration and auto rates over them all; nothing is fitted",
    )
    parser.add_argument(
        "--retable",
        nargs="+",
        metavar="NAME",
        help="rewrite the tables of finished result files (results/NAME.json) from their "
        "runs with this summary code; nothing is fitted",
    )
    args = parser.parse_args(argv)
    if args.cases is None:
        args.cases = [c for c in CASES if CASES[c][0] or not args.true_law_only]
    if args.output is None:
        args.output = "laws_calibration" if args.true_law_only else "laws"
    if args.retable:
        return _retable_files(args.retable)
    if args.pool:
        return _pool_files(args.pool, output_path(args.output))
    settings = _settings(args)
    load_start = os.getloadavg()
    source = {"commit": commit()}
    import bayestribo

    source["package_version"] = bayestribo.__version__
    source["module"] = require_this_tree()
    jobs = [(c, n, i) for c in args.cases for n in args.levels for i in range(args.runs)]
    records: list[dict[str, Any]] = []
    output = output_path(args.output)
    if args.resume and output.is_file():
        old = json.loads(output.read_text())
        same = (
            old.get("settings", {}).get("seed") == args.seed
            and old.get("settings", {}).get("max_steps") == args.max_steps
            and old.get("settings", {}).get("auto", True) == settings["auto"]
        )
        if same:
            wanted = set(jobs)
            records = [
                r for r in old.get("runs", []) if (r["case"], r["noise"], r["index"]) in wanted
            ]
            done = {(r["case"], r["noise"], r["index"]) for r in records}
            jobs = [j for j in jobs if j not in done]
            print(f"resumed {len(records)} runs from {output}", flush=True)
    # run 0 of every case first, so that an interrupted file holds every case
    jobs.sort(key=lambda j: (j[2], CASES[j[0]][0] in ("viscous", "coulomb", "viscous+coulomb")))
    start = time.perf_counter()
    what = "a true-law fit" if args.true_law_only else "a true-law fit and an auto fit"
    print(
        f"{len(jobs)} runs (each {what}) on {args.workers} workers, "
        f"load average {load_start[0]:.2f}",
        flush=True,
    )

    def write(complete: bool) -> Path:
        records.sort(key=lambda r: (list(CASES).index(r["case"]), r["noise"], r["index"]))
        return write_json(
            output,
            {
                "complete": complete,
                "settings": settings,
                "notes": NOTES,
                "source": source,
                "wall_seconds": time.perf_counter() - start,
                "load_average_start": list(load_start),
                "load_average_now": list(os.getloadavg()),
                "table": summarise(records),
                "confusion": confusion(records),
                "pooled": pooled(records),
                "calibration": calibration(records, CASES),
                "runs": records,
            },
        )

    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        futures = {
            pool.submit(one_run, c, n, i, args.seed, args.max_steps, settings["auto"]): (c, n, i)
            for c, n, i in jobs
        }
        for k, future in enumerate(as_completed(futures), 1):
            c, n, i = futures[future]
            try:
                rec = future.result()
            except Exception as exc:  # a worker that died: recorded, the others go on
                key = "true_fit" if CASES[c][0] else "default_fit"
                rec = {
                    "case": c,
                    "noise": n,
                    "index": i,
                    "worker_error": _tail(exc),
                    key: {"error": "worker died"},
                }
                if settings["auto"]:
                    rec["auto_fit"] = {"error": "worker died"}
            records.append(rec)
            a = rec.get("auto_fit", {})
            said = f"auto {a.get('law', a.get('error', '?'))[:60]}" if a else "true law"
            print(
                f"{k}/{len(jobs)} {c}@{n:g}x#{i}: {said} "
                f"({rec.get('seconds', 0):.0f} s), {time.perf_counter() - start:.0f} s, "
                f"load {os.getloadavg()[0]:.2f}",
                flush=True,
            )
            write(False)
    path = write(True)
    table = summarise(records)
    _print_table(table, confusion(records))
    print_calibration(calibration(records, CASES))
    print("\npooled over the registered laws:", json.dumps(pooled(records), indent=1))
    print(f"\nwall {time.perf_counter() - start:.0f} s; wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
