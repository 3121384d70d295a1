"""Real-parameter linear fractional transformations (asekit.ase.robust.polynomial_lft,
fit_polynomial, lft_state_matrix) and their mu through loop_matrix, on matrices and loops with
known answers (issue 26)."""

import itertools

import numpy as np
import pytest

from asekit.ase import robust
from asekit.ase.mu import mu_bounds

MONOMIALS = [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)]


def poly(A0, terms, d):
    return A0 + sum(np.prod(np.asarray(d) ** np.array(p)) * dA for p, dA in terms)


def random_terms(rng, n=5):
    """Low-rank coefficient matrices (ranks 1..3) for MONOMIALS."""
    return [(p, rng.standard_normal((n, r)) @ rng.standard_normal((r, n)))
            for p, r in zip(MONOMIALS, (2, 3, 1, 2, 1))]


def test_lft_reproduces_the_polynomial_exactly():
    """Zhou, Doyle & Glover 1996, Sec. 10.2: the LFT of a polynomial matrix is that polynomial
    for every parameter value (not only the sampled ones)."""
    rng = np.random.default_rng(1)
    A0 = rng.standard_normal((5, 5))
    terms = random_terms(rng)
    lft = robust.polynomial_lft(A0, terms, ("a", "b"))
    # a: (1,0) rank 2 + (1,1) rank 1 + (2,0) rank 2 twice = 7; b: 3 + 1 + 2 x 1 = 6
    assert lft.sizes == (7, 6)
    assert [b.kind for b in lft.blocks] == ["real", "real"]
    for d in itertools.chain(itertools.product((-1.0, 1.0), repeat=2),
                             rng.uniform(-1, 1, (10, 2))):
        np.testing.assert_allclose(robust.lft_state_matrix(lft, d), poly(A0, terms, d),
                                   rtol=1e-10, atol=1e-10)


def test_fit_recovers_a_quadratic_and_reports_its_residual():
    rng = np.random.default_rng(2)
    A0 = rng.standard_normal((4, 4))
    terms = random_terms(rng, 4)
    grid = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=2)))
    As = np.array([poly(A0, terms, d) for d in grid])
    A0f, fitted, res = robust.fit_polynomial(grid, As, MONOMIALS)
    np.testing.assert_allclose(A0f, A0, atol=1e-10)
    for (p, dA), (pf, dAf) in zip(terms, fitted):
        assert p == pf
        np.testing.assert_allclose(dAf, dA, atol=1e-10)
    assert np.abs(res).max() < 1e-10
    # a d1^2 d2^2 term (independent of the basis on the 3 x 3 grid; d^3 would not be, d^3 = d
    # there) shows up in the residual: the least-squares residual of 1 at the corners
    quartic = As + np.array([d[0] ** 2 * d[1] ** 2 * np.eye(4) for d in grid])
    _, _, res4 = robust.fit_polynomial(grid, quartic, MONOMIALS)
    assert np.abs(res4).max() > 0.1
    with pytest.raises(ValueError, match="rank-deficient"):
        robust.fit_polynomial(grid[:3], As[:3], MONOMIALS)
    with pytest.raises(ValueError, match="monomial"):
        robust.fit_polynomial(grid, As, [(3, 0)])


def test_mu_of_a_bilinear_parameter_loop():
    """x' = (a0 + a1 d1 + a12 d1 d2) x + u, y = x, u = -k y: the closed-loop pole
    a0 - k + a1 d1 + a12 d1 d2 (a1, a12 > 0) first reaches 0 on the box |d_i| <= alpha at the
    corner d1 = d2 = alpha, a0 - k + a1 alpha + a12 alpha^2 = 0; so mu(M(0)) = 1 / alpha
    (Packard & Doyle 1993, Def. 3.1 with a real pole crossing at s = 0)."""
    a0, a1, a12, k = 1.0, 0.6, 0.8, 3.0
    lft = robust.polynomial_lft(np.array([[a0]]), [((1, 0), np.array([[a1]])),
                                                   ((1, 1), np.array([[a12]]))], ("d1", "d2"))
    alpha = (-a1 + np.sqrt(a1 * a1 + 4 * a12 * (k - a0))) / (2 * a12)
    unc = robust.Uncertainty(lft=lft)
    one = np.array([[1.0]])
    r = robust.robust_stability(one * a0, one, one, lambda w: -k, unc, [0.0], delay=0.0)
    assert r["blocks"] == lft.blocks
    # the LFT's M(0) at the worst corner is singular: a verified destabilising perturbation
    assert r["mu_peak_lower"] <= 1 / alpha + 1e-9 <= r["mu_peak"] + 2e-9
    # the D-G bound (diagonal D on the repeated d1) is not exact in general; here it meets the
    # lower bound (measured: both 0.8 to 1e-13)
    assert r["mu_peak"] == pytest.approx(1 / alpha, rel=1e-6)
    # the destabilising corner: det(I - M Delta) = 0 at Delta = alpha diag(1, 1, 1)
    M = r["M"][0]
    assert abs(np.linalg.det(np.eye(3) - M * alpha)) < 1e-9
    with pytest.raises(ValueError, match="lft.A0"):
        robust.loop_matrix(np.eye(2), np.ones((2, 1)), np.ones((1, 2)), lambda w: -k, unc,
                           [0.0], delay=0.0)


def test_lft_input_errors():
    with pytest.raises(ValueError, match="monomial"):
        robust.polynomial_lft(np.eye(2), [((1, 1, 1), np.eye(2))], ("a", "b"))
    with pytest.raises(ValueError, match="every parameter"):
        robust.polynomial_lft(np.eye(2), [((1, 0), np.eye(2))], ("a", "b"))
    lft = robust.polynomial_lft(np.eye(2), [((1, 0), np.eye(2)), ((0, 1), np.eye(2))],
                                ("a", "b"))
    with pytest.raises(ValueError, match="deltas"):
        robust.lft_state_matrix(lft, [0.1])
    mu = mu_bounds(np.zeros((4, 4)), lft.blocks)
    assert mu.upper == 0.0
