"""Recordings from rigs nobody here has seen, third round: other sensors, clocks and files.

Each case is its own simulation, none from the package's simulator: the closed-form
viscous + Coulomb decay of ``unseen_rigs.simulate`` for a linear rig, or ``solve_ivp``
half cycle by half cycle (the friction's sign fixed between turning points, sticking
where the restoring force at a turning point is within the static friction's reach)
for a Duffing spring or a pendulum with quadratic drag. Each is written as another
lab's sensor or tool writes it (a rotary encoder's counts, a gyroscope in deg/s, an
AC-coupled velocity sensor, an accelerometer in g on its axis, a 24-bit ADC with its
scale in a sidecar, jittered stamps at a non-integer rate, clock-time stamps, a
whitespace ``.dat`` with a BOM and CRLF, a scope's pre-trigger, a decay fading into
1/f noise, a Duffing cantilever, a pendulum in air, an Excel workbook of two runs, a
TDMS file, a UFF 58 file, a 50 Hz hum, a sidecar in kgf and grams). For each file the
probe runs ``bayestribo inspect FILE`` and ``bayestribo fit FILE --json`` as a user
would; where the fit is refused (exit 2) and the message names options, it fits once
more with the options parsed from the message (:func:`advice_of`), and where it exits 1
with a warning that advises an option, once more with that option
(:func:`warning_advice`: a named reading or force before ``--law auto``); it records
the exit status, the warnings, and whether the 95 % intervals cover the truth.

Run::

    python benchmarks/unseen_rigs3.py [--only NAME ...] [--jobs 2] [--name unseen_rigs3]
    python benchmarks/unseen_rigs3.py --table [--name unseen_rigs3] [--base unseen_rigs3_main]

Results: ``benchmarks/results/unseen_rigs3.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.signal import lfilter

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import RESULTS, ROOT, commit, write_results
from unseen_rigs import rig, sidecar, warnings_of

G = 9.80665
Case = dict[str, Any]


# ------------------------------------------------------------------ nonlinear rigs
def ivp_decay(
    stiff: Callable[[float], float],
    damp: Callable[[float], float],
    theta_c: float,
    theta_s: float,
    x0: float,
    fs: float,
    t_pre: float,
    t_post: float,
    t_end: float = np.inf,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A free decay x'' = -stiff(x) - damp(x') - ω²θ_c sgn x' by ``solve_ivp``.

    Parameters
    ----------
    stiff : callable
        Restoring acceleration of the displacement [unit/s²].
    damp : callable
        Drag acceleration of the velocity [unit/s²], odd in the velocity.
    theta_c, theta_s : float
        Kinetic and static friction as accelerations [unit/s²].
    x0 : float
        Release displacement (at rest) [unit].
    fs : float
        Sample rate [Hz].
    t_pre, t_post : float
        Rest before the release and after the stop [s].
    t_end : float, optional
        End of the record [s] where it ends before the stop.

    Returns
    -------
    t, x, v : numpy.ndarray
        Time [s], displacement [unit] and velocity [unit/s], noise-free.
    """
    pieces_t, pieces_y = [], []
    x, t0 = x0, t_pre
    for _ in range(100000):
        if abs(stiff(x)) <= theta_s or t0 >= t_end:
            break
        s = -np.sign(stiff(x))  # direction of motion

        def rhs(_t: float, y: np.ndarray, s: float = s) -> list[float]:
            return [y[1], -stiff(y[0]) - damp(y[1]) - theta_c * s]

        def turn(_t: float, y: np.ndarray) -> float:
            return y[1]

        turn.terminal = True  # type: ignore[attr-defined]
        turn.direction = -s  # type: ignore[attr-defined]
        sol = solve_ivp(
            rhs,
            (t0, t0 + 100.0),
            [x, 0.0],
            events=turn,
            rtol=1e-11,
            atol=1e-14,
            dense_output=True,
            first_step=1e-6,
        )
        t1 = float(sol.t_events[0][0])
        pieces_t.append((t0, t1))
        pieces_y.append(sol.sol)
        x, t0 = float(sol.y_events[0][0][0]), t1
    t_stop = t0
    n = round(min(t_stop + t_post, t_end) * fs)
    t = np.arange(n) / fs
    xs = np.full(n, x0)
    vs = np.zeros(n)
    for (a, b), sol in zip(pieces_t, pieces_y, strict=True):
        m = (t >= a) & (t < b)
        y = sol(t[m])
        xs[m], vs[m] = y[0], y[1]
    xs[t >= t_stop] = x
    return t, xs, vs


