"""Argument checks shared by every module: a clear ValueError naming the argument and its valid
range, never a silent NaN."""

from __future__ import annotations

import math

import numpy as np


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a string, bool, complex or float where a real number or a
    count belongs): a TypeError, and a ValueError like every other user-input error of asekit,
    so that one ``except ValueError`` catches every refusal."""


def _float(name: str, value) -> float:
    """``float(value)``, or TypeError/ValueError naming ``name`` (never a bare conversion
    error). Booleans and complex numbers are refused."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be a real number, got the string {value!r}")
    if isinstance(value, (bool, np.bool_, complex, np.complexfloating)):
        raise ArgumentTypeError(f"{name} must be a real number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError) as exc:
        raise (ArgumentTypeError if isinstance(exc, TypeError) else ValueError)(
            f"{name} must be a real number, got {value!r}") from exc


def integer(name: str, value, low: int | None = None, high: int | None = None) -> int:
    """``int(value)`` for an integer (Python or numpy) within [low, high] (None: unbounded);
    a bool, a float (even 4.0), a string or anything else is an :class:`ArgumentTypeError`
    (a TypeError and a ValueError) naming ``name``, an integer outside the range a ValueError
    naming ``name`` and the range.

    Examples
    --------
    >>> integer("n_states", 4, low=1)
    4
    >>> integer("n_states", 4.5, low=1)
    Traceback (most recent call last):
    ...
    asekit.util.validate.ArgumentTypeError: n_states must be an integer >= 1, got 4.5
    """
    if low is not None and high is not None:
        valid = f"an integer in [{low}, {high}]"
    elif low is not None:
        valid = f"an integer >= {low}"
    elif high is not None:
        valid = f"an integer <= {high}"
    else:
        valid = "an integer"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentTypeError(f"{name} must be {valid}, got {value!r}")
    if (low is not None and value < low) or (high is not None and value > high):
        raise ValueError(f"{name} must be {valid}, got {value!r}")
    return int(value)


def real(name: str, value) -> float:
    """``float(value)`` of a real number (Python or numpy, finite or not); a string, a bool or
    a complex number is refused naming ``name`` (see :func:`finite` for a finite one)."""
    return _float(name, value)


def _index(a: np.ndarray, flat: int) -> str:
    return "[" + ", ".join(str(int(i)) for i in np.unravel_index(flat, a.shape)) + "]" \
        if a.ndim else ""


def real_array(name: str, values) -> np.ndarray:
    """``values`` (any shape) as a float array, refusing what ``np.asarray(..., float)`` would
    coerce silently: strings (ValueError), booleans, None or other objects, and complex values
    with a nonzero imaginary part (TypeError naming ``name`` and the first such entry).
    Integer and real numpy arrays are accepted; finiteness is not checked
    (:func:`finite_array`)."""
    if isinstance(values, (str, bytes)):
        raise ValueError(f"{name} must be real numbers, got the string {values!r}")
    try:
        a = np.asarray(values)
    except (TypeError, ValueError) as exc:      # ragged nesting
        raise ArgumentTypeError(f"{name} must be an array of real numbers, got "
                                f"{values!r}") from exc
    if a.dtype.kind == "O":
        if not all(isinstance(v, (int, float, complex, np.number))
                   and not isinstance(v, (bool, np.bool_)) for v in a.ravel()):
            raise ArgumentTypeError(f"{name} must be real numbers, got {values!r}")
        a = np.asarray(a.tolist())
    if a.dtype.kind in "US":
        raise ValueError(f"{name} must be real numbers, got strings {values!r}")
    if a.dtype.kind == "c":
        imag = np.flatnonzero(a.imag != 0)
        if imag.size:
            raise ArgumentTypeError(f"{name} must be real numbers, got the complex value "
                            f"{a.ravel()[imag[0]].item()!r} at {name}{_index(a, imag[0])}")
        a = a.real
    if a.dtype.kind not in "iuf":
        raise ArgumentTypeError(f"{name} must be real numbers, got {values!r}")
    return a.astype(float)


def finite_array(name: str, values, complex_values: bool = False) -> np.ndarray:
    """``values`` as a float array (:func:`real_array`), or with ``complex_values`` a complex
    one (strings, booleans and objects still refused), every entry finite; else ValueError
    naming ``name`` and the first non-finite entry, e.g. ``Q[2, 0, 1] = nan``."""
    if complex_values:
        if isinstance(values, (str, bytes)):
            raise ValueError(f"{name} must be numbers, got the string {values!r}")
        a = np.asarray(values)
        if a.dtype.kind == "O":
            a = np.asarray(a.tolist()) if all(
                isinstance(v, (int, float, complex, np.number))
                and not isinstance(v, (bool, np.bool_)) for v in a.ravel()) else a
        if a.dtype.kind not in "iufc":
            raise ArgumentTypeError(f"{name} must be numbers, got {values!r}")
        a = a.astype(complex)
    else:
        a = real_array(name, values)
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError(f"{name} must be finite, got {name}{_index(a, bad[0])} = "
                         f"{a.ravel()[bad[0]].item()!r} ({bad.size} non-finite of {a.size})")
    return a


class NonFiniteResultError(ValueError):
    """A computed result holds NaN or inf although its inputs passed their checks: the message
    names the result, the inputs that caused it and what to change."""


def finite_result(what: str, values, hint: str) -> np.ndarray:
    """``values`` unchanged if every entry is finite, else :class:`NonFiniteResultError`
    ``"<what> is not finite (<count> of <size> entries): <hint>"``; ``hint`` names the
    arguments and their valid range. The last check before a result is returned."""
    a = np.asarray(values)
    ok = np.isfinite(a)
    if not np.all(ok):
        raise NonFiniteResultError(f"{what} is not finite ({int(a.size - ok.sum())} of {a.size} "
                                   f"entries): {hint}")
    return values


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
    a = np.atleast_1d(real_array(name, values))
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
