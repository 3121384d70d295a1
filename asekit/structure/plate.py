"""MITC4 Reissner-Mindlin plate bending element (Bathe & Dvorkin 1985) and its consistent mass.

Reference: K.-J. Bathe and E. N. Dvorkin, "A four-node plate bending element based on
Mindlin/Reissner plate theory and a mixed interpolation", Int. J. Numer. Meth. Eng. 21 (1985)
367-383 (the "MITC4" element); also Bathe, *Finite Element Procedures* (1996), Ch. 5
(plate bending elements based on Reissner-Mindlin theory).

Degrees of freedom per node, in this order: ``w`` (m, +z), ``theta_x``, ``theta_y`` (rad,
right-handed rotations about +x and +y). A positive ``theta_y`` is nose-up: the trailing edge
moves down. Kinematics (z through the thickness):

    u = z * theta_y,   v = -z * theta_x,   w = w(x, y)

so that the curvatures and transverse shear strains are

    kappa = [d theta_y/dx, -d theta_x/dy, d theta_y/dy - d theta_x/dx]
    gamma_xz = dw/dx + theta_y,   gamma_yz = dw/dy - theta_x,

and the Kirchhoff limit (gamma = 0) is ``theta_y = -dw/dx``, ``theta_x = dw/dy``.

Bending uses the bilinear interpolation of w and of the rotations (isoparametric Q4).
Transverse shear uses the MITC4 assumed covariant strains tied at the mid-sides
A (0, 1), B (-1, 0), C (0, -1), D (1, 0) (the mixed interpolation of Bathe & Dvorkin 1985):

    e_rz = 1/2 (1 + s) e_rz^A + 1/2 (1 - s) e_rz^C
    e_sz = 1/2 (1 + r) e_sz^D + 1/2 (1 - r) e_sz^B

which removes shear locking: the element passes the patch test and stays accurate as h -> 0.
The in-plane (membrane) behaviour of the flat fin is uncoupled from bending and does not interact
with the aerodynamics; it is not part of this element or of the modal model.
:func:`membrane_matrices` (plane-stress Q4) exists only to examine the thesis's in-plane mode.

The thickness ``h`` may vary in the element: it is evaluated at each integration point from the
mesh's spanwise law (``thickness_rule="gauss"``) or taken constant at the element centroid
(``"centroid"``, as a per-element Nastran PSHELL would).
"""

from __future__ import annotations

import numpy as np

from asekit.geometry import Material
from asekit.structure.mesh import PlateMesh

#: Natural coordinates of the four corner nodes, counter-clockwise.
NODE_RS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
#: Shear correction factor of Reissner-Mindlin theory.
SHEAR_FACTOR = 5.0 / 6.0
DOF_PER_NODE = 3


def gauss_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor-product Gauss-Legendre rule on [-1, 1]^2: points (n*n, 2) and weights (n*n,)."""
    g, w = np.polynomial.legendre.leggauss(n)
    r, s = np.meshgrid(g, g, indexing="ij")
    wr, ws = np.meshgrid(w, w, indexing="ij")
    return np.stack([r.ravel(), s.ravel()], axis=1), (wr * ws).ravel()


def shape_functions(r, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bilinear shape functions N_i = (1 + r r_i)(1 + s s_i) / 4 and their r, s derivatives.

    ``r``, ``s`` broadcast together; the outputs have a trailing axis of length 4.
    """
    r = np.asarray(r, float)[..., None]
    s = np.asarray(s, float)[..., None]
    ri, si = NODE_RS[:, 0], NODE_RS[:, 1]
    N = 0.25 * (1 + r * ri) * (1 + s * si)
    dNr = 0.25 * ri * (1 + s * si)
    dNs = 0.25 * si * (1 + r * ri)
    return N, dNr, dNs


def _jacobian(xy: np.ndarray, r: float, s: float):
    """Jacobian J[e] = [[x_r, y_r], [x_s, y_s]] (n_elem, 2, 2) at (r, s), its determinant and
    the r/s shape-function derivatives."""
    N, dNr, dNs = shape_functions(r, s)
    J = np.stack([dNr @ xy, dNs @ xy], axis=1)      # xy (ne, 4, 2) -> (ne, 2, 2)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    return N, dNr, dNs, J, det


