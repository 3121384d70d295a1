"""Structured singular value mu: an upper bound by D-scaling and a lower bound by power
iteration, so every result carries its gap (issue 26).

For a complex matrix M (n x n) and a block structure Delta = diag(Delta_1, ..., Delta_m),

    mu(M) = 1 / min{ sigma_max(Delta) : Delta in the structure, det(I - M Delta) = 0 }

(0 if no Delta makes I - M Delta singular; Packard & Doyle, "The complex structured singular
value", Automatica 29(1), 1993, Definition 3.1). A block is a :class:`Block`:

* ``Block(n, "full")``   a full complex n x n block (unmodelled dynamics);
* ``Block(n, "complex")`` a repeated complex scalar delta I_n (n = 1: a complex scalar);
* ``Block(n, "real")``    a repeated real scalar delta I_n (a real parameter).

Bounds (Packard & Doyle 1993, Eqs 6.1-6.2 and Sec. 8-9):

* lower: for any Delta in the unit ball of the structure, rho(M Delta) <= mu(M) (complex
  blocks; Eq. 8.1: mu = max rho(M Delta)); for real blocks the eigenvalue must be real and
  positive-or-negative real, rho_R(M Delta) <= mu (Young & Doyle 1990). The perturbation is
  found by the power iteration of Packard & Doyle 1993, Sec. 9.2 (Eqs 9.5-9.8), and the bound
  reported is the eigenvalue it actually reaches (verified, never the iterate's estimate);
* upper: mu(M) <= inf_D sigma_max(D M D^-1) over positive D that commute with the structure
  (Eq. 6.2): one scalar d per full block (d I_n), a positive diagonal per repeated scalar block
  (a subset of its commutant, so the bound stays valid). log sigma_max(e^X M e^-X) is convex in
  the diagonal X (Sezginer & Overton, IEEE TAC 35(2), 1990), so a quasi-Newton descent from
  Osborne's balancing (Osborne, "On pre-conditioning of matrices", J. ACM 7, 1960) reaches the
  global infimum; its gradient is sigma (|u_k|^2 - |v_k|^2) summed over the block's entries,
  with u, v the top singular vectors.

For real blocks the upper bound is the complex one (a real block is a complex block restricted
to real values, so mu_complex >= mu_real): conservative, stated, no D-G scaling. The bound is
exact (gap 0 up to the optimiser's tolerance) for 2 S + F <= 3 complex blocks, S repeated
scalar, F full (Packard & Doyle 1993, Theorem 9.1; Sec. 9 of the paper).

Plain numpy/scipy; no toolbox needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

KINDS = ("full", "complex", "real")


@dataclass(frozen=True)
class Block:
    """One block of the structure: ``size`` >= 1 and ``kind`` one of :data:`KINDS`."""

    size: int
    kind: str = "complex"

    def __post_init__(self):
        if int(self.size) != self.size or self.size < 1:
            raise ValueError(f"Block.size must be an integer >= 1, got {self.size!r}")
        if self.kind not in KINDS:
            raise ValueError(f"Block.kind must be one of {KINDS}, got {self.kind!r}")


@dataclass(frozen=True)
class MuBounds:
    """Bounds of mu at one matrix: ``lower`` <= mu <= ``upper``; ``scaling`` the D diagonal
    (n,) of the upper bound; ``delta`` the (n, n) perturbation of the lower bound
    (sigma_max(delta) <= 1, rho(M delta) = lower)."""

    lower: float
    upper: float
    scaling: np.ndarray
    delta: np.ndarray

    @property
    def gap(self) -> float:
        """(upper - lower) / upper (0 when exact; 1 when the lower bound found nothing)."""
        return 0.0 if self.upper == 0 else (self.upper - self.lower) / self.upper


def _check(M, blocks):
    M = np.atleast_2d(np.asarray(M, dtype=complex))
    if M.ndim != 2 or M.shape[0] != M.shape[1]:
        raise ValueError(f"M must be a square matrix, got shape {M.shape}")
    blocks = tuple(blocks)
    if not blocks or not all(isinstance(b, Block) for b in blocks):
        raise ValueError("blocks must be a non-empty sequence of Block")
    n = sum(b.size for b in blocks)
    if n != M.shape[0]:
        raise ValueError(f"the blocks' sizes add up to {n}, but M is {M.shape[0]} x "
                         f"{M.shape[0]}")
    if not np.all(np.isfinite(M)):
        raise ValueError("M must be finite")
    return M, blocks


def _groups(blocks):
    """Index arrays of the free scaling variables: one per full block, one per entry of a
    repeated scalar block."""
    out, k = [], 0
    for b in blocks:
        if b.kind == "full":
            out.append(np.arange(k, k + b.size))
        else:
            out.extend(np.array([k + i]) for i in range(b.size))
        k += b.size
    return out


def _expand(x, groups, n):
    d = np.empty(n)
    for xi, g in zip(x, groups):
        d[g] = xi
    return d


def _osborne(M, groups, sweeps: int = 20):
    """Osborne's balancing of |M| (row and column norms equal per group), log scales."""
    A = np.abs(M)
    x = np.zeros(len(groups))
    n = M.shape[0]
    for _ in range(sweeps):
        for i, g in enumerate(groups):
            d = np.exp(_expand(x, groups, n))
            S = d[:, None] * A / d[None, :]
            mask = np.ones(n, bool)
            mask[g] = False
            r = np.linalg.norm(S[np.ix_(g, mask)])
            c = np.linalg.norm(S[np.ix_(mask, g)])
            if r > 0 and c > 0:
                x[i] += 0.5 * np.log(c / r)
    return x - x[0]


