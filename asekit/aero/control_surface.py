"""Hinged control surfaces (flaps, ailerons, tabs) on a trapezoidal panel: a box mesh aligned
with the hinge line and the side edges, the normalwash of a rigid deflection, hinge moments and
the steady control derivatives.

Geometry. A :class:`ControlSurface` lies on one :class:`~asekit.aero.boxes.TrapezoidSurface`
(the panel): its hinge line joins the points at chord fraction ``hinge_inboard`` of the panel's
local chord at span fraction ``span_start`` and at ``hinge_outboard`` at ``span_end``; the
surface is the part of the panel aft of that line between the two span stations (to the
trailing edge). :func:`hinged_mesh` cuts the panel at every side edge and along every hinge
line, so that box edges fall on the hinge line and on the side edges (MSC Nastran's AESURF
practice, and the requirement of the doublet lattice that a discontinuous normalwash fall on
box edges: Rodden & Johnson, *MSC/NASTRAN Aeroelastic Analysis User's Guide*, 1994, Sec. 2.3).

Deflection. A positive deflection delta is a rotation about the hinge axis that moves the
trailing edge down, the sense of the pitch convention (a nose-up rotation about +y,
docs/conventions.md). A point at in-plane distance d aft of the hinge line moves along the box
normal by h = -delta d; with the hinge swept by Lambda_h, the streamwise slope is
dh/dx = -delta cos(Lambda_h). The normalwash of an oscillating deflection delta exp(i omega t)
is then the modal one of :mod:`asekit.aero.spline` (thesis Eq. 2.10 and the DLM of
:mod:`asekit.aero.dlm`),

    w/U = dh/dx + i k h / b = -delta (cos(Lambda_h) + i k d / b)      (on the surface's boxes),

and 0 elsewhere, so every method of :mod:`asekit.aero.methods` (VLM at k = 0, DLM, Mach box,
piston theory) takes it through the same interface as a structural mode
(:class:`~asekit.aero.spline.BoxModes`).

Hinge moment. The work-conjugate of delta, per unit dynamic pressure (m^3),

    H / q = sum_boxes h(load point) DeltaCp A = -sum_{surface boxes} d DeltaCp A,

positive when it tends to deflect the trailing edge down (Eqs. 2.10-2.11 of the thesis with the
deflection as the mode). The hinge-moment coefficient is C_h = H / (q S_f c_f) with S_f the
surface's area and c_f its mean chord aft of the hinge (S_f over the surface's span), the
usual NACA definition (Abbott & von Doenhoff, *Theory of Wing Sections*, 1959, Sec. 8.7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aero.boxes import BoxMesh, TrapezoidSurface
from asekit.aero.spline import BoxModes, modal_forces
from asekit.util.validate import in_range, integer

__all__ = ["ControlSurface", "HingedMesh", "hinged_mesh", "nesting", "deflection_modes", "hinge_moments",
           "steady_control_derivatives", "ControlDerivatives", "glauert_flap_effectiveness",
           "oscillatory_control_coefficients", "thin_airfoil_flap_derivatives",
           "dimensional_hinge_moments", "mean_aerodynamic_chord", "gearing_matrix",
           "thin_airfoil_hinge_moment"]


@dataclass(frozen=True)
class ControlSurface:
    """A rigid control surface aft of a hinge line on one panel.

    Parameters
    ----------
    name : label used in outputs.
    hinge_inboard, hinge_outboard : chord fractions (0, 1) of the hinge line at the surface's
        inboard and outboard side edges (0 the leading edge, 1 the trailing edge).
    span_start, span_end : span fractions of the panel, 0 <= span_start < span_end <= 1, of the
        inboard and outboard side edges.

    Examples
    --------
    >>> ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0).flap_chord_fraction
    0.25
    """

    name: str
    hinge_inboard: float
    hinge_outboard: float
    span_start: float = 0.0
    span_end: float = 1.0

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string, got {self.name!r}")
        for nm in ("hinge_inboard", "hinge_outboard"):
            object.__setattr__(self, nm, in_range(nm, getattr(self, nm), 0.0, high=1.0,
                                                  high_inclusive=False))
        object.__setattr__(self, "span_start", in_range("span_start", self.span_start, 0.0,
                                                        inclusive=True, high=1.0,
                                                        high_inclusive=False))
        object.__setattr__(self, "span_end", in_range("span_end", self.span_end, 0.0, high=1.0))
        if self.span_end <= self.span_start:
            raise ValueError(f"span_end must be > span_start = {self.span_start:g}, "
                             f"got {self.span_end:g}")

    @property
    def flap_chord_fraction(self) -> float:
        """Mean chord fraction aft of the hinge, 1 - (hinge_inboard + hinge_outboard) / 2."""
        return 1.0 - 0.5 * (self.hinge_inboard + self.hinge_outboard)


@dataclass(frozen=True)
class HingedMesh:
    """A panel's boxes cut along its control surfaces' hinge lines and side edges.

    ``mesh`` the :class:`BoxMesh`; ``surfaces`` the control surfaces; ``on_surface``
    (n_surfaces, n_boxes) bool, the boxes of each surface; ``hinge_point`` (n_surfaces, 3) the
    hinge line's inboard end and ``hinge_axis`` (n_surfaces, 3) its unit direction (outboard).
    """

    mesh: BoxMesh
    surfaces: tuple
    on_surface: np.ndarray
    hinge_point: np.ndarray
    hinge_axis: np.ndarray

    def distance_aft(self, index: int, points: np.ndarray) -> np.ndarray:
        """In-plane distance (m) of ``points`` (m, 3) aft of hinge line ``index``, measured
        perpendicular to the hinge line, positive downstream."""
        s = self.hinge_axis[index]
        aft = np.array([s[1], -s[0], 0.0])
        aft /= np.linalg.norm(aft)
        return (np.asarray(points, float) - self.hinge_point[index]) @ aft

    def surface_area(self, index: int) -> float:
        """Area S_f (m^2) of surface ``index``."""
        return float(np.sum(self.mesh.area[self.on_surface[index]]))

    def surface_span(self, index: int) -> float:
        """Span (m) of surface ``index``: the widths of its strips."""
        m = self.on_surface[index]
        strips, first = np.unique(self.mesh.strip[m], return_index=True)
        return float(np.sum(2.0 * self.mesh.half_width[m][first]))

    def mean_chord(self, index: int) -> float:
        """Mean chord c_f (m) of surface ``index`` aft of its hinge: S_f / its span."""
        return self.surface_area(index) / self.surface_span(index)


def _span_cuts(surfaces) -> np.ndarray:
    cuts = {0.0, 1.0}
    for s in surfaces:
        cuts.update((s.span_start, s.span_end))
    return np.array(sorted(cuts))


def _hinge_fraction_at(surfaces, eta: float, side: str) -> float | None:
    """The hinge chord fraction at span fraction ``eta`` of the surface that touches it from
    ``side`` ("left": the surface ends there, "right": it starts there), or None."""
    for s in surfaces:
        if side == "left" and abs(s.span_end - eta) < 1e-12:
            return s.hinge_outboard
        if side == "right" and abs(s.span_start - eta) < 1e-12:
            return s.hinge_inboard
    return None


def _hinge_at(s: ControlSurface, e0: float, e1: float) -> tuple[float, float]:
    """The hinge chord fractions of ``s`` at span fractions e0 and e1 (inside its span)."""
    t0 = (e0 - s.span_start) / (s.span_end - s.span_start)
    t1 = (e1 - s.span_start) / (s.span_end - s.span_start)
    h = (s.hinge_inboard, s.hinge_outboard)
    return h[0] + t0 * (h[1] - h[0]), h[0] + t1 * (h[1] - h[0])


def _covers(s: ControlSurface, e0: float, e1: float) -> bool:
    return s.span_start <= e0 + 1e-12 and s.span_end >= e1 - 1e-12


def _segment_hinges(surfaces, e0: float, e1: float, default: float, parents):
    """(index of the top-level surface covering [e0, e1] or -1, hinge fraction at e0, at e1);
    ``parents`` (:func:`nesting`) leaves the nested surfaces (tabs) out."""
    for i, s in enumerate(surfaces):
        if parents[i] < 0 and _covers(s, e0, e1):
            return (i, *_hinge_at(s, e0, e1))
    top = [s for s, p in zip(surfaces, parents) if p < 0]
    h0 = _hinge_fraction_at(top, e0, "left")
    h1 = _hinge_fraction_at(top, e1, "right")
    h0 = h1 if h0 is None else h0
    h1 = h0 if h1 is None else h1
    return -1, (default if h0 is None else h0), (default if h1 is None else h1)


def _nested_in(child: ControlSurface, parent: ControlSurface) -> bool:
    """Whether ``child`` is a tab on ``parent``: its span inside the parent's and its hinge
    aft of the parent's hinge at both of its side edges."""
    if not _covers(parent, child.span_start, child.span_end):
        return False
    p0, p1 = _hinge_at(parent, child.span_start, child.span_end)
    return child.hinge_inboard > p0 + 1e-9 and child.hinge_outboard > p1 + 1e-9


