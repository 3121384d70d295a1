"""Flutter and divergence by three methods (thesis Section 3.3): p-k, root locus, time domain.

* p-k (Eq. 3.12): for each airspeed U and each tracked mode, solve

      (p^2 M + p (C - rho b U / (2k) Q^I(k)) + (K - q Q^R(k))) zeta = 0

  iterating k = Im(p) b / U to convergence (Hassig, "An approximate true damping solution of
  the flutter equation by determinant iteration", J. Aircraft 8(11), 1971; the MSC Nastran PK
  method with linear interpolation of Q in k). Modes are tracked across airspeed and inside the
  k-iteration by eigenvector correlation (modal assurance criterion), not by frequency order.
  Damping is reported as g = 2 Re(p)/|Im(p)| (Nastran's g = 2 gamma, p = omega (gamma +- i);
  g > 0 unstable; clipped to +-2, the value of real roots; docs/conventions.md) and the decay
  rate sigma = Re(p) (1/s).
* root locus (Section 3.3.2): eigenvalues of A_sys (Eq. 2.63) over airspeed; aeroelastic roots
  are continued from the structural roots (U -> 0) and separated from the aerodynamic lag roots
  by continuation with eigenvector correlation; damping ratio and frequency by Eq. (3.13).
* time domain (Section 3.3.3, Eqs. 3.14-3.15): free response of z' = A_sys z from a unit initial
  value of one elastic coordinate, by scipy's RK45 with a maximum step (the thesis used ode45
  with steps no larger than 1e-4 s) and by the exact matrix exponential; the growth rate of the
  late response over airspeed gives the onset speed.

Instabilities: flutter where an oscillatory root crosses to Re(p) > 0, divergence where a real
(zero-frequency) root does. All interpolated to Re(p) = 0 and refined by a scalar root search.
A root already unstable at the first airspeed of the sweep is reported as its own result
(``Instability.at_first_point``: "flutter at or below U0"), never dropped. "Unstable" means
Re(p) > tol with a tolerance scaled to the roots' magnitude (``crossing_tolerance``), so that
rounding (Re p = +1e-14 on an undamped structure at U -> 0) is not taken for an instability.

Units: any consistent set (SI for the fin; inch-lbf-s for Nastran's HA145B).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import linalg, optimize

from asekit.aero.gaf import TabulatedGaf
from asekit.aeroelastic.statespace import ModalArrays, aeroelastic_matrices, modal_arrays
from asekit.atmosphere import standard_atmosphere
from asekit.util.blas import small_dense
from asekit.util.conventions import damping_ratio, mode_label, vg_damping
from asekit.util.validate import (
    ArgumentTypeError,
    finite_array,
    integer,
    positive,
    positive_array,
)

#: relative tolerance of the stability test: a root is unstable when Re p > RTOL_UNSTABLE * scale,
#: ``scale`` the largest root magnitude of the sweep (rounding of eigenvalues is ~1e-16 of it).
RTOL_UNSTABLE = 1e-9
#: largest number of steps / samples a single call may ask for before it is refused.
MAX_STEPS = 5_000_000
#: p-k continuation (:func:`pk_flutter`): a step between two points of the path is split in two
#: when a tracked root moves by more than ``STEP_FRACTION`` of its distance to the nearest other
#: root of the previous point, when its eigenvector correlates with the previous point's by a
#: MAC below ``MIN_MAC``, or when two tracked columns land on the same root.
STEP_FRACTION = 0.5
MIN_MAC = 0.8
#: a step between two requested airspeeds is halved at most ``MAX_HALVINGS`` times: the shortest
#: sub-step is (U[i] - U[i-1]) / 2**MAX_HALVINGS; a step that short is taken as it is (and
#: counted in ``PkResult.forced_steps``), its columns assigned to distinct roots.
MAX_HALVINGS = 8
#: relative tolerance of the refined crossing speed (Brent's ``xtol = REFINE_RTOL * U``).
REFINE_RTOL = 1e-6


class FlutterConvergenceWarning(RuntimeWarning):
    """The p-k frequency iteration did not converge within ``max_iter`` for some (mode, speed)."""


def crossing_tolerance(roots) -> float:
    """Tolerance of the stability test for a set of roots (any shape, complex, 1/s):
    ``RTOL_UNSTABLE * max |p|`` over the finite roots (0 if there are none). A root counts as
    unstable when Re p > tolerance."""
    r = np.abs(np.asarray(roots))
    r = r[np.isfinite(r)]
    return float(RTOL_UNSTABLE * r.max()) if r.size else 0.0


def _ascending(name: str, values) -> np.ndarray:
    """Finite, > 0, strictly ascending 1-D array, else ValueError naming ``name``."""
    U = positive_array(name, values)
    if U.ndim != 1:
        raise ValueError(f"{name} must be a 1-D sequence of airspeeds, got shape {U.shape}")
    if np.any(np.diff(U) <= 0):
        raise ValueError(f"{name} must be strictly ascending (no repeats); got {U}. Pass "
                         f"np.unique({name}) to sort them.")
    return U


def _pressure_ok(rho: float, U: np.ndarray) -> None:
    """Refuse density x velocities whose dynamic pressure overflows (ValueError naming both)."""
    with np.errstate(over="ignore"):
        q = 0.5 * rho * np.square(np.max(U))
    if not np.isfinite(q):
        raise ValueError(f"density = {rho:g} and velocities up to {np.max(U):g} give an "
                         "infinite dynamic pressure")


def _count(name: str, value, low: int = 1) -> int:
    """An integer >= low (bool refused), else TypeError/ValueError naming ``name``
    (:func:`asekit.util.validate.integer`)."""
    return integer(name, value, low=low)


def _mac(a: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Modal assurance criterion of vector a against the columns of B (complex)."""
    num = np.abs(a.conj() @ B) ** 2
    den = (np.real(a.conj() @ a) * np.real(np.sum(B.conj() * B, axis=0))) + 1e-300
    return num / den


def _elastic_part(modal: ModalArrays, Q: np.ndarray, include_rigid: bool):
    if include_rigid or modal.n_rigid == 0:
        return modal.M, modal.K, modal.C, Q
    s = slice(modal.n_rigid, modal.n_modes)
    return modal.M[s, s], modal.K[s, s], modal.C[s, s], Q[:, s, s]


# --------------------------------------------------------------------------------------------
# p-k method
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PkResult:
    """p-k solution over airspeed for each tracked mode.

    velocities (n_v,), p (n_v, n_t) complex roots, sigma = Re p (1/s), frequency_hz = Im p/2pi,
    damping_g = 2 Re p/|Im p| (V-g damping, > 0 unstable, :func:`asekit.util.conventions.vg_damping`),
    k (n_v, n_t), vectors (n_v, n_t, n) eigenvectors (modal coordinates), converged (n_v, n_t)
    bool, structural_frequencies_hz (n_t,), density, mach. ``modes`` (n_t,): the index of each
    tracked column among the modes solved (None: column j is mode j); ``n_rigid``: rigid modes
    among the modes solved (0 when the rigid mode is held, the default), so that column j is
    named ``mode_labels[j]`` (docs/conventions.md: elastic modes 1, 2, ..., "rigid pitch").

    How fine the search was: the roots are continued along ``path_velocities`` (n_path,), the
    requested velocities plus the sub-steps the step control of :func:`pk_flutter` inserted
    between them (``substeps`` of them), with ``path_p``, ``path_vectors`` and
    ``path_converged`` the roots there; :func:`pk_instabilities` brackets every crossing on
    this path. ``step_fraction`` and ``min_mac`` are the step control's thresholds,
    ``forced_steps`` the number of sub-steps taken at the shortest length without meeting them
    (0 when every step met them). The path fields are None for a result not made by
    :func:`pk_flutter` (the path is then ``velocities``).
    """

    velocities: np.ndarray
    p: np.ndarray
    k: np.ndarray
    vectors: np.ndarray
    converged: np.ndarray
    structural_frequencies_hz: np.ndarray
    density: float
    mach: float | None = None
    b_ref: float = 1.0
    modes: np.ndarray | None = None
    n_rigid: int = 0
    path_velocities: np.ndarray | None = None
    path_p: np.ndarray | None = None
    path_vectors: np.ndarray | None = None
    path_converged: np.ndarray | None = None
    step_fraction: float = STEP_FRACTION
    min_mac: float = MIN_MAC
    forced_steps: int = 0

    @property
    def substeps(self) -> int:
        """Number of sub-steps inserted between the requested velocities."""
        return 0 if self.path_velocities is None else int(self.path_velocities.size
                                                          - self.velocities.size)

    def path(self):
        """(velocities, p, vectors, converged) along the continuation path (the requested
        velocities when the result has no path)."""
        if self.path_velocities is None:
            return self.velocities, self.p, self.vectors, self.converged
        return self.path_velocities, self.path_p, self.path_vectors, self.path_converged

    @property
    def sigma(self) -> np.ndarray:
        return self.p.real

    @property
    def frequency_hz(self) -> np.ndarray:
        return np.abs(self.p.imag) / (2 * np.pi)

    @property
    def damping_g(self) -> np.ndarray:
        """V-g damping g = 2 Re p / |Im p| (-), > 0 unstable (clipped to +-2)."""
        return vg_damping(self.p)

    @property
    def damping_ratio(self) -> np.ndarray:
        """Damping ratio zeta = -Re p / |p| (-), > 0 stable."""
        return damping_ratio(self.p)

    def mode_index(self, column: int) -> int:
        """The index among the modes solved of tracked column ``column``."""
        return int(column if self.modes is None else self.modes[column])

    @property
    def mode_labels(self) -> list[str]:
        """User-facing names of the tracked columns ("mode 1", ..., "rigid pitch")."""
        return [mode_label(self.mode_index(j), self.n_rigid) for j in range(self.p.shape[1])]


