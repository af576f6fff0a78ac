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
"""

from bayestribo.campaign.analysis import CampaignAnalysis, analyse_campaign
from bayestribo.campaign.fitting import fit_many

__all__ = ["CampaignAnalysis", "analyse_campaign", "fit_many"]
