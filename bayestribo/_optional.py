"""Optional dependencies: import one where a feature needs it, or say what to install.

The core (numerics, emcee, ArviZ, matplotlib) is always installed. File formats, the
acquisition link, reports and Dask are extras; a feature that needs a missing one
raises :class:`~bayestribo.errors.MissingDependencyError` with a one-line message
naming the extra, e.g. ``reading UFF files needs pyuff: pip install 'bayestribo[formats]'``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from bayestribo.errors import MissingDependencyError

__all__ = ["EXTRAS", "require"]

#: Extra that installs each optional top-level module.
EXTRAS: dict[str, str] = {
    "pyuff": "formats",
    "nptdms": "formats",
    "openpyxl": "formats",
    "h5py": "hdf5",
    "serial": "acquire",
    "nbformat": "report",
    "nbclient": "report",
    "nbconvert": "report",
    "ipykernel": "report",
    "pandas": "report",
    "dask": "dask",
}

#: Distribution names where they differ from the module names.
_DISTRIBUTIONS = {"serial": "pyserial", "nptdms": "npTDMS"}


def require(module: str, feature: str) -> ModuleType:
    """Import ``module`` (e.g. ``"pyuff"`` or ``"dask.distributed"``) for ``feature``.

    Parameters
    ----------
    module : str
        Module to import; its top-level name must be in :data:`EXTRAS`.
    feature : str
        What needs it, for the message (e.g. ``"reading UFF files"``).

    Returns
    -------
    module

    Raises
    ------
    MissingDependencyError
        If the module cannot be imported, naming the package and the extra.
    """
    top = module.split(".")[0]
    extra = EXTRAS[top]
    try:
        return importlib.import_module(module)
    except ImportError:
        name = _DISTRIBUTIONS.get(top, top)
        raise MissingDependencyError(
            f"{feature} needs {name}: pip install 'bayestribo[{extra}]'"
        ) from None
