"""Analytic design sensitivities of the plate model: element and global matrix derivatives with
respect to thickness, Young's modulus, orthotropic moduli and fibre angle, density and point
masses, and the derivatives of the natural frequencies and mode shapes (Nelson's method).

Thickness enters the MITC4 element (:mod:`asekit.structure.plate`) only through the
constitutive factors at the integration points g: bending D_b = h_g^3 / 12 Q, transverse shear
D_s = k h_g G_s, translational inertia rho h_g, rotary inertia rho h_g^3 / 12. Each element
matrix is therefore a polynomial in the integration-point thicknesses,

    K_e = sum_g (h_g^3 Kb_eg + h_g Ks_eg),    M_e = sum_g (h_g Mt_eg + h_g^3 Mr_eg),

with thickness-independent coefficient matrices (:class:`ElementParts`), and its derivative with
respect to any thickness parameter theta is exact:

    dK_e/dtheta = sum_g (3 h_g^2 Kb_eg + Ks_eg) dh_g/dtheta,
    dM_e/dtheta = sum_g (Mt_eg + 3 h_g^2 Mr_eg) dh_g/dtheta.

An isotropic material's K is linear in E (nu fixed, G = E / 2(1 + nu)): dK/dE = K / E; an
orthotropic lamina's K is linear in its constitutive matrices Q_xy and G_xy, so dK/dp for a
modulus or the fibre angle is K assembled with dQ_xy/dp, dG_xy/dp
(:func:`orthotropic_derivative`, :func:`orthotropic_stiffness_derivative`); the
plate's M is linear in rho: dM/drho = M_plate / rho; a point mass m enters M linearly:
dM/dm = the point-mass matrix of a unit mass (:func:`asekit.structure.assembly.point_mass_matrix`).

Eigen-derivatives of K phi_i = lambda_i M phi_i (lambda = omega^2, phi_i^T M phi_i = 1):

    dlambda_i = phi_i^T (dK - lambda_i dM) phi_i                    (Fox & Kapoor 1968, Eq. 8)

and Nelson's method for the mode shape (R. B. Nelson, "Simplified calculation of eigenvector
derivatives", AIAA J. 14(9), 1976, 1201-1205): solve the singular system
(K - lambda_i M) v = -(dK - lambda_i dM - dlambda_i M) phi_i with the component p of largest
|phi_i| set to zero (row and column p replaced by the identity, Nelson Eq. 15), then
dphi_i = v + c phi_i with c = -phi_i^T M v - phi_i^T dM phi_i / 2 (Nelson Eq. 20, the
derivative of the mass normalisation). Exact (no modal truncation) but valid for **distinct**
eigenvalues only: at a repeated eigenvalue the mode shapes are not differentiable (any vector of
the eigenspace is a mode), and :func:`mode_shape_derivatives` refuses such modes with a
ValueError naming them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from asekit.structure.mesh import PlateMesh
from asekit.structure.plate import (
    DOF_PER_NODE,
    SHEAR_FACTOR,
    _check_geometry,
    _covariant_shear_rows,
    _jacobian,
    _thickness,
    gauss_points,
    locate_points,
    shape_functions,
)

#: Two eigenvalues closer than this (relative to the larger) count as repeated.
REPEATED_RTOL = 1e-8


@dataclass(frozen=True)
class ElementParts:
    """Thickness-independent coefficient matrices of the MITC4 element matrices.

    Attributes
    ----------
    Kb, Ks : (n_elem, n_gk, 12, 12) bending (coefficient of h_g^3) and shear (coefficient of h_g)
        stiffness at the n_gk stiffness integration points (N/m^3..., SI).
    Mt, Mr : (n_elem, n_gm, 12, 12) translational (coefficient of h_g) and rotary (coefficient
        of h_g^3) mass at the n_gm mass integration points.
    h_k, h_m : (n_elem, n_gk) and (n_elem, n_gm) thickness (m) at those points.
    xy_k, xy_m : (n_elem, n_gk, 2) and (n_elem, n_gm, 2) their (x, y) coordinates (m).
    rs_k, rs_m : (n_gk, 2) and (n_gm, 2) their natural coordinates (r, s).
    """

    Kb: np.ndarray
    Ks: np.ndarray
    Mt: np.ndarray
    Mr: np.ndarray
    h_k: np.ndarray
    h_m: np.ndarray
    xy_k: np.ndarray
    xy_m: np.ndarray
    rs_k: np.ndarray
    rs_m: np.ndarray

    def stiffness(self) -> np.ndarray:
        """K_e = sum_g (h_g^3 Kb_eg + h_g Ks_eg), (n_elem, 12, 12)."""
        return (np.einsum("eg,egij->eij", self.h_k ** 3, self.Kb)
                + np.einsum("eg,egij->eij", self.h_k, self.Ks))

    def mass(self) -> np.ndarray:
        """M_e = sum_g (h_g Mt_eg + h_g^3 Mr_eg), (n_elem, 12, 12)."""
        return (np.einsum("eg,egij->eij", self.h_m, self.Mt)
                + np.einsum("eg,egij->eij", self.h_m ** 3, self.Mr))

    def stiffness_derivative(self, dh_k: np.ndarray) -> np.ndarray:
        """dK_e (n_elem, 12, 12) for the thickness change ``dh_k`` (n_elem, n_gk) at the stiffness
        points: sum_g (3 h_g^2 Kb_eg + Ks_eg) dh_g."""
        dh = np.asarray(dh_k, float)
        return (np.einsum("eg,egij->eij", 3 * self.h_k ** 2 * dh, self.Kb)
                + np.einsum("eg,egij->eij", dh, self.Ks))

    def mass_derivative(self, dh_m: np.ndarray) -> np.ndarray:
        """dM_e (n_elem, 12, 12) for the thickness change ``dh_m`` (n_elem, n_gm) at the mass
        points: sum_g (Mt_eg + 3 h_g^2 Mr_eg) dh_g."""
        dh = np.asarray(dh_m, float)
        return (np.einsum("eg,egij->eij", dh, self.Mt)
                + np.einsum("eg,egij->eij", 3 * self.h_m ** 2 * dh, self.Mr))


def element_parts(mesh: PlateMesh, material, thickness_rule: str = "gauss",
                  n_gauss_k: int = 2, n_gauss_m: int = 3) -> ElementParts:
    """The coefficient matrices of :class:`ElementParts` (the MITC4 stiffness and consistent mass
    of :func:`asekit.structure.plate.mitc4_stiffness` and
    :func:`~asekit.structure.plate.consistent_mass`, split by their thickness power).

    Parameters
    ----------
    mesh : the plate mesh; material : its material (isotropic or orthotropic);
    thickness_rule : ``"gauss"`` (h at every point) or ``"centroid"`` (the element's centroid
        thickness at all its points), as the plate module; n_gauss_k, n_gauss_m : the stiffness
        and mass rules (2 and 3, the plate module's defaults).

    Returns
    -------
    :class:`ElementParts`; its ``stiffness()`` and ``mass()`` equal the plate module's matrices.

    Examples
    --------
    >>> from asekit.geometry import Material
    >>> from asekit.structure.mesh import rectangular_mesh
    >>> from asekit.structure.plate import mitc4_stiffness
    >>> mesh = rectangular_mesh(0.2, 0.1, 0.002, 2, 1)
    >>> al = Material(70e9, 0.3, 2700.0)
    >>> bool(np.allclose(element_parts(mesh, al).stiffness(), mitc4_stiffness(mesh, al)))
    True
    """
    xy = mesh.nodes[mesh.elements]
    ne = xy.shape[0]
    Db0 = material.plane_stress_matrix() / 12.0
    Gs = material.transverse_shear_matrix()
    tie = {}
    for name, (r, s) in {"A": (0, 1), "C": (0, -1), "D": (1, 0), "B": (-1, 0)}.items():
        N, dNr, dNs, J, _ = _jacobian(xy, r, s)
        tie[name] = _covariant_shear_rows(N, dNr, dNs, J)
    pts_k, wts_k = gauss_points(n_gauss_k)
    Kb = np.zeros((ne, len(wts_k), 12, 12))
    Ks = np.zeros_like(Kb)
    h_k = np.zeros((ne, len(wts_k)))
    xy_k = np.zeros((ne, len(wts_k), 2))
    for g, ((r, s), wgt) in enumerate(zip(pts_k, wts_k)):
        N, dNr, dNs, J, det = _jacobian(xy, r, s)
        _check_geometry(det)
        h_k[:, g] = _thickness(mesh, xy, N, thickness_rule)
        xy_k[:, g] = np.einsum("k,ekd->ed", N, xy)
        Jinv = np.linalg.inv(J)
        dNx = Jinv[:, 0, 0][:, None] * dNr + Jinv[:, 0, 1][:, None] * dNs
        dNy = Jinv[:, 1, 0][:, None] * dNr + Jinv[:, 1, 1][:, None] * dNs
        Bb = np.zeros((ne, 3, 12))
        Bb[:, 0, 2::3] = dNx
        Bb[:, 1, 1::3] = -dNy
        Bb[:, 2, 2::3] = dNy
        Bb[:, 2, 1::3] = -dNx
        erz = 0.5 * (1 + s) * tie["A"][0] + 0.5 * (1 - s) * tie["C"][0]
        esz = 0.5 * (1 + r) * tie["D"][1] + 0.5 * (1 - r) * tie["B"][1]
        Bs = np.einsum("eij,ejk->eik", Jinv, np.stack([erz, esz], axis=1))
        f = (wgt * det)[:, None, None]
        Kb[:, g] = f * np.einsum("eji,jk,ekl->eil", Bb, Db0, Bb)
        Ks[:, g] = f * SHEAR_FACTOR * np.einsum("eji,jk,ekl->eil", Bs, Gs, Bs)
    pts_m, wts_m = gauss_points(n_gauss_m)
    Mt = np.zeros((ne, len(wts_m), 12, 12))
    Mr = np.zeros_like(Mt)
    h_m = np.zeros((ne, len(wts_m)))
    xy_m = np.zeros((ne, len(wts_m), 2))
    for g, ((r, s), wgt) in enumerate(zip(pts_m, wts_m)):
        N, _, _, _, det = _jacobian(xy, r, s)
        _check_geometry(det)
        h_m[:, g] = _thickness(mesh, xy, N, thickness_rule)
        xy_m[:, g] = np.einsum("k,ekd->ed", N, xy)
        NN = np.outer(N, N)
        f = (wgt * det * material.density)[:, None, None]
        Mt[:, g, 0::3, 0::3] = f * NN
        Mr[:, g, 1::3, 1::3] = f * NN / 12.0
        Mr[:, g, 2::3, 2::3] = f * NN / 12.0
    return ElementParts(Kb=Kb, Ks=Ks, Mt=Mt, Mr=Mr, h_k=h_k, h_m=h_m, xy_k=xy_k, xy_m=xy_m,
                        rs_k=pts_k, rs_m=pts_m)


def scatter(mesh: PlateMesh, Ke: np.ndarray) -> sp.csr_matrix:
    """Global sparse matrix (3 n_nodes square) of element matrices ``Ke`` (n_elem, 12, 12),
    symmetrised, with the assembly's DOF numbering (node n owns rows 3 n + (0, 1, 2))."""
    from asekit.structure.assembly import element_dofs
    dofs = element_dofs(mesh)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    n = 3 * mesh.n_nodes
    A = sp.csr_matrix((np.asarray(Ke, float).ravel(), (rows, cols)), shape=(n, n))
    return (0.5 * (A + A.T)).tocsr()


def thickness_derivatives(mesh: PlateMesh, parts: ElementParts, dh_k: np.ndarray,
                          dh_m: np.ndarray) -> tuple[list, list]:
    """Global dK and dM (lists of sparse matrices, one per design variable) of thickness
    variables given by their thickness derivatives at the integration points.

    Parameters
    ----------
    mesh : the mesh; parts : its :func:`element_parts`;
    dh_k, dh_m : (n_var, n_elem, n_gk) and (n_var, n_elem, n_gm) dh/dtheta_j (m per unit
        theta_j) at the stiffness and mass points (e.g. from :func:`element_scale_dh`).

    Returns
    -------
    dK, dM : lists of n_var scipy.sparse CSR matrices (3 n_nodes square).
    """
    dK = [scatter(mesh, parts.stiffness_derivative(d)) for d in np.asarray(dh_k, float)]
    dM = [scatter(mesh, parts.mass_derivative(d)) for d in np.asarray(dh_m, float)]
    return dK, dM


def element_scale_dh(parts: ElementParts, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dh/dtheta at the integration points for thickness-scale variables: variable j multiplies
    the thickness of the elements with ``groups == j`` by theta_j (so dh_g/dtheta_j = h_g on them
    at theta = 1; an element with group -1 belongs to no variable).

    Returns (dh_k (n_var, n_elem, n_gk), dh_m (n_var, n_elem, n_gm)), n_var = groups.max() + 1.

    Examples
    --------
    >>> from asekit.geometry import Material
    >>> from asekit.structure.mesh import rectangular_mesh
    >>> p = element_parts(rectangular_mesh(0.2, 0.1, 0.002, 2, 1), Material(70e9, 0.3, 2700.0))
    >>> dh_k, dh_m = element_scale_dh(p, np.array([0, 1]))
    >>> dh_k.shape, float(dh_k[0, 0, 0]), float(dh_k[0, 1, 0])
    ((2, 2, 4), 0.002, 0.0)
    """
    groups = np.asarray(groups, int)
    if groups.shape != (parts.h_k.shape[0],):
        raise ValueError(f"groups must hold one variable index per element "
                         f"({parts.h_k.shape[0]}), got shape {groups.shape}")
    n_var = int(groups.max()) + 1
    sel = (groups[None, :] == np.arange(n_var)[:, None]).astype(float)      # (n_var, n_elem)
    return sel[:, :, None] * parts.h_k[None], sel[:, :, None] * parts.h_m[None]


def youngs_modulus_derivative(K, material):
    """dK/dE = K / E (1/m..., per Pa) of an isotropic plate's stiffness ``K`` (nu held fixed, so
    G = E / 2(1 + nu) scales with E too). Orthotropic materials are refused (their moduli are
    separate variables).

    Examples
    --------
    >>> from asekit.geometry import Material
    >>> float(youngs_modulus_derivative(np.array([[7.0]]), Material(70e9, 0.3, 2700.0))[0, 0])
    1e-10
    """
    if not hasattr(material, "youngs_modulus"):
        raise ValueError("youngs_modulus_derivative needs an isotropic material "
                         f"(got {type(material).__name__})")
    return K / float(material.youngs_modulus)


def density_derivative(M_plate, material):
    """dM/drho = M_plate / rho (m^3 per kg/m^3 blocks) of the plate's own mass matrix (point
    masses excluded: they do not depend on the density).

    Examples
    --------
    >>> from asekit.geometry import Material
    >>> float(density_derivative(np.array([[2.7]]), Material(70e9, 0.3, 2700.0))[0, 0])
    0.001
    """
    return M_plate / float(material.density)


def point_mass_derivative(mesh: PlateMesh, position) -> sp.csr_matrix:
    """dM/dm (3 n_nodes square, sparse, per kg) of a point mass at ``position`` (x, y) m: the
    consistent point-mass matrix of a unit mass without rotary inertia.

    Examples
    --------
    >>> from asekit.structure.mesh import rectangular_mesh
    >>> dM = point_mass_derivative(rectangular_mesh(0.2, 0.1, 0.002, 2, 1), (0.1, 0.05))
    >>> round(float(dM.sum()), 12)                      # the unit mass, shared by the w DOFs
    1.0
    """
    from asekit.structure.assembly import point_mass_matrix
    return point_mass_matrix(mesh, [(tuple(position), 1.0, (0.0, 0.0))])


def point_mass_position_derivative(mesh: PlateMesh, position, mass: float,
                                   inertia=(0.0, 0.0), axis: int = 0) -> sp.csr_matrix:
    """dM/dx (``axis`` 0) or dM/dy (``axis`` 1) (3 n_nodes square, sparse, kg/m) of a point mass
    moved on the plate.

    The point mass enters M through the bilinear shape functions N(r, s) of the element holding
    it (:func:`asekit.structure.assembly.point_mass_matrix`): M_pm = m N N^T on the w DOFs (and
    I_xx N N^T, I_yy N N^T on the rotations), so moving it by dx changes

        dM_pm/dx = m (N_x N^T + N N_x^T),   [N_x; N_y] = J^-1 [N_r; N_s],

    J = [[x_r, y_r], [x_s, y_s]] the element's Jacobian at the point (the isoparametric chain
    rule, e.g. Bathe, *Finite Element Procedures*, 1996, Eq. 5.25). Exact inside an element; N is
    only C0 across element edges, so at an edge (or a node) this is the derivative of the element
    that :func:`~asekit.structure.plate.locate_points` assigns the point to (one-sided).

    Parameters
    ----------
    mesh : the plate mesh; position : (x, y) m; mass : kg; inertia : (I_xx, I_yy) kg m^2;
    axis : 0 for x (chordwise), 1 for y (spanwise).

    Returns
    -------
    scipy.sparse CSR matrix, per metre.

    Examples
    --------
    A mass at the middle of a one-element plate: N = 1/4 at every node, and moving it along x
    shifts mass from the x = 0 nodes to the x = 0.2 nodes; the total stays m (the sum is 0).

    >>> from asekit.structure.mesh import rectangular_mesh
    >>> dM = point_mass_position_derivative(rectangular_mesh(0.2, 0.1, 0.002, 1, 1),
    ...                                     (0.1, 0.05), 2.0)
    >>> round(float(dM.sum()), 12), round(float(dM.diagonal().max()), 12)
    (0.0, 2.5)
    """
    if axis not in (0, 1):
        raise ValueError(f"axis must be 0 (x) or 1 (y), got {axis!r}")
    elem, rs = locate_points(mesh.nodes, mesh.elements, np.array(position, float).reshape(1, 2))
    conn = mesh.elements[elem[0]]
    N, dNr, dNs = shape_functions(rs[0, 0], rs[0, 1])
    xy = mesh.nodes[conn, :2]
    J = np.array([dNr @ xy, dNs @ xy])                      # [[x_r, y_r], [x_s, y_s]]
    dN = np.linalg.solve(J, np.array([dNr, dNs]))[axis]    # N_x or N_y
    dNN = np.outer(dN, N) + np.outer(N, dN)
    n = DOF_PER_NODE * mesh.n_nodes
    rows, cols, vals = [], [], []
    for dof, value in ((0, mass), (1, inertia[0]), (2, inertia[1])):
        d = DOF_PER_NODE * conn + dof
        rows.append(np.repeat(d, 4))
        cols.append(np.tile(d, 4))
        vals.append((float(value) * dNN).ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))


def reduce(T, A) -> sp.csr_matrix:
    """T^T A T: a fin-DOF matrix derivative in a supported system's reduced coordinates
    (``SupportedSystem.T``; supports are constant in the design variables)."""
    return sp.csr_matrix(T.T @ sp.csr_matrix(A) @ T)


def eigenvalue_derivatives(phi: np.ndarray, lam: np.ndarray, dK, dM) -> np.ndarray:
    """dlambda_i/dtheta_j = phi_i^T (dK_j - lambda_i dM_j) phi_i (Fox & Kapoor 1968, Eq. 8) for
    mass-normalised modes (phi^T M phi = I).

    Parameters
    ----------
    phi : (n, n_modes) mass-normalised modes; lam : (n_modes,) omega^2 (rad^2/s^2);
    dK, dM : sequences of n_var (n, n) matrices (dense or sparse).

    Returns
    -------
    (n_var, n_modes) dlambda (rad^2/s^2 per unit theta); d omega / dtheta = dlambda / (2 omega).

    Examples
    --------
    >>> float(eigenvalue_derivatives(np.eye(1), np.array([4.0]), [np.eye(1)], [np.eye(1)])[0, 0])
    -3.0
    """
    out = np.empty((len(dK), phi.shape[1]))
    for j, (a, b) in enumerate(zip(dK, dM)):
        out[j] = (np.einsum("ij,ij->j", phi, a @ phi)
                  - lam * np.einsum("ij,ij->j", phi, b @ phi))
    return out


def repeated_modes(lam: np.ndarray, rtol: float = REPEATED_RTOL) -> list[int]:
    """Indices of eigenvalues within ``rtol`` (relative) of another one (repeated modes)."""
    lam = np.asarray(lam, float)
    out = []
    for i, li in enumerate(lam):
        others = np.delete(lam, i)
        scale = np.maximum(np.abs(others), abs(li))
        if others.size and np.any(np.abs(others - li) <= rtol * np.maximum(scale, 1e-300)):
            out.append(i)
    return out


def _nelson_one(K, M, lam_i, phi_i, dK, dM, dlam_i):
    """Nelson (1976) for one distinct mode: dphi_i (n, n_var)."""
    n = phi_i.size
    p = int(np.argmax(np.abs(phi_i)))
    A = sp.lil_matrix(sp.csr_matrix(K - lam_i * M))
    A[p, :] = 0
    A[:, p] = 0
    A[p, p] = 1.0
    F = np.empty((n, len(dK)))
    Mphi = M @ phi_i
    for j, (a, b) in enumerate(zip(dK, dM)):
        F[:, j] = -(a @ phi_i - lam_i * (b @ phi_i) - dlam_i[j] * Mphi)
    F[p, :] = 0.0
    V = spla.splu(sp.csc_matrix(A)).solve(F) if sp.issparse(K) else np.linalg.solve(A.toarray(), F)
    c = -(Mphi @ V) - 0.5 * np.array([phi_i @ (b @ phi_i) for b in dM])
    return V + phi_i[:, None] * c[None, :]


def mode_shape_derivatives(K, M, lam: np.ndarray, phi: np.ndarray, dK, dM,
                           modes=None, rtol: float = REPEATED_RTOL):
    """Eigenvalue and mode-shape derivatives of K phi = lambda M phi by Nelson's method (module
    docstring; Nelson 1976, AIAA J. 14(9), Eqs. 15-20), exact for distinct eigenvalues.

    Parameters
    ----------
    K, M : (n, n) stiffness and mass (sparse or dense), the system the modes solve;
    lam : (n_modes,) eigenvalues omega^2; phi : (n, n_modes) mass-normalised modes;
    dK, dM : n_var derivative matrices each; modes : indices of the modes to differentiate
        (default all); rtol : the relative gap below which two eigenvalues count as repeated.

    Returns
    -------
    dlam : (n_var, n_modes) eigenvalue derivatives; dphi : (n_var, n, n_modes) mode-shape
    derivatives of the mass-normalised modes (columns of modes not requested are zero).

    Raises
    ------
    ValueError
        A requested mode has a repeated eigenvalue (its shape is not differentiable).

    Examples
    --------
    >>> K, M = np.diag([1.0, 4.0]), np.eye(2)
    >>> dlam, dphi = mode_shape_derivatives(K, M, np.array([1.0, 4.0]), np.eye(2),
    ...                                     [np.array([[0.0, 1.0], [1.0, 0.0]])], [np.zeros((2, 2))])
    >>> dlam[0].tolist(), dphi[0].round(6).tolist()      # dphi_1 = -phi_2 / (4 - 1)
    ([0.0, 0.0], [[0.0, 0.333333], [-0.333333, 0.0]])
    """
    lam = np.asarray(lam, float)
    modes = list(range(lam.size)) if modes is None else [int(i) for i in modes]
    bad = sorted(set(repeated_modes(lam, rtol)) & set(modes))
    if bad:
        raise ValueError(f"modes {bad} have repeated eigenvalues (relative gap <= {rtol:g}): "
                         f"their shapes are not differentiable; Nelson's method needs distinct "
                         f"eigenvalues (differentiate a perturbed, symmetry-broken model instead)")
    dlam = eigenvalue_derivatives(phi, lam, dK, dM)
    dphi = np.zeros((len(dK), phi.shape[0], phi.shape[1]))
    for i in modes:
        dphi[:, :, i] = _nelson_one(K, M, lam[i], phi[:, i], dK, dM, dlam[:, i]).T
    return dlam, dphi


#: The orthotropic material parameters :func:`orthotropic_derivative` differentiates.
ORTHOTROPIC_PARAMETERS = ("e1", "e2", "g12", "g13", "g23", "fibre_angle")


@dataclass(frozen=True)
class _MatrixMaterial:
    """A stand-in material whose constitutive matrices are given (the derivatives dQ, dG), so
    that :func:`element_parts` forms the element stiffness's derivative (K is linear in them)."""

    Q: np.ndarray
    G: np.ndarray
    density: float = 1.0

    def plane_stress_matrix(self) -> np.ndarray:
        return self.Q

    def transverse_shear_matrix(self) -> np.ndarray:
        return self.G


