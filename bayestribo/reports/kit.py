"""What every report notebook does the same way: figures, notes, the report's header.

Called from the notebooks' first code cell::

    from bayestribo.reports import kit

    save = kit.setup(figure_dir, figure_format)

:func:`setup` sets the figures' look, turns warnings into short notes in the text
(not red stderr boxes) and returns the function that writes a figure to
``figure_dir`` in ``figure_format`` (PNG, or PDF/SVG as vector graphics for a paper).
:func:`note` writes a remark; :func:`about` the table of what a report is about (the
run's metadata, the file's SHA-256, the bayestribo version, when it was made);
:func:`heading` a heading; :func:`page_title` what the page is about (its title).

Every one of them escapes the strings it is given (a file name, a lubricant, a sidecar's
field may hold markup: :mod:`bayestribo.reports.safety`); a notebook that writes its own
Markdown puts a name in it with :func:`markdown_text`.
"""

from __future__ import annotations

import hashlib
import html
import json
import platform
import re
import warnings
from collections.abc import Callable, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from bayestribo._files import atomic_file, write_text
from bayestribo._plural import count
from bayestribo.reports._errors import ReportError
from bayestribo.reports.html import NOTE_CLASS, PAGE_MIME
from bayestribo.reports.safety import markdown_text

__all__ = [
    "FIGURE_FORMATS",
    "FIGURE_PROBLEMS",
    "about",
    "checks",
    "count",
    "empty_panels",
    "facts",
    "figure_alt",
    "file_sha256",
    "folder_text",
    "heading",
    "interval_text",
    "keep_together",
    "markdown_text",
    "note",
    "overlapping_labels",
    "page_title",
    "sentence",
    "setup",
    "show_warnings_as_notes",
    "small_texts",
    "table",
    "verdict",
    "write_summary",
]

#: Formats a report's figures can be written in (``--figure-format``).
FIGURE_FORMATS = ("png", "pdf", "svg")

#: What :func:`setup`'s ``save`` says in a note about a figure that is not legible, one
#: phrase per kind of problem (the browser's probe looks for them in the notes).
FIGURE_PROBLEMS = ("labels overlap", "empty panel", "text below 8 pt")

#: Smallest font size of a figure's texts at the size it is saved (print size) [pt].
MIN_FONT_PT = 8.0

#: Largest |value| of an axis on which every value counts as zero: a panel whose data all
#: lie within it shows nothing (a friction of 1e-14 where the law has no friction).
ZERO = 1e-12

#: The figures' look in every report.
RC = {
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "font.size": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "pdf.fonttype": 42,  # TrueType in PDF: text stays text for a journal
    "svg.fonttype": "path",
}


def interval_text(mean: float, low: float, high: float) -> str:
    """``mean [low, high]`` with the digits the interval supports
    (:func:`bayestribo.summary.interval_text`, shared with the figures' titles).

    Examples
    --------
    >>> interval_text(0.0236012, 0.0236003, 0.0236021)
    '0.02360120 [0.02360030, 0.02360210]'
    >>> interval_text(1.2e-30, 0.0, 3e-29)
    '< 1e-9'
    >>> interval_text(1.1e-4, 0.0, 3.1e-4)
    '0 (at the bound) [0, 0.00031]'
    """
    from bayestribo.summary import interval_text as shared

    return shared(mean, low, high)


def folder_text(path: str | Path | None, label: str | None = None) -> str | None:
    """A folder as a report names it: ``label`` (as the user typed it) or its path; one
    under the system's temporary directory by its name only, said to be temporary (a
    reader of the report cannot open ``/tmp/pytest-7/...``). None for no folder.

    Examples
    --------
    >>> import tempfile, os
    >>> folder_text(os.path.join(tempfile.gettempdir(), "x1", "results"))
    'results (a temporary folder)'
    >>> folder_text("/data/campaign", "campaign/")
    'campaign/'
    """
    import tempfile

    if path is None and label is None:
        return None
    shown = str(label if label is not None else path)
    where = Path(path if path is not None else shown).expanduser().resolve()
    if where.is_relative_to(Path(tempfile.gettempdir()).resolve()):
        return f"{where.name} (a temporary folder)"
    return shown


def sentence(text: str) -> str:
    """``text`` as a sentence: a capital first letter where the first letter is Latin
    (a Greek symbol stays as it is: "ζ and μ_k are constant", not "Ζ and ..."), and one
    full stop at the end.

    Examples
    --------
    >>> sentence("ζ and μ_k are constant.")
    'ζ and μ_k are constant.'
    >>> sentence("the end of motion agrees")
    'The end of motion agrees.'
    """
    text = text.strip().rstrip(".")
    if text[:1].isascii():
        text = text[:1].upper() + text[1:]
    return text + "."


