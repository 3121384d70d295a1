"""Piston theory for supersonic lifting surfaces, first to third order, per box of a BoxMesh.

References (equation numbers below refer to these):

- [L53] M. J. Lighthill, "Oscillating airfoils at high Mach number", J. Aeronaut. Sci. 20(6),
  1953, 402-406: the surface acts as a piston in a one-dimensional simple wave,
  p / p_inf = (1 + (gamma - 1)/2 * v_n / a_inf)^(2 gamma / (gamma - 1))  (his Eq. 2),
  whose expansion to third order in W = v_n / a_inf is
  p / p_inf = 1 + gamma W + gamma (gamma + 1)/4 W^2 + gamma (gamma + 1)/12 W^3  (his Eq. 5).
- [AZ56] H. Ashley, G. Zartarian, "Piston theory -- a new aerodynamic tool for the
  aeroelastician", J. Aeronaut. Sci. 23(12), 1956, 1109-1118: the expansion applied to each
  surface of a profiled section with the thickness slopes (their Eqs. 6-8), and its range of
  validity, M^2 >> 1 or k^2 M^2 >> 1, with M tau not much larger than 1 (their Section II).

Formulation. A thin section of half-thickness z_t(x) (symmetric: upper surface z_t + h, lower
-z_t + h) moving with the normal displacement h(x, y) exp(i omega t) has the surface normal
velocities v_n,upper = U (tau + w/U) and v_n,lower = U (tau - w/U), tau = dz_t/dx the
thickness slope and w/U = dh/dx + i k h / b the normalwash of :mod:`asekit.aero.dlm`. Putting
both into the [L53] Eq. 5 expansion and keeping the part linear in w (the perturbation about
the steady thickness flow) gives, with q = gamma p_inf M^2 / 2,

    DeltaCp = (p_lower - p_upper) / q
            = -(4 / M) (w/U) [1 + c2 (gamma + 1)/2 M tau + c3 (gamma + 1)/4 M^2 tau^2],

(c2 = c3 = 0 first order, c2 = 1 second order, c2 = c3 = 1 third order; [AZ56] Eqs. 7-8
for the surface pressures). First order, DeltaCp = -(4/M) w/U, is Ackeret's 4 alpha / beta
with beta -> M. Delta Cp > 0 pushes the box along +z, the sign convention of the DLM.

The pressure is local: it depends on w at the same point. On a box mesh whose normalwash is
given at the DLM control points (3/4 chord) and whose forces are taken at the load points
(1/4 chord, :mod:`asekit.aero.gaf`), asekit evaluates the local law at the box centroids,
interpolating w linearly along the chordwise strip from the control points, and moves each
centroid force to the load points by the transpose of the same linear interpolation
(virtual-work consistent, so rigid plunge and pitch are integrated exactly). The matrix
returned, DeltaCp = A (w/U), is therefore the same kind of pressure-per-normalwash matrix as
the DLM's AIC and feeds :mod:`asekit.aero.gaf` unchanged.

Validity ([AZ56] Section II; [L53]): the first-order error in the steady lift is the ratio
M / sqrt(M^2 - 1) - 1 (13 % at M 2, 6 % at M 3), and it falls as 1 / (k M)^2 at high reduced
frequency. asekit calls a case valid when M >= PISTON_MACH_MIN (2) or M k >= PISTON_MK_MIN (2,
k on the reference semi-chord), and, from second order on, M |tau| <= 1 (the expansion of
[L53] Eq. 2 in W needs |W| = M |tau| < 1). Outside it a :class:`PistonValidityWarning` names
the Mach number and k. M <= 1 raises ValueError.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from asekit.aero.boxes import BoxMesh
from asekit.aero.validity import SUPERSONIC, check_k, check_mach

#: Validity bound ([AZ56] Section II, asekit's choice of ">>"): M >= 2 or M k >= 2.
PISTON_MACH_MIN = 2.0
PISTON_MK_MIN = 2.0


class PistonValidityWarning(UserWarning):
    """A piston-theory case lies outside the validity bound (Mach and k are named)."""


def check_supersonic_mach(mach: float, name: str = "mach") -> float:
    """Finite Mach number > 1 (:data:`asekit.aero.validity.SUPERSONIC`; raises ValueError
    naming ``name`` otherwise)."""
    return check_mach(mach, SUPERSONIC, "the supersonic methods", name)


def piston_validity(mach: float, k: float, tau_max: float = 0.0, order: int = 1) -> bool:
    """True when (M, k) lies inside the bound of the module docstring: M >= 2 or M k >= 2, and
    M |tau_max| <= 1 when ``order`` >= 2."""
    ok = mach >= PISTON_MACH_MIN or mach * k >= PISTON_MK_MIN
    if order >= 2:
        ok = ok and mach * abs(tau_max) <= 1.0
    return bool(ok)


def strip_interpolation(mesh: BoxMesh, box: np.ndarray, x: np.ndarray,
                        which: str = "control") -> np.ndarray:
    """Linear-in-x interpolation matrix G (n_points, n_boxes) from values at the boxes' control
    points (``which="control"``) or load points (``"load"``) to points at streamwise position
    ``x`` (m) lying in box ``box`` (indices into ``mesh``), along that box's chordwise strip
    (linear extrapolation beyond the first and last point of the strip; constant on a strip of
    one box). Exact for fields linear in x along a strip."""
    ref = mesh.control_point if which == "control" else mesh.load_point
    box = np.asarray(box, int)
    x = np.asarray(x, float)
    g = np.zeros((box.size, mesh.n))
    strips = mesh.strip[box]
    for s in np.unique(strips):
        members = np.flatnonzero(mesh.strip == s)
        members = members[np.argsort(ref[members, 0])]
        rows = np.flatnonzero(strips == s)
        if members.size == 1:
            g[rows, members[0]] = 1.0
            continue
        xs = ref[members, 0]
        j = np.clip(np.searchsorted(xs, x[rows]), 1, members.size - 1)
        t = (x[rows] - xs[j - 1]) / (xs[j] - xs[j - 1])
        g[rows, members[j - 1]] = 1.0 - t
        g[rows, members[j]] = t
    return g


def box_centroids(mesh: BoxMesh) -> np.ndarray:
    """Area centroids (n, 3) of the (trapezoidal) boxes."""
    c = mesh.corners
    a = c[:, 1, 0] - c[:, 0, 0]                  # inboard chord
    b = c[:, 2, 0] - c[:, 3, 0]                  # outboard chord
    # centroid of a trapezoid with parallel (streamwise) sides a, b: spanwise fraction from
    # the inboard side (a + 2 b) / (3 (a + b)); chordwise at the mid-chord line there
    f = ((a + 2.0 * b) / (3.0 * (a + b)))[:, None]
    le = c[:, 0] + f * (c[:, 3] - c[:, 0])
    te = c[:, 1] + f * (c[:, 2] - c[:, 1])
    return 0.5 * (le + te)


def _thickness(mesh: BoxMesh, thickness_slope) -> np.ndarray:
    if thickness_slope is None:
        return np.zeros(mesh.n)
    tau = np.broadcast_to(np.asarray(thickness_slope, float), (mesh.n,)).copy()
    if not np.all(np.isfinite(tau)):
        raise ValueError("thickness_slope must be finite (dz_t/dx of the upper surface per box)")
    return tau


def piston_coefficient(mach: float, order: int = 1, thickness_slope=0.0,
                       gamma: float = 1.4) -> np.ndarray:
    """The local factor c with DeltaCp = c (w/U) (module docstring):
    c = -(4/M) [1 + c2 (gamma+1)/2 M tau + c3 (gamma+1)/4 M^2 tau^2]."""
    m = check_supersonic_mach(mach)
    if order not in (1, 2, 3):
        raise ValueError(f"order must be 1, 2 or 3, got {order!r}")
    if not (math.isfinite(gamma) and gamma > 1.0):
        raise ValueError(f"gamma must be a finite ratio of specific heats > 1, got {gamma!r}")
    tau = np.asarray(thickness_slope, float)
    m = np.float64(m)
    with np.errstate(over="ignore", invalid="ignore"):
        c = 1.0 + 0.0 * tau
        if order >= 2:
            c = c + 0.5 * (gamma + 1.0) * m * tau
        if order >= 3:
            c = c + 0.25 * (gamma + 1.0) * m**2 * tau**2
        c = -(4.0 / m) * c
    if not np.all(np.isfinite(c)):
        raise ValueError(f"mach = {float(m):g} with thickness_slope up to "
                         f"{float(np.max(np.abs(tau))):g} overflows the order-{order} piston "
                         "coefficient: mach must be a physical Mach number (piston theory: "
                         "M >= 2, M |tau| <= 1)")
    return c


def piston_transfer(mesh: BoxMesh) -> tuple[np.ndarray, np.ndarray]:
    """(S, T), each (n, n): S takes w/U at the control points to the box centroids, T takes h
    at the load points to the centroids (both :func:`strip_interpolation`)."""
    cen = box_centroids(mesh)
    idx = np.arange(mesh.n)
    return (strip_interpolation(mesh, idx, cen[:, 0], "control"),
            strip_interpolation(mesh, idx, cen[:, 0], "load"))


def piston_pressure_matrices(mesh: BoxMesh, mach: float, k, b_ref: float, order: int = 1,
                             thickness_slope=None, gamma: float = 1.4,
                             warn: bool = True) -> np.ndarray:
    """Piston-theory pressure-per-normalwash matrices A (n_k, n, n) complex, DeltaCp = A (w/U),
    ``w/U`` at the DLM control points, DeltaCp lumped at the load points (module docstring).

    Parameters
    ----------
    mesh : a planar or nonplanar :class:`~asekit.aero.boxes.BoxMesh` (the law is local).
    mach : M > 1.
    k : reduced frequencies omega b_ref / U >= 0 (only the validity check uses them: the
        piston law has no memory).
    b_ref : reference semi-chord of k (m) > 0.
    order : 1, 2 or 3 ([L53] Eq. 5 truncated).
    thickness_slope : dz_t/dx of the upper surface at each box (n,) or scalar; None = flat.
    gamma : ratio of specific heats (1.4).
    warn : :class:`PistonValidityWarning` naming M and k outside the bound.
    """
    m = check_supersonic_mach(mach)
    ks = check_k(k)
    if not (math.isfinite(float(b_ref)) and float(b_ref) > 0):
        raise ValueError(f"b_ref must be a finite reference semi-chord > 0 m, got {b_ref!r}")
    tau = _thickness(mesh, thickness_slope)
    if warn:
        bad = [float(kk) for kk in ks if not piston_validity(m, kk, float(np.abs(tau).max()),
                                                             order)]
        if bad:
            warnings.warn(f"piston theory outside its validity bound at mach={m:g}, k={bad[:6]} "
                          f"(needs M >= {PISTON_MACH_MIN:g} or M k >= {PISTON_MK_MIN:g}, and "
                          "M |thickness slope| <= 1 from second order on)",
                          PistonValidityWarning, stacklevel=2)
    c = piston_coefficient(m, order, tau, gamma)
    s, t = piston_transfer(mesh)
    area = mesh.area
    a = (t.T * (area * c)[None, :]) @ s / area[:, None]
    out = np.empty((ks.size, mesh.n, mesh.n), complex)
    out[:] = a[None]
    return out


def piston_pressure_matrix(mesh: BoxMesh, mach: float, k: float, b_ref: float, order: int = 1,
                           thickness_slope=None, gamma: float = 1.4,
                           warn: bool = True) -> np.ndarray:
    """A (n, n) at one reduced frequency; see :func:`piston_pressure_matrices`."""
    if np.ndim(k) != 0:
        raise ValueError(f"k must be a scalar reduced frequency, got shape {np.shape(k)}")
    return piston_pressure_matrices(mesh, mach, [k], b_ref, order, thickness_slope, gamma,
                                    warn)[0]
