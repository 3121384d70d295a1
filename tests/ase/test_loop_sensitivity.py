"""Derivatives of the AEM1 loop's matrices and margins (issue 28), against central
differences of the whole physics chain: perturbed modal M, K, C and GAF table -> Roger refit
-> :func:`asekit.ase.loop.build_model` -> FWTF 2 (:func:`asekit.ase.loop.forward_path`, an
independent assembly through python-control) -> refined crossovers."""

import numpy as np
import pytest

from asekit.aeroelastic.statespace import modal_arrays
from asekit.ase import loop as L
from asekit.ase.loop_sensitivity import aem1_loop, aem1_loop_derivatives, aem1_margin_sensitivity
from asekit.ase.margin_sensitivity import margin_sensitivities
from asekit.rfa.roger import roger_fit, roger_fit_derivative
from asekit.servo.actuator import SYSTEM_3, ActuatorParameters

RHO, U, B_REF = 1.0, 200.0, 0.05
W = (2 * np.pi, 2 * np.pi * 1e4)


def _model(coupling=0.03, f1=100.0):
    """Rigid pitch + 2 damped elastic modes, inertially coupled, with Theodorsen-shaped GAFs;
    coupling 0.03 at 100 Hz gives three gain crossovers (75, 106, 132 Hz)."""
    rng = np.random.default_rng(1)
    k = np.linspace(0.0, 1.2, 10)
    qb = 1e-4 * rng.normal(size=(4, 3, 3))
    lag = 1j * k / (1j * k + 0.3)
    Q = (qb[0] + 1j * k[:, None, None] * qb[1] - 0.1 * (k ** 2)[:, None, None] * qb[2]
         + lag[:, None, None] * qb[3])
    M = np.array([[2e-3, coupling, 1e-3], [coupling, 1.0, 0.0], [1e-3, 0.0, 1.0]])
    w = 2 * np.pi * np.array([f1, 900.0])
    K = np.diag([0.0, *w ** 2])
    C = np.diag([0.0, *(0.06 * w)])
    # one design direction: stiffer, heavier, different air loads
    dM = np.array([[1e-4, 2e-3, 0.0], [2e-3, 0.05, 0.01], [0.0, 0.01, 0.02]])
    dK = np.diag([0.0, 0.3 * w[0] ** 2, 0.1 * w[1] ** 2])
    dQ = 0.5 * Q + 1e-5 * (rng.normal(size=Q.shape) + 1j * rng.normal(size=Q.shape))
    return k, Q, M, K, C, dM, dK, dQ


def _margins_via_loop_module(k, Q, M, K, C):
    fit = roger_fit(k, Q, B_REF, n_lags=2)
    m = L.build_model(modal_arrays(M=M, K=K, C=C, n_rigid=1), fit, RHO, U,
                      {"fin_root_pitch": np.array([1.0, 0.2, -0.1])},
                      actuator=ActuatorParameters())
    fw = L.forward_path(m, SYSTEM_3, 2)
    return margin_sensitivities(np.array(fw.A), np.array(fw.B), np.array(fw.C),
                                np.array(fw.D), w_range=W, points=4000)


def test_loop_is_forward_path_2():
    k, Q, M, K, C, *_ = _model()
    fit = roger_fit(k, Q, B_REF, n_lags=2)
    lm = aem1_loop(M, K, C, fit, RHO, U, ActuatorParameters(), SYSTEM_3)
    m = L.build_model(modal_arrays(M=M, K=K, C=C, n_rigid=1), fit, RHO, U,
                      {"fin_root_pitch": np.array([1.0, 0.0, 0.0])}, actuator=ActuatorParameters())
    f = np.logspace(0, 4, 50)
    ref = L.frequency_response(L.forward_path(m, SYSTEM_3, 2), f)
    got = L.state_space_response(lm.A, lm.B, lm.C, lm.D, 2j * np.pi * f)[0, 0]
    assert np.abs(got - ref).max() < 1e-10 * np.abs(ref).max()
    assert lm.effective_fin_inertia == pytest.approx(m.effective_fin_inertia, rel=1e-12)


def test_matrix_derivative_matches_central_differences():
    k, Q, M, K, C, dM, dK, dQ = _model()
    fit = roger_fit(k, Q, B_REF, n_lags=2)
    dA = roger_fit_derivative(fit, dQ)
    act = ActuatorParameters()
    dF = aem1_loop_derivatives(M, K, C, fit, RHO, U, act, SYSTEM_3, dM=[dM], dK=[dK],
                               dA=[dA])[0]
    h = 1e-6

    def F(t):
        f = roger_fit(k, Q + t * dQ, B_REF, n_lags=2)
        return aem1_loop(M + t * dM, K + t * dK, C, f, RHO, U, act, SYSTEM_3).A

    fd = (F(h) - F(-h)) / (2 * h)
    assert np.abs(dF - fd).max() < 1e-6 * np.abs(fd).max()


def test_margin_derivatives_match_central_differences_of_the_chain():
    k, Q, M, K, C, dM, dK, dQ = _model()
    fit = roger_fit(k, Q, B_REF, n_lags=2)
    s = aem1_margin_sensitivity(M, K, C, fit, RHO, U, ActuatorParameters(), SYSTEM_3,
                                dM=[dM], dK=[dK], dA=[roger_fit_derivative(fit, dQ)])
    assert s.phase_margins_deg.size == 3          # the three crossovers of _model's docstring
    h = 1e-5
    plus = _margins_via_loop_module(k, Q + h * dQ, M + h * dM, K + h * dK, C)
    minus = _margins_via_loop_module(k, Q - h * dQ, M - h * dM, K - h * dK, C)
    base = _margins_via_loop_module(k, Q, M, K, C)
    assert np.allclose(base.phase_margins_deg, s.phase_margins_deg, rtol=1e-9)
    fd_pm = (plus.phase_margins_deg - minus.phase_margins_deg) / (2 * h)
    fd_wc = (plus.gain_crossovers_rad_s - minus.gain_crossovers_rad_s) / (2 * h)
    rel_pm = np.abs(s.d_phase_margins_deg[0] - fd_pm) / np.abs(fd_pm)
    rel_wc = np.abs(s.d_gain_crossovers_rad_s[0] - fd_wc) / np.abs(fd_wc)
    assert rel_pm.max() < 1e-4 and rel_wc.max() < 1e-4, (rel_pm, rel_wc)


def test_bad_input_names_the_argument():
    k, Q, M, K, C, dM, *_ = _model()
    fit = roger_fit(k, Q, B_REF, n_lags=2)
    act = ActuatorParameters()
    with pytest.raises(ValueError, match="K must be finite"):
        aem1_loop(M, K[:2, :2], C, fit, RHO, U, act, SYSTEM_3)
    with pytest.raises(ValueError, match="dM has 1 derivatives, expected 2"):
        aem1_loop_derivatives(M, K, C, fit, RHO, U, act, SYSTEM_3, dM=[dM], dK=[dM, dM])
    with pytest.raises(ValueError, match="rfa must be a RogerFit"):
        aem1_loop(M, K, C, object(), RHO, U, act, SYSTEM_3)