def _display(obj: Any) -> None:
    from IPython.display import display

    display(obj)


def note(text: str) -> None:
    """Show ``text`` as a short note in the report (a remark, a warning), in words
    (:func:`bayestribo.reports.tables.prose`: laws and column names as a reader names
    them)."""
    from IPython.display import HTML

    from bayestribo.reports.tables import prose

    said = html.escape(prose(str(text)))
    _display(HTML(f'<div class="{NOTE_CLASS}"><b>Note.</b> {said}</div>'))


def verdict(text: str) -> None:
    """Show a conclusion as a sentence of its own, in bold."""
    from IPython.display import HTML

    _display(HTML(f'<p class="bt-verdict">{html.escape(str(text))}</p>'))


def table(frame: Any, *, digits: int = 5) -> None:
    """Show a pandas DataFrame as a table: numbers to ``digits`` significant digits,
    missing values as a dash (not NaN), the index's name in the header's corner (not on
    a header row of its own), and a cell that is a number or a value with its interval
    kept on one line (:func:`keep_together`): the table's words wrap, its numbers never
    break ("-3.511e- / 05")."""
    from IPython.display import HTML

    if frame.index.name is not None and frame.columns.name is None and frame.columns.nlevels == 1:
        frame = frame.rename_axis(index=None, columns=frame.index.name)

    def cell(value: Any) -> Any:
        if isinstance(value, float) and value != value:
            return value  # NaN: a dash (na_rep)
        if isinstance(value, float):
            value = f"{value:.{digits}g}"
        return keep_together(value) if isinstance(value, str) else value

    frame = _escaped_labels(frame.apply(lambda col: col.map(cell)))
    _display(HTML(frame.to_html(na_rep="–", escape=False, border=0)))


def _escaped_labels(frame: Any) -> Any:
    """``frame`` with its column and index labels and their names escaped for HTML (the
    table is written with ``escape=False`` for its cells' spans, which pandas applies to
    the labels too: a run or a lubricant named ``<script>`` would be markup)."""

    def label(value: Any) -> Any:
        return (
            _unbroken_numbers(html.escape(value, quote=False)) if isinstance(value, str) else value
        )

    frame = frame.rename(index=label, columns=label)
    frame.index = frame.index.set_names([label(n) for n in frame.index.names])
    frame.columns = frame.columns.set_names([label(n) for n in frame.columns.names])
    return frame


def heading(text: str, level: int = 3) -> None:
    """Show ``text`` (a run's name, a file's) as a heading of ``level`` (2 to 6), as text:
    its markup and Markdown marks escaped.

    Raises
    ------
    ReportError
        If ``level`` is not 2 to 6 (a report has one title, its first cell's).
    """
    from IPython.display import Markdown

    if not isinstance(level, int) or not 2 <= level <= 6:
        raise ReportError(f"level: expected an integer from 2 to 6, got {level!r}")
    _display(Markdown(f"{'#' * level} {markdown_text(text)}"))


def page_title(subject: str) -> None:
    """Say what the page is about (a run's name, a campaign's folder): the page's title
    is ``"<subject> – <the report's title>"`` (:func:`bayestribo.reports.html.page_facts`).
    Nothing is shown."""
    from IPython.display import display

    display({PAGE_MIME: {"subject": str(subject)}}, raw=True)


#: A cell that is a number or a value with its interval ("0.0243 [0.0241, 0.0245]",
#: "< 1e-9", "0.0236 ± 0.0012", "0 (at the bound) [0, 8.2e-05]").
_NUMERIC = re.compile(r"^[-+0-9.eE−–,;\[\]<>≤±% ]+$|^0 \(at the bound\) \[")


#: A number in words that a line may break inside: at the sign of its exponent
#: ("2.45e-05") or after its leading minus.
_BREAKABLE_NUMBER = re.compile(r"(?<![\w.])-?\d[\d.]*[eE][-+]?\d+|(?<![\w.])-\d[\d.]*")


