"""Thesis Ch. 2.2 and 3.2 (aerodynamics): computed quantities and figures.

Reproduce keys: ``aero.Qcc_steady_m3`` (Re Q_cc at M 0.6, k 0.001, isolated fin, from the
cached GAF database), ``aero.CLalpha_fin_per_rad`` (isolated fin, M 0.6, steady VLM, per unit
fin area), ``aero.boxes``, ``aero.min_bpw`` and ``aero.max_box_aspect_ratio`` of the fin's
aerodynamic mesh (built from the mesh rules of Section 3.2.1).

Figures: Fig 7 (quasi-steady vs Theodorsen lift), the Theodorsen vs DLM check, Figs 20/21
(mesh coloured by boxes-per-wavelength and by aspect ratio), the steady pressure distribution
and span loading of the fin, GAF elements vs k at each Mach, and box-count convergence of Q_cc.
"""

from __future__ import annotations

import numpy as np
from scipy.special import hankel2

from asekit.aero.boxes import TrapezoidSurface, check_mesh_rules, mesh_surfaces
from asekit.aero.dlm import normalwash_matrices, pressure_jump
from asekit.aero.gaf import steady_hinge_coefficient
from asekit.aero.vlm import lift_curve_slope, steady_pressure
from asekit.case import pipeline
from asekit.case.variants import with_boxes
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import fin_case
from asekit.reproduction.thesis import thesis_value
from asekit.util.plotting import THESIS_COLOR, new_figure

#: Mach of the steady hinge-moment coefficient (thesis Eq. 4.6).
STEADY_MACH = 0.6


def theodorsen(k) -> np.ndarray:
    """Theodorsen's function C(k) = H1(k) / (H1(k) + i H0(k)) (second-kind Hankel functions)."""
    k = np.asarray(k, float)
    return hankel2(1, k) / (hankel2(1, k) + 1j * hankel2(0, k))


def theodorsen_pitch_lift(k, a: float = -0.5) -> np.ndarray:
    """c_l / alpha of a 2-D plate pitching about x = a b from mid-chord (thesis Eq. 2.9 with
    w = 0, divided by q 2b): pi (i k + a k^2) + 2 pi C(k) (1 + (1/2 - a) i k)."""
    k = np.asarray(k, float)
    return np.pi * (1j * k + a * k**2) + 2 * np.pi * theodorsen(k) * (1 + (0.5 - a) * 1j * k)


def pitch_axis_x(case=None) -> float:
    """x (m) of the fin's pitch axis (default case :func:`fin_case`)."""
    case = fin_case() if case is None else case
    return case.support.axis_point[0]


def _fin_boxes(n_chord: int | None = None, n_span: int | None = None, case=None):
    """The fin's box mesh (:func:`asekit.case.pipeline.box_mesh`), default from the mesh rules;
    a count given replaces the rule's (:func:`asekit.case.variants.with_boxes`)."""
    case = fin_case() if case is None else case
    return pipeline.box_mesh(with_boxes(case, n_chord, n_span) if (n_chord, n_span) != (None, None)
                             else case)


def hinge_coefficient(mesh, mach: float, k: float = 0.001, symmetric: bool = False,
                      case=None) -> float:
    """Re Q_cc (m^3/rad) of the rigid pitch mode on ``mesh`` (analytic mode shape)."""
    case = fin_case() if case is None else case
    xa, b = pitch_axis_x(case), case.aero.reference_semichord
    x, xl = mesh.control_point[:, 0], mesh.load_point[:, 0]
    cp = pressure_jump(mesh, mach, k, b, -1.0 + 1j * k * (-(x - xa)) / b, symmetric=symmetric)
    return float(np.sum(-(xl - xa) * cp * mesh.area).real)