class NestingError(ValueError):
    """:func:`nesting`'s refusal; ``surfaces`` holds the indices of the surfaces it names (the
    overlapping pair, earlier first; or the tab, its flap and the flap's own flap)."""

    def __init__(self, message: str, surfaces: tuple):
        super().__init__(message)
        self.surfaces = tuple(surfaces)


def nesting(surfaces) -> tuple:
    """The parent of each control surface: the index of the surface it is a tab on (its span
    inside the parent's and its hinge aft of the parent's hinge), -1 for a surface on the
    wing. Surfaces whose spans overlap must be nested so, one level deep (a tab on a flap,
    not a tab on a tab); a tab rotates about its own hinge relative to its parent and with the
    parent about the parent's hinge. Raises :class:`NestingError` (a ValueError) naming the
    surfaces otherwise.

    Examples
    --------
    >>> nesting([ControlSurface("flap", 0.7, 0.7, 0.2, 0.8),
    ...          ControlSurface("tab", 0.9, 0.9, 0.4, 0.6)])
    (-1, 0)
    """
    surfaces = tuple(surfaces)
    parents = [-1] * len(surfaces)
    for i, a in enumerate(surfaces):
        for j, b in enumerate(surfaces[:i]):
            if b.span_start >= a.span_end - 1e-12 or a.span_start >= b.span_end - 1e-12:
                continue
            if not (_nested_in(a, b) or _nested_in(b, a)):
                raise NestingError(
                    f"control surfaces '{b.name}' and '{a.name}' overlap in span "
                    f"({b.span_start:g}-{b.span_end:g} and {a.span_start:g}-{a.span_end:g}): "
                    f"give each its own span range, or nest one in the other (a tab: its "
                    f"span inside the flap's and its hinge aft of the flap's)", (j, i))
    for i, a in enumerate(surfaces):          # the innermost surface a tab lies in
        hosts = [j for j, b in enumerate(surfaces) if j != i and _nested_in(a, b)]
        if hosts:
            parents[i] = min(hosts, key=lambda j: surfaces[j].flap_chord_fraction)
    for i, p in enumerate(parents):
        if p >= 0 and parents[p] >= 0:
            raise NestingError(f"control surface '{surfaces[i].name}' is a tab on "
                               f"'{surfaces[p].name}', itself a tab on "
                               f"'{surfaces[parents[p]].name}': one level of nesting only",
                               (i, p, parents[p]))
    return tuple(parents)


