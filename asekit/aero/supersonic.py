"""Supersonic lifting-surface method for harmonically oscillating planar surfaces: a Mach-box
(velocity-potential) method with exact box integrals and a diaphragm, for about 1.15 <= M <= 3.

References (equation numbers below refer to these):

- [ZH55] G. Zartarian, P. T. Hsu, "Theoretical studies on the prediction of unsteady
  supersonic airloads on elastic wings", WADC TR 56-97, 1955 (the Mach box method).
- [PDN55] S. Pines, J. Dugundji, J. Neuringer, "Aerodynamic flutter derivatives for a flexible
  wing with supersonic and subsonic edges", J. Aeronaut. Sci. 22(10), 1955, 693-700 (the
  diaphragm: phi = 0 on the plane off the wing, after Evvard).
- [BAH55] R. L. Bisplinghoff, H. Ashley, R. L. Halfman, *Aeroelasticity*, Addison-Wesley 1955,
  Section 5-7 (Eq. 5-302: the planar supersonic velocity potential below) and Section 7-4.
- [GR46] I. E. Garrick, S. I. Rubinow, "Theoretical study of air forces on an oscillating or
  steady thin wing in a supersonic main stream", NACA Report 872, 1946 (the 2-D case).

Formulation. With exp(i omega t), the perturbation potential of the linearised equation
beta^2 phi_xx - phi_yy - phi_zz + 2 i omega M^2 / U phi_x - omega^2 M^2 / U^2 phi = 0
(beta = sqrt(M^2 - 1)) is phi = psi exp(-i lambda x), lambda = omega M^2 / (U beta^2), with psi
a Klein-Gordon field of mass mu = omega M / (U beta); its retarded source solution gives the
potential on the upper side of the plane z = 0 in terms of the normalwash w ([BAH55] Eq. 5-302,
[ZH55])

    phi(x, y) = -(1/pi) int int_tau w(xi, eta) exp(-i lambda X) cos(kappa R) / R d xi d eta,

X = x - xi, R = sqrt(X^2 - beta^2 (y - eta)^2), kappa = omega M / (U beta^2), tau the part of the
plane inside the forward Mach cone of (x, y). The pressure jump follows from the (antisymmetric)
potential, DeltaCp = Cp_lower - Cp_upper = (4 / U^2) (i omega phi + U phi_x): Delta Cp > 0 pushes
along +z, the DLM convention. Off the wing the plane carries no load, so phi = 0 there (the
diaphragm of [PDN55]); behind a supersonic trailing edge the wake cannot reach the wing.
Behind a subsonic trailing edge (|tan Lambda_TE| >= beta) it can: the wake carries a potential
jump but no load, so there DeltaCp = 0 (the linearised wake condition, with phi = 0 off the
wing and the wake the boundary conditions of [PDN55] for wings with subsonic edges).

Discretisation (asekit's). The plane is cut into a uniform grid of rectangular cells, Mach boxes
with dx = beta dy as in [ZH55] (the diaphragm march is unstable on finer grids otherwise);
w is constant on each cell. With beta t = X sin(theta) the inner integral over a cell's span
becomes dt / R = d theta / beta, so the potential influence of a cell is

    I = (1/beta) int d theta int_L(theta)^H(theta) exp(-i lambda X) cos(kappa X cos theta) dX,

done exactly in X (exponentials) and by Gauss-Legendre quadrature in theta between the kinks of
L and H; phi_x needs the same integrand at the cell's two chordwise edges only,
F(X) = (1/beta) exp(-i lambda X) int cos(kappa X cos theta) d theta, so no numerical
differentiation of phi is needed. In steady flow I reduces to the exact area integral of 1/R and
F(X) to (theta_2 - theta_1) / beta, and in 2-D (far from edges) DeltaCp = -4 (w/U) / beta:
Ackeret's 4 alpha / beta. The influences depend on the cell offset only. Cells whose centre lies
in a box are wing cells; off-wing cells ahead of the trailing edge within the Mach cones of the
wing (beyond side edges, ahead of subsonic leading edges) are diaphragm cells whose w follows
from phi = 0 at their centres, and off-wing cells behind a subsonic trailing edge are wake
cells whose w follows from DeltaCp = 0 at their centres (all solved together, row by row);
the pressure is evaluated at the wing-cell centres.

Transfer to the box mesh. The input is the normalwash w/U at the DLM control points (3/4 chord
of each box, w/U = dh/dx + i k h / b); it is interpolated linearly in x along each chordwise
strip to the cell centres. Each box's force (the pressures of the cells whose centres it holds,
weighted so that they carry exactly its area) is placed at the box centroid and goes back to
the strip's load points (1/4 chord) by the transpose of the linear interpolation from the load
points, which keeps the virtual work of rigid plunge and pitch exact up to the midpoint rule
(as in :mod:`asekit.aero.piston`). A uniform load gives equal lumped pressures on interior
boxes; the first and last box of a strip carry the redistribution (0.75 and 1.25 times).
The result is a
pressure-per-normalwash matrix DeltaCp = A (w/U) with DeltaCp lumped at the load points, the
same kind of matrix as the DLM's AIC, so :mod:`asekit.aero.gaf` uses either.

Two evaluations of the same sums. Columns (a few modes, :func:`supersonic_pressures`): each
normalwash field is convolved with the offset tables by 2-D FFT. The full matrix
(:func:`supersonic_pressure_matrices`): the influence coefficients depend only on the cell
offset (di, |dj|) and k, so one nx x ny table per k is evaluated and gathered into sparse
influence matrices holding only the cell pairs inside each other's Mach cone (10-30 % of them);
their index pattern is built once per grid and reused for every k, and the strip-local
transfers are sparse too. The two agree to rounding (tests/aero/test_supersonic.py, 1e-12).

Limits. Planar meshes in z = 0 only. Leading, side and trailing edges may be subsonic or
supersonic (a subsonic trailing edge checked by the flow-reversal theorem, 1-3 %,
tests/aero/test_supersonic.py); at subsonic leading edges
the staircase of cells and the square-root pressure singularity cost accuracy (delta wings with
beta cot Lambda = 0.33-0.56: lift slope 4-7 % above Stewart's conical-flow value, against
0.1-0.3 % with supersonic leading edges; tests/aero/test_supersonic.py). The reference fin's leading
edge is supersonic from M 1.13. On the AGARD 445.6 wing at M 1.072 and 1.141 (subsonic
leading and trailing edges) the flutter speed index moves by 1-2 % (M 1.141) and 2-7 %
(M 1.072) under grid refinement (tests/aero/test_supersonic.py). The box mesh must resolve
the shortest kernel wavelength 2 pi b (M - 1) / (k M) with at least ``bpw_min`` boxes (a
:class:`~asekit.aero.boxes.MeshRuleWarning` otherwise); the cell grid resolves it with
``cells_per_wavelength`` cells and every box with about ``cells_per_box`` cells chordwise.
Near M = 1 this wavelength shrinks to zero and the linear theory itself fails: the dispatcher
(:mod:`asekit.aero.methods`) refuses 0.9 < M < 1.15.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft
import scipy.linalg as sla
import scipy.sparse as sp

from asekit.aero.boxes import BoxMesh, MeshRuleWarning
from asekit.aero.piston import check_supersonic_mach, piston_transfer, strip_interpolation
from asekit.aero.validity import check_k

_GAUSS_PHI = np.polynomial.legendre.leggauss(12)
_GAUSS_F = np.polynomial.legendre.leggauss(32)
#: Largest share of the mesh area allowed in boxes too small to hold a cell centre (the
#: slivers at a delta wing's tip); their area goes to the nearest cell of the grid.
EMPTY_AREA_FRACTION = 0.02
#: dx / (beta dy) of the grid cells: 1, Mach boxes (see :func:`mach_grid`).
MACH_BOX_RATIO = 1.0
#: Grid resolution defaults (:func:`mach_grid`): cells across the mean box chord, cells per
#: kernel wavelength, and the largest number of cells solved for (wing, diaphragm and wake;
#: the grid rectangle may hold 4 times as many).
CELLS_PER_BOX = 1.5
CELLS_PER_WAVELENGTH = 8.0
MAX_CELLS = 6000
#: The mesh rule of the Mach-box method: boxes per shortest kernel wavelength
#: 2 pi b (M - 1) / (k M) (a MeshRuleWarning below it; :func:`max_box_chord`).
BPW_MIN = 6.0


# ---------------------------------------------------------------------------------------------
# influence coefficients of one constant-w cell
# ---------------------------------------------------------------------------------------------
def cell_potential_integral(xa, xb, t1, t2, beta: float, lam: float, kap: float) -> np.ndarray:
    """I = int_{X in [xa, xb]} int_{t in [t1, t2]} exp(-i lam X) cos(kap R) / R dt dX over the
    part inside the Mach cone X > beta |t| (module docstring), broadcast over the arrays.

    ``xa < xb`` the range of X = x - xi and ``t1 < t2`` that of t = y - eta of the source cell
    seen from the field point (m); lam, kap in 1/m (0, 0 steady)."""
    xa, xb, t1, t2 = np.broadcast_arrays(*(np.asarray(v, float) for v in (xa, xb, t1, t2)))
    xa = np.maximum(xa, 0.0)
    a1, a2 = beta * t1, beta * t2
    half = 0.5 * np.pi
    kinks = [np.full(xa.shape, -half), np.full(xa.shape, half)]
    for a in (a1, a2):
        for x in (xa, xb):
            with np.errstate(divide="ignore", invalid="ignore"):
                r = np.where(x > 0, a / np.where(x > 0, x, 1.0), -2.0)
            kinks.append(np.arcsin(np.clip(r, -1.0, 1.0)))
    th = np.sort(np.stack(kinks, axis=-1), axis=-1)            # (..., 6)
    lo, hi = th[..., :-1], th[..., 1:]                          # 5 segments
    g, wg = _GAUSS_PHI
    mid, rad = 0.5 * (lo + hi), 0.5 * (hi - lo)
    theta = mid[..., None] + rad[..., None] * g                 # (..., 5, ng)
    s, c = np.sin(theta), np.cos(theta)
    s = np.where(s == 0.0, 1e-300, s)
    e = (Ellipsis, None, None)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        low = np.where(s > 0, a1[e] / s, a2[e] / s)
        upp = np.where(s > 0, a2[e] / s, a1[e] / s)
    L = np.maximum(xa[e], low)
    H = np.minimum(xb[e], upp)
    ln = np.maximum(H - L, 0.0)
    m = 0.5 * (H + L)
    m = np.where(ln > 0, m, 0.0)
    if lam == 0.0 and kap == 0.0:
        inner = ln.astype(complex)
    else:
        def ex(nu):
            return ln * np.exp(1j * nu * m) * np.sinc(nu * ln / (2.0 * np.pi))
        inner = 0.5 * (ex(kap * c - lam) + ex(-kap * c - lam))
    return np.sum(inner * (rad[..., None] * wg), axis=(-1, -2)) / beta


def edge_line_integral(x, t1, t2, beta: float, lam: float, kap: float) -> np.ndarray:
    """F(X) = int_{t1}^{t2} exp(-i lam X) cos(kap R) / R dt inside the Mach cone
    = (1/beta) exp(-i lam X) int_{theta1}^{theta2} cos(kap X cos theta) d theta, 0 for X <= 0."""
    x, t1, t2 = np.broadcast_arrays(*(np.asarray(v, float) for v in (x, t1, t2)))
    pos = x > 0
    xs = np.where(pos, x, 1.0)
    th1 = np.arcsin(np.clip(beta * t1 / xs, -1.0, 1.0))
    th2 = np.arcsin(np.clip(beta * t2 / xs, -1.0, 1.0))
    g, wg = _GAUSS_F
    mid, rad = 0.5 * (th1 + th2), 0.5 * (th2 - th1)
    theta = mid[..., None] + rad[..., None] * g
    val = np.sum(np.cos(kap * xs[..., None] * np.cos(theta)) * wg, axis=-1) * rad
    return np.where(pos, np.exp(-1j * lam * xs) * val / beta, 0.0)


class GridTooCoarseError(ValueError):
    """Too much of the mesh area lies in boxes that hold no cell centre of the grid."""


# ---------------------------------------------------------------------------------------------
# the cell grid
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MachGrid:
    """Cells of the supersonic method for one mesh and Mach number.

    ``x0, y0`` grid origin (m), ``dx, dy`` cell size (m), ``nx, ny`` cells per direction;
    ``wing_i, wing_j`` (n_w,) indices of the wing cells and ``wing_box`` the box (index into the
    mesh) each lies in, ``image`` (n_w,) True for cells of the mirror image (symmetric case);
    ``dia_i, dia_j`` (n_d,) the off-wing cells solved for (diaphragm and wake) and
    ``dia_wake`` (n_d,) True for the wake cells among them (behind a subsonic trailing edge:
    DeltaCp = 0 there instead of phi = 0; None: no wake cells).
    """

    x0: float
    y0: float
    dx: float
    dy: float
    nx: int
    ny: int
    beta: float
    wing_i: np.ndarray
    wing_j: np.ndarray
    wing_box: np.ndarray
    image: np.ndarray
    dia_i: np.ndarray
    dia_j: np.ndarray
    dia_wake: np.ndarray | None = None

    def wake_mask(self) -> np.ndarray:
        """(n_d,) bool: which solved off-wing cells are wake cells."""
        return np.zeros(self.dia_i.size, bool) if self.dia_wake is None else self.dia_wake

    @property
    def n_cells(self) -> int:
        return self.wing_i.size + self.dia_i.size

    def centres(self, i, j) -> np.ndarray:
        return np.column_stack([self.x0 + (np.asarray(i) + 0.5) * self.dx,
                                self.y0 + (np.asarray(j) + 0.5) * self.dy])


def _check_planar(mesh: BoxMesh) -> None:
    scale = float(np.ptp(mesh.corners[:, :, 0])) + float(np.ptp(mesh.corners[:, :, 1]))
    if np.any(np.abs(mesh.corners[:, :, 2]) > 1e-9 * scale) or np.any(np.abs(mesh.dihedral) > 1e-9):
        raise ValueError("mesh must be planar in z = 0 (horizontal boxes) for the supersonic "
                         "method; nonplanar meshes are not supported")


def _locate(corners: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Index of the box containing each point (-1 if none); boxes with streamwise sides."""
    y1, y2 = corners[:, 0, 1], corners[:, 3, 1]
    ylo, yhi = np.minimum(y1, y2), np.maximum(y1, y2)
    out = np.full(pts.shape[0], -1)
    for i0 in range(0, pts.shape[0], 2048):
        p = pts[i0:i0 + 2048]
        f = (p[:, None, 1] - y1[None]) / (y2 - y1)[None]
        xle = corners[None, :, 0, 0] + f * (corners[None, :, 3, 0] - corners[None, :, 0, 0])
        xte = corners[None, :, 1, 0] + f * (corners[None, :, 2, 0] - corners[None, :, 1, 0])
        inside = ((p[:, None, 1] >= ylo[None]) & (p[:, None, 1] < yhi[None])
                  & (p[:, None, 0] >= xle) & (p[:, None, 0] < xte))
        hit = inside.any(axis=1)
        out[i0:i0 + 2048] = np.where(hit, inside.argmax(axis=1), -1)
    return out


