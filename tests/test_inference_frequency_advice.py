"""The frequency warning's advice on a restoring force: given only where a force follows.

A half period that changes along the decay is warned about; the warning used to advise
``--restoring duffing`` (and ``--restoring auto``) whatever the change. Where the change
is not a function of the swing that any registered force makes (here a stiffness that
rises and falls again in time, as a rig warming and cooling would), the Duffing spring,
followed, leaves the change as it was, and ``--restoring auto`` keeps the linear spring
with a warning: the advice answered nothing. The warning now says that no force follows
the change and advises none; on a Duffing spring's record it advises the force as before.

The records are independent simulations (``solve_ivp``, the package's models unused).
"""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from bayestribo.cli import main
from bayestribo.io import write_run
from bayestribo.io.run import Run

F_HZ, ZETA, X0 = 5.0, 0.004, 0.02  # frequency [Hz], damping ratio, release [m]
RATE_HZ, DURATION_S, NOISE_M = 500.0, 24.0, 2e-6


def _record(rhs, seed: int) -> Run:
    """The free decay of ``rhs(t, x, v) -> x''`` from rest at X0, at RATE_HZ with white
    noise on both channels (sd NOISE_M and Ω NOISE_M)."""
    omega = 2.0 * math.pi * F_HZ
    t = np.arange(int(DURATION_S * RATE_HZ)) / RATE_HZ
    sol = solve_ivp(
        lambda tt, s: [s[1], rhs(tt, s[0], s[1])],
        (0.0, t[-1]),
        [X0, 0.0],
        method="DOP853",
        rtol=1e-11,
        atol=1e-14,
        t_eval=t,
    )
    rng = np.random.default_rng(seed)
    x = sol.y[0] + rng.normal(0.0, NOISE_M, t.size)
    v = sol.y[1] + rng.normal(0.0, omega * NOISE_M, t.size)
    return Run(t, x, v, {"run_id": "drift", "length_unit": "m"})


def _fit(path: Path, capsys) -> tuple[int, str]:
    with contextlib.redirect_stdout(io.StringIO()):
        status = main(["fit", str(path), "--law", "viscous", "--json"])
    return status, capsys.readouterr().err


def _frequency_warning(err: str) -> str:
    return next(w for w in err.split("bayestribo fit: warning: ") if "half period changes" in w)


def test_a_stiffness_that_drifts_in_time_is_said_to_follow_no_force(tmp_path, capsys) -> None:
    omega = 2.0 * math.pi * F_HZ

    # the stiffness 0.8 % above its mean in the middle of the decay, at it at both ends:
    # the half period falls and rises again, a change no force of the swing makes
    def rhs(t: float, x: float, v: float) -> float:
        k = omega**2 * (1.0 + 0.008 * math.sin(math.pi * t / DURATION_S))
        return -2.0 * ZETA * omega * v - k * x

    path = write_run(_record(rhs, seed=3), tmp_path / "drift.csv")
    _, err = _fit(path, capsys)
    warning = _frequency_warning(err)
    assert "no registered restoring force follows the change" in warning, warning
    assert "--restoring" not in warning, warning


def test_a_duffing_springs_change_still_advises_the_force(tmp_path, capsys) -> None:
    omega = 2.0 * math.pi * F_HZ
    beta = 40.0  # 1/m²: the half period shortens by about 3βX0²/8 = 0.6 % at the release

    def rhs(t: float, x: float, v: float) -> float:
        return -2.0 * ZETA * omega * v - omega**2 * (x + beta * x**3)

    path = write_run(_record(rhs, seed=4), tmp_path / "duffing.csv")
    _, err = _fit(path, capsys)
    warning = _frequency_warning(err)
    assert "--restoring duffing" in warning, warning
    assert "no registered restoring force" not in warning, warning
