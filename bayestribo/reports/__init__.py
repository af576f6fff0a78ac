"""Reports: the notebooks under ``notebooks/`` run with parameters and rendered as HTML."""

from bayestribo.reports.notebooks import NOTEBOOKS, ReportError, run_report

__all__ = ["NOTEBOOKS", "ReportError", "run_report"]
