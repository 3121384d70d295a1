"""Hinged control surfaces (asekit.aero.control_surface): the hinge-aligned mesh, the deflection
normalwash and hinge moments against thin-airfoil theory (Glauert) and Theodorsen's
oscillating-flap theory (NACA Report 496)."""

import math

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import (
    ControlSurface,
    deflection_modes,
    glauert_flap_effectiveness,
    hinge_moments,
    hinged_mesh,
    steady_control_derivatives,
)
from asekit.aero.dlm import pressure_jump
from asekit.aero.spline import analytic_modes
from asekit.aeroelastic.typical_section import (
    TypicalSection,
    section_matrices,
    theodorsen_function,
    theodorsen_t,
)


def test_box_edges_fall_on_hinge_line_and_side_edges():
    panel = TrapezoidSurface((0, 0), 1.2, (0.5, 3.0), 0.6, 10, 12)
    cs = ControlSurface("aileron", 0.7, 0.8, 0.4, 0.9)
    hm = hinged_mesh(panel, cs)
    c = hm.mesh.corners
    on = hm.on_surface[0]
    # leading corners (1, 4) of the first surface box of each strip lie on the hinge line
    d_le = np.concatenate([hm.distance_aft(0, c[on][:, 0]), hm.distance_aft(0, c[on][:, 3])])
    first = on & ~np.roll(on, 1)
    assert np.abs(hm.distance_aft(0, c[first][:, 0])).max() < 1e-12
    assert np.abs(hm.distance_aft(0, c[first][:, 3])).max() < 1e-12
    assert d_le.min() > -1e-12                            # no surface box ahead of the hinge
    # side edges: the surface spans exactly y = 0.4 * 3 .. 0.9 * 3
    y = c[on][:, :, 1]
    assert y.min() == pytest.approx(1.2) and y.max() == pytest.approx(2.7)
    # the surface covers the panel aft of the hinge: its area is the trapezoid's
    # (chord aft of hinge at the side edges: (1 - h) x local chord)
    ch = lambda eta: 1.2 + eta * (0.6 - 1.2)  # noqa: E731
    area = 0.5 * ((1 - 0.7) * ch(0.4) + (1 - 0.8) * ch(0.9)) * 1.5
    assert hm.surface_area(0) == pytest.approx(area, rel=1e-12)
    # the whole mesh still covers the panel
    assert hm.mesh.area.sum() == pytest.approx(0.5 * (1.2 + 0.6) * 3.0, rel=1e-12)


def test_deflection_is_a_pitch_about_the_hinge_on_the_surface():
    """On the flap boxes the deflection mode equals the pitch mode about x_h of
    asekit.aero.spline.analytic_modes (h = -(x - x_h), dh/dx = -1); zero elsewhere."""
    panel = TrapezoidSurface((0, 0), 1.0, (0, 2.0), 1.0, 8, 4)
    hm = hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75, 0.25, 0.75))
    m = deflection_modes(hm)
    pitch = analytic_modes(hm.mesh, [lambda x, y: (-(x - 0.75), -1.0 + 0 * x)])
    on = hm.on_surface[0]
    for a, b in ((m.h_cp, pitch.h_cp), (m.dhdx_cp, pitch.dhdx_cp), (m.h_lp, pitch.h_lp)):
        assert np.allclose(a[on], b[on], atol=1e-14)
        assert np.all(a[~on] == 0.0)
    k, b_ref = 0.4, 0.5
    w = m.normalwash(k, b_ref)[on, 0]
    assert np.allclose(w, -1.0 - 1j * k * (hm.mesh.control_point[on, 0] - 0.75) / b_ref)


def test_swept_hinge_slope_is_cos_sweep():
    panel = TrapezoidSurface((0, 0), 1.0, (0.5, 2.0), 1.0, 8, 4)
    hm = hinged_mesh(panel, ControlSurface("f", 0.7, 0.7))
    m = deflection_modes(hm)
    sweep = math.atan2(0.5, 2.0)
    assert np.allclose(m.dhdx_cp[hm.on_surface[0], 0], -math.cos(sweep))


