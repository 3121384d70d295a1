"""Flutter solvers: Nastran's HA145B benchmark, a hand-derivable quasi-steady case, U -> 0
limits, static divergence, agreement of p-k / root locus / time domain, bad input."""

import numpy as np
import pytest

from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    divergence_speeds,
    first_of,
    initial_state,
    pk_flutter,
    pk_instabilities,
    root_locus,
    root_locus_instabilities,
    simulate_free_response,
    time_domain_sweep,
)
from asekit.aeroelastic.statespace import aeroelastic_matrices, modal_arrays
from asekit.io.op4 import load_ha145b
from asekit.rfa import RogerFit, roger_fit

# MSC Nastran Aeroelastic Analysis User's Guide, Example HA145B (BAH wing, PK method, Mach 0,
# sea level): flutter of the second mode at about 12,672 in/s (1056 ft/s) near 3.1 Hz, as
# quoted in shared/benchmarks/bah_ha145b/README.md.
HA145B_FLUTTER_SPEED = 12672.0      # in/s
HA145B_FLUTTER_FREQ = 3.1           # Hz


@pytest.fixture(scope="module")
def ha145b():
    case = load_ha145b()
    modal = modal_arrays(M=case.M, K=case.K, n_rigid=0)
    gaf = TabulatedGaf(case.k, case.Q, case.b_ref, mach=0.0)
    U = np.linspace(4800.0, 25200.0, 69)
    res = pk_flutter(modal, gaf, case.rho, U)
    return case, modal, gaf, res


def test_ha145b_pk_matches_nastran(ha145b):
    case, modal, gaf, res = ha145b
    fl = first_of(pk_instabilities(res, modal, gaf), "flutter")
    assert fl is not None and fl.mode == 1                     # the second mode flutters
    assert fl.speed == pytest.approx(HA145B_FLUTTER_SPEED, rel=0.02)
    assert fl.frequency_hz == pytest.approx(HA145B_FLUTTER_FREQ, rel=0.02)
    assert res.converged.mean() > 0.95


def test_ha145b_divergence_pk_equals_static(ha145b):
    case, modal, gaf, res = ha145b
    dv = first_of(pk_instabilities(res, modal, gaf), "divergence")
    static = divergence_speeds(modal, case.Q[0], case.rho)
    assert dv is not None and dv.speed == pytest.approx(static[0], rel=1e-4)


def test_ha145b_three_methods_agree(ha145b):
    case, modal, gaf, res = ha145b
    pk = first_of(pk_instabilities(res, modal, gaf), "flutter")
    fit = roger_fit(case.k, case.Q, case.b_ref, n_lags=4)
    rl = root_locus(modal, fit, case.rho, res.velocities)
    rl_f = first_of(root_locus_instabilities(rl, modal, fit), "flutter")
    assert rl_f.speed == pytest.approx(pk.speed, rel=0.02)
    assert rl_f.frequency_hz == pytest.approx(pk.frequency_hz, rel=0.02)
    td = time_domain_sweep(modal, fit, case.rho, np.linspace(11500, 14000, 6), coordinate=1,
                           t_end=3.0)
    assert td.onset_speed == pytest.approx(rl_f.speed, rel=0.005)   # same A_sys
    assert td.onset_speed == pytest.approx(pk.speed, rel=0.02)
    # root-locus elastic roots start from the structural frequencies
    f0 = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(case.M, case.K)).real)) / 2 / np.pi
    assert rl.natural_frequency_hz[0, 0] == pytest.approx(f0[0], rel=0.05)


def _coalescence_case(c=2.0):
    """2 dof, M = I, K = diag(k1, k2), C = c I, Q = [[0, a], [d, 0]] real and independent of k.
    Flutter (Re p = 0 on the coalescing pair): q_f^2 (-a d) = ((k1-k2)/2)^2 + c^2 (k1+k2)/2,
    omega_f = sqrt((k1+k2)/2) (derived from p = -c/2 +- sqrt(c^2/4 - lambda), lambda the
    eigenvalues of K - q Q)."""
    k1, k2, a, d = 100.0 ** 2, 150.0 ** 2, 1.0, -2.0
    M, K, C = np.eye(2), np.diag([k1, k2]), c * np.eye(2)
    Q = np.array([[0.0, a], [d, 0.0]], complex)
    q_f = np.sqrt((((k1 - k2) / 2) ** 2 + c ** 2 * (k1 + k2) / 2) / (-a * d))
    return M, K, C, Q, q_f, np.sqrt((k1 + k2) / 2)


