"""MSC Nastran's four flutter methods -- K, KE, PK and PKNL -- with Nastran's definitions of
damping and frequency, beside asekit's own p-k (:func:`asekit.aeroelastic.flutter.pk_flutter`,
the default ``"pk"`` of :data:`asekit.aeroelastic.methods.FLUTTER_METHODS`).

Source: MSC Nastran Aeroelastic Analysis User's Guide (Rodden and Johnson, 1994), Section 2.6
"Flutter solution techniques" (Eqs. 2-117 to 2-130 of the 2004 edition); the FLUTTER and
FLFACT cards of the Quick Reference Guide. Notation: M, B, K the modal mass, viscous damping
and stiffness, Q(m, k) = Q^R + i Q^I the generalised aerodynamic forces per unit dynamic
pressure, b = c_bar / 2 the reference semichord, k = omega b / V the reduced frequency,
rho the density and q = rho V^2 / 2.

* **K method** (Theodorsen's "American" method, Eq. 2-120): harmonic motion is imposed and an
  artificial structural damping g makes it possible at every k,

      [ -omega^2 M + (1 + i g) K - q Q(k) ] u = 0,   V = omega b / k.

  Dividing by -omega^2 with q = rho omega^2 b^2 / (2 k^2) gives the linear eigenproblem

      [ M + rho b^2 / (2 k^2) Q(k) ] u = lambda K u,   lambda = (1 + i g) / omega^2,

  so omega = 1 / sqrt(Re lambda), g = Im lambda / Re lambda, V = omega b / k. asekit's modal
  viscous damping B enters as the equivalent structural damping of each mode at its natural
  frequency, K -> K + i diag(B_jj omega_j) (Nastran's PARAM KDAMP = -1 form), so flutter is
  where the required g crosses 0. A root with Re lambda <= 0 has no physical interpretation
  (Nastran's user information message): its frequency, velocity and damping are NaN.
  **KE** is the same eigenproblem solved for eigenvalues only (no eigenvectors): its roots are
  sorted by continuity of lambda from one k to the next, K's by eigenvector correlation (MAC).
* **PK method** (Eq. 2-124):

      [ M p^2 + (B - rho b V Q^I(k) / (2 k)) p + (K - q Q^R(k)) ] u = 0,   p = omega (gamma + i),

  solved as a 2n x 2n real eigenproblem at fixed (V, k), and for each mode the k of the
  aerodynamic matrix is iterated, k <- |Im p| b / V, until ``|k_new - k_old| < EPS max(1, k)``
  (EPS the FLUTTER card's field 9, default 1e-3). Damping g = 2 gamma = 2 Re p / |Im p|
  (the transient decay rate coefficient gamma; real roots clipped to +-2 as asekit does),
  frequency |Im p| / 2 pi. Each velocity is solved from the converged k of the same mode at
  the previous velocity (the first from its structural frequency, mode j taking the j-th root
  in frequency order as Nastran does, real roots one slot); later, the root is the one whose
  eigenvector correlates best with the mode's previous vector and whose k is nearest, never a
  root an earlier mode of the same point has taken (Nastran sorts by frequency; asekit by
  MAC, which gives the same curves when the frequencies do not cross).
* **PKNL** (PK "without looping"): the FLFACT density, Mach and velocity lists have equal
  lengths and index i is one flight point (rho_i, M_i, V_i); no density x Mach x velocity
  loop. The crossing is interpolated linearly in g between consecutive points (index order)
  and ``unstable_at_first_point`` flags a root already unstable at point 1.

The flutter point of every method is where its g crosses 0 (interpolated linearly in V, as one
reads a Nastran V-g table). K and PK agree there (g = 0 is harmonic motion in both); away from
it they answer different questions (docs/nastran-flutter.md derives the difference).

asekit's own ``"pk"`` solves the same PK equation (Eq. 3.12 of the thesis is Eq. 2-124 above)
with continuation in V, sub-steps and a Brent-refined crossing; this module is the plain
Nastran algorithm, so that V-g tables compare with an f06 point for point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg
from scipy.optimize import linear_sum_assignment

from asekit.aero.gaf import TabulatedGaf
from asekit.aeroelastic.statespace import ModalArrays, modal_arrays
from asekit.util.conventions import mode_label, vg_damping
from asekit.util.validate import positive, positive_array

#: Nastran's default EPS of the FLUTTER card (convergence of k in PK and PKNL).
DEFAULT_EPS = 1e-3
#: largest number of k iterations per mode and velocity.
MAX_K_ITER = 60
#: the Nastran method names this module implements.
NASTRAN_METHODS = ("K", "KE", "PK", "PKNL")


@dataclass(frozen=True)
class NastranFlutterResult:
    """One FLUTTER card's solution: ``n_pt`` points (K/KE: reduced frequencies; PK: velocities;
    PKNL: matched (density, Mach, velocity) points) x ``n_m`` tracked modes.

    Attributes
    ----------
    method : "K", "KE", "PK" or "PKNL".
    velocity : (n_pt, n_m) V (m/s or the input's unit); the same in every column for PK/PKNL.
    damping_g : (n_pt, n_m) Nastran's damping (K: the required structural damping g; PK:
        g = 2 gamma), > 0 unstable; NaN for a K root without physical interpretation.
    frequency_hz : (n_pt, n_m) omega / 2 pi (Hz).
    k : (n_pt, n_m) reduced frequency omega b / V.
    eigenvalue : (n_pt, n_m) complex: K/KE lambda = (1 + i g) / omega^2 (s^2); PK/PKNL p (1/s).
    vectors : (n_pt, n_m, n) modal eigenvectors, or None (KE).
    converged : (n_pt, n_m) bool (PK: k iteration met EPS; K: a physical root).
    density, mach : (n_pt,) of each point.
    b_ref : reference semichord; modes : (n_m,) index of each column's structural mode;
    print_vectors : (n_pt,) bool, the points whose eigenvectors Nastran prints (negative
    FLFACT velocities).
    """

    method: str
    velocity: np.ndarray
    damping_g: np.ndarray
    frequency_hz: np.ndarray
    k: np.ndarray
    eigenvalue: np.ndarray
    vectors: np.ndarray | None
    converged: np.ndarray
    density: np.ndarray
    mach: np.ndarray
    b_ref: float
    modes: np.ndarray
    n_rigid: int = 0
    print_vectors: np.ndarray | None = None

    @property
    def mode_labels(self) -> list[str]:
        """'mode 1', 'mode 2', ... of the columns (docs/conventions.md)."""
        return [mode_label(int(j), self.n_rigid) for j in self.modes]


@dataclass(frozen=True)
class NastranCrossing:
    """A g = 0 crossing of one mode (or a root unstable at the first point): ``speed``,
    ``frequency_hz``, ``density``, ``mach`` interpolated linearly in g between points
    ``index - 1`` and ``index``; ``unstable_at_first_point``: g > 0 already at point 1
    (then the values are those of point 1, an upper bound on the onset); ``mode`` the
    structural mode index (0-based); ``kind`` 'flutter' or 'divergence' (a real root)."""

    method: str
    mode: int
    speed: float
    frequency_hz: float
    density: float
    mach: float
    index: int
    unstable_at_first_point: bool
    kind: str = "flutter"
    n_rigid: int = 0

    @property
    def mode_name(self) -> str:
        return mode_label(self.mode, self.n_rigid)


# ---------------------------------------------------------------------------------------------
# shared pieces
# ---------------------------------------------------------------------------------------------
def mac_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Modal assurance criterion of every column of A against every column of B (vectorised):
    MAC_ij = |a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j)).

    Examples
    --------
    >>> mac_matrix(np.eye(2), np.array([[1.0, 1.0], [0.0, 1.0]])).round(2).tolist()
    [[1.0, 0.5], [0.0, 0.5]]
    """
    num = np.abs(A.conj().T @ B) ** 2
    na = np.real(np.sum(A.conj() * A, axis=0))
    nb = np.real(np.sum(B.conj() * B, axis=0))
    return num / (np.outer(na, nb) + 1e-300)


