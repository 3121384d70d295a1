"""Optional dependencies by the extra that installs them (pyproject ``[project.optional-
dependencies]``): :func:`require` imports one or raises :class:`MissingExtra` whose one-line
message names the ``pip install`` that fixes it. The command line prints that line, exit 2."""

from __future__ import annotations

import importlib

#: The distribution name on the package index (``import asekit``; README, Install).
DISTRIBUTION = "asekit-aero"

#: module -> (extra, the pip line's target): what installs each optional import.
EXTRAS = {
    "pandas": "sweep",
    "dask": "dask",
    "dask.distributed": "dask",
    "numba": "fast",
    "ipywidgets": "notebooks",
    "nbclient": "notebooks",
    "nbformat": "notebooks",
    "nbconvert": "notebooks",
    "slycot": "robust",
}


class MissingExtra(ImportError):
    """An optional dependency is not installed; the message names the pip line."""


def install_line(module: str) -> str:
    """The ``pip install`` command that provides ``module``.

    Examples
    --------
    >>> install_line("pandas")
    "pip install 'asekit-aero[sweep]'"
    """
    return f"pip install '{DISTRIBUTION}[{EXTRAS[module]}]'"


def require(module: str, purpose: str):
    """Import ``module`` (one of :data:`EXTRAS`) and return it.

    Parameters
    ----------
    module : the module's import name, e.g. ``"pandas"``.
    purpose : what needs it, for the message, e.g. ``"asekit sweep (the results table)"``.

    Raises
    ------
    MissingExtra
        ``"<purpose> needs <module>: pip install 'asekit-aero[<extra>]'"``.

    Examples
    --------
    >>> require("math_is_not_an_extra", "x")
    Traceback (most recent call last):
    ...
    KeyError: 'math_is_not_an_extra'
    """
    line = install_line(module)
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtra(f"{purpose} needs {module.split('.')[0]}: {line}") from None
