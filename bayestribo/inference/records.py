"""The records of a law's checks that a result keeps: typed, with their plain data.

:class:`LawComparison` is what the comparison of ``law="auto"`` decides
(:mod:`bayestribo.inference.comparison`), :class:`LawHalves` what fitting the verdict
to each half of the motion says (:mod:`bayestribo.inference.halves`). Each turns into
plain data (``to_dict``) and back (``from_dict``), the form a
:class:`~bayestribo.inference.result.FitResult` saves, and describes itself in words.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

__all__ = ["LawComparison", "LawHalves", "p_text"]


def p_text(p: float) -> str:
    """``p = 1.2e-05``, or ``p < 1e-300`` where the p-value underflows."""
    return "p < 1e-300" if p < 1e-300 else f"p = {p:.1e}"


@dataclass(frozen=True)
class LawComparison:
    """PSIS-LOO comparison of the dissipation laws of one run.

    Attributes
    ----------
    run_name : str
        The run.
    table : dict
        Law -> ``elpd_loo``, ``se``, ``p_loo``, ``elpd_diff``, ``dse``, ``weight``,
        ``rank``, ``pareto_k_max``, ``converged``, ``sampled``, the posterior medians,
        and the time the law took (optimum and sampling: ``seconds`` of wall time,
        ``cpu_seconds`` of the process's).
    best : str
        Law with the highest elpd_loo.
    verdict : str
        Simplest adequate law as good as the best (see the module notes).
    as_good : list of str
        Laws as good as the best (the best included).
    warnings : list of str
        Unreliable estimates (Pareto k) and unconverged fits.
    adequate : bool
        True when the verdict is adequate (no misfit at its optimum, and the halves of
        the motion agree); False when no law compared holds, and the verdict is only
        the best of them.
    rivals : dict or None
        The comparison of the verdict and its rivals on the finer grid (module notes):
        ``laws``, ``grid_points``, ``verdict``, ``adequate``, ``decided`` and its table.
    halves : dict or None
        The verdict fitted to each half of the motion
        (:class:`bayestribo.inference.halves.LawHalves` as plain data), when checked.
    equivalent : dict
        Law -> the law compared that it reduces to: its extra terms at 0 at its
        optimum, so that it was neither sampled nor compared by PSIS-LOO (module
        notes); its table row says ``reduces_to``, ``terms_at_zero`` and
        ``sampled`` False.
    screened : list of str
        Laws screened out at their optimum: too far behind the best to win, or with
        as many sampled parameters as the record's increments (module notes,
        Screening), not sampled; their rows say ``screened`` and ``screen``
        (the estimate at the optimum and the limit it passed).
    settled : list of str
        Laws not sampled because they could no longer change the choice, judged at
        their optimum (:mod:`bayestribo.inference.settling`); their rows say
        ``settled`` and ``settle`` (the estimate, its reach and whether the law is as
        good as the best, by which it is in ``as_good`` or not).
    """

    run_name: str
    table: dict[str, dict[str, Any]]
    best: str
    verdict: str
    as_good: list[str]
    warnings: list[str] = field(default_factory=list)
    adequate: bool = True
    halves: dict[str, Any] | None = None
    rivals: dict[str, Any] | None = None
    equivalent: dict[str, str] = field(default_factory=dict)
    screened: list[str] = field(default_factory=list)
    settled: list[str] = field(default_factory=list)

    def describe(self) -> str:
        """One sentence: the law chosen and why (the laws that reduced to others, those
        screened out at their optimum and those settled there)."""
        text = self._choice()
        if self.equivalent:
            text += "; " + _equivalence_text(self.equivalent, self.table)
        outnumbered = [
            law
            for law in self.screened
            if (self.table.get(law, {}).get("screen") or {}).get("stage") == "increments"
        ]
        behind = [law for law in self.screened if law not in outnumbered]
        if behind:
            text += (
                f"; {len(behind)} not sampled, too far behind the best to win "
                f"(screened): {', '.join(behind)}"
            )
        if outnumbered:
            text += (
                f"; {len(outnumbered)} not sampled, with as many parameters as the record "
                f"has increments, which do not identify them (screened): {', '.join(outnumbered)}"
            )
        if self.settled:
            text += (
                f"; {len(self.settled)} not sampled, unable to change the choice at their "
                f"optimum (settled): {', '.join(self.settled)}"
            )
        return text

    def _choice(self) -> str:
        """The law chosen and why."""
        n = len(self.table)
        split = self.halves or {}
        if not self.adequate and split.get("tested") and not split.get("agree"):
            return (
                f"{self.verdict} fits the decay as a whole, but not both halves of it "
                f"alike: fitted to each half, it measures a ΔE(A) {split['largest_z']:.1f} "
                f"sd apart ({p_text(split['p_value'])} over {split['n_swings']} swings). "
                f"No law of the {n} compared holds along the decay: its parameters are not "
                "a measurement, and the answer is ΔE(A) measured from the turning points "
                "(law-free)"
            )
        if not self.adequate:
            return (
                f"no law of the {n} compared holds (each misfits the decay); "
                f"{self.verdict} is the simplest of the best by PSIS-LOO, but its parameters "
                "are not a measurement: the answer is ΔE(A) measured from the turning "
                "points (law-free)"
            )
        others = [law for law in self.as_good if law != self.verdict]
        tie = f", as good as {', '.join(others)}" if others else ""
        rivals = self.rivals or {}
        if rivals.get("decided"):
            lost = [law for law in rivals["laws"] if law != self.verdict]
            tie += (
                f"; chosen over {', '.join(lost)} on {rivals['per_half_cycle']} increments per "
                "half cycle, where the decay tells them apart"
            )
        elif rivals:
            tie += (
                f"; {rivals['per_half_cycle']} increments per half cycle did not tell it from "
                f"{', '.join(law for law in rivals['laws'] if law != self.verdict)}"
            )
        if self.verdict == "free":
            return (
                f"no law of the {n - 1} compared holds; the law-free fit (ΔE(A) any "
                "increasing polynomial of degree 1-4) describes the decay: its ΔE(A) is "
                "the answer, its parameters are not a measurement of any mechanism"
            )
        untested = (
            f"; adequate on its misfit tests alone, the halves not compared: {split['note']}"
            if split and not split.get("tested", True)
            else ""
        )
        return (
            f"{self.verdict} chosen from {n} laws: the simplest adequate law as good as "
            f"the best by PSIS-LOO (best {self.best}{tie}){untested}"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "run_name": self.run_name,
            "best": self.best,
            "verdict": self.verdict,
            "as_good": list(self.as_good),
            "adequate": self.adequate,
            "halves": self.halves,
            "rivals": self.rivals,
            "table": self.table,
            "warnings": list(self.warnings),
            "equivalent": dict(self.equivalent),
            "screened": list(self.screened),
            "settled": list(self.settled),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LawComparison:
        """The comparison from its plain data (:meth:`to_dict`; keys it does not hold,
        such as a result's ``departures``, are left aside; those a fit saved before they
        were recorded take their defaults)."""
        return cls(
            str(data.get("run_name", "")),
            dict(data["table"]),
            data["best"],
            data["verdict"],
            list(data["as_good"]),
            warnings=list(data.get("warnings") or []),
            adequate=bool(data.get("adequate", True)),
            halves=data.get("halves"),
            rivals=data.get("rivals"),
            equivalent=dict(data.get("equivalent") or {}),
            screened=list(data.get("screened") or []),
            settled=list(data.get("settled") or []),
        )


def _equivalence_text(equivalent: Mapping[str, str], table: Mapping[str, Any]) -> str:
    """The laws that reduced to a nested law at their optimum, in words: "not sampled,
    equivalent at the optimum to a nested law compared: coulomb+power to coulomb (power
    at 0)"."""
    parts = []
    for law, nested in equivalent.items():
        zero = table.get(law, {}).get("terms_at_zero") or []
        parts.append(f"{law} to {nested} ({', '.join(zero)} at 0)")
    return "not sampled, equivalent at the optimum to a nested law compared: " + ", ".join(parts)


