"""Normal modes, mode selection and the fin's modal model (thesis Eqs. (2.2)-(2.6), (2.45)-(2.46),
Sections 3.1.1-3.1.2, Tables 4-6).

The eigenproblem K phi = omega^2 M phi (Eq. (2.4)) is solved for the lowest modes with the
sparse Lanczos solver of ARPACK in shift-invert mode (:func:`scipy.sparse.linalg.eigsh`), the
same family of method as MSC Nastran SOL 103's default.

:func:`fictitious_mass_modal_model` builds the thesis's model FN2 (fictitious-mass method,
Sec. 3.1.1): one eigen-analysis gives the rigid pitch mode and the elastic modes. The fictitious inertia is then
removed: the rigid mode is scaled to a unit (1 rad) pitch rotation and the elastic modes are
re-diagonalised by a Rayleigh-Ritz step with the fin's own mass matrix and the FN1 stiffness
(the shaft spring to ground) in the span of the FN2 elastic modes. Because those modes differ
from the FN1 modes by O(J_fin / I_f) ~ 1e-6, the Ritz frequencies agree with FN1 to O(1e-12),
and the elastic set is exactly mass-normalised (M_ss = I), as the thesis's Eq. (2.46) assumes.
The rigid-elastic inertial coupling M_cs = phi_c^T M phi_s of Eq. (2.46) remains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from asekit.structure.assembly import SupportedSystem, rigid_pitch_vector, shaft_support
from asekit.structure.mesh import PlateMesh
from asekit.structure.plate import locate_points, membrane_matrices, shape_functions
from asekit.util.validate import integer, positive

#: Modes whose share of kinetic energy in the out-of-plane translation w is below this are
#: "modes with no out-of-plane motion" and are dropped (thesis Fig. 15/16: in-plane mode).
MIN_OUT_OF_PLANE = 0.01


@dataclass(frozen=True)
class NormalModes:
    """Eigen-solution of a supported structure.

    frequencies_hz : (n,) natural frequencies (Hz), ascending (sqrt of max(lambda, 0) / 2 pi).
    eigenvalues : (n,) omega^2 (rad^2/s^2) as solved (may be ~ -0 for a rigid mode).
    q : (n_q, n) eigenvectors in the reduced coordinates, mass-normalised: q^T M q = I.
    fin : (3 n_nodes, n) the same modes on the fin's DOFs (w, theta_x, theta_y per node).
    out_of_plane : (n,) share of each mode's kinetic energy in the w translations.
    system : the supported system solved.
    """

    frequencies_hz: np.ndarray
    eigenvalues: np.ndarray
    q: np.ndarray
    fin: np.ndarray
    out_of_plane: np.ndarray
    system: SupportedSystem


def _fin_mass_share(fin_vecs: np.ndarray, M_fin) -> np.ndarray:
    """Share of kinetic energy in the w DOFs (M is block-diagonal in w / rotations)."""
    Mphi = M_fin @ fin_vecs
    total = np.einsum("ij,ij->j", fin_vecs, Mphi)
    w_part = np.einsum("ij,ij->j", fin_vecs[0::3], Mphi[0::3])
    return np.divide(w_part, total, out=np.zeros_like(total), where=total > 0)


#: From this many degrees of freedom the shift-invert factor of K - sigma M is a symmetric
#: (minimum-degree on A^T + A, no pivoting) sparse LU instead of eigsh's default (COLAMD, partial
#: pivoting): K - sigma M = K + |sigma| M is positive definite for sigma < 0, so no pivoting is
#: needed, and the fill is 2.4x smaller (the fin's 96 x 112 distributed-shaft FN2 system, 32816
#: dof: factor 0.5 s vs 2.0 s, a solve 15 ms vs 47 ms, issue 12). Smaller systems keep eigsh's
#: own factor bit for bit (the shipped GAF database's mode set).
SYMMETRIC_LU_MIN_DOF = 2000


def shift_invert_operator(system: SupportedSystem, sigma: float):
    """(K - sigma M)^-1 as a ``LinearOperator`` for ``eigsh(..., sigma=sigma, OPinv=...)``,
    factored once (reusable across eigsh calls on the same system), or None below
    :data:`SYMMETRIC_LU_MIN_DOF` (eigsh then factors itself).

    SuperLU with ``permc_spec="MMD_AT_PLUS_A"``, ``diag_pivot_thresh=0`` and symmetric mode
    (valid for the positive definite K + |sigma| M, sigma < 0); the factor is checked by the
    residual of one solve and, if that is not small (an indefinite or singular matrix), redone
    with SuperLU's default partial pivoting."""
    n = system.K.shape[0]
    if n < SYMMETRIC_LU_MIN_DOF:
        return None
    A = (system.K - sigma * system.M).tocsc()
    b = np.cos(np.arange(n, dtype=float))
    lu = None
    if sigma < 0:
        try:
            lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
            x = lu.solve(b)
            if not np.linalg.norm(A @ x - b) <= 1e-6 * np.linalg.norm(b):
                lu = None
        except RuntimeError:                 # a zero pivot: not positive definite
            lu = None
    if lu is None:
        lu = spla.splu(A)
    return spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)


