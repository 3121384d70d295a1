"""The figures of the ``analyse`` HTML report (:mod:`asekit.case.report`), each with the alt
text that says what it shows.

- the flutter and divergence speeds against Mach, one colour per flight condition, with the
  flight speed U = M a(h), the envelope, the match points and the transonic gap left open
  (speeds are never joined across M 1: :func:`asekit.case.envelope.across_sonic`);
- per analysed Mach, V-g and V-f of every flight condition (small multiples: one column per
  condition, colours per mode through :func:`asekit.util.plotting.plot_vg`) and the root locus
  (one colour per condition), the flutter points starred;
- the planform (thin grey FE mesh over coloured aerodynamic box outlines) and every kept mode
  shape with one colour bar and the node lines (w = 0);
- with an actuator, the forward paths FWTF 1-3 and the power-limited step responses;
- with ``[control_surface.actuator]``, the actuator-on-flap loop (AEM1, AEM2): the surface's
  power-limited step response and the open-loop Bode plot with its margins marked.

Conventions (docs/conventions.md): SI inside, Hz and deg only on the axes; elastic modes named
from 1 and the rigid mode "rigid pitch" (:func:`asekit.util.conventions.mode_label`); V-g damping
g = 2 Re p / |Im p|, > 0 unstable. The style is :mod:`asekit.util.plotting`'s; every figure uses
matplotlib's constrained layout and is saved with ``bbox_inches="tight"``, so titles and
legends stay inside the image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aero.methods import DLM_MACH_MAX, SUPERSONIC_MACH_MIN
from asekit.ase import loop as ase_mod
from asekit.case import pipeline as P
from asekit.case.envelope import across_sonic, flutter_points, start_kind
from asekit.util.conventions import mode_label
from asekit.util.plotting import new_figure, plot_vg

#: Report sections, in page order.
SECTIONS = ("Flutter and divergence against Mach", "V-g, V-f and root locus at each Mach",
            "Structure: planform and mode shapes", "Aeroservoelastic loop", "Gust loads",
            "Control surfaces")

#: The g axis of the V-g panels (-): wide enough for the crossings, narrow enough to read them.
G_LIMITS = (-0.5, 0.3)


@dataclass(frozen=True)
class ReportFigure:
    """One figure of the report: the matplotlib ``figure``, its ``alt`` text (what it shows,
    with the numbers a reader looks for) and the report ``section`` it belongs to."""

    figure: object
    alt: str
    section: str


def condition_label(c) -> str:
    """A flight condition as the report names it: ``"2500 m"`` or ``"rho 0.4278 kg/m^3"``.

    Examples
    --------
    >>> from asekit.case.pipeline import FlightCondition
    >>> condition_label(FlightCondition(2500.0, 0.957, 334.9)), condition_label(
    ...     FlightCondition(None, 0.4278, None))
    ('2500 m', 'rho 0.4278 kg/m^3')
    """
    if c.altitude is not None:
        return f"{c.altitude:g} m"
    return f"rho {c.density:.4g} kg/m^3"


def flutter_phrase(r, velocities) -> str:
    """What the p-k sweep of one condition found, in words: ``"mode 2 crosses g = 0 at
    218.1 m/s (140.9 Hz)"``, unstable at the first point, or no flutter up to the last one."""
    if r.unstable_at_start:
        return (f"{start_kind(r)} at or below {velocities[0]:g} m/s, the first point "
                f"({mode_label(r.start_mode, r.pk.n_rigid)})")
    f = r.flutter
    if f is None:
        return f"no flutter up to {velocities[-1]:g} m/s"
    return f"{f.mode_name} crosses g = 0 at {f.speed:.1f} m/s ({f.frequency_hz:.4g} Hz)"


def _conditions(a):
    """The flight conditions in analysis order (each once)."""
    out = []
    for r in a.flutter.results:
        if r.condition not in out:
            out.append(r.condition)
    return out


def _machs(a):
    return sorted({r.mach for r in a.flutter.results})


# ---------------------------------------------------------------------------------------------
# flutter and divergence against Mach
# ---------------------------------------------------------------------------------------------
def _broken_line(points):
    """(Mach, speed) arrays of consecutive points with NaN between two Machs on either side of
    M 1, so that matplotlib never draws a line across the transonic gap."""
    xs, ys = [], []
    for i, (m, u) in enumerate(points):
        if i and across_sonic(points[i - 1][0], m):
            xs.append(np.nan)
            ys.append(np.nan)
        xs.append(m)
        ys.append(u)
    return np.array(xs, float), np.array(ys, float)


def _shows_gap(machs, env) -> bool:
    lo, hi = min(machs + env), max(machs + env)
    return lo < SUPERSONIC_MACH_MIN and hi > DLM_MACH_MAX and (lo < 1.0 < hi or any(
        DLM_MACH_MAX < m < SUPERSONIC_MACH_MIN for m in machs))


def _envelope_covers(case, c) -> bool:
    f = case.flight
    if f.envelope_mach is None or c.speed_of_sound is None:
        return False
    h = f.envelope_altitude
    return h is None or c.altitude is None or h[0] <= c.altitude <= h[1]


def _plot_condition_speeds(ax, a, c, color):
    """Flutter (solid, bounds as triangles) and divergence (dashed) speeds of one condition."""
    U = a.case.flight.velocities
    pts = flutter_points([r for r in a.flutter.results if r.condition == c], U)
    x, y = _broken_line([(m, u if kind == "value" else np.nan) for m, u, kind in pts])
    ax.plot(x, y, "-o", color=color, ms=5)
    for kind, marker in (("upper", "v"), ("lower", "^")):
        b = [(m, u) for m, u, k in pts if k == kind]
        if b:
            ax.plot(*np.array(b).T, marker, color=color, ms=8, ls="none")
    div = sorted((d["mach"], np.nan if d["speed_ms"] is None else d["speed_ms"])
                 for d in a.flutter.divergence
                 if d["altitude_m"] == c.altitude and d["density"] == c.density)
    if div:
        ax.plot(*_broken_line(div), "--x", color=color, ms=6, lw=1.2)