def _assign(score: np.ndarray) -> np.ndarray:
    """Column of ``score`` (rows: tracked modes, columns: candidate roots) given to each row,
    maximising the total score (Hungarian algorithm), so no two rows share a root."""
    rows, cols = linear_sum_assignment(-score)
    out = np.empty(score.shape[0], int)
    out[rows] = cols
    return out


def _modal(modal) -> ModalArrays:
    return modal if isinstance(modal, ModalArrays) else modal_arrays(modal)


def _structural_omegas(m: ModalArrays) -> np.ndarray:
    w2 = linalg.eigvals(m.K, m.M).real
    return np.sqrt(np.clip(np.sort(w2), 0.0, None))


def _gaf_at(gaf: TabulatedGaf, k: float, interpolation: str):
    """(Q^R, Q^I / k) at k, Nastran's IMETH: 'L' linear, 'S' (asekit: a cubic spline in k)."""
    return gaf.parts(k, "linear" if interpolation.upper() in ("L", "LINEAR") else "cubic")


def _check_interp(interpolation: str) -> str:
    if not isinstance(interpolation, str) or interpolation.upper() not in (
            "L", "S", "LINEAR", "CUBIC"):
        raise ValueError(f"interpolation (FLUTTER IMETH) must be 'L' or 'S', got "
                         f"{interpolation!r}")
    return interpolation


# ---------------------------------------------------------------------------------------------
# K and KE
# ---------------------------------------------------------------------------------------------
def _complex_stiffness(m: ModalArrays) -> np.ndarray:
    """K + i diag(B_jj omega_j): modal viscous damping as the equivalent structural damping
    g_j = B_jj omega_j / K_jj at each mode's frequency (Nastran's KDAMP = -1 form)."""
    omega = np.sqrt(np.clip(np.diag(m.K) / np.diag(m.M), 0.0, None))
    return m.K + 1j * np.diag(np.diag(m.C) * omega)


