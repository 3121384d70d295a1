"""Control surfaces in the aeroelastic model: the hinge degree of freedom of a rigid surface
added to a plate's modal model, its inertia and static unbalance, and the static aeroelastic
control effectiveness and reversal.

Hinge mode (MSC Nastran's AESURF with a rigid surface and a hinge spring: Rodden & Johnson,
*MSC/NASTRAN Aeroelastic Analysis User's Guide*, 1994, Sec. 3.5). The wing's modes phi are
computed with the surface locked to the wing (it is part of the plate); each surface adds one
coordinate delta, its rigid rotation about the hinge relative to the wing (trailing edge down
positive, :mod:`asekit.aero.control_surface`). The displacement of the structure is the Ritz
expansion u = Phi zeta + U_f delta, with U_f the surface's rigid rotation on the finite-element
degrees of freedom (w = -d, theta_x = dw/dy, theta_y = -dw/dx; d the distance aft of the
hinge), so that the modal mass, stiffness and damping are

    M = [[M_ww, Phi^T M_fe U_f], [U_f^T M_fe Phi, U_f^T M_fe U_f]] + balance masses,
    K = diag(K_ww, k_h),   C = diag(C_ww, c_h),

with k_h the hinge spring (N m/rad) and c_h the hinge damper (N m s/rad): the surface's own
bending is the wing's (the plate's stiffness ties it to the wing in the locked modes), its
rotation relative to the wing is resisted by the hinge spring only. The surface's inertia about
its hinge is I_h = U_f^T M_fe U_f and its static unbalance S_h = sum m d (kg m, > 0 when the
centre of mass lies aft of the hinge, the classic flutter-prone case). A balance mass m_b at
(x_b, y_b) on the surface (usually ahead of the hinge, d_b < 0) moves by
phi(x_b, y_b) zeta - d_b delta and adds its mass to every block.

The aerodynamic box modes are the wing's (splined) and the deflections of
:func:`asekit.aero.control_surface.deflection_modes`, side by side, so the GAFs and the p-k
method (:mod:`asekit.aeroelastic.flutter`) take the surface as one more mode.

Static aeroelasticity (Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955, Sec. 8-4): with
the deflection held (an irreversible actuator), the wing's steady response to delta is
(K_ww - q Q_ww(0)) zeta = q Q_wd(0) delta; the flexible rolling moment (or lift) is the rigid
one plus that of zeta, and the reversal dynamic pressure q_R is where it crosses zero.

Strip theory (a uniform wing, elastic axis e chords behind the aerodynamic centre) reverses
only when the deflection's moment about the elastic axis is nose-down, e c_l,delta + c_m,delta
< 0 (for a 25 % flap, e < 0.17 with the thin-airfoil c_l,delta = 3.83, c_m,delta = -0.65); a
flat plate (e = 0.25) would gain effectiveness up to divergence. The lifting surface moves the
deflection's centre of pressure aft as the effective aspect ratio falls, so a plate wing can
reverse all the same: measured on the 0.3 m x 1.2 m aluminium plate of the examples, a
full-span 25 % flap with the symmetric image (aspect ratio 8) gains lift up to divergence as
strip theory says, while the same wing alone or loaded antisymmetrically (rolling) reverses
just below divergence (q_R = 477-488 Pa against q_D = 515-540 Pa).

Elastic surfaces (``kind = "elastic"``, :func:`elastic_flap_modal_model`): the plate region
released along its hinge (:mod:`asekit.structure.hinge`) reduced by Craig & Bampton's method,
the hinge rotation the interface coordinate. The rigid kind above is that reduction with the
locked plate's modes for the fixed-interface modes and a prescribed rigid rotation (lumped at
the hinge line) for the constraint mode; the elastic kind computes both from the released
plate, so the surface's inertia and unbalance are its elements' exactly and its side edges are
free.

Rigid and elastic surfaces in one model (:func:`mixed_flap_modal_model`): the elastic ones
released and reduced as above, the rigid ones' hinge rotations added as the rigid kind's, every
hinge coordinate coupled to the others through the mass. Linked surfaces (Nastran's AELINK, a
geared tab delta_t = G delta_f: :func:`link_surfaces`) are eliminated by the gearing
transformation.

The strip-theory closed forms are :func:`strip_theory_effectiveness` and
:func:`strip_theory_reversal_q`; on a uniform torsion beam with its elastic axis 5 % of the chord
behind the quarter chord, the vortex lattice's q_R tends to them as the aspect ratio grows
(+7 % at aspect ratio 10, -0.3 % at 40: tests/aeroelastic/test_reversal_strip_theory.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import linalg
from scipy.optimize import brentq

from asekit.aero.control_surface import HingedMesh, deflection_modes, nesting
from asekit.aero.spline import BoxModes, fe_spline
from asekit.aeroelastic.statespace import ModalArrays
from asekit.structure.modes import mode_shapes_at
from asekit.util.validate import in_range, integer, positive


@dataclass(frozen=True)
class BalanceMass:
    """A concentrated mass (kg) at (x, y) (m) fixed to control surface ``surface`` (index),
    moving with the wing and with the surface's rotation (a mass balance when ahead of the
    hinge)."""

    surface: int
    x: float
    y: float
    mass: float

    def __post_init__(self):
        object.__setattr__(self, "mass", positive("mass", self.mass))


@dataclass(frozen=True)
class FlapModel:
    """A wing's modal model with hinge coordinates.

    ``modal`` the :class:`ModalArrays` (wing modes first, in the wing model's order and with its
    ``n_rigid``, then one coordinate per surface); ``box_modes`` the matching
    :class:`BoxModes`; ``inertia`` (n_s,) about each hinge (kg m^2) and ``static_unbalance``
    (n_s,) (kg m, > 0 centre of mass aft of the hinge), balance masses included;
    ``hinge_frequency_hz`` (n_s,) sqrt(k_h / I_h) / 2 pi, the uncoupled hinge frequency;
    ``n_wing`` the wing's modes; ``names`` of the surfaces.
    """

    modal: ModalArrays
    box_modes: BoxModes
    inertia: np.ndarray
    static_unbalance: np.ndarray
    hinge_frequency_hz: np.ndarray
    n_wing: int
    names: tuple

    @property
    def hinge_mass_matrix(self) -> np.ndarray:
        """(n_s, n_s) the hinge coordinates' block of the modal mass (kg m^2): the inertias on
        its diagonal, the surfaces' inertial coupling off it (M_jk = Psi_j^T M Psi_k, nonzero
        when two surfaces share nodes or a balance mass)."""
        return np.array(self.modal.M, float)[self.n_wing:, self.n_wing:]


def flap_rotation_vector(nodes: np.ndarray, hm: HingedMesh, index: int) -> np.ndarray:
    """Unit rigid rotation (1 rad, trailing edge down) of surface ``index`` on the
    finite-element degrees of freedom (w, theta_x, theta_y per node; ``nodes`` (n, 2) m):
    w = -d, theta_x = dw/dy, theta_y = -dw/dx on the nodes aft of the hinge line inside the
    surface's span, zero elsewhere. Nodes on the hinge line (|d| below 1e-9 of the chord)
    carry half the rotation: their mass is shared by the wing and the surface (the lumped
    view of a node on the cut; the structural mesh should have a line on the hinge).

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 1.0, (0, 2.0), 1.0, 4, 2),
    ...                  ControlSurface("f", 0.5, 0.5))
    >>> flap_rotation_vector(np.array([[0.25, 1.0], [0.5, 1.0], [1.0, 1.0]]), hm, 0).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.5, -0.5, 0.0, 1.0]
    """
    p = np.column_stack([np.asarray(nodes, float), np.zeros(len(nodes))])
    d = hm.distance_aft(index, p)
    s = hm.hinge_axis[index]
    tol = 1e-9 * (float(np.ptp(hm.mesh.corners[:, :, 0])) + 1e-300)
    along = (p - hm.hinge_point[index]) @ s            # position along the hinge line
    inside = (along >= -tol) & (along <= _hinge_length(hm, index) + tol)
    weight = np.where(d > tol, 1.0, np.where(d > -tol, 0.5, 0.0)) * inside
    u = np.zeros(3 * len(p))
    u[0::3] = -np.maximum(d, 0.0) * weight + 0.0          # no -0.0
    u[1::3] = s[0] / np.hypot(s[0], s[1]) * weight       # dw/dy = s_x (w = -d)
    u[2::3] = s[1] / np.hypot(s[0], s[1]) * weight       # -dw/dx = cos(Lambda_h)
    return u


def _hinge_length(hm: HingedMesh, index: int) -> float:
    m = hm.on_surface[index]
    c = hm.mesh.corners[m]
    pts = np.concatenate([c[:, 0], c[:, 3]])
    return float(np.max((pts - hm.hinge_point[index]) @ hm.hinge_axis[index]))


def flap_modal_model(model, M_fe, hm: HingedMesh, hinge_stiffness, hinge_damping=0.0,
                     balance=()) -> FlapModel:
    """The wing's modal model with one hinge coordinate per control surface (module docstring).

    Parameters
    ----------
    model : :class:`asekit.structure.modes.ModalModel` of the wing, the surfaces locked.
    M_fe : (3 n_nodes, 3 n_nodes) finite-element mass matrix (kg, kg m, kg m^2 blocks) of the
        same mesh, unsupported (:func:`asekit.case.pipeline.mass_and_stiffness`).
    hm : the boxes with the surfaces (:func:`asekit.aero.control_surface.hinged_mesh`) in the
        plate's plane.
    hinge_stiffness : k_h per surface (N m/rad, >= 0; scalar or one per surface).
    hinge_damping : c_h per surface (N m s/rad, >= 0).
    balance : :class:`BalanceMass` items; one on a tab (a surface nested in a flap,
        :func:`asekit.aero.control_surface.nesting`) moves with the flap's rotation too.

    A tab's rotation vector is its own rotation about its hinge; the flap's includes the tab's
    nodes (aft of the flap's hinge), so the hinge block of M couples the two through the tab's
    mass, M_ft = sum m d_f d_t.

    Returns
    -------
    FlapModel

    Examples
    --------
    A clamped 0.3 m x 1.2 m, 2 mm aluminium plate with a 25 % aileron on its outboard half:
    the uniform plate flap of 0.243 kg has S = m c_f / 2 = 9.1 g m and I = m c_f^2 / 3 =
    0.46 g m^2 (the finite-element mass: 9.7 and 0.47).

    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> from asekit.structure.modes import fixed_modal_model
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> K, M = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> model = fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=4)
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> fm = flap_modal_model(model, M, hm, 0.5)
    >>> round(1e3 * float(fm.static_unbalance[0]), 2), round(1e3 * float(fm.inertia[0]), 3)
    (9.68, 0.475)
    """
    n_s = len(hm.surfaces)
    k_h = np.broadcast_to(np.asarray(hinge_stiffness, float), (n_s,)).copy()
    c_h = np.broadcast_to(np.asarray(hinge_damping, float), (n_s,)).copy()
    for nm, v in (("hinge_stiffness", k_h), ("hinge_damping", c_h)):
        for x in v:
            in_range(nm, x, 0.0, inclusive=True)
    parents = nesting(hm.surfaces)
    nodes = np.asarray(model.nodes, float)
    phi = np.asarray(model.shapes, float).reshape(3 * len(nodes), -1)
    uf = np.column_stack([flap_rotation_vector(nodes, hm, i) for i in range(n_s)])
    basis = np.hstack([phi, uf])
    n_w = phi.shape[1]
    M = np.array(model.M, float)
    mu = basis.T @ (M_fe @ uf)                                   # (n_w + n_s, n_s)
    m_aug = np.zeros((n_w + n_s, n_w + n_s))
    m_aug[:n_w, :n_w] = M
    m_aug[:, n_w:] = mu
    m_aug[n_w:, :n_w] = mu[:n_w].T
    w_unit = np.zeros(3 * len(nodes))
    w_unit[0::3] = 1.0
    unbalance = -(w_unit @ (M_fe @ uf))                          # sum m d
    inertia = np.diag(mu[n_w:]).copy()
    for bm in balance:
        if not isinstance(bm, BalanceMass) or not 0 <= bm.surface < n_s:
            raise ValueError(f"balance must hold BalanceMass items with surface in [0, "
                             f"{n_s - 1}], got {bm!r}")
        h, _ = mode_shapes_at(model, np.array([[bm.x, bm.y]]))
        d = float(hm.distance_aft(bm.surface, np.array([[bm.x, bm.y, 0.0]]))[0])
        v = np.zeros(n_w + n_s)
        v[:n_w] = h[0]
        v[n_w + bm.surface] = -d
        if parents[bm.surface] >= 0:        # a tab's mass rides on its flap as well
            p = parents[bm.surface]
            d_p = float(hm.distance_aft(p, np.array([[bm.x, bm.y, 0.0]]))[0])
            v[n_w + p] = -d_p
            unbalance[p] += bm.mass * d_p
            inertia[p] += bm.mass * d_p * d_p
        m_aug += bm.mass * np.outer(v, v)
        unbalance[bm.surface] += bm.mass * d
        inertia[bm.surface] += bm.mass * d * d
    k_aug = np.zeros_like(m_aug)
    k_aug[:n_w, :n_w] = model.K
    k_aug[n_w:, n_w:] = np.diag(k_h)
    c_aug = np.zeros_like(m_aug)
    c_aug[:n_w, :n_w] = model.C
    c_aug[n_w:, n_w:] = np.diag(c_h)
    wing = fe_spline(model, hm.mesh)
    flap = deflection_modes(hm)
    box = BoxModes(np.hstack([wing.h_cp, flap.h_cp]), np.hstack([wing.dhdx_cp, flap.dhdx_cp]),
                   np.hstack([wing.h_lp, flap.h_lp]))
    f_h = np.sqrt(k_h / inertia) / (2.0 * math.pi)
    return FlapModel(ModalArrays(m_aug, k_aug, c_aug, int(model.n_rigid)), box, inertia,
                     unbalance, f_h, n_w, tuple(s.name for s in hm.surfaces))


def surface_elements(mesh, hm: HingedMesh, index: int) -> np.ndarray:
    """(n_elem,) bool, the plate elements of control surface ``index``: those whose centroid
    lies aft of its hinge line and inside its span. Raises ValueError unless they cover the
    surface exactly (their area equals the surface's box area S_f to 1e-9): the structural
    mesh must have element lines on the hinge line and on the side edges.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Planform, Thickness
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> int(surface_elements(pm, hm, 0).sum())                   # 2 chordwise x 8 spanwise
    16
    """
    c = mesh.element_centroids()
    p = np.column_stack([c, np.zeros(len(c))])
    along = (p - hm.hinge_point[index]) @ hm.hinge_axis[index]
    inside = (hm.distance_aft(index, p) > 0) & (along > 0) & (along < _hinge_length(hm, index))
    xy = mesh.nodes[mesh.elements]                                   # (n_elem, 4, 2)
    area = 0.5 * np.abs(np.sum(xy[:, :, 0] * np.roll(xy[:, :, 1], -1, 1)
                               - np.roll(xy[:, :, 0], -1, 1) * xy[:, :, 1], axis=1))
    s_f = hm.surface_area(index)
    if abs(float(area[inside].sum()) - s_f) > 1e-9 * s_f:
        raise ValueError(f"the plate elements of surface {hm.surfaces[index].name!r} cover "
                         f"{float(area[inside].sum()):.6g} m^2, not its {s_f:.6g} m^2: the "
                         f"structural mesh needs element lines on its hinge line and side edges")
    return inside


def elastic_flap_modal_model(released, M_split, hm: HingedMesh, n_modes: int,
                             modal_damping_ratio=None, structural_g=None,
                             dense_limit: int = 3000) -> FlapModel:
    """The modal model of a wing with one or several elastic control surfaces
    (``kind = "elastic"``): the plate released along the hinges
    (:func:`asekit.structure.hinge.release_hinge`, a ``"single"`` release, or
    :func:`asekit.structure.hinge.release_hinges` for several side-by-side surfaces) reduced by
    Craig & Bampton's method ("Coupling of substructures for dynamic analyses", AIAA J. 6(7),
    1968, Eqs. 5-9) with the hinge rotations delta_k as the interface coordinates:

        u = Phi zeta + sum_k psi_k delta_k,

    Phi the ``n_modes`` lowest modes with every delta held (mass-normalised) and psi_k the
    constraint modes (:func:`asekit.structure.hinge.hinge_constraint_modes`, surface k's static
    rotation about its hinge with the other surfaces held). M = B^T M_r B, K = B^T K_r B (the
    Phi-Psi stiffness coupling vanishes: K_oo Psi_o + K_oR = 0), C the hinge dampers plus the
    wing modes' damping; the surfaces' inertial coupling is M's hinge block off its diagonal
    (:attr:`FlapModel.hinge_mass_matrix`). The coordinate
    delta is the hinge's relative rotation, so the hinge moment of the spring is k_h delta, as
    for the rigid kind (:func:`flap_modal_model`), whose model is this one with Phi the locked
    plate's modes and psi the prescribed rigid rotation.

    Parameters
    ----------
    released : :class:`asekit.structure.hinge.ReleasedHinge` of the supported wing.
    M_split : the unreduced mass matrix of ``released.split.mesh`` (for the static unbalance).
    hm : the boxes with the surfaces (:func:`asekit.aero.control_surface.hinged_mesh`), in
        the order of ``released.splits``.
    n_modes : fixed-interface modes kept (>= 1).
    modal_damping_ratio, structural_g : the wing modes' damping
        (:func:`asekit.structure.modes.with_damping`).
    dense_limit : the fixed-hinge modes by a dense eigen-solution up to this many reduced
        DOFs, beyond it by shift-invert Lanczos about 0 (the supported wing has no rigid mode).

    Returns
    -------
    FlapModel (its box modes splined from the structure, :func:`asekit.aero.spline.fe_spline`,
    for the wing modes and for psi alike).

    Examples
    --------
    :func:`flap_modal_model`'s wing with the aileron's plate released along its hinge: the
    exact plate strip of 0.243 kg has S = m c_f / 2 = 9.1 g m and I = m c_f^2 / 3 = 0.456 g m^2
    (the rigid kind's lumped hinge line gives 9.7 and 0.475).

    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.hinge import release_hinge, split_at_hinge
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> hs = split_at_hinge(pm, surface_elements(pm, hm, 0), (0.225, 0.6), (0.0, 1.0))
    >>> K, M = assemble(hs.mesh, Material(70e9, 0.3, 2700.0))
    >>> K0, M0 = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinge(hs, K, M, 0.5, support=clamped_edge(pm, K0, M0).T)
    >>> fm = elastic_flap_modal_model(rh, M, hm, 4)
    >>> round(1e3 * float(fm.static_unbalance[0]), 2), round(1e3 * float(fm.inertia[0]), 3)
    (9.11, 0.456)
    """
    n_s = len(hm.surfaces)
    if released.hinge_index.size != n_s or (n_s > 1 and len(released.splits) != n_s):
        raise ValueError(f"elastic_flap_modal_model needs one 'single' hinge release per "
                         f"surface ({n_s} surfaces, {released.hinge_index.size} hinge "
                         f"rotations)")
    cb = _craig_bampton(released, n_modes, modal_damping_ratio, structural_g, dense_limit)
    n = cb.wing.M.shape[0]
    flap = replace(cb.wing, frequencies_hz=np.zeros(n_s), M=np.eye(n_s), K=np.zeros((n_s, n_s)),
                   C=np.zeros((n_s, n_s)), shapes=cb.shapes[:, :, n:])
    bw, bf = fe_spline(cb.wing, hm.mesh), fe_spline(flap, hm.mesh)
    box = BoxModes(np.hstack([bw.h_cp, bf.h_cp]), np.hstack([bw.dhdx_cp, bf.dhdx_cp]),
                   np.hstack([bw.h_lp, bf.h_lp]))
    split = released.split.mesh
    u_psi = released.T @ cb.psi
    w_unit = np.zeros(3 * split.n_nodes)
    w_unit[0::3] = 1.0
    inertia = np.diag(cb.M[n:, n:]).copy()
    unbalance = -(w_unit @ (M_split @ u_psi))
    k_h = np.asarray(released.hinge_stiffness, float)
    f_h = np.sqrt(k_h / inertia) / (2.0 * math.pi)
    return FlapModel(ModalArrays(cb.M, cb.K, cb.C, 0), box, inertia, unbalance, f_h,
                     n, tuple(s.name for s in hm.surfaces))


@dataclass(frozen=True)
class _Reduction:
    """Craig & Bampton's reduction of a released plate (:func:`_craig_bampton`): ``M``, ``K``,
    ``C`` over (zeta, delta); ``psi`` the constraint modes on the released DOFs; ``shapes``
    (n_nodes, 3, n + n_e) every column on the split mesh; ``wing`` the fixed-hinge modes as a
    :class:`asekit.structure.modes.ModalModel` (damped)."""

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    psi: np.ndarray
    shapes: np.ndarray
    wing: object


def _craig_bampton(released, n_modes, modal_damping_ratio, structural_g,
                   dense_limit) -> _Reduction:
    """The reduction of :func:`elastic_flap_modal_model` (its docstring), without the boxes."""
    from asekit.structure.hinge import hinge_constraint_modes
    from asekit.structure.modes import ModalModel, with_damping

    n_modes = integer("n_modes", n_modes, low=1)
    n_s = released.hinge_index.size
    R = np.asarray(released.hinge_index)
    o = np.setdiff1d(np.arange(released.K.shape[0]), R)
    K_oo, M_oo = released.K[o][:, o], released.M[o][:, o]
    if o.size <= dense_limit:
        lam, phi_o = linalg.eigh(K_oo.toarray(), M_oo.toarray(), subset_by_index=[0, n_modes - 1])
    else:
        from scipy.sparse.linalg import eigsh

        lam, phi_o = eigsh(K_oo.tocsc(), k=n_modes, M=M_oo.tocsc(), sigma=0.0, which="LM")
        order = np.argsort(lam)
        lam, phi_o = lam[order], phi_o[:, order]
        phi_o = phi_o / np.sqrt(np.einsum("im,im->m", phi_o, M_oo @ phi_o))
    psi = hinge_constraint_modes(released)
    n = n_modes
    basis = np.zeros((released.K.shape[0], n + n_s))
    basis[o, :n] = phi_o
    basis[:, n:] = psi
    m_aug = basis.T @ (released.M @ basis)
    k_aug = basis.T @ (released.K @ basis)
    # Craig-Bampton: the fixed-interface modes and the constraint modes are K-orthogonal
    # (K_oo Psi_o + K_oR = 0); what is left is the solver's round-off, removed here so that the
    # hinge rows couple to nothing but through the mass (as the rigid kind's)
    coupling = float(np.max(np.abs(k_aug[:n, n:])))
    if coupling > 1e-6 * float(np.max(np.abs(np.diag(k_aug)))):
        raise ValueError(f"the hinge constraint mode is not K-orthogonal to the fixed-hinge "
                         f"modes (coupling {coupling:.3g}): the released system is ill-posed")
    k_aug[:n, n:] = 0.0
    k_aug[n:, :n] = 0.0
    c_aug = basis.T @ (released.C @ basis)
    split = released.split.mesh
    shapes = (released.T @ basis).reshape(split.n_nodes, 3, n + n_s)
    f_hz = np.sqrt(np.maximum(lam, 0.0)) / (2.0 * math.pi)
    wing = ModalModel(f_hz, np.eye(n), np.diag(lam), np.zeros((n, n)), 0,
                      math.nan, split.nodes, shapes[:, :, :n], split.elements,
                      f"{split.n_elements}-element plate, hinge released")
    wing = with_damping(wing, modal_damping_ratio, structural_g)
    c_aug[:n, :n] += wing.C
    return _Reduction(m_aug, k_aug, c_aug, psi, shapes, wing)


def mixed_flap_modal_model(released, M_split, hm: HingedMesh, kinds, n_modes: int,
                           hinge_stiffness, hinge_damping=0.0, balance=(),
                           modal_damping_ratio=None, structural_g=None,
                           dense_limit: int = 3000) -> FlapModel:
    """The modal model of a wing with rigid and elastic control surfaces in one model (an
    elastic aileron inboard and a rigid one outboard).

    The elastic surfaces are released along their hinges and reduced by Craig & Bampton's
    method exactly as in :func:`elastic_flap_modal_model` (AIAA J. 6(7), 1968, Eqs. 5-9:
    fixed-hinge modes Phi and constraint modes psi_k of the released plate, in which the rigid
    surfaces are part of the plate); each rigid surface j adds its rigid rotation U_j about its
    hinge as the rigid kind builds it (:func:`flap_rotation_vector`, on the split mesh's nodes
    by their coordinates, so that a node on the rigid surface's edge rotates with it as in
    :func:`flap_modal_model`; Rodden & Johnson 1994, Sec. 3.5). With B = [Phi, Psi, U] on the
    finite-element DOFs (u = B x),

        M = [[M_cb, Phi_Psi^T M_fe U], [U^T M_fe Phi_Psi, U^T M_fe U]] + balance masses,
        K = diag(K_cb, k_h,j),   C = diag(C_cb, c_h,j),

    M_cb, K_cb, C_cb the Craig-Bampton blocks (:func:`elastic_flap_modal_model`), M_fe the
    split mesh's mass: every pair of hinge coordinates is coupled through the mass
    (:attr:`FlapModel.hinge_mass_matrix`), the rigid rotations through the hinge springs only
    (the rigid kind's assumption). A rigid surface's inertia U_j^T M_fe U_j and unbalance are
    those of :func:`flap_modal_model` on the unsplit mesh (the split only duplicates nodes:
    M_unsplit = S^T M_fe S for the duplication S, and U_j = S U_j,unsplit).

    Parameters
    ----------
    released : :class:`asekit.structure.hinge.ReleasedHinge` of the supported wing, the
        elastic surfaces released (:func:`asekit.structure.hinge.release_hinges`, in their
        order in ``hm``), their springs and dampers in it.
    M_split : the unreduced mass matrix of ``released.split.mesh`` (point masses and the
        elastic surfaces' balance masses included).
    hm : the boxes with every surface, rigid and elastic, in case order.
    kinds : "rigid" or "elastic" per surface of ``hm``.
    n_modes : fixed-hinge modes kept (>= 1).
    hinge_stiffness, hinge_damping : k_h (N m/rad) and c_h (N m s/rad) per surface of ``hm``
        (scalar or one per surface; used for the rigid surfaces).
    balance : :class:`BalanceMass` items on the rigid surfaces (index in ``hm``): a mass at
        (x_b, y_b) moves with the wing's columns at that point and by -d_b with its surface.
    modal_damping_ratio, structural_g, dense_limit : as :func:`elastic_flap_modal_model`.

    Returns
    -------
    FlapModel : the wing's fixed-hinge modes, then one hinge coordinate per surface in the
    order of ``hm``; box modes the splined structure for the wing modes and the elastic
    surfaces' psi, :func:`asekit.aero.control_surface.deflection_modes` for the rigid ones.

    Examples
    --------
    The aluminium plate wing of :func:`flap_modal_model`, an elastic aileron over 50-75 % of
    the span and a rigid one over 75-100 %. The rigid aileron's 0.3 m plate strip has
    S = m c_f / 2 = 4.56 g m and I = m c_f^2 / 3 = 0.228 g m^2 (m = 0.1215 kg); its rigid
    rotation lumps the hinge nodes half and the edge nodes whole, as :func:`flap_modal_model`
    on the unsplit mesh, and gives 5.13 g m and 0.247 g m^2.

    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.hinge import release_hinge, split_at_hinge
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  [ControlSurface("in", 0.75, 0.75, 0.5, 0.75),
    ...                   ControlSurface("out", 0.75, 0.75, 0.75, 1.0)])
    >>> hs = split_at_hinge(pm, surface_elements(pm, hm, 0), (0.225, 0.6), (0.0, 1.0))
    >>> K, M = assemble(hs.mesh, Material(70e9, 0.3, 2700.0))
    >>> K0, M0 = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinge(hs, K, M, 0.25, support=clamped_edge(pm, K0, M0).T)
    >>> fm = mixed_flap_modal_model(rh, M, hm, ("elastic", "rigid"), 4, 0.25)
    >>> fm.names, fm.hinge_mass_matrix.shape
    (('in', 'out'), (2, 2))
    >>> round(1e3 * float(fm.static_unbalance[1]), 2), round(1e3 * float(fm.inertia[1]), 3)
    (5.13, 0.247)
    """
    kinds = tuple(kinds)
    n_s = len(hm.surfaces)
    if len(kinds) != n_s or any(k not in ("rigid", "elastic") for k in kinds):
        raise ValueError(f"kinds must give 'rigid' or 'elastic' for each of the {n_s} "
                         f"surfaces, got {kinds}")
    el = [i for i, k in enumerate(kinds) if k == "elastic"]
    rg = [i for i, k in enumerate(kinds) if k == "rigid"]
    if released.hinge_index.size != len(el) or (len(el) > 1 and len(released.splits) != len(el)):
        raise ValueError(f"mixed_flap_modal_model needs one 'single' hinge release per elastic "
                         f"surface ({len(el)} elastic, {released.hinge_index.size} hinge "
                         f"rotations)")
    k_h = np.broadcast_to(np.asarray(hinge_stiffness, float), (n_s,)).copy()
    c_h = np.broadcast_to(np.asarray(hinge_damping, float), (n_s,)).copy()
    for nm, v in (("hinge_stiffness", k_h), ("hinge_damping", c_h)):
        for x in v:
            in_range(nm, x, 0.0, inclusive=True)
    cb = _craig_bampton(released, n_modes, modal_damping_ratio, structural_g, dense_limit)
    n, n_e = cb.wing.M.shape[0], len(el)
    split = released.split.mesh
    u_cb = cb.shapes.reshape(3 * split.n_nodes, n + n_e)
    u_r = np.column_stack([flap_rotation_vector(split.nodes, hm, j) for j in rg]) if rg \
        else np.zeros((3 * split.n_nodes, 0))
    mu = np.hstack([u_cb, u_r]).T @ (M_split @ u_r)            # (n + n_s, n_r)
    m = np.zeros((n + n_s, n + n_s))
    m[:n + n_e, :n + n_e] = cb.M
    m[:, n + n_e:] = mu
    m[n + n_e:, :n + n_e] = mu[:n + n_e].T
    k = np.zeros_like(m)
    k[:n + n_e, :n + n_e] = cb.K
    k[n + n_e:, n + n_e:] = np.diag(k_h[rg])
    c = np.zeros_like(m)
    c[:n + n_e, :n + n_e] = cb.C
    c[n + n_e:, n + n_e:] = np.diag(c_h[rg])
    w_unit = np.zeros(3 * split.n_nodes)
    w_unit[0::3] = 1.0
    unbalance = -(w_unit @ (M_split @ np.hstack([u_cb[:, n:], u_r])))
    col = {j: n + p for p, j in enumerate(el + rg)}              # surface -> its column
    _mixed_balance(m, unbalance, balance, hm, cb, col, kinds)
    order = np.r_[np.arange(n), [col[j] for j in range(n_s)]].astype(int)
    m, k, c = (a[np.ix_(order, order)] for a in (m, k, c))
    unbalance = unbalance[order[n:] - n]
    inertia = np.diag(m[n:, n:]).copy()
    k_all = np.array([released.hinge_stiffness[el.index(j)] if kinds[j] == "elastic"
                      else k_h[j] for j in range(n_s)], float)
    flap = replace(cb.wing, frequencies_hz=np.zeros(n_e), M=np.eye(n_e), K=np.zeros((n_e, n_e)),
                   C=np.zeros((n_e, n_e)), shapes=cb.shapes[:, :, n:])
    bw, be, br = fe_spline(cb.wing, hm.mesh), fe_spline(flap, hm.mesh), deflection_modes(hm)
    cols = [np.hstack([getattr(bw, a)] + [getattr(be, a)[:, [el.index(j)]]
                                          if kinds[j] == "elastic" else getattr(br, a)[:, [j]]
                                          for j in range(n_s)])
            for a in ("h_cp", "dhdx_cp", "h_lp")]
    f_h = np.sqrt(k_all / inertia) / (2.0 * math.pi)
    return FlapModel(ModalArrays(m, k, c, 0), BoxModes(*cols), inertia, unbalance, f_h, n,
                     tuple(s.name for s in hm.surfaces))


def _mixed_balance(m, unbalance, balance, hm, cb, col, kinds) -> None:
    """Add the rigid surfaces' balance masses to ``m`` and ``unbalance`` in place
    (:func:`mixed_flap_modal_model`: a point mass moving with the wing's and the elastic
    surfaces' columns at its point and by -d_b with its rigid surface, and with its parent's
    rotation when the surface is a tab; ``col`` each surface's column in ``m``)."""
    n_s = len(kinds)
    if not balance:
        return
    parents = nesting(hm.surfaces)
    everything = replace(cb.wing, shapes=cb.shapes)
    n_cb = cb.shapes.shape[2]
    n = cb.wing.M.shape[0]
    for bm in balance:
        if not isinstance(bm, BalanceMass) or not 0 <= bm.surface < n_s \
                or kinds[bm.surface] != "rigid":
            raise ValueError(f"balance must hold BalanceMass items on rigid surfaces (index in "
                             f"[0, {n_s - 1}]), got {bm!r}")
        h, _ = mode_shapes_at(everything, np.array([[bm.x, bm.y]]))
        v = np.zeros(m.shape[0])
        v[:n_cb] = h[0]
        for j in (bm.surface, parents[bm.surface]):
            if j < 0:
                continue
            d = float(hm.distance_aft(j, np.array([[bm.x, bm.y, 0.0]]))[0])
            v[col[j]] = -d
            unbalance[col[j] - n] += bm.mass * d
        m += bm.mass * np.outer(v, v)


def link_surfaces(fm: FlapModel, links) -> FlapModel:
    """The model with linked hinge coordinates (MSC Nastran's AELINK; a geared tab,
    delta_tab = G delta_flap): x = T_x x_free with T_x = diag(I, T) and T the surfaces'
    gearing matrix (:func:`asekit.aero.control_surface.gearing_matrix`), so that
    M' = T_x^T M T_x, K' = T_x^T K T_x, C' = T_x^T C T_x (the kinetic and strain energies of
    the constrained motion; Cook, Malkus, Plesha & Witt, 2002, Sec. 9.2) and the box modes
    B' = B T_x (a free surface's column carries its slaves' deflections, G times theirs).

    The free surfaces' inertia is the linked motion's, I' = I_m + 2 G M_ms + G^2 I_s, their
    unbalance S' = S_m + G S_s, their hinge stiffness k' = k_m + G^2 k_s (a slave's own
    hinge spring, if any, is strained by the gearing), ``names`` the free surfaces'.

    Examples
    --------
    Two uncoupled unit hinges, the second geared to the first by G = 2:

    >>> from asekit.aero.spline import BoxModes
    >>> from asekit.aeroelastic.statespace import ModalArrays
    >>> z = np.zeros((1, 3))
    >>> fm = FlapModel(ModalArrays(np.eye(3), np.diag([1.0, 4.0, 0.0]), np.zeros((3, 3)), 0),
    ...                BoxModes(z, z, z), np.ones(2), np.array([0.1, 0.2]), np.ones(2), 1,
    ...                ("flap", "tab"))
    >>> lk = link_surfaces(fm, [(1, 0, 2.0)])
    >>> lk.names, lk.inertia.tolist(), round(float(lk.static_unbalance[0]), 12)
    (('flap',), [5.0], 0.5)
    """
    from asekit.aero.control_surface import gearing_matrix

    n_s = len(fm.names)
    T, free = gearing_matrix(n_s, links)
    n = fm.n_wing
    tx = np.zeros((n + n_s, n + free.size))
    tx[:n, :n] = np.eye(n)
    tx[n:, n:] = T
    m, k, c = (tx.T @ np.asarray(a, float) @ tx for a in (fm.modal.M, fm.modal.K, fm.modal.C))
    box = BoxModes(fm.box_modes.h_cp @ tx, fm.box_modes.dhdx_cp @ tx, fm.box_modes.h_lp @ tx)
    inertia = np.diag(m[n:, n:]).copy()
    k_h = np.diag(k[n:, n:])
    return FlapModel(ModalArrays(m, k, c, fm.modal.n_rigid), box, inertia,
                     T.T @ np.asarray(fm.static_unbalance, float),
                     np.sqrt(k_h / inertia) / (2.0 * math.pi), n,
                     tuple(fm.names[i] for i in free))


@dataclass(frozen=True)
class StaticEffectiveness:
    """Steady flexible-to-rigid effectiveness of each surface: ``dynamic_pressure`` (n_q,) Pa;
    ``ratio`` (n_s, n_q) flexible over rigid rolling moment (or lift) per unit deflection;
    ``reversal_q`` (n_s,) Pa (nan: none below the divergence or the search limit);
    ``divergence_q`` Pa (nan: none found); ``what`` "rolling moment" or "lift"; ``rigid``
    (n_s,) the rigid value per unit dynamic pressure and per radian of each surface's
    deflection (rolling moment about y = 0, m^3, positive for lift at y > 0; or lift, m^2),
    of the half model when there is an image."""

    dynamic_pressure: np.ndarray
    ratio: np.ndarray
    reversal_q: np.ndarray
    divergence_q: float
    what: str
    rigid: np.ndarray | None = None

    def reversal_speed(self, density: float) -> np.ndarray:
        """Reversal speeds sqrt(2 q_R / rho) (m/s) at air density ``density`` (kg/m^3)."""
        rho = positive("density", density)
        return np.sqrt(2.0 * self.reversal_q / rho)


#: the images in the plane y = 0 of the steady solution: none (an isolated surface), a wall
#: (symmetric loading: a symmetric deflection of both halves) or antisymmetric loading (the
#: two ailerons of a wing deflected in opposite senses, the rolling case)
IMAGES = ("none", "symmetric", "antisymmetric")


def steady_generalised_forces(fm: FlapModel, hm: HingedMesh, mach: float,
                              image: str = "none") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Q0, lift, roll): the steady GAFs Q0 (n, n) per unit dynamic pressure (vortex lattice,
    :mod:`asekit.aero.vlm`, with the ``image`` of :data:`IMAGES` in y = 0: the antisymmetric
    normalwash matrix is D_self - D_image = 2 D_self - D_symmetric), and the lift (m^2) and
    rolling moment about y = 0 (m^3, positive for lift at y > 0) of each coordinate per unit
    dynamic pressure (of the half model when there is an image)."""
    from asekit.aero.vlm import vlm_normalwash_matrix

    if image not in IMAGES:
        raise ValueError(f"image must be one of {IMAGES}, got {image!r}")
    mesh = hm.mesh
    d = vlm_normalwash_matrix(mesh, mach, False)
    if image != "none":
        d_sym = vlm_normalwash_matrix(mesh, mach, True)
        d = d_sym if image == "symmetric" else 2.0 * d - d_sym
    cp = np.linalg.solve(d, fm.box_modes.normalwash(0.0, 1.0).real)
    q0 = fm.box_modes.h_lp.T @ (mesh.area[:, None] * cp)
    lift = (mesh.area * mesh.normal[:, 2]) @ cp
    roll = (mesh.area * mesh.normal[:, 2] * mesh.load_point[:, 1]) @ cp
    return q0, lift, roll


def static_effectiveness(fm: FlapModel, hm: HingedMesh, mach: float, q_max: float,
                         n_q: int = 60, image: str = "none",
                         what: str = "rolling moment") -> StaticEffectiveness:
    """Flexible-to-rigid effectiveness against dynamic pressure and the reversal dynamic
    pressure of every surface (module docstring), the surfaces held at their deflection
    (hinge coordinates constrained) and the wing's rigid modes held (a clamped or
    actuator-held wing).

    Parameters
    ----------
    fm, hm : the model (:func:`flap_modal_model`) and its boxes.
    mach : 0 <= M < 1 (vortex lattice).
    q_max : the largest dynamic pressure searched (Pa, > 0).
    n_q : points of the effectiveness curve (>= 2).
    image : the image in y = 0 (:data:`IMAGES`): "antisymmetric" for the ailerons of a half
        wing at a symmetry plane (rolling), "symmetric" for flaps, "none" for an isolated
        surface.
    what : "rolling moment" (about y = 0, a half wing's aileron) or "lift".

    Returns
    -------
    StaticEffectiveness

    Examples
    --------
    :func:`flap_modal_model`'s aluminium plate wing, isolated (no image): the aileron
    reverses below the wing's divergence.

    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> from asekit.structure.modes import fixed_modal_model
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> K, M = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> model = fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=4)
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> fm = flap_modal_model(model, M, hm, 0.5)
    >>> se = static_effectiveness(fm, hm, 0.0, 2000.0)
    >>> bool(0 < se.reversal_q[0] < se.divergence_q), float(se.ratio[0, 0])
    (True, 1.0)
    """
    q_max = positive("q_max", q_max)
    if what not in ("rolling moment", "lift"):
        raise ValueError(f"what must be 'rolling moment' or 'lift', got {what!r}")
    q0, lift, roll = steady_generalised_forces(fm, hm, mach, image)
    r = roll if what == "rolling moment" else lift
    nr, nw = fm.modal.n_rigid, fm.n_wing
    w = np.arange(nr, nw)
    f = np.arange(nw, nw + len(fm.names))
    K = fm.modal.K[np.ix_(w, w)]
    Qww = q0[np.ix_(w, w)]

    def ratio(q, j):
        zeta = np.linalg.solve(K - q * Qww, q * q0[w, f[j]])
        return (r[f[j]] + r[w] @ zeta) / r[f[j]]

    mu = linalg.eigvals(Qww, K)                       # Q x = mu K x, q = 1 / mu
    mu = mu[np.abs(mu.imag) <= 1e-9 * np.maximum(np.abs(mu), 1e-300)].real
    q_div = float(1.0 / mu[mu > 0].max()) if np.any(mu > 0) else math.nan
    q_top = min(q_max, 0.999 * q_div) if math.isfinite(q_div) else q_max
    qs = np.linspace(0.0, q_top, integer("n_q", n_q, low=2))
    rat = np.array([[ratio(q, j) for q in qs] for j in range(len(f))])
    q_r = np.full(len(f), math.nan)
    for j in range(len(f)):
        sign = np.flatnonzero(np.diff(np.sign(rat[j])) != 0)
        if sign.size:
            i = int(sign[0])
            q_r[j] = brentq(lambda q: ratio(q, j), qs[i], qs[i + 1], xtol=1e-10 * q_top)
    return StaticEffectiveness(qs, rat, q_r, q_div, what, np.asarray(r[f], float))





def _strip_g(what: str, lam: float) -> float:
    """The span integral factor of strip theory: tan(L)/L (lift) or
    2 (1 - cos L) / (L^2 cos L) (rolling moment); 1 at L = 0, infinite at L = pi/2."""
    if lam < 1e-4:                                   # series: 1 + L^2/3 and 1 + 5 L^2/12
        return 1.0 + lam * lam * (1.0 / 3.0 if what == "lift" else 5.0 / 12.0)
    if what == "lift":
        return math.tan(lam) / lam
    return 2.0 * (1.0 - math.cos(lam)) / (lam * lam * math.cos(lam))


def _strip_inputs(gj, chord, span, e, cl_alpha, cl_delta, cm_delta, what):
    vals = tuple(positive(n, v) for n, v in (("gj", gj), ("chord", chord), ("span", span),
                                            ("e", e), ("cl_alpha", cl_alpha),
                                            ("cl_delta", cl_delta)))
    if what not in ("rolling moment", "lift"):
        raise ValueError(f"what must be 'rolling moment' or 'lift', got {what!r}")
    return vals + (float(cm_delta),)


def strip_theory_effectiveness(q, gj: float, chord: float, span: float, e: float,
                               cl_alpha: float, cl_delta: float, cm_delta: float,
                               what: str = "rolling moment") -> np.ndarray:
    """Closed-form (strip-theory) flexible-to-rigid effectiveness of a full-span control
    surface on a uniform straight wing clamped at y = 0, the surface held at its deflection
    (Bisplinghoff, Ashley & Halfman, *Aeroelasticity*, 1955, Sec. 8-4; Hodges & Pierce,
    *Introduction to Structural Dynamics and Aeroelasticity*, 2002, Sec. 3.4, whose typical
    section is the rigid-in-span limit).

    Derivation (written out here). With the twist theta(y) (nose up), the section lift and
    moment about the elastic axis are L' = q c (a theta + c_l,delta delta) and
    M' = e c L' + q c^2 c_m,delta delta; torsional equilibrium GJ theta'' + M' = 0 with
    theta(0) = 0, theta'(l) = 0 gives, with lambda^2 = q c^2 e a / GJ and
    theta_p = -(e c_l,delta + c_m,delta) delta / (e a),

        theta(y) = theta_p (1 - cos(lambda y) - tan(lambda l) sin(lambda y)),

    and the flexible over rigid lift and rolling moment (about y = 0), L = lambda l,

        ratio = 1 - (e c_l,delta + c_m,delta) / (e c_l,delta) (1 - g(L)),
        g = tan(L) / L  (lift),   g = 2 (1 - cos L) / (L^2 cos L)  (rolling moment).

    Divergence is at L = pi/2, q_D = pi^2 GJ / (4 c^2 e a l^2).

    Parameters
    ----------
    q : dynamic pressure(s) (Pa, >= 0, below q_D).
    gj : torsional stiffness (N m^2, > 0).
    chord, span : c and l (m, > 0).
    e : distance of the elastic axis behind the aerodynamic centre, in chords (> 0).
    cl_alpha, cl_delta : section lift slopes (per rad, > 0).
    cm_delta : section moment slope about the aerodynamic centre (per rad, nose up positive;
        < 0 for a trailing-edge flap).
    what : "rolling moment" (about y = 0) or "lift".

    Returns
    -------
    ndarray : the ratio at each q (nan at and above divergence).

    Examples
    --------
    A flat plate (elastic axis at mid-chord, e = 0.25) with a 25 % flap gains effectiveness:

    >>> r = strip_theory_effectiveness([0.0, 1000.0], 100.0, 0.1, 2.0, 0.25, 2 * math.pi,
    ...                                3.826, -0.6495)
    >>> [round(float(v), 3) for v in r]
    [1.0, 1.113]
    """
    gj, c, ln, e, a, cl_d, cm_d = _strip_inputs(gj, chord, span, e, cl_alpha, cl_delta,
                                                cm_delta, what)
    qs = np.atleast_1d(np.asarray(q, float))
    if qs.size == 0 or not np.all(np.isfinite(qs)) or np.any(qs < 0):
        raise ValueError(f"q must be finite dynamic pressures >= 0 (Pa), got {q}")
    lam = ln * c * np.sqrt(qs * e * a / gj)
    g = np.array([_strip_g(what, x) if x < 0.5 * math.pi else math.nan for x in lam])
    return 1.0 - (e * cl_d + cm_d) / (e * cl_d) * (1.0 - g)


def strip_theory_reversal_q(gj: float, chord: float, span: float, e: float, cl_alpha: float,
                            cl_delta: float, cm_delta: float,
                            what: str = "rolling moment") -> float:
    """Closed-form (strip-theory) reversal dynamic pressure of a uniform straight wing clamped
    at y = 0 with a full-span control surface held at its deflection: the zero of
    :func:`strip_theory_effectiveness` (same model and parameters), where
    g(L) = c_m,delta / (e c_l,delta + c_m,delta) with L = lambda l in (0, pi/2), so that
    q_R = L^2 GJ / (c^2 e a l^2). A root exists only when e c_l,delta + c_m,delta < 0 (the
    deflection's lift acts behind the elastic axis).

    Returns
    -------
    float : q_R (Pa), nan when the surface does not reverse below divergence.

    Examples
    --------
    A 25 % flap (thin-airfoil slopes), the elastic axis 5 % of the chord behind the quarter
    chord, GJ = 100 N m^2, c = 0.1 m, l = 2 m:

    >>> round(strip_theory_reversal_q(100.0, 0.1, 2.0, 0.05, 2 * math.pi, 3.826, -0.6495))
    5667
    >>> math.isnan(strip_theory_reversal_q(100.0, 0.1, 2.0, 0.25, 2 * math.pi, 3.826, -0.6495))
    True
    """
    gj, c, ln, e, a, cl_d, cm_d = _strip_inputs(gj, chord, span, e, cl_alpha, cl_delta,
                                                cm_delta, what)
    s = e * cl_d + cm_d
    if s >= 0.0 or cm_d / s <= 1.0:
        return math.nan
    r = cm_d / s
    lam = brentq(lambda x: _strip_g(what, x) - r, 1e-6, 0.5 * math.pi - 1e-12, xtol=1e-14)
    return lam * lam * gj / (c * c * e * a * ln * ln)