@dataclass(frozen=True)
class Instability:
    """A flutter or divergence point: ``kind`` ('flutter' or 'divergence'), tracked ``mode``
    index (0-based among the modes solved), ``speed`` (m/s), ``frequency_hz`` (0 for divergence),
    ``vector`` (modal eigenvector at the point, if known), ``method``; ``n_rigid``: rigid modes
    among the modes solved (0 when held), so the user-facing name is :attr:`mode_name`.

    ``at_first_point`` marks the other result kind: the root is already unstable at the first
    airspeed of the sweep, so the instability is *at or below* ``speed`` (= U0, an upper bound,
    not a crossing); ``frequency_hz`` is then the frequency at U0. Start the sweep lower to
    locate it.

    ``speed_tolerance`` (m/s): how well ``speed`` is known. For a refined crossing, Brent's
    tolerance on the bracketing sub-step (``REFINE_RTOL`` times the speed); for an
    interpolated one, the length of the bracketing step; for an ``at_first_point`` result,
    ``speed`` itself (the instability lies somewhere in [0, speed]); 0 when not stated.
    """

    kind: str
    mode: int
    speed: float
    frequency_hz: float
    vector: np.ndarray | None = field(default=None, repr=False)
    method: str = ""
    at_first_point: bool = False
    n_rigid: int = 0
    speed_tolerance: float = 0.0

    @property
    def mode_name(self) -> str:
        """'mode 1', 'mode 2', ... (elastic modes from 1) or 'rigid pitch'
        (:func:`asekit.util.conventions.mode_label`)."""
        return mode_label(self.mode, self.n_rigid)

    def describe(self, unit: str = "m/s") -> str:
        """One-line description, e.g. 'flutter at 218.1 m/s, 140.9 Hz (mode 2, p-k)' or
        'unstable at the first point of the sweep: flutter at or below 250 m/s (mode 2, p-k)'."""
        where = self.mode_name + (f", {self.method}" if self.method else "")
        if self.at_first_point:
            return (f"unstable at the first point of the sweep: {self.kind} at or below "
                    f"{self.speed:.6g} {unit} ({where})")
        freq = f", {self.frequency_hz:.4g} Hz" if self.kind == "flutter" else ""
        return f"{self.kind} at {self.speed:.6g} {unit}{freq} ({where})"


class _PkProblem:
    """Eq. (3.12) at one density on one GAF table, in first-order form: the lower blocks of
    the system matrix are -M^-1 (K - q Re Q(k)) and -M^-1 (C - rho b U Im Q(k) / (2 k)), with
    M^-1 Re Q and M^-1 Im Q / k tabulated once (linear interpolation in k is then a blend of
    two tabulated matrices)."""

    def __init__(self, M, K, C, gaf: TabulatedGaf, rho, interpolation):
        self.M, self.K, self.C = M, K, C
        self.Minv = np.linalg.inv(M)
        self.gaf = gaf
        self.rho = rho
        self.n = M.shape[0]
        self.interp = interpolation
        kk = gaf.k
        qik = gaf.Q.imag / np.where(kk > 0, kk, 1.0)[:, None, None]
        if kk[0] == 0:
            qik[0] = qik[1]
        self._mqr = self.Minv @ gaf.Q.real              # M^-1 Re Q(k_j), (n_k, n, n)
        self._mqik = self.Minv @ qik                    # M^-1 Im Q(k_j) / k_j
        self._mk, self._mc = -self.Minv @ K, -self.Minv @ C
        self._kmin, self._kmax = float(kk[0]), float(kk[-1])
        self._eye = np.eye(self.n)
        self._stack = None

    def _parts(self, ks: np.ndarray):
        """M^-1 Re Q(k) and M^-1 Im Q(k) / k at the reduced frequencies ``ks`` (m,), each
        (m, n, n): linearly interpolated in k inline (clamped to the tabulated range), or by
        :meth:`TabulatedGaf.parts` for other interpolations."""
        if self.interp != "linear":
            parts = [self.gaf.parts(float(k), self.interp) for k in ks]
            return (self.Minv @ np.array([a for a, _ in parts]),
                    self.Minv @ np.array([c for _, c in parts]))
        kk = self.gaf.k
        kq = np.minimum(np.maximum(ks, self._kmin), self._kmax)
        j = np.minimum(np.maximum(np.searchsorted(kk, kq) - 1, 0), kk.size - 2)
        t = ((kq - kk[j]) / (kk[j + 1] - kk[j]))[:, None, None]
        return ((1 - t) * self._mqr[j] + t * self._mqr[j + 1],
                (1 - t) * self._mqik[j] + t * self._mqik[j + 1])

    def eig(self, U, k):
        """All roots p and modal eigenvectors of Eq. (3.12) at (U, k)."""
        lam, vec = self.eig_batch(U, np.array([float(k)]))
        return lam[0], vec[0]

    def eig_batch(self, U, ks: np.ndarray):
        """The roots (m, 2n) and modal eigenvectors (m, n, 2n) of Eq. (3.12) at airspeed ``U``
        and each reduced frequency of ``ks`` (m,): the m first-order system matrices are
        stacked and solved by one call of :func:`numpy.linalg.eig` (issue 23: one LAPACK
        call per batch instead of one Python round trip per root)."""
        ks = np.asarray(ks, float)
        return self.stack.eig_rows(np.zeros(ks.size, int), np.full(ks.size, float(U)), ks)

    @property
    def stack(self) -> _PkStack:
        """This problem as the one lane of a :class:`_PkStack` (built once)."""
        if self._stack is None:
            self._stack = _PkStack([self])
        return self._stack

    def solve_mode(self, U, omega_guess, ref, tol=1e-7, max_iter=60):
        """Converge one root: returns (p, vector, k, converged)."""
        return self.solve_root(U, omega_guess, ref, tol, max_iter)[:4]

    def solve_root(self, U, omega_guess, ref, tol=1e-7, max_iter=60):
        """Converge one root: returns (p, vector, k, converged, spacing), ``spacing`` the
        distance (1/s) from p to the nearest other root of the last eigenproblem (other real
        roots not counted when p is real: a real pair is one branch, reported by its least
        stable root; inf when there is none)."""
        p, v, k, ok, sp = self.solve_roots(U, np.array([float(omega_guess)]),
                                           np.asarray(ref)[None, :], tol, max_iter)
        return p[0], v[0], k[0], bool(ok[0]), float(sp[0])

    def solve_roots(self, U, omega_guess: np.ndarray, refs: np.ndarray, tol=1e-7, max_iter=60):
        """Converge m roots at airspeed ``U`` together (Hassig's k-iteration, batched).

        Root i starts from the circular frequency ``omega_guess[i]`` (rad/s) and follows the
        eigenvector ``refs[i]`` (n,): at each iteration, k_i = omega_i b / U, the eigenproblem
        of Eq. (3.12) is solved at every k_i of the roots not yet converged (one stacked
        :meth:`eig_batch`), and root i takes the upper-half-plane root that best correlates
        with ``refs[i]`` (MAC, less 0.2 times its relative frequency distance); a real pair
        is reported by its least stable well-correlated real root. Root i has converged when
        its frequency changes by at most ``tol`` relative. Returns ``(p (m,), vectors (m, n),
        k (m,), converged (m,), spacing (m,))``, ``spacing`` the distance (1/s) from p to the
        nearest other root of its last eigenproblem (other real roots not counted when p is
        real; inf when there is none).
        """
        omega = np.asarray(omega_guess, float)
        return self.stack.solve_rows(np.zeros(omega.size, int), np.full(omega.size, float(U)),
                                     omega, np.asarray(refs), tol, max_iter)


class _PkStack:
    """Several p-k problems (lanes: :class:`_PkProblem` of one modal model at different GAF
    tables and densities) solved together, row by row (issue 23, "p-k batched"): each row is
    one root of one lane at its own airspeed, and one k-iteration of every row is one stacked
    :func:`numpy.linalg.eig`. The arithmetic of each row is that of the row alone (elementwise
    blends of the lane's tabulated M^-1 Re Q(k_j), M^-1 Im Q(k_j) / k_j; Eq. 3.12), so a row's
    result does not depend on the other rows of the batch.

    Lanes need the same number of modes; linear interpolation is vectorised over the rows
    when every lane has the same reduced-frequency table (else, and for other
    interpolations, each row is interpolated by its own lane)."""

    def __init__(self, probs):
        self.probs = list(probs)
        p0 = self.probs[0]
        if any(p.n != p0.n for p in self.probs):
            raise ValueError("the p-k lanes must have the same number of modes")
        self.n = p0.n
        self.rho = np.array([p.rho for p in self.probs], float)
        self.b = np.array([p.gaf.b_ref for p in self.probs], float)
        self._mk = np.stack([p._mk for p in self.probs])
        self._mc = np.stack([p._mc for p in self.probs])
        self._eye = np.eye(self.n)
        kk = p0.gaf.k
        self._vector = all(p.interp == "linear" and np.array_equal(p.gaf.k, kk)
                           for p in self.probs)
        self._one = len(self.probs) == 1      # one lane: broadcast its arrays, no gathers
        if self._vector:
            self._kk = kk
            self._mqr = np.stack([p._mqr for p in self.probs])       # (L, n_k, n, n)
            self._mqik = np.stack([p._mqik for p in self.probs])
            self._kmin, self._kmax = float(kk[0]), float(kk[-1])

    def _parts(self, lanes: np.ndarray, ks: np.ndarray):
        """M^-1 Re Q(k) and M^-1 Im Q(k) / k of row i's lane at ``ks[i]``, each (m, n, n)
        (:meth:`_PkProblem._parts`, linear in k, clamped to the table)."""
        if not self._vector:
            parts = [self.probs[ln]._parts(np.array([k])) for ln, k in zip(lanes, ks)]
            return (np.concatenate([a for a, _ in parts]),
                    np.concatenate([c for _, c in parts]))
        kk = self._kk
        kq = np.minimum(np.maximum(ks, self._kmin), self._kmax)
        j = np.minimum(np.maximum(np.searchsorted(kk, kq) - 1, 0), kk.size - 2)
        t = ((kq - kk[j]) / (kk[j + 1] - kk[j]))[:, None, None]
        if self._one:
            mqr, mqik = self._mqr[0], self._mqik[0]
            return ((1 - t) * mqr[j] + t * mqr[j + 1], (1 - t) * mqik[j] + t * mqik[j + 1])
        return ((1 - t) * self._mqr[lanes, j] + t * self._mqr[lanes, j + 1],
                (1 - t) * self._mqik[lanes, j] + t * self._mqik[lanes, j + 1])

    def eig_rows(self, lanes: np.ndarray, U: np.ndarray, ks: np.ndarray):
        """The roots (m, 2n) and modal eigenvectors (m, n, 2n) of Eq. (3.12) for row i at
        lane ``lanes[i]``, airspeed ``U[i]`` and reduced frequency ``ks[i]``: one stacked
        :func:`numpy.linalg.eig` of the m first-order system matrices."""
        mqr, mqik = self._parts(lanes, ks)
        n, m = self.n, mqr.shape[0]
        if self._one:                 # the same numbers, broadcast instead of gathered
            rho, b, mk, mc = self.rho[0], self.b[0], self._mk[0], self._mc[0]
        else:
            rho, b, mk, mc = self.rho[lanes], self.b[lanes], self._mk[lanes], self._mc[lanes]
        A = np.zeros((m, 2 * n, 2 * n))
        A[:, :n, n:] = self._eye
        A[:, n:, :n] = mk + ((0.5 * rho) * U ** 2)[:, None, None] * mqr
        A[:, n:, n:] = mc + ((0.5 * rho * b) * U)[:, None, None] * mqik
        lam, vec = np.linalg.eig(A)
        return lam, vec[:, :n, :]

    def solve_rows(self, lanes: np.ndarray, U: np.ndarray, omega_guess: np.ndarray,
                   refs: np.ndarray, tol=1e-7, max_iter=60):
        """Converge m roots together, row i in lane ``lanes[i]`` at airspeed ``U[i]``
        (Hassig's k-iteration of :meth:`_PkProblem.solve_roots`, each row on its own): the
        rows not yet converged are iterated by one :meth:`eig_rows` per iteration. Returns
        ``(p (m,), vectors (m, n), k (m,), converged (m,), spacing (m,))``."""
        b = self.b[lanes]
        omega = np.maximum(np.asarray(omega_guess, float), 0.0)
        m = omega.size
        p_out, v_out = np.zeros(m, complex), np.zeros((m, self.n), complex)
        ok, spacing = np.zeros(m, bool), np.full(m, np.inf)
        active = np.arange(m)
        last_w, last_f = np.full(m, np.nan), np.full(m, np.nan)
        for it in range(max_iter):
            om, ua, ba = omega[active], U[active], b[active]
            lam, vec = self.eig_rows(lanes[active], ua, om * ba / ua)
            p, v, sp = _pick_roots(lam, vec, refs[active], om)
            om_new = np.abs(p.imag)
            conv = np.abs(om_new - om) <= tol * np.maximum(np.maximum(om_new, 1e-6 * ua / ba),
                                                           1e-12)
            done = conv | (it == max_iter - 1)
            idx = active[done]
            p_out[idx], v_out[idx], ok[idx], spacing[idx] = p[done], v[done], conv[done], sp[done]
            omega[active] = _secant_step(om, om_new - om, last_w[active], last_f[active])
            last_w[active], last_f[active] = om, om_new - om
            active = active[~done]
            if active.size == 0:
                break
        return p_out, v_out, np.abs(p_out.imag) * b / U, ok, spacing