def upper_bound(M, blocks, x0=None):
    """inf_D sigma_max(D M D^-1) (Packard & Doyle 1993, Eq. 6.2): returns (bound, d) with d
    the (n,) diagonal of the optimal D. ``x0``: a starting log-scaling per group (warm start
    over frequency).

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[1.0, 100.0], [0.01, 1.0]])
    >>> round(upper_bound(M, [Block(1), Block(1)])[0], 6)     # |1| + sqrt(100 * 0.01)
    2.0
    """
    from scipy.optimize import minimize

    M, blocks = _check(M, blocks)
    n = M.shape[0]
    groups = _groups(blocks)
    if len(groups) == 1:
        return float(np.linalg.norm(M, 2)), np.ones(n)

    def f(z):
        x = np.concatenate([[0.0], z])
        d = np.exp(_expand(x, groups, n))
        N = d[:, None] * M / d[None, :]
        U, s, Vh = np.linalg.svd(N)
        u, v = U[:, 0], Vh[0].conj()
        w = np.abs(u) ** 2 - np.abs(v) ** 2
        g = np.array([w[gi].sum() for gi in groups])
        return np.log(max(s[0], 1e-300)), g[1:]

    start = _osborne(M, groups) if x0 is None else np.asarray(x0, float) - x0[0]
    z0 = start[1:]
    res = minimize(f, z0, jac=True, method="BFGS", options={"gtol": 1e-9, "maxiter": 500})
    z = res.x if res.fun <= f(z0)[0] else z0
    best = min(float(np.exp(f(z)[0])), float(np.linalg.norm(M, 2)))
    return best, np.exp(_expand(np.concatenate([[0.0], z]), groups, n))


def _slices(blocks):
    k, out = 0, []
    for b in blocks:
        out.append(slice(k, k + b.size))
        k += b.size
    return out


def _delta_of(a, w, blocks):
    """The perturbation aligning a (the input of Delta's output side) with w (Eq. 9.8)."""
    n = len(a)
    D = np.zeros((n, n), complex)
    for b, s in zip(blocks, _slices(blocks)):
        ai, wi = a[s], w[s]
        if b.kind == "full":
            na, nw = np.linalg.norm(ai), np.linalg.norm(wi)
            if na > 0 and nw > 0:
                D[s, s] = np.outer(wi, ai.conj()) / (na * nw)
        else:
            q = np.vdot(ai, wi)                     # a^* w
            ph = q / abs(q) if abs(q) > 0 else 1.0
            if b.kind == "real":
                ph = 1.0 if np.real(ph) >= 0 else -1.0
            D[s, s] = ph * np.eye(b.size)
    return D


def _rho(M, D, real):
    lam = np.linalg.eigvals(M @ D)
    if real:
        lam = lam[np.abs(lam.imag) <= 1e-9 * max(1.0, np.max(np.abs(lam)))]
        return float(np.max(np.abs(lam.real))) if lam.size else 0.0
    return float(np.max(np.abs(lam)))


