"""Two-degree-of-freedom H-infinity design, reduction, discretisation and the mu certificate
(asekit.ase.robust) on small plants with known answers; the fin's design is checked in
tests/reproduction/test_design_hinf.py."""

import math

import control as ct
import numpy as np
import pytest

from asekit.ase import robust
from asekit.ase.robust import Uncertainty


def motor():
    """1 / (s (0.02 s + 1)) rad/V: a DC motor with a 20 ms mechanical time constant."""
    return ct.ss(ct.tf([1.0], [0.02, 1.0, 0.0]))


def test_weights_from_table2():
    w = robust.weights_from_requirements(settling=0.05, steady_error=0.02, model_fraction=0.5)
    # critically damped 2nd order: (1 + x) exp(-x) = 0.02 at x = 5.834
    x = w.reference_rad_s * 0.025
    assert (1 + x) * math.exp(-x) == pytest.approx(0.02, rel=1e-3)
    assert w.integral == pytest.approx(1e-3) and w.voltage == pytest.approx(1e-3)
    low = robust.weights_from_requirements(voltage_weight=1e-6, voltage_limit=24.0)
    assert low.voltage == pytest.approx(math.radians(1) / 24)     # 1 deg may use the supply
    with pytest.raises(ValueError, match="model_fraction"):
        robust.weights_from_requirements(model_fraction=1.5)


def test_hinf_2dof_tracks_without_overshoot():
    w = robust.weights_from_requirements(settling=0.2, rolloff=None)
    d = robust.hinf_2dof(motor(), w, delay=0.0, design_order=None)
    K = d.continuous
    # closed loop: u = K_r r + K_y y
    P = motor()
    Kr, Ky = K[0, 0], K[0, 1]
    T = ct.ss(ct.feedback(P, ct.ss(Ky), sign=+1)) * ct.ss(Kr)
    assert ct.isctime(T) and np.all(np.real(ct.poles(T)) < 0)
    t = np.linspace(0, 0.5, 501)
    y = ct.step_response(T, t).outputs
    assert abs(y[-1] - 1) < 0.02                           # the near-integrator
    assert y.max() < 1.05                                  # the critically damped model
    ts = t[np.nonzero(np.abs(y - y[-1]) > 0.02)[0][-1]]
    assert ts < 0.2


def _fr(sys, z):
    A, B, C, D = (np.array(x) for x in (sys.A, sys.B, sys.C, sys.D))
    return C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B) + D


def test_discretise_integrator_state():
    """(s + 5) / (s + 1e-3) (r - y): the near-integrator becomes state 0, decoupled, and the
    transform keeps the frequency response of the Tustin controller."""
    K = ct.ss(ct.tf([[[1.0, 5.0], [-1.0, -5.0]]], [[[1.0, 1e-3], [1.0, 1e-3]]]))
    c = robust.discretise(K, 1e-3)
    assert c.integrator_states == (0,)
    A = np.array(c.ss.A)
    assert abs(A[0, 0] - 1) < 1e-2 and np.allclose(A[1:, 0], 0, atol=1e-12) \
        and np.allclose(A[0, 1:], 0, atol=1e-12)
    Kd = ct.sample_system(K, 1e-3, method="tustin")
    z = np.exp(1j * 2 * np.pi * 3.0 * 1e-3)
    assert np.allclose(_fr(Kd, z), _fr(c.ss, z)[:, :2])
    with pytest.raises(ValueError, match="inputs"):
        robust.discretise(ct.ss(ct.tf([1.0], [1.0, 1.0])), 1e-3)


def test_rank_factors():
    r = np.random.default_rng(0)
    dA = r.standard_normal((5, 2)) @ r.standard_normal((2, 5))
    U, V = robust.rank_factors(dA)
    assert U.shape == (5, 2) and np.allclose(U @ V.T, dA)
    with pytest.raises(ValueError, match="zero"):
        robust.rank_factors(np.zeros((3, 3)))


