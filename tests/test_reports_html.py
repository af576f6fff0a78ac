"""Offline HTML of a report: equations as SVG, warnings as notes, contents, no network."""

from __future__ import annotations

import base64
import re

import pytest

nbformat = pytest.importorskip("nbformat")
pytest.importorskip("nbconvert")

from bayestribo.reports.html import (  # noqa: E402
    external_references,
    math_to_svg,
    render_math,
    stderr_as_notes,
    table_of_contents,
    to_html,
)
from bayestribo.reports.notebooks import execute_notebook  # noqa: E402

EQUATION = r"y'' + 2\zeta y' + y = -\mu_k\,\mathrm{sgn}(y')"


def test_an_equation_becomes_an_svg_image_with_its_tex_as_alt_text():
    tag = math_to_svg(EQUATION, display=True)
    src = re.search(r'src="data:image/svg\+xml;base64,([^"]+)"', tag).group(1)
    svg = base64.b64decode(src).decode()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg and "<path" in svg  # glyphs
    assert "&#x27;" in tag or "y&#x27;&#x27;" in tag or "y''" in tag  # TeX kept as alt text
    inline = math_to_svg(r"\zeta_0")
    assert "vertical-align" in inline and "bt-math-display" not in inline


def test_markdown_math_is_replaced_and_text_is_kept():
    text = render_math(f"Motion: $${EQUATION}$$ with $\\zeta$ and a price of 5 \\$.")
    assert "$$" not in text and "$\\zeta$" not in text
    assert text.count("<img") == 2 and "a price of 5 \\$." in text
    # what mathtext cannot parse stays as TeX, visible to the reader
    assert render_math(r"$\notacommand{x}$") == r"$\notacommand{x}$"


def test_stderr_becomes_short_notes_without_source_lines_or_progress_bars():
    cell = nbformat.v4.new_code_cell("")
    cell.outputs = [
        nbformat.v4.new_output(
            "stream",
            name="stderr",
            text="/x/pkg/mod.py:12: UserWarning: the sampler stopped early\n"
            "  warnings.warn(msg)\n"
            " 40%|####      | 4/10 [00:01<00:01,  3.9it/s]\r",
        )
    ]
    nb = stderr_as_notes(nbformat.v4.new_notebook(cells=[cell]))
    [out] = nb.cells[0].outputs
    html = out["data"]["text/html"]
    assert "the sampler stopped early" in html and 'class="bt-note"' in html
    assert "warnings.warn" not in html and "it/s" not in html and "mod.py" not in html


def test_contents_list_every_section_and_give_ids_to_headings_without_one():
    page = (
        '<main><h1 id="t">Title</h1><h2 id="A">A<a class="anchor-link" href="#A">¶</a></h2>'
        '<h3><img class="bt-math" alt="x"> band</h3></main>'
    )
    out = table_of_contents(page)
    nav = re.search(r'<nav class="bt-toc">.*?</nav>', out).group(0)
    assert '<a href="#A">A</a>' in nav and 'href="#bt-section-2"' in nav
    assert '<h3 id="bt-section-2">' in out and out.index("</h1>") < out.index("<nav")


def test_a_rendered_notebook_loads_nothing_from_a_network_and_shows_no_code():
    md = nbformat.v4.new_markdown_cell(f"# Title\n\n## Section\n\n$${EQUATION}$$")
    code = nbformat.v4.new_code_cell("print('result')\nsecret = 1")
    code.outputs = [nbformat.v4.new_output("stream", name="stdout", text="result\n")]
    page = to_html(nbformat.v4.new_notebook(cells=[md, code]))
    assert external_references(page) == []
    assert "secret" not in page and "result" in page and "$$" not in page
    assert "bayestribo" in page.split('class="bt-footer"')[1]  # version in the footer


def test_external_references_are_found():
    page = (
        '<script src="https://cdn.example/x.js"></script><link href="//cdn.example/s.css">'
        '<a href="https://example.org">a link is not a load</a>'
        "<style>@import 'https://fonts.example/f.css'; b {background: url(http://x/y.png)}</style>"
    )
    assert sorted(external_references(page)) == sorted(
        [
            "https://cdn.example/x.js",
            "//cdn.example/s.css",
            "https://fonts.example/f.css",
            "http://x/y.png",
        ]
    )


def test_warnings_in_a_notebook_are_notes_and_the_kernel_stays_quiet(tmp_path, capfd):
    cell = nbformat.v4.new_code_cell(
        "import warnings\nfrom bayestribo.reports import kit\nsave = kit.setup(None)\n"
        "warnings.warn('ζ is near its bound')"
    )
    nb = nbformat.v4.new_notebook(cells=[cell])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    execute_notebook(nb, cwd=tmp_path)
    [out] = nb.cells[0].outputs
    assert out["output_type"] == "display_data"
    assert (
        "ζ is near its bound" in out["data"]["text/html"] and "bt-note" in out["data"]["text/html"]
    )
    captured = capfd.readouterr()
    assert "Kernel is running over TCP" not in captured.err + captured.out


def test_symbols_read_as_symbols_in_the_text_and_code_stays_code():
    """``μ_k`` and ``x_c`` in a table, a note or a sentence are set with a subscript
    (μ<sub>k</sub>); code names, file names, attributes and code spans are left alone."""
    import doctest

    from bayestribo.reports import symbols

    assert doctest.testmod(symbols).failed == 0
    md = nbformat.v4.new_markdown_cell("# Title\n\nWithout a load, x_c replaces μ_k.")
    code = nbformat.v4.new_code_cell("")
    code.outputs = [
        nbformat.v4.new_output(
            "display_data",
            data={
                "text/html": '<table><tr><th title="mu_k">μ_s/μ_k</th><td>x_c [m]</td></tr>'
                "</table><code>--param max_steps=5000 mu_k</code><p>file disc_14.9_1</p>"
            },
        )
    ]
    page = to_html(nbformat.v4.new_notebook(cells=[md, code]))
    assert "x<sub>c</sub> replaces μ<sub>k</sub>" in page
    assert '<th title="mu_k">μ<sub>s</sub>/μ<sub>k</sub></th><td>x<sub>c</sub> [m]</td>' in page
    assert "<code>--param max_steps=5000 mu_k</code>" in page and "disc_14.9_1" in page
