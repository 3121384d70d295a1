"""Transonic small-disturbance (TSD) aerodynamics of a thin wing in 3-D (issue 29, the 3-D step):
the steady thickness flow about a symmetric wing at zero incidence (:func:`steady_tsd3d`) and
the time-linearised lifting pressure of a harmonic motion about it (:func:`harmonic_tsd3d`).

The steady equation (the 3-D TSD equation without the cross-flow terms, Bailey & Ballhaus 1972,
NASA SP-347 pp. 1215-1245, Eq. 1; conservative form as Murman 1974, AIAA J. 12(5) 626-633), for
the perturbation potential phi per U (a length: x, y, z and phi in the planform's unit, e.g. m):

    d/dx [ (1 - M^2) phi_x - (gamma + 1)/2 M^2 phi_x^2 ] + phi_yy + phi_zz = 0,         (1)

and, with ``cross_flow=True`` (issue 29, tsdswept: needed by swept wings), the modified TSD
equation of Batina (1989, J. Aircraft 26(6) 531-538, Eq. 1; CAP-TSD) with the cross-flow
terms in conservative form::

    d/dx [ (1 - M^2) phi_x - (gamma + 1)/2 M^2 phi_x^2 + G phi_y^2 ]
        + d/dy [ phi_y + H phi_x phi_y ] + phi_zz = 0,
    G = (gamma - 3)/2 M^2,  H = -(gamma - 1) M^2,                                    (1b)

whose expansion adds -(gamma - 1) M^2 phi_x phi_yy - 2 M^2 phi_y phi_xy, the cross-flow terms
of the full-potential expansion (Ballhaus, Bailey & Frick 1977, NASA CP-2001): on an infinite
yawed wing, phi = f(x - y tan Lambda), Eq. (1b) is exactly the TSD equation of the normal
Mach number M cos Lambda (simple sweep theory), while Eq. (1) under-weights the nonlinear term
by cos^2 Lambda (tests/aero/test_tsd_swept.py). The G phi_y^2 flux is differenced with the
x-flux by the Murman-Cole operator (phi_y at an x-face the mean of the nodes' central
phi_y), the H phi_x phi_y flux through the y-faces (phi_x there the mean of the nodes'
central phi_x); the type switch stays that of Eq. (1), A = 1 - M^2 - (gamma+1) M^2 phi_x.
The terms are quadratic in phi: the linear limit (thickness -> 0) is unchanged, but
gamma = -1 no longer makes the equation linear with them. :func:`harmonic_tsd3d` linearises them about the
background (their Jacobian, :class:`_CrossFlow`).

With the thin-wing boundary condition on the mean plane phi_z(x, y, 0+) = dz_t/dx on the
planform (upper surface z_t; the flow is symmetric in z, so only z >= 0 is solved, and no wake is
needed), phi_z = 0 on z = 0 off the planform, phi_y = 0 on the root plane y = 0 (a half wing
mirrored there, or a wall), phi = 0 on the far boundaries, and Cp = -2 phi_x.

Discretisation: the finite-volume form of :mod:`asekit.aero.tsd` (its Eq. 2: Murman's fully
conservative type-dependent differencing of the x-flux f(u) = (1 - M^2) u - (gamma+1)/2 M^2 u^2,
central where A = 1 - M^2 - (gamma+1) M^2 phi_x > 0, upwind where A < 0, with the shock- and
parabolic-point operators) along every x line, and central second differences of phi_yy and
phi_zz on a stretched Cartesian (x, y, z) grid (:func:`tsd3d_grid`). The thickness flux through
the bottom face of a cell is integrated exactly in x, int dz_t/dx dx = c(y) [t(xi_b) - t(xi_a)],
t = z_t / c the thickness distribution, xi the local chord fraction, so planform edges need not
lie on grid lines. The nonlinear system is solved by pseudo-transient continuation with sparse
LU, as in 2-D; with gamma = -1 the equation is the linear Prandtl-Glauert equation.

The planform (:class:`TsdPlanform`) is a half wing of straight-tapered trapezoidal panels in the
plane z = 0 (:meth:`TsdPlanform.from_surfaces` takes the panels of
:class:`asekit.aero.boxes.TrapezoidSurface`), root at y = 0.

Validity and state: the steady background of a symmetric wing at zero incidence (no steady
lift), with a reflection plane at the root; the far field phi = 0 on a box ``far`` root chords
away. The lifting problem (:func:`harmonic_tsd3d`, :func:`tsd_gaf`) is first order in the cell
size at the edges (Richardson extrapolation of two grids recovers the DLM's steady lift of an
aspect-ratio-3 wing at M 0.8 to 0.1 %; at k = 0.3 the 16 x 8-cell GAFs are within 4.9 % of the
DLM's and converging; before issue 29's tsdswept projection fix 0.3 % and 6.4 %), and its far field reflects part of the short upstream-running acoustic
waves at high subsonic Mach. On swept wings the Cartesian grid resolves the local chord by
fewer cells (the n_chord cells span the whole planform's x extent, the leading and trailing
edges cut the cells obliquely): for the AGARD 445.6 planform (45 deg, taper 0.66) at M 0.8,
k = 0 and zero thickness the lift GAFs are +30 %, +7.1 %, +1.9 % from the DLM's on 8 x 4,
12 x 6, 16 x 8 cells (issue 29, tsdswept; tests/aero/test_tsd_swept.py; the rectangular
aspect-ratio-3 wing: +7.2 %, +3.7 %, +2.0 %, Richardson-extrapolated 12/16 within 0.1 % of
the DLM's extrapolated lift). Not yet: camber /
incidence backgrounds (steady lift and wake). ``method = "tsd"`` of the
registry (:mod:`asekit.aero.methods`) wraps :func:`tsd_pressure_matrices` on the grid of
:func:`mesh_grid_options` (limit :data:`MAX_NODES`); :func:`tsd_validity` states the
similarity parameter and shock presence of a background. On the coarse grids of unit tests
the continuation can stall at a strong shock (4 % biconvex at M 0.95 on 8 x 4 cells:
residual 8e-3 after 60, 150 and 300 steps). The sparse LU costs grow as about n^1.5-2 in 3-D: about 1e4 nodes solve in a second
(real) or a few seconds (the complex harmonic system), 4e4 nodes in tens of seconds.

Supersonic free streams, 1 < M < 1.3 (issue 29, tsdfin: the fin's envelope through the
gap). The Murman-Cole switch is then upwind at every node off the pockets of subsonic flow, so
the x-operator is the first-order backward one of the supersonic wave equation; the harmonic
problem's time term -2 i kappa M^2 phi1_x is backward there too (:func:`_time_term`). The
far boundaries need no special treatment: the inflow plane is undisturbed (phi = 0 steady,
phi1_x = 0 harmonic), and the upper and outboard boundaries (phi = 0 steady; the acoustic
condition's K = kappa M / sqrt(max(1 - M^2, 1e-6)) makes them nearly phi1 = 0 above M 1)
reflect Mach waves that return to z = 0 at least 2 beta far root chords downstream of where
they left, behind the wing for beta > 1 / (2 far) (M > 1.0035 with far 6). Measured (zero
thickness, rectangular wing of aspect ratio 4, tests/aero/test_tsd_supersonic.py): the lift at
M 1.2 is 5.6 %, 4.7 %, 3.9 % below the exact linear value on 8, 12, 16 chordwise cells (first
order: the upwind operator lags the pressure by about a cell), the harmonic GAFs at k 0.3
within 9.2 % of asekit's Mach-box method on 8 cells (18 % with a central time term). The
steady background converges at M 1.0 and 1.05 on the lifting grids (``edges="faces"``); a
free stream of exactly M 1 has no linear limit (a0 = 0), so only a thick section's
background is defined there.

Examples
--------
>>> wing = TsdPlanform.rectangular(chord=1.0, semispan=2.0)
>>> g = tsd3d_grid(wing, n_chord=12, n_span=6, far=4.0, ratio=1.4)
>>> sol = steady_tsd3d(wing, biconvex_thickness(0.04), 0.5, g)
>>> bool(sol.converged), sol.supersonic_points
(True, 0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from asekit.aero.tsd import GAMMA_AIR, _stretched, tsd_mach

_EPS = 1e-12


# ---------------------------------------------------------------------------------------------
# planform and grid
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TsdPlanform:
    """A half wing of straight-tapered panels in z = 0: spanwise stations ``y`` (increasing
    from the root y = 0 to the tip), the leading-edge abscissa ``x_le`` and the streamwise
    ``chord`` (> 0) at each, linear in between (lengths in any one unit, e.g. m)."""

    y: np.ndarray
    x_le: np.ndarray
    chord: np.ndarray

    def __post_init__(self):
        y, xl, c = (np.asarray(a, float).ravel() for a in (self.y, self.x_le, self.chord))
        if y.size < 2 or xl.size != y.size or c.size != y.size:
            raise ValueError("y, x_le and chord must have the same length >= 2")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(xl)) and np.all(np.isfinite(c))):
            raise ValueError("y, x_le and chord must be finite")
        if abs(y[0]) > _EPS or np.any(np.diff(y) <= 0.0):
            raise ValueError(f"y must start at the root 0 and increase, got {y.tolist()}")
        if np.any(c <= 0.0):
            raise ValueError(f"chord must be > 0 at every station, got {c.tolist()}")
        for nm, a in (("y", y), ("x_le", xl), ("chord", c)):
            object.__setattr__(self, nm, a)

    @classmethod
    def rectangular(cls, chord: float, semispan: float) -> "TsdPlanform":
        """A rectangular half wing, leading edge on x = 0."""
        return cls(np.array([0.0, semispan]), np.zeros(2), np.full(2, float(chord)))

    @classmethod
    def from_surfaces(cls, surfaces) -> "TsdPlanform":
        """The planform of contiguous :class:`~asekit.aero.boxes.TrapezoidSurface` panels in
        the plane z = 0, root first (each panel's root edge the previous panel's tip edge)."""
        ys, xl, ch = [], [], []
        for n, s in enumerate(surfaces):
            if abs(s.root_le[2]) > _EPS or abs(s.tip_le[2]) > _EPS:
                raise ValueError(f"surface {n} ({s.name}) is not in the plane z = 0")
            if n == 0:
                ys.append(s.root_le[1])
                xl.append(s.root_le[0])
                ch.append(s.root_chord)
            elif (abs(s.root_le[1] - ys[-1]) > 1e-9 or abs(s.root_le[0] - xl[-1]) > 1e-9
                  or abs(s.root_chord - ch[-1]) > 1e-9):
                raise ValueError(f"surface {n} ({s.name}) does not continue surface {n - 1}")
            ys.append(s.tip_le[1])
            xl.append(s.tip_le[0])
            ch.append(s.tip_chord)
        return cls(np.array(ys), np.array(xl), np.array(ch))

    @property
    def semispan(self) -> float:
        return float(self.y[-1])

    def edges(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Leading edge and chord at span stations ``y`` (chord 0 beyond the tip)."""
        y = np.asarray(y, float)
        xl = np.interp(y, self.y, self.x_le)
        c = np.where(y <= self.semispan + _EPS, np.interp(y, self.y, self.chord), 0.0)
        return xl, c


