"""An executed notebook as one HTML page a reader can open offline.

:func:`to_html` renders with nbconvert's ``HTMLExporter`` through the package's own
template (``template/bayestribo``, extending JupyterLab's): no script or stylesheet
is fetched from the network (the lab template loads require.js and MathJax from a
CDN; this one loads nothing), the code cells are left out unless asked for, and

* every equation of the Markdown (``$...$`` and ``$$...$$``) is rendered here, with
  matplotlib's mathtext, to an SVG image embedded as a ``data:`` URI with its TeX as
  ``alt`` text (:func:`math_to_svg`). No JavaScript is needed to read the page, so the
  equations show in a browser offline, in a mail client's preview and on paper;
  mathtext covers the TeX subset the reports use (Greek, sub- and superscripts,
  ``\\mathrm``, spacing); its ``alt`` text is the TeX in words and Unicode
  (:func:`bayestribo.reports.alt.tex_words`: ``\\mu_k`` -> ``μ_k``);
* text written to stderr (a warning that escaped the notebook's notes, a progress
  line) becomes a short note in the text instead of a red box (:func:`stderr_as_notes`);
* a table of contents of the section headings follows the title, and a footer gives
  the bayestribo version and when the page was made;
* a symbol's subscript is set as one (``μ_k`` -> μ<sub>k</sub>,
  :func:`bayestribo.reports.symbols.subscripts_html`), in the text only;
* the page's title is what the notebook said it is about (:func:`bayestribo.reports.kit.
  page_title`) and the report's own title (its first heading); each figure's ``alt`` text
  is the description the notebook recorded with it (:func:`bayestribo.reports.kit.setup`),
  else the section it is in;
* nothing on the page can run: every Markdown output is read as text, never as HTML
  (:func:`bayestribo.reports.safety.markdown_without_html`), the page carries a
  Content-Security-Policy that allows no script, and a page holding anything that could
  run is refused (:func:`bayestribo.reports.safety.inert_problems`).

:func:`external_references` lists the ``src``/``href`` addresses of a page that would
be loaded from the network (the tests require none).
"""

from __future__ import annotations

import base64
import copy
import html as html_lib
import io
import re
from datetime import UTC, datetime
from importlib import resources
from typing import Any

from bayestribo._optional import require
from bayestribo.reports._errors import ReportError

__all__ = [
    "NOTE_CLASS",
    "PAGE_MIME",
    "external_references",
    "math_to_svg",
    "render_math",
    "stderr_as_notes",
    "table_of_contents",
    "to_html",
]

#: CSS class of the notes (warnings and remarks) in a report.
NOTE_CLASS = "bt-note"

#: MIME type of the outputs by which a notebook says what its page is about
#: (``{"subject": ...}``, :func:`bayestribo.reports.kit.page_title`); not shown.
PAGE_MIME = "application/vnd.bayestribo.page+json"

# $$...$$ first (display), then $...$ (inline, not empty, not spanning a blank line);
# a backslash-escaped dollar is text.
_DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.DOTALL)
_INLINE = re.compile(r"(?<![\\$])\$(?!\$)([^$\n]+?)(?<!\\)\$(?!\$)")
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def math_to_svg(tex: str, *, fontsize: float = 12.0, display: bool = False) -> str:
    """One equation as an ``<img>`` tag holding its SVG rendering (a ``data:`` URI).

    Parameters
    ----------
    tex : str
        The TeX source without the dollar signs (matplotlib mathtext's subset).
    fontsize : float
        Font size [pt].
    display : bool
        A display equation (centred on its own line) rather than inline text.

    Returns
    -------
    str
        ``<img class="bt-math" ...>`` with the TeX in words as ``alt`` text, its size in em of
        the surrounding text and, inline, the baseline aligned with the text
        (``vertical-align`` by the depth).
    """
    from matplotlib import mathtext
    from matplotlib.font_manager import FontProperties

    buf = io.BytesIO()
    depth = mathtext.math_to_image(
        f"${tex.strip()}$", buf, prop=FontProperties(size=fontsize), format="svg"
    )
    svg = buf.getvalue().decode("utf-8")
    size = re.search(r'width="([\d.]+)pt" height="([\d.]+)pt"', svg)
    width, height = (size.group(1), size.group(2)) if size else ("", "")
    data = base64.b64encode(svg.encode("utf-8")).decode("ascii")
    from bayestribo.reports.alt import tex_words

    alt = html_lib.escape(tex_words(tex.strip()), quote=True)
    kind = "bt-math bt-math-display" if display else "bt-math"
    # sizes in em of the text around (rendered at ``fontsize``): an equation in a
    # heading grows with the heading
    em = float(fontsize)
    style = ""
    if width and height:
        style = f"width:{float(width) / em:.3f}em;height:{float(height) / em:.3f}em"
    if not display:
        style += f";vertical-align:-{float(depth) / em:.3f}em"
    src = f"data:image/svg+xml;base64,{data}"
    return f'<img class="{kind}" alt="{alt}" style="{style}" src="{src}">'