def _plot_flight_speed(ax, a, c, color, mach_range):
    """The flight speed U = M a(h) (dotted) and, inside the envelope, its thick band."""
    if c.speed_of_sound is None:
        return
    m = np.linspace(*mach_range, 50)
    ax.plot(m, m * c.speed_of_sound, ":", color=color, lw=1.0)
    if _envelope_covers(a.case, c):
        e = np.array(a.case.flight.envelope_mach, float)
        ax.plot(e, e * c.speed_of_sound, "-", color=color, lw=6, alpha=0.3,
                solid_capstyle="butt")


def _legend_right(ax, **kw):
    """A legend to the right of ``ax``, outside it (inside the image: constrained layout)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kw)


def _mach_legend(ax, conds, has):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    h = [Line2D([], [], color=f"C{i}", lw=3, label=condition_label(c))
         for i, c in enumerate(conds)]
    k = "0.3"
    style = [("flutter speed U_f", Line2D([], [], color=k, ls="-", marker="o", ms=5)),
             ("divergence speed", Line2D([], [], color=k, ls="--", marker="x")),
             ("flutter at or below (unstable at the first point)",
              Line2D([], [], color=k, ls="none", marker="v", ms=8)),
             ("no flutter up to (the last point)",
              Line2D([], [], color=k, ls="none", marker="^", ms=8)),
             ("flight speed U = M a", Line2D([], [], color=k, ls=":")),
             ("envelope", Line2D([], [], color=k, lw=6, alpha=0.3)),
             ("match point (U_f = M a)", Line2D([], [], color=k, ls="none", marker="o", ms=10,
                                                mfc="none", mec="k", mew=2)),
             ("transonic gap", Patch(color="0.85"))]
    gap = f"transonic gap M {DLM_MACH_MAX:g}-{SUPERSONIC_MACH_MIN:g} (never interpolated)"
    h.append(Line2D([], [], ls="none", label=" "))
    for name, handle in style:
        if has.get(name, True):
            handle.set_label(gap if name == "transonic gap" else name)
            h.append(handle)
    _legend_right(ax, handles=h, fontsize=8)


def fig_flutter_mach(a) -> ReportFigure:
    """Flutter and divergence speed (m/s) against Mach for every flight condition, with the
    flight speed M a, the envelope, the match points and the transonic gap."""
    conds, machs = _conditions(a), _machs(a)
    env = list(a.case.flight.envelope_mach or ())
    lo, hi = min(machs + env), max(machs + env)
    pad = max(0.05, 0.05 * (hi - lo))
    fig, ax = new_figure(f"{a.case.name}: flutter and divergence speed against Mach",
                         figsize=(9.0, 5.2), layout="constrained")
    gap = _shows_gap(machs, env)
    if gap:
        ax.axvspan(DLM_MACH_MAX, SUPERSONIC_MACH_MIN, color="0.85", zorder=0)
        ax.text(0.5 * (DLM_MACH_MAX + SUPERSONIC_MACH_MIN), 0.02, "transonic gap",
                transform=ax.get_xaxis_transform(), ha="center", fontsize=8, rotation=90)
    for i, c in enumerate(conds):
        _plot_condition_speeds(ax, a, c, f"C{i}")
        _plot_flight_speed(ax, a, c, f"C{i}", (lo - pad, hi + pad))
    if len(machs) == 1:                                # one Mach: the speeds written out
        for r in a.flutter.results:
            if r.flutter is not None and not r.unstable_at_start:
                ax.annotate(f"{r.flutter.speed:.1f} m/s", (r.mach, r.flutter.speed),
                            textcoords="offset points", xytext=(6, 4), fontsize=8)
    matched = []
    for m in a.flutter.match_points:
        if m["matched_mach"] is not None:
            i = next(j for j, c in enumerate(conds) if c.altitude == m["altitude_m"])
            ax.plot(m["matched_mach"], m["matched_speed_ms"], "o", ms=10, mfc="none", mec="k",
                    mew=2, zorder=5)
            ax.plot(m["matched_mach"], m["matched_speed_ms"], "o", ms=5, color=f"C{i}", zorder=6)
            matched.append(f"{condition_label(conds[i])} M {m['matched_mach']:.3f} "
                           f"({m['matched_speed_ms']:.1f} m/s)")
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("Mach number M (-)")
    ax.set_ylabel("speed (m/s)")
    has = {"flight speed U = M a": any(c.speed_of_sound for c in conds),
           "envelope": any(_envelope_covers(a.case, c) for c in conds),
           "match point (U_f = M a)": bool(matched), "transonic gap": gap,
           "divergence speed": any(d["speed_ms"] is not None for d in a.flutter.divergence),
           "flutter at or below (unstable at the first point)":
               any(r.unstable_at_start for r in a.flutter.results),
           "no flutter up to (the last point)":
               any(r.flutter is None and not r.unstable_at_start for r in a.flutter.results)}
    _mach_legend(ax, conds, has)
    alt = ("Flutter speed (solid)" + (" and divergence speed (dashed)" if has[
        "divergence speed"] else "") + f" against Mach {', '.join(f'{m:g}' for m in machs)} at "
        + ", ".join(map(condition_label, conds)))
    if has["flight speed U = M a"]:
        alt += ", with the flight speed M a (dotted)"
    if has["envelope"]:
        alt += f" and the envelope M {env[0]:g}-{env[1]:g} (thick)"
    if not has["divergence speed"]:
        alt += "; no static divergence"
    low = min((r for r in a.flutter.results if r.flutter is not None
               and not r.unstable_at_start), key=lambda r: r.flutter.speed, default=None)
    if low is not None:
        alt += (f"; lowest flutter speed {low.flutter.speed:.1f} m/s at M {low.mach:g}, "
                f"{condition_label(low.condition)}")
    alt += ("; match points: " + "; ".join(matched)) if matched else "; no match point"
    across = [m for m in a.flutter.match_points if m.get("match_across_sonic")]
    if across:
        alt += "; U_f = M a inside the transonic gap (not interpolated) at " + ", ".join(
            f"{m['altitude_m']:g} m (M {m['match_across_sonic'][0]:g}-"
            f"{m['match_across_sonic'][1]:g})" for m in across)
    if gap:
        alt += "; the transonic gap is left open"
    return ReportFigure(fig, alt, SECTIONS[0])


# ---------------------------------------------------------------------------------------------
# V-g / V-f and root locus per Mach
# ---------------------------------------------------------------------------------------------
def _grid(n: int, max_cols: int = 3):
    """(columns, rows) of ``n`` panels, at most ``max_cols`` wide, rows filled evenly (4 -> 2 x 2).

    >>> _grid(1), _grid(3), _grid(4), _grid(5), _grid(7)
    ((1, 1), (3, 1), (2, 2), (3, 2), (3, 3))
    """
    rows = math.ceil(n / max_cols)
    return math.ceil(n / rows), rows


def _vg_panel(ax_g, ax_f, r, velocities):
    pk = r.pk
    plot_vg(ax_g, ax_f, pk.velocities, pk.p, pk.mode_labels, g_limits=None)
    f = r.flutter
    if f is not None and not r.unstable_at_start:
        ax_g.plot(f.speed, 0.0, "r*", ms=12, label="flutter point")
        ax_f.plot(f.speed, f.frequency_hz, "r*", ms=12)
        head = f"flutter {f.speed:.1f} m/s, {f.frequency_hz:.4g} Hz ({f.mode_name})"
    elif r.unstable_at_start:
        head = f"unstable at the first point ({velocities[0]:g} m/s)"
    else:
        head = f"no flutter up to {velocities[-1]:g} m/s"
    ax_g.set_title(f"{condition_label(r.condition)}\n{head}", fontsize=9)
    ax_g.set_ylim(*G_LIMITS)


def fig_vg_mach(a, mach: float, results=None) -> ReportFigure:
    """V-g (top) and V-f (bottom) of every flight condition at ``mach``: one column per
    condition, colours per mode (:func:`asekit.util.plotting.plot_vg`), flutter points starred.
    ``results``: the conditions to draw (default: every one analysed at ``mach``)."""
    rs = [r for r in a.flutter.results if r.mach == mach] if results is None else list(results)
    U = a.case.flight.velocities
    ncols, npairs = _grid(len(rs))
    fig, axes = new_figure(f"{a.case.name}: V-g and V-f at M {mach:g}", nrows=2 * npairs,
                           ncols=ncols, figsize=(3.8 * ncols + 0.8, 5.0 * npairs + 1.0),
                           sharex=True, sharey="row", layout="constrained")
    axes = np.asarray(axes, dtype=object).reshape(2 * npairs, ncols)
    for i, r in enumerate(rs):
        _vg_panel(axes[2 * (i // ncols), i % ncols], axes[2 * (i // ncols) + 1, i % ncols], r, U)
    for i in range(len(rs), npairs * ncols):           # empty slots of the last row
        axes[-2, i % ncols].set_visible(False)
        axes[-1, i % ncols].set_visible(False)
    for col in range(ncols):
        last = (len(rs) - 1 - col) // ncols             # the column's last pair
        axes[2 * last + 1, col].xaxis.set_tick_params(labelbottom=True)
        axes[2 * last + 1, col].set_xlabel("airspeed U (m/s)")
        for row in range(2 * npairs):
            if col:
                axes[row, col].set_ylabel("")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 7))
    for row in range(0, 2 * npairs, 2):                # the g label is long: a taller row
        axes[row, 0].yaxis.label.set_fontsize(9)
    alt = (f"V-g and V-f at M {mach:g}: " + "; ".join(
        f"at {condition_label(r.condition)} {flutter_phrase(r, U)}" for r in rs))
    return ReportFigure(fig, alt, SECTIONS[1])


def fig_root_locus_mach(a, mach: float, results=None) -> ReportFigure:
    """The p-k roots at ``mach`` in the complex plane (Re p 1/s, Im p / 2 pi Hz) over the
    airspeed sweep, one colour per flight condition, modes named at the lowest speed, flutter
    points starred. ``results``: the conditions to draw (default: every one at ``mach``)."""
    rs = [r for r in a.flutter.results if r.mach == mach] if results is None else list(results)
    fig, ax = new_figure(f"{a.case.name}: root locus of the p-k roots at M {mach:g}",
                         figsize=(8.0, 5.2), layout="constrained")
    for i, r in enumerate(rs):
        p = r.pk.p
        for j in range(p.shape[1]):
            ax.plot(p[:, j].real, p[:, j].imag / (2 * math.pi), "-", color=f"C{i}", lw=1.2,
                    label=condition_label(r.condition) if j == 0 else None)
            ax.plot(p[0, j].real, p[0, j].imag / (2 * math.pi), "o", color=f"C{i}", ms=4,
                    mfc="none")
            if i == 0:
                ax.annotate(r.pk.mode_labels[j], (p[0, j].real, p[0, j].imag / (2 * math.pi)),
                            textcoords="offset points", xytext=(-4, 4), ha="right", fontsize=8)
        f = r.flutter
        if f is not None and not r.unstable_at_start:
            ax.plot(0.0, f.frequency_hz, "*", color=f"C{i}", mec="k", ms=13, zorder=5)
    ax.plot([], [], "o", color="0.3", mfc="none", ms=4, label="lowest airspeed")
    ax.plot([], [], "*", color="0.6", mec="k", ms=13, label="flutter point")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re p (1/s), > 0 unstable")
    ax.set_ylabel("Im p / 2 pi (Hz)")
    _legend_right(ax, fontsize=8)
    U = a.case.flight.velocities
    alt = (f"Root locus at M {mach:g} from {U[0]:g} to {U[-1]:g} m/s, one colour per "
           f"condition: " + "; ".join(f"at {condition_label(r.condition)} "
                                      f"{flutter_phrase(r, U)}" for r in rs))
    return ReportFigure(fig, alt, SECTIONS[1])


# ---------------------------------------------------------------------------------------------
# structure
# ---------------------------------------------------------------------------------------------
def _outlines(polygons):
    """Closed outlines of polygons given by their (x, y) corners (m), as (span y, chord x)
    point lists for a LineCollection; any number of corners per polygon.

    >>> _outlines([[(0, 0), (1, 0), (1, 2)]])[0].tolist()
    [[0.0, 0.0], [0.0, 1.0], [2.0, 1.0], [0.0, 0.0]]
    """
    out = []
    for p in polygons:
        p = np.asarray(p, float)[:, :2]
        out.append(np.vstack([p, p[:1]])[:, ::-1])
    return out


def fig_planform(a) -> ReportFigure:
    """The planform in two panels sharing their axes: the FE mesh (grey, with the pitch axis of
    a shaft support) and the aerodynamic boxes (orange outlines over the FE mesh, faint), so
    that neither hides the other however close the two meshes are."""
    from matplotlib.collections import LineCollection
    mesh = P.structural_mesh(a.case)
    boxes = P.box_mesh(a.case).corners
    n_el, n_box = len(mesh.elements), len(boxes)
    fe = _outlines([mesh.nodes[np.asarray(e)] for e in mesh.elements])
    fig, (ax1, ax2) = new_figure(f"{a.case.name}: planform, FE mesh and aerodynamic boxes",
                                 ncols=2, figsize=(8.0, 5.0), sharex=True, sharey=True,
                                 layout="constrained")
    ax1.add_collection(LineCollection(fe, colors="0.3", lw=0.8))
    ax1.set_title(f"FE mesh: {n_el} plate elements", fontsize=10)
    ax2.add_collection(LineCollection(fe, colors="0.75", lw=0.6, zorder=2))
    ax2.add_collection(LineCollection(_outlines(boxes), colors="C1", lw=1.0,
                                      zorder=3))
    ax2.set_title(f"aerodynamic boxes: {n_box} (FE mesh faint)", fontsize=10)
    s = a.case.support
    shaft = s is not None and s.kind == "shaft"
    for ax in (ax1, ax2):
        if shaft:
            ax.plot(s.axis_point[1], s.axis_point[0], "rs", zorder=4, label="pitch axis")
        ax.autoscale_view()
        ax.set_xlabel("y (m), span from the root")
        ax.set_aspect("equal")
    ax1.set_ylabel("x (m), downstream")
    ax1.invert_yaxis()
    if shaft:                                          # below the panels: covers no box
        fig.legend(handles=ax1.get_lines()[-1:], loc="outside lower center")
    alt = (f"Planform of {a.case.name}: left the FE mesh of {n_el} plate elements, right the "
           f"{n_box} aerodynamic boxes (orange) over the FE mesh (faint grey)"
           + ("; the pitch axis marked red" if shaft else ""))
    return ReportFigure(fig, alt, SECTIONS[2])


def _mode_panel(ax, m, tri, j, levels):
    w = m.shapes[:, 0, j]
    scale = np.abs(w).max()
    w = w / scale if scale > 0 else w
    cs = ax.tricontourf(m.nodes[:, 1], m.nodes[:, 0], tri, w, levels=levels, cmap="RdBu_r",
                        vmin=-1.0, vmax=1.0)
    if w.min() < 0 < w.max():
        ax.tricontour(m.nodes[:, 1], m.nodes[:, 0], tri, w, levels=[0.0], colors="k",
                      linewidths=1.4)
    ax.set_title(f"{mode_label(j, m.n_rigid)}: {m.frequencies_hz[j]:.4g} Hz", fontsize=10)
    ax.set_aspect("equal")
    return cs


def fig_modes(a) -> ReportFigure:
    """Every kept mode (the rigid pitch mode included): w normalised to max |w| = 1, one colour
    bar, the node lines (w = 0) in black."""
    m = a.modal
    n = len(m.frequencies_hz)
    ncols, nrows = _grid(n)
    fig, axes = new_figure(f"{a.case.name}: mode shapes w / max|w|, node lines (w = 0) black",
                           nrows=nrows, ncols=ncols, figsize=(3.4 * ncols + 1.2, 3.2 * nrows + 0.8),
                           sharex=True, sharey=True, layout="constrained")
    axes = np.atleast_1d(np.asarray(axes, dtype=object)).ravel()
    el = np.asarray(m.elements)
    tri = np.concatenate([el[:, [0, 1, 2]], el[:, [0, 2, 3]]])
    levels = np.linspace(-1.0, 1.0, 21)
    cs = None
    for j in range(n):
        cs = _mode_panel(axes[j], m, tri, j, levels)
    for ax in axes[n:]:
        ax.set_visible(False)
    for j, ax in enumerate(axes[:n]):                  # shared axes: labels on the outside
        if j % ncols == 0:
            ax.set_ylabel("x (m)")
        if j + ncols >= n:
            ax.set_xlabel("y (m)")
            ax.xaxis.set_tick_params(labelbottom=True)
    axes[0].invert_yaxis()                             # shared: once for all
    axes[0].locator_params(axis="x", nbins=4)          # tick labels clear of the neighbour's
    fig.colorbar(cs, ax=list(axes[:n]), label="w / max|w| (-)", shrink=0.7)
    alt = (f"Mode shapes of the {n} kept modes (w normalised, node lines black): "
           + ", ".join(f"{mode_label(j, m.n_rigid)} {m.frequencies_hz[j]:.4g} Hz"
                       for j in range(n)))
    return ReportFigure(fig, alt, SECTIONS[2])


# ---------------------------------------------------------------------------------------------
# the ASE loop
# ---------------------------------------------------------------------------------------------
def fig_ase_bode(a) -> ReportFigure:
    """Gain (dB) and phase (deg) of the forward paths FWTF 1-3, gain crossovers marked."""
    s = a.ase
    f = np.logspace(0, 3.5, 800)
    fig, (ax1, ax2) = new_figure(f"{a.case.name}: forward paths FWTF 1-3, M {s.mach:g}",
                                 nrows=2, figsize=(7.0, 6.4), sharex=True, layout="constrained")
    for i in (1, 2, 3):
        h = ase_mod.frequency_response(ase_mod.forward_path(s.model, s.controller, i), f)
        ax1.semilogx(f, 20 * np.log10(np.abs(h)), label=f"FWTF {i}")
        ax2.semilogx(f, np.degrees(np.unwrap(np.angle(h))))
        c = s.crossovers[i]
        if c.gain_crossovers_hz.size:
            ax1.plot(c.gain_crossovers_hz[0], 0.0, "k|", ms=12)
    ax1.axhline(0.0, color="k", lw=0.8)
    ax2.axhline(-180.0, color="k", lw=0.8)
    ax1.set_ylabel("gain (dB)")
    ax2.set_ylabel("phase (deg)")
    ax2.set_xlabel("frequency (Hz)")
    ax1.legend()
    pm = "; ".join(f"FWTF {i} phase margin {c.phase_margin_deg:.1f} deg"
                   for i, c in s.crossovers.items() if c.phase_margin_deg is not None
                   and math.isfinite(c.phase_margin_deg))
    alt = f"Bode plot of the forward paths FWTF 1-3 at M {s.mach:g}" + (f": {pm}" if pm else "")
    return ReportFigure(fig, alt, SECTIONS[3])


def fig_ase_steps(a) -> ReportFigure:
    """Fin-root pitch (deg) of the power-limited step responses against time (ms)."""
    s = a.ase
    step = a.case.actuator.step_deg
    fig, ax = new_figure(f"{a.case.name}: power-limited step, fin-root pitch",
                         figsize=(7.0, 4.4), layout="constrained")
    for t, sim in s.simulations.items():
        ax.plot(sim.t * 1e3, np.degrees(sim.fin_root), label=t)
    ax.axhline(step, color="k", lw=0.8, ls="--", label="command")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("fin-root pitch (deg)")
    ax.set_ylim(-0.5 * step, 2.5 * step)
    ax.legend()
    alt = (f"Fin-root pitch after a {step:g} deg step command: " + "; ".join(
        f"{t} {'stable' if s.stable[t] else 'unstable'}" for t in s.simulations))
    return ReportFigure(fig, alt, SECTIONS[3])


def _gust_label(c) -> str:
    """A gust's name: "H = 1 m" for a 1-cos gust, the file name for a ``gust.profile``."""
    return f"H = {c.gradient_length:g} m" if c.gradient_length is not None else c.profile


