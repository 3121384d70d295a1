"""State-space aeroelastic model (Eqs. 2.63-2.70): frequency-domain identity with Eq. (2.44),
U -> 0 limit, quasi-steady hand-derived case, static hinge moment, outputs, bad input."""

import numpy as np
import pytest

from asekit.aeroelastic.statespace import (
    aeroelastic_matrices,
    aeroelastic_model,
    modal_arrays,
    rotation_rows,
)
from asekit.rfa import RogerFit, roger_fit


def _model(seed=0, ns=3, lags=(0.2, 0.9)):
    """A rigid pitch mode (M_cc = J, K_cc = 0) coupled by inertia to ns mass-normalised elastic
    modes, and a Roger function with random coefficients (b = 0.078 m)."""
    rng = np.random.default_rng(seed)
    n = ns + 1
    M = np.eye(n)
    M[0, 0] = 2.5e-4
    M[0, 1:] = M[1:, 0] = 1e-3 * rng.normal(size=ns)
    w = 2 * np.pi * np.array([87.0, 160.0, 560.0])[:ns]
    K = np.zeros((n, n))
    K[1:, 1:] = np.diag(w ** 2)
    C = np.zeros((n, n))
    C[1:, 1:] = np.diag(2 * 0.01 * w)
    A = 1e-4 * rng.normal(size=(3 + len(lags), n, n))
    k = np.geomspace(1e-3, 3.0, 14)
    fit = RogerFit(A=A, lag_roots=np.array(lags), b_ref=0.078, k=k, Q=np.zeros((14, n, n)),
                   element_error=np.zeros((n, n)), fit_error=0.0)
    return modal_arrays(M=M, K=K, C=C, n_rigid=1), fit


def _reference_response(modal, fit, rho, U, s):
    """Hinge moment and elastic coordinates per unit theta from Eq. (2.44) directly."""
    q = 0.5 * rho * U ** 2
    Z = s ** 2 * modal.M + s * modal.C + modal.K - q * fit.evaluate_laplace(s, U)
    zeta_s = -np.linalg.solve(Z[1:, 1:], Z[1:, 0])
    t_fin = Z[0, 0] + Z[0, 1:] @ zeta_s
    return -t_fin, zeta_s                       # Eq. (2.49): T_hinge = -T_fin


@pytest.mark.parametrize("s", [2j * np.pi * 30.0, 2j * np.pi * 150.0, -50 + 2j * np.pi * 400.0])
def test_state_space_reproduces_eq_2_44(s):
    modal, fit = _model()
    rho, U = 1.225, 250.0
    sys = aeroelastic_model(modal, fit, rho, U)
    H = sys(s)                                   # (outputs, inputs)
    u = np.array([1.0, s, s ** 2])               # theta, theta_dot, theta_ddot per unit theta
    y = H @ u
    hinge_ref, zeta_ref = _reference_response(modal, fit, rho, U, s)
    assert sys.output_labels[0] == "hinge_moment"
    assert list(sys.input_labels) == ["theta", "theta_dot", "theta_ddot"]
    np.testing.assert_allclose(y[0], hinge_ref, rtol=1e-8)
    np.testing.assert_allclose(y[1:4], zeta_ref, rtol=1e-8, atol=1e-14)


def test_u_to_zero_gives_structural_poles():
    modal, fit = _model()
    mats = aeroelastic_matrices(modal, fit, 1.225, 1e-3)
    ev = np.linalg.eigvals(mats.A)
    osc = np.sort(ev[ev.imag > 1.0].imag) / (2 * np.pi)
    expected = np.array([87.0, 160.0, 560.0]) * np.sqrt(1 - 0.01 ** 2)
    np.testing.assert_allclose(osc, expected, rtol=1e-5)
    # lag roots at -(U/b) beta_n, one per elastic mode and one per hinge state
    lag = np.sort(ev[np.abs(ev.imag) < 1e-9].real)
    assert lag.size == 2 * 3 + 2
    np.testing.assert_allclose(np.unique(np.round(lag, 8)),
                               np.sort(-1e-3 / 0.078 * np.array([0.9, 0.2])), rtol=1e-6)


