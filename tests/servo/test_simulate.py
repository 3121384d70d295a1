"""Nonlinear power-limited actuator simulation (asekit.servo.simulate), thesis Secs. 4.2.1, 4.3."""

import math

import control as ct
import numpy as np
import pytest

from asekit.servo.actuator import SYSTEM_2, SYSTEM_3, ActuatorParameters, actuator_state_space
from asekit.servo.simulate import (
    CURRENT_REGULATED_LIMITS,
    NO_LIMITS,
    THESIS_LIMITS,
    PowerLimits,
    SteadyHingeMoment,
    actuator_rhs,
    applied_voltage,
    holding_current,
    motor_rhs,
    motor_torque_at_fin,
    no_hinge_moment,
    simulate,
)

P = ActuatorParameters()
DEG = math.pi / 180


def test_motor_rhs_without_limits_is_the_linear_state_space():
    ss = actuator_state_space(P)
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = rng.normal(size=3) * [0.2, 5.0, 2.0]
        u = rng.normal(size=2) * [10.0, 3.0]
        np.testing.assert_allclose(motor_rhs(P, NO_LIMITS, x, u[0], u[1]), ss.A @ x + ss.B @ u,
                                   rtol=1e-12)


def test_unlimited_simulation_matches_the_linear_closed_loop():
    # derivative on the measurement: theta/theta_cmd = K_c K_P K_t / (Eq. 4.18 denominator)
    sim = simulate(P, SYSTEM_3, 1.0 * DEG, t_final=0.04, limits=NO_LIMITS,
                   hinge_moment=no_hinge_moment, n_out=401)
    from asekit.servo.actuator import closed_loop_polynomial
    den = closed_loop_polynomial(P, SYSTEM_3)
    g = ct.tf([SYSTEM_3.gain * SYSTEM_3.kp * P.motor.torque_constant], den)
    ref = ct.step_response(g, T=sim.t).outputs.squeeze() * DEG
    np.testing.assert_allclose(sim.theta, ref, atol=1e-6 * DEG * 100)


def test_steady_state_under_hinge_moment_is_analytic():
    # at rest: I = -k theta/(N eta K_t), R I = K_c K_P (theta_c - theta), k = q Q_cc
    hm = SteadyHingeMoment()
    k = hm.stiffness
    kc_kp = SYSTEM_3.gain * SYSTEM_3.kp
    a = P.motor.resistance * k / (66 * 0.7 * P.motor.torque_constant * kc_kp)
    theta_c = 14 * DEG
    sim = simulate(P, SYSTEM_3, theta_c, t_final=0.15, limits=THESIS_LIMITS)
    assert sim.theta[-1] == pytest.approx(theta_c / (1 - a), rel=1e-6)
    # thesis: System 3 meets the 2 % requirement, System 2 does not (Sec. 4.3)
    assert sim.steady_error < 0.02
    assert simulate(P, SYSTEM_2, theta_c, t_final=0.15).steady_error > 0.02


def test_step14_system3_settles_under_50_ms_with_no_overshoot_of_its_final_value():
    sim = simulate(P, SYSTEM_3, 14 * DEG, t_final=0.1)
    assert sim.settling_time() < 0.05                    # thesis: "well below 50 ms"
    assert np.max(sim.theta) <= sim.theta[-1] * (1 + 1e-6)
    assert np.max(np.abs(sim.voltage)) <= 24.0 + 1e-12


def test_reversal_against_the_decentering_moment_figs_55_57():
    sim = simulate(P, SYSTEM_3, 0.0, t_final=0.1, theta0=15 * DEG)
    # the motor starts from the holding current and is driven to -24 V: the torque cannot
    # exceed the 24 V stall torque K_t (24/R) N eta by more than the holding torque margin
    assert sim.peak_torque <= P.stall_torque_at_fin(24.0) + 1e-9
    assert sim.peak_torque == pytest.approx(6.6, rel=0.05)     # thesis Fig 57, "approximately"
    # opposed all the way: slower than the 24 V no-load rate (602 deg/s)
    assert sim.peak_rate < P.no_load_rate_at_fin(24.0)
    assert math.degrees(sim.peak_rate) == pytest.approx(500, rel=0.05)   # thesis Fig 56
    assert sim.settling_time() < 0.05                                    # thesis Fig 55


def test_response_is_odd_in_the_command():
    a = simulate(P, SYSTEM_3, 10 * DEG, t_final=0.05, n_out=201)
    b = simulate(P, SYSTEM_3, -10 * DEG, t_final=0.05, n_out=201)
    np.testing.assert_allclose(a.theta, -b.theta, atol=1e-9)
    np.testing.assert_allclose(a.torque, -b.torque, atol=1e-6)


