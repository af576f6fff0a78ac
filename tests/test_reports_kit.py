"""What every report notebook does the same way: figure files, notes, legibility check."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pytest

from bayestribo.reports import ReportError
from bayestribo.reports.kit import FIGURE_FORMATS, overlapping_labels, setup


def test_tick_labels_running_together_are_found():
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0.02360001, 0.02360009], [0, 1])
    ax.ticklabel_format(useOffset=False)
    ax.set_xticks([0.02360001 + i * 1e-8 for i in range(9)])
    found = overlapping_labels(fig)
    assert found and "x axis" in found[0] and "0.02360001" in found[0]
    plt.close(fig)


def test_a_plain_figure_has_no_overlapping_labels():
    fig, axes = plt.subplots(2, 2, figsize=(7, 5), layout="constrained")
    for ax in axes.flat:
        ax.plot([0, 1], [0.0236, 0.0237])
    assert overlapping_labels(fig) == []
    plt.close(fig)


@pytest.mark.parametrize("fmt", FIGURE_FORMATS)
def test_figures_are_written_in_the_format_asked_for(tmp_path, fmt):
    save = setup(str(tmp_path / "figs"), fmt)
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    assert save(fig, "line") is None  # a cell ending with save(...) shows only the figure
    written = tmp_path / "figs" / f"line.{fmt}"
    head = written.read_bytes()[:200]
    assert {"pdf": b"%PDF", "png": b"\x89PNG", "svg": b"<?xml"}[fmt] in head
    plt.close(fig)


def test_an_unknown_format_is_refused():
    with pytest.raises(ReportError, match="figure_format: expected one of"):
        setup(None, "jpeg")
