"""A geared tab in a case (issue 25, MSC Nastran's AELINK): ``control_surface[i].linked_to`` and
``gear_ratio`` (delta_tab = G delta_aileron) on the shipped aileron wing with a 12.5 % tab on
the aileron's outer half (as tests/aero/test_control_surface_tab.py), on a coarse copy (8 x 8
elements and boxes, Mach 0, 2-30 m/s).

Physics asserted: the linked model is the unlinked one constrained (link_surfaces, exact) and
the limit of the unlinked one with a penalty spring k_p (delta_t - G delta_f)^2 as k_p grows
(error ~ 1 / k_p); the geared aileron's dCL/d delta and C_h delta are its own plus G times the
tab's lift and the tab's load on the aileron's hinge (the lattice is linear), so a balance tab
(G < 0) reduces the aileron's hinge moment; its inertia is I_f + 2 G M_ft + G^2 I_t.
The thin-airfoil check of the tab's load is tests/aero/test_control_surface_aelink.py.
"""

import math
import tomllib

import numpy as np
import pytest
from scipy import linalg

from asekit.aero.control_surface import steady_control_derivatives
from asekit.aeroelastic.control_surface import link_surfaces
from asekit.case import CaseError, case_from_dict, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

G = -0.5


def _dict(linked=True):
    d = tomllib.loads((CASES_DIR / "aileron_wing.toml").read_text())
    d["control_surface"][0].pop("actuator", None)
    d["case"]["name"] += "_geared" if linked else "_tab_free"
    d["panel"][0].update(n_chord=8, n_span=8)
    d["aero"]["boxes"] = [{"n_chord": 8, "n_span": 8}]
    d["aero"]["machs"] = [0.0]
    d["flight"]["velocities"] = {"min": 2.0, "max": 30.0, "step": 2.0}
    tab = {"name": "tab", "panel": 0, "hinge_chord_fraction": [0.875, 0.875],
           "span_fraction": [0.75, 1.0]}
    tab.update({"linked_to": "aileron", "gear_ratio": G} if linked else {"hinge_stiffness": 0.0})
    d["control_surface"].append(tab)
    return d


@pytest.fixture(scope="module")
def cases():
    return case_from_dict(_dict()), case_from_dict(_dict(linked=False))


def _f(fm):
    return np.sqrt(np.abs(linalg.eigh(fm.modal.K, fm.modal.M, eigvals_only=True))) / (2 * math.pi)


def test_keys_are_read_and_checked():
    c = case_from_dict(_dict()).control_surfaces[1]
    assert (c.linked_to, c.gear_ratio, c.hinge_stiffness) == ("aileron", G, 0.0)
    d = _dict()
    d["control_surface"][1]["linked_to"] = "flap"
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.linked_to = 'flap' must name "
                                        r"another control surface"):
        case_from_dict(d)
    d = _dict()
    d["control_surface"][1].pop("gear_ratio")
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.gear_ratio is missing"):
        case_from_dict(d)
    d = _dict(linked=False)
    d["control_surface"][1]["gear_ratio"] = 0.5
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.gear_ratio needs "
                                        r"control_surface\[1\]\.linked_to"):
        case_from_dict(d)
    d = _dict()
    d["control_surface"][1]["gear_ratio"] = 20.0
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.gear_ratio"):
        case_from_dict(d)
    d = _dict()
    d["control_surface"][0]["actuator"] = {"speed": 8.0}
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.actuator cannot be combined "
                                        r"with linked surfaces"):
        case_from_dict(d)


def test_the_linked_model_is_the_constrained_one_and_the_penalty_limit(cases):
    linked, free = cases
    fl, ff = P.control_surface_model(linked), P.control_surface_model(free)
    assert fl.names == ("aileron",) and ff.names == ("aileron", "tab")
    ref = link_surfaces(ff, [(1, 0, G)])
    for a, b in ((fl.modal.M, ref.modal.M), (fl.modal.K, ref.modal.K),
                 (fl.box_modes.h_cp, ref.box_modes.h_cp)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-14 * np.abs(b).max())
    hb = ff.hinge_mass_matrix
    assert fl.inertia[0] == pytest.approx(hb[0, 0] + 2 * G * hb[0, 1] + G * G * hb[1, 1],
                                          rel=1e-12)
    assert fl.static_unbalance[0] == pytest.approx(
        ff.static_unbalance[0] + G * ff.static_unbalance[1], rel=1e-12)
    n = fl.modal.M.shape[0]
    target = _f(fl)
    v = np.zeros(ff.modal.M.shape[0])
    v[-2:] = [-G, 1.0]                                   # delta_t - G delta_f
    err = []
    for k_p in (1e2, 1e4, 1e6):
        K = np.asarray(ff.modal.K) + k_p * np.outer(v, v)
        f = np.sqrt(linalg.eigh(K, ff.modal.M, eigvals_only=True)) / (2 * math.pi)
        err.append(np.abs(f[:n] / target - 1).max())
    assert err[2] < 1e-5 and err[1] / err[2] > 50        # ~ 1 / k_p: measured 5.5e-5, 5.5e-7,
    assert err[0] / err[1] > 50                          # 7.8e-9 (round-off near the last)


def test_geared_rows_are_the_aileron_plus_gear_times_the_tab(cases):
    """``analyse``: one row for the aileron (the tab has none of its own), its dCL/d delta
    and C_h delta the aileron's own plus G times the tab's lift and load on the aileron's
    hinge: the balance tab reduces the hinge moment; the hinge-load rows and the 1 x 1
    hinge_mass_matrix likewise; the flutter sweep runs with the geared aileron."""
    linked, free = cases
    out = report.summary(report.run_analysis(linked, progress=False))
    (row,) = out["control_surfaces"]
    hm = P.control_surface_mesh(free)
    d = steady_control_derivatives(hm, 0.0, symmetric=True)
    from asekit.aero.control_surface import deflection_modes, hinge_moments
    from asekit.aero.vlm import steady_pressure
    cp = steady_pressure(hm.mesh, 0.0, deflection_modes(hm).normalwash(0.0, 1.0).real, True)
    h_ft = hinge_moments(hm, cp)[0, 1] / (hm.surface_area(0) * hm.mean_chord(0))
    assert row["name"] == "aileron"
    assert row["dCL_ddelta_per_rad"] == pytest.approx(d.dCL_ddelta[0] + G * d.dCL_ddelta[1],
                                                      rel=1e-10)
    assert row["Ch_delta"] == pytest.approx(d.Ch_delta[0] + G * h_ft, rel=1e-10)
    assert d.Ch_delta[0] < row["Ch_delta"] < 0.0 and h_ft < 0.0
    assert row["Ch_alpha"] == pytest.approx(d.Ch_alpha[0], rel=1e-12)
    (h,) = out["control_surface_hinge_moments"]
    q, sc = h["dynamic_pressure_pa"], hm.surface_area(0) * hm.mean_chord(0)
    assert h["hinge_moment_per_delta_Nm_per_rad"] == pytest.approx(q * sc * row["Ch_delta"],
                                                                   rel=1e-12)
    assert np.shape(out["hinge_mass_matrix"]) == (1, 1)
    assert out["hinge_mass_matrix"][0][0] == row["hinge_inertia_kgm2"]
    (fl,) = out["control_surface_flutter"]
    assert fl["speed_ms"] is not None and not fl["unstable_at_first_point"]
