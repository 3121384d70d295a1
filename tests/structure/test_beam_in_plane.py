"""The out-of-plane solve of a straight beam (asekit.structure.beam.beam_modes in_plane_fixed)
and the straight extension of the beam spline beyond its ends (asekit.aero.beam_spline,
extend=True, MSC Nastran's SPLINE2 convention; issue 24).

References: the decoupling of the in-plane (ux, uy, rz) and out-of-plane (uz, rx, ry) motion of
a beam in the (x, y) plane with in-plane mass offsets (Przemieniecki, *Theory of Matrix
Structural Analysis*, 1968: the element matrices are rotated about z only, Eq. 6.26), so the
out-of-plane modes of the free beam and of the beam with its in-plane motion fixed are the same
to round-off; a rigid motion (w linear in s, uniform twist) is reproduced exactly by the cubic
Hermite interpolation and by its straight extension.
"""

import numpy as np
import pytest

from asekit.aero.beam_spline import beam_spline_matrices
from asekit.structure.beam import (
    BeamSection,
    PointMass,
    beam_modes,
    straight_beam,
    uniform_beam,
)

SEC = BeamSection(1e9, 0.987e6, 9.77e6, 1e8, 35.71, 8.64, 0.18288)


def _beam(sec=SEC):
    pm = (PointMass(5, 3.0, (0.1, -0.05, 0.0), (0.2, 0.3, 0.4)),)
    return straight_beam((0.6, 0.0), (np.sin(0.3), np.cos(0.3)), np.linspace(0, 6.0, 13),
                         sec, pm)


def test_out_of_plane_modes_are_unchanged_by_fixing_the_in_plane_motion():
    free = beam_modes(_beam(), 12)
    fixed = beam_modes(_beam(), 4, in_plane_fixed=True)
    flat = free.shapes[:, [2, 3, 4], :].reshape(-1, 12)
    out = np.linalg.norm(flat, axis=0) > 1e-6 * np.abs(flat).max()   # the out-of-plane modes
    np.testing.assert_allclose(fixed.frequencies_hz, free.frequencies_hz[out][:4], rtol=1e-9)
    assert np.abs(fixed.shapes[:, [0, 1, 5], :]).max() == 0.0


def test_zero_in_plane_stiffness_needs_the_in_plane_motion_fixed():
    soft = BeamSection(0.0, 0.987e6, 9.77e6, 0.0, 35.71, 0.0)
    with pytest.raises(ValueError, match="in_plane_fixed=True"):
        beam_modes(_beam(soft), 2)
    ref = beam_modes(_beam(BeamSection(1e9, 0.987e6, 9.77e6, 1e8, 35.71, 0.0)), 3,
                     in_plane_fixed=True)
    np.testing.assert_allclose(beam_modes(_beam(soft), 3, in_plane_fixed=True).frequencies_hz,
                               ref.frequencies_hz, rtol=1e-12)


def test_spline_extension_is_the_straight_end_section():
    beam = uniform_beam((0.5, 0.0), (np.sin(0.2), np.cos(0.2)), 4.0, 4, SEC)
    e1, aft = beam.direction[:2], np.array([beam.direction[1], -beam.direction[0]])
    u = np.zeros(6 * beam.n_nodes)
    c, th = 0.03, 0.01                       # w = c s, nose-up twist th about e1
    u[2::6] = c * beam.stations
    u[3::6], u[4::6] = th * e1[0] + c * aft[0], th * e1[1] + c * aft[1]   # r: twist + slope
    s, a = np.array([-0.3, 4.5, 2.0]), np.array([0.2, -0.4, 0.1])
    pts = beam.root[None, :2] + s[:, None] * e1[None, :] + a[:, None] * aft[None, :]
    with pytest.raises(ValueError, match="outside the beam"):
        beam_spline_matrices(beam, pts)
    G, Gx = beam_spline_matrices(beam, pts, extend=True)
    np.testing.assert_allclose(G @ u, c * s - a * th, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Gx @ u, c * e1[0] - th * e1[1], rtol=1e-12)
