"""``bayestribo demo``: the quick start fits, reports and prints the intervals."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from _paths import REPO

from bayestribo.cli import demo, main

pytest.importorskip("nbclient")


@pytest.mark.skipif(not (REPO / "data").is_dir(), reason="the bundled campaign data/ is absent")
def test_quick_demo_prints_intervals_beside_the_paper_and_writes_reports(tmp_path, capsys):
    pytest.importorskip("nbconvert")
    out = tmp_path / "demo"
    assert main(["demo", "--quick", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "paper, glycerol (mean, σ)" in text
    assert "0.0236 (σ 0.0012)" in text and "0.0294 (σ 0.0036)" in text
    fit_line = next(line for line in text.splitlines() if "Bayesian fit" in line)
    intervals = re.findall(r"([\d.]+) \[([\d.]+), ([\d.]+)\]", fit_line)
    assert len(intervals) == 2  # ζ and μ_k
    for mean, lo, hi in intervals:
        assert float(lo) <= float(mean) <= float(hi)
    assert "population" in text and "between-run σ" in text
    for name in ("single-run-report.html", "campaign-report.html"):
        assert (out / name).is_file()
        assert str(out / name) in text  # says where they are
        assert "data:image/png;base64" in (out / name).read_text(encoding="utf-8")
    assert list((out / "figures" / "single-run").glob("*.png"))
    assert list((out / "figures" / "campaign").glob("*.png"))


def test_campaign_is_simulated_into_the_cache_when_data_is_absent(tmp_path, monkeypatch):
    calls = []

    def fake_write_campaign(folder):
        calls.append(Path(folder))
        Path(folder).mkdir(parents=True)
        (Path(folder) / "manifest.csv").write_text("run_id,file\n")
        return Path(folder) / "manifest.csv"

    monkeypatch.setenv("BAYESTRIBO_DATA", str(tmp_path / "no-data-here"))
    monkeypatch.setattr("bayestribo.synthetic.campaign.write_campaign", fake_write_campaign)
    folder, origin = demo.campaign_folder(cache=tmp_path / "cache")
    assert origin == "simulated now" and calls == [folder]
    assert folder.parent == tmp_path / "cache"
    again, origin = demo.campaign_folder(cache=tmp_path / "cache")
    assert again == folder and origin.startswith("simulated earlier") and len(calls) == 1


def test_bundled_data_is_used_when_present(monkeypatch):
    if not (REPO / "data" / "manifest.csv").is_file():
        pytest.skip("the bundled campaign data/ is absent")
    monkeypatch.delenv("BAYESTRIBO_DATA", raising=False)
    folder, origin = demo.campaign_folder()
    assert folder == REPO / "data" and origin == "bundled"


def test_quick_and_full_exclude_each_other(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--quick", "--full"])
    assert "not allowed with" in capsys.readouterr().err


def _single(converged=True):
    interval = {"mean": 0.0242507, "interval": [0.0242501, 0.0242513]}
    return {
        "name": "glycerol-N0.31-r1",
        "fit": {
            "parameters": {
                "zeta": interval,
                "mu_k": {"mean": 0.02854, "interval": [0.0285, 0.0286]},
            },
            "diagnostics": {"converged": converged},
        },
        "true": {"zeta": 0.0242508, "mu_k": 0.0285408},
    }


def _campaign(converged=True):
    summary = {"mean": 0.0238, "interval": [0.0230, 0.0247]}
    return {
        "runs": {"glycerol-N0.07-r1": {"diagnostics": {"converged": converged}}},
        "failed": {},
        "population": {
            "pooled": {
                "n_runs": 5,
                "parameters": {p: {"mean": summary, "sigma": summary} for p in ("zeta", "mu_k")},
            }
        },
    }


def test_summary_shows_enough_digits_for_a_narrow_interval_and_the_truth():
    text = "\n".join(demo.summary_lines(_single(), _campaign()))
    # an interval 1.2e-6 wide needs seven decimals to be seen at all
    assert "0.0242507 [0.0242501, 0.0242513]" in text
    assert "true value (simulated run)" in text and "0.0242508" in text
    assert "campaign, 5 runs across loads" in text
    assert "NOT CONVERGED" not in text and "left out" not in text


def test_summary_never_shows_an_unconverged_fit_as_if_it_had_converged():
    text = "\n".join(demo.summary_lines(_single(converged=False), _campaign(converged=False)))
    assert "SAMPLER NOT CONVERGED" in text
    assert "not converged ['glycerol-N0.07-r1']" in text
