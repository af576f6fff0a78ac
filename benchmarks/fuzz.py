"""Fuzzing every registered reader: bad files give the package's errors, in bounded memory.

Seed files of every registered format are written from one simulated run (the
canonical CSV and its JSON sidecar, a CSV whose header names units, a Tektronix and a
LabVIEW ``.lvm`` export, an Excel workbook, UFF 58b, TDMS, MATLAB v5 and v7.3, HDF5,
a NumPy ``.npz`` archive and ``.npy`` array, a 16-bit WAV file),
each with the reading options that read it right. ``--mutants`` mutants are drawn
from them, seeded: bytes flipped, the file cut short, bytes inserted or deleted, a block
repeated, 4- and 8-byte fields overwritten with huge values (sizes a header claims),
numbers replaced by ``nan``, ``inf``, ``1e308``, ``-`` or nothing, an empty file; and
sidecars with absurd values (1e308, 1e-320, -1, text, lists, nesting) and misspelt keys.
A seed's mutants are the same in every run but the workbook's, whose file holds the
time it was written.

Each mutant is read in a reading process (``read_run`` with the seed's options, then
``describe_file`` and the ``inspect`` command's code) under an address-space limit and
an alarm; a process reads up to 200 mutants in turn, saying which it starts, so that
one that dies on a mutant (a library's crash) names it, and a fresh process goes on.
Counted per reader: read, refused with the package's error, other exceptions (each
named with its type and the mutation: the goal is none), reads whose resident memory
grew by more than 300 MB, timeouts, crashes.

Run: ``python benchmarks/fuzz.py --mutants 4200``; prints a table and writes
``benchmarks/results/fuzz.json``.
"""

from __future__ import annotations

import argparse
import collections
import json
import random
import re
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import write_results  # noqa: E402

#: Largest growth of a worker's resident memory over one read [MB] (the goal).
MEMORY_GOAL_MB = 300.0
#: Address-space limit of a worker [bytes]: a read that claims more is refused.
ADDRESS_LIMIT = 8 * 1024**3
#: Longest read [s].
ALARM_S = 30

X_PER_V, V_PER_V = 2e-4, 5e-3


def _seed_run() -> Any:
    from bayestribo.synthetic import Release, Sensor, simulate

    return simulate(
        seed=7,
        sensor=Sensor(sample_rate_Hz=2000.0),
        release=Release(motion_duration_s=0.8, rest_before_s=0.05, rest_after_s=0.1),
    )