def _tab_boxes(surfaces, parents, n_aft: int) -> int:
    """Boxes per chord aft of the tabs' hinges: n_aft times the mean share of the tabs in
    their parents' chord aft of the hinge, at least 1 and leaving at least 1 between the
    hinges (0 without tabs)."""
    share = [s.flap_chord_fraction / surfaces[p].flap_chord_fraction
             for s, p in zip(surfaces, parents) if p >= 0]
    if not share:
        return 0
    if n_aft < 2:
        raise ValueError(f"n_chord_aft = {n_aft}: a tab needs at least 2 boxes per chord aft of "
                         f"its flap's hinge (one between the hinges, one on the tab); raise "
                         f"panel.n_chord")
    return min(n_aft - 1, max(1, round(n_aft * float(np.mean(share)))))


def _point(panel: TrapezoidSurface, eta: float, xi: float) -> np.ndarray:
    r, t = np.asarray(panel.root_le), np.asarray(panel.tip_le)
    le = r + eta * (t - r)
    chord = panel.root_chord + eta * (panel.tip_chord - panel.root_chord)
    return le + np.array([xi * chord, 0.0, 0.0])


def hinged_mesh(panel: TrapezoidSurface, surfaces, n_chord_aft: int | None = None) -> HingedMesh:
    """Boxes of ``panel`` whose chordwise lines fall on the hinge lines and whose spanwise
    lines fall on the side edges of ``surfaces``.

    Parameters
    ----------
    panel : the trapezoid; its ``n_chord`` (boxes per chord) and ``n_span`` (boxes across the
        span) are kept, the span boxes shared among the spanwise segments in proportion to
        their width (at least one each).
    surfaces : :class:`ControlSurface` (one or a sequence); spans must not overlap unless one
        surface is a tab on another (:func:`nesting`).
    n_chord_aft : boxes aft of the hinge (1 .. n_chord - 1); default the nearest integer to
        n_chord times the mean chord fraction aft of the hinges of the surfaces on the wing.
        Where a tab lies, these boxes are shared between the flap ahead of the tab's hinge
        and the tab (:func:`_tab_boxes`, at least one each).

    Returns
    -------
    HingedMesh : the boxes (strips root to tip, leading-edge box first in each strip, as
    :func:`asekit.aero.boxes.mesh_surfaces`) and each surface's boxes and hinge line; a
    flap's boxes include those of its tabs (they rotate with it), so its deflection mode,
    hinge moment, area and mean chord run to the trailing edge.

    Examples
    --------
    >>> panel = TrapezoidSurface((0, 0), 1.0, (0, 4.0), 1.0, 8, 8)
    >>> hm = hinged_mesh(panel, ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> hm.mesh.n, int(hm.on_surface[0].sum()), round(hm.surface_area(0), 6)
    (64, 8, 0.5)
    """
    if isinstance(surfaces, ControlSurface):
        surfaces = (surfaces,)
    surfaces = tuple(surfaces)
    if not surfaces or not all(isinstance(s, ControlSurface) for s in surfaces):
        raise ValueError("surfaces must be one or more ControlSurface")
    if not isinstance(panel, TrapezoidSurface):
        raise ValueError(f"panel must be a TrapezoidSurface, got {type(panel).__name__}")
    parents = nesting(surfaces)
    if panel.n_chord < 2:
        raise ValueError(f"panel.n_chord must be >= 2 (boxes ahead of and aft of the hinge), "
                         f"got {panel.n_chord}")
    top = [s for s, p in zip(surfaces, parents) if p < 0]
    mean_aft = float(np.mean([s.flap_chord_fraction for s in top]))
    if n_chord_aft is None:
        n_chord_aft = min(panel.n_chord - 1, max(1, round(panel.n_chord * mean_aft)))
    n_aft = integer("n_chord_aft", n_chord_aft, low=1, high=panel.n_chord - 1)
    n_fwd = panel.n_chord - n_aft
    n_tab = _tab_boxes(surfaces, parents, n_aft)
    cuts = _span_cuts(surfaces)
    widths = np.diff(cuts)
    n_seg = np.maximum(1, np.round(panel.n_span * widths).astype(int))
    corners, strip, owner = [], [], []
    strip0 = 0
    for e0, e1, ns in zip(cuts[:-1], cuts[1:], n_seg):
        isurf, h0, h1 = _segment_hinges(surfaces, e0, e1, 1.0 - mean_aft, parents)
        itab = next((i for i, (s, p) in enumerate(zip(surfaces, parents))
                     if p >= 0 and p == isurf and _covers(s, e0, e1)), -1)
        lines = [(0.0, 0.0), (h0, h1)]
        counts, owners = [n_fwd], [-1]
        if itab >= 0:
            lines.append(_hinge_at(surfaces[itab], e0, e1))
            counts += [n_aft - n_tab, n_tab]
            owners += [isurf, itab]
        else:
            counts.append(n_aft)
            owners.append(isurf)
        lines.append((1.0, 1.0))
        parts = []
        for (a0, a1), (b0, b1), nc in zip(lines[:-1], lines[1:], counts):
            p0, p1 = _point(panel, e0, a0), _point(panel, e1, a1)
            q0, q1 = _point(panel, e0, b0), _point(panel, e1, b1)
            part = TrapezoidSurface(p0, q0[0] - p0[0], p1, q1[0] - p1[0], nc, int(ns))
            parts.append(part.boxes().reshape(int(ns), nc, 4, 3))
        corners.append(np.concatenate(parts, axis=1).reshape(-1, 4, 3))
        strip.append(strip0 + np.repeat(np.arange(int(ns)), panel.n_chord))
        owner.append(np.tile(np.concatenate([np.full(nc, o) for nc, o in zip(counts, owners)]),
                             int(ns)))
        strip0 += int(ns)
    corners = np.concatenate(corners)
    mesh = BoxMesh(corners, np.concatenate(strip), np.zeros(len(corners), int), (panel.name,))
    owner = np.concatenate(owner)
    on = np.array([owner == i for i in range(len(surfaces))])
    for i, p in enumerate(parents):          # a tab's boxes rotate with its parent too
        if p >= 0:
            on[p] |= on[i]
    pts = np.array([_point(panel, s.span_start, s.hinge_inboard) for s in surfaces])
    ends = np.array([_point(panel, s.span_end, s.hinge_outboard) for s in surfaces])
    axis = (ends - pts) / np.linalg.norm(ends - pts, axis=1)[:, None]
    return HingedMesh(mesh, surfaces, on, pts, axis)