def _check_geometry(det: np.ndarray):
    bad = np.flatnonzero(det <= 0)
    if bad.size:
        raise ValueError(f"elements {bad[:10].tolist()} are inverted or degenerate "
                         f"(det J <= 0): node order must be counter-clockwise")


def _thickness(mesh: PlateMesh, xy: np.ndarray, N: np.ndarray, rule: str) -> np.ndarray:
    ct = getattr(mesh, "corner_thickness", None)
    if ct is not None:                              # per-element corner thicknesses (T1-T4)
        if rule == "gauss":
            return np.asarray(ct, float) @ N
        if rule == "centroid":
            return np.asarray(ct, float).mean(axis=1)
    if rule == "gauss":
        x = N @ xy[:, :, 0].T                       # N (4,) -> (ne,)
        y = N @ xy[:, :, 1].T
        return mesh.thickness_xy(x, y)
    if rule == "centroid":
        return mesh.thickness_xy(xy[:, :, 0].mean(axis=1), xy[:, :, 1].mean(axis=1))
    raise ValueError(f"thickness_rule must be 'gauss' or 'centroid', got {rule!r}")


def _covariant_shear_rows(N, dNr, dNs, J):
    """Rows of the covariant transverse shear strains e_rz, e_sz (ne, 12) at one point.

    e_rz = dw/dr + x_r theta_y - y_r theta_x,  e_sz = dw/ds + x_s theta_y - y_s theta_x
    (the covariant components g_r . gamma, g_s . gamma of gamma = [dw/dx + theta_y,
    dw/dy - theta_x]).
    """
    ne = J.shape[0]
    Brz = np.zeros((ne, 12))
    Bsz = np.zeros((ne, 12))
    Brz[:, 0::3] = dNr
    Brz[:, 1::3] = -J[:, 0, 1][:, None] * N
    Brz[:, 2::3] = J[:, 0, 0][:, None] * N
    Bsz[:, 0::3] = dNs
    Bsz[:, 1::3] = -J[:, 1, 1][:, None] * N
    Bsz[:, 2::3] = J[:, 1, 0][:, None] * N
    return Brz, Bsz


