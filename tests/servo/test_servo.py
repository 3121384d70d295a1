"""Linear servo-actuator model (asekit.servo.actuator): thesis Sec. 2.3, Ch. 4 Tables 13-15, 17, Fig 54."""

import math

import control as ct
import numpy as np
import pytest

from asekit.servo.actuator import (
    NO_CONTROLLER,
    SYSTEM_1,
    SYSTEM_2,
    SYSTEM_3,
    ActuatorParameters,
    DCMotor,
    PDController,
    Transmission,
    actuator_state_space,
    actuator_transfer_function,
    closed_loop,
    closed_loop_poles,
    forward_path,
    margins,
    motor_transfer_function,
    open_loop_poles,
    root_locus_data,
    stable_kp_range,
    step_response,
)

P = ActuatorParameters()


def test_inertia_at_motor_eq_2_33():
    # Eq 2.33 by hand: 1.1e-6 + 0.5e-7 + 2.958e-4 / (66^2 * 0.7)
    assert P.inertia_at_motor == pytest.approx(1.1e-6 + 0.5e-7 + 2.958e-4 / (66**2 * 0.7), rel=1e-12)


def test_open_loop_poles_table_13():
    poles = open_loop_poles(P)
    assert abs(poles[0]) < 1e-9
    # Thesis Table 13/14: -168.806, -10340.285 rad/s
    np.testing.assert_allclose(poles[1:], [-168.806, -10340.285], rtol=1e-5)


def test_open_loop_poles_are_the_quadratic_roots():
    # analytic: J L s^2 + (J R + c L) s + (K_b K_t + c R) = 0, here with c != 0
    m = DCMotor(viscous_damping=2e-6)
    p = ActuatorParameters(motor=m)
    j = p.inertia_at_motor
    a, b, c = j * m.inductance, j * m.resistance + 2e-6 * m.inductance, \
        m.back_emf_constant * m.torque_constant + 2e-6 * m.resistance
    disc = math.sqrt(b * b - 4 * a * c)
    expected = sorted([(-b + disc) / (2 * a), (-b - disc) / (2 * a)], reverse=True)
    np.testing.assert_allclose(open_loop_poles(p)[1:], expected, rtol=1e-9)


def test_motor_and_fin_transfer_functions_differ_by_ratio():
    gm, gf = motor_transfer_function(P), actuator_transfer_function(P)
    w = np.array([1.0, 100.0, 5000.0])
    np.testing.assert_allclose(gm(1j * w) / gf(1j * w), 66.0, rtol=1e-12)


@pytest.mark.parametrize("controller, table", [
    (SYSTEM_1, [-214.381917, -666.563583, -9628.15]),   # Table 15
    (SYSTEM_2, [-321.484467, -555.387425, -9632.22]),   # Table 15
    (SYSTEM_3, [-378.25, -581.96, -9548.87]),           # Table 17
])
def test_closed_loop_poles_tables_15_17(controller, table):
    np.testing.assert_allclose(closed_loop_poles(P, controller), table, rtol=1e-3)


def test_no_controller_poles_table_14():
    # Table 14: -0.43, -168.35, -10340.29 (the thesis rounds the first to two decimals)
    np.testing.assert_allclose(closed_loop_poles(P, NO_CONTROLLER), [-0.43, -168.35, -10340.29],
                               atol=0.01)


def test_zero_location_and_closed_loop_dc_gain():
    assert SYSTEM_3.zero == -275.0
    assert NO_CONTROLLER.zero == -math.inf
    # a type-1 loop tracks a step exactly (thesis Sec. 4.3)
    assert ct.dcgain(closed_loop(P, SYSTEM_3)) == pytest.approx(1.0, rel=1e-12)


def test_closed_loop_equals_feedback_of_forward_path():
    # Eq 4.18 (with K_c in the constant term) is G/(1+G) of Eq 4.17
    ref = ct.feedback(forward_path(P, SYSTEM_3), 1)
    w = np.logspace(0, 5, 7)
    np.testing.assert_allclose(closed_loop(P, SYSTEM_3)(1j * w), ref(1j * w), rtol=1e-9)


def test_margins_system_3_fig_54():
    m = margins(P, SYSTEM_3)
    assert m.phase_margin_deg == pytest.approx(78.4, abs=0.1)   # thesis Sec. 4.3
    assert math.isinf(m.gain_margin_db) and m.gain_margin_db > 0
    # at the gain crossover the forward path has unit magnitude
    assert abs(forward_path(P, SYSTEM_3)(1j * m.gain_crossover)) == pytest.approx(1.0, rel=1e-6)


