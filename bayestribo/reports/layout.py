"""A report as it lays out on paper and on a phone, and what it runs.

Read from the live page in headless Chromium (:class:`bayestribo.reports.devtools.Chromium`):

* :func:`print_layout` lays the page out for print at the width of the text on a sheet
  of A4 or Letter (the paper less the margins of the report's ``@page`` rule,
  :data:`PAGE_MARGIN_MM`) and lists every table whose columns run past the margin, every
  box that would cut its content, every heading free to stand alone at the bottom of a
  page and every figure free to be split; then prints the page to PDF and counts its
  pages;
* :func:`screen_layout` lays it out on a narrow screen (a phone, 375 px) and says whether
  the contents box sits beside the text (squeezing it) or above it, and whether
  preformatted text may break inside a number;
* :func:`script_check` opens the page as it is and says whether any script ran (the
  page's title or a marker changed) and which of its parts the page's
  Content-Security-Policy had to block.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bayestribo.reports._errors import ReportError
from bayestribo.reports.devtools import Chromium

__all__ = [
    "PAGE_MARGIN_MM",
    "PAPERS_MM",
    "PrintLayout",
    "ScreenLayout",
    "ScriptCheck",
    "pdf_pages",
    "print_layout",
    "screen_layout",
    "script_check",
]

#: Paper sizes (width, height) [mm].
PAPERS_MM: dict[str, tuple[float, float]] = {"A4": (210.0, 297.0), "Letter": (215.9, 279.4)}

#: The report's print margins (top and bottom, left and right) [mm]: the ``@page`` rule
#: of the template (``template/bayestribo/index.html.j2``) says the same.
PAGE_MARGIN_MM: tuple[float, float] = (15.0, 12.0)

_PX_PER_MM = 96 / 25.4

_PRINT_PROBE = r"""
(() => {
  const W = document.documentElement.clientWidth;
  const text = (el) => (el.textContent || "").trim().replace(/\s+/g, " ").slice(0, 80);
  const tables = [...document.querySelectorAll("table")];
  const cut = tables.filter((t) => {
    const r = t.getBoundingClientRect();
    return r.width > 0 && (r.right > W + 1 || r.left < -1 || t.scrollWidth > t.clientWidth + 1);
  }).map(text);
  const clipped = [...document.querySelectorAll("body *")].filter((el) => {
    const s = getComputedStyle(el);
    const clips = ["hidden", "auto", "scroll", "clip"].includes(s.overflowX);
    return clips && el.clientWidth > 0 && el.scrollWidth > el.clientWidth + 1;
  }).map((el) => el.tagName.toLowerCase() + "." + [...el.classList].join(".") + ": " + text(el));
  const loose = [...document.querySelectorAll("h1, h2, h3, h4, h5, h6")]
    .filter((h) => getComputedStyle(h).breakAfter !== "avoid").map(text);
  const split = [...document.querySelectorAll(".jp-RenderedImage, .bt-equation")]
    .filter((f) => getComputedStyle(f).breakInside !== "avoid").length;
  return {width: W, page_width: document.documentElement.scrollWidth, tables: tables.length,
          cut_tables: cut, clipped: clipped.slice(0, 20), loose_headings: loose.slice(0, 20),
          split_figures: split};
})()
"""

_SCREEN_PROBE = r"""
(() => {
  const W = document.documentElement.clientWidth;
  const toc = document.querySelector(".bt-toc");
  let beside = false;
  if (toc) {
    const r = toc.getBoundingClientRect();
    beside = [...document.querySelectorAll("main p, main li:not(.bt-toc li)")].some((p) => {
      if (toc.contains(p)) { return false; }
      const q = p.getBoundingClientRect();
      return q.height > 0 && q.top < r.bottom - 1 && q.bottom > r.top + 1;
    });
  }
  const pre = [...document.querySelectorAll("pre")]
    .filter((p) => ["break-all", "break-word"].includes(getComputedStyle(p).wordBreak) ||
                   getComputedStyle(p).overflowWrap === "anywhere").length;
  return {width: W, page_width: document.documentElement.scrollWidth, toc: !!toc,
          toc_beside_text: beside, pre_breaking_numbers: pre};
})()
"""

#: Run before the page's own content: the Content-Security-Policy's refusals, recorded.
_VIOLATIONS = r"""
window.__btViolations = [];
document.addEventListener("securitypolicyviolation", (e) => {
  window.__btViolations.push(e.violatedDirective + ": " + (e.sample || e.blockedURI || ""));
});
"""

_SCRIPT_PROBE = r"""
(() => ({title: document.title,
         marker: document.documentElement.getAttribute("data-pwned"),
         violations: window.__btViolations || []}))()
