"""The report of ``asekit optimise --report DIR`` (issue 28): the thickness field before and
after, V-g / V-f before and after at the critical flight condition, the constraint activity at
the optimum (a table) and the optimiser's history,
written with the JSON as an HTML page (the figures' alt texts as captions).

Every number drawn comes from the case pipeline's re-analysis of the baseline and the optimised
case (:func:`asekit.case.pipeline.flutter`), not from the optimiser's own chain, except the
history, which is the optimiser's.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from asekit.case import pipeline as P
from asekit.case.report import write_text_atomic
from asekit.case.report_figures import ReportFigure, _vg_panel
from asekit.util.plotting import new_figure

SECTION = "Design optimisation"


def element_thickness(case) -> np.ndarray:
    """Thickness (m) of every plate element of ``case`` at its centroid (the corner values'
    mean where the mesh carries corner thicknesses).

    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> h = element_thickness(load_case(FIN_FILE))
    >>> bool(h.min() > 0.0019 and h.max() < 0.0041)
    True
    """
    mesh = P.structural_mesh(case)
    corner = getattr(mesh, "corner_thickness", None)
    if corner is not None:
        return np.asarray(corner, float).mean(axis=1)
    c = mesh.element_centroids()
    return np.asarray(mesh.thickness_xy(c[:, 0], c[:, 1]), float)


def fig_thickness(base, opt) -> ReportFigure:
    """The element thickness (mm) of the baseline and the optimised case on one colour scale."""
    hb, ho = element_thickness(base) * 1e3, element_thickness(opt) * 1e3
    lo, hi = float(min(hb.min(), ho.min())), float(max(hb.max(), ho.max()))
    fig, axes = new_figure(f"{base.name}: thickness before and after optimisation", ncols=2,
                           figsize=(10.0, 4.4), layout="constrained")
    for ax, case, h, label in ((axes[0], base, hb, "baseline"), (axes[1], opt, ho, "optimised")):
        mesh = P.structural_mesh(case)
        poly = mesh.nodes[mesh.elements]                       # (n_e, 4, 2)
        from matplotlib.collections import PolyCollection
        pc = PolyCollection(poly, array=h, cmap="viridis", edgecolors="0.6", linewidths=0.3)
        pc.set_clim(lo, hi if hi > lo else lo + 1e-9)
        ax.add_collection(pc)
        ax.autoscale_view()
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{label}: {h.min():.3g}-{h.max():.3g} mm")
    fig.colorbar(pc, ax=list(axes), label="thickness (mm)")
    alt = (f"Element thickness over the planform, baseline {hb.min():.3g}-{hb.max():.3g} mm and "
           f"optimised {ho.min():.3g}-{ho.max():.3g} mm, on one colour scale")
    return ReportFigure(fig, alt, SECTION)


def _critical(fa):
    """The analysed condition with the lowest flutter speed (or the first one)."""
    rs = list(fa.results)
    speeds = [r.flutter.speed if r.flutter is not None and not r.unstable_at_start else np.inf
              for r in rs]
    return rs[int(np.argmin(speeds))]


def fig_vg(base, opt, fa_base, fa_opt) -> ReportFigure:
    """V-g (top) and V-f (bottom) at the baseline's critical condition, baseline left and
    optimised right (the same Mach and altitude)."""
    rb = _critical(fa_base)
    same = [r for r in fa_opt.results if r.mach == rb.mach
            and r.condition.altitude == rb.condition.altitude]
    ro = same[0] if same else _critical(fa_opt)
    fig, axes = new_figure(f"{base.name}: V-g and V-f before and after optimisation", nrows=2,
                           ncols=2, figsize=(9.5, 7.0), sharex=True, sharey="row",
                           layout="constrained")
    _vg_panel(axes[0, 0], axes[1, 0], rb, base.flight.velocities)
    _vg_panel(axes[0, 1], axes[1, 1], ro, opt.flight.velocities)
    axes[0, 0].set_title("baseline\n" + axes[0, 0].get_title(), fontsize=9)
    axes[0, 1].set_title("optimised\n" + axes[0, 1].get_title(), fontsize=9)
    for ax in axes[1]:
        ax.set_xlabel("airspeed U (m/s)")

    def speed(r):
        f = r.flutter
        return "none" if f is None or r.unstable_at_start else f"{f.speed:.1f} m/s"
    alt = (f"V-g and V-f at M {rb.mach:g}, {rb.condition.altitude:g} m: flutter {speed(rb)} "
           f"before, {speed(ro)} after")
    return ReportFigure(fig, alt, SECTION)


def fig_history(history) -> ReportFigure:
    """Mass (kg) and the smallest flutter margin (%) of the optimiser's iterates."""
    it = [r["iteration"] for r in history]
    fig, ax = new_figure("optimiser history", figsize=(7.0, 4.0), layout="constrained")
    ax.plot(it, [r["mass_kg"] for r in history], "o-", color="C0")
    ax.set_xlabel("iteration")
    ax.set_ylabel("mass (kg)", color="C0")
    ax2 = ax.twinx()
    ax2.plot(it, [r["min_margin_pct"] for r in history], "s--", color="C1")
    ax2.set_ylabel("smallest flutter margin (%)", color="C1")
    last = history[-1] if history else None
    alt = ("Mass and smallest flutter margin per iteration" + (
        f"; last: {last['mass_kg']:.5g} kg, {last['min_margin_pct']:+.2f} %" if last else ""))
    return ReportFigure(fig, alt, SECTION)