def test_several_surfaces_and_bad_input():
    panel = TrapezoidSurface((0, 0), 1.0, (0, 4.0), 1.0, 8, 16)
    hm = hinged_mesh(panel, [ControlSurface("in", 0.7, 0.7, 0.1, 0.5),
                             ControlSurface("out", 0.8, 0.8, 0.5, 1.0)])
    assert hm.on_surface.shape == (2, hm.mesh.n)
    assert not np.any(hm.on_surface[0] & hm.on_surface[1])
    assert hm.surface_span(0) == pytest.approx(1.6) and hm.surface_span(1) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="overlap"):
        hinged_mesh(panel, [ControlSurface("a", 0.7, 0.7, 0.1, 0.6),
                            ControlSurface("b", 0.8, 0.8, 0.5, 1.0)])
    with pytest.raises(ValueError, match="hinge_inboard"):
        ControlSurface("a", 1.0, 0.7)
    with pytest.raises(ValueError, match="span_end"):
        ControlSurface("a", 0.7, 0.7, 0.5, 0.4)
    with pytest.raises(ValueError, match="n_chord_aft"):
        hinged_mesh(panel, ControlSurface("a", 0.7, 0.7), n_chord_aft=8)
    with pytest.raises(ValueError, match="delta_cp"):
        hinge_moments(hm, np.zeros(3))


@pytest.fixture(scope="module")
def ar20_flap():
    """A rectangular wing of aspect ratio 20 (chord 1 m, half span 10 m, symmetric image),
    a full-span 25 %-chord flap, 24 x 40 boxes per half (18 ahead of the hinge, 6 aft)."""
    panel = TrapezoidSurface((0, 0), 1.0, (0, 10.0), 1.0, 24, 40)
    return steady_control_derivatives(hinged_mesh(panel, ControlSurface("flap", .75, .75)),
                                      0.0, symmetric=True)


def test_glauert_flap_effectiveness(ar20_flap):
    """Glauert's thin-airfoil flap effectiveness tau = 1 - (theta_h - sin theta_h) / pi,
    cos theta_h = 1 - 2 x_h / c (Glauert 1926, Sec. 7.5; Abbott & von Doenhoff 1959,
    Eq. 8.14): 0.609 for a 25 %-chord flap. The AR 20 wing's (dCL/d delta) / (dCL/d alpha)
    within 2 % (measured 0.6025, -1.1 %: the vortex lattice converges slowly in the chordwise
    boxes at the hinge, 0.597 with 16 and 0.605 with 32 boxes per chord)."""
    tau = glauert_flap_effectiveness(0.25)
    assert tau == pytest.approx(0.609, abs=5e-4)
    assert ar20_flap.effectiveness[0] == pytest.approx(tau, rel=0.02)


def _thin_airfoil_hinge_coefficients(c_hinge: float):
    """2-D thin-airfoil C_h alpha and C_h delta (per rad, C_h = H / (q c_f^2)) from the steady
    terms of Theodorsen's flap theory (NACA Report 496, 1935): H = -rho U^2 b^2 T12 alpha for
    alpha and -rho U^2 b^2 (T5 - T4 T10 + T12 T10) / pi delta for the flap, c_f = b (1 - c)."""
    T = theodorsen_t(0.0, c_hinge)
    e2 = (1.0 - c_hinge) ** 2
    return -2.0 * T[12] / e2, -2.0 * (T[5] - T[4] * T[10] + T[12] * T[10]) / (math.pi * e2)


def test_thin_airfoil_hinge_alpha_by_quadrature():
    """Cross-check of C_h alpha from the T functions: the exact flat-plate loading
    DeltaCp = 4 alpha sqrt((c - x) / x) (thin-airfoil theory, Abbott & von Doenhoff Eq. 4.28)
    integrated times the distance aft of the hinge."""
    from scipy.integrate import quad
    xh = 0.75
    h, _ = quad(lambda x: -(x - xh) * 4.0 * math.sqrt((1.0 - x) / x), xh, 1.0)
    ch_alpha, _ = _thin_airfoil_hinge_coefficients(0.5)
    assert h / 0.25 ** 2 == pytest.approx(ch_alpha, rel=1e-8)