@dataclass(frozen=True)
class Tsd3dGrid:
    """A stretched Cartesian grid: node abscissae ``x`` (n_x,), span stations ``y`` (n_y,,
    y[0] = 0 the root plane) and heights ``z`` (n_z,, z[0] = 0 the mean plane)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.x.size, self.y.size, self.z.size


def _chord_nodes(n: int, spacing: str, edges: str) -> np.ndarray:
    """Nodes on [0, 1]: the faces f (cosine or uniform) themselves (``edges`` "nodes") or
    their midpoints plus one node half a cell outside each end (``edges`` "faces": the ends
    lie midway between two nodes)."""
    if spacing == "cosine":
        f = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, n + 1)))
    elif spacing == "uniform":
        f = np.linspace(0.0, 1.0, n + 1)
    else:
        raise ValueError(f"spacing must be 'cosine' or 'uniform', got {spacing!r}")
    if edges == "nodes":
        return f
    if edges != "faces":
        raise ValueError(f"edges must be 'nodes' or 'faces', got {edges!r}")
    h0, h1 = f[1] - f[0], f[-1] - f[-2]
    return np.concatenate([[-0.5 * h0], 0.5 * (f[1:] + f[:-1]), [1.0 + 0.5 * h1]])


def tsd3d_grid(planform: TsdPlanform, n_chord: int = 24, n_span: int = 12, far: float = 8.0,
               ratio: float = 1.25, spacing: str = "cosine", edges: str = "nodes") -> Tsd3dGrid:
    """The grid of :func:`steady_tsd3d` and :func:`harmonic_tsd3d`: ``n_chord`` cells from the
    most forward leading edge to the most aft trailing edge ("cosine" or "uniform" spacing, as
    :func:`asekit.aero.tsd.tsd_grid`), ``n_span`` uniform cells on the span, and geometric
    stretching by ``ratio`` up- and downstream, outboard and above to ``far`` root chords;
    the first cell above the plane as fine as the chord's end cells. ``edges`` "nodes" puts
    grid nodes on the leading and trailing edges and the tip; "faces" puts those edges midway
    between nodes (the wing's cells then lie inside the planform: the usual choice of
    lifting TSD codes, e.g. Bailey & Ballhaus 1972, and of :func:`harmonic_tsd3d`).

    >>> g = tsd3d_grid(TsdPlanform.rectangular(1.0, 3.0), n_chord=8, n_span=6, far=5.0)
    >>> float(g.x[0]) <= -5.0, float(g.y[6]), float(g.z[0])
    (True, 3.0, 0.0)
    """
    for nm, v, low in (("n_chord", n_chord, 4), ("n_span", n_span, 2)):
        if isinstance(v, bool) or int(v) != v or int(v) < low:
            raise ValueError(f"{nm} must be an integer >= {low}, got {v!r}")
    if not 1.0 < ratio <= 1.6:
        raise ValueError(f"ratio must be in (1, 1.6], got {ratio!r}")
    c0 = float(planform.chord[0])
    if not far > 1.0:
        raise ValueError(f"far must be > 1 root chord, got {far!r}")
    x0 = float(np.min(planform.x_le))
    x1 = float(np.max(planform.x_le + planform.chord))
    xs = x0 + (x1 - x0) * _chord_nodes(int(n_chord), spacing, edges)
    h = float(xs[1] - xs[0])
    side = _stretched(h * ratio, far * c0, ratio)
    x = np.concatenate([xs[0] - side[::-1], xs, xs[-1] + side])
    semi = planform.semispan
    if edges == "faces":            # nodes 0, hy, ..., the tip at (n_span - 1/2) hy
        hy = semi / (int(n_span) - 0.5)
        ys = hy * np.arange(int(n_span) + 1)
    else:
        ys = np.linspace(0.0, semi, int(n_span) + 1)
        hy = float(ys[1] - ys[0])
    y = np.concatenate([ys, ys[-1] + _stretched(hy * ratio, far * c0, ratio)])
    z = np.concatenate([[0.0], _stretched(h, far * c0, ratio)])
    return Tsd3dGrid(x, y, z)


def biconvex_thickness(thickness_ratio: float) -> Callable[[np.ndarray], np.ndarray]:
    """The upper-surface ordinate per local chord, t(xi) = z_t / c = 2 tau xi (1 - xi), of a
    biconvex (parabolic-arc) section of thickness ratio tau (its slope is
    :func:`asekit.aero.tsd.biconvex`).

    >>> biconvex_thickness(0.1)(np.array([0.0, 0.5, 1.0])).tolist()
    [0.0, 0.05, 0.0]
    """
    tau = float(thickness_ratio)
    if not 0.0 <= tau < 0.3:
        raise ValueError(f"thickness_ratio must be in [0, 0.3) for a thin wing, got {tau!r}")
    return lambda xi: 2.0 * tau * np.asarray(xi, float) * (1.0 - np.asarray(xi, float))


def _half_cells(s: np.ndarray, closed_start: bool) -> np.ndarray:
    """Cell widths of nodes ``s`` (half cells at the ends)."""
    h = np.empty(s.size)
    d = np.diff(s)
    h[1:-1] = 0.5 * (s[2:] - s[:-2])
    h[0] = 0.5 * d[0] if closed_start else 0.0
    h[-1] = 0.5 * d[-1]
    return h


def _faces(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper face positions of the cells of nodes ``s`` (clipped at the ends)."""
    mid = 0.5 * (s[1:] + s[:-1])
    return np.concatenate([[s[0]], mid]), np.concatenate([mid, [s[-1]]])


def thickness_flux(planform: TsdPlanform, thickness, grid: Tsd3dGrid,
                   n_sub: int = 8) -> np.ndarray:
    """(n_x, n_y) flux int int dz_t/dx dx dy through the bottom face (z = 0) of each cell:
    exact in x (c(y) [t(xi_b) - t(xi_a)], xi clipped to the chord), midpoint rule on ``n_sub``
    strips in y (so a tip between nodes is resolved to 1/n_sub of a cell)."""
    xa, xb = _faces(grid.x)
    ya, yb = _faces(grid.y)
    out = np.zeros((grid.x.size, grid.y.size))
    frac = (np.arange(n_sub) + 0.5) / n_sub
    for j in range(grid.y.size):
        ys = ya[j] + (yb[j] - ya[j]) * frac
        xl, c = planform.edges(ys)
        w = (yb[j] - ya[j]) / n_sub
        for ysub, x0, cc in zip(ys, xl, c):
            if cc <= 0.0:
                continue
            ta = thickness(np.clip((xa - x0) / cc, 0.0, 1.0))
            tb = thickness(np.clip((xb - x0) / cc, 0.0, 1.0))
            out[:, j] += w * cc * (tb - ta)
    return out