def _locate_grid(corners: np.ndarray, x0: float, y0: float, dx: float, dy: float, nx: int,
                 ny: int) -> np.ndarray:
    """:func:`_locate` for the centres of an nx x ny cell grid (origin x0, y0, cells dx x dy),
    raveled row-major (index i ny + j): only the cells in each box's bounding rectangle (plus
    one cell around it) are tested, with the same containment test, and a centre in two boxes
    goes to the lower box index, as in :func:`_locate`."""
    y1, y2 = corners[:, 0, 1], corners[:, 3, 1]
    ylo, yhi = np.minimum(y1, y2), np.maximum(y1, y2)
    xs = corners[:, :, 0]
    j0 = np.clip(np.floor((ylo - y0) / dy - 0.5).astype(int) - 1, 0, ny)
    j1 = np.clip(np.ceil((yhi - y0) / dy - 0.5).astype(int) + 1, 0, ny)
    i0 = np.clip(np.floor((xs.min(axis=1) - x0) / dx - 0.5).astype(int) - 1, 0, nx)
    i1 = np.clip(np.ceil((xs.max(axis=1) - x0) / dx - 0.5).astype(int) + 1, 0, nx)
    ni, nj = i1 - i0, j1 - j0
    count = ni * nj
    box = np.repeat(np.arange(corners.shape[0]), count)
    local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    ii = i0[box] + local // nj[box]
    jj = j0[box] + local % nj[box]
    px, py = x0 + (ii + 0.5) * dx, y0 + (jj + 0.5) * dy
    c = corners[box]
    f = (py - c[:, 0, 1]) / (c[:, 3, 1] - c[:, 0, 1])
    xle = c[:, 0, 0] + f * (c[:, 3, 0] - c[:, 0, 0])
    xte = c[:, 1, 0] + f * (c[:, 2, 0] - c[:, 1, 0])
    inside = (py >= ylo[box]) & (py < yhi[box]) & (px >= xle) & (px < xte)
    out = np.full(nx * ny, corners.shape[0])
    np.minimum.at(out, (ii * ny + jj)[inside], box[inside])
    out[out == corners.shape[0]] = -1
    return out