def sidecar_of(r: dict[str, Any], **extra: Any) -> dict[str, Any]:
    """The rig's sidecar (load, mass, frequency) with ``extra`` keys."""
    return {**r["meta"], **extra}


def csv_rows(cols: list[np.ndarray], fmt: str, sep: str = ",") -> list[str]:
    """Rows of ``cols`` formatted with ``fmt`` each, joined by ``sep``."""
    return [sep.join(format(v, fmt) for v in row) for row in zip(*cols, strict=True)]


# ------------------------------------------------------------------ the cases
def c_encoder_counts(d: Path) -> Case:
    """A torsion pendulum on a rotary encoder: raw counts, counts per rev in the header."""
    cpr = 8192
    # friction as an angle: θ_c = 0.01 rad, θ_s = 0.015 rad (torque / k_t)
    from unseen_rigs import simulate

    rng = np.random.default_rng(31)
    t, th, _ = simulate(0.8, 0.006, 0.01, 0.015, 0.6, 200, 1.0, 3.0, rng, 0.0, 0.0)
    counts = np.round(th / (2 * np.pi) * cpr).astype(int)
    p = d / "torsion_encoder.csv"
    lines = [
        "# Rotary encoder log, US Digital E6 (quadrature x4)",
        f"# counts_per_rev: {cpr}",
        "# sample_rate_Hz: 200",
        "time_s,counts",
    ] + [f"{a:.3f},{c}" for a, c in zip(t, counts, strict=True)]
    p.write_text("\n".join(lines) + "\n")
    sidecar(p, {"natural_frequency_Hz": 0.8})
    return {
        "file": p,
        "args": [],
        "truth": {"zeta": 0.006, "x_c": 0.01, "x_c_unit": "rad"},
        "kind": f"rotary encoder counts ({cpr}/rev in the header), torsion pendulum",
    }


def c_gyro_degps(d: Path) -> Case:
    """A smartphone gyroscope on a torsion oscillator: three axes in deg/s, no angle."""
    from unseen_rigs import simulate

    rng = np.random.default_rng(32)
    t, _th, om = simulate(1.5, 0.01, 0.004, 0.006, 0.35, 100, 1.0, 3.0, rng, 0.0, 0.0)
    deg = np.degrees(om)
    gx = rng.normal(0, 0.15, t.size)
    gy = rng.normal(0, 0.15, t.size)
    gz = deg + rng.normal(0, 0.15, t.size) + 0.4  # a gyro's bias
    p = d / "gyroscope.csv"
    head = '"Time (s)","Gyroscope x (deg/s)","Gyroscope y (deg/s)","Gyroscope z (deg/s)"'
    p.write_text(head + "\n" + "\n".join(csv_rows([t, gx, gy, gz], ".6f")) + "\n")
    sidecar(p, {"natural_frequency_Hz": 1.5})
    return {
        "file": p,
        "args": [],
        "truth": {"zeta": 0.01, "x_c": 0.004, "x_c_unit": "rad"},
        "kind": "gyroscope x,y,z in deg/s (bias 0.4 deg/s), angular velocity only",
    }


def c_ac_coupled(d: Path) -> Case:
    """A geophone-like velocity sensor, AC-coupled: a one-pole 0.5 Hz high-pass, velocity only."""
    r = rig(
        33,
        f=3.0,
        zeta=0.008,
        mu_k=0.02,
        N=1.0,
        m=0.3,
        x0=0.02,
        fs=500,
        t_pre=1.0,
        t_post=3.0,
        nx=0,
        nv=0,
    )
    fs, fc = 500.0, 0.5
    a = np.exp(-2 * np.pi * fc / fs)
    v = lfilter([(1 + a) / 2, -(1 + a) / 2], [1, -a], r["v"])
    v = v + np.random.default_rng(33).normal(0, 2e-4, v.size)
    p = d / "geophone_ac.csv"
    p.write_text(
        "time_s,velocity_mm_per_s\n" + "\n".join(csv_rows([r["t"], v * 1e3], ".5f")) + "\n"
    )
    sidecar(p, sidecar_of(r))
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "velocity only, AC-coupled (one-pole 0.5 Hz high-pass) at 3 Hz",
    }


