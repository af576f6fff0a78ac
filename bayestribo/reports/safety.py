"""A report shows names; it never runs them.

Every string a report takes from outside (a file name, a sidecar's field, a lubricant,
a run's label, an option) may hold markup: a lubricant named
``<script>alert(1)</script>`` or a file ``air <svg onload=alert(1)>-r1.csv``. Three
layers keep such a name text:

* the helpers that write a report's HTML and Markdown escape every string they are
  given (:func:`html_text`, :func:`markdown_text`; :func:`bayestribo.reports.kit.table`
  escapes a table's headers and index as well as its cells, :func:`kit.heading
  <bayestribo.reports.kit.heading>` a heading);
* every Markdown output of a notebook is read as text with Markdown's own marks, never
  as HTML (:func:`markdown_without_html`, applied by :func:`bayestribo.reports.html.to_html`
  to every output, so a report that forgets to escape a name still shows it as text);
* the page declares a Content-Security-Policy (:data:`CONTENT_SECURITY_POLICY`) that
  lets no script run and nothing load but the page's own ``data:`` images; and
  :func:`inert_problems` lists anything in a page that could run (a ``<script>``, an
  ``on...=`` attribute, a ``javascript:`` address): :func:`to_html
  <bayestribo.reports.html.to_html>` refuses to write a page with any.
"""

from __future__ import annotations

import html
import re
from html.parser import HTMLParser

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "csp_meta",
    "html_text",
    "inert_problems",
    "markdown_text",
    "markdown_without_html",
]

#: The reports' Content-Security-Policy: no script at all, images only from ``data:``
#: URIs (the figures and equations are embedded), fonts likewise, no form, no base
#: address, no frame, no connection. Styles: the page's own ``<style>`` blocks and the
#: ``style`` attributes of nbconvert's and pandas' output (an equation's size, a table
#: cell's alignment) need ``'unsafe-inline'`` for ``style-src``; no style is fetched.
CONTENT_SECURITY_POLICY = (
    "default-src 'none'; script-src 'none'; object-src 'none'; base-uri 'none'; "
    "form-action 'none'; frame-src 'none'; connect-src 'none'; img-src data:; "
    "font-src data:; style-src 'unsafe-inline'"
)

#: Characters with a meaning in Markdown (CommonMark's backslash-escapable punctuation
#: that starts emphasis, links, images, code, headings, lists, tables or HTML).
_MARKDOWN_MARKS = re.compile(r"([\\`*_{}\[\]()#+\-.!|~$])")


def html_text(value: object) -> str:
    """``value`` as text in HTML: ``&``, ``<``, ``>`` and both quotes escaped.

    Examples
    --------
    >>> html_text("<script>alert('x')</script>")
    '&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt;'
    """
    return html.escape(str(value), quote=True)


def markdown_text(value: object) -> str:
    """``value`` as plain text inside Markdown: every Markdown mark backslash-escaped and
    ``&``, ``<``, ``>`` as entities, so it shows as typed (no emphasis, link, image, code
    or tag).

    Examples
    --------
    >>> markdown_text("air <svg onload=alert(1)>-r1")
    'air &lt;svg onload=alert\\\\(1\\\\)&gt;\\\\-r1'
    >>> markdown_text("glycerol_N0.31 [**1**]")
    'glycerol\\\\_N0\\\\.31 \\\\[\\\\*\\\\*1\\\\*\\\\*\\\\]'
    """
    text = _MARKDOWN_MARKS.sub(r"\\\1", str(value)).replace("\n", " ")
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


#: A Markdown link or image to an address that runs or embeds code (``[x](javascript:...)``)
#: and a link reference definition to one (``[x]: javascript:...``).
_SCHEMES = r"(?:javascript|vbscript|data|file):"
_HARMFUL_LINK = re.compile(rf"\]\(\s*<?(?={_SCHEMES})", re.IGNORECASE)
_HARMFUL_REFERENCE = re.compile(rf"^(\s*)\[(?=[^\]]+\]:\s*<?{_SCHEMES})", re.IGNORECASE)
_FENCE = re.compile(r"^(\s*)(```|~~~)")
_CODE_SPAN = re.compile(r"(`+)(.+?)\1", re.DOTALL)
# $$...$$ and $...$ (as bayestribo.reports.html renders them): their "<" is TeX
_MATH = re.compile(r"\$\$.+?\$\$|(?<![\\$])\$(?!\$)[^$\n]+?(?<!\\)\$(?!\$)", re.DOTALL)


