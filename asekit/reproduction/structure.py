"""Thesis Ch. 3.1 (structure): normal modes of the fin, FN1 vs FN2, the modal model (Tables 4-6,
Figs 3, 4, 12, 13, 16-19) and asekit's mesh-convergence study of the shaft models.

:func:`compute` runs the analyses, :func:`run` gives the reproduce rows, the ``fig_*`` functions
draw the figures (the chapter notebook ``notebooks/ch3_structure.ipynb`` calls them too).

The thesis's values come from MSC Nastran QUAD4 elements on the same 6 x 7 mesh with the same
single-node shaft; asekit uses MITC4 plate elements, density 2700 kg/m^3 (not given by the
thesis) and the exact spanwise thickness at the integration points. In-plane (membrane)
behaviour is not modelled: it is uncoupled from bending for a flat plate and from the
aerodynamics; the thesis's 16.57 Hz "in-plane bending" mode (its Fig. 16) is the fin turning in
its own plane about the single pinned shaft node, restrained only by the shell element's
artificial drilling stiffness, and the thesis discards it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from asekit.case import pipeline
from asekit.case.schema import Case
from asekit.case.variants import with_mesh, with_modes
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import distributed_case, fin_case, fn1_case
from asekit.reproduction.thesis import thesis_value
from asekit.structure.assembly import rigid_pitch_vector
from asekit.structure.modes import ModalModel, NormalModes, normal_modes
from asekit.util.conventions import mode_label
from asekit.util.plotting import THESIS_COLOR, new_figure

#: Mesh used for the distributed-shaft result (the 5 mm shaft radius of the fin case file is resolved
#: by 23 nodes here; 192 x 224 changes modes 1-2 by a further +0.3 / +1.0 %).
CONVERGED_MESH = (96, 112)
#: Meshes of the convergence study (issue 3: 6x7 up to at least 48x56).
CONVERGENCE_MESHES = ((6, 7), (12, 14), (24, 28), (48, 56), (96, 112))


@dataclass(frozen=True)
class StructureChapter:
    """Every computed Ch. 3.1 result (SI units, frequencies in Hz)."""

    case: Case                      # the reference fin (data/cases/nalci2013_fin.toml)
    fn2: ModalModel                 # thesis model: FN2 6x7 single-node shaft, modes kept
    fn1_modes: NormalModes          # FN1 6x7, 9 modes (Table 4 left column, no in-plane mode)
    fn2_modes: NormalModes          # FN2 6x7 raw eigen-solution, rigid + 9 elastic (Table 4/5)
    J_exact: float                  # exact integral of the pitch inertia (kg m^2)
    distributed: ModalModel         # FN2 with the distributed shaft on CONVERGED_MESH


def compute(case: Case | None = None) -> StructureChapter:
    """Run the Ch. 3.1 analyses on the reference fin (default :func:`fin_case`)."""
    case = fin_case() if case is None else case
    M = pipeline.mass_and_stiffness(case)[1]
    fn1 = normal_modes(pipeline.supported_system(fn1_case(case)), 9, M_fin=M)
    fn2 = normal_modes(pipeline.supported_system(case), 10, M_fin=M)
    return StructureChapter(case=case, fn2=pipeline.modal_model(case), fn1_modes=fn1,
                            fn2_modes=fn2, J_exact=pipeline.pitch_inertia_exact(case),
                            distributed=pipeline.modal_model(
                                distributed_case(*CONVERGED_MESH, case=case)))


def convergence_study(case: Case | None = None, meshes=CONVERGENCE_MESHES,
                      shaft: str = "single_node", radius: float | None = None,
                      n_elastic: int = 5, progress: bool = False) -> np.ndarray:
    """Elastic frequencies (Hz), shape (len(meshes), n_elastic), of the FN2 model per mesh.

    ``shaft``: ``"single_node"`` (the thesis) or ``"distributed"`` (a rigid region of
    ``radius`` m, default :data:`asekit.reproduction.fin.DEFAULT_SHAFT_RADIUS`). Modes above
    1000 Hz are included here (f_max raised to 5000 Hz) so that every mesh gives ``n_elastic``
    values.
    """
    case = fin_case() if case is None else case
    if shaft not in ("single_node", "distributed"):
        raise ValueError(f"shaft must be 'single_node' or 'distributed', got {shaft!r}")
    case = with_modes(case, f_max=5000.0)
    if shaft == "distributed":
        case = distributed_case(radius=radius, case=case)
    iterator = meshes
    if progress:
        from tqdm.auto import tqdm
        iterator = tqdm(meshes, desc=f"{shaft} shaft meshes")
    out = []
    for n_c, n_s in iterator:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")            # unresolved-region warning on coarse meshes
            m = pipeline.modal_model(with_mesh(case, n_c, n_s))
        out.append(m.frequencies_hz[m.n_rigid:m.n_rigid + n_elastic])
    return np.array(out)


def run(figures: bool = False) -> ChapterResult:
    """The reproduce rows of Ch. 3.1 (and figures if asked)."""
    ch = compute()
    f_el = [float(f) for f in ch.fn2.frequencies_hz[ch.fn2.n_rigid:]]
    q = (
        Quantity("structure.frequencies_hz", f_el, "Hz",
                 "MITC4, 6x7, single-node shaft; thesis: Nastran QUAD4 (element, density, point "
                 "support differ; see ch3_structure.ipynb)"),
        Quantity("structure.fn1_frequencies_hz", [float(f) for f in ch.fn1_modes.frequencies_hz[:8]],
                 "Hz", "FN1 6x7, out-of-plane modes (no membrane model)"),
        Quantity("structure.inplane_mode_hz", None, "Hz",
                 "membrane not in the modal model (uncoupled from bending and aerodynamics); "
                 "membrane check: in-plane rotation about the pinned node is 0 Hz without the "
                 "shell's artificial drilling stiffness, so the thesis's mode is an artefact"),
        Quantity("structure.rigid_mode_hz", float(ch.fn2_modes.frequencies_hz[0]), "Hz",
                 "FN2 fictitious-mass eigen-solution (factor 1e6)"),
        Quantity("structure.J_fin_kgm2", float(ch.fn2.J_fin), "kg m^2",
                 "r^T M r of the FE model, density 2700 kg/m^3; thesis value not reproducible "
                 "from its stated geometry"),
        Quantity("structure.J_fin_exact_kgm2", float(ch.J_exact), "kg m^2",
                 "exact integral over the planform"),
        Quantity("structure.distributed_frequencies_hz",
                 [float(f) for f in ch.distributed.frequencies_hz[1:]], "Hz",
                 f"rigid shaft region r={_radius(ch) * 1e3:g} mm, "
                 f"{CONVERGED_MESH[0]}x{CONVERGED_MESH[1]} mesh (192x224: mode 2 +1 %)"),
    )
    figs = {}
    if figures:
        figs = {"fig03_planform": fig_planform(ch.case), "fig04_thickness": fig_thickness(ch.case),
                "fig12_fn1": fig_fe_model(ch.fn2, ch.case, "FN1"),
                "fig16_inplane": fig_inplane(ch.case),
                "fig13_fn2": fig_fe_model(ch.fn2, ch.case, "FN2"),
                "fig17_modes": fig_mode_shapes(ch.fn2),
                "fig18_rigid": fig_rigid_mode(ch),
                "fig19_fn1_fn2": fig_fn1_vs_fn2(ch)}
    return ChapterResult("structure", q, figs)


def _radius(ch: StructureChapter) -> float:
    """The shaft radius (m) of the distributed-shaft result."""
    return float(distributed_case(case=ch.case).support.radius)


# ---- figures -------------------------------------------------------------------------------

def _outline(ax, case: Case, **kw):
    c = case.panels[0].planform.corners
    c = np.vstack([c, c[:1]])
    ax.plot(c[:, 0] * 1e3, c[:, 1] * 1e3, "k-", **kw)


def fig_planform(case: Case):
    """Fig 3: the fin's planform with the shaft axis (mm)."""
    fig, ax = new_figure("Missile control fin planform", "Fig 3", figsize=(5.5, 5))
    _outline(ax, case)
    xa, ya = case.support.axis_point
    ax.axvline(xa * 1e3, color="C3", ls="--", lw=1, label="pitch (shaft) axis")
    ax.plot(xa * 1e3, ya * 1e3, "o", color="C3")
    for x, y in case.panels[0].planform.corners:
        ax.annotate(f"({x * 1e3:.0f}, {y * 1e3:.0f})", (x * 1e3, y * 1e3), fontsize=8,
                    textcoords="offset points", xytext=(4, 4))
    ax.set_xlabel("x, chordwise (mm)")
    ax.set_ylabel("y, spanwise (mm)")
    ax.set_aspect("equal")
    ax.legend(loc="lower right")
    return fig


