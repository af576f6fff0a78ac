"""Recordings as other labs' software writes them, run through the command line as a user would.

Each case is an independent closed-form simulation of a viscous + Coulomb oscillator
(half cycle by half cycle: a damped oscillation about the equilibrium shifted by the
friction displacement, ending when the turning point lies within the static friction's
reach), with its own noise, written in one lab's file format. For each file the probe
runs ``bayestribo inspect FILE`` and ``bayestribo fit FILE [OPTIONS] --json`` in a
subprocess and records the exit status, the warnings, the printed error, and whether the
95 % intervals of ζ and μ_k (or the friction displacement x_c where no load is known)
cover the truth.

Run::

    python benchmarks/unseen_rigs.py [--only NAME ...] [--jobs 2]

Results: ``benchmarks/results/unseen_rigs.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import wave
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import RESULTS, ROOT, commit, write_results

#: A rig: natural frequency [Hz], ζ, μ_k, μ_s, load [N], mass [kg], release [m].
BASE = {"f": 32.6, "zeta": 0.02, "mu_k": 0.03, "mu_s": 0.04, "N": 0.3, "m": 0.035, "x0": 2e-3}


def simulate(
    f: float,
    zeta: float,
    x_c: float,
    x_s: float,
    x0: float,
    fs: float,
    t_pre: float,
    t_post: float,
    rng: np.random.Generator,
    noise_x: float,
    noise_v: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form viscous + Coulomb free decay sampled at ``fs``.

    Parameters
    ----------
    f : float
        Natural frequency [Hz].
    zeta : float
        Viscous damping ratio [-].
    x_c, x_s : float
        Kinetic and static friction displacements [m].
    x0 : float
        Release displacement [m].
    fs : float
        Sample rate [Hz].
    t_pre, t_post : float
        Rest held before the release and kept after the stop [s].
    rng : numpy.random.Generator
        Noise source.
    noise_x, noise_v : float
        White-noise standard deviations of displacement [m] and velocity [m/s].

    Returns
    -------
    t, x, v : numpy.ndarray
        Time [s], displacement [m] and velocity [m/s].
    """
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - zeta**2)
    half = np.pi / wd
    starts, eqs, u0s = [], [], []
    x, t0 = x0, t_pre
    while abs(x) > x_s and len(starts) < 100000:
        e = x_c * np.sign(x)
        starts.append(t0)
        eqs.append(e)
        u0s.append(x - e)
        x = e - (x - e) * np.exp(-zeta * w * half)
        t0 += half
    t_stop = t0
    n = round((t_stop + t_post) * fs)
    t = np.arange(n) / fs
    xs = np.full(n, x0)
    vs = np.zeros(n)
    idx = np.searchsorted(np.asarray(starts), t, side="right") - 1
    moving = (idx >= 0) & (t < t_stop)
    k = idx[moving]
    tau = t[moving] - np.asarray(starts)[k]
    u0 = np.asarray(u0s)[k]
    env = np.exp(-zeta * w * tau)
    xs[moving] = np.asarray(eqs)[k] + u0 * env * (
        np.cos(wd * tau) + zeta * w / wd * np.sin(wd * tau)
    )
    vs[moving] = -u0 * env * (w**2 / wd) * np.sin(wd * tau)
    xs[t >= t_stop] = x
    return t, xs + rng.normal(0, noise_x, n), vs + rng.normal(0, noise_v, n)


def rig(seed: int, **over: float) -> dict[str, Any]:
    """Simulate one rig (``BASE`` with ``over``) and return its arrays and truth."""
    p = {**BASE, "fs": 2000.0, "t_pre": 0.05, "t_post": 0.1, "nx": 1e-6, "nv": 2e-4, **over}
    k = p["m"] * (2 * np.pi * p["f"]) ** 2
    x_c = p["mu_k"] * p["N"] / k
    x_s = p["mu_s"] * p["N"] / k
    rng = np.random.default_rng(seed)
    t, x, v = simulate(
        p["f"],
        p["zeta"],
        x_c,
        x_s,
        p["x0"],
        p["fs"],
        p["t_pre"],
        p["t_post"],
        rng,
        p["nx"],
        p["nv"],
    )
    truth = {"zeta": p["zeta"], "mu_k": p["mu_k"], "x_c": x_c}
    meta = {"load_N": p["N"], "mass_kg": p["m"], "natural_frequency_Hz": p["f"]}
    return {"t": t, "x": x, "v": v, "truth": truth, "meta": meta, "p": p}


