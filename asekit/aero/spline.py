"""Interpolation between the structural model and the aerodynamic boxes (thesis Eq. 2.10).

Displacements go from the structure to the boxes: the normal displacement h and its streamwise
slope dh/dx at the control points give the normalwash of a harmonic motion h exp(i omega t),

    w / U = dh/dx + i k h / b        (k = omega b / U, b the reference semi-chord),

and forces go back by the transpose of the displacement interpolation evaluated at the load
points (the quarter-chord mid-points, where each box's lift acts). With
F_box = q DeltaCp A n, the virtual work of the box forces through a displacement field equals
the work of the interpolated nodal forces: delta W = sum_boxes h(lp) F = delta u^T (G^T F) with
h(lp) = G u, which is Eq. (2.10), Q_aa = G_ka^T Q_kk G_ka.

Two interpolations:

- :func:`fe_spline`: through the finite-element shape functions of the structural model itself
  (``asekit.structure.modes.mode_shapes_at``), exact where the structure and the aerodynamic
  surface share a plane (the fin).
- :class:`InfinitePlateSpline`: the infinite-plate spline of Harder & Desmarais, "Interpolation
  using surface splines", J. Aircraft 9(2), 1972, 189-191 (Eqs. 1-9):
  w(x, y) = a0 + a1 x + a2 y + sum_i F_i r_i^2 ln r_i^2 with sum F_i = sum F_i x_i =
  sum F_i y_i = 0, for structures that do not share the aerodynamic plane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.structure.modes import mode_shapes_at


def normalwash(h: np.ndarray, dh_dx: np.ndarray, k: float, b_ref: float) -> np.ndarray:
    """Normalwash w/U = dh/dx + i k h / b_ref of the motion h exp(i omega t) (any shape).

    ``h`` in m (per unit modal coordinate), ``dh_dx`` dimensionless, ``k`` >= 0 the reduced
    frequency omega b_ref / U, ``b_ref`` (m) > 0.
    """
    if not math.isfinite(float(k)) or float(k) < 0:
        raise ValueError(f"k must be a finite reduced frequency >= 0, got {k!r}")
    if not math.isfinite(float(b_ref)) or float(b_ref) <= 0:
        raise ValueError(f"b_ref must be a finite semi-chord > 0 m, got {b_ref!r}")
    return np.asarray(dh_dx) + 1j * float(k) * np.asarray(h) / float(b_ref)


@dataclass(frozen=True)
class BoxModes:
    """Mode shapes on the boxes: ``h_cp``, ``dhdx_cp`` at the control points and ``h_lp`` at the
    load points, each (n_boxes, n_modes), per unit modal coordinate. h is the displacement
    along the box normal (+z for the fin)."""

    h_cp: np.ndarray
    dhdx_cp: np.ndarray
    h_lp: np.ndarray

    def normalwash(self, k: float, b_ref: float) -> np.ndarray:
        """w/U (n_boxes, n_modes) at the control points for reduced frequency ``k``."""
        return normalwash(self.h_cp, self.dhdx_cp, k, b_ref)


def fe_spline(model, mesh) -> BoxModes:
    """Mode shapes of a :class:`~asekit.structure.modes.ModalModel` on the boxes, interpolated
    with the model's own finite-element shape functions (``mode_shapes_at``).

    The boxes must lie in the structure's plane (z = 0, horizontal); raises ValueError otherwise.
    """
    if np.any(np.abs(mesh.corners[:, :, 2]) > 1e-9) or np.any(np.abs(mesh.dihedral) > 1e-12):
        raise ValueError("fe_spline needs boxes in the structural plane z = 0; "
                         "use InfinitePlateSpline for other configurations")
    h_cp, dhdx_cp = mode_shapes_at(model, mesh.control_point[:, :2])
    h_lp, _ = mode_shapes_at(model, mesh.load_point[:, :2])
    return BoxModes(h_cp, dhdx_cp, h_lp)


def analytic_modes(mesh, functions) -> BoxModes:
    """Box mode shapes from analytic fields: ``functions`` is a list of callables
    ``f(x, y) -> (h, dh/dx)`` (e.g. plunge ``lambda x, y: (1 + 0*x, 0*x)``, pitch about x_a
    ``lambda x, y: (-(x - x_a), -1 + 0*x)``)."""
    cp, lp = mesh.control_point, mesh.load_point
    h_cp, s_cp, h_lp = [], [], []
    for f in functions:
        h, s = f(cp[:, 0], cp[:, 1])
        h_cp.append(np.broadcast_to(h, (mesh.n,)))
        s_cp.append(np.broadcast_to(s, (mesh.n,)))
        h_lp.append(np.broadcast_to(f(lp[:, 0], lp[:, 1])[0], (mesh.n,)))
    return BoxModes(np.column_stack(h_cp), np.column_stack(s_cp), np.column_stack(h_lp))


class InfinitePlateSpline:
    """Infinite-plate spline through structural points (Harder & Desmarais 1972).

    Parameters
    ----------
    nodes : (n_nodes, 2) x, y (m) of the structural points carrying the displacement h.

    ``matrices(points)`` returns (G, Gx): h(points) = G h_nodes and dh/dx(points) = Gx h_nodes.
    The force transpose is G^T (work-conserving, see the module docstring).
    """

    def __init__(self, nodes: np.ndarray):
        p = np.asarray(nodes, float)
        if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3 or not np.all(np.isfinite(p)):
            raise ValueError(f"nodes must be a finite (n >= 3, 2) array, got shape {p.shape}")
        a = np.column_stack([np.ones(len(p)), p])
        if np.linalg.matrix_rank(a) < 3:
            raise ValueError("nodes must not all lie on one line (the spline needs a plane fit)")
        self.nodes = p
        n = len(p)
        # [[K, A], [A^T, 0]] [F; a] = [h; 0]  (Harder & Desmarais Eqs. 7-9)
        big = np.zeros((n + 3, n + 3))
        big[:n, :n] = self._kernel(p, p)
        big[:n, n:] = a
        big[n:, :n] = a.T
        self._inv = np.linalg.inv(big)[:, :n]      # (n + 3, n): coefficients per nodal value

    @staticmethod
    def _kernel(p, q):
        d = p[:, None, :] - q[None, :, :]
        r2 = np.einsum("ijk,ijk->ij", d, d)
        return np.where(r2 > 0, r2 * np.log(np.where(r2 > 0, r2, 1.0)), 0.0)

    def matrices(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(G, Gx), each (n_points, n_nodes): value and x-derivative interpolation matrices."""
        pts = np.atleast_2d(np.asarray(points, float))[:, :2]
        d = pts[:, None, :] - self.nodes[None, :, :]
        r2 = np.einsum("ijk,ijk->ij", d, d)
        safe = np.where(r2 > 0, r2, 1.0)
        kern = np.where(r2 > 0, r2 * np.log(safe), 0.0)
        # d/dx (r^2 ln r^2) = 2 dx (ln r^2 + 1)
        kern_x = np.where(r2 > 0, 2.0 * d[..., 0] * (np.log(safe) + 1.0), 0.0)
        ones = np.ones((len(pts), 1))
        g = np.hstack([kern, ones, pts]) @ self._inv
        gx = np.hstack([kern_x, np.zeros((len(pts), 1)), ones, np.zeros((len(pts), 1))]) @ self._inv
        return g, gx

    def box_modes(self, mesh, h_nodes: np.ndarray) -> BoxModes:
        """Box mode shapes from nodal normal displacements ``h_nodes`` (n_nodes, n_modes)."""
        h = np.asarray(h_nodes, float)
        if h.ndim == 1:
            h = h[:, None]
        if h.shape[0] != self.nodes.shape[0]:
            raise ValueError(f"h_nodes must have {self.nodes.shape[0]} rows, got {h.shape[0]}")
        g_cp, gx_cp = self.matrices(mesh.control_point)
        g_lp, _ = self.matrices(mesh.load_point)
        return BoxModes(g_cp @ h, gx_cp @ h, g_lp @ h)


def modal_forces(box_modes: BoxModes, delta_cp: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Generalised forces per unit dynamic pressure, Q = H_lp^T diag(A) DeltaCp (Eqs. 2.10-2.11):
    ``delta_cp`` (n_boxes, n_cols) -> (n_modes, n_cols)."""
    return box_modes.h_lp.T @ (np.asarray(area)[:, None] * delta_cp)
