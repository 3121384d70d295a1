"""The two-dimensional pitch-plunge-flap typical section with Theodorsen aerodynamics in
state-space form (Wagner's indicial function in R. T. Jones' two-exponential approximation).

Coordinates q = [h, alpha, beta]: plunge h (m, positive down), pitch alpha about the elastic
axis (rad, nose up), flap beta about the hinge (rad, trailing edge down); semichord b, elastic
axis at x = a b and hinge at x = c b from mid-chord (positive aft). Everything per unit span.

Structure (Theodorsen 1935, NACA Report 496, Eqs. for the three-degree-of-freedom section):

    M_s = [[m_h, S_a, S_b], [S_a, I_a, I_b + b (c - a) S_b], [S_b, I_b + b (c - a) S_b, I_b]],
    K_s = diag(K_h, K_a, K_b),  D_s = diag(2 zeta_i sqrt(K_i M_s,ii))   (uncoupled damping)

Aerodynamic forces (Theodorsen 1935, NACA 496, with his geometric functions T1..T14 of c and a):
the plunge force P (positive down), pitching moment M_a and hinge moment M_b are a
non-circulatory part (apparent mass, damping and stiffness, exact in the time domain) and a
circulatory part proportional to the effective downwash at the three-quarter chord

    Q = U alpha + h' + b (1/2 - a) alpha' + (U / pi) T10 beta + (b / (2 pi)) T11 beta',
    P_c = -2 pi rho U b C Q,  M_a,c = 2 pi rho U b^2 (a + 1/2) C Q,  M_b,c = -rho U b^2 T12 C Q,

C being Theodorsen's function. In the time domain C acts as the convolution with Wagner's
function phi(s), s = U t / b, approximated by R. T. Jones (NACA Report 681, 1940) as
phi(s) = 1 - 0.165 exp(-0.0455 s) - 0.335 exp(-0.3 s). With two lag states x_i' =
-(U/b) eps_i x_i + Q the effective downwash is

    Q_eff = (1 - A1 - A2) Q + (U/b) (A1 eps1 x1 + A2 eps2 x2),  A = (0.165, 0.335),
    eps = (0.0455, 0.3),

whose transfer function Q_eff / Q = 1 - sum A_i i k / (i k + eps_i) is Jones' approximation of
C(k) (within about 1-2 % of the exact C(k) = H1(k) / (H1(k) + i H0(k)), Hankel functions of
the second kind). This is the model of Conner, Tang, Dowell & Virgin (J. Fluids Struct. 11,
1997, Sec. 2) and Edwards, Ashley & Breakwell (AIAA J. 17, 1979).

State x = [h, alpha, beta, h', alpha', beta', x1, x2] (8 states), x' = A x. The flap spring
K_b is the connection of :mod:`asekit.aeroelastic.nonlinear`: :func:`connected_system` returns
(A0 with K_b = 0, b, c) so the hinge spring can be freeplay.

With the exact C(k) the section is solved in the frequency domain two ways: the neutral point of
the flutter determinant by Newton iteration (:func:`flutter_speed_exact`) and the classical V-g
(k) method of Theodorsen & Garrick (:func:`flutter_vg`, :func:`vg_matrices`), which sweeps k and
needs no guess. :func:`theodorsen_garrick_section` builds the section from the nondimensional
parameters of NACA Reports 496, 685 and 741 (kappa, x, r^2, frequency ratios), and
:func:`lifting_surface_aero` replaces Theodorsen's strip by a doublet-lattice wing of finite
aspect ratio moving in the same three coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import hankel2

from asekit.aeroelastic.nonlinear import ConnectedSystem
from asekit.util.roots import first_crossing
from asekit.util.validate import in_range, integer, positive

JONES_A = (0.165, 0.335)
JONES_EPS = (0.0455, 0.3)
STATE_NAMES = ("h", "alpha", "beta", "h_dot", "alpha_dot", "beta_dot", "lag1", "lag2")


@dataclass(frozen=True)
class TypicalSection:
    """A pitch-plunge-flap section, per unit span, SI.

    semichord b (m); a, c : elastic axis and hinge from mid-chord in semichords (-1 < a < c < 1);
    heave_mass (kg/m) : mass moving in plunge; static_moment_alpha S_a, static_moment_beta S_b
    (kg m/m; S_a about the elastic axis, S_b about the hinge, positive when the centre of mass
    is aft); inertia_alpha I_a about the elastic axis, inertia_beta I_b about the hinge
    (kg m^2/m); stiffness_h (N/m/m), stiffness_alpha, stiffness_beta (N m/rad/m);
    damping ratios zeta_h, zeta_alpha, zeta_beta (uncoupled); density rho (kg/m^3).
    """

    semichord: float
    a: float
    c: float
    heave_mass: float
    static_moment_alpha: float
    static_moment_beta: float
    inertia_alpha: float
    inertia_beta: float
    stiffness_h: float
    stiffness_alpha: float
    stiffness_beta: float
    zeta_h: float = 0.0
    zeta_alpha: float = 0.0
    zeta_beta: float = 0.0
    density: float = 1.225

    def __post_init__(self):
        for n in ("semichord", "heave_mass", "inertia_alpha", "inertia_beta", "stiffness_h",
                  "stiffness_alpha", "density"):
            positive(n, getattr(self, n))
        in_range("stiffness_beta", self.stiffness_beta, 0.0, inclusive=True)
        in_range("a", self.a, -1.0, high=1.0, high_inclusive=False)
        in_range("c", self.c, self.a, high=1.0, high_inclusive=False)
        for n in ("zeta_h", "zeta_alpha", "zeta_beta"):
            in_range(n, getattr(self, n), 0.0, inclusive=True, high=1.0)

    def with_flap_stiffness(self, k_beta: float) -> "TypicalSection":
        return replace(self, stiffness_beta=float(k_beta))


def theodorsen_t(a: float, c: float) -> dict:
    """Theodorsen's geometric functions T1..T14 (NACA Report 496, 1935) for elastic axis a and
    hinge c (semichords from mid-chord)."""
    s = math.sqrt(1.0 - c * c)
    ac = math.acos(c)
    T = {}
    T[1] = -s * (2 + c * c) / 3 + c * ac
    T[2] = c * (1 - c * c) - s * (1 + c * c) * ac + c * ac * ac
    T[3] = -(1 / 8 + c * c) * ac * ac + c * s * ac * (7 + 2 * c * c) / 4 \
        - (1 - c * c) * (5 * c * c + 4) / 8
    T[4] = -ac + c * s
    T[5] = -(1 - c * c) - ac * ac + 2 * c * s * ac
    T[6] = T[2]
    T[7] = -(1 / 8 + c * c) * ac + c * s * (7 + 2 * c * c) / 8
    T[8] = -s * (2 * c * c + 1) / 3 + c * ac
    T[9] = 0.5 * (s ** 3 / 3 + a * T[4])
    T[10] = s + ac
    T[11] = ac * (1 - 2 * c) + s * (2 - c)
    T[12] = s * (2 + c) - ac * (2 * c + 1)
    T[13] = 0.5 * (-T[7] - (c - a) * T[1])
    T[14] = 1 / 16 + a * c / 2
    return T


def theodorsen_function(k):
    """Theodorsen's C(k) = H1(k) / (H1(k) + i H0(k)) (Hankel functions of the second kind),
    k = omega b / U > 0."""
    k = np.asarray(k, dtype=float)
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return h1 / (h1 + 1j * h0)


def jones_function(k):
    """R. T. Jones' approximation of C(k): 1 - sum A_i i k / (i k + eps_i)."""
    k = np.asarray(k, dtype=float)
    return 1.0 - sum(A * 1j * k / (1j * k + e) for A, e in zip(JONES_A, JONES_EPS))


