"""Full D-G scalings of the mixed-mu upper bound on repeated scalar blocks
(asekit.ase.mu.full_dg_upper_bound, issue 26), against structures whose mu is known in closed
form (Packard & Doyle, "The complex structured singular value", Automatica 29(1), 1993;
Fan, Tits & Doyle, IEEE TAC 36(1), 1991)."""

import numpy as np
import pytest

from asekit.ase.mu import Block, full_dg_upper_bound, lower_bound, mixed_upper_bound, upper_bound


def similar(rng, eigenvalues):
    """M = S diag(eigenvalues) S^-1, S a random complex (non-unitary) similarity."""
    r = len(eigenvalues)
    S = rng.standard_normal((r, r)) + 1j * rng.standard_normal((r, r))
    return S @ np.diag(eigenvalues) @ np.linalg.inv(S)


def certificate(M, blocks, beta, T, G):
    """The bound's LMI at the returned scalings (Fan, Tits & Doyle 1991): with D = T^H T and
    G = T^H Gh T, M^H D M + j (G M - M^H G) - beta^2 D must be negative semidefinite, D must be
    in the commutant (block-diagonal) and G zero on the complex blocks."""
    D, Gf = T.conj().T @ T, T.conj().T @ G @ T
    L = M.conj().T @ D @ M + 1j * (Gf @ M - M.conj().T @ Gf) - beta ** 2 * D
    k = 0
    for b in blocks:
        s = slice(k, k + b.size)
        off = np.ones(len(M), bool)
        off[s] = False
        assert np.allclose(D[s][:, off], 0) and np.allclose(Gf[s][:, off], 0)
        if b.kind != "real":
            assert np.allclose(Gf[s, s], 0)
        if b.kind == "full":
            assert np.allclose(D[s, s], D[k, k] * np.eye(b.size))
        k += b.size
    return np.linalg.eigvalsh(0.5 * (L + L.conj().T)).max() / np.linalg.eigvalsh(D).max()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_repeated_real_scalar_is_the_largest_real_eigenvalue(seed):
    """delta I_r real: det(I - delta M) = 0 iff 1/delta is a real eigenvalue of M, so mu =
    max |lambda| over M's real eigenvalues (0.8 here; the complex pair 0.5 +- 0.9j and 1.2j,
    larger in modulus, do not count). The diagonal D-G bound is far above it for a non-normal
    M; the full bound reaches it (T = S^-1, Gh diagonal)."""
    rng = np.random.default_rng(seed)
    M = similar(rng, [0.8, -0.3, 0.5 + 0.9j, 0.5 - 0.9j, 1.2j])
    blocks = [Block(5, "real")]
    beta, T, G = full_dg_upper_bound(M, blocks)
    assert beta == pytest.approx(0.8, rel=1e-6)
    assert mixed_upper_bound(M, blocks)[0] > 1.5 * 0.8
    assert certificate(M, blocks, beta * (1 + 1e-9), T, G) <= 1e-9
    assert lower_bound(M, blocks)[0] <= 0.8 + 1e-9


def test_repeated_real_scalar_without_real_eigenvalue_is_zero():
    rng = np.random.default_rng(3)
    M = similar(rng, [0.5 + 0.9j, 0.5 - 0.9j, 2.0j])
    beta, _, _ = full_dg_upper_bound(M, [Block(3, "real")])
    assert beta == 0.0


def test_rank_one_repeated_real():
    """M = u v^H with delta I_r real: det(I - delta u v^H) = 1 - delta v^H u, so mu = |v^H u| if
    v^H u is real, else 0 (Young, Automatica 30(12), 1994, rank-one mixed mu)."""
    rng = np.random.default_rng(4)
    u, v = rng.standard_normal(4), rng.standard_normal(4)
    M = np.outer(u, v).astype(complex)
    assert full_dg_upper_bound(M, [Block(4, "real")])[0] == pytest.approx(abs(v @ u),
                                                                           rel=1e-6)
    vc = v + 1j * rng.standard_normal(4)
    assert abs(np.vdot(vc, u).imag) > 0.1
    assert full_dg_upper_bound(np.outer(u, vc.conj()), [Block(4, "real")])[0] \
        <= 1e-6 * abs(np.vdot(vc, u))


def test_repeated_complex_scalar_is_the_spectral_radius():
    """delta I_r complex: mu = rho(M) (Packard & Doyle 1993, Sec. 3), reached by the full D =
    S^-H S^-1 for a diagonalisable M; the diagonal D bound of upper_bound is above it."""
    rng = np.random.default_rng(5)
    M = similar(rng, [0.9, 0.4j, -0.6 + 0.2j, 0.1])
    blocks = [Block(4, "complex")]
    beta, T, G = full_dg_upper_bound(M, blocks)
    assert beta == pytest.approx(0.9, rel=1e-6)
    assert upper_bound(M, blocks)[0] > 1.2 * 0.9
    assert certificate(M, blocks, beta * (1 + 1e-9), T, G) <= 1e-9


def test_block_triangular_mixed_structure():
    """M = [[M1, C], [0, M2]] with M1 seen by delta I_3 real (mu 0.5: its real eigenvalue; the
    pair 0.3 +- 0.9j does not count) and M2 by a full 2 x 2 complex block (mu = sigma_max(M2)
    = 0.4): det(I - M Delta) = det(I - M1 Delta_1) det(I - M2 Delta_2) for any coupling C, so
    mu(M) = max = 0.5; the coupling (norm 2) must be scaled away by D."""
    rng = np.random.default_rng(6)
    M1 = similar(rng, [0.5, 0.3 + 0.9j, 0.3 - 0.9j])
    M2 = rng.standard_normal((2, 2)) + 1j * rng.standard_normal((2, 2))
    M2 *= 0.4 / np.linalg.norm(M2, 2)
    M = np.zeros((5, 5), complex)
    M[:3, :3], M[3:, 3:] = M1, M2
    M[:3, 3:] = rng.standard_normal((3, 2))
    M[:3, 3:] *= 2.0 / np.linalg.norm(M[:3, 3:], 2)
    blocks = [Block(3, "real"), Block(2, "full")]
    beta, T, G = full_dg_upper_bound(M, blocks)
    assert beta == pytest.approx(0.5, rel=1e-4)
    assert certificate(M, blocks, beta * (1 + 1e-9), T, G) <= 1e-9


def test_never_above_the_diagonal_bound_and_always_above_the_lower_bound():
    """On random mixed structures the full bound starts from the diagonal D-G point, so it is
    never above it, and stays above the verified lower bound (both bounds of one mu)."""
    rng = np.random.default_rng(7)
    blocks = [Block(2, "real"), Block(1, "real"), Block(2, "complex"), Block(2, "full")]
    for _ in range(3):
        M = rng.standard_normal((7, 7)) + 1j * rng.standard_normal((7, 7))
        diag = mixed_upper_bound(M, blocks)
        full, T, G = full_dg_upper_bound(M, blocks, start=diag[1:])
        assert full <= diag[0] * (1 + 1e-12)
        assert lower_bound(M, blocks)[0] <= full * (1 + 1e-9)
        assert certificate(M, blocks, full * (1 + 1e-9), T, G) <= 1e-9
