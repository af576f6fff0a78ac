"""Symbols as a reader reads them: ``μ_k`` in a report's HTML becomes μ<sub>k</sub>.

The package names its quantities in plain text with an underscore for the subscript
(``μ_k``, ``x_c``, ``ζ_k``, ``τ_end``: :attr:`bayestribo.inference.FitResult.symbols`,
:data:`bayestribo.reports.tables.SYMBOLS`), which is what a terminal can show. In HTML
the subscript is set as one: :func:`subscripts_html` rewrites the text of a page (never
its tags, attributes, code, scripts or styles), so every table, note, verdict and
sentence of every report reads ``μ<sub>k</sub>`` whatever made it; in a figure,
:func:`subscripts_figure` sets it in matplotlib's mathtext (``μ$_{k}$``) in every text of
the figure (labels, titles, tick labels, legends, annotations).

A symbol is one letter (Latin or Greek, or ℓ) that does not continue a word, an
underscore and a subscript of one to three letters or digits that ends there
(``x_c``, ``σ_d``, ``τ_end``, ``ζ_α``): a code name (``load_N``, ``max_steps``) or a file
name (``disc_14.9_1``) is not one and is left as it is (the browser's probe,
:mod:`bayestribo.reports.browser`, fails a report that shows one).
"""

from __future__ import annotations

import re
from typing import Any

__all__ = [
    "SYMBOL",
    "plain_symbols",
    "subscripts",
    "subscripts_figure",
    "subscripts_html",
    "subscripts_mathtext",
]

#: One letter that does not continue a word, ``_``, a subscript of 1-3 letters or digits.
SYMBOL = re.compile(r"(?<![\w])([A-Za-z\u0391-\u03a9\u03b1-\u03c9ℓ])_([^\W_]{1,3})(?![\w])")

#: Elements whose text is left as it is: code, preformatted text, scripts, styles, the
#: page's title (shown by the browser as plain text).
_VERBATIM = ("code", "pre", "script", "style", "title", "textarea", "kbd", "samp")

_TAG = re.compile(r"(<!--.*?-->|<[^>]*>)", re.DOTALL)
_NAME = re.compile(r"<\s*(/?)\s*([A-Za-z][A-Za-z0-9]*)")


def subscripts(text: str) -> str:
    """Escaped HTML text with each symbol's subscript set as ``<sub>``.

    Examples
    --------
    >>> subscripts("μ_k and x_c [m]; μ_s/μ_k; τ_end")
    'μ<sub>k</sub> and x<sub>c</sub> [m]; μ<sub>s</sub>/μ<sub>k</sub>; τ<sub>end</sub>'
    >>> subscripts("load_N, max_steps, disc_14.9_1")
    'load_N, max_steps, disc_14.9_1'
    """
    return SYMBOL.sub(r"\1<sub>\2</sub>", text)


def subscripts_html(page: str) -> str:
    """An HTML page (or fragment) with :func:`subscripts` applied to its text only:
    tags, attributes, comments and the text of code, preformatted text, scripts, styles
    and the title are left as they are.

    Examples
    --------
    >>> subscripts_html('<p title="μ_k">μ_k = 0.03</p><code>mu_k, x_c</code>')
    '<p title="μ_k">μ<sub>k</sub> = 0.03</p><code>mu_k, x_c</code>'
    """
    out = []
    verbatim: list[str] = []
    for part in _TAG.split(page):
        if part.startswith("<"):
            out.append(part)
            found = _NAME.match(part)
            if found is None or part.endswith("/>"):
                continue
            closing, name = found.group(1), found.group(2).lower()
            if name in _VERBATIM:
                if not closing:
                    verbatim.append(name)
                elif name in verbatim:
                    del verbatim[len(verbatim) - 1 - verbatim[::-1].index(name) :]
        elif part and not verbatim and "_" in part:
            out.append(subscripts(part))
        else:
            out.append(part)
    return "".join(out)


def subscripts_mathtext(text: str) -> str:
    """A figure text with each symbol's subscript in matplotlib's mathtext.

    A text that holds mathtext already (a ``$``) is left as it is.

    Examples
    --------
    >>> subscripts_mathtext("μ_k [-]; x_c [m]")
    'μ$_{k}$ [-]; x$_{c}$ [m]'
    >>> subscripts_mathtext("$x_c$ and load_N")
    '$x_c$ and load_N'
    """
    if "$" in text or "_" not in text:
        return text
    return SYMBOL.sub(r"\1$_{\2}$", text)


def subscripts_figure(fig: Any) -> int:
    """Set the subscripts of every text of ``fig`` in mathtext (:func:`subscripts_mathtext`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    int
        The number of texts rewritten.
    """
    from matplotlib.text import Text

    changed = 0
    for artist in fig.findobj(Text):
        text = artist.get_text()
        new = subscripts_mathtext(text)
        if new != text:
            artist.set_text(new)
            changed += 1
    return changed


#: A subscript set by :func:`subscripts_mathtext`.
_MATHTEXT_SUBSCRIPT = re.compile(r"\$_\{([^\W_]{1,3})\}\$")


def plain_symbols(text: str) -> str:
    """A figure text quoted in prose (a note naming a panel) with its mathtext
    subscripts back in plain text, for the page to set them (:func:`subscripts_html`).

    Examples
    --------
    >>> plain_symbols("empty panel: 'μ$_{k}$ [-]'")
    "empty panel: 'μ_k [-]'"
    """
    return _MATHTEXT_SUBSCRIPT.sub(r"_\1", text)
