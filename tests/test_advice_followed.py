"""Advice the command line prints, followed as printed: each situation built, the command
run as a user would, the option copied out of the message (never written here), and the
followed command checked to do what the advice promised.

Records are independent simulations (``_law_recording.py``, ``_free_decay.py``: ``solve_ivp``
half cycle by half cycle), written as files and read back as a user's would be. The
advice that costs a comparison of every law or a campaign is followed under
``-m validation`` (``tests/test_advice_followed_heavy.py``: a campaign, ``--law auto``
from a misfit, ``--law NAME`` after an unresolved ``auto``).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from _free_decay import METADATA as ARBITRARY
from _free_decay import X_C, ZETA, free_decay
from _law_recording import law_recording

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.io.run import Run

#: The paper's rig: ζ, μ_k, load [N], mass [kg], frequency [Hz].
RIG_ZETA, RIG_MU_K, LOAD, MASS, F_HZ = 0.02, 0.03, 0.31, 0.035, 32.6


def command(argv: list[str], capsys) -> tuple[int, str, str]:
    """``bayestribo ARGV``: exit status, standard output and standard error."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(argv)
    return status, buf.getvalue(), capsys.readouterr().err


def covers(record: dict, truths: dict[str, float]) -> None:
    """Each truth inside its 95 % interval in ``fit --json``'s record."""
    for name, truth in truths.items():
        low, high = record["parameters"][name]["interval"]
        assert low <= truth <= high, (name, truth, low, high)


def _without_frequency(run: Run, folder: Path, name: str) -> Path:
    metadata = {k: v for k, v in run.metadata.items() if k != "natural_frequency_Hz"}
    return write_run(Run(run.time, run.displacement, run.velocity, metadata), folder / name)


def _rig_run(friction_mu: float, duration_s: float, static_ratio: float = 1.5) -> Run:
    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * RIG_ZETA * omega * v,
        friction=friction_mu * LOAD / MASS,
        static_ratio=static_ratio,
        duration_s=duration_s,
        seed=3,
    )
    return run


def test_a_load_without_a_frequency_takes_the_nominal_one_the_warning_names(
    tmp_path, capsys
) -> None:
    path = _without_frequency(_rig_run(RIG_MU_K, 1.0), tmp_path, "nofreq.csv")
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 0 and "natural_frequency_Hz is not given" in err
    option = re.search(r"(--[\w-]+), to use a nominal value", err)
    assert option is not None, err
    status, out, err = command(["fit", str(path), "--json", option[1], str(F_HZ)], capsys)
    record = json.loads(out)
    assert status == 0 and "natural_frequency_Hz" not in err, err
    assert record["metadata"]["natural_frequency_Hz"] == F_HZ
    covers(record, {"zeta": RIG_ZETA, "mu_k": RIG_MU_K})


def test_a_short_decay_whose_frequency_cannot_be_measured_is_answered_with_it(
    tmp_path, capsys
) -> None:
    # a friction that stops the motion in four cycles: too few to measure f from
    path = _without_frequency(_rig_run(0.3, 0.3, static_ratio=1.2), tmp_path, "short.csv")
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 2 and "no two full cycles were found to measure it" in err
    option = re.search(r"give natural_frequency_Hz \((--[\w-]+)\)", err)
    assert option is not None, err
    status, out, err = command(["fit", str(path), "--json", option[1], str(F_HZ)], capsys)
    # answered: exit 1 for the short decay it says, its intervals wide and covering
    assert status == 1 and "short decay" in err and "natural_frequency_Hz" not in err, err
    covers(json.loads(out), {"zeta": RIG_ZETA, "mu_k": 0.3})


@pytest.fixture(scope="module")
def duffing_file(tmp_path_factory) -> Path:
    """A stiffening spring on the paper's rig (+0.1 % at 2 mm, ``solve_ivp``), viscous
    damping and Coulomb friction (test_signal_frequency)."""
    from test_signal_frequency import _decay

    t, x, v = _decay(10_000.0, k3_over_k=667.0)
    rng = np.random.default_rng(5)
    run = Run(
        t,
        x + rng.normal(0.0, 1.5e-6, t.size),
        v + rng.normal(0.0, 1.5e-7, t.size),
        {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31},
    )
    return write_run(run, tmp_path_factory.mktemp("duffing") / "stiffening.csv")


