"""The live page of ``bayestribo campaign --watch``: each run's answer as it lands.

One self-contained HTML file (no script, nothing fetched) listing every run answered
(its law and the medians and credible intervals of its quantities, or its error), the
runs waiting, and the populations of repeats as last computed. While the watch runs,
the page carries ``<meta http-equiv="refresh">`` so that a browser showing it reloads
it; the last page, written when the watch stops, has none. :func:`status` is the same
state as a small JSON document (``watch.json`` beside the page) for scripts.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from bayestribo._plural import count

__all__ = ["Answer", "PageState", "interval_text", "render_page", "status"]


def _number(value: Any, digits: int = 4) -> str:
    try:
        x = float(value)
    except (TypeError, ValueError):
        return "–"
    return f"{x:.{digits}g}" if math.isfinite(x) else "–"


def interval_text(median: Any, low: Any, high: Any) -> str:
    """``median [low, high]`` with 4 significant digits, or as many more (up to 9) as
    tell the three apart: a run's interval is often narrower than 1e-4 of its median."""
    values = (median, low, high)
    pairs = [(i, j) for i, j in ((0, 1), (0, 2), (1, 2)) if values[i] != values[j]]
    for digits in range(4, 10):
        texts = [_number(v, digits) for v in values]
        if all(texts[i] != texts[j] for i, j in pairs):
            break
    return f"{texts[0]} [{texts[1]}, {texts[2]}]"


def quantity_text(q: dict[str, Any]) -> str:
    """One quantity of an answer: :func:`interval_text`, or ``< high (not constrained
    by the data)`` for one whose posterior is its prior's up to a bound (``bound``: the
    fit's summary of ``kind`` ``"bound"``), as the fit's own table says it."""
    if q.get("bound"):
        return f"< {_number(q['high'], 2)} (not constrained by the data)"
    return interval_text(q["median"], q["low"], q["high"])


@dataclass(frozen=True)
class Answer:
    """One run's answer: its law and quantities, or why it has none.

    Attributes
    ----------
    run : str
        The run's identity.
    path : str
        Its file.
    law : str or None
        The law it was fitted in.
    quantities : dict of str to dict
        Per quantity: ``symbol``, ``unit``, ``median``, ``low``, ``high`` and ``bound``
        (True where the data do not constrain it: ``low`` is its prior's lower end,
        ``high`` the bound).
    converged : bool
        Whether the fit's sampler converged.
    fit_s : float
        Wall time of the fit in the warm worker [s]; nan for a fit read back from the
        catalog.
    cached : bool
        The fit was read back from the catalog (the same data and settings).
    error : str or None
        Why the run has no answer.
    """

    run: str
    path: str
    law: str | None = None
    quantities: dict[str, dict[str, Any]] = field(default_factory=dict)
    converged: bool = True
    fit_s: float = float("nan")
    cached: bool = False
    error: str | None = None

    @property
    def ok(self) -> bool:
        """True when the run has an answer."""
        return self.error is None

    def line(self) -> str:
        """The answer as one line of text: run, law, each quantity as median [low,
        high] with its unit, and the fit's time."""
        if not self.ok:
            return f"FAILED {self.run}: {self.error}"
        parts = [self.run, self.law or "?"]
        for q in self.quantities.values():
            unit = "" if q.get("unit") in (None, "", "1", "-") else f" {q['unit']}"
            parts.append(f"{q['symbol']} {quantity_text(q)}{unit}")
        how = "from the catalog" if self.cached else f"fit {self.fit_s:.2f} s"
        if not self.converged:
            how += ", NOT CONVERGED"
        return "  ".join(parts) + f"  ({how})"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (a nan fit time as None)."""
        fit_s = self.fit_s if math.isfinite(self.fit_s) else None
        return {
            "run": self.run,
            "path": self.path,
            "law": self.law,
            "quantities": self.quantities,
            "converged": self.converged,
            "fit_s": fit_s,
            "cached": self.cached,
            "error": self.error,
        }


@dataclass(frozen=True)
class PageState:
    """What the page shows.

    Attributes
    ----------
    folder : str
        The folder watched.
    state : str
        ``"warming up"``, ``"watching"`` or why the watch stopped.
    prob : float
        Probability of the credible intervals.
    answers : sequence of Answer
        Every run answered, in the order of their answers.
    waiting : sequence of str
        Files seen that are not complete yet, or queued for a fit.
    fitting : sequence of str
        Files being fitted.
    trends : sequence of dict
        The trend rows (:meth:`bayestribo.campaign.analysis.CampaignAnalysis.trend_rows`)
        with each row's ``symbol`` and its series' ``label`` in words.
    report_command : str
        The command that makes the full campaign report of these results.
    populations : sequence of dict
        The population rows (:meth:`bayestribo.campaign.analysis.CampaignAnalysis.group_rows`)
        with each row's ``symbol`` and its group's ``label`` in words; empty before the
        first population.
    population_runs : int
        How many runs the populations were computed from.
    population_note : str
        Why there is no population yet, or what went wrong making it.
    updated_utc : str
        When the page was written (ISO 8601).
    """

    folder: str
    state: str
    prob: float
    answers: Sequence[Answer] = ()
    waiting: Sequence[str] = ()
    fitting: Sequence[str] = ()
    populations: Sequence[Mapping[str, Any]] = ()
    trends: Sequence[Mapping[str, Any]] = ()
    report_command: str = ""
    population_runs: int = 0
    population_note: str = ""
    updated_utc: str = ""


_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 70em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; }
th, td { padding: 0.25em 0.8em; border-bottom: 1px solid #ddd; text-align: left; }
td.num { font-variant-numeric: tabular-nums; white-space: nowrap; }
tr.failed td { color: #a00; }
.state { color: #555; }
"""


