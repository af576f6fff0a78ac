"""Free decays that fade into 1/f (pink) noise: exit codes, the cause named, coverage.

Each record is this file's own simulation: the closed-form viscous (+ Coulomb) decay
of a 12 Hz oscillator, half cycle by half cycle (the friction's sign fixed between
turning points, the mass sticking where a turning point lies within the static
friction's reach), released from 1 mm after 0.3 s at rest and recorded for 20 s at
1 kHz, displacement only, plus pink noise (white noise shaped by 1/√f in frequency,
from 1/20 s up, scaled to its rms) and white noise of a quarter of that rms. Cells: the
law (``viscous``, ``viscous+coulomb``) × the pink noise's rms (0.1 %, 0.5 % and 2 % of
the release) × seeds. Each record is fitted with ``bayestribo fit FILE --law LAW
--json`` by each tree given (the tree of this file and, with ``--base``, another, in
alternation, seed by seed across the cells), and then, where a fit exited 1 with a
warning that advises an option, once more with that option (as
``unseen_rigs3.warning_advice`` reads it); the results are written as each fit lands. Recorded: exit
status, whether a warning names the 1/f noise, whether the 95 % intervals of ζ and
the friction displacement cover the truth, CPU seconds.

Run::

    python benchmarks/fade_1f.py [--seeds 8] [--jobs 2] [--base <worktree of main>]
    python benchmarks/fade_1f.py --table

Results: ``benchmarks/results/fade_1f.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import RESULTS, ROOT, commit, write_results
from unseen_rigs3 import fit_record, warning_advice

F_HZ = 12.0
FS = 1000.0
X0 = 1e-3
T_PRE = 0.3
T_TOTAL = 20.0
LAWS = {
    "viscous": {"zeta": 0.01, "x_c": 0.0, "x_s": 0.0},
    "viscous+coulomb": {"zeta": 0.004, "x_c": 2e-6, "x_s": 3e-6},
}
LEVELS = (0.001, 0.005, 0.02)  # pink rms over the release


def decay(zeta: float, x_c: float, x_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The noise-free record: rest at ``X0``, then the viscous + Coulomb decay.

    Parameters
    ----------
    zeta : float
        Viscous damping ratio (dimensionless).
    x_c, x_s : float
        Kinetic and static friction displacements [m] (0 for a viscous decay).

    Returns
    -------
    t, x : numpy.ndarray
        Time [s] and displacement [m].
    """
    w = 2 * np.pi * F_HZ
    wd = w * np.sqrt(1 - zeta**2)
    half = np.pi / wd
    n = round(T_TOTAL * FS)
    t = np.arange(n) / FS
    x = np.full(n, X0)
    pos, start = X0, T_PRE
    while start < T_TOTAL:
        if x_c > 0 and abs(pos) <= x_s:
            x[t >= start] = pos  # stuck
            break
        centre = x_c * np.sign(pos)
        span = (t >= start) & (t < start + half)
        s = t[span] - start
        u = pos - centre
        x[span] = centre + u * np.exp(-zeta * w * s) * (
            np.cos(wd * s) + zeta * w / wd * np.sin(wd * s)
        )
        pos = centre - u * np.exp(-zeta * w * half)
        start += half
    return t, x


def pink_noise(n: int, rng: np.random.Generator) -> np.ndarray:
    """Unit-rms 1/f noise: white noise's spectrum divided by √f (f from 1/length)."""
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, 1.0 / FS)
    f[0] = f[1]
    noise = np.fft.irfft(spectrum / np.sqrt(f), n)
    return noise / noise.std()


def write_record(d: Path, law: str, level: float, seed: int) -> tuple[Path, dict[str, Any]]:
    """One record's CSV and sidecar; its truth (ζ, and x_c in m with friction)."""
    p = LAWS[law]
    t, x = decay(p["zeta"], p["x_c"], p["x_s"])
    rng = np.random.default_rng([seed, round(level * 1e4), len(law)])
    rms = level * X0
    x = x + rms * pink_noise(t.size, rng) + rng.normal(0.0, 0.25 * rms, t.size)
    path = d / f"{law.replace('+', '_')}_{level:g}_{seed}.csv"
    path.write_text(
        "time_s,displacement_m\n"
        + "\n".join(f"{a:.4f},{b:.6e}" for a, b in zip(t, x, strict=True))
        + "\n"
    )
    path.with_suffix(".json").write_text(json.dumps({"natural_frequency_Hz": F_HZ}))
    truth: dict[str, Any] = {"zeta": p["zeta"]}
    if p["x_c"] > 0:
        truth["x_c"] = p["x_c"]
    return path, truth


def names_colour(stderr: str) -> bool:
    """Whether the fit's warnings name the 1/f noise."""
    return "1/f" in stderr


def first_fit(tree: str, path: Path, truth: dict[str, Any], law: str, timeout: float) -> dict:
    """``bayestribo fit PATH --law LAW --json`` with the package of ``tree``, and the
    option its warning advises (not yet followed) where it exits 1."""
    env = {**os.environ, "PYTHONPATH": tree, "MPLBACKEND": "Agg"}
    args = ["--law", law]
    rec = fit_record(str(path), args, truth, env, timeout)
    rec["names_1f"] = names_colour(rec["stderr"])
    if rec["rc"] == 1:
        rec["advice"] = warning_advice(rec["stderr"], args)
    return rec