def c_accel_1g(d: Path) -> Case:
    """An accelerometer on the oscillator's axis along gravity: z in g, reading 1 g at rest."""
    r = rig(
        34,
        f=4.0,
        zeta=0.01,
        mu_k=0.03,
        N=2.0,
        m=0.4,
        x0=0.01,
        fs=400,
        t_pre=1.0,
        t_post=2.0,
        nx=0,
        nv=0,
    )
    acc = np.gradient(r["v"], r["t"])
    rng = np.random.default_rng(34)
    az = 1.0 + acc / G + rng.normal(0, 0.002, acc.size)
    ax = rng.normal(0, 0.002, acc.size) + 0.01
    ay = rng.normal(0, 0.002, acc.size) - 0.02
    p = d / "accelerometer_g.csv"
    p.write_text(
        "time_s,acc_x_g,acc_y_g,acc_z_g\n" + "\n".join(csv_rows([r["t"], ax, ay, az], ".6f")) + "\n"
    )
    sidecar(p, sidecar_of(r))
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "accelerometer x,y,z in g, 1 g on the oscillating axis",
    }


def c_adc24_sidecar(d: Path) -> Case:
    """A 24-bit ADC's raw counts; the sidecar gives its scale (m per count) and rate."""
    r = rig(35, f=32.6, fs=2000, nx=1e-6, nv=1e-9)
    lsb = 2.5e-6 / 2**12  # a 24-bit ADC on a ±... probe: 0.6 nm per count
    counts = np.round(r["x"] / lsb).astype(int)
    p = d / "adc24.txt"
    p.write_text("\n".join(str(c) for c in counts) + "\n")
    sidecar(p, sidecar_of(r, sample_rate_Hz=2000.0, scale_m_per_count=lsb))
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "24-bit ADC counts, one column, scale in the sidecar",
    }


def c_jitter_resampled(d: Path) -> Case:
    """Resampled to 1234.567 Hz, time stamps jittered by ±2 % of a step."""
    from unseen_rigs import simulate

    fs = 1234.567
    rng = np.random.default_rng(36)
    k = 2 * np.pi * 32.6
    k = 0.035 * k**2
    x_c, x_s = 0.03 * 0.3 / k, 0.04 * 0.3 / k
    t, x, v = simulate(32.6, 0.02, x_c, x_s, 2e-3, fs, 0.05, 0.1, rng, 1e-6, 2e-4)
    stamps = t + rng.uniform(-0.02, 0.02, t.size) / fs
    p = d / "resampled_jitter.csv"
    p.write_text(
        "time_s,displacement_m,velocity_m_per_s\n"
        + "\n".join(f"{a:.7f},{b:.5e},{c:.5e}" for a, b, c in zip(stamps, x, v, strict=True))
        + "\n"
    )
    sidecar(p, dict(rig(36)["meta"]))
    return {
        "file": p,
        "args": [],
        "truth": {"zeta": 0.02, "mu_k": 0.03},
        "kind": "1234.567 Hz, stamps jittered ±2 % of a step",
    }


def c_clock_times(d: Path) -> Case:
    """A data logger writing the time of day, ``HH:MM:SS.fff``, crossing a minute."""
    r = rig(
        37,
        f=2.0,
        zeta=0.01,
        mu_k=0.05,
        N=2.0,
        m=0.3,
        x0=0.08,
        fs=100,
        t_pre=0.5,
        t_post=1.5,
        nx=2e-4,
        nv=5e-3,
    )
    t0 = 14 * 3600 + 7 * 60 + 55.0
    stamps = [f"{int(s // 3600):02d}:{int(s % 3600 // 60):02d}:{s % 60:06.3f}" for s in t0 + r["t"]]
    p = d / "logger_clock.csv"
    rows = [f"{a},{b * 1e3:.2f}" for a, b in zip(stamps, r["x"], strict=True)]
    p.write_text("Time,Position (mm)\n" + "\n".join(rows) + "\n")
    sidecar(p, sidecar_of(r))
    return {"file": p, "args": [], "truth": r["truth"], "kind": "HH:MM:SS.fff time of day"}