def _k_roots(m: ModalArrays, Kc, gaf, rho, k, interpolation, vectors: bool):
    qr, qik = _gaf_at(gaf, k, interpolation)
    A = m.M + rho * gaf.b_ref ** 2 / (2 * k ** 2) * (qr + 1j * k * qik)
    if vectors:
        lam, vec = linalg.eig(A, Kc)
        return lam, vec
    return linalg.eigvals(A, Kc), None


def _k_order(lam, vec, prev_lam, prev_vec):
    """The order of the roots that continues the previous point's modes: by the relative
    distance of lambda (KE), less the MAC of the eigenvectors (K: near a coalescence two
    vectors correlate alike and lambda decides)."""
    d = np.abs(prev_lam[:, None] - lam[None, :]) / np.maximum(np.abs(prev_lam)[:, None], 1e-300)
    if vec is not None:
        return _assign(mac_matrix(prev_vec, vec) - d)
    return _assign(-d)


def k_method(modal, gaf: TabulatedGaf, density: float, ks, vectors: bool = True,
             interpolation: str = "L", mach: float | None = None) -> NastranFlutterResult:
    """Nastran's K method (``vectors=True``) or KE (``vectors=False``) at the reduced
    frequencies ``ks``.

    Solves [M + rho b^2 / (2 k^2) Q(k)] u = lambda (K + i G_s) u (MSC Aeroelastic User's Guide
    Eq. 2-120 divided by -omega^2), lambda = (1 + i g) / omega^2: omega = 1 / sqrt(Re lambda),
    g = Im lambda / Re lambda, V = omega b / k.

    Parameters
    ----------
    modal : ModalArrays (or an object with M, K, C): modal mass, stiffness, viscous damping.
    gaf : TabulatedGaf, Q(k) per unit dynamic pressure at one Mach (b_ref its semichord).
    density : float (kg/m^3, or the consistent unit of the model).
    ks : reduced frequencies > 0 (FLFACT of FLUTTER RFREQ), solved from the largest down
        (increasing V) and returned in that order.
    vectors : False for KE (eigenvalues only, roots continued by lambda).
    interpolation : 'L' (linear in k, Nastran's IMETH default) or 'S' (a cubic spline).
    mach : the Mach number of ``gaf`` (recorded).

    Returns
    -------
    NastranFlutterResult
        method "K" or "KE"; columns the structural modes (assigned at the largest k).

    Examples
    --------
    One undamped mode, no aerodynamics: lambda = 1/omega^2 at every k, g = 0.

    >>> g = TabulatedGaf(np.array([0.1, 1.0]), np.zeros((2, 1, 1), complex), 1.0)
    >>> r = k_method(modal_arrays(M=[[1.0]], K=[[100.0]]), g, 1.0, [0.5, 0.2])
    >>> r.frequency_hz[:, 0].round(4).tolist(), r.velocity[:, 0].tolist(), float(r.damping_g[0, 0])
    ([1.5915, 1.5915], [20.0, 50.0], 0.0)
    """
    m = _modal(modal)
    rho = positive("density", density)
    ks = np.sort(positive_array("ks (FLFACT of FLUTTER RFREQ)", ks))[::-1]
    _check_interp(interpolation)
    Kc = _complex_stiffness(m)
    n, n_k = m.n_modes, ks.size
    lam_t = np.empty((n_k, n), complex)
    vec_t = np.empty((n_k, n, n), complex) if vectors else None
    prev_lam = 1.0 / np.where(_structural_omegas(m) > 0, _structural_omegas(m), 1e-300) ** 2
    prev_vec = np.eye(n, dtype=complex)
    for i, k in enumerate(ks):
        lam, vec = _k_roots(m, Kc, gaf, rho, k, interpolation, vectors)
        order = _k_order(lam, vec, prev_lam, prev_vec if vectors else None)
        lam_t[i] = prev_lam = lam[order]
        if vectors:
            vec_t[i] = prev_vec = vec[:, order].T
    return _k_result(m, lam_t, vec_t, ks, rho, gaf.b_ref, mach, vectors)


def _k_result(m, lam, vec, ks, rho, b, mach, vectors) -> NastranFlutterResult:
    physical = lam.real > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        omega = np.where(physical, 1.0 / np.sqrt(np.where(physical, lam.real, 1.0)), np.nan)
        g = np.where(physical, lam.imag / lam.real, np.nan)
    kk = np.broadcast_to(ks[:, None], lam.shape).copy()
    n_pt = ks.size
    return NastranFlutterResult(
        method="K" if vectors else "KE", velocity=omega * b / kk, damping_g=g,
        frequency_hz=omega / (2 * np.pi), k=kk, eigenvalue=lam, vectors=vec,
        converged=physical, density=np.full(n_pt, rho), mach=np.full(n_pt, np.nan if mach is
                                                                      None else mach),
        b_ref=b, modes=np.arange(m.n_modes), n_rigid=m.n_rigid)