def test_thesis_current_limit_is_a_voltage_clip_that_never_binds_at_24_v():
    lim = PowerLimits(supply_voltage=None, current_limit=10.0)
    x = np.array([0.0, 0.0, 0.0])
    assert applied_voltage(P, lim, x, 100.0) == pytest.approx(10.0 * 5.78)     # Eqs. 4.14-4.15
    assert applied_voltage(P, THESIS_LIMITS, x, 100.0) == 24.0
    a = simulate(P, SYSTEM_3, 0.0, t_final=0.08, theta0=15 * DEG, limits=THESIS_LIMITS)
    b = simulate(P, SYSTEM_3, 0.0, t_final=0.08, theta0=15 * DEG,
                 limits=PowerLimits(current_limit=None))
    np.testing.assert_allclose(a.theta, b.theta, atol=1e-12)


def test_true_current_limit_holds_the_current():
    # 48 V supply, 3 A limit, no hinge moment, 30 deg reversal (braking against back-emf)
    kw = dict(t_final=0.1, theta0=15 * DEG, hinge_moment=no_hinge_moment)
    reg = simulate(P, SYSTEM_3, -15 * DEG, limits=PowerLimits(
        supply_voltage=48.0, current_limit=3.0, current_limit_model="regulator"), **kw)
    assert np.max(np.abs(reg.current)) <= 3.0 * 1.001
    assert np.max(np.abs(reg.current)) >= 3.0 * 0.999          # it binds
    clip = simulate(P, SYSTEM_3, -15 * DEG,
                    limits=PowerLimits(supply_voltage=48.0, current_limit=3.0), **kw)
    # the thesis's voltage clip (3 A x R = 17.3 V) lets back-emf push the current past 3 A
    assert np.max(np.abs(clip.voltage)) <= 3.0 * 5.78 + 1e-9
    assert np.max(np.abs(clip.current)) > 3.03
    # and, weaker than the regulator's full 48 V, it is slower
    assert clip.settling_time() > reg.settling_time()
    # the 24 V reference case never reaches 10 A: both models agree
    a = simulate(P, SYSTEM_3, 0.0, t_final=0.06, theta0=15 * DEG, limits=CURRENT_REGULATED_LIMITS)
    b = simulate(P, SYSTEM_3, 0.0, t_final=0.06, theta0=15 * DEG, limits=THESIS_LIMITS)
    np.testing.assert_allclose(a.theta, b.theta, atol=1e-9)


def test_feedback_signal_is_an_argument():
    # a feedback sensor reading `bias` too high makes the loop settle `bias` low
    bias = 0.5 * DEG
    x = np.array([0.1, 0.0, 0.0])
    d_true = actuator_rhs(P, SYSTEM_3, NO_LIMITS, x, 0.1, x[0], x[1], 0.0)
    d_bias = actuator_rhs(P, SYSTEM_3, NO_LIMITS, x, 0.1, x[0] + bias, x[1], 0.0)
    assert d_true[2] == pytest.approx(0.0)
    assert d_bias[2] == pytest.approx(-SYSTEM_3.gain * SYSTEM_3.kp * bias / P.motor.inductance)


def test_holding_current_balances_the_hinge_moment():
    x = np.array([0.2, 0.0, holding_current(P, 3.0)])
    assert motor_rhs(P, NO_LIMITS, x, 0.0, 3.0)[1] == pytest.approx(0.0, abs=1e-9)
    assert motor_torque_at_fin(P, x[2]) == pytest.approx(-3.0)


def test_zero_order_hold_converges_to_the_continuous_controller():
    cont = simulate(P, SYSTEM_3, 14 * DEG, t_final=0.06, n_out=301)
    fine = simulate(P, SYSTEM_3, 14 * DEG, t_final=0.06, n_out=301, sample_time=1e-4)
    khz = simulate(P, SYSTEM_3, 14 * DEG, t_final=0.06, n_out=301, sample_time=1e-3)
    err_fine = np.max(np.abs(fine.theta - cont.theta))
    err_khz = np.max(np.abs(khz.theta - cont.theta))
    assert err_fine < err_khz
    assert err_fine < 0.1 * DEG
    assert khz.settling_time() < 0.05          # the 1 kHz controller still meets 50 ms


