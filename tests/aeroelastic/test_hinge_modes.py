"""The hinge degree of freedom of a rigid control surface in a plate wing's modal model
(asekit.aeroelastic.control_surface): inertia and static unbalance, flutter against mass
balance, static control effectiveness, reversal and divergence. (Named apart from
tests/aero/test_control_surface.py: pytest needs unique test-module basenames.)"""

import math

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import ControlSurface, hinged_mesh
from asekit.aero.gaf import TabulatedGaf, gaf_from_box_modes
from asekit.aeroelastic.control_surface import (
    BalanceMass,
    flap_modal_model,
    static_effectiveness,
    steady_generalised_forces,
)
from asekit.aeroelastic.flutter import divergence_speeds, pk_flutter, pk_instabilities
from asekit.aeroelastic.statespace import ModalArrays
from asekit.case import load_case
from asekit.case import pipeline as P

#: a cantilevered aluminium plate wing, chord 0.3 m, span 1.2 m, 2 mm (8 x 16 elements, the
#: element lines on the hinge at 75 % chord and at the aileron's inboard edge at half span)
WING = """
[case]
name = "plate_wing_aileron"
[[panel]]
root_leading_edge = [0.0, 0.0]
root_chord = 0.3
tip_leading_edge = [0.0, 1.2]
tip_chord = 0.3
n_chord = 8
n_span = 16
[thickness]
root = 0.002
tip = 0.002
[material]
kind = "isotropic"
youngs_modulus = 70.0e9
poisson_ratio = 0.3
density = 2700.0
[support]
kind = "clamped_root"
[modes]
count = 4
[aero]
machs = [0.0]
reference_semichord = 0.15
boxes = [{ n_chord = 8, n_span = 16 }]
[flight]
densities = [1.225]
velocities = { min = 2.0, max = 60.0, step = 2.0 }
"""
B_REF = 0.15
K_TABLE = np.array([0.001, 0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 1.5])
RHO = 1.225


