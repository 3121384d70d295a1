"""Hierarchical-matrix compression of the DLM normalwash matrix and its iterative solve.

For large box meshes the dense DLM costs O(n^2) memory and O(n^3) time per reduced frequency
(:mod:`asekit.aero.dlm`: D formed, then LU). The kernel is smooth between boxes far apart
(compared with their size), so the blocks of D coupling two well-separated groups of boxes have
low numerical rank. This module

1. orders the boxes by a cluster tree (recursive bisection of the control points along the
   longest side of their bounding box, :func:`cluster_tree`),
2. partitions D into blocks: a pair of clusters (s, t) is *admissible* if
   min(diam s, diam t) <= eta dist(s, t) (the standard rule, Bebendorf 2000 Eq. (2.2);
   Hackbusch 1999), diameters and distances of the boxes' corner bounding boxes
   (:func:`block_partition`); admissible blocks are approximated by a low-rank product
   U V, the others (the near field) stored dense,
3. builds the low-rank factors by adaptive cross approximation with partial pivoting
   (ACA; M. Bebendorf, "Approximation of boundary element matrices", Numer. Math. 86 (2000)
   565-589, Sec. 4; M. Bebendorf, S. Rjasanow, "Adaptive low-rank approximation of collocation
   matrices", Computing 70 (2003) 1-24, Algorithm 1 and the stopping rule Eq. (3.6)), which
   evaluates only the rows and columns of D that it needs
   (:class:`asekit.aero.dlm.NormalwashBlocks`, :func:`aca`),
4. applies the compressed matrix (:meth:`HMatrix.matvec`) in O(n log n) and solves
   D DeltaCp = w/U for the few modal normalwash columns by GMRES (Saad & Schultz 1986;
   all columns in lockstep, :func:`gmres_columns`) preconditioned by the sparse LU of the
   near-field blocks (or of their diagonal blocks only) (:func:`solve`,
   :class:`HmatrixFactor`).
5. sweeps the reduced frequencies (:func:`compressed_pressures`) reusing what does not depend
   on k: the tree, the partition and the near-field pattern (:class:`BlockStructure`), every
   kernel evaluation shared by the k of a batch (:func:`build_hmatrices`, :func:`aca_multi`:
   one row or column call for all k, the steady part D0 computed once per call) and the
   near-field LU of the batch's middle k as every k's preconditioner.

Error control. ACA stops at rank r when ||u_r|| ||v_r|| <= eps/10 ||S_r||_F (Bebendorf &
Rjasanow 2003 Eq. (3.6), S_r the approximant so far) holds for two successive steps; the
factors are then recompressed (:func:`recompress`) to eps/4 relative, which keeps the relative
Frobenius error of every admissible block below eps (the stopping rule is a heuristic
estimate; measured in tests/aero/test_hmatrix.py); GMRES stops at ||D_H x - w|| <= rtol ||w||. The error of the
pressures against the dense solve is then of order cond(D) (eps + rtol); the defaults
(:data:`DEFAULT_EPS`, :data:`DEFAULT_RTOL`) keep the generalised aerodynamic forces within
1e-6 relative of the dense LU solve (tests/aero/test_hmatrix.py: a 400-box wing at M 0.5 and
0.8, k 0 and 1; tests/benchmarks/bench_hmatrix.py: 1e-10 to 4e-8 at 1000-8000 boxes, M 0.8,
k 0.5). The admissible blocks of one row cluster are approximated together, as one block row
(:func:`_far_fields`), so that each row or column evaluation serves all of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from asekit.aero.boxes import BoxMesh
from asekit.aero.dlm import NormalwashBlocks
from asekit.util.blas import one_blas_thread

#: Default ACA stopping tolerance (relative Frobenius error of each admissible block).
DEFAULT_EPS = 1e-7
#: Default GMRES relative residual.
DEFAULT_RTOL = 1e-9
#: Default admissibility parameter eta of min(diam) <= eta dist.
DEFAULT_ETA = 1.0
#: Default largest cluster that is not bisected further: large, because every row or column
#: that ACA asks for costs a call of fixed overhead (~1 ms); at 4000 boxes, M 0.8, k 0.5, one
#: thread, the build took 43 s with 48, 16 s with 96 and 10.7 s with 160 (compression 0.43,
#: 0.46, 0.49 of the dense matrix).
DEFAULT_LEAF = 160
#: The DLM solvers of the GAF path (``aero.solver``): dense LU, this module, or by size.
SOLVERS = ("dense", "hmatrix", "auto")
#: "auto" takes the compressed solve from this many boxes: where one dense complex D alone
#: (16 n^2 bytes) passes 2 GiB, the large-model memory budget of issue 23 (floor(sqrt(2^31 /
#: 16)) = 11585). Kept there after the sweep reuse of :func:`compressed_pressures`, because no
#: crossover in time was measured: over 15 k (0 to 1.4) at M 0.8, 6 modes, one BLAS thread
#: (tests/benchmarks/bench_hmatrix.py, CPU s, dense / compressed sweep): 4.9 / 10.4 at 1000,
#: 21.5 / 31.3 at 2002, 107.0 / 141.9 at 4000 boxes (a second run at 4000: 117.3 / 118.5);
#: growth exponents 2.13 / 1.59 and 2.31 / 2.18. The sweep made the compressed path 2-3x
#: faster than one build per k (31.3 s per-k at 1000, 67.2 s at 2002), and its memory is
#: below dense's from 4000 boxes (peak RSS 1.23 against 1.39 GB), but a time crossover lies
#: beyond the measured sizes (8000+ boxes not measured in the slot).
AUTO_MIN_BOXES = 11585


# ---------------------------------------------------------------------------------------------
# cluster tree and block partition
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ClusterTree:
    """Binary cluster tree of n items (boxes).

    Attributes
    ----------
    perm : (n,) int; the items in tree order: cluster c holds ``perm[start[c]:stop[c]]``.
    start, stop : (c,) int ranges of the clusters in ``perm`` (cluster 0 is the root).
    children : (c, 2) int, the two sons of a cluster, -1 for a leaf.
    lo, hi : (c, 3) float, the bounding box (m) of the cluster's items' extents.
    """

    perm: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    children: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def is_leaf(self, c: int) -> bool:
        """True if cluster ``c`` has no sons."""
        return self.children[c, 0] < 0

    def size(self, c: int) -> int:
        """Number of items in cluster ``c``."""
        return int(self.stop[c] - self.start[c])

    def leaves(self) -> list:
        """The leaf clusters, in tree order (their ranges tile 0..n)."""
        return [c for c in range(self.start.size) if self.is_leaf(c)]


def cluster_tree(points, leaf_size: int = DEFAULT_LEAF, lo=None, hi=None) -> ClusterTree:
    """Cluster tree by recursive bisection of ``points`` along the longest side of their
    bounding box (at the median, so that sons differ in size by at most one; geometric
    bisection of Hackbusch's H-matrix book, Sec. 5.4.2, with a cardinality-balanced split).

    Parameters
    ----------
    points : (n, 3) the items' positions (m), here the boxes' control points.
    leaf_size : clusters of at most this many items (>= 1) are leaves.
    lo, hi : optional (n, 3) lower and upper corners of each item's extent (m); the clusters'
        bounding boxes enclose them (default: the points themselves).

    Returns
    -------
    :class:`ClusterTree`.

    Examples
    --------
    >>> t = cluster_tree(np.column_stack([np.arange(8.0), np.zeros(8), np.zeros(8)]), 2)
    >>> [t.size(c) for c in t.leaves()]
    [2, 2, 2, 2]
    """
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] == 0 or not np.isfinite(p).all():
        raise ValueError(f"points must be a finite (n, 3) array with n >= 1, got shape {p.shape}")
    if isinstance(leaf_size, bool) or not isinstance(leaf_size, (int, np.integer)) \
            or leaf_size < 1:
        raise ValueError(f"leaf_size must be an integer >= 1, got {leaf_size!r}")
    lo_i = p if lo is None else np.asarray(lo, float)
    hi_i = p if hi is None else np.asarray(hi, float)
    perm = np.arange(p.shape[0])
    start, stop, children = [0], [p.shape[0]], [[-1, -1]]
    todo = [0]
    while todo:
        c = todo.pop()
        idx = perm[start[c]:stop[c]]
        if idx.size <= leaf_size:
            continue
        q = p[idx]
        axis = int(np.argmax(q.max(axis=0) - q.min(axis=0)))
        order = np.argsort(q[:, axis], kind="stable")
        perm[start[c]:stop[c]] = idx[order]
        mid = start[c] + idx.size // 2
        for a, b in ((start[c], mid), (mid, stop[c])):
            children[c][0 if a == start[c] else 1] = len(start)
            todo.append(len(start))
            start.append(a)
            stop.append(b)
            children.append([-1, -1])
    start, stop = np.array(start), np.array(stop)
    lo_c = np.array([lo_i[perm[a:b]].min(axis=0) for a, b in zip(start, stop)])
    hi_c = np.array([hi_i[perm[a:b]].max(axis=0) for a, b in zip(start, stop)])
    return ClusterTree(perm, start, stop, np.array(children, int), lo_c, hi_c)


def admissible(tree: ClusterTree, s: int, t: int, eta: float) -> bool:
    """The admissibility rule min(diam s, diam t) <= eta dist(s, t) > 0 of the bounding boxes
    of clusters ``s`` and ``t`` (Bebendorf 2000 Eq. (2.2); diam the box diagonal, dist the
    Euclidean distance between the two boxes)."""
    diam = min(float(np.linalg.norm(tree.hi[s] - tree.lo[s])),
               float(np.linalg.norm(tree.hi[t] - tree.lo[t])))
    gap = np.maximum(0.0, np.maximum(tree.lo[s] - tree.hi[t], tree.lo[t] - tree.hi[s]))
    dist = float(np.linalg.norm(gap))
    return dist > 0.0 and diam <= eta * dist


def block_partition(tree: ClusterTree, eta: float = DEFAULT_ETA) -> tuple[list, list]:
    """The blocks (s, t) of the matrix in tree order: ``(near, far)`` lists of cluster pairs,
    far the admissible ones (:func:`admissible`), near the inadmissible pairs of which one is
    a leaf. Together they tile the n x n matrix exactly once."""
    if not (isinstance(eta, (int, float)) and math.isfinite(eta) and eta > 0):
        raise ValueError(f"eta must be a finite admissibility parameter > 0, got {eta!r}")
    near, far = [], []
    todo = [(0, 0)]
    while todo:
        s, t = todo.pop()
        if admissible(tree, s, t, eta):
            far.append((s, t))
        elif tree.is_leaf(s) or tree.is_leaf(t):
            near.append((s, t))
        else:
            todo.extend((a, b) for a in tree.children[s] for b in tree.children[t])
    return near, far


# ---------------------------------------------------------------------------------------------
# adaptive cross approximation
# ---------------------------------------------------------------------------------------------
def _probe(row, us, vs, used, rng, bound, n_probe: int = 3):
    """Check of the ACA stopping rule on ``n_probe`` random rows not used yet: returns the
    first row whose residual, scaled to the block (||R[i, :]|| sqrt(unused rows)), exceeds
    ``bound``, or None if all pass (or no row is left)."""
    free = np.flatnonzero(~used)
    if free.size == 0:
        return None
    for i in rng.choice(free, size=min(n_probe, free.size), replace=False):
        r = np.array(row(int(i)), dtype=complex)
        for u, v in zip(us, vs):
            r -= u[i] * v
        if np.linalg.norm(r) * math.sqrt(free.size) > bound:
            return int(i)
    return None


def aca(row, col, m: int, n: int, eps: float, max_rank: int | None = None):
    """Adaptive cross approximation with partial pivoting of an implicit m x n matrix A.

    Bebendorf (2000) Sec. 4 / Bebendorf & Rjasanow (2003) Algorithm 1: at step r take the
    residual row i_r, R_r[i, :] = A[i, :] - sum_l u_l[i] v_l, its largest entry j_r as pivot,
    v_r = R_r[i_r, :] / R_r[i_r, j_r], u_r = A[:, j_r] - sum_l u_l v_l[j_r]; the next row is
    the largest |u_r| among the rows not used. Stops when ||u_r|| ||v_r|| <= eps ||S_r||_F
    (Eq. (3.6), ||S_r||_F updated recursively) for two successive steps and the residuals of
    three random unused rows, scaled to the block, are below the same bound (the rule alone
    can stop early when the pivot rows miss part of the block: seen on DLM blocks, 1.2e-7
    error at eps = 1e-8), or at ``max_rank``.

    Parameters
    ----------
    row : callable i -> A[i, :] (n,); col : callable j -> A[:, j] (m,).
    m, n : the shape; eps : relative tolerance (> 0); max_rank : default min(m, n).

    Returns
    -------
    (U (m, r), V (r, n), converged) with A ~ U V; ``converged`` False if ``max_rank`` was hit
    before the stopping rule held.

    Examples
    --------
    >>> x, y = np.linspace(0, 1, 30), np.linspace(3, 4, 20)
    >>> a = 1.0 / np.abs(x[:, None] - y[None, :])
    >>> u, v, ok = aca(lambda i: a[i], lambda j: a[:, j], 30, 20, 1e-10)
    >>> bool(ok and np.linalg.norm(u @ v - a) <= 1e-9 * np.linalg.norm(a) and u.shape[1] < 15)
    True
    """
    max_rank = min(m, n) if max_rank is None else min(max_rank, m, n)
    rng = np.random.default_rng(0)
    us, vs = [], []
    norm2 = 0.0
    used = np.zeros(m, bool)
    i, small = 0, 0
    while len(us) < max_rank and not used.all():
        used[i] = True
        r = np.array(row(i), dtype=complex)
        for u, v in zip(us, vs):
            r -= u[i] * v
        j = int(np.argmax(np.abs(r)))
        if r[j] == 0.0:                           # a zero residual row: try another row
            i = int(np.flatnonzero(~used)[0]) if not used.all() else i
            continue
        v = r / r[j]
        u = np.array(col(j), dtype=complex)
        for uu, vv in zip(us, vs):
            u -= uu * vv[j]
        nu, nv = np.linalg.norm(u), np.linalg.norm(v)
        # ||S_r||^2 = ||S_(r-1)||^2 + 2 Re sum_l (u_l^H u)(v^H v_l)... + ||u||^2 ||v||^2
        cross = sum((np.vdot(uu, u) * np.vdot(v, vv)).real for uu, vv in zip(us, vs))
        norm2 += 2.0 * cross + (nu * nv) ** 2
        us.append(u)
        vs.append(v)
        small = small + 1 if nu * nv <= eps * math.sqrt(max(norm2, 0.0)) else 0
        au = np.abs(u)
        au[used] = -1.0
        i = int(np.argmax(au))
        if small >= 2:
            probe = _probe(row, us, vs, used, rng, eps * math.sqrt(max(norm2, 0.0)))
            if probe is None:
                break
            i, small = probe, 0
    if not us:
        return np.zeros((m, 0), complex), np.zeros((0, n), complex), True
    return np.column_stack(us), np.vstack(vs), small >= 2


def recompress(u: np.ndarray, v: np.ndarray, tol: float):
    """The shortest U' V' with ||U V - U' V'||_F <= tol ||U V||_F: QR of U and of V^T, SVD of
    the small core R_u R_v^T, truncation of the singular values (Bebendorf 2008,
    "Hierarchical matrices", Sec. 1.1.5; Grasedyck's rounding).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.standard_normal((40, 3)), rng.standard_normal((3, 30))
    >>> u2, v2 = recompress(np.hstack([a, a]), np.vstack([b, b]), 1e-12)
    >>> u2.shape[1], bool(np.allclose(u2 @ v2, 2 * a @ b))
    (3, True)
    """
    if u.shape[1] <= 1:
        return u, v
    qu, ru = np.linalg.qr(u)
    qv, rv = np.linalg.qr(v.T)
    w, s, zh = np.linalg.svd(ru @ rv.T)
    tail = np.sqrt(np.cumsum((s * s)[::-1]))[::-1]        # tail[i] = ||s[i:]||
    keep = max(1, int(np.count_nonzero(tail > tol * tail[0])))
    return qu @ (w[:, :keep] * s[:keep]), zh[:keep] @ qv.T


# ---------------------------------------------------------------------------------------------
# the compressed matrix
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class HMatrix:
    """A compressed n x n matrix in the ordering of its cluster tree.

    Attributes
    ----------
    tree : :class:`ClusterTree`.
    near : (n, n) scipy CSR matrix, the dense near-field blocks (tree order).
    far : tuple of (r0, r1, cols, U, V): the rows r0:r1 (tree order) of a row cluster against
        the columns ``cols`` (tree order) of all its admissible partners, ~ U V.
    diag : tuple of (start, stop, lu, piv): LU factors of the leaves' diagonal blocks (the
        preconditioner of :func:`solve`).
    eps, eta : the ACA tolerance and admissibility parameter it was built with.
    """

    tree: ClusterTree
    near: sp.csr_matrix
    far: tuple
    diag: tuple
    eps: float
    eta: float

    @property
    def n(self) -> int:
        """Order of the matrix."""
        return self.tree.perm.size

    @property
    def nbytes(self) -> int:
        """Bytes of the stored entries (near-field values and indices, low-rank factors)."""
        far = sum(u.nbytes + v.nbytes for *_, u, v in self.far)
        return int(self.near.data.nbytes + self.near.indices.nbytes
                   + self.near.indptr.nbytes + far)

    @property
    def compression(self) -> float:
        """:attr:`nbytes` over the dense complex matrix's 16 n^2 bytes."""
        return self.nbytes / (16.0 * self.n * self.n)

    def matvec(self, x) -> np.ndarray:
        """D_H x for x (n,) or (n, m) in the original box order."""
        x = np.asarray(x)
        xp = x[self.tree.perm]
        yp = self._matvec_tree(xp)
        y = np.empty_like(yp)
        y[self.tree.perm] = yp
        return y

    def _matvec_tree(self, xp: np.ndarray) -> np.ndarray:
        y = np.asarray(self.near @ xp, dtype=complex)
        for r0, r1, cs, u, v in self.far:
            y[r0:r1] += u @ (v @ xp[cs])
        return y

    def to_dense(self) -> np.ndarray:
        """The approximant as a dense (n, n) matrix in the original order (for tests)."""
        return self.matvec(np.eye(self.n))


def _mesh_extents(mesh: BoxMesh):
    c = mesh.corners
    return c.min(axis=1), c.max(axis=1)


def build_hmatrix(mesh: BoxMesh, mach: float, k: float, b_ref: float, method: str = "quartic",
                  symmetric: bool = False, eps: float = DEFAULT_EPS, eta: float = DEFAULT_ETA,
                  leaf_size: int = DEFAULT_LEAF, kernel: str | None = None) -> HMatrix:
    """The DLM normalwash matrix D(M, k) of ``mesh`` (:mod:`asekit.aero.dlm`) as an
    :class:`HMatrix`: cluster tree of the control points (:func:`cluster_tree`, extents the
    box corners), block partition (:func:`block_partition`), near-field blocks dense and
    admissible blocks by ACA (:func:`aca`) from single rows and columns of D
    (:class:`asekit.aero.dlm.NormalwashBlocks`).

    Parameters
    ----------
    mesh, mach, k, b_ref, method, symmetric, kernel : as
        :func:`asekit.aero.dlm.normalwash_matrices` (one scalar k).
    eps : ACA tolerance, 0 < eps < 1; eta : admissibility, > 0; leaf_size : >= 1.

    Returns
    -------
    :class:`HMatrix` with :meth:`HMatrix.matvec` ~ D x.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.aero.dlm import normalwash_matrix
    >>> m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.2, 3, 0), 0.6, 6, 24)])
    >>> h = build_hmatrix(m, 0.5, 0.4, 0.5, eps=1e-8, leaf_size=16)
    >>> d = normalwash_matrix(m, 0.5, 0.4, 0.5)
    >>> bool(np.linalg.norm(h.to_dense() - d) <= 1e-7 * np.linalg.norm(d))
    True
    """
    if np.ndim(k) != 0:
        raise ValueError(f"k must be a scalar reduced frequency, got shape {np.shape(k)}")
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    if not (isinstance(eps, (int, float)) and 0.0 < eps < 1.0):
        raise ValueError(f"eps must be an ACA tolerance in (0, 1), got {eps!r}")
    return build_hmatrices(mesh, mach, [k], b_ref, method, symmetric, eps,
                           block_structure(mesh, eta, leaf_size), kernel)[0]


# ---------------------------------------------------------------------------------------------
# several reduced frequencies at once (the k sweep, issue 23)
# ---------------------------------------------------------------------------------------------
def _grow(a: np.ndarray, axis: int, cap: int) -> np.ndarray:
    """``a`` with its ``axis`` extended to ``cap`` (zeros appended)."""
    shape = list(a.shape)
    shape[axis] = cap - a.shape[axis]
    return np.concatenate([a, np.zeros(shape, a.dtype)], axis=axis)


def _shared_pivot(r: np.ndarray):
    """The column j of the residual rows ``r`` (nk, n) that is largest relative to each k's
    largest entry (max over k of |r_k[j]| / max |r_k|), and the k that may pivot on it: those
    whose entry there is at least 1e-3 of their largest (a smaller pivot would amplify
    rounding; such a k skips the step and is served by a later pivot)."""
    scale = np.abs(r).max(axis=1)
    ok = scale > 0.0
    rel = np.abs(r[ok]) / scale[ok, None]
    j = int(np.argmax(rel.max(axis=0)))
    active = np.zeros(r.shape[0], bool)
    active[ok] = rel[:, j] >= 1e-3
    return j, active


def _probe_multi(row, us, vs, rank, used, rng, bound, n_probe: int = 3):
    """:func:`_probe` for all k: the first of ``n_probe`` random unused rows whose residual
    (scaled to the block) exceeds ``bound`` (nk,) for some k, or None."""
    free = np.flatnonzero(~used)
    if free.size == 0:
        return None
    for i in rng.choice(free, size=min(n_probe, free.size), replace=False):
        r = np.array(row(int(i)), dtype=complex)
        r -= (us[:, i, None, :rank] @ vs[:, :rank])[:, 0]
        if (np.linalg.norm(r, axis=1) * math.sqrt(free.size) > bound).any():
            return int(i)
    return None


def aca_multi(row, col, m: int, n: int, eps: float, max_rank: int | None = None):
    """Adaptive cross approximation of nk implicit m x n matrices A_k (the DLM block at nk
    reduced frequencies) with shared pivots.

    Each step evaluates one row i and one column j of all A_k at once (one kernel call serves
    every k: the k-independent geometry, the steady horseshoe part D0 and the call overhead are
    paid once, :class:`asekit.aero.dlm.NormalwashBlocks`) and updates every k's own cross
    approximant exactly as in :func:`aca` (Bebendorf & Rjasanow 2003 Algorithm 1): residual row
    R_k[i, :] = A_k[i, :] - sum_l u_kl[i] v_kl, v_k = R_k[i, :] / R_k[i, j],
    u_k = A_k[:, j] - sum_l u_kl v_kl[j]. The pivots are chosen jointly: j maximises
    max_k |R_k[i, j]| / max |R_k[i, :]|, the next row i maximises max_k |u_k| / max |u_k|; a k
    whose pivot entry is below 1e-3 of its largest residual entry skips the step. The error is
    controlled per k: the stopping rule ||u_k|| ||v_k|| <= eps ||S_k||_F (Eq. (3.6)) must hold
    for two successive steps for every k and three random unused rows must pass the residual
    check of :func:`aca` for every k (else ACA continues from the failing row), or
    ``max_rank`` is reached.

    Parameters
    ----------
    row : callable i -> (nk, n) rows A_k[i, :]; col : callable j -> (nk, m) columns A_k[:, j].
    m, n : the shape; eps : relative tolerance (> 0); max_rank : default min(m, n).

    Returns
    -------
    (us, vs, converged): lists over k of U_k (m, r), V_k (r, n) with A_k ~ U_k V_k (zero
    columns of skipped steps included; :func:`recompress` removes them).

    Examples
    --------
    >>> x, y = np.linspace(0, 1, 30), np.linspace(3, 4, 20)
    >>> a = np.stack([np.exp(1j * w * np.abs(x[:, None] - y)) / np.abs(x[:, None] - y)
    ...               for w in (0.0, 1.0, 2.0)])
    >>> us, vs, ok = aca_multi(lambda i: a[:, i], lambda j: a[:, :, j], 30, 20, 1e-10)
    >>> errs = [np.linalg.norm(u @ v - ak) / np.linalg.norm(ak) for u, v, ak in zip(us, vs, a)]
    >>> bool(ok and max(errs) <= 1e-9 and us[0].shape[1] < 20)
    True
    """
    max_rank = min(m, n) if max_rank is None else min(max_rank, m, n)
    rng = np.random.default_rng(0)
    r0 = np.array(row(0), dtype=complex)
    nk = r0.shape[0]
    cap = min(max_rank, 16)
    us, vs = np.zeros((nk, m, cap), complex), np.zeros((nk, cap, n), complex)
    norm2, small = np.zeros(nk), np.zeros(nk, int)
    used = np.zeros(m, bool)
    i, rank, r = 0, 0, r0
    while rank < max_rank and not used.all():
        used[i] = True
        if r is None:
            r = np.array(row(i), dtype=complex)
        if rank:
            r -= (us[:, i, None, :rank] @ vs[:, :rank])[:, 0]
        if not np.abs(r).max() > 0.0:             # a zero residual row for every k
            i, r = (int(np.flatnonzero(~used)[0]) if not used.all() else i), None
            continue
        j, active = _shared_pivot(r)
        if rank == cap:
            cap = min(2 * cap, max_rank)
            us, vs = _grow(us, 2, cap), _grow(vs, 1, cap)
        v = np.zeros((nk, n), complex)
        v[active] = r[active] / r[active, j, None]
        u = np.array(col(j), dtype=complex)
        if rank:
            u -= (us[:, :, :rank] @ vs[:, :rank, j, None])[..., 0]
        u[~active] = 0.0
        nu, nv = np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1)
        # ||S_r||^2 = ||S_(r-1)||^2 + 2 Re sum_l (u_l^H u)(v^H v_l) + ||u||^2 ||v||^2
        a = np.einsum("kmr,km->kr", us[:, :, :rank].conj(), u)
        b = np.einsum("krn,kn->kr", vs[:, :rank], v.conj())
        norm2 += 2.0 * (a * b).sum(axis=1).real + (nu * nv) ** 2
        us[:, :, rank], vs[:, rank] = u, v
        rank += 1
        conv = nu * nv <= eps * np.sqrt(np.maximum(norm2, 0.0))
        small = np.where(active, np.where(conv, small + 1, 0), small)
        au = np.abs(u) / np.maximum(np.abs(u).max(axis=1), 1e-300)[:, None]
        au = au.max(axis=0)
        au[used] = -1.0
        i, r = int(np.argmax(au)), None
        if (small >= 2).all():
            probe = _probe_multi(row, us, vs, rank, used, rng,
                                 eps * np.sqrt(np.maximum(norm2, 0.0)))
            if probe is None:
                break
            i, small = probe, np.zeros(nk, int)
    return ([us[k, :, :rank] for k in range(nk)], [vs[k, :rank] for k in range(nk)],
            bool((small >= 2).all()))