# ---------------------------------------------------------------------------------------------
# the discrete operator
# ---------------------------------------------------------------------------------------------
class _Operator:
    """Eq. (1) on a grid: the cell volumes, the (constant) y-z Laplacian and the Murman-Cole
    x-operator's residual and Jacobian. Unknowns are the nodes off the Dirichlet boundaries
    (first and last x, last y, last z)."""

    def __init__(self, grid: Tsd3dGrid, mach: float, gamma: float, cross_flow: bool = False):
        self.grid = grid
        nx, ny, nz = self.shape = grid.shape
        self.dx = np.diff(grid.x)
        self.hx = _half_cells(grid.x, False)
        self.hx[0] = 0.0
        self.hy = _half_cells(grid.y, True)
        self.hz = _half_cells(grid.z, True)
        self.a0 = 1.0 - mach ** 2
        self.b = (gamma + 1.0) * mach ** 2
        self.node = np.arange(nx * ny * nz).reshape(nx, ny, nz)
        mask = np.zeros(self.shape, bool)
        mask[1:-1, :-1, :-1] = True
        self.idx = np.flatnonzero(mask.ravel())
        self.vol = (self.hx[:, None, None] * self.hy[None, :, None]
                    * self.hz[None, None, :])
        self.lap = self._laplacian()
        self.cross = _CrossFlow(self, mach, gamma) if cross_flow else None

    def _laplacian(self):
        """phi_yy + phi_zz times the cell volume (flux differences times face areas)."""
        nx, ny, nz = self.shape
        rows, cols, vals = [], [], []
        for axis, s, area in ((1, self.grid.y, self.hx[:, None, None] * self.hz[None, None, :]),
                              (2, self.grid.z, self.hx[:, None, None] * self.hy[None, :, None])):
            d = np.diff(s)
            lo = [slice(None)] * 3
            hi = [slice(None)] * 3
            lo[axis], hi[axis] = slice(0, -1), slice(1, None)
            shp = [1, 1, 1]
            shp[axis] = d.size
            coef = np.broadcast_to(area, self.shape)
            a_lo = coef[tuple(lo)] / d.reshape(shp)      # face between lo and hi nodes
            n_lo, n_hi = self.node[tuple(lo)], self.node[tuple(hi)]
            a_hi = coef[tuple(hi)] / d.reshape(shp)
            # cell of the lo node gains (phi_hi - phi_lo)/d times its face area, and so on
            for r, c, v in ((n_lo, n_hi, a_lo), (n_lo, n_lo, -a_lo), (n_hi, n_lo, a_hi),
                            (n_hi, n_hi, -a_hi)):
                rows.append(r.ravel())
                cols.append(c.ravel())
                vals.append(v.ravel())
        n = nx * ny * nz
        return sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                         np.concatenate(cols))),
                                 shape=(n, n)).tocsr()

    def switches(self, phi: np.ndarray) -> np.ndarray:
        """mu: 1 where A = 1 - M^2 - (gamma+1) M^2 phi_x < 0 (central phi_x), else 0."""
        mu = np.zeros(self.shape)
        u = (phi[2:] - phi[:-2]) / (self.grid.x[2:] - self.grid.x[:-2])[:, None, None]
        mu[1:-1] = (self.a0 - self.b * u) < 0.0
        return mu

    def x_parts(self, mu: np.ndarray):
        """The weights of Eq. (2) of :mod:`asekit.aero.tsd` for nodes i = 1 .. n_x - 2:
        central ``c`` = 1 - mu_i, upwind ``up`` = mu_{i-1} and the width ratio h_i / h_{i-1}."""
        nx = self.shape[0]
        i = np.arange(1, nx - 1)
        c = 1.0 - mu[i]
        up = mu[i - 1].copy()
        up[0] = 0.0
        ratio = (self.hx[i] / np.where(self.hx[i - 1] > 0, self.hx[i - 1], 1.0))[:, None, None]
        area = (self.hy[None, :, None] * self.hz[None, None, :])
        return i, c * area, up * ratio * area

    def residual(self, phi: np.ndarray, mu: np.ndarray, source: np.ndarray) -> np.ndarray:
        u = np.diff(phi, axis=0) / self.dx[:, None, None]
        f = self.a0 * u - 0.5 * self.b * u ** 2
        i, c, up = self.x_parts(mu)
        fm = np.concatenate([f[:1], f[:-2]])
        r = np.zeros(self.shape)
        r[1:-1] = c * (f[i] - f[i - 1]) + up * (f[i - 1] - fm)
        r = r.ravel() + self.lap @ phi.ravel() - source.ravel()
        if self.cross is not None:
            r = r + self.cross.residual(phi, mu)
        return r[self.idx]

    def x_jacobian(self, a: np.ndarray, mu: np.ndarray, dtype=float):
        """The x-operator's matrix for face coefficients ``a`` = df/du / dx (n_x - 1, ...)."""
        n = int(np.prod(self.shape))
        i, c, up = self.x_parts(mu)
        node = self.node
        im2 = np.maximum(i - 2, 0)
        entries = ((node[i + 1], c * a[i]),
                   (node[i], -c * a[i] - c * a[i - 1] + up * a[i - 1]),
                   (node[i - 1], c * a[i - 1] - up * a[i - 1] - up * a[i - 2]),
                   (node[im2], up * a[i - 2]))
        rows = np.concatenate([node[i].ravel()] * 4)
        cols = np.concatenate([e[0].ravel() for e in entries])
        vals = np.concatenate([np.asarray(e[1], dtype).ravel() for e in entries])
        return sparse.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()

    def jacobian(self, phi: np.ndarray, mu: np.ndarray):
        u = np.diff(phi, axis=0) / self.dx[:, None, None]
        a = (self.a0 - self.b * u) / self.dx[:, None, None]
        J = self.x_jacobian(a, mu) + self.lap
        if self.cross is not None:
            J = J + self.cross.jacobian(phi, mu)
        return J[self.idx][:, self.idx].tocsc()


# --- issue 29 (tsdswept): the cross-flow terms of swept wings --------------------------------
def cross_flow_coefficients(mach: float, gamma: float = GAMMA_AIR) -> tuple[float, float]:
    """(G, H) of the cross-flow terms of the modified TSD equation (Batina 1989, J. Aircraft
    26(6) 531-538, Eq. 1: x-flux + G phi_y^2, y-flux + H phi_x phi_y), G = (gamma - 3) M^2 / 2,
    H = -(gamma - 1) M^2: with these, expanded, the terms are -(gamma - 1) M^2 phi_x phi_yy -
    2 M^2 phi_y phi_xy, the cross-flow terms of the full-potential expansion kept by Ballhaus,
    Bailey & Frick (1977, "Improved computational treatment of transonic flow about swept
    wings", NASA CP-2001, pp. 1311-1320) for swept wings.

    >>> [round(c, 12) for c in cross_flow_coefficients(0.5, 1.4)]
    [-0.2, -0.1]
    """
    m2 = float(mach) ** 2
    return 0.5 * (float(gamma) - 3.0) * m2, -(float(gamma) - 1.0) * m2


def _coo(rows, cols, vals, shape):
    return sparse.coo_matrix((np.concatenate([np.ravel(v) for v in vals]),
                              (np.concatenate([np.ravel(r) for r in rows]),
                               np.concatenate([np.ravel(c) for c in cols]))),
                             shape=shape).tocsr()