def lower_bound(M, blocks, iterations: int = 200, starts: int = 4, seed: int = 0):
    """max over the tried perturbations Delta (sigma_max <= 1, in the structure) of
    rho(M Delta) (rho_R, the largest real eigenvalue's magnitude, when a block is real):
    a verified lower bound of mu. Delta from the power iteration of Packard & Doyle 1993,
    Sec. 9.2 (beta a = M b, z = aligned a, alpha w = M^* z, b = aligned w), started from the top
    singular vectors of M and ``starts`` - 1 random vectors. Returns (bound, Delta).

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[0.5, 2.0], [0.0, 0.5]])
    >>> bool(abs(lower_bound(M, [Block(2, "full")])[0] - np.linalg.norm(M, 2)) < 1e-9)
    True
    """
    M, blocks = _check(M, blocks)
    n = M.shape[0]
    real = any(b.kind == "real" for b in blocks)
    rng = np.random.default_rng(seed)
    U, _, Vh = np.linalg.svd(M)
    inits = [Vh[0].conj()] + [rng.standard_normal(n) + 1j * rng.standard_normal(n)
                              for _ in range(max(0, starts - 1))]
    best, best_D = 0.0, np.eye(n, dtype=complex)
    sl = _slices(blocks)
    for b in inits:
        b = b / np.linalg.norm(b)
        w = b.copy()
        for it in range(int(iterations)):
            a = M @ b
            if np.linalg.norm(a) == 0:
                break
            a = a / np.linalg.norm(a)
            z = _align(a, w, blocks, sl)
            w = M.conj().T @ z
            if np.linalg.norm(w) == 0:
                break
            w = w / np.linalg.norm(w)
            b_new = _align(w, a, blocks, sl)
            done = np.linalg.norm(b_new - b) < 1e-10 * max(np.linalg.norm(b), 1e-300)
            b = b_new
            if done or it % 25 == 24:
                D = _delta_of(a, w, blocks)
                r = _rho(M, D, real)
                if r > best:
                    best, best_D = r, D
            if done:
                break
    return best, best_D


def _align(x, y, blocks, slices=None):
    """Per block: x's direction scaled to y's norm (full), or x with y's block norms and
    phases matched for scalar blocks (Packard & Doyle 1993, Eqs 9.6-9.7)."""
    out = np.empty_like(x)
    for blk, s in zip(blocks, _slices(blocks) if slices is None else slices):
        xi, yi = x[s], y[s]
        if blk.kind == "full":
            nx = math.sqrt(np.vdot(xi, xi).real)
            ny = math.sqrt(np.vdot(yi, yi).real)
            out[s] = xi * (ny / nx) if nx > 0 else yi
        else:
            q = complex(np.vdot(yi, xi))
            ph = q / abs(q) if q != 0 else 1.0
            if blk.kind == "real":
                ph = 1.0 if ph.real >= 0 else -1.0
            out[s] = ph * yi
    return out


def mu_bounds(M, blocks, x0=None, iterations: int = 200, starts: int = 4) -> MuBounds:
    """Both bounds of mu(M) for ``blocks`` (module docstring).

    Parameters
    ----------
    M : (n, n) complex matrix, the loop seen by the perturbation (Delta's output to its input).
    blocks : sequence of :class:`Block` whose sizes add up to n.
    x0 : optional warm start of the upper bound's log scalings.
    iterations, starts : of the lower bound's power iteration (:func:`lower_bound`).

    Returns
    -------
    MuBounds (lower, upper, scaling, delta).

    Examples
    --------
    >>> import numpy as np
    >>> u, v = np.array([1.0, 2.0]), np.array([3.0, -1.0])
    >>> b = mu_bounds(np.outer(u, v), [Block(1), Block(1)])   # rank one: sum |u_i v_i| = 5
    >>> round(b.lower, 4), round(b.upper, 4)
    (5.0, 5.0)
    """
    M, blocks = _check(M, blocks)
    up, d = upper_bound(M, blocks, x0)
    lo, D = lower_bound(M, blocks, iterations, starts)
    return MuBounds(lower=float(min(lo, up)), upper=float(up), scaling=d, delta=D)


def mu_frequency(Ms, blocks, iterations: int = 100, starts: int = 2) -> dict:
    """Bounds of mu over a frequency grid: ``Ms`` (n_f, n, n) the loop matrix at each
    frequency. Warm starts the D-scaling from the previous frequency. Returns ``{"lower":
    (n_f,), "upper": (n_f,), "peak_upper": float, "i_peak": int}``.

    Examples
    --------
    >>> import numpy as np
    >>> Ms = np.array([np.diag([a, 0.5]) for a in (0.1, 0.9, 0.3)])
    >>> r = mu_frequency(Ms, [Block(1), Block(1)])
    >>> round(r["peak_upper"], 6), r["i_peak"]
    (0.9, 1)
    """
    Ms = np.asarray(Ms, dtype=complex)
    if Ms.ndim != 3:
        raise ValueError(f"Ms must be (n_f, n, n), got shape {Ms.shape}")
    groups = _groups(_check(Ms[0], blocks)[1])
    lo, up = np.zeros(len(Ms)), np.zeros(len(Ms))
    x = None
    for i, M in enumerate(Ms):
        b = mu_bounds(M, blocks, x, iterations, starts)
        lo[i], up[i] = b.lower, b.upper
        x = np.array([np.log(b.scaling[g[0]]) for g in groups])
    i = int(np.argmax(up))
    return {"lower": lo, "upper": up, "peak_upper": float(up[i]), "i_peak": i}
