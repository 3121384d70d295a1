"""``support.region_fit`` (issue 23): the rigid shaft region fitted by the mesh's nodes
(asekit.structure.mesh.snap_to_circle through asekit.case.pipeline.structural_mesh)."""

import tomllib
import warnings

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, pipeline
from asekit.case.variants import with_shaft, with_shaft_grading
from asekit.util.paths import FIN_FILE

R = 0.005            # m, the distributed shaft of asekit.reproduction.fin.DEFAULT_SHAFT_RADIUS


def _fin(**support) -> dict:
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    d["support"].update(support)
    return d


def test_the_key_is_read_and_matches_the_variant():
    c = case_from_dict(_fin(region=R, region_fit="snap"))
    assert c.support.option("region_fit") == "snap"
    assert c == with_shaft(case_from_dict(_fin(region=R)), region_fit="snap")
    # the default is not stored: a case without the key is the case with "nodes"
    plain = case_from_dict(_fin(region=R))
    assert case_from_dict(_fin(region=R, region_fit="nodes")) == plain
    assert with_shaft(c, region_fit="nodes") == plain


@pytest.mark.parametrize("support, words", [
    ({"region": R, "region_fit": "round"}, "support.region_fit"),
    ({"region_fit": "snap"}, "support.region_fit"),                 # single-node shaft
])
def test_bad_values_name_the_key(support, words):
    with pytest.raises(CaseError, match=words):
        case_from_dict(_fin(**support))


def test_a_mesh_too_coarse_for_the_circle_is_fitted_partly_with_a_warning():
    # the graded 16 x 12 and 43 x 32 meshes (the second is the extrapolated study's middle
    # mesh): a few nodes would invert their anisotropic neighbours if moved, so they stay
    from asekit.structure.mesh import _inverted_elements
    for n in ((16, 12), (43, 32)):
        c = with_shaft_grading(case_from_dict(_fin(region=R, region_fit="snap")), *n)
        with pytest.warns(UserWarning, match="not moved"):
            m = pipeline.structural_mesh(c)
        assert _inverted_elements(m.nodes, m.elements).size == 0


def test_fitted_nodes_sit_on_the_circle_and_join_the_shaft_region():
    c = with_shaft_grading(case_from_dict(_fin(region=R, region_fit="snap")), 32, 24)
    plain = with_shaft_grading(case_from_dict(_fin(region=R)), 32, 24)
    m, m0 = pipeline.structural_mesh(c), pipeline.structural_mesh(plain)
    d = np.hypot(m.nodes[:, 0] - 0.078, m.nodes[:, 1])
    moved = np.any(m.nodes != m0.nodes, axis=1)
    assert moved.sum() > 0
    np.testing.assert_allclose(d[moved], R, rtol=1e-12)
    region = pipeline.supported_system(c).shaft_nodes
    assert set(np.flatnonzero(moved & (d <= R * (1 + 1e-9)))) <= set(region.tolist())


def test_fitted_region_converges_the_fins_first_modes_faster():
    # the fin's first two elastic modes (the region's rim decides the root's stiffness) on the
    # graded meshes 32 x 24 and 64 x 48: staircase region 93.02 -> 93.16 Hz and 171.83 ->
    # 172.32 Hz, fitted 93.35 -> 93.38 Hz and 173.14 -> 173.18 Hz (measured 2026-12-03)
    f = {}
    for fit in ("nodes", "snap"):
        for n in ((32, 24), (64, 48)):
            c = with_shaft_grading(case_from_dict(_fin(region=R, region_fit=fit)), *n)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                f[fit, n] = pipeline.modal_model(c).frequencies_hz[1:3]
    d_nodes = np.abs(f["nodes", (64, 48)] - f["nodes", (32, 24)])
    d_snap = np.abs(f["snap", (64, 48)] - f["snap", (32, 24)])
    assert np.all(d_snap < 0.3 * d_nodes), (d_snap, d_nodes)
    assert np.all(d_snap / f["snap", (64, 48)] < 5e-4)
    # the staircase region lies inside the circle, so it converges from below: the fitted
    # 32 x 24 is already above the staircase 64 x 48
    assert np.all(f["snap", (32, 24)] > f["nodes", (64, 48)])