# ---------------------------------------------------------------------------------------------
# PK and PKNL
# ---------------------------------------------------------------------------------------------
def _pk_roots(m: ModalArrays, gaf, rho, V, k, interpolation):
    """All 2n roots p and modal eigenvectors of Eq. 2-124 at (V, k)."""
    qr, qik = _gaf_at(gaf, k, interpolation)
    Keff = m.K - 0.5 * rho * V ** 2 * qr
    Beff = m.C - 0.5 * rho * gaf.b_ref * V * qik
    n = m.n_modes
    Minv = np.linalg.inv(m.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Keff, -Minv @ Beff]])
    lam, vec = np.linalg.eig(A)
    keep = lam.imag >= -1e-9 * np.maximum(np.abs(lam), 1.0)
    return lam[keep], vec[:n, keep]


def _taken(lam: np.ndarray, taken: list) -> np.ndarray:
    """Whether each root is (to 1e-3 relative: EPS apart in k) one already claimed by another
    mode."""
    if not taken:
        return np.zeros(lam.size, bool)
    t = np.asarray(taken)
    scale = np.maximum(np.abs(lam), 1e-12)[:, None]
    return np.any(np.abs(lam[:, None] - t[None, :]) <= 1e-3 * scale, axis=1)


def _pk_mode(m, gaf, rho, V, k0, ref, interpolation, eps, taken=()):
    """Nastran's k iteration for one mode: (p, vector, k, converged). The root: the one whose
    eigenvector correlates best with ``ref`` (the mode's vector at the previous point, or at
    the first point its root at k = 0, :func:`_cold_start`); roots in ``taken`` (claimed by
    the modes solved before at this point) are not chosen again."""
    b, k = gaf.b_ref, k0
    for _ in range(MAX_K_ITER):
        lam, vec = _pk_roots(m, gaf, rho, V, k, interpolation)
        score = mac_matrix(ref[:, None], vec)[0]
        score = score - 0.05 * np.abs(np.abs(lam.imag) * b / V - k) / max(k, 1e-3)
        score = score - 10.0 * _taken(lam, list(taken))
        j = int(np.argmax(score))
        k_new = abs(lam[j].imag) * b / V
        if abs(k_new - k) < eps * max(1.0, k):
            return lam[j], vec[:, j], k_new, True
        k = k_new
    return lam[j], vec[:, j], k_new, False


#: a root |p| below this fraction of the largest is a free rigid body's zero root (plunge of
#: a free-free model: no aerodynamic stiffness), which Nastran does not print.
ZERO_ROOT = 1e-8


