"""A report shows names as text and never runs them; its figures and equations have words.

Fast checks, without a kernel: the helpers that write tables and headings escape what
they are given, a notebook's Markdown output is read as text, a page that holds code is
refused, equations and figures get alt text in words, the page its title. The reports
themselves, made from hostile names and opened in Chromium, are in
``test_reports_pages.py``.
"""

from __future__ import annotations

import html
import re

import pytest

nbformat = pytest.importorskip("nbformat")
pytest.importorskip("nbconvert")
pd = pytest.importorskip("pandas")

from bayestribo.reports import kit  # noqa: E402
from bayestribo.reports._errors import ReportError  # noqa: E402
from bayestribo.reports.alt import figure_description, tex_words  # noqa: E402
from bayestribo.reports.html import PAGE_MIME, math_to_svg, to_html  # noqa: E402
from bayestribo.reports.safety import (  # noqa: E402
    CONTENT_SECURITY_POLICY,
    inert_problems,
    markdown_without_html,
)

SCRIPT = "<script>document.title='PWNED'</script>"
SVG = "air <svg onload=document.title='PWNED'>-r1"
IMG = "<img src=x onerror=document.title='PWNED'>"


@pytest.fixture
def shown(monkeypatch):
    """What the kit's helpers would show, as (MIME type, data) pairs."""
    out = []

    def display(obj):
        data = obj._repr_html_() if hasattr(obj, "_repr_html_") else None
        out.append(("text/html", data) if data is not None else ("text/markdown", obj.data))

    monkeypatch.setattr(kit, "_display", display)
    return out


def test_a_tables_headers_index_and_cells_are_escaped(shown):
    frame = pd.DataFrame({SCRIPT: ["0.0243 [0.0241, 0.0245]"], "unit": [IMG]}, index=[SVG])
    frame.index.name = SCRIPT
    kit.table(frame)
    [(_, page)] = shown
    assert inert_problems(page) == []
    assert "&lt;script&gt;" in page and "&lt;svg onload" in page and "&lt;img src=x" in page
    assert '<span class="bt-num">' in page  # the cells' own markup is kept


def test_a_labels_number_stays_on_one_line_and_its_words_are_escaped(shown):
    """A row label's number ("ΔE(A = 2.45e-05 m)") does not break at its exponent's
    sign where its column is narrow; the label's markup stays text."""
    frame = pd.DataFrame({"value": ["1.0 [0.9, 1.1]"]}, index=[f"ΔE(A = 2.45e-05 m) {SCRIPT}"])
    kit.table(frame)
    [(_, page)] = shown
    assert '<span class="bt-num">2.45e-05</span> m' in page
    assert inert_problems(page) == [] and "&lt;script&gt;" in page


def test_a_multi_index_table_is_escaped(shown):
    frame = pd.DataFrame(
        {"ζ": [1.0, 2.0]}, index=pd.MultiIndex.from_tuples([(SCRIPT, SVG), ("a", IMG)])
    )
    kit.table(frame)
    assert inert_problems(shown[0][1]) == []


def test_a_heading_is_text(shown):
    kit.heading(SVG + " *bold* [link](x)")
    [(_, markdown)] = shown
    assert markdown.startswith("### ")
    rendered = to_html(_notebook(_markdown_output(markdown)))
    assert inert_problems(rendered) == []
    heading = re.search(r"<h3[^>]*>(.*?)<a class=\"anchor-link\"", rendered, re.DOTALL).group(1)
    assert "&lt;svg onload" in heading and "<em>" not in heading and "<a " not in heading
    with pytest.raises(ReportError, match="level"):
        kit.heading("x", level=1)


def _markdown_output(text):
    return nbformat.v4.new_output("display_data", data={"text/markdown": text})


def _notebook(*outputs, title="# A report\n\nSome text.\n\n## 1. A section"):
    cell = nbformat.v4.new_code_cell("")
    cell.outputs = list(outputs)
    return nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(title), cell])


def test_a_markdown_output_is_read_as_text_not_html():
    """A notebook that forgets to escape a name in its own Markdown still shows it as text."""
    said = f"**{SCRIPT}** from {IMG}, `{SVG}`, at $a < b$"
    page = to_html(_notebook(_markdown_output(said)))
    assert inert_problems(page) == []
    assert "&lt;script&gt;" in page and "<strong>" in page  # Markdown's marks still work
    assert "<code>air &lt;svg" in page
    assert markdown_without_html("```\n<b>\n```") == "```\n<b>\n```"  # code blocks as typed


def test_a_page_that_would_run_code_is_refused():
    raw = nbformat.v4.new_output("display_data", data={"text/html": f"<p>{SCRIPT}</p>"})
    with pytest.raises(ReportError, match="would run code"):
        to_html(_notebook(raw))


