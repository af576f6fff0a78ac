"""Campaigns: many runs fitted on any executor, catalogued, and analysed together.

Modules
-------
fitting
    :func:`fit_many`: fit many runs on any executor with per-run seeds.
catalog
    :class:`Catalog`: the runs of a campaign and their fits in SQLite.
analysis
    :func:`analyse_campaign`: fits → populations per group, ζ₀, ζ_k, d_k, trends.
figures
    Figures of a campaign analysis.
results
    :func:`load_campaign`: a campaign's results folder read back.

The public names are imported on first use: the acquisition logger registers runs in
the catalog (plain SQLite) without loading the inference stack (numba, emcee, ArviZ:
about 130 MB of memory).
"""

from __future__ import annotations

from bayestribo._lazy import lazy_exports

__all__ = ["CampaignAnalysis", "analyse_campaign", "fit_many"]

_LAZY = {
    "CampaignAnalysis": "bayestribo.campaign.analysis",
    "analyse_campaign": "bayestribo.campaign.analysis",
    "fit_many": "bayestribo.campaign.fitting",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
