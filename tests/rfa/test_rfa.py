"""Roger RFA (Eqs. 2.13-2.24): exact recovery, constraint, weights, errors, bad input."""

import numpy as np
import pytest

from asekit.io.op4 import load_ha145b
from asekit.rfa import default_lag_roots, roger_fit


def _synthetic(n=3, lags=(0.1, 0.5), seed=1, k=None):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(3 + len(lags), n, n))
    k = np.concatenate([[0.001], np.geomspace(0.02, 2.0, 11)]) if k is None else k
    ik = 1j * k[:, None, None]
    Q = A[0] + ik * A[1] + ik ** 2 * A[2]
    for j, b in enumerate(lags):
        Q = Q + ik * A[3 + j] / (ik + b)
    return k, Q, A, np.array(lags)


def test_exact_recovery_of_a_roger_function():
    k, Q, A, lags = _synthetic()
    fit = roger_fit(k, Q, b_ref=0.078, lag_roots=lags)
    np.testing.assert_allclose(fit.A, A, atol=1e-8)
    assert fit.fit_error < 1e-10
    assert fit.element_error.shape == (3, 3) and fit.element_error.max() < 1e-9


def test_evaluate_laplace_matches_k_form():
    k, Q, _, lags = _synthetic()
    fit = roger_fit(k, Q, b_ref=0.078, lag_roots=lags)
    U, kk = 250.0, 0.7
    s = 1j * kk * U / 0.078                        # Eq. (2.25)-(2.27): s = i omega
    np.testing.assert_allclose(fit.evaluate_laplace(s, U), fit.evaluate(kk), rtol=1e-12)


def test_quasi_steady_fit_without_lags():
    # constant + linear + quadratic data is fitted exactly with N = 0 lag terms
    k = np.linspace(0.0, 1.0, 6)
    Q = (2.0 + 0.5j * k - 0.3 * k ** 2)[:, None, None] * np.ones((1, 2, 2))
    fit = roger_fit(k, Q, b_ref=1.0, n_lags=0)
    assert fit.n_lags == 0
    np.testing.assert_allclose(fit.A[0], 2.0, atol=1e-12)
    np.testing.assert_allclose(fit.A[1], 0.5, atol=1e-12)
    np.testing.assert_allclose(fit.A[2], 0.3, atol=1e-12)   # (ik)^2 A2 = -k^2 A2


def test_constraint_through_steady_data():
    k, Q, _, _ = _synthetic(lags=(0.05, 0.3, 1.2))
    Q = Q + 0.05 * np.random.default_rng(3).normal(size=Q.shape)   # noise: fit no longer exact
    free = roger_fit(k, Q, 0.078, lag_roots=[0.2, 0.8])
    con = roger_fit(k, Q, 0.078, lag_roots=[0.2, 0.8], constrain_k0=True)
    assert np.abs(free.evaluate(k[0]).real - Q[0].real).max() > 1e-4
    np.testing.assert_allclose(con.evaluate(k[0]).real, Q[0].real, atol=1e-10)
    assert con.fit_error >= free.fit_error           # least squares is optimal unconstrained


def test_weights_pull_the_fit():
    k, Q, _, _ = _synthetic(lags=(0.05, 0.3, 1.2))
    w = np.ones(k.size)
    w[5] = 1e4
    fit = roger_fit(k, Q, 0.078, lag_roots=[0.5], weights=w)
    plain = roger_fit(k, Q, 0.078, lag_roots=[0.5])
    e_w = np.abs(fit.evaluate(k[5]) - Q[5]).max()
    e_p = np.abs(plain.evaluate(k[5]) - Q[5]).max()
    assert e_w < 0.1 * e_p


def test_default_lag_roots_spread():
    b = default_lag_roots(2.0, 4)
    assert np.all(b > 0) and np.all(np.diff(b) > 0) and b[-1] < 2.0 * 1.7


def test_fit_of_nastran_gafs_is_good():
    case = load_ha145b()
    fit = roger_fit(case.k, case.Q, case.b_ref, n_lags=4)
    assert fit.fit_error < 0.01
    assert np.isfinite(fit.element_error).all()


