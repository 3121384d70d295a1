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

from asekit.geometry import LinearThickness, Planform, Thickness, ThicknessField
from asekit.util.validate import integer, positive


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
    thickness_field : optional h(x, y) (m), e.g. a :class:`~asekit.geometry.ThicknessField`
        with a chordwise profile; when given it replaces the spanwise linear law everywhere
        the element integrates (:meth:`thickness_xy`).
    corner_thickness : optional (n_elem, 4) thickness (m) at each element's four corners,
        interpolated bilinearly inside the element with the shape functions (as Nastran's
        CQUAD4 T1-T4 fields); when given it replaces both laws above in the element matrices.
    """

    nodes: np.ndarray
    elements: np.ndarray
    thickness_root: float
    thickness_tip: float
    y_root: float
    span: float
    n_chord: int = 0
    n_span: int = 0
    thickness_field: object = None
    corner_thickness: np.ndarray | None = None

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

    def thickness_xy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Plate thickness (m) at points (x, y) (m): the thickness field if the mesh has one,
        else the spanwise linear law."""
        if self.thickness_field is None:
            return self.thickness_at(y)
        return self.thickness_field(x, y)

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
                f"{name} ({p[0]:.6g}, {p[1]:.6g}) m is not a node of the mesh (nearest node {i} "
                f"at ({self.nodes[i, 0]:.6g}, {self.nodes[i, 1]:.6g}) m, {d[i]:.3g} m away): "
                f"choose n_chord so that a node falls there (e.g. an even n_chord for a "
                f"mid-chord axis) or use a shaft region of finite radius")
        return i


def _check_count(name: str, value) -> int:
    """Elements per direction: an integer >= 1 (:func:`asekit.util.validate.integer`)."""
    return integer(name, value, low=1)


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
    field = None if thickness.profile.is_flat else ThicknessField((planform,), thickness)
    return PlateMesh(nodes=nodes, elements=elements.astype(np.int64),
                     thickness_root=thickness.root, thickness_tip=thickness.tip,
                     y_root=planform.root_le[1], span=planform.span,
                     n_chord=n_chord, n_span=n_span, thickness_field=field)


def panels_mesh(panels, thickness: Thickness, n_chord: int, n_spans) -> PlateMesh:
    """Mesh one or more trapezoidal panels joined spanwise (a cranked planform).

    Parameters
    ----------
    panels : sequence of :class:`~asekit.geometry.Planform`, root to tip; panel ``i + 1``'s root
        chord must coincide with panel ``i``'s tip chord (same leading edge and chord).
    thickness : the spanwise x chordwise law over the whole span (first root to last tip).
    n_chord : elements chordwise, the same on every panel (a conforming mesh).
    n_spans : elements spanwise per panel.

    Returns
    -------
    PlateMesh whose nodes on each panel junction are shared, with a
    :class:`~asekit.geometry.ThicknessField` over all panels.
    """
    panels = tuple(panels)
    n_spans = [int(_check_count(f"panel[{i}].n_span", n)) for i, n in enumerate(n_spans)]
    if len(panels) < 1 or len(n_spans) != len(panels):
        raise ValueError("panels and n_spans must be non-empty and of equal length")
    n_chord = _check_count("n_chord", n_chord)
    for i in range(1, len(panels)):
        a, b = panels[i - 1], panels[i]
        if (not np.allclose(a.tip_le, b.root_le, atol=1e-9 * max(a.span, 1e-3))
                or not np.isclose(a.tip_chord, b.root_chord, rtol=1e-9)):
            raise ValueError(f"panel[{i}] root (leading edge {b.root_le}, chord {b.root_chord}) "
                             f"must coincide with panel[{i - 1}] tip (leading edge {a.tip_le}, "
                             f"chord {a.tip_chord})")
    xi = np.linspace(0.0, 1.0, n_chord + 1)
    rows = []
    for i, (p, ns) in enumerate(zip(panels, n_spans)):
        eta = np.linspace(0.0, 1.0, ns + 1)[(1 if i else 0):]
        XI, ETA = np.meshgrid(xi, eta)
        rows.append(p.point(XI.ravel(), ETA.ravel()))
    nodes = np.concatenate(rows)
    n_stations = sum(n_spans)
    i, j = np.meshgrid(np.arange(n_chord), np.arange(n_stations))
    n0 = (j * (n_chord + 1) + i).ravel()
    elements = np.stack([n0, n0 + 1, n0 + n_chord + 2, n0 + n_chord + 1], axis=1)
    y0, y1 = panels[0].root_le[1], panels[-1].tip_le[1]
    return PlateMesh(nodes=nodes, elements=elements.astype(np.int64),
                     thickness_root=thickness.root, thickness_tip=thickness.tip,
                     y_root=y0, span=y1 - y0, n_chord=n_chord, n_span=n_stations,
                     thickness_field=None if thickness.profile.is_flat and len(panels) == 1
                     else ThicknessField(panels, thickness))


def rectangular_mesh(a: float, b: float, thickness: float, n_x: int, n_y: int) -> PlateMesh:
    """A uniform ``n_x x n_y`` mesh of the rectangle [0, a] x [0, b] with constant thickness
    (validation plates). Lengths in m."""
    for name, v in (("a", a), ("b", b), ("thickness", thickness)):
        positive(name, v)
    planform = Planform((0.0, 0.0), a, (0.0, b), a)
    return structured_mesh(planform, LinearThickness(thickness, thickness), n_x, n_y)
