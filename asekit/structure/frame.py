"""A 3-D frame element in any orientation: the bar of a stick model (Nastran's CBAR idea).

The element joins two nodes with six degrees of freedom each, (u_x, u_y, u_z, r_x, r_y, r_z)
per node. Its own frame follows Nastran's CBAR convention (MSC Nastran Quick Reference Guide,
CBAR): e_x from node A to node B; the orientation vector v fixes plane 1, the plane of e_x and
v: e_y is the part of v normal to e_x, e_z = e_x x e_y. Bending in plane 1 (deflection along
e_y, slope r_z = dv/dx) has stiffness E I1; bending in plane 2 (deflection along e_z,
r_y = -dw/dx) has E I2; axial E A, St Venant torsion G J.

Local stiffness: Przemieniecki, *Theory of Matrix Structural Analysis* (McGraw-Hill 1968),
Eq. 5.116 (cubic Hermite deflections, linear axial and twist; with a finite shear stiffness
K G A per plane its shear parameter Phi, Timoshenko's shear flexibility, as Nastran's PBEAM
K1 / K2 and PBAR K1 / K2 ask). Mass: the consistent ("coupled")
matrix of the same shape functions, Przemieniecki Eq. 11.41 for axial and transverse motion, or
the lumped one, m L / 2 on each node's three translations (Nastran's default for the CBAR,
PARAM COUPMASS < 1). A CBAR carries no polar (torsional) mass moment: its mass is m = rho A
+ NSM per length on its axis (its PBAR has no polar-inertia field; torsional inertia is given by
point masses). A CBEAM carries I_p = rho (I1 + I2) per length on its twist, with the same
linear shape (I_p L / 6 [[2, 1], [1, 2]], or I_p L / 2 on each end when lumped): Simcenter
Nastran 2019.2's lumped modes of pyNastran's beam_modes deck (data/benchmarks/beam_modes) have
it on the CBEAM and not on the CBARs.

Global matrices: with the direction-cosine matrix R (rows e_x, e_y, e_z in the global frame)
and T = diag(R, R, R, R) (12 x 12), u_local = T u_global and

    K_global = T^T K_local T,  M_global = T^T M_local T          (Przemieniecki Eq. 6.26),

so the element's frequencies do not depend on how the structure is placed in space. SI units.

A bar whose section varies along it (Nastran's tapered PBEAM / PBEAML):
:func:`tapered_bar_matrices`, its stiffness from the flexibility of the element clamped at one
end (exact for end loads whatever the variation), its mass from the same shape functions with
the mass per length under the integral.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.util.validate import finite_array, in_range, positive

#: degrees of freedom per node: u_x, u_y, u_z, r_x, r_y, r_z.
NODE_DOF = 6


@dataclass(frozen=True)
class BarSection:
    """Stiffness and mass of a bar's cross-section (SI), uniform along the element.

    Parameters
    ----------
    ea : axial stiffness E A (N), > 0.
    gj : torsional stiffness G J (N m^2), >= 0.
    ei1 : bending stiffness in plane 1, E I1 (deflection along e_y) (N m^2), >= 0.
    ei2 : bending stiffness in plane 2, E I2 (deflection along e_z) (N m^2), >= 0.
    mass : mass per length m = rho A + NSM (kg/m), >= 0.
    gas1, gas2 : transverse shear stiffness K G A of plane 1 and plane 2 (N), > 0; inf
        (default) neglects the shear flexibility (Euler-Bernoulli).
    polar : polar mass moment of inertia per length about the axis, rho (I1 + I2) (kg m),
        >= 0 (default 0: Nastran's CBAR has none; its CBEAM has it).

    Examples
    --------
    >>> BarSection(ea=1e6, gj=10.0, ei1=5.0, ei2=0.0, mass=2.0).ei2
    0.0
    """

    ea: float
    gj: float
    ei1: float
    ei2: float
    mass: float
    gas1: float = math.inf
    gas2: float = math.inf
    polar: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "ea", positive("ea", self.ea))
        for name in ("gj", "ei1", "ei2", "mass", "polar"):
            object.__setattr__(self, name, in_range(name, getattr(self, name), 0.0, True))
        for name in ("gas1", "gas2"):
            v = float(getattr(self, name))
            if not v > 0:
                raise ValueError(f"{name} must be > 0 N (inf: no shear flexibility), got {v}")
            object.__setattr__(self, name, v)


def bar_frame(xa, xb, v) -> tuple[float, np.ndarray]:
    """Length and direction cosines of a bar from node A to node B with orientation vector v.

    Parameters
    ----------
    xa, xb : (3,) node positions (m), distinct.
    v : (3,) orientation vector (any length), not parallel to B - A.

    Returns
    -------
    (L, R) : the length (m) and the (3, 3) matrix whose rows are e_x, e_y, e_z (Nastran's
        CBAR element frame: e_x = (B - A)/L, e_y = the part of v normal to e_x, normalised,
        e_z = e_x x e_y).

    Examples
    --------
    >>> L, R = bar_frame([0, 0, 0], [0, 2, 0], [0, 0, 1])
    >>> float(L), R[0].tolist(), R[2].tolist()
    (2.0, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    """
    xa, xb, v = (finite_array(n, a).reshape(3) for n, a in (("xa", xa), ("xb", xb), ("v", v)))
    d = xb - xa
    L = float(np.linalg.norm(d))
    if L <= 1e-12 * max(1.0, float(np.linalg.norm(xa))):
        raise ValueError("xb must differ from xa (a bar of zero length)")
    ex = d / L
    vy = v - (v @ ex) * ex
    nv = float(np.linalg.norm(vy))
    if nv <= 1e-9 * max(float(np.linalg.norm(v)), 1e-300):
        raise ValueError("v must not be parallel to the bar's axis xb - xa (or zero)")
    ey = vy / nv
    return L, np.vstack([ex, ey, np.cross(ex, ey)])


def _bending(ei: float, m: float, L: float, slope_sign: float, coupled: bool,
             gas: float = math.inf):
    """(4, 4) stiffness and mass of one bending plane, DOFs (w1, r1, w2, r2), r = slope_sign w'
    (Przemieniecki Eqs. 5.116 and 11.41). With a finite shear stiffness ``gas`` = K G A the
    stiffness is Przemieniecki's Eq. 5.116 with the shear parameter Phi = 12 E I / (K G A L^2)
    (exact for end loads: tip deflection P L^3 / (3 E I) + P L / (K G A)); the mass stays
    Eq. 11.41's (no shear terms)."""
    phi = 12 * ei / (gas * L * L) if math.isfinite(gas) else 0.0
    a, b = (4 + phi) * L * L, (2 - phi) * L * L
    k = ei / ((1 + phi) * L ** 3) * np.array([[12, 6 * L, -12, 6 * L], [6 * L, a, -6 * L, b],
                                              [-12, -6 * L, 12, -6 * L], [6 * L, b, -6 * L, a]])
    if coupled:
        mm = m * L / 420 * np.array([[156, 22 * L, 54, -13 * L],
                                     [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                     [54, 13 * L, 156, -22 * L],
                                     [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    else:
        mm = np.diag([m * L / 2, 0.0, m * L / 2, 0.0])
    s = np.diag([1.0, slope_sign, 1.0, slope_sign])
    return s @ k @ s, s @ mm @ s


def bar_matrices(section: BarSection, length: float, coupled: bool = True):
    """Local stiffness and mass (12 x 12) of a bar, DOFs (u1, u2, u3, r1, r2, r3) of node A,
    then of node B, in the element frame of :func:`bar_frame`.

    Parameters
    ----------
    section : :class:`BarSection`.
    length : L (m), > 0.
    coupled : the consistent mass (True, Nastran's PARAM COUPMASS 1) or the lumped one.

    Returns
    -------
    (K, M) : (12, 12) symmetric arrays (SI). Blocks: axial E A / L [[1, -1], [-1, 1]] with
        mass m L / 6 [[2, 1], [1, 2]] (coupled); torsion G J / L with mass I_p L / 6
        [[2, 1], [1, 2]] (lumped I_p L / 2 each; I_p = ``polar``, 0 for a CBAR); plane 1 (u2, r3 =
        u2') with E I1 and plane 2 (u3, r2 = -u3') with E I2 by Hermite cubics.

    Examples
    --------
    >>> K, M = bar_matrices(BarSection(1.0, 1.0, 1.0, 1.0, 3.0), 2.0)
    >>> round(float(M[np.ix_([2, 8], [2, 8])].sum()), 12)     # transverse mass m L
    6.0
    """
    L = positive("length", length)
    s = section
    K = np.zeros((12, 12))
    M = np.zeros((12, 12))
    ax, tw = np.array([0, 6]), np.array([3, 9])
    K[np.ix_(ax, ax)] = s.ea / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M[np.ix_(ax, ax)] = (s.mass * L / 6 * np.array([[2.0, 1.0], [1.0, 2.0]]) if coupled
                         else np.diag([s.mass * L / 2] * 2))
    K[np.ix_(tw, tw)] = s.gj / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M[np.ix_(tw, tw)] = (s.polar * L / 6 * np.array([[2.0, 1.0], [1.0, 2.0]]) if coupled
                         else np.diag([s.polar * L / 2] * 2))
    for dofs, ei, sign, gas in (([1, 5, 7, 11], s.ei1, 1.0, s.gas1),
                                ([2, 4, 8, 10], s.ei2, -1.0, s.gas2)):
        k, m = _bending(ei, s.mass, L, sign, coupled, gas)
        K[np.ix_(dofs, dofs)] = k
        M[np.ix_(dofs, dofs)] = m
    return K, M


def rotate(A: np.ndarray, R: np.ndarray) -> np.ndarray:
    """A 12 x 12 element matrix from the element frame to the global one: T^T A T with
    T = diag(R, R, R, R) (Przemieniecki Eq. 6.26).

    Examples
    --------
    >>> R = np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])
    >>> A = np.eye(12)
    >>> bool(np.allclose(rotate(A, R), A))
    True
    """
    T = np.kron(np.eye(4), np.asarray(R, float))
    return T.T @ np.asarray(A, float) @ T


def global_bar_matrices(xa, xb, v, section: BarSection, coupled: bool = True):
    """Stiffness and mass (12 x 12) of a bar in the global frame: :func:`bar_frame`, then
    :func:`bar_matrices`, then :func:`rotate`.

    Returns
    -------
    (K, M) : (12, 12) arrays, DOFs (u_x, u_y, u_z, r_x, r_y, r_z) of A then B (SI).

    Examples
    --------
    >>> K, M = global_bar_matrices([0, 0, 0], [1, 1, 0], [0, 0, 1],
    ...                            BarSection(1.0, 1.0, 1.0, 1.0, 1.0))
    >>> bool(np.allclose(K, K.T)) and round(float(M[np.ix_([2, 8], [2, 8])].sum()), 12)
    1.414213562373
    """
    L, R = bar_frame(xa, xb, v)
    K, M = bar_matrices(section, L, coupled)
    return rotate(K, R), rotate(M, R)


# ---------------------------------------------------------------------------------------------
# a bar whose section varies along it (Nastran's tapered PBEAM / PBEAML)
# ---------------------------------------------------------------------------------------------
def _gauss_points(breaks, n: int, parts: int = 4):
    """Composite Gauss-Legendre points and weights on [0, 1]: each interval between
    ``breaks`` cut into ``parts`` equal pieces of n points (the flexibility integrands
    1 / EI are not polynomials: a strong taper puts their pole near the interval)."""
    g, w = np.polynomial.legendre.leggauss(n)
    xs, ws = [], []
    for a0, b0 in zip(breaks[:-1], breaks[1:]):
        cuts = np.linspace(a0, b0, parts + 1)
        for a, b in zip(cuts[:-1], cuts[1:]):
            xs.append(a + (b - a) * (g + 1) / 2)
            ws.append((b - a) / 2 * w)
    return np.concatenate(xs), np.concatenate(ws)


def _hermite(xi, L):
    """Cubic Hermite functions (w1, w1', w2, w2') on xi in [0, 1] of a bar of length L."""
    return np.array([1 - 3 * xi ** 2 + 2 * xi ** 3, L * (xi - 2 * xi ** 2 + xi ** 3),
                     3 * xi ** 2 - 2 * xi ** 3, L * (xi ** 3 - xi ** 2)])


def _end_flexibility_stiffness(f11, f12, f22, L, sign):
    """(4, 4) stiffness of one bending plane, DOFs (w1, r1, w2, r2), r = sign w', from the
    flexibility (f11, f12, f22) of end B of the bar clamped at A, loads (P, M) -> (w, w'):
    K_BB = F^-1 and, with the rigid-body map R = [[1, L], [0, 1]] of end A's (w, w') to
    end B, K = [[R^T K_BB R, -R^T K_BB], [-K_BB R, K_BB]] (equilibrium of the free body)."""
    Kbb = np.linalg.inv(np.array([[f11, f12], [f12, f22]]))
    R = np.array([[1.0, L], [0.0, 1.0]])
    k = np.block([[R.T @ Kbb @ R, -R.T @ Kbb], [-Kbb @ R, Kbb]])
    s = np.diag([1.0, sign, 1.0, sign])
    return s @ k @ s


def tapered_bar_matrices(section_at, length: float, breaks=(0.0, 1.0), coupled: bool = True,
                         n_gauss: int = 16):
    """Local stiffness and mass (12 x 12) of a bar whose section varies along it, DOFs and
    frame as :func:`bar_matrices` (which it reproduces for a uniform section).

    Stiffness from the flexibility of the bar clamped at end A under end-B loads, exact for a
    bar loaded only at its ends whatever the variation (the force method: complementary
    energy of the end loads' internal forces, Przemieniecki 1968 Ch. 5, the cantilever
    flexibility inverted and completed by equilibrium as in its derivation of Eq. 5.116):
    per bending plane, with x from A and xi = x / L,

        f11 = int (L - x)^2 / EI dx + int 1 / (K G A) dx,  f12 = int (L - x) / EI dx,
        f22 = int 1 / EI dx,

    axial stiffness 1 / int 1 / (E A) dx and torsional 1 / int 1 / (G J) dx. Mass: the
    consistent matrix of the uniform bar's shape functions with m(x) (Przemieniecki Eq. 11.41
    with m under the integral: int m N^T N dx, Hermite cubics across, linear along and in
    twist with the polar inertia), or the lumped one, int m (1 - xi) dx and int m xi dx on
    A's and B's translations (and the polar inertia likewise on their twists). Integrals by
    composite Gauss-Legendre quadrature, each interval between ``breaks`` (the stations where
    the section's interpolation changes slope) in four pieces of ``n_gauss`` points (the
    flexibility of a linear E I from 1 to 1/27 along the bar to 1e-10).

    Parameters
    ----------
    section_at : callable xi -> :class:`BarSection` (xi in [0, 1], 0 at A).
    length : L (m), > 0.
    breaks : ascending stations from 0.0 to 1.0 (the section is smooth between them).
    coupled : consistent (True) or lumped mass.
    n_gauss : quadrature points per piece (>= 2).

    Returns
    -------
    (K, M) : (12, 12) symmetric arrays (SI).

    Examples
    --------
    A uniform section gives the uniform bar:

    >>> s = BarSection(2.0, 1.0, 3.0, 4.0, 5.0)
    >>> K, M = tapered_bar_matrices(lambda xi: s, 1.5)
    >>> K0, M0 = bar_matrices(s, 1.5)
    >>> bool(np.allclose(K, K0, rtol=1e-12) and np.allclose(M, M0, rtol=1e-12))
    True
    """
    L = positive("length", length)
    breaks = np.asarray(breaks, float)
    if (breaks.ndim != 1 or breaks.size < 2 or breaks[0] != 0.0 or breaks[-1] != 1.0
            or np.any(np.diff(breaks) <= 0)):
        raise ValueError(f"breaks must ascend strictly from 0.0 to 1.0, got {breaks.tolist()}")
    if int(n_gauss) < 2:
        raise ValueError(f"n_gauss must be >= 2, got {n_gauss}")
    xi, wq = _gauss_points(breaks, int(n_gauss))
    secs = [section_at(float(x)) for x in xi]
    val = {k: np.array([getattr(s, k) for s in secs], float)
           for k in ("ea", "gj", "ei1", "ei2", "mass", "gas1", "gas2", "polar")}
    if np.any(val["ea"] <= 0):
        raise ValueError("the section's ea must be > 0 along the bar")
    dx = wq * L
    K, M = np.zeros((12, 12)), np.zeros((12, 12))
    ax, tw = np.array([0, 6]), np.array([3, 9])
    unit = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[np.ix_(ax, ax)] = unit / np.sum(dx / val["ea"])
    with np.errstate(divide="ignore"):
        flex_gj = np.sum(dx / val["gj"])
    K[np.ix_(tw, tw)] = unit * (1.0 / flex_gj if np.isfinite(flex_gj) else 0.0)
    m = val["mass"]
    N = _hermite(xi, L)
    lin = np.array([1 - xi, xi])
    for dofs, ei, gas, sign in (([1, 5, 7, 11], val["ei1"], val["gas1"], 1.0),
                                ([2, 4, 8, 10], val["ei2"], val["gas2"], -1.0)):
        if np.all(ei > 0):
            arm = L * (1 - xi)
            f11 = np.sum(dx * arm ** 2 / ei) + np.sum(dx / gas)
            K[np.ix_(dofs, dofs)] = _end_flexibility_stiffness(
                f11, np.sum(dx * arm / ei), np.sum(dx / ei), L, sign)
        elif np.any(ei > 0):
            raise ValueError("a bending stiffness that vanishes on part of the bar only")
        if coupled:
            s = np.diag([1.0, sign, 1.0, sign])
            M[np.ix_(dofs, dofs)] = s @ ((N * (m * dx)) @ N.T) @ s
    ip = val["polar"]
    if coupled:
        M[np.ix_(ax, ax)] = (lin * (m * dx)) @ lin.T
        M[np.ix_(tw, tw)] = (lin * (ip * dx)) @ lin.T
    else:
        mab = (lin * (m * dx)).sum(axis=1)
        pab = (lin * (ip * dx)).sum(axis=1)
        for node, (mm, pp) in enumerate(zip(mab, pab)):
            for c in range(3):
                M[6 * node + c, 6 * node + c] = mm
            M[6 * node + 3, 6 * node + 3] = pp
    return K, M


def global_tapered_bar_matrices(xa, xb, v, section_at, breaks=(0.0, 1.0),
                                coupled: bool = True):
    """:func:`tapered_bar_matrices` in the global frame (:func:`bar_frame`, :func:`rotate`).

    Returns
    -------
    (K, M) : (12, 12) arrays, DOFs (u_x, u_y, u_z, r_x, r_y, r_z) of A then B (SI).

    Examples
    --------
    >>> s = BarSection(1.0, 1.0, 1.0, 1.0, 1.0)
    >>> K, M = global_tapered_bar_matrices([0, 0, 0], [1, 1, 0], [0, 0, 1], lambda xi: s)
    >>> round(float(M[np.ix_([2, 8], [2, 8])].sum()), 12)
    1.414213562373
    """
    L, R = bar_frame(xa, xb, v)
    K, M = tapered_bar_matrices(section_at, L, breaks, coupled)
    return rotate(K, R), rotate(M, R)