@dataclass(frozen=True, eq=False)
class BlockStructure:
    """The k-independent part of the compressed DLM matrix of one mesh: cluster tree, block
    partition and the near field's sparsity pattern (built once per sweep,
    :func:`block_structure`).

    Attributes
    ----------
    tree : :class:`ClusterTree`; near, far : the blocks of :func:`block_partition`.
    near_rows : tuple of (s, ts, cols) per near row cluster s: its partners ts and their
        columns (tree order).
    order : (nnz,) int, position in the CSR data of each near-field entry in the order the row
        clusters' blocks are evaluated (raveled); indices, indptr : the CSR pattern (tree
        order).
    eta, leaf_size : the admissibility parameter and leaf size it was built with.
    """

    tree: ClusterTree
    near: tuple
    far: tuple
    near_rows: tuple
    order: np.ndarray
    indices: np.ndarray
    indptr: np.ndarray
    eta: float
    leaf_size: int

    @property
    def nnz(self) -> int:
        """Entries of the near field."""
        return int(self.order.size)


def block_structure(mesh: BoxMesh, eta: float = DEFAULT_ETA,
                    leaf_size: int = DEFAULT_LEAF) -> BlockStructure:
    """The :class:`BlockStructure` of ``mesh``: :func:`cluster_tree` of the control points
    (extents the box corners), :func:`block_partition` and the near-field CSR pattern.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.2, 3, 0), 0.6, 4, 24)])
    >>> s = block_structure(m, leaf_size=16)
    >>> bool(0 < s.nnz < m.n ** 2 and len(s.far) > 0)
    True
    """
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    lo, hi = _mesh_extents(mesh)
    tree = cluster_tree(mesh.control_point, leaf_size, lo, hi)
    near, far = block_partition(tree, eta)
    by_row: dict = {}
    for s, t in near:
        by_row.setdefault(s, []).append(t)
    ri, ci, rows_out = [], [], []
    for s, ts in by_row.items():
        rs = np.arange(tree.start[s], tree.stop[s])
        cs = np.concatenate([np.arange(tree.start[t], tree.stop[t]) for t in ts])
        ri.append(np.repeat(rs, cs.size))
        ci.append(np.tile(cs, rs.size))
        rows_out.append((s, tuple(ts), cs))
    n = tree.perm.size
    ri, ci = np.concatenate(ri), np.concatenate(ci)
    # the blocks tile the near field once: the CSR of the entry numbers is the permutation
    pos = sp.csr_matrix((np.arange(1, ri.size + 1, dtype=np.int64), (ri, ci)), shape=(n, n))
    order = np.empty(ri.size, np.int64)
    order[pos.data - 1] = np.arange(ri.size)
    return BlockStructure(tree, tuple(near), tuple(far), tuple(rows_out), order, pos.indices,
                          pos.indptr, float(eta), int(leaf_size))


