"""The aeroservoelastic interconnection (thesis Ch. 5): independent paths must agree, physical
limits must hold, bad input must be refused."""

import math

import control as ct
import numpy as np
import pytest

from asekit import ase, metrics
from asekit.servo import SYSTEM_3, ActuatorParameters, PDController, actuator_transfer_function
from asekit.servo import margins as servo_margins
from asekit.reproduction import fin as reffin


@pytest.fixture(scope="module")
def fin():
    return reffin.fin_ase(mach=0.5, altitude=0.0)


def test_oploop1_is_eq_2_41(fin):
    # OPLOOP 1 must be the thesis's actuator transfer function, Eq. (2.41), of the same actuator
    f = np.array([1.0, 10.0, 100.0, 1000.0])
    h = ase.frequency_response(ase.open_loop(fin.model, 1), f)
    ref = ase.frequency_response(actuator_transfer_function(fin.model.actuator), f)
    np.testing.assert_allclose(h, ref, rtol=1e-9)


def test_oploop2_low_frequency_sees_the_whole_fin_inertia(fin):
    # Well below the first elastic mode (~90 Hz) the elastic fin follows the transmission
    # rigidly, so with the air removed the transmission must feel the fin's full pitch inertia
    # J_fin (= M_cc), although the actuator itself carries only the tiny effective inertia.
    vac = ase.build_model(fin.modal, fin.rfa, 1e-9, fin.velocity, _rows(fin), mach=0.5)
    f = np.array([2.0, 5.0, 10.0])
    h = ase.frequency_response(ase.open_loop(vac, 2), f)
    rigid = ActuatorParameters(fin_inertia=float(fin.modal.J_fin))
    ref = ase.frequency_response(actuator_transfer_function(rigid), f)
    np.testing.assert_allclose(np.abs(h), np.abs(ref), rtol=2e-3)
    assert vac.effective_fin_inertia < 0.01 * fin.modal.J_fin


def _rows(f):
    from asekit.aeroelastic import fin_outputs
    from asekit.reproduction.fin import load_fin

    return fin_outputs(f.modal, np.array([[0.156, 0.15]]), names=["tip_te"],
                       shaft_point=load_fin().shaft.axis_point)


def test_fwtf1_with_rigid_fin_matches_chapter_4_margins(fin):
    # crossovers() (grid + interpolation) against python-control's stability_margins on the
    # Ch. 4 design loop, whose load is the rigid fin's inertia
    rigid = ase.build_model(fin.modal, fin.rfa, fin.density, fin.velocity, _rows(fin),
                            actuator=ActuatorParameters(), count_fin_inertia_twice=True)
    c = ase.crossovers(ase.forward_path(rigid, SYSTEM_3, 1))
    ref = servo_margins(ActuatorParameters(), SYSTEM_3)
    assert c.phase_margin_deg == pytest.approx(ref.phase_margin_deg, abs=0.01)
    assert c.gain_margin_db == math.inf


def test_crossovers_of_an_analytic_loop():
    # L = 4 / (s (s + 1)): |L| = 1 at w^4 + w^2 - 16 = 0, PM = 180 - 90 - atan(w)
    w = math.sqrt((-1 + math.sqrt(65)) / 2)
    c = ase.crossovers(ct.tf([4.0], [1.0, 1.0, 0.0]), np.logspace(-3, 1, 20000) / (2 * np.pi))
    assert c.gain_crossovers_hz[0] == pytest.approx(w / (2 * np.pi), rel=1e-5)
    assert c.phase_margin_deg == pytest.approx(90 - math.degrees(math.atan(w)), abs=1e-3)
    # a third-order loop has a phase crossover at w = 1 for 1/(s+1)^3 with GM 20 log10(8/K)
    c3 = ase.crossovers(ct.tf([2.0], [1, 3, 3, 1]), np.logspace(-2, 2, 20000) / (2 * np.pi))
    assert c3.phase_crossovers_hz[0] == pytest.approx(math.sqrt(3) / (2 * np.pi), rel=1e-5)
    assert c3.gain_margin_db == pytest.approx(20 * math.log10(8 / 2), abs=1e-4)