def test_quasi_steady_reduces_to_hand_derived_model():
    """No lags, constant real GAF A0: z = [zeta, zeta_dot], A = [[0, I], [-M^-1 (K - q A0), 0]]."""
    modal, fit = _model(lags=())
    A = np.zeros_like(fit.A)
    A[0] = fit.A[0]
    qs = RogerFit(A=A, lag_roots=np.array([]), b_ref=0.078, k=fit.k, Q=fit.Q,
                  element_error=fit.element_error, fit_error=0.0)
    m0 = modal_arrays(M=np.diag(np.diag(modal.M)), K=modal.K, C=np.zeros_like(modal.K),
                      n_rigid=1)
    rho, U = 1.1, 300.0
    q = 0.5 * rho * U ** 2
    mats = aeroelastic_matrices(m0, qs, rho, U)
    Mss, Kss = m0.M[1:, 1:], m0.K[1:, 1:]
    hand = np.block([[np.zeros((3, 3)), np.eye(3)],
                     [-np.linalg.solve(Mss, Kss - q * A[0][1:, 1:]), np.zeros((3, 3))]])
    np.testing.assert_allclose(mats.A, hand, rtol=1e-12, atol=1e-9)
    # theta enters as a stiffness force q A0_sc theta; hinge D = q A0_cc - M_cc s^2 ...
    np.testing.assert_allclose(mats.B[3:, 0], np.linalg.solve(Mss, q * A[0][1:, 0]), rtol=1e-12)
    np.testing.assert_allclose(mats.D_hinge[0], [q * A[0][0, 0], 0.0, -m0.M[0, 0]], rtol=1e-12)


def test_static_hinge_moment():
    """DC gain theta -> hinge: q (A0_cc + q A0_cs (K_ss - q A0_ss)^-1 A0_sc); -> q Q_cc when
    the structure is stiff."""
    modal, fit = _model()
    rho, U = 1.225, 200.0
    q = 0.5 * rho * U ** 2
    A0 = fit.A[0]
    dc = aeroelastic_model(modal, fit, rho, U)(0.0) @ np.array([1.0, 0.0, 0.0])
    Kss = modal.K[1:, 1:] - q * A0[1:, 1:]
    expected = q * A0[0, 0] + q * A0[0, 1:] @ np.linalg.solve(Kss, q * A0[1:, 0])
    assert dc[0] == pytest.approx(expected, rel=1e-9)
    stiff = modal_arrays(M=modal.M, K=1e8 * modal.K, C=modal.C, n_rigid=1)
    dc_stiff = aeroelastic_model(stiff, fit, rho, U)(0.0) @ np.array([1.0, 0.0, 0.0])
    assert dc_stiff[0] == pytest.approx(q * A0[0, 0], rel=1e-6)


def test_named_outputs_and_rotation_rows():
    modal, fit = _model()
    dwdx = np.array([[-1.0, 0.3, -0.2, 0.1]])           # rigid pitch slope is -1 (nose up)
    rows = rotation_rows(dwdx, n_rigid=1)
    np.testing.assert_allclose(rows, [[1.0, -0.3, 0.2, -0.1]])
    sys = aeroelastic_model(modal, fit, 1.225, 250.0, outputs={"fin_root_pitch": rows[0]},
                            modal_outputs=False)
    assert list(sys.output_labels) == ["hinge_moment", "fin_root_pitch"]
    s = 2j * np.pi * 100
    y = sys(s) @ np.array([1.0, s, s * s])
    _, zeta = _reference_response(modal, fit, 1.225, 250.0, s)
    assert y[1] == pytest.approx(1.0 + rows[0, 1:] @ zeta, rel=1e-8)