@dataclass(frozen=True)
class SectionMatrices:
    """Structural M_s, D_s, K_s; non-circulatory aerodynamic M_nc, B_nc, K_nc (left-hand side);
    circulatory force vector f_c (per unit effective downwash Q, N/(m/s)), downwash rows w_q,
    w_qd (Q = w_q q + w_qd q'), all 3 x 3 / 3-vectors at airspeed U."""

    M_s: np.ndarray
    D_s: np.ndarray
    K_s: np.ndarray
    M_nc: np.ndarray
    B_nc: np.ndarray
    K_nc: np.ndarray
    f_c: np.ndarray
    w_q: np.ndarray
    w_qd: np.ndarray


def section_matrices(sec: TypicalSection, velocity: float) -> SectionMatrices:
    """The matrices of the module docstring at airspeed U = ``velocity`` (m/s, >= 0)."""
    U = in_range("velocity", velocity, 0.0, inclusive=True)
    b, a, c, rho = sec.semichord, sec.a, sec.c, sec.density
    T = theodorsen_t(a, c)
    pi = math.pi
    Sa, Sb, Ia, Ib = (sec.static_moment_alpha, sec.static_moment_beta, sec.inertia_alpha,
                      sec.inertia_beta)
    cab = Ib + b * (c - a) * Sb
    M_s = np.array([[sec.heave_mass, Sa, Sb], [Sa, Ia, cab], [Sb, cab, Ib]])
    K_s = np.diag([sec.stiffness_h, sec.stiffness_alpha, sec.stiffness_beta])
    zeta = np.array([sec.zeta_h, sec.zeta_alpha, sec.zeta_beta])
    D_s = np.diag(2 * zeta * np.sqrt(np.diag(K_s) * np.diag(M_s)))
    r = rho * b * b
    bb = b * b
    M_nc = r * np.array([[pi, -pi * b * a, -T[1] * b],
                         [-a * pi * b, pi * bb * (1 / 8 + a * a), -(T[7] + (c - a) * T[1]) * bb],
                         [-T[1] * b, 2 * T[13] * bb, -T[3] * bb / pi]])
    b_ab = (T[1] - T[8] - (c - a) * T[4] + 0.5 * T[11]) * b          # M_a per beta'
    b_ba = (-2 * T[9] - T[1] + T[4] * (a - 0.5)) * b                  # M_b per alpha'
    B_nc = r * U * np.array([[0.0, pi, -T[4]],
                             [0.0, pi * (0.5 - a) * b, b_ab],
                             [0.0, b_ba, -T[4] * T[11] * b / (2 * pi)]])
    K_nc = r * U * U * np.array([[0.0, 0.0, 0.0],
                                 [0.0, 0.0, T[4] + T[10]],
                                 [0.0, 0.0, (T[5] - T[4] * T[10]) / pi]])
    f_c = np.array([-2 * pi * rho * U * b, 2 * pi * rho * U * b * b * (a + 0.5),
                    -rho * U * b * b * T[12]])
    w_q = np.array([0.0, U, U * T[10] / pi])
    w_qd = np.array([1.0, b * (0.5 - a), b * T[11] / (2 * pi)])
    return SectionMatrices(M_s, D_s, K_s, M_nc, B_nc, K_nc, f_c, w_q, w_qd)