def _esc(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _runs_table(answers: Sequence[Answer], prob: float) -> list[str]:
    names = list(dict.fromkeys(n for a in answers for n in a.quantities))
    symbols = {n: q for a in answers for n, q in a.quantities.items()}
    head = "".join(
        f"<th>{_esc(symbols[n]['symbol'])}"
        + (
            ""
            if symbols[n].get("unit") in (None, "", "1", "-")
            else f" [{_esc(symbols[n]['unit'])}]"
        )
        + "</th>"
        for n in names
    )
    out = [
        f"<h2>Runs ({len(answers)})</h2>",
        f"<p>Posterior median [{100 * prob:g} % credible interval] of each run's quantities.</p>",
        f'<table id="runs"><tr><th>run</th><th>law</th>{head}<th>fit</th></tr>',
    ]
    for a in answers:
        if not a.ok:
            out.append(
                f'<tr class="failed" data-run="{_esc(a.run)}"><td>{_esc(a.run)}</td>'
                f'<td colspan="{len(names) + 2}">FAILED: {_esc(a.error)}</td></tr>'
            )
            continue
        cells = "".join(
            f'<td class="num">{_esc(quantity_text(q))}</td>'
            if (q := a.quantities.get(n))
            else "<td></td>"
            for n in names
        )
        how = "catalog" if a.cached else f"{a.fit_s:.2f} s"
        if not a.converged:
            how += ", not converged"
        out.append(
            f'<tr data-run="{_esc(a.run)}"><td>{_esc(a.run)}</td><td>{_esc(a.law or "?")}</td>'
            f"{cells}<td>{_esc(how)}</td></tr>"
        )
    out.append("</table>")
    return out


def _population_table(state: PageState) -> list[str]:
    out = ["<h2>Populations of repeats</h2>"]
    if not state.populations:
        out.append(f"<p>{_esc(state.population_note or 'Not computed yet.')}</p>")
        return out
    out.append(
        f"<p>Computed from {count(state.population_runs, 'fitted run')}: the mean and σ (the "
        f"spread between repeats) of each group, median [{100 * state.prob:g} % interval]."
        + (f" {_esc(state.population_note)}" if state.population_note else "")
        + "</p>"
    )
    out.append(
        '<table id="populations"><tr><th>group</th><th>runs</th><th>quantity</th>'
        "<th>mean</th><th>σ</th></tr>"
    )
    for r in state.populations:
        symbol = r.get("symbol") or r.get("parameter")
        mean = interval_text(r["mean_median"], r["mean_low"], r["mean_high"])
        sigma = interval_text(r["sigma_median"], r["sigma_low"], r["sigma_high"])
        out.append(
            f"<tr><td>{_esc(r.get('label') or r.get('group'))} ({_esc(r.get('kind'))})</td>"
            f"<td>{_esc(r.get('n_runs'))}</td><td>{_esc(symbol)}</td>"
            f'<td class="num">{mean}</td><td class="num">{sigma}</td></tr>'
        )
    out.append("</table>")
    return out


def _trend_table(state: PageState) -> list[str]:
    if not state.trends:
        return []
    out = [
        "<h2>Trends</h2>",
        f"<p>Slope of each quantity against {_esc(state.trends[0].get('covariate'))} per "
        f"series, median [{100 * state.prob:g} % interval], and the probability that it is "
        "positive.</p>",
        '<table id="trends"><tr><th>series</th><th>runs</th><th>quantity</th><th>slope</th>'
        "<th>P(slope &gt; 0)</th></tr>",
    ]
    for r in state.trends:
        slope = interval_text(r["slope_median"], r["slope_low"], r["slope_high"])
        out.append(
            f"<tr><td>{_esc(r.get('label') or r.get('series'))}</td>"
            f"<td>{_esc(r.get('n_runs'))}</td><td>{_esc(r.get('symbol') or r['parameter'])}</td>"
            f'<td class="num">{slope}</td><td class="num">{_number(r["prob_positive"], 3)}</td>'
            "</tr>"
        )
    out.append("</table>")
    return out


def render_page(state: PageState, *, refresh_s: float | None) -> str:
    """The page as HTML text.

    Parameters
    ----------
    state : PageState
    refresh_s : float or None
        Seconds between the reloads of a browser showing the page (a
        ``<meta http-equiv="refresh">``); None for a page that is not reloaded (the
        watch has stopped).
    """
    refresh = "" if refresh_s is None else f'<meta http-equiv="refresh" content="{refresh_s:g}">\n'
    waiting = "".join(
        f"<p>{what}: {_esc(', '.join(files))}</p>"
        for what, files in (("Fitting", state.fitting), ("Waiting for", state.waiting))
        if files
    )
    body = [
        f"<h1>Campaign of {_esc(state.folder)}</h1>",
        f'<p class="state" id="state">{_esc(state.state)}; updated {_esc(state.updated_utc)}</p>',
        waiting,
        *_runs_table(state.answers, state.prob),
        *_population_table(state),
        *_trend_table(state),
        (
            f"<p>The full campaign report (figures, each run's fit): "
            f"<code>{_esc(state.report_command)}</code></p>"
            if state.report_command
            else ""
        ),
    ]
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"{refresh}<title>bayestribo campaign: {_esc(state.folder)}</title>\n"
        f"<style>{_STYLE}</style>\n</head>\n<body>\n"
        + "\n".join(b for b in body if b)
        + "\n</body>\n</html>\n"
    )


def status(state: PageState) -> dict[str, Any]:
    """The page's state as a JSON-ready dict (``watch.json``)."""
    return {
        "folder": state.folder,
        "state": state.state,
        "updated_utc": state.updated_utc,
        "prob": state.prob,
        "answers": [a.to_dict() for a in state.answers],
        "waiting": list(state.waiting),
        "fitting": list(state.fitting),
        "population_runs": state.population_runs,
        "population_note": state.population_note,
    }