def test_mu_of_a_parametric_loop_is_its_exact_margin():
    """x' = a x + b u, u = -k y: the loop pole is a - k b. With a uncertain, a = a0 + delta da,
    the loop is stable while delta < (k b - a0) / da: mu_peak (at w = 0) = da / (k b - a0)."""
    a0, da, b, k = 1.0, 2.0, 1.0, 5.0
    unc = Uncertainty(parameters=(("a", np.array([[da]])),))
    r = robust.robust_stability(np.array([[a0]]), np.array([[b]]), np.array([[1.0]]),
                                lambda w: -k, unc, np.linspace(0.0, 5.0, 51), delay=0.0)
    assert r["mu_peak"] == pytest.approx(da / (k * b - a0), rel=1e-6)
    assert r["f_peak_hz"] == 0.0 and r["margin"] == pytest.approx(2.0, rel=1e-6)


def test_cover_block_small_gain():
    """A complex multiplicative block alone: mu = |w_f T| (Skogestad & Postlethwaite Eq. 7.33),
    T = -L / (1 - L) with u = L y (positive feedback convention of loop_matrix)."""
    A, B, C = np.array([[-1.0]]), np.array([[1.0]]), np.array([[1.0]])
    f = np.array([0.0, 0.1, 1.0])
    unc = Uncertainty(cover_hz=f, cover=np.full(3, 0.5))
    r = robust.robust_stability(A, B, C, lambda w: -4.0, unc, f, delay=0.0)
    L = np.array([-4.0 / (2j * np.pi * x + 1) for x in f])
    assert np.allclose(r["upper"], 0.5 * np.abs(L / (1 - L)), rtol=1e-6)


def test_without_slycot_the_error_names_the_pip_line(monkeypatch):
    import sys

    from asekit.util.extras import MissingExtra
    P, w = motor(), robust.weights_from_requirements()        # (python-control uses slycot)
    monkeypatch.setitem(sys.modules, "slycot", None)          # import slycot -> ImportError
    with pytest.raises(MissingExtra, match=r"pip install 'asekit-aero\[robust\]'"):
        robust.hinf_2dof(P, w, delay=0.0)


def test_real_parameters_of_a_resonance_mixed_bound_is_exact():
    """x'' + 2 z w0 (1 + rho d2) x' + w0^2 (1 + kappa d1) x = 0 is stable while both
    coefficients stay positive (Routh, second order): |d1| < 1/kappa and |d2| < 1/rho
    independently, so real mu = max(kappa, rho) (reached by the damping near w0). The complex
    bound sees the stiffness block as j kappa / (2 z) at resonance (a complex perturbation is
    negative damping) and is 1/(2 z) times too large; the loop matrix is rank one, where the
    D-G bound is exact (Young 1994)."""
    w0, z, kappa, rho = 2 * math.pi * 10.0, 0.02, 0.5, 0.8
    A = np.array([[0.0, 1.0], [-w0 ** 2, -2 * z * w0]])
    unc = Uncertainty(parameters=(("stiffness", np.array([[0.0, 0.0], [-kappa * w0 ** 2, 0.0]])),
                                  ("damping", np.array([[0.0, 0.0], [0.0, -rho * 2 * z * w0]]))))
    f = np.array([0.0, 3.0, 9.0, 10.0, 10.5, 13.0, 20.0])
    B, C = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    r = robust.robust_stability(A, B, C, lambda w: 0.0, unc, f, delay=0.0)
    # at s = j w a root needs w0^2 (1 + kappa d1) = w^2 and (for w > 0) zero damping, d2 =
    # -1/rho: mu(w) = 1 / max(1/rho, |(w/w0)^2 - 1| / kappa) (kappa at w = 0: no damping term)
    exact = 1 / np.maximum(1 / rho, np.abs((f / 10.0) ** 2 - 1) / kappa)
    assert np.allclose(r["upper"], exact, rtol=1e-3)
    assert r["mu_peak"] == pytest.approx(max(kappa, rho), rel=1e-3)
    from asekit.ase.mu import upper_bound
    complex_peak = max(upper_bound(M, r["blocks"])[0] for M in r["M"])
    assert complex_peak > 0.9 * kappa / (2 * z)
