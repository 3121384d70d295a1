"""Structured quadrilateral meshes of a trapezoidal lifting surface (thesis Section 3.1.1).

The thesis models the fin with 6 chordwise x 7 spanwise QUAD4 elements (42 elements). A mesh
here is ``n_chord x n_span`` bilinear quadrilaterals whose nodes sit at chord fractions
``xi_i`` along spanwise stations ``eta_j`` (both ascending from 0 to 1): node
``j * (n_chord + 1) + i`` is at :meth:`asekit.geometry.Planform.point` ``(xi_i, eta_j)``.
Elements list their four nodes counter-clockwise seen from +z (x downstream, y spanwise).

The stations are equally spaced by default (``xi_i = i / n_chord``, ``eta_j = j / n_span``);
:class:`Stations` gives them explicitly (e.g. Nastran rows at 12.5 % chord) and
:class:`Grading` clusters them toward a chord fraction or span fraction -- toward a support, a
root, an edge -- so that a few hundred elements resolve what uniform refinement needs 10^5 for.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from asekit.geometry import LinearThickness, Planform, Thickness, ThicknessField
from asekit.util.validate import in_range, integer, positive


@dataclass(frozen=True)
class PlateMesh:
    """A quadrilateral plate mesh.

    Attributes
    ----------
    nodes : (n_nodes, 2) node coordinates x, y (m).
    elements : (n_elem, 4) node indices, counter-clockwise seen from +z.
    thickness_root, thickness_tip, y_root, span : the spanwise linear thickness law
        h(y) = h_root + (y - y_root) / span * (h_tip - h_root) (m).
    n_chord, n_span : elements per direction (0 when the mesh is not structured).
    thickness_field : optional h(x, y) (m), e.g. a :class:`~asekit.geometry.ThicknessField`
        with a chordwise profile; when given it replaces the spanwise linear law everywhere
        the element integrates (:meth:`thickness_xy`).
    corner_thickness : optional (n_elem, 4) thickness (m) at each element's four corners,
        interpolated bilinearly inside the element with the shape functions (as Nastran's
        CQUAD4 T1-T4 fields); when given it replaces both laws above in the element matrices.
    """

    nodes: np.ndarray
    elements: np.ndarray
    thickness_root: float
    thickness_tip: float
    y_root: float
    span: float
    n_chord: int = 0
    n_span: int = 0
    thickness_field: object = None
    corner_thickness: np.ndarray | None = None

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.elements.shape[0]

    def thickness_at(self, y: np.ndarray) -> np.ndarray:
        """Plate thickness (m) at spanwise station(s) ``y`` (m), linear in y."""
        eta = (np.asarray(y, float) - self.y_root) / self.span
        return self.thickness_root + eta * (self.thickness_tip - self.thickness_root)

    def thickness_xy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Plate thickness (m) at points (x, y) (m): the thickness field if the mesh has one,
        else the spanwise linear law."""
        if self.thickness_field is None:
            return self.thickness_at(y)
        return self.thickness_field(x, y)

    def element_centroids(self) -> np.ndarray:
        """(n_elem, 2) mean of each element's four node coordinates (m)."""
        return self.nodes[self.elements].mean(axis=1)

    def node_at(self, point, tol: float = 1e-9, name: str = "point") -> int:
        """Index of the node at ``point`` (x, y) within ``tol`` m; ValueError if there is none."""
        p = np.asarray(point, float).reshape(2)
        d = np.hypot(*(self.nodes - p).T)
        i = int(np.argmin(d))
        if d[i] > tol:
            raise ValueError(
                f"{name} ({p[0]:.6g}, {p[1]:.6g}) m is not a node of the mesh (nearest node {i} "
                f"at ({self.nodes[i, 0]:.6g}, {self.nodes[i, 1]:.6g}) m, {d[i]:.3g} m away): "
                f"choose n_chord so that a node falls there (e.g. an even n_chord for a "
                f"mid-chord axis) or use a shaft region of finite radius")
        return i


def _check_count(name: str, value) -> int:
    """Elements per direction: an integer >= 1 (:func:`asekit.util.validate.integer`)."""
    return integer(name, value, low=1)


