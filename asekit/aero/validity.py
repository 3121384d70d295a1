"""Valid ranges of the aerodynamic inputs: the Mach regimes of the linear methods and the
reduced frequencies.

This module is the leaf that the kernels (:mod:`asekit.aero.vlm`, :mod:`asekit.aero.dlm`,
:mod:`asekit.aero.piston`, :mod:`asekit.aero.supersonic`) and the method registry
(:mod:`asekit.aero.methods`, the front door that the schema, the pipeline and the sweep use)
share, so that each range is written once and every Mach or k error reads the same. It imports
no asekit module but :mod:`asekit.util.validate` (no import cycle with the kernels it serves).

- :data:`SUBSONIC`: 0 <= M < 1, the doublet lattice and the vortex lattice (Prandtl-Glauert
  factor beta = sqrt(1 - M^2) > 0);
- :data:`SUPERSONIC`: M > 1, the Mach-box method and piston theory (beta = sqrt(M^2 - 1) > 0).

Reduced frequency k = omega b / U: finite and >= 0 (:func:`check_k`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.util.validate import real, real_array


@dataclass(frozen=True)
class MachRange:
    """An interval of Mach numbers: ``low`` < M (or <= M when ``low_closed``) and M < ``high``
    (or <= when ``high_closed``); ``regime`` names it ("subsonic", "supersonic")."""

    low: float
    high: float
    low_closed: bool
    high_closed: bool
    regime: str

    def contains(self, mach: float) -> bool:
        """True when ``mach`` is finite and inside the interval."""
        m = float(mach)
        if not math.isfinite(m):
            return False
        lo = m >= self.low if self.low_closed else m > self.low
        hi = m <= self.high if self.high_closed else m < self.high
        return bool(lo and hi)

    def interval(self) -> str:
        """The interval as text, e.g. ``0 <= M < 1`` or ``M > 1``."""
        lo = f"{self.low:g} {'<=' if self.low_closed else '<'} M"
        if math.isinf(self.high):
            return f"M {'>=' if self.low_closed else '>'} {self.low:g}"
        return f"{lo} {'<=' if self.high_closed else '<'} {self.high:g}"


#: The doublet lattice's (and the vortex lattice's) range.
SUBSONIC = MachRange(0.0, 1.0, True, False, "subsonic")
#: The Mach-box method's and piston theory's range.
SUPERSONIC = MachRange(1.0, math.inf, False, False, "supersonic")


def mach_number(mach, name: str = "mach") -> float:
    """``float(mach)`` if it is a finite Mach number >= 0, else ValueError naming ``name``.

    Examples
    --------
    >>> mach_number(0.75)
    0.75
    """
    m = real(name, mach)
    if not math.isfinite(m) or m < 0:
        raise ValueError(f"{name} must be a finite Mach number >= 0, got {mach!r}")
    return m


def check_mach(mach, mach_range: MachRange, who: str = "", name: str = "mach",
               hint: str = "") -> float:
    """``float(mach)`` if it lies in ``mach_range``, else ValueError
    ``"<name> must be <bound> for <who> (<regime>: <interval>), got <mach><hint>"``.

    Parameters
    ----------
    mach : the Mach number (-).
    mach_range : its valid :class:`MachRange`.
    who : the method the range belongs to, e.g. ``"the DLM"`` (empty: not named).
    name : the argument or key path named in the message.
    hint : text appended to the message (e.g. which method to use instead).

    Returns
    -------
    float : the Mach number.

    Examples
    --------
    >>> check_mach(0.5, SUBSONIC)
    0.5
    >>> check_mach(1.2, SUBSONIC, "the DLM")
    Traceback (most recent call last):
    ...
    ValueError: mach must be < 1 for the DLM (subsonic: 0 <= M < 1), got 1.2
    """
    m = real(name, mach)
    if mach_range.contains(m):
        return m
    r = mach_range
    if not math.isfinite(m):
        bound = "a finite Mach number"
    elif m < r.low or (m == r.low and not r.low_closed):
        bound = f"{'>=' if r.low_closed else '>'} {r.low:g}"
    else:
        bound = f"{'<=' if r.high_closed else '<'} {r.high:g}"
    who = f" for {who}" if who else ""
    raise ValueError(f"{name} must be {bound}{who} ({r.regime}: {r.interval()}), got "
                     f"{mach!r}{hint}")


def check_k(k, name: str = "k") -> np.ndarray:
    """Reduced frequencies k = omega b / U as a 1-D float array, each finite and >= 0 (raises
    ValueError naming ``name`` otherwise).

    Examples
    --------
    >>> check_k(0.1)
    array([0.1])
    >>> check_k([0.0, -0.1])
    Traceback (most recent call last):
    ...
    ValueError: k must be finite reduced frequencies >= 0, got [0.0, -0.1]
    """
    ks = np.atleast_1d(real_array(name, k))
    if ks.ndim != 1 or ks.size == 0 or not np.all(np.isfinite(ks)) or np.any(ks < 0):
        raise ValueError(f"{name} must be finite reduced frequencies >= 0, got {k!r}")
    return ks