def fig_gust_histories(a) -> ReportFigure:
    """Hinge moment, root bending moment and (with an actuator) motor current against time in
    each 1-cos gust of ``[gust]`` and its ``profile`` (:mod:`asekit.case.gust_loads`), the
    tuned gust (largest hinge moment, named in the alt text) drawn thicker; in the current panel the actuator's
    current limit (dotted) and, for a gust that saturates, the power-limited current (dashed)."""
    g = a.gust
    rows = [("root_bending", "root bending (N m)")]
    if g.cases[0].hinge_moment is not None:
        rows.insert(0, ("hinge_moment", "hinge moment (N m)"))
    if g.cases[0].current is not None:
        rows.append(("current", "motor current (A)"))
    fig, axes = new_figure(f"{a.case.name}: 1-cos gusts, U_ds {g.design_velocity:g} m/s at "
                           f"M {g.mach:g}, {g.altitude:g} m", nrows=len(rows),
                           figsize=(7.0, 2.2 * len(rows) + 0.8), layout="constrained",
                           sharex=True)
    axes = np.atleast_1d(axes)
    tuned_h = g.tuned("hinge_moment") if g.cases[0].hinge_moment is not None else None
    for c in g.cases:
        lines = {}
        for ax, (name, _) in zip(axes, rows):
            lines[name], = ax.plot(c.t * 1e3, getattr(c, name), label=_gust_label(c),
                                   lw=2.0 if c is tuned_h else 1.2)
        lim = c.servo.get("AEM1", {})
        if "current" in lines and lim.get("saturated"):
            axes[-1].plot(c.t * 1e3, lim["current_limited"], "--",
                          color=lines["current"].get_color(), lw=1.0)
    sat = [c for c in g.cases if c.servo.get("AEM1", {}).get("saturated")]
    if g.cases[0].current is not None:
        _, _, plim = P.actuator_setup(a.case)
        peak = max(abs(c.peak_current) for c in g.cases)
        i_lim = plim.current_limit
        if i_lim is not None and (sat or peak > 0.5 * i_lim):
            for sgn in (1, -1):
                axes[-1].axhline(sgn * i_lim, color="k", ls=":", lw=0.8)
            top = 1.3 * max(peak, i_lim)      # a runaway limited current stays off-scale
            axes[-1].set_ylim(-top, top)
    for ax, (_, label) in zip(axes, rows):
        ax.set_ylabel(label)
    axes[-1].set_xlabel("time (ms)")
    axes[0].legend(fontsize="small")
    tuned = g.tuned("root_bending")
    names = ", ".join(_gust_label(c) for c in g.cases)
    alt = (f"Loads in the gusts {names}; the largest root bending "
           f"{tuned.peak_root_bending:.3g} N m in {_gust_label(tuned)}")
    if tuned.peak_hinge_moment is not None:
        h = g.tuned("hinge_moment")
        alt += f"; the largest hinge moment {h.peak_hinge_moment:.3g} N m in {_gust_label(h)}"
    if g.cases[0].current is not None and "AEM1" in g.cases[0].servo:
        alt += ("; the power-limited AEM1 loop saturates in " + ", ".join(
            _gust_label(c) for c in sat) if sat else
            "; the AEM1 loop stays within the actuator's power limits")
    return ReportFigure(fig, alt, SECTIONS[4])