def test_the_linear_fits_duffing_advice_followed_fits_the_spring_and_covers(
    duffing_file, capsys
) -> None:
    status, _, err = command(["fit", str(duffing_file), "--json"], capsys)
    assert "half period changes by" in err
    named = re.findall(r"(--restoring) (\w+)", err)
    # the force named for a spring that stiffens, beside `auto` (followed in
    # test_inference_restoring_choice)
    option, force = next((o, f) for o, f in named if f != "auto")
    assert force == "duffing"
    # and it is the first advice the fit prints (the law holds the decay: no misfit)
    assert first_advice(err) == f"{option} {force}", err
    status, out, err = command(["fit", str(duffing_file), "--json", option, force], capsys)
    record = json.loads(out)
    assert status == 0 and "half period changes" not in err, err
    assert record["restoring"]["name"] == "duffing" and record["restoring"]["in_model"]
    mu_k = 0.035 * (2 * np.pi * 32.6) ** 2 * 6.2e-6 / 0.31
    covers(record, {"zeta": 0.0236, "mu_k": mu_k})


#: An option the fit's warnings advise: another law, another restoring force, a prior.
ADVICE = re.compile(r"--law \w+|--restoring \w+|--prior \S+?=\w+\([^()]*\)")


def first_advice(err: str) -> str:
    """The first option the printed warnings advise (``--law auto``, ...)."""
    found = ADVICE.search(err)
    assert found is not None, err
    return found[0]


def quadratic_drag_file(folder: Path) -> Path:
    """Quadratic drag alone (air drag, c₂/m = 40 /m, ``solve_ivp``) on the paper's rig
    without a load: the default law misfits it, and the drag shortens the half period
    as the swing decays (−0.024 %, 87 standard errors)."""
    run = law_recording(lambda v: 40.0 * v * abs(v), duration_s=1.5, seed=2, load_N=None)
    return write_run(run, folder / "drag.csv")


def test_a_drags_change_of_half_period_advises_another_law_before_the_spring(
    tmp_path, capsys
) -> None:
    path = quadratic_drag_file(tmp_path)
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 1 and "misfits" in err
    warning = next(w for w in err.split("bayestribo fit: warning: ") if "half period" in w)
    # the frequency warning's first advice is the law the misfit advises, not a spring
    # (--restoring duffing, followed, misfits as before); followed under -m validation
    # (test_advice_followed_heavy.py): exit 0 with the drag, c₂ covered
    assert first_advice(warning) == "--law auto", warning
    assert first_advice(err) == "--law auto"
    assert warning.index("--law auto") < warning.index("--restoring duffing")


#: Viscous damping, quadratic drag and Coulomb friction that sticks at μ_s = μ_k on the
#: paper's rig: ζ, c₂/m [1/m], μ_k.
VCQ_ZETA, VCQ_DRAG, VCQ_MU_K = 0.01, 47.0, 0.0294


def damping_growing_file(folder: Path) -> Path:
    """Damping that grows with the swing (ζ 0.01 and quadratic drag, about
    ζ = 0.01 + 20 A, with Coulomb friction; ``solve_ivp``, 2 kHz): the default law
    misfits it along the decay and holds μ_s/μ_k on its prior's bound 10, which the
    record's stop does not ask for."""
    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * VCQ_ZETA * omega * v + VCQ_DRAG * v * abs(v),
        friction=VCQ_MU_K * LOAD / MASS,
        static_ratio=1.0,
        x0=1.5e-3,
        sample_rate_Hz=2000.0,
        duration_s=1.0,
        seed=9,
    )
    return write_run(run, folder / "growing.csv")


def test_a_misfit_along_the_decay_advises_another_law_before_a_wider_prior(
    tmp_path, capsys
) -> None:
    path = damping_growing_file(tmp_path)
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 1 and "mu_s_ratio piles on the upper bound" in err
    # the widened prior, followed, misfits as before (the misfit is not the stop's):
    # another law first, the prior after it; followed under -m validation
    assert first_advice(err) == "--law auto", err
    misfit = next(w for w in err.split("bayestribo fit: warning: ") if "misfits" in w)
    assert misfit.index("--law auto") < misfit.index("--prior mu_s_ratio=")