def _secant_step(w: np.ndarray, f: np.ndarray, w0: np.ndarray, f0: np.ndarray) -> np.ndarray:
    """The next frequency of the k-iteration for the fixed point w = g(w), f = g(w) - w: the
    secant root of f through (w0, f0) and (w, f) where its slope says the iteration contracts
    (-3 < f' < -0.2, i.e. -2 < g' < 0.8), else the plain fixed-point step g(w) = w + f (the
    first iteration, a root that changed branch, a slope out of range)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (f - f0) / (w - w0)
        secant = w - f / slope
    use = np.isfinite(secant) & (slope > -3.0) & (slope < -0.2) & (secant > 0)
    return np.where(use, secant, w + f)


def _mac_rows(refs: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """MAC of each row's reference vector ``refs[i]`` (n,) against the columns of ``vec[i]``
    (n, c): (m, c)."""
    num = np.abs(np.einsum("in,inc->ic", refs.conj(), vec)) ** 2
    den = (np.real(np.einsum("in,in->i", refs.conj(), refs))[:, None]
           * np.real(np.einsum("inc,inc->ic", vec.conj(), vec))) + 1e-300
    return num / den


def _pick_roots(lam: np.ndarray, vec: np.ndarray, refs: np.ndarray, omega: np.ndarray):
    """One k-iteration's choice for m roots at once (see :meth:`_PkProblem.solve_roots`):
    from the roots ``lam`` (m, 2n) and vectors ``vec`` (m, n, 2n) of m eigenproblems, the
    upper-half-plane root of each that best matches its reference vector ``refs[i]`` and
    frequency ``omega[i]``; returns (p (m,), vectors (m, n), spacing (m,))."""
    absl = np.abs(lam)
    upper = lam.imag >= -1e-9 * np.maximum(absl, 1.0)
    real = upper & (np.abs(lam.imag) <= 1e-9 * np.maximum(absl, 1.0))
    mac = _mac_rows(refs, vec)
    scale = np.maximum(np.maximum(omega, absl.max(axis=1) * 1e-3), 1e-12)
    score = mac - 0.2 * np.abs(np.abs(lam.imag) - omega[:, None]) / scale[:, None]
    rows = np.arange(lam.shape[0])
    j = np.argmax(np.where(upper, score, -np.inf), axis=1)
    if real[rows, j].any():
        # a real pair: report the least stable of the well-correlated real roots
        cand = real & (mac >= 0.8 * mac[rows, j][:, None])
        j = np.where(real[rows, j], np.argmax(np.where(cand, lam.real, -np.inf), axis=1), j)
    p = lam[rows, j]
    other = upper.copy()
    other[rows, j] = False
    other &= ~(real & real[rows, j][:, None])
    spacing = np.where(other, np.abs(lam - p[:, None]), np.inf).min(axis=1)
    return p, vec[rows, :, j], spacing


@dataclass(frozen=True)
class _Roots:
    """The tracked roots at one point of the p-k path: p (n_t,), vectors (n_t, n), k (n_t,),
    converged (n_t,), spacing (n_t,) (see :meth:`_PkProblem.solve_root`)."""

    p: np.ndarray
    v: np.ndarray
    k: np.ndarray
    ok: np.ndarray
    spacing: np.ndarray


def _solve_all(prob: _PkProblem, u: float, prev: _Roots, tol, max_iter) -> _Roots:
    """Every tracked root at airspeed ``u``, each continued from its root at ``prev`` (one
    batched k-iteration, :meth:`_PkProblem.solve_roots`)."""
    return _Roots(*prob.solve_roots(u, np.abs(prev.p.imag), prev.v, tol, max_iter))


def _same_root(r: _Roots) -> list[tuple[int, int]]:
    """Pairs of tracked columns that hold the same root (equal to 1e-6 of its magnitude, their
    eigenvectors correlated above 0.99)."""
    a = np.abs(r.p)
    close = (np.abs(r.p[:, None] - r.p[None, :])
             <= 1e-6 * np.maximum(np.maximum(a[:, None], a[None, :]), 1e-12))
    close.flat[::a.size + 1] = False      # not a pair: a root and itself
    if not close.any():                   # the usual case: nothing to correlate
        return []
    return [(int(i), int(j)) for i, j in np.argwhere(np.triu(close, 1))
            if _mac(r.v[i], r.v[j][:, None])[0] > 0.99]


def _step_accepted(prev: _Roots, new: _Roots, fraction: float, min_mac: float) -> bool:
    """The step control's test: every tracked root moved by at most ``fraction`` of its
    spacing at ``prev``, its eigenvector's MAC with the previous one is >= ``min_mac``, and no
    two columns hold the same root that did not at ``prev`` already (two columns may share a
    real root for good: each reports the least stable real root it correlates with)."""
    if np.any(np.abs(new.p - prev.p) > fraction * prev.spacing):
        return False
    macs = _mac_rows(prev.v, new.v[:, :, None])[:, 0]
    return macs.min() >= min_mac and not set(_same_root(new)) - set(_same_root(prev))


def _reassign(prob: _PkProblem, u: float, prev: _Roots, new: _Roots, tol, max_iter) -> _Roots:
    """Columns that hold the same root at ``u`` reassigned to distinct roots: the roots of the
    eigenproblem at the shared root's k are assigned to every column's previous root by the
    Hungarian method on the cost |p - p_prev| / spacing_prev + (1 - MAC), and each column is
    converged again from its candidate (kept when fewer columns share a root than before)."""
    dup = _same_root(new)
    if not dup:
        return new
    cols = list(range(new.p.size))
    lam, vec = prob.eig(u, new.k[dup[0][0]])
    up = lam.imag >= -1e-9 * np.maximum(np.abs(lam), 1.0)
    lam, vec = lam[up], vec[:, up]
    cost = np.array([np.abs(lam - prev.p[c]) / max(prev.spacing[c], 1e-300)
                     + (1 - _mac(prev.v[c], vec)) for c in cols])
    rows, cand = optimize.linear_sum_assignment(np.minimum(cost, 1e6))
    p, v, k, ok, sp = (np.array(a) for a in (new.p, new.v, new.k, new.ok, new.spacing))
    for r, c in zip(rows, cand):
        j = cols[r]
        p[j], v[j], k[j], ok[j], sp[j] = prob.solve_root(u, abs(lam[c].imag), vec[:, c], tol,
                                                         max_iter)
    out = _Roots(p, v, k, ok, sp)
    return out if len(_same_root(out)) < len(dup) else new


def _continue(prob: _PkProblem, ua: float, prev: _Roots, ub: float, tol, max_iter,
              fraction: float, min_mac: float, max_halvings: int):
    """Continue the tracked roots from ``prev`` at ``ua`` to ``ub`` with step control.

    The first trial is the whole step; a step that fails :func:`_step_accepted` is halved, at
    most ``max_halvings`` times (a step of (ub - ua) / 2**max_halvings is taken as it is, its
    columns made distinct by :func:`_reassign`); after an accepted step the next trial is twice
    as long. Returns the accepted points [(u, roots), ...] ending at ``ub`` and the number of
    forced steps.

    A generator (issue 23): each trial step yields ``(u, prev)`` and is sent back the tracked
    roots at u continued from ``prev`` (:func:`_solve_all`), so that :func:`_run_lanes` can
    solve the trial steps of many sweeps in one batch.
    """
    points, forced, direct = [], 0, None
    h_min = (ub - ua) / 2.0 ** max_halvings
    u, h = ua, ub - ua
    while u < ub:
        un = ub if u + h >= ub else u + h
        new = yield un, prev
        if direct is None:
            direct = new                  # the whole step, as a sweep without step control
        if not _step_accepted(prev, new, fraction, min_mac):
            if h > h_min * (1 + 1e-9):
                h *= 0.5
                continue
            new = _reassign(prob, un, prev, new, tol, max_iter)
            forced += 1
        points.append((un, new))
        u, prev, h = un, new, 2 * h
    if len(points) > 1:
        points[-1] = (ub, _prefer_direct(points[-1][1], direct))
    return points, forced


def _prefer_direct(cont: _Roots, direct: _Roots) -> _Roots:
    """The roots at the end of a split step: each column's root of the whole (direct) step
    where it is the continued root too (equal to 1e-5 of its magnitude, MAC > 0.999), else the
    continued root. Where the direct step did not jump, the result is bit for bit that of a
    sweep without step control; the same converged root either way, to the k-iteration's
    tolerance."""
    same = np.array([abs(c - d) <= 1e-5 * max(abs(c), 1e-12)
                     and _mac(vc, vd[:, None])[0] > 0.999
                     for c, d, vc, vd in zip(cont.p, direct.p, cont.v, direct.v)])
    if not same.any():
        return cont
    pick = [np.where(same if a.ndim == 1 else same[:, None], b, a)
            for a, b in ((cont.p, direct.p), (cont.v, direct.v), (cont.k, direct.k),
                         (cont.ok, direct.ok), (cont.spacing, direct.spacing))]
    out = _Roots(*pick)
    return cont if set(_same_root(out)) - set(_same_root(cont)) else out


@small_dense
def pk_flutter(modal, gaf: TabulatedGaf, density: float, velocities, modes=None,
               include_rigid: bool = False, interpolation: str = "linear", tol: float = 1e-7,
               max_iter: int = 60, step_fraction: float = STEP_FRACTION,
               min_mac: float = MIN_MAC, max_halvings: int = MAX_HALVINGS) -> PkResult:
    """p-k solution of Eq. (3.12) over a list of airspeeds, the roots continued with step
    control so that a tracked root never jumps to another branch between two airspeeds.

    Each tracked root is continued from its structural root (U = 0: p = i omega_j, the
    undamped mode shape) through the requested airspeeds; at each new airspeed it is
    converged from its root at the previous point (Hassig's k-iteration, roots picked by
    eigenvector correlation, :class:`_PkProblem`). A step from U_a to U_b is accepted when,
    for every tracked root j,

        |p_j(U_b) - p_j(U_a)| <= step_fraction * s_j(U_a),   MAC(phi_j(U_a), phi_j(U_b)) >= min_mac

    (s_j the distance from p_j to the nearest other root at U_a) and no two tracked columns
    hold the same root; otherwise it is halved, at most ``max_halvings`` times, and the next
    trial after an accepted step is twice as long. On a fine sweep every step is accepted as
    it is (no extra work); the sub-steps land in ``PkResult.path_velocities``, where
    :func:`pk_instabilities` brackets the crossings. A step still failing at the shortest
    length is taken, its columns assigned to distinct roots by the Hungarian method on
    |p - p_prev| / s_prev + (1 - MAC) (``PkResult.forced_steps`` counts them).

    Parameters
    ----------
    modal : ModalArrays or ModalModel-like (M, K, C, n_rigid). By default the rigid modes are
        held (actuator clamped), as in Eq. (3.12) which uses the elastic (s-set) matrices only.
    gaf : :class:`TabulatedGaf` of all modes (rigid first).
    density : air density (kg/m^3 or the model's unit), > 0.
    velocities : ascending airspeeds (> 0).
    modes : indices (among the modes solved) to track; default all.
    include_rigid : solve with the rigid modes free too.
    interpolation : "linear" (Nastran's default) or "cubic" in k.
    tol, max_iter : k-iteration convergence (relative frequency change) and limit.
    step_fraction : largest root movement per step as a fraction of its spacing, in (0, 1].
    min_mac : smallest eigenvector correlation (MAC) between consecutive points, in [0, 1).
    max_halvings : integer >= 0, most halvings of a step (0: no sub-steps, the requested
        velocities only).

    Returns
    -------
    :class:`PkResult` at the requested velocities, with the path and the step control's
    thresholds.

    See Also
    --------
    pk_flutter_many : several (gaf, density) sweeps of one model solved together, each
        result equal to this function's (issue 23: the envelope's sweeps in one batch).
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    rho = positive("density", density)
    U = _ascending("velocities", velocities)
    _pressure_ok(rho, U)
    opts = _pk_options(max_iter, tol, step_fraction, min_mac, max_halvings, interpolation)
    lane = _pk_lane(m, gaf, rho, U, include_rigid, interpolation, modes)
    (run,) = _run_lanes(_PkStack([lane.prob]), U, [lane.start], *opts)
    return _pk_result(m, lane, U, run, include_rigid, opts)


@small_dense
def pk_flutter_many(modal, conditions, velocities, modes=None, include_rigid: bool = False,
                    interpolation: str = "linear", tol: float = 1e-7, max_iter: int = 60,
                    step_fraction: float = STEP_FRACTION, min_mac: float = MIN_MAC,
                    max_halvings: int = MAX_HALVINGS) -> list[PkResult]:
    """:func:`pk_flutter` of one modal model at several flight conditions, solved together.

    ``conditions`` is a sequence of ``(gaf, density)`` pairs (a Mach number's
    :class:`TabulatedGaf` and an air density, kg/m^3 or the model's unit), each swept over the
    same ``velocities``. The sweeps are independent: each runs Eq. (3.12)'s continuation with
    its own step control, but at every round the pending trial step of every sweep (all its
    tracked roots at its next airspeed) is one batched k-iteration, each iteration one stacked
    :func:`numpy.linalg.eig` over all sweeps' unconverged roots (issue 23, "p-k batched"). The
    arithmetic of each root is that of its sweep alone, so result ``i`` equals
    ``pk_flutter(modal, *conditions[i], velocities, ...)``. The other arguments are
    :func:`pk_flutter`'s, shared by every condition.

    Returns
    -------
    list of :class:`PkResult`, one per condition, in order.

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.aero.gaf import TabulatedGaf
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> modal = ModalArrays(M=np.eye(2), K=np.diag([1.0, 4.0]), C=np.zeros((2, 2)), n_rigid=0)
    >>> ks = np.array([0.0, 1.0])
    >>> Q = np.array([[[0.0, 0.5], [-0.5, 0.0]]] * 2, complex)   # a circulatory coupling
    >>> gaf = TabulatedGaf(ks, Q, 1.0)
    >>> many = pk_flutter_many(modal, [(gaf, 1.0), (gaf, 2.0)], [0.5, 1.0])
    >>> one = pk_flutter(modal, gaf, 2.0, [0.5, 1.0])
    >>> bool(np.array_equal(many[1].p, one.p))
    True
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    U = _ascending("velocities", velocities)
    opts = _pk_options(max_iter, tol, step_fraction, min_mac, max_halvings, interpolation)
    try:
        pairs = [tuple(c) for c in conditions]
    except TypeError:
        raise TypeError("conditions must be a sequence of (gaf, density) pairs, got "
                        f"{type(conditions).__name__}") from None
    if not pairs or any(len(c) != 2 for c in pairs):
        raise ValueError("conditions must be a non-empty sequence of (gaf, density) pairs")
    lanes = []
    for i, (gaf, density) in enumerate(pairs):
        lanes.append(_pk_lane(m, gaf, positive(f"conditions[{i}] density", density), U,
                              include_rigid, interpolation, modes, f"conditions[{i}] "))
    runs = _run_lanes(_PkStack([ln.prob for ln in lanes]), U, [ln.start for ln in lanes],
                      *opts)
    results = []
    for ln, run in zip(lanes, runs):
        results.append(_pk_result(m, ln, U, run, include_rigid, opts))
    return results


def _pk_options(max_iter, tol, step_fraction, min_mac, max_halvings, interpolation):
    """pk_flutter's solver options, checked: (tol, max_iter, step_fraction, min_mac,
    max_halvings); errors name the argument and its range."""
    max_iter = _count("max_iter", max_iter)
    tol = positive("tol", tol)
    step_fraction = _fraction("step_fraction", step_fraction, 0.0, 1.0, low_open=True)
    min_mac = _fraction("min_mac", min_mac, 0.0, 1.0, high_open=True)
    max_halvings = _count("max_halvings", max_halvings, 0)
    if max_halvings > 30:
        raise ValueError(f"max_halvings must be an integer in [0, 30], got {max_halvings}")
    if interpolation not in ("linear", "cubic"):
        raise ValueError(f"interpolation must be 'linear' or 'cubic', got {interpolation!r}")
    return tol, max_iter, step_fraction, min_mac, max_halvings


@dataclass(frozen=True)
class _PkLane:
    """One p-k sweep's problem (:class:`_PkProblem`), structural circular frequencies w
    (ascending, rad/s), tracked ``modes`` and the structural roots it starts from."""

    prob: _PkProblem
    w: np.ndarray
    modes: np.ndarray
    start: _Roots
    mach: float | None
    b_ref: float


def _pk_lane(m: ModalArrays, gaf, rho: float, U: np.ndarray, include_rigid: bool,
             interpolation: str, modes, where: str = "") -> _PkLane:
    """The checked set-up of one sweep of :func:`pk_flutter` (``where`` prefixes the names of
    the arguments in errors, e.g. "conditions[2] ")."""
    _pressure_ok(rho, U)
    if not isinstance(gaf, TabulatedGaf):
        raise TypeError(f"{where}gaf must be a TabulatedGaf, got {type(gaf).__name__}")
    if gaf.Q.shape[1] != m.n_modes:
        raise ValueError(f"{where}gaf has {gaf.Q.shape[1]} modes, the modal model {m.n_modes}")
    M, K, C, _ = _elastic_part(m, gaf.Q, include_rigid)
    sel = slice(0, m.n_modes) if (include_rigid or m.n_rigid == 0) else slice(m.n_rigid,
                                                                               m.n_modes)
    g = TabulatedGaf(gaf.k, gaf.Q[:, sel, sel], gaf.b_ref, gaf.mach)
    prob = _PkProblem(M, K, C, g, rho, interpolation)
    w2, phi = linalg.eigh(K, M)
    w = np.sqrt(np.clip(w2, 0, None))
    order = np.argsort(w)
    w, phi = w[order], phi[:, order]
    modes = np.arange(M.shape[0]) if modes is None else np.atleast_1d(np.asarray(modes, int))
    if np.any(modes < 0) or np.any(modes >= M.shape[0]):
        raise ValueError(f"modes must be indices in [0, {M.shape[0] - 1}], got {modes}")
    return _PkLane(prob, w, modes, _structural_roots(w, phi, modes), gaf.mach, gaf.b_ref)


def _pk_result(m: ModalArrays, lane: _PkLane, U: np.ndarray, run, include_rigid: bool,
               opts) -> PkResult:
    """The :class:`PkResult` of one lane's path ``run`` = (path airspeeds, roots, forced)."""
    tol, max_iter, step_fraction, min_mac, _ = opts
    path_u, path, forced = run
    at = np.searchsorted(path_u, U)                       # the requested points on the path
    P = np.array([r.p for r in path])
    V = np.array([r.v for r in path])
    conv = np.array([r.ok for r in path])
    KK = np.array([r.k for r in path])
    n_r = m.n_rigid if include_rigid else 0
    _warn_unconverged(U, conv[at], lane.modes, n_r, max_iter, tol, int((~conv).sum()),
                      stacklevel=5)
    return PkResult(velocities=U, p=P[at], k=KK[at], vectors=V[at], converged=conv[at],
                    structural_frequencies_hz=lane.w[lane.modes] / (2 * np.pi),
                    density=lane.prob.rho, mach=lane.mach, b_ref=lane.b_ref,
                    modes=lane.modes, n_rigid=n_r, path_velocities=path_u, path_p=P,
                    path_vectors=V, path_converged=conv, step_fraction=step_fraction,
                    min_mac=min_mac, forced_steps=forced)