def trailing_edge_tangents(mesh: BoxMesh) -> np.ndarray:
    """|tan Lambda_TE| (n_strips,) of the trailing edge of every chordwise strip."""
    out = []
    for s in np.unique(mesh.strip):
        members = np.flatnonzero(mesh.strip == s)
        last = members[np.argmax(mesh.corners[members, 1, 0])]
        c = mesh.corners[last]
        out.append(abs((c[2, 0] - c[1, 0]) / (c[2, 1] - c[1, 1])))
    return np.array(out)


def has_subsonic_trailing_edge(mesh: BoxMesh, mach: float) -> bool:
    """True when some trailing edge is subsonic, |tan Lambda_TE| >= sqrt(M^2 - 1): its wake
    then lies inside the forward Mach cones of wing points (module docstring)."""
    m = check_supersonic_mach(mach)
    return bool(np.any(trailing_edge_tangents(mesh) >= math.sqrt(m * m - 1.0)))


def kernel_wavelength(mach: float, k: float, b_ref: float) -> float:
    """Shortest streamwise wavelength of the kernel, 2 pi / (lambda + kappa) =
    2 pi b (M - 1) / (k M) (m); inf for k = 0."""
    return math.inf if k <= 0 else 2.0 * math.pi * b_ref * (mach - 1.0) / (k * mach)


def max_box_chord(mach: float, k_max: float, b_ref: float, bpw_min: float = BPW_MIN) -> float:
    """The longest box chord (m) of the mesh rule of the Mach-box method: ``bpw_min`` boxes
    per shortest kernel wavelength, dx <= 2 pi b (M - 1) / (k_max M bpw_min) (the rule
    :func:`supersonic_pressure_matrices` warns about; inf for k_max = 0).

    Examples
    --------
    >>> round(max_box_chord(1.5, 1.0, 0.1), 5)      # 2 pi 0.1 0.5 / (1.5 x 6) m
    0.03491
    """
    return kernel_wavelength(mach, k_max, b_ref) / float(bpw_min)


@dataclass(frozen=True)
class _Geometry:
    """What the cell grid needs of a box mesh: ``corners`` (n, 4, 3), the box ``chord`` and
    ``area`` (n,) and whether a trailing edge is subsonic at the Mach number."""

    corners: np.ndarray
    chord: np.ndarray
    area: np.ndarray
    subsonic_te: bool


def _corner_geometry(corners: np.ndarray, strip: np.ndarray, mach: float) -> _Geometry:
    """:class:`_Geometry` from box corners and strip indices alone (the formulas of
    :class:`~asekit.aero.boxes.BoxMesh`, without its overlap check: the cheap estimate)."""
    c = np.asarray(corners, float)
    chord = 0.5 * ((c[:, 1, 0] - c[:, 0, 0]) + (c[:, 2, 0] - c[:, 3, 0]))
    p1 = c[:, 0] + 0.25 * (c[:, 1] - c[:, 0])
    p3 = c[:, 3] + 0.25 * (c[:, 2] - c[:, 3])
    d = p3 - p1
    area = chord * 2.0 * (0.5 * np.hypot(d[:, 1], d[:, 2]))
    strip = np.asarray(strip)
    tans = []
    for s in np.unique(strip):
        members = np.flatnonzero(strip == s)
        e = c[members[np.argmax(c[members, 1, 0])]]
        tans.append(abs((e[2, 0] - e[1, 0]) / (e[2, 1] - e[1, 1])))
    return _Geometry(c, chord, area, bool(np.any(np.array(tans) >= math.sqrt(mach * mach - 1))))


