"""Resources of a case's aerodynamics, counted before any computation, in case-file terms.

What the pipeline would build is counted from the case's keys alone (no mode, no box mesh, no
matrix): the boxes (``aero.boxes`` or the mesh rules of the method used at each Mach,
:func:`box_counts`), the dense DLM matrix of those boxes (16 n_boxes^2 bytes within
:data:`asekit.aero.boxes.MAX_MATRIX_BYTES`) and, at every Mach the Mach-box method serves,
its cell grid at the largest reduced frequency (:func:`asekit.aero.supersonic.grid_size`).
A case over a limit is refused by the loader (:func:`asekit.case.schema.case_from_dict`) and
again at the pipeline's door (:func:`asekit.case.pipeline.gaf_database`, for cases built in
Python) with one line naming the keys that change the count and the values that fit, found by
bisection (:func:`resource_problem`):

- ``aero.f_max`` and ``aero.u_min``: with ``reduced_frequencies = "auto"`` the largest k is
  2 pi f_max b / u_min and with ``boxes = "auto"`` the box chords follow u_min / f_max, so
  every count depends on their ratio alone; the message gives the largest f_max (the smallest
  u_min) that fits;
- ``aero.reduced_frequencies`` (a list): its largest k that fits;
- ``aero.boxes`` (a list): the chordwise counts that fit (the grid's cells follow the box
  chords, the DLM matrix the box count).

The module imports no other module of :mod:`asekit.case` (the schema imports it), so it works
on the specs' fields; the schema turns a message into a :class:`~asekit.case.schema.CaseError`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

from asekit.aero.boxes import (
    MAX_MATRIX_BYTES,
    TrapezoidSurface,
    box_corners,
    dlm_max_box_chord,
)
from asekit.aero.gaf import default_reduced_frequencies
from asekit.aero.methods import TransonicWarning, max_box_chord, resolve_method
from asekit.aero.supersonic import MAX_CELLS, grid_size
from asekit.util.validate import positive

#: Bisection steps of the fitting values (each halves a log-interval of 1e4: 0.1 % at 14).
_STEPS = 14
#: Smallest scale tried: a fix that needs a key changed 1e4 times is not offered.
_LOWEST = 1e-4


def auto_boxes(planform, u_min: float, f_max: float, n_chord: int | None = None,
               n_span: int | None = None, bpw_min: float = 15.0,
               ar_max: float = 3.0) -> tuple[int, int]:
    """Box counts (n_chord, n_span) of one panel from the DLM mesh rules (thesis Sec. 3.2.1).

    n_chord (unless given): the smallest n_chord >= 4 with boxes per wavelength
    U_min / (f_max dx) > ``bpw_min`` (strictly) on the root strip, dx = root chord / n_chord
    (Eq. 3.5); n_span (unless given): the smallest keeping the tip boxes' aspect ratio
    span / (n_span dx_tip) below 0.9 ``ar_max`` (a 10 % margin), dx_tip = tip chord / n_chord.
    u_min in m/s, f_max in Hz. A case's boxes follow the rule of the method used at each of
    its Mach numbers: :func:`box_counts`.

    Examples
    --------
    >>> from asekit.geometry import Planform
    >>> auto_boxes(Planform((0.0, 0.0), 0.156, (0.078, 0.15), 0.078), 180.0, 1000.0)
    (14, 10)
    """
    u_min, f_max = positive("aero.u_min", u_min), positive("aero.f_max", f_max)
    bpw_min, ar_max = positive("bpw_min", bpw_min), positive("ar_max", ar_max)
    if n_chord is None:
        n_chord = _chord_count(planform.root_chord, dlm_max_box_chord(u_min, f_max, bpw_min))
    if n_span is None:
        dx_tip = planform.tip_chord / n_chord
        n_span = max(1, math.ceil(planform.span / (0.9 * ar_max * dx_tip)))
    return int(n_chord), int(n_span)


def _chord_count(root_chord: float, dx_max: float) -> int:
    """The smallest n >= 4 with root_chord / n < dx_max (strictly: the rules' '>' on BPW)."""
    return max(4, math.floor(root_chord / dx_max) + 1)


def aero_reduced_frequencies(aero) -> tuple[float, ...]:
    """``aero.reduced_frequencies``, or the automatic list up to k_max = 2 pi f_max b / u_min
    (:func:`asekit.aero.gaf.default_reduced_frequencies`, thesis Sec. 3.2.1)."""
    if aero.reduced_frequencies is not None:
        return tuple(float(k) for k in aero.reduced_frequencies)
    k_max = 2 * math.pi * aero.f_max * aero.reference_semichord / aero.u_min
    return tuple(float(k) for k in default_reduced_frequencies(k_max))


def _quiet_method(method: str, mach: float) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        return resolve_method(method, mach)


def box_counts(panels, aero) -> tuple[tuple[int, int], ...]:
    """(n_chord, n_span) per panel: ``aero.boxes``, or automatic. Automatic boxes meet the
    mesh rule of the method used at every one of ``aero.machs``
    (:func:`asekit.aero.methods.max_box_chord`: the DLM's 15 boxes per wavelength U_min /
    f_max, the Mach box's 6 per kernel wavelength 2 pi b (M - 1) / (k_max M), piston theory
    the DLM's): the box chord is the smallest of them, then n_chord >= 4 and the aspect ratio
    as :func:`auto_boxes`. A case whose Machs are all DLM Machs gets :func:`auto_boxes`'s
    counts exactly.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> from asekit.geometry import Planform
    >>> p = NS(planform=Planform((0.0, 0.0), 0.3, (0.2, 0.2), 0.1))
    >>> a = NS(boxes=None, machs=(0.8,), method="auto", reduced_frequencies=None, f_max=400.0,
    ...        u_min=100.0, reference_semichord=0.1)
    >>> box_counts([p], a)                        # the DLM: 0.3 m / (100 / (15 x 400)) + 1
    ((19, 15),)
    >>> a.machs = (0.8, 1.2)                      # + the Mach box at M 1.2: finer boxes
    >>> box_counts([p], a)
    ((44, 33),)
    """
    if aero.boxes is not None:
        return tuple(tuple(b) for b in aero.boxes)
    k_max = aero_reduced_frequencies(aero)[-1]
    dx = min(max_box_chord(aero.method, m, k_max, aero.reference_semichord, aero.u_min,
                           aero.f_max) for m in aero.machs)
    dx_dlm = dlm_max_box_chord(aero.u_min, aero.f_max)
    out = []
    for p in panels:
        nc = None if dx >= dx_dlm else _chord_count(p.planform.root_chord, dx)
        out.append(auto_boxes(p.planform, aero.u_min, aero.f_max, n_chord=nc))
    return tuple(out)


def panel_surfaces(panels, counts) -> list[TrapezoidSurface]:
    """The panels' :class:`~asekit.aero.boxes.TrapezoidSurface` with ``counts`` boxes each,
    named ``"surface"`` (one panel) or ``"panel<i>"``."""
    out = []
    for i, (p, (nc, ns)) in enumerate(zip(panels, counts)):
        pf = p.planform
        out.append(TrapezoidSurface(pf.root_le + (0.0,), pf.root_chord, pf.tip_le + (0.0,),
                                    pf.tip_chord, nc, ns,
                                    name=f"panel{i}" if len(panels) > 1 else "surface"))
    return out


# ---------------------------------------------------------------------------------------------
# the limits
# ---------------------------------------------------------------------------------------------
def _dlm_excess(panels, aero):
    """(counts, n_boxes, bytes) when the dense DLM matrix exceeds MAX_MATRIX_BYTES, else None."""
    counts = box_counts(panels, aero)
    n = sum(nc * ns for nc, ns in counts)
    need = 16.0 * n * n
    return (counts, n, need) if need > MAX_MATRIX_BYTES else None


def _grid_excess(panels, aero):
    """(index, Mach, k_max, GridSize) of the first Mach whose Mach-box grid does not fit,
    else None."""
    machs = [(i, m) for i, m in enumerate(aero.machs)
             if _quiet_method(aero.method, m) == "supersonic"]
    if not machs:
        return None
    corners, strip = box_corners(panel_surfaces(panels, box_counts(panels, aero)))
    k_max = aero_reduced_frequencies(aero)[-1]
    for i, m in machs:
        g = grid_size(corners, strip, m, k_max, aero.reference_semichord,
                      aero.symmetry == "wall")
        if not g.fits:
            return i, m, k_max, g
    return None


def _fits(panels, aero) -> bool:
    return _dlm_excess(panels, aero) is None and _grid_excess(panels, aero) is None


def _largest_fitting(panels, aero, vary, lowest: float = _LOWEST) -> float | None:
    """The largest scale s in [lowest, 1) (to 0.1 %) at which ``vary(aero, s)`` fits, or None
    (bisection in log s; the counts grow with s)."""
    if lowest >= 1.0 or not _fits(panels, vary(aero, lowest)):
        return None
    lo, hi = math.log(lowest), 0.0
    for _ in range(_STEPS):
        mid = 0.5 * (lo + hi)
        if _fits(panels, vary(aero, math.exp(mid))):
            lo = mid
        else:
            hi = mid
    return math.exp(lo)


def _round_down(x: float) -> float:
    """``x`` rounded down to 3 significant digits."""
    e = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.floor(x / e) * e


def _round_up(x: float) -> float:
    e = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.ceil(x / e) * e


def _ratio(aero, s):
    return replace(aero, f_max=aero.f_max * s)


def _k_scaled(aero, s):
    ks = aero.reduced_frequencies
    top = ks[-1] * s
    kept = tuple(k for k in ks if k < top * (1 - 1e-9))
    return replace(aero, reduced_frequencies=kept + (top,))


def _box_scaled(aero, s):
    r = math.sqrt(s)
    return replace(aero, boxes=tuple((max(1, math.floor(nc * r)), max(1, math.floor(ns * r)))
                                     for nc, ns in aero.boxes))


def fixes(panels, aero) -> list[str]:
    """What fits, in case-file terms: the largest ``aero.f_max`` / smallest ``aero.u_min``
    (when k or the boxes are automatic), the largest k of an explicit
    ``aero.reduced_frequencies``, and coarser explicit ``aero.boxes`` (both counts scaled
    alike: the grid's cells follow the box chords and the strip widths, the DLM matrix the
    box count)."""
    out = []
    if aero.reduced_frequencies is None or aero.boxes is None:
        # the automatic k list needs k_max > 0.001 (asekit.aero.gaf.default_reduced_frequencies)
        k_auto = 2 * math.pi * aero.f_max * aero.reference_semichord / aero.u_min
        lowest = max(_LOWEST, 0.0011 / k_auto) if aero.reduced_frequencies is None else _LOWEST
        s = _largest_fitting(panels, aero, _ratio, lowest)
        if s is not None:
            f = _round_down(aero.f_max * s)
            u = _round_up(aero.u_min / s)
            out.append(f"aero.f_max <= {f:g} Hz or aero.u_min >= {u:g} m/s")
    if aero.reduced_frequencies is not None:
        s = _largest_fitting(panels, aero, _k_scaled)
        if s is not None:
            out.append(f"aero.reduced_frequencies up to k = "
                       f"{_round_down(aero.reduced_frequencies[-1] * s):g}")
    if aero.boxes is not None:
        s = _largest_fitting(panels, aero, _box_scaled)
        if s is not None:
            boxes = _box_scaled(aero, s).boxes
            out.append("aero.boxes = [" + ", ".join(f"{{ n_chord = {nc}, n_span = {ns} }}"
                                                    for nc, ns in boxes) + "]")
    return out


def _fix_text(found: list[str]) -> str:
    if not found:
        return ("no value of these keys alone fits: lower aero.machs' supersonic Mach numbers "
                "or the surface's size")
    return " or ".join(found) + " fits"


def _keys(aero) -> str:
    k = ("aero.f_max / aero.u_min (k up to 2 pi f_max b / u_min)"
         if aero.reduced_frequencies is None else "aero.reduced_frequencies")
    b = ("aero.boxes (\"auto\": box chords from aero.f_max / aero.u_min and the mesh rules)"
         if aero.boxes is None else "aero.boxes")
    return f"{k} and {b}"


def resource_problem(panels, aero) -> str | None:
    """One line saying which limit the case's aerodynamics exceed, the keys that change it and
    the values that fit, or None when everything fits: the dense DLM matrix (16 n_boxes^2
    bytes within :data:`asekit.aero.boxes.MAX_MATRIX_BYTES`), then the Mach-box grid at each
    supersonic Mach (:func:`asekit.aero.supersonic.grid_size` within
    :data:`asekit.aero.supersonic.MAX_CELLS` cells on and around the surface, 4 times that in
    its rectangle) at the largest k. Cheap when everything fits (a few ms per supersonic
    Mach); the bisection of the fitting values takes up to a few seconds."""
    dlm = _dlm_excess(panels, aero)
    if dlm is not None:
        counts, n, need = dlm
        fit = math.isqrt(int(MAX_MATRIX_BYTES // 16))
        what = (" ".join(f"{nc} x {ns}" for nc, ns in counts) + f" = {n} boxes"
                + (" from the mesh rules" if aero.boxes is None else ""))
        knob = ("lower aero.f_max, raise aero.u_min or give aero.boxes" if aero.boxes is None
                else "lower aero.boxes")
        return (f"aero.boxes: {what} need a {need / 2 ** 30:.3g} GiB DLM matrix (limit "
                f"{MAX_MATRIX_BYTES / 2 ** 30:.3g} GiB, asekit.aero.boxes.MAX_MATRIX_BYTES): "
                f"at most {fit} boxes fit (e.g. {math.isqrt(fit)} x {math.isqrt(fit)}); {knob}; "
                + _fix_text(fixes(panels, aero)))
    grid = _grid_excess(panels, aero)
    if grid is None:
        return tsd_problem(panels, aero)
    i, m, k_max, g = grid
    where = ("on and around the surface" if g.n_relevant is not None
             else "in the grid's rectangle")
    limit = g.max_cells if g.n_relevant is not None else 4 * g.max_cells
    return (f"aero.machs[{i}] = {m:g}: the Mach-box grid would need {g.cells} cells {where} at "
            f"k up to {k_max:.4g} (at most {limit} fit; the cells follow the shortest kernel "
            f"wavelength 2 pi b (M - 1) / (k M) and the box chords), set by {_keys(aero)}; "
            + _fix_text(fixes(panels, aero)))


# --- issue 29 (tsdcase): the TSD grid ----------------------------------------------------------
def tsd_nodes(panels, aero) -> int:
    """Nodes of the TSD grid of a case with ``aero.method = "tsd"`` (0 otherwise): the grid
    rule of :func:`asekit.aero.tsd3d.tsd_grid_options` on the case's boxes (the most boxes
    per strip of any panel, the strips of all panels) over the panels' planform."""
    if aero.method != "tsd":
        return 0
    from asekit.aero.tsd3d import TsdPlanform, grid_nodes, tsd_grid_options

    counts = box_counts(panels, aero)
    planform = TsdPlanform.from_surfaces(panel_surfaces(panels, counts))
    return grid_nodes(planform, tsd_grid_options(max(nc for nc, _ in counts),
                                                 sum(ns for _, ns in counts)))


def tsd_problem(panels, aero) -> str | None:
    """One line when the TSD grid (:func:`tsd_nodes`) exceeds
    :data:`asekit.aero.tsd3d.MAX_NODES`, naming the keys that set it; else None."""
    from asekit.aero.tsd3d import MAX_NODES

    n = tsd_nodes(panels, aero)
    if n <= MAX_NODES:
        return None
    return (f"aero.boxes: the TSD grid of aero.method = \"tsd\" would have {n} nodes (at most "
            f"{MAX_NODES}, asekit.aero.tsd3d.MAX_NODES: 2 cells per chordwise box, 1 per strip, "
            f"at least 8 x 4, stretched to 6 root chords); set by {_keys(aero)}: give fewer "
            f"aero.boxes (e.g. {{ n_chord = 6, n_span = 6 }}) or lower aero.f_max")


#: Largest p-k work of a case: Mach numbers x flight conditions x speeds of the sweep. About
#: 20 ms a point on the project's shared 2-core machine (the clipped-delta fin, 4 elastic modes:
#: 14 conditions x 111 speeds in 30 s), so about 1.4 h at the limit.
MAX_PK_POINTS = 250_000


def pk_problem(n_machs: int, n_conditions: int, velocities) -> str | None:
    """One line when the flutter sweeps (``n_machs`` x ``n_conditions`` x the speeds of
    ``flight.velocities``) exceed :data:`MAX_PK_POINTS` points, naming the keys and the
    ``flight.velocities.step`` that fits; else None. The p-k roots are continued with step
    control, so a coarser sweep finds the same first flutter
    (:func:`asekit.aeroelastic.flutter.pk_flutter`).

    Examples
    --------
    >>> pk_problem(7, 2, [100.0 + 10 * i for i in range(111)]) is None
    True
    >>> pk_problem(20, 40, [100.0 + 0.1 * i for i in range(9001)])[:60]
    'flight.velocities: 20 Mach numbers x 40 flight conditions x '
    """
    n = len(velocities)
    points = n_machs * n_conditions * n
    if points <= MAX_PK_POINTS:
        return None
    span = float(velocities[-1]) - float(velocities[0])
    per_sweep = MAX_PK_POINTS // (n_machs * n_conditions)
    fit = (f"flight.velocities.step >= {_round_up(span / (per_sweep - 1)):g} m/s fits"
           if per_sweep >= 2 else "fewer aero.machs or flight conditions fit")
    return (f"flight.velocities: {n_machs} Mach numbers x {n_conditions} flight conditions x "
            f"{n} speeds = {points} p-k points (at most {MAX_PK_POINTS}, about "
            f"{MAX_PK_POINTS * 0.02 / 3600:.2g} h at 20 ms a point), set by aero.machs, "
            f"flight.altitudes / flight.densities and flight.velocities; {fit} (the p-k "
            f"continuation's step control finds the same first flutter on a coarser sweep)")


__all__ = ["MAX_CELLS", "MAX_PK_POINTS", "pk_problem", "aero_reduced_frequencies", "auto_boxes", "box_counts", "fixes",
           "panel_surfaces", "resource_problem", "tsd_nodes", "tsd_problem"]
