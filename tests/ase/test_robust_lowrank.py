"""The low-rank LFT of a polynomial state matrix (asekit.ase.robust.lowrank_polynomial_lft,
issue 26): a real parameter's repeated-block size is the rank of its coefficient matrices
(Zhou, Doyle & Glover 1996, Sec. 10.2), so truncating their SVDs shrinks the blocks, within a
stated bound on the dropped part."""

import itertools

import numpy as np
import pytest

from asekit.ase import robust
from asekit.ase.mu import Block, mixed_upper_bound, mu_bounds, rank_one_mu

MONOMIALS = [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)]


def poly(A0, terms, d):
    return A0 + sum(np.prod(np.asarray(d) ** np.array(p)) * dA for p, dA in terms)


def rows_terms(rng, n=12, rows=3, noise=0.0):
    """Coefficient matrices that change only ``rows`` rows of A (as the flight condition
    changes only the aeroelastic rows of the fin's state matrix): each has rank <= rows and
    all share one column space; ``noise`` adds a full-rank part of that relative size."""
    E = np.zeros((n, rows))
    E[rng.choice(n, rows, replace=False), range(rows)] = 1.0
    out = []
    for p in MONOMIALS:
        dA = E @ rng.standard_normal((rows, n))
        out.append((p, dA + noise * np.linalg.norm(dA, 2) * rng.standard_normal((n, n)) / n))
    return out


def box(rng):
    return itertools.chain(itertools.product((-1.0, 0.0, 1.0), repeat=2),
                           rng.uniform(-1, 1, (20, 2)))


def test_exact_low_rank_polynomial_is_reproduced_with_smaller_blocks():
    """Rank-3 terms sharing their column space: per term (polynomial_lft) a: 3 + 3 + 2 x 3 =
    12, b: 3 + 3 + 2 x 3 = 12; shared column space (lowrank): a: 3 (outer, [A_a A_aa A_ab])
    + 3 (inner of a^2) = 6, b: 3 (outer) + 3 (b^2) + 3 (inner of ab) = 9; exact (nothing
    dropped)."""
    rng = np.random.default_rng(3)
    A0 = rng.standard_normal((12, 12))
    terms = rows_terms(rng)
    full = robust.polynomial_lft(A0, terms, ("a", "b"))
    low = robust.lowrank_polynomial_lft(A0, terms, ("a", "b"), rtol=1e-9)
    assert full.sizes == (12, 12)
    assert low.sizes == (6, 9)
    assert low.truncation < 1e-9 * max(np.linalg.norm(t[1], 2) for t in terms)
    for d in box(rng):
        np.testing.assert_allclose(robust.lft_state_matrix(low, d), poly(A0, terms, d),
                                   rtol=1e-10, atol=1e-10)


def test_truncation_is_bounded_by_the_stated_tolerance():
    """Full-rank noise of relative size 1e-6 on rank-3 terms: polynomial_lft at its numerical
    rank keeps nearly every channel (up to 12 per term); the low-rank LFT at rtol 1e-4 drops the noise,
    keeps the blocks of the exact case, and its error over the unit box stays below its
    ``truncation`` bound, itself of the order of the noise (a few rtol x the terms' size)."""
    rng = np.random.default_rng(4)
    A0 = rng.standard_normal((12, 12))
    terms = rows_terms(rng, noise=1e-6)
    assert min(robust.polynomial_lft(A0, terms, ("a", "b")).sizes) > 40     # of 48
    low = robust.lowrank_polynomial_lft(A0, terms, ("a", "b"), rtol=1e-4)
    assert low.sizes == (6, 9)
    scale = max(np.linalg.norm(t[1], 2) for t in terms)
    assert 0 < low.truncation < 1e-4 * scale
    err = max(np.linalg.norm(robust.lft_state_matrix(low, d) - poly(A0, terms, d), 2)
              for d in box(rng))
    assert 0 < err <= low.truncation
    # a looser tolerance drops real content: a larger bound, and the error still under it
    loose = robust.lowrank_polynomial_lft(A0, terms, ("a", "b"), rtol=0.6)
    assert sum(loose.sizes) < sum(low.sizes) and loose.truncation > 1e-3 * scale
    err = max(np.linalg.norm(robust.lft_state_matrix(loose, d) - poly(A0, terms, d), 2)
              for d in box(rng))
    assert err <= loose.truncation


def test_rank_one_parameter_dependence_has_its_analytic_mu():
    """A(d) = A0 + (a d1 + b d2) u u^T with A0 symmetric negative definite: A(d) stays symmetric,
    so it can lose stability only through a real eigenvalue at s = 0, where det A(d) = 0 <=>
    (a d1 + b d2) g = -1, g = u^T A0^-1 u; on the box |d_i| <= alpha the smallest alpha is
    1 / ((|a| + |b|) |g|), so mu(M(0)) = (|a| + |b|) |g| (Packard & Doyle 1993, Def. 3.1).
    The LFT has two scalar blocks and M(0) is rank one: the mixed bound and rank_one_mu
    (Young 1994) are exact."""
    rng = np.random.default_rng(5)
    Q = rng.standard_normal((4, 4))
    A0 = -(Q @ Q.T + np.eye(4))
    u = rng.standard_normal((4, 1))
    a, b = 0.7, -1.3
    terms = [((1, 0), a * u @ u.T), ((0, 1), b * u @ u.T)]
    lft = robust.lowrank_polynomial_lft(A0, terms, ("d1", "d2"))
    assert lft.sizes == (1, 1)
    g = (u.T @ np.linalg.solve(A0, u)).item()
    mu_exact = (abs(a) + abs(b)) * abs(g)
    one = np.ones((4, 1))
    Ms, blocks = robust.loop_matrix(A0, one, one.T, lambda w: 0.0,
                                    robust.Uncertainty(lft=lft), [0.0], delay=0.0)
    M = Ms[0]
    assert np.linalg.matrix_rank(M, tol=1e-10 * np.abs(M).max()) == 1
    U, s, Vh = np.linalg.svd(M)
    assert rank_one_mu(U[:, 0] * s[0], Vh[0].conj(), blocks) == pytest.approx(mu_exact,
                                                                                rel=1e-9)
    r = mu_bounds(M, blocks)
    assert r.lower == pytest.approx(mu_exact, rel=1e-6)
    assert r.upper == pytest.approx(mu_exact, rel=1e-6)
    assert mixed_upper_bound(M, blocks)[0] == pytest.approx(mu_exact, rel=1e-6)
    assert blocks == (Block(1, "real"), Block(1, "real"))


def test_lowrank_input_errors():
    with pytest.raises(ValueError, match="rtol"):
        robust.lowrank_polynomial_lft(np.eye(2), [((1,), np.eye(2))], ("a",), rtol=0.0)
    with pytest.raises(ValueError, match="every parameter"):
        robust.lowrank_polynomial_lft(np.eye(2), [((1, 0), np.eye(2))], ("a", "b"))
    with pytest.raises(ValueError, match="zero"):
        robust.lowrank_polynomial_lft(np.eye(2), [((1,), np.zeros((2, 2)))], ("a",))
    with pytest.raises(ValueError, match="monomial"):
        robust.lowrank_polynomial_lft(np.eye(2), [((3,), np.eye(2))], ("a",))
