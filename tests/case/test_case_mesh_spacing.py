"""Node stations of a panel's structural mesh in the case file and its variants:
``panel.chord_stations`` / ``span_stations`` / ``chord_grading`` / ``span_grading``
(asekit/case/schema.py), :func:`with_mesh` and :func:`with_shaft_grading`
(asekit/case/variants.py)."""

import tomllib
import warnings
from dataclasses import replace

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, pipeline
from asekit.case.variants import with_mesh, with_shaft, with_shaft_grading
from asekit.structure.mesh import Grading, Stations
from asekit.util.paths import FIN_FILE


def _fin(**panel) -> dict:
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    for k, v in panel.items():
        if v is None:
            d["panel"][0].pop(k, None)
        else:
            d["panel"][0][k] = v
    return d


def test_explicit_stations_place_the_nodes_and_give_the_count():
    # rows at 12.5 % chord from each edge (the Nastran decks of issue 24)
    c = case_from_dict(_fin(chord_stations=[0, 0.125, 0.5, 0.875, 1], n_chord=None,
                            span_stations=[0, 0.25, 1], n_span=None))
    p = c.panels[0]
    assert (p.n_chord, p.n_span) == (4, 2)
    assert p.chord_spacing == Stations((0.0, 0.125, 0.5, 0.875, 1.0))
    mesh = pipeline.structural_mesh(c)
    root = np.sort(mesh.nodes[np.abs(mesh.nodes[:, 1]) < 1e-12, 0])
    np.testing.assert_allclose(root, 0.156 * np.array([0, 0.125, 0.5, 0.875, 1]), atol=1e-12)
    np.testing.assert_allclose(np.unique(np.round(mesh.nodes[:, 1], 12)), [0, 0.0375, 0.15])
    # a count that is a multiple of the stations' refines them: 8 elements split each in two
    assert pipeline.structural_mesh(case_from_dict(_fin(
        chord_stations=[0, 0.125, 0.5, 0.875, 1], n_chord=8))).n_nodes == 9 * 8


def test_a_grading_table_is_read_and_used_by_the_pipeline():
    c = case_from_dict(_fin(n_chord=8, chord_grading={"toward": 0.5, "ratio": 4.0},
                            span_grading={"toward": [0.0], "ratio": 4.0, "width": 0.1,
                                          "ramp": 0.5}))
    p = c.panels[0]
    assert p.chord_spacing == Grading((0.5,), 4.0)
    assert p.span_spacing == Grading((0.0,), 4.0, 0.1, 0.5)
    mesh = pipeline.structural_mesh(c)
    root = np.sort(mesh.nodes[np.abs(mesh.nodes[:, 1]) < 1e-12, 0])
    h = np.diff(root)
    assert h[3] < h[0] and h[4] < h[7]                 # finest at the shaft, mid-chord
    assert pipeline.modal_model(c).n_rigid == 1        # the single-node shaft finds its node


@pytest.mark.parametrize("panel, message", [
    ({"chord_stations": [0, 0.5, 0.4, 1]},
     r"panel\[0\]\.chord_stations must be strictly ascending, got panel\[0\]\.chord_stations\[2\]"),
    ({"chord_stations": [0.1, 1]}, r"panel\[0\]\.chord_stations must start at 0 and end at 1"),
    ({"span_stations": [0, 1.5]}, r"panel\[0\]\.span_stations\[1\] must be <= 1, got 1.5"),
    ({"span_stations": [0, "a", 1]}, r"panel\[0\]\.span_stations\[1\] must be a finite number"),
    ({"chord_stations": [0, 0.5, 1], "n_chord": 3},
     r"panel\[0\]\.chord_stations holds 3 stations \(2 elements\): the element count must be a "
     r"multiple of 2, got 3 \(panel\[0\]\.n_chord = 3\)"),
    ({"chord_stations": [0, 0.5, 1], "chord_grading": {"toward": 0.5, "ratio": 2.0}},
     r"panel\[0\]\.chord_stations and panel\[0\]\.chord_grading both given"),
    ({"chord_grading": {"toward": 0.5, "ratio": 0.5}},
     r"panel\[0\]\.chord_grading\.ratio must be >= 1, got 0.5"),
    ({"chord_grading": {"toward": [0.6, 0.4], "ratio": 2.0}},
     r"panel\[0\]\.chord_grading\.toward must be strictly ascending"),
    ({"span_grading": {"toward": 0.0, "ratio": 2.0, "width": 1.0}},
     r"panel\[0\]\.span_grading\.width must be < 1, got 1"),
    ({"span_grading": {"toward": 0.0, "ratio": 2.0, "ramp": 0}},
     r"panel\[0\]\.span_grading\.ramp must be > 0, got 0"),
    ({"span_grading": {"toward": 0.0, "ratio": 2.0, "grow": 1.2}},
     r"panel\[0\]\.span_grading\.grow is not a known key"),
    ({"span_grading": {"ratio": 2.0}}, r"panel\[0\]\.span_grading\.toward is missing"),
    ({"span_grading": {"toward": 0.0, "ratio": 2.0}, "n_span": None},
     r"panel\[0\]\.n_span is missing: panel\[0\]\.span_grading needs the element count"),
    ({"chord_grading": {"toward": [0.2, 0.8], "ratio": 2.0}, "n_chord": 2},
     r"panel\[0\]\.chord_grading: clustering toward \[0.2, 0.8\] splits \[0, 1\] into 3 pieces "
     r"and needs at least 3 elements, got 2 \(panel\[0\]\.n_chord = 2\)"),
])
def test_bad_station_keys_name_the_key_path(panel, message):
    with pytest.raises(CaseError, match=message):
        case_from_dict(_fin(**panel))