def _fraction(name: str, value, lo: float, hi: float, low_open: bool = False,
              high_open: bool = False) -> float:
    """A real number in the interval lo..hi (ends open as asked), else TypeError/ValueError
    naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    ok = (lo < v if low_open else lo <= v) and (v < hi if high_open else v <= hi)
    if not ok:
        raise ValueError(f"{name} must be in {'(' if low_open else '['}{lo:g}, {hi:g}"
                         f"{')' if high_open else ']'}, got {value!r}")
    return v


def _structural_roots(w: np.ndarray, phi: np.ndarray, modes: np.ndarray) -> _Roots:
    """The start of the continuation, U = 0: p = i omega_j and the mode shapes of the tracked
    modes; the spacing is the distance to the nearest other structural root (floored at 1e-9
    of the largest, so that repeated frequencies still allow a step)."""
    n = w.size
    d = np.abs(w[:, None] - w[None, :]) + np.diag(np.full(n, np.inf))
    spacing = np.maximum(d.min(axis=1), 1e-9 * max(float(w.max()), 1e-300))
    nt = modes.size
    return _Roots(1j * w[modes], phi[:, modes].T.astype(complex), np.zeros(nt),
                  np.ones(nt, bool), spacing[modes])


def _pk_path(prob, U, start: _Roots, tol, max_iter, fraction, min_mac, max_halvings):
    """The continuation from U = 0 through every requested airspeed: (path airspeeds,
    [roots per path point], forced steps). Points below U[0] (the way from the structural
    roots) are not kept. A generator of trial steps like :func:`_continue` (run it with
    :func:`_run_lanes`)."""
    path_u, path, forced = [], [], 0
    ua, prev = 0.0, start
    for u in U:
        points, nf = yield from _continue(prob, ua, prev, float(u), tol, max_iter, fraction,
                                          min_mac, max_halvings)
        forced += nf
        if ua == 0.0:
            points = points[-1:]
        path_u += [p[0] for p in points]
        path += [p[1] for p in points]
        ua, prev = float(u), points[-1][1]
    path_u = np.array(path_u)
    return path_u, path, forced


def _run_lanes(stack: _PkStack, U, starts, tol, max_iter, fraction, min_mac, max_halvings):
    """The p-k paths (:func:`_pk_path`) of every lane of ``stack`` from its structural roots
    ``starts[l]``, advanced together: at each round, the pending trial step of every unfinished
    lane (its tracked roots continued to its next airspeed) is one batched k-iteration
    (:meth:`_PkStack.solve_rows`). Each lane's step control runs on its own, so a lane's path
    is the one it takes alone. Returns [(path airspeeds, roots, forced steps)] per lane."""
    gens = [_pk_path(prob, U, start, tol, max_iter, fraction, min_mac, max_halvings)
            for prob, start in zip(stack.probs, starts)]

    def solve(lanes, requests):
        sizes = [prev.p.size for _, prev in requests]
        rows = np.repeat(np.array(lanes, int), sizes)
        u_rows = np.repeat(np.array([u for u, _ in requests], float), sizes)
        omega = np.concatenate([np.abs(prev.p.imag) for _, prev in requests])
        refs = np.concatenate([prev.v for _, prev in requests])
        solved = stack.solve_rows(rows, u_rows, omega, refs, tol, max_iter)
        ends = np.cumsum(sizes).tolist()
        return [_Roots(*(a[e - n:e].copy() for a in solved)) for e, n in zip(ends, sizes)]

    return _lockstep(gens, solve)


def _lockstep(gens, solve):
    """Run generators in lock-step: each yields a request and is sent its answer; at each
    round ``solve(lanes, requests)`` answers the pending request of every unfinished generator
    at once (a list, in order). Returns the generators' return values, in order."""
    out, pending = [None] * len(gens), {}

    def advance(lane, value):
        try:
            pending[lane] = gens[lane].send(value)
        except StopIteration as stop:
            out[lane] = stop.value
            pending.pop(lane, None)

    for lane in range(len(gens)):
        advance(lane, None)
    while pending:
        lanes = list(pending)
        for lane, answer in zip(lanes, solve(lanes, [pending[ln] for ln in lanes])):
            advance(lane, answer)
    return out