@dataclass(frozen=True)
class _Layout:
    """The cell grid's frame: all corners (the image's too, ``owner`` and ``is_img`` per box),
    origin (x0, y0), cell size dx, dy (m), nx x ny cells, beta."""

    all_c: np.ndarray
    owner: np.ndarray
    is_img: np.ndarray
    x0: float
    y0: float
    dx: float
    dy: float
    nx: int
    ny: int
    beta: float


def _layout(geo: _Geometry, m: float, k_max: float, b_ref: float, symmetric: bool,
            cells_per_box: float, cells_per_wavelength: float, max_cells: int) -> _Layout:
    """The grid frame of :func:`mach_grid` (its docstring); ValueError for a grid whose
    spanwise count alone is not finite or beyond 4 ``max_cells``."""
    beta = math.sqrt(m * m - 1.0)
    corners = geo.corners
    n = corners.shape[0]
    if symmetric:
        img = (corners * np.array([1.0, -1.0, 1.0]))[:, [3, 2, 1, 0]]
        all_c = np.concatenate([corners, img])
        owner = np.concatenate([np.arange(n), np.arange(n)])
        is_img = np.concatenate([np.zeros(n, bool), np.ones(n, bool)])
    else:
        all_c, owner, is_img = corners, np.arange(n), np.zeros(n, bool)
    x_min, x_max = float(all_c[:, :, 0].min()), float(all_c[:, :, 0].max())
    dx = float(np.sum(geo.chord * geo.area) / np.sum(geo.area)) / cells_per_box
    dx = min(dx, kernel_wavelength(m, k_max, b_ref) / cells_per_wavelength)
    # Mach boxes: dx = beta dy, the cell diagonals on Mach lines (the classic choice of
    # [ZH55]). Then cells of one row lie outside each other's Mach cones (the diaphragm is
    # solved by forward substitution), and the diaphragm march is stable: asekit's tests found
    # it growing without bound on fine grids for dx / (beta dy) = 0.5, and slower but similar
    # trouble below that. dy divides the strip width when the strips are equally wide.
    ylo = np.minimum(all_c[:, 0, 1], all_c[:, 3, 1])
    yhi = np.maximum(all_c[:, 0, 1], all_c[:, 3, 1])
    edges = np.unique(np.round(np.concatenate([ylo, yhi]), 12))
    y_wmin, y_wmax = float(edges[0]), float(edges[-1])
    widths = np.diff(edges)
    spanwise = beta * (y_wmax - y_wmin) / (MACH_BOX_RATIO * dx)       # <= ny (Mach boxes)
    if not spanwise <= 4 * max_cells:                                  # NaN or inf too
        raise ValueError(f"the supersonic grid would need more than {spanwise:.3g} cells "
                         f"(> {max_cells} relevant cells, max_cells) at mach={m:g}, "
                         f"k={k_max:g}: mach must be a physical Mach number (beta = "
                         f"sqrt(M^2 - 1) = {beta:.3g} sets the Mach boxes' width)")
    if widths.size and np.allclose(widths, widths[0], rtol=1e-6):
        width = float(widths[0])
        dy = width / max(1, math.ceil(beta * width / (MACH_BOX_RATIO * dx) - 1e-9))
    else:
        dy = MACH_BOX_RATIO * dx / beta
    dx = MACH_BOX_RATIO * beta * dy
    nx = max(1, math.ceil((x_max - x_min) / dx - 1e-9))
    margin = (x_max - x_min) / (2.0 * beta) + dy
    n_lo = math.ceil(margin / dy)
    ny_w = max(1, round((y_wmax - y_wmin) / dy))
    return _Layout(all_c, owner, is_img, x_min, y_wmin - n_lo * dy, dx, dy, nx, ny_w + 2 * n_lo,
                   beta)


def _select_cells(lay: _Layout, subsonic_te: bool):
    """(box, ii, jj, wing, wake, dia) of the nx x ny grid: the box holding each cell centre
    (-1: none), the cells' indices, the wing cells (mask), the wake cells (mask) and the
    solved off-wing cells (indices): the diaphragm and wake cells that both feel the wing and
    influence it."""
    nx, ny, dx, dy, beta = lay.nx, lay.ny, lay.dx, lay.dy, lay.beta
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()
    box = _locate_grid(lay.all_c, lay.x0, lay.y0, dx, dy, nx, ny)
    wing = box >= 0
    if not wing.any():
        raise ValueError("no grid cell centre lies on the mesh: the mesh is degenerate")
    # wake: off-wing cells behind a wing cell of the same column
    first_wing_row = np.full(ny, nx)
    np.minimum.at(first_wing_row, jj[wing], ii[wing])
    last_wing_row = np.full(ny, -1)
    np.maximum.at(last_wing_row, jj[wing], ii[wing])
    wake = (~wing) & (ii > last_wing_row[jj]) & (last_wing_row[jj] >= 0)
    # behind supersonic trailing edges the wake cannot reach the wing: leave it out; behind a
    # subsonic one it can, and its cells are solved with DeltaCp = 0
    cand = np.flatnonzero((~wing) & (~wake)) if not subsonic_te else np.flatnonzero(~wing)
    # keep the off-wing cells inside the downstream Mach cone of some wing cell and ahead of
    # another's: per column, the most upstream / downstream wing cell decides (the cone test
    # is monotone in the streamwise distance)
    cols = np.flatnonzero(last_wing_row >= 0)
    ddy = np.abs(jj[cand][:, None] - cols[None, :]) * dy
    down_dx = (ii[cand][:, None] - first_wing_row[cols][None, :]) * dx
    up_dx = (last_wing_row[cols][None, :] - ii[cand][:, None]) * dx
    down = (down_dx > 0) & (beta * (ddy - dy) < down_dx + dx)
    up = (up_dx > 0) & (beta * (ddy - dy) < up_dx + dx)
    keep = down.any(axis=1) & up.any(axis=1)
    return box, ii, jj, wing, wake, cand[keep]


def _empty_boxes(lay: _Layout, box: np.ndarray, wing: np.ndarray, area: np.ndarray):
    """(indices of the boxes, image included, that hold no cell centre; their share of the
    area)."""
    all_area = np.concatenate([area, area]) if lay.all_c.shape[0] > area.size else area
    counts = np.bincount(box[wing], minlength=lay.all_c.shape[0])
    empty = np.flatnonzero(counts == 0)
    return empty, float(all_area[empty].sum() / all_area.sum())


def _check_grid_options(cells_per_box: float, cells_per_wavelength: float) -> float:
    cells_per_box = float(cells_per_box)
    if not (math.isfinite(cells_per_box) and cells_per_box >= 1.0):
        raise ValueError(f"cells_per_box must be >= 1, got {cells_per_box!r}")
    if not (math.isfinite(cells_per_wavelength) and cells_per_wavelength >= 2.0):
        raise ValueError(f"cells_per_wavelength must be >= 2, got {cells_per_wavelength!r}")
    return cells_per_box