#: The turbulence loads of the report's PSD figure: (key, axis label, unit of the PSD).
_TURBULENCE_LOADS = (("hinge_moment", "hinge moment", "(N m)^2/Hz"),
                     ("root_bending", "root bending", "(N m)^2/Hz"),
                     ("current", "motor current (AEM1)", "A^2/Hz"))


def fig_gust_psd(a) -> ReportFigure:
    """One-sided PSDs (per Hz: 2 pi times the per-rad/s PSD) of the hinge moment, root
    bending moment and (with an actuator) AEM1 motor current in the ``[gust.turbulence]``
    spectrum, against frequency (Hz), with each load's RMS in the legend."""
    g = a.gust
    t = g.turbulence
    sp = t["spectra"]
    rows = [r for r in _TURBULENCE_LOADS if r[0] in sp]
    f = sp["omega"][1:] / (2 * np.pi)
    spec = a.case.gust.spectrum.replace("_", " ")
    fig, axes = new_figure(f"{a.case.name}: {spec} turbulence, sigma_w "
                           f"{a.case.gust.turbulence_sigma:g} m/s, L {a.case.gust.scale_length:g}"
                           f" m, M {g.mach:g}, {g.altitude:g} m", nrows=len(rows),
                           figsize=(7.0, 2.2 * len(rows) + 0.8), layout="constrained",
                           sharex=True)
    axes = np.atleast_1d(axes)
    parts = []
    for ax, (key, label, unit) in zip(axes, rows):
        rms = t[key]["rms"]
        ax.loglog(f, 2 * np.pi * sp[key][1:], label=f"RMS {rms:.3g}")
        ax.set_ylabel(f"{label}\nPSD ({unit})")
        ax.legend(fontsize="small")
        parts.append(f"{label} RMS {rms:.3g}, N0 {t[key]['N0_per_s']:.3g}/s")
    axes[-1].set_xlabel("frequency (Hz)")
    alt = "Power spectral densities of the loads in continuous turbulence: " + "; ".join(parts)
    return ReportFigure(fig, alt, SECTIONS[4])