def test_state_space_matches_eq_2_41_and_names():
    ss = actuator_state_space(P)
    assert ss.input_labels == ["voltage", "hinge_moment"]
    assert ss.output_labels == ["theta", "omega", "alpha", "current"]
    g = actuator_transfer_function(P)
    for w in (0.5, 50.0, 3000.0):
        assert ss(1j * w)[0, 0] == pytest.approx(g(1j * w), rel=1e-9)


def test_state_space_hinge_moment_accelerates_the_reflected_inertia():
    # With J_rotor, J_tr -> tiny and eta = 1 the inertia seen at the fin is J_fin: alpha = T/J_fin
    p = ActuatorParameters(motor=DCMotor(rotor_inertia=1e-15), transmission=Transmission(
        efficiency=1.0, inertia=0.0))
    d = actuator_state_space(p).D
    assert d[2, 1] == pytest.approx(1.0 / p.fin_inertia, rel=1e-6)
    # thesis transmission: T / (N^2 eta J_total@motor)
    d = actuator_state_space(P).D
    assert d[2, 1] == pytest.approx(1.0 / (66**2 * 0.7 * P.inertia_at_motor), rel=1e-12)


def test_fin_inertia_is_a_parameter():
    p_ours = ActuatorParameters(fin_inertia=2.5e-4)
    assert p_ours.inertia_at_motor < P.inertia_at_motor
    # a lighter fin gives a faster mechanical pole
    assert open_loop_poles(p_ours)[1] < open_loop_poles(P)[1]


def test_stall_torque_and_no_load_rate():
    # 24 V stall at the fin: K_t (24/R) N eta = 6.64 N m, enough for the 6 N m requirement
    assert P.stall_torque_at_fin(24.0) == pytest.approx(34.6e-3 * 24 / 5.78 * 66 * 0.7)
    assert P.stall_torque_at_fin(24.0) > 6.0
    assert P.no_load_rate_at_fin(24.0) == pytest.approx(24 / 34.6e-3 / 66)


def test_routh_bound_puts_poles_on_the_imaginary_axis():
    c = PDController(1.0, 1.0, 0.2)
    _, kp_max = stable_kp_range(P, c)
    at_bound = PDController(1.0, kp_max, 0.2)
    poles = closed_loop_poles(P, at_bound, require_stable=False)
    assert np.min(np.abs(np.real(poles))) < 1e-6 * np.max(np.abs(poles))
    closed_loop_poles(P, PDController(1.0, 0.99 * kp_max, 0.2))   # stable: no error


def test_unstable_gains_raise_when_stable_design_requested():
    bad = PDController(gain=1.0, kp=1e6, kd=0.0)
    with pytest.raises(ValueError, match=r"kp K_P=1e\+06.*K_c\*K_P in"):
        closed_loop(P, bad)
    with pytest.raises(ValueError, match="unstable"):
        closed_loop_poles(P, PDController(gain=-1.0, kp=275.0, kd=1.0))
    poles = closed_loop_poles(P, bad, require_stable=False)
    assert np.any(np.real(poles) > 0)


@pytest.mark.parametrize("factory, word", [
    (lambda: DCMotor(resistance=0.0), "resistance"),
    (lambda: DCMotor(inductance=-1e-3), "inductance"),
    (lambda: DCMotor(torque_constant=-0.01), "torque_constant"),
    (lambda: DCMotor(back_emf_constant=0.0), "back_emf_constant"),
    (lambda: DCMotor(rotor_inertia=float("nan")), "rotor_inertia"),
    (lambda: DCMotor(viscous_damping=-1.0), "viscous_damping"),
    (lambda: Transmission(ratio=0.0), "ratio"),
    (lambda: Transmission(ratio=-66.0), "ratio"),
    (lambda: Transmission(efficiency=0.0), r"efficiency must be .* \(0, 1\]"),
    (lambda: Transmission(efficiency=1.2), "efficiency"),
    (lambda: ActuatorParameters(fin_inertia=-1e-4), "fin_inertia"),
    (lambda: PDController(float("inf"), 1.0, 1.0), "gain"),
    (lambda: root_locus_data(P, gains=[-1.0]), "gains"),
    (lambda: step_response(P, SYSTEM_3, t_final=0.0), "t_final"),
])
def test_bad_input(factory, word):
    with pytest.raises(ValueError, match=word):
        factory()


def test_root_locus_starts_at_open_loop_poles_and_stays_stable_for_pd():
    gains, poles = root_locus_data(P, SYSTEM_2, [1e-9, 9.0, 1e3])
    np.testing.assert_allclose(np.sort(poles[0].real), np.sort(open_loop_poles(P)), atol=1e-3)
    # Fig 50: "as K_c is increased the system gets faster without becoming unstable"
    assert np.all(poles[1:].real < 0)
    np.testing.assert_allclose(np.sort(poles[1].real), np.sort(closed_loop_poles(P, SYSTEM_2)),
                               rtol=1e-9)


