"""Advice followed as printed where following it costs a campaign or a comparison of
every law (``-m validation``; the light ones are ``tests/test_advice_followed.py``)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from _free_decay import METADATA, free_decay
from _law_recording import law_recording
from test_advice_followed import (
    VCQ_DRAG,
    VCQ_MU_K,
    VCQ_ZETA,
    command,
    covers,
    damping_growing_file,
    first_advice,
)

from bayestribo.io import write_run
from bayestribo.io.run import Run

pytestmark = [
    pytest.mark.validation,
    pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning"),
]


def test_a_campaign_refused_a_locked_folder_writes_to_another_out(tmp_path, capsys) -> None:
    from bayestribo.campaign.lock import FolderLock

    runs = tmp_path / "runs"
    runs.mkdir()
    for seed in (3, 4):
        d = free_decay(seed=seed)
        write_run(Run(d.time, d.displacement, d.velocity, dict(METADATA)), runs / f"r{seed}.csv")
    argv = ["campaign", str(runs), "--quiet", "--json", "--workers", "1", "--no-figures"]
    argv += ["--max-steps", "400", "--population-steps", "400"]
    with FolderLock(tmp_path / "out"):  # another campaign writes there
        status, _, err = command([*argv, "--out", str(tmp_path / "out")], capsys)
    assert status == 2 and "another campaign" in err
    option = re.search(r"give another (--[\w-]+)", err)
    assert option is not None, err
    other = tmp_path / "other"
    status, _, err = command([*argv, option[1], str(other)], capsys)
    assert status in (0, 1), err  # 1: the short population sampling, said
    for name in ("catalog.sqlite", "population.json", "runs.csv"):
        assert (other / name).is_file(), name
    assert sorted(p.name for p in (other / "fits").iterdir()) == ["r3.nc", "r4.nc"]
    assert not any((tmp_path / "out").iterdir())  # the locked folder untouched


def test_a_misfits_advice_law_auto_followed_finds_the_drag_and_covers_it(tmp_path, capsys) -> None:
    # quadratic drag alone, c₂/m = 40 /m, on the paper's rig without a load
    drag = 40.0
    run = law_recording(lambda v: drag * v * abs(v), duration_s=1.5, seed=2, load_N=None)
    path = write_run(run, tmp_path / "drag.csv")
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 1 and "misfits" in err
    option = re.search(r"\((--law \w+)\)", err)
    assert option is not None, err
    # the first advice, the misfit's and the frequency warning's
    assert first_advice(err) == option[1]
    status, out, err = command(["fit", str(path), "--json", *option[1].split()], capsys)
    record = json_record(out)
    assert status == 0, err
    assert "quadratic" in record["law"].split("+")
    covers(record, {"c2_SI": drag * run.metadata["mass_kg"]})


def test_a_misfit_along_the_decay_on_a_prior_bound_followed_as_first_advised_covers(
    tmp_path, capsys
) -> None:
    path = damping_growing_file(tmp_path)
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 1 and "mu_s_ratio piles on the upper bound" in err
    option = first_advice(err)
    status, out, err = command(["fit", str(path), "--json", *option.split()], capsys)
    record = json_record(out)
    assert status == 0, err
    assert record["law"] == "viscous+coulomb+quadratic"
    mass = 0.035
    covers(record, {"zeta": VCQ_ZETA, "mu_k": VCQ_MU_K, "c2_SI": VCQ_DRAG * mass})


#: A Coulomb decay on the paper's rig, x_c = 25 µm from 2 mm.
OMEGA, X_C = 2.0 * math.pi * 32.6, 25e-6
RIG = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31, "gain_uncertainty": 0.0}


def _coarse_coulomb(folder, seed: int = 2):
    """The decay (``solve_ivp``) with both channels on 4 steps across their swing after
    0.05 step of noise, levels placed at random: a record whose swings span too few
    steps for ``auto`` to tell friction's A¹ from drag's A² (benchmarks/shape_unresolved)."""
    run = law_recording(
        lambda v: 0.0,
        friction=X_C * OMEGA**2,
        static_ratio=1.36,
        x0=2e-3,
        sample_rate_Hz=10_000.0,
        noise_x=1e-12,
        noise_v=1e-12,
        duration_s=1.1,
    )
    rng = np.random.default_rng([5, 4, 5, seed])
    placement = rng.uniform(-0.5, 0.5, 2)
    channels = []
    for s, u in zip((run.displacement, run.velocity), placement, strict=True):
        q = float(np.ptp(s)) / 4
        channels.append((np.round((s + 0.05 * q * rng.standard_normal(s.size)) / q + u) - u) * q)
    return write_run(Run(run.time, *channels, RIG), folder / "coarse.csv")


def test_an_unresolved_shape_followed_with_the_law_the_physics_says_covers(
    tmp_path, capsys
) -> None:
    path = _coarse_coulomb(tmp_path)
    status, _, err = command(["fit", str(path), "--json", "--law", "auto", "--quiet"], capsys)
    assert status == 1 and "The record does not tell which law dissipates" in err, err
    option = re.search(r"(--law) NAME where the physics says which", err)
    named = re.findall(r"([\w+]+) \(ΔE ∝ A\^([\d.]+)\)", err)
    assert option is not None and named, err
    # the physics: the record is a dry friction's, ΔE ∝ A¹; of the laws named, the one
    # of that shape
    law = min(named, key=lambda pair: abs(float(pair[1]) - 1.0))[0]
    status, out, err = command(["fit", str(path), "--json", option[1], law], capsys)
    assert status == 0, err
    covers(json_record(out), {"mu_k": X_C * OMEGA**2 * RIG["mass_kg"] / RIG["load_N"]})


def json_record(out: str) -> dict:
    import json

    return json.loads(out)
