"""Sparse global stiffness and mass matrices and the fin's supports (thesis Eq. (2.1), Sec. 3.1.1).

Global degrees of freedom: node ``n`` owns rows ``3 n + (0, 1, 2)`` = ``(w, theta_x, theta_y)``
(see :mod:`asekit.structure.plate` for the sign convention).

Supports are applied by a transformation ``u_fin = T q`` from the reduced (independent)
coordinates ``q`` to the fin's degrees of freedom, so ``K_r = T^T K T`` and ``M_r = T^T M T``
(master-slave elimination of linear multi-point constraints, e.g. Cook, Malkus, Plesha & Witt,
*Concepts and Applications of FEA*, 4th ed., Sec. 9.2):

* ``clamped``: every degree of freedom of the root-edge nodes is removed (cantilever plate).
* shaft, ``region="single_node"`` (thesis model FN1/FN2): the root mid-chord node is held in w
  and theta_x and its theta_y equals the shaft rotation ``theta_s``.
* shaft, ``region="distributed"``: every node within ``radius`` of the shaft axis point is tied
  rigidly to the shaft (a rigid multi-point constraint): ``w_n = -(x_n - x_a) theta_s``,
  ``theta_x,n = 0``, ``theta_y,n = theta_s``. This is a finite, physical shaft footprint; unlike
  the single-node support (a point support of a plate, a singularity) it converges with mesh
  refinement.

The shaft rotation ``theta_s`` is the last fin coordinate of ``q``. Model FN1 adds the actuator's
torsional spring ``k`` between ``theta_s`` and the ground. Model FN2 (fictitious-mass method,
Karpel's [22] in the thesis; Sec. 3.1.1) frees the ground point: it becomes one more coordinate
``phi_g`` carrying a fictitious inertia ``I_f`` (about 1e6 times the fin's pitch inertia), and
the spring acts between ``theta_s`` and ``phi_g``. One eigen-analysis then yields a zero-frequency
rigid pitch mode (everything rotating together) and the FN1 elastic modes (the huge inertia
keeps ``phi_g`` still), with relative errors of order ``J_fin / I_f``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from asekit.geometry import Material
from asekit.structure.mesh import PlateMesh
from asekit.structure.plate import (
    DOF_PER_NODE,
    consistent_mass,
    locate_points,
    mitc4_stiffness,
    shape_functions,
)
from asekit.util.validate import positive


def element_dofs(mesh: PlateMesh) -> np.ndarray:
    """(n_elem, 12) global degree-of-freedom numbers of each element, node by node."""
    return (DOF_PER_NODE * mesh.elements[:, :, None] + np.arange(DOF_PER_NODE)).reshape(-1, 12)


def assemble(mesh: PlateMesh, material: Material, thickness_rule: str = "gauss"):
    """Global stiffness K (N/m, ...) and consistent mass M (kg, ...) as scipy.sparse CSR
    matrices of size 3 n_nodes (thesis Eq. (2.1) before boundary conditions)."""
    Ke = mitc4_stiffness(mesh, material, thickness_rule)
    Me = consistent_mass(mesh, material, thickness_rule)
    dofs = element_dofs(mesh)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    n = DOF_PER_NODE * mesh.n_nodes
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    M = sp.csr_matrix((Me.ravel(), (rows, cols)), shape=(n, n))
    # exact symmetry (the element matrices are symmetric up to round-off)
    return (0.5 * (K + K.T)).tocsr(), (0.5 * (M + M.T)).tocsr()


def rigid_pitch_vector(mesh: PlateMesh, axis_x: float) -> np.ndarray:
    """Fin displacement vector of a unit (1 rad) nose-up rigid pitch about the spanwise axis
    x = ``axis_x``: w = -(x - axis_x), theta_x = 0, theta_y = 1."""
    r = np.zeros(DOF_PER_NODE * mesh.n_nodes)
    r[0::3] = -(mesh.nodes[:, 0] - axis_x)
    r[2::3] = 1.0
    return r


def pitch_inertia(mesh: PlateMesh, M, axis_x: float) -> float:
    """Pitch inertia of the plate about the spanwise axis x = ``axis_x`` (kg m^2): r^T M r with
    the rigid pitch vector r (includes the small rotary inertia rho h^3 / 12)."""
    r = rigid_pitch_vector(mesh, axis_x)
    return float(r @ (M @ r))


def plate_pitch_inertia(planform, thickness, density: float, axis_x: float) -> float:
    """Pitch inertia (kg m^2) of a flat trapezoidal plate about the spanwise axis x = ``axis_x``,
    by exact integration (no finite elements):

        J = int_y rho h(y) int_x [(x - x_a)^2 + h(y)^2 / 12] dx dy,

    the second term being the plate's own rotary inertia. Gauss-Legendre (8 points) in the span
    fraction eta is exact for this polynomial integrand (h linear in eta).

    Parameters
    ----------
    planform : :class:`asekit.geometry.Planform` (m).
    thickness : :class:`asekit.geometry.Thickness`, flat chordwise profile (m).
    density : rho (kg/m^3), > 0.
    axis_x : x of the pitch axis (m).

    Returns
    -------
    J (kg m^2).

    Examples
    --------
    >>> from asekit.geometry import Planform, Thickness
    >>> J = plate_pitch_inertia(Planform((0.0, 0.0), 1.0, (0.0, 1.0), 1.0),
    ...                         Thickness(0.01, 0.01), 1000.0, 0.5)
    >>> round(J, 10) == round(10.0 * (1 / 12 + 0.01 ** 2 / 12), 10)      # m (c^2 + h^2) / 12
    True
    """
    positive("density", density)
    if getattr(thickness, "is_table", False):
        raise ValueError("plate_pitch_inertia needs a root/tip thickness law, not a table")
    if not getattr(getattr(thickness, "profile", None), "is_flat", True):
        raise ValueError("plate_pitch_inertia needs a flat chordwise thickness profile")
    p, t, rho = planform, thickness, float(density)
    g, wg = np.polynomial.legendre.leggauss(8)
    eta = 0.5 * (g + 1)
    h = t.at(eta)
    x0 = p.root_le[0] + eta * (p.tip_le[0] - p.root_le[0]) - axis_x
    c = p.root_chord + eta * (p.tip_chord - p.root_chord)
    x1 = x0 + c
    inner = (x1**3 - x0**3) / 3 + h**2 / 12 * c
    return float(0.5 * p.span * np.sum(wg * rho * h * inner))


@dataclass(frozen=True)
class SupportedSystem:
    """A supported structure ready for eigen-analysis.

    Attributes
    ----------
    K, M : reduced stiffness and mass (sparse CSR), size n_q.
    T : (3 n_nodes, n_q) sparse map from the reduced coordinates q to the fin's DOFs.
    shaft_index : index of the shaft rotation theta_s in q (None when clamped).
    ground_index : index of the FN2 ground rotation phi_g in q (None otherwise).
    fictitious_inertia : I_f at phi_g (kg m^2), 0 when not FN2.
    shaft_nodes : nodes tied to the shaft (empty when clamped).
    mesh : the mesh; label : a description, e.g. "FN2 6x7 single-node shaft".
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    T: sp.csr_matrix
    shaft_index: int | None
    ground_index: int | None
    fictitious_inertia: float
    shaft_nodes: np.ndarray
    mesh: PlateMesh
    label: str

    def fin_dofs(self, q: np.ndarray) -> np.ndarray:
        """Fin DOF vectors (3 n_nodes, ...) from reduced coordinates q (n_q, ...)."""
        return self.T @ q


