"""The bundled synthetic campaign in data/: programme, true parameters, regeneration."""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest
from _paths import DATA

from bayestribo import read_run
from bayestribo.cli import simulate as simulate_command
from bayestribo.model.laws import get_law
from bayestribo.model.viscosity import glycerol_water_viscosity
from bayestribo.synthetic import LawParameters
from bayestribo.synthetic.campaign import (
    CAMPAIGN_SEED,
    LOADS_N,
    MANIFEST_COLUMNS,
    OIL_LAW,
    OIL_LOADS_N,
    WATER_FRACTIONS,
    campaign_plan,
)


@pytest.fixture(scope="module")
def plan():
    return campaign_plan()


@pytest.fixture(scope="module")
def manifest() -> list[dict[str, str]]:
    with (DATA / "manifest.csv").open(newline="") as fh:
        return list(csv.DictReader(fh))


def test_programme_of_the_paper(plan) -> None:
    series = [p.series for p in plan]
    assert series.count("air") == 3
    assert series.count("glycerol") == 15
    assert series.count("glycerol-water") == 6 * 2 * 3
    assert len({p.run_id for p in plan}) == len(plan)
    glycerol = [p for p in plan if p.series == "glycerol"]
    assert sorted({p.rig.load_N for p in glycerol}) == list(LOADS_N)
    water = [p for p in plan if p.series == "glycerol-water"]
    fractions = sorted({p.metadata["water_mass_fraction"] for p in water})
    assert fractions == list(WATER_FRACTIONS)
    for p in water:
        assert p.metadata["repeat"] in (1, 2, 3)
    air = [p for p in plan if p.series == "air"]
    assert all(p.rig.load_N == 0.0 and p.law.mu_k == 0.0 for p in air)
    oil = [p for p in plan if p.series == "oil"]
    assert len(oil) == len(OIL_LOADS_N) * 3 and sorted({p.rig.load_N for p in oil}) == list(
        OIL_LOADS_N
    )
    assert all(isinstance(p.law, LawParameters) and p.law.name == OIL_LAW for p in oil)
    assert all(p.sensor.sample_rate_Hz == 2000.0 for p in oil)
    # the series of the paper come first: their draws do not depend on the oil's
    assert [p.series for p in plan[-len(oil) :]] == ["oil"] * len(oil)


def test_the_oil_runs_lose_about_half_their_first_cycle_to_the_drag(plan) -> None:
    """Each term of the oil's law has a measurable share of the energy lost over the
    first cycle from the release displacement, by the registry's ΔE(A) of each term."""
    law = get_law(OIL_LAW)
    for p in (p for p in plan if p.series == "oil"):
        y0 = p.release.initial_displacement_m / p.rig.scaling().length_scale
        shares = law.dissipation([y0], dict(p.law.values), y0, by_term=True)
        total = sum(float(v[0, 0]) for v in shares.values())
        drag = float(shares["quadratic"][0, 0]) / total
        assert 0.35 < drag < 0.6, (p.run_id, drag)
        assert float(shares["viscous"][0, 0]) / total > 0.25
        assert float(shares["coulomb"][0, 0]) / total > 0.05


def test_glycerol_scatter_is_the_papers(plan) -> None:
    laws = [p.law for p in plan if p.series == "glycerol"]
    zeta = np.array([law.zeta for law in laws])
    mu = np.array([law.mu_k for law in laws])
    n = zeta.size
    # Means of 15 draws: standard error σ/sqrt(15); 4 standard errors.
    assert abs(zeta.mean() - 0.0236) < 4 * 0.0012 / math.sqrt(n)
    assert abs(mu.mean() - 0.0294) < 4 * 0.0036 / math.sqrt(n)
    # Sample standard deviations within the 99.8 % chi-square interval for 14 d.o.f.
    # (chi2.ppf(0.001, 14) = 4.18, chi2.ppf(0.999, 14) = 36.12).
    for values, sigma in ((zeta, 0.0012), (mu, 0.0036)):
        s2 = values.var(ddof=1)
        assert 4.18 / 14 < s2 / sigma**2 < 36.12 / 14


