"""Digital controllers and the sampled aeroservoelastic loop (issue 15): the sampled simulation
against the independent nonlinear integrator of asekit.ase.loop, filters, stability by eigenvalues,
the unstable-pole overshoot constraint. (The designs of the design chapter against thesis
Table 2 and its perturbed modal models: tests/reproduction/test_design_chapter.py.)"""

import math

import control as ct
import numpy as np
import pytest

from asekit.ase import loop as ase
from asekit.ase import metrics
from asekit.servo.actuator import SYSTEM_3
from asekit.servo.controllers import lowpass, notch, pd_controller, pid_filtered


@pytest.fixture(scope="module")
def model(fin_ase):
    """The fin's ASE model at Mach 0.5, sea level (tests/conftest.py, via the case pipeline)."""
    return fin_ase.model


def _dc_gains(plant, controller, names, delay):
    """Exact steady-state gains of the sampled linear loop from the command to ``names``: the
    fixed point x = (I - Phi)^-1 Gamma of the closed-loop recursion x+ = Phi x + Gamma r
    (:func:`asekit.ase.loop.closed_loop_sampled_matrix`), the plant's part read through C."""
    Phi, Gam = ase.closed_loop_sampled_matrix(plant, controller, delay)
    x = np.linalg.solve(np.eye(Phi.shape[0]) - Phi, Gam)[:plant.Ad.shape[0], 0]
    outs = plant.output_names
    return {n: float(plant.C[outs.index(n)] @ x) for n in names}


def test_sampled_simulation_matches_the_nonlinear_integrator(model):
    # the same digital PD (1 kHz ZOH, no computational delay, backward-difference derivative)
    # by asekit.ase.loop.simulate_closed_loop (solve_ivp over each sample, voltage clip inside the
    # motor equations) and by the exact discretisation with the clip on the held voltage
    cmd = math.radians(1.0)
    ref = ase.simulate_closed_loop(model, SYSTEM_3, cmd, "AEM1", t_final=0.03, n_out=301,
                                   sample_time=1e-3, method="RK45")
    plant = ase.sampled_plant(model, "AEM1", 1e-3)
    r = ase.simulate_sampled(plant, pd_controller(10.0, 275.0, 1.0), cmd, t_final=0.03,
                             delay_samples=0)
    for name, y_ref in (("theta", ref.theta), (ase.FIN_ROOT, ref.fin_root)):
        y = np.interp(ref.t[:-1], r.t, r.outputs[name])
        assert np.max(np.abs(y - y_ref[:-1])) < 1e-3 * cmd
    assert np.max(np.abs(r.voltage)) == pytest.approx(24.0)      # the clip acts


def test_eigenvalues_decide_stability_and_the_dc_gain(model):
    # System 3 on the 1 kHz processor: stable without the computational delay on AEM1, unstable
    # with one sample of delay (a linear simulation grows); the eigenvalue verdict agrees
    plant = ase.sampled_plant(model, "AEM1", 1e-3)
    s3 = pd_controller(10.0, 275.0, 1.0)
    assert ase.is_stable_sampled(plant, s3, delay_samples=0)
    assert not ase.is_stable_sampled(plant, s3, delay_samples=1)
    lin = dict(limits=None, t_final=0.3)
    grow = ase.simulate_sampled(plant, s3, math.radians(0.1), delay_samples=1, **lin)
    assert np.max(np.abs(grow.outputs["theta"][-300:])) > 10 * math.radians(0.1)
    ok = ase.simulate_sampled(plant, s3, math.radians(0.1), delay_samples=0, **lin)
    g = _dc_gains(plant, s3, ["theta"], delay=0)["theta"]
    # mean over the last 20 ms: the 149 Hz mode still rings (damping ratio ~0.004)
    late = ok.t >= ok.t[-1] - 0.02
    assert np.mean(ok.outputs["theta"][late]) / math.radians(0.1) == pytest.approx(g, rel=1e-3)


