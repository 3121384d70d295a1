"""Freeplay in the hinge of a control surface (issue 25): the wing with its surface free on a
nonlinear hinge connection, as a :class:`asekit.aeroelastic.nonlinear.ConnectedSystem`.

Model. The wing's modal model with one hinge coordinate per surface
(:func:`asekit.aeroelastic.control_surface.flap_modal_model`: coordinates xi = [zeta, delta],
K = diag(K_ww, k_h), Rodden & Johnson 1994 Sec. 3.5) has the hinge rotation delta of surface
``s`` as a coordinate of its own, relative to the wing, so the relative rotation across the
hinge is simply d = delta_s = e_h . xi (e_h the unit vector of that coordinate). The hinge
spring k_h = K[h, h] is taken out of K (K0 = K - k_h e_h e_h^T) and returned as the connection:
the generalised force of the connection moment f(d) on the structure is -e_h f(d), so

    M xi'' + C xi' + K0 xi = q (Roger aerodynamic forces) - e_h f(e_h . xi),

which in the state space of thesis Eqs. (2.60)-(2.63) (all coordinates free, n_rigid = 0,
:func:`asekit.aeroelastic.statespace.aeroelastic_matrices`) is x' = A0 x + b f(c . x) with
c = [e_h, 0, 0] and b = [0, -M_bar^-1 e_h, 0], M_bar = M - rho b_ref^2 / 2 A2 (thesis Eq. 2.60).
This is exactly the fin-shaft freeplay model of :mod:`asekit.reproduction.freeplay` with the
fin-root pitch row replaced by the hinge coordinate. With f(d) = k_h d (zero gap) A0 + k_h b c^T
is the linear hinge-free aeroelastic state matrix of the same wing.

The freeplay law, harmonic balance and exact time integration are those of
:mod:`asekit.aeroelastic.nonlinear` (Connection, harmonic_balance, simulate_exact): with a
centred freeplay gap the describing function N(A) of the hinge spring covers [0, k_h), so a
harmonic-balance LCO exists at an airspeed exactly when the linear system with some hinge
stiffness k in [0, k_h) is neutrally stable there: the LCO onset is the lowest flutter speed
over k in [0, k_h] (no higher than the flutter speeds with k = 0 and k = k_h).

All quantities SI (rad, N m/rad, m/s).
"""

from __future__ import annotations

import math

import numpy as np

from asekit.aeroelastic.nonlinear import ConnectedSystem, Connection, growth_rate
from asekit.aeroelastic.statespace import aeroelastic_matrices, modal_arrays
from asekit.util.roots import first_crossing
from asekit.util.validate import in_range, integer


def _check_hinge(modal, hinge: int) -> int:
    n = modal.M.shape[0]
    h = integer("hinge", hinge, low=0, high=n - 1)
    if int(getattr(modal, "n_rigid", 0)) != 0:
        raise ValueError("hinge freeplay needs a wing without rigid modes (modal.n_rigid = 0), "
                         f"got n_rigid = {modal.n_rigid}")
    K = np.asarray(modal.K, float)
    off = np.abs(np.delete(K[h], h)).max(initial=0.0)
    if off > 1e-12 * max(abs(K[h, h]), 1e-300):
        raise ValueError(f"hinge = {h} is not a hinge coordinate: K[{h}, :] must be zero off "
                         "the diagonal (the hinge spring couples to nothing else)")
    return h


def hinge_spring(modal, hinge: int) -> float:
    """The hinge spring k_h = K[h, h] (N m/rad) of hinge coordinate ``hinge`` of a flap modal
    model (:attr:`FlapModel.modal`; the surface's coordinate is ``n_wing + surface``).

    Examples
    --------
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> m = ModalArrays(np.eye(2), np.diag([100.0, 0.5]), np.zeros((2, 2)), 0)
    >>> hinge_spring(m, 1)
    0.5
    """
    h = _check_hinge(modal, hinge)
    return float(np.asarray(modal.K, float)[h, h])


def hinge_connection(modal, hinge: int, freeplay: float) -> Connection:
    """The hinge spring of coordinate ``hinge`` as a :class:`Connection` with a centred
    freeplay gap of half-width ``freeplay`` (rad, >= 0; total play 2 ``freeplay``) and no
    stiffness inside the gap.

    Examples
    --------
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> m = ModalArrays(np.eye(2), np.diag([100.0, 0.5]), np.zeros((2, 2)), 0)
    >>> c = hinge_connection(m, 1, 0.01)
    >>> (c.stiffness, c.freeplay, round(float(c.moment(0.03)), 12))
    (0.5, 0.01, 0.01)
    """
    k = hinge_spring(modal, hinge)
    if k <= 0:
        raise ValueError(f"the hinge spring of coordinate {hinge} is {k:g} N m/rad; freeplay "
                         "needs a hinge spring > 0")
    return Connection(stiffness=k, freeplay=in_range("freeplay", freeplay, 0.0, inclusive=True))


