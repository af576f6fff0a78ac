"""Every kind of report, made from hostile names, as a browser shows it, prints it and a
phone lays it out.

Each report kind is made once from runs whose names would run a script if a page showed
them as markup (the single-run and viscosity reports are the session's shared renderings
of ``conftest.py``, the campaign and real-data ones this module's own, on few runs): a
lubricant ``<script>...</script>``, a file ``air <svg onload=...>-r1.csv`` (the run's
label: a sidecar's ``run_id`` is checked and cannot hold one), sidecar fields ``<img
src=x onerror=...>`` and a README with the same (the recordings of another rig are written
here from a bundled run). Every payload sets ``document.title`` to ``PWNED``. Then, in
headless Chromium (one browser for all the checks):

* no script ran, with the page's Content-Security-Policy and without it (the escaping
  alone holds), and the policy had nothing to block; the names show as text;
* printed on A4 and on Letter, every table's columns are on the page, no box cuts its
  content, every heading is kept with what follows it and no figure is split;
* at 375 px the contents box is above the text, and the page does not scroll sideways;
* every figure's alt text says what it shows and every equation's is words, not TeX;
  the page's title names the report and what it is about.

Skipped where Chromium is not installed.
"""

from __future__ import annotations

import html
import re

import numpy as np
import pytest
from _hostile_names import HOSTILE_FIELD, HOSTILE_FILE_WORD, HOSTILE_SCRIPT, PAYLOAD, hostile_copy
from _paths import RUNS
from _renderings import GROUP

pytest.importorskip("nbclient")
pytest.importorskip("nbconvert")

from bayestribo.cli import main
from bayestribo.reports.browser import find_chromium
from bayestribo.reports.safety import inert_problems

pytestmark = [
    pytest.mark.skipif(find_chromium() is None, reason="no headless Chromium on PATH"),
    pytest.mark.xdist_group(GROUP),  # the shared renderings made on one worker
]

LUBRICANT, FILE_WORD, FIELD = HOSTILE_SCRIPT, HOSTILE_FILE_WORD, HOSTILE_FIELD


@pytest.fixture(scope="module")
def reports(tmp_path_factory, single_run_report, viscosity_report, acquisition_report):
    """Each report kind's page, made from hostile names: kind -> path."""
    if not RUNS.is_dir():
        pytest.skip("the bundled campaign data/ is absent")
    root = tmp_path_factory.mktemp("hostile")
    # a single run, the series against viscosity: their file names (their runs' labels),
    # series and sidecar fields (conftest.py); the simulated acquisition takes no name
    made = {
        "single_run": single_run_report.html,
        "viscosity": viscosity_report.html,
        "acquisition": acquisition_report.html,
    }
    # a campaign: runs of a hostile lubricant (its series) at two loads (a trend), a run in
    # air with a hostile name; one run each (the names and the layout are checked)
    campaign = root / "campaign"
    campaign.mkdir()
    for load in ("0.07", "0.59"):
        hostile_copy(
            RUNS / f"glycerol-N{load}-r1.csv",
            campaign,
            f"lub-N{load}-r1",
            lubricant=LUBRICANT,
            series=LUBRICANT,
            run_id=f"lub-N{load}-r1",
            notes=FIELD,
            user={"operator": FIELD},
        )
    hostile_copy(RUNS / "air-r1.csv", campaign, f"air {FILE_WORD}-r1", run_id=None)
    out = root / "campaign.html"
    argv = ["report", str(campaign), "--notebook", "loads", "--out", str(out)]
    argv += ["--param", f"series={LUBRICANT!r}", "--param", "population_steps=600"]
    argv += ["--param", "fit_kwargs={'grid_points': 32}"]
    main(argv)  # exit 1 is allowed: short population samplers may not converge
    made["loads"] = out
    # recordings of another rig: a hostile file name and README
    rig = root / "rig"
    rig.mkdir()
    (rig / "README.md").write_text(f"# A rig {LUBRICANT}\n\nA spring {FIELD} and a mass.\n")
    name = f"osc {FILE_WORD}.txt"  # time and position, as the AppStat files hold them
    recorded = np.loadtxt(RUNS / "glycerol-N0.31-r1.csv", delimiter=",", skiprows=1)
    np.savetxt(rig / name, recorded[::4, :2], delimiter="\t", fmt="%.7g")
    out = root / "real.html"
    argv = ["report", str(rig), "--notebook", "real_data", "--out", str(out)]
    argv += ["--param", f"files=[{name!r}]", "--param", "fit_files=[]"]
    argv += ["--param", "check_files=[]"]
    main(argv)
    made["real_data"] = out
    return made