#: The fin's thickness at the root and tip chords (mm) read off Nalci & Kayran, AIAA 2014-2055,
#: Fig 4 (the thesis's Fig 4 is missing from its text; /work/shared/reference/fin.md): the
#: reference the case file's law is compared against, never an input.
THICKNESS_REFERENCE_MM = {"root": 4.0, "tip": 2.0}


@dataclass(frozen=True)
class ThicknessCheck:
    """The thickness the FE model uses, against the case's law and the exact mass.

    ``root_mm`` / ``tip_mm``: the structural mesh's thickness (mm) averaged over the nodes of the
    root / tip chord (:meth:`asekit.structure.mesh.PlateMesh.thickness_xy`, what the elements
    integrate); ``fe_mass``: the assembled plate mass r^T M r (kg), r the unit translation in w;
    ``exact_mass``: rho * integral over the span of c(y) t_mean(y) h(y) dy (kg), by Simpson's
    rule on the (quadratic, for a linear chord and thickness) integrand, exact here.
    """

    root_mm: float
    tip_mm: float
    fe_mass: float
    exact_mass: float


def thickness_check(case: Case) -> ThicknessCheck:
    """Root/tip thickness and mass of ``case``'s structural model (see :class:`ThicknessCheck`).

    >>> c = thickness_check(fin_case())
    >>> round(c.root_mm, 6), round(c.tip_mm, 6), abs(c.fe_mass / c.exact_mass - 1) < 1e-9
    (4.0, 2.0, True)
    """
    mesh = pipeline.structural_mesh(case)
    x, y = mesh.nodes[:, 0], mesh.nodes[:, 1]
    h = mesh.thickness_xy(x, y)
    root, tip = np.isclose(y, y.min()), np.isclose(y, y.max())
    _, M = pipeline.mass_and_stiffness(case)
    r = np.zeros(M.shape[0])
    r[0::3] = 1.0                                       # w = 1 at every node (w, theta_x, theta_y)
    pf = case.panels[0].planform
    eta = np.linspace(0.0, 1.0, 201)                    # Simpson on 200 intervals
    yy = pf.root_le[1] + eta * pf.span
    f = pf.chord_at(yy) * case.thickness.at(eta) * case.thickness.profile.mean()
    w = np.ones_like(eta)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    exact = case.material.density * pf.span * (eta[1] - eta[0]) / 3.0 * float(w @ f)
    return ThicknessCheck(float(1e3 * h[root].mean()), float(1e3 * h[tip].mean()),
                          float(r @ (M @ r)), float(exact))


