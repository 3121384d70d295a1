"""Variants of a :class:`~asekit.case.schema.Case`: each is ``dataclasses.replace`` of the case
(frozen, so the variant is a new case and the pipeline memoises it separately), with the
checks the case file would make. Used by the thesis reproduction for the fin's FN1 model, its
refined meshes, the distributed shaft and the symmetry wall, and by anyone studying one case
around another.
"""

from __future__ import annotations

from dataclasses import replace

from asekit.case.resources import auto_boxes
from asekit.case.schema import Case, CaseError
from asekit.structure.mesh import Grading, Stations, check_stations, station_array


def _one_panel(case: Case, what: str):
    if len(case.panels) != 1:
        raise CaseError(f"{what} needs a one-panel case, got {len(case.panels)} panels")
    return case.panels[0]


def _count(name: str, v) -> int:
    if isinstance(v, bool) or int(v) != v or not 1 <= v <= 2000:
        raise CaseError(f"{name} must be an integer in [1, 2000], got {v!r}")
    return int(v)


#: "Keep the case's spacing" (the default of :func:`with_mesh`; None means equal spacing).
KEEP = "keep"


def _spacing(name: str, spacing, n: int):
    """``spacing`` as the case holds it (None, :class:`Stations` or :class:`Grading`; a plain
    list of stations becomes a :class:`Stations`), checked against ``n`` elements."""
    try:
        if spacing is not None and not isinstance(spacing, (Stations, Grading)):
            spacing = Stations(tuple(check_stations(name, spacing)))
        station_array(spacing, n, name)
    except ValueError as exc:
        raise CaseError(str(exc)) from None
    return spacing


def with_mesh(case: Case, n_chord: int | None = None, n_span: int | None = None,
              chord_spacing=KEEP, span_spacing=KEEP) -> Case:
    """The one-panel ``case`` on an ``n_chord x n_span`` structural mesh (``panel[0].n_chord``,
    ``panel[0].n_span``; None keeps the case's), its nodes at ``chord_spacing`` /
    ``span_spacing`` (``panel[0].chord_stations`` or ``chord_grading``, ...): None for equal
    spacing, a :class:`~asekit.structure.mesh.Grading`, a
    :class:`~asekit.structure.mesh.Stations` or a list of stations; :data:`KEEP` (default)
    keeps the case's, so a graded case refines on its own grading (explicit stations refine
    by splitting each interval: the count must be a multiple of theirs).

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.structure.mesh import Grading
    >>> from asekit.util.paths import FIN_FILE
    >>> p = with_mesh(load_case(FIN_FILE), 12, 14).panels[0]
    >>> p.n_chord, p.n_span
    (12, 14)
    >>> g = with_mesh(load_case(FIN_FILE), 24, 16, Grading(0.5, 8.0), Grading(0.0, 8.0))
    >>> g.panels[0].span_spacing
    Grading(toward=(0.0,), ratio=8.0, width=0.0, ramp=None)
    """
    p = _one_panel(case, "with_mesh")
    nc = p.n_chord if n_chord is None else _count("panel[0].n_chord", n_chord)
    ns = p.n_span if n_span is None else _count("panel[0].n_span", n_span)
    cs = p.chord_spacing if isinstance(chord_spacing, str) and chord_spacing == KEEP \
        else chord_spacing
    ss = p.span_spacing if isinstance(span_spacing, str) and span_spacing == KEEP \
        else span_spacing
    cs = _spacing("panel[0].chord_spacing", cs, nc)
    ss = _spacing("panel[0].span_spacing", ss, ns)
    return replace(case, panels=(replace(p, n_chord=nc, n_span=ns, chord_spacing=cs,
                                         span_spacing=ss),))


def with_boxes(case: Case, n_chord: int | None = None, n_span: int | None = None) -> Case:
    """The one-panel ``case`` with ``aero.boxes = [(n_chord, n_span)]``; a count left None
    follows the mesh rules (:func:`asekit.case.resources.auto_boxes`, the spanwise count from
    the given chordwise one); both None gives the automatic mesh (``aero.boxes = "auto"``)."""
    p = _one_panel(case, "with_boxes")
    if n_chord is None and n_span is None:
        return replace(case, aero=replace(case.aero, boxes=None))
    a = case.aero
    nc = None if n_chord is None else _count("aero.boxes[0].n_chord", n_chord)
    ns = None if n_span is None else _count("aero.boxes[0].n_span", n_span)
    return replace(case, aero=replace(a, boxes=(auto_boxes(p.planform, a.u_min, a.f_max,
                                                           nc, ns),)))


def with_shaft(case: Case, **changes) -> Case:
    """The shaft-supported ``case`` with support fields changed, e.g. ``model="FN1"`` (spring to
    ground, no rigid mode: ``modes.keep_rigid`` turns False) or ``radius=0.005`` (a rigid shaft
    region of 5 mm instead of the single node; ``radius=None`` the single node) or
    ``region_fit="snap"`` (the mesh's nodes fitted to that region's circle)."""
    s = case.support
    if s.kind != "shaft":
        raise CaseError(f"with_shaft needs support.kind = \"shaft\", got {s.kind!r}")
    unknown = sorted(set(changes) - {"axis_point", "torsional_stiffness", "bending_stiffness",
                                     "model", "radius", "fictitious_inertia_factor",
                                     "region_fit"})
    if unknown:
        raise CaseError(f"support.{unknown[0]} is not a shaft key")
    if "region_fit" in changes:                 # a kind's own key: held in spec.options
        case = _with_region_fit(case, changes.pop("region_fit"))
        s = case.support
    if changes.get("model", s.model) not in ("FN1", "FN2"):
        raise CaseError(f"support.model must be 'FN1' or 'FN2', got {changes['model']!r}")
    r = changes.get("radius", s.radius)
    if r is not None and not 0.0 < r <= 1e3:
        raise CaseError(f"support.region must be \"single_node\" or a shaft radius in (0, 1000] m,"
                        f" got {r!r}")
    s = replace(s, **changes)
    modes = case.modes if s.model == "FN2" else replace(case.modes, keep_rigid=False)
    if case.actuator is not None and not modes.keep_rigid:
        case = replace(case, actuator=None)      # the actuator drives the rigid mode
    return replace(case, support=s, modes=modes)