@pytest.fixture(scope="module")
def browser():
    from bayestribo.reports.devtools import Chromium

    with Chromium() as b:
        yield b


@pytest.fixture(scope="module")
def seen(reports, browser, tmp_path_factory):
    """What Chromium found in each report: kind -> dict of findings."""
    from bayestribo.reports.layout import print_layout, screen_layout, script_check

    found = {}
    for kind, page in reports.items():
        source = page.read_text(encoding="utf-8")
        bare = page.with_name(f"{page.stem}-no-policy.html")
        bare.write_text(
            re.sub(r"<meta[^>]*Content-Security-Policy[^>]*>", "", source), encoding="utf-8"
        )
        found[kind] = {
            "source": source,
            "scripts": script_check(page, browser=browser),
            "scripts_without_policy": script_check(bare, browser=browser),
            "print": {
                paper: print_layout(page, paper, browser=browser) for paper in ("A4", "Letter")
            },
            "phone": screen_layout(page, 375, browser=browser),
        }
    return found


KINDS = ("single_run", "loads", "real_data", "viscosity", "acquisition")
#: The kinds made from hostile names (the simulated acquisition takes none).
NAMED = KINDS[:-1]


def _kind(seen, kind):
    if kind not in seen:
        pytest.skip(f"no {kind} report (its data are absent)")
    return seen[kind]


@pytest.mark.parametrize("kind", KINDS)
def test_hostile_names_show_as_text_and_run_nothing(seen, kind):
    page = _kind(seen, kind)
    assert inert_problems(page["source"]) == []
    assert "<script" not in page["source"].lower()
    for check in (page["scripts"], page["scripts_without_policy"]):
        assert check.title != "PWNED" and check.marker is None
    assert page["scripts"].violations == []  # nothing the policy had to stop
    if kind in NAMED:  # the names are shown, as text
        assert "&lt;svg onload=document.title=" in page["source"]
        assert "&lt;script&gt;document.title=" in page["source"]


@pytest.mark.parametrize("kind", KINDS)
def test_every_table_fits_a4_and_letter_and_headings_keep_with_their_text(seen, kind):
    for paper, layout in _kind(seen, kind)["print"].items():
        assert layout.tables > 0, paper
        assert layout.cut_tables == [], (paper, layout.cut_tables)
        assert layout.page_width <= layout.width, paper
        assert layout.clipped == [], (paper, layout.clipped)
        assert layout.loose_headings == [] and layout.split_figures == 0, paper
        assert layout.pages >= 1


@pytest.mark.parametrize("kind", KINDS)
def test_a_phone_shows_the_contents_above_the_text(seen, kind):
    phone = _kind(seen, kind)["phone"]
    assert phone.toc and not phone.toc_beside_text
    assert phone.page_width <= phone.width  # no sideways scrolling of the page
    assert phone.pre_breaking_numbers == 0