def test_a_second_panel_shares_the_first_panels_chord_spacing():
    d = _fin(n_chord=4, chord_grading={"toward": 0.5, "ratio": 3.0})
    p0 = d["panel"][0]
    tip = {"root_leading_edge": p0["tip_leading_edge"], "root_chord": p0["tip_chord"],
           "tip_leading_edge": [0.1, 0.2], "tip_chord": 0.05, "n_chord": 4, "n_span": 2}
    d["panel"].append(tip)
    c = case_from_dict(d)
    assert c.panels[1].chord_spacing == c.panels[0].chord_spacing      # inherited
    tip["chord_grading"] = {"toward": 0.4, "ratio": 3.0}
    with pytest.raises(CaseError, match=r"panel\[1\] chord spacing .* must equal panel\[0\]'s"):
        case_from_dict(d)


def test_with_mesh_keeps_sets_and_checks_the_spacing(fin_case):
    g = with_mesh(fin_case, 12, 14, Grading(0.5, 8.0), Grading(0.0, 8.0))
    assert g.panels[0].chord_spacing == Grading(0.5, 8.0)
    kept = with_mesh(g, 24, 28)                                  # refined on its own grading
    assert kept.panels[0].span_spacing == Grading(0.0, 8.0) and kept.panels[0].n_span == 28
    assert with_mesh(g, 24, 28, None, None).panels[0].chord_spacing is None
    s = with_mesh(fin_case, 4, None, [0, 0.25, 0.5, 0.75, 1])
    assert isinstance(s.panels[0].chord_spacing, Stations)
    with pytest.raises(CaseError, match=r"panel\[0\]\.chord_spacing holds 5 stations"):
        with_mesh(s, 6)
    with pytest.raises(CaseError, match=r"panel\[0\]\.span_spacing must start at 0"):
        with_mesh(fin_case, None, 2, span_spacing=[0.2, 0.5, 1.0])


def test_shaft_grading_puts_node_lines_on_the_shaft_region_and_the_root(fin_case):
    r = 0.005
    c = with_shaft_grading(with_shaft(fin_case, radius=r), 32, 24)
    mesh = pipeline.structural_mesh(c)
    x_a = fin_case.support.axis_point[0]
    for x in (x_a - 0.85 * r, x_a + 0.85 * r):                   # the band's centre lines
        assert np.min(np.hypot(mesh.nodes[:, 0] - x, mesh.nodes[:, 1])) < 1e-12
    assert np.any(np.abs(mesh.nodes[:, 1] - 0.85 * r) < 1e-12)
    d = np.hypot(mesh.nodes[:, 0] - x_a, mesh.nodes[:, 1])
    assert np.count_nonzero(d <= r) >= 20                        # the region is resolved
    single = with_shaft_grading(fin_case, 8, 8)                  # toward the axis node
    assert single.panels[0].chord_spacing.toward == (0.5,)
    assert pipeline.modal_model(single).n_rigid == 1
    with pytest.raises(CaseError, match="support.kind"):
        with_shaft_grading(_clamped(fin_case), 8, 8)
    with pytest.raises(CaseError, match="does not fit"):
        with_shaft_grading(with_shaft(fin_case, radius=0.1), 8, 8)


def _clamped(case):
    return replace(case, support=replace(case.support, kind="clamped_root"))


def test_graded_fin_resolves_the_shaft_region_with_fewer_nodes(fin_case):
    # The fin on the distributed shaft (r = 5 mm): the torsion mode's frequency of a graded
    # 48 x 32 mesh (1617 nodes) is within 1.5 % of 173.5 Hz, the Richardson limit of the graded
    # sequence 48x32, 96x64, 192x128 (171.64, 172.52, 172.99 Hz; tests/benchmarks/
    # bench_converged.py), while a uniform 48 x 56 mesh (2793 nodes) is more than 5 % below:
    # uniform refinement resolves the region's edge only like 1 / h.
    base = with_shaft(fin_case, radius=0.005)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        graded = pipeline.modal_model(with_shaft_grading(base, 48, 32))
        uniform = pipeline.modal_model(with_mesh(base, 48, 56))
    assert graded.nodes.shape[0] < uniform.nodes.shape[0]
    f_g, f_u = graded.frequencies_hz[2], uniform.frequencies_hz[2]
    assert abs(f_g / 173.5 - 1) < 0.015, f_g
    assert f_u / 173.5 - 1 < -0.05, f_u