@pytest.mark.parametrize("topology, t_final", [("AEM1", 0.1), ("AEM2", 0.04)])
def test_linear_interconnection_equals_direct_simulation(fin, topology, t_final):
    # Two independent paths: python-control's interconnect + feedback (state space) and the
    # direct right-hand side used by the nonlinear simulation, with the limits removed.
    cmd = math.radians(1.0)
    sim = ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, topology, limits=None,
                                   t_final=t_final, n_out=401, max_step=2e-5)
    cl = ase.closed_loop(fin.model, SYSTEM_3, topology, outputs=["theta", ase.FIN_ROOT,
                                                                  "theta_tip_te", "current"])
    resp = ct.forced_response(cl, sim.t, np.full(sim.t.size, cmd))
    y = np.asarray(resp.outputs)
    scale = np.max(np.abs(y), axis=1)
    for i, hist in enumerate([sim.theta, sim.fin_root, sim.outputs["theta_tip_te"],
                              sim.current]):
        assert np.max(np.abs(hist - y[i])) < 2e-3 * scale[i]


def test_closed_loop_static_torque_balance(fin):
    # At rest, the motor torque at the fin K_t I N eta balances the hinge moment, and the
    # voltage equals R I (no back-emf at rest).
    cl = ase.closed_loop(fin.model, SYSTEM_3, "AEM1",
                         outputs=["current", "voltage", "hinge_moment"])
    i, v, hm = np.asarray(ct.dcgain(cl)).ravel()
    act = fin.model.actuator
    tr = act.transmission
    assert act.motor.torque_constant * i * tr.ratio * tr.efficiency == pytest.approx(-hm,
                                                                                   rel=1e-8)
    assert v == pytest.approx(act.motor.resistance * i, rel=1e-8)


def test_thesis_behaviour_aem1_stable_aem2_unstable(fin):
    # Thesis Sec. 5.3: the encoder loop (AEM1) is stable, the fin-root loop (AEM2) is not
    assert ase.is_stable(ase.closed_loop(fin.model, SYSTEM_3, "AEM1"))
    assert not ase.is_stable(ase.closed_loop(fin.model, SYSTEM_3, "AEM2"))


def test_power_limits_hold_and_bound_the_aem2_oscillation(fin):
    r = ase.simulate_closed_loop(fin.model, SYSTEM_3, math.radians(1.0), "AEM2", t_final=0.15)
    assert np.max(np.abs(r.voltage)) <= 24.0 + 1e-9
    amp, freq = metrics.limit_cycle(r.t, r.fin_root)
    assert math.isfinite(amp) and amp < math.radians(10.0)      # bounded: a limit cycle
    assert 60.0 < freq < 200.0                                   # near the first elastic mode


def test_spectrum_and_limit_cycle_of_known_signals():
    t = np.linspace(0, 0.5, 20001)
    y = 1.0 + 0.1 * np.sin(2 * np.pi * 90 * t) + 0.05 * np.sin(2 * np.pi * 150 * t)
    y[0] = 0.0                       # starts at rest, reaches 95 % of the command at once
    f, amp = metrics.spectrum_after_rise(t, y, 1.0)
    assert metrics.spectrum_peaks(f, amp, n=2) == pytest.approx([90.0, 150.0], abs=0.5)
    a, fr = metrics.limit_cycle(t, 0.2 * np.sin(2 * np.pi * 92 * t))
    assert a == pytest.approx(0.2, rel=1e-3)
    assert fr == pytest.approx(92.0, rel=1e-3)


def test_bad_input(fin):
    with pytest.raises(ValueError, match="topology"):
        ase.closed_loop(fin.model, SYSTEM_3, "AEM3")
    with pytest.raises(ValueError, match="PDController"):
        ase.forward_path(fin.model, (10.0, 275.0, 1.0), 1)
    with pytest.raises(ValueError, match="angular position limit"):
        ase.simulate_closed_loop(fin.model, SYSTEM_3, math.radians(20.0), "AEM1")
    with pytest.raises(ValueError, match="mach"):
        reffin.fin_ase(mach=0.9)
    with pytest.raises(ValueError, match="which"):
        ase.open_loop(fin.model, 4)
    with pytest.raises(ValueError, match="finite"):
        PDController(math.nan, 1.0, 1.0)


def test_digital_controller_tends_to_the_continuous_one(fin):
    # a zero-order-hold PD sampled fast enough must reproduce the continuous loop; at 1 kHz
    # (thesis Table 2) it differs visibly but stays bounded
    cmd = math.radians(1.0)
    cont = ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1", t_final=0.03, n_out=301)
    fast = ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1", t_final=0.03, n_out=301,
                                    sample_time=1e-5)
    slow = ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1", t_final=0.03, n_out=301,
                                    sample_time=1e-3)
    assert np.max(np.abs(fast.theta - cont.theta)) < 2e-3 * cmd
    assert np.max(np.abs(slow.theta - cont.theta)) > 1e-2 * cmd
    assert np.max(np.abs(slow.voltage)) <= 24.0 + 1e-9
    with pytest.raises(ValueError, match="sample_time"):
        ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1", sample_time=-1.0)
