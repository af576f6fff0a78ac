"""A report as a reader sees it: rendered by headless Chromium, offline.

The single-run report of a bundled run is made with ``bayestribo report`` and opened in
Chromium with the network switched off; the live page must show every image (figures
and equations) with a non-zero natural size, no raw TeX, no code and no stderr box.
Skipped, with the reason, where Chromium is not installed (``apt-get install chromium``).
"""

from __future__ import annotations

import pytest
from _paths import REPO

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli import main
from bayestribo.reports.browser import (
    CHROMIUM_NAMES,
    find_chromium,
    inspect_report,
    screenshot,
)

RUN = REPO / "data" / "runs" / "glycerol-N0.31-r1.csv"

pytestmark = pytest.mark.skipif(
    find_chromium() is None,
    reason=f"no headless browser: none of {', '.join(CHROMIUM_NAMES)} on PATH "
    "(apt-get install chromium)",
)


@pytest.fixture(scope="module")
def single_run_report(tmp_path_factory):
    if not RUN.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    out = tmp_path_factory.mktemp("report") / "single.html"
    argv = ["report", str(RUN), "--out", str(out), "--param", "grid_points=32"]
    assert main(argv) == 0
    return out


def test_the_report_reads_offline_in_a_browser(single_run_report):
    page = inspect_report(single_run_report)
    assert page.images > 0 and page.all_images_loaded, page.broken
    assert page.figures >= 8  # signals ... peak residuals, none left out on this run
    assert page.equations >= 5  # the equation of motion and the symbols in the text
    assert not page.raw_tex
    assert page.code_cells == 0 and page.stderr_boxes == 0
    assert page.toc_links >= 6


def test_the_figure_files_are_vector_pdf_next_to_the_report(single_run_report):
    figures = single_run_report.with_name("single-figures")
    files = sorted(figures.glob("*.pdf"))
    assert len(files) >= 8 and all(f.read_bytes().startswith(b"%PDF") for f in files)


def test_a_missing_image_is_seen(tmp_path):
    page = tmp_path / "page.html"
    page.write_text(
        '<html><body><img src="missing.png"><img src="data:image/svg+xml;base64,'
        'PHN2ZyB4bWxucz0iaHR0cDovL3d3dy53My5vcmcvMjAwMC9zdmciIHdpZHRoPSIxMCIgaGVpZ2h0PSIxMCIvPg==">'
        "<p>$$x$$</p></body></html>"
    )
    found = inspect_report(page)
    assert found.images == 2 and found.loaded == 1 and found.broken == ["missing.png"]
    assert found.raw_tex


def test_a_screenshot_is_written(single_run_report, tmp_path):
    png = screenshot(single_run_report, tmp_path / "shot.png", width=800, height=600)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_a_bad_parameter_fails_before_the_kernel_starts(tmp_path, capfd):
    if not RUN.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    assert main(["report", str(RUN), "--out", str(tmp_path / "r.html"), "--param", "seed=x"]) == 2
    err = capfd.readouterr().err
    assert "parameter 'seed'" in err and "Kernel is running over TCP" not in err