def mitc4_stiffness(mesh: PlateMesh, material: Material, thickness_rule: str = "gauss",
                    n_gauss: int = 2) -> np.ndarray:
    """Element stiffness matrices of all elements, shape (n_elem, 12, 12) (SI: N/m, N, N m).

    K_e = int B_b^T D_b B_b dA + int B_s^T D_s B_s dA with the general bending and
    transverse-shear constitutive matrices D_b = h^3 / 12 Q (Q the material's plane-stress
    matrix in x-y axes, isotropic or orthotropic at any fibre angle) and D_s = k h G_s
    (G_s its 2 x 2 transverse-shear moduli, k = 5/6); for an isotropic material
    D_b = E h^3 / (12 (1 - nu^2)) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu)/2]] and
    D_s = k G h I. The shear strains come from the MITC4 assumed covariant field
    (Bathe & Dvorkin 1985); ``n_gauss`` x ``n_gauss`` Gauss integration (2 is the
    standard MITC4 rule); h is evaluated at every integration point.
    """
    xy = mesh.nodes[mesh.elements]                   # (ne, 4, 2)
    Db0 = material.plane_stress_matrix() / 12.0
    Gs = material.transverse_shear_matrix()
    # covariant shear rows at the tying points A (0,1), C (0,-1) [e_rz] and D (1,0), B (-1,0) [e_sz]
    tie = {}
    for name, (r, s) in {"A": (0, 1), "C": (0, -1), "D": (1, 0), "B": (-1, 0)}.items():
        N, dNr, dNs, J, _ = _jacobian(xy, r, s)
        tie[name] = _covariant_shear_rows(N, dNr, dNs, J)
    ne = xy.shape[0]
    K = np.zeros((ne, 12, 12))
    pts, wts = gauss_points(n_gauss)
    for (r, s), wgt in zip(pts, wts):
        N, dNr, dNs, J, det = _jacobian(xy, r, s)
        _check_geometry(det)
        h = _thickness(mesh, xy, N, thickness_rule)
        Jinv = np.linalg.inv(J)                      # [[r_x, s_x], [r_y, s_y]]
        dNx = Jinv[:, 0, 0][:, None] * dNr + Jinv[:, 0, 1][:, None] * dNs
        dNy = Jinv[:, 1, 0][:, None] * dNr + Jinv[:, 1, 1][:, None] * dNs
        Bb = np.zeros((ne, 3, 12))
        Bb[:, 0, 2::3] = dNx                          # d theta_y / dx
        Bb[:, 1, 1::3] = -dNy                         # -d theta_x / dy
        Bb[:, 2, 2::3] = dNy                          # d theta_y / dy - d theta_x / dx
        Bb[:, 2, 1::3] = -dNx
        Db = (h**3)[:, None, None] * Db0
        # assumed covariant shear strains, then Cartesian gamma = J^{-1} [e_rz, e_sz]
        erz = 0.5 * (1 + s) * tie["A"][0] + 0.5 * (1 - s) * tie["C"][0]
        esz = 0.5 * (1 + r) * tie["D"][1] + 0.5 * (1 - r) * tie["B"][1]
        Bs = np.einsum("eij,ejk->eik", Jinv, np.stack([erz, esz], axis=1))
        ds = SHEAR_FACTOR * h
        f = wgt * det
        K += f[:, None, None] * (np.einsum("eji,ejk,ekl->eil", Bb, Db, Bb)
                                 + ds[:, None, None] * np.einsum("eji,jk,ekl->eil", Bs, Gs, Bs))
    return K


def consistent_mass(mesh: PlateMesh, material: Material, thickness_rule: str = "gauss",
                    n_gauss: int = 3) -> np.ndarray:
    """Consistent element mass matrices (n_elem, 12, 12) (kg, kg m, kg m^2).

    M_e = int N^T diag(rho h, rho h^3/12, rho h^3/12) N dA with the bilinear shape functions of
    w, theta_x, theta_y (translational and rotary inertia of the Mindlin plate). The default
    3 x 3 Gauss rule integrates the products exactly for a parallelogram of constant thickness.
    """
    xy = mesh.nodes[mesh.elements]
    rho = material.density
    ne = xy.shape[0]
    M = np.zeros((ne, 12, 12))
    pts, wts = gauss_points(n_gauss)
    for (r, s), wgt in zip(pts, wts):
        N, _, _, _, det = _jacobian(xy, r, s)
        _check_geometry(det)
        h = _thickness(mesh, xy, N, thickness_rule)
        NN = np.outer(N, N)                           # (4, 4)
        f = wgt * det * rho
        for k, inertia in enumerate((h, h**3 / 12, h**3 / 12)):
            M[:, k::3, k::3] += (f * inertia)[:, None, None] * NN
    return M


