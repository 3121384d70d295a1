"""Two elastic control surfaces in one case (issue 25): data/cases/aileron_wing_two_elastic.toml,
the elastic aileron wing (aileron_wing_elastic.toml) with its aileron split into an inboard
and an outboard half, each released along the same hinge line on its own spring
(asekit.structure.hinge.split_at_hinges / release_hinges,
asekit.aeroelastic.control_surface.elastic_flap_modal_model with two hinge coordinates).

Reference numbers: each half is a uniform 2 mm aluminium plate strip (density 2700 kg/m^3) of
chord c_f = 0.075 m aft of the hinge and span b = 0.3 m, so m = rho h b c_f = 0.1215 kg,
S = m c_f / 2 and I_h = m (c_f^2 / 3 + h^2 / 12) about the hinge (exact for the consistent
mass of a rigid rotation); on 0.25 N m/rad each (the one aileron's 0.5 N m/rad shared by hinge
length) the uncoupled hinge frequency sqrt(k_h / I_h) / 2 pi is the one aileron's. The vortex
lattice is linear: the two halves deflected together are the one aileron deflected, so their
rigid dCL/d delta add up to the one aileron's on the same boxes.

The analysis runs on a coarse copy (8 x 8 elements and boxes, Mach 0, 2-30 m/s; the hinge and
the halves' edges still on element lines) with the actuator on the outboard aileron, through
the Python entry of ``asekit analyse`` (report.run_analysis + report.summary), in ~6 s.
"""

import math
import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

TWO = CASES_DIR / "aileron_wing_two_elastic.toml"
ONE = CASES_DIR / "aileron_wing_elastic.toml"
RHO, H, C_F, B = 2700.0, 0.002, 0.075, 0.3
MASS = RHO * H * B * C_F


def _coarse(d):
    d["case"]["name"] += "_coarse"
    d["panel"][0].update(n_chord=8, n_span=8)
    d["aero"]["boxes"] = [{"n_chord": 8, "n_span": 8}]
    d["aero"]["machs"] = [0.0]
    d["flight"]["velocities"] = {"min": 2.0, "max": 30.0, "step": 2.0}
    return d


@pytest.fixture(scope="module")
def coarse():
    d = _coarse(tomllib.loads(TWO.read_text()))
    d["control_surface"][1]["actuator"] = {"speed": 8.0, "mach": 0.0, "altitude": 0.0,
                                           "step_deg": 2.0}
    return case_from_dict(d)


@pytest.fixture(scope="module")
def summary(coarse):
    return report.summary(report.run_analysis(coarse, progress=False))


def test_the_shipped_case_is_the_one_aileron_split_in_two():
    two, one = tomllib.loads(TWO.read_text()), tomllib.loads(ONE.read_text())
    a, b = two.pop("control_surface")
    (c,) = one.pop("control_surface")
    c.pop("actuator")
    for d in (one, two):
        d.pop("case")
    assert one == two                              # the same wing, aerodynamics and flight
    assert (a["span_fraction"][0], a["span_fraction"][1], b["span_fraction"][1]) == \
        (c["span_fraction"][0], b["span_fraction"][0], c["span_fraction"][1])
    for s in (a, b):                               # the same hinge stiffness per length
        length = s["span_fraction"][1] - s["span_fraction"][0]
        assert s["hinge_stiffness"] / length == pytest.approx(
            c["hinge_stiffness"] / (c["span_fraction"][1] - c["span_fraction"][0]))
    case = case_from_dict(dict(two, case={"name": "x"}, control_surface=[a, b]))
    assert [s.kind for s in case.control_surfaces] == ["elastic", "elastic"]


def test_each_surface_has_its_strip_inertia_and_no_inertial_coupling(coarse):
    """The two hinge coordinates: each half's exact strip integrals, congruent halves equal,
    mass-orthogonal to each other (they share no element and the clamped wing stays still
    under a half's rigid rotation), coupled to the wing's modes through the mass."""
    fm = P.control_surface_model(coarse)
    assert fm.names == ("inboard", "outboard")
    np.testing.assert_allclose(fm.inertia, MASS * (C_F ** 2 / 3 + H ** 2 / 12), rtol=1e-7)
    np.testing.assert_allclose(fm.static_unbalance, MASS * C_F / 2, rtol=1e-7)
    hm = fm.hinge_mass_matrix
    np.testing.assert_allclose(np.diag(hm), fm.inertia)
    assert abs(hm[0, 1]) < 1e-7 * fm.inertia[0]          # the solve's round-off (1e-7 as I_h)
    np.testing.assert_allclose(fm.hinge_frequency_hz,
                               np.sqrt(0.25 / fm.inertia) / (2 * math.pi), rtol=1e-12)
    np.testing.assert_allclose(np.diag(fm.modal.K)[fm.n_wing:], 0.25, rtol=1e-6)
    coupling = np.abs(np.asarray(fm.modal.M)[:fm.n_wing, fm.n_wing:]).max(axis=0)
    assert np.all(coupling > 1e-3 * np.sqrt(fm.inertia))


