"""Corner thicknesses (Nastran CQUAD4 T1-T4) in a case file through ``[thickness] kind =
"table"`` with zero at a sharp edge (asekit/geometry.py ThicknessTable, docs/case-format.md
"Corner thicknesses"), and the shipped HA145E case data/cases/ha145e_plate.toml (issue 24).
The comparison with the deck import itself needs pyNastran: tests/io/test_bdf.py."""

import copy
import dataclasses
import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, load_case
from asekit.case import pipeline as P
from asekit.geometry import ThicknessTable
from asekit.structure.assembly import assemble
from asekit.util.paths import CASES_DIR

HA145E = CASES_DIR / "ha145e_plate.toml"
RAW = tomllib.loads(HA145E.read_text())


def _corner_thickness(mesh, planform, t_in: float) -> np.ndarray:
    """HA145E's CQUAD4 T1-T4 (ha145e_structure.bdf) on the case's mesh: 0 at the corners on
    the leading and trailing edges, t_in elsewhere (every element of the deck has T1-T4 or
    PSHELL T = 0.041 in)."""
    x, y = mesh.nodes.T
    xc = (x - planform.leading_edge_at(y)) / planform.chord_at(y)
    node_t = np.where((xc < 1e-6) | (xc > 1 - 1e-6), 0.0, t_in)
    return node_t[mesh.elements]


def test_table_with_sharp_edges_equals_corner_thicknesses():
    """The HA145E case's table (0 at x/c = 0 and 1, 0.041 in from 12.5 % to 87.5 % chord) is
    linear on each element of its parallelogram mesh, so it equals T1-T4 interpolated over the
    element (asekit.structure.plate, thickness_rule "gauss"): same K and M to rounding."""
    case = load_case(HA145E)
    mesh = P.structural_mesh(case)
    K, M = assemble(mesh, case.material)
    ct = _corner_thickness(mesh, case.panels[0].planform, 0.041 * 0.0254)
    assert np.count_nonzero(ct == 0.0) == 2 * 7 * 2       # two bevelled rows of 7, 2 corners
    K2, M2 = assemble(dataclasses.replace(mesh, corner_thickness=ct), case.material)
    assert abs(K - K2).max() <= 1e-9 * abs(K).max()
    assert abs(M - M2).max() <= 1e-9 * abs(M).max()
    # the bevelled rows are lighter: mass = rho A t (1 - 2 x 0.125 / 2) for the taper to zero
    area = 0.05259197 * 0.14033754
    u = np.tile([1.0, 0.0, 0.0], mesh.n_nodes)            # unit translation w = 1
    total = float(u @ (M @ u))
    assert total == pytest.approx(case.material.density * area * 0.041 * 0.0254 * 0.875,
                                  rel=1e-9)


def test_ha145e_case_is_the_deck_mesh_and_support():
    """4 x 7 elements at 0, 12.5, 50, 87.5, 100 % chord, 4 modes, held at the two root grids
    (9 and 25 of the deck, x = 0.258819 and 1.81173 in): 4 modes, lowest above zero."""
    case = load_case(HA145E)
    mesh = P.structural_mesh(case)
    assert (mesh.n_chord, mesh.n_span, mesh.n_nodes) == (4, 7, 40)
    root = np.sort(mesh.nodes[np.abs(mesh.nodes[:, 1]) < 1e-12, 0]) / 0.0254
    np.testing.assert_allclose(root, [0, 0.258819, 1.035275, 1.81173, 2.07055], atol=2e-6)
    assert P.supported_system(case).K.shape[0] == 3 * 40 - 6   # two clamped nodes x 3 DOFs
    f = P.modal_model(case).frequencies_hz
    assert f.size == 4 and f[0] > 1.0 and np.all(np.diff(f) > 0)


@pytest.mark.parametrize("values, message", [
    ([[0.0, 0.0, 1e-3], [0.0, 0.0, 1e-3]],
     r"thickness.values_m\[0..1\]\[0..1\] are all zero: the plate would have no thickness"),
    ([[0.0, -1e-3, 1e-3], [0.0, 1e-3, 1e-3]], r"thickness.values_m\[0\]\[1\] must be >= 0"),
])
def test_a_table_with_no_plate_somewhere_is_refused(values, message):
    raw = copy.deepcopy(RAW)
    raw["thickness"] = {"kind": "table", "x_over_c": [0.0, 0.5, 1.0], "eta": [0.0, 1.0],
                        "values_m": values}
    with pytest.raises(CaseError, match=message):
        case_from_dict(raw)


def test_zero_at_an_edge_is_allowed_and_interpolated():
    t = ThicknessTable((0.0, 0.125, 1.0), (0.0, 1.0), ((0.0, 1e-3, 1e-3), (0.0, 1e-3, 1e-3)))
    assert float(t.at(0.0625, 0.5)) == pytest.approx(0.5e-3, rel=1e-14)
    assert float(t.at(0.0, 0.3)) == 0.0
    with pytest.raises(ValueError, match="values_m\\[0\\]\\[0\\] must be a finite number >= 0"):
        ThicknessTable((0.0, 1.0), (0.0, 1.0), ((-1.0, 1e-3), (1e-3, 1e-3)))