def clamped_edge(mesh: PlateMesh, K, M, y_edge: float | None = None,
                 tol: float = 1e-12) -> SupportedSystem:
    """Clamp every DOF of the nodes on the spanwise station ``y_edge`` (default: the root)."""
    y_edge = mesh.y_root if y_edge is None else float(y_edge)
    clamped = np.flatnonzero(np.abs(mesh.nodes[:, 1] - y_edge) <= tol + 1e-9 * mesh.span)
    if clamped.size == 0:
        raise ValueError(f"y_edge={y_edge} m: no mesh node lies on that station")
    fixed = (DOF_PER_NODE * clamped[:, None] + np.arange(DOF_PER_NODE)).ravel()
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))),
                      shape=(K.shape[0], free.size))
    return SupportedSystem(K=(T.T @ K @ T).tocsr(), M=(T.T @ M @ T).tocsr(), T=T,
                           shaft_index=None, ground_index=None, fictitious_inertia=0.0,
                           shaft_nodes=np.array([], dtype=np.int64), mesh=mesh,
                           label=f"clamped {mesh.n_chord}x{mesh.n_span}")


def shaft_region_nodes(mesh: PlateMesh, axis_point, region: str, radius: float) -> np.ndarray:
    """Nodes tied to the shaft: the node at ``axis_point`` (``"single_node"``) or every node
    within ``radius`` m of it (``"distributed"``)."""
    p = np.asarray(axis_point, float).reshape(2)
    if region == "single_node":
        return np.array([mesh.node_at(p, tol=1e-9 * max(mesh.span, 1.0), name="shaft axis_point")])
    if region == "distributed":
        positive("radius", radius)
        d = np.hypot(*(mesh.nodes - p).T)
        nodes = np.flatnonzero(d <= radius * (1 + 1e-9))
        if nodes.size == 0:
            raise ValueError(f"no mesh node lies within radius={radius} m of the shaft "
                             f"axis_point {tuple(p)}: refine the mesh or enlarge the radius")
        if nodes.size < 3:
            warnings.warn(f"distributed shaft: only {nodes.size} node(s) {nodes.tolist()} inside "
                          f"the shaft radius {radius} m on this {mesh.n_chord}x{mesh.n_span} mesh; "
                          f"the rigid region is not resolved (acts as a point support)",
                          stacklevel=3)
        return nodes
    raise ValueError(f"shaft region must be 'single_node' or 'distributed', got {region!r}")