def hinge_connected_system(modal, rfa, density: float, velocity: float,
                           hinge: int) -> ConnectedSystem:
    """The wing with its surface's hinge spring removed, around the hinge connection
    (module docstring): x' = A0 x + b f(c . x), d = c . x the hinge rotation (rad).

    Parameters
    ----------
    modal : the flap modal model's :class:`ModalArrays` (wing modes, then the hinge
        coordinates; n_rigid = 0), e.g. ``FlapModel.modal``.
    rfa : a Roger (or minimum-state) fit of the GAFs over the same coordinates.
    density : air density (kg/m^3), > 0.
    velocity : airspeed U (m/s), > 0.
    hinge : index of the surface's hinge coordinate (``n_wing + surface``).

    Returns
    -------
    ConnectedSystem
        States [xi, xi', lag states]; output ``"hinge"`` = d (rad).

    Examples
    --------
    A one-coordinate "wing" (a hinged mass on its spring, no air: an RFA with zero
    coefficients): A(k_h) has the roots +-i sqrt(k_h / I).

    >>> from types import SimpleNamespace
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> from asekit.rfa.roger import roger_fit
    >>> m = ModalArrays(np.eye(1) * 2e-3, np.eye(1) * 0.5, np.zeros((1, 1)), 0)
    >>> fit = roger_fit(np.array([0.1, 0.5, 1.0]), np.zeros((3, 1, 1)), 0.15, n_lags=1)
    >>> s = hinge_connected_system(m, fit, 1.225, 10.0, 0)
    >>> w = np.sort(s.eigenvalues(0.5).imag)
    >>> round(float(w[-1]), 6) == round(math.sqrt(0.5 / 2e-3), 6)
    True
    """
    h = _check_hinge(modal, hinge)
    M = np.asarray(modal.M, float)
    K0 = np.array(modal.K, float)
    K0[h, h] = 0.0
    m0 = modal_arrays(M=M, K=K0, C=np.asarray(modal.C, float), n_rigid=0)
    mats = aeroelastic_matrices(m0, rfa, density, velocity)
    n, nz = M.shape[0], mats.n_states
    Mb = M - 0.5 * density * rfa.b_ref ** 2 * np.asarray(rfa.A[2], float)      # Eq. (2.60)
    e = np.zeros(n)
    e[h] = 1.0
    b = np.zeros(nz)
    b[n:2 * n] = -np.linalg.solve(Mb, e)
    c = np.zeros(nz)
    c[:n] = e
    return ConnectedSystem(mats.A, b, c, outputs={"hinge": (c.copy(), np.zeros(0))},
                           velocity=float(velocity), state_names=tuple(mats.state_names))


def connected_flutter_speed(system_at, stiffness: float, u_lo: float, u_hi: float,
                            n: int = 40, min_frequency_hz: float = 0.05):
    """Lowest airspeed (m/s) in [u_lo, u_hi] at which the linear system A0 + k b c^T of
    ``system_at(U)`` (a :class:`ConnectedSystem` per airspeed) has an unstable oscillatory
    root, by a scan of ``n`` speeds and Brent's method on the growth rate; and that root's
    frequency (Hz). (None, None) when stable throughout.

    Examples
    --------
    A system whose damping -1 + U / 10 (1/s) crosses zero at 10 m/s:

    >>> A = lambda U: np.array([[-1 + U / 10, 5.0], [-5.0, -1 + U / 10]])
    >>> at = lambda U: ConnectedSystem(A(U), np.zeros(2), np.zeros(2))
    >>> u, f = connected_flutter_speed(at, 0.0, 1.0, 20.0)
    >>> round(u, 4), round(f * 2 * math.pi, 4)
    (10.0, 5.0)
    """
    n = integer("n", n, low=2)
    if not (0 < u_lo < u_hi):
        raise ValueError(f"need 0 < u_lo < u_hi (m/s), got {u_lo!r}, {u_hi!r}")
    k = float(stiffness)

    def sig(u):
        return growth_rate(system_at(u), k, min_frequency_hz)[0]

    uf = first_crossing(sig, np.linspace(u_lo, u_hi, n), xtol=1e-6, rtol=1e-10,
                        at_start=f"already unstable at u_lo = {u_lo:g} m/s with k = {k:g} N m/rad")
    if uf is None:
        return None, None
    w = growth_rate(system_at(uf), k, min_frequency_hz)[1]
    return float(uf), float(w / (2 * math.pi))
