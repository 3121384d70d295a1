"""Torque requirement, thesis Sec. 4.1.1 (Eqs. 4.1-4.12, Figs 40-43)."""

import math

import numpy as np
import pytest

from asekit.servo.torque_requirement import (
    SecondOrderProfile,
    dynamic_pressure,
    profile_rhs,
    profile_step,
    required_stall_torque,
    tune_rate_limit,
)

STEP = math.radians(15.0)


def test_dynamic_pressure_sea_level_mach_06():
    # 0.5 * 1.225 * (0.6 * 340.294)^2 (1976 standard atmosphere)
    assert dynamic_pressure(0.6) == pytest.approx(25533.9, abs=0.1)
    assert dynamic_pressure(0.0) == 0.0


def test_unlimited_profile_is_the_critically_damped_second_order_system():
    # Eq. 4.8 with zeta = 1: y = r (1 - (1 + w t) exp(-w t)), y'' (0) = w^2 r
    prof = SecondOrderProfile(natural_frequency=157.0, damping_ratio=1.0)
    r = profile_step(prof, STEP, t_final=0.06)
    w = 157.0
    exact = STEP * (1 - (1 + w * r.t) * np.exp(-w * r.t))
    np.testing.assert_allclose(r.theta, exact, atol=1e-9)
    assert r.peak_acceleration == pytest.approx(w**2 * STEP, rel=1e-9)
    # 2 % settling of a critically damped system: w t_s = 5.834 (root of (1+x)e^-x = 0.02)
    assert r.settling_time * w == pytest.approx(5.8335, abs=1e-3)


def test_rate_limited_profile_peak_acceleration_and_rate():
    v_max = math.radians(400.0)
    prof = SecondOrderProfile(rate_limit=v_max)
    r = profile_step(prof, STEP, t_final=0.1)
    # the dynamic acceleration limit 2 zeta w (v_max - |y'|) peaks at t = 0
    assert r.peak_acceleration == pytest.approx(2 * 157.0 * v_max, rel=1e-9)
    assert np.max(np.abs(r.omega)) <= v_max * (1 + 1e-9)
    assert r.overshoot == 0.0
    # rate-limited profiles are slower than the linear one
    assert r.settling_time > profile_step(SecondOrderProfile(), STEP).settling_time


def test_profile_is_odd_in_the_command():
    prof = SecondOrderProfile(rate_limit=math.radians(500.0))
    a, b = profile_step(prof, STEP), profile_step(prof, -STEP)
    np.testing.assert_allclose(a.theta, -b.theta, atol=1e-12)


def test_position_limit_clips_the_command():
    prof = SecondOrderProfile(rate_limit=math.radians(500.0))
    r = profile_step(prof, math.radians(25.0), t_final=0.2)
    assert np.max(r.theta) <= prof.position_limit * (1 + 1e-9)
    assert profile_rhs(prof, 1.0, (prof.position_limit, 0.0))[1] == 0.0


def test_tuned_profile_settles_in_50_ms_and_compares_with_fig_43():
    prof = tune_rate_limit()
    r = profile_step(prof, STEP, t_final=0.1)
    assert r.settling_time == pytest.approx(0.05, abs=1e-5)
    assert r.overshoot == 0.0
    # thesis Fig 43: 157100 deg/s^2. asekit's reconstruction (2 % band, smallest rate limit)
    # gives about 139300 deg/s^2: within 15 % (the thesis's exact limits are lost with Eq. 4.9)
    assert math.degrees(r.peak_acceleration) == pytest.approx(157100, rel=0.15)
    # a tighter band needs a faster profile
    tighter = tune_rate_limit(band=0.01)
    assert tighter.rate_limit > prof.rate_limit


def test_required_torque_eq_4_11():
    # Eq. 4.11 with the thesis's own 157100 deg/s^2: J a + q Q_cc theta_max
    t = required_stall_torque(math.radians(157100.0))
    assert t.inertial == pytest.approx(math.radians(157100.0) * 2.958e-4)
    assert t.aerodynamic == pytest.approx(25533.9 * 5.825e-4 * STEP, rel=1e-5)
    # thesis Eq. 4.12: 4.74 N m; its speed of sound is not stated (ISA gives 4.705)
    assert t.required == pytest.approx(4.74, rel=0.01)
    assert t.design == 6.0          # x 1.25, "taken as 6 N m"


def test_design_rounding_and_safety_factor():
    t = required_stall_torque(0.0, round_up_to=0.0, safety_factor=1.0)
    assert t.design == pytest.approx(t.required)
    assert required_stall_torque(0.0, round_up_to=0.5).design == 5.0


@pytest.mark.parametrize("factory, word", [
    (lambda: dynamic_pressure(-0.1), "mach"),
    (lambda: dynamic_pressure(0.6, density=0.0), "density"),
    (lambda: SecondOrderProfile(natural_frequency=0.0), "natural_frequency"),
    (lambda: SecondOrderProfile(damping_ratio=-1.0), "damping_ratio"),
    (lambda: SecondOrderProfile(rate_limit=0.0), "rate_limit"),
    (lambda: profile_step(SecondOrderProfile(), 0.0), "step"),
    (lambda: profile_step(SecondOrderProfile(), STEP, band=1.5), "band"),
    (lambda: tune_rate_limit(natural_frequency=50.0), "settling_time"),
    (lambda: required_stall_torque(-1.0), "max_acceleration"),
    (lambda: required_stall_torque(1.0, safety_factor=0.5), "safety_factor"),
])
def test_bad_input(factory, word):
    with pytest.raises(ValueError, match=word):
        factory()