def write_seeds(folder: Path) -> list[dict[str, Any]]:
    """Seed files, each ``{"name", "reader", "path", "options", "cli"}`` (it reads right)."""
    import numpy as np

    from bayestribo.io import write_run
    from bayestribo.io.sidecar import sidecar_path, write_sidecar

    folder.mkdir(parents=True, exist_ok=True)
    run = _seed_run()
    meta = dict(run.metadata)
    t, x, v = run.time, run.displacement, run.velocity
    seeds = []

    def add(name: str, reader: str, path: Path, options: dict, cli: list[str]) -> None:
        if reader != "sidecar":
            write_sidecar(meta, sidecar_path(path))
        seeds.append(
            {"name": name, "reader": reader, "path": str(path), "options": options, "cli": cli}
        )

    path = write_run(run, folder / "canonical.csv")
    add("canonical CSV", "text", path, {}, [])
    add("sidecar", "sidecar", path, {}, [])
    units = folder / "units.csv"
    rows = [
        f"{a!r},{1e3 * b!r},{1e3 * c!r}"
        for a, b, c in zip(t.tolist(), x.tolist(), v.tolist(), strict=True)
    ]
    units.write_text("time_s,displacement_mm,velocity_mm_per_s\n" + "\n".join(rows) + "\n")
    add("CSV with units", "text", units, {}, [])
    tek = folder / "tektronix.csv"
    head = [
        "Model,MSO44",
        "Firmware Version,1.26.7",
        "",
        "Waveform Type,ANALOG",
        "Horizontal Units,s",
        f"Sample Interval,{t[1] - t[0]:.6e}",
        f"Record Length,{t.size}",
        "Vertical Units,V,V",
        "Label,,",
        "TIME,CH1,CH2",
    ]
    rows = [
        f"{a:.12e},{b / X_PER_V:.12e},{c / V_PER_V:.12e}" for a, b, c in zip(t, x, v, strict=True)
    ]
    tek.write_text("\n".join([*head, *rows]) + "\n")
    scale = {"displacement_m": X_PER_V, "velocity_m_per_s": V_PER_V}
    roles = ["time_s", "displacement_m", "velocity_m_per_s"]
    cli = ["--columns", "t", "x", "v", "--scale", f"x={X_PER_V}", "--scale", f"v={V_PER_V}"]
    add("Tektronix export", "text", tek, {"columns": roles, "scale": scale}, cli)
    lvm = folder / "daq.lvm"
    dt = t[1] - t[0]
    header = [
        "LabVIEW Measurement\t",
        "Writer_Version\t2",
        "Reader_Version\t2",
        "Separator\tTab",
        "Decimal_Separator\t.",
        "Multi_Headings\tNo",
        "X_Columns\tOne",
        "Time_Pref\tRelative",
        "***End_of_Header***\t",
        "",
        "Channels\t2\t",
        f"Samples\t{t.size}\t{t.size}",
        "Y_Unit_Label\tVolts\tVolts",
        "X_Dimension\tTime\tTime",
        f"X0\t{t[0]:.17g}\t{t[0]:.17g}",
        f"Delta_X\t{dt:.17g}\t{dt:.17g}",
        "***End_of_Header***\t",
        "X_Value\tUntitled\tUntitled 1\tComment",
    ]
    rows = [
        f"{a:.12e}\t{b / X_PER_V:.12e}\t{c / V_PER_V:.12e}" for a, b, c in zip(t, x, v, strict=True)
    ]
    lvm.write_text("\n".join([*header, *rows]) + "\n")
    add("LabVIEW export", "text", lvm, {"columns": roles, "scale": scale}, cli)

    import openpyxl

    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Time (s)", "Position (mm)", "Velocity (m/s)"])
    for row in zip(t, 1e3 * x, v, strict=True):
        sheet.append([float(c) for c in row])
    xlsx = folder / "book.xlsx"
    book.save(xlsx)
    add("Excel workbook", "xlsx", xlsx, {}, [])

    import pyuff

    def record(data: Any, spec: int, unit: str) -> dict:
        return pyuff.prepare_58(
            binary=1,
            id1=f"vibrometer {unit}",
            func_type=1,
            rsp_node=1,
            rsp_dir=1,
            ref_node=1,
            ref_dir=1,
            abscissa_spacing=1,
            data=data,
            x=t[0] + dt * np.arange(data.size),
            abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s",
            ordinate_spec_data_type=spec,
            ordinate_axis_units_lab=unit,
            orddenom_spec_data_type=0,
            z_axis_spec_data_type=0,
        )

    uff = folder / "modal.uff"
    pyuff.UFF(str(uff)).write_sets([record(x, 8, "m"), record(v, 11, "m/s")], mode="add")
    add("UFF 58b", "uff", uff, {}, [])

    import nptdms

    props = {"wf_increment": float(dt), "wf_start_offset": 0.0}
    tdms = folder / "daq.tdms"
    with nptdms.TdmsWriter(str(tdms)) as writer:
        writer.write_segment(
            [
                nptdms.ChannelObject("Vib", "Disp", x, {**props, "unit_string": "m"}),
                nptdms.ChannelObject("Vib", "Vel", v, {**props, "unit_string": "m/s"}),
            ]
        )
    channels = {"displacement_m": "Disp", "velocity_m_per_s": "Vel"}
    add(
        "TDMS",
        "tdms",
        tdms,
        {"group": "Vib", "channels": channels},
        ["--group", "Vib", "--channel", "x=Disp", "--channel", "v=Vel"],
    )

    import scipy.io

    mat = folder / "meas.mat"
    scipy.io.savemat(mat, {"meas": {"t": t, "x": 1e3 * x, "v": v}})
    # the header's text holds the time of writing: a fixed one, so that a seed's
    # mutants are the same in every run
    raw = bytearray(mat.read_bytes())
    raw[:116] = b"MATLAB 5.0 MAT-file, written by benchmarks/fuzz.py".ljust(116)
    mat.write_bytes(bytes(raw))
    mat_channels = {"time_s": "meas.t", "displacement_mm": "meas.x", "velocity_m_per_s": "meas.v"}
    mat_cli = ["--channel", "t=meas.t", "--channel", "displacement_mm=meas.x"]
    mat_cli += ["--channel", "v=meas.v"]
    add("MATLAB v5", "mat", mat, {"channels": mat_channels}, mat_cli)

    import h5py

    v73 = folder / "v73.mat"
    with h5py.File(v73, "w", userblock_size=512) as handle:
        for name, values in (("time_s", t), ("displacement_m", x), ("velocity_m_per_s", v)):
            handle.create_dataset(name, data=np.asarray(values)[None, :])
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 ."
    with open(v73, "r+b") as handle:
        handle.write(text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM")
    add("MATLAB v7.3", "mat", v73, {}, [])
    h5 = folder / "run.h5"
    with h5py.File(h5, "w") as handle:
        group = handle.create_group("run1")
        group.create_dataset("time", data=t).attrs["units"] = "s"
        group.create_dataset("displacement", data=1e6 * x).attrs["units"] = "um"
        group.create_dataset("velocity", data=v).attrs["units"] = "m/s"
    add("HDF5", "hdf5", h5, {"group": "run1"}, ["--group", "run1"])
    npz = folder / "arrays.npz"
    np.savez_compressed(npz, time_s=t, displacement_mm=1e3 * x, velocity_m_per_s=v)
    add("NumPy .npz", "npz", npz, {}, [])
    npy = folder / "frames.npy"  # one array, its columns named
    np.save(npy, np.column_stack([t, x, v]))
    columns = ["time_s", "displacement_m", "velocity_m_per_s"]
    add("NumPy .npy", "npz", npy, {"columns": columns}, ["--columns", *columns])
    import scipy.io.wavfile

    wav = folder / "sound.wav"  # 16-bit PCM, one channel: fractions of full scale
    pcm = np.round(x / np.abs(x).max() * 3e4).astype(np.int16)
    scipy.io.wavfile.write(wav, round(1.0 / (t[1] - t[0])), pcm)
    add(
        "WAV",
        "wav",
        wav,
        {"channels": {"displacement_m": "0"}, "metadata": {"length_unit": "arbitrary"}},
        ["--channel", "displacement_m=0", "--length-unit", "arbitrary"],
    )
    return seeds


_NUMBER = re.compile(rb"-?\d+\.\d+(?:e[-+]?\d+)?")
_WEIRD = [b"nan", b"inf", b"-inf", b"1e308", b"-1e308", b"1e-320", b"-", b"", b"0x1p3", b"1,5"]
_HUGE = [
    b"\xff\xff\xff\xff",
    b"\xff\xff\xff\x7f",
    b"\x00\x00\x00\x80",
    b"\xff" * 8,
    b"\x7f" + b"\xff" * 7,
]
_SIDECAR_VALUES = [1e308, 1e-320, -1, 0, "x", [], {}, None, True, [[[[[1]]]]], "1e400", 2**70]


def mutate(data: bytes, reader: str, rng: random.Random) -> tuple[bytes, str]:
    """One mutant of ``data`` and a word for the mutation."""
    if reader == "sidecar":
        return _mutate_sidecar(data, rng)
    kinds = ["flip", "truncate", "insert", "delete", "repeat", "huge", "empty"]
    if reader in ("text", "sidecar"):
        kinds += ["number"] * 3
    kind = rng.choice(kinds)
    n = len(data)
    if kind == "empty" or n == 0:
        return b"", "empty"
    if kind == "flip":
        out = bytearray(data)
        for _ in range(rng.randint(1, 20)):
            i = rng.randrange(n)
            out[i] ^= 1 << rng.randrange(8)
        return bytes(out), kind
    if kind == "truncate":
        return data[: rng.randrange(n)], kind
    if kind == "insert":
        i = rng.randrange(n)
        return data[:i] + rng.randbytes(rng.randint(1, 64)) + data[i:], kind
    if kind == "delete":
        i = rng.randrange(n)
        return data[:i] + data[i + rng.randint(1, 4096) :], kind
    if kind == "repeat":
        i = rng.randrange(n)
        block = data[i : i + rng.randint(1, 4096)]
        return data[:i] + block * rng.randint(2, 50) + data[i:], kind
    if kind == "huge":
        out = bytearray(data)
        # header fields (sizes, counts, offsets) sit in the first kilobytes
        for _ in range(rng.randint(1, 6)):
            i = rng.randrange(min(n, 4096))
            field = rng.choice(_HUGE)
            out[i : i + len(field)] = field
        return bytes(out[:n] if len(out) > n else out), kind
    matches = list(_NUMBER.finditer(data))
    if not matches:
        return data[: n // 2], "truncate"
    m = rng.choice(matches)
    return data[: m.start()] + rng.choice(_WEIRD) + data[m.end() :], kind


def _mutate_sidecar(data: bytes, rng: random.Random) -> tuple[bytes, str]:
    try:
        meta = json.loads(data)
    except ValueError:
        meta = {}
    kind = rng.choice(["value", "value", "typo", "text"])
    if kind == "text":
        out = bytearray(data)
        for _ in range(rng.randint(1, 5)):
            if out:
                out[rng.randrange(len(out))] = rng.randrange(256)
        return bytes(out), "sidecar bytes"
    keys = list(meta) or ["load_N"]
    key = rng.choice(keys)
    if kind == "typo":
        word = list(key)
        i = rng.randrange(len(word))
        word[i] = rng.choice("abcdefghijklmnopqrstuvwxyz_")
        meta["".join(word)] = meta.pop(key, 1.0)
        return json.dumps(meta).encode(), "sidecar key typo"
    meta[key] = rng.choice(_SIDECAR_VALUES)
    return json.dumps(meta, allow_nan=True).encode(), f"sidecar {key}"


def _task(item: dict[str, Any]) -> dict[str, Any]:
    """Read one mutant in this worker: the outcome, its memory growth and its time."""
    import warnings

    from bayestribo.errors import BayestriboError
    from bayestribo.io import read_run
    from bayestribo.io.layout import describe_file

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    outcome, detail = "read", ""

    def alarm(signum: int, frame: Any) -> None:
        raise TimeoutError(f"more than {ALARM_S} s")

    signal.signal(signal.SIGALRM, alarm)
    signal.alarm(ALARM_S)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            stage = "describe_file"
            describe_file(
                item["path"],
                **{
                    k: v
                    for k, v in item["options"].items()
                    if k in ("file_format", "skip_rows", "encoding", "sheet")
                },
            )
            stage = "read_run"
            read_run(item["path"], **item["options"])
            stage = "inspect"
            from contextlib import redirect_stderr, redirect_stdout
            from io import StringIO

            from bayestribo.cli import main

            with redirect_stdout(StringIO()), redirect_stderr(StringIO()):
                main(["inspect", item["path"], *item["cli"]])
    except BayestriboError as exc:
        outcome, detail = "package error", f"{stage}: {type(exc).__name__}"
    except TimeoutError:
        outcome, detail = "timeout", stage
    except MemoryError:
        outcome, detail = "memory error", stage
    except SystemExit as exc:  # argparse refusing an option: the command line's error
        outcome, detail = ("package error", f"{stage}: exit {exc.code}")
    except Exception as exc:
        tb = traceback.extract_tb(exc.__traceback__)
        where = next(
            (
                f"{Path(f.filename).name}:{f.lineno}"
                for f in reversed(tb)
                if "bayestribo" in f.filename
            ),
            "?",
        )
        outcome, detail = (
            "other exception",
            f"{stage}: {type(exc).__name__} at {where}: {str(exc)[:120]}",
        )
    finally:
        signal.alarm(0)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "reader": item["reader"],
        "seed": item["seed"],
        "mutation": item["mutation"],
        "outcome": outcome,
        "detail": detail,
        "growth_MB": max(0.0, (peak - before) / 1024),
        "peak_MB": peak / 1024,
        "seconds": time.perf_counter() - start,
    }


def _init() -> None:
    import logging

    logging.disable(logging.WARNING)  # npTDMS's notes on damaged files
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_LIMIT, ADDRESS_LIMIT))
    import bayestribo.cli
    import bayestribo.io  # noqa: F401