def deflection_modes(hm: HingedMesh) -> BoxModes:
    """The unit deflections (1 rad, trailing edge down) of the surfaces as box modes:
    h = -d, dh/dx = -cos(Lambda_h) on each surface's boxes, 0 elsewhere (module docstring),
    one column per surface; ``.normalwash(k, b_ref)`` gives w/U = dh/dx + i k h / b.

    Examples
    --------
    >>> panel = TrapezoidSurface((0, 0), 1.0, (0, 4.0), 1.0, 4, 2)
    >>> m = deflection_modes(hinged_mesh(panel, ControlSurface("flap", 0.75, 0.75)))
    >>> m.normalwash(0.0, 0.5)[:4, 0].real.tolist()       # steady: w/U = -delta on the flap
    [0.0, 0.0, 0.0, -1.0]
    """
    mesh = hm.mesh
    n_s = len(hm.surfaces)
    h_cp, s_cp, h_lp = (np.zeros((mesh.n, n_s)) for _ in range(3))
    for i in range(n_s):
        on = hm.on_surface[i]
        ax = hm.hinge_axis[i]
        cos_sweep = ax[1] / np.hypot(ax[0], ax[1])      # d(distance aft)/dx = cos(Lambda_h)
        h_cp[on, i] = -hm.distance_aft(i, mesh.control_point[on])
        s_cp[on, i] = -cos_sweep
        h_lp[on, i] = -hm.distance_aft(i, mesh.load_point[on])
    return BoxModes(h_cp, s_cp, h_lp)


