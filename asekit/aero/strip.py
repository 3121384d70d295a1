"""Strip theory: Theodorsen's two-dimensional unsteady lift and moment applied strip by strip
to mode shapes given as the plunge and pitch of each strip's reference (elastic) axis.

Per unit span, for a harmonic plunge h (positive *down*, Theodorsen's sign) and pitch alpha
(nose up) about the axis at x = a b behind mid-chord (Theodorsen, NACA Report 496, 1935;
Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955, Eqs. 5-308, 5-309):

    L = pi rho b^2 (h'' + U alpha' - b a alpha'')
        + 2 pi rho U b C(k) (h' + U alpha + b (1/2 - a) alpha')                  (lift, up)
    M = pi rho b^2 (b a h'' - U b (1/2 - a) alpha' - b^2 (1/8 + a^2) alpha'')
        + 2 pi rho U b^2 (a + 1/2) C(k) (h' + U alpha + b (1/2 - a) alpha')     (nose up)

with C(k) = H1(k) / (H1(k) + i H0(k)) (Hankel functions of the second kind), k = omega b / U.
For the mode shapes w_j(y) (up, so h = -w) and theta_j(y) (nose-up) the generalised forces
per unit dynamic pressure q = rho U^2 / 2, in asekit's convention F = q Q zeta
(:mod:`asekit.aero.gaf`), are the strip sums

    Q_ij(k) = sum_strips dy [ L_j w_i + M_j theta_i ] / q,

which depend on k only (evaluated with U = 1, rho = 2, omega = k / b). This is the
aerodynamics of Goland's 1945 uniform-wing flutter solution (J. Appl. Mech. 12, A197) and the
two-dimensional limit the 3-D lifting-surface methods (:mod:`asekit.aero.dlm`) tend to at
large aspect ratio.
"""

from __future__ import annotations

import numpy as np
from scipy.special import hankel2

from asekit.aero.validity import check_k
from asekit.util.validate import finite, finite_array, positive


def theodorsen(k) -> np.ndarray:
    """Theodorsen's function C(k) = H1(k) / (H1(k) + i H0(k)), with C(0) = 1 (the steady
    limit).

    Examples
    --------
    >>> c = theodorsen([0.0, 0.1, 1.0])
    >>> np.round(c, 4).tolist()
    [(1+0j), (0.8319-0.1723j), (0.5394-0.1003j)]
    """
    k = check_k(k)
    out = np.ones(k.shape, complex)
    pos = k > 0
    h1, h0 = hankel2(1, k[pos]), hankel2(0, k[pos])
    out[pos] = h1 / (h1 + 1j * h0)
    return out


def strip_gaf(w, theta, widths, semichord, a: float, k) -> np.ndarray:
    """Generalised aerodynamic forces by Theodorsen strip theory (module docstring).

    Parameters
    ----------
    w : (n_strips, n_modes) deflection of each strip's axis, positive up (m per unit modal
        coordinate).
    theta : (n_strips, n_modes) nose-up pitch of each strip about its axis (rad per unit).
    widths : (n_strips,) strip widths dy (m), > 0.
    semichord : the strips' semi-chord b (m), > 0 (also the reference of k).
    a : axis position behind mid-chord in semi-chords (-1 leading edge, +1 trailing edge).
    k : reduced frequencies omega b / U (>= 0), 1-D.

    Returns
    -------
    Q : (n_k, n_modes, n_modes) complex, per unit dynamic pressure.

    Examples
    --------
    A rigid unit-span strip of unit chord pitching about its quarter chord (a = -1/2) at
    k = 0: the lift 2 pi c q per radian and no moment about the quarter chord.

    >>> Q = strip_gaf([[0.0, 1.0]], [[1.0, 0.0]], [1.0], 0.5, -0.5, [0.0])
    >>> np.round(Q[0].real, 12).tolist()            # columns: pitch, plunge
    [[0.0, 0.0], [6.28318530718, 0.0]]
    """
    W = np.atleast_2d(finite_array("w", w))
    T = np.atleast_2d(finite_array("theta", theta))
    dy = np.atleast_1d(finite_array("widths", widths))
    if W.shape != T.shape or dy.shape != (W.shape[0],):
        raise ValueError(f"w {W.shape} and theta {T.shape} must be (n_strips, n_modes) and "
                         f"widths ({W.shape[0]},); got widths {dy.shape}")
    if np.any(dy <= 0):
        raise ValueError("widths must be > 0 (m)")
    b = positive("semichord", semichord)
    a = finite("a", a)
    ks = check_k(k)
    rho, U = 2.0, 1.0                               # q = rho U^2 / 2 = 1
    out = np.empty((ks.size, W.shape[1], W.shape[1]), complex)
    for ik, kk in enumerate(ks):
        om = kk * U / b
        c = theodorsen([kk])[0]
        h = -W                                      # Theodorsen's plunge, positive down
        hd, hdd = 1j * om * h, -om * om * h
        ad, add = 1j * om * T, -om * om * T
        circ = 2 * np.pi * rho * U * b * c * (hd + U * T + b * (0.5 - a) * ad)
        lift = np.pi * rho * b * b * (hdd + U * ad - b * a * add) + circ
        moment = (np.pi * rho * b * b * (b * a * hdd - U * b * (0.5 - a) * ad
                                         - b * b * (0.125 + a * a) * add)
                  + b * (a + 0.5) * circ)
        out[ik] = (W * dy[:, None]).T @ lift + (T * dy[:, None]).T @ moment
    return out