def mach_grid(mesh: BoxMesh, mach: float, k_max: float, b_ref: float, symmetric: bool = False,
              cells_per_box: float = CELLS_PER_BOX,
              cells_per_wavelength: float = CELLS_PER_WAVELENGTH,
              max_cells: int = MAX_CELLS) -> MachGrid:
    """Build the cell grid (:class:`MachGrid`) for ``mesh`` at ``mach`` and the highest reduced
    frequency ``k_max``: dx from ``cells_per_box`` cells across the area-weighted mean box chord and
    ``cells_per_wavelength`` cells per :func:`kernel_wavelength` (upper bounds); dy = dx / beta
    (Mach boxes), with cell boundaries on the strip edges when the strips are equally wide.
    The grid extends (x_max - x_min) / (2 beta) beyond the spanwise extremes of the mesh: no
    off-wing point farther out both feels the wing and influences it.

    Raises ValueError when more than ``max_cells`` cells would be needed (:func:`grid_size`
    counts them without building the grid).
    """
    m = check_supersonic_mach(mach)
    _check_planar(mesh)
    cells_per_box = _check_grid_options(cells_per_box, cells_per_wavelength)
    geo = _Geometry(mesh.corners, mesh.chord, mesh.area, has_subsonic_trailing_edge(mesh, m))
    lay = _layout(geo, m, k_max, b_ref, symmetric, cells_per_box, cells_per_wavelength,
                  max_cells)
    if lay.nx * lay.ny > 4 * max_cells:
        raise ValueError(f"the supersonic grid would need about {lay.nx * lay.ny} cells (> "
                         f"{max_cells} relevant cells, max_cells) at mach={m:g}, k={k_max:g}: "
                         "coarsen with cells_per_box / cells_per_wavelength or lower k")
    box, ii, jj, wing, wake, dia = _select_cells(lay, geo.subsonic_te)
    n_rel = int(wing.sum()) + dia.size
    if n_rel > max_cells:
        raise ValueError(f"the supersonic grid needs {n_rel} cells (> max_cells={max_cells}) at "
                         f"mach={m:g}, k={k_max:g}: coarsen with cells_per_box / "
                         "cells_per_wavelength, or raise max_cells")
    empty, share = _empty_boxes(lay, box, wing, mesh.area)
    if share > EMPTY_AREA_FRACTION:
        raise GridTooCoarseError(f"boxes {lay.owner[empty][:10].tolist()} hold no cell centre "
                                 f"of the supersonic grid (dx {lay.dx:.3g} m, dy {lay.dy:.3g} m; "
                                 f"{100 * share:.2g} % of the area): raise cells_per_box")
    return MachGrid(lay.x0, lay.y0, lay.dx, lay.dy, lay.nx, lay.ny, lay.beta, ii[wing], jj[wing],
                    lay.owner[box[wing]], lay.is_img[box[wing]], ii[dia], jj[dia],
                    wake[dia] if geo.subsonic_te else None)


@dataclass(frozen=True)
class GridSize:
    """The size of the Mach-box grid of a mesh at one Mach number and highest k, counted
    without building it (:func:`grid_size`): ``n_grid`` = nx ny cells of the grid rectangle,
    ``n_relevant`` the wing, diaphragm and wake cells solved for (None when ``n_grid`` alone
    is over the limit: not counted), ``max_cells`` the limit of :func:`mach_grid`."""

    n_grid: int
    n_relevant: int | None
    max_cells: int

    @property
    def fits(self) -> bool:
        """Whether :func:`mach_grid` accepts the grid (both counts within the limits)."""
        return (self.n_grid <= 4 * self.max_cells and self.n_relevant is not None
                and self.n_relevant <= self.max_cells)

    @property
    def cells(self) -> int:
        """The count that decides: the relevant cells when counted, else the rectangle's."""
        return self.n_grid if self.n_relevant is None else self.n_relevant


def grid_size(corners: np.ndarray, strip: np.ndarray, mach: float, k_max: float, b_ref: float,
              symmetric: bool = False, cells_per_box: float = CELLS_PER_BOX,
              cells_per_wavelength: float = CELLS_PER_WAVELENGTH,
              max_cells: int = MAX_CELLS) -> GridSize:
    """Count the cells of the grid :func:`supersonic_pressure_matrices` would build for boxes
    with ``corners`` (n, 4, 3) and chordwise-strip indices ``strip`` (n,) (a
    :class:`~asekit.aero.boxes.BoxMesh`'s, or :func:`asekit.aero.boxes.box_corners` of
    surfaces not yet meshed) at ``mach`` and ``k_max``, without building the grid or the
    mesh: the frame in closed form, the relevant cells (wing, diaphragm, wake) counted only
    when the frame is within the limit (a few ms then). The same refinement as the solver's
    when boxes hold no cell centre (``cells_per_box`` x 1.5, up to three times).

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, box_corners
    >>> c, s = box_corners([TrapezoidSurface((0, 0), 0.3, (0.2, 0.2), 0.1, 8, 6)])
    >>> g = grid_size(c, s, 1.5, 1.0, 0.1)
    >>> g.fits, g.n_relevant
    (True, 492)
    >>> grid_size(c, s, 1.5, 20.0, 0.1).fits       # k 20: the kernel's wavelength 5 mm
    False
    """
    m = check_supersonic_mach(mach)
    cpb = _check_grid_options(cells_per_box, cells_per_wavelength)
    geo = _corner_geometry(corners, strip, m)
    for attempt in range(4):
        lay = _layout(geo, m, float(k_max), float(b_ref), symmetric, cpb * 1.5 ** attempt,
                      cells_per_wavelength, max_cells)
        n_grid = lay.nx * lay.ny
        if n_grid > 4 * max_cells:
            return GridSize(n_grid, None, int(max_cells))
        box, _, _, wing, _, dia = _select_cells(lay, geo.subsonic_te)
        n_rel = int(wing.sum()) + dia.size
        if n_rel > max_cells or _empty_boxes(lay, box, wing, geo.area)[1] <= EMPTY_AREA_FRACTION:
            break
    return GridSize(n_grid, n_rel, int(max_cells))


# ---------------------------------------------------------------------------------------------
# solution on the grid
# ---------------------------------------------------------------------------------------------
def _cone_mask(grid: MachGrid) -> np.ndarray:
    """(nx, ny) bool over offsets (di, dj >= 0): the Mach cone of a receiving cell centre
    reaches the cell, beta (dj - 1/2) dy < (di + 1/2) dx; the influence tables are zero
    elsewhere (both, since the cone grows with di)."""
    di, dj = np.meshgrid(np.arange(grid.nx), np.arange(grid.ny), indexing="ij")
    return grid.beta * (dj - 0.5) * grid.dy < (di + 0.5) * grid.dx * (1.0 + 1e-9)


def _offset_tables(grid: MachGrid, lam: float, kap: float):
    """Influence tables over offsets (di >= 0, dj >= 0): potential I[di, dj] at a cell centre
    and edge integrals F[m, dj] at X = (m + 1/2) dx; evaluated only where the Mach cone of the
    receiving point reaches the cell (beta (dj - 1/2) dy < (di + 1/2) dx), zero elsewhere."""
    di, dj = np.nonzero(_cone_mask(grid))
    xb = (di + 0.5) * grid.dx
    t1 = (dj - 0.5) * grid.dy
    t2 = (dj + 0.5) * grid.dy
    pot = np.zeros((grid.nx, grid.ny), complex)
    edge = np.zeros((grid.nx, grid.ny), complex)
    pot[di, dj] = cell_potential_integral(xb - grid.dx, xb, t1, t2, grid.beta, lam, kap)
    edge[di, dj] = edge_line_integral(xb, t1, t2, grid.beta, lam, kap)
    return pot, edge


