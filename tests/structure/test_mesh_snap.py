"""A circle fitted by a mesh's nodes (asekit.structure.mesh.snap_to_circle, issue 23): the
rigid shaft region of radius r as an inscribed polygon instead of a staircase."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from asekit.structure.mesh import _inverted_elements, rectangular_mesh, snap_to_circle

#: A circle centred on the bottom edge of the unit square, as the fin's shaft on its root.
CENTRE, R = (0.5, 0.0), 0.23


def _dist(mesh):
    return np.hypot(mesh.nodes[:, 0] - CENTRE[0], mesh.nodes[:, 1] - CENTRE[1])


def _cut_edges(mesh):
    d = _dist(mesh) - R
    e = mesh.elements
    edges = np.concatenate([e[:, [0, 1]], e[:, [1, 2]], e[:, [2, 3]], e[:, [3, 0]]])
    a, b = edges.T
    return edges[(d[a] * d[b] < 0) & (np.abs(d[a]) > 1e-12) & (np.abs(d[b]) > 1e-12)]


def _region_polygon_area(mesh):
    """Area of the polygon spanned by the region's nodes (every node within R)."""
    return ConvexHull(mesh.nodes[_dist(mesh) <= R * (1 + 1e-9)]).volume


@pytest.mark.parametrize("n", [8, 13, 32])
def test_no_edge_is_cut_and_moved_nodes_sit_on_the_circle(n):
    m = rectangular_mesh(1.0, 1.0, 0.01, n, n)
    s = snap_to_circle(m, CENTRE, R)
    assert len(_cut_edges(m)) > 0 and len(_cut_edges(s)) == 0
    moved = np.flatnonzero(np.any(s.nodes != m.nodes, axis=1))
    assert moved.size > 0
    np.testing.assert_allclose(_dist(s)[moved], R, rtol=1e-12)
    # a move is radial and at most half an edge (the nearer end of a cut edge)
    step = np.hypot(*(s.nodes[moved] - m.nodes[moved]).T)
    assert step.max() <= 0.5 / n * (1 + 1e-12)
    # the root edge (through the centre) keeps its nodes on it
    on_root = np.abs(m.nodes[:, 1]) < 1e-15
    assert np.all(np.abs(s.nodes[on_root, 1]) < 1e-15)
    np.testing.assert_array_equal(s.elements, m.elements)


def test_region_area_converges_at_second_order_when_fitted():
    # exact: the half disc pi R^2 / 2. The polygon of the nodes within R has vertices on the
    # circle once fitted, so its error is the chord-sagitta one, O(h^2) (4x per halving, measured
    # 0.0181, 0.0045, 0.00103, 0.00026 at n = 16..128); the staircase's is O(h) and erratic
    # (0.201, 0.060, 0.060, 0.016: no change at all from 32 to 64).
    exact = np.pi * R * R / 2
    ns = (16, 32, 64, 128)
    fit = [abs(_region_polygon_area(snap_to_circle(rectangular_mesh(1, 1, .01, n, n), CENTRE, R))
               / exact - 1) for n in ns]
    raw = [abs(_region_polygon_area(rectangular_mesh(1, 1, .01, n, n)) / exact - 1) for n in ns]
    orders = np.log2(np.array(fit[:-1]) / np.array(fit[1:]))
    assert np.all(orders > 1.8), orders
    assert all(f < 0.1 * u for f, u in zip(fit[1:], raw[1:]))


def test_bad_input_is_refused_and_a_too_coarse_mesh_is_fitted_partly_with_a_warning():
    m = rectangular_mesh(1.0, 1.0, 0.01, 8, 8)
    with pytest.raises(ValueError, match="radius"):
        snap_to_circle(m, CENTRE, 0.0)
    with pytest.raises(ValueError, match="centre"):
        snap_to_circle(m, (0.5, np.nan), R)
    # 2 x 2: the nearer end of a cut edge is the centre node itself, which cannot move
    with pytest.warns(UserWarning, match="1 of 1 nodes of cut edges not moved"):
        s = snap_to_circle(rectangular_mesh(1.0, 1.0, 0.01, 2, 2), CENTRE, 0.1)
    assert _inverted_elements(s.nodes, s.elements).size == 0