def render_math(markdown: str) -> str:
    """Markdown with every ``$$...$$`` and ``$...$`` replaced by its SVG image.

    A display equation becomes a centred block of its own. A span that mathtext cannot
    parse is left as text (the reader sees its TeX, escaped).
    """

    def display(m: re.Match[str]) -> str:
        try:
            return f'\n\n<div class="bt-equation">{math_to_svg(m.group(1), display=True)}</div>\n\n'
        except ValueError:
            return html_lib.escape(m.group(0), quote=False)

    def inline(m: re.Match[str]) -> str:
        try:
            return math_to_svg(m.group(1))
        except ValueError:
            return html_lib.escape(m.group(0), quote=False)

    return _INLINE.sub(inline, _DISPLAY.sub(display, markdown))


def _note_html(text: str) -> str:
    return f'<div class="{NOTE_CLASS}"><b>Note.</b> {html_lib.escape(text)}</div>'


def _stderr_text(text: str) -> list[str]:
    """The lines of a stderr stream worth a note: no progress bars, no source lines."""
    out = []
    for raw in _ANSI.sub("", text).replace("\r", "\n").splitlines():
        line = raw.strip()
        if not line or "it/s]" in line or "%|" in line:
            continue  # a progress bar
        if raw.startswith((" ", "\t")):
            continue  # the source line a warning prints under itself
        # "path/to/file.py:123: SomeWarning: message" -> "message"
        line = re.sub(r"^\S+\.py:\d+: (\w+Warning): ", "", line)
        out.append(line)
    return out


def stderr_as_notes(nb: Any) -> Any:
    """A copy of ``nb`` whose stderr outputs are short HTML notes (one per message).

    Progress bars and the source lines that :mod:`warnings` prints are dropped, and
    ``file.py:N: SomeWarning:`` prefixes removed.
    """
    nbformat = require("nbformat", "making reports")
    nb = copy.deepcopy(nb)
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        outputs = []
        for out in cell.get("outputs", []):
            if out.get("output_type") == "stream" and out.get("name") == "stderr":
                lines = _stderr_text(out.get("text", ""))
                if lines:
                    outputs.append(
                        nbformat.v4.new_output(
                            "display_data", data={"text/html": "".join(map(_note_html, lines))}
                        )
                    )
            else:
                outputs.append(out)
        cell.outputs = outputs
    return nb


def _math_in_markdown(nb: Any) -> Any:
    """Equations as SVG; a Markdown output (made from data) read as text, not HTML."""
    from bayestribo.reports.safety import markdown_without_html

    for cell in nb.cells:
        if cell.cell_type == "markdown":
            cell.source = render_math(cell.source)
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            if "text/markdown" in data:
                data["text/markdown"] = render_math(markdown_without_html(data["text/markdown"]))
    return nb


_H1 = re.compile(r"^#\s+(.+?)\s*$", re.MULTILINE)
_SECTION = re.compile(r"^#{1,3}\s+(.+?)\s*$", re.MULTILINE)


def _plain_heading(markdown: str) -> str:
    """A Markdown heading as plain text: its equations in words, no marks."""
    from bayestribo.reports.alt import tex_words

    text = re.sub(r"\$([^$]+)\$", lambda m: tex_words(m.group(1)), markdown)
    return re.sub(r"[*`]", "", text).strip()


def page_facts(nb: Any) -> Any:
    """A copy of ``nb`` with its title set and every figure's ``alt`` text.

    The title (``nb.metadata["title"]``) is the subject the notebook gave
    (:data:`PAGE_MIME` outputs, removed here), then the report's first ``#`` heading:
    ``"glycerol-N0.31-r1 – One run: friction ..."``. A figure (``image/png``) without a
    description of its own is described by the section it is in.
    """
    nb = copy.deepcopy(nb)
    subject, report, section = None, None, None
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            if report is None and (m := _H1.search(cell.source)):
                report = _plain_heading(m.group(1))
            headings = _SECTION.findall(cell.source)
            if headings:
                section = _plain_heading(headings[-1])
            continue
        kept = []
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            if PAGE_MIME in data:
                subject = str(data[PAGE_MIME].get("subject") or "") or subject
                continue
            if "image/png" in data:
                meta = out.setdefault("metadata", {})
                png = meta.setdefault("image/png", {})
                if not png.get("alt"):
                    png["alt"] = f"Figure in the section {section!r}." if section else "Figure."
            kept.append(out)
        if cell.cell_type == "code":
            cell.outputs = kept
    title = " – ".join(t for t in (subject, report) if t)
    if title:
        nb.metadata["title"] = title
    return nb