class _Convolver:
    """Causal 2-D convolution on the full nx x ny grid by FFT: out[i, j] = sum K[i - i', |j - j'|]
    f[i', j'] over i' <= i, for kernel tables K[di >= 0, dj >= 0] (zero-padded to fast FFT
    lengths >= 2 nx, 2 ny). ``spectrum`` transforms fields once; ``apply`` multiplies by one
    kernel's spectrum and transforms back, so several kernels share one forward transform."""

    def __init__(self, tables, nx: int, ny: int):
        self.nx, self.ny = nx, ny
        self.shape = (sfft.next_fast_len(2 * nx), sfft.next_fast_len(2 * ny))
        self.kf = []
        for table in tables:
            full = np.zeros(self.shape, complex)
            full[:nx, :ny] = table
            full[:nx, self.shape[1] - ny + 1:] = table[:, 1:][:, ::-1]     # negative dj: mirror
            self.kf.append(sfft.fft2(full, workers=1))

    def spectrum(self, fields: np.ndarray) -> np.ndarray:
        return sfft.fft2(fields, s=self.shape, workers=1)

    def apply(self, spec: np.ndarray, which: int) -> np.ndarray:
        return sfft.ifft2(spec * self.kf[which], workers=1)[:, :self.nx, :self.ny]


def _kernels(grid: MachGrid, mach: float, k: float, b_ref: float):
    """(potential table, pressure table) over offsets, per unit w/U: phi/U = sum Kphi w/U and
    DeltaCp = sum Kp w/U with Kp = -(4/pi) [(i k/b) I + F(X_b) - F(X_a)]."""
    beta = grid.beta
    kb = k / b_ref
    lam, kap = kb * mach**2 / beta**2, kb * mach / beta**2
    pot, edge = _offset_tables(grid, lam, kap)
    f_a = np.zeros_like(edge)
    f_a[1:] = edge[:-1]
    kp = (-4.0 / np.pi) * (1j * kb * pot + edge - f_a)
    return (-1.0 / np.pi) * pot, kp


def _grid_solve(grid: MachGrid, mach: float, k: float, b_ref: float,
                w_wing: np.ndarray) -> np.ndarray:
    """DeltaCp at the wing-cell centres (m, n_w) for wing-cell normalwash w/U (m, n_w): the
    off-wing w from phi = 0 at the diaphragm and DeltaCp = 0 at the wake cell centres
    (:func:`_offwing_solve`), the influences of the wing cells on them and the pressure by
    FFT convolution."""
    kphi, kp = _kernels(grid, mach, k, b_ref)
    nx, ny = grid.nx, grid.ny
    m = w_wing.shape[0]
    conv = _Convolver((kphi, kp), nx, ny)
    field = np.zeros((m, nx, ny), complex)
    field[:, grid.wing_i, grid.wing_j] = w_wing
    spec = conv.spectrum(field)
    if grid.dia_i.size:
        order = np.lexsort((grid.dia_j, grid.dia_i))
        di, dj = grid.dia_i[order], grid.dia_j[order]
        wake = grid.wake_mask()[order]
        rhs = -conv.apply(spec, 0)[:, di, dj].T                             # (n_d, m)
        if wake.any():
            rhs[wake] = -conv.apply(spec, 1)[:, di[wake], dj[wake]].T
        wd = _offwing_solve(_offwing(grid), _signed_table(kphi), _signed_table(kp), rhs)
        dfield = np.zeros((m, nx, ny), complex)
        dfield[:, di, dj] = wd.T
        spec = spec + conv.spectrum(dfield)
    return conv.apply(spec, 1)[:, grid.wing_i, grid.wing_j]


def _signed_table(table: np.ndarray) -> np.ndarray:
    """An (nx, ny) offset table K[di >= 0, dj >= 0] spread to signed offsets and raveled:
    T[(di + nx) 2 ny + (dj + ny)] = K[di, |dj|] for di >= 0 and 0 for di < 0 (upstream cells
    feel nothing), so that the influence of cell (i', j') on cell (i, j) is
    T[(i 2 ny + j) - (i' 2 ny + j') + nx 2 ny + ny] (see :class:`_GridGather`)."""
    nx, ny = table.shape
    t = np.zeros((2 * nx, 2 * ny), table.dtype)
    t[nx:, ny:] = table
    t[nx:, 1:ny] = table[:, :0:-1]
    return t.ravel()


@dataclass(frozen=True)
class _Pattern:
    """Sparsity pattern of one influence matrix (receiving cells x source cells) in CSR form:
    ``indptr``, ``indices`` and, per stored entry, ``table`` its index into a signed table
    (:func:`_signed_table`); ``shape``."""

    indptr: np.ndarray
    indices: np.ndarray
    table: np.ndarray
    shape: tuple

    def matrix(self, signed: np.ndarray, rows_alt: np.ndarray | None = None,
               alt: np.ndarray | None = None) -> sp.csr_matrix:
        """The matrix with values from ``signed``, and from ``alt`` in the rows ``rows_alt``
        (bool per row) when given."""
        data = signed[self.table]
        if rows_alt is not None and rows_alt.any():
            entry = np.repeat(rows_alt, np.diff(self.indptr))
            data[entry] = alt[self.table[entry]]
        return sp.csr_matrix((data, self.indices, self.indptr), shape=self.shape)


def _pattern(rkey: np.ndarray, ckey: np.ndarray, n2: int, off: int,
             reach: np.ndarray) -> _Pattern:
    """The pairs (receiving cell, source cell) inside the Mach cone: for every receiving cell
    (key i n2 + j) and every row offset di >= 0, the source cells of row i - di with
    |j' - j| <= reach[di] (:func:`_cone_mask`), one contiguous run of the sorted source keys
    ``ckey`` (found by bisection). Entries of a row of the pattern come in ascending source
    order."""
    nr, nx = rkey.size, reach.size
    ip = rkey[:, None] // n2 - np.arange(nx, dtype=rkey.dtype)[::-1][None, :]   # ascending
    base = ip * n2 + (rkey % n2)[:, None]
    rr = reach[::-1][None, :]
    lo = np.searchsorted(ckey, base - rr, "left")
    cnt = np.where(ip >= 0, np.searchsorted(ckey, base + rr, "right") - lo, 0).ravel()
    per_row = cnt.reshape(nr, nx).sum(axis=1)
    indptr = np.zeros(nr + 1, np.int64)
    np.cumsum(per_row, out=indptr[1:])
    total = int(indptr[-1])
    ends = np.cumsum(cnt)
    cols = np.repeat((lo.ravel() - ends + cnt).astype(rkey.dtype), cnt)
    cols += np.arange(total, dtype=rkey.dtype)
    table = np.repeat(rkey + off, per_row)
    table -= ckey[cols]
    return _Pattern(indptr, cols, table, (nr, ckey.size))