def test_zeta_rises_with_viscosity_and_mu_k_jumps_above_six_percent_water(plan) -> None:
    by_water: dict[float, list] = {}
    for p in plan:
        if p.series == "glycerol-water":
            by_water.setdefault(p.metadata["water_mass_fraction"], []).append(p.law)
    zeta = [np.mean([law.zeta for law in by_water[w]]) for w in WATER_FRACTIONS]
    mu = {w: np.mean([law.mu_k for law in by_water[w]]) for w in WATER_FRACTIONS}
    nu = glycerol_water_viscosity(list(WATER_FRACTIONS))
    # ζ ordered like viscosity (decreasing with water).
    assert np.all(np.diff(zeta) < 0) and np.all(np.diff(nu) < 0)
    low = [mu[w] for w in WATER_FRACTIONS if w <= 0.06]
    assert max(low) < 1.3 * min(low)  # almost constant up to 6 %
    assert mu[0.08] > 1.5 * np.mean(low) and mu[0.09] > 2.2 * np.mean(low)


def test_manifest_lists_every_run_with_its_true_parameters(plan, manifest) -> None:
    assert list(manifest[0]) == list(MANIFEST_COLUMNS)
    assert [row["run_id"] for row in manifest] == [p.run_id for p in plan]
    for row, planned in zip(manifest, plan, strict=True):
        law = planned.law
        if isinstance(law, LawParameters):  # a registered law: every parameter a column
            assert row["law"] == law.name
            for name, value in law.values.items():
                assert float(row[name]) == value, (row["run_id"], name)
        else:
            assert float(row["zeta"]) == law.zeta
            assert float(row["mu_k"]) == law.mu_k
            assert row["law"] == ("viscous+coulomb" if planned.rig.load_N else "viscous")
        assert float(row["load_N"]) == planned.rig.load_N
        assert (DATA / row["file"]).is_file()


def test_every_bundled_run_reads_and_matches_the_manifest(manifest) -> None:
    for row in manifest:
        run = read_run(DATA / row["file"])
        assert run.n_samples == int(row["n_samples"])
        assert run.metadata["run_id"] == row["run_id"]
        assert run.metadata["sample_rate_Hz"] == float(row["sample_rate_Hz"])
        rig = run.rig()
        assert rig.natural_frequency_Hz == 32.6 and rig.mass_kg == 0.035
        if row["series"] == "glycerol":
            assert run.metadata["sample_rate_Hz"] == 10_000.0


def test_the_manifest_states_the_truth_of_each_sidecar(manifest) -> None:
    """The manifest's true values are those of each run's sidecar, by name: ζ, μ_k and
    μ_s of the paper's law, or a registered law's name, parameters and physical
    quantities; the columns of values a run's sidecar does not state are empty."""
    law_columns = MANIFEST_COLUMNS[MANIFEST_COLUMNS.index("law") + 1 :]
    laws = set()
    for row in manifest:
        truth = read_run(DATA / row["file"]).metadata["simulation"]
        if "law" in truth:
            assert row["law"] == truth["law"]
            laws.add(truth["law"])
            values = {
                k: v["value"] for part in ("parameters", "physical") for k, v in truth[part].items()
            }
            assert float(row["mu_s"]) == values["mu_s_ratio"] * values["mu_k"]
        else:
            values = {k: truth[k] for k in ("zeta", "mu_k", "mu_s")}
        for name in dict.fromkeys((*values, *law_columns)):
            got = float(row[name]) if row[name] else None
            assert got == values.get(name), (row["run_id"], name)
    assert laws == {OIL_LAW}


def test_glycerol_runs_have_about_half_a_second_of_motion_at_10_khz(manifest) -> None:
    # From 2 mm the motion lasts 0.8 s at 0.07 N down to 0.4 s at 0.59 N (more friction
    # force stops it sooner); the middle loads give the "10 kHz, ~0.6 s" benchmark case.
    motion = [float(r["motion_duration_s"]) for r in manifest if r["series"] == "glycerol"]
    assert all(0.35 < m < 0.9 for m in motion)
    assert sum(0.45 < m < 0.8 for m in motion) >= 6