def hinge_moments(hm: HingedMesh, delta_cp: np.ndarray) -> np.ndarray:
    """Hinge moments per unit dynamic pressure H / q (m^3), (n_surfaces, n_cols), of the
    pressure jumps ``delta_cp`` (n_boxes, n_cols): -sum d DeltaCp A over each surface's boxes
    (module docstring), positive when they tend to deflect the trailing edge down.

    Examples
    --------
    A unit DeltaCp on a flap of chord 0.25 m and span 2 m, one box per chord: each box's load
    acts at its quarter chord (the lattice's load point), d = 0.0625 m, so H / q = -0.0625 x
    0.5 m^2 (-0.0625 for the continuous integral, -c_f^2 / 2 x span: the boxes converge to it).

    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 1.0, (0, 2.0), 1.0, 4, 2),
    ...                  ControlSurface("flap", 0.75, 0.75))
    >>> round(float(hinge_moments(hm, np.ones(hm.mesh.n))[0, 0]), 6)
    -0.03125
    """
    cp = np.asarray(delta_cp)
    if cp.ndim == 1:
        cp = cp[:, None]
    if cp.shape[0] != hm.mesh.n:
        raise ValueError(f"delta_cp must have {hm.mesh.n} rows (one per box), got {cp.shape[0]}")
    return modal_forces(deflection_modes(hm), cp, hm.mesh.area)


@dataclass(frozen=True)
class ControlDerivatives:
    """Steady (rigid) derivatives of a panel with control surfaces at one Mach number, per
    radian: lift coefficients on the reference area, ``dCL_dalpha`` and ``dCL_ddelta``
    (n_surfaces,); hinge-moment coefficients C_h = H / (q S_f c_f), ``Ch_alpha`` and
    ``Ch_delta`` (n_surfaces,); ``mach``; ``reference_area`` (m^2); pitching-moment
    coefficients ``dCm_dalpha`` and ``dCm_ddelta`` (n_surfaces,), Cm = M_y / (q S c_ref)
    positive nose up, about the axis x = ``moment_reference[0]`` (m) parallel to y, with
    c_ref = ``moment_reference[1]`` (m)."""

    mach: float
    reference_area: float
    dCL_dalpha: float
    dCL_ddelta: np.ndarray
    Ch_alpha: np.ndarray
    Ch_delta: np.ndarray
    dCm_dalpha: float = math.nan
    dCm_ddelta: np.ndarray | None = None
    moment_reference: tuple = (math.nan, math.nan)

    @property
    def effectiveness(self) -> np.ndarray:
        """(dCL/d delta) / (dCL/d alpha), the 3-D flap effectiveness (-)."""
        return self.dCL_ddelta / self.dCL_dalpha


def mean_aerodynamic_chord(mesh: BoxMesh) -> tuple[float, float]:
    """(x_ref, c_ref) m: the quarter-chord point x of the mean aerodynamic chord and the mean
    aerodynamic chord c_ref = int c^2 dy / int c dy of the boxes' strips (each strip's chord
    its area over its width, its leading edge that of its foremost box at mid-strip), x_ref =
    x_le,MAC + c_ref / 4 with x_le,MAC = int x_le c dy / int c dy (the standard reference of
    pitching moments; Raymer, *Aircraft Design*, 1992, Sec. 7.5).

    Examples
    --------
    >>> p = TrapezoidSurface((0, 0), 2.0, (1.0, 4.0), 1.0, 4, 40)
    >>> from asekit.aero.boxes import mesh_surfaces
    >>> x, c = mean_aerodynamic_chord(mesh_surfaces([p]))
    >>> round(c, 3), round(x, 3)                    # 2/3 (cr + ct - cr ct / (cr + ct)) = 1.556
    (1.556, 0.833)
    """
    strips = np.unique(mesh.strip)
    c, w, x_le = (np.empty(strips.size) for _ in range(3))
    for n, st in enumerate(strips):
        m = mesh.strip == st
        w[n] = 2.0 * float(mesh.half_width[m][0])
        c[n] = float(np.sum(mesh.area[m])) / w[n]
        le = 0.5 * (mesh.corners[m][:, 0, 0] + mesh.corners[m][:, 3, 0])
        x_le[n] = float(np.min(le))
    c_ref = float(np.sum(c * c * w) / np.sum(c * w))
    return float(np.sum(x_le * c * w) / np.sum(c * w)) + 0.25 * c_ref, c_ref


