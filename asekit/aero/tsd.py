"""Transonic small-disturbance (TSD) aerodynamics of a thin airfoil (issue 29, its first steps,
in 2-D): the steady background flow about a symmetric airfoil (:func:`steady_tsd`) and the
time-linearised lifting pressure of a harmonic motion about it (:func:`harmonic_tsd`), the
method that the 3-D wing GAFs (``method = "tsd"``) will use.

The equation (Murman & Cole 1971, AIAA J. 9(1) 114-121; conservative form as Murman 1974,
AIAA J. 12(5) 626-633), for the perturbation potential phi (per U c; x, y per chord c):

    d/dx [ (1 - M^2) phi_x - (gamma + 1)/2 M^2 phi_x^2 ] + d/dy [ phi_y ] = 0,      (1)

with the thin-airfoil boundary condition on the mean plane phi_y(x, 0+) = dz_t/dx on the chord
(upper surface z_t(x); the flow is symmetric, so only y >= 0 is solved), phi = 0 far away, and
the surface pressure coefficient Cp = -2 phi_x (the small-disturbance Cp). Eq. (1) is elliptic
where A = 1 - M^2 - (gamma + 1) M^2 phi_x > 0 (locally subsonic) and hyperbolic where A < 0.

Discretisation: a finite-volume form of (1) on a stretched Cartesian grid (uniform on the chord,
geometric outside), with Murman's fully conservative type-dependent differencing of the
x-flux f(u) = (1 - M^2) u - (gamma + 1)/2 M^2 u^2 (u = phi_x at cell faces): with the switch
mu_i = 1 where A_i < 0 at node i (central u) and 0 elsewhere,

    (1 - mu_i) (f_{i+1/2} - f_{i-1/2}) + mu_{i-1} (f_{i-1/2} - f_{i-3/2}) h_i / h_{i-1}
        + h_i [ phi_y ]_{j-1/2}^{j+1/2} / k_j = 0,                                    (2)

so that a subsonic node is central, a supersonic node is upwind, the node after the sonic line
carries both terms (the shock-point operator, which makes the captured shock satisfy the
jump conditions of (1)) and a node whose upstream neighbour is subsonic while it is supersonic
carries neither x term (the parabolic point). The nonlinear system (2) is solved from phi = 0
by pseudo-transient continuation (implicit-Euler pseudo-time steps with sparse LU, the switches
frozen within a step, the pseudo-time step grown as the residual falls, so that the last steps
are Newton's method). With gamma = -1 the equation is linear (the Prandtl-Glauert
equation) and one step solves it.

Validity and state (issue 29, first steps): 2-D only; the steady flow of symmetric airfoils at
zero incidence (the background of a symmetric wing's flutter problem, so no steady lift or
wake); the far field is phi = 0 on a boundary ``far`` chords away. Shocks up to about x = 0.9 of the chord
converge (10 % biconvex at M 0.85); a shock that reaches the trailing edge (10 % biconvex at
M 0.9) does not yet (``converged`` False).

The unit of everything here is the chord (x, y) and U c (phi): the caller scales.

Examples
--------
>>> import numpy as np
>>> sol = steady_tsd(biconvex(0.02), mach=0.5, grid=tsd_grid(n_chord=40))
>>> bool(sol.converged), sol.supersonic_points
(True, 0)
>>> float(np.round(sol.cp[np.argmin(np.abs(sol.x_surface - 0.5))], 3))
-0.059
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

GAMMA_AIR = 1.4


@dataclass(frozen=True)
class TsdGrid:
    """A stretched Cartesian grid for Eq. (1): node abscissae ``x`` (n_x,) from far upstream to
    far downstream (chord from 0 to 1, nodes on both ends), ordinates ``y`` (n_y,) from the mean
    plane y = 0 to the far field, both in chords."""

    x: np.ndarray
    y: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.x.size, self.y.size


def _stretched(h0: float, extent: float, ratio: float) -> np.ndarray:
    """Offsets 0 < h0, h0 (1 + r), ... (geometric, ratio ``ratio``) up to at least ``extent``."""
    out, h, s = [], h0, 0.0
    while s < extent:
        s += h
        out.append(s)
        h *= ratio
    return np.array(out)


def tsd_grid(n_chord: int = 80, far: float = 30.0, ratio: float = 1.12,
             wall_spacing: float | None = None, spacing: str = "cosine") -> TsdGrid:
    """The default grid: ``n_chord`` cells on the chord, ``spacing`` "cosine" (nodes
    x = (1 - cos theta) / 2, theta uniform: fine at the leading and trailing edges, where the
    lifting pressure is singular; the lift then converges to first order, against about
    h^0.5 with uniform cells) or "uniform"; geometric stretching by ``ratio`` up- and
    downstream and normal to the plane to ``far`` chords, the first cells as fine as the
    chord's end cells; the first cell above the plane ``wall_spacing`` (default that size).

    >>> g = tsd_grid(n_chord=20, far=10.0)
    >>> bool(g.x[0] <= -10.0), bool(g.x[-1] >= 11.0), float(g.y[0])
    (True, True, 0.0)
    """
    if isinstance(n_chord, bool) or int(n_chord) != n_chord or int(n_chord) < 4:
        raise ValueError(f"n_chord must be an integer >= 4, got {n_chord!r}")
    if not far > 1.0:
        raise ValueError(f"far must be > 1 chord, got {far!r}")
    if not 1.0 <= ratio <= 1.5:
        raise ValueError(f"ratio must be in [1, 1.5], got {ratio!r}")
    if spacing == "cosine":
        chord = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, int(n_chord) + 1)))
    elif spacing == "uniform":
        chord = np.linspace(0.0, 1.0, int(n_chord) + 1)
    else:
        raise ValueError(f"spacing must be 'cosine' or 'uniform', got {spacing!r}")
    h = float(chord[1] - chord[0])
    side = _stretched(h * ratio, far, ratio)
    x = np.concatenate([-side[::-1], chord, 1.0 + side])
    y = np.concatenate([[0.0], _stretched(wall_spacing or h, far, ratio)])
    return TsdGrid(x, y)


def biconvex(thickness_ratio: float) -> Callable[[np.ndarray], np.ndarray]:
    """The slope dz_t/dx of the upper surface of a symmetric biconvex (parabolic-arc) airfoil
    z_t = 2 tau x (1 - x) of thickness ratio tau: dz_t/dx = 2 tau (1 - 2 x).

    >>> biconvex(0.1)(np.array([0.0, 0.5, 1.0])).tolist()
    [0.2, 0.0, -0.2]
    """
    tau = float(thickness_ratio)
    if not 0.0 <= tau < 0.3:
        raise ValueError(f"thickness_ratio must be in [0, 0.3) for a thin airfoil, got {tau!r}")
    return lambda x: 2.0 * tau * (1.0 - 2.0 * np.asarray(x, float))


def biconvex_linear_cp(thickness_ratio: float, mach: float, x: np.ndarray) -> np.ndarray:
    """Linear (Prandtl-Glauert) thin-airfoil Cp on a biconvex airfoil, 0 < x < 1:

        Cp = -(4 tau / (pi beta)) [2 + (1 - 2x) ln(x / (1 - x))],   beta = sqrt(1 - M^2),

    from u/U = (1/pi) PV int_0^1 z_t'(xi) / (x - xi) dxi with z_t' = 2 tau (1 - 2 xi) (thin-airfoil
    thickness problem, e.g. Katz & Plotkin, Low-Speed Aerodynamics, Sec. 5.2) and the
    Prandtl-Glauert rule Cp = Cp_0 / beta.

    >>> round(float(biconvex_linear_cp(0.1, 0.0, np.array([0.5]))[0]), 4)
    -0.2546
    """
    x = np.asarray(x, float)
    beta = np.sqrt(1.0 - mach ** 2)
    return -(4.0 * thickness_ratio / (np.pi * beta)) * (2.0 + (1.0 - 2.0 * x)
                                                        * np.log(x / (1.0 - x)))


@dataclass(frozen=True)
class TsdSolution:
    """A converged (or the last) steady TSD solution.

    Attributes
    ----------
    grid : the grid.
    phi : (n_x, n_y) perturbation potential per U c.
    x_surface : (n_c,) chordwise stations of ``cp`` (cell midpoints on the chord).
    cp : (n_c,) upper-surface pressure coefficient -2 phi_x at y = 0.
    mach, gamma : free-stream Mach number and ratio of specific heats.
    converged : the Newton residual fell below the tolerance.
    iterations : Newton iterations taken.
    residual : final max-norm residual of Eq. (2).
    supersonic_points : nodes with A < 0 (0: the flow is subcritical everywhere).
    """

    grid: TsdGrid
    phi: np.ndarray
    x_surface: np.ndarray
    cp: np.ndarray
    mach: float
    gamma: float
    converged: bool
    iterations: int
    residual: float
    supersonic_points: int

    @property
    def cp_critical(self) -> float:
        """The small-disturbance critical (sonic) pressure coefficient
        Cp* = -2 (1 - M^2) / ((gamma + 1) M^2): Cp below it is locally supersonic."""
        return -2.0 * (1.0 - self.mach ** 2) / ((self.gamma + 1.0) * self.mach ** 2)


class _System:
    """Eq. (2) on a grid: residual and Jacobian of the unknown potential (Dirichlet phi = 0 on
    the upstream, downstream and far boundaries)."""

    def __init__(self, grid: TsdGrid, slope, mach: float, gamma: float):
        x, y = grid.x, grid.y
        self.nx, self.ny = x.size, y.size
        self.dx = np.diff(x)                                   # (nx-1,) face spacings
        self.hx = np.zeros(self.nx)
        self.hx[1:-1] = 0.5 * (x[2:] - x[:-2])                 # cell widths
        self.dy = np.diff(y)
        self.hy = np.empty(self.ny)
        self.hy[0] = 0.5 * self.dy[0]
        self.hy[1:-1] = 0.5 * (y[2:] - y[:-2])
        self.hy[-1] = 0.5 * self.dy[-1]
        on_chord = (x >= -1e-12) & (x <= 1.0 + 1e-12)
        self.g = np.where(on_chord, slope(np.clip(x, 0.0, 1.0)), 0.0)   # phi_y at y = 0
        self.a0 = 1.0 - mach ** 2
        self.b = (gamma + 1.0) * mach ** 2
        self.xc = x[2:] - x[:-2]                               # central spans (nx-2,)
        self.interior = np.zeros((self.nx, self.ny), bool)
        self.interior[1:-1, :-1] = True
        self.idx = np.flatnonzero(self.interior.ravel())

    def switches(self, phi: np.ndarray) -> np.ndarray:
        """mu (n_x, n_y): 1 where A = 1 - M^2 - (gamma+1) M^2 phi_x < 0 (central phi_x)."""
        mu = np.zeros_like(phi)
        u = (phi[2:] - phi[:-2]) / self.xc[:, None]
        mu[1:-1] = (self.a0 - self.b * u) < 0.0
        return mu

    def residual_jacobian(self, phi: np.ndarray, mu: np.ndarray, jacobian: bool = True):
        nx, ny = self.nx, self.ny
        u = np.diff(phi, axis=0) / self.dx[:, None]             # faces i+1/2, (nx-1, ny)
        f = self.a0 * u - 0.5 * self.b * u ** 2
        a = (self.a0 - self.b * u) / self.dx[:, None]           # df/dphi_{i+1} at the face
        i = np.arange(1, nx - 1)
        # x part: (1 - mu_i)(f_{i+1/2} - f_{i-1/2}) + mu_{i-1}(f_{i-1/2} - f_{i-3/2}) h_i/h_{i-1}
        c = (1.0 - mu[i])                                       # (nx-2, ny)
        up = mu[i - 1].copy()
        up[0] = 0.0                                             # no face i-3/2 at i = 1
        ratio = (self.hx[i] / np.where(self.hx[i - 1] > 0, self.hx[i - 1], 1.0))[:, None]
        fm = np.vstack([f[:1], f[:-2]])                         # f_{i-3/2} (dummy at i = 1)
        rx = c * (f[i] - f[i - 1]) + up * ratio * (f[i - 1] - fm)
        # y part times the cell width, flux phi_y = slope through the plane at j = 0
        fy = np.diff(phi, axis=1) / self.dy[None, :]            # (nx, ny-1) faces j+1/2
        ry = np.zeros((nx, ny))
        ry[:, :-1] += fy
        ry[:, 1:] -= fy
        ry[:, 0] -= self.g
        r = np.zeros((nx, ny))
        r[1:-1] = self.hy[None, :] * rx + self.hx[1:-1, None] * ry[1:-1]
        res = r.ravel()[self.idx]
        if not jacobian:
            return res, None
        return res, self._jacobian(a, c, up, ratio)

    def _jacobian(self, a, c, up, ratio):
        nx, ny = self.nx, self.ny
        node = np.arange(nx * ny).reshape(nx, ny)
        rows, cols, vals = [], [], []

        def add(r, cidx, v):
            rows.append(r.ravel())
            cols.append(cidx.ravel())
            vals.append(np.broadcast_to(v, r.shape).ravel())

        i = np.arange(1, nx - 1)
        R = node[i]
        hy = self.hy[None, :]
        # f_{i+1/2} = f(phi_{i+1} - phi_i), f_{i-1/2} = f(phi_i - phi_{i-1}), ...
        add(R, node[i + 1], hy * c * a[i])
        add(R, node[i], hy * (-c * a[i] - c * a[i - 1] + up * ratio * a[i - 1]))
        add(R, node[i - 1], hy * (c * a[i - 1] - up * ratio * a[i - 1] - up * ratio * a[i - 2]))
        im2 = np.maximum(i - 2, 0)
        add(R, node[im2], hy * up * ratio * a[i - 2])
        hx = self.hx[i][:, None]
        inv = 1.0 / self.dy
        add(R[:, :-1], node[i][:, 1:], hx * inv[None, :])
        add(R[:, :-1], node[i][:, :-1], -hx * inv[None, :])
        add(R[:, 1:], node[i][:, :-1], hx * inv[None, :])
        add(R[:, 1:], node[i][:, 1:], -hx * inv[None, :])
        J = sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                      np.concatenate(cols))),
                              shape=(nx * ny, nx * ny)).tocsr()
        return J[self.idx][:, self.idx].tocsc()


def tsd_mach(mach) -> float:
    """``mach`` as a float, checked against the range of the small-disturbance equation,
    0 <= M < 1.3 (a ValueError naming ``mach`` otherwise); shared by the 2-D and 3-D solvers.

    Examples
    --------
    >>> tsd_mach(0.8)
    0.8
    """
    mach = float(mach)
    if not 0.0 <= mach < 1.3:
        raise ValueError(f"mach must be in [0, 1.3) for the transonic small-disturbance "
                         f"equation, got {mach!r}")
    return mach


def steady_tsd(slope, mach: float, grid: TsdGrid | None = None, gamma: float = GAMMA_AIR,
               tol: float = 1e-10, max_iter: int = 60) -> TsdSolution:
    """Steady TSD flow about a thin symmetric airfoil (Eq. 1-2 of the module docstring).

    Parameters
    ----------
    slope : callable x -> dz_t/dx of the upper surface on 0 <= x <= 1 (chords), e.g.
        :func:`biconvex`.
    mach : free-stream Mach number, 0 <= M < 1.3 (the small-disturbance range; a thin airfoil
        only).
    grid : :func:`tsd_grid` (default ``tsd_grid()``).
    gamma : ratio of specific heats (1.4 for air).
    tol : Newton tolerance on the max-norm residual, relative to that of the zero potential.
    max_iter : pseudo-time steps at most.

    Returns
    -------
    :class:`TsdSolution` (check ``converged``).
    """
    mach = tsd_mach(mach)
    grid = tsd_grid() if grid is None else grid
    sys_ = _System(grid, slope, mach, float(gamma))
    phi = np.zeros(grid.shape)
    r0 = np.max(np.abs(sys_.residual_jacobian(phi, np.zeros_like(phi), False)[0])) or 1.0
    phi, total = _ptc(sys_, phi, tol * r0, max_iter)
    r = sys_.residual_jacobian(phi, sys_.switches(phi), False)[0]
    res = float(np.max(np.abs(r)))
    return _solution(grid, sys_, phi, mach, float(gamma), res <= tol * r0, total, res / r0)


def _ptc(sys_: _System, phi: np.ndarray, tol: float, max_iter: int):
    """Pseudo-transient continuation (Kelley & Keyes 1998, SIAM J. Numer. Anal. 35(2)): the
    implicit-Euler steps (V / dtau - J) dphi = R of V phi_tau = R(phi), V the cell area, with
    dtau grown by switched evolution relaxation (dtau_n = dtau_0 |R_0| / |R_{n-1}|), which
    becomes Newton's method as the residual falls. Returns (phi, steps)."""
    vol = (sys_.hx[:, None] * sys_.hy[None, :]).ravel()[sys_.idx]
    r, J = sys_.residual_jacobian(phi, sys_.switches(phi))
    res = r_first = max(float(np.max(np.abs(r))), 1e-300)
    dtau0 = 1.0
    for it in range(1, max_iter + 1):
        if res <= tol:
            return phi, it
        dtau = dtau0 * r_first / res
        step = splu((sparse.diags(vol / dtau) - J).tocsc()).solve(r)
        flat = phi.ravel().copy()
        flat[sys_.idx] += step
        phi = flat.reshape(phi.shape)
        r, J = sys_.residual_jacobian(phi, sys_.switches(phi))
        res = float(np.max(np.abs(r)))
    return phi, max_iter