def _with_region_fit(case: Case, fit: str) -> Case:
    """``case`` with ``support.region_fit`` set (:data:`asekit.structure.supports.REGION_FITS`;
    the default "nodes" is not stored, as the case loader does)."""
    from asekit.structure.supports import REGION_FITS
    if fit not in REGION_FITS:
        raise CaseError(f"support.region_fit must be one of {', '.join(map(repr, REGION_FITS))}, "
                        f"got {fit!r}")
    opts = tuple((k, v) for k, v in case.support.options if k != "region_fit")
    if fit != "nodes":
        opts = tuple(sorted(opts + (("region_fit", fit),)))
    return replace(case, support=replace(case.support, options=opts))


def with_modes(case: Case, f_max: float | None = None, count: int | None = None) -> Case:
    """The ``case`` keeping its elastic modes below ``f_max`` (Hz; ``modes.f_max``) or its first
    ``count`` (``modes.count``); None keeps the case's."""
    m = case.modes
    if f_max is not None and not 0.0 < f_max <= 1e7:
        raise CaseError(f"modes.f_max must be in (0, 1e7] Hz, got {f_max!r}")
    return replace(case, modes=replace(m, f_max=m.f_max if f_max is None else float(f_max),
                                       count=m.count if count is None else
                                       _count("modes.count", count)))


def with_symmetry_wall(case: Case, wall: bool = True) -> Case:
    """The ``case`` with a reflection plane at the root (``aero.symmetry = "wall"``, the surface
    on a body) or without (``"none"``)."""
    if wall and abs(case.panels[0].planform.root_le[1]) > 1e-12:
        raise CaseError(f"aero.symmetry = \"wall\" puts the reflection plane at y = 0, but the "
                        f"root is at y = {case.panels[0].planform.root_le[1]:g} m")
    return replace(case, aero=replace(case.aero, symmetry="wall" if wall else "none"))


#: The band of a rigid shaft region of radius r that :func:`with_shaft_grading` resolves: node
#: lines cluster on 0.7 r <= d <= r from the axis (a plateau of finest elements centred at
#: 0.85 r, half-width 0.15 r), where the circle's normal is within 45 deg of the grid lines.
SHAFT_BAND = (0.85, 0.15)


def with_shaft_grading(case: Case, n_chord: int, n_span: int, ratio: float = 25.0,
                       ramp_chord: float = 0.15, ramp_span: float = 0.2) -> Case:
    """The shaft-supported one-panel ``case`` on an ``n_chord x n_span`` mesh graded toward its
    shaft (:class:`~asekit.structure.mesh.Grading`, ``panel[0].chord_grading`` and
    ``span_grading``).

    A rigid shaft region of radius r (``support.region`` a radius) decides the fin's support
    stiffness at its edge (the flutter speed moves about 18 m/s per mm of radius on the
    reference fin), so the node lines cluster on the band 0.7 r <= d <= r around the axis
    (:data:`SHAFT_BAND`): chordwise at the axis's root chord fractions (x_a -+ 0.85 r) / c_root
    with a plateau of half-width 0.15 r / c_root, spanwise at the root and at 0.85 r / span
    (half-width 0.15 r / span). The single-node shaft clusters toward the axis's chord fraction
    and the root. Beyond the plateau the element size grows linearly (a geometric progression)
    to ``ratio`` times the finest over ``ramp_chord`` of the chord / ``ramp_span`` of the span
    (fractions), then stays: :func:`asekit.structure.mesh.graded_stations`. The band's node
    lines still cut the circle (a staircase region); ``with_shaft(case, region_fit="snap")``
    also fits the circle by the nodes (:func:`asekit.structure.mesh.snap_to_circle`).

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> c = with_shaft_grading(with_shaft(load_case(FIN_FILE), radius=0.005), 64, 48)
    >>> [round(t, 4) for t in c.panels[0].chord_spacing.toward]
    [0.4728, 0.5272]
    """
    p = _one_panel(case, "with_shaft_grading")
    s = case.support
    if s.kind != "shaft":
        raise CaseError(f"with_shaft_grading needs support.kind = \"shaft\", got {s.kind!r}")
    pf = p.planform
    xi = (s.axis_point[0] - pf.root_le[0]) / pf.root_chord
    if s.radius is None:
        chord = Grading((xi,), ratio, 0.0, ramp_chord)
        span = Grading((0.0,), ratio, 0.0, ramp_span)
    else:
        f, w = SHAFT_BAND
        rc, rs = s.radius / pf.root_chord, s.radius / pf.span
        if not (0.0 < xi - rc and xi + rc < 1.0 and rs < 1.0):
            raise CaseError(f"support.region: the shaft radius {s.radius:g} m does not fit in "
                            f"the root chord and span of panel[0]")
        chord = Grading((xi - f * rc, xi + f * rc), ratio, w * rc, ramp_chord)
        span = Grading((0.0, f * rs), ratio, w * rs, ramp_span)
    return with_mesh(case, n_chord, n_span, chord, span)