def orthotropic_derivative(material, name: str) -> tuple[np.ndarray, np.ndarray]:
    """dQ_xy/dp (3 x 3) and dG_xy/dp (2 x 2) of an
    :class:`~asekit.geometry.OrthotropicMaterial` for p = ``name`` in
    :data:`ORTHOTROPIC_PARAMETERS` (Pa per Pa for the moduli, Pa per rad for ``fibre_angle``).

    Q_xy = T^T Q T with Q = [[e1, nu12 e2, 0], [nu12 e2, e2, 0], [0, 0, g12 d]] / d,
    d = 1 - nu12^2 e2 / e1 (Jones, *Mechanics of Composite Materials*, 2nd ed., Eqs. 2.61 and
    2.84; nu12 is held fixed), and G_xy = R^T diag(g13, g23) R. The moduli enter Q (quotient
    rule on a / d, dd/de1 = nu12^2 e2 / e1^2, dd/de2 = -nu12^2 / e1) or G linearly; the fibre
    angle enters T and R: dQ_xy = T'^T Q T + T^T Q T', dG_xy = R'^T D R + R^T D R', with
    T' = [[-2cs, 2cs, c^2 - s^2], [2cs, -2cs, s^2 - c^2], [2(s^2 - c^2), 2(c^2 - s^2), -4cs]]
    and R' = [[-s, c], [-c, -s]].

    Examples
    --------
    >>> from asekit.geometry import OrthotropicMaterial
    >>> m = OrthotropicMaterial(10e9, 1e9, 0.7e9, 0.3, 600.0)
    >>> dQ, dG = orthotropic_derivative(m, "g12")
    >>> dQ.round(12).tolist(), dG.tolist()
    ([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]])
    """
    if name not in ORTHOTROPIC_PARAMETERS:
        raise ValueError(f"name must be one of {list(ORTHOTROPIC_PARAMETERS)}, got {name!r}")
    e1, e2, nu = float(material.e1), float(material.e2), float(material.nu12)
    d = 1.0 - nu * nu * e2 / e1
    a = np.array([[e1, nu * e2, 0.0], [nu * e2, e2, 0.0], [0.0, 0.0, 0.0]])
    Q = a / d
    Q[2, 2] = material.g12
    c, s = math.cos(material.fibre_angle), math.sin(material.fibre_angle)
    T = np.array([[c * c, s * s, c * s], [s * s, c * c, -c * s],
                  [-2 * c * s, 2 * c * s, c * c - s * s]])
    R = np.array([[c, s], [-s, c]])
    D = np.diag([float(material.g13), float(material.g23)])
    dQm, dD = np.zeros((3, 3)), np.zeros((2, 2))
    if name in ("e1", "e2"):
        da = np.zeros((3, 3))
        if name == "e1":
            da[0, 0], dd = 1.0, nu * nu * e2 / e1 ** 2
        else:
            da[0, 1] = da[1, 0] = nu
            da[1, 1], dd = 1.0, -nu * nu / e1
        dQm = (da * d - a * dd) / d ** 2
    elif name == "g12":
        dQm[2, 2] = 1.0
    elif name in ("g13", "g23"):
        i = ("g13", "g23").index(name)
        dD[i, i] = 1.0
    if name != "fibre_angle":
        dQ, dG = T.T @ dQm @ T, R.T @ dD @ R
    else:
        cc, ss, cs = c * c, s * s, c * s
        dT = np.array([[-2 * cs, 2 * cs, cc - ss], [2 * cs, -2 * cs, ss - cc],
                       [2 * (ss - cc), 2 * (cc - ss), -4 * cs]])
        dR = np.array([[-s, c], [-c, -s]])
        dQ = dT.T @ Q @ T + T.T @ Q @ dT
        dG = dR.T @ D @ R + R.T @ D @ dR
    return 0.5 * (dQ + dQ.T), 0.5 * (dG + dG.T)