# ---------------------------------------------------------------------------------------------
# node stations along one direction (chord fraction xi or span fraction eta, both in [0, 1])
# ---------------------------------------------------------------------------------------------
def check_stations(name: str, values) -> np.ndarray:
    """``values`` as a float array if they are node stations: at least 2, finite, strictly
    ascending, from exactly 0 to exactly 1; else ValueError naming ``name``."""
    try:
        s = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a list of numbers from 0 to 1, got {values!r}") from None
    if s.size < 2 or not np.all(np.isfinite(s)):
        raise ValueError(f"{name} must hold at least 2 finite stations from 0 to 1, got "
                         f"{s.tolist()}")
    if s[0] != 0.0 or s[-1] != 1.0:
        raise ValueError(f"{name} must start at 0 and end at 1 (fractions of the chord or "
                         f"span), got {s[0]:g} ... {s[-1]:g}")
    bad = np.flatnonzero(np.diff(s) <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"{name} must be strictly ascending, got {name}[{i}] = {s[i]:g} after "
                         f"{s[i - 1]:g}")
    return s


@dataclass(frozen=True)
class Stations:
    """Explicit node stations ``0 = s_0 < s_1 < ... < s_m = 1`` (fractions of the chord or of
    the span): ``m`` elements, e.g. ``Stations((0, 0.125, 0.5, 0.875, 1))`` for rows at 12.5 %
    chord from the leading and trailing edges.

    :meth:`stations` of ``n = r m`` elements (r = 1, 2, ...) splits each interval into ``r``
    equal ones, so the meshes of a refinement study are nested and keep the given rows.

    Examples
    --------
    >>> Stations((0.0, 0.125, 0.875, 1.0)).stations(6).tolist()
    [0.0, 0.0625, 0.125, 0.5, 0.875, 0.9375, 1.0]
    """

    values: tuple

    def __post_init__(self):
        s = check_stations("stations", self.values)
        object.__setattr__(self, "values", tuple(float(v) for v in s))

    @property
    def n_elements(self) -> int:
        return len(self.values) - 1

    def stations(self, n: int | None = None, name: str = "stations") -> np.ndarray:
        """The ``n + 1`` stations of ``n`` elements (default :attr:`n_elements`; ``n`` must be
        a multiple of it)."""
        m = self.n_elements
        n = m if n is None else int(n)
        if n < m or n % m:
            raise ValueError(f"{name} holds {m + 1} stations ({m} elements): the element count "
                             f"must be a multiple of {m}, got {n}")
        s = np.asarray(self.values)
        r = n // m
        fine = s[:-1, None] + np.diff(s)[:, None] * (np.arange(r) / r)
        return np.append(fine.ravel(), 1.0)


@dataclass(frozen=True)
class _SizeRamp:
    """The element size h(d) / h_0 of :func:`graded_stations` at distance d from the nearest
    clustering point: 1 on the plateau d <= a, 1 + (d - a) / c on the ramp (c = b / (R - 1),
    b the ramp's length), R beyond a + b. :meth:`phi` is Phi(d) = int_0^d h_0 / h (the mesh
    coordinate), :meth:`distance` its inverse; both closed-form."""

    a: float
    b: float
    R: float

    def phi(self, d):
        d = np.asarray(d, float)
        plateau = np.minimum(d, self.a)
        if self.R == 1.0 or self.b == 0.0:
            return plateau + np.maximum(d - self.a, 0.0) / self.R
        c = self.b / (self.R - 1.0)
        ramp = c * np.log1p(np.clip(d - self.a, 0.0, self.b) / c)
        return plateau + ramp + np.maximum(d - self.a - self.b, 0.0) / self.R

    def distance(self, phi):
        phi = np.asarray(phi, float)
        plateau = np.minimum(phi, self.a)
        if self.R == 1.0 or self.b == 0.0:
            return plateau + np.maximum(phi - self.a, 0.0) * self.R
        c = self.b / (self.R - 1.0)
        top = c * np.log(self.R)                         # Phi across the whole ramp
        ramp = c * np.expm1(np.clip(phi - self.a, 0.0, top) / c)
        return plateau + ramp + np.maximum(phi - self.a - top, 0.0) * self.R


