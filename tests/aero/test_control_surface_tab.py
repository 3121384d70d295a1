"""A tab on a flap (issue 25: "several surfaces per case ... a tab on a flap"): two hinged
surfaces whose spans overlap, the tab aft of the flap's hinge, rotating about its own hinge
relative to the flap and with the flap about the flap's hinge
(asekit.aero.control_surface.nesting / hinged_mesh, asekit.aeroelastic.control_surface).

Physics asserted: the nested mesh and deflection modes equal those of the flap and of the tab
each built alone on the same box lines (to rounding); the tab's and the flap's (with its tab)
effectiveness on an aspect-ratio-20 wing tend to Glauert's thin-airfoil value
tau = 1 - (theta_h - sin theta_h) / pi (Glauert 1926, Sec. 7.5; Abbott & von Doenhoff 1959,
Eq. 8.14) for 10 % and 30 % chord; the hinge block of the mass matrix couples the flap and the
tab through the tab's mass, M_ft / I_t = (e c_t^2 / 2 + c_t^3 / 3) / (c_t^3 / 3) for a uniform
strip (c_t the tab's chord, e the distance between the hinges).
"""

import math
import tomllib

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import (
    ControlSurface,
    deflection_modes,
    glauert_flap_effectiveness,
    hinged_mesh,
    nesting,
    steady_control_derivatives,
)
from asekit.case import CaseError, case_from_dict
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

FLAP = ControlSurface("flap", 0.7, 0.7)
TAB = ControlSurface("tab", 0.9, 0.9)


def test_nested_mesh_and_modes_equal_the_surfaces_built_alone():
    """20 boxes per chord: 14 ahead of the flap's hinge, 4 between the hinges, 2 on the tab,
    every box 5 % of the chord, as the flap alone with 6 boxes aft and the tab alone with 2."""
    panel = TrapezoidSurface((0, 0), 1.0, (0.2, 3.0), 0.8, 20, 6)
    both = hinged_mesh(panel, [FLAP, TAB])
    flap = hinged_mesh(panel, FLAP, n_chord_aft=6)
    tab = hinged_mesh(panel, TAB, n_chord_aft=2)
    np.testing.assert_allclose(both.mesh.corners, flap.mesh.corners, atol=1e-12)
    np.testing.assert_allclose(both.mesh.corners, tab.mesh.corners, atol=1e-12)
    assert np.array_equal(both.on_surface[0], flap.on_surface[0])     # the flap carries its tab
    assert np.array_equal(both.on_surface[1], tab.on_surface[0])
    m2, mf, mt = deflection_modes(both), deflection_modes(flap), deflection_modes(tab)
    for a in ("h_cp", "dhdx_cp", "h_lp"):
        np.testing.assert_allclose(getattr(m2, a), np.hstack([getattr(mf, a), getattr(mt, a)]),
                                   atol=1e-12)
    assert both.surface_area(1) == pytest.approx(0.1 * 0.5 * (1.0 + 0.8) * 3.0, rel=1e-12)
    assert both.surface_area(0) == pytest.approx(0.3 * 0.5 * (1.0 + 0.8) * 3.0, rel=1e-12)


def test_part_span_tab_has_box_edges_on_its_hinge_and_side_edges():
    panel = TrapezoidSurface((0, 0), 1.2, (0.5, 3.0), 0.6, 12, 12)
    flap = ControlSurface("aileron", 0.7, 0.75, 0.3, 0.9)
    tab = ControlSurface("tab", 0.85, 0.9, 0.5, 0.8)
    assert nesting([flap, tab]) == (-1, 0) and nesting([tab, flap]) == (1, -1)
    hm = hinged_mesh(panel, [flap, tab])
    on = hm.on_surface[1]
    c = hm.mesh.corners[on]
    assert np.abs(hm.distance_aft(1, c[:, [0, 3]].reshape(-1, 3))).min() < 1e-12
    first = on & ~np.roll(on, 1)
    assert np.abs(hm.distance_aft(1, hm.mesh.corners[first][:, 0])).max() < 1e-12
    assert c[:, :, 1].min() == pytest.approx(1.5) and c[:, :, 1].max() == pytest.approx(2.4)
    assert np.all(hm.on_surface[0][on])                   # the tab's boxes are the flap's too
    ch = lambda eta: 1.2 + eta * (0.6 - 1.2)  # noqa: E731
    h = lambda eta: 0.85 + (eta - 0.5) / 0.3 * 0.05  # noqa: E731
    area = 0.5 * ((1 - h(0.5)) * ch(0.5) + (1 - h(0.8)) * ch(0.8)) * 0.9
    assert hm.surface_area(1) == pytest.approx(area, rel=1e-12)
    assert hm.mesh.area.sum() == pytest.approx(0.5 * (1.2 + 0.6) * 3.0, rel=1e-12)