def gearing_matrix(n_surfaces: int, links=()) -> tuple[np.ndarray, np.ndarray]:
    """The linear links between control-surface deflections (MSC Nastran's AELINK; a geared
    tab: delta_tab = G delta_flap; Rodden & Johnson, *MSC/NASTRAN Aeroelastic Analysis User's
    Guide*, 1994, Sec. 3.5): delta = T delta_free.

    Parameters
    ----------
    n_surfaces : the surfaces' count (>= 1).
    links : (slave, master, gear) triples, surface indices: delta_slave = gear delta_master
        (gear finite, any sign: > 0 the tab deflects with the flap, < 0 against it, a balance
        tab). A slave is linked once and is no master; a master is not linked itself.

    Returns
    -------
    T : (n_surfaces, n_free) the gearing matrix, identity rows for the free surfaces.
    free : (n_free,) the free surfaces' indices, ascending.

    Examples
    --------
    >>> T, free = gearing_matrix(2, [(1, 0, -0.5)])
    >>> T.tolist(), free.tolist()
    ([[1.0], [-0.5]], [0])
    """
    n = integer("n_surfaces", n_surfaces, low=1)
    slaves = [int(k[0]) for k in links]
    for slave, master, gear in links:
        if not (0 <= slave < n and 0 <= master < n) or slave == master or master in slaves \
                or slaves.count(slave) > 1 or not math.isfinite(gear):
            raise ValueError(f"links must be (slave, master, gear) with two different surface "
                             f"indices in [0, {n - 1}], each slave linked once and no master "
                             f"a slave, gear finite; got {tuple(links)}")
    free = np.array([i for i in range(n) if i not in slaves], int)
    T = np.zeros((n, free.size))
    T[free, np.arange(free.size)] = 1.0
    for slave, master, gear in links:
        T[slave, int(np.flatnonzero(free == master)[0])] = float(gear)
    return T, free


def thin_airfoil_hinge_moment(hinge_chord_fraction: float, deflected_chord_fraction: float,
                              n: int = 1000) -> float:
    """2-D thin-airfoil hinge-moment coefficient C_h = H / (q c_f^2) (per rad, trailing edge
    down positive) about a hinge at ``1 - hinge_chord_fraction`` of the chord (c_f the chord
    aft of it) of the load of a deflected trailing-edge segment of chord fraction
    ``deflected_chord_fraction``: the flap's own C_h delta when both are equal, the flap's
    hinge moment per rad of its tab's deflection when the tab is the shorter segment.

    The load of a segment deflected by delta from theta_t (cos theta_t = 1 - 2 x_t / c) is
    Glauert's series summed in closed form (Glauert, *The Elements of Aerofoil and Airscrew
    Theory*, 1926, Ch. VII: A_0 = delta (pi - theta_t) / pi, A_n = 2 delta sin(n theta_t) /
    (n pi), DeltaCp = 4 (A_0 cot(theta/2) + sum A_n sin(n theta)), and
    sum sin(n a) sin(n b) / n = ln abs(sin((a + b)/2) / sin((a - b)/2)) / 2),

        DeltaCp = 4 delta [(pi - theta_t) / pi cot(theta/2)
                           + ln abs(sin((theta + theta_t)/2) / sin((theta - theta_t)/2)) / pi],

    and H / q = -int_{x_f}^{c} (x - x_f) DeltaCp dx, integrated here in theta by the
    Gauss-Legendre rule with ``n`` points on each side of theta_t (the logarithm integrable).

    Examples
    --------
    A 25 %-chord flap (Theodorsen's steady value, NACA Report 496, is -0.944 per rad):

    >>> round(thin_airfoil_hinge_moment(0.25, 0.25), 3)
    -0.944
    """
    from scipy.special import roots_legendre

    e_f = in_range("hinge_chord_fraction", hinge_chord_fraction, 0.0, high=1.0)
    e_t = in_range("deflected_chord_fraction", deflected_chord_fraction, 0.0, high=1.0)
    n = integer("n", n, low=8)
    th_t = math.acos(1.0 - 2.0 * (1.0 - e_t))
    th_f = math.acos(1.0 - 2.0 * (1.0 - e_f))
    x_f = 1.0 - e_f
    g, w = roots_legendre(n)

    def integral(a, b):
        th = 0.5 * (b - a) * g + 0.5 * (a + b)
        dcp = 4.0 * ((math.pi - th_t) / math.pi / np.tan(0.5 * th)
                     + np.log(np.abs(np.sin(0.5 * (th + th_t)) / np.sin(0.5 * (th - th_t))))
                     / math.pi)
        x = 0.5 * (1.0 - np.cos(th))
        return float(np.sum(w * -(x - x_f) * dcp * 0.5 * np.sin(th)) * 0.5 * (b - a))

    pieces = [th_f, th_t, math.pi] if th_t > th_f else [th_f, math.pi]
    h = sum(integral(a, b) for a, b in zip(pieces[:-1], pieces[1:]))
    return h / (e_f * e_f)


