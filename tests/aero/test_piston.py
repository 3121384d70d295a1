"""Piston theory (asekit.aero.piston): closed-form integrals of the local law on box meshes,
the thickness terms, the validity warning and bad input.

Reference formulas (no tabulated numbers are needed):
- first order, DeltaCp = -(4/M) w/U: Lighthill 1953 (J. Aeronaut. Sci. 20(6)) Eq. 5 to first
  order in w/a, applied to both surfaces; integrated over a chord in closed form below;
- thickness terms: the same expansion to third order with the surface slopes (Ashley &
  Zartarian 1956, J. Aeronaut. Sci. 23(12)); for a double wedge of thickness ratio t/c the
  second-order term moves the aerodynamic centre forward by (gamma + 1) M (t/c) c / 8 (from the
  mid-chord) and the third-order term multiplies the lift slope by 1 + (gamma+1)/4 M^2 (t/c)^2,
  derived by integrating those pressures over the two faces of the wedge.
"""

import warnings

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.piston import (
    PistonValidityWarning,
    piston_coefficient,
    piston_pressure_matrices,
    piston_pressure_matrix,
)

C = 0.4            # chord (m)
B = C / 2          # reference semi-chord (m)
XA = 0.1           # pitch axis (m from the leading edge)


def _wing(n_chord=8, n_span=3, span=0.6):
    return mesh_surfaces([TrapezoidSurface((0, 0), C, (0, span), C, n_chord, n_span)])


def _section(mesh, cp):
    """Lift per unit span / q and nose-up moment about XA per unit span / q."""
    span = mesh.corners[:, :, 1].max() - mesh.corners[:, :, 1].min()
    lift = np.sum(cp * mesh.area) / span
    mom = np.sum(-(mesh.load_point[:, 0] - XA) * cp * mesh.area) / span
    return lift, mom


@pytest.mark.parametrize("mach, k", [(2.0, 0.0), (3.0, 0.4), (5.0, 1.5)])
def test_first_order_rigid_modes_exact(mach, k):
    """Plunge and pitch of a flat plate: the box version integrates the local law by the
    midpoint rule on each box (linear normalwash, virtual-work-consistent transfer), exact up
    to the rule's dx^2 / 12 term in the pitch-pitch moment. Closed forms from DeltaCp =
    -(4/M) w/U with w/U = i k h / b (plunge h = 1 m) and -1 - i k (x - x_a)/b (pitch)."""
    mesh = _wing()
    dx = C / 8
    a = piston_pressure_matrix(mesh, mach, k, B, warn=False)
    x = mesh.control_point[:, 0]
    kb = k / B
    i1 = C**2 / 2 - XA * C                               # int (x - xa) dx
    i2 = ((C - XA) ** 3 + XA**3) / 3 - C * dx**2 / 12   # int (x - xa)^2 dx, midpoint rule
    l_h, m_h = _section(mesh, a @ (1j * kb * np.ones(mesh.n)))
    l_a, m_a = _section(mesh, a @ (-1.0 - 1j * kb * (x - XA)))
    f = 4.0 / mach
    np.testing.assert_allclose(l_h, -f * 1j * kb * C, atol=1e-12)
    np.testing.assert_allclose(m_h, f * 1j * kb * i1, atol=1e-12)
    np.testing.assert_allclose(l_a, f * (C + 1j * kb * i1), rtol=1e-12)
    np.testing.assert_allclose(m_a, -f * (i1 + 1j * kb * i2), rtol=1e-12)