def _check_toward(name: str, toward) -> tuple:
    """``toward`` (a fraction or an ascending sequence of them, each in [0, 1]) as a tuple."""
    t = np.atleast_1d(np.asarray(toward, dtype=float)) if not isinstance(toward, str) else None
    if t is None or t.ndim != 1 or t.size < 1:
        raise ValueError(f"{name} must be a fraction in [0, 1] or a list of them, got {toward!r}")
    for k, v in enumerate(t):
        in_range(f"{name}[{k}]" if t.size > 1 else name, v, 0.0, True, 1.0)
    if np.any(np.diff(t) <= 0.0):
        raise ValueError(f"{name} must be strictly ascending, got {t.tolist()}")
    return tuple(float(v) for v in t)


def _segments(points):
    """The pieces of [0, 1] between the ends and the clustering ``points``: (lo, hi,
    clustered at lo, clustered at hi)."""
    knots = sorted({0.0, 1.0, *points})
    return [(lo, hi, lo in points, hi in points) for lo, hi in zip(knots, knots[1:])]


def _segment_phi(ramp: _SizeRamp, lo, hi, at_lo, at_hi) -> float:
    """Phi across one segment: graded from both ends to its middle, or from one end."""
    if at_lo and at_hi:
        return 2.0 * float(ramp.phi(0.5 * (hi - lo)))
    return float(ramp.phi(hi - lo))


def _segment_stations(ramp: _SizeRamp, lo, hi, at_lo, at_hi, k: int) -> np.ndarray:
    """The k + 1 stations of one segment (both ends included), equidistributing Phi."""
    total = _segment_phi(ramp, lo, hi, at_lo, at_hi)
    tau = total * np.arange(k + 1) / k
    if at_lo and at_hi:
        s = np.where(tau <= 0.5 * total, lo + ramp.distance(tau), hi - ramp.distance(total - tau))
    elif at_lo:
        s = lo + ramp.distance(tau)
    else:
        s = hi - ramp.distance(total - tau)
    s[0], s[-1] = lo, hi                                 # exact ends (round-off of Phi^-1)
    return s


def _allocate(n: int, weights) -> np.ndarray:
    """``n`` elements over segments in proportion to ``weights``, at least one each (largest
    remainder)."""
    w = np.asarray(weights, float)
    raw = n * w / w.sum()
    k = np.maximum(np.floor(raw).astype(int), 1)
    while k.sum() > n:
        k[np.argmax(np.where(k > 1, k - raw, -np.inf))] -= 1
    while k.sum() < n:
        k[np.argmax(raw - k)] += 1
    return k