def run(figures: bool = False) -> ChapterResult:
    case = fin_case()
    db = pipeline.gaf_database(case, progress=False)
    mesh = pipeline.box_mesh(case)
    rep = check_mesh_rules(mesh, case.aero.u_min, case.aero.f_max, warn=False)
    qcc = steady_hinge_coefficient(db, STEADY_MACH)
    cla = lift_curve_slope(mesh, STEADY_MACH)
    quantities = (
        Quantity("aero.Qcc_steady_m3", qcc, "m^3",
                 f"isolated fin, {mesh.n} boxes; -> about 5.6e-4 with 1200 boxes; wall at root "
                 f"{hinge_coefficient(mesh, STEADY_MACH, symmetric=True):.3g}"),
        Quantity("aero.CLalpha_fin_per_rad", cla, "1/rad",
                 f"isolated fin, M {STEADY_MACH}, VLM, S = {case.panels[0].planform.area:.5f} m^2"),
        Quantity("aero.boxes", float(mesh.n), "-",
                 f"{mesh.strip.max() + 1} strips x {mesh.n // (mesh.strip.max() + 1)} "
                 "chordwise, from the mesh rules"),
        Quantity("aero.min_bpw", float(rep.bpw.min()), "-", "U_min 180 m/s, f_max 1000 Hz"),
        Quantity("aero.max_box_aspect_ratio", float(rep.aspect_ratio.max()), "-",
                 "longer / shorter box side"),
    )
    figs = {}
    if figures:
        figs = {"fig07_quasisteady_vs_theodorsen": fig_quasi_steady(),
                "fig20_mesh_bpw": fig_mesh_bpw(mesh, rep),
                "fig21_mesh_aspect_ratio": fig_mesh_aspect_ratio(mesh, rep),
                "aero_steady_pressure": fig_steady_pressure(mesh),
                "aero_gaf_vs_k": fig_gaf_vs_k(db)}
    return ChapterResult("aero", quantities, figs)


# ---- figures ---------------------------------------------------------------------------------
def fig_quasi_steady(k_values=(0.1, 0.5), a: float = -0.5):
    """Fig 7: lift of a 2-D plate for a sinusoidal incidence alpha = sin(omega t), pitching
    about the quarter chord: quasi-steady (C = 1, no apparent mass) vs Theodorsen."""
    fig, axes = new_figure("Quasi-steady vs unsteady lift, sinusoidal incidence",
                           "Fig 7", ncols=2)
    s = np.linspace(0, 2 * np.pi, 361)
    for ax, k in zip(axes, k_values):
        h = complex(theodorsen_pitch_lift(k, a))
        alpha = np.sin(s)
        ax.plot(np.degrees(s), 2 * np.pi * alpha, color=THESIS_COLOR, label="quasi-steady 2 pi alpha")
        ax.plot(np.degrees(s), np.imag(h * np.exp(1j * s)), label="Theodorsen (unsteady)")
        ax.set_xlabel("omega t (deg)")
        ax.set_ylabel("c_l per rad of amplitude")
        ax.set_title(f"k = {k:g}: |C| = {abs(complex(theodorsen(k))):.3f}, "
                     f"phase {np.degrees(np.angle(h)):.1f} deg")
        ax.legend(loc="lower left")
    return fig


def theodorsen_check(ks=(0.05, 0.1, 0.2, 0.5, 1.0), n_chord: int = 12):
    """DLM pitch lift (about mid-chord) of the root strip of a 400-chord semi-span wing with a
    wall at the root, against Theodorsen. Returns (ks, dlm c_l/alpha, Theodorsen c_l/alpha)."""
    b = 0.5
    m = mesh_surfaces([
        TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, n_chord, 16, "inner"),
        TrapezoidSurface((0, 2, 0), 1.0, (0, 20, 0), 1.0, n_chord, 18, "mid"),
        TrapezoidSurface((0, 20, 0), 1.0, (0, 400, 0), 1.0, n_chord, 19, "outer")])
    ks = np.asarray(ks, float)
    d = normalwash_matrices(m, 0.0, ks, b, symmetric=True)
    root = m.strip == 0
    x = m.control_point[:, 0]
    cl = np.array([np.sum(np.linalg.solve(d[i], -1.0 + 1j * k * (-(x - 0.5)) / b)[root]
                          * m.chord[root]) for i, k in enumerate(ks)])
    return ks, cl, theodorsen_pitch_lift(ks, a=0.0)


