"""The reference thesis's reported numbers, read from ``data/thesis.toml``.

These are the values asekit is compared against in ``python -m asekit reproduce`` and in the
notebooks. They are never used as inputs to a computation.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from asekit.util.paths import THESIS_FILE


@dataclass(frozen=True)
class ThesisValue:
    """One reported value: ``value`` is a float, a list of floats, a bool or None (not reported)."""

    key: str
    value: float | list | bool | None
    unit: str
    source: str


@lru_cache(maxsize=4)
def _load(path: Path) -> dict:
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def thesis_value(key: str, path: Path = THESIS_FILE) -> ThesisValue:
    """Return the thesis's value for a reproduce key; ``value`` is None where none is reported.

    Raises
    ------
    KeyError
        If ``key`` is not listed in ``data/thesis.toml`` (every published key must be).
    """
    table = _load(Path(path))
    if key not in table:
        raise KeyError(f"key {key!r} is not in {path}; add it there with its unit and source")
    entry = table[key]
    return ThesisValue(key=key, value=entry.get("value"), unit=entry["unit"],
                       source=entry.get("source", ""))


def all_keys(path: Path = THESIS_FILE) -> list[str]:
    """All keys listed in the thesis table, in file order."""
    return list(_load(Path(path)).keys())


def is_number(value) -> bool:
    """True for a real number (bool excluded), including inf."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value)