def graded_stations(n: int, toward, ratio: float, width: float = 0.0, ramp=None,
                    name: str = "grading") -> np.ndarray:
    """``n + 1`` stations in [0, 1] clustered toward the fraction(s) ``toward``: a geometric
    progression of element sizes away from each.

    With d the distance to the nearest point of ``toward``, the element size is the size
    field (Gmsh's "Threshold" field: SizeMin within DistMin, a linear ramp to SizeMax at
    DistMax)

        h(d) = h_0                                  for d <= a          (the plateau, ``width``)
        h(d) = h_0 (1 + (ratio - 1) (d - a) / b)    for a < d <= a + b  (the ramp, ``ramp``)
        h(d) = ratio h_0                            beyond,

    and the stations equidistribute the density h_0 / h (de Boor's equidistribution
    principle: every element holds the same integral of it; C. de Boor, "Good approximation by
    splines with variable knots II", Lecture Notes in Math. 363, 1974). The integral, on the
    ramp Phi(d) = a + c ln(1 + (d - a) / c) with c = b / (ratio - 1), and its inverse are
    closed-form, so the stations are exact. Sampled so, a linear size ramp makes the element
    sizes a geometric progression exactly (common ratio exp(dPhi / c), dPhi the mesh
    coordinate per element: Gmsh's "Progression" of a transfinite line; element size
    proportional to the distance from a singular point, the geometric mesh of Babuska & Guo's
    h-p method). At a fixed grading the meshes of a refinement study are one fixed mapping of a
    uniform mesh: doubling ``n`` halves every element, and the order of convergence is the
    uniform mesh's with a smaller error constant.

    Every point of ``toward`` is a node; the pieces between the ends and the points get
    elements in proportion to their mesh coordinate (at least one each), a piece between two
    points being graded from both ends to its middle.

    Parameters
    ----------
    n : elements, an integer >= the number of pieces (1 + the interior points of ``toward``).
    toward : the fraction (in [0, 1]) or strictly ascending fractions the nodes cluster toward.
    ratio : largest / smallest element size, in [1, 1e6] (1: equal elements on each piece,
        exactly ``linspace(0, 1, n + 1)`` when the pieces' ends are multiples of 1 / n).
    width : half-width a (fraction, in [0, 1)) of the plateau of finest elements around each
        point (e.g. a support's radius over the chord), 0 for none.
    ramp : length b (fraction, in (0, 1]) over which the size grows from h_0 to ``ratio`` h_0;
        None (default): to the farthest station from the points, so that the largest element
        is about ``ratio`` times the smallest (ratio^((n - 1) / n) one-sided, without a
        plateau).
    name : the argument's name in error messages (e.g. a case-file key path).

    Returns
    -------
    (n + 1,) strictly ascending stations, 0 first and 1 last.

    Examples
    --------
    >>> s = graded_stations(4, 0.0, 8.0)           # toward the root: finest first
    >>> float(s[0]), float(s[-1]), bool(s[1] < 0.25 < s[-1] - s[-2])
    (0.0, 1.0, True)
    >>> h = np.diff(s); bool(np.allclose(h[1:] / h[:-1], 8.0 ** 0.25))   # geometric
    True
    >>> graded_stations(4, 0.5, 1.0).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    >>> graded_stations(8, [0.25, 0.75], 1.0).tolist()   # every point is a node
    [0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0]
    """
    n = _check_count(f"{name} element count", n)
    points = _check_toward(f"{name}.toward", toward)
    R = in_range(f"{name}.ratio", ratio, 1.0, True, 1e6)
    a = in_range(f"{name}.width", width, 0.0, True, 1.0, False)
    segs = _segments(points)
    if n < len(segs):
        raise ValueError(f"{name}: clustering toward {list(points)} splits [0, 1] into "
                         f"{len(segs)} pieces and needs at least {len(segs)} elements, got {n}")
    far = max((0.5 if (p and q) else 1.0) * (hi - lo) for lo, hi, p, q in segs)
    b = max(far - a, 0.0) if ramp is None else in_range(f"{name}.ramp", ramp, 0.0, False, 1.0)
    size = _SizeRamp(a, b, R if b > 0.0 else 1.0)
    k = _allocate(n, [_segment_phi(size, *sg) for sg in segs])
    parts = [_segment_stations(size, *sg, int(m)) for sg, m in zip(segs, k)]
    return np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])


@dataclass(frozen=True)
class Grading:
    """Node stations clustered toward the fraction(s) ``toward`` (of the chord or of the span)
    with the largest element about ``ratio`` times the smallest, a plateau of finest
    elements of half-width ``width`` around each point and the sizes growing over ``ramp``
    (:func:`graded_stations`).

    For a shaft-supported fin: chordwise ``Grading(toward=x_a / c_root)`` (the shaft's chord
    fraction at the root; the graded chord fraction is a line from root to tip) and spanwise
    ``Grading(toward=0)`` (the root): the tensor-product mesh is finest at the shaft. For a
    rigid shaft region of radius r, clustering toward its edges resolves the edge, where the
    support's stiffness is decided: chordwise ``toward = [(x_a - r) / c_root, (x_a + r) /
    c_root]``, spanwise ``toward = r / span``.

    Examples
    --------
    >>> Grading(0.0, 1.0).stations(4).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    >>> Grading([0.4, 0.6], 20.0).toward
    (0.4, 0.6)
    """

    toward: tuple
    ratio: float
    width: float = 0.0
    ramp: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "toward", _check_toward("grading.toward", self.toward))
        graded_stations(2 * len(self.toward) + 1, self.toward, self.ratio, self.width,
                        self.ramp)                                   # checks the fields
        for k in ("ratio", "width"):
            object.__setattr__(self, k, float(getattr(self, k)))
        if self.ramp is not None:
            object.__setattr__(self, "ramp", float(self.ramp))

    def stations(self, n: int, name: str = "grading") -> np.ndarray:
        """The ``n + 1`` stations of ``n`` elements."""
        return graded_stations(n, self.toward, self.ratio, self.width, self.ramp, name)