def fig_thickness(case: Case):
    """Fig 4: the fin's thickness profile, drawn from the case's thickness law.

    Left: the section thickness h(y) along the span (the law, and the mesh's thickness at the
    element centroids, what each element carries on average) with the root and tip values read
    off Nalci & Kayran (2014), Fig 4. Right: the root and tip sections to scale in z (the
    chordwise profile times h; flat for the thesis's fin), x along the chord (mm).
    """
    fig, (ax, ax2) = new_figure("Fin thickness profile (from the case's thickness law)", "Fig 4",
                                ncols=2, figsize=(11, 4.2))
    pf = case.panels[0].planform
    th = case.thickness
    eta = np.linspace(0, 1, 101)
    y_mm = (pf.root_le[1] + eta * pf.span) * 1e3
    ax.plot(y_mm, th.at(eta) * 1e3, color="C0", label="case thickness law h(y)")
    mesh = pipeline.structural_mesh(case)
    c = mesh.element_centroids()
    ax.plot(c[:, 1] * 1e3, mesh.thickness_xy(c[:, 0], c[:, 1]) * 1e3, "s", ms=4, mfc="none",
            color="C1", label=f"FE mesh, element centroids ({mesh.n_elements} elements)")
    ref_y = [pf.root_le[1] * 1e3, (pf.root_le[1] + pf.span) * 1e3]
    ref_h = [THICKNESS_REFERENCE_MM["root"], THICKNESS_REFERENCE_MM["tip"]]
    ax.plot(ref_y, ref_h, "o", ms=10, mfc="none", mew=1.5, color=THESIS_COLOR,
            label="Nalci & Kayran (2014) Fig 4: root, tip")
    ax.set(xlabel="y, spanwise (mm)", ylabel="thickness h (mm)", ylim=(0, 1.35 * max(ref_h)))
    ax.legend(loc="upper right", fontsize=8)
    xi = np.linspace(0, 1, 201)
    for eta_s, name, col in ((0.0, "root", "C0"), (1.0, "tip", "C2")):
        yy = pf.root_le[1] + eta_s * pf.span
        x_mm = (pf.leading_edge_at(yy) + xi * pf.chord_at(yy)) * 1e3
        half = 0.5 * th.at(eta_s) * th.profile.at(xi) * 1e3
        ax2.fill_between(x_mm, -half, half, color=col, alpha=0.35,
                         label=f"{name} section, y = {yy * 1e3:.0f} mm")
        ax2.plot(x_mm, half, color=col, lw=1)
        ax2.plot(x_mm, -half, color=col, lw=1)
    ax2.set(xlabel="x, chordwise (mm)", ylabel="z, thickness direction (mm)",
            ylim=(-0.9 * max(ref_h), 0.9 * max(ref_h)))
    ax2.set_title(f"chordwise profile: {th.profile.name}", fontsize=9)
    ax2.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def _mesh_lines(ax, model: ModalModel, **kw):
    for e in model.elements:
        p = model.nodes[np.append(e, e[0])] * 1e3
        ax.plot(p[:, 0], p[:, 1], "-", color="0.5", lw=0.7, **kw)


