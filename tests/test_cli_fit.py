"""``bayestribo fit``: one JSON object, the table, output files, exit statuses."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from bayestribo.cli import build_parser, main
from bayestribo.errors import BayestriboError
from bayestribo.inference import FitResult
from bayestribo.synthetic import PAPER_RIG, Sensor

DIAGNOSTICS = {
    "converged",
    "n_walkers",
    "n_steps",
    "autocorr_time_max",
    "ess_min",
    "acceptance_fraction",
}
#: The keys of each parameter: the first seven since the first release, then what the
#: quantity is and its sampler diagnostics (keys are added, never renamed).
SUMMARY = {"mean", "sd", "median", "interval", "prob", "kind", "unit"} | {
    "name", "symbol", "label", "sampled", "ess", "r_hat",
}  # fmt: skip


@pytest.fixture(scope="module")
def run_file(tmp_path_factory) -> Path:
    from bayestribo.io import write_run
    from bayestribo.synthetic.recording import simulate

    # 2 kHz: a converged fit in a few seconds
    path = tmp_path_factory.mktemp("runs") / "glycerol-2k.csv"
    write_run(
        simulate(
            rig=PAPER_RIG,
            sensor=Sensor(sample_rate_Hz=2000.0),
            seed=21,
        ),
        path,
    )
    return path


@pytest.fixture(scope="module")
def json_run(run_file: Path, tmp_path_factory) -> tuple[int, dict, Path, str]:
    out_dir = tmp_path_factory.mktemp("out")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(["fit", str(run_file), "--seed", "4", "--json", "--out", str(out_dir)])
    text = buf.getvalue()
    return status, json.loads(text), out_dir, text


def test_fit_is_a_registered_command() -> None:
    args = build_parser().parse_args(["fit", "x.csv", "--model", "averaged", "--seed", "3"])
    assert args.model == "averaged" and args.seed == 3 and args.json is False


def test_json_is_one_object_with_the_issue_shape(json_run, run_file: Path) -> None:
    status, record, _, text = json_run
    assert status == 0
    assert text.count("\n") == 1  # exactly one JSON object on one line
    assert record["run"] == str(run_file) and record["model"] == "exact"
    assert record["seed"] == 4
    assert DIAGNOSTICS <= set(record["diagnostics"])
    assert record["diagnostics"]["converged"] is True
    assert isinstance(record["seconds"], float) and record["seconds"] > 0
    # Units, the run's metadata and the package version travel with the numbers.
    import bayestribo

    assert record["bayestribo_version"] == bayestribo.__version__
    assert record["metadata"]["load_N"] == 0.31
    units = {name: p["unit"] for name, p in record["parameters"].items()}
    assert (units["zeta"], units["mu_k"], units["friction_displacement"]) == ("1", "1", "m")
    assert units.get("d_k", "s/m") == "s/m"
    assert {"zeta", "mu_k", "mu_s", "friction_displacement"} <= set(record["parameters"])
    # every sampled parameter, the static to kinetic friction ratio too
    assert {"mu_s_ratio", "y0"} <= set(record["parameters"])
    assert record["parameters"]["mu_s_ratio"]["sampled"] is True
    assert record["parameters"]["mu_s"]["sampled"] is False
    for name, s in record["parameters"].items():
        assert set(s) == SUMMARY, name
        assert s["name"] == name and s["label"] and s["symbol"]
        lo, hi = s["interval"]
        assert lo <= s["median"] <= hi and s["prob"] == 0.95 and s["sd"] > 0
    # the simulated truth (ζ = 0.0236, μ_k = 0.0294) inside the 95 % intervals; the
    # seed is fixed, so this is one draw of a calibrated interval, checked once
    for name, truth in (("zeta", 0.0236), ("mu_k", 0.0294)):
        lo, hi = record["parameters"][name]["interval"]
        assert lo < truth < hi, (name, lo, hi)
    assert "displacement" in record["noise"] and "description" in record["noise"]


def test_out_writes_netcdf_and_figures(json_run, run_file: Path) -> None:
    _, record, out_dir, _ = json_run
    stem = run_file.stem
    for suffix in ("_corner.png", "_trace.png", "_pi.png"):
        path = out_dir / f"{stem}{suffix}"
        assert path.stat().st_size > 5000, path
    saved = FitResult.load(out_dir / f"{stem}.nc")
    assert saved.run_name == str(run_file) and saved.seed == 4
    np.testing.assert_allclose(
        saved.summary()["zeta"].mean, record["parameters"]["zeta"]["mean"], rtol=1e-12
    )


def test_table_and_non_convergence_exit_status(run_file: Path, capsys) -> None:
    # 200 steps are far fewer than 50 autocorrelation times: not converged, status 1,
    # and the table says so
    status = main(["fit", str(run_file), "--seed", "1", "--max-steps", "200"])
    captured = capsys.readouterr()
    assert status == 1
    assert "NOT CONVERGED" in captured.out
    assert "equivalent viscous damping ratio ζ" in captured.out
    assert "kinetic friction coefficient (x_c k/N) μ_k" in captured.out
    assert "did not converge" in captured.err


def test_the_table_names_each_quantity_in_words_with_its_unit(json_run, run_file: Path) -> None:
    from bayestribo.model.laws import get_law

    _, _, out_dir, _ = json_run
    result = FitResult.load(out_dir / f"{run_file.stem}.nc")
    lines = result.to_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.split()[:2] == ["unit", "mean"])
    rows = {}
    for line in lines[header + 1 :]:
        if line.startswith("energy dissipated"):
            break
        title, rest = line.split("  ", 1)
        rows[title] = rest.split()[0]
    # the law's parameters by the registry's words and symbol, the friction
    # displacement in metres, a number said to be dimensionless: no "-" anywhere
    for p in get_law(result.law).parameters:
        assert rows[f"{p.label} {p.symbol}"] == "dimensionless", p.name
    assert rows["friction as displacement x_c"] == "m"
    assert "-" not in rows.values() and len(rows) == len(result.summary())


def test_missing_file_is_a_package_error(tmp_path: Path, capsys) -> None:
    status = main(["fit", str(tmp_path / "nope.csv")])
    assert status == 2
    assert "nope.csv" in capsys.readouterr().err


def test_out_that_is_a_file_is_a_package_error(tmp_path: Path) -> None:
    from bayestribo.cli.fit import write_outputs

    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(BayestriboError, match="--out"):
        write_outputs(None, blocker, "x")


def test_options_reach_the_fit(json_run, run_file: Path, monkeypatch, capsys) -> None:
    import bayestribo.inference

    _, _, out_dir, _ = json_run
    saved = FitResult.load(out_dir / f"{run_file.stem}.nc")
    seen = {}

    def fake_fit(run, **kwargs):
        seen.update(kwargs, run=run)
        return saved

    monkeypatch.setattr(bayestribo.inference, "fit", fake_fit)
    argv = [
        "fit",
        str(run_file),
        "--model",
        "averaged",
        "--seed",
        "9",
        "--discrepancy",
        "--progress",
        "--skip",
        "2",
        "--load",
        "0.5",
        "--mass",
        "0.04",
    ]
    assert main(argv) == 0
    assert seen["model"] == "averaged" and seen["seed"] == 9
    assert seen["discrepancy"] is True and seen["progress"] is True
    assert seen["skip_oscillations"] == 2
    # --load and --mass override the sidecar, as for the other commands
    assert seen["run"].metadata["load_N"] == 0.5 and seen["run"].metadata["mass_kg"] == 0.04
    assert "equivalent viscous damping ratio ζ" in capsys.readouterr().out


def test_a_misfit_exits_1_with_its_warning(tmp_path, capsys) -> None:
    from bayestribo.io import write_run
    from bayestribo.synthetic import DissipationLaw
    from bayestribo.synthetic.recording import simulate

    # Damping that grows with amplitude: the linear law misfits it.
    run = simulate(
        DissipationLaw(zeta=lambda a: 0.01 + 20.0 * a, mu_k=0.0294),
        sensor=Sensor(
            sample_rate_Hz=2000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=9,
    )
    path = write_run(run, tmp_path / "drag.csv")
    assert main(["fit", str(path), "--max-steps", "3000"]) == 1
    err = capsys.readouterr().err
    assert "bayestribo fit: warning: the law viscous+coulomb misfits" in err
    assert "--law auto" in err


def test_the_table_writes_each_value_by_the_digit_rule_and_a_flat_one_as_a_bound(
    json_run, run_file: Path
) -> None:
    from bayestribo.inference.flatness import is_bound
    from bayestribo.summary import interval_text

    _, record, out_dir, _ = json_run
    result = FitResult.load(out_dir / f"{run_file.stem}.nc")
    text = result.to_text()
    bounds = 0
    for name, s in result.summary().items():
        row = next(line for line in text.splitlines() if line.startswith(s.title + " "))
        # the JSON says what the table says: a bound where the data set none
        assert record["parameters"][name]["kind"] == s.kind
        assert record["parameters"][name]["interval"] == list(s.interval)
        if is_bound(result, name):
            bounds += 1
            assert s.kind == "bound", name
            assert f"< {s.interval[1]:.2g} (not constrained by the data" in row, row
        else:
            assert s.kind == "posterior", name
            assert interval_text(s.mean, *s.interval) in row, row
    # μ_s/μ_k of a run that stops inside its static band is flat up to the stop
    assert bounds >= 1 and "not constrained by the data" in text


@pytest.fixture(scope="module")
def pendulum_file(tmp_path_factory) -> Path:
    """A pendulum released at 90° (test_inference_restoring_choice), in radians, whose
    sidecar says 'restoring': 'auto'."""
    from test_inference_restoring_choice import _rubbing_pendulum

    from bayestribo.io import write_run
    from bayestribo.io.run import Run

    t, angle = _rubbing_pendulum()
    path = tmp_path_factory.mktemp("pendulum") / "pendulum.csv"
    metadata = {"length_unit": "rad", "gain_uncertainty": 0.0, "restoring": "auto"}
    write_run(Run(t, angle, metadata=metadata), path)
    assert json.loads(path.with_suffix(".json").read_text())["restoring"] == "auto"
    return path


def test_restoring_auto_from_the_sidecar_is_printed_and_in_the_json(pendulum_file, capsys):
    argv = ["fit", str(pendulum_file), "--grid-points", "32", "--seed", "3"]
    assert main([*argv, "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["restoring"]["name"] == "pendulum"
    assert record["restoring"]["auto"]["chosen"] == "pendulum"
    assert record["metadata"]["restoring"] == "pendulum"
    # the same from the command line over the sidecar, and the table's line
    assert main([*argv, "--restoring", "auto"]) == 0
    out = capsys.readouterr().out
    assert "restoring auto → pendulum: the half period changes by" in out
    # the linear spring on the same swings: a misfit, exit 1, naming the force to try
    assert main([*argv, "--restoring", "linear"]) == 1
    err = capsys.readouterr().err
    assert "half period changes by" in err and "--restoring auto chooses it" in err


def test_inspect_reads_a_run_whose_restoring_is_auto(pendulum_file, capsys):
    assert main(["inspect", str(pendulum_file), "--restoring", "auto"]) == 0
    assert "pendulum.csv" in capsys.readouterr().out


def test_a_warning_raised_by_two_passes_is_told_once(capsys):
    """``--law auto`` prepares the run for the comparison and again for its verdict's
    fit: a spike found in both passes was printed twice (a real recording's export);
    each distinct warning is told once, and one told at reading is not told again."""
    import sys
    import warnings

    from bayestribo.cli.fit import tell
    from bayestribo.errors import MisfitWarning, ReadingWarning

    spike = "1 spike(s) in the displacement at t = 17.6 s (0.513)"
    with warnings.catch_warnings(record=True) as read:
        warnings.simplefilter("always")
        warnings.warn("2 row(s) have no value for velocity_m_per_s", ReadingWarning, stacklevel=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(2):  # the two passes
            warnings.warn(spike, ReadingWarning, stacklevel=1)
            warnings.warn(
                "2 row(s) have no value for velocity_m_per_s", ReadingWarning, stacklevel=1
            )
        warnings.warn(spike, MisfitWarning, stacklevel=1)  # same text, another kind: told
    with warnings.catch_warnings():
        warnings.showwarning = lambda message, category, *_: print(
            f"{category.__name__}: {message}", file=sys.stderr
        )
        tell(caught, told=read)
    told = capsys.readouterr().err.splitlines()
    assert told == [f"ReadingWarning: {spike}", f"MisfitWarning: {spike}"]