def test_the_page_has_a_strict_content_security_policy_and_no_script():
    page = to_html(_notebook(_markdown_output("text")))
    meta = re.search(r'<meta[^>]*http-equiv="Content-Security-Policy"[^>]*>', page).group(0)
    assert html.unescape(re.search(r'content="([^"]+)"', meta).group(1)) == CONTENT_SECURITY_POLICY
    assert "script-src 'none'" in CONTENT_SECURITY_POLICY
    assert (
        "default-src 'none'" in CONTENT_SECURITY_POLICY
        and "img-src data:" in CONTENT_SECURITY_POLICY
    )
    assert "<script" not in page.lower()
    # the policy comes before every style and image it governs
    assert page.index("Content-Security-Policy") < page.index("<style")


def test_the_page_title_names_the_subject_and_the_report():
    subject = nbformat.v4.new_output("display_data", data={PAGE_MIME: {"subject": SCRIPT}})
    page = to_html(_notebook(subject, title="# One run: friction $\\mu_k$\n\ntext"))
    title = re.search(r"<title>(.*?)</title>", page, re.DOTALL).group(1)
    assert title == "&lt;script&gt;document.title='PWNED'&lt;/script&gt; – One run: friction μ_k"
    assert PAGE_MIME not in page
    untitled = to_html(_notebook(_markdown_output("x")))
    assert "<title>A report</title>" in untitled  # the report's own title at least


@pytest.mark.parametrize(
    ("tex", "words"),
    [
        (r"\mu_k", "μ_k"),
        (r"\zeta_k = \zeta - \zeta_0", "ζ_k = ζ - ζ_0"),
        (r"d_k = 2\zeta_k\sqrt{km}/N", "d_k = 2ζ_k√(km)/N"),
        (r"\Delta E(A)", "ΔE(A)"),
        (r"\frac{1}{2}kA^2", "1/2kA²"),
        (r"\mathrm{sgn}(y')", "sgn(y')"),
        (r"\tau = \Omega t,\quad y = kx/N", "τ = Ωt, y = kx/N"),
    ],
)
def test_an_equations_alt_text_is_words_not_tex(tex, words):
    assert tex_words(tex) == words
    tag = math_to_svg(tex)
    alt = re.search(r'alt="([^"]*)"', tag).group(1)
    assert "\\" not in alt


def test_a_figures_alt_text_says_what_it_shows():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(2, 1)
    a.plot([0, 1], [0, 1], label="run 1")
    a.set(title="signals", xlabel="time t [s]", ylabel="displacement x [mm]")
    a.legend()
    b.plot([0, 1], [1, 0])
    b.set(xlabel="time t [s]", ylabel="$\\mu_k$ [-]")
    fig.suptitle("glycerol-N0.31-r1")
    said = figure_description(fig)
    plt.close(fig)
    assert said.startswith("Figure: glycerol-N0.31-r1: 2 panels.")
    assert "x: time t [s]; y: displacement x [mm]; showing run 1" in said
    assert "y: μ_k [-]" in said and "$" not in said


def test_the_template_uses_the_figures_description_and_escapes_it():
    png = (
        "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR4nGNgYGD4DwABBAEAwS2OUAAAA"
        "ABJRU5ErkJggg=="
    )
    described = nbformat.v4.new_output(
        "display_data", data={"image/png": png}, metadata={"image/png": {"alt": f"Figure: {IMG}"}}
    )
    bare = nbformat.v4.new_output("display_data", data={"image/png": png})
    page = to_html(_notebook(described, bare))
    alts = re.findall(r'<img[^>]*alt="([^"]*)"', page)
    assert [html.unescape(a) for a in alts] == [
        f"Figure: {IMG}",
        "Figure in the section '1. A section'.",
    ]
    assert "&lt;img" in alts[0]
    assert "No description has been provided" not in page
    assert inert_problems(page) == []


def test_a_link_to_code_in_a_markdown_output_is_shown_as_typed():
    """A README's paragraph (the real-data report shows one) may link anywhere: a link to
    ``javascript:`` or ``data:`` is text, other links stay links."""
    said = "[x](javascript:alert(1)) [y](DATA:text/html,hi) [ok](https://example.org)"
    said += "\n\n[r]: javascript:alert(3)\n\nsee [r]"
    page = to_html(_notebook(_markdown_output(said)))
    assert inert_problems(page) == []
    assert "[x](javascript:alert(1))" in page and "[y](DATA:text/html,hi)" in page
    assert '<a href="https://example.org">ok</a>' in page
