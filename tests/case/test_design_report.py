"""The report of ``asekit optimise --report`` (asekit.case.design_report, issue 28) on a small
fin (4 x 4 plate elements, 3 modes, 6 x 6 boxes; as tests/case/test_design.py)."""

import copy
import json
import tomllib

import numpy as np
import pytest

from asekit.case import case_from_dict
from asekit.case import pipeline as P
from asekit.case.design import with_values
from asekit.case.design_report import element_thickness, write_design_report
from asekit.util.paths import FIN_FILE

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


def _small_case():
    raw = tomllib.loads(FIN_FILE.read_text())
    raw["panel"][0].update(n_chord=4, n_span=4)
    raw["modes"] = {"count": 3, "keep_rigid": True}
    raw["aero"].update(machs=[0.6], boxes=[{"n_chord": 6, "n_span": 6}],
                       reduced_frequencies=[0.001, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8])
    raw["flight"].update(altitudes=[0.0], velocities={"min": 120.0, "max": 420.0, "step": 20.0})
    raw.pop("actuator")
    return case_from_dict(copy.deepcopy(raw), "small fin")


def test_element_thickness_follows_the_linear_law():
    """The fin's 4 -> 2 mm spanwise law (data/cases/nalci2013_fin.toml): every centroid's
    thickness is the law at its y, so the values lie strictly between the tip and root."""
    case = _small_case()
    h = element_thickness(case)
    mesh = P.structural_mesh(case)
    y = mesh.element_centroids()[:, 1]
    assert h.shape == (mesh.n_elements,)
    np.testing.assert_allclose(h, mesh.thickness_at(y), rtol=1e-12)
    assert 0.002 < h.min() < h.max() < 0.004


def test_report_writes_the_page_figures_and_json(tmp_path):
    base = _small_case()
    opt = with_values(base, ("thickness.tip",), np.array([0.0015]))
    history = [{"iteration": 0, "mass_kg": 0.05, "min_margin_pct": 2.0},
               {"iteration": 1, "mass_kg": 0.045, "min_margin_pct": 15.0}]
    doc = {"design": {"baseline": {"mass_kg": 0.05}, "optimised": {"mass_kg": 0.045}}}
    page = write_design_report(tmp_path / "rep", base, opt, P.flutter(base), P.flutter(opt),
                               history, doc)
    names = sorted(p.name for p in (tmp_path / "rep").iterdir())
    assert names == ["history.png", "index.html", "summary.json", "thickness.png", "vg.png"]
    text = page.read_text()
    for f in ("thickness.png", "vg.png", "history.png", "summary.json"):
        assert f'"{f}"' in text
    assert json.loads((tmp_path / "rep" / "summary.json").read_text()) == doc
    # the V-g caption names the flutter speeds the pipeline found, before and after
    fb = min(r.flutter.speed for r in P.flutter(base).results if r.flutter is not None)
    assert f"{fb:.1f} m/s before" in text
