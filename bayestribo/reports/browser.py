"""A report as a reader's browser shows it: headless Chromium, offline.

:func:`inspect_report` opens a copy of the HTML report in headless Chromium with the
network switched off, lets it load, and reads back from the live page what a reader
gets: how many images there are, how many loaded with a non-zero natural size, how
many equations (SVG images with their TeX in words as ``alt``), whether any raw ``$$`` or
``\\(`` TeX is left in the visible text, whether code cells are shown. The probe is a
small script added to the copy only (the report itself has no script), which writes
its findings as JSON into the page before Chromium dumps the DOM; the copy's
Content-Security-Policy lets that one script run (by its nonce) and no other.

:func:`screenshot` writes a PNG of the page as Chromium renders it. From the command
line::

    python -m bayestribo.reports.browser report.html --screenshot docs/report.png

prints the inspection and writes the screenshot (``--top`` and ``--height`` choose the
part of the page).
"""

from __future__ import annotations

import argparse
import json
import re
import secrets
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bayestribo._files import atomic_path
from bayestribo.reports._errors import ReportError

__all__ = ["PageInspection", "find_chromium", "inspect_report", "main", "screenshot"]

#: Names of the Chromium executable, tried in order.
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")

#: Flags of every run: headless, no sandbox (containers run as root), no GPU, no network.
_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--hide-scrollbars",
    "--no-first-run",
    "--disable-extensions",
    "--proxy-server=http://127.0.0.1:9",  # offline: any network request fails
    "--proxy-bypass-list=<-loopback>",
)

_PROBE = r"""
<script nonce="__NONCE__">
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var text = document.body.innerText;
  var result = {
    images: imgs.length,
    loaded: imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length,
    broken: imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); })
                .map(function (i) { return (i.getAttribute("src") || "").slice(0, 80); }),
    equations: imgs.filter(function (i) { return i.classList.contains("bt-math"); }).length,
    figures: imgs.filter(function (i) {
      return (i.getAttribute("src") || "").indexOf("data:image/png") === 0; }).length,
    // figures with fewer than 2 image pixels per CSS pixel shown (below 200 dpi at the
    // page's 100 px per inch of a figure): blurred in print and on a high-density screen
    low_resolution: imgs.filter(function (i) {
      var shown = i.getBoundingClientRect().width;
      return (i.getAttribute("src") || "").indexOf("data:image/png") === 0 &&
             i.naturalWidth > 0 && shown > 0 && i.naturalWidth < 1.9 * shown; }).length,
    raw_tex: text.indexOf("$$") >= 0 || text.indexOf("\\(") >= 0,
    code_cells: document.querySelectorAll(".jp-CodeCell .jp-InputArea").length,
    toc_links: document.querySelectorAll(".bt-toc a").length,
    notes: document.querySelectorAll(".bt-note").length,
    stderr_boxes: document.querySelectorAll(
      "[data-mime-type='application/vnd.jupyter.stderr']").length,
    text_length: text.length,
    text_dumps: Array.prototype.filter.call(
      document.querySelectorAll(".jp-OutputArea-output pre"),
      function (el) { return el.textContent.trim().length > 0; }).length,
    reprs: (text.match(/.{0,30}(np\.\w+\(|array\(|\{'|\['|\bNone\b|\bnan\b).{0,30}/g) || [])
      .slice(0, 20),
    identifiers: prose(),
    broken_numbers: brokenNumbers(),
    figure_problems: figureProblems()
  };
  function figureProblems() {
    // notes by which the report says a figure is not legible (labels overlap, a panel
    // with nothing to show): the report's figures are checked as they are drawn
    var kinds = __FIGURE_PROBLEMS__;
    var found = [];
    document.querySelectorAll(".bt-note").forEach(function (el) {
      var text = el.textContent.replace(/^\s*Note\.\s*/, "");
      if (kinds.some(function (k) { return text.indexOf(": " + k + ": ") >= 0; })) {
        found.push(text.slice(0, 200));
      }
    });
    return found.slice(0, 20);
  }
  function prose() {
    // names with an underscore in the text a reader sees (paragraphs, lists, headings,
    // tables, notes, the contents): code names (load_N, log_decrement) and symbols
    // typed as code (mu_k, μ_k, x_c: a report sets them as μ<sub>k</sub>); code, preformatted
    // text and images left out. A name is one whose every part starts with a letter: a
    // file name's numbered parts ("disc_14.9_1") are not names
    var found = [];
    var walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
    var node;
    while ((node = walker.nextNode())) {
      if (node.parentElement &&
          node.parentElement.closest("code, pre, script, style, #bt-probe")) {
        continue;
      }
      (node.data.match(/[\p{L}\p{N}_]+/gu) || []).forEach(function (w) {
        var parts = w.split("_");
        var named = parts.length > 1 && parts.every(function (p) { return /^\p{L}/u.test(p); });
        if (named && found.indexOf(w) < 0) { found.push(w); }
      });
    }
    return found.slice(0, 20);
  }
  function brokenNumbers() {
    // numbers (1.5158e-07, -0.0006399) that the layout splits over two lines
    var found = [];
    var walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
    var number = /[-+\u2212]?\d[\d.]*(?:e[-+\u2212]?\d+)?/g;
    var node;
    while ((node = walker.nextNode())) {
      if (node.parentElement && node.parentElement.closest("pre, script, style")) {
        continue;
      }
      var m;
      number.lastIndex = 0;
      while ((m = number.exec(node.data)) !== null) {
        if (m[0].length < 2) { continue; }
        var range = document.createRange();
        range.setStart(node, m.index);
        range.setEnd(node, m.index + m[0].length);
        var tops = [];
        Array.prototype.forEach.call(range.getClientRects(), function (r) {
          var top = Math.round(r.top);
          if (r.width > 0 && tops.indexOf(top) < 0) { tops.push(top); }
        });
        if (tops.length > 1) { found.push(m[0]); }
      }
    }
    return found.slice(0, 20);
  }
  var out = document.createElement("pre");
  out.id = "bt-probe";
  out.textContent = JSON.stringify(result);
  document.body.appendChild(out);
});
</script>
"""