def c_iso_times(d: Path) -> Case:
    """ISO 8601 date-times with a zone, as a cloud logger exports them."""
    r = rig(
        38,
        f=1.8,
        zeta=0.012,
        mu_k=0.04,
        N=2.0,
        m=0.4,
        x0=0.07,
        fs=50,
        t_pre=0.5,
        t_post=1.5,
        nx=2e-4,
        nv=5e-3,
    )
    base = np.datetime64("2026-11-30T23:59:57.500")
    stamps = [str(base + np.timedelta64(round(s * 1e6), "us"))[:23] + "Z" for s in r["t"]]
    p = d / "cloud_iso.csv"
    rows = [f"{a},{b:.4f},{c:.3f}" for a, b, c in zip(stamps, r["x"], r["v"], strict=True)]
    p.write_text("timestamp,position_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, sidecar_of(r))
    return {"file": p, "args": [], "truth": r["truth"], "kind": "ISO 8601 stamps across midnight"}


def c_dat_bom_crlf(d: Path) -> Case:
    """Whitespace-separated ``.dat``: ``#`` comment lines, a UTF-8 BOM, CRLF line ends."""
    r = rig(39, fs=2000)
    p = d / "rig_output.dat"
    lines = [
        "# free decay, rig B",
        "# columns: time [s]  displacement [um]  velocity [mm/s]",
        "#",
        "# t_s      x_um      v_mm_per_s",
    ] + [
        f"{a:10.6f}  {b * 1e6:10.4f}  {c * 1e3:9.4f}"
        for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)
    ]
    p.write_bytes(("\ufeff" + "\r\n".join(lines) + "\r\n").encode("utf-8"))
    sidecar(p, sidecar_of(r))
    return {"file": p, "args": [], "truth": r["truth"], "kind": ".dat, # comments, BOM, CRLF"}


def c_scope_pretrigger(d: Path) -> Case:
    """A scope record: 20 % pre-trigger, the trigger (release) at t = 0, negative times."""
    r = rig(40, fs=10000, t_pre=0.1, t_post=0.1, nx=5e-7, nv=1e-9)
    t = r["t"] - 0.1
    p = d / "scope_pretrig.csv"
    p.write_text(
        "Time (s),Displacement (mm)\n"
        + "\n".join(f"{a:.5f},{b * 1e3:.5f}" for a, b in zip(t, r["x"], strict=True))
        + "\n"
    )
    sidecar(p, sidecar_of(r))
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "pre-trigger, t < 0 before the release",
    }


def pink(n: int, rng: np.random.Generator) -> np.ndarray:
    """Unit-variance 1/f noise by shaping white noise's spectrum."""
    w = np.fft.rfft(rng.normal(size=n))
    f = np.arange(w.size, dtype=float)
    f[0] = 1.0
    x = np.fft.irfft(w / np.sqrt(f), n)
    return x / x.std()


def c_fade_1f(d: Path) -> Case:
    """A viscous decay fading 12 time constants into 1/f noise, no stop, no rest after."""
    rng = np.random.default_rng(41)
    # 20 s: the release of 1 mm decays to 1 µm after 9 s, then 11 s of noise
    n = 20000
    t = np.arange(n) / 1000.0
    w = 2 * np.pi * 12.0
    wd = w * np.sqrt(1 - 1e-4)
    tau = np.clip(t - 0.2, 0, None)
    x = np.where(
        t < 0.2,
        1e-3,
        1e-3 * np.exp(-0.01 * w * tau) * (np.cos(wd * tau) + 0.01 * w / wd * np.sin(wd * tau)),
    )
    x = x + 2e-6 * pink(n, rng) + rng.normal(0, 5e-7, n)
    p = d / "fade_pink.csv"
    p.write_text(
        "time_s,displacement_m\n"
        + "\n".join(f"{a:.4f},{b:.5e}" for a, b in zip(t, x, strict=True))
        + "\n"
    )
    sidecar(p, {"natural_frequency_Hz": 12.0})
    return {
        "file": p,
        "args": ["--law", "viscous"],
        "truth": {"zeta": 0.01},
        "kind": "viscous decay into 1/f noise (2 µm), --law viscous",
    }


def c_duffing(d: Path) -> Case:
    """A Duffing-stiffened cantilever: the frequency falls 1 % over the decay."""
    f0, zeta = 50.0, 0.003
    w = 2 * np.pi * f0
    x0 = 1e-3
    # frequency ≈ f0 (1 + 3/8 β A²): 1 % at A = x0
    beta = 0.01 / (3 / 8 * x0**2)
    m, N, mu_k, mu_s = 0.02, 0.05, 0.05, 0.07
    k = m * w**2
    ac = mu_k * N / m
    as_ = mu_s * N / m
    t, x, v = ivp_decay(
        lambda y: w**2 * (y + beta * y**3),
        lambda u: 2 * zeta * w * u,
        ac,
        as_,
        x0,
        20000.0,
        0.02,
        0.05,
    )
    rng = np.random.default_rng(42)
    x = x + rng.normal(0, 5e-8, x.size)
    v = v + rng.normal(0, 1e-4, x.size)
    p = d / "duffing_cantilever.csv"
    p.write_text(
        "time_s,displacement_m,velocity_m_per_s\n"
        + "\n".join(f"{a:.6f},{b:.6e},{c:.6e}" for a, b, c in zip(t, x, v, strict=True))
        + "\n"
    )
    sidecar(p, {"load_N": N, "mass_kg": m, "natural_frequency_Hz": f0})
    del k
    return {
        "file": p,
        "args": [],
        "truth": {"zeta": zeta, "mu_k": mu_k},
        "kind": "Duffing cantilever, frequency 1 % higher at the release",
    }


