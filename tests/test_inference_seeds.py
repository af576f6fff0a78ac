"""An answer does not depend on the random seed.

The Monte Carlo that propagates the noise through a derived channel (a position-only
record's velocity) is seeded from the recording itself: its ~8 % error on each
increment's variance once moved HarmOsc3's friction displacement by up to 5 posterior
sd from one fit seed to the next (each fit converged), because where a law misfits a
record the weights of the residuals decide where the optimum lies.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo import fit, read_run
from bayestribo.inference import prepare


@pytest.fixture(scope="module")
def harmosc3(appstat_file):
    return read_run(
        appstat_file("HarmOsc3.txt"),
        columns=["time_s", "displacement_m"],
        metadata={"length_unit": "arbitrary"},
    )


def test_the_observation_of_a_derived_channel_is_a_function_of_the_data(harmosc3):
    a, b = prepare(harmosc3), prepare(harmosc3)
    assert a.decay.derived_channel == "velocity"
    np.testing.assert_array_equal(a.data.variance, b.data.variance)
    # an explicit seed still draws the Monte Carlo anew (to study its spread)
    c = prepare(harmosc3, seed=5)
    assert not np.array_equal(a.data.variance, c.data.variance)


@pytest.mark.validation  # three fits of a real recording: run by hand (-m validation)
def test_fits_with_different_seeds_agree_within_a_fifth_of_a_posterior_sd(harmosc3):
    """Three seeds: the friction displacement's means within 0.2 posterior sd (the
    sampler's own Monte Carlo error is about sd/√ESS, ESS > 1000).

    A statistical check left out of the default run; by default the cause it guards
    against is checked: the derived channel's variance is a function of the data alone,
    whatever the fit's seed (the test above)."""
    means, sds = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # this record misfits the law: said elsewhere
        for seed in (1, 2, 3):
            s = fit(harmosc3, seed=seed).summary()["friction_displacement"]
            means.append(s.mean)
            sds.append(s.sd)
    assert (max(means) - min(means)) < 0.2 * float(np.mean(sds))
