"""A friction coefficient no contact has is said, with the load and mass it came from."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.errors import ImplausibleFrictionWarning, MisfitWarning
from bayestribo.inference.plausibility import MU_K_LIMIT, implausible_friction

MASS, LOAD, FREQ, MU_K = 0.035, 0.3, 32.6, 0.03


def _coulomb_record(tmp_path, meta, seed=3):
    """An independent closed-form Coulomb decay (half cycle by half cycle about ±x_c,
    stopping where a turning point is within μ_s = 1.5 μ_k), 5 kHz, 0.1 µm noise, as a
    canonical CSV with ``meta`` beside it."""
    w = 2 * np.pi * FREQ
    xc = MU_K * LOAD / (MASS * w**2)
    fs, rest = 5000.0, 0.3
    t = np.arange(int(1.6 * fs)) / fs
    x = np.full(t.size, 5e-4)
    start, x0 = rest, 5e-4
    while abs(x0) > 1.5 * xc:
        centre = np.sign(x0) * xc
        inside = (t >= start) & (t < start + np.pi / w)
        x[inside] = centre + (x0 - centre) * np.cos(w * (t[inside] - start))
        x0, start = 2 * centre - x0, start + np.pi / w
        x[t >= start] = x0
    x = x + np.random.default_rng(seed).normal(0.0, 1e-7, t.size)
    path = tmp_path / "run.csv"
    rows = "\n".join(f"{a:.6f},{b:.9e}" for a, b in zip(t, x, strict=True))
    path.write_text("time_s,displacement_m\n" + rows + "\n")
    (tmp_path / "run.json").write_text(json.dumps({**meta, "natural_frequency_Hz": FREQ}))
    return path


def _fit(path, capsys):
    """Exit status, the JSON's μ_k and the warnings printed, as a user runs it."""
    status = main(["fit", str(path), "--json", "--seed", "1"])
    out = capsys.readouterr()
    return status, json.loads(out.out)["parameters"]["mu_k"], out.err


def test_a_mass_in_grams_under_mass_kg_is_said_and_exits_1(tmp_path, capsys):
    # the sidecar a user writes after renaming mass_g to mass_kg and keeping its number
    path = _coulomb_record(tmp_path, {"load_N": LOAD, "mass_kg": 1000 * MASS})
    status, mu_k, err = _fit(path, capsys)
    assert status == 1
    said = [line for line in err.splitlines() if "no contact's kinetic friction" in line]
    assert len(said) == 1
    assert "mass_kg = 35.0 kg" in said[0] and "load_N = 0.3 N" in said[0]
    assert issubclass(ImplausibleFrictionWarning, MisfitWarning)  # what makes the exit 1
    # the record is fitted as well as ever: μ_k is 1000 times the truth
    low, high = mu_k["interval"]
    assert low < 1000 * MU_K < high


def test_the_advice_followed_gives_the_truth_without_the_warning(tmp_path, capsys):
    # the message says: give the mass in kilograms (or under a key naming grams)
    path = _coulomb_record(tmp_path, {"load_N": LOAD, "mass_g": 1000 * MASS})
    status, mu_k, err = _fit(path, capsys)
    assert "no contact's kinetic friction" not in err
    assert status == 0, err
    low, high = mu_k["interval"]
    assert low < MU_K < high


@pytest.mark.parametrize(
    ("centre", "spread", "said"),
    [(30.0, 0.5, True), (1.2, 0.1, False), (MU_K_LIMIT, 0.5, False), (0.03, 0.001, False)],
)
def test_only_an_interval_wholly_above_the_limit_is_said(centre, spread, said):
    draws = np.random.default_rng(0).normal(centre, spread, 4000)
    reason = implausible_friction({"mu_k": draws}, {"load_N": 0.3, "mass_kg": 35.0})
    assert (reason is not None) is said
    assert implausible_friction({"zeta": draws}, {}) is None
