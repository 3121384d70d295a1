"""Minimum-state RFA (Karpel 1982; Tiffany & Adams, NASA TP-2776, 1988): exact recovery,
monotone alternating least squares, constraints, Roger as a special case, the aeroelastic state
space with shared lag states, and the fin's flutter speed against p-k."""

import numpy as np
import pytest

from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    first_of,
    pk_flutter,
    pk_instabilities,
    root_locus,
    root_locus_instabilities,
)
from asekit.aeroelastic.statespace import aeroelastic_matrices, modal_arrays
from asekit.rfa import MinimumStateFit, minimum_state_fit, reduced_frequency_weights, roger_fit


def _ms_data(n=3, roots=(0.1, 0.4, 1.2), seed=2):
    rng = np.random.default_rng(seed)
    nL = len(roots)
    A = rng.normal(size=(3, n, n))
    D = rng.normal(size=(n, nL))
    E = rng.normal(size=(nL, n))
    r = np.array(roots)
    k = np.concatenate([[0.001], np.geomspace(0.02, 2.0, 14)])
    p = 1j * k
    Q = (A[0] + p[:, None, None] * A[1] + (p ** 2)[:, None, None] * A[2]
         + np.einsum("fl,il,lj->fij", p[:, None] / (p[:, None] + r), D, E))
    return k, Q, r


@pytest.fixture(scope="module")
def fin(fin_gafs, fin_modal):
    """(GafDatabase, ModalModel) of the fin (tests/conftest.py, via the case pipeline)."""
    return fin_gafs, fin_modal


def test_exact_recovery_of_a_minimum_state_function():
    # data that is exactly of the minimum-state form is fitted to round-off with its roots
    k, Q, r = _ms_data()
    for kw in ({}, {"constrain_k0": True}, {"match_k": k[-1], "normalize": True}):
        fit = minimum_state_fit(k, Q, 1.0, lag_roots=r, max_iter=5000, tol=1e-14, **kw)
        assert fit.fit_error < 1e-9, kw
        np.testing.assert_allclose(fit.evaluate(k), Q, atol=1e-8)


def test_error_never_increases_and_laplace_form():
    k, Q, _ = _ms_data()
    Q = Q + 0.05 * np.random.default_rng(5).normal(size=Q.shape)
    fit = minimum_state_fit(k, Q, 0.078, n_states=2)
    h = fit.error_history
    assert np.all(np.diff(h) <= 1e-12 * h[0])          # each LS step is optimal given the other
    U, kk = 250.0, 0.7
    np.testing.assert_allclose(fit.evaluate_laplace(1j * kk * U / 0.078, U), fit.evaluate(kk),
                               rtol=1e-12)


def test_root_optimisation_recovers_a_better_fit():
    # the nonlinear-programming extension (Tiffany & Adams 1988): from wrong lag roots the
    # bounded Nelder-Mead search on log beta lowers the error of the fixed-root fit, here on
    # data that are exactly of the minimum-state form with roots (0.1, 0.4, 1.2)
    k, Q, r = _ms_data()
    start = [0.03, 0.9, 1.9]
    fixed = minimum_state_fit(k, Q, 1.0, lag_roots=start, max_iter=200)
    opt = minimum_state_fit(k, Q, 1.0, lag_roots=start, optimize_roots=True,
                            max_root_evaluations=40, max_iter=200)
    assert opt.fit_error < 0.5 * fixed.fit_error
    lo, hi = 1e-3 * k.max(), 2.0 * k.max()
    assert np.all((opt.lag_roots >= lo) & (opt.lag_roots <= hi))


def test_constraints_hold_exactly_on_noisy_data():
    k, Q, _ = _ms_data()
    Q = Q + 0.05 * np.random.default_rng(3).normal(size=Q.shape)
    free = minimum_state_fit(k, Q, 1.0, n_states=2)
    con = minimum_state_fit(k, Q, 1.0, n_states=2, constrain_k0=True, match_k=k[8])
    assert np.abs(free.evaluate(k[0]).real - Q[0].real).max() > 1e-4
    np.testing.assert_allclose(con.evaluate(k[0]).real, Q[0].real, atol=1e-10)
    np.testing.assert_allclose(con.evaluate(k[8]), Q[8], atol=1e-10)
    assert con.constrained_k0 and con.match_k == k[8]


