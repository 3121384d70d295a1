"""Analytic sensitivities of the modal model, the GAFs, the p-k roots and the flutter point.

Design variables theta change the structure only; the aerodynamic influence of the boxes does
not depend on them, so the GAFs Q(k) = Phi^T A(k) Phi (A the structure-independent aerodynamic
operator from the FE degrees of freedom through the spline, the boxes' pressures and back;
:func:`asekit.aero.gaf.gaf_from_box_modes`) change only through the mode shapes:

    dQ(k) = dPhi^T A(k) Phi + Phi^T A(k) dPhi,

i.e. the cross blocks of the GAF table of the extended mode set [Phi, dPhi_1, ..., dPhi_n_var]
(:func:`extended_shapes`, :func:`gaf_derivative`). The modal matrices follow by the product
rule (:func:`modal_matrix_derivative`).

p-k root (the equation of :mod:`asekit.aeroelastic.flutter`, thesis Eq. 3.12):

    F(p, k, U, theta) v = [p^2 M + p (C - rho b U / 2 Q^I(k)/k) + K - q Q^R(k)] v = 0,
    k = b Im(p) / U,  q = rho U^2 / 2,

with Q^R and Q^I/k interpolated linearly in k between the table points, as the solver does.
With right and left null vectors v, w (w^H F = 0), the first-order change of the root
p = sigma + i omega satisfies the complex (two real) equations

    w^H F_p v dp + w^H F_k v dk + w^H F_theta v dtheta + w^H F_U v dU = 0,
    dk = (b / U) domega - (b omega / U^2) dU,

solved for (dsigma, domega) (:func:`pk_root_sensitivity`): the k dependence is included
through dF/dk = p d(C_eff)/dk + d(K_eff)/dk, the slope of the linear interpolant (piecewise
constant in k: the derivative is one-sided at a table point, where the interpolant has a
kink). The flutter point sigma(U_f, theta) = 0 then gives, by the implicit function theorem,

    dU_f/dtheta = -(dsigma/dtheta) / (dsigma/dU),
    domega_f/dtheta = domega/dtheta + (domega/dU) dU_f/dtheta

(:func:`flutter_speed_sensitivity`); :func:`flutter_point` converges the crossing itself by
Newton's method on sigma(U) = 0 with that analytic dsigma/dU.

Any consistent units (SI for the fin): rho in kg/m^3, U in m/s, p in 1/s, b in m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aero.gaf import TabulatedGaf
from asekit.aeroelastic.flutter import _mac, _PkProblem


def modal_matrix_derivative(Phi: np.ndarray, A, dPhi: np.ndarray, dA) -> np.ndarray:
    """d(Phi^T A Phi) = dPhi^T A Phi + Phi^T dA Phi + Phi^T A dPhi (symmetric A), per variable.

    Parameters
    ----------
    Phi : (n_dof, n) modes; A : (n_dof, n_dof) matrix (dense or sparse);
    dPhi : (n_var, n_dof, n) mode derivatives; dA : n_var derivatives of A.

    Returns
    -------
    (n_var, n, n) derivatives of the modal matrix.

    Examples
    --------
    >>> Phi = np.array([[1.0], [0.0]])
    >>> d = modal_matrix_derivative(Phi, np.eye(2), np.array([[[0.5], [0.0]]]), [np.zeros((2, 2))])
    >>> float(d[0, 0, 0])                             # 2 * 0.5 * 1
    1.0
    """
    out = np.empty((len(dA), Phi.shape[1], Phi.shape[1]))
    APhi = A @ Phi
    for j, (dP, da) in enumerate(zip(dPhi, dA)):
        cross = dP.T @ APhi
        out[j] = cross + cross.T + Phi.T @ (da @ Phi)
    return out


def extended_shapes(shapes: np.ndarray, dshapes: np.ndarray) -> np.ndarray:
    """The mode table [Phi, dPhi_1, ..., dPhi_n_var] of a ModalModel's ``shapes`` (n_nodes, 3,
    n) and their derivatives ``dshapes`` (n_var, n_nodes, 3, n): (n_nodes, 3, n (1 + n_var)).
    Splined to the boxes and put through :func:`asekit.aero.gaf.gaf_from_box_modes` it gives the
    table :func:`gaf_derivative` reads (the spline and the aerodynamics are linear in the shapes).
    """
    shapes = np.asarray(shapes, float)
    return np.concatenate([shapes] + [np.asarray(d, float) for d in dshapes], axis=2)


def gaf_derivative(Q_ext: np.ndarray, n_modes: int) -> np.ndarray:
    """dQ (n_var, n_k, n, n) from the GAF table ``Q_ext`` (n_k, N, N) of the extended mode set
    of :func:`extended_shapes` (N = n (1 + n_var)): dQ_j = Q[dPhi_j, Phi] + Q[Phi, dPhi_j]
    (rows: the mode the force acts on; columns: the motion).

    Examples
    --------
    >>> Q = np.arange(16.0).reshape(1, 4, 4)          # n = 2 modes, one variable
    >>> gaf_derivative(Q, 2)[0, 0].tolist()           # Q[2:4, 0:2] + Q[0:2, 2:4]
    [[10.0, 12.0], [18.0, 20.0]]
    """
    Q_ext = np.asarray(Q_ext)
    n = int(n_modes)
    N = Q_ext.shape[1]
    if N % n or Q_ext.shape[2] != N:
        raise ValueError(f"Q_ext must be (n_k, N, N) with N a multiple of n_modes = {n}, "
                         f"got {Q_ext.shape}")
    n_var = N // n - 1
    out = np.empty((n_var, Q_ext.shape[0], n, n), dtype=Q_ext.dtype)
    for j in range(n_var):
        s = slice(n * (j + 1), n * (j + 2))
        out[j] = Q_ext[:, s, :n] + Q_ext[:, :n, s]
    return out


def _segment(kk: np.ndarray, k: float):
    """The interpolation segment j, weight t and dt/dk of the p-k solver's linear rule (k held
    at the end values outside the table: dt/dk = 0 there)."""
    kq = min(max(k, kk[0]), kk[-1])
    j = min(max(int(np.searchsorted(kk, kq)) - 1, 0), kk.size - 2)
    h = kk[j + 1] - kk[j]
    inside = kk[0] < k < kk[-1]
    return j, (kq - kk[j]) / h, (1.0 / h if inside else 0.0)


def _split(Q: np.ndarray, kk: np.ndarray):
    """Q^R and Q^I / k tables (the k = 0 row of Q^I / k takes the next row, as the solver)."""
    qik = Q.imag / np.where(kk > 0, kk, 1.0)[:, None, None]
    if kk[0] == 0:
        qik[0] = qik[1]
    return Q.real, qik


def _interp(tables, j, t):
    return [(1 - t) * a[j] + t * a[j + 1] for a in tables]


@dataclass(frozen=True)
class RootSensitivity:
    """A converged p-k root and its derivatives.

    p : the root (1/s), Im p >= 0; vector : (n,) right eigenvector; k : its reduced frequency;
    dp : (n_var,) complex dp/dtheta_j; dp_du : complex dp/dU (s/m per 1/s) at fixed theta.
    """

    p: complex
    vector: np.ndarray
    k: float
    dp: np.ndarray
    dp_du: complex


def _null_vectors(F: np.ndarray):
    u, _, vh = np.linalg.svd(F)
    return u[:, -1], vh[-1].conj()


def pk_root_sensitivity(M, K, C, gaf: TabulatedGaf, density: float, velocity: float, p: complex,
                        dM, dK, dC, dQ) -> RootSensitivity:
    """Derivatives of a converged p-k root with respect to the design variables and to U
    (module docstring: implicit differentiation of Eq. 3.12 including k = b Im p / U).

    Parameters
    ----------
    M, K, C : (n, n) modal matrices of the modes solved (the elastic set when the rigid mode is
        held); gaf : their :class:`TabulatedGaf`; density : rho (kg/m^3); velocity : U (m/s);
    p : the converged root (Im p >= 0, as the solver returns it);
    dM, dK, dC : (n_var, n, n) derivatives; dQ : (n_var, n_k, n, n) derivatives of gaf.Q.

    Returns
    -------
    :class:`RootSensitivity`.

    Examples
    --------
    One mode, no aerodynamics (Q = 0): p = i omega, omega^2 = K / M, dp/dK = i / (2 omega M).

    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 1, 1)), 1.0)
    >>> r = pk_root_sensitivity(np.eye(1), 4 * np.eye(1), np.zeros((1, 1)), g, 1.0, 10.0, 2j,
    ...                         np.zeros((1, 1, 1)), np.ones((1, 1, 1)), np.zeros((1, 1, 1)),
    ...                         np.zeros((1, 2, 1, 1)))
    >>> bool(abs(r.dp[0].real) < 1e-15), float(r.dp[0].imag)
    (True, 0.25)
    """
    rho, U, b = float(density), float(velocity), gaf.b_ref
    kk = gaf.k
    k = b * abs(p.imag) / U
    j, t, dt = _segment(kk, k)
    qr_t, qik_t = _split(gaf.Q, kk)
    qr, qik = _interp((qr_t, qik_t), j, t)
    dqr_dk, dqik_dk = (qr_t[j + 1] - qr_t[j]) * dt, (qik_t[j + 1] - qik_t[j]) * dt
    q = 0.5 * rho * U ** 2
    Ceff = C - 0.5 * rho * b * U * qik
    F = p ** 2 * M + p * Ceff + K - q * qr
    w, v = _null_vectors(F)
    a = w.conj() @ ((2 * p * M + Ceff) @ v)
    fk = w.conj() @ ((-0.5 * rho * b * U * p * dqik_dk - q * dqr_dk) @ v)
    c = fk * b / U
    # a dsigma + (i a + c) domega = -r: two real equations
    S = np.array([[a.real, (1j * a + c).real], [a.imag, (1j * a + c).imag]])

    def solve(r):
        x = np.linalg.solve(S, [-r.real, -r.imag])
        return complex(x[0], x[1])

    fu = w.conj() @ ((-0.5 * rho * b * p * qik - rho * U * qr) @ v)
    dp_du = solve(fu - fk * b * abs(p.imag) / U ** 2)
    dp = np.empty(len(dM), complex)
    for i in range(len(dM)):
        dqr_i, dqik_i = _interp(_split(np.asarray(dQ[i]), kk), j, t)
        dF = (p ** 2 * dM[i] + p * (dC[i] - 0.5 * rho * b * U * dqik_i) + dK[i] - q * dqr_i)
        dp[i] = solve(w.conj() @ (dF @ v))
    return RootSensitivity(p=complex(p), vector=v, k=k, dp=dp, dp_du=dp_du)


def converge_root(M, K, C, gaf: TabulatedGaf, density: float, velocity: float,
                  omega_guess: float, ref: np.ndarray, tol: float = 1e-13, max_iter: int = 400):
    """The p-k root at U nearest ``omega_guess`` (rad/s) and best correlated with ``ref``,
    converged tightly (Hassig's k-iteration of :mod:`asekit.aeroelastic.flutter`, linear
    interpolation in k). Returns (p, vector). Raises RuntimeError if it does not converge."""
    prob = _PkProblem(np.asarray(M, float), np.asarray(K, float), np.asarray(C, float), gaf,
                      float(density), "linear")
    p, v, _, ok = prob.solve_mode(float(velocity), omega_guess, np.asarray(ref, complex), tol,
                                  max_iter)
    if not ok:
        raise RuntimeError(f"the p-k root near {omega_guess:.6g} rad/s at U = {velocity:.6g} did "
                           f"not converge in {max_iter} k-iterations")
    return complex(p), v


def flutter_point(M, K, C, gaf: TabulatedGaf, density: float, velocity: float, p: complex,
                  vector: np.ndarray, rtol: float = 1e-12, max_iter: int = 30):
    """The flutter crossing Re p(U_f) = 0 of the root (p, vector) found at ``velocity`` near it,
    by Newton's method on sigma(U) with the analytic dsigma/dU of :func:`pk_root_sensitivity`.

    Returns (U_f, p_f, vector_f). Raises RuntimeError when Newton does not converge (a root that
    does not cross, or a crossing far from ``velocity``).
    """
    U = float(velocity)
    n = M.shape[0]
    zero = np.zeros((0, n, n))
    for _ in range(max_iter):
        p, vector = converge_root(M, K, C, gaf, density, U, abs(p.imag), vector)
        s = pk_root_sensitivity(M, K, C, gaf, density, U, p, zero, zero, zero,
                                np.zeros((0,) + gaf.Q.shape))
        step = -p.real / s.dp_du.real
        U += step
        if abs(step) <= rtol * U:
            p, vector = converge_root(M, K, C, gaf, density, U, abs(p.imag), vector)
            return U, p, vector
    raise RuntimeError(f"the flutter crossing did not converge from U = {velocity:.6g}")


@dataclass(frozen=True)
class FlutterSensitivity:
    """Flutter speed U_f (m/s) and frequency (Hz) at a crossing and their derivatives
    ``d_speed`` (n_var,) (m/s per unit theta) and ``d_frequency_hz`` (n_var,); ``root`` the
    :class:`RootSensitivity` at the crossing."""

    speed: float
    frequency_hz: float
    d_speed: np.ndarray
    d_frequency_hz: np.ndarray
    root: RootSensitivity


def flutter_speed_sensitivity(M, K, C, gaf: TabulatedGaf, density: float, speed: float,
                              p: complex, dM, dK, dC, dQ) -> FlutterSensitivity:
    """dU_f/dtheta = -Re(dp/dtheta) / Re(dp/dU) and domega_f/dtheta at the crossing (module
    docstring), for a root p with Re p = 0 at U = ``speed`` (:func:`flutter_point`).

    Examples
    --------
    One mode with a negative aerodynamic damping Q = 2i k: sigma = (rho b U - c) / 2 (M = K = 1),
    so with C = c the crossing is at U_f = c / (rho b) and dU_f/dc = 1 / (rho b):

    >>> k = np.array([0.0, 1.0])
    >>> g = TabulatedGaf(k, (2j * k)[:, None, None], 1.0)
    >>> s = flutter_speed_sensitivity(np.eye(1), np.eye(1), np.eye(1), g, 1.0, 1.0,
    ...                               complex(0.0, 1.0), np.zeros((1, 1, 1)), np.zeros((1, 1, 1)),
    ...                               np.ones((1, 1, 1)), np.zeros((1, 2, 1, 1)))
    >>> round(float(s.d_speed[0]), 12)
    1.0
    """
    r = pk_root_sensitivity(M, K, C, gaf, density, speed, p, dM, dK, dC, dQ)
    if r.dp_du.real == 0:
        raise ValueError("dRe(p)/dU = 0 at the crossing: a tangency, not a crossing; the flutter "
                         "speed is not differentiable there")
    dU = -r.dp.real / r.dp_du.real
    domega = r.dp.imag + r.dp_du.imag * dU
    return FlutterSensitivity(speed=float(speed), frequency_hz=abs(p.imag) / (2 * np.pi),
                              d_speed=dU, d_frequency_hz=domega / (2 * np.pi), root=r)


def correlate(vectors: np.ndarray, ref: np.ndarray) -> int:
    """Index of the column of ``vectors`` best correlated (MAC) with ``ref``."""
    return int(np.argmax(_mac(np.asarray(ref, complex), np.asarray(vectors, complex))))


@dataclass(frozen=True)
class DivergenceSensitivity:
    """The static-divergence eigenvalue of the elastic modes and its derivatives.

    mu : the largest real eigenvalue of Re Q(0) x = mu K x (m^2/N per modal unit, i.e. 1 / q);
    mu > 0: divergence at q_D = 1 / mu (Pa), U_D = sqrt(2 q_D / rho); mu <= 0: no divergence.
    d_mu : (n_var,) dmu/dtheta_j. ``mu`` is NaN (and ``d_mu`` zero) when no eigenvalue is real.
    """

    mu: float
    d_mu: np.ndarray

    def speed(self, density: float) -> float:
        """U_D = sqrt(2 / (rho mu)) (m/s) at the density rho (kg/m^3); inf without divergence."""
        return math.sqrt(2.0 / (density * self.mu)) if self.mu > 0 else math.inf

    def d_speed(self, density: float) -> np.ndarray:
        """dU_D/dtheta = -U_D dmu / (2 mu) (m/s per unit theta); zero without divergence."""
        if not self.mu > 0:
            return np.zeros_like(self.d_mu)
        return -0.5 * self.speed(density) * self.d_mu / self.mu


def divergence_sensitivity(K, Q0, dK, dQ0) -> DivergenceSensitivity:
    """The divergence eigenvalue mu = 1 / q_D of the steady GAFs and its derivatives.

    Divergence is det(K - q Re Q(0)) = 0 (thesis Eq. 3.13; :func:`asekit.aeroelastic.flutter.\
divergence_speeds`), written here as the eigenproblem Re Q(0) x = mu K x with mu = 1 / q, so that
    the quantity stays smooth where a design loses its divergence (mu passes through zero while q
    passes through infinity). With the right and left eigenvectors v, w of the largest real mu
    (w^H (Q0 - mu K) = 0), differentiating (Q0 - mu K) v = 0 and projecting on w gives

        dmu/dtheta = w^H (dQ0 - mu dK) v / (w^H K v)

    (the first-order perturbation of a simple eigenvalue of a non-symmetric pencil, e.g.
    Wilkinson, *The Algebraic Eigenvalue Problem*, 1965, Ch. 2, Sec. 8-10), equivalent to
    dq_D = -q_D^2 dmu = w^H (dK - q_D dQ0) v / (w^H Q0 v). dQ0 comes through the mode-shape
    derivatives as the GAF derivative (:func:`gaf_derivative` at the table's first k).

    Parameters
    ----------
    K : (n, n) modal stiffness of the elastic modes; Q0 : (n, n) their GAF at k = 0 (or the
    table's nearest k; its real part is used); dK : (n_var, n, n); dQ0 : (n_var, n, n).

    Returns
    -------
    :class:`DivergenceSensitivity`.

    Examples
    --------
    One mode: Q0 = 2, K = 4: mu = 0.5 (q_D = 2), dmu/dK = -Q0 / K^2 = -0.125.

    >>> s = divergence_sensitivity(np.array([[4.0]]), np.array([[2.0]]), np.ones((1, 1, 1)),
    ...                            np.zeros((1, 1, 1)))
    >>> float(s.mu), float(s.d_mu[0])
    (0.5, -0.125)
    """
    from scipy import linalg
    K = np.asarray(K, float)
    Q0 = np.asarray(Q0).real
    mu, wl, vr = linalg.eig(Q0, K, left=True, right=True)
    real = np.flatnonzero(np.isfinite(mu)
                          & (np.abs(mu.imag) <= 1e-9 * np.maximum(np.abs(mu), 1e-300)))
    if real.size == 0:
        return DivergenceSensitivity(mu=math.nan, d_mu=np.zeros(len(dK)))
    i = real[np.argmax(mu[real].real)]
    m, v, w = float(mu[i].real), vr[:, i], wl[:, i]
    den = w.conj() @ K @ v
    d = np.array([(w.conj() @ (np.asarray(b).real - m * np.asarray(a)) @ v / den).real
                  for a, b in zip(dK, dQ0)])
    return DivergenceSensitivity(mu=m, d_mu=d)