def steady_control_derivatives(hm: HingedMesh, mach: float, symmetric: bool = False,
                               reference_area: float | None = None,
                               moment_reference: tuple | None = None,
                               links=()) -> ControlDerivatives:
    """dCL/d alpha, dCL/d delta, dCm/d alpha, dCm/d delta, C_h alpha and C_h delta of every
    surface from the vortex lattice (:mod:`asekit.aero.vlm`) at Mach ``mach`` (0 <= M < 1).

    With ``links`` (:func:`gearing_matrix`: a geared tab, delta_slave = G delta_master) the
    derivatives are those of the free surfaces only, each deflected with its slaves: dCL/d
    delta = CL_master + G CL_slave, and C_h delta the master's hinge moment under that
    motion, its own C_h plus G times the slave's load on the master's hinge (the classic
    reduction of a flap's hinge moment by a balance tab, G < 0).

    The angle of attack is w/U = -1 on every box, a deflection the steady normalwash of
    :func:`deflection_modes`; CL = sum DeltaCp A n_z / S (S the panel's area, doubled with
    its image when ``symmetric``, or ``reference_area``), Cm = -sum (x_lp - x_ref) DeltaCp A
    n_z / (S c_ref) (nose up positive; each box's load at its load point x_lp; (x_ref, c_ref)
    = ``moment_reference``, default :func:`mean_aerodynamic_chord`), C_h = H / (q S_f c_f)
    with H from :func:`hinge_moments`.

    Examples
    --------
    >>> panel = TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 12)
    >>> d = steady_control_derivatives(hinged_mesh(panel, ControlSurface("f", .75, .75)), 0.0,
    ...                                symmetric=True)
    >>> round(float(d.effectiveness[0]), 2), bool(d.Ch_delta[0] < 0 and d.Ch_alpha[0] < 0)
    (0.59, True)
    """
    from asekit.aero.vlm import steady_pressure

    mesh = hm.mesh
    nz = mesh.normal[:, 2]
    T, free = gearing_matrix(len(hm.surfaces), links)    # identity without links
    wash = np.column_stack([-nz, deflection_modes(hm).normalwash(0.0, 1.0).real @ T])
    cp = steady_pressure(mesh, mach, wash, symmetric)
    lift = (mesh.area * nz) @ cp
    x_ref, c_ref = (mean_aerodynamic_chord(mesh) if moment_reference is None else
                    (float(moment_reference[0]), in_range("moment_reference[1]",
                                                          moment_reference[1], 0.0)))
    pitch = -((mesh.load_point[:, 0] - x_ref) * mesh.area * nz) @ cp
    s = float(np.sum(mesh.area))
    if symmetric:
        lift, pitch = 2.0 * lift, 2.0 * pitch
        s *= 2.0
    if reference_area is not None:
        s = in_range("reference_area", reference_area, 0.0)
    h = hinge_moments(hm, cp)[free]                 # (n_free, 1 + n_free)
    sc = np.array([hm.surface_area(i) * hm.mean_chord(i) for i in free])
    cm = pitch / (s * c_ref)
    return ControlDerivatives(float(mach), s, float(lift[0] / s), lift[1:] / s,
                              h[:, 0] / sc, h[np.arange(free.size), 1 + np.arange(free.size)]
                              / sc, float(cm[0]), cm[1:], (float(x_ref), float(c_ref)))


def oscillatory_control_coefficients(hm: HingedMesh, mach: float, k, b_ref: float,
                                     method: str = "auto", symmetric: bool = False):
    """Lift and hinge-moment coefficients of oscillating deflections delta exp(i omega t) at
    reduced frequencies ``k`` (k = omega b_ref / U) by the method of
    :mod:`asekit.aero.methods` (``"auto"``: the doublet lattice below M 1, the Mach box
    above), the deflection normalwash of :func:`deflection_modes`.

    Returns
    -------
    CL_delta : (n_k, n_s) complex, lift coefficient on the panel area (doubled with the image
        when ``symmetric``) per rad of each surface's deflection.
    Ch_delta : (n_k, n_s, n_s) complex, C_h of surface i (rows) per rad of surface j's
        deflection, H / (q S_f c_f) (module docstring).

    Examples
    --------
    >>> panel = TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 6)
    >>> hm = hinged_mesh(panel, ControlSurface("f", 0.75, 0.75))
    >>> cl, ch = oscillatory_control_coefficients(hm, 0.0, [0.001, 0.5], 0.5, symmetric=True)
    >>> bool(abs(cl[1, 0]) < abs(cl[0, 0])), bool(ch[0, 0, 0].real < 0)
    (True, True)
    """
    from asekit.aero.methods import pressures

    mesh = hm.mesh
    modes = deflection_modes(hm)
    cp = pressures(mesh, mach, k, b_ref, lambda kk: modes.normalwash(kk, b_ref), method,
                   symmetric)                                    # (n_k, n, n_s)
    s = float(np.sum(mesh.area)) * (2.0 if symmetric else 1.0)
    lift = np.einsum("b,kbj->kj", mesh.area * mesh.normal[:, 2], cp) * (2.0 if symmetric else 1.0)
    sc = np.array([hm.surface_area(i) * hm.mean_chord(i) for i in range(len(hm.surfaces))])
    h = np.stack([modal_forces(modes, c, mesh.area) for c in cp])   # (n_k, n_s, n_s)
    return lift / s, h / sc[None, :, None]