class _CrossFlow:
    """The cross-flow terms (:func:`cross_flow_coefficients`) of an :class:`_Operator`, finite
    volume like the rest: the x-face flux G v^2 (v = phi_y at the x-faces, the mean of the
    central phi_y of the two nodes; 0 on the root plane) differenced by the operator's
    Murman-Cole x-operator, and the y-face flux H u v (u = phi_x at the y-faces, the mean of
    the central phi_x of the two nodes; v the face's difference) through the y-faces."""

    def __init__(self, op: "_Operator", mach: float, gamma: float):
        self.op = op
        self.g, self.h = cross_flow_coefficients(mach, gamma)
        nx, ny, nz = op.shape
        node, n = op.node, nx * ny * nz
        x, y = op.grid.x, op.grid.y
        # central phi_y at the nodes (0 on the root plane, one-sided at the far y boundary)
        j = np.arange(1, ny - 1)
        dyc = (y[j + 1] - y[j - 1])[None, :, None]
        one = np.ones((nx, j.size, nz))
        d_last = 1.0 / (y[-1] - y[-2]) * np.ones((nx, nz))
        cy = _coo([node[:, j], node[:, j], node[:, -1], node[:, -1]],
                  [node[:, j + 1], node[:, j - 1], node[:, -1], node[:, -2]],
                  [one / dyc, -one / dyc, d_last, -d_last], (n, n))
        # central phi_x at the nodes (one-sided at the ends)
        i = np.arange(1, nx - 1)
        dxc = (x[i + 1] - x[i - 1])[:, None, None]
        onex = np.ones((i.size, ny, nz))
        e0 = np.ones((ny, nz)) / (x[1] - x[0])
        e1 = np.ones((ny, nz)) / (x[-1] - x[-2])
        cx = _coo([node[i], node[i], node[0], node[0], node[-1], node[-1]],
                  [node[i + 1], node[i - 1], node[1], node[0], node[-1], node[-2]],
                  [onex / dxc, -onex / dxc, e0, -e0, e1, -e1], (n, n))
        # x-face (i + 1/2) means and y-face (j + 1/2) means and differences
        fx = np.arange((nx - 1) * ny * nz).reshape(nx - 1, ny, nz)
        fy = np.arange(nx * (ny - 1) * nz).reshape(nx, ny - 1, nz)
        half_x = 0.5 * np.ones(fx.shape)
        half_y = 0.5 * np.ones(fy.shape)
        self.vx = _coo([fx, fx], [node[:-1], node[1:]], [half_x, half_x],
                       (fx.size, n)) @ cy
        self.uy = _coo([fy, fy], [node[:, :-1], node[:, 1:]], [half_y, half_y],
                       (fy.size, n)) @ cx
        inv = np.broadcast_to((1.0 / np.diff(y))[None, :, None], fy.shape)
        self.dy = _coo([fy, fy], [node[:, 1:], node[:, :-1]], [inv, -inv], (fy.size, n))
        # the y-faces' fluxes into the nodes' cells (face areas hx hz, as the Laplacian)
        area = np.broadcast_to(op.hx[:, None, None] * op.hz[None, None, :], fy.shape)
        self.ydiv = _coo([node[:, :-1], node[:, 1:]], [fy, fy], [area, -area], (n, fy.size))
        self.fx = fx

    def sx(self, mu: np.ndarray):
        """The Murman-Cole x-operator (n_nodes x n_x-faces) of :meth:`_Operator.residual`."""
        op = self.op
        i, c, up = op.x_parts(mu)
        fx, node = self.fx, op.node
        im2 = np.maximum(i - 2, 0)
        n = int(np.prod(op.shape))
        return _coo([node[i]] * 4, [fx[i], fx[i - 1], fx[i - 1], fx[im2]],
                    [c, -c, up, -up], (n, fx.size))

    def residual(self, phi: np.ndarray, mu: np.ndarray) -> np.ndarray:
        p = phi.ravel()
        v = self.vx @ p
        return (self.sx(mu) @ (self.g * v * v)
                + self.ydiv @ (self.h * (self.uy @ p) * (self.dy @ p)))

    def jacobian(self, phi: np.ndarray, mu: np.ndarray):
        """The terms' derivative at ``phi`` (also their time-linearisation about it)."""
        p = phi.ravel()
        v = self.vx @ p
        u, d = self.uy @ p, self.dy @ p
        return (self.sx(mu) @ sparse.diags(2.0 * self.g * v) @ self.vx
                + self.ydiv @ (sparse.diags(self.h * u) @ self.dy
                               + sparse.diags(self.h * d) @ self.uy))


# ---------------------------------------------------------------------------------------------
# steady thickness flow
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Tsd3dSolution:
    """A converged (or the last) steady 3-D TSD solution.

    Attributes
    ----------
    planform, grid : the wing and the grid.
    phi : (n_x, n_y, n_z) perturbation potential per U (planform length unit).
    cp : (n_x - 1, n_y) upper-surface Cp = -2 phi_x on z = 0 at the x midpoints
        ``x_mid`` (n_x - 1,) of the grid and the span stations ``grid.y``.
    mach, gamma : free-stream Mach number and ratio of specific heats.
    converged, iterations, residual : the continuation's state (residual relative to that of
        phi = 0).
    supersonic_points : nodes with A < 0.
    seconds : wall time of the solve.
    cross_flow : the cross-flow terms of swept wings were included (:func:`steady_tsd3d`).
    """

    planform: TsdPlanform
    grid: Tsd3dGrid
    phi: np.ndarray
    x_mid: np.ndarray
    cp: np.ndarray
    mach: float
    gamma: float
    converged: bool
    iterations: int
    residual: float
    supersonic_points: int
    seconds: float
    cross_flow: bool = False

    @property
    def cp_critical(self) -> float:
        """Cp* = -2 (1 - M^2) / ((gamma + 1) M^2), the small-disturbance sonic Cp."""
        return -2.0 * (1.0 - self.mach ** 2) / ((self.gamma + 1.0) * self.mach ** 2)

    def section_cp(self, y: float) -> tuple[np.ndarray, np.ndarray]:
        """(xi, Cp) on the chord at the grid station nearest ``y``: xi the local chord
        fraction of the x midpoints inside the chord."""
        j = int(np.argmin(np.abs(self.grid.y - y)))
        xl, c = self.planform.edges(self.grid.y[j])
        xi = (self.x_mid - xl) / c
        on = (xi > 0.0) & (xi < 1.0)
        return xi[on], self.cp[on, j]


def steady_tsd3d(planform: TsdPlanform, thickness, mach: float, grid: Tsd3dGrid | None = None,
                 gamma: float = GAMMA_AIR, tol: float = 1e-9, max_iter: int = 60,
                 cross_flow: bool = False) -> Tsd3dSolution:
    """Steady TSD flow about a thin symmetric wing at zero incidence (Eq. 1 of the module).

    Parameters
    ----------
    planform : :class:`TsdPlanform` (half wing, root plane y = 0).
    thickness : callable xi -> z_t / c on the chord fraction 0 <= xi <= 1 (0 at both ends),
        e.g. :func:`biconvex_thickness`.
    mach : free-stream Mach number, 0 <= M < 1.3.
    grid : :func:`tsd3d_grid` (default ``tsd3d_grid(planform)``).
    gamma : ratio of specific heats (1.4; -1 gives the linear equation).
    tol : tolerance on the max-norm residual relative to that of phi = 0.
    max_iter : pseudo-time steps at most.
    cross_flow : add the cross-flow terms of swept wings (Eq. 1b of the module; issue 29,
        tsdswept); the equation is then nonlinear even with gamma = -1 (only thickness -> 0
        is the linear limit).

    Returns
    -------
    :class:`Tsd3dSolution` (check ``converged``).
    """
    import time

    mach = tsd_mach(mach)
    grid = tsd3d_grid(planform) if grid is None else grid
    t0 = time.perf_counter()
    op = _Operator(grid, mach, float(gamma), bool(cross_flow))
    src = np.zeros(grid.shape)
    src[:, :, 0] = thickness_flux(planform, thickness, grid)
    phi = np.zeros(grid.shape)
    r0 = float(np.max(np.abs(op.residual(phi, np.zeros(grid.shape), src)))) or 1.0
    phi, steps = _continuation(op, phi, src, tol * r0, max_iter, float(planform.chord[0]) ** 2)
    mu = op.switches(phi)
    res = float(np.max(np.abs(op.residual(phi, mu, src)))) / r0
    u = np.diff(phi[:, :, 0], axis=0) / op.dx[:, None]
    return Tsd3dSolution(planform, grid, phi, 0.5 * (grid.x[1:] + grid.x[:-1]), -2.0 * u, mach,
                         float(gamma), res <= tol, steps, res, int(mu.sum()),
                         time.perf_counter() - t0, bool(cross_flow))


def _continuation(op: _Operator, phi: np.ndarray, src: np.ndarray, tol: float, max_iter: int,
                  dtau0: float):
    """Pseudo-transient continuation (Kelley & Keyes 1998, SIAM J. Numer. Anal. 35(2)) as in
    :func:`asekit.aero.tsd._ptc`: steps (V / dtau - J) dphi = R, dtau grown as the residual
    falls (switched evolution relaxation), so the last steps are Newton's method; ``dtau0``
    the first step (a length squared: the root chord's square, as the 2-D solver's 1 chord^2)."""
    vol = op.vol.ravel()[op.idx]
    mu = op.switches(phi)
    r = op.residual(phi, mu, src)
    res = r_first = max(float(np.max(np.abs(r))), 1e-300)
    for it in range(1, max_iter + 1):
        if res <= tol:
            return phi, it - 1
        linear = op.b == 0.0 and op.cross is None
        dtau = np.inf if linear else dtau0 * r_first / res         # linear: one Newton step
        J = op.jacobian(phi, mu)
        step = splu((sparse.diags(vol / dtau) - J).tocsc()).solve(r)
        flat = phi.ravel().copy()
        flat[op.idx] += step
        phi = flat.reshape(phi.shape)
        mu = op.switches(phi)
        r = op.residual(phi, mu, src)
        res = float(np.max(np.abs(r)))
    return phi, max_iter