def _warn_unconverged(U, conv, modes, n_r, max_iter, tol, n_path_bad,
                      stacklevel: int = 4):
    """FlutterConvergenceWarning naming the (mode, airspeed) points whose k-iteration did not
    converge (``conv`` at the requested points; ``n_path_bad`` counts the whole path)."""
    if conv.all() and n_path_bad == 0:
        return
    bad = np.argwhere(~conv)
    listed = ", ".join(f"{mode_label(int(modes[jt]), n_r)} at U = {U[i]:.6g} m/s"
                       for i, jt in bad[:8])
    more = f" and {len(bad) - 8} more" if len(bad) > 8 else ""
    sub = n_path_bad - len(bad)
    if len(bad):
        where = (f"at {len(bad)} of {conv.size} requested points"
                 + (f" (and {sub} sub-step points of the continuation)" if sub > 0 else "")
                 + f": {listed}{more}; their roots are the last iterate (PkResult.converged "
                 "is False there): treat them as approximate")
    else:               # only between the requested points: their results are converged
        where = (f"at {sub} sub-step points of the continuation between the requested "
                 f"velocities (all {conv.size} requested points converged); the tracking "
                 "through those steps used the last iterate")
    # Issue 30: the advice names the one option that takes it (pk_flutter's max_iter; a case
    # file has no such key), and every number its unit (tol is a relative change: no unit).
    warnings.warn(f"p-k: the k-iteration did not converge within {max_iter} iterations "
                  f"(relative frequency change still above {tol:g}) {where}; from Python, "
                  "pk_flutter(..., max_iter=N) allows more iterations",
                  FlutterConvergenceWarning, stacklevel=stacklevel)  # past @small_dense


def _crossings(U, sigma, freq_hz, real_mask, tol: float = 0.0):
    """Onsets of instability along one branch: (i, U*, f*, kind, at_first_point) tuples.

    Unstable means sigma > tol. A branch unstable at the first point gives (0, U[0], f[0], kind,
    True) ("at or below U0"); each later stable-to-unstable change between i-1 and i gives the
    linear interpolation to sigma = tol (clipped to [U[i-1], U[i]]).
    """
    unstable = np.asarray(sigma) > tol
    out = []
    if unstable.size and unstable[0]:
        kind = "divergence" if real_mask[0] else "flutter"
        out.append((0, float(U[0]), float(freq_hz[0]), kind, True))
    for i in range(1, len(U)):
        if not unstable[i - 1] and unstable[i]:
            t = float(np.clip((tol - sigma[i - 1]) / (sigma[i] - sigma[i - 1]), 0.0, 1.0))
            us = U[i - 1] + t * (U[i] - U[i - 1])
            f = freq_hz[i - 1] + t * (freq_hz[i] - freq_hz[i - 1])
            kind = "divergence" if real_mask[i] else "flutter"
            out.append((i, us, f, kind, False))
    return out


def pk_instabilities(result: PkResult, modal=None, gaf: TabulatedGaf | None = None,
                     refine: bool = True, include_rigid: bool = False,
                     interpolation: str = "linear") -> list[Instability]:
    """All flutter / divergence onsets of a p-k sweep, sorted by speed; one per physical root.

    The crossings are bracketed on the continuation path (``PkResult.path_velocities``: the
    requested velocities and the step control's sub-steps), interpolated linearly to Re p = 0
    and, with ``refine`` (needs the ``modal`` and ``gaf`` of the sweep), refined by Brent's
    method on Re(p)(U) of the tracked root inside the bracketing sub-step, continued from its
    unstable end (``xtol = REFINE_RTOL * U``, stated in ``Instability.speed_tolerance``). A
    root unstable at the first airspeed (Re p > :func:`crossing_tolerance`) is returned with
    ``at_first_point=True`` and ``speed = velocities[0]`` (flutter or divergence at or below
    U0). Two tracked columns that report the same crossing (same speed within tolerance, same
    frequency, correlated eigenvectors) give one instability, the lower column's.
    """
    prob = _refine_problem(result, modal, gaf, include_rigid, interpolation) if refine else None
    (found,) = _lockstep([_instabilities(result, prob)], _refine_answers([prob]))
    return found


def pk_instabilities_many(results, modal, gafs, refine: bool = True,
                          include_rigid: bool = False, interpolation: str = "linear"
                          ) -> list[list[Instability]]:
    """:func:`pk_instabilities` of several sweeps of one modal model (``results[i]`` the
    sweep of ``gafs[i]``, e.g. from :func:`pk_flutter_many`), the crossings of all sweeps
    refined together: every Brent iteration's k-iteration of every sweep is one batched
    eigen call (issue 23). Brent's method runs step for step as
    :func:`scipy.optimize.brentq` (:func:`_brent`), so list ``i`` equals
    ``pk_instabilities(results[i], modal, gafs[i], ...)``.

    Returns
    -------
    list of lists of :class:`Instability`, one list per sweep, each sorted by speed.

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.aero.gaf import TabulatedGaf
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> modal = ModalArrays(M=np.eye(2), K=np.diag([1.0, 4.0]), C=np.zeros((2, 2)), n_rigid=0)
    >>> gaf = TabulatedGaf(np.array([0.0, 1.0]), np.array([[[0, 1.0], [-2.0, 0]]] * 2), 1.0)
    >>> res = pk_flutter_many(modal, [(gaf, 1.0), (gaf, 2.0)], np.linspace(0.5, 3.0, 11))
    >>> [[round(s.speed, 4) for s in found]
    ...  for found in pk_instabilities_many(res, modal, [gaf, gaf])]
    [[1.4565], [1.0299]]

    (the hand-derived coalescence U_f = sqrt(2 q_f / rho), q_f = |k1 - k2| / (2 sqrt(-a d))
    = 1.0607 for K = diag(k1, k2), Q = [[0, a], [d, 0]]: 1.4565 and 1.0299).
    """
    results, gafs = list(results), list(gafs)
    if len(results) != len(gafs):
        raise ValueError(f"gafs must hold one TabulatedGaf per result ({len(results)}), got "
                         f"{len(gafs)}")
    probs = [_refine_problem(r, modal, g, include_rigid, interpolation) if refine else None
             for r, g in zip(results, gafs)]
    return _lockstep([_instabilities(r, p) for r, p in zip(results, probs)],
                     _refine_answers(probs))


def _refine_problem(result: PkResult, modal, gaf, include_rigid: bool, interpolation: str):
    """The :class:`_PkProblem` on which a sweep's crossings are refined (None without
    ``modal`` or ``gaf``)."""
    if modal is None or gaf is None:
        return None
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    M, K, C, _ = _elastic_part(m, gaf.Q, include_rigid)
    sel = slice(0, m.n_modes) if (include_rigid or m.n_rigid == 0) else slice(
        m.n_rigid, m.n_modes)
    return _PkProblem(M, K, C, TabulatedGaf(gaf.k, gaf.Q[:, sel, sel], gaf.b_ref),
                      result.density, interpolation)