def fig_gust_ellipse(a) -> ReportFigure:
    """Correlated loads, hinge moment against root bending moment: the equal-probability
    ellipse (one sigma) of their joint covariance in turbulence
    (:func:`asekit.aeroelastic.gust.correlated_load_ellipse`, Hoblit 1988 Ch. 7) with the
    RMS values marked, and each 1-cos gust's path (hinge moment, root bending)(t) with its
    peak hinge moment and peak root bending points overlaid. Needs a rigid pitch mode (the
    hinge moment) and ``[gust.turbulence]``."""
    from asekit.aeroelastic.gust import correlated_load_ellipse

    g = a.gust
    cov = g.turbulence["covariance"]["matrix"]
    sx, sy = math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1])
    rho = cov[0, 1] / (sx * sy) if sx * sy > 0 else 0.0
    e = correlated_load_ellipse(cov)
    fig, ax = new_figure(f"{a.case.name}: correlated loads, M {g.mach:g}, {g.altitude:g} m",
                         figsize=(7.0, 5.4), layout="constrained")
    ax.plot(e[0], e[1], "k", lw=2.0, zorder=5, label=f"turbulence, 1 sigma (rho {rho:.2f})")
    ax.plot([sx, -sx, rho * sx, -rho * sx], [rho * sy, -rho * sy, sy, -sy], "ko", ms=4, zorder=6)
    for c in g.cases:
        line, = ax.plot(c.hinge_moment, c.root_bending, lw=0.8, alpha=0.7,
                        label=f"1-cos {_gust_label(c)}")
        ih = int(np.argmax(np.abs(c.hinge_moment)))
        ib = int(np.argmax(np.abs(c.root_bending)))
        ax.plot(c.hinge_moment[[ih, ib]], c.root_bending[[ih, ib]], "s",
                color=line.get_color(), ms=5)
    ax.set_xlabel("hinge moment (N m)")
    ax.set_ylabel("root bending moment (N m)")
    ax.legend(fontsize="small")
    alt = (f"Hinge moment against root bending moment: the one-sigma turbulence ellipse "
           f"(RMS {sx:.3g} N m and {sy:.3g} N m, correlation {rho:.2f}) and the 1-cos gusts' "
           f"load paths, their peak points marked")
    return ReportFigure(fig, alt, SECTIONS[4])


