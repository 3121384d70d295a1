"""The beam-to-box spline (asekit/aero/beam_spline.py): rigid motions of the beam give the
exact rigid motions of every box (plunge, pitch about the elastic axis, roll), on unswept and
swept axes; Hermite interpolation reproduces cubic deflections exactly; a mode evaluated on
the axis equals its node values; bad points are refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from asekit.aero.beam_spline import beam_box_modes, beam_spline_matrices
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.structure.beam import BeamSection, beam_modes, straight_beam, uniform_beam

SEC = BeamSection(1e10, 0.987e6, 9.77e6, 1e9, 35.71, 8.64, 0.18288)


def _rigid(beam, translation=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0), about=(0.0, 0.0, 0.0)):
    """Global DOF vector of a small rigid motion: u = t + r x (p - about), node rotations r."""
    t, r, c = (np.asarray(v, float) for v in (translation, rotation, about))
    u = np.zeros((beam.n_nodes, 6))
    u[:, :3] = t + np.cross(r, beam.nodes - c)
    u[:, 3:] = r
    return u.ravel()


def _points(rng, beam, n=40):
    """Points over the planform: s along the axis in [0, L], a from -1 to 1.5 m aft."""
    e1 = beam.direction[:2]
    aft = np.array([e1[1], -e1[0]])
    s = rng.uniform(0, beam.stations[-1], n)
    a = rng.uniform(-1.0, 1.5, n)
    return beam.root[None, :2] + s[:, None] * e1 + a[:, None] * aft


@pytest.mark.parametrize("sweep_deg", [0.0, 30.0, -20.0])
def test_rigid_motions_are_exact(sweep_deg):
    lam = math.radians(sweep_deg)
    beam = straight_beam((0.6, 0.2), (math.sin(lam), math.cos(lam)), [0, 0.7, 2.1, 3.0, 4.4],
                         SEC)
    pts = _points(np.random.default_rng(3), beam)
    G, Gx = beam_spline_matrices(beam, pts)
    x, y = pts[:, 0], pts[:, 1]
    # plunge: h = 1, dh/dx = 0
    u = _rigid(beam, translation=(0, 0, 1))
    np.testing.assert_allclose(G @ u, 1.0, atol=1e-13)
    np.testing.assert_allclose(Gx @ u, 0.0, atol=1e-13)
    # unit nose-up pitch about +y through the root point: h = -(x - x0), dh/dx = -1
    u = _rigid(beam, rotation=(0, 1, 0), about=beam.root)
    np.testing.assert_allclose(G @ u, -(x - beam.root[0]), atol=1e-12)
    np.testing.assert_allclose(Gx @ u, -1.0, atol=1e-12)
    # unit roll about +x through the root point: h = y - y0, dh/dx = 0
    u = _rigid(beam, rotation=(1, 0, 0), about=beam.root)
    np.testing.assert_allclose(G @ u, y - beam.root[1], atol=1e-12)
    np.testing.assert_allclose(Gx @ u, 0.0, atol=1e-12)


def test_cubic_deflection_and_linear_twist_are_reproduced():
    """w(s) = c s^3 + b s^2 and theta(s) = t s on an unswept axis lie in the element space:
    h and dh/dx are exact inside every element."""
    beam = uniform_beam((0.5, 0.0), (0.0, 1.0), 3.0, 3, SEC)
    s = beam.stations
    c, b, t = 0.02, -0.1, 0.05
    u = np.zeros((beam.n_nodes, 6))
    u[:, 2] = c * s ** 3 + b * s ** 2
    u[:, 0 + 3] = (3 * c * s ** 2 + 2 * b * s)       # slope dw/dy = rx for an axis along +y
    u[:, 4] = t * s
    pts = np.column_stack([np.linspace(-0.3, 1.6, 11), np.linspace(0.05, 2.95, 11)])
    G, Gx = beam_spline_matrices(beam, pts)
    ss, a = pts[:, 1], pts[:, 0] - 0.5
    np.testing.assert_allclose(G @ u.ravel(), c * ss ** 3 + b * ss ** 2 - a * t * ss, atol=1e-13)
    np.testing.assert_allclose(Gx @ u.ravel(), -t * ss, atol=1e-13)


def test_box_modes_of_beam_modes_on_the_axis_equal_the_node_values():
    modes = beam_modes(uniform_beam((0.6035, 0.0), (0.0, 1.0), 6.096, 8, SEC), 3)
    beam = modes.beam
    G, Gx = beam_spline_matrices(beam, beam.nodes[:, :2])
    phi = modes.shapes.reshape(-1, 3)
    np.testing.assert_allclose(G @ phi, modes.shapes[:, 2, :], atol=1e-14)
    np.testing.assert_allclose(Gx @ phi, -modes.shapes[:, 4, :], atol=1e-14)
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.8288, (0, 6.096, 0), 1.8288, 5, 8)])
    bm = beam_box_modes(modes, mesh)
    g_cp, gx_cp = beam_spline_matrices(beam, mesh.control_point)
    np.testing.assert_allclose(bm.h_cp, g_cp @ phi)
    np.testing.assert_allclose(bm.dhdx_cp, gx_cp @ phi)
    assert bm.h_lp.shape == (40, 3)


def test_points_off_the_beam_are_refused():
    beam = uniform_beam((0.5, 0.0), (0.0, 1.0), 3.0, 3, SEC)
    with pytest.raises(ValueError, match=r"points\[1\].*outside the beam \[0, 3\]"):
        beam_spline_matrices(beam, [[0.5, 1.0], [0.5, 3.2]])
    with pytest.raises(ValueError, match="points"):
        beam_spline_matrices(beam, [[0.5, float("nan")]])