def _escape_line(line: str) -> str:
    """One line of Markdown prose with its ``<`` as text (an entity; an entity already
    there, ``&lt;``, is left to show its character); a code span holding ``<`` becomes an
    HTML ``<code>`` of the escaped text (an entity in a code span would show as typed)."""

    def prose(part: str) -> str:
        part = _HARMFUL_LINK.sub(r"]\\(", part)  # shown as typed, not a link
        part = _HARMFUL_REFERENCE.sub(r"\1\\[", part)
        return part.replace("<", "&lt;")

    out, last = [], 0
    for m in _CODE_SPAN.finditer(line):
        out.append(prose(line[last : m.start()]))
        code = m.group(2)
        out.append(
            f"<code>{html.escape(code.strip(), quote=False)}</code>" if "<" in code else m.group(0)
        )
        last = m.end()
    out.append(prose(line[last:]))
    return "".join(out)


def markdown_without_html(markdown: str) -> str:
    """Markdown whose raw HTML is text: every ``<`` outside code and equations becomes an
    entity, so no tag or attribute reaches the page, and a link or image to a
    ``javascript:``, ``vbscript:``, ``data:`` or ``file:`` address is shown as typed
    (Markdown's own marks, ``**bold**``, lists, tables and other links, still work).

    A notebook's Markdown *outputs* are made from data (file names, metadata); the
    reports pass every one through this before rendering.

    Examples
    --------
    >>> markdown_without_html("**<img src=x onerror=alert(1)>** at $a < b$")
    '**&lt;img src=x onerror=alert(1)>** at $a < b$'
    >>> markdown_without_html("the file `a<b.csv`")
    'the file <code>a&lt;b.csv</code>'
    >>> markdown_without_html("[docs](javascript:alert(1))")
    '[docs]\\\\(javascript:alert(1))'
    """
    result, fenced = [], False
    for line in markdown.split("\n"):
        if _FENCE.match(line):
            fenced = not fenced
            result.append(line)
            continue
        if fenced:
            result.append(line)
            continue
        parts, last = [], 0
        for m in _MATH.finditer(line):
            parts.append(_escape_line(line[last : m.start()]))
            parts.append(m.group(0))
            last = m.end()
        parts.append(_escape_line(line[last:]))
        result.append("".join(parts))
    return "\n".join(result)


def csp_meta() -> str:
    """The ``<meta http-equiv="Content-Security-Policy">`` tag of a report."""
    return (
        '<meta http-equiv="Content-Security-Policy" '
        f'content="{html_text(CONTENT_SECURITY_POLICY)}">'
    )


#: Elements that run or load code, or take the page elsewhere.
_ACTIVE_TAGS = frozenset(
    {"script", "iframe", "frame", "object", "embed", "applet", "base", "form", "portal"}
)
_URL_ATTRS = frozenset({"href", "src", "action", "formaction", "xlink:href", "data", "srcdoc"})


class _Inspector(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.problems: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in _ACTIVE_TAGS:
            self.problems.append(f"a <{tag}> element")
        for name, value in attrs:
            name = name.lower()
            if name.startswith("on"):
                self.problems.append(f"an event handler {name}= on <{tag}>")
            if name in _URL_ATTRS and value is not None:
                address = re.sub(r"[\x00-\x20]", "", value).lower()
                if address.startswith(("javascript:", "vbscript:")):
                    self.problems.append(f"a {address[:11]} address in <{tag} {name}>")
                if name == "srcdoc":
                    self.problems.append(f"an inline document (srcdoc) on <{tag}>")
            if tag == "meta" and name == "http-equiv" and (value or "").lower() == "refresh":
                self.problems.append("a <meta http-equiv=refresh>")

    handle_startendtag = handle_starttag


def inert_problems(page: str) -> list[str]:
    """What in an HTML page could run code or take the reader elsewhere: ``<script>``,
    ``<iframe>``, ``<object>``, ``<embed>``, ``<base>``, ``<form>`` elements, ``on...=``
    event handlers, ``javascript:`` addresses, a refresh.

    Returns
    -------
    list of str
        One phrase per finding, in page order; empty for an inert page.

    Examples
    --------
    >>> inert_problems('<p>&lt;script&gt;</p><img alt="x" src="data:,">')
    []
    >>> inert_problems('<svg onload=alert(1)></svg><script>1</script>')
    ['an event handler onload= on <svg>', 'a <script> element']
    """
    inspector = _Inspector()
    inspector.feed(page)
    inspector.close()
    return inspector.problems
