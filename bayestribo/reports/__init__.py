"""Reports: the packaged notebooks run with parameters and rendered as offline HTML."""

from bayestribo.reports._errors import ReportError
from bayestribo.reports.notebooks import NOTEBOOKS, notebooks_dir, run_report

__all__ = ["NOTEBOOKS", "ReportError", "notebooks_dir", "run_report"]