def test_bundle_is_small() -> None:
    total = sum(p.stat().st_size for p in DATA.rglob("*") if p.is_file())
    assert total < 8e6, f"data/ holds {total / 1e6:.1f} MB"


def _close(a: object, b: object) -> bool:
    """Equal, with floats equal to 1e-12 relative (last-bit libm differences across
    platforms in derived values such as the motion duration; the data are quantised)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300)
    return a == b


def _number(text: str) -> object:
    try:
        return float(text)
    except ValueError:
        return text


def _assert_same_signal(old: Path, new: Path) -> None:
    with old.open() as a, new.open() as b:
        assert a.readline() == b.readline(), new
    a, b = np.loadtxt(old, delimiter=",", skiprows=1), np.loadtxt(new, delimiter=",", skiprows=1)
    assert a.shape == b.shape, new
    np.testing.assert_array_equal(a[:, 0], b[:, 0], err_msg=str(new))
    meta = json.loads(old.with_suffix(".json").read_text())
    step = np.array(
        [meta["displacement_resolution_m"], meta["velocity_resolution_m_per_s"]][: a.shape[1] - 1]
    )
    steps = np.abs(a[:, 1:] - b[:, 1:]) / step
    assert np.max(steps) <= 1.0 + 1e-6, (new, float(np.max(steps)))
    assert np.mean(steps > 1e-6) <= 0.01, (new, float(np.mean(steps > 1e-6)))


def test_one_command_regenerates_the_bundle(tmp_path: Path) -> None:
    parser = argparse.ArgumentParser(prog="bayestribo")
    simulate_command.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["simulate", "--campaign", str(tmp_path)])
    assert args.handler(args) == 0
    bundled = sorted(p.relative_to(DATA) for p in (DATA / "runs").rglob("*") if p.is_file())
    fresh = sorted(p.relative_to(tmp_path) for p in (tmp_path / "runs").rglob("*") if p.is_file())
    assert fresh == bundled
    # The signals (quantised, time stamps rounded to 1 ns) regenerate: the same header
    # and time stamps, and every sample the same quantisation step or its neighbour.
    # A neighbour on a few samples is the CPU's: numpy's SIMD kernels (AVX-512 or
    # AVX2) round the integration's last bits differently, and a value lying on a
    # step's edge rounds to either side.
    for p in (p for p in bundled if p.suffix == ".csv"):
        _assert_same_signal(DATA / p, tmp_path / p)
    for p in bundled:
        if p.suffix == ".json":
            old = json.loads((DATA / p).read_text())
            new = json.loads((tmp_path / p).read_text())
            # the data file's hash is of the bytes just compared step by step; the
            # fresh one is its own file's
            digest = new["data_file"].pop("sha256")
            old["data_file"].pop("sha256")
            data_file = (tmp_path / p).with_suffix(".csv").read_bytes()
            assert digest == hashlib.sha256(data_file).hexdigest(), p
            # the motion's end is the integrator's event time: equal to the solver's
            # tolerance (rtol 1e-10 per half cycle), not to the last bit
            t_old = old["simulation"].pop("motion_duration_s")
            t_new = new["simulation"].pop("motion_duration_s")
            assert math.isclose(t_old, t_new, rel_tol=1e-9), (p, t_old, t_new)
            assert _close(old, new), p
    with (DATA / "manifest.csv").open() as a, (tmp_path / "manifest.csv").open() as b:
        rows = zip(csv.reader(a), csv.reader(b), strict=True)
        header, _ = next(rows)
        for old, new in rows:
            for key, x, y in zip(header, old, new, strict=True):
                if key == "motion_duration_s":  # the integrator's event time, as above
                    assert math.isclose(float(x), float(y), rel_tol=1e-9), (key, x, y)
                else:
                    assert _close(_number(x), _number(y)), (key, x, y)
    assert CAMPAIGN_SEED == 20100320
