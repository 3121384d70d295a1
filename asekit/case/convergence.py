"""Discretisation error of a case's flutter results: the case run on two or three meshes
(structure and aerodynamic boxes refined together) and Richardson-extrapolated, with a
grid-convergence-index error bar (issue 23, "every flutter result with an error bar").

The case's own meshes are the finest; the coarser ones divide every element and box count by
``ratio`` (rounded, at least 2), the structural nodes keeping the case's spacing (a graded case
stays graded), so a study costs little more than one run: with ``ratio`` 2 a coarser mesh has
a quarter of the elements and of the boxes.

Method (P. J. Roache, "Perspective: a method for uniform reporting of grid refinement
studies", J. Fluids Eng. 116, 405-413, 1994; I. B. Celik, U. Ghia, P. J. Roache, C. J.
Freitas, H. Coleman, P. E. Raad, "Procedure for estimation and reporting of uncertainty due to
discretization in CFD applications", J. Fluids Eng. 130, 078001, 2008), for a result phi
(flutter speed or frequency) on meshes 1 (finest), 2, 3 with representative cell sizes
h_1 < h_2 < h_3:

* cell size h = (N_e N_b)^(-1/4) with N_e structural elements and N_b boxes (the geometric
  mean of the two 2-D cell sizes, Celik et al. Eq. 1 with each mesh's cell count), refinement
  ratios r_21 = h_2 / h_1, r_32 = h_3 / h_2;
* observed order p (three meshes, Celik et al. Eqs. 3a-3c, solved by fixed-point iteration):
  p = |ln|e_32 / e_21| + q(p)| / ln r_21, q(p) = ln((r_21^p - s) / (r_32^p - s)),
  s = sign(e_32 / e_21), e_21 = phi_2 - phi_1, e_32 = phi_3 - phi_2; used when the three
  values converge monotonically (s > 0) and p lies in [:data:`P_MIN`, :data:`P_MAX`], else
  the assumed ``order`` (two meshes always use it);
* extrapolated value phi_ext = (r_21^p phi_1 - phi_2) / (r_21^p - 1) (Celik et al. Eq. 4a);
* error bar: Roache's grid convergence index of the finest mesh in absolute terms,
  GCI = F_s |phi_1 - phi_2| / (r_21^p - 1) = F_s |phi_ext - phi_1|, with the safety factor
  F_s = 1.25 when the order was observed on three meshes and 3 when it was assumed (Roache
  1994). It bounds the discretisation error of the finest mesh's value and is reported as the
  error bar of the extrapolated value (a conservative one: the extrapolation removes the
  leading error term). When three meshes oscillate or stagnate (no observed order) the error
  bar is at least the spread of the three values (Celik et al. 2008 treat oscillatory
  convergence by the range of the solutions), so a small e_21 between two meshes that happen
  to agree cannot pass for a converged result.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, replace

from asekit.case import pipeline
from asekit.case.resources import box_counts
from asekit.case.schema import Case, CaseError, ConvergenceSpec
from asekit.structure.mesh import Stations
from asekit.util.conventions import mode_number

#: The range of observed orders accepted as asymptotic (outside it the assumed order is used).
P_MIN, P_MAX = 0.5, 4.0
#: Roache's (1994) safety factors: order observed on three meshes / assumed.
FS_OBSERVED, FS_ASSUMED = 1.25, 3.0
#: The smallest element or box count along a direction of the coarsest mesh.
MIN_COUNT = 2


@dataclass(frozen=True)
class Extrapolation:
    """Richardson extrapolation of one result over meshes finest first.

    ``values`` (finest first, the result's unit), ``h`` the representative cell sizes (finest
    first, any consistent unit), ``order`` the order used, ``observed`` whether it was observed
    on three meshes (else assumed), ``value`` the extrapolated result and ``error`` its error
    bar (the GCI, same unit)."""

    values: tuple[float, ...]
    h: tuple[float, ...]
    order: float
    observed: bool
    value: float
    error: float


def observed_order(phi, h, max_iter: int = 100, tol: float = 1e-10) -> float | None:
    """The observed order of convergence of three results ``phi`` (finest first) on meshes of
    cell sizes ``h`` (finest first), Celik et al. (2008) Eqs. 3a-3c; None when the results do
    not converge monotonically (oscillating, stagnating or diverging) or the iteration fails.

    Examples
    --------
    Values 1 + h^2 on h = 1, 2, 4 have order 2:

    >>> round(observed_order([2.0, 5.0, 17.0], [1.0, 2.0, 4.0]), 6)
    2.0
    """
    f1, f2, f3 = (float(v) for v in phi)
    r21, r32 = h[1] / h[0], h[2] / h[1]
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0.0 or e32 == 0.0 or e32 / e21 <= 0.0:
        return None                       # s < 0 (oscillatory) or a stagnating result
    ratio = abs(e32 / e21)
    if ratio <= 1.0:
        return None                       # |e32| <= |e21|: not converging
    p = abs(math.log(ratio)) / math.log(r21)
    for _ in range(max_iter):
        q = math.log((r21 ** p - 1.0) / (r32 ** p - 1.0)) if p > 0 else 0.0
        p_new = abs(math.log(ratio) + q) / math.log(r21)
        if abs(p_new - p) < tol:
            return p_new
        p = p_new
    return None


def extrapolate(phi, h, order: float = 1.0) -> Extrapolation:
    """Richardson extrapolation of results ``phi`` on meshes of cell sizes ``h`` (both finest
    first, two or three meshes) with the observed order when three meshes give one in
    [:data:`P_MIN`, :data:`P_MAX`], else the assumed ``order``; the error bar is Roache's GCI
    (module docstring).

    Examples
    --------
    Two meshes at the assumed first order: phi_ext = 2 phi_1 - phi_2, GCI = 3 |phi_ext - phi_1|:

    >>> e = extrapolate([250.0, 245.0], [1.0, 2.0])
    >>> e.value, e.error, e.observed
    (255.0, 15.0, False)
    """
    phi = tuple(float(v) for v in phi)
    h = tuple(float(v) for v in h)
    if len(phi) not in (2, 3) or len(h) != len(phi):
        raise ValueError(f"extrapolate needs 2 or 3 results and as many cell sizes, got "
                         f"{len(phi)} and {len(h)}")
    if not all(b > a > 0 for a, b in zip(h, h[1:])):
        raise ValueError(f"cell sizes h must be positive and grow from the finest, got {h}")
    if not order > 0:
        raise ValueError(f"order must be > 0, got {order!r}")
    p = observed_order(phi, h) if len(phi) == 3 else None
    observed = p is not None and P_MIN <= p <= P_MAX
    p = p if observed else float(order)
    rp = (h[1] / h[0]) ** p
    value = (rp * phi[0] - phi[1]) / (rp - 1.0)
    fs = FS_OBSERVED if observed else FS_ASSUMED
    error = fs * abs(value - phi[0])
    if len(phi) == 3 and not observed:       # oscillating or stagnating: at least the spread
        error = max(error, max(phi) - min(phi))
    return Extrapolation(phi, h, p, observed, value, error)


# ---------------------------------------------------------------------------------------------
# the meshes of a study
# ---------------------------------------------------------------------------------------------
def _coarse(n: int, factor: float, what: str, spec: ConvergenceSpec) -> int:
    m = int(round(n / factor))
    if m < MIN_COUNT:
        raise CaseError(f"convergence.meshes = {spec.meshes} with convergence.ratio = "
                        f"{spec.ratio:g}: the coarsest mesh would have {what} = {m} (< "
                        f"{MIN_COUNT}); refine the case's mesh, use fewer meshes or a smaller "
                        f"ratio")
    return m


def _box_counts(case: Case) -> tuple[tuple[int, int], ...]:
    return box_counts(case.panels, case.aero)


def check_study(case: Case, spec: ConvergenceSpec | None = None) -> ConvergenceSpec:
    """The study's settings (``spec``, default the case's ``[convergence]``), checked against
    the case before any computation: a case-file surface (not an imported deck) whose coarsest
    mesh keeps at least :data:`MIN_COUNT` elements and boxes per direction, with equal or
    graded node spacing (explicit stations cannot be coarsened), each coarser structure
    supported as the case says (e.g. a single-node shaft needs a node on its axis)."""
    spec = case.convergence if spec is None else spec
    if case.structure is not None or not case.panels:
        raise CaseError(f"{case.name}: convergence needs a case-file surface ([[panel]]), not "
                        f"an imported structure")
    if case.aero is None:
        raise CaseError(f"{case.name}: convergence needs [aero]")
    for i, p in enumerate(case.panels):
        for d in ("chord", "span"):
            sp = getattr(p, f"{d}_spacing")
            if isinstance(sp, Stations):
                raise CaseError(f"panel[{i}].{d}_stations: explicit stations cannot be "
                                f"coarsened for convergence; use {d}_grading or equal spacing")
    for i, c in enumerate(study_meshes(case, spec)[1:], start=2):
        try:                              # each coarser structure supported (cheap: coarser)
            pipeline.supported_system(c)
        except ValueError as exc:
            p = c.panels[0]
            raise CaseError(f"convergence.ratio = {spec.ratio:g}: mesh {i} of the study "
                            f"(panel[0] {p.n_chord} x {p.n_span} elements) fails: "
                            f"{' '.join(str(exc).split())}") from None
    return spec


def study_meshes(case: Case, spec: ConvergenceSpec) -> list[Case]:
    """The cases of the study, finest (``case`` itself) first: level i divides every panel's
    element counts and box counts by ``spec.ratio ** i`` (rounded)."""
    out = [case]
    boxes = _box_counts(case)
    for level in range(1, spec.meshes):
        f = spec.ratio ** level
        panels = tuple(replace(p, n_chord=_coarse(p.n_chord, f, f"panel[{i}].n_chord", spec),
                               n_span=_coarse(p.n_span, f, f"panel[{i}].n_span", spec))
                       for i, p in enumerate(case.panels))
        bx = tuple((_coarse(nc, f, f"aero.boxes[{i}].n_chord", spec),
                    _coarse(ns, f, f"aero.boxes[{i}].n_span", spec))
                   for i, (nc, ns) in enumerate(boxes))
        out.append(replace(case, panels=panels, aero=replace(case.aero, boxes=bx)))
    return out


def cell_size(case: Case) -> float:
    """The representative cell size h = (N_e N_b)^(-1/4) of a case's meshes (N_e structural
    elements, N_b boxes; dimensionless, only ratios matter)."""
    n_e = sum(p.n_chord * p.n_span for p in case.panels)
    n_b = sum(nc * ns for nc, ns in _box_counts(case))
    return float(n_e * n_b) ** -0.25


# ---------------------------------------------------------------------------------------------
# the study
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlutterConvergence:
    """Flutter speed and frequency of one (Mach, flight condition) over the study's meshes:
    ``speed`` and ``frequency`` (:class:`Extrapolation`, m/s and Hz) or None when a mesh has no
    flutter crossing there (``note`` says which)."""

    mach: float
    altitude: float | None
    density: float
    speed: Extrapolation | None
    frequency: Extrapolation | None
    note: str = ""


@dataclass(frozen=True)
class ConvergenceStudy:
    """A case's convergence study: the ``meshes`` (per level, finest first: structural
    elements per panel, boxes per panel), cell sizes ``h``, the per-mesh flutter analyses
    ``analyses`` (finest first) and the extrapolated ``rows`` (one per Mach and condition, in
    the order of :func:`asekit.case.pipeline.flutter`'s results)."""

    spec: ConvergenceSpec
    meshes: tuple
    h: tuple[float, ...]
    analyses: tuple
    rows: tuple[FlutterConvergence, ...]
    seconds: float = 0.0


def _speed_of(r):
    f = None if r.unstable_at_start else r.flutter
    return None if f is None else (float(f.speed), float(f.frequency_hz))


def _row(results, h, spec: ConvergenceSpec) -> FlutterConvergence:
    r0 = results[0]
    pts = [_speed_of(r) for r in results]
    base = dict(mach=r0.mach, altitude=r0.condition.altitude, density=r0.condition.density)
    missing = [i for i, p in enumerate(pts) if p is None]
    if missing:
        return FlutterConvergence(**base, speed=None, frequency=None,
                                  note="no flutter crossing in the sweep on mesh "
                                       + ", ".join(str(i + 1) for i in missing)
                                       + " (1 = the case's)")
    modes = [mode_number(r.flutter.mode, r.flutter.n_rigid) for r in results]
    note = "" if len(set(modes)) == 1 else \
        "flutter on mode " + ", ".join(map(str, modes)) + " (finest first)"
    return FlutterConvergence(**base,
                              speed=extrapolate([p[0] for p in pts], h, spec.order),
                              frequency=extrapolate([p[1] for p in pts], h, spec.order),
                              note=note)


def convergence_study(case: Case, spec: ConvergenceSpec | None = None, finest=None,
                      progress: bool = False) -> ConvergenceStudy:
    """Run ``case`` on the study's meshes (:func:`study_meshes`; the case's own meshes are the
    finest, its flutter analysis ``finest`` reused when given) and extrapolate the flutter
    speed and frequency of every Mach and flight condition (:func:`extrapolate`).

    Parameters
    ----------
    case : the case (a case-file surface); its mesh is the finest of the study.
    spec : the settings (default ``case.convergence``: meshes 2 or 3, ratio, assumed order).
    finest : :func:`asekit.case.pipeline.flutter` of ``case`` if already computed.
    progress : show the GAF databases' progress bars.

    Returns
    -------
    ConvergenceStudy

    Examples
    --------
    AGARD 445.6 (Yates 1987: 172 m/s measured, FSI 0.4459) on its 20 x 20 elements / 16 x 16
    boxes, 13 x 13 / 11 x 11 and 9 x 9 / 7 x 7 (the default three meshes, ratio 1.5): the
    flutter speed converges with an observed order near 1.7 to 182.8 +- 1.0 m/s:

    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> s = convergence_study(load_case(CASES_DIR / "agard445_6.toml"))
    >>> (row,) = s.rows
    >>> round(row.speed.value), round(row.speed.error), row.speed.observed
    (183, 1, True)
    """
    import time

    t0 = time.perf_counter()
    spec = check_study(case, spec)
    cases = study_meshes(case, spec)
    h = tuple(cell_size(c) for c in cases)
    analyses = [finest if finest is not None else pipeline.flutter(case, progress=progress)]
    for c in cases[1:]:
        analyses.append(pipeline.flutter(c, progress=progress))
    rows = tuple(_row([a.results[j] for a in analyses], h, spec)
                 for j in range(len(analyses[0].results)))
    meshes = tuple((tuple((p.n_chord, p.n_span) for p in c.panels), _box_counts(c))
                   for c in cases)
    return ConvergenceStudy(spec, meshes, h, tuple(analyses), rows, time.perf_counter() - t0)


# ---------------------------------------------------------------------------------------------
# output: the JSON fields and the table of ``analyse --convergence``
# ---------------------------------------------------------------------------------------------
#: Units of the keys the study adds to the ``analyse`` JSON (merged into its ``units`` block).
UNITS = {"speed_extrapolated_ms": "m/s", "speed_error_ms": "m/s (grid convergence index)",
         "frequency_extrapolated_hz": "Hz", "frequency_error_hz": "Hz (grid convergence index)",
         "speeds_ms": "m/s", "order": "- (order of convergence in the cell size h)",
         "cell_size": "- (h = (elements x boxes)^(-1/4), relative)", "ratio": "-",
         "meshes": "count", "assumed_order": "- (order used when not observed)",
         "order_observed": "bool (order observed on three meshes, else assumed)",
         "structure": "elements (chordwise, spanwise) per panel",
         "aero_boxes": "boxes (chordwise, spanwise) per panel"}


def _fields(e: Extrapolation | None, name: str, unit: str) -> dict:
    return {f"{name}_extrapolated_{unit}": None if e is None else float(e.value),
            f"{name}_error_{unit}": None if e is None else float(e.error)}


def summary_fields(study: ConvergenceStudy) -> dict:
    """The study as JSON: ``{"flutter": [per-row fields], "convergence": {...}}``; each
    flutter row gains ``speed_extrapolated_ms``, ``speed_error_ms``,
    ``frequency_extrapolated_hz``, ``frequency_error_hz`` (None when a mesh has no flutter)."""
    rows, detail = [], []
    for r in study.rows:
        rows.append({**_fields(r.speed, "speed", "ms"), **_fields(r.frequency, "frequency", "hz")})
        detail.append({"mach": r.mach, "altitude_m": r.altitude, "density": r.density,
                       "speeds_ms": None if r.speed is None else list(r.speed.values),
                       "frequencies_hz": None if r.frequency is None
                       else list(r.frequency.values),
                       "order": None if r.speed is None else r.speed.order,
                       "order_observed": None if r.speed is None else r.speed.observed,
                       "note": r.note})
    s = study.spec
    return {"flutter": rows,
            "convergence": {"meshes": s.meshes, "ratio": s.ratio, "assumed_order": s.order,
                            "structure": [[list(m) for m in st] for st, _ in study.meshes],
                            "aero_boxes": [[list(m) for m in bx] for _, bx in study.meshes],
                            "cell_size": list(study.h), "rows": detail,
                            "seconds": float(study.seconds)}}


def add_to_summary(summary: dict, study: ConvergenceStudy) -> dict:
    """The ``analyse`` JSON ``summary`` with the study's fields added (a new dict): every
    flutter row gains the four extrapolated keys, the document a ``convergence`` block and the
    keys' units, ``seconds`` the study's wall-clock time (the coarser meshes only when the
    finest analysis was reused)."""
    extra = summary_fields(study)
    if len(extra["flutter"]) != len(summary["flutter"]):
        raise ValueError("the convergence study and the summary have different flutter rows")
    out = dict(summary)
    out["flutter"] = [{**row, **f} for row, f in zip(summary["flutter"], extra["flutter"])]
    out["convergence"] = extra["convergence"]
    out["units"] = {**summary.get("units", {}), **UNITS}
    out["seconds"] = {**summary.get("seconds", {}), "convergence": float(study.seconds)}
    return out


def _pm(e: Extrapolation | None, fmt: str) -> str:
    return "-" if e is None else f"{fmt.format(e.value)} +- {fmt.format(e.error)}"


def format_study(study: ConvergenceStudy) -> str:
    """The study as a plain-text table (fits 100 columns): per Mach and condition the speeds
    on the meshes, the extrapolated speed and frequency with their error bars and the order."""
    s = study.spec
    mesh_txt = "; ".join(f"{i + 1}: FE " + " ".join(f"{a}x{b}" for a, b in st) + ", boxes "
                         + " ".join(f"{a}x{b}" for a, b in bx)
                         for i, (st, bx) in enumerate(study.meshes))
    lines = textwrap.wrap(f"flutter convergence ({s.meshes} meshes, ratio {s.ratio:g}; GCI "
                          f"error bars, Roache 1994): {mesh_txt}", 100, subsequent_indent="  ")
    lines += [f"{'Mach':>6} {'altitude m':>10} {'U_f per mesh m/s':>24} {'U_f extrap. m/s':>17} "
             f"{'f_f extrap. Hz':>17} {'order':>9}"]
    for r in study.rows:
        alt = "-" if r.altitude is None else f"{r.altitude:.0f}"
        per = "-" if r.speed is None else " ".join(f"{v:.2f}" for v in r.speed.values)
        order = "-" if r.speed is None else \
            f"{r.speed.order:.2f} {'obs' if r.speed.observed else 'set'}"
        ln = (f"{r.mach:>6.3g} {alt:>10} {per:>24} {_pm(r.speed, '{:.2f}'):>17} "
              f"{_pm(r.frequency, '{:.2f}'):>17} {order:>9}")
        lines.append(ln)
        if r.note:
            lines.append(f"{'':>6} note: {r.note}")
    return "\n".join(lines)
