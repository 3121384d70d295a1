"""A Case that carries an imported structure (asekit.case.imported.ImportedModel): the pipeline
uses its mesh, K, M, support reduction and boxes. Checked without pyNastran by importing a file
case's own model: the imported case must give the file case's modes and flutter exactly."""

import dataclasses
import tomllib

import numpy as np
import pytest

from asekit.case import ImportedModel, SupportSpec, case_from_dict
from asekit.case import pipeline as pl
from asekit.case.schema import CaseError, PointMass
from asekit.structure.assembly import clamped_edge
from asekit.util.paths import DATA_DIR


@pytest.fixture(scope="module")
def clamped_fin():
    """The thesis fin on a clamped root (no actuator), 6 x 7 elements, 0.4 times as thick (so
    that it flutters in the sweep: measured 219 m/s at M 0.5, sea level)."""
    with open(DATA_DIR / "cases" / "nalci2013_fin.toml", "rb") as f:
        d = tomllib.load(f)
    d.pop("actuator", None)
    d["thickness"].update(root=0.4 * d["thickness"]["root"], tip=0.4 * d["thickness"]["tip"])
    d["aero"]["machs"] = [0.5]
    d["flight"]["altitudes"] = [0.0]
    d["flight"].pop("envelope", None)
    d["support"] = {"kind": "clamped_root"}
    d["modes"] = {"count": 4}
    d["damping"] = {"modal_damping_ratio": 0.01}
    return case_from_dict(d)


def _imported(case, **kw):
    """``case`` with its own structure and boxes handed over as an ImportedModel."""
    mesh = pl.structural_mesh(case)
    K, M = pl.mass_and_stiffness(case)
    s = ImportedModel(mesh, K, M, clamped_edge(mesh, K, M).T, boxes=pl.box_mesh(case), **kw)
    return dataclasses.replace(case, panels=(), thickness=None, material=None,
                               support=SupportSpec(kind="imported"), point_masses=(),
                               structure=s, aero=dataclasses.replace(case.aero, boxes=None))


def test_imported_case_equals_the_file_case(clamped_fin):
    imp = _imported(clamped_fin)
    ref, got = pl.modal_model(clamped_fin), pl.modal_model(imp)
    np.testing.assert_allclose(got.frequencies_hz, ref.frequencies_hz, rtol=1e-12)
    np.testing.assert_allclose(np.diag(got.C), np.diag(ref.C), rtol=1e-12)
    assert pl.box_mesh(imp) is imp.structure.boxes
    assert pl.structural_mesh(imp) is imp.structure.mesh
    fa, fb = pl.flutter(clamped_fin), pl.flutter(imp)
    assert any(r.flutter is not None for r in fa.results)
    for a, b in zip(fa.results, fb.results, strict=True):
        assert (a.flutter is None) == (b.flutter is None)
        if a.flutter is not None:
            assert b.flutter.speed == pytest.approx(a.flutter.speed, rel=1e-9)
            assert b.flutter.mode == a.flutter.mode
    assert imp.span == pytest.approx(clamped_fin.span, rel=1e-12)


def test_imported_model_identity_is_its_content(clamped_fin):
    a, b = _imported(clamped_fin), _imported(clamped_fin)
    assert a.structure is not b.structure and a.structure == b.structure
    assert hash(a) == hash(b) and a.fingerprint() == b.fingerprint()
    assert pl.modal_model(a) is pl.modal_model(b)                  # lru_cache on the case
    K2 = a.structure.K * 1.01
    c = dataclasses.replace(a, structure=dataclasses.replace(a.structure, K=K2))
    assert c.structure.digest != a.structure.digest and c.fingerprint() != a.fingerprint()
    # 1 % stiffer: every frequency sqrt(1.01) higher
    np.testing.assert_allclose(pl.modal_model(c).frequencies_hz,
                               pl.modal_model(a).frequencies_hz * np.sqrt(1.01), rtol=1e-9)
    # the declarative file case keeps its fingerprint key set (no "structure" key)
    assert clamped_fin.structure is None


def test_imported_damping_table_and_point_masses(clamped_fin):
    """Without a case damping the model's table applies (g -> zeta = g / 2 at each mode); a
    point mass of the case enters the imported mass matrix."""
    imp = _imported(clamped_fin, damping_g=((0.0, 0.02), (1e4, 0.02)))
    none = dataclasses.replace(imp, damping=dataclasses.replace(imp.damping,
                                                                modal_damping_ratio=None))
    m = pl.modal_model(none)
    w = 2 * np.pi * m.frequencies_hz
    np.testing.assert_allclose(np.diag(m.C), 2 * 0.01 * w * np.diag(m.M), rtol=1e-12)
    tip = tuple(float(v) for v in pl.structural_mesh(imp).nodes[-1])
    heavy = dataclasses.replace(none, point_masses=(PointMass(tip, 0.01),))
    assert np.all(pl.modal_model(heavy).frequencies_hz < m.frequencies_hz)


def test_imported_without_boxes_or_flight_says_what_is_missing(clamped_fin):
    imp = _imported(clamped_fin)
    bare = dataclasses.replace(imp, structure=dataclasses.replace(imp.structure, boxes=None))
    with pytest.raises(CaseError, match="no aerodynamic boxes"):
        pl.box_mesh(bare)
    with pytest.raises(CaseError, match="no flight conditions"):
        pl.flight_conditions(dataclasses.replace(imp, flight=None))
    with pytest.raises(CaseError, match="no aerodynamics"):
        pl.gaf_database(dataclasses.replace(imp, aero=None), progress=False)
    with pytest.raises(ValueError, match="ImportedModel.T must have"):
        ImportedModel(imp.structure.mesh, imp.structure.K, imp.structure.M,
                      imp.structure.T[:-3])