def sidecar(path: Path, meta: dict[str, Any]) -> None:
    """Write the JSON sidecar beside ``path``."""
    path.with_suffix(".json").write_text(json.dumps(meta))


# ---------------------------------------------------------------------- the files
Case = dict[str, Any]


def c_tracker(d: Path) -> Case:
    """Tracker (video analysis) export: ``mass A`` line, ``t x y`` tab-separated, 30 fps."""
    r = rig(
        1,
        f=1.2,
        zeta=0.01,
        mu_k=0.02,
        N=2.0,
        m=0.5,
        x0=0.12,
        fs=30,
        t_pre=0.5,
        t_post=2,
        nx=5e-4,
        nv=1e-9,
    )
    p = d / "tracker_spring.txt"
    y = 0.3 + np.random.default_rng(11).normal(0, 5e-4, r["t"].size)
    lines = ["mass A", "t\tx\ty"] + [
        f"{a:.6E}\t{b:.6E}\t{c:.6E}" for a, b, c in zip(r["t"], r["x"], y, strict=True)
    ]
    p.write_text("\n".join(lines) + "\n")
    sidecar(p, r["meta"])
    return {
        "followup": ["--columns", "t", "x", "-"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "Tracker video export (t,x,y; no units)",
    }


def c_phyphox(d: Path) -> Case:
    """phyphox 'Acceleration (without g)' CSV export with an absolute-acceleration column."""
    r = rig(
        2,
        f=1.6,
        zeta=0.008,
        mu_k=0.01,
        N=1.0,
        m=0.25,
        x0=0.05,
        fs=100,
        t_pre=1.0,
        t_post=2,
        nx=1e-9,
        nv=1e-9,
    )
    a = np.gradient(r["v"], r["t"])
    rng = np.random.default_rng(12)
    ax = a + rng.normal(0, 0.02, a.size)
    ay = rng.normal(0, 0.02, a.size)
    az = rng.normal(0, 0.02, a.size)
    ab = np.sqrt(ax**2 + ay**2 + az**2)
    p = d / "phyphox_accel.csv"
    head = ",".join(
        f'"{name}"'
        for name in (
            "Time (s)",
            "Linear Acceleration x (m/s^2)",
            "Linear Acceleration y (m/s^2)",
            "Linear Acceleration z (m/s^2)",
            "Absolute acceleration (m/s^2)",
        )
    )
    rows = [
        f"{t:.9E},{b:.9E},{c:.9E},{e:.9E},{g:.9E}"
        for t, b, c, e, g in zip(r["t"], ax, ay, az, ab, strict=True)
    ]
    p.write_text(head + "\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "phyphox linear acceleration (x,y,z,|a|)",
    }


def c_pasco(d: Path) -> Case:
    """PASCO Capstone: ``Time (s) Run #1,Position (m) Run #1,Velocity (m/s) Run #1``."""
    r = rig(
        3,
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
    p = d / "capstone.csv"
    head = "Time (s) Run #1,Position (m) Run #1,Velocity (m/s) Run #1"
    rows = [f"{a:.3f},{b:.4f},{c:.3f}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text(head + "\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "PASCO Capstone, run tags"}


def c_vernier_ga(d: Path) -> Case:
    """Vernier Graphical Analysis 4: ``Run 1: Time (s)`` headers, quoted."""
    r = rig(
        4,
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
    p = d / "graphical_analysis.csv"
    head = '"Run 1: Time (s)","Run 1: Position (m)","Run 1: Velocity (m/s)"'
    rows = [f"{a:.2f},{b:.4f},{c:.3f}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text(head + "\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "Vernier Graphical Analysis, 'Run 1:' tags",
    }


def c_rigol(d: Path) -> Case:
    """Rigol DS1000Z CSV in volts: ``X,CH1,Start,Increment``; 5 mm/V displacement probe."""
    r = rig(5, fs=5000, nx=5e-7, nv=1e-9)
    p = d / "rigol_ds1054z.csv"
    sens = 5e-3  # m per volt
    dt = 1 / r["p"]["fs"]
    t0 = -r["p"]["t_pre"]
    lines = ["X,CH1,Start,Increment,", f"Sequence,Volt,{t0:.6e},{dt:.6e}"]
    lines += [f"{i},{xv / sens:.5e}," for i, xv in enumerate(r["x"])]
    p.write_text("\n".join(lines) + "\n")
    sidecar(p, r["meta"])
    return {
        "followup": ["--columns", "t", "x", "--scale", "x=5e-3"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "Rigol CSV in volts, sequence column",
    }


def c_lvm(d: Path) -> Case:
    """LabVIEW Write-To-Measurement-File ``.lvm`` (one header, X_Value column, comment)."""
    r = rig(6, fs=2000)
    p = d / "labview_run.lvm"
    n, dt = r["t"].size, 1 / r["p"]["fs"]
    head = (
        "LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\n"
        "Decimal_Separator\t.\nMulti_Headings\tNo\nX_Columns\tOne\nTime_Pref\tRelative\n"
        "Operator\tlab\nDate\t2026/11/30\nTime\t09:15:02.1234\n***End_of_Header***\t\n\n"
        f"Channels\t2\t\nSamples\t{n}\t{n}\t\n"
        "Date\t2026/11/30\t2026/11/30\t\nTime\t09:15:02.1234\t09:15:02.1234\t\n"
        "X_Dimension\tTime\tTime\t\nX0\t0.0000000000000000E+0\t0.0000000000000000E+0\t\n"
        f"Delta_X\t{dt:.6E}\t{dt:.6E}\t\n***End_of_Header***\t\t\t\n"
        "X_Value\tDisplacement\tVelocity\tComment\n"
    )
    rows = [f"{a:.6f}\t{b:.6E}\t{c:.6E}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text(head + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "followup": ["--columns", "t", "x", "v", "--scale", "x=1", "--scale", "v=1"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "LabVIEW .lvm, channels without units",
    }


def c_mat_struct(d: Path) -> Case:
    """MATLAB ``.mat`` holding a struct ``rec`` with fields ``t`` [s] and ``x_mm`` [mm]."""
    import scipy.io

    r = rig(7, fs=2000)
    p = d / "matlab_struct.mat"
    scipy.io.savemat(p, {"rec": {"t": r["t"], "x_mm": r["x"] * 1e3, "fs": r["p"]["fs"]}})
    sidecar(p, r["meta"])
    return {
        "followup": ["--channel", "t=rec.t", "--channel", "x=rec.x_mm"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "MATLAB struct rec.t, rec.x_mm",
    }


def c_hdf5_attrs(d: Path) -> Case:
    """HDF5: a dataset ``/disp`` with attributes ``units='um'``, ``sample_rate``; no time."""
    import h5py

    r = rig(8, fs=2000)
    p = d / "daq_attrs.h5"
    with h5py.File(p, "w") as h:
        ds = h.create_dataset("disp", data=r["x"] * 1e6)
        ds.attrs["units"] = "um"
        ds.attrs["sample_rate"] = 2000.0
    sidecar(p, r["meta"])
    return {
        "followup": ["--channel", "x=disp", "--sample-rate", "2000"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "HDF5 dataset with units and sample_rate attributes",
    }


def c_npz(d: Path) -> Case:
    """NumPy ``np.savez(path, t=t, x=x)`` (metres)."""
    r = rig(9, fs=2000)
    p = d / "arrays.npz"
    np.savez(p, t=r["t"], x=r["x"])
    sidecar(p, r["meta"])
    return {
        "followup": ["--channel", "t=t", "--channel", "x=x"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "NumPy .npz t, x",
    }


def c_wav(d: Path) -> Case:
    """A 16-bit mono WAV at 48 kHz of a piezo pickup on a 440 Hz fork-like beam with a contact."""
    r = rig(
        10,
        f=440.0,
        zeta=0.002,
        mu_k=0.02,
        N=0.5,
        m=0.01,
        x0=2e-4,
        fs=48000,
        t_pre=0.02,
        t_post=0.05,
        nx=2e-8,
        nv=1e-9,
    )
    p = d / "fork.wav"
    full = 4e-4  # metres per full scale
    pcm = np.clip(np.round(r["x"] / full * 32767), -32768, 32767).astype("<i2")
    with wave.open(str(p), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(48000)
        w.writeframes(pcm.tobytes())
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": ["--channel", "x=0", "--scale", "x=4e-4"],
        "truth": r["truth"],
        "kind": "16-bit WAV, 48 kHz, 440 Hz",
    }


def c_ms_wrap(d: Path) -> Case:
    """An Arduino log: ``millis`` as a 16-bit counter that wraps at 65536 ms, ``pos_mm``."""
    r = rig(
        11,
        f=1.0,
        zeta=0.01,
        mu_k=0.02,
        N=1.0,
        m=0.2,
        x0=0.05,
        fs=100,
        t_pre=1.0,
        t_post=2.0,
        nx=5e-5,
        nv=1e-9,
    )
    p = d / "arduino_millis.csv"
    ms = (np.round(r["t"] * 1000).astype(int) + 60000) % 65536
    rows = [f"{a},{b * 1e3:.3f}" for a, b in zip(ms, r["x"], strict=True)]
    p.write_text("time_ms,pos_mm\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "time_ms from a 16-bit counter that wraps",
    }


def c_two_acq(d: Path) -> Case:
    """Two acquisitions appended: the header repeated mid-file, time restarting at 0."""
    r = rig(12, fs=2000)
    r2 = rig(13, fs=2000)
    p = d / "appended.csv"
    h = "time_s,displacement_m,velocity_m_per_s"
    a = [f"{x:.6f},{y:.4e},{z:.4e}" for x, y, z in zip(r["t"], r["x"], r["v"], strict=True)]
    b = [f"{x:.6f},{y:.4e},{z:.4e}" for x, y, z in zip(r2["t"], r2["x"], r2["v"], strict=True)]
    p.write_text("\n".join([h, *a, h, *b]) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "two acquisitions appended (header repeated)",
    }


def c_nan_cells(d: Path) -> Case:
    """A DAQ export with ``NaN`` in a few velocity cells and one ``inf``."""
    r = rig(14, fs=2000)
    p = d / "nan_cells.csv"
    v = r["v"].copy()
    v[[300, 301, 700]] = np.nan
    v[900] = np.inf
    rows = [f"{a:.6f},{b:.4e},{c:.4e}" for a, b, c in zip(r["t"], r["x"], v, strict=True)]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "NaN and inf cells in the velocity"}


def c_tsv_trailing(d: Path) -> Case:
    """Tab-separated with a tab at the end of every line, units in brackets."""
    r = rig(15, fs=2000)
    p = d / "trailing_tabs.txt"
    rows = [
        f"{a:.6f}\t{b * 1e3:.5f}\t{c * 1e3:.3f}\t"
        for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)
    ]
    p.write_text("Time [s]\tDisplacement [mm]\tVelocity [mm/s]\t\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "followup": ["--delimiter", "tab"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "TSV with trailing tabs",
    }


def c_thousands(d: Path) -> Case:
    """A European export: ``;``, decimal commas, thousands separators in the time in ms."""
    r = rig(16, fs=2000)
    p = d / "european_thousands.csv"

    def eu(val: float, nd: int) -> str:
        s = f"{val:,.{nd}f}"
        return s.replace(",", "_").replace(".", ",").replace("_", ".")

    rows = [f"{eu(a * 1e3, 1)};{eu(b * 1e6, 2)}" for a, b in zip(r["t"], r["x"], strict=True)]
    p.write_text("Zeit [ms];Weg [µm]\n" + "\n".join(rows) + "\n", encoding="utf-8")
    sidecar(p, r["meta"])
    return {
        "followup": ["--decimal", ","],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "';', decimal comma, thousands '.' in ms",
    }


def c_v_first(d: Path) -> Case:
    """Columns in the order velocity, time, displacement."""
    r = rig(17, fs=2000)
    p = d / "velocity_first.csv"
    rows = [f"{c:.4e},{a:.6f},{b:.4e}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text("velocity_m_per_s,time_s,displacement_m\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "velocity column before time"}


def c_upside_down(d: Path) -> Case:
    """A displacement sensor mounted the other way round: x negated, v as it is."""
    r = rig(18, fs=2000)
    p = d / "upside_down.csv"
    rows = [f"{a:.6f},{-b:.4e},{c:.4e}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "followup": ["--scale", "v=-1"],
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "displacement sign flipped, velocity not",
    }


def c_mid_swing(d: Path) -> Case:
    """An acquisition started 0.1 s after the release: no rest before, mid swing."""
    r = rig(19, fs=2000)
    p = d / "mid_swing.csv"
    keep = r["t"] >= r["p"]["t_pre"] + 0.1037
    t = r["t"][keep] - r["t"][keep][0]
    rows = [
        f"{a:.6f},{b:.4e},{c:.4e}" for a, b, c in zip(t, r["x"][keep], r["v"][keep], strict=True)
    ]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "starts mid swing, no release"}


def c_slow_pendulum(d: Path) -> Case:
    """A 0.3 Hz pendulum bob, position in metres at 20 Hz."""
    r = rig(
        20,
        f=0.3,
        zeta=0.004,
        mu_k=0.002,
        N=5.0,
        m=2.0,
        x0=0.2,
        fs=20,
        t_pre=3,
        t_post=5,
        nx=2e-4,
        nv=1e-9,
    )
    p = d / "slow_pendulum.csv"
    rows = [f"{a:.3f},{b:.5f}" for a, b in zip(r["t"], r["x"], strict=True)]
    p.write_text("time_s,displacement_m\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "0.3 Hz pendulum, 20 Hz sampling"}


def c_fast_cantilever(d: Path) -> Case:
    """A 5 kHz cantilever with a contact, position in metres at 200 kHz."""
    r = rig(
        21,
        f=5000.0,
        zeta=0.003,
        mu_k=0.05,
        N=0.2,
        m=1e-4,
        x0=2e-5,
        fs=200000,
        t_pre=0.002,
        t_post=0.004,
        nx=1e-9,
        nv=1e-9,
    )
    p = d / "fast_cantilever.csv"
    rows = [f"{a:.8f},{b:.5e}" for a, b in zip(r["t"], r["x"], strict=True)]
    p.write_text("time_s,displacement_m\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": [],
        "truth": r["truth"],
        "kind": "5 kHz cantilever, 200 kHz sampling",
    }


def c_drift(d: Path) -> Case:
    """A DC offset of 3 mm and a linear drift of 20 µm/s on the displacement."""
    r = rig(22, fs=2000)
    p = d / "offset_drift.csv"
    x = r["x"] + 3e-3 + 2e-5 * r["t"]
    rows = [f"{a:.6f},{b:.4e},{c:.4e}" for a, b, c in zip(r["t"], x, r["v"], strict=True)]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "DC offset + linear drift on x"}


def c_keysight_v(d: Path) -> Case:
    """Keysight InfiniiVision CSV: ``x-axis,1,2`` / ``second,Volt,Volt``, two channels in volts."""
    r = rig(23, fs=5000, nx=5e-7, nv=5e-5)
    p = d / "keysight.csv"
    lines = ["x-axis,1,2", "second,Volt,Volt"]
    lines += [
        f"{a - r['p']['t_pre']:.6E},{b / 2e-4:.5E},{c / 5e-3:.5E}"
        for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)
    ]
    p.write_text("\n".join(lines) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": ["--columns", "t", "x", "v", "--scale", "x=2e-4", "--scale", "v=5e-3"],
        "truth": r["truth"],
        "kind": "Keysight CSV, volts with sensitivities",
    }


def c_coulomb_both(d: Path) -> Case:
    """A 1 Hz spring with strong friction (x_c 5 % of the release), both channels at 1 kHz."""
    r = rig(
        25,
        f=1.0,
        zeta=0.01,
        mu_k=0.02,
        N=1.0,
        m=0.2,
        x0=0.05,
        fs=1000,
        t_pre=1.0,
        t_post=2.0,
        nx=5e-5,
        nv=5e-4,
    )
    p = d / "strong_friction.csv"
    rows = [f"{a:.3f},{b:.6e},{c:.6e}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {"file": p, "args": [], "truth": r["truth"], "kind": "1 Hz, x_c 5 % of release, x and v"}


def c_auto(d: Path) -> Case:
    """The canonical CSV, fitted with ``--law auto`` (viscous+coulomb truth)."""
    r = rig(24, fs=2000)
    p = d / "auto_canonical.csv"
    rows = [f"{a:.6f},{b:.4e},{c:.4e}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    p.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    sidecar(p, r["meta"])
    return {
        "file": p,
        "args": ["--law", "auto"],
        "truth": r["truth"],
        "kind": "canonical CSV, --law auto",
    }


CASES: dict[str, Callable[[Path], Case]] = {
    name[2:]: fn for name, fn in dict(globals()).items() if name.startswith("c_") and callable(fn)
}

#: A warning line of the command line: ``bayestribo fit: warning: FILE: text``.
WARN = re.compile(r"^bayestribo \w+: warning: (?:\S+: )?(.*)$", re.MULTILINE)


def warnings_of(stderr: str) -> list[str]:
    """The warnings a command printed, each cut to its first 90 characters."""
    return [w[:90] for w in WARN.findall(stderr)]


def bayestribo(args: list[str], env: dict[str, str], timeout: float) -> dict[str, Any]:
    """Run ``bayestribo ARGS`` in a subprocess; exit status, stdout, stderr, CPU seconds."""
    t0 = os.times()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "bayestribo", *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=timeout,
        )
        rc, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = None, "", "timeout"
    t1 = os.times()
    return {"rc": rc, "stdout": out, "stderr": err, "cpu_s": t1.children_user - t0.children_user}


def verdict(fit: dict[str, Any], truth: dict[str, float]) -> dict[str, Any]:
    """Which of ζ, μ_k (else x_c) the printed 95 % intervals cover."""
    out: dict[str, Any] = {}
    params = fit.get("parameters") or {}
    names = ["zeta", "mu_k"] if "mu_k" in params else ["zeta", "x_c"]
    for name in names:
        key = name
        if name == "x_c":
            key = next(
                (k for k in params if params[k].get("symbol") == "x_c" or k in ("x_c", "d_k")), ""
            )
        if key not in params:
            continue
        lo, hi = params[key]["interval"]
        unit = params[key].get("unit")
        true = truth[name]
        out[name] = {"truth": true, "interval": [lo, hi], "unit": unit, "covers": lo <= true <= hi}
    return out


def fit_record(
    path: str, args: list[str], truth: dict[str, float], env: dict[str, str], timeout: float
) -> dict[str, Any]:
    """``bayestribo fit PATH ARGS --json``: exit status, warnings, error, coverage."""
    fit = bayestribo(["fit", path, *args, "--json"], env, timeout)
    rec: dict[str, Any] = {
        "command": " ".join(["bayestribo fit", Path(path).name, *args]),
        "rc": fit["rc"],
        "cpu_s": round(fit["cpu_s"], 2),
        "warnings": warnings_of(fit["stderr"]),
        "stderr": fit["stderr"][-1500:],
    }
    try:
        res = json.loads(fit["stdout"])
    except json.JSONDecodeError:
        res = None
    if res:
        rec["law"] = res.get("law")
        rec["converged"] = (res.get("diagnostics") or {}).get("converged")
        rec["coverage"] = verdict(res, truth)
    return rec


def run_case(name: str, d: Path, env: dict[str, str], timeout: float) -> dict[str, Any]:
    """Write one case's file, inspect it and fit it as a user would; where the fit is
    refused (exit 2) and the refusal names options, fit again with them."""
    case = CASES[name](d)
    path = str(case["file"])
    ins = bayestribo(
        ["inspect", path, *[a for a in case["args"] if a not in ("--law", "auto")]], env, timeout
    )
    rec: dict[str, Any] = {
        "case": name,
        "kind": case["kind"],
        "truth": case["truth"],
        "inspect_rc": ins["rc"],
        "inspect_head": ins["stdout"].splitlines()[:14],
        **fit_record(path, case["args"], case["truth"], env, timeout),
    }
    if rec["rc"] == 2 and case.get("followup"):
        rec["followup"] = fit_record(path, case["followup"], case["truth"], env, timeout)
    return rec


def line(r: dict[str, Any]) -> str:
    """One line per case: exit status, warnings, coverage."""
    cov = " ".join(
        f"{k}:{'ok' if v['covers'] else 'MISS'}" for k, v in (r.get("coverage") or {}).items()
    )
    return f"rc={r['rc']} warnings={len(r['warnings'])} {cov}"


def table(path: Path) -> str:
    """The results as a Markdown table: case, first command's exit, the advice's, coverage."""
    out = [
        "| case | file as written by | first `fit` | after the refusal's advice | warnings | "
        "95 % intervals |",
        "|---|---|---|---|---|---|",
    ]
    for r in json.loads(path.read_text())["cases"]:
        last = r.get("followup", r)
        cov = ", ".join(
            f"{k} {'covers' if v['covers'] else '**misses**'}"
            for k, v in (last.get("coverage") or {}).items()
        )
        then = (
            f"`{' '.join(last['command'].split()[3:])}`: exit {last['rc']}" if last is not r else ""
        )
        said = [re.sub(r"/\S*/", "", w) for w in last["warnings"]]
        warns = "; ".join(" ".join(w.split()[:6]) for w in said) or "-"
        cells = [r["case"], r["kind"], f"exit {r['rc']}", then or "-", warns, cov or "-"]
        out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--name", default="unseen_rigs")
    ap.add_argument("--table", action="store_true", help="print the stored results as a table")
    a = ap.parse_args()
    if a.table:
        print(table(RESULTS / f"{a.name}.json"))
        return
    names = a.only or list(CASES)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        with ThreadPoolExecutor(a.jobs) as pool:
            recs = list(pool.map(lambda n: run_case(n, d, env, a.timeout), names))
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
    print(write_results(a.name, {"commit": commit(), "date": stamp, "cases": recs}))


if __name__ == "__main__":
    main()