@pytest.mark.parametrize("kind", KINDS)
def test_figures_and_equations_have_words_and_the_page_a_title(seen, kind):
    source = _kind(seen, kind)["source"]
    images = re.findall(r"<img\b[^>]*>", source)
    figures = [i for i in images if 'src="data:image/png' in i]
    assert figures
    for tag in images:
        alt = re.search(r'\balt="([^"]*)"', tag)
        assert alt is not None and alt.group(1).strip(), tag[:120]
        text = html.unescape(alt.group(1))
        assert "No description" not in text and "\\" not in text, text
    for tag in figures:  # each figure described from its own texts, not only its section
        alt = html.unescape(re.search(r'\balt="([^"]*)"', tag).group(1))
        assert alt.startswith("Figure") and ("x: " in alt or "y: " in alt or "Panel" in alt), alt
    title = html.unescape(re.search(r"<title>(.*?)</title>", source, re.DOTALL).group(1))
    h1 = re.search(r"<h1[^>]*>(.*?)</h1>", source, re.DOTALL).group(1)
    h1 = re.sub(r"<[^>]+>", "", re.sub(r"<sub>(.*?)</sub>", r"_\1", h1))  # μ_k in a title
    assert html.unescape(h1).replace("¶", "").strip() in title
    assert " – " in title  # what it is about, then the report


def test_the_print_stylesheets_margins_are_the_measured_ones():
    """The print check measures the text's width from PAGE_MARGIN_MM: the template's
    ``@page`` rule must say the same."""
    from importlib import resources

    from bayestribo.reports.layout import PAGE_MARGIN_MM

    template = resources.files("bayestribo.reports") / "template" / "bayestribo" / "index.html.j2"
    rule = re.search(r"@page\s*\{\s*margin:\s*([\d.]+)mm\s+([\d.]+)mm", template.read_text())
    assert rule is not None and tuple(map(float, rule.groups())) == PAGE_MARGIN_MM


def test_the_checks_see_a_script_a_cut_table_and_a_squeezed_text(browser, tmp_path):
    """The checks above can fail: a handler that runs (and, under the report's policy, is
    stopped and reported), a table wider than the paper, a contents box beside the text
    on a phone, a heading free to end a page."""
    from bayestribo.reports.layout import print_layout, screen_layout, script_check
    from bayestribo.reports.safety import csp_meta

    wide = "".join(f"<td>{'x' * 30}{i}</td>" for i in range(12))
    body = (
        f'<main><h1>A report</h1><nav class="bt-toc" style="float:right;width:40%">'
        f"<ul><li>one</li></ul></nav><p>{'text ' * 80}</p><h2>Table</h2>"
        f'<table><tr>{wide}</tr></table><img src=x onerror="{PAYLOAD}"></main>'
    )
    bare = tmp_path / "bare.html"
    bare.write_text(f"<html><head><title>t</title></head><body>{body}</body></html>")
    guarded = tmp_path / "guarded.html"
    guarded.write_text(f"<html><head>{csp_meta()}<title>t</title></head><body>{body}</body></html>")
    assert script_check(bare, browser=browser).title == "PWNED"
    stopped = script_check(guarded, browser=browser)
    assert stopped.title == "t" and any("script-src" in v for v in stopped.violations)
    printed = print_layout(bare, "A4", browser=browser)
    assert len(printed.cut_tables) == 1 and printed.loose_headings == ["A report", "Table"]
    assert screen_layout(bare, 375, browser=browser).toc_beside_text


def test_printed_text_output_never_breaks_a_number(browser, tmp_path):
    """A result printed as text (``<pre>``): JupyterLab's stylesheet breaks it anywhere
    (``word-break: break-all``, "1.5158e- / 07"); the report's rules come after it."""
    import nbformat

    from bayestribo.reports.html import to_html
    from bayestribo.reports.layout import screen_layout

    cell = nbformat.v4.new_code_cell("")
    number = "0.000561643215507 " * 6
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=number)]
    page = tmp_path / "pre.html"
    page.write_text(to_html(nbformat.v4.new_notebook(cells=[cell])), encoding="utf-8")
    found = screen_layout(page, 375, browser=browser)
    assert found.pre_breaking_numbers == 0
    assert found.page_width <= found.width  # the text scrolls in its box, not the page
    # the check can fail: the same page with JupyterLab's rule last
    source = page.read_text(encoding="utf-8")
    broken = tmp_path / "broken.html"
    broken.write_text(
        source.replace(
            "</head>", "<style>.jp-OutputArea-output pre { word-break: break-all; }</style></head>"
        ),
        encoding="utf-8",
    )
    assert screen_layout(broken, 375, browser=browser).pre_breaking_numbers == 1