def fig_fe_model(model: ModalModel, case: Case, which: str = "FN1"):
    """Figs 12/13: the 6x7 QUAD mesh, the shaft node, its spring (FN1) or spring + fictitious
    inertia at the free ground point (FN2)."""
    number = "Fig 12" if which == "FN1" else "Fig 13"
    fig, ax = new_figure(f"Finite-element model {which}", number, figsize=(5.5, 5))
    _mesh_lines(ax, model)
    xa, ya = case.support.axis_point
    ax.plot(xa * 1e3, ya * 1e3, "s", color="C3", ms=8, label="shaft node")
    k = case.support.torsional_stiffness
    if which == "FN1":
        text = f"theta_y: spring {k:g} N m/rad to ground"
    else:
        I_f = case.support.fictitious_inertia_factor * model.J_fin
        text = (f"theta_y: spring {k:g} N m/rad to a free ground point\n"
                f"with fictitious inertia {I_f:.3g} kg m^2 (1e6 J_fin)")
    ax.annotate(text, (xa * 1e3, ya * 1e3), xytext=(-60, -45), textcoords="offset points",
                fontsize=8, arrowprops=dict(arrowstyle="->"))
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    ax.set_ylim(-40, 160)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"{model.elements.shape[0]} elements, {model.nodes.shape[0]} nodes", fontsize=9)
    return fig


def _triangles(elements: np.ndarray) -> np.ndarray:
    return np.vstack([elements[:, [0, 1, 2]], elements[:, [0, 2, 3]]])


