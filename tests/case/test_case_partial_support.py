"""``support.kind = "partial"``: clamped or pinned nodes at listed points and on parts of the
named edges (asekit/structure/supports.py, the case file's ``[support]``; docs/case-format.md),
the case-file form of a Nastran SPC1 on some grids (issue 24, HA145E clamps two root grids)."""

import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, pipeline
from asekit.structure.supports import partial_support_nodes
from asekit.util.paths import FIN_FILE


def _fin(**support) -> dict:
    """The reference fin's case file with ``[support]`` replaced and no rigid mode kept."""
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    d["support"] = support
    d["modes"] = {"count": 4}
    for k in ("actuator", "ase", "controller"):
        d.pop(k, None)
    return d


def _freqs(**support) -> np.ndarray:
    return pipeline.modal_model(case_from_dict(_fin(**support))).frequencies_hz


def test_whole_root_edge_equals_clamped_root():
    """root = [0, 1] holds every root node: the same system as kind = "clamped_root"."""
    ref = _freqs(kind="clamped_root")
    np.testing.assert_allclose(_freqs(kind="partial", root=[0.0, 1.0]), ref, rtol=1e-10)
    # the root nodes listed as points give the same system again
    mesh = pipeline.structural_mesh(case_from_dict(_fin(kind="clamped_root")))
    root = mesh.nodes[np.abs(mesh.nodes[:, 1]) < 1e-12]
    np.testing.assert_allclose(_freqs(kind="partial", points=root.tolist()), ref, rtol=1e-10)


def test_a_root_point_clamp_is_softer_than_the_whole_root():
    """A cantilever clamped at one root node (a subset of the constraints) has every
    frequency at or below the fully clamped one (Rayleigh's constraint theorem), the first
    strictly lower; clamping part of the root lies in between."""
    full = _freqs(kind="clamped_root")
    half = _freqs(kind="partial", root=[0.0, 0.5])
    point = _freqs(kind="partial", points=[[0.078, 0.0]])
    assert point[0] < half[0] < full[0]
    assert np.all(point <= half * (1 + 1e-9)) and np.all(half <= full * (1 + 1e-9))
    assert point[0] < 0.9 * full[0]
    assert point[0] > 0.0


def test_pinned_support_holds_only_w():
    """Pinned nodes keep their rotations, so pinning the root and one tip node is softer than
    clamping the same nodes; pinning only the root (nodes on one line) leaves the plate free to
    rotate about it and is refused."""
    pinned = _freqs(kind="partial", condition="pinned", root=[0.0, 1.0],
                    points=[[0.117, 0.15]])
    clamped = _freqs(kind="partial", condition="clamped", root=[0.0, 1.0],
                     points=[[0.117, 0.15]])
    assert 0.0 < pinned[0] < clamped[0]
    with pytest.raises(ValueError, match="support.condition = \"pinned\" at nodes .* leaves a "
                                         "rigid-body motion"):
        _freqs(kind="partial", condition="pinned", root=[0.0, 1.0])


def test_nodes_nearest_to_points_and_edge_ranges():
    mesh = pipeline.structural_mesh(case_from_dict(_fin(kind="clamped_root")))
    n_root = int(np.sum(np.abs(mesh.nodes[:, 1]) < 1e-12))
    root = partial_support_nodes(mesh, ranges=[("root", (0.0, 1.0))])
    assert root.size == n_root
    lead = partial_support_nodes(mesh, ranges=[("leading_edge", (0.0, 1.0))])
    assert lead.size == mesh.n_span + 1
    # a point a little off a node snaps to it
    node = mesh.nodes[5]
    assert partial_support_nodes(mesh, points=[node + 1e-5]).tolist() == [5]


def test_root_springs_tend_to_the_clamped_root():
    """Grounded springs on every root node: the frequencies rise with the stiffness and tend
    to the clamped root's from below (finite springs are a relaxed constraint)."""
    full = _freqs(kind="clamped_root")
    f = [_freqs(kind="partial", condition="springs", root=[0.0, 1.0], springs=[k, k, k])
         for k in (1e4, 1e6, 1e8, 1e11)]
    for lo, hi in zip(f, f[1:]):
        assert np.all(lo < hi * (1 + 1e-9))
    assert np.all(f[-1] <= full * (1 + 1e-9))
    np.testing.assert_allclose(f[-1], full, rtol=1e-4)
    assert f[0][0] < 0.6 * full[0]                       # measured 100.4 vs 186.9 Hz
    # a w spring alone at nodes on one line leaves the rotation about it free: refused
    with pytest.raises(ValueError, match="leaves a rigid-body motion"):
        _freqs(kind="partial", condition="springs", root=[0.0, 1.0], springs=[1e6, 0.0, 0.0])
    # ... a rotational spring about that line (theta_x: the root runs along x) restrains it
    assert _freqs(kind="partial", condition="springs", root=[0.0, 1.0],
                  springs=[1e6, 1e3, 0.0])[0] > 0.0


@pytest.mark.parametrize("support, message", [
    ({"condition": "springs", "root": [0, 1]}, r"support.springs = \[k_w, k_theta_x, k_theta_y\] "
                                               r"\(N/m, N m/rad, N m/rad\) is needed with"),
    ({"springs": [1.0, 1.0, 1.0], "root": [0, 1]}, r"support.springs .* only with"),
    ({"condition": "springs", "springs": [0.0, 0.0, 0.0], "root": [0, 1]},
     r"support.springs must have one stiffness > 0"),
    ({"condition": "springs", "springs": [1.0, -1.0, 0.0], "root": [0, 1]},
     r"support.springs\[1\] must be"),
    ({"points": [[0.5, 0.0]]}, r"support.points\[0\] = \[0.5, 0\] m is off the plate: at y = 0 "
                               r"m, x must lie in \[0, 0.156\] m"),
    ({"points": [[0.0, 0.2]]}, r"support.points\[0\].*y must lie in \[0, 0.15\] m"),
    ({"points": [[0.0]]}, r"support.points\[0\] must be a point \[x, y\]"),
    ({"points": []}, r"support.points must be a non-empty list"),
    ({"root": [0.6, 0.2]}, r"support.root must be a range \[start, end\] of fractions with "
                           r"0 <= start <= end <= 1"),
    ({"tip": [0.0, 1.5]}, r"support.tip must be a range"),
    ({}, r"support.kind = \"partial\" needs support.points"),
    ({"condition": "welded", "root": [0, 1]}, r"support.condition must be one of"),
    ({"root": [0, 1], "radius": 1.0}, r"support.radius is not a known key"),
])
def test_bad_partial_support_names_the_key(support, message):
    with pytest.raises(CaseError, match=message):
        case_from_dict(_fin(kind="partial", **support))


def test_a_range_without_a_node_is_refused_naming_the_key():
    with pytest.raises(ValueError, match=r"support.root = \[0.2, 0.3\] holds no node"):
        _freqs(kind="partial", root=[0.2, 0.3])