def glauert_flap_effectiveness(flap_chord_fraction: float) -> float:
    """Thin-airfoil flap effectiveness tau = 1 - (theta_h - sin theta_h) / pi with
    cos theta_h = 1 - 2 x_h / c, x_h / c = 1 - E (Glauert, *The Elements of Aerofoil and
    Airscrew Theory*, 1926, Sec. 7.5; Abbott & von Doenhoff Eq. 8.14): the 2-D
    (dcl/d delta) / (dcl/d alpha) of a flap of chord fraction E.

    Examples
    --------
    >>> round(glauert_flap_effectiveness(0.25), 3)
    0.609
    """
    e = in_range("flap_chord_fraction", flap_chord_fraction, 0.0, high=1.0)
    th = np.arccos(1.0 - 2.0 * (1.0 - e))
    return float(1.0 - (th - np.sin(th)) / np.pi)


def thin_airfoil_flap_derivatives(flap_chord_fraction: float) -> tuple[float, float, float]:
    """Thin-airfoil (2-D, incompressible) lift and moment slopes of an airfoil with a plain
    flap of chord fraction E, from the Fourier coefficients of the flap's camber line,
    A_0 = delta (pi - theta_h) / pi, A_n = 2 delta sin(n theta_h) / (n pi), with
    c_l = pi (2 A_0 + A_1) and c_m,c/4 = pi (A_2 - A_1) / 4 (Glauert, *The Elements of
    Aerofoil and Airscrew Theory*, 1926, Ch. VII; Abbott & von Doenhoff, *Theory of Wing
    Sections*, 1959, Sec. 8.7):

        c_l,alpha = 2 pi,   c_l,delta = 2 (pi - theta_h + sin theta_h),
        c_m,delta = -(1/2) sin theta_h (1 - cos theta_h)   (about the quarter chord),

    with cos theta_h = 1 - 2 x_h / c, x_h / c = 1 - E, per radian.

    Returns
    -------
    (c_l_alpha, c_l_delta, c_m_delta) per rad; c_m nose up positive.

    Examples
    --------
    >>> [round(v, 3) for v in thin_airfoil_flap_derivatives(0.25)]
    [6.283, 3.826, -0.65]
    """
    e = in_range("flap_chord_fraction", flap_chord_fraction, 0.0, high=1.0)
    th = float(np.arccos(1.0 - 2.0 * (1.0 - e)))
    return (2.0 * np.pi, float(2.0 * (np.pi - th + np.sin(th))),
            float(-0.5 * np.sin(th) * (1.0 - np.cos(th))))


def dimensional_hinge_moments(hm: HingedMesh, d: ControlDerivatives,
                              dynamic_pressure: float) -> tuple[np.ndarray, np.ndarray]:
    """Hinge moments per unit deflection and per unit incidence of every surface at dynamic
    pressure q (Pa): H_delta = q S_f c_f C_h,delta and H_alpha = q S_f c_f C_h,alpha (N m/rad),
    the definition C_h = H / (q S_f c_f) of the module docstring inverted, with S_f the
    surface's area and c_f its mean chord aft of the hinge. A rigid surface's hinge moment is
    linear in q at a fixed Mach; the actuator holding the surface applies -H (trailing edge
    down positive).

    Parameters
    ----------
    hm : the boxes with the surfaces (:func:`hinged_mesh`).
    d : their steady derivatives (:func:`steady_control_derivatives`) at the Mach of q.
    dynamic_pressure : q (Pa, >= 0).

    Returns
    -------
    (H_delta, H_alpha) : (n_surfaces,) arrays, N m/rad.

    Examples
    --------
    >>> panel = TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 12)
    >>> hm = hinged_mesh(panel, ControlSurface("f", .75, .75))
    >>> d = steady_control_derivatives(hm, 0.0, symmetric=True)
    >>> h_d, h_a = dimensional_hinge_moments(hm, d, 1000.0)
    >>> bool(np.isclose(h_d[0], 1000.0 * 0.75 * 0.25 * d.Ch_delta[0])), bool(h_a[0] < 0)
    (True, True)
    """
    q = in_range("dynamic_pressure", dynamic_pressure, 0.0, inclusive=True)
    sc = np.array([hm.surface_area(i) * hm.mean_chord(i) for i in range(len(hm.surfaces))])
    return q * sc * np.asarray(d.Ch_delta, float), q * sc * np.asarray(d.Ch_alpha, float)