def test_hinge_moment_coefficients_thin_airfoil(ar20_flap):
    """C_h alpha and C_h delta of the AR 20 wing within 5 % of thin-airfoil theory (2-D values
    -0.565 and -0.944 per rad for a 25 %-chord flap: _thin_airfoil_hinge_coefficients),
    corrected to 3-D by lifting-line's induced angle (Prandtl): the sections see
    alpha_e = alpha - alpha_i with alpha_i = alpha + tau delta - CL / a0, a0 = 2 pi, so
    C_h alpha,3D = C_h alpha,2D CL_alpha / a0 and
    C_h delta,3D = C_h delta,2D - C_h alpha,2D (tau - CL_delta / a0). Measured -2.7 % and
    +2.8 % (24 boxes per chord)."""
    ch_a2, ch_d2 = _thin_airfoil_hinge_coefficients(0.5)
    a0 = 2.0 * math.pi
    tau = glauert_flap_effectiveness(0.25)
    ch_a3 = ch_a2 * ar20_flap.dCL_dalpha / a0
    ch_d3 = ch_d2 - ch_a2 * (tau - ar20_flap.dCL_ddelta[0] / a0)
    assert ar20_flap.Ch_alpha[0] == pytest.approx(ch_a3, rel=0.05)
    assert ar20_flap.Ch_delta[0] == pytest.approx(ch_d3, rel=0.05)
    # the finite wing: CL_alpha below 2 pi (lifting line: 2 pi AR / (AR + 2) = 5.71 for AR 20)
    assert 5.2 < ar20_flap.dCL_dalpha < 5.9


def _theodorsen_flap(k: float, b: float):
    """Lift per span (up) and hinge moment per span (trailing edge down) per unit flap angle,
    per unit dynamic pressure, of Theodorsen's oscillating flap (NACA Report 496) from
    asekit.aeroelastic.typical_section (rho = 2, U = 1: q = 1)."""
    sec = TypicalSection(b, 0.0, 0.5, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, density=2.0)
    m = section_matrices(sec, 1.0)
    w = k / b
    f = ((w ** 2 * m.M_nc - 1j * w * m.B_nc - m.K_nc)[:, 2]
         + theodorsen_function(k) * m.f_c * (m.w_q + 1j * w * m.w_qd)[2])
    return -f[0], f[2]


def test_oscillating_flap_against_theodorsen():
    """Theodorsen's oscillating flap (NACA Report 496, T functions; hinge at 75 % chord)
    against the mid-span strip of a DLM wing of aspect ratio 100 (16 x 50 boxes per half) at
    M 0, k = 0.05 and 1 (the ends of the range; 0.1, 0.3 and 0.5 measured in between): lift
    within 4 % in magnitude and 4 deg in phase (measured over k = 0.05-1: -1.4..-2.7 %,
    0.4-3.1 deg), hinge moment within 6 % and 7 deg (measured +5.0..-3.7 %, -0.2..-5.8 deg;
    the finite span and the chordwise boxes at the hinge: 24 boxes per chord bring the hinge
    magnitude to +3.5..-3.3 % and the lift to -0.5..-1.8 %)."""
    b = 0.5
    panel = TrapezoidSurface((0, 0), 1.0, (0, 50.0), 1.0, 16, 50)
    hm = hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75))
    modes = deflection_modes(hm)
    mesh = hm.mesh
    mid = mesh.strip == 0
    for k in (0.05, 1.0):
        cp = pressure_jump(mesh, 0.0, k, b, modes.normalwash(k, b)[:, 0], symmetric=True)
        lift = np.sum(cp[mid] * mesh.chord[mid])
        hinge = np.sum((modes.h_lp[:, 0] * cp * mesh.chord)[mid])
        lt, ht = _theodorsen_flap(k, b)
        assert abs(lift) == pytest.approx(abs(lt), rel=0.04), k
        assert abs(np.degrees(np.angle(lift / lt))) < 4.0, k
        assert abs(hinge) == pytest.approx(abs(ht), rel=0.06), k
        assert abs(np.degrees(np.angle(hinge / ht))) < 7.0, k