def _unbroken_numbers(text: str) -> str:
    """Escaped text (a table's row or column label, "ΔE(A = 2.45e-05 m), law") with each
    number that could break across lines in a span that does not wrap (``bt-num``).

    Examples
    --------
    >>> _unbroken_numbers("ΔE(A = 2.45e-05 m), law")
    'ΔE(A = <span class="bt-num">2.45e-05</span> m), law'
    >>> _unbroken_numbers("N = 0.12 N, run-2")
    'N = 0.12 N, run-2'
    """
    return _BREAKABLE_NUMBER.sub(lambda m: f'<span class="bt-num">{m.group(0)}</span>', text)


def keep_together(text: str) -> str:
    """A cell's text as HTML: escaped, and a number or a value with its interval in a
    span that does not wrap (class ``bt-num``); in a cell of words, each number that could
    break at its exponent's sign or its minus (:func:`_unbroken_numbers`).

    Examples
    --------
    >>> keep_together("-3.58e-05 [-3.65e-05, -3.51e-05]")
    '<span class="bt-num">-3.58e-05 [-3.65e-05, -3.51e-05]</span>'
    >>> keep_together("ignores friction: ζ < μ")
    'ignores friction: ζ &lt; μ'
    >>> keep_together("0.0007568 (± 3e-05, too narrow)")
    '0.0007568 (± <span class="bt-num">3e-05</span>, too narrow)'
    """
    escaped = html.escape(text, quote=False)
    if _NUMERIC.match(text):
        return f'<span class="bt-num">{escaped}</span>'
    return _unbroken_numbers(escaped)


def _warning_as_note(message, category, filename, lineno, file=None, line=None) -> None:
    text = str(message).strip().splitlines()[0] if str(message).strip() else category.__name__
    if not category.__module__.startswith("bayestribo"):
        text = f"{category.__name__}: {text}"
    note(text)


def show_warnings_as_notes() -> None:
    """Every warning from now on is shown once as a note in the output, not on stderr."""
    warnings.showwarning = _warning_as_note
    warnings.simplefilter("default")  # each distinct warning once per location
    warnings.filterwarnings("ignore", category=FutureWarning)  # libraries' announcements
    warnings.filterwarnings("ignore", category=DeprecationWarning)


def figure_alt(fig: Any, description: str | None = None) -> None:
    """Show ``fig`` in the report with ``description`` as its alt text (default: what its
    own texts say it shows, :func:`bayestribo.reports.alt.figure_description`), and close
    it (the inline backend would show it a second time, without one)."""
    import matplotlib.pyplot as plt
    from IPython import get_ipython
    from IPython.display import publish_display_data

    from bayestribo.reports.alt import figure_description

    shell = get_ipython()
    if shell is None:  # not in a kernel: nothing to show
        return
    said = description or figure_description(fig)
    data, metadata = shell.display_formatter.format(fig)
    for mime in ("image/png", "image/jpeg", "image/svg+xml"):
        if mime in data:
            metadata[mime] = {**metadata.get(mime, {}), "alt": said}
    publish_display_data(data, metadata)
    plt.close(fig)


def setup(figure_dir: str | None, figure_format: str = "png") -> Callable[..., Path | None]:
    """Figures' look, warnings as notes; the function that writes a figure.

    Parameters
    ----------
    figure_dir : str or None
        Folder the figures are written to (created); None writes none.
    figure_format : {"png", "pdf", "svg"}
        File format of the written figures (the report itself embeds PNG).

    Returns
    -------
    callable
        ``save(fig, name, description=None)``: writes
        ``<figure_dir>/<name>.<figure_format>`` (nothing without ``figure_dir``) and
        shows the figure with ``description`` as its alt text (default: what its texts
        say it shows); it returns None, so a cell ending with it shows only the figure.

    Raises
    ------
    ReportError
        If ``figure_format`` is not one of :data:`FIGURE_FORMATS`.
    """
    import matplotlib.pyplot as plt

    if figure_format not in FIGURE_FORMATS:
        raise ReportError(f"figure_format: expected one of {FIGURE_FORMATS}, got {figure_format!r}")
    plt.rcParams.update(RC)
    try:  # the figures in the HTML at twice the screen's resolution (200 dpi)
        from matplotlib_inline.backend_inline import set_matplotlib_formats

        set_matplotlib_formats("retina")
    except ImportError:  # pragma: no cover - comes with ipykernel (the report extra)
        pass
    show_warnings_as_notes()
    try:
        import pandas as pd

        pd.set_option("display.float_format", lambda v: f"{v:.5g}")
    except ImportError:  # pragma: no cover - pandas comes with the report extra
        pass
    folder = Path(figure_dir) if figure_dir else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)

    def save(fig: Any, name: str, description: str | None = None) -> None:
        """Write ``fig`` as ``<name>.<format>`` in the figure folder (if any), and show it
        with ``description`` (default: its own texts, in words) as its alt text.

        Texts that overlap, panels with nothing to show and texts smaller than
        :data:`MIN_FONT_PT` are said in a note (the report's tests and the browser's
        probe require none). Symbols' subscripts are set as subscripts first
        (:func:`bayestribo.reports.symbols.subscripts_figure`: ``μ_k`` as ``μ$_{k}$``).
        """
        from bayestribo.reports.alt import figure_description
        from bayestribo.reports.symbols import plain_symbols, subscripts_figure

        said = description or figure_description(fig)
        subscripts_figure(fig)
        for problem, found in zip(
            FIGURE_PROBLEMS,
            (overlapping_labels(fig), empty_panels(fig), small_texts(fig)),
            strict=True,
        ):
            if found:
                note(plain_symbols(f"figure {name}: {problem}: {'; '.join(found[:3])}"))
        if folder is not None:
            with atomic_file(folder / f"{name}.{figure_format}", "wb") as fh:
                fig.savefig(fh, format=figure_format, bbox_inches="tight")
        figure_alt(fig, said)

    return save