def station_array(spacing, n: int, name: str = "stations") -> np.ndarray:
    """The ``n + 1`` node stations (fractions in [0, 1]) of ``n`` elements along one
    direction: equal (``spacing`` None), :class:`Stations`, :class:`Grading`, or a plain
    sequence of ``n + 1`` stations; ``name`` names the argument in errors."""
    n = _check_count(name, n)
    if spacing is None:
        return np.linspace(0.0, 1.0, n + 1)
    if isinstance(spacing, (Stations, Grading)):
        return spacing.stations(n, name=name)
    s = check_stations(name, spacing)
    if s.size != n + 1:
        raise ValueError(f"{name} must hold n + 1 = {n + 1} stations for {n} elements, got "
                         f"{s.size}")
    return s


def structured_mesh(planform: Planform, thickness: LinearThickness, n_chord: int,
                    n_span: int, chord_spacing=None, span_spacing=None) -> PlateMesh:
    """Mesh a trapezoidal planform with ``n_chord x n_span`` quadrilaterals.

    Parameters
    ----------
    planform : the trapezoid (root/tip leading edges and chords, m).
    thickness : spanwise linear thickness law (m).
    n_chord, n_span : elements chordwise and spanwise, integers >= 1.
    chord_spacing, span_spacing : the node stations (chord fractions xi, span fractions eta):
        None for equal spacing, a :class:`Stations`, a :class:`Grading` or a sequence of
        ``n + 1`` stations (:func:`station_array`).

    Returns
    -------
    PlateMesh with (n_chord + 1) * (n_span + 1) nodes and n_chord * n_span elements.
    """
    n_chord = _check_count("n_chord", n_chord)
    n_span = _check_count("n_span", n_span)
    xi = station_array(chord_spacing, n_chord, "chord_spacing")
    eta = station_array(span_spacing, n_span, "span_spacing")
    XI, ETA = np.meshgrid(xi, eta)                 # (n_span+1, n_chord+1), row j = station j
    nodes = planform.point(XI.ravel(), ETA.ravel())
    i, j = np.meshgrid(np.arange(n_chord), np.arange(n_span))
    n0 = (j * (n_chord + 1) + i).ravel()
    elements = np.stack([n0, n0 + 1, n0 + n_chord + 2, n0 + n_chord + 1], axis=1)
    field = (None if not thickness.is_table and thickness.profile.is_flat
             else ThicknessField((planform,), thickness))
    return PlateMesh(nodes=nodes, elements=elements.astype(np.int64),
                     thickness_root=thickness.root, thickness_tip=thickness.tip,
                     y_root=planform.root_le[1], span=planform.span,
                     n_chord=n_chord, n_span=n_span, thickness_field=field)