def fig_theodorsen_check(result=None):
    ks, cl, th = theodorsen_check() if result is None else result
    fig, axes = new_figure("Theodorsen vs asekit DLM (2-D limit, pitch about mid-chord)", ncols=2)
    kk = np.linspace(0.01, 1.2, 200)
    tt = theodorsen_pitch_lift(kk, a=0.0)
    axes[0].plot(kk, np.abs(tt), color=THESIS_COLOR, label="Theodorsen")
    axes[0].plot(ks, np.abs(cl), "o", label="DLM, 12 boxes/chord")
    axes[0].set_xlabel("k = omega b / U")
    axes[0].set_ylabel("|c_l / alpha| (1/rad)")
    axes[1].plot(kk, np.degrees(np.angle(tt)), color=THESIS_COLOR, label="Theodorsen")
    axes[1].plot(ks, np.degrees(np.angle(cl)), "o", label="DLM")
    axes[1].set_xlabel("k = omega b / U")
    axes[1].set_ylabel("phase of c_l / alpha (deg)")
    for ax in axes:
        ax.legend()
    return fig


def _draw_mesh(ax, mesh, values, label, cmap="viridis", vmin=None, vmax=None):
    from matplotlib.collections import PolyCollection
    polys = mesh.corners[:, :, :2] * 1000.0
    pc = PolyCollection(polys, array=np.asarray(values, float), cmap=cmap, edgecolors="k",
                        linewidths=0.4)
    if vmin is not None or vmax is not None:
        pc.set_clim(vmin, vmax)
    ax.add_collection(pc)
    ax.set_xlim(polys[..., 0].min() - 5, polys[..., 0].max() + 5)
    ax.set_ylim(polys[..., 1].min() - 5, polys[..., 1].max() + 5)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm, streamwise)")
    ax.set_ylabel("y (mm, span)")
    ax.figure.colorbar(pc, ax=ax, label=label)


def fig_mesh_bpw(mesh=None, rep=None):
    """Fig 20: the aerodynamic mesh coloured by boxes per wavelength of each strip (Eq. 3.5)."""
    case = fin_case()
    mesh = pipeline.box_mesh(case) if mesh is None else mesh
    rep = check_mesh_rules(mesh, case.aero.u_min, case.aero.f_max, warn=False) if rep is None else rep
    fig, ax = new_figure(f"Aerodynamic mesh - boxes per wavelength (min {rep.bpw.min():.1f}, "
                         "rule >= 15)", "Fig 20", figsize=(6.4, 5.2))
    _draw_mesh(ax, mesh, rep.bpw[mesh.strip], "BPW = U_min / (f_max dx)")
    return fig


def fig_mesh_aspect_ratio(mesh=None, rep=None):
    """Fig 21: the aerodynamic mesh coloured by box aspect ratio."""
    case = fin_case()
    mesh = pipeline.box_mesh(case) if mesh is None else mesh
    rep = check_mesh_rules(mesh, case.aero.u_min, case.aero.f_max, warn=False) if rep is None else rep
    fig, ax = new_figure(f"Aerodynamic mesh - box aspect ratio (max {rep.aspect_ratio.max():.2f}, "
                         "rule < 3)", "Fig 21", figsize=(6.4, 5.2))
    _draw_mesh(ax, mesh, rep.aspect_ratio, "box aspect ratio", cmap="magma", vmin=1.0, vmax=3.0)
    return fig


def fig_steady_pressure(mesh=None, mach: float = STEADY_MACH):
    """Steady Delta Cp per radian of incidence on the fin, and the span loading c_l c / c_ref."""
    case = fin_case()
    mesh = pipeline.box_mesh(case) if mesh is None else mesh
    fig, axes = new_figure(f"Steady pressure jump and span loading, M {mach}, isolated fin vs "
                           "wall at root", ncols=2, figsize=(12.0, 5.0))
    cp = steady_pressure(mesh, mach, -np.ones(mesh.n))
    _draw_mesh(axes[0], mesh, cp, "Delta Cp per rad", cmap="plasma")
    n_strips = mesh.strip.max() + 1
    y = np.array([mesh.load_point[mesh.strip == s, 1].mean() for s in range(n_strips)])
    c_ref = case.panels[0].planform.mean_aerodynamic_chord
    for sym, label in ((False, "isolated"), (True, "wall at root (symmetry plane)")):
        cps = steady_pressure(mesh, mach, -np.ones(mesh.n), symmetric=sym)
        load = np.array([np.sum(cps[mesh.strip == s] * mesh.chord[mesh.strip == s])
                         for s in range(n_strips)])
        axes[1].plot(y * 1000, load / c_ref, "o-", label=label)
    axes[1].set_xlabel("y (mm)")
    axes[1].set_ylabel("c_l c / c_mac per rad")
    axes[1].legend()
    return fig


