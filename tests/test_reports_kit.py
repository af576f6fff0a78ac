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


def test_the_overlaps_are_those_of_a_full_draw():
    """The check lays the figure out without rasterising it: the texts' boxes are a
    full draw's (exactly; a constrained layout, whose solver moves on by hundredths of
    a pixel from one draw to the next, within 0.05 px), and so are the overlaps."""
    from bayestribo.reports.kit import _texts

    def figure(layout):
        fig, axes = plt.subplots(2, 1, figsize=(2.5, 2), layout=layout)
        for ax in axes:
            ax.plot([0.02360001, 0.02360009], [0, 1])
            ax.ticklabel_format(useOffset=False)
            ax.set_xticks([0.02360001 + i * 1e-8 for i in range(9)])
            ax.set_ylabel("μ$_{k}$ [-]")
        return fig

    for layout, tolerance in ((None, 0.0), ("tight", 0.0), ("constrained", 0.05)):
        fig, reference = figure(layout), figure(layout)
        found = overlapping_labels(fig)
        laid_out = [t.get_window_extent(fig.canvas.get_renderer()) for _, t in _texts(fig)]
        reference.canvas.draw()  # the first draw of the same figure, in full
        renderer = reference.canvas.get_renderer()
        drawn = [t.get_window_extent(renderer) for _, t in _texts(reference)]
        assert len(laid_out) == len(drawn) == 24
        for a, b in zip(laid_out, drawn, strict=True):
            assert max(abs(u - v) for u, v in zip(a.bounds, b.bounds, strict=True)) <= tolerance
        # the overlapping pairs of the drawn boxes, shrunk by a pixel as the check does
        pairs = [
            (i, j)
            for i, a in enumerate(drawn)
            for j, b in enumerate(drawn[i + 1 :], i + 1)
            if a.x1 - 1 > b.x0 + 1
            and b.x1 - 1 > a.x0 + 1
            and a.y1 - 1 > b.y0 + 1
            and b.y1 - 1 > a.y0 + 1
        ]
        assert found and len(found) == len(pairs)
        plt.close(fig)
        plt.close(reference)


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


def test_a_panel_with_nothing_to_show_is_found_and_said(tmp_path, monkeypatch):
    """An axes without data, and a friction panel on a 1e-14 axis where every value is
    zero: both are found, and ``save`` says so in a note the tests and the browser's
    probe look for."""
    from bayestribo.reports import kit

    fig, (a, b, c) = plt.subplots(3, 1, figsize=(5, 6), layout="constrained")
    a.plot([0.1, 0.2], [0.0236, 0.0237])
    a.set_title("ζ")
    b.set_title("nothing")
    c.plot([0.1, 0.2], [3e-15, -2e-14])
    c.set_ylabel("x_c [m]")
    assert kit.empty_panels(fig) == ["'nothing': no data", "'x_c [m]': every y value is zero"]
    said = []
    monkeypatch.setattr(kit, "note", said.append)
    kit.setup(None)(fig, "windows")
    assert said and said[0].startswith(f"figure windows: {kit.FIGURE_PROBLEMS[1]}: ")
    plt.close(fig)


def test_panels_that_are_not_drawn_as_panels_are_not_empty():
    """A log axis of small values, a blank corner-plot cell (no frame), an axes holding
    only a legend (axis off) and a hidden one are not empty panels."""
    from bayestribo.reports.kit import empty_panels

    fig, axes = plt.subplots(2, 2, figsize=(6, 5), layout="constrained")
    axes[0, 0].semilogy([0.1, 0.2], [1e-15, 3e-14])
    axes[0, 1].set_frame_on(False)
    axes[0, 1].set_xticks([])
    axes[1, 0].axis("off")
    axes[1, 0].legend(*axes[0, 0].get_legend_handles_labels())
    axes[1, 1].set_visible(False)
    assert empty_panels(fig) == []
    plt.close(fig)


def test_text_below_8_pt_is_found_and_said(monkeypatch):
    """Run labels at 6.5 pt and a legend in x-small (6.94 pt at the reports' 10 pt) are
    below the 8 pt a journal prints; ``save`` says so in a note the tests and the
    browser's probe look for. The same figure at 8 pt passes."""
    from bayestribo.reports import kit

    kit.setup(None)  # the reports' look: 10 pt text
    fig, ax = plt.subplots(figsize=(5, 3), layout="constrained")
    ax.plot([0, 1], [0, 1], label="a run")
    ax.set_yticks([0, 1], ["glycerol-N0.07-r1", "air-r1"], fontsize=6.5)
    ax.legend(fontsize="x-small")
    ax.set_title("hidden", fontsize=5).set_visible(False)  # not drawn: not counted
    found = kit.small_texts(fig)
    assert found == ["'glycerol-N0.07-r1' (6.5 pt)", "'air-r1' (6.5 pt)", "'a run' (6.94 pt)"]
    said = []
    monkeypatch.setattr(kit, "note", said.append)
    kit.setup(None)(fig, "forest")
    assert said == [f"figure forest: {kit.FIGURE_PROBLEMS[2]}: " + "; ".join(found)]
    ax.tick_params(labelsize=8)
    ax.legend(fontsize=8)
    assert kit.small_texts(fig) == []
    plt.close(fig)


def test_the_kit_examples_hold():
    """The kit's examples: a sentence opening with ζ keeps it lower case ("ζ and μ_k are
    constant.", not "Ζ and ..."), intervals in the digits they support, numbers kept
    on one line, small texts and empty panels found."""
    import doctest

    from bayestribo.reports import kit

    assert doctest.testmod(kit).failed == 0


def test_symbols_in_a_saved_figure_are_set_with_their_subscripts(tmp_path):
    save = setup(str(tmp_path / "figs"), "svg")
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0.02, 0.03], label="μ_k of run disc_14.9_1")
    ax.set_ylabel("μ_k [-]")
    ax.set_title("x_c against load_N")
    ax.legend()
    save(fig, "friction")
    assert ax.get_ylabel() == "μ$_{k}$ [-]"
    # a code or file name is not a symbol: left as it is (the browser probe flags those)
    assert ax.get_title() == "x$_{c}$ against load_N"
    assert ax.get_legend().get_texts()[0].get_text() == "μ$_{k}$ of run disc_14.9_1"
    plt.close(fig)
