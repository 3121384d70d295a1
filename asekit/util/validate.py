"""Argument checks shared by every module: a clear ValueError naming the argument and its valid
range, never a silent NaN."""

from __future__ import annotations

import math

import numpy as np


def _float(name: str, value) -> float:
    """``float(value)``, or TypeError/ValueError naming ``name`` (never a bare conversion
    error). Booleans and complex numbers are refused."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a real number, got the string {value!r}")
    if isinstance(value, (bool, np.bool_, complex, np.complexfloating)):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError) as exc:
        raise type(exc)(f"{name} must be a real number, got {value!r}") from exc


def in_range(name: str, value, low: float = 0.0, inclusive: bool = False,
             high: float = math.inf, high_inclusive: bool = True) -> float:
    """Return ``float(value)`` if it is finite and within the range, else raise ValueError
    naming ``name`` and the range (default: ``(0, inf)``)."""
    value = _float(name, value)
    lo_ok = value >= low if inclusive else value > low
    hi_ok = value <= high if high_inclusive else value < high
    if not math.isfinite(value) or not lo_ok or not hi_ok:
        lb = "[" if inclusive else "("
        rb = "]" if high_inclusive and math.isfinite(high) else ")"
        raise ValueError(f"{name} must be a finite number in {lb}{low:g}, {high:g}{rb}, "
                         f"got {value!r}")
    return value


def positive(name: str, value) -> float:
    """``float(value)`` if finite and > 0, else ValueError naming ``name``."""
    value = _float(name, value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def finite(name: str, value) -> float:
    """``float(value)`` if finite, else ValueError naming ``name``."""
    value = _float(name, value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return value


def positive_array(name: str, values) -> np.ndarray:
    """A non-empty 1-D float array of finite values > 0, else ValueError naming ``name``."""
    try:
        a = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be a sequence of real numbers, got {values!r}") from exc
    if a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name} must be finite and > 0, got {values}")
    return a


def read_toml(path, error: type[Exception] = ValueError) -> dict:
    """Parse the TOML file ``path`` as UTF-8, with or without a byte-order mark; a file that is
    not UTF-8, a directory or a syntax error becomes ``error`` naming the file in one line (a
    missing file raises FileNotFoundError)."""
    import tomllib
    from pathlib import Path
    path = Path(path)
    if path.is_dir():
        raise error(f"{path} is a directory, not a TOML file")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")           # a leading BOM (EF BB BF) is dropped
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise error(f"{path.name} is not UTF-8 (byte 0x{raw[exc.start]:02x} on line {line}): "
                    f"save it as UTF-8") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path.name} is not valid TOML: {exc}") from None