@pytest.mark.parametrize("surfaces, match", [
    ([ControlSurface("a", 0.7, 0.7, 0.0, 0.6), ControlSurface("b", 0.9, 0.9, 0.4, 1.0)],
     "overlap in span"),                                   # not inside the flap's span
    ([ControlSurface("a", 0.8, 0.8), ControlSurface("b", 0.7, 0.7, 0.2, 0.5)],
     "overlap in span"),                                   # its hinge ahead of the flap's
    ([FLAP, TAB, ControlSurface("c", 0.95, 0.95, 0.4, 0.6)], "one level of nesting"),
])
def test_overlaps_that_are_not_a_tab_on_a_flap_are_refused(surfaces, match):
    with pytest.raises(ValueError, match=match):
        nesting(surfaces)


def test_a_tab_needs_two_boxes_aft_of_the_flap_hinge():
    with pytest.raises(ValueError, match="a tab needs at least 2 boxes"):
        hinged_mesh(TrapezoidSurface((0, 0), 1.0, (0, 2.0), 1.0, 4, 2), [FLAP, TAB])


def test_tab_and_flap_effectiveness_tend_to_glauert():
    """Aspect ratio 20 (10 m half span with the symmetric image, chord 1 m), M 0, full-span
    30 % flap carrying a full-span 10 % tab, 20 and 40 boxes per chord (20 strips): the
    vortex lattice converges like 1 / n_chord at a hinge, so the Richardson limit
    2 E(40) - E(20) is compared with Glauert's tau (0.6607 and 0.3958). Measured: flap
    0.6532 / 0.6591 -> 0.6650 (+0.6 %), tab 0.3767 / 0.3880 -> 0.3992 (+0.9 %); the same
    1 % as the lattice's lift-curve slope leaves on this wing (the finite-span effect on
    the ratio is below it: the existing AR-20 flap test, tests/aero/test_control_surface)."""
    eff = {}
    for nc in (20, 40):
        panel = TrapezoidSurface((0, 0), 1.0, (0, 10.0), 1.0, nc, 20)
        eff[nc] = steady_control_derivatives(hinged_mesh(panel, [FLAP, TAB]), 0.0,
                                             symmetric=True).effectiveness
    limit = 2 * eff[40] - eff[20]
    tau = np.array([glauert_flap_effectiveness(0.3), glauert_flap_effectiveness(0.1)])
    assert tau == pytest.approx([0.6607, 0.3958], abs=1e-4)
    np.testing.assert_allclose(limit, tau, rtol=0.015)
    assert np.all(np.abs(eff[40] - tau) < np.abs(eff[20] - tau))       # converging


@pytest.fixture(scope="module")
def plate():
    """The 0.3 m x 1.2 m, 2 mm aluminium plate clamped at the root, 20 x 16 elements, 4 modes,
    a 30 % aileron (hinge at 0.7 chord) on the outboard half with a 10 % tab on it."""
    from asekit.geometry import Material, Planform, Thickness
    from asekit.structure.assembly import assemble, clamped_edge
    from asekit.structure.mesh import panels_mesh
    from asekit.structure.modes import fixed_modal_model
    pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 20, [16])
    K, M = assemble(pm, Material(70e9, 0.3, 2700.0))
    model = fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=4)
    hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 20, 16),
                     [ControlSurface("aileron", 0.7, 0.7, 0.5, 1.0),
                      ControlSurface("tab", 0.9, 0.9, 0.5, 1.0)])
    return model, M, hm