def normal_modes(system: SupportedSystem, n_modes: int = 10, M_fin=None,
                 shift_hz: float = 1.0, opinv=None) -> NormalModes:
    """Lowest ``n_modes`` natural modes of a supported system (thesis Eq. (2.4)).

    Shift-invert Lanczos (``eigsh``) about the negative shift -(2 pi ``shift_hz``)^2, so that a
    singular K (rigid mode) is handled; dense ``scipy.linalg.eigh`` only when nearly all modes
    of a tiny system are requested. The start
    vector is fixed and each mode's sign is fixed (largest |w| positive; the rigid mode's shaft
    rotation positive), so results are reproducible bit for bit.

    M_fin : the fin's global (unsupported) mass matrix, used for each mode's out-of-plane
    kinetic-energy share; without it ``out_of_plane`` is NaN.
    opinv : a :func:`shift_invert_operator` of this system and shift (default: made here).
    """
    n_q = system.K.shape[0]
    n_modes = min(integer("n_modes", n_modes, low=1), n_q)
    sigma = -(2 * math.pi * shift_hz) ** 2
    if n_modes >= n_q - 1:
        # tiny systems: dense solve (less accurate for a near-zero rigid mode next to a huge
        # fictitious inertia, because the Cholesky factor of M is ill-conditioned)
        lam, q = sla.eigh(system.K.toarray(), system.M.toarray(), subset_by_index=(0, n_modes - 1))
    else:
        v0 = np.ones(n_q) / math.sqrt(n_q)
        if opinv is None:
            opinv = shift_invert_operator(system, sigma)
        lam, q = spla.eigsh(system.K, k=n_modes, M=system.M, sigma=sigma, which="LM", v0=v0,
                            OPinv=opinv)
    order = np.argsort(lam)
    lam, q = lam[order], q[:, order]
    # exact mass normalisation (ARPACK returns M-orthonormal vectors to ~1e-12)
    q = q / np.sqrt(np.einsum("ij,ij->j", q, system.M @ q))
    fin = system.T @ q
    # deterministic signs
    for j in range(q.shape[1]):
        if system.ground_index is not None and abs(q[system.ground_index, j]) > 0.5 * np.abs(q[:, j]).max():
            sgn = np.sign(q[system.shaft_index, j])
        else:
            w = fin[0::3, j]
            sgn = np.sign(w[np.argmax(np.abs(w))]) if np.abs(w).max() > 0 else 1.0
        if sgn < 0:
            q[:, j] *= -1
            fin[:, j] *= -1
    if M_fin is not None:
        share = _fin_mass_share(fin, M_fin)
    else:
        share = np.full(q.shape[1], np.nan)
    freqs = np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)
    return NormalModes(frequencies_hz=freqs, eigenvalues=lam, q=q, fin=fin, out_of_plane=share,
                       system=system)


def select_modes(frequencies_hz: np.ndarray, out_of_plane: np.ndarray, f_max_hz: float = 1000.0,
                 min_out_of_plane: float = MIN_OUT_OF_PLANE) -> np.ndarray:
    """Boolean mask of the elastic modes kept (thesis Sec. 3.1.1, Fig. 15 MODESELECT): below
    ``f_max_hz`` and with at least ``min_out_of_plane`` of their kinetic energy in the
    out-of-plane translation w (a mode with no out-of-plane motion does not interact with the
    aerodynamics of a flat fin, like the thesis's discarded in-plane mode of Fig. 16)."""
    f = np.asarray(frequencies_hz, float)
    share = np.asarray(out_of_plane, float)
    if f.shape != share.shape:
        raise ValueError(f"frequencies_hz {f.shape} and out_of_plane {share.shape} must match")
    positive("f_max_hz", f_max_hz)
    if not 0 <= min_out_of_plane <= 1:
        raise ValueError(f"min_out_of_plane must lie in [0, 1], got {min_out_of_plane!r}")
    return (f < f_max_hz) & (np.nan_to_num(share, nan=0.0) >= min_out_of_plane)


