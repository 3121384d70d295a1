"""Geometry of the reference fin's case and the cache's file format. (The thesis table and the
reproduce command's plumbing: tests/reproduction/test_thesis_table.py.)"""

import math

import numpy as np
import pytest

from asekit.case import pipeline
from asekit.geometry import LinearThickness, Material, Planform
from asekit.util.cache import CacheError, load_npz, save_npz


def test_reference_fin_geometry_matches_fin_md(fin_case):
    # shared/reference/fin.md: area 0.01755 m^2, MAC 121.3 mm, LE sweep 27.47 deg, taper 0.5
    fin = fin_case
    p = fin.panels[0].planform
    assert p.area == pytest.approx(0.01755, rel=1e-9)
    assert p.mean_aerodynamic_chord == pytest.approx(0.1213, abs=1e-4)
    assert math.degrees(p.leading_edge_sweep) == pytest.approx(27.47, abs=0.01)
    assert p.taper == pytest.approx(0.5)
    assert fin.thickness.at(0.5) == pytest.approx(0.003)
    # k_max = 2 pi f_max b / U_min with b = 0.078 m: the highest of the automatic k
    assert pipeline.reduced_frequencies(fin)[-1] == pytest.approx(2 * math.pi * 1000 * 0.078 / 180)


def test_planform_point_and_contains(fin_case):
    p = fin_case.panels[0].planform
    corners = p.point(np.array([0, 1, 1, 0]), np.array([0, 0, 1, 1]))
    np.testing.assert_allclose(corners, p.corners)
    assert p.contains(np.array([[0.1, 0.05], [0.01, 0.149], [0.2, 0.1]])).tolist() == [True, False, False]


@pytest.mark.parametrize("kwargs, word", [
    (dict(root_le=(0, 0), root_chord=-1, tip_le=(0, 1), tip_chord=1), "root_chord"),
    (dict(root_le=(0, 0), root_chord=1, tip_le=(0, 0), tip_chord=1), "span"),
])
def test_planform_bad_input(kwargs, word):
    with pytest.raises(ValueError, match=word):
        Planform(**kwargs)


def test_material_and_thickness_bad_input():
    with pytest.raises(ValueError, match="poisson_ratio"):
        Material(70e9, 0.5, 2700)
    with pytest.raises(ValueError, match="thickness"):
        LinearThickness(0.004, 0.0)


def test_cache_roundtrip_and_corruption(tmp_path):
    path = tmp_path / "x.npz"
    a = {"q": np.arange(6.0).reshape(2, 3) + 1j}
    save_npz(path, a, {"mach": 0.5})
    arrays, meta = load_npz(path)
    np.testing.assert_array_equal(arrays["q"], a["q"])
    assert meta["mach"] == 0.5
    # a file whose arrays were altered fails its checksum
    with np.load(path) as d:
        payload = {k: d[k] for k in d.files}
    payload["q"] = payload["q"] * 2
    np.savez(path, **payload)
    with pytest.raises(CacheError, match="checksum"):
        load_npz(path)
    with pytest.raises(CacheError, match="does not exist"):
        load_npz(tmp_path / "missing.npz")
