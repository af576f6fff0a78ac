"""A rotational rig: angles and angular velocities read in radians, friction as an angle
and, with the moment of inertia, as a torque.

Independent simulation: ``solve_ivp`` of I θ'' + c θ' + κ θ + T_c sgn θ' = 0 (a torsion
pendulum with a dry pivot: I = 0.01 kg m², f = 1 Hz, ζ = 0.005, T_c = 2 mN m), from
0.5 rad at rest, half cycle by half cycle until it sticks (|κθ| <= 1.2 T_c), sampled at
200 Hz and written in degrees with 2 millidegrees of noise.
"""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo import check_adequacy, estimate_all, fit, read_run
from bayestribo.errors import RunFormatError
from bayestribo.io.columns import parse_column

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

INERTIA, F_HZ, ZETA, TORQUE, THETA0, FS = 0.01, 1.0, 0.005, 0.002, 0.5, 200.0


@pytest.mark.parametrize(
    ("name", "canonical", "factor"),
    [
        ("angle_deg", "angle_rad", math.pi / 180),
        ("Angle (rad)", "angle_rad", 1.0),
        ("theta [deg]", "angle_rad", math.pi / 180),
        ("angular_velocity_deg_per_s", "angular_velocity_rad_per_s", math.pi / 180),
        ("Angular velocity (rad/s)", "angular_velocity_rad_per_s", 1.0),
        ("omega [rpm]", "angular_velocity_rad_per_s", 2 * math.pi / 60),
        ("velocity_m_per_s", "velocity_m_per_s", 1.0),
    ],
)
def test_angle_columns_are_named_with_their_unit(name, canonical, factor):
    assert parse_column(name) == (canonical, pytest.approx(factor, rel=1e-15))


def test_an_angle_without_a_unit_is_refused():
    with pytest.raises(ValueError, match="has no unit"):
        parse_column("angle")


@functools.lru_cache(maxsize=1)
def _torsion() -> tuple[np.ndarray, np.ndarray]:
    w = 2 * math.pi * F_HZ
    kappa, c = INERTIA * w * w, 2 * ZETA * INERTIA * w
    t = np.arange(0.0, 25.0, 1.0 / FS)
    theta = np.full(t.size, np.nan)
    state, t0 = [THETA0, 0.0], 0.0
    while t0 < t[-1] and abs(kappa * state[0]) > 1.2 * TORQUE:
        s = -math.copysign(1.0, state[0])

        def rhs(_t, u, s=s):
            return [u[1], (-c * u[1] - kappa * u[0] - TORQUE * s) / INERTIA]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t0, t0 + 2 / F_HZ),
            state,
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-13,
        )
        t1 = float(sol.t_events[0][0])
        inside = (t >= t0) & (t < t1)
        theta[inside] = sol.sol(t[inside])[0]
        state, t0 = [float(sol.sol(t1)[0]), 0.0], t1
    theta[np.isnan(theta)] = state[0]
    noise = np.random.default_rng(1).normal(0.0, 2e-3, t.size)
    return t, np.degrees(theta) + noise


def _write(tmp_path, header: str = "time_s,angle_deg", **sidecar) -> object:
    t, degrees = _torsion()
    path = tmp_path / "torsion.csv"
    np.savetxt(path, np.c_[t, degrees], delimiter=",", header=header, comments="", fmt="%.6f")
    if sidecar:
        path.with_suffix(".json").write_text(json.dumps(sidecar))
    return path


def test_a_file_of_angles_reads_in_radians(tmp_path):
    run = read_run(_write(tmp_path))
    assert run.length_unit == "rad"
    assert run.displacement[0] == pytest.approx(THETA0, abs=1e-4)
    rig = run.rig(natural_frequency_Hz=F_HZ)
    assert rig.mass_kg is None and rig.load_N is None  # no load on an angle


def test_angles_beside_lengths_are_refused(tmp_path):
    t, degrees = _torsion()
    path = tmp_path / "both.csv"
    np.savetxt(
        path,
        np.c_[t, degrees, degrees],
        delimiter=",",
        header="time_s,angle_deg,x_mm",
        comments="",
    )
    with pytest.raises(RunFormatError, match=r"are angles and \['displacement_m'\] lengths"):
        read_run(path)


def test_metadata_stating_metres_for_angles_is_refused(tmp_path):
    with pytest.raises(RunFormatError, match="are angles but the metadata give length_unit 'm'"):
        read_run(_write(tmp_path, length_unit="m"))


def test_a_torsion_pendulum_gives_its_friction_torque(tmp_path):
    path = _write(tmp_path, inertia_kg_m2=INERTIA, gain_uncertainty=0.0)
    result = fit(path, seed=2, grid_points=32)
    units = result.units()
    assert units["friction_displacement"] == "rad" and units["friction_torque"] == "N m"
    torque = result.samples("friction_torque")
    assert abs(np.mean(torque) - TORQUE) < 4.5 * np.std(torque)
    angle = result.samples("friction_displacement")
    kappa = INERTIA * (2 * math.pi * F_HZ) ** 2
    assert abs(np.mean(angle) - TORQUE / kappa) < 4.5 * np.std(angle)
    zeta = result.samples("zeta")
    assert abs(np.mean(zeta) - ZETA) < 4.5 * np.std(zeta)
    assert result.dissipation["unit"] == "J" and result.dissipation["amplitude_unit"] == "rad"


def test_the_adequacy_check_of_a_rotation_speaks_of_angles(tmp_path):
    """Its amplitudes in rad and its friction the angle θ_c, never x_c in a signal unit."""
    check = check_adequacy(read_run(_write(tmp_path)), seed=1)
    text = check.to_text()
    assert "amplitude [rad]" in text and "signal unit" not in text
    assert "θ_c" in text and "x_c" not in text
    assert check.windows.length_unit == "rad" and check.windows.friction_symbol == "θ_c"


def test_a_reports_symbols_for_a_rotation_are_angles(tmp_path):
    from bayestribo.reports.laws import paper_parameters
    from bayestribo.reports.tables import estimates_frame, fit_frame

    result = fit(read_run(_write(tmp_path)), seed=2, grid_points=16)
    assert paper_parameters(result)["friction_displacement"] == "θ_c"
    quantities = list(fit_frame(result, dissipation=False).index)
    assert "θ_c" in quantities and "x_c" not in quantities
    classical = estimates_frame(estimate_all(read_run(_write(tmp_path))), unit="rad")
    assert "θ_c [rad] [95 %]" in classical.columns