def figures_of_gust(a) -> dict:
    """The report's gust figures: the 1-cos histories, and with ``[gust.turbulence]`` the
    load PSDs and (with a hinge moment) the correlated-load ellipse."""
    out = {"gust_histories": fig_gust_histories(a)}
    t = a.gust.turbulence
    if t is not None and "spectra" in t:
        out["gust_psd"] = fig_gust_psd(a)
        if t["covariance"]["names"][:1] == ("hinge_moment",):
            out["gust_ellipse"] = fig_gust_ellipse(a)
    return out


def fig_control_effectiveness(a) -> ReportFigure:
    """Flexible-to-rigid rolling-moment effectiveness of each control surface against speed,
    one curve per surface and Mach, the reversal speeds marked (dotted)."""
    fig, ax = new_figure(f"{a.case.name}: control-surface effectiveness (rolling moment, "
                         f"flexible / rigid)", figsize=(7.0, 4.4), layout="constrained")
    parts = []
    for r in a.control:
        line, = ax.plot(r.speeds_ms, r.effectiveness_ratio, label=f"{r.name}, M {r.mach:g}")
        if r.reversal_speed_ms is not None:
            ax.axvline(r.reversal_speed_ms, ls=":", color=line.get_color())
        parts.append(f"{r.name} at M {r.mach:g}: reversal " + (
            f"at {r.reversal_speed_ms:.1f} m/s" if r.reversal_speed_ms is not None else
            f"none below {r.speed_limit_ms:.0f} m/s"))
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel(f"airspeed (m/s), density {a.control[0].density:.4g} kg/m^3")
    ax.set_ylabel("effectiveness ratio (-)")
    ax.set_ylim(-1.0, 1.2)
    ax.legend()
    alt = ("Rolling moment per unit control deflection, flexible over rigid, against airspeed; "
           + "; ".join(parts))
    return ReportFigure(fig, alt, SECTIONS[5])