def _solution(grid, sys_, phi, mach, gamma, converged, it, res) -> TsdSolution:
    on = (grid.x[:-1] >= -1e-12) & (grid.x[1:] <= 1.0 + 1e-12)
    u = np.diff(phi[:, 0]) / np.diff(grid.x)
    xm = 0.5 * (grid.x[:-1] + grid.x[1:])
    mu = sys_.switches(phi)
    return TsdSolution(grid=grid, phi=phi, x_surface=xm[on], cp=-2.0 * u[on], mach=mach,
                       gamma=gamma, converged=bool(converged), iterations=int(it),
                       residual=float(res), supersonic_points=int(mu.sum()))


# ---------------------------------------------------------------------------------------------
# time-linearised (frequency-domain) lifting problem about the steady background
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HarmonicTsdSolution:
    """The pressure jump of a harmonic motion about a steady TSD background.

    Attributes
    ----------
    x : (n_c,) chordwise stations (cell midpoints on the chord, chords).
    delta_cp : (n_c,) complex pressure-jump amplitude Cp_lower - Cp_upper per unit motion
        amplitude (positive: lift up).
    cl : complex lift coefficient per unit amplitude (reference q c), the integral of
        ``delta_cp`` over the chord.
    cm_le : complex moment coefficient about the leading edge (nose up > 0, reference q c^2).
    reduced_frequency : omega c / U (chord-based; asekit's semichord k is half of it).
    """

    x: np.ndarray
    delta_cp: np.ndarray
    cl: complex
    cm_le: complex
    reduced_frequency: float


