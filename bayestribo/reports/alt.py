"""Words for what a reader cannot see: the alt text of equations and figures.

:func:`tex_words` turns an equation's TeX into the text a screen reader can speak and a
reader without images can read (``\\mu_k`` -> ``μ_k``, ``\\sqrt{km}`` -> ``√(km)``,
``\\Delta E(A)`` -> ``ΔE(A)``). :func:`figure_description` says what a figure shows from
its own texts: its title, each panel's title, axes and curves.
"""

from __future__ import annotations

import re
from typing import Any

__all__ = ["figure_description", "tex_words"]

_GREEK = {
    "alpha": "α", "beta": "β", "gamma": "γ", "delta": "δ", "epsilon": "ε",
    "varepsilon": "ε", "zeta": "ζ", "eta": "η", "theta": "θ", "vartheta": "ϑ",
    "iota": "ι", "kappa": "κ", "lambda": "λ", "mu": "μ", "nu": "ν", "xi": "ξ",
    "pi": "π", "rho": "ρ", "sigma": "σ", "tau": "τ", "upsilon": "υ", "phi": "φ",
    "varphi": "φ", "chi": "χ", "psi": "ψ", "omega": "ω", "Gamma": "Γ", "Delta": "Δ",
    "Theta": "Θ", "Lambda": "Λ", "Xi": "Ξ", "Pi": "Π", "Sigma": "Σ", "Phi": "Φ",
    "Psi": "Ψ", "Omega": "Ω", "ell": "ℓ",
}  # fmt: skip

_SYMBOLS = {
    "cdot": "·", "times": "×", "pm": "±", "mp": "∓", "le": "≤", "leq": "≤", "ge": "≥",
    "geq": "≥", "ne": "≠", "neq": "≠", "approx": "≈", "sim": "~", "propto": "∝",
    "infty": "∞", "to": "→", "rightarrow": "→", "leftarrow": "←", "partial": "∂",
    "nabla": "∇", "sum": "∑", "prod": "∏", "int": "∫", "in": "∈", "circ": "°",
    "degree": "°", "prime": "′", "ldots": "…", "dots": "…", "cdots": "⋯", "langle": "⟨",
    "rangle": "⟩", "lvert": "|", "rvert": "|", "vert": "|", "mid": "|",
}  # fmt: skip

#: Spacing commands, read as one space.
_SPACES = ("qquad", "quad", ",", ";", ":", "!", " ", "enspace", "thinspace")

#: Commands whose argument is read as it is (fonts, text, operators' names).
_AS_IS = ("mathrm", "mathit", "mathbf", "mathsf", "mathtt", "mathcal", "text", "textrm",
          "operatorname", "boldsymbol", "mathnormal")  # fmt: skip