@dataclass(frozen=True)
class PageInspection:
    """What headless Chromium found in a report.

    Attributes
    ----------
    images, loaded : int
        Images on the page, and those that loaded with a non-zero natural width.
    broken : list of str
        The start of the ``src`` of each image that did not load.
    equations : int
        Equation images (SVG rendered from TeX).
    figures : int
        Figures (PNG data).
    low_resolution : int
        Figures shown with fewer than two image pixels per CSS pixel (below 200 dpi).
    raw_tex : bool
        Raw TeX (``$$`` or ``\\(``) left in the visible text.
    code_cells : int
        Code cells shown.
    toc_links : int
        Links of the table of contents.
    notes : int
        Notes (warnings and remarks) in the text.
    stderr_boxes : int
        stderr outputs shown as such.
    text_length : int
        Characters of visible text.
    text_dumps : int
        Outputs shown as preformatted (monospace) text: a result printed instead of
        shown as a table.
    reprs : list of str
        Python representations in the visible text (``np.float64(``, ``{'``, ``['``,
        ``None``, ``nan``), with their context.
    identifiers : list of str
        Names with an underscore in the visible text (code names such as ``load_N``,
        symbols typed as code such as ``μ_k`` or ``x_c`` where the report should show
        μ<sub>k</sub>), code spans and preformatted text left out.
    broken_numbers : list of str
        Table cells with digits that the layout breaks across lines.
    figure_problems : list of str
        Notes saying a figure is not legible: texts that overlap, a panel with nothing
        to show (:data:`bayestribo.reports.kit.FIGURE_PROBLEMS`).
    """

    images: int
    loaded: int
    broken: list[str]
    equations: int
    figures: int
    low_resolution: int
    raw_tex: bool
    code_cells: int
    toc_links: int
    notes: int
    stderr_boxes: int
    text_length: int
    text_dumps: int
    reprs: list[str]
    identifiers: list[str]
    broken_numbers: list[str]
    figure_problems: list[str]

    @property
    def all_images_loaded(self) -> bool:
        """Every image loaded with a non-zero size."""
        return self.images == self.loaded


