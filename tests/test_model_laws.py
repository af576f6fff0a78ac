"""Dissipation laws as plug-ins (bayestribo/model/laws): names, registry, ΔE(A), and
the compiled half-cycle integrator against the closed form and quadrature."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.integrate import quad

from bayestribo.model.laws import (
    TERMS,
    Law,
    Parameter,
    PhysicalScale,
    Term,
    available_terms,
    get_law,
    get_term,
)
from bayestribo.model.laws.base import harmonic_power_integral

# -- names ---------------------------------------------------------------------------


def test_the_built_in_terms_are_registered_in_order():
    assert available_terms()[:5] == ["viscous", "coulomb", "quadratic", "power", "hysteretic"]


def test_a_law_is_its_terms_in_registration_order_whatever_the_order_written():
    law = Law.from_name(" Coulomb + viscous")
    assert law.name == "viscous+coulomb"
    assert law.parameter_names == ["zeta", "mu_k", "mu_s_ratio"]
    assert get_law(None).name == "viscous+coulomb"
    assert get_law("quadratic+viscous+coulomb").parameter_names == [
        "zeta",
        "mu_k",
        "mu_s_ratio",
        "c2",
    ]


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("viscous+drag", "unknown dissipation term 'drag'; registered terms: viscous, coulomb"),
        ("viscous+viscous", "names each term once"),
        ("viscous++coulomb", "an empty term"),
        ("", "expected terms joined with '+'"),
    ],
)
def test_a_bad_law_name_is_refused_with_the_registered_terms(name, message):
    with pytest.raises(ValueError, match=message.replace("+", r"\+").replace("(", r"\(")):
        Law.from_name(name)


def test_a_term_whose_parameter_another_term_has_is_refused():
    viscous = get_term("viscous")
    clash = Term(
        name="clash",
        kind="drag",
        parameters=viscous.parameters,
        n_coefficients=1,
        force=viscous.force,
        coefficients=viscous.coefficients,
        dissipation=viscous.dissipation,
        physical=viscous.physical,
        description="",
    )
    with pytest.raises(ValueError, match="'zeta' is already a parameter of term 'viscous'"):
        TERMS.add(clash)
    assert "clash" not in TERMS


def test_only_the_viscous_and_coulomb_laws_have_the_closed_form():
    assert get_law("viscous+coulomb").closed_form
    assert get_law("viscous").closed_form and get_law("coulomb").closed_form
    assert not get_law("viscous+quadratic").closed_form
    with pytest.raises(ValueError, match="has no closed form"):
        get_law("quadratic").pi_grid([0.0], {"c2": 0.01}, [1.0], method="closed")


# -- ΔE(A) -----------------------------------------------------------------------------

VALUES = {
    "zeta": 0.013,
    "mu_k": 0.021,
    "mu_s_ratio": 1.4,
    "c2": 0.037,
    "zeta_alpha": 0.008,
    "alpha": 0.6,
    "eta": 0.011,
}


def _force(term: Term, values: dict, reference: float):
    """The term's force F(v, A) as plain Python: (drag magnitude, friction magnitude)."""
    coef = np.concatenate(
        [
            np.atleast_1d(c)
            for c in term.coefficients({k: np.array([v]) for k, v in values.items()}, reference)
        ]
    )
    return lambda speed, amp: float(term.force(speed if term.kind == "drag" else amp, coef))


@pytest.mark.parametrize("name", ["viscous", "coulomb", "quadratic", "power", "hysteretic"])
@pytest.mark.parametrize("amplitude", [0.3, 2.0, 7.5])
def test_each_terms_dissipation_is_the_integral_of_its_force_over_a_cycle(name, amplitude):
    """ΔE(A) = ∮ F(y') y' dτ over y = A cos τ by quadrature of the compiled force."""
    term = get_term(name)
    reference = 4.0
    force = _force(term, VALUES, reference)

    def power(tau: float) -> float:
        v = -amplitude * math.sin(tau)
        return force(abs(v), amplitude) * abs(v)

    numeric = quad(power, 0.0, math.pi, epsabs=0, epsrel=1e-13, limit=200)[0] * 2.0
    vals = {k: np.array([v]) for k, v in VALUES.items()}
    closed = float(term.dissipation(np.array([amplitude]), vals, reference)[0])
    assert closed == pytest.approx(numeric, rel=1e-10)