_SUPERSCRIPTS = str.maketrans("0123456789+-−()n", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻⁻⁽⁾ⁿ")


def _group(tex: str, i: int) -> tuple[str, int]:
    """The argument starting at ``tex[i]``: a braced group or one character."""
    while i < len(tex) and tex[i] == " ":
        i += 1
    if i >= len(tex):
        return "", i
    if tex[i] != "{":
        if tex[i] == "\\":
            m = re.match(r"\\([A-Za-z]+|.)", tex[i:])
            assert m is not None
            return m.group(0), i + len(m.group(0))
        return tex[i], i + 1
    depth = 0
    for j in range(i, len(tex)):
        depth += {"{": 1, "}": -1}.get(tex[j], 0)
        if depth == 0:
            return tex[i + 1 : j], j + 1
    return tex[i + 1 :], len(tex)


def _wrap(words: str) -> str:
    """``words`` in parentheses where it is more than one symbol."""
    return words if len(words) <= 1 or words.isalnum() else f"({words})"


def tex_words(tex: str) -> str:
    """An equation's TeX as readable text: Greek letters and operators in Unicode,
    fonts and spacing dropped, fractions and roots written out, a numeric superscript
    raised (``^2`` -> ``²``), a subscript kept as ``_`` (``\\mu_k`` -> ``μ_k``).

    Examples
    --------
    >>> tex_words(r"\\mu_k")
    'μ_k'
    >>> tex_words(r"d_k = 2\\zeta_k\\sqrt{km}/N")
    'd_k = 2ζ_k√(km)/N'
    >>> tex_words(r"y'' + 2\\zeta\\,y' + y = -\\mu_k\\,\\mathrm{sgn}(y')")
    "y'' + 2ζ y' + y = -μ_k sgn(y')"
    >>> tex_words(r"\\frac{1}{2} k A^{2}")
    '1/2 k A²'
    """
    out: list[str] = []
    i = 0
    while i < len(tex):
        c = tex[i]
        if c == "\\":
            m = re.match(r"\\([A-Za-z]+|.)", tex[i:])
            assert m is not None
            name, i = m.group(1), i + len(m.group(0))
            if name.isalpha():  # TeX ends a command's name at the spaces after it
                j = i
                while j < len(tex) and tex[j] == " ":
                    j += 1
                if j < len(tex) and tex[j].isalnum():  # "\Delta E": one symbol
                    i = j
            if name in _GREEK:
                out.append(_GREEK[name])
            elif name in _SYMBOLS:
                out.append(f" {_SYMBOLS[name]} " if name in ("le", "leq", "ge", "geq", "approx",
                                                             "ne", "neq", "propto", "to")
                           else _SYMBOLS[name])  # fmt: skip
            elif name in _SPACES:
                out.append(" ")
            elif name in _AS_IS:
                arg, i = _group(tex, i)
                out.append(tex_words(arg))
            elif name in ("frac", "dfrac", "tfrac"):
                num, i = _group(tex, i)
                den, i = _group(tex, i)
                out.append(f"{_wrap(tex_words(num))}/{_wrap(tex_words(den))}")
            elif name == "sqrt":
                arg, i = _group(tex, i)
                out.append(f"√({tex_words(arg)})")
            elif name in ("left", "right", "big", "Big", "bigg", "Bigg", "displaystyle"):
                continue
            elif name in ("{", "}", "$", "%", "&", "#", "_"):
                out.append(name)
            else:
                out.append(name)  # an operator's name (sin, log, exp) or a word
        elif c in "^_":
            arg, i = _group(tex, i + 1)
            words = tex_words(arg)
            if c == "^" and words and all(ch in "0123456789+-−()n" for ch in words):
                out.append(words.translate(_SUPERSCRIPTS))
            else:
                out.append(f"{c}{words}" if len(words) <= 1 else f"{c}{{{words}}}"
                           if c == "^" else f"_{words}")  # fmt: skip
        elif c in "{}":
            i += 1
        elif c == "~":
            out.append(" ")
            i += 1
        else:
            out.append(c)
            i += 1
    return re.sub(r" {2,}", " ", "".join(out)).strip()


def _plain(text: str) -> str:
    """A figure's text without mathtext markup: ``$\\mu_k$`` -> ``μ_k``."""
    return re.sub(r"\$([^$]+)\$", lambda m: tex_words(m.group(1)), text).strip()


def figure_description(fig: Any, *, limit: int = 600) -> str:
    """What a matplotlib figure shows, in words, from its own texts: its title, then for
    each panel its title, its axes' labels and its curves' legend labels.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    limit : int
        Longest description [characters]; a longer one ends with "…".

    Returns
    -------
    str
        E.g. ``"Figure: run-1: signals. Panel 'displacement': x: time t [s]; y:
        displacement x [mm]."``; ``"Figure."`` for a figure without any text.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> _ = ax.plot([0, 1], [0, 1], label="the law's $\\\\Delta E(A)$")
    >>> _ = ax.set(title="energy lost per cycle", xlabel="swing A [m]", ylabel="ΔE [J]")
    >>> _ = ax.legend()
    >>> figure_description(fig)
    "Figure: energy lost per cycle: x: swing A [m]; y: ΔE [J]; showing the law's ΔE(A)."
    >>> plt.close(fig)
    """
    parts = []
    suptitle = getattr(fig, "_suptitle", None)
    head = _plain(suptitle.get_text()) if suptitle is not None else ""
    panels = [
        ax
        for ax in fig.axes
        if ax.get_visible() and ax.axison and ax.get_frame_on() and ax.has_data()
    ]
    for ax in panels:
        title = " ".join(
            _plain(t.get_text()) for t in (ax._left_title, ax.title, ax._right_title)
        ).strip()
        said = []
        for name, label in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())):
            if label.strip():
                said.append(f"{name}: {_plain(label).replace(chr(10), ' ')}")
        legend = ax.get_legend()
        if legend is not None:
            labels = [_plain(t.get_text()) for t in legend.get_texts() if t.get_text().strip()]
            if labels:
                said.append("showing " + ", ".join(labels))
        text = "; ".join(said)
        if title and text:
            parts.append(f"{title}: {text}")
        elif title or text:
            parts.append(title or text)
    if len(panels) > 1:
        body = f"{len(panels)} panels. " + ". ".join(
            f"Panel {k}, {p}" for k, p in enumerate(parts, start=1)
        )
    else:
        body = ". ".join(parts)
    words = "Figure" + (f": {head}" if head else "") + (f": {body}" if body else "")
    words = re.sub(r"\s+", " ", words).strip().rstrip(".") + "."
    return words if len(words) <= limit else words[: limit - 1].rstrip() + "…"
