"""The ASE loop with the actuator on a control surface's hinge (asekit.ase.flap, issue 25).

A small clamped aluminium plate wing (0.3 m x 1.2 m, 2 mm; 4 x 8 elements and boxes) with a
25 %-chord aileron over its outboard half, the thesis's actuator (Table 12) and System 3 PD
(Table 17). Reference numbers are computed, never typed: the servo chapter's closed loop
(asekit.servo.actuator, Eq. 4.18) with J_fin = the aileron's hinge inertia, and the p-k
flutter speed of the same wing with the aileron locked.
"""

import control as ct
import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import ControlSurface, hinged_mesh
from asekit.aero.gaf import build_gaf_database
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.control_surface import flap_modal_model
from asekit.aeroelastic.statespace import ModalArrays
from asekit.ase import flap
from asekit.ase import loop as ase_loop
from asekit.geometry import Material, Planform, Thickness
from asekit.rfa.roger import roger_fit
from asekit.servo import actuator as servo
from asekit.structure.assembly import assemble, clamped_edge
from asekit.structure.mesh import panels_mesh
from asekit.structure.modes import fixed_modal_model

RHO = 1.225
CTL = servo.SYSTEM_3
K = np.array([0.001, 0.05, 0.1, 0.2, 0.4, 0.8, 1.5])
B_REF = 0.15


@pytest.fixture(scope="module")
def wing():
    pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 4, [8])
    Kf, Mf = assemble(pm, Material(70e9, 0.3, 2700.0))
    model = fixed_modal_model(clamped_edge(pm, Kf, Mf), Mf, n_modes=3)
    hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 4, 8),
                     ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    fm = flap_modal_model(model, Mf, hm, 0.5)
    db = build_gaf_database(fm.box_modes, hm.mesh, [0.0], K, B_REF, 0, symmetric=True,
                            method="quartic", progress=False)
    modal, order = flap.hinge_actuated_modal(fm, 0)
    row = flap.surface_angle_row(model, hm, 0, order)
    Q = flap.reorder_modes(db.at(0.0).Q, order)
    db_w = build_gaf_database(fe_spline(model, hm.mesh), hm.mesh, [0.0], K, B_REF, 0,
                              symmetric=True, method="quartic", progress=False)
    return dict(fm=fm, gaf_locked=db_w.at(0.0), modal=modal, order=order, row=row, Q=Q, Q_wing=db.at(0.0).Q)


def _locked_wing(w, Q):
    """Only the hinge coordinate (the wing's modes locked)."""
    m = w["modal"]
    return (ModalArrays(m.M[:1, :1], m.K[:1, :1], m.C[:1, :1], 1),
            roger_fit(K, Q[:, :1, :1], B_REF, n_lags=2), np.array([1.0]))


def _step(sys, t):
    """Step-response histories (n_outputs, n_t) of a single-input system."""
    return np.asarray(ct.step_response(sys, T=t).outputs).reshape(sys.noutputs, len(t))


def _servo_poles(ol_poles, lag_poles):
    """Closed-loop poles without the (uncoupled) aerodynamic lag poles."""
    p = list(ol_poles)
    for lp in lag_poles:
        p.pop(int(np.argmin(np.abs(np.array(p) - lp))))
    return np.sort_complex(np.array(p))


def test_actuated_modal_moves_hinge_first_and_drops_its_spring(wing):
    fm, modal, order = wing["fm"], wing["modal"], wing["order"]
    assert order.tolist() == [3, 0, 1, 2]
    assert modal.n_rigid == 1 and modal.K[0, 0] == 0.0
    assert modal.M[0, 0] == pytest.approx(fm.inertia[0], rel=1e-12)
    np.testing.assert_allclose(modal.M[1:, 1:], fm.modal.M[:3, :3], rtol=1e-12)
    assert wing["row"][0] == 1.0 and np.any(wing["row"][1:] != 0.0)