"""


@dataclass(frozen=True)
class PrintLayout:
    """A report laid out for print on one paper size.

    Attributes
    ----------
    paper : str
        "A4" or "Letter".
    width : int
        Width of the text on the sheet [CSS px].
    page_width : int
        Width of the laid-out page [CSS px]: more than ``width`` where something runs
        past the margin.
    tables : int
        Tables on the page.
    cut_tables : list of str
        The start of the text of each table whose columns run past the margin.
    clipped : list of str
        Boxes that would cut their content at their edge (a scrolling box on paper).
    loose_headings : list of str
        Headings that may stand alone at the bottom of a page.
    split_figures : int
        Figures and equations that may be split across two pages.
    pages : int
        Pages of the PDF.
    """

    paper: str
    width: int
    page_width: int
    tables: int
    cut_tables: list[str]
    clipped: list[str]
    loose_headings: list[str]
    split_figures: int
    pages: int


@dataclass(frozen=True)
class ScreenLayout:
    """A report laid out on a screen of one width.

    Attributes
    ----------
    width, page_width : int
        The screen's width and the laid-out page's [CSS px] (more: the page scrolls
        sideways).
    toc : bool
        The page has a contents box.
    toc_beside_text : bool
        The contents box sits beside text (not above it), squeezing the text.
    pre_breaking_numbers : int
        Preformatted blocks whose style may break a word (a number) anywhere.
    """

    width: int
    page_width: int
    toc: bool
    toc_beside_text: bool
    pre_breaking_numbers: int


@dataclass(frozen=True)
class ScriptCheck:
    """What ran when a page was opened.

    Attributes
    ----------
    title : str
        ``document.title`` after loading.
    marker : str or None
        The ``data-pwned`` attribute of the root element (set by a test's payload).
    violations : list of str
        What the page's Content-Security-Policy refused (directive: sample).
    """

    title: str
    marker: str | None
    violations: list[str]


def content_width(paper: str) -> int:
    """Width of the text on a sheet of ``paper`` within the report's margins [CSS px].

    Raises
    ------
    ReportError
        For a paper not in :data:`PAPERS_MM`.
    """
    if paper not in PAPERS_MM:
        raise ReportError(f"paper: expected one of {sorted(PAPERS_MM)}, got {paper!r}")
    return int((PAPERS_MM[paper][0] - 2 * PAGE_MARGIN_MM[1]) * _PX_PER_MM)


def pdf_pages(pdf: bytes) -> int:
    """Number of pages of a PDF (its ``/Type /Page`` objects)."""
    return len(re.findall(rb"/Type\s*/Page(?![s\w])", pdf))


def _with(browser: Chromium | None, run: Any) -> Any:
    if browser is not None:
        return run(browser)
    with Chromium() as own:
        return run(own)


def print_layout(
    html: str | Path,
    paper: str = "A4",
    *,
    browser: Chromium | None = None,
    pdf: str | Path | None = None,
) -> PrintLayout:
    """Lay a report out for print on ``paper`` and read what would be lost or split.

    Parameters
    ----------
    html : path
        The HTML report.
    paper : {"A4", "Letter"}
    browser : Chromium, optional
        An open browser to use (default: one started and closed here).
    pdf : path, optional
        Where to write the printed PDF.

    Returns
    -------
    PrintLayout
    """
    width = content_width(paper)

    def run(b: Chromium) -> PrintLayout:
        b.open(html, width=width, media="print")
        found = b.evaluate(_PRINT_PROBE)
        printed = b.print_pdf(paper_mm=PAPERS_MM[paper])
        if pdf is not None:
            Path(pdf).write_bytes(printed)
        return PrintLayout(paper=paper, pages=pdf_pages(printed), **found)

    return _with(browser, run)


def screen_layout(
    html: str | Path, width: int = 375, *, browser: Chromium | None = None
) -> ScreenLayout:
    """Lay a report out on a screen ``width`` CSS pixels wide (375: a phone).

    Returns
    -------
    ScreenLayout
    """

    def run(b: Chromium) -> ScreenLayout:
        b.open(html, width=width, height=800, media="screen")
        return ScreenLayout(**b.evaluate(_SCREEN_PROBE))

    return _with(browser, run)


def script_check(html: str | Path, *, browser: Chromium | None = None) -> ScriptCheck:
    """Open a report as it is and read whether any script ran.

    A script that ran shows as a changed title or a ``data-pwned`` attribute (what a
    test's hostile names set); one that the page's Content-Security-Policy stopped shows
    as a violation (the policy saved the reader, but the page held code it should not).

    Returns
    -------
    ScriptCheck
    """

    def run(b: Chromium) -> ScriptCheck:
        b.add_script_on_load(_VIOLATIONS)
        b.open(html, width=1280, media="screen")
        return ScriptCheck(**b.evaluate(_SCRIPT_PROBE))

    return _with(browser, run)