def test_bad_input():
    k, Q, _, _ = _synthetic()
    with pytest.raises(ValueError, match="lag_roots"):
        roger_fit(k, Q, 0.078, lag_roots=[0.1, -0.2])
    with pytest.raises(ValueError, match="lag_roots"):
        roger_fit(k, Q, 0.078, lag_roots=[0.0])
    with pytest.raises(ValueError, match="fewer"):
        roger_fit(k[:3], Q[:3], 0.078, lag_roots=[0.1, 0.2, 0.3, 0.4])
    with pytest.raises(ValueError, match="b_ref"):
        roger_fit(k, Q, 0.0)
    with pytest.raises(ValueError, match="ascending"):
        roger_fit(k[::-1], Q, 0.078)
    with pytest.raises(ValueError, match="weights"):
        roger_fit(k, Q, 0.078, weights=-np.ones(k.size))


def test_mach_selection():
    from asekit.aero.gaf import GafDatabase
    db = GafDatabase(np.array([0.5, 0.75]), np.array([0.0, 1.0]),
                     np.array([np.ones((2, 2, 2)), 3 * np.ones((2, 2, 2))]).astype(complex),
                     0.078, 0, {})
    with pytest.raises(ValueError, match="mach 0.6 is not in the GAF database"):
        db.at(0.6)
    with pytest.raises(ValueError, match=r"valid range \[0.5, 0.75\]"):
        db.at(0.9, interpolate=True)
    g = db.at(0.625, interpolate=True)
    np.testing.assert_allclose(g.Q, 2.0)
    assert g.mach == 0.625 and g.b_ref == 0.078
    np.testing.assert_array_equal(db.at(0.75 + 1e-12).Q, db.Q[1])      # exact within atol


# ---- issue 22: strict types and finite coefficients --------------------------------------------
def _table():
    rng = np.random.default_rng(0)
    return np.linspace(0.0, 1.0, 8), rng.normal(size=(8, 2, 2)) + 1j * rng.normal(size=(8, 2, 2))


@pytest.mark.parametrize("kw, word, error", [
    ({"n_lags": 2.5}, "n_lags must be an integer >= 0", TypeError),
    ({"n_lags": True}, "n_lags must be an integer >= 0", TypeError),
    ({"n_lags": "2"}, "n_lags must be an integer >= 0", TypeError),
    ({"b_ref": "1.0"}, "b_ref must be a real number", ValueError),
    ({"lag_roots": [0.1, np.nan]}, r"lag_roots must be finite, got lag_roots\[1\]", ValueError),
])
def test_roger_fit_strict_types(kw, word, error):
    k, Q = _table()
    a = {"b_ref": 1.0} | kw
    with pytest.raises(error, match=word):
        roger_fit(k, Q, a.pop("b_ref"), **a)


def test_roger_fit_refuses_complex_k_and_non_finite_q():
    k, Q = _table()
    with pytest.raises(TypeError, match=r"k must be real numbers.*k\[0\]"):
        roger_fit(k + 0.1j, Q, 1.0)
    Q[3, 1, 0] = np.nan
    with pytest.raises(ValueError, match=r"Q must be finite, got Q\[3, 1, 0\]"):
        roger_fit(k, Q, 1.0)


def test_roger_fit_holding_nan_is_refused_at_construction():
    """Issue 22's reproducer: a RogerFit holding NaN (e.g. dataclasses.replace of a fit) gave
    NaN state-space matrices; the fit itself now refuses non-finite coefficients."""
    import dataclasses

    k, Q = _table()
    fit = roger_fit(k, Q, 1.0, n_lags=2)
    A = fit.A.copy()
    A[4, 0, 1] = np.nan
    with pytest.raises(ValueError, match=r"A must be finite, got A\[4, 0, 1\] = nan"):
        dataclasses.replace(fit, A=A)
    with pytest.raises(ValueError, match="lag_roots"):
        dataclasses.replace(fit, lag_roots=np.array([0.1, -1.0]))
    with pytest.raises(ValueError, match="b_ref"):
        dataclasses.replace(fit, b_ref=np.inf)