def write_design_report(directory, base, opt, fa_base, fa_opt, history, doc: dict) -> Path:
    """Write ``thickness.png``, ``vg.png``, ``history.png`` (when there is a history),
    ``summary.json`` (``doc``) and ``index.html`` into ``directory`` (created); returns the
    page's path. Files are written atomically."""
    import matplotlib.pyplot as plt
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    figs = {"thickness": fig_thickness(base, opt), "vg": fig_vg(base, opt, fa_base, fa_opt)}
    if history:
        figs["history"] = fig_history(history)
    saved = []
    for name, rf in figs.items():
        tmp = out / f".{name}.png.tmp"
        rf.figure.savefig(tmp, format="png", dpi=110)
        tmp.replace(out / f"{name}.png")
        plt.close(rf.figure)
        saved.append((f"{name}.png", rf.alt))
    write_text_atomic(out / "summary.json", json.dumps(doc, indent=2) + "\n")
    d = doc.get("design", {})
    rows = "".join(
        f"<tr><td>{k}</td><td>{html.escape(_fmt(d.get('baseline', {}).get(k)))}</td>"
        f"<td>{html.escape(_fmt(d.get('optimised', {}).get(k)))}</td></tr>"
        for k in ("mass_kg", "flutter_margin_pct", "divergence_speed_ms", "meets_constraints"))
    body = "".join(f'<figure><img src="{f}" alt="{html.escape(a)}"><figcaption>'
                   f"{html.escape(a)}</figcaption></figure>" for f, a in saved)
    page = ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(base.name)}: design optimisation</title></head><body>"
            f"<h1>{html.escape(base.name)}: design optimisation</h1>"
            "<table><tr><th></th><th>baseline</th><th>optimised</th></tr>" + rows + "</table>"
            + constraint_table(d.get("constraints", ())) +
            '<p><a href="summary.json">summary.json</a> (the whole result)</p>'
            f"<h2>{SECTION}</h2>{body}</body></html>\n")
    return write_text_atomic(out / "index.html", page)


def constraint_table(constraints) -> str:
    """The constraint activity at the optimum (``design.constraints`` of the JSON) as an HTML
    table: name, value, bound, active, KKT multiplier; empty without constraints.

    >>> constraint_table([{"name": "flutter_margin[0 m]", "value": 0.15, "bound": 0.15,
    ...                    "active": True, "multiplier": 0.5}]).count("<tr>")
    2
    """
    if not constraints:
        return ""
    head = ("<h2>Constraints at the optimum</h2><table><tr><th>constraint</th><th>value</th>"
            "<th>bound</th><th>active</th><th>multiplier</th></tr>")
    rows = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_fmt(c.get(k)))}</td>"
                         for k in ("name", "value", "bound", "active", "multiplier")) + "</tr>"
        for c in constraints)
    return head + rows + "</table>"


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)