@dataclass(frozen=True)
class LawHalves:
    """The law fitted to each half of the motion, and whether they agree.

    Attributes
    ----------
    law : str
        The law fitted.
    tested : bool
        False when the run could not be split or a half not fitted (``note`` says why).
    cut_time_s : float
        Time of the cut [s] (a turning point).
    amplitude : list of float
        Swings A compared [length unit].
    unit : str
        Unit of ΔE(A)/k (the length unit squared).
    first, second : dict
        Each half's ``mean`` and ``sd`` of ΔE(A)/k at ``amplitude``, its ``range``: the
        smallest and largest swing of its own motion, and ``draws``: the effective
        number of the draws they are estimated from (their Monte Carlo error is carried
        in the z, :mod:`bayestribo.inference.halves_statistic`).
    largest_z : float
        The largest |z| over the swings (module notes).
    n_swings : int
        The number of swings compared.
    p_value : float
        Its Bonferroni p-value over the swings.
    agree : bool
        True when ``p_value >= HALVES_P`` (or not tested).
    note : str
        Why the halves were not tested, if so.
    """

    law: str
    tested: bool
    cut_time_s: float = math.nan
    amplitude: list[float] = field(default_factory=list)
    unit: str = ""
    first: dict[str, Any] = field(default_factory=dict)
    second: dict[str, Any] = field(default_factory=dict)
    largest_z: float = math.nan
    n_swings: int = 0
    p_value: float = math.nan
    agree: bool = True
    note: str = ""

    def most_apart(self) -> tuple[float, float]:
        """The swing at which the halves differ most, in sd of the difference, and that
        difference ``(A, z)``."""
        if not self.amplitude:
            return math.nan, math.nan
        m1, s1 = np.asarray(self.first["mean"]), np.asarray(self.first["sd"])
        m2, s2 = np.asarray(self.second["mean"]), np.asarray(self.second["sd"])
        # each mean's Monte Carlo variance s²/n where the effective draws are recorded
        n1, n2 = self.first.get("draws", math.inf), self.second.get("draws", math.inf)
        z = (m1 - m2) / np.sqrt(s1**2 * (1.0 + 1.0 / n1) + s2**2 * (1.0 + 1.0 / n2))
        i = int(np.nanargmax(np.abs(z)))
        return float(self.amplitude[i]), float(z[i])

    def describe(self) -> str:
        """One sentence: what the halves say."""
        if not self.tested:
            return f"halves not compared: {self.note}"
        a, z = self.most_apart()
        i = self.amplitude.index(a)
        unit = self.unit.replace("^2", "²")
        verdict = "agree" if self.agree else "disagree"
        return (
            f"the {self.law} law fitted to each half of the motion (cut at "
            f"{self.cut_time_s:.4g} s): the halves {verdict}; most apart at the swing "
            f"{a:.3g}: ΔE/k = {self.first['mean'][i]:.4g} ± {self.first['sd'][i]:.2g} "
            f"(first half) against {self.second['mean'][i]:.4g} ± "
            f"{self.second['sd'][i]:.2g} (second) [{unit}], {abs(z):.1f} sd "
            f"({p_text(self.p_value)} over {self.n_swings} swings)"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields."""
        out = asdict(self)
        for key in ("cut_time_s", "largest_z", "p_value"):
            if not math.isfinite(out[key]):
                out[key] = None
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LawHalves:
        """The halves from their plain data (:meth:`to_dict`: a missing number, None,
        is NaN again)."""
        out = dict(data)
        for key in ("cut_time_s", "largest_z", "p_value"):
            if out.get(key) is None:
                out[key] = math.nan
        return cls(**out)