def modes_up_to(system: SupportedSystem, f_max_hz: float, M_fin=None, n_start: int = 12) -> NormalModes:
    """All modes below ``f_max_hz`` plus at least one above it (to show where the cut falls);
    the shift-invert factor is made once for all the eigsh calls."""
    n = n_start
    n_q = system.K.shape[0]
    opinv = shift_invert_operator(system, -(2 * math.pi) ** 2)       # normal_modes' shift
    while True:
        modes = normal_modes(system, n, M_fin=M_fin, opinv=opinv)
        if modes.frequencies_hz[-1] > f_max_hz or n >= n_q:
            return modes
        n = min(2 * n, n_q)


@dataclass(frozen=True)
class ModalModel:
    """The fin's reduced structural model in the m-set (thesis Eqs. (2.5), (2.45)-(2.46)).

    Attributes
    ----------
    frequencies_hz : (n_modes,) rigid mode(s) first (0 Hz), then the elastic modes kept.
    M : (n_modes, n_modes) modal mass, fictitious inertia removed; M[0, 0] = J_fin for FN2.
    K : (n_modes, n_modes) modal stiffness (zero row/col for the rigid mode).
    C : (n_modes, n_modes) modal damping, zeros by default (the conference paper: C_mm = 0).
    n_rigid : number of rigid modes at the front: 1 for FN2, 0 for FN1 / clamped.
    J_fin : pitch inertia of the fin about the shaft axis (kg m^2).
    nodes : (n_nodes, 2) FE node coordinates x, y (m).
    shapes : (n_nodes, 3, n_modes) w (m), theta_x, theta_y (rad) per node and unit modal coordinate.
        The rigid mode is a unit (1 rad) nose-up pitch: w = -(x - x_axis), theta_y = 1.
        Elastic modes are mass-normalised with the fin's own mass matrix (M_ss = I).
    elements : (n_elem, 4) node indices, counter-clockwise.
    label : e.g. "FN2 6x7 single-node shaft".
    """

    frequencies_hz: np.ndarray
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    n_rigid: int
    J_fin: float
    nodes: np.ndarray
    shapes: np.ndarray
    elements: np.ndarray
    label: str


@dataclass(frozen=True)
class ModalPartition:
    """The rigid (c) / elastic (s) partition of the m-set matrices (thesis Eqs. (2.45)-(2.46)):
    M_cc (n_c x n_c), M_cs (n_c x n_s), M_sc = M_cs^T, M_ss, C_ss and K_ss (n_s x n_s); damping
    and stiffness have no rigid part."""

    M_cc: np.ndarray
    M_cs: np.ndarray
    M_sc: np.ndarray
    M_ss: np.ndarray
    C_ss: np.ndarray
    K_ss: np.ndarray


def modal_partition(model: ModalModel) -> ModalPartition:
    """Split a ModalModel into the c-set (its first ``n_rigid`` modes) and the s-set (Eq. 2.46)."""
    c = model.n_rigid
    return ModalPartition(M_cc=model.M[:c, :c].copy(), M_cs=model.M[:c, c:].copy(),
                          M_sc=model.M[c:, :c].copy(), M_ss=model.M[c:, c:].copy(),
                          C_ss=model.C[c:, c:].copy(), K_ss=model.K[c:, c:].copy())


