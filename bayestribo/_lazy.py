"""Names a package re-exports from its modules, imported on first use.

A package's ``__init__`` lists what it re-exports and from where, and takes its
module-level ``__getattr__`` and ``__dir__`` from :func:`lazy_exports`, so importing
the package imports none of the modules behind those names (the command line's
start-up; ``tests/test_cli_startup.py``).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, names: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` for the lazily re-exported ``names``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : mapping
        Each re-exported name and the module that defines it.

    Returns
    -------
    getattr, dir : callable
        ``__getattr__(name)`` imports ``names[name]``'s module, keeps the value in the
        package's namespace (later lookups do not come back) and returns it, and raises
        ``AttributeError`` for any other name; ``__dir__()`` lists the namespace and
        ``names``. A name that is also a submodule's (``estimators.feeny_liang``) must
        be imported at once instead: importing the submodule would bind the module.
    """

    def __getattr__(name: str) -> Any:
        try:
            source = names[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(source), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