def test_quasi_steady_hand_derived_flutter():
    M, K, C, Q, q_f, w_f = _coalescence_case()
    rho, b = 1.0, 1.0
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), b)
    modal = modal_arrays(M=M, K=K, C=C)
    U_f = np.sqrt(2 * q_f / rho)
    U = np.linspace(0.5 * U_f, 1.5 * U_f, 21)
    res = pk_flutter(modal, gaf, rho, U)
    fl = first_of(pk_instabilities(res, modal, gaf), "flutter")
    assert fl.speed == pytest.approx(U_f, rel=1e-6)
    assert fl.frequency_hz == pytest.approx(w_f / (2 * np.pi), rel=1e-6)
    # the same by root locus of the lag-free state-space model
    A = np.zeros((3, 2, 2))
    A[0] = Q.real
    fit = RogerFit(A=A, lag_roots=np.array([]), b_ref=b, k=gaf.k, Q=gaf.Q,
                   element_error=np.zeros((2, 2)), fit_error=0.0)
    rl = root_locus(modal, fit, rho, U)
    rl_f = first_of(root_locus_instabilities(rl, modal, fit), "flutter")
    assert rl_f.speed == pytest.approx(U_f, rel=1e-6)
    td = time_domain_sweep(modal, fit, rho, U, coordinate=0, t_end=1.0)
    assert td.onset_speed == pytest.approx(U_f, rel=2e-3)


def test_u_to_zero_pk_roots_are_structural():
    M, K, C, Q, _, _ = _coalescence_case(c=0.0)
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), 1.0)
    res = pk_flutter(modal_arrays(M=M, K=K), gaf, 1.0, [1e-4, 2e-4])
    np.testing.assert_allclose(res.frequency_hz[0], np.array([100.0, 150.0]) / (2 * np.pi),
                               rtol=1e-9)
    assert np.abs(res.sigma[0]).max() < 1e-9


def test_divergence_quasi_steady():
    """1 dof torsion: K - q Q0 = 0 at q = K/Q0."""
    K, Q0 = np.array([[400.0]]), np.array([[2.0]])
    modal = modal_arrays(M=np.eye(1), K=K, C=0.5 * np.eye(1))
    assert divergence_speeds(modal, Q0, 1.0)[0] == pytest.approx(np.sqrt(2 * 200.0))
    gaf = TabulatedGaf(np.array([0.0, 1.0]), np.array([Q0, Q0]).astype(complex), 1.0)
    res = pk_flutter(modal, gaf, 1.0, np.linspace(5.0, 40.0, 36))
    dv = first_of(pk_instabilities(res, modal, gaf), "divergence")
    assert dv.speed == pytest.approx(20.0, rel=1e-6) and dv.frequency_hz == 0.0


def test_rk45_matches_matrix_exponential():
    M, K, C, Q, q_f, _ = _coalescence_case()
    A = np.zeros((3, 2, 2))
    A[0] = Q.real
    fit = RogerFit(A=A, lag_roots=np.array([]), b_ref=1.0, k=np.array([0.0, 1.0]),
                   Q=np.zeros((2, 2, 2)), element_error=np.zeros((2, 2)), fit_error=0.0)
    mats = aeroelastic_matrices(modal_arrays(M=M, K=K, C=C), fit, 1.0, np.sqrt(2 * q_f))
    z0 = initial_state(mats.n_states, 1)
    ex = simulate_free_response(mats.A, z0, 0.2, method="exact")
    rk = simulate_free_response(mats.A, z0, 0.2, max_step=1e-4, method="RK45")
    assert rk.steps.max() <= 1e-4 + 1e-15
    np.testing.assert_allclose(rk.z, ex.z, atol=1e-4)


def test_bad_input():
    M, K, C, Q, _, _ = _coalescence_case()
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), 1.0)
    modal = modal_arrays(M=M, K=K, C=C)
    with pytest.raises(ValueError, match="velocities"):
        pk_flutter(modal, gaf, 1.0, [10.0, -1.0])
    with pytest.raises(ValueError, match="density"):
        pk_flutter(modal, gaf, 0.0, [10.0])
    with pytest.raises(ValueError, match="k must"):
        TabulatedGaf(np.array([1.0, 0.5]), np.array([Q, Q]), 1.0)
    with pytest.raises(ValueError, match="b_ref"):
        TabulatedGaf(np.array([0.0, 1.0]), np.array([Q, Q]), -1.0)
    with pytest.raises(ValueError, match="modes"):
        pk_flutter(modal, gaf, 1.0, [1.0], modes=[5])