def shaft_support(mesh: PlateMesh, K, M, axis_point, torsional_stiffness: float,
                  model: str = "FN1", region: str = "single_node", radius: float = 0.0,
                  fictitious_inertia: float | None = None,
                  fictitious_inertia_factor: float = 1.0e6,
                  bending_stiffness: float | None = None) -> SupportedSystem:
    """Support the plate on the pitch shaft (thesis Sec. 3.1.1, Figs 12 and 13).

    Parameters
    ----------
    mesh, K, M : the mesh and its global sparse matrices from :func:`assemble`.
    axis_point : (x, y) of the shaft axis on the root chord (m).
    torsional_stiffness : actuator/shaft spring about y (N m/rad), > 0.
    model : "FN1" (spring to ground) or "FN2" (spring to a free ground point with a fictitious
        inertia: fictitious-mass method).
    region : "single_node" (thesis) or "distributed" (rigid region of ``radius`` m).
    fictitious_inertia : I_f (kg m^2); default ``fictitious_inertia_factor`` x the fin's pitch
        inertia about the axis.
    bending_stiffness : optional stiffness (N m/rad) of the actuator-fin connection about the
        chordwise (x) axis through ``axis_point`` (thesis Sec. 6.2). Without it the shaft nodes
        are held in that rotation (rigid in bending, the thesis's model). With it the shaft
        region rotates rigidly about x by one more coordinate phi (w_n += (y_n - y_a) phi,
        theta_x,n = phi), restrained by a spring of this stiffness to the ground.
    """
    if not np.isfinite(torsional_stiffness) or torsional_stiffness <= 0:
        raise ValueError(f"torsional_stiffness must be > 0 (N m/rad), got {torsional_stiffness!r}")
    if model not in ("FN1", "FN2"):
        raise ValueError(f"model must be 'FN1' or 'FN2', got {model!r}")
    x_a = float(np.asarray(axis_point, float)[0])
    nodes = shaft_region_nodes(mesh, axis_point, region, radius)
    n_full = K.shape[0]
    slave = (DOF_PER_NODE * nodes[:, None] + np.arange(DOF_PER_NODE)).ravel()
    free = np.setdiff1d(np.arange(n_full), slave)
    bend = bending_stiffness is not None
    if bend and (not np.isfinite(bending_stiffness) or bending_stiffness <= 0):
        raise ValueError(f"bending_stiffness must be > 0 (N m/rad), got {bending_stiffness!r}")
    n_q = free.size + (2 if model == "FN2" else 1) + (1 if bend else 0)
    s_idx = free.size
    rows = np.concatenate([free, DOF_PER_NODE * nodes, DOF_PER_NODE * nodes + 2])
    cols = np.concatenate([np.arange(free.size), np.full(2 * nodes.size, s_idx)])
    vals = np.concatenate([np.ones(free.size), -(mesh.nodes[nodes, 0] - x_a), np.ones(nodes.size)])
    if bend:
        b_idx = n_q - 1
        y_a = float(np.asarray(axis_point, float)[1])
        rows = np.concatenate([rows, DOF_PER_NODE * nodes, DOF_PER_NODE * nodes + 1])
        cols = np.concatenate([cols, np.full(2 * nodes.size, b_idx)])
        vals = np.concatenate([vals, mesh.nodes[nodes, 1] - y_a, np.ones(nodes.size)])
    T = sp.csr_matrix((vals, (rows, cols)), shape=(n_full, n_q))
    Kr = (T.T @ K @ T).tolil()
    Mr = (T.T @ M @ T).tolil()
    if bend:
        Kr[b_idx, b_idx] += float(bending_stiffness)
    k = float(torsional_stiffness)
    kind = "single-node" if region == "single_node" else f"distributed r={radius * 1e3:g} mm"
    label = f"{model} {mesh.n_chord}x{mesh.n_span} {kind} shaft"
    if model == "FN1":
        Kr[s_idx, s_idx] += k
        g_idx, I_f = None, 0.0
    else:
        g_idx = s_idx + 1
        if fictitious_inertia is None:
            if not np.isfinite(fictitious_inertia_factor) or fictitious_inertia_factor <= 0:
                raise ValueError("fictitious_inertia_factor must be > 0, got "
                                 f"{fictitious_inertia_factor!r}")
            fictitious_inertia = fictitious_inertia_factor * pitch_inertia(mesh, M, x_a)
        I_f = float(fictitious_inertia)
        if not np.isfinite(I_f) or I_f <= 0:
            raise ValueError(f"fictitious_inertia must be > 0 (kg m^2), got {I_f!r}")
        Kr[s_idx, s_idx] += k
        Kr[g_idx, g_idx] += k
        Kr[s_idx, g_idx] -= k
        Kr[g_idx, s_idx] -= k
        Mr[g_idx, g_idx] += I_f
    return SupportedSystem(K=Kr.tocsr(), M=Mr.tocsr(), T=T, shaft_index=s_idx, ground_index=g_idx,
                           fictitious_inertia=I_f, shaft_nodes=nodes, mesh=mesh, label=label)


