"""Beam-to-box spline: mode shapes of a stick model on the aerodynamic boxes (the idea of
MSC Nastran's SPLINE2, *MSC Nastran Aeroelastic Analysis User's Guide*, Sec. 2.3 "Beam
splines", with the beam's own shape functions in place of the spline's).

A box point at distance s along the beam's elastic axis and a *aft* of it (in the surface's
plane, perpendicular to the axis) moves normal to the surface by the section's rigid motion:

    h(s, a) = w(s) - a theta(s),

w the deflection of the axis along +z, theta the nose-up twist about the axis direction e1
(a positive twist moves the trailing edge down, the convention of
``asekit.structure.assembly.rigid_pitch_vector``; Nastran's SPLINE2 writes
w + (x - x_ea) theta with its twist of the opposite sense). Inside each element w is the
element's cubic Hermite interpolation of the node deflections and slopes (slope = -r2, the
rotation about e2 = e3 x e1) and theta the linear interpolation of the node twists
r1 = e1 . r (:mod:`asekit.structure.beam`). The streamwise slope follows from the chain rule
with s = (p - p0) . e1 and a = (p - p0) . (e1 x e3):

    dh/dx = (dw/ds - a dtheta/ds) e1_x - theta e1_y,

which is -theta on an unswept axis (e1 = +y). Forces return by the transpose of the
displacement interpolation at the load points, as for every spline of
:mod:`asekit.aero.spline` (:func:`asekit.aero.spline.modal_forces`), so the generalised forces
are work-consistent.
"""

from __future__ import annotations

import numpy as np

from asekit.aero.spline import BoxModes
from asekit.structure.beam import NODE_DOF, BeamModes, StraightBeam
from asekit.util.validate import finite_array

#: a point may lie this fraction of the beam's length beyond its root or tip (rounding).
SPAN_TOLERANCE = 1e-9


def _hermite(xi: np.ndarray, length: np.ndarray):
    """Cubic Hermite functions (n, 4) of (w_a, w'_a, w_b, w'_b) and their s-derivatives."""
    n = np.column_stack([1 - 3 * xi ** 2 + 2 * xi ** 3, length * (xi - 2 * xi ** 2 + xi ** 3),
                         3 * xi ** 2 - 2 * xi ** 3, length * (xi ** 3 - xi ** 2)])
    dn = np.column_stack([(-6 * xi + 6 * xi ** 2) / length, 1 - 4 * xi + 3 * xi ** 2,
                          (6 * xi - 6 * xi ** 2) / length, 3 * xi ** 2 - 2 * xi])
    return n, dn