# ---------------------------------------------------------------------------------------------
# time-linearised lifting problem about the steady background
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HarmonicTsd3dSolution:
    """The lifting potential of harmonic motions about a steady 3-D TSD background.

    Attributes
    ----------
    grid : the background's grid.
    phi : (n_modes, n_x, n_y) complex upper-surface potential per U (length unit) on z = 0+
        per unit modal amplitude (antisymmetric: the lower surface carries -phi).
    wing : (n_x, n_y) bool, the nodes on the planform (the flux condition).
    kappa : omega / U (1 / length unit); asekit's k is kappa b_ref.
    planform : the wing (:func:`box_pressures` samples each grid row at the boxes' chord
        fractions on it; None: at the boxes' own abscissae).
    """

    grid: Tsd3dGrid
    phi: np.ndarray
    wing: np.ndarray
    kappa: float
    planform: TsdPlanform | None = None

    def delta_cp(self) -> np.ndarray:
        """(n_modes, n_x - 1, n_y) pressure jump Cp_lower - Cp_upper = 4 (phi_x + i kappa phi)
        at the x midpoints (positive: lift up)."""
        dx = np.diff(self.grid.x)[None, :, None]
        mid = 0.5 * (self.phi[:, 1:] + self.phi[:, :-1])
        return 4.0 * (np.diff(self.phi, axis=1) / dx + 1j * self.kappa * mid)


def _surface_sets(planform: TsdPlanform, grid: Tsd3dGrid):
    """Node sets on z = 0: the wing (the flux condition), the wake behind it (the convected
    jump) and the rest (phi = 0 by antisymmetry)."""
    xl, c = planform.edges(grid.y)
    x = grid.x[:, None]
    inside = (c > 0.0)[None, :]
    wing = inside & (x > xl[None, :]) & (x < (xl + c)[None, :])
    wake = inside & (x >= (xl + c)[None, :])
    return wing, wake


def _time_term(kappa: float, mach: float, vol: np.ndarray, span: np.ndarray, x: np.ndarray,
               i: np.ndarray, mu: np.ndarray):
    """The term -2 i kappa M^2 phi1_x of Eq. (3) times the cell volume at nodes ``i``: central
    (phi_{i+1} - phi_{i-1}) / (x_{i+1} - x_{i-1}) where the background is subsonic (mu 0), the
    backward (phi_i - phi_{i-1}) / (x_i - x_{i-1}) where it is supersonic (mu 1), as the
    Murman-Cole switch does for the x-flux (issue 29, tsdfin: a central difference there
    reaches one node downstream, against the supersonic domain of dependence). Returns the
    coefficients ((of phi_{i+1}, negated), (of phi_{i-1})) and the diagonal's (negated)."""
    m = mu[i]
    c = 2j * kappa * mach ** 2 * vol / span * (1.0 - m)
    back = 2j * kappa * mach ** 2 * vol / (x[i] - x[i - 1])[:, None, None] * m
    return (c, c + back), back


def _lifting_matrix(background: Tsd3dSolution, kappa: float, wing, wake):
    """The time-linearised operator (Eq. 3 of :mod:`asekit.aero.tsd` in 3-D) with its
    boundary rows, over all nodes (i, j, k) -> (i n_y + j) n_z + k."""
    grid, mach = background.grid, background.mach
    op = _Operator(grid, mach, background.gamma, background.cross_flow)
    nx, ny, nz = grid.shape
    n = nx * ny * nz
    u0 = np.diff(background.phi, axis=0) / op.dx[:, None, None]
    a = (op.a0 - op.b * u0) / op.dx[:, None, None]
    node = op.node
    i = np.arange(1, nx - 1)
    vol = op.vol[i]
    span = (grid.x[i + 1] - grid.x[i - 1])[:, None, None]
    mu0 = op.switches(background.phi)
    t, diag = _time_term(kappa, mach, vol, span, grid.x, i, mu0)
    rows = np.concatenate([node[i].ravel()] * 3)
    cols = np.concatenate([node[i].ravel(), node[i + 1].ravel(), node[i - 1].ravel()])
    vals = np.concatenate([(vol * mach ** 2 * kappa ** 2 - diag).ravel(), -t[0].ravel(),
                           t[1].ravel()])
    # radiation through the outboard and upper faces, phi_n + i K phi = 0 with the acoustic
    # wavenumber K = kappa M / beta of Eq. (3) (after phi = psi exp(i kappa M^2 x / beta^2) it
    # is beta^2 psi_xx + psi_yy + psi_zz + K^2 psi = 0; first-order Sommerfeld condition:
    # walls there would make a closed, resonant wind tunnel at kappa > 0)
    k_ac = kappa * mach / np.sqrt(max(1.0 - mach ** 2, 1e-6))
    top = op.node[i, :, -1]
    side = op.node[i, -1, :]
    rows = np.concatenate([rows, top.ravel(), side.ravel()])
    cols = np.concatenate([cols, top.ravel(), side.ravel()])
    vals = np.concatenate([vals,
                           np.broadcast_to(-1j * k_ac * op.hx[i, None] * op.hy[None, :],
                                           top.shape).ravel(),
                           np.broadcast_to(-1j * k_ac * op.hx[i, None] * op.hz[None, :],
                                           side.shape).ravel()])
    K = (op.x_jacobian(a, mu0, complex) + op.lap
         + sparse.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr())
    if op.cross is not None:        # the cross-flow terms linearised about phi0 (tsdswept)
        K = K + op.cross.jacobian(background.phi, mu0)
    # replaced rows: upstream phi_x = 0, downstream phi_x + i kappa phi = 0, z = 0 off the
    # wing: phi = 0 (antisymmetry) or, on the wake, phi_i = phi_{i-1} exp(-i kappa dx)
    bi, bj, bv = [], [], []

    def put(r, c, v):
        r, c = np.broadcast_arrays(r, c)
        bi.append(r.ravel())
        bj.append(c.ravel())
        bv.append(np.broadcast_to(np.asarray(v, complex), r.shape).ravel())

    d0 = grid.x[1] - grid.x[0]
    k_up = kappa * mach / (1.0 - mach) if mach < 1.0 else 0.0
    put(node[0], node[0], -1.0 / d0 - 0.5j * k_up)
    put(node[0], node[1], 1.0 / d0 - 0.5j * k_up)
    d = grid.x[-1] - grid.x[-2]
    put(node[-1], node[-1], 1.0 / d + 0.5j * kappa)
    put(node[-1], node[-2], -1.0 / d + 0.5j * kappa)
    surf = np.zeros((nx, ny), bool)
    surf[1:-1] = True
    off = surf & ~wing & ~wake
    put(node[:, :, 0][off], node[:, :, 0][off], 1.0)
    iw, jw = np.nonzero(wake & surf)
    put(node[iw, jw, 0], node[iw, jw, 0], 1.0)
    put(node[iw, jw, 0], node[iw - 1, jw, 0],
        -np.exp(-1j * kappa * (grid.x[iw] - grid.x[iw - 1])))
    replaced = np.zeros(n, bool)
    replaced[np.concatenate(bi)] = True
    B = sparse.coo_matrix((np.concatenate(bv), (np.concatenate(bi), np.concatenate(bj))),
                          shape=(n, n)).tocsr()
    return (sparse.diags((~replaced).astype(float)) @ K + B).tocsc(), op