def c_air_pendulum(d: Path) -> Case:
    """A large pendulum bob in air: quadratic drag, angle in radians, ``--law auto``."""
    f0 = 0.5
    w = 2 * np.pi * f0
    gamma = 0.05  # θ'' = -ω² sin θ - γ θ'|θ'| [1/rad]
    t, th, _om = ivp_decay(
        lambda y: w**2 * np.sin(y),
        lambda u: gamma * u * abs(u),
        0.0,
        0.0,
        0.5,
        50.0,
        1.0,
        0.0,
        t_end=151.0,
    )
    th = th + np.random.default_rng(43).normal(0, 2e-4, t.size)
    p = d / "pendulum_air.csv"
    p.write_text(
        "time_s,angle_rad\n"
        + "\n".join(f"{a:.3f},{b:.6f}" for a, b in zip(t, th, strict=True))
        + "\n"
    )
    sidecar(p, {"natural_frequency_Hz": f0})
    return {
        "file": p,
        "args": ["--law", "auto"],
        "truth": {"c2": gamma},
        "kind": "pendulum (0.5 rad) in air, quadratic drag, --law auto",
    }


def c_excel_two_runs(d: Path) -> Case:
    """An Excel workbook with two runs on two sheets, units in the header."""
    import openpyxl

    r1 = rig(
        44,
        f=2.0,
        zeta=0.01,
        mu_k=0.05,
        N=2.0,
        m=0.3,
        x0=0.08,
        fs=50,
        t_pre=0.5,
        t_post=1.5,
        nx=2e-4,
        nv=5e-3,
    )
    r2 = rig(
        45,
        f=2.0,
        zeta=0.02,
        mu_k=0.02,
        N=2.0,
        m=0.3,
        x0=0.06,
        fs=50,
        t_pre=0.5,
        t_post=1.5,
        nx=2e-4,
        nv=5e-3,
    )
    wb = openpyxl.Workbook()
    for i, r in enumerate((r1, r2)):
        ws = wb.active if i == 0 else wb.create_sheet()
        ws.title = f"Run {i + 1}"
        ws.append(["Time (s)", "Position (m)", "Velocity (m/s)"])
        for a, b, c in zip(r["t"], r["x"], r["v"], strict=True):
            ws.append([round(float(a), 3), round(float(b), 5), round(float(c), 4)])
    p = d / "two_runs.xlsx"
    wb.save(p)
    sidecar(p, sidecar_of(r1))
    return {
        "file": p,
        "args": [],
        "truth": r1["truth"],
        "truth_by_sheet": {"Run 2": r2["truth"], "1": r2["truth"]},
        "kind": "Excel, two runs on two sheets (truth of sheet 1; sheet 2 checked if read)",
    }