def test_match_point_table_and_matched_mach():
    """Flutter speed independent of Mach (same GAFs): M_eq = U_f / a is the same for every
    analysis Mach, so the matched Mach is M_eq itself when bracketed."""
    M, K, C, Q, q_f, _ = _coalescence_case()
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), 1.0)
    modal = modal_arrays(M=M, K=K, C=C)
    from asekit.aeroelastic.flutter import match_point_table, matched_mach
    from asekit.atmosphere import speed_of_sound
    rho = 1.225
    U_f = np.sqrt(2 * q_f / rho)
    rows = match_point_table(modal, lambda mach: gaf, [0.01, 0.9], [0.0],
                             np.linspace(0.5 * U_f, 1.5 * U_f, 11))
    m_eq = U_f / float(speed_of_sound(0.0))
    assert all(r.speed == pytest.approx(U_f, rel=1e-6) for r in rows)
    assert rows[0].mach_equivalent == pytest.approx(m_eq, rel=1e-6)
    assert rows[0].equivalent_speed == pytest.approx(U_f, rel=1e-3)
    assert 0.01 < m_eq < 0.9 and matched_mach(rows, 0.0) == pytest.approx(m_eq, rel=1e-6)
    assert matched_mach(rows, 2500.0) is None


def test_tracking_follows_eigenvectors_through_a_frequency_crossing():
    """Two uncoupled modes; aerodynamic stiffness lowers the 150 rad/s mode below the 100 rad/s
    one. Sorting by frequency would swap the labels; eigenvector correlation keeps each mode on
    its own branch: omega^2 = k1 - q a exactly."""
    k1, k2, a = 150.0 ** 2, 100.0 ** 2, 20.0
    Q = np.array([[0.0, 0.0], [0.0, a]], complex)     # acts on dof 1 (the 150 rad/s mode)
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), 1.0)
    U = np.linspace(1.0, 40.0, 40)                    # q up to 800: omega down to ~77 rad/s
    res = pk_flutter(modal_arrays(M=np.eye(2), K=np.diag([k2, k1])), gaf, 1.0, U)
    q = 0.5 * U ** 2
    w1 = np.sqrt(np.clip(k1 - q * a, 0, None))
    ok = k1 - q * a > 0
    assert np.any(w1[ok] < 100.0)                      # the branches really cross
    np.testing.assert_allclose(res.frequency_hz[:, 0], 100.0 / (2 * np.pi), rtol=1e-9)
    np.testing.assert_allclose(res.frequency_hz[ok, 1], w1[ok] / (2 * np.pi), rtol=1e-9)
    assert np.all(np.abs(res.vectors[:, 0, 1]) < 1e-9 * np.abs(res.vectors[:, 0, 0]))
    assert np.all(np.abs(res.vectors[ok, 1, 0]) < 1e-9 * np.abs(res.vectors[ok, 1, 1]))


# ---- issue 22: divergence_speeds names a missing or bad Q0 -------------------------------------
@pytest.mark.parametrize("Q0, word, error", [
    (None, r"Q0 must be the \(2, 2\) GAF matrix at k = 0", TypeError),
    (np.eye(3), r"Q0 must be \(2, 2\) like the modal model, got shape \(3, 3\)", ValueError),
    (np.full((2, 2), np.nan), r"Q0 must be finite, got Q0\[0, 0\]", ValueError),
    ("Q0", "Q0 must be numbers", ValueError),
])
def test_divergence_speeds_bad_q0_is_named(Q0, word, error):
    """Issue 22's reproducer: divergence_speeds(Q0=None) was an AttributeError ('NoneType' has
    no attribute 'real'); a wrong shape or NaN gave scipy's unnamed errors."""
    modal = modal_arrays(M=np.eye(2), K=np.diag([100.0, 400.0]))
    with pytest.raises(error, match=word):
        divergence_speeds(modal, Q0, 1.2)


def test_pk_refuses_complex_velocities_and_float_counts():
    """Issue 22: velocities with an imaginary part were cast to float (imaginary part dropped)
    and max_iter = 3.5 was a bare TypeError."""
    from property_targets import two_dof_coalescence
    modal, gaf, _ = two_dof_coalescence(1.0)
    with pytest.raises(TypeError, match=r"velocities must be real numbers.*velocities\[1\]"):
        pk_flutter(modal, gaf, 1.2, np.array([10.0, 20.0 + 1j]))
    with pytest.raises(TypeError, match="density must be a real number"):
        pk_flutter(modal, gaf, np.complex128(1.2 + 1j), [10.0, 20.0])
    with pytest.raises(TypeError, match="max_iter must be an integer >= 1"):
        pk_flutter(modal, gaf, 1.2, [10.0, 20.0], max_iter=3.5)