def membrane_matrices(mesh: PlateMesh, material: Material, thickness_rule: str = "gauss",
                      n_gauss: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Plane-stress bilinear (Q4) membrane stiffness and consistent mass, (n_elem, 8, 8) each,
    DOFs (u, v) per node.

    K_e = int B^T D B dA, D = h Q (Q the plane-stress matrix; isotropic:
    E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu)/2]]),
    B = [[N_x, 0], [0, N_y], [N_y, N_x]]; M_e = int rho h N^T N dA (3 x 3 Gauss). Used only to
    examine the in-plane behaviour that the bending model leaves out (the flat plate's membrane
    and bending fields are uncoupled). The element has no drilling stiffness: an in-plane rigid
    rotation costs no energy (cf. the artificial drilling stiffness of shell elements).
    """
    xy = mesh.nodes[mesh.elements]
    rho = material.density
    D0 = material.plane_stress_matrix()
    ne = xy.shape[0]
    K = np.zeros((ne, 8, 8))
    M = np.zeros((ne, 8, 8))
    pts, wts = gauss_points(n_gauss)
    for (r, s), wgt in zip(pts, wts):
        N, dNr, dNs, J, det = _jacobian(xy, r, s)
        _check_geometry(det)
        h = _thickness(mesh, xy, N, thickness_rule)
        Jinv = np.linalg.inv(J)
        dNx = Jinv[:, 0, 0][:, None] * dNr + Jinv[:, 0, 1][:, None] * dNs
        dNy = Jinv[:, 1, 0][:, None] * dNr + Jinv[:, 1, 1][:, None] * dNs
        B = np.zeros((ne, 3, 8))
        B[:, 0, 0::2] = dNx
        B[:, 1, 1::2] = dNy
        B[:, 2, 0::2] = dNy
        B[:, 2, 1::2] = dNx
        K += (wgt * det * h)[:, None, None] * np.einsum("eji,jk,ekl->eil", B, D0, B)
    pts, wts = gauss_points(3)
    for (r, s), wgt in zip(pts, wts):
        N, _, _, _, det = _jacobian(xy, r, s)
        h = _thickness(mesh, xy, N, thickness_rule)
        NN = (wgt * det * rho * h)[:, None, None] * np.outer(N, N)
        M[:, 0::2, 0::2] += NN
        M[:, 1::2, 1::2] += NN
    return K, M


def locate_points(nodes: np.ndarray, elements: np.ndarray, points: np.ndarray,
                  tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Element index and natural coordinates (r, s) of each (x, y) point.

    Inverts the bilinear isoparametric map of the candidate elements (bounding-box filter, then
    Newton iterations). Raises ValueError naming the points that lie on no element.
    """
    p = np.atleast_2d(np.asarray(points, float))
    if p.ndim != 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
        raise ValueError(f"points must be a finite (n_points, 2) array of x, y in m, got shape {p.shape}")
    xy = nodes[elements]
    size = float(np.ptp(nodes, axis=0).max())
    atol = tol * max(size, 1.0)
    lo, hi = xy.min(axis=1) - atol, xy.max(axis=1) + atol
    elem = np.full(p.shape[0], -1)
    rs = np.zeros((p.shape[0], 2))
    chunk = max(1, 2_000_000 // max(elements.shape[0], 1))
    for start in range(0, p.shape[0], chunk):
        pc = p[start:start + chunk]
        cand = np.all((pc[:, None, :] >= lo[None]) & (pc[:, None, :] <= hi[None]), axis=2)
        pi, ei = np.nonzero(cand)
        if pi.size == 0:
            continue
        X = xy[ei]
        r = np.zeros(pi.size)
        s = np.zeros(pi.size)
        for _ in range(25):
            N, dNr, dNs = shape_functions(r, s)
            res = np.einsum("pk,pkd->pd", N, X) - pc[pi]
            a = np.einsum("pk,pk->p", dNr, X[:, :, 0]); b = np.einsum("pk,pk->p", dNs, X[:, :, 0])
            c = np.einsum("pk,pk->p", dNr, X[:, :, 1]); d = np.einsum("pk,pk->p", dNs, X[:, :, 1])
            det = a * d - b * c
            dr = (d * res[:, 0] - b * res[:, 1]) / det
            ds = (-c * res[:, 0] + a * res[:, 1]) / det
            r -= dr
            s -= ds
            if np.max(np.abs(dr) + np.abs(ds)) < 1e-14:
                break
        ok = (np.abs(r) <= 1 + 1e-7) & (np.abs(s) <= 1 + 1e-7)
        for k in np.flatnonzero(ok)[::-1]:          # reversed: the first hit wins
            elem[start + pi[k]] = ei[k]
            rs[start + pi[k]] = np.clip([r[k], s[k]], -1, 1)
    missing = np.flatnonzero(elem < 0)
    if missing.size:
        raise ValueError(f"points {missing[:10].tolist()} (e.g. {tuple(p[missing[0]])}) lie "
                         f"outside the structural surface")
    return elem, rs
