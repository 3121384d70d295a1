"""Roger's rational function approximation of generalized aerodynamic forces (thesis 2.2.1.4).

Every element of the tabulated GAF matrix Q(M, k) at one Mach number is fitted with

    Q~(k) = A0 + (ik) A1 + (ik)^2 A2 + sum_n (ik) A_{n+2} / (ik + beta_n)        Eq. (2.13)

with preset lag roots beta_n > 0. Real and imaginary parts (Eqs. 2.15-2.16) give one linear
least-squares problem per element (Eqs. 2.17-2.24); all elements share the same design matrix,
so the fit is one solve with n^2 right-hand sides. Options beyond the thesis: per-k weights and an
exact equality constraint through the lowest-k (steady) data (Karpel & Strul / Tiffany & Adams,
"Nonlinear programming extensions to rational function approximation methods for unsteady
aerodynamic forces", NASA TP-2776, 1988, Sec. "constraints").

In the Laplace domain (Eq. 2.28), with s = i omega and k = omega b / U:

    Q~(s) = A0 + (s b/U) A1 + (s b/U)^2 A2 + sum_n s A_{n+2} / (s + (U/b) beta_n).

(The thesis's Eq. 2.28 prints the lag denominator as s + (b/U) beta_n; Eq. 2.56 and Eq. 2.63 use
the dimensionally correct (U/b) beta_n, implemented here.)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from asekit.util.blas import small_dense
from asekit.util.validate import finite_array, finite_result, integer, positive, real_array


def default_lag_roots(k_max: float, n_lags: int = 4) -> np.ndarray:
    """Lag roots spread over the reduced-frequency range, beta_n = 1.7 k_max (n/(N+1))^2
    (Tiffany & Adams, NASA TP-2776, 1988, recommended spacing). Returns (n_lags,) > 0."""
    positive("k_max", k_max)
    n_lags = integer("n_lags", n_lags, low=0)
    n = np.arange(1, n_lags + 1)
    return 1.7 * k_max * (n / (n_lags + 1)) ** 2


def check_coefficients(fit, names=("A",)) -> None:
    """Refuse a fit (RogerFit, MinimumStateFit) whose coefficient arrays ``names`` or lag roots
    are not finite, or whose b_ref is not a finite number > 0 (ValueError naming the field)."""
    for name in names:
        object.__setattr__(fit, name, finite_array(name, getattr(fit, name)))
    roots = np.atleast_1d(finite_array("lag_roots", fit.lag_roots))
    if np.any(roots <= 0):
        raise ValueError(f"lag_roots must all be > 0, got {roots}")
    object.__setattr__(fit, "lag_roots", roots)
    object.__setattr__(fit, "b_ref", positive("b_ref", fit.b_ref))


@dataclass(frozen=True)
class RogerFit:
    """A Roger RFA at one Mach number.

    Attributes
    ----------
    A : (N + 3, n, n) real coefficient matrices A0, A1, A2, A3..A_{N+2} of Eq. (2.13).
    lag_roots : (N,) beta_n (dimensionless, > 0).
    b_ref : reference semi-chord b (m or the data's length unit) of k = omega b / U.
    k : (n_k,) reduced frequencies fitted.
    Q : (n_k, n, n) complex data fitted.
    element_error : (n, n) normalised error per element, ||Q_ij - Q~_ij|| / ||Q_ij|| over k
        (NaN-free: an all-zero element gets error 0 when fitted exactly, else the absolute error
        divided by the largest element norm).
    fit_error : overall normalised error ||Q - Q~||_F / ||Q||_F over all k and elements.
    constrained_k0 : whether the fit passes exactly through the real part of the lowest-k
        data (the steady load).
    mach : Mach number (informational; None if unknown).
    """

    A: np.ndarray
    lag_roots: np.ndarray
    b_ref: float
    k: np.ndarray
    Q: np.ndarray
    element_error: np.ndarray
    fit_error: float
    constrained_k0: bool = False
    mach: float | None = None
    weights: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        check_coefficients(self, ("A",))

    @property
    def n_lags(self) -> int:
        return len(self.lag_roots)

    @property
    def n_modes(self) -> int:
        return self.A.shape[1]

    @property
    def n_lag_states(self) -> int:
        """Aerodynamic lag states of the state-space model: one per lag term and mode, N n."""
        return self.n_lags * self.n_modes

    def lag_realization(self, n_rigid: int = 0):
        """The lag terms as one realization  sum_n (ik) A_{n+2} / (ik + beta_n) =
        D (ik I + diag(beta))^-1 E (ik)  (the minimum-state form of Karpel, with D a 0/1
        selection matrix): returns ``(D (n, N n), E (N n, n), roots (N n,), names)``.

        States are ordered as in thesis Eq. (2.63): for each lag n the rows of the elastic
        modes (``lag<n>_zeta<j>``), then, for each lag, the rigid rows (``lag<n>_hinge``);
        ``n_rigid`` (0 or 1) is the number of rigid modes in front.
        """
        n, N = self.n_modes, self.n_lags
        ns = n - n_rigid
        rows = [(n_, n_rigid + j) for n_ in range(N) for j in range(ns)]
        rows += [(n_, c) for n_ in range(N) for c in range(n_rigid)]
        D = np.zeros((n, N * n))
        E = np.zeros((N * n, n))
        roots = np.zeros(N * n)
        for r, (n_, i) in enumerate(rows):
            D[i, r] = 1.0
            E[r] = self.A[3 + n_][i]
            roots[r] = self.lag_roots[n_]
        names = ([f"lag{n_ + 1}_zeta{j + 1}" for n_ in range(N) for j in range(ns)]
                 + [f"lag{n_ + 1}_hinge" for n_ in range(N) for _ in range(n_rigid)])
        return D, E, roots, names

    def evaluate(self, k) -> np.ndarray:
        """Q~ at reduced frequencies ``k`` (scalar or array): (n, n) or (len(k), n, n) complex,
        Eq. (2.13)."""
        k_arr = np.atleast_1d(real_array("k", k))
        ik = 1j * k_arr
        terms = [np.ones_like(ik), ik, ik ** 2] + [ik / (ik + b) for b in self.lag_roots]
        basis = np.stack(terms, axis=1)                       # (n_k, N+3)
        out = np.einsum("fc,cij->fij", basis, self.A)
        return out[0] if np.ndim(k) == 0 else out

    def evaluate_laplace(self, s, velocity: float) -> np.ndarray:
        """Q~ at complex Laplace variable(s) ``s`` (1/s) and airspeed ``velocity``, Eq. (2.28)."""
        positive("velocity", velocity)
        s_arr = np.atleast_1d(np.asarray(s, dtype=complex))
        sb = s_arr * self.b_ref / velocity
        terms = [np.ones_like(sb), sb, sb ** 2] + [sb / (sb + b) for b in self.lag_roots]
        out = np.einsum("fc,cij->fij", np.stack(terms, axis=1), self.A)
        return out[0] if np.ndim(s) == 0 else out


def fit_errors(Q: np.ndarray, Q_fit: np.ndarray) -> tuple[np.ndarray, float]:
    """Normalised errors of a fit over k: per element ||Q_ij - Q~_ij|| / ||Q_ij|| (an all-zero
    element: the absolute error divided by the largest element norm), and overall
    ||Q - Q~||_F / ||Q||_F. Inputs (n_k, n, n) complex; returns ((n, n), float)."""
    err = Q - Q_fit
    num = np.sqrt(np.sum(np.abs(err) ** 2, axis=0))
    den = np.sqrt(np.sum(np.abs(Q) ** 2, axis=0))
    scale = max(float(den.max()), 1e-300)
    elem = np.where(den > 1e-12 * scale, num / np.where(den > 0, den, 1.0), num / scale)
    overall = float(np.linalg.norm(err) / max(np.linalg.norm(Q), 1e-300))
    return elem, overall


def check_gaf_table(k, Q) -> tuple[np.ndarray, np.ndarray]:
    """Validate a GAF table: k (n_k,) finite, >= 0, strictly ascending; Q (n_k, n, n) finite
    complex. Returns (k, Q) as float and complex arrays; ValueError otherwise."""
    k = finite_array("k", k)
    Q = finite_array("Q", Q, complex_values=True)
    if k.ndim != 1 or Q.ndim != 3 or Q.shape[0] != k.size or Q.shape[1] != Q.shape[2]:
        raise ValueError(f"Q must have shape (n_k, n, n) with n_k = len(k) = {k.size}; "
                         f"got Q {Q.shape}")
    if not (np.all(np.isfinite(k)) and np.all(np.isfinite(Q))) or np.abs(Q).max(initial=0) > 1e150:
        raise ValueError("k and Q must be finite (|Q| <= 1e150: its squares must not overflow)")
    if k.size == 0 or np.any(k < 0) or np.any(np.diff(k) <= 0):
        raise ValueError(f"k must be >= 0 and strictly ascending, got {k}")
    return k, Q


def design_rows(k: np.ndarray, lag_roots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows K_Rf and K_If of Eqs. (2.19)-(2.20) for every k: two arrays (n_k, N + 3)."""
    k = np.asarray(k, dtype=float)[:, None]
    beta = np.asarray(lag_roots, dtype=float)[None, :]
    one, zero = np.ones_like(k), np.zeros_like(k)
    kr = np.hstack([one, zero, -k ** 2, k ** 2 / (k ** 2 + beta ** 2)])
    ki = np.hstack([zero, k, zero, beta * k / (k ** 2 + beta ** 2)])
    return kr, ki


@small_dense
def roger_fit(k, Q, b_ref: float, lag_roots=None, n_lags: int = 4, weights=None,
              constrain_k0: bool = False, mach: float | None = None) -> RogerFit:
    """Least-squares Roger fit of tabulated GAFs, Eqs. (2.13)-(2.24).

    Parameters
    ----------
    k : (n_k,) reduced frequencies k = omega b / U, ascending, >= 0.
    Q : (n_k, n, n) complex GAF matrices (force per unit dynamic pressure per unit modal
        coordinate; time convention e^{i omega t}).
    b_ref : reference semi-chord used in k (> 0).
    lag_roots : (N,) lag roots beta_n > 0; default :func:`default_lag_roots` (k_max, n_lags).
    n_lags : number of lag terms when ``lag_roots`` is None (0 allowed: quasi-steady fit).
    weights : (n_k,) non-negative weights of each k point in the squared error (default 1).
    constrain_k0 : if True the fit matches the real (steady-load) part of Q at the lowest k
        exactly, the remaining error being minimised (equality-constrained least squares via the
        KKT system). The imaginary part at k ~ 0 is not constrained: it is O(k) and its slope
        from DLM data at k ~ 1e-6 is numerical noise. The thesis did not constrain its fit and names this as a source of spread.
    mach : stored for information.

    Returns
    -------
    :class:`RogerFit`

    Raises
    ------
    ValueError
        Non-positive lag roots, negative weights, fewer equations (2 n_k, real and imaginary)
        than coefficients N + 3, shape mismatch, or non-finite data.
    """
    positive("b_ref", b_ref)
    k, Q = check_gaf_table(k, Q)
    n_lags = integer("n_lags", n_lags, low=0)
    if lag_roots is None:
        lag_roots = default_lag_roots(float(k.max()), n_lags)
    lag_roots = np.atleast_1d(finite_array("lag_roots", lag_roots))
    if np.any(~np.isfinite(lag_roots)) or np.any(lag_roots <= 0):
        raise ValueError(f"lag_roots must all be finite and > 0, got {lag_roots}")
    n_coef = 3 + lag_roots.size
    if 2 * k.size < n_coef:
        raise ValueError(f"k has {k.size} points (2 n_k = {2 * k.size} real equations), fewer "
                         f"than the {n_coef} coefficients of a fit with {lag_roots.size} lag "
                         "roots; give more k points or fewer lag_roots")
    if weights is None:
        w = np.ones(k.size)
    else:
        w = np.asarray(weights, dtype=float)
        if w.shape != k.shape or np.any(w < 0) or not np.all(np.isfinite(w)):
            raise ValueError(f"weights must be (n_k,) = ({k.size},) finite values >= 0")
    kr, ki = design_rows(k, lag_roots)
    sw = np.sqrt(w)[:, None]
    G = np.vstack([kr * sw, ki * sw])                          # (2 n_k, n_coef)
    n = Q.shape[1]
    rhs = np.vstack([Q.real.reshape(k.size, -1) * sw, Q.imag.reshape(k.size, -1) * sw])
    if constrain_k0:
        # the steady (real) part at the lowest k: A0 - k0^2 A2 + sum k0^2/(k0^2+b^2) A_n
        C = kr[:1]
        d = Q[0].real.reshape(1, -1)
        nc = 1
        kkt = np.block([[G.T @ G, C.T], [C, np.zeros((nc, nc))]])
        sol = np.linalg.lstsq(kkt, np.vstack([G.T @ rhs, d]), rcond=None)[0]
        coef = sol[:n_coef]
    else:
        coef = np.linalg.lstsq(G, rhs, rcond=None)[0]          # Eq. (2.24)
    A = finite_result("the Roger fit's coefficients A", coef.reshape(n_coef, n, n),
                      "check the scale of Q and the lag_roots (finite, > 0, of the order of k)")
    fit = RogerFit(A=A, lag_roots=lag_roots, b_ref=float(b_ref), k=k, Q=Q,
                   element_error=np.zeros((n, n)), fit_error=0.0,
                   constrained_k0=bool(constrain_k0), mach=mach, weights=w)
    elem, overall = fit_errors(Q, fit.evaluate(k))
    return RogerFit(A=A, lag_roots=lag_roots, b_ref=float(b_ref), k=k, Q=Q,
                    element_error=elem, fit_error=overall, constrained_k0=bool(constrain_k0),
                    mach=mach, weights=w)


def roger_fit_database(database, mach: float, interpolate: bool = False, **kwargs) -> RogerFit:
    """:func:`roger_fit` of a :class:`~asekit.aero.gaf.GafDatabase` at one Mach (see
    :meth:`~asekit.aero.gaf.GafDatabase.at`); ``kwargs`` go to :func:`roger_fit`."""
    g = database.at(mach, interpolate=interpolate)
    return roger_fit(g.k, g.Q, database.b_ref, mach=mach, **kwargs)


def roger_fit_derivative(fit: RogerFit, dQ) -> np.ndarray:
    """Derivative of a Roger fit's coefficients with respect to a design parameter.

    For fixed lag roots, weights and k points the fit of Eqs. (2.17)-(2.24) (and its
    equality-constrained variant) is a linear least-squares solve A = G^+ [Re Q; Im Q], so its
    derivative is the same solve applied to the derivative of the data (issue 28):

        dA_j / dtheta = fit(dQ / dtheta)  (lags fixed),

    exact, not a finite difference. (Default lag roots depend on k only, never on Q.)

    Parameters
    ----------
    fit : :class:`RogerFit`
        The fit at the design point (its k, lag roots, weights and constraint are reused).
    dQ : (n_k, n, n) complex
        dQ/dtheta at the fit's k (e.g. :func:`asekit.aeroelastic.sensitivity.gaf_derivative`).

    Returns
    -------
    (N + 3, n, n) real: dA0/dtheta, ..., dA_{N+2}/dtheta.

    Examples
    --------
    The fit is linear: the derivative of the fit of Q + t dQ is the fit of dQ.

    >>> k = np.linspace(0.0, 1.0, 8)
    >>> Q = (1.0 + 0.5j * k - 0.2 * k ** 2)[:, None, None] * np.ones((1, 1, 1))
    >>> f = roger_fit(k, Q, 1.0, n_lags=2)
    >>> dA = roger_fit_derivative(f, 2.0 * Q)
    >>> bool(np.allclose(dA, 2.0 * f.A))
    True
    """
    dQ = finite_array("dQ", dQ, complex_values=True)
    if dQ.shape != fit.Q.shape:
        raise ValueError(f"dQ must have the fit's data shape {fit.Q.shape}, got {dQ.shape}")
    kr, ki = design_rows(fit.k, fit.lag_roots)
    w = np.ones(fit.k.size) if fit.weights is None else np.asarray(fit.weights, float)
    sw = np.sqrt(w)[:, None]
    G = np.vstack([kr * sw, ki * sw])
    nk, n = fit.k.size, fit.n_modes
    rhs = np.vstack([dQ.real.reshape(nk, -1) * sw, dQ.imag.reshape(nk, -1) * sw])
    n_coef = G.shape[1]
    if fit.constrained_k0:
        C = kr[:1]
        kkt = np.block([[G.T @ G, C.T], [C, np.zeros((1, 1))]])
        coef = np.linalg.lstsq(kkt, np.vstack([G.T @ rhs, dQ[0].real.reshape(1, -1)]),
                               rcond=None)[0][:n_coef]
    else:
        coef = np.linalg.lstsq(G, rhs, rcond=None)[0]
    return coef.reshape(n_coef, n, n)
