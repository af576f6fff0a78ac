"""The results of ``bayestribo campaign``, read back (for the campaign report).

``bayestribo campaign DIR --out OUTDIR`` fits every run under ``DIR``, records each fit
in the SQLite catalog ``OUTDIR/catalog.sqlite`` (:mod:`bayestribo.campaign.catalog`,
the result itself in ``OUTDIR/fits/<run_id>.nc``) and writes the populations to
``OUTDIR/population.json`` with the settings they were made with (campaign seed, fit
settings, grouping keys, interval probability). The campaign report reuses them:
:func:`load_campaign` reads the catalogued fits made with those settings, so the
report shows the campaign's own fits, and its populations are recomputed from them
with the campaign's seed by the same :func:`bayestribo.campaign.analysis.analyse_campaign`
(:func:`compare_populations` checks they agree with ``population.json``).
:func:`find_campaign` looks for such a folder for a data folder; without one the
report fits every run with :data:`DEFAULT_SEED`, the campaign's default seed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import bayestribo
from bayestribo.campaign.catalog import CatalogError

__all__ = [
    "CAMPAIGN_OUT",
    "DEFAULT_SEED",
    "CampaignResults",
    "compare_populations",
    "find_campaign",
    "is_campaign_folder",
    "load_campaign",
]

#: Seed of a campaign that nothing else names: the package's default seed, that of
#: ``bayestribo campaign --seed`` (a test keeps the two equal).
DEFAULT_SEED: int = int(getattr(bayestribo, "DEFAULT_SEED", 0))

#: Default output folder of ``bayestribo campaign`` (relative to where it ran).
CAMPAIGN_OUT = "bayestribo-campaign"

#: The function ``bayestribo campaign`` fits with (as the catalog records it).
_FIT_FUNCTION = "bayestribo.inference.fit"


def _catalog_path(folder: Path, report: dict[str, Any] | None = None) -> Path:
    named = (report or {}).get("catalog")
    if named and Path(named).is_file():
        return Path(named)
    return folder / "catalog.sqlite"


def _read_report(folder: Path) -> dict[str, Any] | None:
    try:
        return json.loads((folder / "population.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def is_campaign_folder(folder: str | Path) -> bool:
    """True if ``folder`` holds the results of ``bayestribo campaign`` (its ``--out``)."""
    folder = Path(folder)
    report = _read_report(folder)
    return report is not None and _catalog_path(folder, report).is_file()


def _under(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(folder.resolve())
    except ValueError:
        return False
    return True


def find_campaign(data_dir: str | Path, search: Iterable[str | Path] | None = None) -> Path | None:
    """The results folder of a campaign run on ``data_dir``, or None.

    Parameters
    ----------
    data_dir : path
        A folder of run files, or a campaign's results folder itself.
    search : iterable of path, optional
        Candidate results folders; default ``data_dir`` itself, then
        ``data_dir/bayestribo-campaign`` and ``./bayestribo-campaign`` (the campaign's
        default ``--out``). A candidate other than ``data_dir`` counts only if its
        catalog holds runs under ``data_dir``.
    """
    from bayestribo.campaign.catalog import list_runs

    data_dir = Path(data_dir)
    if is_campaign_folder(data_dir):
        return data_dir
    candidates = (
        [Path(s) for s in search]
        if search is not None
        else [data_dir / CAMPAIGN_OUT, Path.cwd() / CAMPAIGN_OUT]
    )
    for folder in candidates:
        if not is_campaign_folder(folder):
            continue
        catalog = _catalog_path(folder, _read_report(folder))
        if any(_under(Path(r.path), data_dir) for r in list_runs(catalog)):
            return folder
    return None


@dataclass(frozen=True)
class CampaignResults:
    """What a ``bayestribo campaign`` folder holds, read back.

    Attributes
    ----------
    folder : Path
        The campaign's results folder.
    catalog : Path
        Its SQLite catalog.
    seed : int
        The campaign seed.
    fit_kwargs : dict
        The fit settings of the campaign.
    by : tuple of str
        Grouping keys of its populations.
    prob : float
        Probability of its intervals.
    population_steps : int
        Step ceiling of its population samplers (10 000 for campaigns that did not
        record it).
    report : dict
        ``population.json`` as written by the campaign.
    fits : dict
        Run id -> :class:`bayestribo.inference.FitResult`, the catalogued fit made with
        the campaign's settings (the latest if several).
    paths : dict
        Run id -> run file, as registered.
    metadata : dict
        Run id -> sidecar metadata, as registered.
    missing : dict
        Run id -> why the run has no usable fit (failed, or its result file is gone).
    package_versions : list of str
        bayestribo versions that made the fits.
    """

    folder: Path
    catalog: Path
    seed: int
    fit_kwargs: dict[str, Any]
    by: tuple[str, ...]
    prob: float
    report: dict[str, Any]
    fits: dict[str, Any] = field(default_factory=dict)
    population_steps: int = 10_000
    paths: dict[str, Path] = field(default_factory=dict)
    metadata: dict[str, dict[str, Any]] = field(default_factory=dict)
    missing: dict[str, str] = field(default_factory=dict)
    package_versions: list[str] = field(default_factory=list)


def load_campaign(folder: str | Path) -> CampaignResults:
    """Read the fits and settings of a ``bayestribo campaign`` results folder.

    Parameters
    ----------
    folder : path
        The campaign's ``--out`` folder (``population.json`` and ``catalog.sqlite``).

    Returns
    -------
    CampaignResults

    Raises
    ------
    CatalogError
        If ``folder`` is not a campaign's results folder.
    """
    from bayestribo.campaign.catalog import list_fits, list_runs
    from bayestribo.inference import FitResult

    folder = Path(folder)
    report = _read_report(folder)
    if report is None or not _catalog_path(folder, report).is_file():
        raise CatalogError(
            f"campaign_dir: {folder} holds no campaign results (population.json and "
            "catalog.sqlite, as written by `bayestribo campaign DIR --out OUTDIR`)"
        )
    catalog = _catalog_path(folder, report)
    settings = report.get("settings") or {}
    seed = int(settings.get("seed", DEFAULT_SEED))
    fit_kwargs = dict(settings.get("fit") or {})
    # the campaign's fit specification (recorded since there is one), else its keywords
    spec = settings.get("spec")
    failed = {f["run"]: f["error"] for f in report.get("failures", [])}
    fits: dict[str, Any] = {}
    paths: dict[str, Path] = {}
    metadata: dict[str, dict[str, Any]] = {}
    missing: dict[str, str] = {}
    versions: set[str] = set()
    for run in list_runs(catalog):
        paths[run.run_id] = Path(run.path)
        metadata[run.run_id] = dict(run.metadata)
        records = [
            f
            for f in list_fits(catalog, run=run.id)
            if f.settings.get("campaign_seed") == seed
            and (
                f.settings.get("spec") == spec
                if spec is not None
                else f.settings.get("fit_kwargs") == fit_kwargs
            )
            and f.settings.get("function") == _FIT_FUNCTION
        ]
        if not records:
            missing[run.run_id] = failed.get(run.run_id, "no fit with the campaign's settings")
            continue
        record = records[-1]
        result_path = Path(record.summary.get("result_path", ""))
        if not result_path.is_file():
            missing[run.run_id] = f"the fit's result file {result_path} is gone"
            continue
        fits[run.run_id] = FitResult.load(result_path)
        versions.add(record.package_version)
    return CampaignResults(
        folder=folder,
        catalog=catalog,
        seed=seed,
        fit_kwargs=fit_kwargs,
        by=tuple(report.get("by") or ()),
        prob=float(report.get("prob", 0.95)),
        report=report,
        fits=fits,
        paths=paths,
        metadata=metadata,
        missing=missing,
        package_versions=sorted(versions),
        population_steps=int(settings.get("population_steps", 10_000)),
    )


def _groups(report: dict[str, Any], kind: str) -> dict[str, dict[str, Any]]:
    pop = report.get(kind) or {}
    groups = list(pop.get("groups") or [])
    if pop.get("pooled"):
        groups.append(pop["pooled"])
    return {str(g["label"]): g for g in groups}


def compare_populations(
    campaign: dict[str, Any], here: dict[str, Any], *, rtol: float = 1e-9
) -> list[str]:
    """Differences between two population reports (``CampaignAnalysis.to_dict()``).

    Compares the posterior median and interval of every group mean and σ that both
    hold (per-run selection may leave groups out of one of them).

    Returns
    -------
    list of str
        One line per quantity that differs (empty: the same populations).
    """
    out = []
    for kind in ("contact", "zeta0", "series"):
        theirs, ours = _groups(campaign, kind), _groups(here, kind)
        for label in sorted(set(theirs) & set(ours)):
            for name, p in ours[label].get("parameters", {}).items():
                q = theirs[label].get("parameters", {}).get(name)
                if q is None:
                    continue
                for what in ("mean", "sigma"):
                    a, b = p[what], q[what]
                    pairs: Sequence[tuple[float, float]] = [
                        (a["median"], b["median"]),
                        *zip(a["interval"], b["interval"], strict=True),
                    ]
                    if not all(math.isclose(x, y, rel_tol=rtol, abs_tol=0.0) for x, y in pairs):
                        out.append(
                            f"{kind} {label} {name} {what}: campaign {b['median']:.6g} "
                            f"{b['interval']}, report {a['median']:.6g} {a['interval']}"
                        )
    return out