def state_matrix(sec: TypicalSection, velocity: float) -> np.ndarray:
    """The 8 x 8 aeroelastic state matrix (module docstring) at U = ``velocity`` (m/s > 0)."""
    U = positive("velocity", velocity)
    m = section_matrices(sec, U)
    b = sec.semichord
    Mt = m.M_s + m.M_nc
    Minv = np.linalg.inv(Mt)
    phi0 = 1.0 - sum(JONES_A)
    # forces on the right-hand side: -B q' - K q + f_c Q_eff
    # Q_eff = phi0 (w_q q + w_qd q') + (U/b) sum A_i eps_i x_i
    K_eff = m.K_s + m.K_nc - phi0 * np.outer(m.f_c, m.w_q)
    D_eff = m.D_s + m.B_nc - phi0 * np.outer(m.f_c, m.w_qd)
    lag_w = np.array([(U / b) * A * e for A, e in zip(JONES_A, JONES_EPS)])
    A = np.zeros((8, 8))
    A[0:3, 3:6] = np.eye(3)
    A[3:6, 0:3] = -Minv @ K_eff
    A[3:6, 3:6] = -Minv @ D_eff
    A[3:6, 6:8] = Minv @ np.outer(m.f_c, lag_w)
    for i, e in enumerate(JONES_EPS):
        A[6 + i, 0:3] = m.w_q
        A[6 + i, 3:6] = m.w_qd
        A[6 + i, 6 + i] = -(U / b) * e
    return A


def frequency_domain_matrix(sec: TypicalSection, velocity: float, omega: float,
                            theodorsen: str = "exact") -> np.ndarray:
    """The 3 x 3 flutter matrix -omega^2 (M_s + M_nc) + i omega (D_s + B_nc) + K_s + K_nc
    - f_c C(k) (w_q + i omega w_qd) at U, omega (rad/s), with the exact C(k) (``"exact"``) or
    Jones' approximation (``"jones"``)."""
    U = positive("velocity", velocity)
    m = section_matrices(sec, U)
    k = omega * sec.semichord / U
    Ck = theodorsen_function(k) if theodorsen == "exact" else jones_function(k)
    return (-omega ** 2 * (m.M_s + m.M_nc) + 1j * omega * (m.D_s + m.B_nc) + m.K_s + m.K_nc
            - Ck * np.outer(m.f_c, m.w_q + 1j * omega * m.w_qd))


def connected_system(sec: TypicalSection, velocity: float) -> ConnectedSystem:
    """The section at U with the flap spring as the connection (:mod:`asekit.aeroelastic.nonlinear`):
    A0 = the state matrix with K_b = 0 (the structural damping keeps its nominal value),
    b = -(M_s + M_nc)^-1 e_beta in the acceleration rows, d = beta. Outputs h, alpha, beta."""
    m = section_matrices(sec, velocity)
    Minv = np.linalg.inv(m.M_s + m.M_nc)
    bvec = np.zeros(8)
    bvec[3:6] = -Minv[:, 2]
    cvec = np.zeros(8)
    cvec[2] = 1.0
    # K_b enters the state matrix only as -Minv e_b K_b e_b^T: A = A0 + K_b b c^T exactly
    A0 = state_matrix(sec, velocity) - sec.stiffness_beta * np.outer(bvec, cvec)
    outs = {n: (np.eye(8)[i], np.zeros(0)) for i, n in enumerate(("h", "alpha", "beta"))}
    return ConnectedSystem(A0, bvec, cvec, outputs=outs, velocity=float(velocity),
                           state_names=STATE_NAMES)