def _where(ax: Any) -> str:
    """A panel's name for a message: its title or an axis label."""
    return ax.get_title() or ax.get_xlabel() or ax.get_ylabel() or "an axes"


def _panels(fig: Any) -> list[Any]:
    """The axes of ``fig`` drawn as panels: visible, with their axes and frame on (a
    corner plot's blank upper triangle and an axes holding only a legend are not)."""
    return [ax for ax in fig.axes if ax.get_visible() and ax.axison and ax.get_frame_on()]


def empty_panels(fig: Any) -> list[str]:
    """Panels of ``fig`` with nothing to show: no data artist (line, marker, patch,
    collection, image), no finite data, or every value of an axis zero (within
    :data:`ZERO` on a linear axis: a friction panel at 1e-14 where the law has none).

    Returns
    -------
    list of str
        ``"'title': no data"`` or ``"'title': every y value is zero"`` for each empty
        panel; empty if none.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, (a, b) = plt.subplots(1, 2)
    >>> _ = a.plot([0, 1], [0, 1]); _ = b.set_title("friction")
    >>> empty_panels(fig)
    ["'friction': no data"]
    >>> plt.close(fig)
    """
    import math

    found = []
    for ax in _panels(fig):
        where = _where(ax)
        if not ax.has_data():
            found.append(f"{where!r}: no data")
            continue
        limits = {"x": ax.dataLim.intervalx, "y": ax.dataLim.intervaly}
        finite = {k: all(math.isfinite(v) for v in lim) for k, lim in limits.items()}
        if not any(finite.values()):
            found.append(f"{where!r}: no finite data")
            continue
        scales = {"x": ax.get_xscale(), "y": ax.get_yscale()}
        for name, lim in limits.items():
            if finite[name] and scales[name] == "linear" and max(map(abs, lim)) <= ZERO:
                found.append(f"{where!r}: every {name} value is zero")
    return found


def small_texts(fig: Any, minimum: float = MIN_FONT_PT) -> list[str]:
    """Texts of ``fig`` drawn smaller than ``minimum`` points at the figure's own size
    (the size it is saved and printed at): tick and axis labels, titles, legends, texts
    placed in the axes, a colour bar's labels.

    Returns
    -------
    list of str
        ``"'run-7' (6.5 pt)"`` for each distinct small text; empty if none.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> _ = ax.set_yticks([0, 1], ["run-1", "run-2"], fontsize=6.5)
    >>> small_texts(fig)
    ["'run-1' (6.5 pt)", "'run-2' (6.5 pt)"]
    >>> plt.close(fig)
    """
    from matplotlib.text import Text

    found = []
    for t in fig.findobj(Text):
        if not (t.get_visible() and t.get_text().strip()) or t.figure is None:
            continue
        if t.axes is not None and not t.axes.get_visible():
            continue  # not drawn (a corner plot's blank upper triangle)
        size = t.get_fontsize()
        said = f"{t.get_text()!r} ({size:g} pt)"
        if size < minimum - 1e-9 and said not in found:
            found.append(said)
    return found


