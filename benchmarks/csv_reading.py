"""Reading a large record: the package's reader against what a user would write instead.

A simulated record of the paper's rig sampled at ``--rate`` (default 1 MHz) for about
``--seconds`` (default 1 s) is written once as the canonical CSV (53 MB at 1 MHz). Each
way of reading it runs in a fresh process, ``--repeats`` rounds, the ways alternating
within a round so that the load of a shared machine falls on all alike:

* ``read_run``: :func:`bayestribo.read_run` with pyarrow installed (the ``large``
  extra), checked and converted to SI;
* ``read_run, no pyarrow``: the same with pyarrow's import blocked (the reader then
  takes pandas' C parser);
* ``pandas.read_csv``: a user's own ``pandas.read_csv(path).to_numpy()``;
* ``numpy.loadtxt``: a user's own ``numpy.loadtxt(path, delimiter=",", skiprows=1)``;
* ``pyarrow.csv``: a user's own ``pyarrow.csv.read_csv(path)``, its columns as NumPy
  float64 arrays.

Reported per way: the process CPU time (``time.process_time``; every thread's) and the
wall time of the read alone, from after the imports to float64 columns in memory, and
of the imports and the read together, medians over the rounds, and their ratios to
``read_run``'s. The package's import (numpy, SciPy and its own modules, which a fit
needs anyway) is in the second figure only.

Run: ``python benchmarks/csv_reading.py --repeats 7``; writes
``benchmarks/results/csv_reading.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import commit, write_results

TREE = Path(__file__).resolve().parent.parent

#: Each way of reading: the imports, then the read, timed apart in the worker.
WAYS = {
    "read_run": ("from bayestribo import read_run", "c = read_run(path); n = c.time.size"),
    "read_run, no pyarrow": (
        "import sys; sys.modules['pyarrow'] = None; from bayestribo import read_run",
        "c = read_run(path); n = c.time.size",
    ),
    "pandas.read_csv": (
        "import pandas",
        "c = pandas.read_csv(path).to_numpy(dtype=float); n = c.shape[0]",
    ),
    "numpy.loadtxt": (
        "import numpy",
        "c = numpy.loadtxt(path, delimiter=',', skiprows=1); n = c.shape[0]",
    ),
    "pyarrow.csv": (
        "import numpy, pyarrow.csv",
        "t = pyarrow.csv.read_csv(path); "
        "c = [numpy.asarray(t.column(i), dtype=float) for i in range(t.num_columns)]; "
        "n = t.num_rows",
    ),
}

WORKER = """
import json, sys, time
w0, c0 = time.perf_counter(), time.process_time()
{imports}
w1, c1 = time.perf_counter(), time.process_time()
path = sys.argv[1]
{read}
w2, c2 = time.perf_counter(), time.process_time()
print(json.dumps({{"rows": int(n), "import_s": w1 - w0, "import_cpu_s": c1 - c0,
                  "read_s": w2 - w1, "read_cpu_s": c2 - c1,
                  "pyarrow": sys.modules.get("pyarrow") is not None}}))
"""


def measure(way: str, path: Path) -> dict:
    """Read ``path`` one way in a fresh process; its times and row count.

    Parameters
    ----------
    way : str
        A key of :data:`WAYS`.
    path : Path
        The CSV record.

    Returns
    -------
    dict
        ``rows``; ``import_s``, ``read_s`` (wall) and ``import_cpu_s``, ``read_cpu_s``
        (process CPU), in s; whether pyarrow was imported.
    """
    imports, read = WAYS[way]
    env = {**os.environ, "PYTHONPATH": str(TREE)}
    proc = subprocess.run(
        [sys.executable, "-c", WORKER.format(imports=imports, read=read), str(path)],
        env=env,
        capture_output=True,
        text=True,
        cwd=path.parent,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{way}: {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def summarise(rows: dict[str, list[dict]]) -> dict[str, dict]:
    """Medians per way, and each against ``read_run``'s.

    Parameters
    ----------
    rows : dict
        Way → the worker results of its rounds.

    Returns
    -------
    dict
        Way → medians of ``read_cpu_s``, ``read_s``, ``total_cpu_s`` (imports and read)
        and ``total_s`` [s], and the same over ``read_run``'s (``*_over_read_run``).
    """
    medians = {
        way: {
            "read_cpu_s": statistics.median(r["read_cpu_s"] for r in results),
            "read_s": statistics.median(r["read_s"] for r in results),
            "total_cpu_s": statistics.median(r["import_cpu_s"] + r["read_cpu_s"] for r in results),
            "total_s": statistics.median(r["import_s"] + r["read_s"] for r in results),
        }
        for way, results in rows.items()
    }
    ref = medians["read_run"]
    for m in medians.values():
        for key in ("read_cpu_s", "read_s", "total_cpu_s", "total_s"):
            m[f"{key[:-2]}_over_read_run"] = m[key] / ref[key]
    return medians


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rate", type=float, default=1e6, help="sample rate [Hz]")
    parser.add_argument("--seconds", type=float, default=1.0, help="record length [s]")
    parser.add_argument("--repeats", type=int, default=5, help="rounds of every way")
    parser.add_argument("--output", default="csv_reading")
    args = parser.parse_args()
    from bayestribo.io import write_run
    from bayestribo.synthetic import Release, Sensor, simulate

    rest = 0.05
    load_start = list(os.getloadavg())
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "record.csv"
        run = simulate(
            seed=1,
            sensor=Sensor(sample_rate_Hz=args.rate),
            release=Release(
                motion_duration_s=args.seconds - 2 * rest, rest_before_s=rest, rest_after_s=rest
            ),
        )
        write_run(run, path)
        size_MB = path.stat().st_size / 1e6
        del run
        rows: dict[str, list[dict]] = {way: [] for way in WAYS}
        for _ in range(args.repeats):
            for way in WAYS:
                result = measure(way, path)
                result["load_average"] = list(os.getloadavg())
                rows[way].append(result)
    summary = summarise(rows)
    print(f"{size_MB:.1f} MB of CSV, {rows['read_run'][0]['rows']} rows; CPU medians")
    print(f"{'way':22s} {'read [s]':>9s} {'x read_run':>11s} {'with imports [s]':>17s} {'x':>6s}")
    for way, m in summary.items():
        print(
            f"{way:22s} {m['read_cpu_s']:9.3f} {m['read_cpu_over_read_run']:11.2f} "
            f"{m['total_cpu_s']:17.3f} {m['total_cpu_over_read_run']:6.2f}"
        )
    write_results(
        args.output,
        {
            "benchmark": "csv_reading",
            "description": __doc__,
            "commit": commit(short=True),
            "settings": vars(args),
            "record": {"csv_MB": size_MB, "rows": rows["read_run"][0]["rows"]},
            "load_average_start": load_start,
            "load_average_end": list(os.getloadavg()),
            "ways": {way: " ; ".join(code) for way, code in WAYS.items()},
            "runs": rows,
            "summary": summary,
        },
    )


if __name__ == "__main__":
    main()