def fig_gaf_vs_k(db=None, elements=((0, 0), (0, 1), (1, 0), (2, 2))):
    """A few GAF elements (real and imaginary parts) vs k at each Mach of the database."""
    if db is None:
        db = pipeline.gaf_database(fin_case(), progress=False)
    fig, axes = new_figure("GAF elements Q_ij(M, k) of the fin (mode 0 = rigid pitch)",
                           nrows=2, ncols=len(elements), figsize=(3.4 * len(elements), 6.0))
    for j, (r, c) in enumerate(elements):
        for im, mach in enumerate(db.machs):
            q = db.Q[im, :, r, c]
            axes[0, j].plot(db.k, q.real, "o-", ms=3, label=f"M {mach:g}")
            axes[1, j].plot(db.k, q.imag, "o-", ms=3)
        axes[0, j].set_title(f"Q_{r}{c}")
        axes[1, j].set_xlabel("k = omega b / U (b = 0.078 m)")
        axes[0, j].set_ylabel("Re Q")
        axes[1, j].set_ylabel("Im Q")
    axes[0, 0].legend()
    return fig


def convergence(box_counts=((4, 4), (8, 6), (14, 10), (20, 16), (28, 24)), mach=STEADY_MACH):
    """Q_cc (steady, isolated) vs box count, refining both directions: (n_boxes, Q_cc)."""
    n, q = [], []
    for nc, ns in box_counts:
        m = _fin_boxes(n_chord=nc, n_span=ns)
        n.append(m.n)
        q.append(hinge_coefficient(m, mach))
    return np.array(n), np.array(q)


def convergence_by_direction(mach=STEADY_MACH, chordwise=(4, 7, 14, 28), spanwise=(5, 10, 20, 40)):
    """Q_cc refined in one direction at a time around the 14 x 10 fin mesh:
    returns {"chordwise": (counts, Q_cc) at 10 strips, "spanwise": (counts, Q_cc) at 14 boxes
    per chord}."""
    return {"chordwise": (np.array(chordwise),
                          np.array([hinge_coefficient(_fin_boxes(n_chord=c, n_span=10), mach)
                                    for c in chordwise])),
            "spanwise": (np.array(spanwise),
                         np.array([hinge_coefficient(_fin_boxes(n_chord=14, n_span=s), mach)
                                   for s in spanwise]))}


def fig_convergence(result=None, by_direction=None):
    n, q = convergence() if result is None else result
    thesis = thesis_value("aero.Qcc_steady_m3").value
    fig, axes = new_figure("Convergence of the steady hinge-moment coefficient, M 0.6", ncols=2)
    ax = axes[0]
    ax.plot(n, q * 1e4, "o-", label="both directions")
    ax.axhline(thesis * 1e4, color=THESIS_COLOR, ls="--", label="thesis (FlightLoads)")
    ax.set_xscale("log")
    ax.set_xlabel("number of boxes")
    ax.set_ylabel("Re Q_cc (1e-4 m^3 / rad)")
    ax.legend()
    d = convergence_by_direction() if by_direction is None else by_direction
    ax = axes[1]
    ax.plot(d["chordwise"][0], d["chordwise"][1] * 1e4, "o-", label="boxes per chord (10 strips)")
    ax.plot(d["spanwise"][0], d["spanwise"][1] * 1e4, "s-", label="strips (14 boxes per chord)")
    ax.axhline(thesis * 1e4, color=THESIS_COLOR, ls="--", label="thesis")
    ax.set_xscale("log")
    ax.set_xlabel("boxes per chord / number of strips")
    ax.set_ylabel("Re Q_cc (1e-4 m^3 / rad)")
    ax.legend()
    return fig