_HEADING = re.compile(r"<h([23])([^>]*)>(.*?)</h\1>", re.DOTALL)
_ANCHOR = re.compile(r'<a class="anchor-link"[^>]*>.*?</a>', re.DOTALL)


def table_of_contents(page: str) -> str:
    """The page with a table of contents of its h2/h3 headings after its first h1.

    A heading without an ``id`` (one holding an equation) is given one. Pages without
    section headings are returned unchanged.
    """
    items = []

    def visit(m: re.Match[str]) -> str:
        level, attrs, inner = m.group(1), m.group(2), m.group(3)
        found = re.search(r'\bid="([^"]+)"', attrs)
        ident = found.group(1) if found else f"bt-section-{len(items) + 1}"
        if not found:
            attrs += f' id="{ident}"'
        cls = "bt-toc-sub" if level == "3" else "bt-toc-section"
        items.append(
            f'<li class="{cls}"><a href="#{ident}">{_ANCHOR.sub("", inner).strip()}</a></li>'
        )
        return f"<h{level}{attrs}>{inner}</h{level}>"

    page = _HEADING.sub(visit, page)
    if not items:
        return page
    nav = '<nav class="bt-toc"><b>Contents</b><ul>' + "".join(items) + "</ul></nav>"
    end = page.find("</h1>")
    if end < 0:
        return page.replace("<main>", "<main>" + nav, 1)
    end += len("</h1>")
    return page[:end] + nav + page[end:]


def _footer(page: str) -> str:
    from bayestribo import __version__

    made = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    foot = (
        f'<footer class="bt-footer">Made with bayestribo {__version__} on {made}. '
        "Self-contained: no network access is needed to read this page.</footer>"
    )
    return page.replace("</main>", foot + "</main>", 1)


def external_references(page: str) -> list[str]:
    """The ``src``/``href`` addresses of ``page`` that a browser would fetch from a network.

    Links a reader may click (``<a href>``) are not loads and are not listed.
    """
    refs = []
    for tag in re.finditer(r"<(\w+)\b[^>]*>", page):
        name = tag.group(1).lower()
        for attr, value in re.findall(r'\b(src|href)\s*=\s*["\']([^"\']+)["\']', tag.group(0)):
            if name == "a" and attr == "href":
                continue
            if re.match(r"(https?:)?//", value):
                refs.append(value)
    refs += re.findall(r"url\(\s*['\"]?((?:https?:)?//[^)'\"]+)", page)
    refs += re.findall(r"@import\s+['\"]((?:https?:)?//[^'\"]+)", page)
    return refs


def to_html(nb: Any, *, show_code: bool = False) -> str:
    """Render an executed notebook as one self-contained HTML page.

    Figures (``image/png`` outputs) are embedded as base64 data and equations as SVG,
    so the file needs nothing beside it and no network.

    Parameters
    ----------
    nb : nbformat.NotebookNode
        The executed notebook (not modified).
    show_code : bool
        Include the code cells (default: a report without code).

    Returns
    -------
    str
        The HTML page.
    """
    HTMLExporter = require("nbconvert", "making reports").HTMLExporter

    from bayestribo.reports.safety import CONTENT_SECURITY_POLICY, inert_problems

    nb = _math_in_markdown(page_facts(stderr_as_notes(nb)))
    template = resources.files("bayestribo.reports") / "template"
    exporter = HTMLExporter(
        extra_template_basedirs=[str(template)],
        template_name="bayestribo",
        exclude_input=not show_code,
        exclude_input_prompt=not show_code,
        exclude_output_prompt=True,
    )
    body, _ = exporter.from_notebook_node(
        nb, resources={"bayestribo": {"csp": CONTENT_SECURITY_POLICY}}
    )
    from bayestribo.reports.symbols import subscripts_html

    page = _footer(subscripts_html(table_of_contents(body)))
    problems = inert_problems(page)
    if problems:
        raise ReportError(
            "the report would run code in a reader's browser ("
            + "; ".join(dict.fromkeys(problems))
            + "): an output holds unescaped HTML; show names with bayestribo.reports.kit "
            "(note, table, facts, heading), which escape them"
        )
    return page