def mode_shapes_at(model: ModalModel, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """w (n_points, n_modes) in m and dw/dx (n_points, n_modes) at (x, y) points on the surface.

    Both are interpolated with the element's bilinear shape functions. The streamwise slope is
    the Mindlin rotation field, dw/dx = -theta_y (exact in the Kirchhoff limit, where the
    transverse shear strain gamma_xz = dw/dx + theta_y vanishes; continuous across elements,
    unlike the derivative of the bilinear w). For the rigid pitch mode it is exactly -1.
    Points outside the planform raise ValueError.
    """
    elem, rs = locate_points(model.nodes, model.elements, points)
    N, _, _ = shape_functions(rs[:, 0], rs[:, 1])            # (n_points, 4)
    conn = model.elements[elem]                              # (n_points, 4)
    w = np.einsum("pk,pkm->pm", N, model.shapes[conn, 0, :])
    dwdx = -np.einsum("pk,pkm->pm", N, model.shapes[conn, 2, :])
    return w, dwdx


def _keep_modes(f_hz, share, f_max_hz, n_modes):
    """Mask of the elastic modes kept: out-of-plane ones below f_max_hz, or the first n_modes."""
    if n_modes is None:
        return select_modes(f_hz, share, f_max_hz)
    oop = np.flatnonzero(select_modes(f_hz, share, 1e300))
    if oop.size < n_modes:
        raise ValueError(f"modes.count = {n_modes} elastic out-of-plane modes requested but only "
                         f"{oop.size} were found: lower the count or refine the mesh")
    keep = np.zeros(len(f_hz), bool)
    keep[oop[:n_modes]] = True
    return keep


def _solve_modes(system, M_fin, f_max_hz, n_modes, extra: int = 0) -> NormalModes:
    if n_modes is None:
        return modes_up_to(system, f_max_hz, M_fin=M_fin)
    n = integer("modes.count", n_modes, low=1)
    return normal_modes(system, min(system.K.shape[0], 2 * n + 4 + extra), M_fin=M_fin)


def fictitious_mass_modal_model(mesh: PlateMesh, K, M, axis_point, torsional_stiffness: float,
                                region: str = "single_node", radius: float = 0.0,
                                fictitious_inertia_factor: float = 1.0e6,
                                bending_stiffness: float | None = None,
                                f_max_hz: float = 1000.0, n_modes: int | None = None
                                ) -> ModalModel:
    """The FN2 modal model of a plate on a pitch shaft (thesis Sec. 3.1.1, Eqs. (2.45)-(2.46);
    Karpel's fictitious-mass method): rigid pitch mode + the elastic modes kept.

    Parameters
    ----------
    mesh, K, M : plate mesh and its global sparse stiffness and mass (point masses included).
    axis_point : (x, y) of the pitch axis on the root chord (m).
    torsional_stiffness : actuator-fin connection about the pitch axis (N m/rad), > 0.
    region, radius : ``"single_node"`` or ``"distributed"`` shaft of ``radius`` m.
    fictitious_inertia_factor : I_f / J_fin of the FN2 ground point.
    bending_stiffness : optional connection stiffness about the chordwise axis (N m/rad).
    f_max_hz : keep the elastic modes with out-of-plane motion below this (Hz) ...
    n_modes : ... or, when given, the first ``n_modes`` such modes.

    Returns
    -------
    ModalModel with n_rigid = 1: M[0, 0] = J_fin, M_ss = I, K = diag(0, omega_s^2), C = 0.
    """
    positive("f_max_hz", f_max_hz)
    fn2 = shaft_support(mesh, K, M, axis_point, torsional_stiffness, model="FN2",
                        region=region, radius=radius,
                        fictitious_inertia_factor=fictitious_inertia_factor,
                        bending_stiffness=bending_stiffness)
    fn1 = shaft_support(mesh, K, M, axis_point, torsional_stiffness, model="FN1",
                        region=region, radius=radius, bending_stiffness=bending_stiffness)
    modes = _solve_modes(fn2, M, f_max_hz, n_modes, extra=1)
    g, s_i = fn2.ground_index, fn2.shaft_index
    # the rigid mode: almost all of its kinetic energy sits in the fictitious inertia
    energy_g = fn2.fictitious_inertia * modes.q[g] ** 2
    i_rigid = int(np.argmax(energy_g))
    q_c = modes.q[:, i_rigid] / modes.q[s_i, i_rigid]            # unit shaft rotation
    phi_c = fn2.T @ q_c
    # elastic: drop the ground coordinate, re-diagonalise with the fin's mass + FN1 stiffness
    elastic = [j for j in range(modes.q.shape[1]) if j != i_rigid]
    Qs = np.delete(modes.q[:, elastic], g, axis=0)
    Kt = Qs.T @ (fn1.K @ Qs)
    Mt = Qs.T @ (fn1.M @ Qs)
    lam, V = sla.eigh(0.5 * (Kt + Kt.T), 0.5 * (Mt + Mt.T))
    Qs = Qs @ V
    phi_s = fn1.T @ Qs
    for j in range(phi_s.shape[1]):                             # deterministic sign
        w = phi_s[0::3, j]
        if w[np.argmax(np.abs(w))] < 0:
            phi_s[:, j] *= -1
            Qs[:, j] *= -1
    f_s = np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)
    share = _fin_mass_share(phi_s, M)
    keep = _keep_modes(f_s, share, f_max_hz, n_modes)
    phi_s, Qs, lam_s = phi_s[:, keep], Qs[:, keep], lam[keep]
    Phi = np.column_stack([phi_c, phi_s])
    M_mm = Phi.T @ (M @ Phi)
    M_mm = 0.5 * (M_mm + M_mm.T)
    K_ss = Qs.T @ (fn1.K @ Qs)
    n = Phi.shape[1]
    K_mm = np.zeros((n, n))
    K_mm[1:, 1:] = 0.5 * (K_ss + K_ss.T)
    # the rigid row of K (plate strain energy of a rigid pitch, spring unstretched) is zero
    k_c = float(phi_c @ (K @ phi_c))
    if abs(k_c) > 1e-8 * max(1.0, float(np.max(np.abs(K_ss))) if K_ss.size else 1.0):
        raise RuntimeError(f"rigid mode carries strain energy {k_c:g}: support model broken")
    f_rigid = math.sqrt(max(modes.eigenvalues[i_rigid], 0.0)) / (2 * math.pi)
    freqs = np.concatenate([[f_rigid], np.sqrt(np.maximum(lam_s, 0.0)) / (2 * math.pi)])
    shapes = Phi.reshape(mesh.n_nodes, 3, n)
    return ModalModel(frequencies_hz=freqs, M=M_mm, K=K_mm, C=np.zeros((n, n)), n_rigid=1,
                      J_fin=float(M_mm[0, 0]), nodes=mesh.nodes.copy(), shapes=shapes,
                      elements=mesh.elements.copy(), label=fn2.label)