def point_mass_matrix(mesh: PlateMesh, masses) -> sp.csr_matrix:
    """Global mass matrix (3 n_nodes square, sparse) of concentrated masses on the plate.

    ``masses`` is a sequence of ``(position (x, y) m, mass kg, (I_xx, I_yy) kg m^2)``. Each is
    attached consistently through the bilinear shape functions N of the element holding it
    (kinetic energy 1/2 m (N w)^2 + 1/2 I_xx (N theta_x)^2 + 1/2 I_yy (N theta_y)^2), so a
    mass need not sit on a node; at a node this is the usual lumped CONM2-like mass.
    """
    n = DOF_PER_NODE * mesh.n_nodes
    M = sp.csr_matrix((n, n))
    masses = list(masses)
    if not masses:
        return M
    pos = np.array([m[0] for m in masses], float).reshape(-1, 2)
    elem, rs = locate_points(mesh.nodes, mesh.elements, pos)
    N, _, _ = shape_functions(rs[:, 0], rs[:, 1])
    rows, cols, vals = [], [], []
    for i, (_, m, inertia) in enumerate(masses):
        conn = mesh.elements[elem[i]]
        NN = np.outer(N[i], N[i])
        for dof, value in ((0, m), (1, inertia[0]), (2, inertia[1])):
            d = DOF_PER_NODE * conn + dof
            rows.append(np.repeat(d, 4))
            cols.append(np.tile(d, 4))
            vals.append((value * NN).ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))