#: Mutants a reading process reads before a fresh one takes over (its peak memory is
#: the measure of a read's growth).
PER_PROCESS = 200

_CHILD = """
import json, sys
sys.path.insert(0, sys.argv[1])
import fuzz
fuzz._init()
items = json.load(open(sys.argv[2]))
for i in map(int, sys.argv[3:]):
    print("start", i, flush=True)
    print("done", i, json.dumps(fuzz._task(items[i])), flush=True)
"""


def _drive(items: list[dict[str, Any]], workers: int, listing: Path) -> list[dict[str, Any]]:
    """Every mutant read in reading processes, ``workers`` at a time, each process
    reading up to :data:`PER_PROCESS` of them in turn and saying which it starts: a
    process that dies on one (a library's crash, SIGSEGV) is counted against that
    mutant as a ``crash``, and a new process goes on from the next."""
    listing.write_text(json.dumps(items))
    results: list[dict[str, Any] | None] = [None] * len(items)
    shares = [list(range(w, len(items), workers)) for w in range(workers)]

    def work(share: list[int]) -> None:
        while share:
            batch, share[:] = share[:PER_PROCESS], share[PER_PROCESS:]
            while batch:
                command = [sys.executable, "-c", _CHILD, str(HERE), str(listing)]
                try:
                    done = subprocess.run(
                        [*command, *map(str, batch)],
                        capture_output=True,
                        text=True,
                        timeout=60 + 2 * ALARM_S * len(batch),
                    )
                    stdout, code = done.stdout, done.returncode
                except subprocess.TimeoutExpired as hung:  # past every read's alarm
                    stdout, code = (hung.stdout or b"").decode(errors="replace"), "hung"
                started = None
                for line in stdout.splitlines():
                    word, index, *rest = line.split(" ", 2)
                    if word == "start":
                        started = int(index)
                    elif word == "done":
                        results[int(index)] = json.loads(rest[0])
                        started = None
                batch = [i for i in batch if results[i] is None]
                if started is None or code == 0:
                    if batch:  # the process ended before its batch, not on a mutant
                        raise RuntimeError(f"a reading process ended early (exit {code})")
                    break
                item = items[started]
                results[started] = {
                    "reader": item["reader"],
                    "seed": item["seed"],
                    "mutation": item["mutation"],
                    "outcome": "crash",
                    "detail": f"the reading process died (exit {code}): {item['path']}",
                    "growth_MB": 0.0,
                    "peak_MB": 0.0,
                    "seconds": float("nan"),
                }
                batch = [i for i in batch if i != started]

    threads = [threading.Thread(target=work, args=(share,)) for share in shares]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return [r for r in results if r is not None]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mutants", type=int, default=4200)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default="fuzz")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="bt-fuzz-") as tmp:
        folder = Path(tmp)
        seeds = write_seeds(folder / "seeds")
        items = []
        for k in range(args.mutants):
            seed = seeds[k % len(seeds)]
            path = Path(seed["path"])
            target = folder / "mutants" / f"{k:05d}"
            target.mkdir(parents=True)
            if seed["reader"] == "sidecar":
                data = path.with_suffix(".json").read_bytes()
                mutant, how = mutate(data, "sidecar", rng)
                file = target / path.name
                file.write_bytes(path.read_bytes())
                file.with_suffix(".json").write_bytes(mutant)
            else:
                mutant, how = mutate(path.read_bytes(), seed["reader"], rng)
                file = target / path.name
                file.write_bytes(mutant)
                file.with_suffix(".json").write_bytes(path.with_suffix(".json").read_bytes())
            items.append(
                {
                    "path": str(file),
                    "options": seed["options"],
                    "cli": seed["cli"],
                    "reader": seed["reader"],
                    "seed": seed["name"],
                    "mutation": how,
                }
            )
        results = _drive(items, args.workers, folder / "items.json")
    wall = time.perf_counter() - start
    table: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    for r in results:
        table[r["seed"]][r["outcome"]] += 1
        if r["growth_MB"] > MEMORY_GOAL_MB:
            table[r["seed"]]["over 300 MB"] += 1
    outcomes = [
        "read",
        "package error",
        "other exception",
        "memory error",
        "timeout",
        "crash",
        "over 300 MB",
    ]
    print(f"{'seed file':18s} " + " ".join(f"{o:>15s}" for o in outcomes))
    for seed, counts in table.items():
        print(f"{seed:18s} " + " ".join(f"{counts[o]:15d}" for o in outcomes))
    total = collections.Counter()
    for counts in table.values():
        total.update(counts)
    print(f"{'all':18s} " + " ".join(f"{total[o]:15d}" for o in outcomes))
    escapes = [
        r
        for r in results
        if r["outcome"] in ("other exception", "memory error", "timeout", "crash")
    ]
    largest = sorted(results, key=lambda r: -r["growth_MB"])[:10]
    slowest = sorted(results, key=lambda r: -r["seconds"])[:5]
    for r in escapes[:20]:
        print(f"  {r['seed']} ({r['mutation']}): {r['outcome']}: {r['detail']}")
    print(
        f"largest memory growth {largest[0]['growth_MB']:.0f} MB; slowest read "
        f"{slowest[0]['seconds']:.1f} s; {wall:.0f} s"
    )
    write_results(
        args.output,
        {
            "benchmark": "fuzz",
            "description": __doc__,
            "settings": vars(args),
            "wall_seconds": wall,
            "mutants": len(results),
            "counts": {seed: dict(c) for seed, c in table.items()},
            "refusals": {
                seed: dict(
                    collections.Counter(
                        r["detail"] for r in results if r["seed"] == seed and r["detail"]
                    ).most_common(8)
                )
                for seed in table
            },
            "total": dict(total),
            "escapes": escapes,
            "largest_memory_growth": largest,
            "slowest": slowest,
            "goal": "0 other exceptions, memory errors, timeouts or crashes; no read growing by "
            "300 MB",
        },
    )


if __name__ == "__main__":
    main()