@pytest.fixture(scope="module")
def wing(tmp_path_factory):
    path = tmp_path_factory.mktemp("wing") / "wing.toml"
    path.write_text(WING)
    case = load_case(path)
    _, m_fe = P.mass_and_stiffness(case)
    panel = TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16)
    hm = hinged_mesh(panel, ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    return P.modal_model(case), m_fe, hm


def test_inertia_and_unbalance_of_a_uniform_flap(wing):
    """A uniform plate flap of chord c_f = 0.075 m, span 0.6 m, 2 mm aluminium: mass
    m = 2700 x 0.002 x 0.075 x 0.6 = 0.243 kg, static unbalance m c_f / 2 = 9.11e-3 kg m,
    inertia about the hinge m c_f^2 / 3 = 4.56e-4 kg m^2 (plus the rotary inertia
    rho t^3 / 12 per area, 1e-8 of it). The finite-element mass (consistent, nodes on the hinge
    shared half-half) gives them within 7 % (measured +6.3 %, +4.1 %: the hinge-line nodes)."""
    model, m_fe, hm = wing
    fm = flap_modal_model(model, m_fe, hm, 0.5)
    m = 2700 * 0.002 * 0.075 * 0.6
    assert fm.static_unbalance[0] == pytest.approx(m * 0.075 / 2, rel=0.07)
    assert fm.inertia[0] == pytest.approx(m * 0.075 ** 2 / 3, rel=0.07)
    # a balance mass ahead of the hinge: S drops by m_b d_b, I grows by m_b d_b^2
    bal = flap_modal_model(model, m_fe, hm, 0.5, balance=(BalanceMass(0, 0.175, 0.9, 0.2),))
    assert bal.static_unbalance[0] == pytest.approx(fm.static_unbalance[0] - 0.2 * 0.05)
    assert bal.inertia[0] == pytest.approx(fm.inertia[0] + 0.2 * 0.05 ** 2)
    # the wing block is the wing's modal model; symmetric positive-definite mass
    n = fm.n_wing
    assert np.allclose(fm.modal.M[:n, :n], model.M)
    assert np.allclose(fm.modal.M, fm.modal.M.T)
    assert np.all(np.linalg.eigvalsh(fm.modal.M) > 0)
    assert fm.hinge_frequency_hz[0] == pytest.approx(math.sqrt(0.5 / fm.inertia[0]) / (2 * math.pi))
    with pytest.raises(ValueError, match="hinge_stiffness"):
        flap_modal_model(model, m_fe, hm, -1.0)


def _first_flutter(fm, hm):
    q = gaf_from_box_modes(fm.box_modes, hm.mesh, 0.0, K_TABLE, B_REF)
    gaf = TabulatedGaf(K_TABLE, q, B_REF, 0.0)
    res = pk_flutter(fm.modal, gaf, RHO, np.arange(2.0, 28.0, 1.5))
    found = [i for i in pk_instabilities(res, fm.modal, gaf, RHO) if i.kind == "flutter"]
    return min(found, key=lambda i: i.speed), q


def test_mass_balance_removes_the_aileron_flutter(wing):
    """Classic wing-bending/aileron flutter (Bisplinghoff, Ashley & Halfman 1955, Sec. 9-7;
    Theodorsen & Garrick, NACA Report 736): an aileron with its centre of mass aft of the
    hinge (S > 0) flutters far below the wing's own flutter; a balance mass ahead of the hinge
    that over-balances it (S < 0) removes that flutter, leaving the wing's own (torsion)
    flutter of the locked-aileron model. Measured: 12.7 m/s (12.1 Hz) unbalanced; with 0.4 kg
    at 5 cm ahead of the hinge 24.5 m/s, the wing alone (aileron locked) 24.4 m/s."""
    model, m_fe, hm = wing
    free = flap_modal_model(model, m_fe, hm, 0.5)
    balanced = flap_modal_model(model, m_fe, hm, 0.5, balance=(BalanceMass(0, 0.175, 0.9, 0.4),))
    assert free.static_unbalance[0] > 0 > balanced.static_unbalance[0]
    f_free, q = _first_flutter(free, hm)
    f_bal, _ = _first_flutter(balanced, hm)
    n = free.n_wing
    locked = ModalArrays(free.modal.M[:n, :n], free.modal.K[:n, :n], free.modal.C[:n, :n], 0)
    gaf = TabulatedGaf(K_TABLE, q[:, :n, :n], B_REF, 0.0)
    res = pk_flutter(locked, gaf, RHO, np.arange(2.0, 28.0, 1.5))
    f_wing = min(i.speed for i in pk_instabilities(res, locked, gaf, RHO) if i.kind == "flutter")
    assert f_free.speed < 0.7 * f_wing
    assert f_bal.speed == pytest.approx(f_wing, rel=0.05)


def test_static_effectiveness_reversal_and_divergence(wing):
    """The aileron's flexible-to-rigid rolling-moment ratio is 1 at q = 0 and falls to 0 at the
    reversal dynamic pressure below divergence (the plate's elastic axis at mid-chord lies aft
    of the aerodynamic centre). Checks: the divergence pressure equals that of
    asekit.aeroelastic.flutter.divergence_speeds on the same steady GAFs; q_R scales linearly
    with the stiffness (K -> 2 K: q_R -> 2 q_R, the static equations are homogeneous in K / q);
    at q_R the flexible rolling moment vanishes."""
    model, m_fe, hm = wing
    fm = flap_modal_model(model, m_fe, hm, 0.5)
    se = static_effectiveness(fm, hm, 0.0, 2000.0, n_q=30)
    assert se.ratio[0, 0] == pytest.approx(1.0)
    assert 0.0 < se.reversal_q[0] < se.divergence_q
    n = fm.n_wing
    q0, _, roll = steady_generalised_forces(fm, hm, 0.0)
    locked = ModalArrays(fm.modal.M[:n, :n], fm.modal.K[:n, :n], fm.modal.C[:n, :n], 0)
    u_div = divergence_speeds(locked, q0[:n, :n], RHO)[0]
    assert 0.5 * RHO * u_div ** 2 == pytest.approx(se.divergence_q, rel=1e-9)
    qr = se.reversal_q[0]
    zeta = np.linalg.solve(fm.modal.K[:n, :n] - qr * q0[:n, :n], qr * q0[:n, n])
    assert abs(roll[n] + roll[:n] @ zeta) < 1e-8 * abs(roll[n])
    stiff = type(fm)(ModalArrays(fm.modal.M, 2 * fm.modal.K, fm.modal.C, 0), fm.box_modes,
                     fm.inertia, fm.static_unbalance, fm.hinge_frequency_hz, n, fm.names)
    assert static_effectiveness(stiff, hm, 0.0, 4000.0, n_q=30).reversal_q[0] == \
        pytest.approx(2 * qr, rel=1e-8)
    assert se.reversal_speed(RHO)[0] == pytest.approx(math.sqrt(2 * qr / RHO))