def follow(tree: str, path: Path, truth: dict[str, Any], law: str, rec: dict, timeout: float):
    """Fit once more with the option the first fit's warning advised (replacing the
    one given), as a user would; recorded under ``rec["followup"]``."""
    env = {**os.environ, "PYTHONPATH": tree, "MPLBACKEND": "Agg"}
    rest = ["--law", law]
    advice = rec["advice"]
    if advice[0] in rest:
        i = rest.index(advice[0])
        del rest[i : i + 2]
    rec["followup"] = fit_record(str(path), [*rest, *advice], truth, env, timeout)
    rec["followup"]["names_1f"] = names_colour(rec["followup"]["stderr"])


def answered(rec: dict[str, Any]) -> dict[str, Any]:
    """The answer a user ends with: the advice's fit where one was followed."""
    return rec.get("followup", rec)


def summary(cases: list[dict[str, Any]], tree: str) -> list[dict[str, Any]]:
    """Per cell (law, level): exit codes, 1/f named, coverage of the final answer."""
    out = []
    for law in LAWS:
        for level in LEVELS:
            rows = [c[tree] for c in cases if c["law"] == law and c["level"] == level]
            if not rows:
                continue
            final = [answered(r) for r in rows]
            cov = [
                v["covers"]
                for r in final
                for v in (r.get("coverage") or {}).values()
                if v.get("covers") is not None
            ]
            out.append(
                {
                    "law": law,
                    "level": level,
                    "n": len(rows),
                    "first_rc": [r["rc"] for r in rows],
                    "final_rc": [r["rc"] for r in final],
                    "named_1f": sum(bool(r.get("names_1f")) for r in rows),
                    "advice_followed": sum("followup" in r for r in rows),
                    "advice_not_followed": sum(
                        bool(r.get("advice")) and "followup" not in r for r in rows
                    ),
                    "intervals": len(cov),
                    "covered": sum(cov),
                    "exit0_missed": sum(
                        1
                        for r in final
                        if r["rc"] == 0
                        for v in (r.get("coverage") or {}).values()
                        if v.get("covers") is False
                    ),
                    "cpu_s_median": float(np.median([r["cpu_s"] for r in rows])),
                }
            )
    return out


def table(path: Path) -> str:
    """The stored results as a Markdown table, one row per cell and tree."""
    res = json.loads(path.read_text())
    lines = [
        "| law | pink rms | tree | first exit (0/1/2) | 1/f named | final exit (0/1/2) "
        "| intervals covering | exit 0 and missing |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for tree in res["trees"]:
        for s in res["summary"][tree]:

            def count(codes: list[int | None]) -> str:
                return "/".join(str(sum(c == k for c in codes)) for k in (0, 1, 2))

            lines.append(
                f"| {s['law']} | {100 * s['level']:g} % | {tree} | {count(s['first_rc'])} "
                f"| {s['named_1f']}/{s['n']} | {count(s['final_rc'])} "
                f"| {s['covered']}/{s['intervals']} | {s['exit0_missed']} |"
            )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--base", default=None, help="another tree fitted beside (main)")
    ap.add_argument("--name", default="fade_1f")
    ap.add_argument("--table", action="store_true")
    a = ap.parse_args()
    path = RESULTS / f"{a.name}.json"
    if a.table:
        print(table(path))
        return
    trees = {"branch": str(ROOT)}
    if a.base:
        trees["main"] = a.base
    settings = {"seeds": a.seeds, "trees": trees, "levels": LEVELS, "laws": LAWS}
    cases: list[dict[str, Any]] = []

    def save() -> Path:
        done = sorted(cases, key=lambda c: (c["law"], c["level"], c["seed"]))
        return write_results(
            a.name,
            {
                "commit": commit(),
                "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                "settings": settings,
                "trees": list(trees),
                "summary": {n: summary(done, n) for n in trees},
                "cases": done,
            },
        )

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        # seed by seed across the cells, so that a run cut short holds every cell
        jobs = [
            (law, level, seed, *write_record(d, law, level, seed))
            for seed in range(a.seeds)
            for law in LAWS
            for level in LEVELS
        ]

        def first(job: tuple[Any, ...]) -> dict[str, Any]:
            law, level, seed, p, truth = job
            rec = {"law": law, "level": level, "seed": seed, "truth": truth, "path": str(p)}
            # the trees in alternation, the order swapped from one record to the next
            order = list(trees) if seed % 2 == 0 else list(trees)[::-1]
            for name in order:
                rec[name] = first_fit(trees[name], p, truth, law, a.timeout)
            print(law, level, seed, {n: rec[n]["rc"] for n in trees}, flush=True)
            return rec

        def followed(item: tuple[dict[str, Any], str]) -> None:
            rec, name = item
            follow(trees[name], Path(rec["path"]), rec["truth"], rec["law"], rec[name], a.timeout)
            print("advice", rec["law"], rec["level"], rec["seed"], name, flush=True)

        with ThreadPoolExecutor(a.jobs) as pool:
            for rec in pool.map(first, jobs):
                cases.append(rec)
                save_path = save()
            # then the advice of each exit 1, followed once (the costly part: main's
            # --law auto), saved as each lands
            todo = [(rec, n) for rec in cases for n in trees if rec[n].get("advice")]
            for _ in pool.map(followed, todo):
                save_path = save()
    for rec in cases:
        rec.pop("path", None)
    print(save_path if not cases else save())
    print(table(RESULTS / f"{a.name}.json"))


if __name__ == "__main__":
    main()
