"""The divergence eigenvalue's derivative (asekit.aeroelastic.sensitivity.divergence_sensitivity)
against central finite differences and against the flutter module's divergence speeds.

The matrices are random but fixed (seeded): a symmetric positive-definite modal stiffness and a
non-symmetric steady GAF (aerodynamic matrices are not symmetric), both linear in theta, so the
central differences with step 1e-6 carry only the eigenvalue's O(h^2) curvature (~1e-12
relative) and round-off (~1e-10 relative); the check asserts 1e-7 relative. The whole chain's
divergence derivative (thickness -> modes -> GAFs -> mu) is checked in tests/case/test_design.py.
"""

import numpy as np
import pytest

from asekit.aeroelastic.flutter import divergence_speeds
from asekit.aeroelastic.sensitivity import divergence_sensitivity
from asekit.aeroelastic.statespace import modal_arrays


def _matrices(seed=3, n=4):
    r = np.random.default_rng(seed)
    a = r.normal(size=(n, n))
    K = a @ a.T + n * np.eye(n)
    Q0 = r.normal(size=(n, n)) + 2.0 * np.eye(n)
    dK = r.normal(size=(2, n, n))
    dK = dK + dK.transpose(0, 2, 1)
    dQ0 = r.normal(size=(2, n, n))
    return K, Q0, dK, dQ0


def test_derivative_matches_central_differences():
    K, Q0, dK, dQ0 = _matrices()
    s = divergence_sensitivity(K, Q0, dK, dQ0)
    assert s.mu > 0
    h = 1e-6
    for j in range(2):
        up = divergence_sensitivity(K + h * dK[j], Q0 + h * dQ0[j], dK, dQ0).mu
        dn = divergence_sensitivity(K - h * dK[j], Q0 - h * dQ0[j], dK, dQ0).mu
        fd = (up - dn) / (2 * h)
        assert s.d_mu[j] == pytest.approx(fd, rel=1e-7)
        # and the speed's chain rule U_D = sqrt(2 / (rho mu))
        rho = 1.2
        fd_u = (np.sqrt(2 / (rho * up)) - np.sqrt(2 / (rho * dn))) / (2 * h)
        assert s.d_speed(rho)[j] == pytest.approx(fd_u, rel=1e-7)


def test_speed_is_the_flutter_modules_divergence_speed():
    K, Q0, dK, dQ0 = _matrices()
    n = K.shape[0]
    modal = modal_arrays(M=np.eye(n), K=K, C=np.zeros((n, n)))
    s = divergence_sensitivity(K, Q0, dK, dQ0)
    assert s.speed(0.9) == pytest.approx(divergence_speeds(modal, Q0, 0.9)[0], rel=1e-12)


def test_no_divergence_gives_infinite_speed_and_zero_speed_gradient():
    # a stabilising steady GAF (negative definite): every mu < 0, no divergence
    K = np.diag([1.0, 4.0])
    s = divergence_sensitivity(K, -np.eye(2), np.ones((1, 2, 2)), np.zeros((1, 2, 2)))
    assert s.mu == pytest.approx(-0.25)                # the largest of -1/1, -1/4
    assert s.speed(1.0) == np.inf and s.d_speed(1.0)[0] == 0.0
    # and mu's own derivative stays analytic there: dmu/dK11-like = w^T (-mu dK) v / w^T K v
    assert s.d_mu[0] == pytest.approx(0.25 * 1.0 / 4.0)