def harmonic_tsd3d(background: Tsd3dSolution, modes, kappa: float) -> HarmonicTsd3dSolution:
    """Time-linearised TSD about a steady 3-D solution: the antisymmetric (lifting) potential
    phi1 e^{i omega t} of harmonic modal motions at kappa = omega / U.

    The unsteady TSD equation (e.g. Batina 1989, J. Aircraft 26(6) 531-538, Eq. 1, without
    the cross-flow terms; time per length / U), linearised about the steady phi0, is for the
    harmonic amplitude phi1 (per U, a length)

        [A0 phi1_x]_x + phi1_yy + phi1_zz + M^2 kappa^2 phi1 - 2 i kappa M^2 phi1_x = 0,
        A0 = 1 - M^2 - (gamma + 1) M^2 phi0_x,                                         (3)

    differenced as the steady operator (the background's Murman-Cole switches for the x term,
    phi1_x of the time term central, backward at supersonic nodes since issue 29 tsdfin,
    :func:`_time_term`). On z = 0+: phi1_z = w/U = dh/dx + i kappa h on the wing (h the upward
    displacement of the mode), phi1 = 0 off the wing and wake (antisymmetry), and on the wake
    a continuous pressure phi1_x + i kappa phi1 = 0, solved exactly along the wake
    (phi1 = phi1_TE exp(-i kappa (x - x_TE)): the jump is convected and the trailing edge
    carries the Kutta condition); phi1_y = 0 on the root plane (symmetric motions of a
    mirrored half wing), phi1_x + i kappa phi1 = 0 downstream, and first-order radiation
    conditions of the acoustic waves of Eq. (3) elsewhere: phi1_n + i K phi1 = 0,
    K = kappa M / beta, on the outboard and upper boundaries, and phi1_x - i kappa M / (1 - M)
    phi1 = 0 upstream (the upstream-running wave; zero flux / phi1_x = 0 at kappa = 0).
    At high subsonic Mach the upstream wave is short (wavelength 2 pi (1 - M) / (kappa M)),
    so the stretched far field resolves it poorly: at M 0.8, k = 0.3 the GAFs still move by
    several per cent with the far-field extent (a limitation of this first version; a
    non-reflecting far field is the next step). One sparse LU per kappa solves all
    modes. Use a grid with ``edges="faces"`` (:func:`tsd3d_grid`). The complex system is
    solved in its real form (see ``_solve``).

    Parameters
    ----------
    background : :class:`Tsd3dSolution` (zero thickness gives the linear lifting problem).
    modes : list of callables f(x, y) -> (h, dh/dx) (as :func:`asekit.aero.spline.analytic_modes`).
    kappa : omega / U >= 0 (1 / length unit).

    Examples
    --------
    >>> wing = TsdPlanform.rectangular(1.0, 1.0)
    >>> g = tsd3d_grid(wing, 8, 4, far=4.0, ratio=1.5, edges="faces")
    >>> bg = steady_tsd3d(wing, biconvex_thickness(0.0), 0.5, g)
    >>> sol = harmonic_tsd3d(bg, [lambda x, y: (0 * x, -1 + 0 * x)], 0.0)   # unit incidence
    >>> bool(np.all(sol.delta_cp()[0][sol.wing[1:] & sol.wing[:-1]].real > 0))
    True
    """
    kappa = float(kappa)
    if not (np.isfinite(kappa) and kappa >= 0.0):
        raise ValueError(f"kappa must be finite and >= 0, got {kappa!r}")
    X, Y = np.meshgrid(background.grid.x, background.grid.y, indexing="ij")
    wash = []
    for f in modes:
        h, dh = (np.broadcast_to(np.asarray(v, float), X.shape) for v in f(X, Y))
        wash.append(dh + 1j * kappa * h)
    return _harmonic_solve(background, np.array(wash), kappa)


def _harmonic_solve(background: Tsd3dSolution, wash: np.ndarray, kappa: float
                    ) -> HarmonicTsd3dSolution:
    """Eq. (3) for normalwash columns ``wash`` (n_cols, n_x, n_y) on the z = 0 nodes (used on
    the wing nodes only)."""
    grid = background.grid
    wing, wake = _surface_sets(background.planform, grid)
    K, op = _lifting_matrix(background, kappa, wing, wake)
    nx, ny, nz = grid.shape
    area = op.hx[:, None] * op.hy[None, :]
    rhs = np.zeros((nx * ny * nz, wash.shape[0]), complex)
    rhs[op.node[:, :, 0][wing]] = (area[None] * wash)[:, wing].T
    phi = _solve(K, rhs).reshape(nx, ny, nz, wash.shape[0])
    return HarmonicTsd3dSolution(grid, np.moveaxis(phi[:, :, 0, :], -1, 0), wing, kappa,
                                 background.planform)


def _solve(K, rhs: np.ndarray) -> np.ndarray:
    """K x = rhs by sparse LU: real when K is (kappa = 0), else in the interleaved real form
    [[Re, -Im], [Im, Re]] per node (SuperLU's complex factorisation was measured 10-200 times
    slower than the real one of twice the size on these grids)."""
    K = K.tocoo()
    if not np.any(K.data.imag):
        real = sparse.csc_matrix((K.data.real, (K.row, K.col)), shape=K.shape)
        lu = splu(real)
        return lu.solve(np.ascontiguousarray(rhs.real)) + 1j * lu.solve(
            np.ascontiguousarray(rhs.imag))
    r, c, v = K.row, K.col, K.data
    n = K.shape[0]
    R = sparse.csc_matrix((np.concatenate([v.real, -v.imag, v.imag, v.real]),
                           (np.concatenate([2 * r, 2 * r, 2 * r + 1, 2 * r + 1]),
                            np.concatenate([2 * c, 2 * c + 1, 2 * c, 2 * c + 1]))),
                          shape=(2 * n, 2 * n))
    b = np.empty((2 * n, rhs.shape[1]))
    b[0::2], b[1::2] = rhs.real, rhs.imag
    x = splu(R).solve(b)
    return x[0::2] + 1j * x[1::2]


