"""The names of the classical estimators, in the order of the table (no imports: the
command line lists them without loading the estimators)."""

from __future__ import annotations

__all__ = ["METHODS"]

#: Method names, in the order of the table.
METHODS: tuple[str, ...] = (
    "log_decrement",
    "exponential_envelope",
    "feeny_liang",
    "nonsuccessive",
    "energy_ls_averaged",
    "energy_ls_exact",
)