def find_chromium() -> str | None:
    """Path of a Chromium (or Chrome) executable on PATH, or None."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    return None


def _chromium(executable: str | None) -> str:
    exe = executable or find_chromium()
    if exe is None:
        raise ReportError(
            f"no Chromium found on PATH (looked for {', '.join(CHROMIUM_NAMES)}); install "
            "it, e.g. `apt-get install chromium`"
        )
    return exe


def _run(args: list[str], timeout: float) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(args, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        raise ReportError(f"Chromium did not finish within {timeout:.0f} s") from None


def inspect_report(
    html: str | Path, *, executable: str | None = None, timeout: float = 120.0
) -> PageInspection:
    """Open a report in headless Chromium, offline, and read what the page shows.

    Parameters
    ----------
    html : path
        The HTML report (not modified: a copy beside it in a temporary folder is opened,
        with any relative files it names reachable).
    executable : str, optional
        Chromium to use (default :func:`find_chromium`).
    timeout : float
        Longest time Chromium may take [s].

    Returns
    -------
    PageInspection

    Raises
    ------
    ReportError
        Without Chromium, or if it does not produce the page's findings.
    """
    exe = _chromium(executable)
    source = Path(html).resolve()
    page = source.read_text(encoding="utf-8")
    from bayestribo.reports.kit import FIGURE_PROBLEMS

    nonce = secrets.token_hex(16)
    probe = _PROBE.replace("__FIGURE_PROBLEMS__", json.dumps(list(FIGURE_PROBLEMS)))
    probe = probe.replace("__NONCE__", nonce)
    # the report's policy runs no script: the copy's runs the probe's, and no other
    page = page.replace("script-src 'none'", f"script-src 'nonce-{nonce}'", 1)
    probed = page.replace("</body>", probe + "</body>", 1)
    with tempfile.NamedTemporaryFile(
        "w", suffix=".html", prefix=".probe-", dir=source.parent, delete=False, encoding="utf-8"
    ) as fh:
        fh.write(probed)
        copy = Path(fh.name)
    try:
        with tempfile.TemporaryDirectory(prefix="bayestribo-chromium-") as profile:
            proc = _run(
                [
                    exe,
                    *_FLAGS,
                    f"--user-data-dir={profile}",
                    "--virtual-time-budget=10000",
                    "--dump-dom",
                    copy.as_uri(),
                ],
                timeout,
            )
    finally:
        copy.unlink(missing_ok=True)
    found = re.search(r'<pre id="bt-probe">(.*?)</pre>', proc.stdout, re.DOTALL)
    if found is None:
        raise ReportError(
            f"Chromium gave no findings for {source} (exit {proc.returncode}): "
            + proc.stderr.strip()[-300:]
        )
    text = found.group(1).replace("&quot;", '"').replace("&amp;", "&")
    text = text.replace("&lt;", "<").replace("&gt;", ">")
    data: dict[str, Any] = json.loads(text)
    return PageInspection(**data)


def screenshot(
    html: str | Path,
    png: str | Path,
    *,
    width: int = 1100,
    height: int = 2400,
    top: int = 0,
    executable: str | None = None,
    timeout: float = 120.0,
) -> Path:
    """Write a PNG of a report as headless Chromium renders it, offline.

    Parameters
    ----------
    html : path
        The HTML report.
    png : path
        The PNG to write (its folder is created).
    width, height : int
        Size of the picture [CSS pixels].
    top : int
        Where the picture starts below the top of the page [CSS pixels] (the page is
        rendered down to ``top + height`` and the part above ``top`` cut off).
    executable : str, optional
        Chromium to use.
    timeout : float
        Longest time Chromium may take [s].

    Returns
    -------
    Path
        ``png``.
    """
    exe = _chromium(executable)
    out = Path(png).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    # Chromium writes a temporary beside it, renamed into place once whole (and cropped)
    with (
        atomic_path(out) as shot,
        tempfile.TemporaryDirectory(prefix="bayestribo-chromium-") as profile,
    ):
        shot.unlink()  # Chromium's own file, or none if it fails
        proc = _run(
            [
                exe,
                *_FLAGS,
                f"--user-data-dir={profile}",
                f"--window-size={width},{top + height}",
                f"--screenshot={shot}",
                Path(html).resolve().as_uri(),
            ],
            timeout,
        )
        if not shot.is_file():
            raise ReportError(f"Chromium wrote no screenshot (exit {proc.returncode})")
        if top > 0:
            from PIL import Image  # pillow comes with matplotlib

            with Image.open(shot) as image:
                cropped = image.crop((0, top, image.width, image.height))
            cropped.save(shot, format="PNG")
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m bayestribo.reports.browser REPORT [--screenshot PNG]``."""
    parser = argparse.ArgumentParser(
        prog="python -m bayestribo.reports.browser",
        description="Open a report in headless Chromium, offline: print what loaded, and "
        "optionally write a screenshot.",
    )
    parser.add_argument("html", type=Path, help="the HTML report")
    parser.add_argument("--screenshot", type=Path, metavar="PNG", help="also write a PNG")
    parser.add_argument("--width", type=int, default=1100, help="window width [px]")
    parser.add_argument("--height", type=int, default=2400, help="picture height [px]")
    parser.add_argument(
        "--top", type=int, default=0, help="where the picture starts below the page top [px]"
    )
    args = parser.parse_args(argv)
    found = inspect_report(args.html)
    print(json.dumps(found.__dict__, indent=2))
    if args.screenshot:
        shot = screenshot(
            args.html, args.screenshot, width=args.width, height=args.height, top=args.top
        )
        print(f"screenshot: {shot}")
    legible = not found.raw_tex and not found.figure_problems
    return 0 if found.all_images_loaded and legible else 1


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