def c_tdms_daq(d: Path) -> Case:
    """A TDMS file as a DAQ writes it: waveform channels, ``wf_increment``, units in mm."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    r = rig(46, fs=5000, nx=5e-7, nv=5e-5)
    props = {
        "wf_increment": 1 / 5000.0,
        "wf_start_offset": 0.0,
        "wf_samples": int(r["x"].size),
        "NI_UnitDescription": "mm",
        "unit_string": "mm",
    }
    pv = {**props, "NI_UnitDescription": "mm/s", "unit_string": "mm/s"}
    p = d / "daq.tdms"
    with TdmsWriter(p) as w:
        w.write_segment(
            [
                RootObject({"name": "free decay"}),
                GroupObject("Dev1", {}),
                ChannelObject("Dev1", "ai0", r["x"] * 1e3, properties=props),
                ChannelObject("Dev1", "ai1", r["v"] * 1e3, properties=pv),
            ]
        )
    sidecar(p, sidecar_of(r))
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "TDMS, ai0 (mm), ai1 (mm/s), wf_increment",
    }


def c_uff58(d: Path) -> Case:
    """A UFF 58 time record (modal software), displacement in mm."""
    import pyuff

    r = rig(47, fs=5000, nx=5e-7, nv=1e-9)
    p = d / "record.uff"
    u = pyuff.UFF(str(p))
    u.write_sets(
        {
            "type": 58,
            "func_type": 1,
            "rsp_node": 1,
            "rsp_dir": 3,
            "ref_node": 1,
            "ref_dir": 3,
            "data": r["x"] * 1e3,
            "x": r["t"],
            "id1": "free decay",
            "rsp_ent_name": "beam",
            "ref_ent_name": "beam",
            "abscissa_spacing": 1,
            "abscissa_spec_data_type": 17,
            "ordinate_spec_data_type": 8,
            "orddenom_spec_data_type": 0,
            "z_axis_spec_data_type": 0,
            "abscissa_axis_units_lab": "s",
            "ordinate_axis_units_lab": "mm",
            "abscissa_len_unit_exp": 0,
            "ordinate_len_unit_exp": 1,
        },
        mode="overwrite",
    )
    sidecar(p, sidecar_of(r))
    return {"file": p, "args": [], "truth": r["truth"], "kind": "UFF 58, displacement in mm"}


def c_hum_50hz(d: Path) -> Case:
    """A 12 Hz oscillator with mains hum (50 Hz) ten times the white noise."""
    r = rig(
        48,
        f=12.0,
        zeta=0.005,
        mu_k=0.02,
        N=1.0,
        m=0.2,
        x0=2e-3,
        fs=1000,
        t_pre=0.5,
        t_post=1.0,
        nx=2e-6,
        nv=1e-9,
    )
    x = r["x"] + 20e-6 * np.sin(2 * np.pi * 50.0 * r["t"] + 0.3)
    p = d / "hum.csv"
    p.write_text(
        "time_s,displacement_m\n"
        + "\n".join(f"{a:.4f},{b:.6e}" for a, b in zip(r["t"], x, strict=True))
        + "\n"
    )
    sidecar(p, sidecar_of(r))
    return {"file": p, "args": [], "truth": r["truth"], "kind": "12 Hz, 50 Hz hum at 10× the noise"}


def c_kgf_grams(d: Path) -> Case:
    """A sidecar giving the load in kgf and the mass in grams, units in the keys."""
    r = rig(49, fs=2000)
    p = d / "units_sidecar.csv"
    p.write_text(
        "time_s,displacement_m,velocity_m_per_s\n"
        + "\n".join(csv_rows([r["t"], r["x"], r["v"]], ".6e"))
        + "\n"
    )
    sidecar(
        p,
        {
            "load_kgf": r["meta"]["load_N"] / G,
            "mass_g": r["meta"]["mass_kg"] * 1e3,
            "natural_frequency_Hz": r["meta"]["natural_frequency_Hz"],
        },
    )
    return {"file": p, "args": [], "truth": r["truth"], "kind": "sidecar load_kgf, mass_g"}


CASES: dict[str, Callable[[Path], Case]] = {
    name[2:]: fn for name, fn in dict(globals()).items() if name.startswith("c_") and callable(fn)
}


# ------------------------------------------------------------------ running
def bayestribo(args: list[str], env: dict[str, str], timeout: float) -> dict[str, Any]:
    """Run ``bayestribo ARGS`` in a subprocess from a neutral folder (``python -m`` puts
    the working folder first on the path: run from a tree, it would import that tree's
    package whatever ``PYTHONPATH`` says); exit status, stdout, stderr, CPU seconds."""
    t0 = os.times()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "bayestribo", *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=timeout,
            cwd=tempfile.gettempdir(),
        )
        rc, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = None, "", "timeout"
    t1 = os.times()
    return {"rc": rc, "stdout": out, "stderr": err, "cpu_s": t1.children_user - t0.children_user}


#: An option the package's messages advise, written as the user would type it.
_OPTION = re.compile(r"--[a-z][a-z-]+(?:[ =](?!--)[^\s`'\"),;]+)*")


def advice_of(stderr: str) -> list[str]:
    """The options a refusal names, parsed from its text as a user would copy them.

    The first back-quoted (or quoted) span that starts with ``--``, or else the options
    written in the text (``--name value ...``), up to the first sentence end.
    """
    text = " ".join(stderr.split())
    for span in re.findall(r"`([^`]*--[^`]+)`", text):
        words = shlex.split(span)
        while words and not words[0].startswith("--"):
            words.pop(0)
        if words:
            return words
    for span in re.findall(r"[`'\"]((?:bayestribo \w+ \S+ )?--[^`'\"]+)[`'\"]", text):
        words = shlex.split(span.split(" --", 1)[0] if not span.startswith("--") else span)
        words = [w for w in shlex.split(span) if w]
        while words and not words[0].startswith("--"):
            words.pop(0)
        if words:
            return words
    found = _OPTION.findall(text)
    out: list[str] = []
    for f in found:
        out += f.replace("=", " ", 1).split() if f.startswith("--window") else f.split()
    return out


def warning_advice(stderr: str, given: list[str]) -> list[str]:
    """The option a warning (exit 1) advises, as a user would follow it: a named
    reading or force (``--restoring pendulum``, ``--pendulum-radius simple``) before the
    general ``--law auto``; [] when it names none not given already."""
    text = " ".join(stderr.split())
    found = []
    pairs = {tuple(given[i : i + 2]) for i in range(len(given))}
    for option in _OPTION.findall(text):
        words = option.split()
        if tuple(words[:2]) in pairs or words[0] in found_names(found):
            continue
        found.append(words)
    specific = [w for w in found if w[0] != "--law"]
    chosen = specific[0] if specific else (found[0] if found else [])
    if chosen and chosen[0] == "--restoring" and "auto" not in chosen:
        chosen = chosen[:2]
    return chosen[:2]


def found_names(found: list[list[str]]) -> set[str]:
    """The option names among ``found``."""
    return {w[0] for w in found}


UNITS = {
    "rad": 1.0,
    "deg": np.pi / 180,
    "°": np.pi / 180,
    "m": 1.0,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
}


def verdict(fit: dict[str, Any], truth: dict[str, Any]) -> dict[str, Any]:
    """Which of the truth's parameters the printed 95 % intervals cover (units converted)."""
    out: dict[str, Any] = {}
    params = fit.get("parameters") or {}
    for name, true in truth.items():
        if name.endswith("_unit"):
            continue
        key = name
        if name == "x_c":
            key = next(
                (
                    k
                    for k in params
                    if params[k].get("symbol") in ("x_c", "θ_c") or k in ("x_c", "d_k")
                ),
                "mu_k" if "mu_k" in params else "",
            )
        if key not in params:
            out[name] = {"truth": true, "reported": sorted(params), "covers": None}
            continue
        lo, hi = params[key]["interval"]
        unit = params[key].get("unit") or ""
        t = true
        if name == "x_c":
            tu = truth.get("x_c_unit", "m")
            if unit in UNITS and tu in UNITS:
                t = true * UNITS[tu] / UNITS[unit]
        out[name] = {
            "truth": t,
            "key": key,
            "interval": [lo, hi],
            "unit": unit,
            "covers": bool(lo <= t <= hi),
            "z": (params[key]["mean"] - t) / params[key]["sd"] if params[key].get("sd") else None,
        }
    return out


