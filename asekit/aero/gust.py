"""Gust aerodynamics: the normalwash of a frozen gust and its generalised-force column
Q_hg(M, k) (issue 27).

A frozen vertical gust travels downstream with the flow at the airspeed U. Its upward
velocity (+z) at the streamwise station x is

    w_g(x, t) = W exp(i omega (t - (x - x0) / U)) = W exp(i omega t) exp(-i k (x - x0) / b),

with k = omega b / U, b the reference semi-chord and x0 the **gust reference point** (m): the
station where the gust velocity is W exp(i omega t) (a sharp-edged gust's front reaches x0 at
t = 0). The surface must cancel it, so in the normalwash convention of :mod:`asekit.aero.dlm`
and :mod:`asekit.aero.spline` (w/U = dh/dx + i k h / b: a nose-up incidence alpha gives
w/U = -alpha and a positive Delta Cp) an upward gust of W / U is an incidence +W/U:

    (w/U)_gust = -(W / U) exp(-i k (x_cp - x0) / b)        at each box's control point.

The gust column per unit gust angle W / U is then, with the force transpose of the modal
GAFs (:func:`asekit.aero.spline.modal_forces`, thesis Eqs. 2.10-2.11),

    Q_hg(M, k) = H_lp^T diag(A) DeltaCp_g,     DeltaCp_g = P(M, k) (w/U)_gust,

so that the modal gust force is F = q Q_hg W / U (N per unit modal coordinate's work,
q = rho U^2 / 2). An upward gust lifts a surface: Q_hg > 0 at k -> 0 on a plunge (h = +1) row.
Any aerodynamic method of :data:`asekit.aero.methods.AERO_METHODS` (DLM, Mach box, piston)
gives P through :func:`asekit.aero.methods.pressures`.

References: W. R. Sears, "Some aspects of non-stationary airfoil theory and its practical
application", J. Aeronautical Sciences 8(3), 1941, 104-108; R. L. Bisplinghoff, H. Ashley,
R. L. Halfman, *Aeroelasticity*, Addison-Wesley 1955, Section 5-7 (Eqs. 5-336..5-338: the
Sears function with the gust referred to mid-chord); the gust-column formulation of MSC
Nastran's aeroelastic user's guide (Rodden & Johnson 1994, Section 2.6: the gust normalwash
with each box's delay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aero.boxes import BoxMesh
from asekit.aero.methods import pressures
from asekit.aero.spline import BoxModes, modal_forces
from asekit.aero.validity import check_k, mach_number
from asekit.util.blas import blas_threads_for
from asekit.util.validate import finite_array, positive

#: Below this many boxes the pressure solves run on one BLAS thread (as
#: :data:`asekit.aero.gaf.SMALL_SOLVE_BOXES`: threads stall on small matrices).
SMALL_SOLVE_BOXES = 2000


def _x0(x0) -> float:
    v = float(x0)
    if not math.isfinite(v):
        raise ValueError(f"x0 must be a finite gust reference station (m), got {x0!r}")
    return v


def gust_normalwash(x: np.ndarray, k: float, b_ref: float, x0: float = 0.0) -> np.ndarray:
    """Normalwash w/U (shape of ``x``) of a unit upward gust angle W/U = 1 at stations ``x`` (m).

    (w/U) = -exp(-i k (x - x0) / b_ref)  (module docstring: the sign makes an upward gust an
    incidence +W/U, the delay exp(-i k (x - x0)/b) its travel with the flow from x0).

    Parameters
    ----------
    x : streamwise stations (m), e.g. the boxes' control points.
    k : reduced frequency omega b_ref / U >= 0.
    b_ref : reference semi-chord (m) > 0.
    x0 : gust reference station (m).

    Returns
    -------
    complex array shaped like ``x``.

    Examples
    --------
    >>> import numpy as np
    >>> gust_normalwash(np.array([0.0, 1.0]), 0.0, 0.5).real
    array([-1., -1.])
    >>> w = gust_normalwash(np.array([1.0]), np.pi / 2, 0.5, x0=0.5)   # half a chord later
    >>> np.round(w, 12)
    array([-0.+1.j])
    """
    xs = finite_array("x", x)
    if not math.isfinite(float(k)) or float(k) < 0:
        raise ValueError(f"k must be a finite reduced frequency >= 0, got {k!r}")
    b = positive("b_ref", b_ref)
    return -np.exp(-1j * float(k) * (xs - _x0(x0)) / b)


def gust_columns(box_modes: BoxModes, mesh: BoxMesh, mach: float, k, b_ref: float,
                 x0: float = 0.0, method: str = "auto", symmetric: bool = False,
                 aero_options: dict | None = None) -> np.ndarray:
    """The gust column Q_hg(M, k) (n_k, n_modes) complex, per unit dynamic pressure and unit
    gust angle W/U (module docstring): DeltaCp of the gust normalwash by ``method``'s
    pressures (:func:`asekit.aero.methods.pressures`: "auto", "dlm", "supersonic", "piston" or a
    DLM kernel), projected with the modal force transpose H_lp^T diag(A) (Eq. 2.11).

    Parameters
    ----------
    box_modes : mode shapes on the boxes (:func:`asekit.aero.spline.fe_spline`).
    mesh : the boxes; mach : Mach number; k : reduced frequencies (>= 0);
    b_ref : reference semi-chord (m); x0 : gust reference station (m);
    method, symmetric, aero_options : as :func:`asekit.aero.gaf.gaf_from_box_modes`.

    Returns
    -------
    (n_k, n_modes) complex array (a plunge row in m per unit W/U: force / q).

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.aero.spline import analytic_modes
    >>> m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 4, 0), 1.0, 4, 8))
    >>> plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    >>> q = gust_columns(plunge, m, 0.0, [0.0, 0.5], 0.5, method="dlm")
    >>> bool(q[0, 0].real > 0)             # an upward gust lifts the wing
    True
    """
    ks = check_k(k)
    m = mach_number(mach)
    b = positive("b_ref", b_ref)
    xg = _x0(x0)
    x = mesh.control_point[:, 0]
    with blas_threads_for(mesh.n, SMALL_SOLVE_BOXES):
        cp = pressures(mesh, m, ks, b, lambda kk: gust_normalwash(x, kk, b, xg)[:, None],
                       method, symmetric, **(aero_options or {}))
    return np.stack([modal_forces(box_modes, c, mesh.area)[:, 0] for c in cp])


@dataclass(frozen=True)
class GustGafTable:
    """Gust columns beside a modal GAF database (:class:`asekit.aero.gaf.GafDatabase`): kept
    apart so that the modal database's cache and fingerprints are unchanged.

    Attributes
    ----------
    machs : (n_mach,) Mach numbers; k : (n_k,) ascending reduced frequencies (>= 0);
    Qg : (n_mach, n_k, n_modes) complex, per unit dynamic pressure and unit gust angle W/U;
    b_ref : reference semi-chord of k (m); x0 : gust reference station (m).
    """

    machs: np.ndarray
    k: np.ndarray
    Qg: np.ndarray
    b_ref: float
    x0: float = 0.0

    def __post_init__(self):
        machs = np.atleast_1d(finite_array("machs", self.machs))
        k = check_k(self.k)
        qg = finite_array("Qg", self.Qg, complex_values=True)
        if qg.ndim != 3 or qg.shape[:2] != (machs.size, k.size):
            raise ValueError(f"Qg must be (n_mach, n_k, n_modes) = ({machs.size}, {k.size}, n);"
                             f" got {qg.shape}")
        if k.size < 2 or np.any(np.diff(k) <= 0):
            raise ValueError(f"k must hold >= 2 strictly ascending values, got {k}")
        object.__setattr__(self, "machs", machs)
        object.__setattr__(self, "k", k)
        object.__setattr__(self, "Qg", qg)
        object.__setattr__(self, "b_ref", positive("b_ref", self.b_ref))
        object.__setattr__(self, "x0", _x0(self.x0))

    def at(self, mach: float, atol: float = 1e-9) -> np.ndarray:
        """Qg (n_k, n_modes) at one of :attr:`machs` (ValueError naming ``mach`` otherwise).

        Examples
        --------
        >>> t = GustGafTable([0.5], [0.0, 1.0], np.ones((1, 2, 1)), 0.1)
        >>> t.at(0.5).shape
        (2, 1)
        """
        m = mach_number(mach)
        hit = np.nonzero(np.abs(self.machs - m) <= atol)[0]
        if not hit.size:
            raise ValueError(f"mach {m} is not in the gust table {self.machs.tolist()}")
        return self.Qg[hit[0]]


def gust_table(box_modes: BoxModes, mesh: BoxMesh, machs, k, b_ref: float, x0: float = 0.0,
               method: str = "auto", symmetric: bool = False,
               aero_options: dict | None = None) -> GustGafTable:
    """:class:`GustGafTable` of :func:`gust_columns` over ``machs`` x ``k`` (arguments as there).

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.aero.spline import analytic_modes
    >>> m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 4, 0), 1.0, 4, 8))
    >>> plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    >>> gust_table(plunge, m, [0.3, 0.5], [0.0, 0.5], 0.5, method="dlm").Qg.shape
    (2, 2, 1)
    """
    ms = [mach_number(v) for v in np.atleast_1d(machs)]
    ks = check_k(k)
    qg = np.stack([gust_columns(box_modes, mesh, v, ks, b_ref, x0, method, symmetric,
                                aero_options) for v in ms])
    return GustGafTable(np.array(ms), ks, qg, float(b_ref), float(x0))


@dataclass(frozen=True)
class GustAeroTables:
    """One Mach's aerodynamic tables of a gust-loads analysis, from one pressure solve per k
    (:func:`gust_aero_tables`), all per unit dynamic pressure:

    Q : (n_k, n, n) modal GAFs (Eq. 2.11); Qg : (n_k, n) gust column (per unit W/U);
    QL : (n_k, n_loads, n) aerodynamic load rows per unit modal coordinate; QLg : (n_k, n_loads)
    the loads per unit W/U; k : reduced frequencies; b_ref (m); x0 : gust reference (m).
    A load row r sums the box forces with the weights ``load_weights[:, r]`` (e.g. 1 for the
    shear, y - y_root for the bending moment about the root line)."""

    k: np.ndarray
    Q: np.ndarray
    Qg: np.ndarray
    QL: np.ndarray
    QLg: np.ndarray
    b_ref: float
    x0: float


def gust_aero_tables(box_modes: BoxModes, mesh: BoxMesh, mach: float, k, b_ref: float,
                     load_weights, x0: float = 0.0, method: str = "auto",
                     symmetric: bool = False, aero_options: dict | None = None) -> GustAeroTables:
    """Modal GAFs, gust column and aerodynamic load rows from one pressure solve per k: the
    normalwash columns of the modes and of the gust, their DeltaCp by ``method``
    (:func:`asekit.aero.methods.pressures`), projected on the modes (H_lp^T diag(A), Eq. 2.11)
    and on the load weights (W^T diag(A): force summation of the box forces at the load
    points).

    Parameters
    ----------
    box_modes, mesh, mach, k, b_ref, x0, method, symmetric, aero_options :
        as :func:`gust_columns`.
    load_weights : (n_boxes, n_loads) weight of each box's force (at its load point) in each
        load: 1 for a shear (N per N), the lever arm (m) for a moment.

    Returns
    -------
    :class:`GustAeroTables`

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> from asekit.aero.spline import analytic_modes
    >>> m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 4, 0), 1.0, 4, 8))
    >>> plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    >>> t = gust_aero_tables(plunge, m, 0.0, [0.0, 0.5], 0.5, np.ones((m.n, 1)), method="dlm")
    >>> bool(np.allclose(t.QLg[:, 0], t.Qg[:, 0]))     # shear of all boxes = the plunge force
    True
    """
    ks = check_k(k)
    b = positive("b_ref", b_ref)
    xg = _x0(x0)
    w_l = finite_array("load_weights", load_weights)
    if w_l.ndim != 2 or w_l.shape[0] != mesh.n:
        raise ValueError(f"load_weights must be (n_boxes, n_loads) = ({mesh.n}, n); got "
                         f"{w_l.shape}")
    x = mesh.control_point[:, 0]

    def wash(kk):
        return np.hstack([box_modes.normalwash(kk, b), gust_normalwash(x, kk, b, xg)[:, None]])

    with blas_threads_for(mesh.n, SMALL_SOLVE_BOXES):
        cp = pressures(mesh, mach_number(mach), ks, b, wash, method, symmetric,
                       **(aero_options or {}))
    force = np.asarray(mesh.area)[None, :, None] * cp              # (n_k, n_boxes, n + 1)
    modal = np.einsum("bm,kbc->kmc", box_modes.h_lp, force)
    loads = np.einsum("bl,kbc->klc", w_l, force)
    return GustAeroTables(ks, modal[:, :, :-1], modal[:, :, -1], loads[:, :, :-1],
                          loads[:, :, -1], b, xg)