def _ode_swing_dissipation(law: Law, values: dict, reference: float, swing: float) -> float:
    """2A(a_s - a_e) by solve_ivp of y'' + y = -F through the half cycle from rest at
    a_s (the terms' forces as plain Python), a_s by Brent's method."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    forces = [(t.kind, _force(t, values, reference)) for t in law.terms]

    def end(a: float) -> float:
        def rhs(_t: float, s: np.ndarray) -> list[float]:
            w = abs(s[1])
            f = sum(fn(w, a) for _, fn in forces)  # each term's magnitude at speed w
            return [s[1], -s[0] + f]  # moving towards -y: the forces push +y

        def turned(_t: float, s: np.ndarray) -> float:
            return s[1]

        turned.terminal, turned.direction = True, 1.0
        sol = solve_ivp(
            rhs,
            (0.0, 2 * math.pi),
            [a, 0.0],
            method="DOP853",
            rtol=1e-12,
            atol=1e-15,
            events=turned,
        )
        return -float(sol.y_events[0][0][0])

    a_s = brentq(lambda a: 0.5 * (a + end(a)) - swing, swing, 2 * swing + 1, xtol=1e-14)
    return 2 * swing * (a_s - end(a_s))


@pytest.mark.parametrize(
    "name",
    [
        "viscous",
        "viscous+coulomb",
        "quadratic",
        "coulomb+power",
        "coulomb+hysteretic",
        "hysteretic",
        "viscous+coulomb+quadratic",
    ],
)
@pytest.mark.parametrize("swing", [0.6, 3.0, 9.0])
def test_swing_dissipation_is_the_half_cycle_loss_of_the_laws_own_motion(name, swing):
    """The closed form (viscous, Coulomb) and the compiled integrator against
    solve_ivp through the half cycle."""
    law = get_law(name)
    vals = {k: VALUES[k] for k in law.parameter_names}
    got = float(law.swing_dissipation([swing], vals, 4.0)[0, 0])
    want = _ode_swing_dissipation(law, vals, 4.0, swing)
    assert got == pytest.approx(want, rel=1e-7)


def test_laws_with_the_same_decay_have_the_same_swing_dissipation_not_harmonic():
    """Viscous damping and a friction proportional to the amplitude with the same
    half-cycle ratio: the same decay, the same ΔE(A) at every swing; their integrals
    over the harmonic motion differ by about η (1.1 % here)."""
    eta = VALUES["eta"]
    beta = -math.log(1 - 2 * eta) / math.pi  # e^{-πβ} = 1 - 2η
    zeta = beta / math.sqrt(1 + beta**2)
    swings = np.array([0.5, 2.0, 8.0])
    hyst = get_law("hysteretic")
    visc = get_law("viscous")
    np.testing.assert_allclose(
        hyst.swing_dissipation(swings, {"eta": eta}, 1.0),
        visc.swing_dissipation(swings, {"zeta": zeta}, 1.0),
        rtol=1e-8,
    )
    ratio = visc.dissipation(swings, {"zeta": zeta}, 1.0) / hyst.dissipation(
        swings, {"eta": eta}, 1.0
    )
    assert np.all(ratio > 1 + 0.9 * eta)


def test_coulomb_swing_dissipation_is_the_harmonic_integral_exactly():
    law = get_law("coulomb")
    swings = np.array([0.5, 2.0, 8.0])
    vals = {"mu_k": 0.021, "mu_s_ratio": 1.4}
    np.testing.assert_allclose(
        law.swing_dissipation(swings, vals, 1.0), law.dissipation(swings, vals, 1.0), rtol=1e-14
    )


def test_power_law_at_exponent_one_is_viscous_damping_at_the_same_zeta():
    law_p, law_v = get_law("power"), get_law("viscous")
    amps = np.array([0.5, 1.0, 3.0])
    p = law_p.dissipation(amps, {"zeta_alpha": 0.02, "alpha": 1.0}, 2.0)
    v = law_v.dissipation(amps, {"zeta": 0.02}, 2.0)
    np.testing.assert_allclose(p, v, rtol=1e-12)


def test_harmonic_power_integral_matches_known_values():
    np.testing.assert_allclose(harmonic_power_integral([1.0, 2.0, 3.0]), [4.0, math.pi, 8 / 3])


def test_a_laws_dissipation_is_the_sum_of_its_terms_and_scales_to_joules():
    law = get_law("viscous+coulomb+quadratic")
    vals = {k: VALUES[k] for k in law.parameter_names}
    parts = law.dissipation([1.0, 2.0], vals, 1.0, by_term=True)
    total = law.dissipation([1.0, 2.0], vals, 1.0)
    np.testing.assert_allclose(total, sum(parts.values()))
    np.testing.assert_allclose(parts["coulomb"], [[4 * 0.021 * 1.0, 4 * 0.021 * 2.0]], rtol=1e-14)
    scale = PhysicalScale(length_scale=2e-4, omega=200.0, stiffness=1400.0)
    assert scale.energy_factor == pytest.approx(1400.0 * 4e-8)
    assert scale.energy_unit == "J"
    assert PhysicalScale(length_unit="mm").energy_unit == "mm^2"


# -- the integrator against the closed form --------------------------------------------


@pytest.mark.parametrize(
    ("law", "values"),
    [
        ("viscous+coulomb", {"zeta": 0.01, "mu_k": 0.02, "mu_s_ratio": 1.5}),
        ("viscous+coulomb", {"zeta": 0.05, "mu_k": 0.001, "mu_s_ratio": 2.5}),
        ("viscous+coulomb", {"zeta": 1e-4, "mu_k": 0.03, "mu_s_ratio": 1.0}),
        ("viscous", {"zeta": 0.003}),
        ("coulomb", {"mu_k": 0.01, "mu_s_ratio": 1.2}),
    ],
)
@pytest.mark.parametrize(("yp0", "tau_end"), [(0.0, None), (0.37, None), (-0.5, 150.0)])
def test_the_integrator_agrees_with_the_closed_form(law, values, yp0, tau_end):
    """Π within 1e-8 of Π(0) at points inside half cycles, through sticking, a start
    inside a half cycle and a record that ends in the motion (the target of the
    laws without a closed form)."""
    the_law = get_law(law)
    tau = np.sort(np.append(np.random.default_rng(4).uniform(0.0, 400.0, 60), 0.0))
    closed = the_law.pi_grid(tau, values, [1.2], yp0=yp0, tau_end=tau_end)
    integrated = the_law.pi_grid(tau, values, [1.2], yp0=yp0, tau_end=tau_end, method="integrate")
    assert np.max(np.abs(integrated - closed)) < 1e-8 * closed[0, 0]
    # and it converges: a quarter of the steps is far off, twice the steps closer still
    coarse, fine = (
        the_law.pi_grid(tau, values, [1.2], yp0=yp0, tau_end=tau_end, method="integrate", steps=n)
        for n in (12, 96)
    )
    assert np.max(np.abs(coarse - closed)) > 1e-8 * closed[0, 0]
    assert np.max(np.abs(fine - closed)) < 2e-9 * closed[0, 0]


def test_the_integrator_handles_many_parameter_sets_at_once():
    law = get_law("viscous+coulomb")
    tau = np.linspace(0.0, 200.0, 30)
    values = {"zeta": [0.01, 0.02, 0.0], "mu_k": [0.02, 0.0, 0.01], "mu_s_ratio": [1.5, 1.0, 2.0]}
    closed = law.pi_grid(tau, values, [1.0, 2.0, 0.53], tau_end=250.0)
    integrated = law.pi_grid(tau, values, [1.0, 2.0, 0.53], tau_end=250.0, method="integrate")
    assert integrated.shape == (3, 30)
    err = np.max(np.abs(integrated - closed), axis=1)
    assert np.all(err < 1e-8 * closed[:, 0])


def test_a_parameter_given_once_or_per_set_gives_the_same_rows():
    """A value shared by every set (a scalar) and the same value given per set give Π
    equal to the bit, row by row as each set alone; the names a law hands out are a
    copy (changing them leaves the law's own)."""
    law = get_law("coulomb+power")
    tau = np.linspace(0.0, 40.0, 12)
    per_set = {
        "mu_k": np.array([0.01, 0.02]),
        "mu_s_ratio": np.array([1.2, 1.2]),
        "zeta_alpha": np.array([0.01, 0.01]),
        "alpha": np.array([0.7, 1.6]),
    }
    shared = {**per_set, "mu_s_ratio": 1.2, "zeta_alpha": 0.01}
    both = law.pi_grid(tau, per_set, [1.0, 1.0], reference=1.0)
    assert np.array_equal(law.pi_grid(tau, shared, [1.0, 1.0], reference=1.0), both)
    for i in range(2):
        alone = {name: value[i : i + 1] for name, value in per_set.items()}
        assert np.array_equal(law.pi_grid(tau, alone, [1.0], reference=1.0)[0], both[i])
    names = law.parameter_names
    names.append("extra")
    assert law.parameter_names == ["mu_k", "mu_s_ratio", "zeta_alpha", "alpha"]


def test_a_drag_too_strong_to_turn_is_followed_without_friction_and_refused_with_it():
    """An overdamped arc (the drag turns the phase angle back before y' = 0): a drag
    alone is followed through it (:mod:`bayestribo.model.laws._creep`; a quadratic drag
    this strong crosses the centre slowly, then decays), within 1e-6 of Π(0) of
    solve_ivp's (3.7e-7 measured); beside a friction the row is outside the law's
    domain (NaN)."""
    from scipy.integrate import solve_ivp

    tau = np.linspace(0, 10, 5)
    pi = get_law("quadratic").pi_grid(tau, {"c2": [0.01, 50.0]}, [1.0, 1.0])
    assert np.all(np.isfinite(pi))

    def rhs(t, s):
        return [s[1], -s[0] - 50.0 * s[1] * abs(s[1]), 0.5 * (s[0] ** 2 + s[1] ** 2)]

    sol = solve_ivp(
        rhs, (0, 2000), [1, 0, 0], method="LSODA", rtol=1e-12, atol=1e-16, dense_output=True
    )
    ref = sol.y[2, -1] - sol.sol(tau)[2]
    assert np.max(np.abs(pi[1] - ref)) < 1e-6 * ref[0]
    with_friction = get_law("coulomb+quadratic").pi_grid(
        tau, {"mu_k": [0.01], "mu_s_ratio": [1.0], "c2": [50.0]}, [1.0]
    )
    assert np.all(np.isnan(with_friction))


@pytest.mark.parametrize(("yp0", "tau_end"), [(0.0, None), (0.37, None), (-0.5, 150.0)])
def test_a_friction_law_at_zero_friction_integrates_as_the_law_without_it(yp0, tau_end):
    """μ_k = 0 (on its bound): Π of the law without the friction term to the last bit,
    also summed past the record to the end of motion (which no friction stops: the sum
    ends as the frictionless law's does, not after the tens of thousands of half cycles
    the drag takes to bring r to zero), and within 1e-8 of Π(0) of the closed form."""
    tau = np.sort(np.append(np.random.default_rng(5).uniform(0.0, 400.0, 60), 0.0))
    drag = {"zeta": [0.013, 0.013], "c2": [0.0, 0.002]}
    frictionless = get_law("viscous+quadratic").pi_grid(tau, drag, [1.2, 1.2], yp0, tau_end)
    for law in ("viscous+coulomb+quadratic", "viscous+coulomb+hysteretic+quadratic"):
        the_law = get_law(law)
        values = {p.name: [p.null, p.null] for p in the_law.parameters}
        values.update(drag, mu_k=[0.0, 0.0], mu_s_ratio=[1.5, 1.5])
        pi = the_law.pi_grid(tau, values, [1.2, 1.2], yp0, tau_end)
        np.testing.assert_array_equal(pi, frictionless)
    closed = get_law("viscous").pi_grid(tau, {"zeta": 0.013}, [1.2], yp0, tau_end)
    integrated = get_law("viscous+coulomb").pi_grid(
        tau,
        {"zeta": 0.013, "mu_k": 0.0, "mu_s_ratio": 1.5},
        [1.2],
        yp0,
        tau_end,
        method="integrate",
    )
    assert np.max(np.abs(pi[0] - closed[0])) < 1e-8 * closed[0, 0]
    assert np.max(np.abs(integrated - closed)) < 1e-8 * closed[0, 0]


# -- a term defined outside the package ------------------------------------------------


@numba.njit
def _cubic_force(w, c):
    return c[0] * w * w * w


def _cubic_dissipation(amplitude, values, reference):
    a = np.asarray(amplitude, dtype=float)
    return (3.0 * math.pi / 4.0) * np.asarray(values["c3"], dtype=float) * a**4


CUBIC = Term(
    name="cubic",
    kind="drag",
    parameters=(
        Parameter(
            "c3",
            "c₃",
            "1/y²",
            0.0,
            math.inf,
            "cubic drag",
            lambda amplitude: {"type": "Uniform", "low": 0.0, "high": 1.0 / amplitude**2},
        ),
    ),
    n_coefficients=1,
    force=_cubic_force,
    coefficients=lambda values, reference: [np.asarray(values["c3"], dtype=float)],
    dissipation=_cubic_dissipation,
    physical=lambda values, reference, scale: {},
    description="cubic drag c₃ v³",
)


def test_a_law_with_a_term_of_its_own_integrates_without_registering_it():
    law = Law((get_term("viscous"), CUBIC))
    assert law.name == "viscous+cubic" and not law.closed_form
    tau = np.linspace(0.0, 60.0, 20)
    with_cubic = law.pi_grid(tau, {"zeta": 0.01, "c3": 0.02}, [1.0], tau_end=80.0)
    without = law.pi_grid(tau, {"zeta": 0.01, "c3": 0.0}, [1.0], tau_end=80.0)
    viscous = get_law("viscous").pi_grid(tau, {"zeta": 0.01}, [1.0], tau_end=80.0)
    np.testing.assert_allclose(without, viscous, rtol=0, atol=1e-8 * viscous[0, 0])
    assert np.all(with_cubic[0, :-1] < without[0, :-1])
    # the cubic term's ΔE is its force's integral over a cycle
    numeric = 2 * quad(lambda t: 0.02 * abs(1.5 * math.sin(t)) ** 4, 0, math.pi)[0]
    assert law.dissipation([1.5], {"zeta": 0.0, "c3": 0.02}, 1.0)[0, 0] == pytest.approx(numeric)


# -- the compiled laws are cached across processes -------------------------------------

_CACHE_SCRIPT = """
import numpy as np
from bayestribo.model.laws import get_law
from bayestribo.model.laws.integrator import make_integrator
law = get_law("viscous+coulomb+quadratic")
pi = law.pi_grid(np.linspace(0, 20, 7), {"zeta": 0.01, "mu_k": 0.01, "mu_s_ratio": 1.5,
                                         "c2": 0.02}, [1.0])
grid, _, _ = make_integrator(*law._layout[0])
print(repr(pi.tolist()), grid.stats.cache_hits and sum(grid.stats.cache_hits.values()),
      sum(grid.stats.cache_misses.values()))
"""


@pytest.mark.validation  # a process compiles the law afresh (a minute)
def test_a_laws_integrator_is_compiled_once_and_loaded_by_later_processes(tmp_path):
    import os
    import subprocess
    import sys

    env = {**os.environ, "BAYESTRIBO_CACHE_DIR": str(tmp_path)}
    runs = [
        subprocess.run(
            [sys.executable, "-c", _CACHE_SCRIPT], env=env, capture_output=True, text=True
        )
        for _ in range(2)
    ]
    for r in runs:
        assert r.returncode == 0, r.stderr
    first, second = (r.stdout.split() for r in runs)
    assert first[0] == second[0]  # the same Π
    assert first[-1] != "0"  # compiled the first time ...
    assert second[-2] != "0" and second[-1] == "0"  # ... loaded from the cache after
    assert list(tmp_path.glob("bayestribo_law_*.py"))


@pytest.mark.validation  # numba compiles a law of a local term afresh
def test_a_term_that_cannot_be_imported_by_name_is_compiled_in_each_process():
    @numba.njit
    def local_drag(w, c):
        return c[0] * w

    term = Term(
        name="local",
        kind="drag",
        parameters=(Parameter("c_local", "c", "-", 0.0, 1.0, "", lambda a: {"type": "Uniform"}),),
        n_coefficients=1,
        force=local_drag,
        coefficients=lambda values, reference: [2.0 * np.asarray(values["c_local"])],
        dissipation=lambda a, values, reference: 0.0,
        physical=lambda values, reference, scale: {},
        description="",
    )
    tau = np.linspace(0.0, 30.0, 9)
    local = Law((term,)).pi_grid(tau, {"c_local": 0.01}, [1.0], tau_end=40.0)
    viscous = get_law("viscous").pi_grid(tau, {"zeta": 0.01}, [1.0], tau_end=40.0)
    np.testing.assert_allclose(local, viscous, rtol=0, atol=1e-8 * viscous[0, 0])