def flutter_speed(sec: TypicalSection, u_lo: float, u_hi: float, n: int = 60):
    """(U_F (m/s), f_F (Hz)) of the linear section: the lowest airspeed in [u_lo, u_hi] at
    which a root of :func:`state_matrix` crosses into the right half-plane (scan of n speeds,
    then Brent; ``n`` an integer in [2, 1e6]); None if none in the range. Raises ValueError if
    it is unstable at u_lo."""
    u_lo, u_hi = positive("u_lo", u_lo), positive("u_hi", u_hi)
    if u_hi <= u_lo:
        raise ValueError(f"u_hi must exceed u_lo, got {u_lo}, {u_hi}")
    n = integer("n", n, low=2, high=1_000_000)

    def sig(u):
        ev = np.linalg.eigvals(state_matrix(sec, u))
        return float(np.max(ev.real))
    uf = first_crossing(sig, np.linspace(u_lo, u_hi, n), xtol=1e-8,
                        at_start=f"the section is already unstable at u_lo = {u_lo:g} m/s")
    if uf is None:
        return None
    ev = np.linalg.eigvals(state_matrix(sec, uf))
    j = np.argmax(ev.real)
    return float(uf), float(abs(ev[j].imag) / (2 * math.pi))


def flutter_speed_exact(sec: TypicalSection, u_guess: float, f_guess_hz: float,
                        theodorsen: str = "exact"):
    """(U_F, f_F) solving det(frequency_domain_matrix(U, omega)) = 0 for real U and omega
    (neutral stability with the exact C(k) or Jones' C(k)) by Newton iteration from a guess."""
    from scipy.optimize import fsolve

    def res(p):
        u, w = p
        dt = np.linalg.det(frequency_domain_matrix(sec, u, w, theodorsen))
        return [dt.real, dt.imag]
    scale = np.array([u_guess, 2 * math.pi * f_guess_hz])
    sol, info, ier, msg = fsolve(lambda z: res(z * scale), np.ones(2), full_output=True,
                                 xtol=1e-12)
    if ier != 1:
        raise RuntimeError(f"flutter determinant did not converge: {msg}")
    u, w = sol * scale
    return float(u), float(w / (2 * math.pi))


# ---------------------------------------------------------------------------------------------
# Theodorsen and Garrick's nondimensional section and the classical V-g (k) method
# ---------------------------------------------------------------------------------------------
def theodorsen_garrick_section(kappa: float, a: float, c: float, x_alpha: float, x_beta: float,
                               r_alpha_sq: float, r_beta_sq: float, omega_h: float,
                               omega_alpha: float, omega_beta: float, semichord: float = 1.0,
                               density: float = 1.225) -> TypicalSection:
    """The section in Theodorsen's nondimensional parameters (NACA Report 496, 1935, p. 8-9;
    Theodorsen & Garrick, NACA Report 685, 1940, and Report 741, 1942, the same symbols).

    Parameters
    ----------
    kappa : float
        Mass ratio kappa = pi rho b^2 / M (> 0; 1 / kappa is the mass ratio mu of later texts),
        M the mass per unit span (moving in plunge, pitch and flap alike).
    a, c : float
        Elastic axis and hinge, semichords from mid-chord (-1 < a < c < 1).
    x_alpha, x_beta : float
        Static unbalances S_alpha / (M b) about the elastic axis and S_beta / (M b) about the
        hinge (positive when the centre of mass is aft).
    r_alpha_sq, r_beta_sq : float
        Squared radii of gyration I_alpha / (M b^2) (about the elastic axis) and
        I_beta / (M b^2) (about the hinge), > 0.
    omega_h, omega_alpha, omega_beta : float
        Uncoupled frequencies (rad/s): omega_h^2 = C_h / M, omega_alpha^2 = C_alpha / I_alpha,
        omega_beta^2 = C_beta / I_beta (omega_beta = 0: a free flap).
    semichord, density : float
        b (m) and rho (kg/m^3) that make the section dimensional; results in U / (b omega_alpha)
        and omega / omega_alpha depend only on the nondimensional set.

    Returns
    -------
    TypicalSection
        M = pi rho b^2 / kappa, S_alpha = M x_alpha b, S_beta = M x_beta b, I_alpha =
        M r_alpha^2 b^2, I_beta = M r_beta^2 b^2, K_h = M omega_h^2, K_alpha = I_alpha
        omega_alpha^2, K_beta = I_beta omega_beta^2; no viscous damping.

    Examples
    --------
    >>> s = theodorsen_garrick_section(0.25, -0.4, 0.6, 0.2, 0.0, 0.25, 0.0012, 0.25, 1.0, 0.5)
    >>> round(s.heave_mass * 0.25 / (math.pi * 1.225), 12), round(s.stiffness_alpha / s.inertia_alpha, 12)
    (1.0, 1.0)
    """
    kappa, b, rho = (positive(n, v) for n, v in (("kappa", kappa), ("semichord", semichord),
                                                  ("density", density)))
    for n, v in (("r_alpha_sq", r_alpha_sq), ("r_beta_sq", r_beta_sq),
                 ("omega_h", omega_h), ("omega_alpha", omega_alpha)):
        positive(n, v)
    in_range("omega_beta", omega_beta, 0.0, inclusive=True)
    m = math.pi * rho * b * b / kappa
    i_a, i_b = m * r_alpha_sq * b * b, m * r_beta_sq * b * b
    return TypicalSection(semichord=b, a=float(a), c=float(c), heave_mass=m,
                          static_moment_alpha=m * float(x_alpha) * b,
                          static_moment_beta=m * float(x_beta) * b,
                          inertia_alpha=i_a, inertia_beta=i_b,
                          stiffness_h=m * omega_h ** 2, stiffness_alpha=i_a * omega_alpha ** 2,
                          stiffness_beta=i_b * float(omega_beta) ** 2, density=rho)