def _preamble_file(folder: Path, with_time: bool) -> Path:
    """The free decay (2 kHz, in mm) as a logger writes it, tab-separated with units in
    its header, under a preamble that states 1 kHz: without a time column (the user
    gives the samples' rate) or with one."""
    decay = free_decay(seed=4)
    header = "Position (mm)\tVelocity (mm/s)"
    columns = [decay.displacement, decay.velocity]
    if with_time:
        header, columns = "Time (s)\t" + header, [decay.time, *columns]
    rows = ["\t".join(repr(float(v)) for v in row) for row in zip(*columns, strict=True)]
    path = folder / ("stamped.txt" if with_time else "counted.txt")
    path.write_text("Device: logger\nSample rate: 1 kHz\n" + header + "\n" + "\n".join(rows) + "\n")
    metadata = {k: v for k, v in ARBITRARY.items() if k != "length_unit"}
    path.with_suffix(".json").write_text(json.dumps(metadata))
    return path


@pytest.mark.parametrize("with_time", [False, True])
def test_a_preamble_rate_that_is_wrong_is_left_out_as_the_refusal_says(
    tmp_path, capsys, with_time
) -> None:
    path = _preamble_file(tmp_path, with_time)
    argv = ["fit", str(path), "--json"] + ([] if with_time else ["--sample-rate", "2000"])
    status, _, err = command(argv, capsys)
    assert status == 2 and "'Sample rate: 1 kHz' (line 2)" in err, err
    option = re.search(r"(--skip-rows) (\d+)", err)
    assert option is not None and "--skip-rows=" not in err, err
    status, out, err = command([*argv, option[1], option[2]], capsys)
    assert status == 0, err
    # the file is in mm: the friction displacement in metres
    covers(json.loads(out), {"zeta": ZETA, "friction_displacement": 1e-3 * X_C})


def test_a_preamble_rate_taken_that_splits_the_channels_names_the_rate_and_its_fix(
    tmp_path, capsys
) -> None:
    # no rate given: the preamble's is taken, and the channels disagree by its error
    path = _preamble_file(tmp_path, with_time=False)
    argv = ["fit", str(path), "--json"]
    status, _, err = command(argv, capsys)
    assert status == 2 and "disagree" in err
    rate = re.search(r"at (\S+) Hz the channels agree", err)
    given = re.search(r"(--sample-rate) HZ", err)
    skip = re.search(r"(--skip-rows) (\d+)", err)
    assert rate is not None and given is not None and skip is not None, err
    status, out, err = command([*argv, given[1], rate[1], skip[1], skip[2]], capsys)
    assert status == 0, err
    covers(json.loads(out), {"zeta": ZETA, "friction_displacement": 1e-3 * X_C})


def _sha(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


@pytest.mark.skipif(not hasattr(__import__("os"), "openpty"), reason="pseudo-terminals")
def test_a_run_id_taken_is_refused_and_another_one_records_the_run(tmp_path, capsys) -> None:
    from bayestribo import read_run

    out = tmp_path / "runs"
    argv = ["acquire", "--simulate", "--load", "0.31", "--lubricant", "glycerol"]
    argv += ["--out", str(out), "--no-catalog", "--quiet", "--duration", "0.2"]
    status, _, err = command([*argv, "--run-id", "r1"], capsys)
    assert status == 0, err
    before = _sha(out)
    status, _, err = command([*argv, "--run-id", "r1"], capsys)
    assert status == 2 and "run 'r1' exists already" in err
    option = re.search(r"give another (--[\w-]+)", err)
    assert option is not None, err
    status, _, err = command([*argv, option[1], "r2"], capsys)
    assert status == 0, err
    assert read_run(out / "r2.csv").n_samples > 0
    assert {k: v for k, v in _sha(out).items() if k.startswith("r1")} == before  # untouched


def test_a_stop_beyond_the_bound_on_the_papers_rig_still_advises_the_prior_first(
    tmp_path, capsys
) -> None:
    # viscous damping and Coulomb friction sticking at μ_s/μ_k = 20 (solve_ivp): the
    # misfit is the stop's, with a smooth part that is significant but small
    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * RIG_ZETA * omega * v,
        friction=RIG_MU_K * LOAD / MASS,
        static_ratio=20.0,
        duration_s=1.0,
        seed=2,
    )
    path = write_run(run, tmp_path / "sticks.csv")
    status, _, err = command(["fit", str(path), "--json"], capsys)
    assert status == 1 and "smoothly along the decay" in err
    option = first_advice(err)
    assert option.startswith("--prior mu_s_ratio="), err
    status, out, err = command(["fit", str(path), "--json", *option.split()], capsys)
    assert status == 0, err
    covers(json.loads(out), {"zeta": RIG_ZETA, "mu_k": RIG_MU_K, "mu_s": 20.0 * RIG_MU_K})
