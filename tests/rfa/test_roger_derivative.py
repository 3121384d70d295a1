"""Derivative of the Roger fit's coefficients with respect to a design parameter (issue 28):
dA = fit(dQ) for fixed lags, checked against central differences of the fit of perturbed GAFs
(the fit is linear in Q, so the difference quotient has no truncation error: only round-off)."""

import numpy as np
import pytest

from asekit.rfa.roger import roger_fit, roger_fit_derivative


def _tables(seed=0, n=3, nk=12):
    rng = np.random.default_rng(seed)
    k = np.linspace(0.0, 1.5, nk)
    # smooth, physically shaped GAF tables: Theodorsen-like lag plus quasi-steady terms
    base = rng.normal(size=(4, n, n))
    lag = 1j * k / (1j * k + 0.3)
    Q = (base[0] + 1j * k[:, None, None] * base[1] - (k ** 2)[:, None, None] * base[2]
         + lag[:, None, None] * base[3])
    dQ = rng.normal(size=(nk, n, n)) + 1j * rng.normal(size=(nk, n, n))
    return k, Q, dQ


@pytest.mark.parametrize("constrain", [False, True])
def test_fit_derivative_matches_central_differences(constrain):
    k, Q, dQ = _tables()
    kw = dict(n_lags=3, constrain_k0=constrain, weights=np.linspace(1.0, 2.0, k.size))
    fit = roger_fit(k, Q, 0.1, **kw)
    dA = roger_fit_derivative(fit, dQ)
    h = 1e-4
    fd = (roger_fit(k, Q + h * dQ, 0.1, **kw).A - roger_fit(k, Q - h * dQ, 0.1, **kw).A) / (2 * h)
    err = np.abs(dA - fd).max() / np.abs(fd).max()
    assert err < 1e-8, err
    if constrain:     # the constrained fit's steady row passes through d Re Q(k0) exactly
        steady = dA[0] - k[0] ** 2 * dA[2] + sum(
            k[0] ** 2 / (k[0] ** 2 + b ** 2) * dA[3 + i] for i, b in enumerate(fit.lag_roots))
        assert np.allclose(steady, dQ[0].real, atol=1e-10)


def test_fit_derivative_rejects_wrong_shape():
    k, Q, dQ = _tables()
    fit = roger_fit(k, Q, 0.1, n_lags=2)
    with pytest.raises(ValueError, match="dQ must have"):
        roger_fit_derivative(fit, dQ[:, :2, :2])