def test_mass_balance_goes_to_its_own_surface():
    """0.1 kg on a rigid arm 3 cm ahead of the outboard aileron's hinge (d = -0.03 m): the
    outboard S and I_h gain exactly m d and m d^2, the inboard's stay the strip's, and the two
    hinge coordinates stay mass-orthogonal."""
    m_b, d_b = 0.1, -0.03
    d = _coarse(tomllib.loads(TWO.read_text()))
    d["control_surface"][1]["mass_balance"] = [{"position": [0.195, 1.05], "mass": m_b}]
    fm = P.control_surface_model(case_from_dict(d))
    i_strip, s_strip = MASS * (C_F ** 2 / 3 + H ** 2 / 12), MASS * C_F / 2
    np.testing.assert_allclose(fm.inertia, [i_strip, i_strip + m_b * d_b ** 2], rtol=1e-7)
    np.testing.assert_allclose(fm.static_unbalance, [s_strip, s_strip + m_b * d_b], rtol=0,
                               atol=1e-7 * s_strip)     # the strip's 1e-7, not the sum's
    assert abs(fm.hinge_mass_matrix[0, 1]) < 1e-7 * fm.inertia[0]


def test_analyse_gives_rows_per_surface_and_names_the_flap_mode(coarse, summary):
    """``analyse``'s JSON: one row per surface (and Mach) with its kind, its inertia and a
    reversal speed; the two halves' rigid dCL/d delta add up to the one aileron's on the same
    boxes (linear lattice, 1e-9); the hinge-free flutter names the half whose mode goes
    unstable and lies below the locked wing's (measured 10.0 against 24.1 m/s, the one
    elastic aileron's 11.5 on the fine mesh); the actuator loops on the outboard half run."""
    from asekit.aero.control_surface import steady_control_derivatives

    rows = summary["control_surfaces"]
    assert [(r["name"], r["kind"], r["mach"]) for r in rows] == [("inboard", "elastic", 0.0),
                                                                 ("outboard", "elastic", 0.0)]
    for r in rows:
        assert r["hinge_inertia_kgm2"] == pytest.approx(MASS * (C_F ** 2 / 3 + H ** 2 / 12),
                                                        rel=1e-7)
        assert r["reversal_speed_ms"] is not None
    one = _coarse(tomllib.loads(ONE.read_text()))
    one["control_surface"][0].pop("actuator")
    d1 = steady_control_derivatives(P.control_surface_mesh(case_from_dict(one)), 0.0,
                                    symmetric=True)
    assert rows[0]["dCL_ddelta_per_rad"] + rows[1]["dCL_ddelta_per_rad"] == pytest.approx(
        float(d1.dCL_ddelta[0]), rel=1e-9)
    (fl,) = summary["control_surface_flutter"]
    (locked,) = summary["flutter"]
    assert fl["mode"] in ("inboard", "outboard") and not fl["unstable_at_first_point"]
    assert fl["speed_ms"] < 0.6 * locked["speed_ms"]
    ase = summary["control_surface_ase"]
    assert [(r["name"], r["topology"]) for r in ase] == [("outboard", "AEM1"),
                                                         ("outboard", "AEM2")]
    assert all(r["stable"] for r in ase)


def test_a_surface_on_the_support_is_refused():
    """(Rigid and elastic surfaces mixed are accepted: tests/case/test_mixed_surfaces.py.)"""
    d = _coarse(tomllib.loads(TWO.read_text()))
    d["control_surface"][0]["span_fraction"] = [0.0, 0.5]
    d["control_surface"][1]["span_fraction"] = [0.5, 1.0]
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.span_fraction \[0\.0, 0\.5\]: "
                                        r"the elastic surface reaches the support"):
        P.control_surface_model(case_from_dict(d))
    d = _coarse(tomllib.loads(TWO.read_text()))
    d["control_surface"][1]["hinge_chord_fraction"] = [0.7, 0.7]     # between node lines
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.hinge_chord_fraction / "
                                        r"span_fraction: .*'outboard'.*element lines"):
        P.control_surface_model(case_from_dict(d))
