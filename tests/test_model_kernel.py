"""The compiled Π kernel against the numpy implementation of the exact model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from bayestribo.model import exact_pi
from bayestribo.model._kernel import exact_pi_grid


@pytest.mark.parametrize("yp0", [0.0, 0.37, -1.2])
@pytest.mark.parametrize("tau_end", [None, 150.3])
def test_kernel_agrees_with_numpy_model(yp0, tau_end):
    rng = np.random.default_rng(11)
    n = 300
    zeta = rng.uniform(0.0, 0.3, n)
    zeta[:5] = 0.0  # pure Coulomb
    zeta[5:8] = 1e-7  # nearly undamped: series branches
    mu_k = rng.uniform(0.0, 0.1, n)
    mu_k[10:15] = 0.0  # pure viscous, some without static friction (endless motion)
    mu_s = mu_k * rng.uniform(1.0, 2.0, n)
    mu_s[10:12] = 0.0
    y0 = rng.uniform(-10.0, 10.0, n)
    tau = np.linspace(0.0, 300.0, 97)
    fast = exact_pi_grid(tau, y0, zeta, mu_k, mu_s, yp0, tau_end)
    ref = exact_pi(
        tau,
        y0[:, None],
        zeta[:, None],
        mu_k[:, None],
        mu_s[:, None],
        yp0,
        tau_end=tau_end,
        backend="numpy",
    )
    finite = np.isfinite(ref)
    np.testing.assert_array_equal(np.isfinite(fast), finite)
    # Same formulas, different grouping of floating-point operations.
    np.testing.assert_allclose(fast[finite], ref[finite], rtol=1e-12, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    zeta=st.floats(0.0, 0.9),
    # Exact zero or at least 1e-12: below that the motion lasts ~1/μ_k half cycles and
    # Π overflows the double range.
    mu_k=st.one_of(st.just(0.0), st.floats(1e-12, 0.5)),
    extra=st.floats(0.0, 0.5),
    y0=st.floats(-20.0, 20.0),
    yp0=st.floats(-5.0, 5.0),
    tau_end=st.one_of(st.none(), st.floats(1.0, 200.0)),
)
def test_kernel_property(zeta, mu_k, extra, y0, yp0, tau_end):
    if zeta == 0.0 and mu_k == 0.0 and tau_end is None:
        return  # endless, undamped: both are inf
    # The stick rule is a discontinuity: a swing of amplitude exactly μ_s - μ_k sticks,
    # one a rounding error above it goes on. Started at |y0| = μ_s with a velocity of
    # 1e-132 (the same float drawn for y0 and μ_s), the first swing is μ_s - μ_k
    # to the last bit, and which side of the tie each implementation's rounding lands
    # on decides Π; that is not a disagreement of the two. Such ties are left out.
    assume(abs(abs(y0) - (mu_k + extra)) > 1e-9 * max(1.0, abs(y0)))
    tau = np.linspace(0.0, 200.0, 41)
    fast = exact_pi_grid(
        tau,
        np.array([y0]),
        np.array([zeta]),
        np.array([mu_k]),
        np.array([mu_k + extra]),
        yp0,
        tau_end,
    )[0]
    ref = exact_pi(tau, y0, zeta, mu_k, mu_k + extra, yp0, tau_end=tau_end, backend="numpy")
    np.testing.assert_allclose(fast, ref, rtol=1e-11, atol=1e-11 * max(1.0, abs(ref[0])))


@pytest.mark.parametrize(
    "shapes",
    [
        # (tau, y0, zeta, mu_k, mu_s, yp0, tau_end)
        ((7,), (5, 1), (5, 1), (5, 1), (5, 1), (), ()),  # walkers against times
        ((7,), (), (), (), (), (), ()),  # one trajectory
        ((), (5,), (5,), (5,), (5,), (), ()),  # one time, many trajectories
        ((5, 7), (5, 1), (1,), (5, 1), (5, 1), (5, 1), (5, 1)),  # a time grid per row
        ((2, 1, 7), (3, 1), (2, 1, 1), (3, 1), (3, 1), (), (3, 7)),  # any broadcast
    ],
)
def test_public_exact_pi_is_the_compiled_kernel_for_any_broadcast(shapes):
    """``exact_pi`` evaluates the compiled kernel by default (one trajectory per row,
    or per element where the parameters vary along the last axis); it agrees with the
    numpy implementation for every broadcast of its arguments."""
    rng = np.random.default_rng(3)
    tau = rng.uniform(0.0, 200.0, shapes[0])
    y0 = rng.uniform(1.0, 8.0, shapes[1])
    zeta = rng.uniform(0.0, 0.05, shapes[2])
    mu_k = rng.uniform(0.0, 0.05, shapes[3])
    mu_s = mu_k * rng.uniform(1.0, 2.0, shapes[4])
    yp0 = rng.uniform(-1.0, 1.0, shapes[5])
    tau_end = rng.uniform(50.0, 300.0, shapes[6])
    args = (tau, y0, zeta, mu_k, mu_s, yp0, tau_end)
    fast = exact_pi(*args)
    ref = exact_pi(*args, backend="numpy")
    assert fast.shape == ref.shape == np.broadcast_shapes(*shapes)
    np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12 * np.max(ref))
    with pytest.raises(ValueError, match="backend must be"):
        exact_pi(*args, backend="jax")
