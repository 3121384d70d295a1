"""The user-facing conventions of ``docs/conventions.md`` as functions, one place for every
table, JSON, report, notebook and figure: the names of the modes (1-based elastic modes, the
rigid mode named, not numbered) and the damping of a root (V-g g > 0 unstable; the damping ratio
of a pole > 0 stable)."""

from __future__ import annotations

import numpy as np

#: The name of the rigid (actuator) pitch mode in every user-facing output; it is never numbered.
RIGID_MODE_NAME = "rigid pitch"


def mode_number(index: int, n_rigid: int = 0) -> int | str:
    """The user-facing name of mode ``index`` (0-based, rigid modes first) of a set holding
    ``n_rigid`` rigid modes in front: the string ``"rigid pitch"`` for the rigid mode, else the
    elastic mode number counted from 1 without the rigid mode (docs/conventions.md).

    Parameters
    ----------
    index : 0-based position of the mode in the array (columns of ``PkResult.p``, rows of
        ``ModalModel.frequencies_hz``, ``Instability.mode``).
    n_rigid : rigid modes at the front of that array (0 for a clamped / FN1 model, and for a
        p-k solution with the rigid mode held; 1 for an FN2 modal model).

    Returns
    -------
    int (elastic mode number, >= 1) or str (the rigid mode's name).

    Examples
    --------
    >>> mode_number(0, n_rigid=1), mode_number(1, n_rigid=1), mode_number(0, n_rigid=0)
    ('rigid pitch', 1, 1)
    """
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise ValueError(f"index must be an integer >= 0, got {index!r}")
    if isinstance(n_rigid, bool) or not isinstance(n_rigid, (int, np.integer)) or n_rigid < 0:
        raise ValueError(f"n_rigid must be an integer >= 0, got {n_rigid!r}")
    if index < n_rigid:
        return RIGID_MODE_NAME if n_rigid == 1 else f"rigid {int(index) + 1}"
    return int(index - n_rigid + 1)


def mode_label(index: int, n_rigid: int = 0) -> str:
    """The text label of mode ``index`` (see :func:`mode_number`): ``"mode 1"``, ``"mode 2"``,
    ... for the elastic modes (1-based, the rigid mode not counted) and ``"rigid pitch"``.

    Examples
    --------
    >>> [mode_label(j, n_rigid=1) for j in range(3)]
    ['rigid pitch', 'mode 1', 'mode 2']
    """
    n = mode_number(index, n_rigid)
    return n if isinstance(n, str) else f"mode {n}"


def vg_damping(p) -> np.ndarray:
    """V-g damping g of roots p = sigma + i omega (1/s): g = 2 sigma / |omega|, **g > 0
    unstable** (the MSC Nastran PK convention: p = omega (gamma +- i), g = 2 gamma), clipped to
    [-2, 2] so that real (non-oscillatory) roots and roots damped beyond |g| = 2 plot at +-2.

    Parameters
    ----------
    p : complex roots, any shape (1/s).

    Returns
    -------
    g (same shape, dimensionless).

    Examples
    --------
    >>> vg_damping([0.05 * 100 + 100j, -10 + 100j, 3 + 0j]).round(3).tolist()
    [0.1, -0.2, 2.0]
    """
    p = np.asarray(p, dtype=complex)
    sigma, omega = p.real, np.abs(p.imag)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(np.abs(2 * sigma) >= 2 * omega, 2 * np.sign(sigma),
                     2 * sigma / np.where(omega > 0, omega, 1.0))
    return np.clip(g, -2.0, 2.0)


def damping_ratio(p) -> np.ndarray:
    """Damping ratio zeta = -sigma / |p| of poles p = sigma + i omega: **zeta > 0 stable**
    (zeta = -g/2 to first order in g). For poles of a transfer function or a closed loop; the
    V-g plots use :func:`vg_damping`.

    Examples
    --------
    >>> damping_ratio([-3 + 4j]).tolist()
    [0.6]
    """
    p = np.asarray(p, dtype=complex)
    return -p.real / np.maximum(np.abs(p), 1e-300)


def vg_damping_label(root: str = "p") -> str:
    """The axis label of every V-g damping axis: ``"damping g = 2 Re p / |Im p| (-), > 0
    unstable"`` (``root`` names the eigenvalue, e.g. ``"lambda"`` for the roots of A_sys)."""
    return f"damping g = 2 Re {root} / |Im {root}| (-), > 0 unstable"