@dataclass(frozen=True)
class _GridGather:
    """Index sets of the direct-summation grid operator, built once per (mesh, Mach) grid and
    reused for every k. The influence of one cell on another depends only on their offset
    (di, |dj|) and on k (module docstring), so every influence matrix is a gather from the
    nx x ny coefficient tables of :func:`_kernels` (a Toeplitz reuse: nx ny coefficients per k
    instead of one per pair of cells). With the cell key c = i 2 ny + j, the table index of the
    influence of cell b on cell a is c_a - c_b + off (:func:`_signed_table`), and only the pairs
    inside each other's Mach cone (:func:`_cone_mask`: 10-30 % of them on the fin) are kept, as
    sparse matrices.

    ``ww`` wing <- wing, ``dw`` diaphragm <- wing, ``wd`` wing <- diaphragm (:class:`_Pattern`),
    ``off`` the off-wing cells among themselves (:class:`_OffWing`), sorted by row, then
    column."""

    ww: _Pattern
    dw: _Pattern
    wd: _Pattern
    off: "_OffWing"


def _grid_gather(grid: MachGrid) -> _GridGather:
    n2 = 2 * grid.ny
    off = grid.nx * n2 + grid.ny
    reach = _cone_mask(grid).sum(axis=1) - 1          # largest |dj| in the cone, per di
    it = np.int32 if 2 * grid.nx * n2 < 2**31 else np.int64
    cw = (grid.wing_i * n2 + grid.wing_j).astype(it)
    if np.any(np.diff(cw) <= 0):
        raise AssertionError("wing cells must be sorted by row, then column")
    ow = _offwing(grid)
    reach = reach.astype(it)
    return _GridGather(_pattern(cw, cw, n2, off, reach), _pattern(ow.key, cw, n2, off, reach),
                       _pattern(cw, ow.key, n2, off, reach), ow)


@dataclass(frozen=True)
class _OffWing:
    """The solved off-wing cells (diaphragm and wake) sorted by row, then column: ``order``
    into ``grid.dia_*``, cell keys ``key`` (:class:`_GridGather`), ``wake`` (n_d,) their
    kind, ``dd`` the pattern of their influences on one another, ``blocks`` the index ranges
    of each grid row; ``triangular`` when the cells of one row lie outside each other's Mach
    cones (dx <= beta dy), so that a row depends on earlier rows and itself only."""

    order: np.ndarray
    key: np.ndarray
    wake: np.ndarray
    dd: _Pattern
    blocks: tuple
    triangular: bool


def _offwing(grid: MachGrid) -> _OffWing:
    n2 = 2 * grid.ny
    it = np.int32 if 2 * grid.nx * n2 < 2**31 else np.int64
    reach = (_cone_mask(grid).sum(axis=1) - 1).astype(it)
    order = np.lexsort((grid.dia_j, grid.dia_i))
    key = (grid.dia_i[order] * n2 + grid.dia_j[order]).astype(it)
    rows = grid.dia_i[order]
    cut = np.flatnonzero(np.diff(rows)) + 1
    edges = np.concatenate([[0], cut, [rows.size]]).astype(int)
    return _OffWing(order, key, grid.wake_mask()[order],
                    _pattern(key, key, n2, grid.nx * n2 + grid.ny, reach),
                    tuple(zip(edges[:-1], edges[1:])),
                    grid.dx <= grid.beta * grid.dy * (1 + 1e-12))


def _offwing_solve(ow: _OffWing, tphi: np.ndarray, tp: np.ndarray,
                   rhs: np.ndarray) -> np.ndarray:
    """w/U of the off-wing cells (n_d, m) from L w = rhs, L their influences on one another
    (phi rows for the diaphragm, DeltaCp rows for the wake, from the signed tables ``tphi``,
    ``tp``), sparse over the Mach cones: forward substitution grid row by grid row,
    w_R = (rhs_R - L_R w) / diag(L)_R while w_R is still zero, when ``ow.triangular``; a dense
    LU otherwise."""
    lmat = ow.dd.matrix(tphi, ow.wake, tp)
    if not ow.triangular:
        dense = lmat.toarray()
        return sla.lu_solve(sla.lu_factor(dense, check_finite=False), rhs, check_finite=False)
    diag = lmat.diagonal()
    x = np.zeros(rhs.shape, complex)
    for a, b in ow.blocks:
        x[a:b] = (rhs[a:b] - lmat[a:b] @ x) / diag[a:b, None]
    return x


def _grid_matrix(grid: MachGrid, gather: _GridGather, mach: float, k: float, b_ref: float,
                 s: sp.csr_matrix, tw: sp.csr_matrix) -> np.ndarray:
    """The pressure-per-normalwash matrix A (n, n) = T_w DeltaCp_grid S by direct summation
    over the gathered kernel tables K (:class:`_GridGather`): with the diaphragm normalwash
    w_d = -(K^phi_dd)^-1 K^phi_dw S (phi = 0 on the diaphragm; forward substitution),
    A = T_w K^p_ww S + (T_w K^p_wd) w_d. ``s`` is S (n_w, n) and ``tw`` T_w (n, n_w), both
    sparse (two entries per row of S, strip-local T_w). The same sums as :func:`_grid_solve`
    applied to the columns of S, without the FFT (equal to rounding)."""
    kphi, kp = _kernels(grid, mach, k, b_ref)
    tp = _signed_table(kp)
    out = (tw @ (gather.ww.matrix(tp) @ s)).toarray()
    ow = gather.off
    if ow.key.size:
        tphi = _signed_table(kphi)
        # (n_d, n): -K^phi_dw S on the diaphragm, -K^p_dw S on the wake
        rhs = -(gather.dw.matrix(tphi, ow.wake, tp) @ s).toarray()
        wd = _offwing_solve(ow, tphi, tp, rhs)
        out += (tw @ gather.wd.matrix(tp)).toarray() @ wd
    return out


def grid_pressure_operator(grid: MachGrid, mach: float, k: float, b_ref: float) -> np.ndarray:
    """A_grid (n_w, n_w) complex: DeltaCp at the wing-cell centres per unit w/U on each wing
    cell, the diaphragm eliminated (for tests and small grids: one solve per wing cell)."""
    return _grid_solve(grid, mach, k, b_ref, np.eye(grid.wing_i.size, dtype=complex)).T


def _transfer(mesh: BoxMesh, grid: MachGrid):
    """(S, G): S (n_w, n) takes w/U at the control points to the wing cells; G (n, n_w) takes
    cell pressures to lumped box pressures: each box's force (its cells' pressures, weighted
    so that they carry exactly the box area) placed at the box centroid, then moved to the
    strip's load points by the transpose of the linear interpolation, divided by the box area.
    Image cells (symmetric case) carry no force."""
    cen = grid.centres(grid.wing_i, grid.wing_j)
    s = strip_interpolation(mesh, grid.wing_box, cen[:, 0], "control")
    real = ~grid.image
    counts = np.bincount(grid.wing_box[real], minlength=mesh.n)
    weight = np.where(real, mesh.area[grid.wing_box] / np.maximum(counts[grid.wing_box], 1), 0.0)
    # boxes too small to hold a cell centre: their area to the nearest real cell
    real_idx = np.flatnonzero(real)
    owner = grid.wing_box.copy()
    for b in np.flatnonzero(counts == 0):
        cb = mesh.corners[b, :, :2].mean(axis=0)
        near = real_idx[np.argmin(np.sum((cen[real_idx] - cb) ** 2, axis=1))]
        weight[near] += mesh.area[b]
    _, t = piston_transfer(mesh)                      # load points -> box centroids (n, n)
    # T^T @ Agg with Agg (n, n_w) holding each cell's weight in its owner's row
    return s, (t.T[:, owner] * weight[None, :]) / mesh.area[:, None]