def test_hinge_mass_block_couples_flap_and_tab_through_the_tab(plate):
    """Uniform strips: I_f = m' c_f^3 / 3, I_t = m' c_t^3 / 3, M_ft = m' (e c_t^2 / 2 +
    c_t^3 / 3) per span (c_f 0.09, c_t 0.03, e 0.06 m). The rigid kind lumps the side-edge
    node line onto the surface (+4.2 % on every entry on this mesh, as for one surface), so
    the ratios are compared: within 1 %. The unbalances likewise: S_f / S_t = c_f^2 / c_t^2."""
    from asekit.aeroelastic.control_surface import flap_modal_model
    model, M, hm = plate
    fm = flap_modal_model(model, M, hm, [0.5, 0.1])
    (i_f, p), (_, i_t) = fm.modal.M[-2:, -2:]
    assert fm.modal.M[-2, -1] == pytest.approx(fm.modal.M[-1, -2], rel=1e-12)
    cf, ct, e = 0.09, 0.03, 0.06
    assert p / i_t == pytest.approx((e * ct**2 / 2 + ct**3 / 3) / (ct**3 / 3), rel=0.01)
    assert i_f / i_t == pytest.approx(cf**3 / ct**3, rel=0.01)
    s_f, s_t = fm.static_unbalance
    assert s_f / s_t == pytest.approx(cf**2 / ct**2, rel=0.01)
    assert np.all(np.linalg.eigvalsh(fm.modal.M) > 0)


def test_a_mass_on_the_tab_moves_with_the_flap_too(plate):
    """A 10 g mass on the tab, 1 cm aft of its hinge (d_t = 0.01 m, d_f = 0.07 m): it adds
    m d_f^2, m d_f d_t and m d_t^2 to the hinge block and m d to both unbalances."""
    from asekit.aeroelastic.control_surface import BalanceMass, flap_modal_model
    model, M, hm = plate
    bare = flap_modal_model(model, M, hm, [0.5, 0.1])
    fm = flap_modal_model(model, M, hm, [0.5, 0.1], balance=[BalanceMass(1, 0.28, 1.0, 0.01)])
    d = np.array([0.07, 0.01])
    np.testing.assert_allclose(fm.modal.M[-2:, -2:] - bare.modal.M[-2:, -2:],
                               0.01 * np.outer(d, d), atol=1e-15)
    np.testing.assert_allclose(fm.static_unbalance - bare.static_unbalance, 0.01 * d,
                               atol=1e-15)
    np.testing.assert_allclose(fm.inertia - bare.inertia, 0.01 * d**2, atol=1e-15)


def _aileron_with_tab(kind="rigid"):
    d = tomllib.loads((CASES_DIR / "aileron_wing.toml").read_text())
    d["control_surface"][0].pop("actuator", None)
    d["control_surface"].append({"name": "tab", "panel": 0, "hinge_chord_fraction": [0.875, 0.875],
                                 "span_fraction": [0.75, 1.0], "kind": kind,
                                 "hinge_stiffness": 0.05, "hinge_damping": 0.0})
    return d


def test_case_with_a_tab_on_the_aileron():
    """The shipped aileron wing with a 12.5 % tab on the aileron's outer half (element and box
    lines at 7/8 chord and 12/16 span): the case reads, both surfaces get their hinge
    coordinate and effectiveness rows; the tab's (dCL/d delta) is below the aileron's (which
    carries the tab) and both lift."""
    case = case_from_dict(_aileron_with_tab())
    fm = P.control_surface_model(case)
    assert fm.names == ("aileron", "tab") and fm.modal.M.shape[0] == fm.n_wing + 2
    assert fm.modal.M[-2, -1] > 0                                # coupled through the tab
    rows = [r for r in P.control_surfaces(case) if r.mach == 0.0]
    by = {r.name: r for r in rows}
    assert 0 < by["tab"].dCL_ddelta_per_rad < by["aileron"].dCL_ddelta_per_rad
    assert by["tab"].Ch_delta < 0 and by["aileron"].Ch_delta < 0


def test_case_refuses_an_overlap_that_is_not_a_tab():
    d = _aileron_with_tab()
    d["control_surface"][1]["hinge_chord_fraction"] = [0.6, 0.6]
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.span_fraction .* overlaps "
                                        r"control_surface\[0\]"):
        case_from_dict(d)
    assert math.isfinite(P.control_surface_model(case_from_dict(_aileron_with_tab()))
                         .inertia[1])