def test_custom_hinge_moment_callable():
    calls = []

    def hm(t, theta, omega):
        calls.append(t)
        return -0.2 * omega              # pure damping at the fin
    sim = simulate(P, SYSTEM_3, 5 * DEG, t_final=0.06, hinge_moment=hm, n_out=101)
    assert calls and sim.theta[-1] == pytest.approx(5 * DEG, rel=1e-3)   # no steady error
    np.testing.assert_allclose(sim.hinge_moment, -0.2 * sim.omega)


@pytest.mark.parametrize("factory, word", [
    (lambda: PowerLimits(supply_voltage=0.0), "supply_voltage"),
    (lambda: PowerLimits(current_limit=-10.0), "current_limit"),
    (lambda: PowerLimits(current_limit_model="fuse"), "current_limit_model"),
    (lambda: SteadyHingeMoment(mach=-1.0), "mach"),
    (lambda: SteadyHingeMoment(q_cc=float("nan")), "q_cc"),
    (lambda: simulate(P, SYSTEM_3, 0.1, t_final=0.0), "t_final"),
    (lambda: simulate(P, SYSTEM_3, 0.1, sample_time=-1e-3), "sample_time"),
    (lambda: simulate(P, SYSTEM_3, 0.1, hinge_moment=3.0), "hinge_moment"),
])
def test_bad_input(factory, word):
    with pytest.raises(ValueError, match=word):
        factory()


def test_actuator_signals_agree_with_the_simulation():
    from asekit.servo.simulate import actuator_signals
    sim = simulate(P, SYSTEM_3, 0.0, t_final=0.02, theta0=15 * DEG, n_out=41)
    k = 10
    x = np.array([sim.theta[k], sim.omega[k], sim.current[k]])
    sig = actuator_signals(P, SYSTEM_3, THESIS_LIMITS, x, 0.0, x[0], x[1], sim.hinge_moment[k])
    assert sig.voltage == pytest.approx(sim.voltage[k])
    assert sig.torque == pytest.approx(sim.torque[k])
    assert sig.alpha == pytest.approx(sim.alpha[k])


def test_fin_inertia_through_the_hinge_moment_is_equivalent():
    # Ch. 5 recipe: a hinge moment -M theta'' with fin_inertia = 0 equals fin_inertia = M
    x = np.array([0.1, 2.0, 1.5])
    m_eff = 2.958e-4
    p0 = ActuatorParameters(fin_inertia=0.0)
    a = motor_rhs(P, NO_LIMITS, x, 10.0, 0.3)
    # solve alpha = f(T0 - M alpha) for the zero-inertia actuator by fixed point (linear)
    alpha = 0.0
    for _ in range(200):
        alpha = motor_rhs(p0, NO_LIMITS, x, 10.0, 0.3 - m_eff * alpha)[1]
    assert alpha == pytest.approx(a[1], rel=1e-9)


@pytest.mark.parametrize("sample_time", [None, 1e-3])
@pytest.mark.parametrize("limits", ["thesis", "regulator"])
def test_exact_propagation_agrees_with_rk45(limits, sample_time):
    # issue 12: with a constant command and the steady hinge moment the power-limited loop is
    # piecewise linear, so method="auto" propagates it exactly (matrix exponential per limit
    # region); it must agree with the RK45 integration (rtol 1e-8) of the same equations to
    # RK45's accuracy (measured <= 2e-6 of each history's peak; 1e-5 allowed). 15 deg steps
    # that saturate the 24 V supply; the regulator case with a 3 A limit that binds.
    lim = THESIS_LIMITS if limits == "thesis" else PowerLimits(
        current_limit=3.0, current_limit_model="regulator")
    kw = dict(t_final=0.08, theta0=15 * DEG, limits=lim, sample_time=sample_time,
              hinge_moment=SteadyHingeMoment())
    ex = simulate(P, SYSTEM_3, -15 * DEG, **kw)
    rk = simulate(P, SYSTEM_3, -15 * DEG, method="RK45", **kw)
    for name in ("theta", "omega", "current", "voltage", "alpha", "torque", "hinge_moment"):
        a, b = getattr(ex, name), getattr(rk, name)
        assert np.max(np.abs(a - b)) <= 1e-5 * np.max(np.abs(b)), name
    assert np.max(np.abs(ex.voltage)) == pytest.approx(24.0, rel=1e-12)   # the clip binds
    if limits == "regulator":
        assert 3.0 * 0.999 < np.max(np.abs(ex.current)) <= 3.0 * (1 + 1e-12)
    with pytest.raises(ValueError, match="method"):
        simulate(P, SYSTEM_3, lambda t: 0.1, method="exact")
    with pytest.raises(ValueError, match="method"):
        simulate(P, SYSTEM_3, 0.1, method="euler")