def test_step_response_system3_fast_and_settles():
    t, y = step_response(P, SYSTEM_3, t_final=0.05)
    assert y[-1] == pytest.approx(1.0, abs=1e-3)
    assert t[np.argmax(y > 0.9)] < 0.01


def test_interconnected_state_space_loop_has_the_design_poles():
    # actuator SS + static PD (derivative on the measured rate) closed through python-control:
    # same characteristic polynomial as Eq. 4.18
    from asekit.servo.actuator import pd_state_space
    loop = ct.interconnect(
        [actuator_state_space(P), pd_state_space(SYSTEM_3)],
        connections=[["actuator.voltage", "pd.voltage"], ["pd.theta_fb", "actuator.theta"],
                     ["pd.omega_fb", "actuator.omega"]],
        inplist=["pd.theta_cmd", "pd.theta_cmd_rate", "actuator.hinge_moment"],
        outlist=["actuator.theta"], ignore_outputs=["actuator.alpha", "actuator.current"])
    np.testing.assert_allclose(np.sort(ct.poles(loop).real), np.sort(closed_loop_poles(P, SYSTEM_3)),
                               rtol=1e-9)
    dc = np.ravel(ct.dcgain(loop))
    assert dc[0] == pytest.approx(1.0, rel=1e-9)
    # a constant hinge moment T gives the analytic offset R T / (N eta K_t K_c K_P)
    kckp = SYSTEM_3.gain * SYSTEM_3.kp
    assert dc[2] == pytest.approx(5.78 / (66 * 0.7 * 34.6e-3 * kckp), rel=1e-9)


# ---- issue 22: no silent NaN from the step response -------------------------------------------
def test_step_response_t_final_1e100_is_refused_naming_the_horizon():
    """Issue 22's reproducer: t_final = 1e100 s returned 2000 NaN of 2001 samples (the matrix
    exponential of a 5e97 s step). Now refused, naming t_final, n and the valid range."""
    with pytest.raises(ValueError, match=r"t_final must be in \(0, .*\] s with n = 2001"):
        step_response(P, SYSTEM_3, t_final=1e100)


def test_step_response_long_stable_horizon_is_computed_and_finite():
    """A long but representable horizon (|p| dt ~ 5e9, far below MAX_STEP_POLE_PRODUCT) is
    computed: a stable loop of unity DC gain (closed_loop's K_c K_P K_t / K_c K_P K_t) settles
    at 1."""
    t, y = step_response(P, SYSTEM_3, t_final=1e6)
    assert np.all(np.isfinite(y)) and y[-1] == pytest.approx(1.0, abs=1e-6)


def test_step_response_unstable_loop_refused_past_its_growth_horizon():
    """An unstable loop grows as e^(sigma t): past sigma t_final = 700 (e^700 ~ 1e304) it is not
    representable (before: 1662 NaN of 2001 at t_final = 10 s); up to it the response is
    finite."""
    bad = PDController(-5.0, 275.0, 1.0)
    sigma = float(np.max(closed_loop_poles(P, bad, require_stable=False).real))
    assert sigma > 0
    with pytest.raises(ValueError, match="t_final must be in"):
        step_response(P, bad, t_final=10.0)
    t, y = step_response(P, bad, t_final=0.9 * 700.0 / sigma)
    assert np.all(np.isfinite(y)) and abs(y[-1]) > 1e100


@pytest.mark.parametrize("kw, word, error", [
    ({"n": 2001.0}, "n must be an integer", TypeError),
    ({"n": True}, "n must be an integer", TypeError),
    ({"n": 1}, r"n must be an integer in \[2, 10000000\]", ValueError),
    ({"t_final": "0.05"}, "t_final must be a real number", ValueError),
    ({"amplitude": "1"}, "amplitude must be a real number", ValueError),
    ({"amplitude": 1 + 1j}, "amplitude must be a real number", TypeError),
    ({"amplitude": float("nan")}, "amplitude must be a finite number", ValueError),
])
def test_step_response_strict_types(kw, word, error):
    with pytest.raises(error, match=word):
        step_response(P, SYSTEM_3, **kw)


def test_step_response_accepts_numpy_scalars():
    t, y = step_response(P, SYSTEM_3, t_final=np.float32(0.05), n=np.int64(101),
                         amplitude=np.float64(2.0))
    assert t.size == 101 and y[-1] == pytest.approx(2.0, abs=2e-3)
