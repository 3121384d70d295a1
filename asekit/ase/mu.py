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

For complex blocks the bound is exact (gap 0 up to the optimiser's tolerance) for 2 S + F <= 3
blocks, S repeated scalar, F full (Packard & Doyle 1993, Theorem 9.1; Sec. 9 of the paper).

Mixed real/complex structures (:func:`mixed_upper_bound`, used by :func:`mu_bounds` whenever a
block is real): the D-G scaled bound of Fan, Tits & Doyle, "Robustness in the presence of mixed
parametric uncertainty and unmodeled dynamics", IEEE TAC 36(1), 1991 (their upper bound, a
largest generalised eigenvalue), shown by Young, Newlin & Doyle, "Computing bounds for the mixed
mu problem", IJRNC 5, 1995, to equal their (I + G^2)^-1/4 singular-value form (equation numbers
not checked against the papers here): mu(M) <= beta if there are D > 0 and G = G^* in the
commutants (G zero on the complex blocks) with

    M^* D M + j (G M - M^* G) - beta^2 D <= 0.

With N = D^1/2 M D^-1/2 and Gh = D^-1/2 G D^-1/2 (diagonal D and G commute) this reads
lambda_max(N^* N + j (Gh N - N^* Gh)) <= beta^2, so the bound is the square root of the
infimum of that largest eigenvalue over log d and Gh, started from the complex D (Gh = 0,
where it equals the complex bound, so the mixed bound never exceeds it). Any (d, Gh) gives a
valid bound; the optimiser only tightens it. A real scalar whose loop gain is not real gets
bound 0 (the G term drives the eigenvalue negative), which the complex bound cannot see. The
bound is exact for rank-one M (Young, "The rank one mixed mu problem and 'Kharitonov-type'
analysis", Automatica 30(12), 1994), whose mu has the closed form of :func:`rank_one_mu`.

The diagonal D and G are a subset of the commutant of a repeated scalar block delta I_r, whose
D may be any Hermitian positive definite r x r and G any Hermitian r x r:
:func:`full_dg_upper_bound` optimises over the full set (D = T^H T, block-diagonal T, module
text of the function), which reaches mu = max |real eigenvalue| of a diagonalisable M under one
repeated real scalar, and rho(M) under a repeated complex one, where the diagonal scalings
stay far above for a non-normal M. It is meant for the small repeated blocks of a low-rank LFT
(:func:`asekit.ase.robust.lowrank_polynomial_lft`): 4 r^2 real variables per real block.

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
    (sigma_max(delta) <= 1, rho(M delta) = lower); ``g_scaling`` the G of the mixed bound."""

    lower: float
    upper: float
    scaling: np.ndarray
    delta: np.ndarray
    #: the (n,) real diagonal Gh of the mixed bound (zeros without real blocks)
    g_scaling: np.ndarray | None = None

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


def _groups(blocks, per_block: bool = False):
    """Index arrays of the free scaling variables: one per full block, one per entry of a
    repeated scalar block (``per_block``: one d I per block of any kind, a smaller subset of
    the commutant: a valid, possibly looser bound with far fewer variables)."""
    out, k = [], 0
    for b in blocks:
        if b.kind == "full" or per_block:
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


def upper_bound(M, blocks, x0=None, per_block: bool = False):
    """inf_D sigma_max(D M D^-1) (Packard & Doyle 1993, Eq. 6.2): returns (bound, d) with d
    the (n,) diagonal of the optimal D. ``x0``: a starting log-scaling per group (warm start
    over frequency). ``per_block``: D = d_i I on each block (for large repeated blocks: one
    variable per block instead of one per entry; still an upper bound).

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
    groups = _groups(blocks, per_block)
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


def _real_entries(blocks):
    """Indices of the entries of the real blocks (the free diagonal of G)."""
    out, k = [], 0
    for b in blocks:
        if b.kind == "real":
            out.extend(range(k, k + b.size))
        k += b.size
    return np.array(out, dtype=int)


def _dg_eig(M, d, gh, groups, ir, t):
    """lambda_max(Phi), Phi = N^* N + j (Gh N - N^* Gh), N = diag(d) M diag(d)^-1, Gh =
    diag(gh) on the entries ``ir``; its smooth majorant lambda_max + t log sum_i
    exp((lambda_i - lambda_max) / t) (t > 0, within t log n of lambda_max) and that
    majorant's gradient in (log d per group, gh): the softmax-weighted d lambda_i =
    v_i^* dPhi v_i, with dN/dx_k = E_k N - N E_k and dPhi/dgh_k = j (E_k N - N^* E_k)."""
    n = M.shape[0]
    N = d[:, None] * M / d[None, :]
    g = np.zeros(n)
    g[ir] = gh
    Phi = N.conj().T @ N + 1j * (g[:, None] * N - N.conj().T * g[None, :])
    lam, V = np.linalg.eigh(0.5 * (Phi + Phi.conj().T))
    e = np.exp((lam - lam[-1]) / t)
    w = e / e.sum()
    smooth = lam[-1] + t * math.log(e.sum())
    A = N @ V
    Bv = g[:, None] * V
    C, E = N.conj().T @ A, N.conj().T @ Bv
    GX = 2 * np.real(np.abs(A) ** 2 - C.conj() * V) - 2 * np.imag(Bv.conj() * A - E.conj() * V)
    gx = GX @ w
    gg = (-2 * np.imag(V.conj() * A)) @ w
    return float(lam[-1]), smooth, np.array([gx[gi].sum() for gi in groups]), gg[ir]


class _Done(Exception):
    """Raised inside the optimiser when the D-G matrix is negative definite (mu = 0)."""

    def __init__(self, z):
        super().__init__("mu = 0")
        self.z = np.array(z)


def mixed_upper_bound(M, blocks, x0=None, g0=None, per_block: bool = False):
    """The D-G scaled upper bound of mixed real/complex mu (Fan, Tits & Doyle 1991; Young,
    Newlin & Doyle 1995; module docstring):

        mu(M) <= sqrt(max(0, inf_{d, Gh} lambda_max(N^* N + j (Gh N - N^* Gh)))),

    N = diag(d) M diag(d)^-1, Gh real diagonal on the real blocks' entries. Returns (bound, d,
    g) with d (n,) and g (n,) (zero off the real blocks) at the optimum found. ``x0``, ``g0``:
    warm starts (log d per scaling group, Gh per real entry); by default the complex D of
    :func:`upper_bound` and Gh = 0, so the result never exceeds the complex bound.
    ``per_block``: D = d_i I per block (as :func:`upper_bound`); G stays diagonal per entry.

    Examples
    --------
    >>> import numpy as np
    >>> round(mixed_upper_bound(np.array([[0.7j]]), [Block(1, "real")])[0], 6)  # no real root
    0.0
    >>> round(mixed_upper_bound(np.array([[-0.7]]), [Block(1, "real")])[0], 6)
    0.7
    """
    from scipy.optimize import minimize

    M, blocks = _check(M, blocks)
    n = M.shape[0]
    groups = _groups(blocks, per_block)
    ir = _real_entries(blocks)
    if x0 is None:
        up, d = upper_bound(M, blocks, per_block=per_block)
        x0 = np.array([np.log(d[gi[0]]) for gi in groups])
    else:
        up = None
    x0 = np.asarray(x0, float) - x0[0]
    g0 = np.zeros(len(ir)) if g0 is None else np.asarray(g0, float)
    scale = max(float(np.linalg.norm(M, 2)) ** 2, 1e-300)
    m = len(groups) - 1

    seen = {}                                   # the best point evaluated: any is valid

    def f(z, t):
        d = np.exp(_expand(np.concatenate([[0.0], z[:m]]), groups, n))
        lam, smooth, gx, gg = _dg_eig(M, d, z[m:], groups, ir, t * scale)
        if lam < seen.get("lam", math.inf):
            seen["lam"], seen["z"] = lam, np.array(z)
        if lam <= 0:                            # certificate of mu = 0 found: stop here
            raise _Done(z)
        return smooth / scale, np.concatenate([gx[1:], gg]) / scale

    z = np.concatenate([x0[1:], g0])
    try:
        f(z, 1.0)
        if len(ir):                             # smoothing continuation: lambda_max is not
            for t, it in ((1e-3, 30), (1e-12, 100), (1e-12, 100)):  # smooth where
                rel = max(seen["lam"] / scale, 1e-9)             # eigenvalues coalesce; the
                z = minimize(f, seen["z"], args=(t * rel,), jac=True,   # last: lambda_max
                             method="BFGS", options={"gtol": 1e-9, "maxiter": it}).x
                f(z, 1.0)
        best_z, best = seen["z"], seen["lam"] / scale
    except _Done as done:
        best_z, best = done.z, 0.0
    bound = math.sqrt(max(best, 0.0) * scale)
    if up is not None:
        bound = min(bound, up)
    d = np.exp(_expand(np.concatenate([[0.0], best_z[:m]]), groups, n))
    g = np.zeros(n)
    g[ir] = best_z[m:]
    return bound, d, g


def _full_layout(blocks):
    """(slice, kind, number of T parameters, number of G parameters) per block for
    :func:`full_dg_upper_bound`: a full block's T = e^x I (1), a repeated scalar's T any complex
    r x r (2 r^2), a real block's Gh = (Y + Y^H) / 2 with Y any complex r x r (2 r^2)."""
    out = []
    for b, s in zip(blocks, _slices(blocks)):
        r2 = 2 * b.size * b.size
        out.append((s, b.kind, 1 if b.kind == "full" else r2, r2 if b.kind == "real" else 0))
    return out


def _full_unpack(z, layout, n):
    T, G = np.zeros((n, n), complex), np.zeros((n, n), complex)
    k = 0
    for s, kind, nt, _ in layout:
        r = s.stop - s.start
        if kind == "full":
            T[s, s] = math.exp(z[k]) * np.eye(r)
        else:
            T[s, s] = (z[k:k + nt // 2] + 1j * z[k + nt // 2:k + nt]).reshape(r, r)
        k += nt
    for s, kind, _, ng in layout:
        if ng:
            r = s.stop - s.start
            Y = (z[k:k + ng // 2] + 1j * z[k + ng // 2:k + ng]).reshape(r, r)
            G[s, s] = 0.5 * (Y + Y.conj().T)
            k += ng
    return T, G


def _full_pack(T, G, layout):
    zt, zg = [], []
    for s, kind, _, ng in layout:
        Tb = T[s, s]
        if kind == "full":
            zt.append([math.log(abs(Tb[0, 0]))])
        else:
            zt += [Tb.real.ravel(), Tb.imag.ravel()]
        if ng:
            zg += [G[s, s].real.ravel(), G[s, s].imag.ravel()]
    return np.concatenate(zt + zg)


def _full_dg_eig(M, z, layout, t):
    """lambda_max of Phi = N^H N + j (Gh N - N^H Gh), N = T M T^-1 (block-diagonal T and
    Hermitian Gh of :func:`_full_unpack`), its softmax majorant (as :func:`_dg_eig`) and the
    majorant's gradient in z: with W = V diag(softmax) V^H, dN = E N - N E for dT = E T, so
    d lambda = Re tr(R E), R = 2 (N Q - Q N), Q = W (N^H + j Gh), and d lambda / dGh =
    S = j (N W - W N^H) (Hermitian)."""
    n = M.shape[0]
    T, G = _full_unpack(z, layout, n)
    Ti = np.zeros_like(T)
    for s, _, _, _ in layout:
        Ti[s, s] = np.linalg.inv(T[s, s])
    N = T @ M @ Ti
    NH = N.conj().T
    Phi = NH @ N + 1j * (G @ N - NH @ G)
    lam, V = np.linalg.eigh(0.5 * (Phi + Phi.conj().T))
    e = np.exp((lam - lam[-1]) / t)
    w = e / e.sum()
    smooth = lam[-1] + t * math.log(e.sum())
    W = (V * w) @ V.conj().T
    Q = W @ (NH + 1j * G)
    Gam = Ti @ (2 * (N @ Q - Q @ N))                # d lambda = Re tr(Gam dT)
    S = 1j * (N @ W - W @ NH)                       # d lambda = Re tr(S dY)
    gt, gg = [], []
    for s, kind, _, ng in layout:
        Gb = Gam[s, s]
        if kind == "full":
            gt.append([float(np.real(np.trace(Gb @ T[s, s])))])
        else:
            gt += [Gb.real.T.ravel(), -Gb.imag.T.ravel()]
        if ng:
            gg += [S[s, s].real.T.ravel(), -S[s, s].imag.T.ravel()]
    return float(lam[-1]), smooth, np.concatenate(gt + gg)


def full_dg_upper_bound(M, blocks, start=None, maxiter: int = 200):
    """The mixed-mu upper bound with full D-G scalings on the repeated scalar blocks (Fan,
    Tits & Doyle, IEEE TAC 36(1), 1991; Young, Newlin & Doyle, IJRNC 5, 1995):

        mu(M) <= beta  if  M^H D M + j (G M - M^H G) - beta^2 D <= 0

    for some D > 0 and G = G^H in the commutants: D = d I on a full block, any Hermitian
    positive definite r x r on a repeated (real or complex) scalar block delta I_r, G any
    Hermitian r x r on a real repeated block and zero elsewhere (the diagonal D, G of
    :func:`mixed_upper_bound` are a subset). With D = T^H T (T block-diagonal, invertible,
    T = t I on full blocks), N = T M T^-1 and Gh = T^-H G T^-1 the condition is
    lambda_max(N^H N + j (Gh N - N^H Gh)) <= beta^2, and Gh ranges over the same set as G;
    so every (T, Gh) gives a valid bound, and the optimiser (L-BFGS on a smoothed
    lambda_max, analytic gradient; :func:`_full_dg_eig`; limited memory: thousands of
    variables for blocks of a few tens) only tightens it. A repeated real
    block with a diagonalisable M = S diag(lambda) S^-1 reaches mu = max |lambda| over the real
    eigenvalues (T = S^-1, Gh diagonal), which no diagonal D gives for a non-normal M.

    ``start``: (d, g) as returned by :func:`mixed_upper_bound` (default: computed here), the
    diagonal starting point, so the result never exceeds that bound; ``maxiter``: (L-)BFGS
    iterations per smoothing stage (BFGS up to 400 variables, L-BFGS above) (five stages, the softmax width from lambda_max itself down
    to 1e-10 of it). Returns (bound, T, Gh).

    Examples
    --------
    >>> import numpy as np
    >>> S = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 1.0], [1.0, 0.0, 1.0]])
    >>> L = np.array([[0.5, 0.0, 0.0], [0.0, 0.3, 0.8], [0.0, -0.8, 0.3]])
    >>> M = S @ L @ np.linalg.inv(S)       # eigenvalues 0.5, 0.3 +- 0.8j: mu = 0.5 for delta I_3
    >>> round(full_dg_upper_bound(M, [Block(3, "real")])[0], 6)
    0.5
    >>> round(mixed_upper_bound(M, [Block(3, "real")])[0], 2)     # diagonal D and G
    1.17
    """
    from scipy.optimize import minimize

    M, blocks = _check(M, blocks)
    n = M.shape[0]
    layout = _full_layout(blocks)
    if start is None:
        b0, d, g = mixed_upper_bound(M, blocks)
    else:
        d, g = (np.asarray(x, float) for x in start)
        b0 = None
    T0, G0 = np.diag(d.astype(complex)), np.diag(g.astype(complex))
    z0 = _full_pack(T0, G0, layout)
    scale = max(float(np.linalg.norm(M, 2)) ** 2, 1e-300)
    seen = {}
    if len(z0) <= 400:                 # dense BFGS (its update is O(n^3) per iteration)
        method, opts = "BFGS", {"maxiter": maxiter, "gtol": 1e-12}
    else:
        method, opts = "L-BFGS-B", {"maxiter": maxiter, "gtol": 1e-12, "ftol": 1e-15,
                                    "maxcor": 30}

    def f(z, t):
        lam, smooth, grad = _full_dg_eig(M, z, layout, t * scale)
        if lam < seen.get("lam", math.inf):
            seen["lam"], seen["z"] = lam, np.array(z)
        if lam <= 0:
            raise _Done(z)
        return smooth / scale, grad / scale

    try:
        f(z0, 1.0)
        for t in (1.0, 1e-2, 1e-4, 1e-7, 1e-10):      # smoothing continuation, relative to
            rel = max(seen["lam"] / scale, 1e-9)      # the current lambda_max
            z = minimize(f, seen["z"], args=(t * rel,), jac=True, method=method,
                         options=opts).x
            f(z, 1.0)
        best_z, best = seen["z"], seen["lam"] / scale
    except _Done as done:
        best_z, best = done.z, 0.0
    bound = math.sqrt(max(best, 0.0) * scale)
    if b0 is not None:
        bound = min(bound, b0)
    T, G = _full_unpack(best_z, layout, n)
    return bound, T, G


def rank_one_mu(u, v, blocks) -> float:
    """Exact mu of the rank-one M = u v^H for scalar blocks (sizes 1; the rank-one mixed mu
    of Young, Automatica 30(12), 1994, derived here): with z_i = conj(v_i) u_i, det(I - M Delta) =
    1 - sum delta_i z_i, so mu is the largest real value of sum delta_i z_i over the unit
    box, by LP duality

        mu = inf_x  sum_real |Re z_i + x Im z_i| + sqrt(1 + x^2) sum_complex |z_i|,

    a convex function of x, minimised here on its kinks and by a bounded scalar search.

    Examples
    --------
    >>> import numpy as np
    >>> rank_one_mu(np.array([1.0, 1.0]), np.array([1.0, 1j]), [Block(1, "real")] * 2)
    1.0
    """
    from scipy.optimize import minimize_scalar

    blocks = tuple(blocks)
    if any(b.size != 1 for b in blocks) or len(blocks) != len(u) or len(u) != len(v):
        raise ValueError("rank_one_mu needs scalar blocks (size 1), one per entry of u and v")
    z = np.conj(np.asarray(v, complex)) * np.asarray(u, complex)
    real = np.array([b.kind == "real" for b in blocks])
    zr, cc = z[real], float(np.sum(np.abs(z[~real])))

    def h(x):
        return float(np.sum(np.abs(zr.real + x * zr.imag)) + math.sqrt(1 + x * x) * cc)
    kinks = [-zi.real / zi.imag for zi in zr if zi.imag != 0]
    cands = [h(0.0)] + [h(x) for x in kinks]       # piecewise linear when no complex block
    if cc > 0:                                     # h(x) >= |x| cc: the minimum has |x| <= R
        R = h(0.0) / cc + 1.0
        cands.append(minimize_scalar(h, bounds=(-R, R), method="bounded",
                                     options={"xatol": 1e-12}).fun)
    return float(min(cands))


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


def mu_bounds(M, blocks, x0=None, iterations: int = 200, starts: int = 4,
              g0=None) -> MuBounds:
    """Both bounds of mu(M) for ``blocks`` (module docstring): the upper bound is the D-G
    mixed bound (:func:`mixed_upper_bound`) when a block is real, else the complex D bound.

    Parameters
    ----------
    M : (n, n) complex matrix, the loop seen by the perturbation (Delta's output to its input).
    blocks : sequence of :class:`Block` whose sizes add up to n.
    x0 : optional warm start of the upper bound's log scalings.
    g0 : optional warm start of the mixed bound's G (one per real entry).
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
    g = np.zeros(M.shape[0])
    if any(b.kind == "real" for b in blocks):
        groups = _groups(blocks)
        xs = np.array([np.log(d[gi[0]]) for gi in groups])
        g0 = None if g0 is None else np.asarray(g0, float)
        up_m, d_m, g_m = mixed_upper_bound(M, blocks, xs, g0)
        if g0 is not None:                   # the warm start may sit in a worse basin
            cold = mixed_upper_bound(M, blocks, xs)
            if cold[0] < up_m:
                up_m, d_m, g_m = cold
        if up_m < up:
            up, d, g = up_m, d_m, g_m
    lo, D = lower_bound(M, blocks, iterations, starts)
    return MuBounds(lower=float(min(lo, up)), upper=float(up), scaling=d, delta=D, g_scaling=g)


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
    ir = _real_entries(blocks)
    x = None
    for i, M in enumerate(Ms):
        b = mu_bounds(M, blocks, x, iterations, starts)
        lo[i], up[i] = b.lower, b.upper
        if not ir.size:
            x = np.array([np.log(b.scaling[g[0]]) for g in groups])
    i = int(np.argmax(up))
    return {"lower": lo, "upper": up, "peak_upper": float(up[i]), "i_peak": i}