def test_aero_off_locked_wing_is_the_servo_chapter_loop(wing):
    """q = 0 (a zero RFA) and the wing locked: the loop is Eq. 4.18's actuator driving the
    aileron's hinge inertia alone -- same poles, same step response."""
    modal, rfa, row = _locked_wing(wing, np.zeros_like(wing["Q"]))
    m = flap.flap_ase_model(modal, rfa, RHO, 20.0, row)
    I_h = float(wing["fm"].inertia[0])
    assert m.effective_fin_inertia == pytest.approx(I_h, rel=1e-12)
    ref = servo.ActuatorParameters(fin_inertia=I_h)
    p_ref = np.sort_complex(servo.closed_loop_poles(ref, CTL))
    lag = -20.0 / B_REF * np.asarray(rfa.lag_roots)
    for topo in ase_loop.TOPOLOGIES:
        cl = ase_loop.closed_loop(m, CTL, topo, outputs=["theta", "fin_root_pitch"])
        p = _servo_poles(np.linalg.eigvals(np.asarray(cl.A)), lag)
        np.testing.assert_allclose(p, p_ref, rtol=1e-7)
        # Eq. 4.18 with the derivative acting on the feedback only (as ase.loop.closed_loop
        # does: no derivative kick of the step), numerator K_c K_P K_t
        t = np.linspace(0.0, 0.05, 501)
        kt = ref.motor.torque_constant
        y_ref = _step(ct.tf([CTL.gain * CTL.kp * kt],
                            servo.closed_loop_polynomial(ref, CTL)), t)[0]
        y = _step(cl, t)
        np.testing.assert_allclose(y[0], y_ref, atol=1e-9 * abs(y_ref).max())
        np.testing.assert_allclose(y[1], y_ref, atol=1e-9 * abs(y_ref).max())


def test_aem1_equals_aem2_for_locked_wing_with_air(wing):
    """Rigid surface, wing locked: the surface's angle is the hinge angle, so the encoder
    (AEM1) and surface (AEM2) loops are one loop, the aerodynamic hinge moment included."""
    modal, rfa, row = _locked_wing(wing, wing["Q"])
    m = flap.flap_ase_model(modal, rfa, RHO, 20.0, row)
    t = np.linspace(0.0, 0.05, 401)
    y = {topo: _step(ase_loop.closed_loop(m, CTL, topo, outputs=["theta"]), t)[0]
         for topo in ase_loop.TOPOLOGIES}
    np.testing.assert_allclose(y["AEM1"], y["AEM2"], atol=1e-12)
    # the air's hinge moment changes the loop (the test above is not vacuous)
    off = flap.flap_ase_model(*_locked_wing(wing, np.zeros_like(wing["Q"]))[:2], RHO, 20.0, row)
    y0 = _step(ase_loop.closed_loop(off, CTL, "AEM1", outputs=["theta"]), t)[0]
    assert np.max(np.abs(y0 - y["AEM1"])) > 1e-6


def test_flexible_wing_stable_at_low_speed_and_differs_by_topology(wing):
    m = flap.flap_ase_model(wing["modal"], roger_fit(K, wing["Q"], B_REF, n_lags=4),
                            RHO, 10.0, wing["row"])
    # the wing's modes couple inertially with the hinge: J_eff below the hinge inertia
    assert 0 < m.effective_fin_inertia < wing["fm"].inertia[0]
    poles = {}
    for topo in ase_loop.TOPOLOGIES:
        cl = ase_loop.closed_loop(m, CTL, topo)
        assert ase_loop.is_stable(cl), topo
        poles[topo] = np.sort_complex(np.linalg.eigvals(np.asarray(cl.A)))
    assert np.max(np.abs(poles["AEM1"] - poles["AEM2"])) > 1e-3


def test_stiff_actuator_loop_goes_unstable_at_the_locked_aileron_flutter_speed(wing):
    """The servo holds the hinge far stiffer than the wing's modes: the AEM1 loop must lose
    stability near the p-k flutter speed of the wing with the aileron locked (the GAFs of the
    wing's modes alone; the RFA and the p-k method differ by a few tenths of a per cent)."""
    from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
    fm = wing["fm"]
    n_w = fm.n_wing
    locked = ModalArrays(fm.modal.M[:n_w, :n_w], fm.modal.K[:n_w, :n_w],
                         fm.modal.C[:n_w, :n_w], 0)
    speeds = np.arange(5.0, 60.0, 0.5)
    res = pk_flutter(locked, wing["gaf_locked"], RHO, speeds, max_iter=300)
    inst = [i for i in pk_instabilities(res, locked, wing["gaf_locked"], RHO)
            if not i.at_first_point]
    U_pk = min(float(i.speed) for i in inst)
    rfa = roger_fit(K, wing["Q"], B_REF, n_lags=4)

    def unstable(U):
        m = flap.flap_ase_model(wing["modal"], rfa, RHO, U, wing["row"])
        return not ase_loop.is_stable(ase_loop.closed_loop(m, CTL, "AEM1",
                                                           outputs=["theta"]))
    lo, hi = 5.0, 60.0
    assert not unstable(lo) and unstable(hi)
    for _ in range(20):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    U_ase = 0.5 * (lo + hi)
    print(f"ASE AEM1 onset {U_ase:.3f} m/s, p-k locked aileron {U_pk:.3f} m/s")
    assert U_ase == pytest.approx(U_pk, rel=0.02)       # measured 23.79 vs 23.88 m/s
