"""Structured quadrilateral meshes of a trapezoidal lifting surface (thesis Section 3.1.1).

The thesis models the fin with 6 chordwise x 7 spanwise QUAD4 elements (42 elements). A mesh
here is ``n_chord x n_span`` bilinear quadrilaterals whose nodes sit at equal chord fractions
``xi_i = i / n_chord`` along equally spaced spanwise stations ``eta_j = j / n_span``: node
``j * (n_chord + 1) + i`` is at :meth:`asekit.geometry.Planform.point` ``(xi_i, eta_j)``.
Elements list their four nodes counter-clockwise seen from +z (x downstream, y spanwise).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import LinearThickness, Planform
from ..validate import positive


@dataclass(frozen=True)
class PlateMesh:
    """A quadrilateral plate mesh.

    Attributes
    ----------
    nodes : (n_nodes, 2) node coordinates x, y (m).
    elements : (n_elem, 4) node indices, counter-clockwise seen from +z.
    thickness_root, thickness_tip, y_root, span : the spanwise linear thickness law
        h(y) = h_root + (y - y_root) / span * (h_tip - h_root) (m).
    n_chord, n_span : elements per direction (0 when the mesh is not structured).
    """

    nodes: np.ndarray
    elements: np.ndarray
    thickness_root: float
    thickness_tip: float
    y_root: float
    span: float
    n_chord: int = 0
    n_span: int = 0

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.elements.shape[0]

    def thickness_at(self, y: np.ndarray) -> np.ndarray:
        """Plate thickness (m) at spanwise station(s) ``y`` (m), linear in y."""
        eta = (np.asarray(y, float) - self.y_root) / self.span
        return self.thickness_root + eta * (self.thickness_tip - self.thickness_root)

    def element_centroids(self) -> np.ndarray:
        """(n_elem, 2) mean of each element's four node coordinates (m)."""
        return self.nodes[self.elements].mean(axis=1)

    def node_at(self, point, tol: float = 1e-9, name: str = "point") -> int:
        """Index of the node at ``point`` (x, y) within ``tol`` m; ValueError if there is none."""
        p = np.asarray(point, float).reshape(2)
        d = np.hypot(*(self.nodes - p).T)
        i = int(np.argmin(d))
        if d[i] > tol:
            raise ValueError(
                f"{name} {tuple(p)} is not a node of the mesh (nearest node {i} at "
                f"{tuple(self.nodes[i])}, {d[i]:.3g} m away); for the fin's root mid-chord shaft "
                f"node use an even n_chord")
        return i


def _check_count(name: str, value) -> int:
    if isinstance(value, bool) or int(value) != value or int(value) < 1:
        raise ValueError(f"{name} must be an integer >= 1 (elements per direction), got {value!r}")
    return int(value)


def structured_mesh(planform: Planform, thickness: LinearThickness, n_chord: int,
                    n_span: int) -> PlateMesh:
    """Mesh a trapezoidal planform with ``n_chord x n_span`` quadrilaterals.

    Parameters
    ----------
    planform : the trapezoid (root/tip leading edges and chords, m).
    thickness : spanwise linear thickness law (m).
    n_chord, n_span : elements chordwise and spanwise, integers >= 1.

    Returns
    -------
    PlateMesh with (n_chord + 1) * (n_span + 1) nodes and n_chord * n_span elements.
    """
    n_chord = _check_count("n_chord", n_chord)
    n_span = _check_count("n_span", n_span)
    xi = np.linspace(0.0, 1.0, n_chord + 1)
    eta = np.linspace(0.0, 1.0, n_span + 1)
    XI, ETA = np.meshgrid(xi, eta)                 # (n_span+1, n_chord+1), row j = station j
    nodes = planform.point(XI.ravel(), ETA.ravel())
    i, j = np.meshgrid(np.arange(n_chord), np.arange(n_span))
    n0 = (j * (n_chord + 1) + i).ravel()
    elements = np.stack([n0, n0 + 1, n0 + n_chord + 2, n0 + n_chord + 1], axis=1)
    return PlateMesh(nodes=nodes, elements=elements.astype(np.int64),
                     thickness_root=thickness.root, thickness_tip=thickness.tip,
                     y_root=planform.root_le[1], span=planform.span,
                     n_chord=n_chord, n_span=n_span)


def rectangular_mesh(a: float, b: float, thickness: float, n_x: int, n_y: int) -> PlateMesh:
    """A uniform ``n_x x n_y`` mesh of the rectangle [0, a] x [0, b] with constant thickness
    (validation plates). Lengths in m."""
    for name, v in (("a", a), ("b", b), ("thickness", thickness)):
        positive(name, v)
    planform = Planform((0.0, 0.0), a, (0.0, b), a)
    return structured_mesh(planform, LinearThickness(thickness, thickness), n_x, n_y)