def vg_matrices(sec: TypicalSection, k: float, aero=None):
    """(K_s, M_s + A(k)) of the harmonic flutter equation in the k-method form
    [K_s (1 + i g) - omega^2 (M_s + A(k))] q = 0 (Theodorsen 1935, Eq. for the "flutter
    determinant"; Smilg & Wasserman, AAF TR 4798, 1942; Bisplinghoff, Ashley & Halfman 1955,
    Sec. 9-4), at reduced frequency k = omega b / U > 0.

    With the hat quantities of :func:`section_matrices` per unit airspeed (B_nc = U B^,
    K_nc = U^2 K^, f_c = U f^, w_q = U w^) and U = omega b / k, every aerodynamic term of
    :func:`frequency_domain_matrix` is -omega^2 times

        A(k) = M_nc - i (b/k) B^ - (b/k)^2 K^ + C(k) (b/k) f^ [(b/k) w^ + i w_qd]^T,

    C(k) Theodorsen's exact function. The structural viscous damping D_s is left out (the
    method's g is the structural damping a mode needs to be neutrally stable).

    ``aero``, when given, replaces A(k): a callable k -> (3, 3) complex matrix per unit span in
    the same form and coordinates [h, alpha, beta] (e.g. a lifting-surface GAF, 1/2 rho (b/k)^2
    Q(k) / span, :func:`lifting_surface_aero`).
    """
    k = positive("k", k)
    m = section_matrices(sec, 1.0)
    if aero is not None:
        A = np.asarray(aero(k), dtype=complex)
        if A.shape != (3, 3) or not np.all(np.isfinite(A)):
            raise ValueError(f"aero(k) must return a finite (3, 3) matrix, got shape {A.shape}")
        return m.K_s, m.M_s + A
    r = sec.semichord / k
    Ck = complex(theodorsen_function(k))
    A = (m.M_nc - 1j * r * m.B_nc - r * r * m.K_nc
         + Ck * r * np.outer(m.f_c, r * m.w_q + 1j * m.w_qd))
    return m.K_s, m.M_s + A


def _vg_roots(sec: TypicalSection, k: float, aero=None) -> np.ndarray:
    """lambda = (1 + i g) / omega^2 of the k-method eigenproblem (M_s + A) q = lambda K_s q:
    the finite roots (a zero flap stiffness makes one infinite: dropped)."""
    from scipy.linalg import eigvals
    K, Mt = vg_matrices(sec, k, aero)
    lam = eigvals(Mt, K)
    return lam[np.isfinite(lam)]


def _match(prev: np.ndarray, new: np.ndarray) -> np.ndarray:
    """``new`` reordered to follow the branches of ``prev`` (least relative change)."""
    from itertools import permutations
    best = min(permutations(range(len(new))),
               key=lambda p: float(np.sum(np.abs(new[list(p)] - prev) / np.abs(prev))))
    return new[list(best)]


def _vg_mode(sec, k, aero, u, f_hz):
    """The eigenvector of the k-method root nearest (1 + 0 i) / omega_F^2 at k, [h / b, alpha,
    beta], largest component 1."""
    from scipy.linalg import eig
    K, Mt = vg_matrices(sec, k, aero)
    lam, vec = eig(Mt, K)
    lam = np.where(np.isfinite(lam), lam, np.inf)
    v = vec[:, int(np.argmin(np.abs(lam - 1.0 / (2 * math.pi * f_hz) ** 2)))].copy()
    v[0] /= sec.semichord
    return v / v[int(np.argmax(np.abs(v)))]


@dataclass(frozen=True)
class VgResult:
    """A V-g (k-method) sweep: ``k`` (n_k,) the reduced frequencies in the order swept
    (descending, airspeed rising), and per branch (n_k, n_branches) the airspeed ``velocity``
    (m/s), ``frequency_hz`` and the required structural damping ``damping`` g; ``flutter``
    (U_F m/s, f_F Hz, k_F, branch) at the lowest airspeed where a branch's g rises through
    zero, or None; ``flutter_mode`` (3,) complex, the flutter eigenvector in [h / b, alpha,
    beta] scaled so that its largest component is 1 (None without flutter)."""

    k: np.ndarray
    velocity: np.ndarray
    frequency_hz: np.ndarray
    damping: np.ndarray
    flutter: tuple | None
    flutter_mode: np.ndarray | None = None