def _refine_answers(probs):
    """The ``solve`` of :func:`_lockstep` for the refinement: request (u, w0, v) of lane l is
    answered by (p, vector) of the root converged from (w0, v) at u on ``probs[l]``
    (:meth:`_PkProblem.solve_mode`); the pending requests of all lanes are one batched
    k-iteration when the problems stack (one :class:`_PkStack`)."""
    live = [p for p in probs if p is not None]
    try:
        stack = _PkStack(live) if live else None
        where = {id(p): i for i, p in enumerate(live)}
    except ValueError:                      # lanes of different sizes: one by one
        stack = None

    def solve(lanes, requests):
        if stack is None:
            return [probs[ln].solve_mode(u, w0, v)[:2] for ln, (u, w0, v) in
                    zip(lanes, requests)]
        rows = np.array([where[id(probs[ln])] for ln in lanes], int)
        p, vec, _, _, _ = stack.solve_rows(rows, np.array([u for u, _, _ in requests], float),
                                           np.array([w0 for _, w0, _ in requests], float),
                                           np.array([v for _, _, v in requests]))
        return list(zip(p, vec))

    return solve


def _instabilities(result: PkResult, prob: _PkProblem | None):
    """The body of :func:`pk_instabilities` as a generator of refinement requests
    (:func:`_refine_crossing`; none when ``prob`` is None). Returns the instabilities."""
    found = []
    U, Pp, Vp, _ = result.path()
    tol = crossing_tolerance(result.p)
    for jt in range(Pp.shape[1]):
        p = Pp[:, jt]
        real_mask = np.abs(p.imag) <= 1e-6 * np.maximum(np.abs(p), 1e-12)
        for i, us, f, kind, first in _crossings(U, p.real, np.abs(p.imag) / (2 * np.pi),
                                                real_mask, tol):
            vec = Vp[i, jt]
            if first:
                found.append(Instability(kind=kind, mode=result.mode_index(jt), speed=float(us),
                                         frequency_hz=0.0 if kind == "divergence" else float(f),
                                         vector=vec, method="p-k", at_first_point=True,
                                         n_rigid=result.n_rigid, speed_tolerance=float(us)))
                continue
            spread = float(U[i] - U[i - 1])
            if prob is not None:
                refined = yield from _refine_on_path(result, U, i, jt, tol)
                if refined is not None:
                    us, f, vec, divergent, spread = refined
                    kind = "divergence" if divergent else kind
            found.append(Instability(kind=kind, mode=result.mode_index(jt), speed=float(us),
                                     frequency_hz=0.0 if kind == "divergence" else float(f),
                                     vector=vec, method="p-k", n_rigid=result.n_rigid,
                                     speed_tolerance=spread))
    return _one_per_root(sorted(found, key=lambda s: s.speed))


def _refine_on_path(result: PkResult, U: np.ndarray, i: int, jt: int, tol: float):
    """The crossing of column ``jt`` bracketed by path points i-1 and i, refined
    (:func:`_refine_crossing`). When the bracket is a sub-step, the refinement over the whole
    requested step that holds it (from the requested end, as a sweep without sub-steps does) is
    tried first and kept when it lands inside the sub-step bracket: the same crossing, and the
    same number bit for bit as without step control; else the sub-step bracket is refined.
    A generator of :func:`_refine_crossing`'s requests."""
    _, Pp, Vp, _ = result.path()
    Ur = result.velocities
    r = int(np.searchsorted(Ur, U[i]))
    if r > 0 and not (U[i - 1] == Ur[r - 1] and U[i] == Ur[r]):
        wide = yield from _refine_crossing(Ur[r - 1], Ur[r], result.p[r, jt],
                                           result.vectors[r, jt], tol)
        if wide is not None and U[i - 1] - wide[4] <= wide[0] <= U[i] + wide[4]:
            return wide
    return (yield from _refine_crossing(U[i - 1], U[i], Pp[i, jt], Vp[i, jt], tol))


def _refine_crossing(ua: float, ub: float, p_b: complex, v_b: np.ndarray, tol: float):
    """Brent's method on Re p(U) - tol in [ua, ub], the root continued from its unstable end
    (p_b, v_b at ub: at an undamped coalescence the sub-critical vector correlates equally with
    the stable and the unstable partner). A generator: each evaluation yields the request
    ``(u, w0, v_b)`` (converge the root from circular frequency w0 = |Im p_b| and vector v_b at
    airspeed u) and is sent back ``(p, vector)``. Returns (U*, f* Hz, vector, divergence?,
    xtol) or None when Re p does not change sign in the bracket."""
    w0 = abs(p_b.imag)
    xtol = REFINE_RTOL * ub
    brent = _brent(float(ua), float(ub), xtol)
    u = next(brent)
    try:
        while True:
            p, _ = yield u, w0, v_b
            # Re p - tol: an undamped sub-critical root (Re = 0 +- rounding) stays < 0
            u = brent.send(float(p.real - tol))
    except StopIteration as stop:
        us = stop.value
    if us is None:
        return None
    pz, vec = yield us, w0, v_b
    f = abs(pz.imag) / (2 * np.pi)
    divergent = abs(pz.imag) <= 1e-6 * max(abs(pz), 1e-9) and f < 1e-6
    return float(us), f, vec, divergent, float(xtol + 4 * np.finfo(float).eps * abs(us))


def _brent(xa: float, xb: float, xtol: float, rtol: float = 4 * np.finfo(float).eps,
           maxiter: int = 100):
    """Brent's root finder (R. P. Brent, "Algorithms for Minimization without Derivatives",
    Prentice-Hall 1973, ch. 4: bisection safeguarding inverse quadratic / linear
    interpolation) as a generator: it yields each abscissa x and is sent f(x); it returns the
    root, or None when f(xa) and f(xb) have the same sign. The steps and the stopping test
    (|half bracket| < (xtol + rtol |x|) / 2) are those of :func:`scipy.optimize.brentq` with
    its default rtol and maxiter, so that it visits the same abscissae and returns the same
    root (a batched refinement then equals the one-sweep one). RuntimeError when maxiter is
    spent, as brentq's."""
    xpre, xcur = xa, xb
    fpre = yield xpre
    fcur = yield xcur
    if fpre * fcur > 0:
        return None
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre * fcur < 0:
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        spre, scur = _brent_step(xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, sbis, delta)
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = yield xcur
    raise RuntimeError(f"Brent's method did not converge in {maxiter} iterations")


def _brent_step(xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, sbis, delta):
    """One step choice of :func:`_brent`: (previous step, step) -- the interpolated step when
    it is short enough, else bisection."""
    if abs(spre) > delta and abs(fcur) < abs(fpre):
        if xpre == xblk:                                        # secant
            stry = -fcur * (xcur - xpre) / (fcur - fpre)
        else:                                                   # inverse quadratic
            dpre = (fpre - fcur) / (xpre - xcur)
            dblk = (fblk - fcur) / (xblk - xcur)
            stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
        if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
            return scur, stry
    return sbis, sbis


def _one_per_root(found: list[Instability]) -> list[Instability]:
    """Drop an instability that repeats an earlier one of the list: same kind and start flag,
    speeds within their tolerances, frequencies within 1e-6 relative, eigenvectors correlated
    above 0.99 (two tracked columns on one physical root)."""
    out = []
    for s in found:
        if not any(_same_instability(s, t) for t in out):
            out.append(s)
    return out


def _same_instability(a: Instability, b: Instability) -> bool:
    if a.kind != b.kind or a.at_first_point != b.at_first_point:
        return False
    if abs(a.speed - b.speed) > a.speed_tolerance + b.speed_tolerance + 1e-12 * abs(a.speed):
        return False
    if abs(a.frequency_hz - b.frequency_hz) > 1e-6 * max(a.frequency_hz, b.frequency_hz, 1e-12):
        return False
    if a.vector is None or b.vector is None or a.vector.size == 0 or b.vector.size == 0:
        return True
    return bool(_mac(a.vector, b.vector[:, None])[0] > 0.99)


def first_of(instabilities: list[Instability], kind: str | None = None) -> Instability | None:
    """The lowest-speed instability of ``kind`` ('flutter', 'divergence' or None for any)."""
    for s in sorted(instabilities, key=lambda s: s.speed):
        if kind is None or s.kind == kind:
            return s
    return None


def divergence_speeds(modal, Q0: np.ndarray, density: float, include_rigid: bool = False
                      ) -> np.ndarray:
    """Static divergence speeds: det(K - q Q^R(0)) = 0, i.e. the positive real eigenvalues q of
    K x = q Q^R(0) x, U = sqrt(2 q / rho). Returns ascending speeds (empty if none).

    ``Q0`` is the (n, n) GAF at (or nearest) k = 0 (rigid modes first); rigid modes are held
    unless ``include_rigid``.
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    rho = float(positive_array("density", density)[0])
    if Q0 is None:
        raise ArgumentTypeError(f"Q0 must be the ({m.n_modes}, {m.n_modes}) GAF matrix at "
                                "k = 0 (e.g. TabulatedGaf.Q[0]), got None")
    Q0 = finite_array("Q0", Q0, complex_values=True)
    if Q0.shape != (m.n_modes, m.n_modes):
        raise ValueError(f"Q0 must be ({m.n_modes}, {m.n_modes}) like the modal model, got "
                         f"shape {Q0.shape}")
    _, K, _, Qs = _elastic_part(m, Q0[None], include_rigid)
    mu = linalg.eigvals(Qs[0].real, K)                # Q x = mu K x, q = 1/mu
    mu = mu[np.abs(mu.imag) <= 1e-9 * np.maximum(np.abs(mu), 1e-300)].real
    q = 1.0 / mu[mu > 0]
    return np.sort(np.sqrt(2 * q / rho))


# --------------------------------------------------------------------------------------------
# match point (Section 3.3.1.1)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MatchPointRow:
    """One row of Tables 9-10: Mach, altitude (m), density, speed of sound, the first flutter
    speed (None if none below the sweep top) and frequency, U_eq (Eq. 3.10) and M_eq = U_f/a.

    ``at_first_point``: the sweep was already unstable at its first airspeed, so ``speed``,
    ``equivalent_speed`` and ``mach_equivalent`` are upper bounds (flutter at or below U0), not
    values; :func:`matched_mach` does not interpolate through such rows.
    """

    mach: float
    altitude: float
    density: float
    speed_of_sound: float
    speed: float | None
    frequency_hz: float | None
    equivalent_speed: float | None
    mach_equivalent: float | None
    kind: str | None = None
    at_first_point: bool = False

    def describe(self, unit: str = "m/s") -> str:
        """'none in the sweep', 'flutter at 218.1 m/s' or 'unstable at the first point of the
        sweep: flutter at or below 250 m/s'."""
        if self.speed is None:
            return "no instability in the sweep"
        if self.at_first_point:
            return (f"unstable at the first point of the sweep: {self.kind} at or below "
                    f"{self.speed:.6g} {unit}")
        return f"{self.kind} at {self.speed:.6g} {unit}"