def fig_control_hinge_moments(a) -> ReportFigure:
    """Hinge moment per degree of deflection of each control surface at the envelope's points
    (or the sweep's top) against dynamic pressure, one marker series per surface and Mach,
    joined to the origin (a rigid surface's H = q S_f c_f C_h is linear in q at one Mach)."""
    fig, ax = new_figure(f"{a.case.name}: hinge moments for servo sizing",
                         figsize=(7.0, 4.4), layout="constrained")
    deg = math.pi / 180.0
    parts = []
    for name in dict.fromkeys(r.name for r in a.control_hinge):
        for m in dict.fromkeys(r.mach for r in a.control_hinge if r.name == name):
            rows = sorted((r for r in a.control_hinge if r.name == name and r.mach == m),
                          key=lambda r: r.dynamic_pressure)
            q = [0.0] + [r.dynamic_pressure for r in rows]
            h = [0.0] + [r.hinge_moment_per_delta * deg for r in rows]
            ax.plot(q, h, marker="o", label=f"{name}, M {m:g}")
        worst = max((r for r in a.control_hinge if r.name == name),
                    key=lambda r: abs(r.hinge_moment_per_delta))
        parts.append(f"{name}: largest {worst.hinge_moment_per_delta * deg:.4g} N m per deg at "
                     f"M {worst.mach:g}, q {worst.dynamic_pressure:.4g} Pa")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("dynamic pressure (Pa)")
    ax.set_ylabel("hinge moment per deflection (N m/deg)")
    ax.legend()
    alt = ("Rigid hinge moment per degree of control deflection against dynamic pressure at the "
           "envelope's points; " + "; ".join(parts))
    return ReportFigure(fig, alt, SECTIONS[5])


# ---------------------------------------------------------------------------------------------
# the actuator loop on a control surface (issue 25, asekit.ase.flap)
# ---------------------------------------------------------------------------------------------
def _margin_text(r) -> str:
    """"PM 78.4 deg at 25.1 Hz, GM 12.0 dB" of a control_surface_ase row (its forward path)."""
    pm = ("no gain crossover" if r.crossover_hz is None or not math.isfinite(r.phase_margin_deg)
          else f"PM {r.phase_margin_deg:.1f} deg at {r.crossover_hz:.1f} Hz")
    gm = ("no phase crossover" if not math.isfinite(r.gain_margin_db)
          else f"GM {r.gain_margin_db:.1f} dB")
    return f"{pm}, {gm}"


def fig_control_ase_bode(a) -> ReportFigure:
    """Gain (dB) and phase (deg) of the open loop (forward path) of the actuator on the control
    surface, AEM1 (FWTF 2) and AEM2 (FWTF 3), each topology's gain crossovers (phase margins)
    and phase crossovers (gain margins) marked."""
    rows = [r for r in a.control_ase if r.open_loop is not None]
    r0 = rows[0]
    fig, (ax1, ax2) = new_figure(
        f"{a.case.name}: actuator on {r0.name}, open loop at {r0.speed_ms:g} m/s, "
        f"M {r0.mach:g}", nrows=2, figsize=(7.0, 6.4), sharex=True, layout="constrained")
    for r in rows:
        f, h = r.frequency_hz, r.open_loop
        which = "FWTF 2" if r.topology == "AEM1" else "FWTF 3"
        line, = ax1.semilogx(f, 20 * np.log10(np.abs(h)), label=f"{r.topology} ({which}): "
                             f"{_margin_text(r)}")
        ph = np.degrees(np.unwrap(np.angle(h)))
        ax2.semilogx(f, ph, color=line.get_color())
        cr = r.crossovers
        for fc, pm in zip(cr.gain_crossovers_hz, cr.phase_margins_deg):
            ax1.plot(fc, 0.0, "o", mfc="none", color=line.get_color())
            p = np.interp(np.log(fc), np.log(f), ph)
            ax2.annotate("", xy=(fc, p), xytext=(fc, p - pm),
                         arrowprops=dict(arrowstyle="<->", color=line.get_color()))
        for fc, gm in zip(cr.phase_crossovers_hz, cr.gain_margins_db):
            ax1.annotate("", xy=(fc, 0.0), xytext=(fc, -gm),
                         arrowprops=dict(arrowstyle="<->", color=line.get_color()))
    ax1.axhline(0.0, color="k", lw=0.8)
    ax2.axhline(-180.0, color="k", lw=0.8)
    ax1.set_ylabel("open-loop gain (dB)")
    ax2.set_ylabel("open-loop phase (deg)")
    ax2.set_xlabel("frequency (Hz)")
    ax1.legend(loc="lower left")
    alt = (f"Bode plot of the open loop of the actuator on {r0.name} at {r0.speed_ms:g} m/s, "
           f"Mach {r0.mach:g}, {r0.altitude:g} m, margins marked (circles: gain crossovers, "
           f"arrows: the phase and gain margins): "
           + "; ".join(f"{r.topology} {_margin_text(r)}" for r in rows))
    return ReportFigure(fig, alt, SECTIONS[5])


