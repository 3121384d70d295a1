"""Minimum-state rational function approximation of generalized aerodynamic forces.

Karpel's minimum-state form (M. Karpel, "Design for active flutter suppression and gust
alleviation using state-space aeroelastic modeling", J. Aircraft 19(3), 1982, 221-227) fits the
whole GAF matrix at one Mach with n_L aerodynamic lag states shared by all elements,

    Q~(p) = A0 + A1 p + A2 p^2 + D (p I - R)^-1 E p,      p = ik,  R = -diag(beta_l),

with A0, A1, A2 (n x n), D (n x n_L), E (n_L x n) real and the lag roots beta_l > 0
(dimensionless, like Roger's). Roger's fit with N lags is the special case n_L = N n with D a
0/1 selection matrix (see :meth:`asekit.rfa.RogerFit.lag_realization`), so for the same number
of aerodynamic states the minimum-state fit has more freedom.

The fit is bilinear in (D, E); it is found by the iterative alternating least squares of
Tiffany & Adams (S. H. Tiffany, W. M. Adams, "Nonlinear programming extensions to rational
function approximation methods for unsteady aerodynamic forces", NASA TP-2776, 1988, Sec.
"Minimum-state method"): with D held, the coefficients A0, A1, A2, E of each column of Q
follow from one linear least-squares problem; with E held, A0, A1, A2, D of each row; the two
steps alternate until the (weighted) squared error

    J = sum_{k, i, j} W_ij(k)^2 |Q~_ij(ik) - Q_ij(ik)|^2

stops decreasing. Each step minimises J exactly over its unknowns with the others held, so J
never increases. Options:

* ``weights`` per k or per element and k (W_ij(k)); ``normalize=True`` divides every element
  by its largest magnitude over k, floored at ``normalize_floor`` times the largest element
  (the normalisation of Tiffany & Adams, so that small elements are fitted to the same
  relative accuracy; physical weights such as Karpel's, J. Guidance 13(1), 1990, can be
  passed as ``weights``);
* ``constrain_k0``: the fit reproduces the real (steady) part of the lowest-k data exactly;
* ``match_k``: the fit reproduces the complex data exactly at one tabulated k (e.g. the
  highest, k_max, or the flutter k);
  both as linear equality constraints in every least-squares step (Tiffany & Adams, Sec.
  "Constraints");
* ``optimize_roots``: the lag roots are optimised by a bounded Nelder-Mead search on log beta
  over the converged error (the nonlinear-programming extension of Tiffany & Adams), within
  ``root_bounds`` (default 1e-3 k_max to 2 k_max).

In the Laplace domain (s = i omega, p = s b / U) the lag term is
D (s I + (U/b) diag(beta))^-1 E s: the aeroelastic state space (:mod:`asekit.aeroelastic.statespace`)
carries n_L lag states x_a with x_a' = -(U/b) diag(beta) x_a + E zeta' and a generalized force
q D x_a.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from asekit.rfa.roger import check_coefficients, check_gaf_table, default_lag_roots, fit_errors
from asekit.util.blas import small_dense
from asekit.util.validate import finite_array, finite_result, integer, positive, real_array


def default_ms_roots(k_max: float, n_states: int) -> np.ndarray:
    """Default minimum-state lag roots: the Roger spacing beta_l = 1.7 k_max (l/(n_L+1))^2
    (Tiffany & Adams, NASA TP-2776, 1988) over the n_L shared states. Returns (n_states,)."""
    return default_lag_roots(k_max, n_states)


def reduced_frequency_weights(k, k_band: float, order: int = 2) -> np.ndarray:
    """Per-k weights W(k) = 1 / sqrt(1 + (k / k_band)^(2 order)) that concentrate the fit on
    the reduced frequencies the aeroelastic system lives in (k <~ k_band) and relax it above.

    A simple physical weighting in the sense of Karpel (J. Guidance 13(1), 1990): with
    k_band a few times the flutter reduced frequency omega_f b / U_f (or omega_max b / U_min
    of the modes of interest) the fitted states go to the frequencies that decide the
    aeroelastic roots instead of the large high-k values that dominate an unweighted fit.
    ``k`` (n_k,) >= 0, ``k_band`` > 0, ``order`` >= 1. Returns (n_k,) in (0, 1].
    """
    k = np.asarray(k, dtype=float)
    positive("k_band", k_band)
    if int(order) < 1:
        raise ValueError(f"order must be >= 1, got {order}")
    return 1.0 / np.sqrt(1.0 + (k / k_band) ** (2 * int(order)))


@dataclass(frozen=True)
class MinimumStateFit:
    """A minimum-state RFA at one Mach number (same interface as :class:`RogerFit`).

    Attributes
    ----------
    A : (3, n, n) real A0, A1, A2.
    D : (n, n_L) real. E : (n_L, n) real.
    lag_roots : (n_L,) beta_l > 0 (R = -diag(beta)).
    b_ref : reference semi-chord of k = omega b / U.
    k, Q : the fitted data (n_k,), (n_k, n, n).
    element_error : (n, n) ||Q_ij - Q~_ij|| / ||Q_ij|| over k (unweighted).
    fit_error : ||Q - Q~||_F / ||Q||_F over all k (unweighted, as RogerFit's).
    weighted_error : the minimised sqrt(J / sum W^2 |Q|^2).
    iterations : alternating least-squares sweeps used; converged : whether the relative
        decrease of J fell below the tolerance; error_history : weighted error per sweep.
    constrained_k0, match_k : the constraints applied (match_k is the k matched, or None).
    mach : informational.
    """

    A: np.ndarray
    D: np.ndarray
    E: np.ndarray
    lag_roots: np.ndarray
    b_ref: float
    k: np.ndarray
    Q: np.ndarray
    element_error: np.ndarray
    fit_error: float
    weighted_error: float
    iterations: int
    converged: bool
    constrained_k0: bool = False
    match_k: float | None = None
    mach: float | None = None
    error_history: np.ndarray = field(default=None, repr=False)
    weights: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        check_coefficients(self, ("A", "D", "E"))

    @property
    def n_lags(self) -> int:
        """Number of lag roots = number of aerodynamic lag states n_L."""
        return len(self.lag_roots)

    @property
    def n_lag_states(self) -> int:
        return len(self.lag_roots)

    @property
    def n_modes(self) -> int:
        return self.A.shape[1]

    def _eval_p(self, p: np.ndarray) -> np.ndarray:
        g = p[:, None] / (p[:, None] + self.lag_roots[None, :])        # (n_f, n_L)
        out = (self.A[0][None] + p[:, None, None] * self.A[1][None]
               + (p ** 2)[:, None, None] * self.A[2][None])
        return out + np.einsum("fl,il,lj->fij", g, self.D, self.E)

    def evaluate(self, k) -> np.ndarray:
        """Q~ at reduced frequencies ``k``: (n, n) or (len(k), n, n) complex."""
        k_arr = np.atleast_1d(real_array("k", k))
        out = self._eval_p(1j * k_arr)
        return out[0] if np.ndim(k) == 0 else out

    def evaluate_laplace(self, s, velocity: float) -> np.ndarray:
        """Q~ at Laplace variable(s) ``s`` (1/s) and airspeed ``velocity`` (p = s b / U)."""
        positive("velocity", velocity)
        s_arr = np.atleast_1d(np.asarray(s, dtype=complex))
        out = self._eval_p(s_arr * self.b_ref / velocity)
        return out[0] if np.ndim(s) == 0 else out

    def lag_realization(self, n_rigid: int = 0):
        """``(D (n, n_L), E (n_L, n), roots (n_L,), names)``: the lag term
        D (p I + diag(beta))^-1 E p, states named ``lag1..lagN`` (``n_rigid`` is not needed:
        the states are shared by all modes)."""
        return (self.D.copy(), self.E.copy(), self.lag_roots.copy(),
                [f"lag{j + 1}" for j in range(self.n_lags)])


# ---------------------------------------------------------------------------------------------
# least squares with equality constraints
# ---------------------------------------------------------------------------------------------
def _lsq_eq(G, h, C, d):
    """min ||G x - h|| subject to C x = d (null-space method); C may be empty. ``h`` and ``d``
    may hold several right-hand sides as columns (one problem per column, same G and C)."""
    if C is None or C.shape[0] == 0:
        return np.linalg.lstsq(G, h, rcond=None)[0]
    x_p = np.linalg.lstsq(C, d, rcond=None)[0]
    res = np.linalg.norm(np.reshape(C @ x_p - d, (C.shape[0], -1)), axis=0)
    ref = np.maximum(np.linalg.norm(np.reshape(d, (C.shape[0], -1)), axis=0), 1.0)
    if np.any(res > 1e-8 * ref):
        raise ValueError("the equality constraints of the fit are inconsistent (constrain_k0 "
                         "and match_k together at the same k, or too few coefficients)")
    _, sv, vt = np.linalg.svd(C)
    rank = int(np.sum(sv > 1e-12 * max(sv.max(), 1e-300)))
    Z = vt[rank:].T
    if Z.shape[1] == 0:
        return x_p
    y = np.linalg.lstsq(G @ Z, h - G @ x_p, rcond=None)[0]
    return x_p + Z @ y


def _blocks(k, n):
    """Complex basis of A0, A1, A2 for one element: (n_k, 3)."""
    ik = 1j * k
    return np.stack([np.ones_like(ik), ik, ik ** 2], axis=1)


class _Als:
    """Alternating least squares of one minimum-state problem (fixed lag roots)."""

    def __init__(self, k, Q, W, roots, k0_con, match_idx):
        self.k, self.Q, self.W = k, Q, W
        self.n = Q.shape[1]
        self.roots = roots
        self.nL = roots.size
        ik = 1j * k
        self.g = ik[:, None] / (ik[:, None] + roots[None, :])          # (n_k, n_L)
        self.basis = _blocks(k, self.n)                                   # (n_k, 3)
        self.con_rows = []                                                # (f, part)
        if k0_con:
            self.con_rows.append((0, "re"))
        if match_idx is not None:
            self.con_rows += [(match_idx, "re"), (match_idx, "im")]
        # one weight per k: all column (row) problems share one design matrix (and the same
        # constraint rows), so they are solved together with several right-hand sides
        self.batch = bool(np.all(W == W[:, :1, :1]))

    def _solve(self, lag_coef, q, w):
        """One column (or row) problem. lag_coef (n_k, n_other, n_L) complex: coefficient of
        the lag unknowns for each k and each element of the column/row; q (n_k, n_other)
        data; w (n_k, n_other) weights. Unknowns [a0 (n), a1 (n), a2 (n), lag (n_L)]."""
        n, nL, nk = self.n, self.nL, self.k.size
        Gc = np.zeros((nk, n, 3 * n + nL), complex)
        for c in range(3):
            Gc[:, np.arange(n), c * n + np.arange(n)] = self.basis[:, c][:, None]
        Gc[:, :, 3 * n:] = lag_coef
        Gw = Gc * w[:, :, None]
        qw = q * w
        G = np.vstack([Gw.real.reshape(nk * n, -1), Gw.imag.reshape(nk * n, -1)])
        h = np.concatenate([qw.real.ravel(), qw.imag.ravel()])
        C, d = [], []
        for f, part in self.con_rows:
            C.append(getattr(Gc[f], "real" if part == "re" else "imag"))
            d.append(getattr(q[f], "real" if part == "re" else "imag"))
        if C:
            C, d = np.vstack(C), np.concatenate(d)
        else:
            C, d = None, None
        x = _lsq_eq(G, h, C, d)
        return x[:n], x[n:2 * n], x[2 * n:3 * n], x[3 * n:]

    def _solve_all(self, lag_coef, Qs):
        """All n column (or row) problems at once when the weights are one per k: the
        design matrix (and the constraint rows of :meth:`_solve`) is common, so one
        (constrained) least-squares solve with n right-hand sides.
        Qs (n_k, n_other, n_problems). Returns (a0, a1, a2 (n, n_problems), lag (n_L, n_p))."""
        n, nk = self.n, self.k.size
        Gc = np.zeros((nk, n, 3 * n + self.nL), complex)
        for c in range(3):
            Gc[:, np.arange(n), c * n + np.arange(n)] = self.basis[:, c][:, None]
        Gc[:, :, 3 * n:] = lag_coef
        w = self.W[:, 0, 0][:, None, None]
        Gw, qw = Gc * w, Qs * w
        G = np.vstack([Gw.real.reshape(nk * n, -1), Gw.imag.reshape(nk * n, -1)])
        h = np.vstack([qw.real.reshape(nk * n, -1), qw.imag.reshape(nk * n, -1)])
        C, d = None, None
        if self.con_rows:
            C = np.vstack([getattr(Gc[f], "real" if part == "re" else "imag")
                           for f, part in self.con_rows])
            d = np.vstack([getattr(Qs[f], "real" if part == "re" else "imag")
                           for f, part in self.con_rows])
        x = _lsq_eq(G, h, C, d)
        return x[:n], x[n:2 * n], x[2 * n:3 * n], x[3 * n:]

    def step_E(self, D):
        n, nL = self.n, self.nL
        A = np.zeros((3, n, n))
        E = np.zeros((nL, n))
        lag = self.g[:, None, :] * D[None, :, :]                          # (n_k, i, l)
        if self.batch:
            A[0], A[1], A[2], E = self._solve_all(lag, self.Q)
            return A, E
        for j in range(n):
            a0, a1, a2, e = self._solve(lag, self.Q[:, :, j], self.W[:, :, j])
            A[0][:, j], A[1][:, j], A[2][:, j], E[:, j] = a0, a1, a2, e
        return A, E

    def step_D(self, E):
        n, nL = self.n, self.nL
        A = np.zeros((3, n, n))
        D = np.zeros((n, nL))
        lag = self.g[:, None, :] * E.T[None, :, :]                        # (n_k, j, l)
        if self.batch:
            a0, a1, a2, dd = self._solve_all(lag, np.swapaxes(self.Q, 1, 2))
            return np.stack([a0.T, a1.T, a2.T]), dd.T
        for i in range(n):
            a0, a1, a2, dd = self._solve(lag, self.Q[:, i, :], self.W[:, i, :])
            A[0][i], A[1][i], A[2][i], D[i] = a0, a1, a2, dd
        return A, D

    def evaluate(self, A, D, E):
        p = 1j * self.k
        out = (A[0][None] + p[:, None, None] * A[1][None]
               + (p ** 2)[:, None, None] * A[2][None])
        return out + np.einsum("fl,il,lj->fij", self.g, D, E)

    def cost(self, A, D, E):
        return float(np.sum(np.abs(self.W * (self.evaluate(A, D, E) - self.Q)) ** 2))

    @staticmethod
    def _normalise(D, E):
        """Remove the scale ambiguity D S, S^-1 E (unit largest entry per column of D)."""
        s = np.abs(D).max(axis=0)
        s = np.where(s > 0, s, 1.0)
        return D / s[None, :], E * s[:, None]

    def run(self, D0, max_iter, tol):
        """Alternate the D and E steps from D0. Each sweep is accelerated by extrapolation
        along the last change of D (a trial D_k + a (D_k - D_{k-1}) followed by an E step,
        kept only if it lowers J; the step a grows on success and is reset on failure), a
        device of alternating least squares for bilinear models; J never increases."""
        D = D0.copy()
        A, E = self.step_E(D)
        D, E = self._normalise(D, E)
        J_prev = self.cost(A, D, E)
        history = [J_prev]
        converged = False
        it = 0
        a = 1.0
        D_old = None
        for it in range(1, max_iter + 1):
            A, D = self.step_D(E)
            A, E = self.step_E(D)
            D, E = self._normalise(D, E)
            J = self.cost(A, D, E)
            if D_old is not None:
                D_try = D + a * (D - D_old)
                A_t, E_t = self.step_E(D_try)
                J_t = self.cost(A_t, D_try, E_t)
                if J_t < J:
                    D, E = self._normalise(D_try, E_t)
                    A, J = A_t, J_t
                    a = min(2.0 * a, 64.0)
                else:
                    a = 1.0
            D_old = D
            history.append(J)
            if J_prev - J <= tol * max(J_prev, 1e-300):
                converged = True
                break
            J_prev = J
        return A, D, E, np.array(history), it, converged


def _initial_D(n: int, nL: int) -> np.ndarray:
    """Roger-like start: lag state l belongs to mode l mod n (D a tiled identity)."""
    D0 = np.zeros((n, nL))
    D0[np.arange(nL) % n, np.arange(nL)] = 1.0
    return D0


@small_dense
def minimum_state_fit(k, Q, b_ref: float, n_states: int = 4, lag_roots=None, weights=None,
                      normalize: bool = False, normalize_floor: float = 0.01,
                      constrain_k0: bool = False, match_k: float | None = None,
                      optimize_roots: bool = False, root_bounds=None, max_iter: int = 500,
                      tol: float = 1e-9, max_root_evaluations: int = 400,
                      initial_D=None, mach: float | None = None) -> MinimumStateFit:
    """Minimum-state fit Q(ik) ~ A0 + A1 ik + A2 (ik)^2 + D (ik I - R)^-1 E ik.

    Parameters
    ----------
    k : (n_k,) reduced frequencies, ascending, >= 0. Q : (n_k, n, n) complex GAFs (e^{i omega t}).
    b_ref : reference semi-chord (> 0).
    n_states : number of lag states n_L (>= 1) when ``lag_roots`` is None.
    lag_roots : (n_L,) beta_l > 0 (default :func:`default_ms_roots`); the start values when
        ``optimize_roots``.
    weights : None, (n_k,) per k or (n_k, n, n) per element and k, finite and >= 0.
    normalize : divide every element's weights by max_k |Q_ij| (floored at
        ``normalize_floor`` x max_ij,k |Q_ij|).
    constrain_k0 : reproduce Re Q(k_min) exactly (steady load).
    match_k : a tabulated k (within 1e-9 relative) at which Q is reproduced exactly.
    optimize_roots : optimise log beta by bounded Nelder-Mead on the converged weighted error,
        at most ``max_root_evaluations`` fits, within ``root_bounds`` ((lo, hi), default
        (1e-3 k_max, 2 k_max)).
    max_iter, tol : alternating sweeps and the relative decrease of J that stops them.
    initial_D : (n, n_L) start for D (default: a tiled identity, the Roger-like assignment).
    mach : informational.

    Returns
    -------
    :class:`MinimumStateFit`

    Raises
    ------
    ValueError
        bad shapes or non-finite data, n_states < 1, non-positive roots, negative weights, too
        few equations for the unknowns, ``match_k`` not in the table.
    """
    positive("b_ref", b_ref)
    k, Q = check_gaf_table(k, Q)
    n_k, n = Q.shape[0], Q.shape[1]
    n_states = integer("n_states", n_states, low=1)
    max_iter = integer("max_iter", max_iter, low=1)
    max_root_evaluations = integer("max_root_evaluations", max_root_evaluations, low=1)
    if lag_roots is None:
        lag_roots = default_ms_roots(float(k.max()), n_states)
    roots = np.atleast_1d(finite_array("lag_roots", lag_roots))
    if roots.size < 1 or np.any(~np.isfinite(roots)) or np.any(roots <= 0):
        raise ValueError(f"lag_roots must be >= 1 finite values > 0, got {roots}")
    nL = roots.size
    if 2 * n_k * n < 3 * n + nL:
        raise ValueError(f"{n_k} k points give {2 * n_k * n} real equations per column, fewer "
                         f"than the {3 * n + nL} unknowns; give more k or fewer lag states")
    if weights is None:
        W = np.ones((n_k, n, n))
    else:
        w = np.asarray(weights, dtype=float)
        if w.shape == (n_k,):
            W = np.broadcast_to(w[:, None, None], (n_k, n, n)).copy()
        elif w.shape == (n_k, n, n):
            W = w.copy()
        else:
            raise ValueError(f"weights must have shape ({n_k},) or ({n_k}, {n}, {n}); "
                             f"got {w.shape}")
        if not np.all(np.isfinite(W)) or np.any(W < 0):
            raise ValueError("weights must be finite and >= 0")
    if normalize:
        positive("normalize_floor", normalize_floor)
        mag = np.abs(Q).max(axis=0)
        W = W / np.maximum(mag, normalize_floor * mag.max())[None]
    match_idx = None
    if match_k is not None:
        hit = np.nonzero(np.abs(k - float(match_k)) <= 1e-9 * max(abs(float(match_k)), 1e-12))[0]
        if hit.size == 0:
            raise ValueError(f"match_k {match_k} is not one of the tabulated k {k.tolist()}")
        match_idx = int(hit[0])
        if constrain_k0 and match_idx == 0:
            raise ValueError("match_k at the lowest k already includes constrain_k0; "
                             "use one of them")
    if initial_D is None:
        D0 = _initial_D(n, nL)
    else:
        D0 = np.asarray(initial_D, dtype=float)
        if D0.shape != (n, nL) or not np.all(np.isfinite(D0)):
            raise ValueError(f"initial_D must be a finite ({n}, {nL}) array")

    def solve(r):
        als = _Als(k, Q, W, r, constrain_k0, match_idx)
        return als, als.run(D0, max_iter, tol)

    if optimize_roots:
        from scipy.optimize import minimize

        kmax = float(k.max())
        lo, hi = (1e-3 * kmax, 2.0 * kmax) if root_bounds is None else map(float, root_bounds)
        if not (0 < lo < hi):
            raise ValueError(f"root_bounds must satisfy 0 < lo < hi, got {(lo, hi)}")
        roots = np.clip(roots, lo * 1.0001, hi * 0.9999)

        def objective(logr):
            als, (A, D, E, _, _, _) = solve(np.sort(np.exp(logr)))
            return als.cost(A, D, E)

        res = minimize(objective, np.log(roots), method="Nelder-Mead",
                       bounds=[(np.log(lo), np.log(hi))] * nL,
                       options={"maxfev": int(max_root_evaluations), "xatol": 1e-4,
                                "fatol": 1e-12})
        roots = np.sort(np.exp(res.x))
    als, (A, D, E, hist, it, conv) = solve(roots)
    for name, a in (("A", A), ("D", D), ("E", E)):
        finite_result(f"the minimum-state fit's {name}", a, "check the scale of Q and the "
                      "lag_roots (finite, > 0, of the order of k) or give initial_D")
    elem, overall = fit_errors(Q, als.evaluate(A, D, E))
    ref = float(np.sum(np.abs(W * Q) ** 2))
    return MinimumStateFit(
        A=A, D=D, E=E, lag_roots=roots, b_ref=float(b_ref), k=k, Q=Q, element_error=elem,
        fit_error=overall, weighted_error=float(np.sqrt(hist[-1] / max(ref, 1e-300))),
        iterations=int(it), converged=bool(conv), constrained_k0=bool(constrain_k0),
        match_k=None if match_idx is None else float(k[match_idx]), mach=mach,
        error_history=np.sqrt(hist / max(ref, 1e-300)), weights=W)


def minimum_state_fit_database(database, mach: float, interpolate: bool = False,
                               **kwargs) -> MinimumStateFit:
    """:func:`minimum_state_fit` of a :class:`~asekit.aero.gaf.GafDatabase` at one Mach (see
    :meth:`~asekit.aero.gaf.GafDatabase.at`); ``kwargs`` go to :func:`minimum_state_fit`."""
    g = database.at(mach, interpolate=interpolate)
    return minimum_state_fit(g.k, g.Q, database.b_ref, mach=mach, **kwargs)
