"""Gain- and phase-margin derivatives (asekit.ase.margin_sensitivity) of state-space loops:
the margins against python-control and a closed form, their derivatives with respect to
parameters in A (poles, a lightly damped structural mode) and C (gain, zero) against central
differences of the re-located crossovers."""

import math

import control as ct
import numpy as np
import pytest

from asekit.ase.margin_sensitivity import margin_sensitivities


def _loop(theta):
    """L(s) = K (s + z) / ((s + a)(s^2 + 2 zeta w s + w^2)) in companion form and the
    derivatives of (A, C) with respect to theta = (a, w, zeta, K, z): the denominator is
    s^3 + (2 zeta w + a) s^2 + (w^2 + 2 a zeta w) s + a w^2."""
    a, w, zeta, K, z = theta
    c = np.array([a * w * w, w * w + 2 * a * zeta * w, 2 * zeta * w + a])
    dc = np.array([[w * w, 2 * zeta * w, 1.0],                     # d/da
                   [2 * a * w, 2 * w + 2 * a * zeta, 2 * zeta],    # d/dw
                   [0.0, 2 * a * w, 2 * w],                        # d/dzeta
                   [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], -c])
    dA = [np.vstack([np.zeros((2, 3)), -d]) for d in dc]
    C = K * np.array([[z, 1.0, 0.0]])
    dC = [np.zeros((1, 3))] * 3 + [np.array([[z, 1.0, 0.0]]), K * np.array([[1.0, 0.0, 0.0]])]
    B = np.array([[0.0], [0.0], [1.0]])
    return A, B, C, np.zeros((1, 1)), dA, dC


THETA = np.array([0.5, 10.0, 0.05, 40.0, 2.0])     # a pole, a 10 rad/s mode at 5 %, gain, zero


def test_margins_match_python_control_and_the_closed_form():
    A, B, C, D, dA, dC = _loop(THETA)
    s = margin_sensitivities(A, B, C, D, dA=dA, dC=dC)
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(ct.ss(A, B, C, D))
    assert s.gain_margins_db.size == 1 and s.phase_margins_deg.size >= 1
    assert s.phase_crossovers_rad_s[0] == pytest.approx(wpc, rel=1e-6)
    assert 10 ** (s.gain_margins_db[0] / 20) == pytest.approx(gm, rel=1e-6)
    i = int(np.argmin(np.abs(s.phase_margins_deg)))
    assert s.phase_margins_deg[i] == pytest.approx(pm, rel=1e-6)
    assert s.gain_crossovers_rad_s[i] == pytest.approx(wgc, rel=1e-6)
    # closed form of K / ((s + 1)(s + 2)(s + 3)): w_p = sqrt(11), GM = 60 / K
    A3 = [[0, 1, 0], [0, 0, 1], [-6, -11, -6]]
    s3 = margin_sensitivities(A3, [[0], [0], [1]], [[20, 0, 0]], [[0]])
    assert s3.phase_crossovers_rad_s[0] == pytest.approx(math.sqrt(11), rel=1e-12)
    assert s3.gain_margins_db[0] == pytest.approx(20 * math.log10(3), rel=1e-12)


def test_margin_derivatives_match_central_differences():
    """dPM, dGM and the crossovers' shifts w.r.t. the five parameters against central
    differences (step 1e-5 relative; the crossovers refined to 1e-13, so the differences are
    good to ~1e-8) to 1e-5 relative."""
    A, B, C, D, dA, dC = _loop(THETA)
    s = margin_sensitivities(A, B, C, D, dA=dA, dC=dC)
    for k in range(THETA.size):
        h = 1e-5 * THETA[k]
        sp = margin_sensitivities(*_loop(THETA + h * np.eye(5)[k])[:4])
        sm = margin_sensitivities(*_loop(THETA - h * np.eye(5)[k])[:4])
        for name, dname in (("phase_margins_deg", "d_phase_margins_deg"),
                            ("gain_margins_db", "d_gain_margins_db"),
                            ("gain_crossovers_rad_s", "d_gain_crossovers_rad_s"),
                            ("phase_crossovers_rad_s", "d_phase_crossovers_rad_s")):
            fd = (getattr(sp, name) - getattr(sm, name)) / (2 * h)
            an = getattr(s, dname)[k]
            scale = np.maximum(np.abs(fd), 1e-12)
            if k in (3,) and name.endswith("crossovers_rad_s") and "phase" in name:
                # a gain in C does not move the phase crossover: both are zero
                assert np.all(np.abs(an) < 1e-9) and np.all(np.abs(fd) < 1e-6)
                continue
            assert np.max(np.abs(an - fd) / scale) <= 1e-5, (k, name, an, fd)


def test_derivative_count_follows_the_parameters():
    A, B, C, D, dA, dC = _loop(THETA)
    s = margin_sensitivities(A, B, C, D, dA=dA[:2])
    assert s.d_gain_margins_db.shape == (2, s.gain_margins_db.size)
    with pytest.raises(ValueError, match=r"dC must have shape \(1, 3\)"):
        margin_sensitivities(A, B, C, D, dC=[np.zeros((3, 1))])
