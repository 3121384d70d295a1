"""Roger fit of the gust column (asekit.rfa.gust)."""

import numpy as np
import pytest

from asekit.rfa.gust import GustFit, gust_fit


def _jones(k):
    # Jones's sharp-edged-gust function in Roger form (NACA Rep. 681, 1940):
    # S(k) ~ 1 - 0.5 ik/(ik + 0.13) - 0.5 ik/(ik + 1)
    ik = 1j * np.asarray(k)
    return 1 - 0.5 * ik / (ik + 0.13) - 0.5 * ik / (ik + 1.0)


def test_recovers_an_exact_roger_column():
    # data that are exactly of the Roger form with the fit's lags are recovered to round-off,
    # for every choice of quasi-steady terms, and with the k0 constraint
    k = np.linspace(0.0, 2.0, 12)
    q = np.column_stack([_jones(k), 3 * _jones(k) + 0.2j * k])
    for nq in (1, 2):
        for ck in (False, True):
            f = gust_fit(k, q, 0.5, lag_roots=[0.13, 1.0], quasi_steady_terms=nq,
                         constrain_k0=ck)
            np.testing.assert_allclose(f.A[[0, 3, 4], 0], [1.0, -0.5, -0.5], atol=1e-9)
            np.testing.assert_allclose(f.A[1, 1], 0.2, atol=1e-9)
            assert f.fit_error < 1e-10
    f = gust_fit(k, q, 0.5, lag_roots=[0.13, 1.0], quasi_steady_terms=0)
    assert f.A[1, 1] == 0 and f.fit_error > 1e-3       # the A1 term is refused: no exact fit


def test_indicial_is_the_inverse_laplace_transform():
    # Q~(p)/p = A0/p + sum A_n / (p + beta_n) -> A0 + sum A_n exp(-beta_n s)
    f = gust_fit(np.linspace(0, 2, 12), _jones(np.linspace(0, 2, 12)), 0.5,
                 lag_roots=[0.13, 1.0], quasi_steady_terms=0)
    s = np.array([0.0, 1.0, 10.0])
    np.testing.assert_allclose(f.indicial(s)[:, 0],
                               1 - 0.5 * np.exp(-0.13 * s) - 0.5 * np.exp(-s), atol=1e-9)


def test_errors():
    k = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="quasi_steady_terms"):
        gust_fit(k, np.ones(5), 0.5, quasi_steady_terms=3)
    with pytest.raises(ValueError, match="lag_roots must all be > 0"):
        gust_fit(k, np.ones(5), 0.5, lag_roots=[-1.0])
    with pytest.raises(ValueError, match="Qg must be"):
        gust_fit(k, np.ones(4), 0.5)
    with pytest.raises(ValueError, match="fewer than the"):
        gust_fit(k[:2], np.ones(2), 0.5, n_lags=4)
    with pytest.raises(ValueError, match="A must be"):
        GustFit(np.ones((4, 1)), np.array([0.1, 0.2]), 0.5, k, np.ones((5, 1)))