def pitch_normalwash(pivot: float, reduced_frequency: float):
    """w/U on the chord for a unit nose-up pitch about x = ``pivot`` (chords): the surface
    z = -alpha (x - pivot) moves as w/U = z_x + i k_c z = -(1 + i k_c (x - pivot)).

    >>> complex(pitch_normalwash(0.5, 0.2)(np.array([0.5]))[0])
    (-1-0j)
    """
    kc = float(reduced_frequency)
    return lambda x: -(1.0 + 1j * kc * (np.asarray(x, float) - pivot))


def harmonic_tsd(background: TsdSolution, normalwash, reduced_frequency: float
                 ) -> HarmonicTsdSolution:
    """Time-linearised TSD about a steady solution: the lifting (antisymmetric) potential
    phi1 e^{i omega t} of a harmonic motion with normalwash ``normalwash(x)`` (w/U on the chord,
    complex), at chord-based reduced frequency k_c = omega c / U.

    The unsteady TSD equation (time per c / U; e.g. Ballhaus & Goorjian 1977, AIAA J. 15(12),
    Eq. 1) M^2 phi_tt + 2 M^2 phi_xt = [(1 - M^2) phi_x - (gamma+1)/2 M^2 phi_x^2]_x + phi_yy,
    linearised about the steady phi0, is for the harmonic amplitude

        [A0 phi1_x]_x + phi1_yy + M^2 k_c^2 phi1 - 2 i k_c M^2 phi1_x = 0,
        A0 = 1 - M^2 - (gamma+1) M^2 phi0_x,                                          (3)

    differenced with the background's type-dependent switches (Eq. 2) for the x term and
    central differences for phi1_x. On y = 0+: phi1 = 0 ahead of the chord (antisymmetry), the
    flux phi1_y = w/U on the chord, and in the wake a continuous pressure, phi1_x + i k_c phi1
    = 0, solved exactly along the wake row (phi1 = phi1_TE exp(-i k_c (x - 1)), the Kutta
    condition); far away, phi1_x = 0 upstream, phi1_y = 0 above and phi1_x + i k_c phi1 = 0
    downstream (first-order far-field conditions: use a far boundary, e.g. 200 chords).
    Pressure: Cp = -2 (phi_x + i k_c phi) on the upper side, so the jump is
    Delta Cp = 4 (phi1_x + i k_c phi1).

    Examples
    --------
    >>> bg = steady_tsd(biconvex(0.0), 0.0, tsd_grid(n_chord=40, far=100.0))
    >>> sol = harmonic_tsd(bg, pitch_normalwash(0.25, 0.0), 0.0)
    >>> round(sol.cl.real / (2 * np.pi), 2)    # 2 pi per rad, less the first-order error
    0.96
    """
    grid, kc = background.grid, float(reduced_frequency)
    if not (np.isfinite(kc) and kc >= 0.0):
        raise ValueError(f"reduced_frequency must be finite and >= 0, got {reduced_frequency!r}")
    mach = background.mach
    x = grid.x
    nx, ny = grid.shape
    sys_ = _System(grid, lambda s: np.zeros_like(s), mach, background.gamma)
    phi0 = background.phi
    u0 = np.diff(phi0, axis=0) / sys_.dx[:, None]
    A = (sys_.a0 - sys_.b * u0) / sys_.dx[:, None]               # face coefficient / dx
    mu = sys_.switches(phi0)
    node = np.arange(nx * ny).reshape(nx, ny)
    rows, cols, vals = [], [], []

    def add(r, c, v):
        r, c = np.broadcast_arrays(r, c)
        rows.append(r.ravel())
        cols.append(c.ravel())
        vals.append(np.broadcast_to(np.asarray(v, complex), r.shape).ravel())

    i = np.arange(1, nx - 1)
    chord = ((x >= -1e-12) & (x <= 1.0 + 1e-12))
    wake = x > 1.0 + 1e-12
    # interior and chord rows: the field equation (3); its y = 0 row carries the flux BC
    R = node[i]
    c = 1.0 - mu[i]
    up = mu[i - 1].copy()
    up[0] = 0.0
    ratio = (sys_.hx[i] / np.where(sys_.hx[i - 1] > 0, sys_.hx[i - 1], 1.0))[:, None]
    hy = sys_.hy[None, :]
    add(R, node[i + 1], hy * c * A[i])
    add(R, node[i], hy * (-c * A[i] - c * A[i - 1] + up * ratio * A[i - 1]))
    add(R, node[i - 1], hy * (c * A[i - 1] - up * ratio * A[i - 1] - up * ratio * A[i - 2]))
    add(R, node[np.maximum(i - 2, 0)], hy * up * ratio * A[i - 2])
    hx = sys_.hx[i][:, None]
    inv = 1.0 / sys_.dy
    add(R[:, :-1], node[i][:, 1:], hx * inv[None, :])
    add(R[:, :-1], node[i][:, :-1], -hx * inv[None, :])
    add(R[:, 1:], node[i][:, :-1], hx * inv[None, :])
    add(R[:, 1:], node[i][:, 1:], -hx * inv[None, :])
    vol = hx * hy
    add(R, node[i], vol * mach ** 2 * kc ** 2)
    span = (x[i + 1] - x[i - 1])[:, None]
    add(R, node[i + 1], -2j * kc * mach ** 2 * vol / span)
    add(R, node[i - 1], 2j * kc * mach ** 2 * vol / span)
    rhs = np.zeros(nx * ny, complex)
    w = np.zeros(nx, complex)
    w[chord] = normalwash(x[chord])
    rhs[node[1:-1, 0]] = sys_.hx[1:-1] * w[1:-1]          # the chord's flux phi_y = w / U
    # rows replaced by boundary equations: phi = 0 ahead of the chord on y = 0, the wake's
    # exact convection phi_i = phi_{i-1} exp(-i k_c dx) along y = 0 behind it, and the far
    # field (phi_x = 0 upstream, phi_x + i k_c phi = 0 downstream; the top row keeps the
    # field equation without the face above: phi_y = 0)
    replaced = np.zeros(nx * ny, bool)
    ahead, behind = np.flatnonzero(x < -1e-12), np.flatnonzero(wake)
    replaced[node[ahead, 0]] = replaced[node[behind, 0]] = True
    replaced[node[0, :]] = replaced[node[-1, :]] = True
    r_all, c_all, v_all = (np.concatenate(a) for a in (rows, cols, vals))
    keep = ~replaced[r_all]
    rows, cols, vals = [r_all[keep]], [c_all[keep]], [v_all[keep]]
    rhs[replaced] = 0.0
    add(node[ahead, 0], node[ahead, 0], 1.0)
    add(node[behind, 0], node[behind, 0], 1.0)
    add(node[behind, 0], node[behind - 1, 0], -np.exp(-1j * kc * (x[behind] - x[behind - 1])))
    add(node[0, 1:], node[0, 1:], 1.0)
    add(node[0, 1:], node[1, 1:], -1.0)
    d = x[-1] - x[-2]
    add(node[-1, 1:], node[-1, 1:], 1.0 / d + 0.5j * kc)
    add(node[-1, 1:], node[-2, 1:], -1.0 / d + 0.5j * kc)
    J = sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(nx * ny, nx * ny)).tocsc()
    phi = splu(J, permc_spec="NATURAL").solve(rhs).reshape(nx, ny)   # banded: i * n_y + j
    u = np.diff(phi[:, 0]) / np.diff(x)
    pm = 0.5 * (phi[1:, 0] + phi[:-1, 0])
    xm = 0.5 * (x[1:] + x[:-1])
    on = (x[:-1] >= -1e-12) & (x[1:] <= 1.0 + 1e-12)
    dcp = 4.0 * (u + 1j * kc * pm)
    dx = np.diff(x)
    cl = complex(np.sum(dcp[on] * dx[on]))
    cm = complex(-np.sum(dcp[on] * xm[on] * dx[on]))
    return HarmonicTsdSolution(xm[on], dcp[on], cl, cm, kc)