def _vg_branch_g(sec, k, lam_ref, branch, aero=None):
    lam = _match(lam_ref, _vg_roots(sec, k, aero))[branch]
    return lam.imag / lam.real, lam


def flutter_vg(sec: TypicalSection, k_values, aero=None) -> VgResult:
    """The classical V-g (k) method for the section with the exact Theodorsen aerodynamics.

    For each reduced frequency k the eigenvalues lambda = (1 + i g) / omega^2 of
    (M_s + A(k)) q = lambda K_s q (:func:`vg_matrices`) give per branch omega = 1 / sqrt(Re
    lambda), g = Im lambda / Re lambda and U = omega b / k (Theodorsen & Garrick, NACA Report
    685, 1940, solve the same determinant for the real and imaginary parts, their X = (omega_a /
    omega)^2 (1 + i g)). Branches are followed from k to k by least change of lambda; the
    flutter point, where a branch's g rises through zero with falling k, is refined by Brent's
    method on that branch's g(k). An independent route to the neutral point of
    :func:`flutter_speed_exact` (which solves det = 0 by Newton iteration from a guess).

    Parameters
    ----------
    sec : TypicalSection
    k_values : array_like
        Reduced frequencies (> 0), at least 2, fine enough to follow the branches; sorted
        descending here. The highest must lie above the flutter k (refused otherwise: a
        branch with g > 0 there is flutter below the sweep).
    aero : callable, optional
        k -> A(k) (3, 3) per unit span replacing Theodorsen's (:func:`vg_matrices`).

    Returns
    -------
    VgResult

    Examples
    --------
    >>> s = theodorsen_garrick_section(0.1, -0.4, 0.6, 0.2, 0.0, 0.25, 0.0012, 0.5, 1.0, 2.0)
    >>> r = flutter_vg(s, np.geomspace(2.0, 0.05, 200))
    >>> uf, ff, kf, br = r.flutter
    >>> abs(flutter_speed_exact(s, uf, ff)[0] / uf - 1) < 1e-6
    True
    """
    from scipy.optimize import brentq
    ks = np.sort(np.asarray(k_values, dtype=float).ravel())[::-1]
    if ks.size < 2 or not np.all(np.isfinite(ks)) or ks[-1] <= 0:
        raise ValueError("k_values must hold at least 2 finite reduced frequencies > 0")
    lams = [_vg_roots(sec, ks[0], aero)]
    lams[0] = lams[0][np.argsort(lams[0].real)]
    for k in ks[1:]:
        lams.append(_match(lams[-1], _vg_roots(sec, k, aero)))
    lam = np.array(lams)
    with np.errstate(invalid="ignore"):
        omega = 1.0 / np.sqrt(lam.real)              # NaN where Re lambda <= 0 (no real omega)
    g = lam.imag / lam.real
    if np.any((lam[0].real > 0) & (g[0] > 0)):
        raise ValueError(f"k_values: a branch already needs g > 0 at the highest k = {ks[0]:g} "
                         "(flutter below the swept airspeeds); extend k_values upward")
    U = omega * sec.semichord / ks[:, None]
    best = None
    for j in range(lam.shape[1]):
        ok = (lam[:-1, j].real > 0) & (lam[1:, j].real > 0)
        for i in np.nonzero(ok & (g[:-1, j] < 0) & (g[1:, j] >= 0))[0]:
            kf = brentq(lambda kk: _vg_branch_g(sec, kk, lam[i], j, aero)[0], ks[i + 1],
                        ks[i], xtol=1e-12)
            w = 1.0 / math.sqrt(_vg_branch_g(sec, kf, lam[i], j, aero)[1].real)
            cand = (w * sec.semichord / kf, w / (2 * math.pi), float(kf), j)
            if best is None or cand[0] < best[0]:
                best = cand
    return VgResult(ks, U, omega / (2 * math.pi), g, best,
                    None if best is None else _vg_mode(sec, best[2], aero, best[0], best[1]))