def panels_mesh(panels, thickness: Thickness, n_chord: int, n_spans, chord_spacing=None,
                span_spacings=None) -> PlateMesh:
    """Mesh one or more trapezoidal panels joined spanwise (a cranked planform).

    Parameters
    ----------
    panels : sequence of :class:`~asekit.geometry.Planform`, root to tip; panel ``i + 1``'s root
        chord must coincide with panel ``i``'s tip chord (same leading edge and chord).
    thickness : the spanwise x chordwise law over the whole span (first root to last tip).
    n_chord : elements chordwise, the same on every panel (a conforming mesh).
    n_spans : elements spanwise per panel.
    chord_spacing : the chord fractions of the nodes, the same on every panel; span_spacings :
        per panel, the span fractions of its nodes (None: all equal spacing); each as
        :func:`station_array` reads it.

    Returns
    -------
    PlateMesh whose nodes on each panel junction are shared, with a
    :class:`~asekit.geometry.ThicknessField` over all panels.
    """
    panels = tuple(panels)
    n_spans = [int(_check_count(f"panel[{i}].n_span", n)) for i, n in enumerate(n_spans)]
    if len(panels) < 1 or len(n_spans) != len(panels):
        raise ValueError("panels and n_spans must be non-empty and of equal length")
    n_chord = _check_count("n_chord", n_chord)
    for i in range(1, len(panels)):
        a, b = panels[i - 1], panels[i]
        if (not np.allclose(a.tip_le, b.root_le, atol=1e-9 * max(a.span, 1e-3))
                or not np.isclose(a.tip_chord, b.root_chord, rtol=1e-9)):
            raise ValueError(f"panel[{i}] root (leading edge {b.root_le}, chord {b.root_chord}) "
                             f"must coincide with panel[{i - 1}] tip (leading edge {a.tip_le}, "
                             f"chord {a.tip_chord})")
    xi = station_array(chord_spacing, n_chord, "panel[0].chord_spacing")
    if span_spacings is None:
        span_spacings = (None,) * len(panels)
    if len(span_spacings) != len(panels):
        raise ValueError(f"span_spacings must hold one spacing per panel ({len(panels)}), got "
                         f"{len(span_spacings)}")
    rows = []
    for i, (p, ns) in enumerate(zip(panels, n_spans)):
        eta = station_array(span_spacings[i], ns, f"panel[{i}].span_spacing")[(1 if i else 0):]
        XI, ETA = np.meshgrid(xi, eta)
        rows.append(p.point(XI.ravel(), ETA.ravel()))
    nodes = np.concatenate(rows)
    n_stations = sum(n_spans)
    i, j = np.meshgrid(np.arange(n_chord), np.arange(n_stations))
    n0 = (j * (n_chord + 1) + i).ravel()
    elements = np.stack([n0, n0 + 1, n0 + n_chord + 2, n0 + n_chord + 1], axis=1)
    y0, y1 = panels[0].root_le[1], panels[-1].tip_le[1]
    return PlateMesh(nodes=nodes, elements=elements.astype(np.int64),
                     thickness_root=thickness.root, thickness_tip=thickness.tip,
                     y_root=y0, span=y1 - y0, n_chord=n_chord, n_span=n_stations,
                     thickness_field=None if (not thickness.is_table and thickness.profile.is_flat
                                             and len(panels) == 1)
                     else ThicknessField(panels, thickness))


def rectangular_mesh(a: float, b: float, thickness: float, n_x: int, n_y: int) -> PlateMesh:
    """A uniform ``n_x x n_y`` mesh of the rectangle [0, a] x [0, b] with constant thickness
    (validation plates). Lengths in m."""
    for name, v in (("a", a), ("b", b), ("thickness", thickness)):
        positive(name, v)
    planform = Planform((0.0, 0.0), a, (0.0, b), a)
    return structured_mesh(planform, LinearThickness(thickness, thickness), n_x, n_y)


# ---------------------------------------------------------------------------------------------
# boundary-fitted circular regions (issue 23): a rigid shaft region as an inscribed polygon
# ---------------------------------------------------------------------------------------------
def _cut_edge_nodes(mesh: PlateMesh, d: np.ndarray) -> np.ndarray:
    """Nodes to move onto the curve: of every element edge whose end points lie on both sides
    of it (signed distances ``d`` of opposite sign), the end nearer to it."""
    e = mesh.elements
    edges = np.concatenate([e[:, [0, 1]], e[:, [1, 2]], e[:, [2, 3]], e[:, [3, 0]]])
    a, b = np.unique(np.sort(edges, axis=1), axis=0).T
    cut = d[a] * d[b] < 0.0
    a, b = a[cut], b[cut]
    return np.unique(np.where(np.abs(d[a]) <= np.abs(d[b]), a, b))