def match_point_table(modal, gaf_for_mach, machs, altitudes, velocities, kind="flutter",
                      densities=None) -> list[MatchPointRow]:
    """p-k over Mach x altitude pairs (thesis Tables 9-10) with the match check of 3.3.1.1.

    ``gaf_for_mach(mach) -> TabulatedGaf``; densities default to the 1976 standard atmosphere
    (pass ``densities`` (per altitude) to use others, e.g. the thesis's). ``kind`` selects
    'flutter', 'divergence' or None (first instability of any kind). A condition unstable at the
    first airspeed gives a row with ``at_first_point=True`` (and a warning naming it).
    """

    if kind not in ("flutter", "divergence", None):
        raise ValueError(f"kind must be 'flutter', 'divergence' or None, got {kind!r}")
    altitudes = list(np.atleast_1d(altitudes))
    if densities is not None and len(np.atleast_1d(densities)) != len(altitudes):
        raise ValueError(f"densities must have one value per altitude ({len(altitudes)}), "
                         f"got {len(np.atleast_1d(densities))}")
    rows, points = [], []
    for mach in np.atleast_1d(machs):
        g = gaf_for_mach(mach)
        for ia, h in enumerate(altitudes):
            atm = standard_atmosphere(h)
            rho = float(atm.density) if densities is None else positive(
                f"densities[{ia}]", np.atleast_1d(densities)[ia])
            points.append((mach, h, g, rho, float(atm.speed_of_sound)))
    # every Mach x altitude sweep solved together (issue 23), each equal to its pk_flutter
    results = pk_flutter_many(modal, [(g, rho) for _, _, g, rho, _ in points], velocities)
    found = pk_instabilities_many(results, modal, [g for _, _, g, _, _ in points])
    for (mach, h, g, rho, a), insts in zip(points, found):
        inst = first_of(insts, kind)
        if inst is None:
            rows.append(MatchPointRow(mach, h, rho, a, None, None, None, None))
        else:
            ueq = inst.speed * np.sqrt(rho / 1.225)
            rows.append(MatchPointRow(mach, h, rho, a, inst.speed, inst.frequency_hz,
                                      float(ueq), inst.speed / a, inst.kind,
                                      inst.at_first_point))
            if inst.at_first_point:
                warnings.warn(f"match point Mach {mach:g}, altitude {h:g} m: "
                              f"{inst.describe()}, only a bound; velocities starting "
                              f"below {float(np.atleast_1d(velocities)[0]):g} m/s "
                              "(match_point_table's argument) locate it",
                              RuntimeWarning, stacklevel=2)
    return rows


def matched_mach(rows: list[MatchPointRow], altitude: float) -> float | None:
    """Mach at which the flutter Mach M_eq equals the analysis Mach, by linear interpolation of
    M_eq - M over the analysed Machs at ``altitude`` (None if no sign change or no flutter).

    Rows flagged ``at_first_point`` (flutter at or below the sweep's first speed: only an upper
    bound of M_eq) are not interpolated through; if the match lies next to such a row the
    result is None and a warning says so.
    """
    here = [r for r in rows if r.altitude == altitude and r.mach_equivalent is not None]
    bounded = sorted(r.mach for r in here if r.at_first_point)
    pts = sorted((r.mach, r.mach_equivalent) for r in here if not r.at_first_point)
    for (m0, e0), (m1, e1) in zip(pts[:-1], pts[1:]):
        d0, d1 = e0 - m0, e1 - m1
        if d0 == 0:
            return m0
        if d0 * d1 <= 0:
            return m0 + (m1 - m0) * d0 / (d0 - d1)
    if bounded:
        warnings.warn(f"matched_mach at altitude {altitude:g} m: the sweep was unstable at its "
                      f"first point for Mach {', '.join(f'{b:g}' for b in bounded)} (flutter at "
                      "or below its first airspeed); the match cannot be located there",
                      RuntimeWarning,
                      stacklevel=2)
    return None


# --------------------------------------------------------------------------------------------
# root locus (Section 3.3.2)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RootLocusResult:
    """Eigenvalues of A_sys over airspeed.

    velocities (n_v,), eigenvalues (n_v, n_z) all roots, elastic (n_v, n_s) the aeroelastic roots
    continued from the structural roots (upper half plane or real axis), max_real (n_v,) the
    largest real part of all roots, density.
    """

    velocities: np.ndarray
    eigenvalues: np.ndarray
    elastic: np.ndarray
    max_real: np.ndarray
    density: float

    @property
    def damping_ratio(self) -> np.ndarray:
        """Damping ratio xi = -Re lambda / |lambda| of Eq. (3.13) for the aeroelastic roots
        (> 0 stable)."""
        return damping_ratio(self.elastic)

    @property
    def damping_g(self) -> np.ndarray:
        """V-g damping g = 2 Re lambda / |Im lambda| of the aeroelastic roots (> 0 unstable,
        clipped to +-2; :func:`asekit.util.conventions.vg_damping`)."""
        return vg_damping(self.elastic)

    @property
    def mode_labels(self) -> list[str]:
        """'mode 1', 'mode 2', ...: the aeroelastic roots are the elastic modes'."""
        return [mode_label(j) for j in range(self.elastic.shape[1])]

    @property
    def natural_frequency_hz(self) -> np.ndarray:
        return np.abs(self.elastic) / (2 * np.pi)

    @property
    def frequency_hz(self) -> np.ndarray:
        return np.abs(self.elastic.imag) / (2 * np.pi)


def _eig_structural(mats, ns):
    lam, vec = np.linalg.eig(mats.A)
    return lam, vec[:ns]


