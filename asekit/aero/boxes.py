"""Aerodynamic boxes (lifting-surface panels) on trapezoidal surfaces, and the DLM mesh rules.

A :class:`TrapezoidSurface` is a flat trapezoid in 3-D with streamwise root and tip chords
(chordwise lines parallel to the free stream, +x) and any sweep, taper and dihedral. It is cut
into ``n_chord x n_span`` boxes; each box carries a doublet line on its quarter chord and a
control point at three-quarter chord, mid-span (Albano & Rodden 1969; thesis Section 2.2.1.2).

Box corners follow the convention of the doublet-lattice literature: 1 inboard leading edge,
2 inboard trailing edge, 3 outboard trailing edge, 4 outboard leading edge, with "outboard"
meaning larger spanwise coordinate along the surface. The box normal is
``n = x_hat x s_hat = (0, -sin(gamma), cos(gamma))`` where ``s_hat`` is the unit spanwise
direction of the doublet line and ``gamma`` the dihedral: +z for a horizontal surface.

Mesh rules (thesis Section 3.2.1, MSC FlightLoads guidelines): boxes per wavelength
``BPW = U_min / (f_max dx) >= 15`` (Eq. 3.5), at least 4 boxes per chord and box aspect ratio
below 3. :func:`check_mesh_rules` returns the numbers and warns, naming the offending strips.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from asekit.util.validate import integer, positive

#: largest dense aerodynamic matrix set a single call may allocate (bytes); calls that would need
#: more are refused up front with the estimate and the setting to change.
MAX_MATRIX_BYTES = 4 * 2 ** 30
#: largest number of boxes of one surface (the corners alone of 1e6 boxes are 96 MB)
MAX_BOXES = 200_000
#: The doublet lattice's mesh rule (thesis Eq. 3.5): boxes per wavelength U_min / (f_max dx).
BPW_MIN = 15.0


def dlm_max_box_chord(u_min: float, f_max: float, bpw_min: float = BPW_MIN) -> float:
    """The longest box chord (m) of the DLM mesh rule BPW = U_min / (f_max dx) >= ``bpw_min``
    (thesis Eq. 3.5): dx = u_min / (bpw_min f_max), u_min in m/s, f_max in Hz.

    Examples
    --------
    >>> round(dlm_max_box_chord(180.0, 1000.0), 6)     # the reference fin: 12 mm
    0.012
    """
    return u_min / (bpw_min * f_max)


def check_matrix_memory(n_boxes: int, n_matrices: int, itemsize: int, what: str,
                        knob: str) -> None:
    """Refuse (ValueError) a dense (n_matrices, n_boxes, n_boxes) allocation above
    :data:`MAX_MATRIX_BYTES`, naming the estimate, ``what`` is built and the ``knob`` to change."""
    need = float(n_matrices) * float(n_boxes) ** 2 * itemsize
    if need > MAX_MATRIX_BYTES:
        raise ValueError(f"{what} for {n_boxes} boxes x {n_matrices} matrices needs about "
                         f"{need / 2 ** 30:.3g} GiB (limit {MAX_MATRIX_BYTES / 2 ** 30:.3g} GiB, "
                         f"asekit.aero.boxes.MAX_MATRIX_BYTES): {knob}")


class MeshRuleWarning(UserWarning):
    """An aerodynamic mesh violates a doublet-lattice guideline (BPW, boxes per chord, AR)."""


def _finite_point(name: str, p) -> tuple[float, float, float]:
    p = tuple(float(v) for v in p)
    if len(p) == 2:
        p = p + (0.0,)
    if len(p) != 3 or not all(math.isfinite(v) for v in p):
        raise ValueError(f"{name} must be a finite (x, y) or (x, y, z) point, got {p!r}")
    return p


@dataclass(frozen=True)
class TrapezoidSurface:
    """A flat trapezoidal lifting surface (all lengths in m).

    Parameters
    ----------
    root_le, tip_le : (x, y, z) of the root and tip leading edges (z may be omitted: 0).
    root_chord, tip_chord : streamwise chords (> 0) at root and tip.
    n_chord, n_span : number of boxes chordwise (>= 1) and spanwise (>= 1), equally spaced in
        chord fraction and span fraction.
    name : label used in mesh-rule warnings.
    """

    root_le: tuple[float, float, float]
    root_chord: float
    tip_le: tuple[float, float, float]
    tip_chord: float
    n_chord: int
    n_span: int
    name: str = "surface"

    def __post_init__(self):
        object.__setattr__(self, "root_le", _finite_point("root_le", self.root_le))
        object.__setattr__(self, "tip_le", _finite_point("tip_le", self.tip_le))
        for nm in ("root_chord", "tip_chord"):
            object.__setattr__(self, nm, positive(nm, getattr(self, nm)))
        for nm in ("n_chord", "n_span"):
            object.__setattr__(self, nm, integer(nm, getattr(self, nm), low=1))
        if self.n_chord * self.n_span > MAX_BOXES:
            raise ValueError(f"n_chord x n_span = {self.n_chord} x {self.n_span} = "
                             f"{self.n_chord * self.n_span} boxes exceeds the limit {MAX_BOXES} "
                             "(asekit.aero.boxes.MAX_BOXES): use fewer boxes")
        dy = self.tip_le[1] - self.root_le[1]
        dz = self.tip_le[2] - self.root_le[2]
        if math.hypot(dy, dz) <= 0.0:
            raise ValueError("root_le and tip_le must differ in (y, z): the surface has zero span")

    def boxes(self) -> np.ndarray:
        """Corner points of the boxes, shape ``(n_span * n_chord, 4, 3)``, strip by strip
        (root strip first), leading-edge box first within a strip."""
        eta = np.linspace(0.0, 1.0, self.n_span + 1)
        xi = np.linspace(0.0, 1.0, self.n_chord + 1)
        r = np.asarray(self.root_le)
        t = np.asarray(self.tip_le)
        le = r[None, :] + eta[:, None] * (t - r)[None, :]          # (n_span+1, 3)
        chord = self.root_chord + eta * (self.tip_chord - self.root_chord)
        grid = le[:, None, :] + (xi[None, :, None] * chord[:, None, None]
                                 * np.array([1.0, 0.0, 0.0])[None, None, :])
        p1 = grid[:-1, :-1]
        p2 = grid[:-1, 1:]
        p3 = grid[1:, 1:]
        p4 = grid[1:, :-1]
        return np.stack([p1, p2, p3, p4], axis=2).reshape(-1, 4, 3)


@dataclass(frozen=True)
class BoxMesh:
    """Boxes of one or several surfaces.

    ``corners`` (n, 4, 3) in m (see the module docstring for the corner order), ``strip`` (n,)
    the global chordwise-strip index of each box, ``surface`` (n,) the surface index and
    ``surface_names`` the surface labels. Derived geometry is exposed as properties.
    """

    corners: np.ndarray
    strip: np.ndarray
    surface: np.ndarray
    surface_names: tuple[str, ...] = ("surface",)

    def __post_init__(self):
        c = np.asarray(self.corners, float)
        if c.ndim != 3 or c.shape[1:] != (4, 3) or c.shape[0] < 1:
            raise ValueError(f"corners must have shape (n >= 1, 4, 3), got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("corners must be finite")
        c.setflags(write=False)
        object.__setattr__(self, "corners", c)
        for nm in ("strip", "surface"):
            a = np.asarray(getattr(self, nm), int)
            if a.shape != (c.shape[0],):
                raise ValueError(f"{nm} must have shape ({c.shape[0]},), got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, nm, a)
        # chordwise edges must be parallel to the flow: same y, z at leading and trailing edge
        side_in = c[:, 1] - c[:, 0]
        side_out = c[:, 2] - c[:, 3]
        scale = np.max(np.ptp(c.reshape(-1, 3), axis=0)) + 1e-300
        bad = np.flatnonzero((np.abs(side_in[:, 1:]).max(axis=1) > 1e-9 * scale)
                             | (np.abs(side_out[:, 1:]).max(axis=1) > 1e-9 * scale)
                             | (side_in[:, 0] <= 0) | (side_out[:, 0] <= 0))
        if bad.size:
            raise ValueError(f"boxes {bad[:10].tolist()} are not aligned with the flow: their side "
                             "edges must run in +x (streamwise) with corner 2 behind corner 1 and "
                             "corner 3 behind corner 4")
        if np.any(self.area <= 1e-12 * scale**2):
            bad = np.flatnonzero(self.area <= 1e-12 * scale**2)
            raise ValueError(f"boxes {bad[:10].tolist()} have zero area")
        self._check_overlap()

    # ---- derived geometry ---------------------------------------------------------------
    @cached_property
    def n(self) -> int:
        return self.corners.shape[0]

    @cached_property
    def doublet_p1(self) -> np.ndarray:
        """Inboard end of the quarter-chord doublet line (n, 3)."""
        c = self.corners
        return c[:, 0] + 0.25 * (c[:, 1] - c[:, 0])

    @cached_property
    def doublet_p3(self) -> np.ndarray:
        """Outboard end of the quarter-chord doublet line (n, 3)."""
        c = self.corners
        return c[:, 3] + 0.25 * (c[:, 2] - c[:, 3])

    @cached_property
    def load_point(self) -> np.ndarray:
        """Mid-point of the doublet line (quarter chord, mid-span), where box forces act (n, 3)."""
        return 0.5 * (self.doublet_p1 + self.doublet_p3)

    @cached_property
    def control_point(self) -> np.ndarray:
        """Three-quarter-chord point at mid-span, where the normalwash is imposed (n, 3)."""
        c = self.corners
        inner = c[:, 0] + 0.75 * (c[:, 1] - c[:, 0])
        outer = c[:, 3] + 0.75 * (c[:, 2] - c[:, 3])
        return 0.5 * (inner + outer)

    @cached_property
    def chord(self) -> np.ndarray:
        """Streamwise box chord at mid-span (m), the Delta x of Albano & Rodden (n,)."""
        c = self.corners
        return 0.5 * ((c[:, 1, 0] - c[:, 0, 0]) + (c[:, 2, 0] - c[:, 3, 0]))

    @cached_property
    def half_width(self) -> np.ndarray:
        """Half the length of the doublet line projected on the y-z plane, e (m) (n,)."""
        d = self.doublet_p3 - self.doublet_p1
        return 0.5 * np.hypot(d[:, 1], d[:, 2])

    @cached_property
    def area(self) -> np.ndarray:
        """Box area (m^2) = chord x width (n,)."""
        return self.chord * 2.0 * self.half_width

    @cached_property
    def dihedral(self) -> np.ndarray:
        """Dihedral angle gamma of the doublet line (rad): atan2(dz, dy) (n,)."""
        d = self.doublet_p3 - self.doublet_p1
        return np.arctan2(d[:, 2], d[:, 1])

    @cached_property
    def tan_sweep(self) -> np.ndarray:
        """tan of the quarter-chord sweep, dx / (2 e) (n,)."""
        d = self.doublet_p3 - self.doublet_p1
        return d[:, 0] / (2.0 * self.half_width)

    @cached_property
    def normal(self) -> np.ndarray:
        """Unit box normal (0, -sin gamma, cos gamma) (n, 3); +z for a horizontal box."""
        g = self.dihedral
        return np.stack([np.zeros_like(g), -np.sin(g), np.cos(g)], axis=1)

    @cached_property
    def aspect_ratio(self) -> np.ndarray:
        """Box aspect ratio, the longer over the shorter of width (2e) and chord (n,)."""
        w = 2.0 * self.half_width
        return np.maximum(w / self.chord, self.chord / w)

    def mirrored(self) -> BoxMesh:
        """The image of the mesh in the plane y = 0, corners re-ordered so that corner 1 is again
        inboard (the image box carries the same upward-symmetric loading: a wall at y = 0).

        Raises ValueError if the mesh crosses y = 0 (``symmetric=True`` needs a half model on
        one side of the plane: its image would overlap it and silently change the loads)."""
        y = self.corners[:, :, 1]
        tol = 1e-9 * (np.ptp(self.corners.reshape(-1, 3), axis=0).max() + 1e-300)
        if y.min() < -tol and y.max() > tol:
            raise ValueError(f"symmetric=True needs the mesh on one side of y = 0 (a half model "
                             f"at a wall), but its boxes span y = {y.min():.6g} .. "
                             f"{y.max():.6g} m: the image would overlap the mesh; pass "
                             "symmetric=False or mesh one half")
        in_plane = np.flatnonzero(np.abs(y).max(axis=1) <= tol)
        if in_plane.size:
            raise ValueError(f"symmetric=True: boxes {in_plane[:10].tolist()} lie in the plane "
                             "y = 0 and would coincide with their own images; pass "
                             "symmetric=False for a surface in the symmetry plane")
        c = self.corners * np.array([1.0, -1.0, 1.0])
        c = c[:, [3, 2, 1, 0]]
        return BoxMesh(c, self.strip, self.surface, self.surface_names)

    def _local_inside(self, pts: np.ndarray, boxes: np.ndarray, tol: float) -> np.ndarray:
        """(len(pts), len(boxes)) bool: point strictly inside box (in its plane, within tol)."""
        c = self.corners[boxes]                                    # (m, 4, 3)
        s_hat = self.doublet_p3[boxes] - self.doublet_p1[boxes]
        s_hat[:, 0] = 0.0
        s_hat /= np.linalg.norm(s_hat, axis=1)[:, None]
        nrm = self.normal[boxes]
        d = pts[:, None, :] - c[None, :, 0, :]                     # from corner 1
        off = np.abs(np.einsum("pmk,mk->pm", d, nrm))
        sp = np.einsum("pmk,mk->pm", d, s_hat)
        s4 = np.einsum("mk,mk->m", c[:, 3] - c[:, 0], s_hat)       # outboard edge station
        t = sp / s4[None, :]
        xle = c[None, :, 0, 0] + t * (c[None, :, 3, 0] - c[None, :, 0, 0])
        xte = c[None, :, 1, 0] + t * (c[None, :, 2, 0] - c[None, :, 1, 0])
        x = pts[:, None, 0]
        return ((off <= tol) & (sp > tol) & (sp < s4[None, :] - tol)
                & (x > xle + tol) & (x < xte - tol))

    def _check_overlap(self) -> None:
        """Raise ValueError if two boxes are duplicated or overlap: the load point, control point
        or centre of one box lies strictly inside another box of the same plane (the VLM/DLM
        matrix would be singular -- a raw LinAlgError -- or ill-conditioned garbage)."""
        n = self.n
        if n < 2:
            return
        c = self.corners
        scale = float(np.ptp(c.reshape(-1, 3), axis=0).max()) + 1e-300
        tol = 1e-9 * scale
        centre = c.mean(axis=1)
        radius = np.linalg.norm(c - centre[:, None, :], axis=2).max(axis=1)
        from scipy.spatial import cKDTree
        tree = cKDTree(centre)
        probes = (("load point", self.load_point), ("control point", self.control_point),
                  ("centre", centre))
        r = float(radius.max()) * (1 + 1e-9) + tol
        for label, pts in probes:
            cand = tree.query_ball_point(pts, r)
            for i, js in enumerate(cand):
                js = np.array([j for j in js if j != i], dtype=int)
                if not js.size:
                    continue
                hit = self._local_inside(pts[i:i + 1], js, tol)[0]
                if hit.any():
                    j = int(js[np.argmax(hit)])
                    names = self.surface_names
                    sa = names[self.surface[i]] if self.surface[i] < len(names) else "?"
                    sb = names[self.surface[j]] if self.surface[j] < len(names) else "?"
                    what = "surfaces overlap" if self.surface[i] != self.surface[j] else \
                        "boxes are duplicated or overlap"
                    raise ValueError(f"corners: {what}: the {label} of box {i} ('{sa}') lies "
                                     f"inside box {j} ('{sb}'); every box must cover its own "
                                     "area")


def mesh_surfaces(surfaces) -> BoxMesh:
    """Mesh one or several :class:`TrapezoidSurface` into a :class:`BoxMesh`.

    Strips are numbered globally, surface by surface, root to tip.
    """
    if isinstance(surfaces, TrapezoidSurface):
        surfaces = [surfaces]
    surfaces = list(surfaces)
    if not surfaces:
        raise ValueError("surfaces must contain at least one TrapezoidSurface")
    corners, strip = box_corners(surfaces)
    surf = np.concatenate([np.full(s.n_span * s.n_chord, i) for i, s in enumerate(surfaces)])
    names = tuple(s.name for s in surfaces)
    if len(set(names)) != len(names):
        names = tuple(f"{s.name}[{i}]" for i, s in enumerate(surfaces))
    return BoxMesh(corners, strip, surf, names)


def box_corners(surfaces) -> tuple[np.ndarray, np.ndarray]:
    """(corners (n, 4, 3), strip (n,)) of the boxes :func:`mesh_surfaces` would make, without
    building the :class:`BoxMesh` (no overlap check: a cheap input to size estimates such as
    :func:`asekit.aero.supersonic.grid_size`).

    Examples
    --------
    >>> c, s = box_corners([TrapezoidSurface((0, 0), 0.3, (0.2, 0.2), 0.1, 4, 2)])
    >>> c.shape, s.tolist()
    ((8, 4, 3), [0, 0, 0, 0, 1, 1, 1, 1])
    """
    if isinstance(surfaces, TrapezoidSurface):
        surfaces = [surfaces]
    corners, strip = [], []
    strip0 = 0
    for i, s in enumerate(surfaces):
        if not isinstance(s, TrapezoidSurface):
            raise ValueError(f"surfaces[{i}] must be a TrapezoidSurface, got {type(s).__name__}")
        corners.append(s.boxes())
        strip.append(strip0 + np.repeat(np.arange(s.n_span), s.n_chord))
        strip0 += s.n_span
    return np.concatenate(corners), np.concatenate(strip)


@dataclass(frozen=True)
class MeshRuleReport:
    """Mesh-rule numbers of a box mesh (thesis Section 3.2.1).

    ``bpw`` (n_strips,) boxes per wavelength of each strip, U_min / (f_max dx_max) with dx_max the
    longest box chord of the strip (Eq. 3.5); ``boxes_per_chord`` (n_strips,);
    ``aspect_ratio`` (n_boxes,); the limits used; ``offending_*`` strip/box indices.
    """

    bpw: np.ndarray
    boxes_per_chord: np.ndarray
    aspect_ratio: np.ndarray
    bpw_min: float
    boxes_per_chord_min: int
    ar_max: float

    @property
    def offending_bpw_strips(self) -> np.ndarray:
        return np.flatnonzero(self.bpw < self.bpw_min)

    @property
    def offending_chord_strips(self) -> np.ndarray:
        return np.flatnonzero(self.boxes_per_chord < self.boxes_per_chord_min)

    @property
    def offending_ar_boxes(self) -> np.ndarray:
        return np.flatnonzero(self.aspect_ratio >= self.ar_max)

    @property
    def ok(self) -> bool:
        return not (self.offending_bpw_strips.size or self.offending_chord_strips.size
                    or self.offending_ar_boxes.size)


def check_mesh_rules(mesh: BoxMesh, u_min: float, f_max: float, bpw_min: float = BPW_MIN,
                     boxes_per_chord_min: int = 4, ar_max: float = 3.0,
                     warn: bool = True) -> MeshRuleReport:
    """Evaluate the DLM mesh rules of thesis Section 3.2.1 and warn about violations.

    Parameters
    ----------
    mesh : the boxes.
    u_min : lowest airspeed of the analysis (m/s, > 0).
    f_max : highest frequency of interest (Hz, > 0).
    bpw_min, boxes_per_chord_min, ar_max : the limits (15, 4, 3 in the thesis).
    warn : emit a :class:`MeshRuleWarning` naming the offending strips / boxes.
    """
    for nm, v in (("u_min", u_min), ("f_max", f_max)):
        positive(nm, v)
    strips = np.unique(mesh.strip)
    n_strips = int(strips.max()) + 1
    dx_max = np.zeros(n_strips)
    count = np.zeros(n_strips, int)
    np.maximum.at(dx_max, mesh.strip, mesh.chord)
    np.add.at(count, mesh.strip, 1)
    with np.errstate(divide="ignore"):
        bpw = np.where(dx_max > 0, u_min / (f_max * np.where(dx_max > 0, dx_max, 1.0)), np.inf)
    rep = MeshRuleReport(bpw, count, mesh.aspect_ratio, float(bpw_min), int(boxes_per_chord_min),
                         float(ar_max))
    if warn:
        if rep.offending_bpw_strips.size:
            s = rep.offending_bpw_strips
            warnings.warn(f"boxes per wavelength below {bpw_min:g} on strips {s.tolist()} "
                          f"(minimum {bpw[s].min():.3g}); refine chordwise (a case file: more "
                          "chordwise boxes in aero.boxes, a lower aero.f_max or a higher "
                          "aero.u_min)", MeshRuleWarning,
                          stacklevel=2)
        if rep.offending_chord_strips.size:
            s = rep.offending_chord_strips
            warnings.warn(f"fewer than {boxes_per_chord_min} boxes per chord on strips {s.tolist()}",
                          MeshRuleWarning, stacklevel=2)
        if rep.offending_ar_boxes.size:
            b = rep.offending_ar_boxes
            s = np.unique(mesh.strip[b])
            warnings.warn(f"box aspect ratio >= {ar_max:g} on strips {s.tolist()} "
                          f"({b.size} boxes, maximum {rep.aspect_ratio.max():.3g})", MeshRuleWarning,
                          stacklevel=2)
    return rep
