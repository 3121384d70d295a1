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


def _graded_fin(fit, n_chord, n_span):
    return with_shaft_grading(case_from_dict(_fin(region=R, region_fit=fit)),
                              n_chord, n_span)


def test_fitted_region_converges_the_fins_first_modes_faster():
    # the fin's first two elastic modes (the region's rim decides the root's stiffness) on the
    # graded meshes 24 x 18 and 48 x 36: staircase region 92.84 -> 93.19 Hz and 170.83 ->
    # 172.31 Hz, fitted 93.39 -> 93.37 Hz and 173.12 -> 173.17 Hz (measured 2026-12-03)
    f = {}
    for fit in ("nodes", "snap"):
        for n in ((24, 18), (48, 36)):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                f[fit, n] = pipeline.modal_model(_graded_fin(fit, *n)).frequencies_hz[1:3]
    d_nodes = np.abs(f["nodes", (48, 36)] - f["nodes", (24, 18)])
    d_snap = np.abs(f["snap", (48, 36)] - f["snap", (24, 18)])
    assert np.all(d_snap < 0.1 * d_nodes), (d_snap, d_nodes)
    assert np.all(d_snap / f["snap", (48, 36)] < 5e-4)
    # the staircase region lies inside the circle, so it converges from below: the fitted
    # 24 x 18 is already above the staircase 48 x 36
    assert np.all(f["snap", (24, 18)] > f["nodes", (48, 36)])


@pytest.mark.slow
def test_fitted_region_fin_flutter_is_mesh_converged_on_coarse_graded_meshes():
    """The fin's p-k flutter at M 0.75, sea level (14 x 10 boxes) with the 5 mm shaft region
    fitted: 32 x 24 and 128 x 96 graded meshes agree within 0.3 % (measured 254.79 and
    255.24 m/s; staircase region 251.43 and 254.10 m/s, tests/benchmarks/bench_converged.py),
    and the fitted 32 x 24 lies nearer the fine mesh than the staircase 64 x 48 does."""
    from dataclasses import replace

    from asekit.case.variants import with_boxes

    def speed(fit, n):
        c = with_boxes(_graded_fin(fit, *n), 14, 10)
        c = replace(c, aero=replace(c.aero, machs=(0.75,)),
                    flight=replace(c.flight, altitudes=(0.0,),
                                   velocities=tuple(np.arange(140.0, 340.0 + 1e-9, 2.0))))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return pipeline.flutter(c).results[0].flutter.speed

    coarse, fine = speed("snap", (32, 24)), speed("snap", (128, 96))
    assert abs(coarse / fine - 1) < 3e-3
    assert abs(coarse - fine) < abs(speed("nodes", (64, 48)) - fine)