@small_dense
def root_locus(modal, rfa, density: float, velocities, substeps: int | None = None
               ) -> RootLocusResult:
    """Eigenvalues of A_sys (Eq. 2.63) over ``velocities`` with the aeroelastic roots tracked.

    Tracking starts from the structural roots at a speed 1e-3 of the first velocity and
    continues in small steps (``substeps`` between list points; by default enough that U
    changes by at most 5 % per step); each step assigns the new roots to the
    branches by a cost combining eigenvalue distance and eigenvector correlation (Hungarian
    assignment), so lag roots, which start near the origin on the real axis, are never taken
    for aeroelastic roots.
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    rho = positive("density", density)
    U = _ascending("velocities", velocities)
    _pressure_ok(rho, U)
    if substeps is not None:
        substeps = _count("substeps", substeps)
    ns = m.n_elastic
    s = slice(m.n_rigid, m.n_modes)
    w2, phi = linalg.eigh(m.K[s, s], m.M[s, s])
    order = np.argsort(w2)
    lam_prev = 1j * np.sqrt(np.clip(w2[order], 0, None))
    vec_prev = phi[:, order].astype(complex)
    # continuation path
    path = list(np.geomspace(1e-3 * U[0], U[0], 25)[:-1])
    marks = []
    for i, u in enumerate(U):
        if i > 0:
            n_sub = substeps if substeps is not None else int(
                np.ceil(np.log(U[i] / U[i - 1]) / np.log(1.05)))
            path += list(np.linspace(U[i - 1], U[i], max(n_sub, 1) + 1)[1:-1])
        marks.append(len(path))
        path.append(u)
    if len(path) > MAX_STEPS // 100:
        raise ValueError(f"root_locus would solve {len(path)} eigenproblems (velocities "
                         f"{U.size}, substeps {substeps}); limit {MAX_STEPS // 100}: use fewer "
                         "velocities or substeps")
    from scipy.optimize import linear_sum_assignment
    all_eigs, elastic = [], []
    for ip, u in enumerate(path):
        mats = aeroelastic_matrices(m, rfa, rho, u)
        lam, vec = _eig_structural(mats, ns)
        up = lam.imag >= -1e-9 * np.maximum(np.abs(lam), 1.0)
        lam_u, vec_u = lam[up], vec[:, up]
        scale = np.maximum(np.abs(lam_prev), 1e-6 * np.abs(lam_prev).max() + 1e-12)
        cost = np.zeros((ns, lam_u.size))
        for j in range(ns):
            cost[j] = (np.abs(lam_u - lam_prev[j]) / scale[j]
                       + (1 - _mac(vec_prev[:, j], vec_u)))
        rows, cols = linear_sum_assignment(cost)
        new_lam = lam_prev.copy()
        new_vec = vec_prev.copy()
        new_lam[rows] = lam_u[cols]
        new_vec[:, rows] = vec_u[:, cols]
        lam_prev, vec_prev = new_lam, new_vec
        if ip in marks:
            all_eigs.append(lam)
            elastic.append(new_lam.copy())
    eig_arr = np.array(all_eigs)
    return RootLocusResult(velocities=U, eigenvalues=eig_arr, elastic=np.array(elastic),
                           max_real=eig_arr.real.max(axis=1), density=rho)


def root_locus_instabilities(result: RootLocusResult, modal=None, rfa=None,
                             refine: bool = True) -> list[Instability]:
    """Crossings of the aeroelastic roots into Re > 0, interpolated (and, given ``modal`` and
    ``rfa``, refined by Brent's method on the real part of the eigenvalue of A_sys nearest the
    crossing root). A root unstable at the first airspeed (Re > :func:`crossing_tolerance`) is
    returned with ``at_first_point=True`` and ``speed = velocities[0]`` (at or below U0)."""
    U = result.velocities
    out = []
    tol = crossing_tolerance(result.elastic)
    for j in range(result.elastic.shape[1]):
        lam = result.elastic[:, j]
        real_mask = np.abs(lam.imag) <= 1e-6 * np.maximum(np.abs(lam), 1e-12)
        for i, us, f, kind, first in _crossings(U, lam.real, np.abs(lam.imag) / (2 * np.pi),
                                                real_mask, tol):
            if first:
                out.append(Instability(kind=kind, mode=j, speed=float(us),
                                       frequency_hz=0.0 if kind == "divergence" else float(f),
                                       method="root locus", at_first_point=True))
                continue
            if refine and modal is not None and rfa is not None:
                # follow the tracked branch: the eigenvalue nearest its linear interpolation
                # between the sweep points (at a coalescence the sub-critical root alone would
                # be equidistant from the stable and the unstable partner)
                def pick_at(u, i=i, lam=lam):
                    ev = np.linalg.eigvals(aeroelastic_matrices(modal, rfa, result.density,
                                                                u).A)
                    ev = ev[ev.imag >= -1e-9]
                    t = (u - U[i - 1]) / (U[i] - U[i - 1])
                    return ev[np.argmin(np.abs(ev - (lam[i - 1] + t * (lam[i] - lam[i - 1]))))]

                def re_lam(u):
                    return pick_at(u).real - tol     # undamped: Re = 0 +- rounding stays < 0

                try:
                    us = optimize.brentq(re_lam, U[i - 1], U[i], xtol=1e-6 * U[i])
                    f = abs(pick_at(us).imag) / (2 * np.pi)
                except ValueError:
                    pass
            out.append(Instability(kind=kind, mode=j, speed=float(us),
                                   frequency_hz=0.0 if kind == "divergence" else float(f),
                                   method="root locus"))
    return sorted(out, key=lambda s: s.speed)


# --------------------------------------------------------------------------------------------
# time domain (Section 3.3.3)
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TimeResponse:
    """Free response z(t) of z' = A_sys z: ``t`` (n_t,), ``z`` (n_t, n_z), ``steps`` (accepted
    step sizes of the integrator, empty for the exact solution), ``method``."""

    t: np.ndarray
    z: np.ndarray
    steps: np.ndarray
    method: str


def initial_state(n_states: int, coordinate: int = 1) -> np.ndarray:
    """Eq. (3.15) initial condition: all zero except elastic coordinate ``coordinate``
    (0-based; the thesis used the second, index 1) set to one."""
    z0 = np.zeros(n_states)
    if not 0 <= coordinate < n_states:
        raise ValueError(f"coordinate must be in [0, {n_states - 1}], got {coordinate}")
    z0[coordinate] = 1.0
    return z0


@small_dense
def simulate_free_response(A: np.ndarray, z0: np.ndarray, t_end: float = 0.25,
                           max_step: float = 1e-4, method: str = "RK45", n_out: int = 2501,
                           rtol: float = 1e-6, atol: float = 1e-9) -> TimeResponse:
    """Integrate Eq. (3.14) z' = A z from z0 over [0, t_end] s.

    ``method="RK45"`` (or any scipy solve_ivp method) with ``max_step`` (s; the thesis capped
    ode45's step at 1e-4 s), or ``method="exact"``: the matrix exponential, z(t_j) =
    expm(A dt)^j z0 on a uniform grid of ``n_out`` points.

    Raises ValueError (before any work) when the record would need more than ``MAX_STEPS``
    steps (t_end / max_step) or output samples (n_out), naming the estimate and the knob.
    """
    from scipy.integrate import solve_ivp

    A = np.asarray(A, dtype=float)
    z0 = np.asarray(z0, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or z0.shape != (A.shape[0],):
        raise ValueError(f"A must be square (n, n) and z0 (n,); got A {A.shape}, z0 {z0.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(z0))):
        raise ValueError("A and z0 must be finite")
    t_end = positive("t_end", t_end)
    n_out = _count("n_out", n_out, 2)
    if n_out > MAX_STEPS:
        raise ValueError(f"n_out = {n_out} output samples exceeds the limit {MAX_STEPS}; "
                         "lower n_out")
    t = np.linspace(0.0, t_end, n_out)
    if method == "exact":
        E = linalg.expm(A * (t[1] - t[0]))
        z = np.empty((t.size, z0.size))
        z[0] = z0
        for j in range(1, t.size):
            z[j] = E @ z[j - 1]
        return TimeResponse(t=t, z=z, steps=np.array([]), method="exact")
    max_step = positive("max_step", max_step)
    if t_end / max_step > MAX_STEPS:
        raise ValueError(f"t_end / max_step = {t_end / max_step:.3g} steps exceeds the limit "
                         f"{MAX_STEPS}; raise max_step or shorten t_end (or use "
                         "method='exact')")
    extra = {"jac": A} if method in ("Radau", "BDF", "LSODA") else {}
    sol = solve_ivp(lambda _t, y: A @ y, (0.0, t_end), z0, method=method, t_eval=t,
                    max_step=max_step, rtol=rtol, atol=atol, **extra)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    # accepted step sizes are not returned by solve_ivp's t_eval output: rerun cheaply
    sol_steps = solve_ivp(lambda _t, y: A @ y, (0.0, t_end), z0, method=method,
                          max_step=max_step, rtol=rtol, atol=atol)
    return TimeResponse(t=sol.t, z=sol.y.T, steps=np.diff(sol_steps.t), method=method)


def growth_rate(t: np.ndarray, y: np.ndarray, window: float) -> float:
    """Exponential growth rate (1/s) of a response: slope of log(max |y| per window) over the
    second half of the record (windows of ``window`` s, at least a period of the slowest
    oscillation). Negative = decaying, positive = growing. ``y`` may be (n_t,) or (n_t, m)
    (its row norms are used).

    Raises ValueError if ``window`` is not > 0, the record holds fewer than 4 windows, or more
    windows than samples (a window shorter than the sampling step measures nothing).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y)
    if t.ndim != 1 or t.size < 2 or y.shape[0] != t.size:
        raise ValueError(f"t must be (n_t,) with n_t >= 2 and y (n_t, ...); got t {t.shape}, "
                         f"y {y.shape}")
    window = positive("window", window)
    n_win = (t[-1] - t[0]) / window
    if n_win > t.size:
        raise ValueError(f"window = {window:g} s is shorter than the sampling step "
                         f"({(t[-1] - t[0]) / (t.size - 1):g} s): {n_win:.3g} windows for "
                         f"{t.size} samples; use a window of at least a period")
    mag = np.abs(y) if y.ndim == 1 else np.linalg.norm(y.reshape(t.size, -1), axis=1)
    if not np.all(np.isfinite(mag)):
        raise ValueError("y holds non-finite values (the response overflowed: shorten t_end)")
    edges = np.arange(t[0], t[-1] + 1e-15, window)
    centers, peaks = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (t >= a) & (t < b)
        if np.any(sel):
            j = np.argmax(mag[sel])
            centers.append(t[sel][j])
            peaks.append(mag[sel][j])
    centers, peaks = np.array(centers), np.array(peaks)
    half = centers >= t[0] + 0.5 * (t[-1] - t[0])
    if half.sum() < 2:
        raise ValueError(f"record too short for the window: need at least 4 windows of "
                         f"{window:g} s, the record is {t[-1] - t[0]:g} s")
    peaks = np.maximum(peaks, 1e-300)
    return float(np.polyfit(centers[half], np.log(peaks[half]), 1)[0])


@dataclass(frozen=True)
class TimeDomainSweep:
    """Growth rate of the free response over airspeed: velocities, growth (1/s), and the onset
    speed (growth = 0, None if none in the range).

    ``at_first_point``: the response already grows at the first airspeed, so the onset is at or
    below ``velocities[0]``; ``onset_speed`` is then that first airspeed (an upper bound).
    """

    velocities: np.ndarray
    growth: np.ndarray
    onset_speed: float | None
    method: str
    at_first_point: bool = False

    def describe(self, unit: str = "m/s") -> str:
        """'onset at 219.6 m/s', 'unstable at the first point of the sweep: onset at or below
        250 m/s' or 'no growth up to 460 m/s'."""
        if self.onset_speed is None:
            return f"no growth up to {self.velocities[-1]:.6g} {unit}"
        if self.at_first_point:
            return (f"unstable at the first point of the sweep: onset at or below "
                    f"{self.onset_speed:.6g} {unit}")
        return f"onset at {self.onset_speed:.6g} {unit}"


@small_dense
def time_domain_sweep(modal, rfa, density: float, velocities, coordinate: int = 1,
                      t_end: float = 0.25, max_step: float = 1e-4, method: str = "exact",
                      window: float | None = None, refine: bool = True) -> TimeDomainSweep:
    """Growth rate of the response of z' = A_sys z (unit initial value on elastic coordinate
    ``coordinate``) over ``velocities``, and the onset speed where it crosses zero (interpolated,
    refined by Brent's method when ``refine``). The growth is measured on the elastic modal
    coordinates zeta_s. ``method`` "exact" (matrix exponential) or a solve_ivp method.

    ``window`` (s) must be at least one period T1 = 2 pi / omega_1 of the slowest elastic
    structural mode, and ``t_end`` at least 4 windows; the default window is
    max(T1, min(2 T1, t_end / 8)). A response growing at the first airspeed (growth > tol, tol
    = 1e-9 omega_max of the structure) gives ``at_first_point=True``, ``onset_speed = U0``.
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    U = _ascending("velocities", velocities)
    rho = positive("density", density)
    _pressure_ok(rho, U)
    t_end = positive("t_end", t_end)
    ns = m.n_elastic
    if ns == 0:
        raise ValueError("modal has no elastic modes: nothing to measure")
    s = slice(m.n_rigid, m.n_modes)
    w2 = linalg.eigvalsh(m.K[s, s], m.M[s, s])
    w1 = np.sqrt(max(w2.min(), 1e-12))
    period = 2 * np.pi / w1
    if window is None:
        window = max(period, min(2 * period, t_end / 8))
    else:
        window = positive("window", window)
        if window < period * (1 - 1e-9):
            raise ValueError(f"window = {window:g} s is shorter than a period of the slowest "
                             f"elastic mode ({period:g} s, {w1 / 2 / np.pi:.4g} Hz): the peaks "
                             f"per window would not measure growth; use window >= {period:g}")
    if t_end < 4 * window:
        raise ValueError(f"t_end = {t_end:g} s holds fewer than 4 windows of {window:g} s "
                         f"(one or two periods of the slowest elastic mode, {period:g} s): "
                         f"use t_end >= {4 * window:g}")
    tol = RTOL_UNSTABLE * np.sqrt(max(w2.max(), 0.0))

    def rate(u):
        mats = aeroelastic_matrices(m, rfa, rho, u)
        z0 = initial_state(mats.n_states, coordinate)
        r = simulate_free_response(mats.A, z0, t_end, max_step, method)
        return growth_rate(r.t, r.z[:, :ns], window)

    g = np.array([rate(u) for u in U])
    if g[0] > tol:
        return TimeDomainSweep(velocities=U, growth=g, onset_speed=float(U[0]), method=method,
                               at_first_point=True)
    onset = None
    for i in range(1, U.size):
        if g[i - 1] <= tol < g[i]:
            onset = U[i - 1] + (tol - g[i - 1]) * (U[i] - U[i - 1]) / (g[i] - g[i - 1])
            onset = float(np.clip(onset, U[i - 1], U[i]))
            if refine:
                try:
                    onset = optimize.brentq(lambda u: rate(u) - tol, U[i - 1], U[i],
                                            xtol=1e-4 * U[i])
                except ValueError:
                    pass
            break
    return TimeDomainSweep(velocities=U, growth=g, onset_speed=None if onset is None
                           else float(onset), method=method)