def fig_control_ase_steps(a) -> ReportFigure:
    """The surface's angle in the air (deg) after the power-limited step command against time
    (ms), AEM1 and AEM2 (AEM1's fed-back hinge angle dashed), each topology's 2 % settling time
    of its fed-back angle marked."""
    rows = [r for r in a.control_ase if r.time_s is not None]
    r0 = rows[0]
    fig, ax = new_figure(f"{a.case.name}: actuator on {r0.name}, power-limited "
                         f"{r0.step_deg:g} deg step", figsize=(7.0, 4.4), layout="constrained")
    for r in rows:
        ts = ("not settled" if r.settling_time_s is None
              else f"settles in {1e3 * r.settling_time_s:.1f} ms")
        line, = ax.plot(r.time_s * 1e3, np.degrees(r.surface_angle_rad),
                        label=f"{r.topology}: {r0.name} angle in the air"
                        + ("" if r.topology == "AEM1" else f" (fed back, {ts})"))
        if r.topology == "AEM1":           # AEM1 feeds back the hinge angle, not the air's
            ax.plot(r.time_s * 1e3, np.degrees(r.fed_back_rad), ls="--", lw=1.0,
                    color=line.get_color(), label=f"AEM1: hinge angle (fed back, {ts})")
        if r.settling_time_s is not None:
            ax.axvline(1e3 * r.settling_time_s, ls=":", color=line.get_color())
    ax.axhline(r0.step_deg, color="k", lw=0.8, ls="--", label="command")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("angle (deg)")
    ax.set_ylim(-0.5 * r0.step_deg, 2.5 * r0.step_deg)
    ax.legend()
    alt = (f"The {r0.name}'s angle after a {r0.step_deg:g} deg power-limited step command at "
           f"{r0.speed_ms:g} m/s: " + "; ".join(
               f"{r.topology} {'stable' if r.stable else 'unstable'}, overshoot "
               f"{100 * r.overshoot:.1f} %, settling " + (
                   "none in 200 ms" if r.settling_time_s is None
                   else f"{1e3 * r.settling_time_s:.1f} ms") for r in rows))
    return ReportFigure(fig, alt, SECTIONS[5])


def figures(a) -> dict:
    """{file name: :class:`ReportFigure`} of the report, in page order: the Mach figure, V-g /
    V-f and root locus at every analysed Mach, the planform and mode shapes, and with an
    actuator the ASE figures."""
    out = {"flutter_mach": fig_flutter_mach(a)}
    for i, m in enumerate(_machs(a)):
        out[f"vg_{i}"] = fig_vg_mach(a, m)              # i: the Mach's rank, ascending
        out[f"root_locus_{i}"] = fig_root_locus_mach(a, m)
    if getattr(a.case, "beam", None) is not None:       # a stick model (issue 24)
        out["planform"], out["modes"] = fig_beam_planform(a), fig_beam_modes(a)
    else:
        out["planform"] = fig_planform(a)
        out["modes"] = fig_modes(a)
    if a.ase is not None:
        out["ase_bode"] = fig_ase_bode(a)
        out["ase_steps"] = fig_ase_steps(a)
    if getattr(a, "gust", None) is not None:
        out.update(figures_of_gust(a))
    if getattr(a, "control", ()):
        out["control_effectiveness"] = fig_control_effectiveness(a)
    if getattr(a, "control_hinge", ()):
        out["control_hinge_moments"] = fig_control_hinge_moments(a)
    if any(r.time_s is not None for r in getattr(a, "control_ase", ())):
        out["control_ase_steps"] = fig_control_ase_steps(a)
        out["control_ase_bode"] = fig_control_ase_bode(a)
    return out


# ---------------------------------------------------------------------------------------------
# stick models ([[beam]], issue 24)
# ---------------------------------------------------------------------------------------------
def fig_beam_planform(a) -> ReportFigure:
    """A stick model's planform: the aerodynamic boxes (orange) and the beam's elastic axis
    with its nodes (black)."""
    from matplotlib.collections import LineCollection
    beam = P.case_beam(a.case)
    boxes = P.box_mesh(a.case).corners
    fig, ax = new_figure(f"{a.case.name}: beam axis and aerodynamic boxes",
                         figsize=(6.0, 5.0), layout="constrained")
    ax.add_collection(LineCollection(_outlines(boxes), colors="C1", lw=1.0))
    nodes = beam.nodes
    ax.plot(nodes[:, 1], nodes[:, 0], "k.-", lw=1.4, ms=4, label="beam (elastic axis)")
    ax.set_xlabel("y (m)")
    ax.set_ylabel("x (m)")
    ax.set_aspect("equal")
    ax.autoscale()
    ax.invert_yaxis()
    ax.legend(loc="lower right")
    alt = (f"Planform of {a.case.name}: {len(boxes)} aerodynamic boxes (orange) and the beam's "
           f"elastic axis with its {beam.n_nodes} nodes (black), from ({nodes[0, 0]:.4g}, "
           f"{nodes[0, 1]:.4g}) m to ({nodes[-1, 0]:.4g}, {nodes[-1, 1]:.4g}) m")
    return ReportFigure(fig, alt, SECTIONS[2])


def fig_beam_modes(a) -> ReportFigure:
    """A stick model's modes along the axis: the deflection w and the nose-up twist (the
    rotation about the axis), each normalised to its largest magnitude over the modes."""
    m = a.modal
    beam = P.case_beam(a.case)
    s = beam.stations
    e1 = beam.direction
    w = m.shapes[:, 0, :]
    twist = e1[0] * m.shapes[:, 1, :] + e1[1] * m.shapes[:, 2, :]
    fig, (ax1, ax2) = new_figure(f"{a.case.name}: beam mode shapes along the axis", nrows=2,
                                 figsize=(6.0, 5.5), sharex=True, layout="constrained")
    for j in range(m.frequencies_hz.size):
        lab = f"{mode_label(j, m.n_rigid)}: {m.frequencies_hz[j]:.4g} Hz"
        ax1.plot(s, w[:, j] / max(np.abs(w).max(), 1e-300), label=lab)
        ax2.plot(s, twist[:, j] / max(np.abs(twist).max(), 1e-300), label=lab)
    ax1.set_ylabel("w / max|w| (-)")
    ax2.set_ylabel("twist / max|twist| (-)")
    ax2.set_xlabel("distance along the axis (m)")
    ax1.legend(fontsize=8)
    alt = (f"Mode shapes of the {m.frequencies_hz.size} kept beam modes along the axis: "
           f"deflection (top) and nose-up twist (bottom), each normalised over all modes")
    return ReportFigure(fig, alt, SECTIONS[2])