def beam_spline_matrices(beam: StraightBeam, points,
                         extend: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Interpolation matrices (G, Gx), each (n_points, 6 n_nodes): h(points) = G u and
    dh/dx(points) = Gx u for a global beam displacement vector u (ux, uy, uz, rx, ry, rz per
    node, :func:`asekit.structure.beam.assemble`'s order).

    Parameters
    ----------
    beam : :class:`~asekit.structure.beam.StraightBeam` (its axis in the (x, y) plane).
    points : (n_points, 2 or 3) x, y (m) of points on the surface; their projection on the
        axis must lie between the root and the tip (ValueError naming the point otherwise)
        unless ``extend``.
    extend : bool, points beyond the root or the tip move with the end section extended
        straight, as MSC Nastran's SPLINE2 (Aeroelastic Analysis User's Guide, Sec. 2.3: the
        spline beam is unloaded beyond its end stations): h = w_e + w'_e (s - s_e) - a theta_e,
        dh/dx = w'_e e1_x - theta_e e1_y (default False).

    Returns
    -------
    (G, Gx) : (n_points, 6 n_nodes) arrays; G in m/m and m/rad, Gx in 1/m and 1/rad.

    Examples
    --------
    >>> from asekit.structure.beam import BeamSection, uniform_beam
    >>> sec = BeamSection(1e9, 1e6, 1e7, 1e8, 35.0, 8.0)
    >>> beam = uniform_beam((0.5, 0.0), (0.0, 1.0), 6.0, 3, sec)
    >>> u = np.zeros(24); u[4::6] = 1.0                 # unit nose-up twist everywhere
    >>> G, Gx = beam_spline_matrices(beam, [[1.5, 2.5], [0.0, 6.0]])
    >>> (G @ u).tolist(), (Gx @ u).tolist()             # h = -(x - 0.5), dh/dx = -1
    ([-1.0, 0.5], [-1.0, -1.0])
    """
    p = finite_array("points", points)
    p = np.atleast_2d(p)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"points must be (n, 2) or (n, 3) x, y (z) coordinates, got {p.shape}")
    e1 = beam.direction[:2]
    aft = np.array([e1[1], -e1[0]])                       # e1 x e3 in the (x, y) plane
    rel = p[:, :2] - beam.root[None, :2]
    s = rel @ e1
    a = rel @ aft
    st = beam.stations
    tol = SPAN_TOLERANCE * st[-1]
    bad = np.flatnonzero((s < -tol) | (s > st[-1] + tol))
    if bad.size and not extend:
        i = int(bad[0])
        raise ValueError(f"points[{i}] = {p[i, :2].tolist()} lies at s = {s[i]:.6g} m along the "
                         f"beam axis, outside the beam [0, {st[-1]:.6g}] m "
                         f"({bad.size} points outside)")
    beyond = (s - np.clip(s, 0.0, st[-1]) if extend      # (0 inside) straight extension
              else np.zeros_like(s))
    s = np.clip(s, 0.0, st[-1])
    elem = np.clip(np.searchsorted(st, s, side="right") - 1, 0, st.size - 2)
    length = st[elem + 1] - st[elem]
    xi = (s - st[elem]) / length
    n, dn = _hermite(xi, length)
    frame = beam.frame
    e2 = frame[1]
    # node rows: deflection uz, slope w' = -r2 = -(e2 . r), twist r1 = e1 . r
    n_pts = p.shape[0]
    G = np.zeros((n_pts, NODE_DOF * beam.n_nodes))
    Gx = np.zeros_like(G)
    rows = np.arange(n_pts)
    e1x, e1y = e1
    for side, node in ((0, elem), (1, elem + 1)):
        base = NODE_DOF * node
        nw, ns = n[:, 2 * side], n[:, 2 * side + 1]            # value and slope functions
        dnw, dns = dn[:, 2 * side], dn[:, 2 * side + 1]
        nt = 1 - xi if side == 0 else xi                         # linear twist
        dnt = np.where(beyond == 0.0, (-1.0 if side == 0 else 1.0) / length, 0.0)
        nw, ns = nw + beyond * dnw, ns + beyond * dns             # w_e + w'_e (s - s_e)
        # h = w - a theta
        G[rows, base + 2] += nw
        Gx[rows, base + 2] += dnw * e1x
        for k in range(3):                                        # rotations rx, ry, rz
            G[rows, base + 3 + k] += -ns * e2[k] - a * nt * frame[0, k]
            Gx[rows, base + 3 + k] += (-dns * e2[k] - a * dnt * frame[0, k]) * e1x \
                - nt * frame[0, k] * e1y
    return G, Gx


def beam_box_modes(modes: BeamModes, mesh) -> BoxModes:
    """Mode shapes of a stick model on a box mesh (:class:`~asekit.aero.spline.BoxModes`):
    h and dh/dx at the control points, h at the load points, per unit modal coordinate.

    Parameters
    ----------
    modes : :class:`~asekit.structure.beam.BeamModes`.
    mesh : :class:`~asekit.aero.boxes.BoxMesh` in the beam's plane (z = 0, no dihedral).

    Returns
    -------
    :class:`~asekit.aero.spline.BoxModes` with n_modes columns.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.structure.beam import BeamSection, beam_modes, uniform_beam
    >>> sec = BeamSection(1e10, 0.987e6, 9.77e6, 1e9, 35.71, 8.64, 0.18288)
    >>> modes = beam_modes(uniform_beam((0.6035, 0.0), (0.0, 1.0), 6.096, 8, sec), 2)
    >>> mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.8288, (0, 6.096, 0), 1.8288, 4, 8)])
    >>> beam_box_modes(modes, mesh).h_cp.shape
    (32, 2)
    """
    if np.any(np.abs(mesh.corners[:, :, 2]) > 1e-9) or np.any(np.abs(mesh.dihedral) > 1e-12):
        raise ValueError("beam_box_modes needs boxes in the beam's plane z = 0 (no dihedral)")
    phi = modes.shapes.reshape(NODE_DOF * modes.beam.n_nodes, -1)
    g_cp, gx_cp = beam_spline_matrices(modes.beam, mesh.control_point)
    g_lp, _ = beam_spline_matrices(modes.beam, mesh.load_point)
    return BoxModes(g_cp @ phi, gx_cp @ phi, g_lp @ phi)
