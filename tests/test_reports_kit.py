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
    assert found and "x tick" in found[0] and "0.02360001" in found[0]
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


def test_a_title_over_tick_labels_is_found():
    """A title placed where tick labels are (a corner plot's titles sit in the gap above
    each diagonal panel, over the tick labels of the panel above): the check finds it."""
    fig, ax = plt.subplots(figsize=(3, 2.5), layout="constrained")
    ax.plot([0, 1], [0, 1])
    ax.set_title("y₀ = 7.4431 ± 3.1e-05", y=-0.1, pad=0)
    found = overlapping_labels(fig)
    assert any("y₀ = 7.4431" in f and "x tick" in f for f in found), found
    plt.close(fig)


def test_a_y_label_over_tick_labels_is_found():
    fig, ax = plt.subplots(figsize=(3, 2.5), layout="constrained")
    ax.plot([0, 1], [0.02361, 0.02369])
    ax.set_ylabel("ζ from the windows [-]")
    ax.yaxis.set_label_coords(-0.05, 0.5)  # over the tick labels
    found = overlapping_labels(fig)
    assert any("ζ from the windows" in f and "y tick" in f for f in found), found
    plt.close(fig)