@pytest.mark.parametrize("mach, n_chord, measured", [(2.0, 16, 0.2354), (3.0, 8, 0.2450)])
def test_supersonic_flap_effectiveness_against_ackeret(mach, n_chord, measured):
    """Ackeret's linear supersonic theory: DeltaCp = 4 theta / sqrt(M^2 - 1) is local, so the
    2-D flap effectiveness is the flap's chord fraction, tau = E = 0.25 (e.g. Bisplinghoff,
    Ashley & Halfman 1955, Sec. 6-5). The Mach box (asekit.aero.supersonic) through the
    deflection normalwash, on the root strip of a wing at a wall (outside the tip's Mach cone:
    2-D flow; its alpha lift is Ackeret's 4 / sqrt(M^2 - 1) to 1e-6): tau within 7 %
    (measured 0.2354 at M 2 with 16 boxes per chord, 0.2450 at M 3 with 8; the Mach-box cells
    do not fall on the hinge line, and the error does not fall monotonically with the boxes).
    Piston theory is not compared: it interpolates w linearly from the control points to the
    box centroids, which smears the hinge's jump over one box (tau = 0.219 with 2 flap boxes)."""
    from asekit.aero.methods import pressures
    panel = TrapezoidSurface((0, 0), 1.0, (0, 1.0), 1.0, n_chord, 4)
    hm = hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75))
    nz = hm.mesh.normal[:, 2]
    wash = np.column_stack([-nz + 0j, deflection_modes(hm).normalwash(0.0, 0.5)[:, 0]])
    cp = pressures(hm.mesh, mach, [0.0], 0.5, wash[None], "supersonic", symmetric=True)[0]
    root = hm.mesh.strip == 0
    lift = hm.mesh.chord[root] @ cp[root]
    assert lift[0].real == pytest.approx(4 / math.sqrt(mach ** 2 - 1), rel=1e-4)
    tau = (lift[1] / lift[0]).real
    assert tau == pytest.approx(0.25, rel=0.07)
    assert tau == pytest.approx(measured, abs=1e-3)


def test_oscillatory_coefficients_reach_the_steady_lattice_as_k_vanishes():
    """The doublet lattice's k -> 0 part is the vortex lattice (Albano & Rodden 1969, Eq. 21):
    at k = 0.001 the oscillating flap's lift and hinge moment equal the steady ones within
    0.5 %; the lift's magnitude then falls with k (Theodorsen's C(k) behaviour)."""
    from asekit.aero.control_surface import oscillatory_control_coefficients
    panel = TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 6)
    hm = hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75))
    steady = steady_control_derivatives(hm, 0.3, symmetric=True)
    cl, ch = oscillatory_control_coefficients(hm, 0.3, [0.001, 0.3], 0.5, symmetric=True)
    assert cl[0, 0] == pytest.approx(steady.dCL_ddelta[0], rel=5e-3)
    assert ch[0, 0, 0] == pytest.approx(steady.Ch_delta[0], rel=5e-3)
    assert abs(cl[1, 0]) < abs(cl[0, 0])


def test_pitching_moment_of_the_flap_against_thin_airfoil_theory(ar20_flap):
    """Thin-airfoil theory (Glauert 1926; Abbott & von Doenhoff 1959, Sec. 4.3 and Eq. 8.15):
    about the quarter chord a flat plate has no pitching moment, and a flap of hinge angle
    theta_h (cos theta_h = 1 - 2 x_h / c) gives Cm_c/4 = -sin(theta_h) (1 - cos(theta_h)) / 2
    per rad, -0.6495 for a 25 %-chord flap. Lifting-line theory adds only flat-plate loading
    (the induced angle), whose moment about the quarter chord is zero, so the AR 20 wing keeps
    the 2-D value: within 3 % (measured -0.6356, -2.1 %), and |dCm/d alpha| below 1 % of dCL/d
    alpha (measured 0.015 against 5.47 per rad), both about the mean aerodynamic chord's
    quarter point (the rectangular wing's quarter chord)."""
    th = math.acos(1.0 - 2.0 * 0.75)
    cm_2d = -math.sin(th) * (1.0 - math.cos(th)) / 2.0
    assert cm_2d == pytest.approx(-0.6495, abs=1e-4)
    assert ar20_flap.moment_reference == pytest.approx((0.25, 1.0), rel=1e-12)
    assert ar20_flap.dCm_ddelta[0] == pytest.approx(cm_2d, rel=0.03)
    assert abs(ar20_flap.dCm_dalpha) < 0.01 * ar20_flap.dCL_dalpha
    # about another axis the moment moves by the lift's lever arm, exactly: M(x1) = M(x0) -
    # (x0 - x1) L, the quarter chord 0.25 m aft of x1 = 0
    panel = TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 6)
    hm = hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75))
    d0 = steady_control_derivatives(hm, 0.3)
    d1 = steady_control_derivatives(hm, 0.3, moment_reference=(0.0, 2.0))
    assert d1.dCm_ddelta[0] == pytest.approx(
        (d0.dCm_ddelta[0] * d0.moment_reference[1] - 0.25 * d0.dCL_ddelta[0]) / 2.0, rel=1e-12)