def _texts(fig: Any) -> list[tuple[str, Any]]:
    """Every visible, non-empty text of ``fig`` with a description of where it is."""
    out = []
    suptitle = getattr(fig, "_suptitle", None)
    if suptitle is not None:
        out.append(("the figure's title", suptitle))
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        where = _where(ax)
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            # the ticks drawn: those within the view (labels of ticks outside it are
            # laid out but not drawn)
            low, high = sorted(axis.get_view_interval())
            span = 1e-9 * (abs(low) + abs(high))
            out += [
                (f"{name} tick of {where!r}", tick.label1)
                for tick, loc in zip(axis.get_major_ticks(), axis.get_majorticklocs(), strict=False)
                if low - span <= loc <= high + span
            ]
            out.append((f"{name} label of {where!r}", axis.label))
            out.append((f"{name} offset of {where!r}", axis.get_offset_text()))
        for title in (ax.title, ax._left_title, ax._right_title):
            out.append((f"title of {where!r}", title))
        out += [(f"text in {where!r}", t) for t in ax.texts]
    return [(w, t) for w, t in out if t.get_visible() and t.get_text().strip()]


def overlapping_labels(fig: Any) -> list[str]:
    """Texts of ``fig`` that overlap each other, as drawn: tick labels, axis labels and
    offsets, titles, the figure's title and texts placed in the axes.

    Every pair is compared by its rendered box, shrunk by a pixel so that texts merely
    touching pass (a corner plot's title running into the panel above, a y label over
    the tick labels of its neighbour, two crowded tick labels).

    Returns
    -------
    list of str
        ``"'a' (x tick of 'title') and 'b' (y label of ...)"`` for each overlapping
        pair; empty if none.
    """
    # the layout of a draw without its pixels: the same boxes as a full draw (same
    # renderer and dpi) at a quarter of its time; the figure is rasterised later, once
    # for its file and once for the page
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    boxes = [(w, t, t.get_window_extent(renderer)) for w, t in _texts(fig)]
    found = []
    for i, (wa, a, ba) in enumerate(boxes):
        for wb, b, bb in boxes[i + 1 :]:
            if (
                ba.x1 - 1 > bb.x0 + 1
                and bb.x1 - 1 > ba.x0 + 1
                and ba.y1 - 1 > bb.y0 + 1
                and bb.y1 - 1 > ba.y0 + 1
            ):
                found.append(f"{a.get_text()!r} ({wa}) and {b.get_text()!r} ({wb})")
    return found


def write_summary(path: str | Path, record: Mapping[str, Any]) -> Path:
    """Write a report's summary as JSON, whole or not at all (its folder is created).

    Parameters
    ----------
    path : str or Path
        The ``.json`` file (a report's ``summary_path``).
    record : mapping
        The summary; a value JSON cannot hold is written as its text (``str``).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_text(path, json.dumps(record, indent=2, default=str))


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file, hexadecimal."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, Mapping):
        return ", ".join(f"{k}: {_cell(v)}" for k, v in value.items())
    return str(value)


def facts(items: Mapping[str, Any], *, title: str) -> None:
    """Show label -> value as a two-column table with a caption; None values left out."""
    from IPython.display import HTML

    body = "".join(
        f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(_cell(v))}</td></tr>"
        for k, v in items.items()
        if v is not None
    )
    _display(HTML(f'<table class="bt-about"><caption>{html.escape(title)}</caption>{body}</table>'))


def checks(adequacy: Any) -> None:
    """Show an adequacy check's checks, each passed or failed with its statement, then
    its verdict in a sentence of its own (``Verdict: ... .``) and, where the check states
    it (``level_text``), the verdict's false-alarm rate on a record of the law."""
    from IPython.display import Markdown

    mark = {True: "passed", False: "**failed**", None: "not run"}
    _display(
        Markdown(
            "\n".join(
                f"* **{sentence(c['name'])[:-1]}**: {mark[c['passed']]}. "
                f"{sentence(c['statement'].removeprefix('not run: '))}"
                for c in adequacy.checks
            )
        )
    )
    verdict("Verdict: " + adequacy.verdict + ".")
    level = getattr(adequacy, "level_text", None)
    if level:
        _display(Markdown(sentence(level)))


def about(items: Mapping[str, Any], *, title: str = "About this report") -> None:
    """Show what the report is about as a two-column table, with the bayestribo version.

    Parameters
    ----------
    items : mapping
        Label -> value (the run's file and metadata, the campaign's settings...);
        None values are left out.
    title : str
        Caption of the table.
    """
    from bayestribo import __version__

    rows = {
        **items,
        "bayestribo version": __version__,
        "Python": platform.python_version(),
        "report made": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
    }
    facts(rows, title=title)