def lifting_surface_aero(sec: TypicalSection, aspect_ratio: float, n_span: int, n_chord: int,
                         k_values, mach: float = 0.0):
    """A(k) per unit span of a rectangular wing of the section's chord and the given aspect ratio
    moving rigidly in the section's three coordinates (plunge, pitch about the elastic axis,
    a full-span flap about the hinge), by the doublet lattice: the 3-D counterpart of
    Theodorsen's A(k) in :func:`vg_matrices`, for the wing "approaching the typical section as
    the aspect ratio grows" (Theodorsen & Garrick's strip assumption).

    The half wing (span s = AR c / 2, the image across the root: a wing of span AR c) is cut
    along the hinge (:func:`asekit.aero.control_surface.hinged_mesh`); the box modes are, in
    the lattice's +z-up displacement, plunge h = -1, pitch h = -(x - x_ea), dh/dx = -1 and the
    flap's :func:`asekit.aero.control_surface.deflection_modes` (flap rotation relative to the
    wing, as Theodorsen's beta). The generalised forces Q(k) per dynamic pressure
    (:func:`asekit.aero.gaf.gaf_from_box_modes`, reference semichord b) on ``k_values`` are
    splined (cubic, in k) and returned as the callable

        A(k) = 1/2 rho (b / k)^2 Q(k) / s,

    so that [K_s (1 + i g) - omega^2 (M_s + A(k))] q = 0 is the wing's flutter equation per unit
    span with the section's structure (the q Q(k) force of :mod:`asekit.aeroelastic.flutter`
    written at U = omega b / k).

    Parameters
    ----------
    sec : TypicalSection
    aspect_ratio : float
        Span over chord of the whole wing (> 0).
    n_span, n_chord : int
        Boxes along the half span and along the chord (the flap gets the nearest share).
    k_values : array_like
        At least 4 increasing reduced frequencies (> 0) of the GAF table; A(k) is refused
        outside it.
    mach : float
        Mach number (below 1: the doublet lattice).

    Returns
    -------
    callable
        k -> (3, 3) complex A(k) for :func:`flutter_vg`'s ``aero``.

    Examples
    --------
    >>> s = theodorsen_garrick_section(0.1, -0.4, 0.6, 0.2, 0.0, 0.25, 0.0012, 0.5, 1.0, 2.0)
    >>> A = lifting_surface_aero(s, 6.0, 6, 5, [0.3, 0.4, 0.5, 0.6])
    >>> A2 = vg_matrices(s, 0.45)[1] - section_matrices(s, 1.0).M_s
    >>> bool(0.7 < abs(A(0.45)[0, 0] / A2[0, 0]) < 1.0)      # the finite wing lifts less
    True
    """
    from scipy.interpolate import CubicSpline

    from asekit.aero.boxes import TrapezoidSurface
    from asekit.aero.control_surface import ControlSurface, deflection_modes, hinged_mesh
    from asekit.aero.gaf import gaf_from_box_modes
    from asekit.aero.spline import BoxModes

    ar = positive("aspect_ratio", aspect_ratio)
    ks = np.asarray(k_values, dtype=float).ravel()
    if ks.size < 4 or not np.all(np.isfinite(ks)) or ks[0] <= 0 or np.any(np.diff(ks) <= 0):
        raise ValueError("k_values must hold at least 4 increasing reduced frequencies > 0")
    b, rho = sec.semichord, sec.density
    half_span = 0.5 * ar * 2 * b
    panel = TrapezoidSurface((0, 0), 2 * b, (0, half_span), 2 * b, n_chord, n_span)
    hinge = 0.5 * (1 + sec.c)
    hm = hinged_mesh(panel, ControlSurface("flap", hinge, hinge))
    mesh, flap = hm.mesh, deflection_modes(hm)
    x_ea = b * (1 + sec.a)
    one = np.ones(mesh.n)
    modes = BoxModes(np.column_stack([-one, -(mesh.control_point[:, 0] - x_ea), flap.h_cp[:, 0]]),
                     np.column_stack([0 * one, -one, flap.dhdx_cp[:, 0]]),
                     np.column_stack([-one, -(mesh.load_point[:, 0] - x_ea), flap.h_lp[:, 0]]))
    spline = CubicSpline(ks, gaf_from_box_modes(modes, mesh, mach, ks, b, symmetric=True), axis=0)

    def aero(k):
        if not ks[0] <= k <= ks[-1]:
            raise ValueError(f"k = {k:g} outside the GAF table [{ks[0]:g}, {ks[-1]:g}]")
        return 0.5 * rho * (b / k) ** 2 * spline(k) / half_span
    return aero


# ---------------------------------------------------------------------------------------------
# the published case
# ---------------------------------------------------------------------------------------------
#: Span of the Duke wind-tunnel model (m; Conner et al. 1997, Table A.1). Informational only: the
#: parameters of :func:`conner_1997` are per unit span as published and are not divided by it.
CONNER_SPAN = 0.52

#: Conner et al. (1997) freeplay "Gap 3" (Sec. 11.2, p. 101: freeplay regions of +-1.15, +-1.83 and
#: +-2.12 deg), the case of Tang, Dowell & Virgin (1998, Sec. 4.2: "a nominal angular gap of 4.24
#: deg, i.e. delta = +-2.12 deg"): the flap moves freely from -2.12 to +2.12 deg, a half-width of
#: 2.12 deg.
CONNER_FREEPLAY_HALF_WIDTH_DEG = 2.12


