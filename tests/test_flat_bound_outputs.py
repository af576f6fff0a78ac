"""A quantity the data do not constrain says so in every output, not only in the text.

A record that ends while the oscillator still moves holds no stop, so μ_s/μ_k has its
prior's posterior (uniform from 1). The text table prints a one-sided bound; the JSON of
``fit --json``, the saved fit's summary and a campaign's digest give the same bound with
the interval from the prior's lower end (``kind`` ``"bound"``), which covers the truth
μ_s/μ_k = 1 of the record (static friction equal to kinetic), where a central interval
of the prior excludes it.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest
from _free_decay import METADATA, X_C, free_decay

from bayestribo.cli import main
from bayestribo.inference import FitResult

#: The record is cut here, half way through its decay: the motion never stops in it.
CUT_S = 0.5


@pytest.fixture(scope="module")
def never_stops(tmp_path_factory) -> tuple[int, dict, Path, Path]:
    from bayestribo.io import write_run
    from bayestribo.io.run import Run

    decay = free_decay(seed=3)
    keep = decay.time < CUT_S
    run = Run(
        time=decay.time[keep],
        displacement=decay.displacement[keep],
        velocity=decay.velocity[keep],
        metadata=dict(METADATA),
        source="moving",
    )
    folder = tmp_path_factory.mktemp("moving")
    path = write_run(run, folder / "moving.csv")
    out = folder / "out"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(["fit", str(path), "--seed", "1", "--json", "--out", str(out)])
    return status, json.loads(buf.getvalue()), out, path


def test_the_json_of_a_prior_only_ratio_is_a_bound_that_covers_the_truth(never_stops) -> None:
    status, record, _, _ = never_stops
    assert status == 0
    ratio = record["parameters"]["mu_s_ratio"]
    assert ratio["kind"] == "bound"
    low, high = ratio["interval"]
    assert low == 1.0 <= high  # from the prior's lower end, the truth 1 inside
    assert 2.0 < high <= 10.0  # the bound: not a value the record measured
    static = record["parameters"]["static_friction_displacement"]
    assert static["kind"] == "bound"
    assert static["interval"][0] <= X_C <= static["interval"][1]  # x_s = x_c, μ_s = μ_k
    # what the record does measure keeps its central interval
    friction = record["parameters"]["friction_displacement"]
    assert friction["kind"] == "posterior" and friction["interval"][0] > 0.9 * X_C


def test_the_text_the_saved_fit_and_a_digest_say_the_same_bound(never_stops) -> None:
    from bayestribo.campaign.digest import digest_fit

    _, record, out, path = never_stops
    result = FitResult.load(out / f"{path.stem}.nc")
    high = record["parameters"]["mu_s_ratio"]["interval"][1]
    saved = result.summary()["mu_s_ratio"]
    assert saved.kind == "bound" and saved.interval == pytest.approx((1.0, high), rel=1e-12)
    assert result.interval("mu_s_ratio") == saved.interval  # the API's interval too
    assert result.interval("zeta") == result.summary()["zeta"].interval
    row = next(line for line in result.to_text().splitlines() if "μ_s/μ_k" in line)
    assert f"< {high:.2g} (not constrained by the data" in row, row
    digest = digest_fit(result, parameters=["mu_s_ratio", "friction_displacement"])
    kept = digest.summaries["mu_s_ratio"]
    assert kept["kind"] == "bound"
    assert kept["interval"] == pytest.approx([1.0, high], rel=1e-12)
    assert digest.summaries["friction_displacement"]["kind"] == "posterior"