def test_model_without_rigid_mode():
    modal, fit = _model()
    m = modal_arrays(M=modal.M[1:, 1:], K=modal.K[1:, 1:], C=modal.C[1:, 1:], n_rigid=0)
    f = RogerFit(A=fit.A[:, 1:, 1:], lag_roots=fit.lag_roots, b_ref=fit.b_ref, k=fit.k,
                 Q=fit.Q[:, 1:, 1:], element_error=fit.element_error[1:, 1:], fit_error=0.0)
    sys = aeroelastic_model(m, f, 1.0, 100.0)
    assert sys.ninputs == 0 and sys.noutputs == 3 and sys.nstates == 3 * 2 + 3 * 2


def test_bad_input():
    modal, fit = _model()
    with pytest.raises(ValueError, match="rho"):
        aeroelastic_matrices(modal, fit, 0.0, 100.0)
    with pytest.raises(ValueError, match="velocity"):
        aeroelastic_matrices(modal, fit, 1.0, -5.0)
    with pytest.raises(ValueError, match="n_rigid"):
        modal_arrays(M=np.eye(2), K=np.eye(2), n_rigid=2)
    with pytest.raises(ValueError, match="K"):
        modal_arrays(M=np.eye(2), K=np.eye(3))
    with pytest.raises(ValueError, match="row"):
        aeroelastic_model(modal, fit, 1.0, 100.0, outputs={"bad": [1.0, 2.0]})


def test_roger_fit_into_model_end_to_end():
    """A fit of tabulated data feeds the model directly (shapes and names agree)."""
    modal, fit = _model()
    Q = fit.evaluate(fit.k)
    f2 = roger_fit(fit.k, Q, fit.b_ref, lag_roots=fit.lag_roots)
    sys = aeroelastic_model(modal, f2, 1.225, 250.0)
    assert sys.nstates == 2 * 3 + 2 * 3 + 2 * 1


def test_fin_outputs_root_pitch_and_corners(fin_modal):
    """With asekit's fin modal model: the fin-root pitch output is theta + elastic rotation at
    the shaft node, with the rigid mode contributing exactly theta; corner outputs exist."""
    pytest.importorskip("asekit.structure.modes")
    from asekit.aeroelastic.statespace import fin_outputs
    modal = fin_modal
    corners = np.array([[0.0, 0.0], [0.156, 0.0], [0.078, 0.15], [0.156, 0.15]])
    out = fin_outputs(modal, corners, names=["rle", "rte", "tle", "tte"],
                      shaft_point=(0.078, 0.0))
    assert out["fin_root_pitch"][0] == pytest.approx(1.0)
    for nm in ("rle", "rte", "tle", "tte"):
        assert out[f"theta_{nm}"][0] == pytest.approx(1.0)
    # the rigid pitch mode moves the leading edge up: w = -(x - x_axis) per rad
    assert out["w_rle"][0] == pytest.approx(0.078, rel=1e-6)
    assert out["w_tte"][0] == pytest.approx(-0.078, rel=1e-6)
    n = modal.M.shape[0]
    A = np.zeros((5, n, n))
    A[0, 0, 0] = 6e-4
    fit = RogerFit(A=A, lag_roots=np.array([0.5, 1.5]), b_ref=0.078, k=np.array([0.0, 1.0]),
                   Q=np.zeros((2, n, n)), element_error=np.zeros((n, n)), fit_error=0.0)
    sys = aeroelastic_model(modal, fit, 1.225, 250.0, outputs=out)
    assert "fin_root_pitch" in sys.output_labels and "w_tte" in sys.output_labels
    # static: no elastic coupling in this GAF -> root pitch equals theta
    y0 = sys(0.0) @ np.array([1.0, 0.0, 0.0])
    assert y0[list(sys.output_labels).index("fin_root_pitch")] == pytest.approx(1.0)