def test_roger_is_a_special_case_of_the_realization():
    # Roger's lag terms written as D (p I + diag beta)^-1 E p give back its Q~ exactly
    k, Q, _ = _ms_data()
    rg = roger_fit(k, Q, 1.0, lag_roots=[0.2, 0.9])
    D, E, roots, names = rg.lag_realization(n_rigid=1)
    assert D.shape == (3, 6) and len(names) == 6 == rg.n_lag_states
    ms = MinimumStateFit(A=rg.A[:3], D=D, E=E, lag_roots=roots, b_ref=1.0, k=k, Q=Q,
                         element_error=rg.element_error, fit_error=rg.fit_error,
                         weighted_error=rg.fit_error, iterations=0, converged=True)
    np.testing.assert_allclose(ms.evaluate(k), rg.evaluate(k), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("n_lags", [1, 2, 3])
def test_minimum_state_fits_the_fin_at_least_as_well_as_roger_with_as_many_states(fin, n_lags):
    # Roger with N lags carries N n aerodynamic states (n = 6 modes of the fin, rigid pitch
    # first); the minimum-state fit with the same number of shared states fits better
    db, _ = fin
    g = db.at(0.75)
    k, Q = g.k, g.Q
    rg = roger_fit(k, Q, db.b_ref, n_lags=n_lags)
    ms = minimum_state_fit(k, Q, db.b_ref, n_states=rg.n_lag_states)
    assert ms.fit_error <= rg.fit_error
    assert ms.n_lag_states == rg.n_lag_states


def test_aeroelastic_eigenvalues_solve_the_flutter_determinant(fin):
    # every root of A_sys built from a minimum-state fit solves
    # det(s^2 M_ss + s C_ss + K_ss - q Q~_ss(s)) = 0 (thesis Eq. 2.44 with the rigid mode held)
    db, modal = fin
    g = db.at(0.6)
    k, Q = g.k, g.Q
    fit = minimum_state_fit(k, Q, db.b_ref, n_states=5)
    m = modal_arrays(modal)
    rho, U = 1.225, 200.0
    mats = aeroelastic_matrices(m, fit, rho, U)
    assert mats.n_states == 2 * m.n_elastic + 5 and mats.n_lag_states == 5
    s_ = slice(1, 6)
    for lam in np.linalg.eigvals(mats.A):
        Z = (lam ** 2 * m.M[s_, s_] + lam * m.C[s_, s_] + m.K[s_, s_]
             - 0.5 * rho * U ** 2 * fit.evaluate_laplace(lam, U)[s_, s_])
        sv = np.linalg.svd(Z, compute_uv=False)
        assert sv[-1] <= 1e-7 * sv[0]


def _elastic(fin, mach):
    """The clamped flutter problem (ModalArrays, k, Q_ss, b_ref) of the fin at ``mach``: the
    rigid pitch mode held (theta = 0), so only the elastic s-set rows and columns of M, K, C
    and Q remain (thesis Eq. 2.46 partition). The same problem as
    asekit.reproduction.design.elastic_problem, written here so that this physics test does not
    depend on the reproduction."""
    db, modal = fin
    m = modal_arrays(modal)
    s = slice(m.n_rigid, m.n_modes)
    me = modal_arrays(M=m.M[s, s], K=m.K[s, s], C=m.C[s, s], n_rigid=0)
    g = db.at(mach)
    k, Q = g.k, g.Q
    return me, k, Q[:, s, s], db.b_ref


@pytest.mark.parametrize("mach", [0.75, 0.6])
@pytest.mark.parametrize("n_states", [5, 6])
def test_flutter_speed_with_few_minimum_state_lags_matches_pk(fin, mach, n_states):
    # reference: asekit's p-k (Eq. 3.12, linear interpolation in k; its cubic interpolation
    # moves the speed by < 0.02 %), sea level, rigid mode held; the fit is weighted towards
    # k <= 2 k_f (reduced_frequency_weights, order 4), k_f the p-k flutter reduced frequency.
    # (The speed depends on the weighting: unweighted 4-6 state fits miss by 3-8 %, and k_band
    # 3-4 k_f or order 2 by up to 2 %; see the design chapter's flutter_weighting_study.)
    me, k, Qe, b = _elastic(fin, mach)
    rho = 1.225
    gaf = TabulatedGaf(k, Qe, b, mach)
    U = np.arange(150.0, 461.0, 5.0)
    pk = first_of(pk_instabilities(pk_flutter(me, gaf, rho, U), me, gaf), "flutter")
    kf = 2 * np.pi * pk.frequency_hz * b / pk.speed
    fit = minimum_state_fit(k, Qe, b, n_states=n_states,
                            weights=reduced_frequency_weights(k, 2 * kf, order=4))
    rl = first_of(root_locus_instabilities(root_locus(me, fit, rho, U), me, fit), "flutter")
    assert rl is not None
    assert abs(rl.speed / pk.speed - 1) < 0.005
    assert abs(rl.frequency_hz / pk.frequency_hz - 1) < 0.01


def test_bad_input_raises():
    k, Q, r = _ms_data()
    with pytest.raises(ValueError, match="n_states"):
        minimum_state_fit(k, Q, 1.0, n_states=0)
    with pytest.raises(ValueError, match="lag_roots"):
        minimum_state_fit(k, Q, 1.0, lag_roots=[0.1, -1.0])
    with pytest.raises(ValueError, match="weights"):
        minimum_state_fit(k, Q, 1.0, weights=np.ones(3))
    with pytest.raises(ValueError, match="match_k"):
        minimum_state_fit(k, Q, 1.0, match_k=0.123)
    with pytest.raises(ValueError, match="b_ref"):
        minimum_state_fit(k, Q, -1.0)
    with pytest.raises(ValueError, match="k_band"):
        reduced_frequency_weights(k, 0.0)


@pytest.mark.parametrize("con", [dict(k0_con=True, match_idx=None), dict(k0_con=True, match_idx=9),
                                 dict(k0_con=False, match_idx=None)])
def test_batched_column_solves_equal_the_column_by_column_solves(con):
    # issue 12: with one weight per k the column (row) problems of both ALS steps share the
    # design matrix and the constraint rows, so they are solved together (several right-hand
    # sides); that must equal the problem-by-problem solution to round-off, constraints
    # included (k = 0 steady value, match at one k)
    from asekit.rfa.minimum_state import _Als

    k, Q, r = _ms_data(n=4, roots=(0.1, 0.4, 1.2))
    Q = Q + 1e-2 * np.random.default_rng(5).normal(size=Q.shape)      # not exactly of the form
    W = np.broadcast_to(np.linspace(1.0, 2.0, k.size)[:, None, None], Q.shape).copy()
    als = _Als(k, Q, W, r, **con)
    assert als.batch
    D = np.random.default_rng(6).normal(size=(4, r.size))
    E = np.random.default_rng(7).normal(size=(r.size, 4))
    A_b, E_b = als.step_E(D)
    A_d, D_b = als.step_D(E)
    als.batch = False
    A_c, E_c = als.step_E(D)
    A_e, D_c = als.step_D(E)
    for x, y in ((A_b, A_c), (E_b, E_c), (A_d, A_e), (D_b, D_c)):
        np.testing.assert_allclose(x, y, rtol=1e-10, atol=1e-12 * np.abs(y).max())
    if con["k0_con"]:                # the steady constraint holds: A0 + D (g(0)) E = Q(k0)
        Qt = als.evaluate(A_b, D, E_b)
        np.testing.assert_allclose(Qt[0].real, Q[0].real, atol=1e-10)


# ---- issue 22: strict types ----------------------------------------------------------------------
@pytest.mark.parametrize("kw, word, error", [
    ({"n_states": 4.5}, "n_states must be an integer >= 1", TypeError),
    ({"n_states": True}, "n_states must be an integer >= 1", TypeError),
    ({"n_states": 0}, "n_states must be an integer >= 1", ValueError),
    ({"max_iter": 2.5}, "max_iter must be an integer >= 1", TypeError),
    ({"max_root_evaluations": 1e3}, "max_root_evaluations must be an integer", TypeError),
])
def test_minimum_state_fit_strict_types(kw, word, error):
    """Issue 22's reproducer: n_states = 4.5 was truncated to 4 silently."""
    rng = np.random.default_rng(0)
    k = np.linspace(0.0, 1.0, 8)
    Q = rng.normal(size=(8, 2, 2)) + 0j
    with pytest.raises(error, match=word):
        minimum_state_fit(k, Q, 1.0, **kw)


def test_minimum_state_fit_refuses_complex_k_and_nan_coefficients():
    import dataclasses

    rng = np.random.default_rng(0)
    k = np.linspace(0.0, 1.0, 8)
    Q = rng.normal(size=(8, 2, 2)) + 0j
    with pytest.raises(TypeError, match=r"k must be real numbers"):
        minimum_state_fit(k + 0.1j, Q, 1.0)
    fit = minimum_state_fit(k, Q, 1.0, n_states=2, max_iter=5)
    E = fit.E.copy()
    E[1, 0] = np.inf
    with pytest.raises(ValueError, match=r"E must be finite, got E\[1, 0\] = inf"):
        dataclasses.replace(fit, E=E)