def test_thickness_terms_double_wedge():
    """Second order moves the aerodynamic centre of a double wedge forward by
    (gamma+1) M (t/c) c / 8; third order raises the lift slope by (gamma+1)/4 M^2 (t/c)^2
    (module docstring of the test for the derivation); flat plate first order has neither."""
    mesh = _wing(n_chord=10)
    mach, tc, gamma = 3.0, 0.04, 1.4
    xc = mesh.control_point[:, 0] - 0.5 * mesh.chord * 0.5     # centroid x (3/4 -> 1/2 chord)
    tau = np.where(xc < C / 2, tc, -tc)
    w = -np.ones(mesh.n)                                         # unit incidence
    span = 0.6
    res = {}
    for order in (1, 2, 3):
        cp = piston_pressure_matrix(mesh, mach, 0.0, B, order, tau, gamma, warn=False) @ w
        lift = np.sum(cp * mesh.area).real / span
        m_mid = np.sum(-(mesh.load_point[:, 0] - C / 2) * cp * mesh.area).real / span
        res[order] = (lift, m_mid / lift)                       # lift, x_mid - x_ac
    np.testing.assert_allclose(res[1][0], 4 / mach * C, rtol=1e-12)
    np.testing.assert_allclose(res[1][1], 0.0, atol=1e-12)
    np.testing.assert_allclose(res[2][0], 4 / mach * C, rtol=1e-12)
    np.testing.assert_allclose(res[2][1], (gamma + 1) * mach * tc * C / 8, rtol=1e-12)
    np.testing.assert_allclose(res[3][0], 4 / mach * C * (1 + (gamma + 1) / 4 * mach**2 * tc**2),
                               rtol=1e-12)


def test_coefficient_is_ackeret_high_mach_limit():
    """First order -(4/M) tends to Ackeret's -4/sqrt(M^2-1) as M grows (ratio beta/M)."""
    for m in (2.0, 3.0, 5.0, 10.0):
        assert piston_coefficient(m) == pytest.approx(-4.0 / m)
        assert (4.0 / np.sqrt(m * m - 1)) / (4.0 / m) - 1 == pytest.approx(
            m / np.sqrt(m * m - 1) - 1)


def test_validity_warning_names_mach_and_k():
    mesh = _wing()
    with pytest.warns(PistonValidityWarning, match=r"mach=1\.5.*k=\[0\.1\]"):
        piston_pressure_matrices(mesh, 1.5, [0.1, 3.0], B)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        piston_pressure_matrices(mesh, 3.0, [0.0, 0.5], B)
        piston_pressure_matrices(mesh, 1.5, [2.0], B)            # M k = 3 >= 2
    with pytest.warns(PistonValidityWarning, match="thickness"):   # M tau > 1
        piston_pressure_matrices(mesh, 3.0, [0.5], B, order=3, thickness_slope=0.4)


@pytest.mark.parametrize("kwargs, match", [
    ({"mach": 1.0}, "mach"), ({"mach": 0.8}, "mach"), ({"mach": float("nan")}, "mach"),
    ({"k": -0.1}, "k must"), ({"b_ref": 0.0}, "b_ref"), ({"order": 4}, "order"),
    ({"thickness_slope": np.nan}, "thickness_slope"),
])
def test_bad_input(kwargs, match):
    args = {"mach": 2.5, "k": 0.2, "b_ref": B}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        piston_pressure_matrices(_wing(), **args)


# ---- issue 22: an absurd Mach number is refused, not an OverflowError ---------------------------
@pytest.mark.parametrize("mach, order", [(1e300, 3), (1e160, 3)])
def test_overflowing_coefficient_names_mach(mach, order):
    """Issue 22's reproducer: Mach 1e300 raised OverflowError (34, 'Numerical result out of
    range') from M^2 tau^2."""
    with pytest.raises(ValueError, match=r"mach = 1e\+\d+ with thickness_slope up to 0\.05 "
                                         r"overflows the order-3 piston coefficient"):
        piston_coefficient(mach, order=order, thickness_slope=0.05)


def test_first_order_coefficient_at_huge_mach_is_the_finite_limit():
    """First order: c = -4 / M exactly (no M^2 term to overflow, before: 0 * inf = nan)."""
    assert piston_coefficient(1e160, order=1, thickness_slope=0.05) == pytest.approx(-4e-160)