def fit_record(
    path: str, args: list[str], truth: dict[str, Any], env: dict[str, str], timeout: float
) -> dict[str, Any]:
    """``bayestribo fit PATH ARGS --json``: exit status, warnings, error, coverage."""
    fit = bayestribo(["fit", path, *args, "--json"], env, timeout)
    rec: dict[str, Any] = {
        "command": " ".join(["bayestribo fit", Path(path).name, *args]),
        "rc": fit["rc"],
        "cpu_s": round(fit["cpu_s"], 2),
        "warnings": warnings_of(fit["stderr"]),
        "stderr": fit["stderr"][-2000:],
    }
    try:
        res = json.loads(fit["stdout"])
    except json.JSONDecodeError:
        res = None
    if res:
        rec["law"] = res.get("law")
        rec["restoring"] = res.get("restoring")
        rec["converged"] = (res.get("diagnostics") or {}).get("converged")
        rec["units"] = {k: v.get("unit") for k, v in (res.get("parameters") or {}).items()}
        rec["coverage"] = verdict(res, truth)
    return rec


def run_case(name: str, d: Path, env: dict[str, str], timeout: float) -> dict[str, Any]:
    """Write one case's file, inspect it and fit it as a user would; where the fit is
    refused (exit 2) and the message names options, fit again with them."""
    case = CASES[name](d)
    path = str(case["file"])
    ins = bayestribo(
        ["inspect", path, *[a for a in case["args"] if a not in ("--law", "auto", "viscous")]],
        env,
        timeout,
    )
    rec: dict[str, Any] = {
        "case": name,
        "kind": case["kind"],
        "truth": case["truth"],
        "inspect_rc": ins["rc"],
        "inspect_head": ins["stdout"].splitlines()[:16],
        "inspect_stderr": ins["stderr"][-1500:],
        **fit_record(path, case["args"], case["truth"], env, timeout),
    }
    if rec["rc"] == 1:
        advice = warning_advice(rec["stderr"], case["args"])
        rec["advice"] = advice
        if advice:
            rest = list(case["args"])
            if advice[0] in rest:  # the option advised replaces the one given
                i = rest.index(advice[0])
                del rest[i : i + 2]
            rec["followup"] = fit_record(path, [*rest, *advice], case["truth"], env, timeout)
    if rec["rc"] == 2:
        advice = advice_of(rec["stderr"])
        rec["advice"] = advice
        if advice:
            truth = case["truth"]
            for sheet, other in (case.get("truth_by_sheet") or {}).items():
                if "--sheet" in advice and advice[advice.index("--sheet") + 1 :][:1] == [sheet]:
                    truth = other
            rec["followup"] = fit_record(path, [*case["args"], *advice], truth, env, timeout)
    return rec


