"""The verdict of ``law="auto"`` fitted again in its own frame from the comparison's
optimum and draws (inference/law_frame.py, ``known`` and ``known_run``)."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest
from _comparison_stubs import stub_fits, stub_prepared

from bayestribo.inference import comparison, law_frame, prepare
from bayestribo.inference.law_frame import posterior_like, sample_in_law_frame
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.screening import LawOptimum

LAW = "viscous+quadratic"


@pytest.fixture(scope="module")
def known(bundled_run):
    """The bundled run prepared, and a law without a closed form taken to its optimum
    there as the comparison takes it."""
    prepared = prepare(bundled_run, seed=1)
    return prepared, comparison._optimise(LAW, prepared, "exact", False, {})


def _posterior_on(at):
    return lambda prep: posterior_like(at.posterior, prep, "exact", False)


def _no_call(name):
    def refuse(*args, **kwargs):
        raise AssertionError(f"{name} ran")

    return refuse


def test_in_the_records_own_frame_the_comparisons_draws_are_kept(known, monkeypatch):
    prepared, at = known
    drawn = SimpleNamespace(posterior=at.second)
    monkeypatch.setattr(law_frame, "_in_law_frame", lambda *args: None)
    monkeypatch.setattr(law_frame, "maximum_a_posteriori", _no_call("the search"))
    monkeypatch.setattr(law_frame, "sample_from", _no_call("the sampler"))
    out_prepared, out = sample_in_law_frame(
        prepared, _posterior_on(at), SamplerSettings(), 1, known=at, known_run=drawn
    )
    assert out is drawn and out_prepared is prepared


def test_the_comparisons_optimum_starts_the_law_in_another_frame(known, monkeypatch):
    prepared, at = known
    seen = {}
    framed = dataclasses.replace(prepared, name="framed")

    def in_frame(prep, posterior, theta):
        seen["theta"] = np.array(theta)
        return framed

    def sampled(start, **kwargs):
        seen["start"] = start
        return "sampled"

    monkeypatch.setattr(law_frame, "_in_law_frame", in_frame)
    monkeypatch.setattr(law_frame, "maximum_a_posteriori", _no_call("the search"))
    monkeypatch.setattr(law_frame, "sample_from", sampled)
    out_prepared, out = sample_in_law_frame(
        prepared,
        _posterior_on(at),
        SamplerSettings(),
        1,
        known=at,
        known_run=SimpleNamespace(posterior=at.second),
    )
    # sampled afresh in the law's frame, from the comparison's optimum
    assert out == "sampled" and out_prepared is framed
    np.testing.assert_array_equal(seen["theta"], at.optimum[0])


def test_another_posterior_is_searched_and_sampled_afresh(known, monkeypatch):
    prepared, at = known
    # the same law on other data: the comparison's optimum is not this posterior's
    other = dataclasses.replace(
        prepared,
        data=dataclasses.replace(prepared.data, increments=prepared.data.increments * 1.01),
    )
    searched, sampled = [], []
    real = law_frame.maximum_a_posteriori

    def search(posterior, decay):
        searched.append(True)
        return real(posterior, decay)

    monkeypatch.setattr(law_frame, "_in_law_frame", lambda *args: None)
    monkeypatch.setattr(law_frame, "maximum_a_posteriori", search)
    monkeypatch.setattr(
        law_frame, "sample_from", lambda start, **kw: sampled.append(start) or "new"
    )
    _, out = sample_in_law_frame(
        other,
        _posterior_on(at),
        SamplerSettings(),
        1,
        known=at,
        known_run=SimpleNamespace(posterior=at.second),
    )
    assert searched and out == "new" and len(sampled) == 1


@pytest.mark.filterwarnings("ignore")
def test_the_comparison_hands_over_every_law_it_took_to_its_optimum(monkeypatch):
    # quadratic far behind: screened at its optimum, but taken there all the same
    shifts = {"viscous": 0.0, "coulomb": 1.0, "quadratic": 500.0}
    stub_fits(monkeypatch, shifts)
    at_optima: dict = {}
    c, runs = comparison.compare_prepared(
        stub_prepared(), list(shifts), seed=1, rivals=False, at_optima=at_optima
    )
    assert set(at_optima) == set(shifts)
    assert all(isinstance(at, LawOptimum) and at.law == law for law, at in at_optima.items())
    assert "quadratic" in c.screened and "quadratic" not in runs
