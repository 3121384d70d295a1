"""The first sign change of a scalar function along a grid, refined by Brent's method: the
scan-then-bracket search behind the flutter speeds of the linear section and of the hinge
freeplay's connected system.

Brent, *Algorithms for Minimization without Derivatives* (1973), Ch. 4 (scipy's ``brentq``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.optimize import brentq


def first_crossing(fun: Callable[[float], float], grid, *, xtol: float,
                   rtol: float = 8.9e-16, at_start: str = "") -> float | None:
    """The first root of ``fun`` where it turns positive along ``grid``.

    ``fun`` is evaluated at every point of ``grid`` (increasing); at the first point where it is
    positive, its root in the preceding interval is refined by Brent's method to ``xtol`` /
    ``rtol``. A positive value at the first point is an error (an instability already there
    must be reported, not skipped), with the message ``at_start``.

    Parameters
    ----------
    fun : float -> float, negative where stable (e.g. the largest real part of the roots).
    grid : increasing 1-D sequence (at least 2 points), the scan.
    xtol, rtol : Brent's absolute and relative tolerances.
    at_start : the ValueError's message when ``fun(grid[0]) > 0``.

    Returns
    -------
    float, or None when ``fun`` stays non-positive on the whole grid.

    Examples
    --------
    >>> round(first_crossing(lambda u: u - 10.0, [1.0, 8.0, 15.0, 20.0], xtol=1e-12), 9)
    10.0
    >>> first_crossing(lambda u: -1.0, [1.0, 2.0], xtol=1e-9) is None
    True
    """
    grid = np.asarray(grid, dtype=float)
    values = np.array([fun(x) for x in grid])
    if values[0] > 0:
        raise ValueError(at_start or f"positive at the grid's first point {grid[0]:g}")
    idx = np.nonzero(values > 0)[0]
    if idx.size == 0:
        return None
    i = idx[0]
    return float(brentq(fun, grid[i - 1], grid[i], xtol=xtol, rtol=rtol))
