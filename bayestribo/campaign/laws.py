"""One law per group of repeats, chosen jointly from the runs' law comparisons.

``bayestribo campaign DIR --law auto`` fits every run with ``law="auto"``
(:mod:`bayestribo.inference.comparison`): each run compares the candidate laws by
PSIS-LOO and keeps a verdict. Repeats of one condition share their physics, so their
law is chosen from all of them: the expected log predictive densities add over
independent runs, so a group's elpd of a law is the sum over its runs,

    elpd_G(L) = Σ_r elpd_r(L),

and the group's law is chosen by the rule each run's comparison uses: the best law is
the one of highest elpd_G; the verdict is the simplest law (fewest sampled
parameters, then the registry's order) whose elpd_G is within the larger of
:data:`~bayestribo.inference.choice.SMALL_ELPD_DIFFERENCE` and two standard errors
of the difference of the best's. The standard error of a difference in one run is
that run's ``dse`` of each law against its own best, combined as independent
(√(dse_L² + dse_best²), an upper bound of the paired one), and summed in quadrature
over the runs.

A law a run did not sample is taken at the elpd of the nested law it reduced to at
its optimum (``equivalent``), which it equals there; a law a run settled at its
optimum (not sampled: it could not change that run's choice,
:mod:`bayestribo.inference.settling`) at the run's best elpd less its difference
estimated there, with that estimate's sd; a law a run left out otherwise
(screened out as unable to win, or failed) cannot be the group's: only laws with an
elpd in every run of the group are compared. Where no law has one (runs compared on
disjoint candidates), the group keeps the law most of its runs chose, and says so.

The runs whose own verdict is another law are named: they are fitted again in the
group's law, so that a population holds runs of one law.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["GroupLaw", "choose_group_law", "comparison_digest"]


@dataclass(frozen=True)
class GroupLaw:
    """The law of one group of repeats.

    Attributes
    ----------
    group : str
        The group's label (``lubricant=oil,load_N=0.3``).
    runs : tuple of str
        Its runs.
    law : str
        The group's law.
    best : str or None
        The law of highest summed elpd (None when none had an elpd in every run).
    verdicts : dict of str to str
        Each run's own verdict.
    disagree : tuple of str
        The runs whose own verdict is not the group's law.
    table : dict of str to dict
        Per law compared in every run: ``elpd`` (summed), ``elpd_diff`` (to the best),
        ``dse`` (its standard error), ``n_parameters``.
    decided : bool
        False when no law had an elpd in every run (the majority's verdict is kept).
    adequate : bool
        Whether the group's law holds in every run (no misfit at its optimum; the
        runs' comparisons say which laws hold).
    """

    group: str
    runs: tuple[str, ...]
    law: str
    best: str | None
    verdicts: dict[str, str]
    disagree: tuple[str, ...]
    table: dict[str, dict[str, Any]] = field(default_factory=dict)
    decided: bool = True
    adequate: bool = True

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {
            "group": self.group,
            "runs": list(self.runs),
            "law": self.law,
            "best": self.best,
            "verdicts": dict(self.verdicts),
            "disagree": list(self.disagree),
            "table": self.table,
            "decided": self.decided,
            "adequate": self.adequate,
        }


def comparison_digest(comparison: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """What the joint choice needs of one run's law comparison (its ``to_dict``):
    verdict, adequacy, equivalences and per law its elpd and dse (a law settled at its
    optimum: its estimate there against the run's best)."""
    if not comparison:
        return None
    table = {}
    for law, row in (comparison.get("table") or {}).items():
        table[law] = {
            "elpd_loo": _number(row.get("elpd_loo")),
            "dse": _number(row.get("dse")),
            "sampled": bool(row.get("sampled", row.get("elpd_loo") is not None)),
            "adequate": bool(row.get("adequate", True)),
            "reduces_to": row.get("reduces_to"),
        }
        settle = row.get("settle") if row.get("settled") else None
        if settle:
            table[law]["settled"] = True
            table[law]["settle"] = {k: settle.get(k) for k in ("best", "elpd_diff", "dse")}
    return {
        "verdict": comparison.get("verdict"),
        "best": comparison.get("best"),
        "adequate": bool(comparison.get("adequate", True)),
        "equivalent": dict(comparison.get("equivalent") or {}),
        "table": table,
    }


def _number(value: Any) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return out if math.isfinite(out) else None


def _elpd(comparison: Mapping[str, Any], law: str) -> tuple[float, float, bool] | None:
    """(elpd, dse against the run's best, adequate) of ``law`` in one run, through the
    nested law it reduced to."""
    table = comparison.get("table") or {}
    row = table.get(law) or {}
    adequate = bool(row.get("adequate", True))
    settle = row.get("settle") or {}
    if row.get("elpd_loo") is None and settle.get("best") in table:
        # settled at its optimum: the run's best less the difference estimated there
        best = _number((table.get(settle["best"]) or {}).get("elpd_loo"))
        diff, dse = _number(settle.get("elpd_diff")), _number(settle.get("dse"))
        if best is not None and diff is not None:
            return best - diff, dse or 0.0, adequate
    if row.get("elpd_loo") is None:
        nested = (comparison.get("equivalent") or {}).get(law) or row.get("reduces_to")
        row = (table.get(nested) or {}) if nested else {}
    if row.get("elpd_loo") is None:
        return None
    return float(row["elpd_loo"]), float(row.get("dse") or 0.0), adequate


def _n_parameters(law: str) -> int:
    from bayestribo.model.laws import get_law

    try:
        return len(get_law(law).parameter_names)
    except (KeyError, ValueError):
        return 10**6


def _order(law: str) -> tuple[int, ...]:
    """The registry's order of a law's terms (ties of complexity)."""
    from bayestribo.model.laws import get_law
    from bayestribo.model.laws.base import TERMS

    names = list(TERMS)
    try:
        return tuple(names.index(t) for t in get_law(law).term_names)
    except (KeyError, ValueError):
        return (len(names),)


def choose_group_law(
    group: str,
    comparisons: Mapping[str, Mapping[str, Any] | None],
    fitted: Mapping[str, str] | None = None,
) -> GroupLaw:
    """The law of a group of repeats from its runs' law comparisons (module notes).

    Parameters
    ----------
    group : str
        The group's label.
    comparisons : mapping of str to dict
        Run name -> its law comparison (:func:`comparison_digest`, or a
        :class:`~bayestribo.inference.comparison.LawComparison`'s ``to_dict``); None
        for a run fitted in one law.
    fitted : mapping of str to str, optional
        Run name -> the law its fit is in (the verdict of a run without a comparison).

    Returns
    -------
    GroupLaw
    """
    from bayestribo.inference.choice import SMALL_ELPD_DIFFERENCE

    fitted = dict(fitted or {})
    runs = tuple(sorted(comparisons))
    digests = {r: comparison_digest(c) if c and "table" in c else c for r, c in comparisons.items()}
    verdicts = {r: str((d or {}).get("verdict") or fitted.get(r) or "") for r, d in digests.items()}
    compared = [d for d in digests.values() if d]
    candidates: list[str] = []
    for d in compared:
        for law in d["table"]:
            if law not in candidates:
                candidates.append(law)
        for law in d.get("equivalent") or {}:
            if law not in candidates:
                candidates.append(law)
    table: dict[str, dict[str, Any]] = {}
    per_run: dict[str, list[tuple[float, float, bool]]] = {}
    if compared and len(compared) == len(runs):
        for law in candidates:
            values = [_elpd(d, law) for d in compared]
            if all(v is not None for v in values):
                per_run[law] = [v for v in values if v is not None]
    adequate = all(bool((d or {}).get("adequate", True)) for d in digests.values())
    if not per_run:
        counts: dict[str, int] = {}
        for v in verdicts.values():
            if v:
                counts[v] = counts.get(v, 0) + 1
        law = max(sorted(counts), key=lambda k: counts[k]) if counts else ""
        disagree = tuple(r for r in runs if verdicts[r] != law)
        return GroupLaw(group, runs, law, None, verdicts, disagree, {}, False, adequate)
    sums = {law: sum(e for e, _, _ in v) for law, v in per_run.items()}
    best = max(sums, key=lambda k: (sums[k], -_n_parameters(k)))
    for law, values in per_run.items():
        dse = math.sqrt(
            sum(d**2 + b**2 for (_, d, _), (_, b, _) in zip(values, per_run[best], strict=True))
        )
        table[law] = {
            "elpd": sums[law],
            "elpd_diff": sums[best] - sums[law],
            "dse": 0.0 if law == best else dse,
            "n_parameters": _n_parameters(law),
            "adequate_in": sum(a for _, _, a in values),
        }
    as_good = [
        law
        for law, row in table.items()
        if row["elpd_diff"] <= max(SMALL_ELPD_DIFFERENCE, 2.0 * row["dse"])
    ]
    # the simplest law as good as the best that holds in every run, where one does
    holding = [k for k in as_good if table[k]["adequate_in"] == len(runs)]
    law = min(holding or as_good, key=lambda k: (table[k]["n_parameters"], _order(k)))
    adequate = adequate and bool(holding)
    disagree = tuple(r for r in runs if verdicts[r] != law)
    return GroupLaw(group, runs, law, best, verdicts, disagree, table, True, adequate)


def group_laws(
    runs: Sequence[Any], by: Sequence[str]
) -> tuple[dict[str, GroupLaw], dict[str, str]]:
    """The law of every group of repeats of a campaign's fits (or their digests).

    Parameters
    ----------
    runs : sequence of fit results or digests
        Each with ``metadata`` (its ``run_id`` and the grouping keys), ``law`` and a
        ``law_comparison`` (a fit with ``law="auto"``), or ``comparison`` (a digest).
    by : sequence of str
        The grouping keys of a group of repeats (those the runs have).

    Returns
    -------
    groups : dict of str to GroupLaw
        By group label.
    law_of_run : dict of str to str
        Each run's group law.
    """
    members: dict[str, list[Any]] = {}
    for r in runs:
        md = getattr(r, "metadata", {}) or {}
        keys = [k for k in by if md.get(k) is not None]
        label = ",".join(f"{k}={md.get(k)}" for k in keys) or "all"
        members.setdefault(label, []).append(r)
    groups: dict[str, GroupLaw] = {}
    law_of_run: dict[str, str] = {}
    for label, rs in members.items():
        names = [_name(r) for r in rs]
        comparisons = {n: _comparison(r) for n, r in zip(names, rs, strict=True)}
        fitted = {n: str(getattr(r, "law", "") or "") for n, r in zip(names, rs, strict=True)}
        chosen = choose_group_law(label, comparisons, fitted)
        groups[label] = chosen
        for n in names:
            law_of_run[n] = chosen.law
    return groups, law_of_run


def _name(result: Any) -> str:
    md = getattr(result, "metadata", {}) or {}
    return str(md.get("run_id") or getattr(result, "run_name", None) or "?")


def _comparison(result: Any) -> dict[str, Any] | None:
    kept = getattr(result, "comparison", None)
    if kept is not None:
        return kept
    return comparison_digest(getattr(result, "law_comparison", None))