def _prepare(mesh, mach, k, b_ref, symmetric, cells_per_box, cells_per_wavelength, max_cells,
             bpw_min, warn, k_grid=None):
    m = check_supersonic_mach(mach)
    ks = check_k(k)
    b = float(b_ref)
    if not (math.isfinite(b) and b > 0):
        raise ValueError(f"b_ref must be a finite reference semi-chord > 0 m, got {b_ref!r}")
    k_max = float(ks.max())
    if k_grid is not None:
        k_grid = float(check_k(k_grid, "k_grid").max())
        if k_grid < k_max:
            raise ValueError(f"k_grid must be >= the largest k ({k_max:g}), got {k_grid:g}")
        k_max = k_grid
    if warn and k_max > 0:
        bpw = kernel_wavelength(m, k_max, b) / float(mesh.chord.max())
        if bpw < bpw_min:
            warnings.warn(f"mesh too coarse for the supersonic kernel at mach={m:g}, "
                          f"k={k_max:g}: {bpw:.2g} boxes per wavelength 2 pi b (M - 1)/(k M) < "
                          f"bpw_min={bpw_min:g}; use box chords below "
                          f"{kernel_wavelength(m, k_max, b) / bpw_min:.3g} m (a case file: "
                          "more chordwise boxes in aero.boxes)", MeshRuleWarning,
                          stacklevel=3)
    for attempt in range(4):        # small boxes (fine meshes, slivers): refine the grid
        try:
            grid = mach_grid(mesh, m, k_max, b, symmetric, cells_per_box * 1.5**attempt,
                             cells_per_wavelength, max_cells)
            break
        except GridTooCoarseError:
            if attempt == 3:
                raise
    s, tw = _transfer(mesh, grid)
    return m, ks, b, grid, s, tw


def supersonic_pressure_matrices(mesh: BoxMesh, mach: float, k, b_ref: float,
                                 symmetric: bool = False, cells_per_box: float = CELLS_PER_BOX,
                                 cells_per_wavelength: float = CELLS_PER_WAVELENGTH,
                                 max_cells: int = MAX_CELLS, bpw_min: float = BPW_MIN,
                                 warn: bool = True) -> np.ndarray:
    """Supersonic pressure-per-normalwash matrices A (n_k, n, n) complex, DeltaCp = A (w/U)
    with w/U at the DLM control points and DeltaCp lumped at the load points (module
    docstring), the counterpart of the DLM's AIC.

    Parameters
    ----------
    mesh : planar :class:`~asekit.aero.boxes.BoxMesh` in z = 0 (subsonic or supersonic edges).
    mach : M > 1 (intended range about 1.15 to 3).
    k : reduced frequencies omega b_ref / U >= 0, scalar or 1-D.
    b_ref : reference semi-chord (m) of k.
    symmetric : mirror image in y = 0 (wall at the root).
    cells_per_box, cells_per_wavelength, max_cells : grid resolution (:func:`mach_grid`); one
        grid, built for the highest k, serves every k.
    bpw_min : boxes of the mesh per kernel wavelength below which a MeshRuleWarning is given.
    warn : give that warning.
    """
    m, ks, b, grid, s, tw = _prepare(mesh, mach, k, b_ref, symmetric, cells_per_box,
                                     cells_per_wavelength, max_cells, bpw_min, warn)
    gather = _grid_gather(grid)                   # one index set for every k
    s_sp, tw_sp = sp.csr_matrix(s), sp.csr_matrix(tw)
    out = np.empty((ks.size, mesh.n, mesh.n), complex)
    for ik, kk in enumerate(ks):
        out[ik] = _grid_matrix(grid, gather, m, float(kk), b, s_sp, tw_sp)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("supersonic pressures are not finite")
    return out


def supersonic_pressures(mesh: BoxMesh, mach: float, k, b_ref: float, normalwash,
                         symmetric: bool = False, cells_per_box: float = CELLS_PER_BOX,
                         cells_per_wavelength: float = CELLS_PER_WAVELENGTH,
                         max_cells: int = MAX_CELLS, bpw_min: float = BPW_MIN,
                         warn: bool = True, k_grid: float | None = None,
                         on_k=None) -> np.ndarray:
    """DeltaCp (n_k, n, m) for given normalwash columns without forming the matrices (one grid
    solve per column instead of one per box: the cheap path for a few modes).

    ``normalwash`` is a callable ``k -> (n, m)`` array of w/U at the control points, or an
    (n_k, n, m) array; the other arguments as :func:`supersonic_pressure_matrices` (the result
    equals ``A[ik] @ normalwash[ik]`` to rounding). ``k_grid`` (default the largest k) is the
    reduced frequency the grid resolves: a k list computed in parts with the whole list's
    largest k gives, k by k, the same numbers as the whole list (a resumed GAF database,
    :func:`asekit.aero.gaf.build_gaf_database`). ``on_k(ik, DeltaCp_k)``, when given, is called
    with each k's (n, m) pressures as soon as they are computed."""
    m, ks, b, grid, s, tw = _prepare(mesh, mach, k, b_ref, symmetric, cells_per_box,
                                     cells_per_wavelength, max_cells, bpw_min, warn, k_grid)
    out = None
    for ik, kk in enumerate(ks):
        w = np.asarray(normalwash(float(kk)) if callable(normalwash) else normalwash[ik])
        w = w.reshape(w.shape[0], -1)
        if w.shape[0] != mesh.n or not np.all(np.isfinite(w)):
            raise ValueError(f"normalwash must be finite with first dimension {mesh.n}, "
                             f"got {w.shape}")
        cp = tw @ _grid_solve(grid, m, float(kk), b, (s @ w).T.astype(complex)).T
        if out is None:
            out = np.empty((ks.size, mesh.n, w.shape[1]), complex)
        out[ik] = cp
        if on_k is not None:
            on_k(ik, out[ik])
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("supersonic pressures are not finite")
    return out


def supersonic_pressure_matrix(mesh: BoxMesh, mach: float, k: float, b_ref: float,
                               symmetric: bool = False, **options) -> np.ndarray:
    """A (n, n) at one reduced frequency; see :func:`supersonic_pressure_matrices`."""
    if np.ndim(k) != 0:
        raise ValueError(f"k must be a scalar reduced frequency, got shape {np.shape(k)}")
    return supersonic_pressure_matrices(mesh, mach, [k], b_ref, symmetric, **options)[0]