def _cold_start(m, gaf, rho, V, interpolation):
    """The first point's start (Nastran's order in an f06 FLUTTER SUMMARY, e.g. pyNastran's
    bah_plane_qhh.f06): the roots of Eq. 2-124 at k = 0, zero roots dropped; the real ones
    first (ascending), converged at k = 0 as they are; then the oscillatory ones by frequency,
    each the reference (vector and k = |Im p| b / V) from which its mode's k iteration starts.
    Real roots come in pairs that take the place of a conjugate pair (a divergent and a
    convergent aperiodic root); as of a conjugate pair one root is kept: the larger half of
    them (the f06 lists the three positive of asekit's six real roots of BAH at Mach 0,
    4774 m/s). Returns (k0, references, n_real, roots in that order)."""
    lam, vec = _pk_roots(m, gaf, rho, V, 0.0, interpolation)
    scale = max(float(np.abs(lam).max(initial=0.0)), 1e-300)
    keep = np.abs(lam) > ZERO_ROOT * scale
    real = keep & (np.abs(lam.imag) <= 1e-9 * np.maximum(np.abs(lam), 1.0))
    r = np.flatnonzero(real)
    r = r[np.argsort(lam.real[r])][r.size // 2:]
    osc = np.flatnonzero(keep & ~real)
    order = np.r_[r, osc[np.argsort(np.abs(lam.imag[osc]))]].astype(int)
    n = m.n_modes
    order = np.r_[order, np.flatnonzero(~keep)][:n]      # too few roots: zero roots last
    return (np.abs(lam.imag[order]) * gaf.b_ref / V, vec[:, order].T, min(r.size, n),
            lam[order])


def _pk_point(m, gaf, rho, V, k_prev, v_prev, interpolation, eps, cold=False):
    n = m.n_modes
    p = np.empty(n, complex)
    vec = np.empty((n, n), complex)
    k = np.empty(n)
    conv = np.empty(n, bool)
    n_real = 0
    if cold:
        k_prev, v_prev, n_real, lam0 = _cold_start(m, gaf, rho, V, interpolation)
        p[:n_real], vec[:n_real], k[:n_real], conv[:n_real] = (lam0[:n_real],
                                                               v_prev[:n_real], 0.0, True)
    for j in range(n_real, n):
        p[j], vec[j], k[j], conv[j] = _pk_mode(m, gaf, rho, V, k_prev[j], v_prev[j],
                                               interpolation, eps, p[:j])
    return p, vec, k, conv


def _pk_sweep(m, gaf_of, points, interpolation, eps, method):
    """Solve the PK equation at each (density, Mach, V) point in order, each mode started
    from its k and vector at the previous point."""
    n, n_pt = m.n_modes, len(points)
    P = np.empty((n_pt, n), complex)
    X = np.empty((n_pt, n, n), complex)
    Kr = np.empty((n_pt, n))
    C = np.empty((n_pt, n), bool)
    v_prev = k_prev = None                      # the first point starts cold (_cold_start)
    for i, (rho, mach, V) in enumerate(points):
        gaf = gaf_of(mach)
        P[i], X[i], Kr[i], C[i] = _pk_point(m, gaf, rho, V, k_prev, v_prev, interpolation, eps,
                                            cold=k_prev is None)
        k_prev, v_prev = Kr[i], X[i]
    dens = np.array([p[0] for p in points], float)
    machs = np.array([np.nan if p[1] is None else p[1] for p in points], float)
    V = np.array([p[2] for p in points], float)
    return NastranFlutterResult(
        method=method, velocity=np.broadcast_to(V[:, None], P.shape).copy(),
        damping_g=vg_damping(P), frequency_hz=np.abs(P.imag) / (2 * np.pi), k=Kr,
        eigenvalue=P, vectors=X, converged=C, density=dens, mach=machs,
        b_ref=gaf_of(points[0][1]).b_ref, modes=np.arange(n), n_rigid=m.n_rigid)


def _velocities(velocities):
    """|V| (m/s) and the print-eigenvector flags (V < 0 in Nastran's FLFACT)."""
    v = np.atleast_1d(np.asarray(velocities, float))
    if v.ndim != 1 or v.size < 1 or not np.all(np.isfinite(v)) or np.any(v == 0):
        raise ValueError(f"velocities (FLFACT of FLUTTER VEL) must be finite and non-zero "
                         f"(negative: print eigenvectors), got {velocities!r}")
    return np.abs(v), v < 0


def _eps(eps) -> float:
    return positive("eps (FLUTTER EPS)", eps)


def pk_method(modal, gaf: TabulatedGaf, density: float, velocities, eps: float = DEFAULT_EPS,
              interpolation: str = "L", mach: float | None = None) -> NastranFlutterResult:
    """Nastran's PK method at one density and Mach over ``velocities`` (in the order given).

    Solves [M p^2 + (B - rho b V Q^I(k) / (2k)) p + (K - q Q^R(k))] u = 0 (MSC Aeroelastic
    User's Guide Eq. 2-124) with k <- |Im p| b / V per mode until |Delta k| < eps max(1, k);
    g = 2 Re p / |Im p|.

    Parameters
    ----------
    modal : ModalArrays (or an object with M, K, C).
    gaf : TabulatedGaf at the Mach of the sweep.
    density : float.
    velocities : FLFACT velocities (negative: print the eigenvectors, solved at |V|).
    eps : the FLUTTER card's EPS (> 0, default 1e-3).
    interpolation : 'L' linear (IMETH default) or 'S'.
    mach : recorded.

    Returns
    -------
    NastranFlutterResult (method "PK"), ``print_vectors`` the negative-velocity points.

    Examples
    --------
    One mode, no aerodynamics, viscous damping 2 zeta omega with zeta = 0.01: g = 2 gamma
    = 2 zeta / sqrt(1 - zeta^2).

    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 1, 1), complex), 1.0)
    >>> m = modal_arrays(M=[[1.0]], K=[[100.0]], C=[[0.2]])
    >>> r = pk_method(m, g, 1.0, [10.0, -20.0])
    >>> round(float(r.damping_g[0, 0]), 6), r.print_vectors.tolist()
    (-0.020001, [False, True])
    """
    m = _modal(modal)
    rho = positive("density", density)
    V, printed = _velocities(velocities)
    _check_interp(interpolation)
    res = _pk_sweep(m, lambda _: gaf, [(rho, mach, v) for v in V], interpolation, _eps(eps),
                    "PK")
    return _with_print(res, printed)


def _with_print(res: NastranFlutterResult, printed) -> NastranFlutterResult:
    from dataclasses import replace
    return replace(res, print_vectors=np.asarray(printed, bool))


def pknl_method(modal, gaf_for_mach, densities, machs, velocities, eps: float = DEFAULT_EPS,
                interpolation: str = "L") -> NastranFlutterResult:
    """Nastran's PKNL: the PK equation at matched flight points (densities[i], machs[i],
    velocities[i]), one point per index, no looping.

    Parameters
    ----------
    modal : ModalArrays.
    gaf_for_mach : callable mach -> TabulatedGaf (e.g. ``GafDatabase.at``).
    densities, machs, velocities : equal-length FLFACT lists (velocities < 0: print vectors).
    eps, interpolation : as :func:`pk_method`.

    Returns
    -------
    NastranFlutterResult (method "PKNL"), point i the i-th triple.

    Examples
    --------
    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 1, 1), complex), 1.0)
    >>> m = modal_arrays(M=[[1.0]], K=[[100.0]])
    >>> pknl_method(m, lambda mach: g, [1.0, 0.5], [0.3, 0.5], [10.0, 20.0]).density.tolist()
    [1.0, 0.5]
    """
    m = _modal(modal)
    rho = positive_array("densities (FLFACT of FLUTTER DENS)", densities)
    mach = np.atleast_1d(np.asarray(machs, float))
    V, printed = _velocities(velocities)
    if not rho.size == mach.size == V.size:
        raise ValueError(f"PKNL needs equal-length density, Mach and velocity lists (one "
                         f"flight point per index), got {rho.size}, {mach.size}, {V.size}")
    _check_interp(interpolation)
    res = _pk_sweep(m, gaf_for_mach, list(zip(rho, mach, V)), interpolation, _eps(eps),
                    "PKNL")
    return _with_print(res, printed)


# ---------------------------------------------------------------------------------------------
# crossings and the FLUTTER SUMMARY
# ---------------------------------------------------------------------------------------------
def _lerp(a, b, t):
    return float(a + t * (b - a))


#: |g| at or below this is neutral, not unstable: a mode with no aerodynamic force (e.g. an
#: in-plane mode of a wing: g = +-1e-16 at every velocity, in Nastran's f06 as in asekit)
#: must not "cross" at every sign change of round-off.
G_NEUTRAL = 1e-9


def _column_crossings(res: NastranFlutterResult, j: int) -> list[NastranCrossing]:
    g, V, f = res.damping_g[:, j], res.velocity[:, j], res.frequency_hz[:, j]
    g = np.where(np.abs(g) <= G_NEUTRAL, 0.0, g)
    ok = np.isfinite(g) & np.isfinite(V)
    idx = np.flatnonzero(ok)
    out = []
    real = res.k[:, j] <= 1e-9
    common = dict(method=res.method, mode=int(res.modes[j]), n_rigid=res.n_rigid)
    if idx.size and g[idx[0]] > 0:
        i = int(idx[0])
        out.append(NastranCrossing(speed=float(V[i]), frequency_hz=float(f[i]),
                                   density=float(res.density[i]), mach=float(res.mach[i]),
                                   index=i, unstable_at_first_point=True,
                                   kind="divergence" if real[i] else "flutter", **common))
    for a, b in zip(idx[:-1], idx[1:]):
        if g[a] <= 0 < g[b]:
            t = -g[a] / (g[b] - g[a])
            out.append(NastranCrossing(
                speed=_lerp(V[a], V[b], t), frequency_hz=_lerp(f[a], f[b], t),
                density=_lerp(res.density[a], res.density[b], t),
                mach=_lerp(res.mach[a], res.mach[b], t), index=int(b),
                unstable_at_first_point=False, kind="divergence" if real[b] else "flutter",
                **common))
    return out


def crossings(res: NastranFlutterResult) -> list[NastranCrossing]:
    """Every g = 0 crossing (stable to unstable) of every mode, in point order, interpolated
    linearly in g between the bracketing points (speed, frequency, density, Mach), plus one
    ``unstable_at_first_point`` entry per mode already unstable at the first point; sorted by
    speed.

    Examples
    --------
    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 1, 1), complex), 1.0)
    >>> crossings(pk_method(modal_arrays(M=[[1.0]], K=[[100.0]], C=[[0.2]]), g, 1.0, [5.0]))
    []
    """
    out = [c for j in range(res.damping_g.shape[1]) for c in _column_crossings(res, j)]
    return sorted(out, key=lambda c: c.speed)


def f06_damping(p, velocity, b_ref) -> np.ndarray:
    """The DAMPING column of Nastran's PK / PKNL FLUTTER SUMMARY for roots p (1/s) at
    velocity V: g = 2 Re p / |Im p| for an oscillatory root (MSC Aeroelastic User's Guide Eq.
    2-124, p = omega (gamma + i), g = 2 gamma; not clipped), and for a real root (printed with
    frequency 0) g = 2 b p / (V ln 2), b the reference semichord: the f06 of pyNastran's
    bah_plane_qhh deck satisfies this in all its 102 real-root rows to 1.1e-5 (ln 2 printed as
    0.69314), i.e. 1 / g is the number of reference chords flown while the root's amplitude
    halves (p < 0) or doubles (p > 0).

    Parameters
    ----------
    p : complex roots (1/s), any shape; velocity : V (m/s), broadcast with p;
    b_ref : reference semichord (m).

    Returns
    -------
    g, the shape of p.

    Examples
    --------
    >>> f06_damping([-2.0 + 40.0j, 0.5 + 0j], 10.0, 2.0).round(6).tolist()
    [-0.1, 0.288539]
    """
    p = np.asarray(p, complex)
    V = np.broadcast_to(np.asarray(velocity, float), p.shape)
    real = np.abs(p.imag) <= 1e-9 * np.maximum(np.abs(p), 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(real, 2 * b_ref * p.real / (V * np.log(2.0)),
                        2 * p.real / np.where(real, 1.0, np.abs(p.imag)))


def _summary_row(res, i, j) -> str:
    k = res.k[i, j]
    inv = 1.0 / k if k > 0 else np.inf
    lam = res.eigenvalue[i, j]
    g = (f06_damping(lam, res.velocity[i, j], res.b_ref) if res.method in ("PK", "PKNL")
         else res.damping_g[i, j])
    return (f"{k:10.4f} {inv:12.4E} {res.density[i]:11.4E} {res.mach[i]:7.4f} "
            f"{res.velocity[i, j]:12.4E} {g:12.4E} "
            f"{res.frequency_hz[i, j]:12.4E} {lam.real:12.4E} {lam.imag:12.4E}")


def _vector_lines(res: NastranFlutterResult, nv: int) -> list[str]:
    """The eigenvectors Nastran prints: at the points flagged by ``print_vectors`` (negative
    FLFACT velocities), each of the first ``nv`` modes' modal vector, scaled to a largest
    component of 1."""
    if res.vectors is None or res.print_vectors is None or not res.print_vectors.any():
        return []
    lines = ["", "EIGENVECTORS (modal coordinates, largest component 1)"]
    for i in np.flatnonzero(res.print_vectors):
        for j in range(nv):
            v = res.vectors[i, j]
            v = v / v[np.argmax(np.abs(v))]
            comps = " ".join(f"{c.real:+.4E}{c.imag:+.4E}j" for c in v)
            lines.append(f"V = {res.velocity[i, j]:.4E}  {res.mode_labels[j]}: {comps}")
    return lines


def flutter_summary(res: NastranFlutterResult, nvalue: int | None = None,
                    velocity_unit: str = "m/s") -> str:
    """Nastran's FLUTTER SUMMARY as text: one block per mode (``POINT = j``, the first
    ``nvalue`` modes, Nastran's NVALUE), one row per point: KFREQ, 1./KFREQ, DENSITY, MACH,
    VELOCITY, DAMPING (g; PK / PKNL as Nastran prints it, :func:`f06_damping`), FREQUENCY
    (Hz), the complex eigenvalue (PK: p; K: lambda); then the eigenvectors of the points whose
    FLFACT velocity was negative.

    Examples
    --------
    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 1, 1), complex), 1.0)
    >>> text = flutter_summary(pk_method(modal_arrays(M=[[1.0]], K=[[100.0]]), g, 1.0, [5.0]))
    >>> "FLUTTER SUMMARY" in text and "METHOD = PK" in text
    True
    """
    n_m = res.damping_g.shape[1]
    nv = n_m if nvalue is None else max(1, min(int(nvalue), n_m))
    head = (f"{'KFREQ':>10} {'1./KFREQ':>12} {'DENSITY':>11} {'MACH':>7} "
            f"{'VELOCITY':>12} {'DAMPING':>12} {'FREQUENCY':>12} {'REAL EIGVAL':>12} "
            f"{'IMAG EIGVAL':>12}")
    lines = []
    for j in range(nv):
        lines += ["", f"FLUTTER SUMMARY   POINT = {j + 1} ({res.mode_labels[j]})   "
                      f"METHOD = {res.method}   velocity in {velocity_unit}", head]
        lines += [_summary_row(res, i, j) for i in range(res.damping_g.shape[0])]
    return "\n".join(lines[1:] + _vector_lines(res, nv))


# ---------------------------------------------------------------------------------------------
# the registry's interface (asekit.aeroelastic.methods): solve(modal, gaf, rfa, rho, U)
# ---------------------------------------------------------------------------------------------
#: reduced frequencies of the K / KE registry entries: this many, log-spaced over the GAF
#: table's positive k (Q linear in k between the tabulated values).
K_POINTS = 200


def elastic_part(modal, gaf: TabulatedGaf):
    """(ModalArrays, TabulatedGaf) of the elastic modes only: a rigid mode held, as asekit's
    p-k does by default (the flutter of the elastic modes of a clamped or held surface).

    Examples
    --------
    >>> m = modal_arrays(M=np.eye(2), K=np.diag([0.0, 4.0]), n_rigid=1)
    >>> g = TabulatedGaf(np.array([0.0, 1.0]), np.zeros((2, 2, 2), complex), 1.0)
    >>> e, ge = elastic_part(m, g)
    >>> e.K.tolist(), ge.Q.shape
    ([[4.0]], (2, 1, 1))
    """
    m = _modal(modal)
    if m.n_rigid == 0:
        return m, gaf
    s = slice(m.n_rigid, m.n_modes)
    return (ModalArrays(m.M[s, s], m.K[s, s], m.C[s, s], 0),
            TabulatedGaf(gaf.k, gaf.Q[:, s, s], gaf.b_ref, gaf.mach))


def _as_pk_result(res: NastranFlutterResult, m: ModalArrays, V, p, k, vectors, converged):
    from asekit.aeroelastic.flutter import PkResult
    n = m.n_modes
    return PkResult(velocities=np.asarray(V, float), p=p, k=k,
                    vectors=np.zeros(p.shape + (0,), complex) if vectors is None else vectors,
                    converged=converged, structural_frequencies_hz=_structural_omegas(m)
                    / (2 * np.pi), density=float(res.density[0]),
                    mach=None if np.isnan(res.mach[0]) else float(res.mach[0]),
                    b_ref=res.b_ref, modes=np.arange(n))


def as_instabilities(found: list[NastranCrossing], name: str, U=None) -> list:
    """The crossings as :class:`asekit.aeroelastic.flutter.Instability` (``method`` = name),
    those inside [U[0], U[-1]] when ``U`` is given."""
    from asekit.aeroelastic.flutter import Instability
    out = []
    for c in found:
        if U is not None and not (U[0] <= c.speed <= U[-1]):
            continue
        out.append(Instability(kind=c.kind, mode=c.mode, speed=c.speed,
                               frequency_hz=0.0 if c.kind == "divergence" else c.frequency_hz,
                               method=name, at_first_point=c.unstable_at_first_point,
                               speed_tolerance=c.speed if c.unstable_at_first_point else 0.0))
    return out


def solve_pk(modal, gaf, rfa, density, velocities):
    """Registry entry ``"nastran_pk"``: :func:`pk_method` -> (PkResult, instabilities)."""
    m, g = elastic_part(modal, gaf)
    res = pk_method(m, g, density, velocities, mach=gaf.mach)
    roots = _as_pk_result(res, m, res.velocity[:, 0], res.eigenvalue, res.k, res.vectors,
                          res.converged)
    return roots, as_instabilities(crossings(res), "nastran_pk")


def _k_grid(gaf: TabulatedGaf) -> np.ndarray:
    kp = gaf.k[gaf.k > 0]
    return np.geomspace(kp[0], kp[-1], K_POINTS)


def _resample_column(V, g, f, k, U):
    """g, f, k of one K-method branch at the velocities U (the first bracketing segment of
    the branch, linear in V); NaN where the branch does not reach U."""
    out = np.full((3, U.size), np.nan)
    ok = np.isfinite(V) & np.isfinite(g)
    for a, b in zip(np.flatnonzero(ok)[:-1], np.flatnonzero(ok)[1:]):
        lo, hi = sorted((V[a], V[b]))
        hit = (U >= lo) & (U <= hi) & np.isnan(out[0])
        if hit.any() and hi > lo:
            t = (U[hit] - V[a]) / (V[b] - V[a])
            for row, y in enumerate((g, f, k)):
                out[row, hit] = y[a] + t * (y[b] - y[a])
    return out


def _solve_k(modal, gaf, density, velocities, vectors: bool, name: str):
    m, g = elastic_part(modal, gaf)
    U = positive_array("velocities", velocities)
    res = k_method(m, g, density, _k_grid(g), vectors=vectors, mach=gaf.mach)
    n = m.n_modes
    G, F, Kk = (np.empty((U.size, n)) for _ in range(3))
    for j in range(n):
        G[:, j], F[:, j], Kk[:, j] = _resample_column(res.velocity[:, j], res.damping_g[:, j],
                                                      res.frequency_hz[:, j], res.k[:, j], U)
    w = 2 * np.pi * F
    p = w * G / 2 + 1j * w
    roots = _as_pk_result(res, m, U, p, Kk, None, np.isfinite(p))
    found = as_instabilities(crossings(res), name, U)
    first = [j for j in range(n) if np.isfinite(G[0, j]) and G[0, j] > 0]
    found += [i for i in as_instabilities(
        [NastranCrossing(res.method, j, float(U[0]), float(F[0, j]), float(density),
                         float(res.mach[0]), 0, True) for j in first], name)]
    return roots, sorted(found, key=lambda s: s.speed)


def solve_k(modal, gaf, rfa, density, velocities):
    """Registry entry ``"k"``: :func:`k_method` at :data:`K_POINTS` reduced frequencies over
    the GAF table, each branch's V-g / V-f resampled at ``velocities`` (linear in V; NaN
    where a branch does not reach a velocity); crossings from the K curves themselves."""
    return _solve_k(modal, gaf, density, velocities, True, "k")


def solve_ke(modal, gaf, rfa, density, velocities):
    """Registry entry ``"ke"``: as :func:`solve_k` without eigenvectors (Nastran's KE)."""
    return _solve_k(modal, gaf, density, velocities, False, "ke")