def fixed_modal_model(system: SupportedSystem, M_fin, f_max_hz: float = 1000.0,
                      n_modes: int | None = None, axis_x: float | None = None) -> ModalModel:
    """A ModalModel without rigid modes (n_rigid = 0) of a supported system with no free
    rotation (clamped root, FN1 shaft, edge supports): the out-of-plane modes below
    ``f_max_hz`` (or the first ``n_modes``), mass-normalised."""
    positive("f_max_hz", f_max_hz)
    modes = _solve_modes(system, M_fin, f_max_hz, n_modes)
    return elastic_modal_model(modes, M_fin, f_max_hz, axis_x=axis_x, n_modes=n_modes)


def with_damping(model: ModalModel, modal_damping_ratio=None, structural_g=None) -> ModalModel:
    """The model with viscous modal damping of its elastic modes.

    C_ii = 2 zeta_i omega_i M_ii for each elastic mode i (``modal_damping_ratio``: one value
    or one per elastic mode, in [0, 1)); a structural damping coefficient g is applied as its
    equivalent viscous damping at each mode's natural frequency, zeta = g / 2 (the viscous
    form of modal structural damping used in p-k flutter, e.g. MSC Nastran's TABDMP1 with
    the PK method). Rigid modes stay undamped. Default (both None): C unchanged (zero, as in
    the thesis).
    """
    import dataclasses
    if modal_damping_ratio is not None and structural_g is not None:
        raise ValueError("give modal_damping_ratio or structural_g, not both")
    if modal_damping_ratio is None and structural_g is None:
        return model
    n_s = len(model.frequencies_hz) - model.n_rigid
    if structural_g is not None:
        g = np.broadcast_to(np.asarray(structural_g, float), (n_s,)) if np.ndim(structural_g) == 0 \
            else np.asarray(structural_g, float)
        zeta = 0.5 * g
        name = "structural_g"
    else:
        zeta = np.asarray(modal_damping_ratio, float)
        zeta = np.full(n_s, float(zeta)) if zeta.ndim == 0 else zeta
        name = "modal_damping_ratio"
    if zeta.shape != (n_s,):
        raise ValueError(f"damping.{name} must be one value or one per elastic mode "
                         f"({n_s}), got {zeta.size} values")
    if not np.all(np.isfinite(zeta)) or np.any(zeta < 0) or np.any(zeta >= 1):
        raise ValueError(f"damping.{name} must give damping ratios in [0, 1), got "
                         f"{np.asarray(modal_damping_ratio if structural_g is None else structural_g).tolist()}")
    omega = 2 * math.pi * model.frequencies_hz[model.n_rigid:]
    C = model.C.copy()
    r = model.n_rigid
    C[r:, r:] += np.diag(2 * zeta * omega * np.diag(model.M)[r:])
    return dataclasses.replace(model, C=C)