def orthotropic_stiffness_derivative(mesh: PlateMesh, material, name: str,
                                     thickness_rule: str = "gauss") -> sp.csr_matrix:
    """dK/dp (3 n_nodes square, sparse) of the plate with an orthotropic ``material`` for its
    parameter p = ``name`` (:func:`orthotropic_derivative`): the MITC4 stiffness is linear in
    the constitutive matrices (K_e = sum_g h_g^3 B_b^T Q B_b / 12 + k h_g B_s^T G B_s, times
    the integration weight), so dK is the stiffness assembled with dQ and dG in their place.
    Exact; the mass does not depend on these parameters.

    Examples
    --------
    A pure rotation of an isotropic-like lamina (e1 = e2, g12 = e1 / 2 (1 + nu)) leaves K
    unchanged, so its fibre-angle derivative vanishes:

    >>> from asekit.geometry import OrthotropicMaterial
    >>> from asekit.structure.mesh import rectangular_mesh
    >>> m = OrthotropicMaterial(70e9, 70e9, 70e9 / 2.6, 0.3, 2700.0, fibre_angle=0.3)
    >>> dK = orthotropic_stiffness_derivative(rectangular_mesh(0.2, 0.1, 0.002, 2, 1), m,
    ...                                       "fibre_angle")
    >>> bool(abs(dK).max() < 1e-6 * 70e9 * 0.002 ** 3)
    True
    """
    dQ, dG = orthotropic_derivative(material, name)
    parts = element_parts(mesh, _MatrixMaterial(dQ, dG), thickness_rule)
    return scatter(mesh, parts.stiffness())