def test_filters():
    f0 = 91.3
    n = notch(f0, 0.05, 0.5)
    w0 = 2 * np.pi * f0
    assert abs(n(1j * w0)) == pytest.approx(0.1, rel=1e-9)       # depth zeta_z / zeta_p
    assert abs(n(1j * 1e-3 * w0)) == pytest.approx(1.0, abs=1e-5)
    assert abs(n(1j * 1e3 * w0)) == pytest.approx(1.0, abs=1e-5)
    lp = lowpass(50.0, 0.7)
    assert abs(lp(2j * np.pi * 50.0)) == pytest.approx(1 / 1.4, rel=1e-9)   # 1/(2 zeta)
    # Tustin with prewarping keeps the notch's frequency and depth in the discrete filter
    c = pid_filtered(1.0, 0.0, 0.0, 1e-3, None, [(f0, 0.05, 0.5)], 1e-3, setpoint_weight=1.0)
    A, B, C, D = (np.array(x) for x in (c.ss.A, c.ss.B, c.ss.C, c.ss.D))
    z = np.exp(1j * w0 * 1e-3)
    h = (C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B[:, :1]) + D[:, :1])[0, 0]
    assert abs(h) == pytest.approx(0.1, rel=1e-6)


def test_pid_feedback_path_matches_its_continuous_prototype():
    c = pid_filtered(200.0, 6000.0, 2.0, 2e-3, 80.0, [(91.3, 0.05, 0.5)], 1e-3)
    A, B, C, D = (np.array(x) for x in (c.ss.A, c.ss.B, c.ss.C, c.ss.D))
    for f in (1.0, 10.0, 30.0):
        z = np.exp(2j * np.pi * f * 1e-3)
        hy = -(C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B[:, 1:2]) + D[:, 1:2])[0, 0]
        hc = ase.frequency_response(c.continuous, [f])[0]
        assert abs(hy / hc - 1) < 0.03 * max(1.0, f / 10)        # Tustin warping, O((wT)^2)


def test_one_degree_of_freedom_loop_obeys_the_unstable_pole_constraint(model):
    # Middleton (Automatica 27(2), 1991): with an open-loop unstable real pole p, the error of
    # a 1-DOF unity-feedback loop satisfies int e(t) exp(-p t) dt = 0, hence overshoot
    ol = ase.open_loop(model, 3)
    poles = ct.poles(ol)
    p = float(np.max(poles.real))
    assert 5.0 < p < 50.0                                # the de-centering pole (~15 rad/s)
    k = ct.tf([2.0 * 0.012, 2.0 * 1.0 * 150.0], [0.0005, 1.0]) * ct.ss(lowpass(200.0))
    loop = ct.feedback(ct.ss(k) * ol, 1)
    assert np.all(ct.poles(loop).real < 0)
    t = np.linspace(0, 1.0, 200001)
    y = ct.step_response(loop, t).outputs.ravel()
    e = 1.0 - y
    integral = np.trapezoid(e * np.exp(-p * t), t)
    assert abs(integral) < 1e-3 * np.trapezoid(np.abs(e) * np.exp(-p * t), t)
    assert metrics.overshoot(y, 1.0) > 0.05


def test_bad_input(model):
    with pytest.raises(ValueError, match="cutoff_hz"):
        ase.SensorModel(cutoff_hz=-1.0)
    plant = ase.sampled_plant(model, "AEM2", 1e-3)
    with pytest.raises(ValueError, match="15"):
        ase.simulate_sampled(plant, pd_controller(1, 1, 0), math.radians(20.0))
    with pytest.raises(ValueError, match="dt"):
        ase.simulate_sampled(plant, pd_controller(1, 1, 0, sample_time=2e-3), 0.01)
    with pytest.raises(ValueError, match="topology"):
        ase.sampled_plant(model, "AEM3")
    with pytest.raises(ValueError, match="zeta_zero"):
        notch(90.0, 0.6, 0.5)