def _inverted_elements(nodes: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Elements with a corner whose two edges turn clockwise (the bilinear map's Jacobian
    determinant at that corner is <= 0: inverted or degenerate)."""
    xy = nodes[elements]                                        # (n_elem, 4, 2)
    nxt, prv = np.roll(xy, -1, axis=1) - xy, np.roll(xy, 1, axis=1) - xy
    cross = nxt[..., 0] * prv[..., 1] - nxt[..., 1] * prv[..., 0]
    scale = np.einsum("ijk,ijk->ij", nxt, nxt).max(axis=1)
    return np.flatnonzero((cross <= 1e-12 * scale[:, None]).any(axis=1))


def snap_to_circle(mesh: PlateMesh, centre, radius: float) -> PlateMesh:
    """``mesh`` with the circle ``|x - centre| = radius`` fitted by its nodes: of every element
    edge the circle cuts, the end node nearer to it is moved radially onto it.

    A region given as "every node within ``radius``" (a rigid shaft region,
    :func:`asekit.structure.assembly.shaft_region_nodes`) is, on a mesh not fitted to it, a
    staircase whose effective radius jumps by up to an element size with the mesh (an O(h)
    error that, for the fin's shaft, moves the flutter speed about 17 m/s per mm of radius).
    After the snap the region's boundary is a polygon inscribed in the circle, its vertices
    nodes and no element edge cut by the circle, so its area error is O(h^2) (the chord-sagitta
    h^2 / (8 r) per edge). This is the vertex "warping" of isosurface stuffing (F. Labelle and
    J. R. Shewchuk, "Isosurface stuffing: fast tetrahedral meshes with good dihedral angles",
    ACM Trans. Graph. 26(3), 2007, Sec. 3: a lattice vertex near the boundary is moved onto
    it, so that the boundary is made of mesh vertices), restricted here to the vertices of cut
    edges: moving the nearer end moves a node at most half its edge, and radially, so a node on
    a straight line through ``centre`` (a root edge through the shaft axis) stays on it.

    Parameters
    ----------
    mesh : PlateMesh
        The mesh (nodes in m); its connectivity is kept.
    centre : (2,) array_like
        The circle's centre (x, y), m.
    radius : float
        The circle's radius, m, > 0.

    Returns
    -------
    PlateMesh
        The mesh with the moved nodes (every other field unchanged).

    Raises
    ------
    ValueError
        ``radius`` not positive or ``centre`` not two finite numbers.

    Warns
    -----
    UserWarning
        When a node is left where it is because its move would invert an element (or it is
        the centre): a mesh too coarse, or too anisotropic, near the circle. The region is then
        a staircase at those nodes (still the same limit under refinement, at order 1 there).

    Examples
    --------
    >>> m = snap_to_circle(rectangular_mesh(1.0, 1.0, 0.01, 8, 8), (0.5, 0.0), 0.3)
    >>> d = np.hypot(m.nodes[:, 0] - 0.5, m.nodes[:, 1])
    >>> int(np.sum(np.isclose(d, 0.3)))           # nodes on the circle (none before the snap)
    7
    """
    positive("radius", radius)
    c = np.asarray(centre, float)
    if c.shape != (2,) or not np.all(np.isfinite(c)):
        raise ValueError(f"centre must be two finite numbers (x, y) in m, got {centre!r}")
    v = mesh.nodes - c
    dist = np.hypot(v[:, 0], v[:, 1])
    move = _cut_edge_nodes(mesh, dist - radius)
    held = move[dist[move] <= 1e-12 * radius]            # a node at the centre cannot move
    move = np.setdiff1d(move, held)
    nodes = np.array(mesh.nodes, float, copy=True)
    nodes[move] = c + v[move] * (radius / dist[move])[:, None]
    for _ in range(mesh.n_nodes):                        # undo the moves that invert elements
        bad = _inverted_elements(nodes, mesh.elements)
        back = np.intersect1d(np.unique(mesh.elements[bad]), move)
        if back.size == 0:
            break
        nodes[back] = mesh.nodes[back]
        held = np.union1d(held, back)
        move = np.setdiff1d(move, back)
    if held.size:
        warnings.warn(f"fitting the circle of radius {radius:g} m: {held.size} of "
                      f"{held.size + move.size} nodes of cut edges not moved (moving them would "
                      f"invert an element); the region is a staircase there: refine the mesh or "
                      f"grade it toward the circle", stacklevel=2)
    return replace(mesh, nodes=nodes)