def elastic_modal_model(modes: NormalModes, M_fin, f_max_hz: float = 1000.0,
                        axis_x: float | None = None, n_modes: int | None = None) -> ModalModel:
    """A ModalModel without rigid modes (n_rigid = 0) from an FN1 or clamped eigen-solution:
    the modes below ``f_max_hz`` with out-of-plane motion, mass-normalised (M = I,
    K = diag(omega^2), C = 0). ``J_fin`` is the plate's pitch inertia about x = ``axis_x``
    (default: the shaft axis of the support, or NaN when clamped)."""
    sys_ = modes.system
    keep = _keep_modes(modes.frequencies_hz, _fin_mass_share(modes.fin, M_fin), f_max_hz, n_modes)
    phi = modes.fin[:, keep]
    n = phi.shape[1]
    M_mm = phi.T @ (M_fin @ phi)
    K_red = modes.q[:, keep].T @ (sys_.K @ modes.q[:, keep])
    if axis_x is None and sys_.shaft_nodes.size:
        axis_x = float(sys_.mesh.nodes[sys_.shaft_nodes, 0].mean())
    J = float("nan")
    if axis_x is not None:
        r = rigid_pitch_vector(sys_.mesh, axis_x)
        J = float(r @ (M_fin @ r))
    return ModalModel(frequencies_hz=modes.frequencies_hz[keep].copy(),
                      M=0.5 * (M_mm + M_mm.T), K=0.5 * (K_red + K_red.T), C=np.zeros((n, n)),
                      n_rigid=0, J_fin=J, nodes=sys_.mesh.nodes.copy(),
                      shapes=phi.reshape(sys_.mesh.n_nodes, 3, n),
                      elements=sys_.mesh.elements.copy(), label=sys_.label)




@dataclass(frozen=True)
class InPlaneModes:
    """In-plane (membrane) modes of a plate pinned at one node (u = v = 0), the situation of the
    thesis's discarded mode (Fig. 16).

    Attributes
    ----------
    frequencies_hz : (n,) ascending; the first is the in-plane rigid rotation about the pinned
        node (0 Hz up to round-off: nothing but an artificial drilling stiffness restrains it).
    shapes : (n_nodes, 2, n) u, v per node (mass-normalised).
    J_z : in-plane rotational inertia of the plate about the pinned node (kg m^2).
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    J_z: float


def inplane_modes(mesh: PlateMesh, material, pinned_point, n_modes: int = 4) -> InPlaneModes:
    """In-plane modes of the plate held only at the node at ``pinned_point`` (x, y) m:
    K_m phi = omega^2 M_m phi with the plane-stress Q4 membrane matrices
    (:func:`asekit.structure.plate.membrane_matrices`), u = v = 0 at that node. Not part of a
    modal model: a flat plate's in-plane motion couples neither with bending nor with the
    aerodynamics.

    Parameters
    ----------
    mesh : the plate mesh; material : its material; pinned_point : (x, y) of a mesh node (m);
    n_modes : number of modes (>= 1).

    Returns
    -------
    :class:`InPlaneModes`.
    """
    n_modes = integer("n_modes", n_modes, low=1)
    Ke, Me = membrane_matrices(mesh, material)
    dofs = (2 * mesh.elements[:, :, None] + np.arange(2)).reshape(-1, 8)
    rows, cols = np.repeat(dofs, 8, axis=1).ravel(), np.tile(dofs, (1, 8)).ravel()
    n = 2 * mesh.n_nodes
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    M = sp.csr_matrix((Me.ravel(), (rows, cols)), shape=(n, n))
    node = mesh.node_at(pinned_point, name="shaft axis_point")
    free = np.setdiff1d(np.arange(n), [2 * node, 2 * node + 1])
    Kf = K[free][:, free]
    Mf = M[free][:, free]
    if free.size <= 2000:
        lam, q = sla.eigh(Kf.toarray(), Mf.toarray(), subset_by_index=(0, n_modes - 1))
    else:
        lam, q = spla.eigsh(Kf.tocsc(), k=n_modes, M=Mf.tocsc(), sigma=-(2 * math.pi) ** 2,
                            which="LM", v0=np.ones(free.size) / math.sqrt(free.size))
        order = np.argsort(lam)
        lam, q = lam[order], q[:, order]
    phi = np.zeros((n, n_modes))
    phi[free] = q
    xa, ya = mesh.nodes[node]
    rz = np.zeros(n)
    rz[0::2] = -(mesh.nodes[:, 1] - ya)
    rz[1::2] = mesh.nodes[:, 0] - xa
    return InPlaneModes(frequencies_hz=np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi),
                        shapes=phi.reshape(mesh.n_nodes, 2, n_modes), J_z=float(rz @ (M @ rz)))