def safe_case(name: str, d: Path, env: dict[str, str], timeout: float) -> dict[str, Any]:
    """:func:`run_case`, a failure of the probe itself recorded, not raised."""
    try:
        return run_case(name, d, env, timeout)
    except Exception as exc:  # the probe's own bug: recorded, the other cases kept
        return {
            "case": name,
            "kind": "probe failed",
            "rc": None,
            "warnings": [],
            "error": repr(exc),
        }


def line(r: dict[str, Any]) -> str:
    """One line per case: exit status, warnings, coverage."""
    cov = " ".join(
        f"{k}:{'ok' if v['covers'] else ('MISS' if v['covers'] is False else 'absent')}"
        for k, v in (r.get("coverage") or {}).items()
    )
    return f"rc={r['rc']} warnings={len(r['warnings'])} {cov}"


def outcome(r: dict[str, Any]) -> str:
    """A case's outcome in a few words: the exit statuses and the intervals' coverage."""
    last = r.get("followup", r)
    cov = last.get("coverage") or {}
    missed = [k for k, v in cov.items() if v["covers"] is False]
    text = f"exit {r['rc']}" + (f" → {last['rc']}" if last is not r else "")
    if cov:
        text += ", " + (f"{', '.join(missed)} missed" if missed else "covered")
    return text


def table(path: Path, base: Path | None = None) -> str:
    """The results as a Markdown table (with ``base``'s outcome of each case beside)."""
    before = {}
    if base is not None:
        before = {r["case"]: outcome(r) for r in json.loads(base.read_text())["cases"]}
    out = [
        "| case | recording | main | first `fit` | advice followed | warnings | 95 % intervals |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in json.loads(path.read_text())["cases"]:
        last = r.get("followup", r)
        word = {True: "covers", False: "**misses**", None: "not reported"}
        cov = ", ".join(f"{k} {word[v['covers']]}" for k, v in (last.get("coverage") or {}).items())
        then = f"`{' '.join(r.get('advice', []))}`: exit {last['rc']}" if last is not r else "-"
        if last is not r and r["rc"] == 1:
            then = "after the warning's " + then
        said = [re.sub(r"/\S*/", "", w) for w in last["warnings"]]
        warns = "; ".join(" ".join(w.split()[:7]) for w in said) or "-"
        main = before.get(r["case"], "-")
        cells = [r["case"], r["kind"], main, f"exit {r['rc']}", then, warns, cov or "-"]
        out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--name", default="unseen_rigs3")
    ap.add_argument("--package", default=str(ROOT), help="tree whose package is run")
    ap.add_argument("--keep", default=None, help="write the files here and keep them")
    ap.add_argument("--table", action="store_true", help="print the stored results as a table")
    ap.add_argument("--base", default=None, help="with --table: the results of main beside")
    a = ap.parse_args()
    if a.table:
        base = None if a.base is None else RESULTS / f"{a.base}.json"
        print(table(RESULTS / f"{a.name}.json", base))
        return
    names = a.only or list(CASES)
    env = {**os.environ, "PYTHONPATH": a.package, "MPLBACKEND": "Agg"}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(a.keep or tmp)
        d.mkdir(parents=True, exist_ok=True)
        with ThreadPoolExecutor(a.jobs) as pool:
            recs = list(pool.map(lambda n: safe_case(n, d, env, a.timeout), names))
    for r in recs:
        print(
            f"{r['case']:18s} {line(r)}"
            + (f" | then {line(r['followup'])}" if "followup" in r else "")
        )
    path = RESULTS / f"{a.name}.json"
    if a.only and path.exists():
        old = {r["case"]: r for r in json.loads(path.read_text())["cases"]}
        old.update({r["case"]: r for r in recs})
        recs = [old[n] for n in CASES if n in old]
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    settings = {"package": a.package}
    print(
        write_results(
            a.name, {"commit": commit(), "date": stamp, "settings": settings, "cases": recs}
        )
    )


if __name__ == "__main__":
    main()