def _near_fields(st: BlockStructure, evaluate, nk: int) -> tuple[list, list]:
    """The near field of every k (one evaluation per row cluster for all k) as CSR matrices
    sharing the pattern of ``st``, and the leaves' diagonal blocks {cluster: dense} per k."""
    tree, perm = st.tree, st.tree.perm
    data = np.empty((nk, st.nnz), complex)
    diag: list = [{} for _ in range(nk)]
    at = 0
    for s, ts, cs in st.near_rows:
        blk = evaluate(perm[tree.start[s]:tree.stop[s]], perm[cs])
        size = blk.shape[1] * blk.shape[2]
        data[:, st.order[at:at + size]] = blk.reshape(nk, -1)
        at += size
        if s in ts:
            off = sum(tree.size(t) for t in ts[:ts.index(s)])
            for ik in range(nk):
                diag[ik][s] = blk[ik, :, off:off + tree.size(s)].copy()
    n = perm.size
    mats = [sp.csr_matrix((data[ik], st.indices, st.indptr), shape=(n, n)) for ik in range(nk)]
    return mats, diag


def _far_fields(st: BlockStructure, evaluate, eps: float, nk: int) -> list:
    """The admissible blocks at nk reduced frequencies, those of one row cluster s together:
    the block row [D_st1 ... D_stq] over its admissible partners t is approximated by one
    :func:`aca_multi` (the kernel is smooth for receivers in s and senders in any t, all far
    from s, so the block row has low rank too, and one call per row or column then serves all
    q blocks and all k), then recompressed per k. A block row whose rank would not save memory
    is stored exactly (U = the block row, V = I, or U = I). Returns a list over k of the
    far-field tuples of :class:`HMatrix`."""
    by_row: dict = {}
    for s, t in st.far:
        by_row.setdefault(s, []).append(t)
    out: list = [[] for _ in range(nk)]
    tree, perm = st.tree, st.tree.perm
    for s, ts in by_row.items():
        r0, r1 = int(tree.start[s]), int(tree.stop[s])
        cs = np.concatenate([np.arange(tree.start[t], tree.stop[t]) for t in ts])
        rows, cols = perm[r0:r1], perm[cs]
        m, n = rows.size, cols.size
        max_rank = max(1, (m * n) // (m + n))
        us, vs, ok = aca_multi(lambda i: evaluate(rows[i:i + 1], cols)[:, 0],
                               lambda j: evaluate(rows, cols[j:j + 1])[:, :, 0], m, n,
                               0.1 * eps, max_rank)
        if ok:
            for ik in range(nk):
                out[ik].append((r0, r1, cs) + recompress(us[ik], vs[ik], 0.25 * eps))
            continue
        full = evaluate(rows, cols)
        for ik in range(nk):
            u, v = full[ik], np.eye(n, dtype=complex)
            if m < n:
                u, v = np.eye(m, dtype=complex), u
            out[ik].append((r0, r1, cs, u, v))
    return [tuple(f) for f in out]


def build_hmatrices(mesh: BoxMesh, mach: float, ks, b_ref: float, method: str = "quartic",
                    symmetric: bool = False, eps: float = DEFAULT_EPS,
                    structure: BlockStructure | None = None, kernel: str | None = None) -> list:
    """:func:`build_hmatrix` at several reduced frequencies at once: one
    :class:`BlockStructure` (tree, partition, near-field pattern: k-independent), every kernel
    evaluation made for all ``ks`` together (:class:`asekit.aero.dlm.NormalwashBlocks`: the
    geometry, the steady part D0 and the call overhead shared) and the admissible blocks by
    :func:`aca_multi` (shared pivots, each k's error checked against ``eps``).

    Parameters
    ----------
    mesh, mach, b_ref, method, symmetric, kernel : as :func:`build_hmatrix`.
    ks : 1-D reduced frequencies (>= 0); eps : ACA tolerance in (0, 1).
    structure : a :class:`BlockStructure` of ``mesh`` to reuse (default: built here with
        :data:`DEFAULT_ETA` and :data:`DEFAULT_LEAF`).

    Returns
    -------
    list of :class:`HMatrix`, one per k (their trees and near-field patterns shared).

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.aero.dlm import normalwash_matrix
    >>> m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.2, 3, 0), 0.6, 6, 24)])
    >>> hs = build_hmatrices(m, 0.5, [0.0, 0.8], 0.5, eps=1e-8,
    ...                      structure=block_structure(m, leaf_size=16))
    >>> d = normalwash_matrix(m, 0.5, 0.8, 0.5)
    >>> bool(np.linalg.norm(hs[1].to_dense() - d) <= 1e-7 * np.linalg.norm(d))
    True
    """
    ks = np.atleast_1d(np.asarray(ks, float))
    if ks.ndim != 1 or ks.size == 0:
        raise ValueError(f"ks must be a non-empty 1-D array of reduced frequencies, got shape "
                         f"{ks.shape}")
    if not (isinstance(eps, (int, float)) and 0.0 < eps < 1.0):
        raise ValueError(f"eps must be an ACA tolerance in (0, 1), got {eps!r}")
    st = block_structure(mesh) if structure is None else structure
    if st.tree.perm.size != getattr(mesh, "n", -1):
        raise ValueError("structure must be the BlockStructure of this mesh (its box count "
                         "differs)")
    blocks = NormalwashBlocks(mesh, mach, ks, b_ref, method, symmetric, kernel)
    with one_blas_thread():         # many small products and QR / SVD
        nears, diags = _near_fields(st, blocks, ks.size)
        fars = _far_fields(st, blocks, float(eps), ks.size)
    out = []
    for near_m, diag, far_t in zip(nears, diags, fars):
        factors = []
        for c in st.tree.leaves():
            lu, piv = sla.lu_factor(diag[c], check_finite=False)
            factors.append((int(st.tree.start[c]), int(st.tree.stop[c]), lu, piv))
        out.append(HMatrix(st.tree, near_m, far_t, tuple(factors), float(eps), st.eta))
    return out


# ---------------------------------------------------------------------------------------------
# iterative solve
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SolveInfo:
    """Convergence of :func:`solve`: GMRES iterations per column and the largest relative
    residual ||D_H x - w|| / ||w|| reached (of the compressed matrix)."""

    iterations: tuple
    residual: float


#: Preconditioners of :func:`solve`: the sparse LU of the whole near field (default) or the
#: LU factors of the leaves' diagonal blocks (block Jacobi).
PRECONDITIONERS = ("near", "block")


def _preconditioner(h: HMatrix, kind: str) -> spla.LinearOperator:
    """M ~ D_H^-1: "near", the sparse LU (SuperLU, COLAMD ordering) of the near-field matrix
    (measured at 1000 boxes, M 0.8, k 0.5: 7 GMRES iterations per column against 45 with
    "block", LU fill 1.7x the near field's entries); "block", the leaves' diagonal blocks."""
    if kind == "near":
        lu = spla.splu(h.near.tocsc())

        def solve_lu(x):
            return lu.solve(np.asarray(x, complex))
        return spla.LinearOperator((h.n, h.n), dtype=complex, matmat=solve_lu,
                                   matvec=lambda x: solve_lu(np.reshape(x, -1)))

    def apply(x):
        y = np.array(x, dtype=complex)
        for a, b, lu, piv in h.diag:
            y[a:b] = sla.lu_solve((lu, piv), y[a:b], check_finite=False)
        return y
    return spla.LinearOperator((h.n, h.n), matvec=lambda x: apply(np.reshape(x, -1)),
                               matmat=apply, dtype=complex)


def near_preconditioner(h: HMatrix, kind: str = "near") -> spla.LinearOperator:
    """The preconditioner M ~ D_H^-1 of :func:`solve` as a LinearOperator in tree order (kind
    one of :data:`PRECONDITIONERS`), to be reused for the matrices of nearby reduced
    frequencies on the same :class:`BlockStructure` (:func:`compressed_pressures`)."""
    if kind not in PRECONDITIONERS:
        raise ValueError(f"kind must be one of {list(PRECONDITIONERS)}, got {kind!r}")
    return _preconditioner(h, kind)


def solve(h: HMatrix, w, rtol: float = DEFAULT_RTOL, maxiter: int = 500,
          restart: int = 60, preconditioner="near") -> tuple[np.ndarray, SolveInfo]:
    """Solve D_H x = w for the columns of ``w`` (n,) or (n, m) by GMRES (Saad & Schultz 1986;
    :func:`gmres_columns`, the columns in lockstep so that the products with D_H and the
    preconditioner are matrix-matrix products), right-preconditioned by the LU of its near
    field (:data:`PRECONDITIONERS`), started from x0 = M^-1 w.

    Parameters
    ----------
    h : :class:`HMatrix`; w : right-hand sides in the original order.
    rtol : relative residual ||D_H x - w|| <= rtol ||w|| per column (0 < rtol < 1).
    maxiter, restart : GMRES restart cycles and Krylov dimension.
    preconditioner : "near" (sparse LU of the whole near field, default) or "block" (LU of
        the leaves' diagonal near-field blocks, block Jacobi: cheaper to form, 6x more
        iterations on the DLM), or a :class:`scipy.sparse.linalg.LinearOperator` in tree
        order from :func:`near_preconditioner` (e.g. of another reduced frequency's matrix
        on the same :class:`BlockStructure`: GMRES still stops at ``rtol`` of this matrix,
        only the iteration count changes).

    Returns
    -------
    (x, :class:`SolveInfo`); x has the shape of ``w``, complex. Raises RuntimeError if a
    column does not converge within ``maxiter``.
    """
    if not (isinstance(rtol, (int, float)) and 0.0 < rtol < 1.0):
        raise ValueError(f"rtol must be a relative residual in (0, 1), got {rtol!r}")
    w = np.asarray(w)
    if w.ndim not in (1, 2) or w.shape[0] != h.n or not np.isfinite(w).all():
        raise ValueError(f"w must be a finite (n,) or (n, m) array with n = {h.n}, got "
                         f"shape {w.shape}")
    cols = w.reshape(h.n, -1)
    perm = h.tree.perm
    if isinstance(preconditioner, spla.LinearOperator):
        if preconditioner.shape != (h.n, h.n):
            raise ValueError(f"preconditioner must be a ({h.n}, {h.n}) LinearOperator, got "
                             f"shape {preconditioner.shape}")
        pre = preconditioner
    elif preconditioner in PRECONDITIONERS:
        pre = _preconditioner(h, preconditioner)
    else:
        raise ValueError(f"preconditioner must be one of {list(PRECONDITIONERS)} or a "
                         f"LinearOperator, got {preconditioner!r}")
    with one_blas_thread():         # small products: threads only contend
        xp, its, worst = _gmres_columns(h, pre, cols, rtol, maxiter, restart)
    x = np.empty_like(xp)
    x[perm] = xp
    return x.reshape(w.shape), SolveInfo(tuple(int(i) for i in its), float(worst))


def _gmres_columns(h, pre, cols, rtol, maxiter, restart):
    """:func:`gmres_columns` on the compressed matrix in tree order for the nonzero columns
    of ``cols`` (original order); returns (x in tree order, iterations, worst residual)."""
    b = cols[h.tree.perm].astype(complex)
    nb = np.linalg.norm(b, axis=0)
    nz = nb > 0.0
    x = np.zeros_like(b)
    its = np.zeros(b.shape[1], int)
    if not nz.any():
        return x, its, 0.0
    x0 = pre.matmat(b[:, nz])
    x[:, nz], its[nz], ok = gmres_columns(h._matvec_tree, pre.matmat, b[:, nz], x0, rtol,
                                          restart, maxiter)
    res = np.linalg.norm(h._matvec_tree(x[:, nz]) - b[:, nz], axis=0) / nb[nz]
    if not ok:
        raise RuntimeError(f"GMRES did not reach rtol = {rtol:g} for every column within "
                           f"{maxiter} x {restart} iterations (residual {res.max():.3g})")
    return x, its, float(res.max())

def _lstsq_residuals(hess: np.ndarray, beta: np.ndarray):
    """Per column c the minimiser y_c of ||beta_c e_1 - H_c y|| over the (j + 1, j) Hessenberg
    matrices ``hess`` (m, j + 1, j) and the residual norms it leaves (the GMRES residual)."""
    m, jp1, j = hess.shape
    rhs = np.zeros((m, jp1), complex)
    rhs[:, 0] = beta
    q, r = np.linalg.qr(hess)                               # (m, j+1, j), (m, j, j)
    qb = np.einsum("mij,mi->mj", q.conj(), rhs)
    y = np.linalg.solve(r, qb[..., None])[..., 0]
    res = np.linalg.norm(rhs - np.einsum("mij,mj->mi", hess, y), axis=1)
    return y, res


def gmres_columns(apply_a, apply_m, b: np.ndarray, x0: np.ndarray, rtol: float,
                  restart: int = 60, maxiter: int = 10):
    """Right-preconditioned GMRES (Saad & Schultz 1986, Algorithm 4 with right
    preconditioning, Saad, "Iterative methods for sparse linear systems", 2003, Algorithm 9.5)
    for all columns of ``b`` in lockstep: each column has its own Krylov space, but the
    products with A and the preconditioner M are made for all columns at once (sparse and
    dense matrix-matrix products instead of m matrix-vector products).

    Parameters
    ----------
    apply_a, apply_m : callables (n, m) -> (n, m), A X and M^-1 X.
    b, x0 : (n, m) right-hand sides and initial guesses.
    rtol : stop a column at ||b - A x|| <= rtol ||b|| (the least-squares residual, checked
        against the true residual at each restart); restart : Krylov dimension; maxiter :
        restart cycles.

    Returns
    -------
    (x (n, m), iterations (m,) int, converged bool).

    Examples
    --------
    >>> a = np.diag(np.arange(1.0, 21.0)) + 0.1 * np.eye(20, k=1)
    >>> b = np.ones((20, 2)) * [1.0, 2.0]
    >>> x, its, ok = gmres_columns(lambda v: a @ v, lambda v: v, b, np.zeros((20, 2)), 1e-10)
    >>> bool(ok and np.linalg.norm(a @ x - b) <= 1e-9 * np.linalg.norm(b))
    True
    """
    n, m = b.shape
    nb = np.linalg.norm(b, axis=0)
    target = rtol * nb
    x = np.array(x0, dtype=complex)
    its = np.zeros(m, int)
    for _ in range(maxiter):
        r = b - apply_a(x)
        beta = np.linalg.norm(r, axis=0)
        todo = beta > target
        if not todo.any():
            return x, its, True
        beta_t = beta[todo]
        basis = [r[:, todo] / beta_t]
        hess = np.zeros((int(todo.sum()), restart + 1, restart), complex)
        y = None
        for j in range(restart):
            w = apply_a(apply_m(basis[j]))
            for i in range(j + 1):                          # modified Gram-Schmidt
                hij = np.einsum("nc,nc->c", basis[i].conj(), w)
                hess[:, i, j] = hij
                w -= basis[i] * hij
            hn = np.linalg.norm(w, axis=0)
            hess[:, j + 1, j] = hn
            basis.append(w / np.where(hn > 0.0, hn, 1.0))
            y, res = _lstsq_residuals(hess[:, :j + 2, :j + 1], beta_t)
            its[todo] += 1
            if (res <= target[todo]).all():
                break
        step = np.einsum("jnc,cj->nc", np.array(basis[:y.shape[1]]), y)
        x[:, todo] += apply_m(step)
    r = b - apply_a(x)
    return x, its, bool((np.linalg.norm(r, axis=0) <= target).all())


@dataclass(frozen=True, eq=False)
class HmatrixFactor:
    """The compressed counterpart of :class:`asekit.aero.dlm.AicFactor`: DeltaCp = D^-1 (w/U)
    by :func:`solve` on the :class:`HMatrix` of D(M, k)."""

    h: HMatrix
    rtol: float = DEFAULT_RTOL

    @property
    def n(self) -> int:
        """Number of boxes."""
        return self.h.n

    def pressures(self, normalwash) -> np.ndarray:
        """DeltaCp for the normalwash ``normalwash`` (n,) or (n, m), complex, same shape."""
        return solve(self.h, normalwash, self.rtol)[0]


def resolve_solver(solver: str, n_boxes: int) -> str:
    """"dense" or "hmatrix" for ``solver`` (one of :data:`SOLVERS`) on ``n_boxes`` boxes:
    "auto" is "hmatrix" from :data:`AUTO_MIN_BOXES` boxes, else "dense".

    >>> resolve_solver("auto", 1200), resolve_solver("auto", 20000), resolve_solver("hmatrix", 10)
    ('dense', 'hmatrix', 'hmatrix')
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
    if solver == "auto":
        return "hmatrix" if n_boxes >= AUTO_MIN_BOXES else "dense"
    return solver


#: Default bytes of compressed matrices built at once by :func:`compressed_pressures` (the
#: reduced frequencies of a batch share every kernel evaluation; the batch is sized from the
#: near field and then from the measured size of the previous batch's matrices).
SWEEP_BYTES = 1 << 30


def _batch_size(per_k: float, n_left: int, max_bytes: int) -> int:
    """How many k fit in ``max_bytes`` at ``per_k`` bytes each (at least 1, at most n_left)."""
    return int(max(1, min(n_left, max_bytes // max(per_k, 1.0))))


def _solve_reusing(h, w, rtol, pre):
    """:func:`solve` with the preconditioner ``pre`` of a nearby k; if GMRES then fails to
    converge, again with this matrix's own (the answer is held to ``rtol`` either way).
    Returns (x, info, refactored)."""
    try:
        return (*solve(h, w, rtol, maxiter=2, preconditioner=pre), False)
    except RuntimeError:
        return (*solve(h, w, rtol), True)


def compressed_pressures(mesh: BoxMesh, mach: float, ks, b_ref: float, normalwash,
                         method: str = "quartic", symmetric: bool = False,
                         eps: float = DEFAULT_EPS, rtol: float = DEFAULT_RTOL, on_k=None,
                         kernel: str | None = None, max_bytes: int = SWEEP_BYTES,
                         reuse_preconditioner: bool = True, on_info=None,
                         structure: BlockStructure | None = None) -> list:
    """DeltaCp per k for the normalwash columns ``normalwash(k)`` (n, m), the compressed
    counterpart of the streamed dense LU of :func:`asekit.aero.gaf.gaf_from_box_modes`.

    What does not depend on k is made once per sweep: the cluster tree, the block partition
    and the near-field pattern (:func:`block_structure`). The k are built in batches of at
    most ``max_bytes`` of compressed matrices by :func:`build_hmatrices` (each row, column and
    near-field block of D evaluated once for all k of the batch, the steady part D0 and the
    geometry shared; admissible blocks by :func:`aca_multi` with each k's error held to
    ``eps``). With ``reuse_preconditioner`` the near-field LU is factored once per batch, at
    its middle k, and serves every k of the batch (GMRES still stops at ``rtol`` of each k's
    own matrix; if it fails to converge, that k is solved again with its own LU).

    Parameters
    ----------
    mesh, mach, b_ref, method, symmetric, kernel : as :func:`build_hmatrix`.
    ks : reduced frequencies; normalwash : callable k -> (n, m) w/U.
    eps, rtol : ACA and GMRES tolerances; max_bytes : > 0, the batch budget.
    on_k : called ``on_k(ik, cp)`` as each k is done; on_info : called
        ``on_info(ik, SolveInfo, refactored)``.
    structure : the :class:`BlockStructure` of ``mesh`` (default :func:`block_structure`).

    Returns
    -------
    list of (n, m) complex DeltaCp, one per k.
    """
    ks = np.atleast_1d(np.asarray(ks, float))
    if not (isinstance(max_bytes, (int, np.integer)) and max_bytes > 0):
        raise ValueError(f"max_bytes must be a positive integer, got {max_bytes!r}")
    st = block_structure(mesh) if structure is None else structure
    per_k = 3.0 * 16.0 * st.nnz            # near-field data (twice while built) + far guess
    out, at = [], 0
    while at < ks.size:
        nb = _batch_size(per_k, ks.size - at, int(max_bytes))
        hs = build_hmatrices(mesh, mach, ks[at:at + nb], b_ref, method, symmetric, eps, st,
                             kernel)
        per_k = max(h.nbytes for h in hs) + 16.0 * st.nnz
        pre = near_preconditioner(hs[nb // 2]) if reuse_preconditioner else None
        for j in range(nb):
            w = normalwash(float(ks[at + j]))
            if pre is None:
                cp, info, again = (*solve(hs[j], w, rtol), False)
            else:
                cp, info, again = _solve_reusing(hs[j], w, rtol, pre)
            hs[j] = None
            if on_info is not None:
                on_info(at + j, info, again)
            if on_k is not None:
                on_k(at + j, cp)
            out.append(cp)
        at += nb
        del hs, pre
    return out
