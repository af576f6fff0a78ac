"""The optimiser's start for a law without a closed form (``inference/start.py``).

Its multi-start runs on a coarse model (8 Runge-Kutta steps per half cycle) and the
distinct optima within the coarse model's error of the best are polished with the
exact integrator; an optimum on a bound of the support (a drag the data put at zero)
is followed along the bound. The bundled run is viscous damping and Coulomb friction:
under ``viscous+quadratic`` the drag c₂ piles at zero and the law misfits by χ² ~ 8e8,
where the least squares used to stall 1.3e7 below the maximum, and the surrogate,
built about that point, failed its check and the exact posterior was sampled (a
minute) from walkers that never reached the maximum.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.pipeline import build_posterior, prepare
from bayestribo.inference.start import (
    _candidates,
    _coarse,
    _first_guesses,
    _optimise,
    _ratio_grid,
    maximum_a_posteriori,
)


@pytest.fixture(scope="module")
def prepared(bundled_runs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare(bundled_runs / "glycerol-N0.31-r1.csv")


def _posterior(prepared, law, **kwargs):
    return build_posterior(prepared.data, law=law, friction=prepared.contact, **kwargs)


def test_a_drag_piled_at_zero_is_followed_along_its_bound(prepared):
    # a law that holds on the bundled run, whose drag the data put at zero (without
    # its Coulomb term the law misfits by χ² ~ 8e8, where an optimum is known to no
    # better than a relative 1e-7 of the log density: tens of units)
    posterior = _posterior(prepared, "viscous+coulomb+quadratic")
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    lp = float(posterior(theta[None])[0])
    c2 = posterior.names.index("c2")
    assert theta[c2] == 0.0
    # the optimum of the law with c2 held at zero: the free one reaches it
    held = _posterior(prepared, "viscous+coulomb+quadratic", fixed={"c2": 0.0})
    theta_held, _, _ = maximum_a_posteriori(held, prepared.decay)
    lp_held = float(held(theta_held[None])[0])
    assert lp >= lp_held - 1.0, (lp, lp_held)
    # the Laplace Gaussian (c2 pinned by the slope) holds the typical set: most of its
    # draws inside the support are within d + 10 of the optimum, where the walkers
    # start (with the curvature's sd of c2, 3e-7 against its posterior's 1e-11, none)
    rng = np.random.default_rng(1)
    draws = rng.multivariate_normal(theta, cov, size=400, method="eigh")
    draws = draws[draws[:, c2] >= 0.0]
    good = posterior(draws) >= lp - (len(theta) + 10.0)
    assert draws.shape[0] > 100
    assert np.mean(good) > 0.5


def test_the_coarse_multistart_finds_the_exact_multistarts_optimum(prepared):
    posterior = _posterior(prepared, "coulomb+power")
    assert _coarse(posterior) is not None
    theta, _, _ = maximum_a_posteriori(posterior, prepared.decay)
    # every start on the exact model, as before the coarse stage
    guesses = _first_guesses(prepared.decay, posterior)
    middle = float(np.median(_ratio_grid(posterior)))
    optima = [_optimise(posterior, g, r) for g in guesses for r in (None, middle)]
    exact, exact_cov, exact_lp = optima[int(np.argmax([lp for _, _, lp in optima]))]
    assert float(posterior(theta[None])[0]) == pytest.approx(exact_lp, abs=1e-2)
    sd = np.sqrt(np.diag(exact_cov))
    free = sd > 0
    assert np.all(np.abs(theta[free] - exact[free]) <= 0.1 * sd[free])
    ratio = posterior.names.index("mu_s_ratio")
    assert theta[ratio] == exact[ratio]


@pytest.mark.parametrize(
    ("law", "middle_starts"),
    [("coulomb+power", False), ("coulomb+hysteretic", True)],
)
def test_the_ratio_middle_starts_run_only_without_a_coarse_model(
    prepared, monkeypatch, law, middle_starts
):
    # a law with a drag starts its coarse multi-start from the first guesses with the
    # ratio at the middle of its scan's highest step only (the optimum it reaches is
    # every start's on the exact model: the test above); a law without a coarse model
    # is also started with the ratio at the middle of its range
    from bayestribo.inference import start

    posterior = _posterior(prepared, law)
    middle = float(np.median(_ratio_grid(posterior)))
    ratios = []

    def recording(post, guess, ratio=None, found=None):
        if found is not None or _coarse(posterior) is None:
            ratios.append(ratio)  # the starts (the polish passes no ``found``)
        return _optimise(post, guess, ratio, found)

    monkeypatch.setattr(start, "_optimise", recording)
    start.maximum_a_posteriori(posterior, prepared.decay)
    n_guesses = len(_first_guesses(prepared.decay, posterior))
    assert ratios.count(None) == n_guesses
    assert ratios.count(middle) == (n_guesses if middle_starts else 0)


def test_a_law_without_drag_is_optimised_on_its_own_model(prepared):
    # the arcs of friction alone need no Runge-Kutta steps: no coarse model
    assert _coarse(_posterior(prepared, "coulomb+hysteretic")) is None
    assert _coarse(_posterior(prepared, "viscous+coulomb")) is None


def test_distinct_optima_within_the_coarse_error_are_each_polished():
    names = ["zeta", "mu_s_ratio", "y0"]
    cov = np.diag([1e-6, 0.0, 1e-4])
    a = np.array([0.02, 1.9, 7.4])
    b = np.array([0.03, 1.9, 7.4])  # another optimum, 4 below a
    a_again = a + np.array([5e-4, 0.0, 5e-3])  # within a Laplace sd of a
    a_other_step = np.array([0.02, 4.4, 7.4])  # a's values, another stick
    far = np.array([0.05, 1.9, 7.0])  # far below: cannot come out on top
    rough = [
        (a_again, cov, 99.9),
        (far, cov, -1e6),
        (a, cov, 100.0),
        (b, cov, 96.0),
        (a_other_step, cov, 95.0),
    ]
    # the exact log density at the coarse best is 0.5 off: window 2 × 0.5 + 10

    class Exact:
        def __init__(self) -> None:
            self.names = names

        def __call__(self, rows):
            return np.full(len(rows), 100.5)

    kept = _candidates(Exact(), rough)
    assert [tuple(k) for k in kept] == [tuple(a), tuple(b), tuple(a_other_step)]


def test_the_integrator_steps_are_checked(prepared):
    with pytest.raises(ValueError, match="steps"):
        PiLikelihood(prepared.data, law="viscous+quadratic", steps=-1)