def conner_1997(heave_mass: float = 3.39298, wing_mass: float = 1.5666) -> TypicalSection:
    """The typical section of Conner, Tang, Dowell & Virgin, "Nonlinear behavior of a typical
    airfoil section with control surface freeplay: a numerical and experimental study",
    J. Fluids Struct. 11 (1997) 89-109, Appendix A, Table A.1 (p. 108), per unit span.

    Values (per unit span, SI): semichord b = 0.127 m (chord 0.254 m, span 0.52 m), elastic
    axis a = -0.5, hinge c = 0.5; S_alpha = 0.08587 kg m/m, S_beta = 0.00395 kg m/m,
    I_alpha = 0.01347 kg m^2/m, I_beta = 0.0003264 kg m^2/m; damping ratios zeta_alpha =
    0.01626, zeta_beta = 0.0115, zeta_h = 0.0113 (log-decrement); rho = 1.225 kg/m^3.

    Masses: Table A.1 lists the wing 0.62868 kg, the aileron 0.18597 kg and the support blocks
    2 x 0.47485 kg (the two blocks move only in plunge, Sec. 7), so the plunging mass per span is
    m_T = (0.62868 + 0.18597 + 2 x 0.47485) / 0.52 = 3.39298 kg/m (``heave_mass``) and the
    wing-aileron mass is (0.62868 + 0.18597) / 0.52 = 1.5666 kg/m (``wing_mass``); the table's
    "mass/length of wing-aileron" M = 1.558 kg/m is the one its nondimensional values use.

    Stiffnesses: Table A.1 gives them reduced as in Theodorsen (1935): K_alpha = C_alpha / (M b^2)
    = 1486 1/s^2, K_beta = C_beta / (M b^2) = 155 1/s^2, K_h = C_h / M = 1809 1/s^2 (M = 1.558);
    the dimensional values used here, C_alpha = 37.34 N m/rad/m, C_beta = 3.9 N m/rad/m,
    C_h = 2818.8 N/m/m, are those of Tang, Dowell & Virgin, J. Fluids Struct. 12 (1998) 839-858,
    Table 1 (p. 841: 37.3, 3.9 and 2818.8 "per span"), and reproduce Table A.1's reduced values
    to its three to four digits (tests). Nondimensional set of Table A.1: x_alpha = 0.434,
    x_beta = 0.01996, r_alpha = 0.7321, r_beta = 0.11397, kappa = pi rho b^2 / M = 0.03984.

    Checks against the paper (tests/aeroelastic/test_typical_section.py): the in-vacuo coupled natural
    frequencies 4.444, 9.209, 19.442 Hz against Conner et al. Table 1 (p. 98, "numerical")
    4.455, 9.218, 19.442 Hz (Tang et al. 1998 Table 1: 4.45, 9.21, 19.44 Hz), which also
    confirms that m_T (not M) moves in plunge (with M the plunge frequency would be 5.8 Hz);
    linear flutter 24.03 m/s, 6.10 Hz with Jones' C(k) against Table 1's 23.9 m/s, 6.112 Hz.

    Differences from the paper's model: Conner et al. (Sec. 3, Eq. 6) treat the measured
    damping ratios as *modal* ratios of the coupled in-vacuo modes and transform that damping
    back to [alpha, beta, h] (a full matrix); here the damping is uncoupled,
    diag(2 zeta_i sqrt(K_i M_s,ii)). The flutter speed moves by 0.1 % between the two (tests).
    Freeplay: Conner et al. test +-1.15, +-1.83 and +-2.12 deg (Gaps 1-3, Sec. 11.2, p. 101);
    Tang et al. (1998, Sec. 4.2) use delta = +-2.12 deg, a 4.24 deg total gap
    (:data:`CONNER_FREEPLAY_HALF_WIDTH_DEG` is the half-width).

    ``heave_mass`` (kg/m): the plunging mass, default m_T; ``wing_mass`` is informational (the
    nondimensional form of the equations uses M for mu, x_alpha, r_alpha; here the dimensional
    S and I are used directly).
    """
    positive("wing_mass", wing_mass)
    return TypicalSection(semichord=0.127, a=-0.5, c=0.5,
                          heave_mass=positive("heave_mass", heave_mass),
                          static_moment_alpha=0.08587, static_moment_beta=0.00395,
                          inertia_alpha=0.01347, inertia_beta=0.0003264,
                          stiffness_h=2818.8, stiffness_alpha=37.34, stiffness_beta=3.9,
                          zeta_h=0.0113, zeta_alpha=0.01626, zeta_beta=0.0115, density=1.225)


__all__ = ["TypicalSection", "theodorsen_t", "theodorsen_function", "jones_function",
           "section_matrices", "state_matrix", "frequency_domain_matrix", "connected_system",
           "flutter_speed", "flutter_speed_exact", "conner_1997", "CONNER_SPAN",
           "CONNER_FREEPLAY_HALF_WIDTH_DEG", "theodorsen_garrick_section", "vg_matrices",
           "VgResult", "flutter_vg", "lifting_surface_aero"]
