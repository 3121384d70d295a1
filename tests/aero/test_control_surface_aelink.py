"""Linked control surfaces (issue 25, MSC Nastran's AELINK): a geared tab, delta_tab =
G delta_flap (asekit.aero.control_surface.gearing_matrix, steady_control_derivatives(links=),
thin_airfoil_hinge_moment; asekit.aeroelastic.control_surface.link_surfaces).

References: Glauert's thin-airfoil flap effectiveness tau = 1 - (theta_h - sin theta_h) / pi
(Glauert 1926, Sec. 7.5; 0.6607 for 30 %, 0.3958 for 10 % chord), so a geared tab's
flap-with-tab effectiveness is tau_f + G tau_t in 2-D; the hinge moments of thin-airfoil
theory: the flap's own C_h delta from Theodorsen's T functions (NACA Report 496, 1935:
-2 (T5 - T4 T10 + T12 T10) / (pi (1 - c)^2)) and the tab's load on the flap's hinge, C_h,ft, by
quadrature of Glauert's closed-form load (thin_airfoil_hinge_moment); on the aspect-ratio-20
wing both corrected to 3-D by lifting line as tests/aero/test_control_surface.py does. The
classic check: the geared flap's hinge moment is its own plus G times the tab's load on its
hinge, so a balance tab (G < 0) reduces it.
"""

import math

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import (
    ControlSurface,
    gearing_matrix,
    glauert_flap_effectiveness,
    hinged_mesh,
    steady_control_derivatives,
    thin_airfoil_hinge_moment,
)
from asekit.aeroelastic.typical_section import theodorsen_t

FLAP = ControlSurface("flap", 0.7, 0.7)
TAB = ControlSurface("tab", 0.9, 0.9)
G = -0.5                                      # a balance tab: half the flap angle, opposite


def _theodorsen(c_hinge):
    """2-D C_h alpha and C_h delta (per rad, H / (q c_f^2)) of a flap hinged at x = c_hinge
    b behind mid-chord (NACA 496's steady terms; as tests/aero/test_control_surface.py)."""
    T = theodorsen_t(0.0, c_hinge)
    e2 = (1.0 - c_hinge) ** 2
    return -2.0 * T[12] / e2, -2.0 * (T[5] - T[4] * T[10] + T[12] * T[10]) / (math.pi * e2)


@pytest.fixture(scope="module")
def ar20():
    """Aspect ratio 20 (chord 1 m, half span 10 m with its image), M 0, a full-span 30 % flap
    carrying a full-span 10 % tab, 20 boxes per chord x 20 strips."""
    hm = hinged_mesh(TrapezoidSurface((0, 0), 1.0, (0, 10.0), 1.0, 20, 20), [FLAP, TAB])
    return (steady_control_derivatives(hm, 0.0, symmetric=True),
            steady_control_derivatives(hm, 0.0, symmetric=True, links=[(1, 0, G)]))


def test_gearing_matrix_and_its_refusals():
    T, free = gearing_matrix(3, [(2, 0, 0.5)])
    assert T.tolist() == [[1.0, 0.0], [0.0, 1.0], [0.5, 0.0]] and free.tolist() == [0, 1]
    T, free = gearing_matrix(2, ())
    assert np.array_equal(T, np.eye(2))
    for bad in ([(1, 1, 1.0)], [(2, 0, 1.0)], [(1, 0, 1.0), (0, 1, 1.0)],
                [(1, 0, 1.0), (1, 0, 2.0)], [(1, 0, math.nan)]):
        with pytest.raises(ValueError, match="links must be"):
            gearing_matrix(2, bad)


def test_thin_airfoil_hinge_moment_is_theodorsens_for_the_flap_itself():
    """The closed-form load integrated (thin_airfoil_hinge_moment with equal fractions) is
    Theodorsen's steady C_h delta to the quadrature's accuracy: -0.944 (25 %), 30 % and 10 %;
    the tab's load on the flap's hinge converges as the rule is refined."""
    for e in (0.25, 0.3, 0.1):
        assert thin_airfoil_hinge_moment(e, e) == pytest.approx(_theodorsen(1 - 2 * e)[1],
                                                                rel=1e-8)
    a, b = thin_airfoil_hinge_moment(0.3, 0.1, 500), thin_airfoil_hinge_moment(0.3, 0.1, 1000)
    assert a == pytest.approx(b, rel=1e-5) and -1.5 < b < -1.3
    with pytest.raises(ValueError, match="hinge_chord_fraction"):
        thin_airfoil_hinge_moment(1.5, 0.1)


def test_geared_effectiveness_is_the_flaps_plus_gear_times_the_tabs(ar20):
    """The lattice is linear: the geared flap's dCL/d delta is CL_f + G CL_t to round-off;
    against 2-D Glauert tau_f + G tau_t = 0.4628 it is within 2 % on these 20 boxes per chord
    (measured +0.4 %; the flap's and the tab's own errors, -1.1 % and -4.8 % here, partly
    cancel with G < 0; the tab test's Richardson limit, tests/aero/test_control_surface_tab.py,
    checks each)."""
    d, g = ar20
    assert g.dCL_ddelta.shape == (1,) and g.dCL_dalpha == d.dCL_dalpha
    assert g.dCL_ddelta[0] == pytest.approx(d.dCL_ddelta[0] + G * d.dCL_ddelta[1], rel=1e-10)
    tau = glauert_flap_effectiveness(0.3) + G * glauert_flap_effectiveness(0.1)
    assert tau == pytest.approx(0.4628, abs=1e-4)
    assert g.effectiveness[0] == pytest.approx(tau, rel=0.02)
    assert g.Ch_alpha[0] == d.Ch_alpha[0]                       # the flap's, unchanged


def test_a_balance_tab_reduces_the_flap_hinge_moment_by_the_tabs_contribution(ar20):
    """C_h,f(geared) - C_h,f = G C_h,ft: the tab's load on the flap's hinge, the lattice's
    within 3 % of thin-airfoil theory corrected to 3-D by lifting line (C_h,ft,3D = C_h,ft,2D
    - C_h alpha,2D (tau_t - CL_t / 2 pi); 2-D -1.419 per rad; measured -1.0 %, -0.7 % with 40
    boxes per chord), and the flap's own C_h delta within 5 % likewise (measured +2.9 %). The
    balance tab (G = -0.5) cuts the flap's hinge moment by ~70 % (measured -0.936 -> -0.254)."""
    d, g = ar20
    ch_ft = (g.Ch_delta[0] - d.Ch_delta[0]) / G
    ch_a2, _ = _theodorsen(0.4)                                  # hinge at 70 % of the chord
    a0 = 2.0 * math.pi
    ft3 = thin_airfoil_hinge_moment(0.3, 0.1) - ch_a2 * (glauert_flap_effectiveness(0.1)
                                                         - d.dCL_ddelta[1] / a0)
    ff3 = thin_airfoil_hinge_moment(0.3, 0.3) - ch_a2 * (glauert_flap_effectiveness(0.3)
                                                         - d.dCL_ddelta[0] / a0)
    assert thin_airfoil_hinge_moment(0.3, 0.1) == pytest.approx(-1.419, abs=1e-3)
    assert ch_ft == pytest.approx(ft3, rel=0.03)
    assert d.Ch_delta[0] == pytest.approx(ff3, rel=0.05)
    assert d.Ch_delta[0] < g.Ch_delta[0] < 0.0                  # reduced, not reversed
    assert abs(g.Ch_delta[0]) < 0.35 * abs(d.Ch_delta[0])