def fig_mode_shapes(model: ModalModel, title: str = "FN2 mode shapes (w, contours)",
                    thesis_figure: str = "Fig 17"):
    """Fig 17 (and Fig 18's rigid mode): contour plots of w of every mode of the modal model:
    the rigid mode per radian of pitch (m/rad), the elastic modes mass-normalised (w per unit
    modal coordinate, kg^-1/2), numbered as asekit's and as the thesis's Table 6."""
    n = model.frequencies_hz.size
    ncols = 3
    nrows = math.ceil(n / ncols)
    fig, axes = new_figure(title, thesis_figure, nrows=nrows, ncols=ncols,
                           figsize=(12, 3.9 * nrows + 0.8))
    tri = _triangles(model.elements)
    for j, ax in enumerate(np.atleast_1d(axes).flat):
        if j >= n:
            ax.set_visible(False)
            continue
        w = model.shapes[:, 0, j]
        lim = np.abs(w).max()
        cs = ax.tricontourf(model.nodes[:, 0] * 1e3, model.nodes[:, 1] * 1e3, tri, w,
                            levels=np.linspace(-lim, lim, 17), cmap="RdBu_r")
        ax.tricontour(model.nodes[:, 0] * 1e3, model.nodes[:, 1] * 1e3, tri, w, levels=[0.0],
                      colors="k", linewidths=0.8)
        rigid = j < model.n_rigid
        # the thesis numbers its in-plane mode "elastic mode 1", so its out-of-plane modes used
        # (Table 6) are its elastic modes 2-6
        kind = ("rigid pitch, 1 rad" if rigid else
                f"{mode_label(j, model.n_rigid)} (thesis elastic {j - model.n_rigid + 2})")
        ax.set_title(f"{kind}: {model.frequencies_hz[j]:.1f} Hz", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        if j % ncols == 0:                  # one y label per row: no label between neighbours
            ax.set_ylabel("y (mm)")
        cb = fig.colorbar(cs, ax=ax, shrink=0.8, pad=0.03,
                          ticks=np.linspace(-lim, lim, 5),
                          label="w (m/rad)" if rigid else "w (kg$^{-1/2}$)")
        cb.ax.tick_params(labelsize=8)
        cb.ax.yaxis.set_major_formatter(_short_number)
    fig.text(0.5, 0.005, "black line: node line (w = 0); elastic modes mass-normalised, the rigid "
             "mode per radian of pitch", ha="center", va="bottom", fontsize=8)
    fig.subplots_adjust(left=0.06, right=0.96, bottom=0.09, top=0.88, wspace=0.45,
                        hspace=0.35)
    return fig


def _short_number(v, _pos=None) -> str:
    """A colour-bar tick with three significant digits (matplotlib tick formatter)."""
    return f"{v:.3g}"


def fig_rigid_mode(ch: StructureChapter):
    """Fig 18: the rigid-body mode vector from the FN2 eigen-solution vs the analytic unit pitch
    rotation, over the fin's degrees of freedom (the thesis compares Nastran with MATLAB)."""
    modes = ch.fn2_modes
    sys = modes.system
    q = modes.q[:, 0] / modes.q[sys.shaft_index, 0]
    phi = sys.T @ q
    r = rigid_pitch_vector(sys.mesh, ch.case.support.axis_point[0])
    fig, ax = new_figure("Rigid-body mode: FN2 eigenvector vs exact rigid pitch", "Fig 18")
    dof = np.arange(phi.size)
    ax.plot(dof, r, "o", mfc="none", color=THESIS_COLOR, ms=5, label="exact unit pitch rotation")
    ax.plot(dof, phi, ".", ms=3, label="FN2 eigen-solution (scaled to 1 rad)")
    ax.set_xlabel("fin degree of freedom (w, theta_x, theta_y per node)")
    ax.set_ylabel("mode shape (m or rad)")
    ax.legend()
    return fig


def fig_fn1_vs_fn2(ch: StructureChapter, mode: int = 1):
    """Fig 19: an elastic mode of FN1 and FN2 (mass-normalised, 0-based elastic index ``mode``;
    default the second out-of-plane mode, the thesis's "elastic mode 3")."""
    a = ch.fn1_modes.fin[:, mode]
    b = ch.fn2_modes.fin[:, mode + 1]
    b = b * np.sign(a @ b)
    fig, ax = new_figure(f"Elastic {mode_label(mode)}: FN1 vs FN2 "
                         f"({ch.fn1_modes.frequencies_hz[mode]:.2f} Hz)", "Fig 19")
    dof = np.arange(a.size)
    ax.plot(dof, a, "o", mfc="none", color=THESIS_COLOR, ms=5, label="FN1 (spring to ground)")
    ax.plot(dof, b, ".", ms=3, label="FN2 (fictitious inertia)")
    ax.set_title("thesis numbering: elastic mode 3 (its mode 1 is the in-plane mode)", fontsize=9)
    ax.set_xlabel("fin degree of freedom (w, theta_x, theta_y per node)")
    ax.set_ylabel("mass-normalised shape (m/kg^0.5, rad/kg^0.5)")
    ax.legend(title=f"max |difference| = {np.abs(a - b).max():.1e}")
    return fig


def fig_convergence(meshes, single: np.ndarray, distributed: dict, n_modes: int = 2):
    """Mesh convergence of the first elastic frequencies: single-node vs distributed shafts.
    ``distributed`` maps a label (e.g. "r = 5 mm") to an array like ``single``."""
    fig, axes = new_figure("Mesh convergence of the FN2 elastic frequencies", None, ncols=n_modes)
    n_el = [a * b for a, b in meshes]
    thesis = thesis_value("structure.frequencies_hz").value
    for j, ax in enumerate(np.atleast_1d(axes)):
        ax.semilogx(n_el, single[:, j], "o-", label="single-node shaft (thesis model)")
        for k, (lab, arr) in enumerate(distributed.items()):
            ax.semilogx(n_el, arr[:, j], "s-", color=f"C{k + 1}", label=f"distributed, {lab}")
        ax.axhline(thesis[j], color=THESIS_COLOR, ls="--", label="thesis (Nastran 6x7)")
        ax.set_xlabel("number of elements")
        ax.set_ylabel(f"elastic {mode_label(j)} frequency (Hz)")
        ax.set_xticks(n_el)
        ax.set_xticklabels([f"{a}x{b}" for a, b in meshes], rotation=30, fontsize=8)
    np.atleast_1d(axes)[0].legend(fontsize=8)
    return fig


def fig_inplane(case: Case, n_chord: int | None = None, n_span: int | None = None):
    """Fig 16 (the thesis's discarded in-plane mode): asekit's membrane check. In-plane modes of
    the fin held only at the shaft node: the first is a rigid in-plane rotation about that node
    (0 Hz without artificial drilling stiffness), the next a genuine in-plane mode (kHz)."""
    case = with_mesh(case, n_chord, n_span)
    ip = pipeline.inplane_modes(case)
    mesh = pipeline.structural_mesh(case)
    fig, axes = new_figure("In-plane modes with the single-node shaft (membrane check)", "Fig 16",
                           ncols=2, figsize=(11, 4.6))
    for j, ax in enumerate(axes):
        uv = ip.shapes[:, :, j]
        for e in mesh.elements:
            p = mesh.nodes[np.append(e, e[0])] * 1e3
            ax.plot(p[:, 0], p[:, 1], "-", color="0.75", lw=0.6)
        ax.quiver(mesh.nodes[:, 0] * 1e3, mesh.nodes[:, 1] * 1e3, uv[:, 0], uv[:, 1], color="C0")
        xa, ya = case.support.axis_point
        ax.plot(xa * 1e3, ya * 1e3, "s", color="C3", ms=7)
        kind = "in-plane rigid rotation about the shaft node" if j == 0 else "first in-plane elastic mode"
        ax.set_title(f"{kind}: {ip.frequencies_hz[j]:.3g} Hz", fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_aspect("equal")
    return fig