def _to_row(planform: TsdPlanform | None, y_box: np.ndarray, y_row: float, xa: np.ndarray,
            xb: np.ndarray, x: np.ndarray, wing_row: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """Box chordwise limits ``xa``, ``xb`` taken at span stations ``y_box`` moved to the grid
    row ``y_row`` (nodes ``x``, wing nodes ``wing_row``) at equal local chord fraction, the
    chord [0, 1] mapped onto the row's last node ahead of the wing and first wake node (issue
    29, tsdswept). A row stands for the potential of its band of span: on a swept or tapered
    wing the edges move across the band, and sampling the row at the boxes' own abscissae put
    the first boxes' x_a behind the row's leading edge and the last boxes' x_b ahead of its
    trailing edge on half the band (a 45-deg wing's lift 23 % low); and the edges lie between
    nodes, so the interpolated potential at them dropped half an edge cell of the jump (the
    rectangular wing's lift 9 % low on 12 x 6 cells). With the map, the boxes of a strip sum
    to the row's whole jump, the solver's circulation 4 phi(first wake node). Unchanged
    without a planform or on a row off the wing."""
    if planform is None:
        return xa, xb
    on = np.flatnonzero(wing_row)
    if on.size == 0 or on[0] == 0 or on[-1] + 1 >= x.size:
        return xa, xb
    x0, x1 = x[on[0] - 1], x[on[-1] + 1]
    xl_b, c_b = planform.edges(y_box)
    c_b = np.where(c_b > 0.0, c_b, 1.0)
    return x0 + (xa - xl_b) / c_b * (x1 - x0), x0 + (xb - xl_b) / c_b * (x1 - x0)


def box_pressures(solution: HarmonicTsd3dSolution, mesh) -> np.ndarray:
    """(n_boxes, n_modes) box-average pressure jumps of a :class:`~asekit.aero.boxes.BoxMesh`
    in z = 0: the integral of Delta Cp = 4 (phi_x + i kappa phi) over each box, exact in x for
    the piecewise-linear potential of each grid row (4 [phi]_{x_a}^{x_b} + 4 i kappa int phi
    dx), rows weighted by their cells' overlap with the box, divided by the box area. With
    the solution's planform, each row is sampled at the boxes' chord fractions between its own
    edge nodes (``_to_row``, issue 29 tsdswept)."""
    grid, kap = solution.grid, solution.kappa
    x = grid.x
    dx = np.diff(x)
    phi = solution.phi                                         # (m, nx, ny)
    cum = np.concatenate([np.zeros_like(phi[:, :1]),
                          np.cumsum(0.5 * (phi[:, 1:] + phi[:, :-1]) * dx[None, :, None],
                                    axis=1)], axis=1)
    ya, yb = _faces(grid.y)
    c = mesh.corners
    y_in = np.minimum(c[:, 0, 1], c[:, 3, 1])
    y_out = np.maximum(c[:, 0, 1], c[:, 3, 1])
    force = np.zeros((mesh.n, phi.shape[0]), complex)

    def values(xq, j):
        i = np.clip(np.searchsorted(x, xq) - 1, 0, x.size - 2)
        t = xq - x[i]
        p0, p1 = phi[:, i, j], phi[:, i + 1, j]
        slope = (p1 - p0) / dx[i]
        return p0 + slope * t, cum[:, i, j] + p0 * t + 0.5 * slope * t ** 2

    for j in range(grid.y.size):
        lo, hi = np.maximum(ya[j], y_in), np.minimum(yb[j], y_out)
        w = np.clip(hi - lo, 0.0, None)
        if not np.any(w > 0):
            continue
        y_mid = 0.5 * (lo + hi)
        eta = (y_mid - c[:, 0, 1]) / (c[:, 3, 1] - c[:, 0, 1])
        xa = c[:, 0, 0] + eta * (c[:, 3, 0] - c[:, 0, 0])
        xb = c[:, 1, 0] + eta * (c[:, 2, 0] - c[:, 1, 0])
        xa, xb = _to_row(solution.planform, y_mid, grid.y[j], xa, xb, x, solution.wing[:, j])
        pa, ca = values(xa, j)
        pb, cb = values(xb, j)
        force += (w * 4.0 * ((pb - pa) + 1j * kap * (cb - ca))).T
    return force / mesh.area[:, None]


def tsd_gaf(background: Tsd3dSolution, mesh, modes, k, b_ref: float) -> np.ndarray:
    """Q(M, k) (n_k, n_modes, n_modes) per unit dynamic pressure of analytic ``modes``
    (callables f(x, y) -> (h, dh/dx), the surface's length unit) about a steady background:
    one :func:`harmonic_tsd3d` per k (kappa = k / b_ref), :func:`box_pressures` on ``mesh``
    and Q = H_lp^T diag(A) Delta Cp, H_lp the modes at the boxes' load points (quarter chord,
    as the DLM; the box-average pressure's own centroid would move the pitch moment of the
    test wing by about 15 % on 12 boxes: the projection, not the solver, then dominates) (:func:`asekit.aero.spline.modal_forces`, thesis
    Eqs. 2.10-2.11, as the DLM's GAFs)."""
    from asekit.aero.spline import analytic_modes, modal_forces

    if not (np.isfinite(b_ref) and b_ref > 0.0):
        raise ValueError(f"b_ref must be a finite semi-chord > 0, got {b_ref!r}")
    ks = np.atleast_1d(np.asarray(k, float))
    bm = analytic_modes(mesh, modes)
    return np.stack([modal_forces(bm, box_pressures(harmonic_tsd3d(background, modes,
                                                                   kk / b_ref), mesh),
                                  mesh.area) for kk in ks])


def planform_of_boxes(mesh) -> TsdPlanform:
    """The :class:`TsdPlanform` covered by the boxes of a planar (z = 0) box mesh whose strips
    tile a half wing from y = 0: per distinct strip edge y, the most forward leading edge and
    the most aft trailing edge of the boxes there (straight-tapered between strip edges)."""
    c = np.asarray(mesh.corners, float)
    if np.any(np.abs(c[:, :, 2]) > 1e-9):
        raise ValueError("the TSD planform needs boxes in the plane z = 0")
    y = np.unique(np.round(np.concatenate([c[:, 0, 1], c[:, 3, 1]]), 12))
    le, te = np.full(y.size, np.inf), np.full(y.size, -np.inf)
    for a, b in ((0, 1), (3, 2)):                      # inboard and outboard edges
        j = np.searchsorted(y, np.round(c[:, a, 1], 12))
        np.minimum.at(le, j, c[:, a, 0])
        np.maximum.at(te, j, c[:, b, 0])
    if abs(y[0]) > 1e-9:
        raise ValueError(f"the boxes must start at the root y = 0 (the symmetry plane), "
                         f"got y = {y[0]!r}")
    return TsdPlanform(y, le, te - le)


def _box_of_nodes(mesh, grid: Tsd3dGrid, wing: np.ndarray) -> np.ndarray:
    """(n_x, n_y) index of the box holding each wing node (-1 off the boxes)."""
    c = mesh.corners
    X, Y = np.meshgrid(grid.x, grid.y, indexing="ij")
    out = np.full(X.shape, -1)
    for b in range(mesh.n):
        y0, y1 = c[b, 0, 1], c[b, 3, 1]
        eta = (Y - y0) / (y1 - y0)
        xa = c[b, 0, 0] + eta * (c[b, 3, 0] - c[b, 0, 0])
        xb = c[b, 1, 0] + eta * (c[b, 2, 0] - c[b, 1, 0])
        out[wing & (eta >= 0) & (eta < 1) & (X >= xa) & (X < xb)] = b
    return out


#: Cells of the grid a box mesh gets (:func:`tsd_grid_options`): per chordwise box, per strip.
CELLS_PER_BOX = (2, 1)
#: The far boundary (root chords) and stretching ratio of that grid (the tests' values).
GRID_FAR, GRID_RATIO = 6.0, 1.3
#: Largest grid (nodes) a case may ask for: the complex harmonic system is solved in its real
#: form of twice the size by sparse LU, about n^1.5-2: 4e4 nodes take tens of seconds per k.
MAX_NODES = 40_000


def tsd_grid_options(n_chord_boxes: int, n_strips: int) -> dict:
    """The :func:`tsd3d_grid` options of a box mesh with ``n_chord_boxes`` boxes per strip and
    ``n_strips`` strips (asekit's rule): n_chord = max(8, 2 n_chord_boxes) chordwise cells
    (the harmonic GAFs are first order in the cell size: 7.8 %, 5.9 %, 4.9 % from the DLM's
    on 8, 12, 16 chordwise cells at M 0.8, k = 0.3, max entry, the rectangular wing of
    tests/aero/test_tsd3d.py; 12 %, 8 %, 6 % before issue 29's tsdswept projection fix), n_span =
    max(4, n_strips) spanwise cells, the far boundary :data:`GRID_FAR` root chords away,
    stretching :data:`GRID_RATIO`, edges between nodes.

    >>> tsd_grid_options(4, 4)["n_chord"], tsd_grid_options(4, 4)["n_span"]
    (8, 4)
    """
    return dict(n_chord=max(8, 2 * int(n_chord_boxes)), n_span=max(4, int(n_strips)),
                far=GRID_FAR, ratio=GRID_RATIO, edges="faces")


def mesh_grid_options(mesh) -> dict:
    """:func:`tsd_grid_options` of a box mesh: its most boxes per strip and its strips."""
    per_strip = np.unique(mesh.strip, return_counts=True)[1]
    return tsd_grid_options(int(per_strip.max()), per_strip.size)


def grid_nodes(planform: TsdPlanform, options: dict) -> int:
    """Nodes of :func:`tsd3d_grid` ``(planform, **options)`` (cheap: no solve).

    >>> grid_nodes(TsdPlanform.rectangular(1.0, 1.5), tsd_grid_options(4, 4))
    6688
    """
    nx, ny, nz = tsd3d_grid(planform, **options).shape
    return nx * ny * nz


def tsd_pressure_matrices(mesh, mach: float, k, b_ref: float, thickness=None,
                          grid_options: dict | None = None, gamma: float = GAMMA_AIR,
                          background: Tsd3dSolution | None = None) -> np.ndarray:
    """Pressure-per-normalwash matrices A (n_k, n, n), DeltaCp = A (w/U), of the boxes of a
    planar half-wing mesh (root y = 0 a symmetry plane) by the time-linearised TSD: each box's
    unit normalwash is applied on the grid nodes inside it, :func:`harmonic_tsd3d`'s operator
    solved for all boxes at once per k (kappa = k / b_ref), and :func:`box_pressures` taken.
    ``thickness`` (callable xi -> z_t / c, default none) gives the steady background
    (:func:`steady_tsd3d`, computed once unless ``background`` is given); ``grid_options``
    go to :func:`tsd3d_grid` (``edges="faces"`` always).

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 1.0, 0), 1.0, 2, 2)])
    >>> a = tsd_pressure_matrices(mesh, 0.5, [0.0], 0.5,
    ...                           grid_options=dict(n_chord=8, n_span=4, far=3.0, ratio=1.5))
    >>> a.shape, bool(np.all((a[0] @ -np.ones(4)).real > 0))     # a unit incidence lifts
    ((1, 4, 4), True)
    """
    if not (np.isfinite(b_ref) and b_ref > 0.0):
        raise ValueError(f"b_ref must be a finite semi-chord > 0, got {b_ref!r}")
    ks = np.atleast_1d(np.asarray(k, float))
    if background is None:
        planform = planform_of_boxes(mesh)
        opts = dict(grid_options or {})
        opts["edges"] = "faces"
        grid = tsd3d_grid(planform, **opts)
        background = steady_tsd3d(planform, thickness or (lambda xi: 0.0 * xi), mach, grid,
                                  gamma=gamma)
        if not background.converged:
            raise ValueError(f"the steady TSD background did not converge at M {mach:g} "
                             f"(residual {background.residual:.2g}); refine or change the grid")
    wing, _ = _surface_sets(background.planform, background.grid)
    owner = _box_of_nodes(mesh, background.grid, wing)
    out = np.empty((ks.size, mesh.n, mesh.n), complex)
    for ik, kk in enumerate(ks):
        wash = np.zeros((mesh.n,) + owner.shape, complex)
        i, j = np.nonzero(owner >= 0)
        wash[owner[i, j], i, j] = 1.0
        out[ik] = box_pressures(_harmonic_solve(background, wash, kk / b_ref), mesh)
    return out


# --- the validity of a TSD result (issue 29) ------------------------------------------------
@dataclass(frozen=True)
class TsdValidity:
    """What a steady TSD background says about the trust in its time-linearised loads.

    Attributes
    ----------
    mach, thickness_ratio : free stream and section thickness ratio tau.
    similarity : von Karman's transonic similarity parameter K = (1 - M^2) / (M^2 tau)^(2/3)
        (von Karman 1947, J. Math. Phys. 26, 182-190; inf for tau = 0, the linear limit):
        flows of equal K are similar; K of order 1 or less is transonic.
    supersonic_points : grid nodes where the steady flow is supersonic (A < 0, Murman-Cole
        upwind); > 0 means a supersonic pocket, closed by a (captured) shock.
    cp_min, cp_critical : the lowest surface Cp of the background and the sonic Cp*.
    converged : the steady solve met its tolerance.
    """

    mach: float
    thickness_ratio: float
    similarity: float
    supersonic_points: int
    cp_min: float
    cp_critical: float
    converged: bool

    @property
    def shock(self) -> bool:
        """The background has a supersonic pocket (hence a shock)."""
        return self.supersonic_points > 0

    def text(self) -> str:
        """One line for the results and the report."""
        k = "inf (linear)" if math.isinf(self.similarity) else f"{self.similarity:.3g}"
        flow = (f"supersonic pocket ({self.supersonic_points} nodes) closed by a captured "
                f"shock: the loads assume small harmonic shock motion"
                if self.shock else "subcritical (no shock): the loads are those of the "
                "background-corrected linear equation")
        conv = "" if self.converged else "; NOT CONVERGED: do not use"
        return (f"TSD at M {self.mach:g}, tau {self.thickness_ratio:g}: similarity K = {k}, "
                f"Cp_min {self.cp_min:.3g} vs Cp* {self.cp_critical:.3g}, {flow}{conv}")


def tsd_validity(background: Tsd3dSolution, thickness_ratio: float) -> TsdValidity:
    """The :class:`TsdValidity` of a steady background of a section of thickness ratio
    ``thickness_ratio``: K = (1 - M^2) / (M^2 tau)^(2/3), the supersonic nodes, Cp_min over
    the planform and Cp* = -2 (1 - M^2) / ((gamma + 1) M^2).

    >>> wing = TsdPlanform.rectangular(1.0, 2.0)
    >>> g = tsd3d_grid(wing, 8, 4, far=4.0, ratio=1.4, edges="faces")
    >>> v = tsd_validity(steady_tsd3d(wing, biconvex_thickness(0.04), 0.5, g), 0.04)
    >>> round(v.similarity, 3), v.shock
    (16.158, False)
    """
    tau = float(thickness_ratio)
    if not 0.0 <= tau < 0.3:
        raise ValueError(f"thickness_ratio must be in [0, 0.3), got {tau!r}")
    m = background.mach
    k = math.inf if tau == 0.0 or m == 0.0 else (1.0 - m * m) / (m * m * tau) ** (2.0 / 3.0)
    xl, c = background.planform.edges(background.grid.y)
    xi = (background.x_mid[:, None] - xl[None, :]) / np.where(c > 0.0, c, 1.0)[None, :]
    on = (xi > 0.0) & (xi < 1.0) & (c > 0.0)[None, :]
    cp_min = float(np.min(background.cp[on])) if np.any(on) else 0.0
    return TsdValidity(m, tau, float(k), int(background.supersonic_points), cp_min,
                       float(background.cp_critical), bool(background.converged))


# --- the steady background, cached (issue 29) ------------------------------------------------
#: Version of the TSD's GAFs (part of a case's GAF database fingerprint): 2 since issue 29's
#: tsdswept step (the cross-flow terms; box_pressures sampling each grid row between its own
#: edge nodes).
TSD_GAF_FORMAT = 3        # 3: the time term upwind at supersonic points (issue 29, tsdfin)
#: Version of the cached steady backgrounds (part of their key).
STEADY_FORMAT = 2        # 2: the cross-flow flag in the key (issue 29, tsdswept)


def steady_key(planform: TsdPlanform, grid: Tsd3dGrid, thickness_ratio: float, mach: float,
               gamma: float = GAMMA_AIR, cross_flow: bool = False) -> str:
    """SHA-256 of what a biconvex background depends on: the planform, the grid, tau, M,
    gamma, the cross-flow terms and :data:`STEADY_FORMAT` (arrays rounded to 12 decimals)."""
    import hashlib

    h = hashlib.sha256(f"tsd-steady-{STEADY_FORMAT}|{float(thickness_ratio)!r}|"
                       f"{float(mach)!r}|{float(gamma)!r}|{bool(cross_flow)}".encode())
    for a in (planform.y, planform.x_le, planform.chord, grid.x, grid.y, grid.z):
        h.update(np.round(np.asarray(a, float), 12).tobytes())
    return h.hexdigest()


def cached_steady_tsd3d(planform: TsdPlanform, grid: Tsd3dGrid, thickness_ratio: float,
                        mach: float, gamma: float = GAMMA_AIR, cache_dir=None,
                        cross_flow: bool = False) -> Tsd3dSolution:
    """:func:`steady_tsd3d` of a biconvex section (:func:`biconvex_thickness`), read from
    ``cache_dir`` (default :func:`asekit.util.paths.user_cache_dir`) when a file
    ``tsd_steady_<key>.npz`` exists whose digest passes (:func:`asekit.util.cache.load_npz`)
    and whose key (:func:`steady_key`) and potential shape match; else solved and written
    atomically (:func:`asekit.util.cache.save_npz`; a folder that cannot be written only warns).
    The solve's ``seconds`` of a cached background are those of the original solve."""
    import warnings

    from asekit.util.cache import CacheError, load_npz, save_npz
    from asekit.util.paths import user_cache_dir

    key = steady_key(planform, grid, thickness_ratio, mach, gamma, cross_flow)
    path = Path(user_cache_dir() if cache_dir is None else cache_dir) / f"tsd_steady_{key[:32]}.npz"
    try:
        arrays, meta = load_npz(path, expect_metadata={"key": key},
                                expect_shapes={"phi": grid.shape})
        if np.all(np.isfinite(arrays["phi"])) and np.all(np.isfinite(arrays["cp"])):
            return Tsd3dSolution(planform, grid, arrays["phi"], arrays["x_mid"], arrays["cp"],
                                 float(mach), float(gamma), bool(meta["converged"]),
                                 int(meta["iterations"]), float(meta["residual"]),
                                 int(meta["supersonic_points"]), float(meta["seconds"]),
                                 bool(cross_flow))
    except (CacheError, FileNotFoundError, OSError, KeyError, ValueError, TypeError):
        pass
    sol = steady_tsd3d(planform, biconvex_thickness(thickness_ratio), mach, grid, gamma=gamma,
                       cross_flow=cross_flow)
    meta = {"key": key, "converged": bool(sol.converged), "iterations": int(sol.iterations),
            "residual": float(sol.residual), "supersonic_points": int(sol.supersonic_points),
            "seconds": float(sol.seconds), "mach": float(mach),
            "thickness_ratio": float(thickness_ratio)}
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        save_npz(path, {"phi": sol.phi, "x_mid": sol.x_mid, "cp": sol.cp}, meta)
    except OSError as exc:
        warnings.warn(f"TSD background computed but not cached ({path}: {exc})", RuntimeWarning,
                      stacklevel=2)
    return sol


def tsd_background(mesh, mach: float, thickness_ratio: float, grid_options: dict | None = None,
                   cache_dir=None, cross_flow: bool = True) -> Tsd3dSolution:
    """The steady biconvex background of a box mesh's planform (:func:`planform_of_boxes`) on
    the grid of :func:`mesh_grid_options` (or ``grid_options``, ``edges="faces"`` always),
    cached (:func:`cached_steady_tsd3d`): what ``method = "tsd"`` linearises about and what its
    validity line (:func:`tsd_validity`) reads. ``cross_flow`` (default on: the method's
    equation is the modified TSD equation, Eq. 1b of the module, since issue 29's tsdswept
    step) adds the cross-flow terms of swept wings; :func:`harmonic_tsd3d` linearises
    them too."""
    planform = planform_of_boxes(mesh)
    opts = dict(mesh_grid_options(mesh) if grid_options is None else grid_options)
    opts["edges"] = "faces"
    return cached_steady_tsd3d(planform, tsd3d_grid(planform, **opts), thickness_ratio, mach,
                               cache_dir=cache_dir, cross_flow=cross_flow)
