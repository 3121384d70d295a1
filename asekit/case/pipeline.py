"""The analysis pipeline of a :class:`~asekit.case.schema.Case`:
structure (plate FE -> modes) -> boxes -> GAF database (cached) -> p-k flutter at every Mach
and flight condition -> match points and flutter margin -> (with an actuator) the ASE loop.

Every step is a plain function of the frozen case; :func:`modal_model` and :func:`box_mesh` are
memoised on the case (frozen, hashable) so that one run computes each once.
"""

from __future__ import annotations

import functools
import logging
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from asekit.aero.beam_spline import beam_spline_matrices
from asekit.aero.boxes import check_matrix_memory, mesh_surfaces
from asekit.aero.gaf import GafDatabase, cached_gaf_database
from asekit.aero.spline import BoxModes
from asekit.aeroelastic.flutter import Instability, PkResult, divergence_speeds, first_of
from asekit.aeroelastic.methods import flutter_method
from asekit.aeroelastic.statespace import fin_outputs
from asekit.ase import loop as ase_mod
from asekit.ase import metrics
from asekit.atmosphere import standard_atmosphere
from asekit.case.envelope import flutter_margin, flutter_points, match_point, start_note
from asekit.case.resources import aero_reduced_frequencies, box_counts, panel_surfaces
from asekit.case.schema import (
    MOTOR_KEYS,
    TRANSMISSION_KEYS,
    Case,
    CaseError,
    SolverError,
    check_resources,
)
from asekit.rfa.methods import rfa_kind
from asekit.servo.actuator import SYSTEM_3, ActuatorParameters, DCMotor, Transmission
from asekit.servo.simulate import THESIS_LIMITS, SteadyHingeMoment
from asekit.structure.assembly import (
    SupportedSystem,
    assemble,
    plate_pitch_inertia,
    point_mass_matrix,
)
from asekit.structure.beam import NODE_DOF, BeamSection, StraightBeam, beam_modes, straight_beam
from asekit.structure.mesh import PlateMesh, panels_mesh, snap_to_circle
from asekit.structure.modes import InPlaneModes, ModalModel, fixed_modal_model, with_damping
from asekit.structure.modes import inplane_modes as _inplane_modes
from asekit.structure.supports import support_kind
from asekit.util.validate import finite

_log = logging.getLogger(__name__)
# ---------------------------------------------------------------------------------------------
# the door: a numerical failure of a checked case becomes a SolverError saying what to change
# ---------------------------------------------------------------------------------------------
_STRUCTURE = ("check material (moduli, density), thickness, support stiffness and "
              "panel[*].n_chord / n_span, or give modes.count / lower modes.f_max")
_AERO = "check aero.boxes, aero.machs and aero.reduced_frequencies"
_FLUTTER = ("check flight.velocities and the flight conditions (altitudes or densities), "
            "flutter.method, flutter.rfa and flutter.lags")
_ASE = "check [actuator] (its motor, transmission, controller and condition)"


def _door(step: str, change: str):
    """Decorator of the pipeline's public functions: a numerical failure inside (ARPACK or
    SuperLU's RuntimeError, LinAlgError, MemoryError, SystemError) is re-raised as a one-line
    :class:`~asekit.case.schema.SolverError` naming ``step``, the solver's message and
    ``change`` (what to change in the case). CaseError, SolverError and the other ValueErrors
    (bad arguments) pass unchanged."""
    def decorate(fn):
        @functools.wraps(fn)
        def wrapper(*args, **kw):
            t0 = time.perf_counter()
            try:
                result = fn(*args, **kw)
                _log.debug("%s: %.3g s", step, time.perf_counter() - t0)
                return result
            except (SolverError, CaseError, NotImplementedError, RecursionError):
                raise
            except (np.linalg.LinAlgError, RuntimeError, MemoryError, SystemError) as exc:
                what = " ".join(str(exc).split()) or "no message"
                if isinstance(exc, MemoryError):
                    what = "out of memory" + (f" ({what})" if str(exc) else "")
                raise SolverError(f"{step} failed ({type(exc).__name__}: {what[:300]}): "
                                  f"{change}") from exc
        return wrapper
    return decorate


# ---------------------------------------------------------------------------------------------
# structure
# ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=16)
@_door("the structural mesh", _STRUCTURE)
def structural_mesh(case: Case) -> PlateMesh:
    """The structural finite-element mesh of the case.

    Parameters
    ----------
    case : Case
        The case (:func:`asekit.case.load_case`).

    Returns
    -------
    PlateMesh
        The MITC4 plate mesh of all panels (``panel[i].n_chord x n_span`` elements each;
        nodes in m, thickness at every node from the case's thickness law), or the imported
        model's mesh when ``case.structure`` is given. Memoised on the case.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> structural_mesh(load_case(FIN_FILE)).elements.shape      # 6 x 7 MITC4 elements
    (42, 4)
    """
    if case.structure is not None:
        return case.structure.mesh
    if case.beam is not None:
        raise CaseError(f"{case.name}: a [[beam]] case has no plate mesh (its structure is the "
                        f"beam: asekit.case.pipeline.case_beam)")
    mesh = panels_mesh([p.planform for p in case.panels], case.thickness,
                       case.panels[0].n_chord, [p.n_span for p in case.panels],
                       case.panels[0].chord_spacing, [p.span_spacing for p in case.panels])
    return _fitted_to_support(mesh, case.support)


def _fitted_to_support(mesh: PlateMesh, s) -> PlateMesh:
    """``mesh`` with its nodes fitted to the rigid shaft region's circle when the case asks
    (``support.region_fit = "snap"``: :func:`asekit.structure.mesh.snap_to_circle`; issue 23)."""
    if s.kind != "shaft" or s.radius is None or s.option("region_fit", "nodes") != "snap":
        return mesh
    return snap_to_circle(mesh, s.axis_point, s.radius)     # its inputs checked by the schema


@_door("assembling K and M", _STRUCTURE)
def mass_and_stiffness(case: Case):
    """Global stiffness and mass matrices of the case's structural mesh.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    K, M : scipy.sparse.csr_matrix
        (3 n_nodes, 3 n_nodes) stiffness (N/m, N, N m/rad blocks) and mass (kg, kg m, kg m^2
        blocks) in the DOFs (w, theta_x, theta_y) of every node: the plate's (Mindlin-Reissner
        MITC4, :func:`asekit.structure.assembly.assemble`) plus the case's point masses in M,
        or the imported model's K and M when ``case.structure`` is given. No support applied
        (that is :func:`supported_system`).
    """
    mesh = structural_mesh(case)
    K, M = _imported_matrices(case) if case.structure is not None else assemble(mesh,
                                                                                 case.material)
    if case.point_masses:
        M = (M + point_mass_matrix(mesh, [(p.position, p.mass, p.inertia)
                                          for p in case.point_masses])).tocsr()
    return K, M


def _read_only(model: ModalModel) -> ModalModel:
    """``model`` with its arrays made read-only (a memoised result is shared by every caller:
    one that changes an array in place gets an error instead of corrupting the memo)."""
    for f in ("frequencies_hz", "M", "K", "C", "nodes", "shapes", "elements"):
        getattr(model, f).setflags(write=False)
    return model


def _memo_with_warnings(fn):
    """Memoise ``fn(case)`` on the frozen (hashable) case, the warnings of its one computation
    issued again on every call (under the caller's filters), so the memo changes neither a
    result nor what the caller is told."""
    @lru_cache(maxsize=32)
    def memo(case):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fn(case)
        return result, tuple((w.message, w.category) for w in caught)

    @functools.wraps(fn)
    def wrapper(case):
        result, caught = memo(case)
        for message, category in caught:
            warnings.warn(message, category, stacklevel=2)
        return result
    wrapper.cache_clear = memo.cache_clear
    return wrapper


@_door("the supported structure", _STRUCTURE)
def supported_system(case: Case) -> SupportedSystem:
    """The case's supported structure: K and M reduced by its support.

    Parameters
    ----------
    case : Case
        The case; ``support.kind`` names a kind of :data:`asekit.structure.supports.SUPPORTS`
        (for a shaft, the FN1 or FN2 system as ``support.model`` says).

    Returns
    -------
    SupportedSystem
        The reduced stiffness and mass (u = T q) on :func:`structural_mesh` with
        :func:`mass_and_stiffness`, or the imported deck's own supports.

    Raises
    ------
    CaseError
        A support key the kind refuses (the message names ``support.<key>``).
    """
    K, M = mass_and_stiffness(case)
    if case.structure is not None:             # the imported deck's own supports
        return case.structure.supported_system(K, M)
    try:
        return support_kind(case.support.kind).system(structural_mesh(case), K, M, case.support)
    except ValueError as exc:
        raise CaseError(f"support: {exc}") from None


@_memo_with_warnings
@_door("the modal model (plate eigenproblem: ARPACK with SuperLU)", _STRUCTURE)
def modal_model(case: Case) -> ModalModel:
    """The case's modal model: natural modes of the supported plate (thesis Eqs. 2.45-2.46).

    Solves the generalised eigenproblem K phi = omega^2 M phi of :func:`supported_system`
    (shift-invert ARPACK) and keeps the elastic modes below ``modes.f_max`` (Hz) or the first
    ``modes.count``, mass-normalised (phi^T M phi = I). For a shaft with ``model = "FN2"`` and
    ``modes.keep_rigid`` the rigid pitch mode comes first (n_rigid = 1, a unit nose-up pitch
    about the shaft, 0 Hz), otherwise the elastic modes only. Modal damping from
    ``[damping]`` (zeta or g = 2 zeta). Built by the support kind's ``modal_model``
    (:data:`asekit.structure.supports.SUPPORTS`); an imported structure:
    :func:`imported_modal_model`.

    Parameters
    ----------
    case : Case
        The case (:func:`asekit.case.load_case`).

    Returns
    -------
    ModalModel
        ``frequencies_hz`` (Hz), modal mass ``M`` (1 for elastic modes; J_fin in kg m^2 for
        the rigid mode), stiffness ``K`` ((rad/s)^2 on the diagonal), damping ``C``, the mode
        ``shapes`` (w in m, rotations in rad per unit modal coordinate) at the FE ``nodes``.
        Memoised on the (frozen) case: one object per case, its arrays read-only.

    Raises
    ------
    CaseError
        No elastic mode below ``modes.f_max``, or a support or damping value the model refuses.
    SolverError
        The eigenproblem failed; the message says which case keys to check.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> m = modal_model(load_case(FIN_FILE))
    >>> m.n_rigid, m.frequencies_hz.size, m.label
    (1, 6, 'FN2 6x7 single-node shaft')
    """
    if case.structure is not None:
        return imported_modal_model(case)
    if case.beam is not None:
        return beam_modal_model(case)
    mesh = structural_mesh(case)
    K, M = mass_and_stiffness(case)
    s, md = case.support, case.modes
    try:
        model = support_kind(s.kind).modal_model(mesh, K, M, s, md.f_max, md.count,
                                                 md.keep_rigid)
    except ValueError as exc:
        raise CaseError(f"support / modes: {exc}") from None
    if len(model.frequencies_hz) - model.n_rigid < 1:
        raise CaseError(f"modes: no elastic mode below modes.f_max = {md.f_max:g} Hz; raise "
                        f"f_max or give modes.count")
    d = case.damping
    try:
        model = _read_only(with_damping(model, d.modal_damping_ratio, d.structural_g))
    except ValueError as exc:
        raise CaseError(str(exc)) from None
    f = model.frequencies_hz
    _log.info("modal model of %s: %d modes, %.4g to %.4g Hz (%s)", case.name, f.size,
              f.min(), f.max(), model.label)
    return model


def _one_panel(case: Case, what: str):
    if len(case.panels) != 1:
        raise CaseError(f"{what} needs a one-panel case, got {len(case.panels)} panels")
    return case.panels[0]


def _shaft(case: Case, what: str):
    if case.support.kind != "shaft":
        raise CaseError(f"{what} needs support.kind = \"shaft\", got {case.support.kind!r}")
    return case.support


@_door("the pitch inertia", _STRUCTURE)
def pitch_inertia_exact(case: Case) -> float:
    """Pitch inertia of a one-panel flat case about its shaft axis, by exact integration.

    J = int_y rho h(y) int_x [(x - x_axis)^2 + h(y)^2 / 12] dx dy over the planform, with the
    plate's own rotary inertia (:func:`asekit.structure.assembly.plate_pitch_inertia`; no point
    masses): the reference for the FE model's J_fin.

    Parameters
    ----------
    case : Case
        A one-panel case with ``support.kind = "shaft"``.

    Returns
    -------
    float
        The pitch inertia (kg m^2).

    Raises
    ------
    CaseError
        More than one panel, no shaft, or a thickness or material the integration refuses.
    """
    p = _one_panel(case, "pitch_inertia_exact")
    try:
        return plate_pitch_inertia(p.planform, case.thickness, case.material.density,
                                   _shaft(case, "pitch_inertia_exact").axis_point[0])
    except ValueError as exc:
        raise CaseError(f"thickness / material: {exc}") from None


@_door("the in-plane modes", _STRUCTURE)
def inplane_modes(case: Case, n_modes: int = 4) -> InPlaneModes:
    """In-plane (membrane) modes of a shaft-supported case held only at the shaft node.

    Parameters
    ----------
    case : Case
        A case with ``support.kind = "shaft"``.
    n_modes : int, optional
        Number of modes (default 4).

    Returns
    -------
    InPlaneModes
        Frequencies (Hz) and shapes (:func:`asekit.structure.modes.inplane_modes` on
        :func:`structural_mesh`); the first is the in-plane rigid rotation about the shaft.
    """
    return _inplane_modes(structural_mesh(case), case.material,
                          _shaft(case, "inplane_modes").axis_point, n_modes)


# ---------------------------------------------------------------------------------------------
# an imported structure (case.structure: asekit.case.imported.ImportedModel)
# ---------------------------------------------------------------------------------------------
def _imported_matrices(case: Case):
    """(K, M) of the imported model, CSR."""
    return case.structure.K.tocsr(), case.structure.M.tocsr()


def _deck_words(structure, msg: str) -> str:
    """``msg`` in a Nastran user's words when the structure is a deck's: ``modes.count`` is
    the deck's EIGRL / EIGR ND field (``structure.deck.eigen_card``)."""
    card = getattr(getattr(structure, "deck", None), "eigen_card", "")
    if not card:
        return msg
    return msg.replace("structure / modes: ", "").replace("modes.count", f"{card} ND")


@_door("the modal model of the imported structure",
       "check the deck's materials, properties and constraints, or give modes.count")
def imported_modal_model(case: Case) -> ModalModel:
    """The modal model (n_rigid = 0) of a case with an imported structure.

    The structure's own supports (its reduction u = T q: constraints and rigid links; springs
    in K) on K and M (+ the case's point masses): the first ``modes.count`` out-of-plane
    modes, or all below ``modes.f_max`` (Hz), mass-normalised. Damping: the case's
    ``damping`` if it gives any, else the structure's table ``damping_g`` at each mode's
    frequency (zeta = g / 2, :func:`asekit.structure.modes.with_damping`).

    Raises
    ------
    CaseError
        No elastic mode in the range, or a bad damping value.
    """
    s, md = case.structure, case.modes
    K, M = mass_and_stiffness(case)
    try:
        model = fixed_modal_model(s.supported_system(K, M), M, md.f_max, md.count)
    except ValueError as exc:
        raise CaseError(_deck_words(s, f"structure / modes: {exc}")) from None
    if len(model.frequencies_hz) < 1:
        raise CaseError(f"modes: no mode below modes.f_max = {md.f_max:g} Hz; raise f_max or "
                        f"give modes.count")
    d = case.damping
    g = d.structural_g
    if d.modal_damping_ratio is None and g is None:
        g = s.structural_g_at(model.frequencies_hz)
    try:
        return with_damping(model, d.modal_damping_ratio, g)
    except ValueError as exc:
        raise CaseError(str(exc)) from None


@_door("the imported mesh's corners", "check the deck's GRIDs")
def imported_corner_points(case: Case) -> dict:
    """The imported mesh's four corners: the nodes of least and greatest x on its root
    (least y) and tip (greatest y) stations, (x, y) m."""
    nodes = case.structure.mesh.nodes
    tol = 1e-9 * max(float(np.ptp(nodes[:, 1])), 1.0)
    out = {}
    for name, y in (("root", nodes[:, 1].min()), ("tip", nodes[:, 1].max())):
        row = nodes[np.abs(nodes[:, 1] - y) <= tol]
        for edge, pick in (("le", np.argmin), ("te", np.argmax)):
            x, yy = row[pick(row[:, 0])]
            out[f"{name}_{edge}"] = (float(x), float(yy))
    return {k: out[k] for k in ("root_le", "root_te", "tip_le", "tip_te")}


@_door("the imported boxes", "check the deck's CAERO1 cards")
def imported_box_mesh(case: Case):
    """The imported structure's boxes; CaseError if it has none."""
    if case.structure.boxes is None:
        raise CaseError(f"{case.name}: the imported structure has no aerodynamic boxes "
                        f"(a deck without CAERO1): modes only")
    return case.structure.boxes


# ---------------------------------------------------------------------------------------------
# a stick model (case.beam: [[beam]], issue 24): the structure kind chosen at the seam
# ---------------------------------------------------------------------------------------------
_BEAM = "check beam[0] (stations, section properties, n_elements) and modes.count / f_max"


@lru_cache(maxsize=16)
def case_beam(case: Case) -> StraightBeam:
    """The case's ``[[beam]]`` as a :class:`~asekit.structure.beam.StraightBeam` (each segment
    between ``stations`` cut into ``n_elements`` equal elements); memoised on the case.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> case_beam(load_case(CASES_DIR / "goland_wing.toml")).n_nodes      # 32 elements
    33
    """
    b = case.beam
    stations, sections = [0.0], []
    for i, sec in enumerate(b.sections):
        s0, s1 = b.stations[i] * b.length, b.stations[i + 1] * b.length
        stations.extend(np.linspace(s0, s1, b.n_elements + 1)[1:].tolist())
        sections.extend([BeamSection(*sec)] * b.n_elements)
    return straight_beam(b.root, b.direction, stations, sections,
                         _beam_point_masses(b, np.asarray(stations)))


def _beam_point_masses(b, stations: np.ndarray) -> tuple:
    """The [[beam]] point_masses as :class:`~asekit.structure.beam.PointMass` es: offset and
    inertia given along (axis e1, aft a = e1 x e3, up e3), rotated to the global axes
    (offset = R^T o, inertia = R^T diag(I) R, R the rows e1, a, e3)."""
    from asekit.structure.beam import PointMass

    e1 = np.array([b.direction[0], b.direction[1], 0.0])
    e3 = np.array([0.0, 0.0, 1.0])
    R = np.array([e1, np.cross(e1, e3), e3])
    return tuple(PointMass(int(np.argmin(np.abs(stations - s))), m, R.T @ np.asarray(o),
                           R.T @ np.diag(inertia) @ R)
                 for s, m, o, inertia in b.point_masses)


def _beam_full_shapes(model: ModalModel) -> np.ndarray:
    """(6 n_nodes, n_modes) beam displacement vectors of a beam ModalModel's (uz, rx, ry)
    shapes (ux, uy and rz, in the plane, move no box)."""
    n_nodes, _, n_modes = model.shapes.shape
    full = np.zeros((n_nodes, NODE_DOF, n_modes))
    full[:, 2:5, :] = model.shapes
    return full.reshape(NODE_DOF * n_nodes, n_modes)


def _structure_spline(case: Case):
    """None for a plate (the FE shape functions), or the beam-to-box spline's named pair for
    :func:`asekit.aero.gaf.cached_gaf_database`."""
    if case.beam is None:
        return None
    beam = case_beam(case)

    def spline(model, boxes):
        try:
            ext = bool(getattr(case.beam, "spline_extension", False))
            g_cp, gx_cp = beam_spline_matrices(beam, boxes.control_point, extend=ext)
            g_lp, _ = beam_spline_matrices(beam, boxes.load_point, extend=ext)
        except ValueError as exc:
            raise CaseError(f"beam[0] / panel: {exc}") from None
        phi = _beam_full_shapes(model)
        return BoxModes(g_cp @ phi, gx_cp @ phi, g_lp @ phi)
    return ("beam (asekit.aero.beam_spline)", spline)


@_door("the modal model (beam eigenproblem)", _BEAM)
def beam_modal_model(case: Case) -> ModalModel:
    """The modal model (n_rigid = 0) of a stick-model case: the lowest ``modes.count`` modes
    of the clamped beam (:func:`asekit.structure.beam.beam_modes`), or those below
    ``modes.f_max`` (Hz), mass-normalised; ``nodes`` the beam's (x, y) node points and
    ``shapes`` their (uz, rx, ry), the plate's (w, theta_x, theta_y) in the global frame;
    no elements. Modal damping from ``[damping]``.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> m = modal_model(load_case(CASES_DIR / "goland_wing.toml"))
    >>> m.label, [round(float(f), 2) for f in m.frequencies_hz]
    ('beam, 32 elements, clamped root', [7.66, 15.23, 38.82])
    """
    beam = case_beam(case)
    md = case.modes
    fixed = getattr(case.beam, "in_plane", "free") == "fixed"
    per_node = 3 if fixed else NODE_DOF
    n_max = per_node * (beam.n_nodes - 1)
    n = min(md.count, n_max) if md.count is not None else n_max
    if md.count is not None and md.count > n_max:
        raise CaseError(f"modes.count must be <= {n_max} ({per_node} x the {beam.n_nodes - 1} "
                        f"beam elements), got {md.count}")
    modes = beam_modes(beam, n, in_plane_fixed=fixed)
    keep = (modes.frequencies_hz <= md.f_max if md.count is None
            else np.ones(n, bool))
    if not keep.any():
        raise CaseError(f"modes: no beam mode below modes.f_max = {md.f_max:g} Hz; raise f_max "
                        f"or give modes.count")
    f = modes.frequencies_hz[keep]
    shapes = modes.shapes[:, 2:5, :][:, :, keep]
    m = f.size
    model = ModalModel(f, np.eye(m), np.diag((2 * math.pi * f) ** 2), np.zeros((m, m)), 0, 0.0,
                       beam.nodes[:, :2].copy(), np.ascontiguousarray(shapes),
                       np.zeros((0, 4), int),
                       f"beam, {beam.n_nodes - 1} elements, clamped root"
                       + (", in-plane motion fixed" if fixed else ""))
    d = case.damping
    try:
        return _read_only(with_damping(model, d.modal_damping_ratio, d.structural_g))
    except ValueError as exc:
        raise CaseError(str(exc)) from None


# ---------------------------------------------------------------------------------------------
# aerodynamics
# ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=16)
@_door("the aerodynamic boxes", _AERO)
def box_mesh(case: Case):
    """The aerodynamic boxes (panels of the lifting-surface mesh) of the case.

    Per panel, ``aero.boxes`` (n_chord, n_span) or, with ``boxes = "auto"``, the mesh rule
    of the method used at each Mach (:func:`asekit.case.resources.box_counts`: box length
    against the shortest wavelength, aspect ratio); an imported structure's own boxes (CAERO1). The surfaces
    are named ``"surface"`` (one panel) or ``"panel<i>"``.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    BoxMesh
        ``corners`` (n_boxes, 4, 3) m, ``strip`` and ``surface`` indices per box; memoised
        on the case.

    Raises
    ------
    ValueError
        The dense DLM matrix of that many boxes would not fit in memory
        (:func:`asekit.aero.boxes.check_matrix_memory`); the message names ``aero.f_max``,
        ``aero.u_min`` or ``aero.boxes``.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> box_mesh(load_case(CASES_DIR / "agard445_6.toml")).corners.shape   # 16 x 16 boxes
    (256, 4, 3)
    """
    if case.structure is not None:
        return imported_box_mesh(case)
    a = case.aero
    counts = box_counts(case.panels, a)
    n_boxes = sum(nc * ns for nc, ns in counts)
    # refused before any box is made, naming the case keys that set the count
    check_matrix_memory(n_boxes, 1, 16, f"one DLM matrix of case {case.name!r} ({n_boxes} boxes"
                        f"{' from the mesh rules' if a.boxes is None else ''})",
                        "lower aero.f_max, raise aero.u_min or give aero.boxes"
                        if a.boxes is None else "lower aero.boxes")
    return mesh_surfaces(panel_surfaces(case.panels, counts))


@_door("the reduced frequencies", _AERO)
def reduced_frequencies(case: Case) -> np.ndarray:
    """The reduced frequencies k = omega b / U of the GAF database.

    ``aero.reduced_frequencies`` when given, otherwise :func:`default_reduced_frequencies` up
    to k_max = 2 pi f_max b / u_min (thesis Sec. 3.2.1; b = ``aero.reference_semichord`` m,
    f_max = ``aero.f_max`` Hz, u_min = ``aero.u_min`` m/s), so that the database covers every
    mode up to f_max at every speed down to u_min.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    numpy.ndarray
        (n_k,) ascending reduced frequencies (dimensionless).

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> k = reduced_frequencies(load_case(FIN_FILE))     # b = 0.078 m, 1000 Hz, 180 m/s
    >>> k.size, round(float(k[-1]), 4)
    (15, 2.7227)
    """
    return np.asarray(aero_reduced_frequencies(case.aero), float)


@_door("the GAF database (doublet lattice, Mach box or piston theory)", _AERO)
def gaf_database(case: Case, progress: bool = True, cache: bool = True,
                 path=None) -> GafDatabase:
    """The generalized aerodynamic forces Q_mm(M, k) of the case (thesis Sec. 2.2).

    Q_mm = Phi_a^T S A(M, k) W Phi_a: the pressures of the case's aerodynamic method
    (``aero.method``: doublet lattice, Mach box or piston theory) for the normalwash of each
    mode of :func:`modal_model` splined to the boxes of :func:`box_mesh`, integrated against
    each mode, over ``aero.machs`` x :func:`reduced_frequencies`. Forces are per unit
    dynamic pressure: the aerodynamic generalized force is q Q_mm x (q in Pa, x the modal
    coordinates; e.g. Q_cc of the rigid pitch mode in m^3/rad). Loaded from a shipped database (the fin's ``data/gaf_fin.npz``) or
    the user cache (``$ASEKIT_CACHE_DIR``) when one matches its fingerprint (mode set, boxes'
    corners, Mach, k, b_ref, symmetry, method), else computed and written there atomically
    (:func:`asekit.aero.gaf.cached_gaf_database`). A rebuild caches each (Mach, k) entry as it
    is computed, so a failed or interrupted run resumes where it stopped
    (:class:`asekit.aero.gaf.GafEntryCache`). Before anything is computed, the case's
    resources are checked (:func:`asekit.case.schema.check_resources`: a case built in Python
    skips the loader's check).

    Parameters
    ----------
    case : Case
        The case; it needs aerodynamics (``[aero]``).
    progress : bool, optional
        Show a progress bar while the database is computed (default True).
    cache : bool, optional
        Read and write the cache (default True); False always recomputes.
    path : str or pathlib.Path, optional
        A file to write the database to instead of the user cache.

    Returns
    -------
    GafDatabase
        ``machs`` (n_M,), ``k`` (n_k,), ``Q`` (n_M, n_k, n_modes, n_modes) complex,
        ``b_ref`` (m); ``at(mach)`` gives one Mach's table.

    Raises
    ------
    CaseError
        The case has no aerodynamics, or it is over a resource limit (the message names the
        case keys that change it and the values that fit).

    Examples
    --------
    The fin's database is shipped (4 Mach numbers x 15 k, 6 modes):

    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> db = gaf_database(load_case(FIN_FILE), progress=False)
    >>> db.machs.tolist(), db.Q.shape
    ([0.4, 0.5, 0.6, 0.75], (4, 15, 6, 6))
    """
    a = case.aero
    if a is None:
        raise CaseError(f"{case.name}: the case has no aerodynamics (an imported deck without "
                        f"CAERO1 / MKAERO1)")
    if case.structure is None:
        check_resources(case.panels, a)
    # the database's method: the DLM kernel name, or the aerodynamic method (asekit.aero.methods)
    method = a.kernel if a.method == "dlm" else a.method
    return cached_gaf_database(modal_model(case), box_mesh(case), a.machs,
                               reduced_frequencies(case), a.reference_semichord,
                               symmetric=a.symmetry == "wall", method=method,
                               progress=progress, rebuild=not cache, path=path,
                               metadata={"case": case.name}, spline=_structure_spline(case),
                               solver=a.solver, aero_options=_aero_options(a))


def _aero_options(aero) -> dict | None:
    """The aerodynamic method's options from the case (issue 29: the TSD's ``aero.section``)."""
    section = getattr(aero, "section", None)
    # issue 29 (tsdswept): the TSD's cross-flow terms of swept wings, always on in a case, and
    # the version of its GAFs (they enter the GAF database's fingerprint: older databases are
    # stale)
    from asekit.aero.tsd3d import TSD_GAF_FORMAT

    return None if section is None else {"section": tuple(section), "cross_flow": True,
                                         "tsd_format": TSD_GAF_FORMAT}


def tsd_validity(case: Case) -> tuple:
    """Issue 29: the :class:`asekit.aero.tsd3d.TsdValidity` of each of ``aero.machs`` for a
    case with ``aero.method = "tsd"`` (empty otherwise): the steady background over the
    case's section on the grid the GAFs used (:func:`asekit.aero.tsd3d.tsd_background` of
    :func:`box_mesh`, cached: the GAFs' own), its similarity parameter, supersonic nodes and Cp_min against Cp*."""
    a = case.aero
    if a is None or a.method != "tsd":
        return ()
    from asekit.aero.tsd3d import tsd_background
    from asekit.aero.tsd3d import tsd_validity as validity

    mesh = box_mesh(case)
    tau = a.section[1]
    return tuple(validity(tsd_background(mesh, m, tau), tau) for m in a.machs)


# ---------------------------------------------------------------------------------------------
# flutter
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlightCondition:
    """An analysed flight condition.

    Attributes
    ----------
    altitude : float or None
        Altitude (m); None when the case gives densities instead of altitudes.
    density : float
        Air density (kg/m^3).
    speed_of_sound : float or None
        Speed of sound (m/s); None when unknown (then no match point is computed).
    """

    altitude: float | None
    density: float
    speed_of_sound: float | None


@_door("the flight conditions", _FLUTTER)
def flight_conditions(case: Case) -> list[FlightCondition]:
    """The flight conditions the flutter analysis runs at.

    Per ``flight.altitudes`` (m) through the 1976 standard atmosphere
    (:func:`asekit.atmosphere.standard_atmosphere`), or per ``flight.densities`` (kg/m^3)
    with the optional ``flight.speeds_of_sound`` (m/s).

    Parameters
    ----------
    case : Case
        The case; it needs ``[flight]``.

    Returns
    -------
    list of FlightCondition
        One per altitude or density, in the case's order.

    Raises
    ------
    CaseError
        The case has no flight conditions.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> c = flight_conditions(load_case(FIN_FILE))[0]        # sea level
    >>> c.altitude, round(c.density, 3), round(c.speed_of_sound, 1)
    (0.0, 1.225, 340.3)
    """
    f = case.flight
    if f is None:
        raise CaseError(f"{case.name}: the case has no flight conditions (an imported deck "
                        f"without FLUTTER / FLFACT): give flight = FlightSpec(...)")
    if f.altitudes is not None:
        out = []
        for h in f.altitudes:
            atm = standard_atmosphere(h)
            out.append(FlightCondition(float(h), float(atm.density), float(atm.speed_of_sound)))
        return out
    sos = f.speeds_of_sound or (None,) * len(f.densities)
    return [FlightCondition(None, float(r), None if a is None else float(a))
            for r, a in zip(f.densities, sos)]


@dataclass(frozen=True)
class ConditionResult:
    """The flutter solution at one (Mach, flight condition).

    Attributes
    ----------
    mach : float
        Mach number.
    condition : FlightCondition
        The flight condition.
    pk : PkResult
        The tracked roots over ``flight.velocities`` (speeds m/s, frequencies Hz, V-g
        damping g = 2 Re p / abs(Im p), g > 0 unstable).
    instabilities : tuple of Instability
        Every crossing found.
    flutter, divergence : Instability or None
        The first of each kind (None if none in the sweep).
    unstable_at_start : bool
        The lowest speed of the sweep is already unstable (flutter or divergence at or below
        it: the sweep must start lower).
    start_mode : int or None
        The 0-based index (among the modes solved) of the mode unstable there (its
        user-facing name: ``asekit.util.conventions.mode_label(start_mode, pk.n_rigid)``).
    """

    mach: float
    condition: FlightCondition
    pk: PkResult
    instabilities: tuple[Instability, ...]
    flutter: Instability | None
    divergence: Instability | None
    unstable_at_start: bool
    start_mode: int | None


@dataclass(frozen=True)
class FlutterAnalysis:
    """The flutter analysis of a case (:func:`flutter`).

    Attributes
    ----------
    results : tuple of ConditionResult
        One per Mach and flight condition, Mach-major.
    divergence : tuple of dict
        Static divergence speed per Mach and condition: ``mach``, ``altitude_m``,
        ``density`` (kg/m^3), ``speed_ms`` (m/s, None when none).
    match_points : tuple of dict
        Per altitude, the Mach at which the flutter speed equals M a (the flight speed).
    margins : tuple of dict
        Per altitude inside the envelope, the flutter margin U_f / U_envelope - 1 at the
        envelope's top Mach (a fraction; negative: flutter inside the envelope).
    seconds : float
        Wall time of the analysis (s).
    notes : tuple of str
        Sentences on conditions already unstable at the sweep's first speed.
    """

    results: tuple[ConditionResult, ...]
    divergence: tuple[dict, ...]
    match_points: tuple[dict, ...]
    margins: tuple[dict, ...]
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)


@_door("the rational function approximation", _FLUTTER)
def rfa_at(case: Case, db: GafDatabase, mach: float):
    """The rational function approximation of the GAFs at one Mach number.

    Q(s) ~ A0 + A1 (s b/U) + A2 (s b/U)^2 + sum_n A_{n+2} s / (s + beta_n U/b) (Roger, thesis
    Eqs. 2.52-2.56) or the minimum-state form, as ``flutter.rfa`` says, with ``flutter.lags`` lag
    roots (:data:`asekit.rfa.methods.RFA_FITS`).

    Parameters
    ----------
    case : Case
        The case.
    db : GafDatabase
        The GAF database (:func:`gaf_database`).
    mach : float
        Mach number; the GAFs are interpolated linearly between the database's Mach numbers.

    Returns
    -------
    RogerFit or MinimumStateFit
        The fit (coefficient matrices, lag roots, fit error).
    """
    g = db.at(mach, interpolate=True)
    k, q = g.k, g.Q
    return rfa_kind(case.flutter.rfa).fit(k, q, db.b_ref, mach, case.flutter.lags)


@_door("the flutter solution", _FLUTTER)
def analyse_condition(case: Case, db: GafDatabase, mach: float, cond: FlightCondition,
                      model: ModalModel | None = None) -> ConditionResult:
    """Flutter at one Mach number and flight condition.

    The case's flutter method (``flutter.method``,
    :data:`asekit.aeroelastic.methods.FLUTTER_METHODS`; p-k by default) tracks the roots of
    the aeroelastic equation [M p^2 + C p + K - q Q(p)] x = 0 over ``flight.velocities`` (m/s)
    and finds where their damping changes sign.

    Parameters
    ----------
    case : Case
        The case.
    db : GafDatabase
        Its GAF database (:func:`gaf_database`); ``mach`` must be one of its Mach numbers.
    mach : float
        Mach number.
    cond : FlightCondition
        The flight condition (density kg/m^3).
    model : ModalModel, optional
        The modal model (default :func:`modal_model` of the case).

    Returns
    -------
    ConditionResult
        The tracked roots, every instability, the first flutter and divergence.
    """
    model = modal_model(case) if model is None else model
    gaf = db.at(mach)
    U = np.asarray(case.flight.velocities, float)
    method = flutter_method(case.flutter.method)
    rfa = rfa_at(case, db, mach) if method.needs_rfa else None
    pk, inst = method.solve(model, gaf, rfa, cond.density, U)
    inst = tuple(inst)
    start = [i for i in inst if i.at_first_point]          # unstable at U0 (asekit.aeroelastic.flutter)
    crossings = [i for i in inst if not i.at_first_point]
    result = ConditionResult(float(mach), cond, pk, inst, first_of(crossings, "flutter"),
                             first_of(crossings, "divergence"), bool(start),
                             start[0].mode if start else None)
    _log.debug("%s at M %g, rho %.4g kg/m^3, %g to %g m/s: %s", case.flutter.method, mach,
               cond.density, U[0], U[-1], result.flutter.describe() if result.flutter
               else "unstable at the first airspeed" if start else "no flutter in the sweep")
    return result


@_door("the flutter analysis", _FLUTTER)
def flutter(case: Case, progress: bool = False, db: GafDatabase | None = None) -> FlutterAnalysis:
    """Flutter at every ``aero.machs`` x flight condition by the case's ``flutter.method``
    (p-k with mode tracking by default, :data:`asekit.aeroelastic.methods.FLUTTER_METHODS`),
    divergence speeds (Eq. 3.13 eigenproblem on the steady GAFs), match points and flutter
    margins.

    The flutter speed at each condition is where a tracked root's V-g damping
    g = 2 Re p / abs(Im p) crosses zero upwards (``docs/conventions.md``); the divergence
    speed solves det(K - q Q(0)) = 0; a match point is the Mach at which the flutter speed
    equals the flight speed M a at that altitude.

    Parameters
    ----------
    case : Case
        The case; it needs ``[aero]`` and ``[flight]``.
    progress : bool, optional
        Show the GAF database's progress bar when it is computed, and a bar over the p-k
        solutions (Mach x flight condition) (default False).
    db : GafDatabase, optional
        A GAF database to use instead of :func:`gaf_database` (e.g. a sweep's).

    Returns
    -------
    FlutterAnalysis
        ``results`` (one :class:`ConditionResult` per Mach and condition: speeds m/s,
        frequencies Hz), ``divergence``, ``match_points``, ``margins``, ``notes``.

    Raises
    ------
    CaseError
        The case has no aerodynamics or no flight conditions.
    SolverError
        A numerical failure; the message names the case keys to check.

    Examples
    --------
    AGARD 445.6 weakened wing 3 at M 0.499 (Yates 1987 measured the flutter speed index 0.4459,
    U_f = 0.4459 b_s omega_alpha sqrt(mu) = 172 m/s with the case's [flutter_speed_index]; the
    linear doublet lattice lands 6 % above):

    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> (r,) = flutter(load_case(CASES_DIR / "agard445_6.toml")).results
    >>> round(r.flutter.speed), r.flutter.mode_name
    (182, 'mode 1')
    """
    t0 = time.perf_counter()
    model = modal_model(case)
    db = gaf_database(case, progress=progress) if db is None else db
    conds = flight_conditions(case)
    pairs = [(m, c) for m in case.aero.machs for c in conds]
    if progress:
        from tqdm.auto import tqdm
        pairs = tqdm(pairs, desc="p-k flutter (Mach x condition)", leave=False)
    results = ([analyse_condition(case, db, m, c, model) for m, c in pairs] if progress
               else _conditions_together(case, db, pairs, model))
    div = []
    for m in case.aero.machs:
        Q0 = db.at(m).Q[0].real
        for c in conds:
            sp = divergence_speeds(model, Q0, c.density)
            div.append({"mach": float(m), "altitude_m": c.altitude, "density": c.density,
                        "speed_ms": float(sp[0]) if sp.size else None})
    matches, margins = [], []
    env_m, env_h = case.flight.envelope_mach, case.flight.envelope_altitude
    U = case.flight.velocities
    for c in conds:
        if c.speed_of_sound is None:
            continue
        pts = flutter_points([r for r in results if r.condition == c], U)
        matches.append(match_point(c, pts))
        if env_m is not None and (env_h is None or c.altitude is None
                                  or env_h[0] <= c.altitude <= env_h[1]):
            margins.append(flutter_margin(c, pts, env_m[1]))
    notes = [start_note(r, U) for r in results if r.unstable_at_start]
    _log.info("flutter of %s: %d Mach x %d flight conditions, flutter.method %r over %d "
              "airspeeds each, in %.1f s", case.name, len(case.aero.machs), len(conds),
              case.flutter.method, len(U), time.perf_counter() - t0)
    return FlutterAnalysis(tuple(results), tuple(div), tuple(matches), tuple(margins),
                           time.perf_counter() - t0, tuple(notes))


# ---------------------------------------------------------------------------------------------
# aeroservoelasticity (thesis Ch. 5)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AseResult:
    """The aeroservoelastic loop at the actuator's flight condition (:func:`ase`).

    Attributes
    ----------
    model : AeroservoelasticModel
        The open-loop model (:func:`asekit.ase.loop.build_model`).
    controller : PDController
        The servo controller.
    mach, altitude, velocity : float
        The flight condition: Mach, altitude (m), speed (m/s).
    stable : dict
        Closed-loop stability per topology (``"AEM1"``: motor-angle feedback, ``"AEM2"``:
        fin-root feedback).
    max_real_pole : dict
        Largest real part of the closed-loop poles per topology (1/s).
    crossovers : dict
        Gain and phase crossovers of the forward-path transfer functions FWTF 1-3.
    simulations : dict
        The power-limited step responses per topology.
    settling_s : dict
        2 % settling time per topology (s; inf when it never settles).
    steady_error : dict
        Final error per topology, a fraction of the command.
    corner_overshoot : dict
        Per topology, the overshoot at each corner of the surface, a fraction of the command.
    """

    model: object
    controller: object
    mach: float
    altitude: float
    velocity: float
    stable: dict
    max_real_pole: dict
    crossovers: dict
    simulations: dict
    settling_s: dict
    steady_error: dict
    corner_overshoot: dict


@_door("the corner points", _STRUCTURE)
def corner_points(case: Case) -> dict:
    """The surface's four corners, where the ASE loop reads its outputs.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    dict
        ``root_le``, ``root_te`` (of the first panel), ``tip_le``, ``tip_te`` (of the last):
        (x, y) in m; of an imported structure: :func:`imported_corner_points`.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> list(corner_points(load_case(FIN_FILE)))
    ['root_le', 'root_te', 'tip_le', 'tip_te']
    """
    if case.structure is not None:
        return imported_corner_points(case)
    r, t = case.panels[0].planform, case.panels[-1].planform
    return {"root_le": r.root_le, "root_te": (r.root_le[0] + r.root_chord, r.root_le[1]),
            "tip_le": t.tip_le, "tip_te": (t.tip_le[0] + t.tip_chord, t.tip_le[1])}


@_door("the actuator", _ASE)
def actuator_setup(case: Case):
    """The servo-actuator of the case's ``[actuator]``: the keys it sets, asekit's defaults
    (thesis Tables 12, 16, 17) for the rest.

    Parameters
    ----------
    case : Case
        The case; it needs ``[actuator]``.

    Returns
    -------
    act : ActuatorParameters
        DC motor and transmission; the load inertia is 0 (the fin's inertia enters through
        its modal model, :func:`asekit.ase.loop.build_model`).
    ctl : PDController
        The controller (gain ``k_c``, ``k_p``, ``k_d``).
    lim : PowerLimits
        Supply voltage (V) and current limit (A).

    Raises
    ------
    CaseError
        The case has no ``[actuator]``.
    """
    a = case.actuator
    if a is None:
        raise CaseError("the case has no [actuator]")

    def given(pairs):            # {servo field: case value} for the keys the case sets
        return {dst: getattr(a, src) for src, dst in pairs if getattr(a, src) is not None}

    act = ActuatorParameters(DCMotor(**given(zip(MOTOR_KEYS, MOTOR_KEYS))),
                             Transmission(**given(TRANSMISSION_KEYS.items())), fin_inertia=0.0)
    ctl = replace(SYSTEM_3, name="case controller",
                  **given((("k_c", "gain"), ("k_p", "kp"), ("k_d", "kd"))))
    lim = replace(THESIS_LIMITS, **given((("supply_voltage", "supply_voltage"),
                                          ("current_limit", "current_limit"))))
    return act, ctl, lim


@dataclass(frozen=True)
class AseCondition:
    """A case's aeroservoelastic model at one flight condition and what it was built from.

    Attributes
    ----------
    model : AeroservoelasticModel
        The state-space model (:class:`asekit.ase.loop.AeroservoelasticModel`).
    modal : ModalModel
        The modal model.
    rfa : RogerFit or MinimumStateFit
        The rational fit at ``mach``.
    q_cc : float
        Steady Re Q_cc at ``mach`` and the database's lowest k (m^3/rad).
    mach : float
        Mach number.
    altitude : float
        Altitude (m).
    density : float
        Air density (kg/m^3).
    velocity : float
        Flight speed (m/s).
    """

    model: object
    modal: object
    rfa: object
    q_cc: float
    mach: float
    altitude: float
    density: float
    velocity: float

    @property
    def dynamic_pressure(self) -> float:
        """q = rho U^2 / 2 (Pa)."""
        return 0.5 * self.density * self.velocity ** 2

    def rigid_fin_actuator(self):
        """The thesis's Ch. 4 design model: the actuator with the rigid surface's pitch inertia
        J_fin (of the structural model) as its load."""
        return replace(self.model.actuator, fin_inertia=float(self.modal.J_fin))

    def steady_hinge_moment(self):
        """The Ch. 4 steady hinge moment q Q_cc theta at this flight condition
        (:class:`asekit.servo.simulate.SteadyHingeMoment`)."""
        atm = standard_atmosphere(self.altitude)
        return SteadyHingeMoment(q_cc=self.q_cc, mach=self.mach, density=float(atm.density),
                                 speed_of_sound=float(atm.speed_of_sound))


@_door("the aeroservoelastic model", _ASE)
def ase_condition(case: Case, mach: float | None = None, altitude: float | None = None,
                  actuator=None, count_fin_inertia_twice: bool = False, n_lags: int | None = None,
                  fit=None, db: GafDatabase | None = None,
                  modal: ModalModel | None = None) -> AseCondition:
    """The case's aeroservoelastic model (thesis Ch. 5) at (``mach``, ``altitude`` m).

    The GAFs of :func:`gaf_database` at ``mach`` (interpolated linearly between the database's
    Mach numbers; outside them a ValueError), the case's RFA (``flutter.rfa``, Roger by
    default) with ``n_lags`` lag roots (default ``flutter.lags``, 4), or ``fit(k, Q, b_ref,
    mach) -> RFA`` (e.g. :func:`asekit.rfa.minimum_state_fit`), the 1976
    standard atmosphere at ``altitude`` and U = mach x speed of sound, assembled by
    :func:`asekit.ase.loop.build_model`. Outputs: the root pitch at the shaft (the AEM2 feedback),
    ``theta_<corner>`` and ``w_<corner>`` at the four corners of :func:`corner_points`, and
    the modal coordinates.

    Parameters
    ----------
    case : Case
        A shaft-supported case with a rigid pitch mode (FN2, ``modes.keep_rigid``).
    mach : float, optional
        Mach number (default ``[actuator.condition]``, else 0.5).
    altitude : float, optional
        Altitude (m; default ``[actuator.condition]``, else 0 m).
    actuator : ActuatorParameters, optional
        The servo-actuator (:class:`asekit.servo.actuator.ActuatorParameters`; default:
        build_model's, the thesis's).
    count_fin_inertia_twice : bool, optional
        The thesis's Simulink choice (see :func:`asekit.ase.loop.build_model`).
    n_lags : int, optional
        Lag roots of the rational fit (default ``flutter.lags``).
    fit : callable, optional
        ``fit(k, Q, b_ref, mach) -> RFA`` replacing the case's fit.
    db : GafDatabase, optional
        A GAF database to use instead of the case's.
    modal : ModalModel, optional
        The modal model of ``db`` (default the case's).

    Returns
    -------
    AseCondition
        The model and what it was built from.

    Raises
    ------
    ValueError
        ``mach`` outside the database's Mach range, or not finite.
    """

    a = case.actuator
    mach = finite("mach", (a.mach if a is not None else 0.5) if mach is None else mach)
    altitude = finite("altitude", (a.altitude if a is not None else 0.0) if altitude is None
                      else altitude)
    shaft = _shaft(case, "ase_condition")
    db = gaf_database(case, progress=False) if db is None else db
    modal = modal_model(case) if modal is None else modal
    lo, hi = float(np.min(db.machs)), float(np.max(db.machs))
    if not lo <= mach <= hi:
        raise ValueError(f"mach must lie within the GAF database's range [{lo}, {hi}], "
                         f"got {mach}")
    g = db.at(mach, interpolate=True)
    k, q = g.k, g.Q
    lags = case.flutter.lags if n_lags is None else n_lags
    rfa = (rfa_kind(case.flutter.rfa).fit(k, q, db.b_ref, mach, lags) if fit is None
           else fit(k, q, db.b_ref, mach))
    atm = standard_atmosphere(altitude)
    rho, sos = float(atm.density), float(atm.speed_of_sound)
    corners = corner_points(case)
    rows = fin_outputs(modal, np.array(list(corners.values())), names=list(corners),
                       shaft_point=shaft.axis_point)
    model = ase_mod.build_model(modal, rfa, rho, mach * sos, rows, actuator=actuator, mach=mach,
                                count_fin_inertia_twice=count_fin_inertia_twice)
    return AseCondition(model=model, modal=modal, rfa=rfa, q_cc=float(np.real(q[0, 0, 0])),
                        mach=mach, altitude=altitude, density=rho, velocity=mach * sos)


@_door("the ASE loop", _ASE)
def ase(case: Case, db: GafDatabase | None = None) -> AseResult | None:
    """The aeroservoelastic analysis of the case's actuator (thesis Ch. 5).

    At the actuator's flight condition (``[actuator.condition]``), builds the ASE model
    (:func:`ase_condition`: structure + RFA aerodynamics + DC motor, transmission and PD
    controller of ``[actuator]``), closes the loop with motor-angle (AEM1) and fin-root (AEM2)
    feedback, checks the closed-loop poles, computes the crossovers of the forward-path
    transfer functions FWTF 1-3 and simulates a power-limited step of ``actuator.step_deg``
    (deg) over 0.2 s.

    Parameters
    ----------
    case : Case
        The case; without ``[actuator]`` nothing is computed.
    db : GafDatabase, optional
        A GAF database to use instead of :func:`gaf_database`.

    Returns
    -------
    AseResult or None
        Stability, pole real parts (1/s), crossovers, step responses, settling times (s),
        steady errors and corner overshoots (fractions of the command); None without
        ``[actuator]``.
    """
    if case.actuator is None:
        return None

    a = case.actuator
    act, ctl, lim = actuator_setup(case)
    cond = ase_condition(case, a.mach, a.altitude, actuator=act, db=db)
    m, U, corners = cond.model, cond.velocity, corner_points(case)
    stable, maxre, sims, settle, err, over = {}, {}, {}, {}, {}, {}
    step = math.radians(a.step_deg)
    for topo in ase_mod.TOPOLOGIES:
        loop = ase_mod.closed_loop(m, ctl, topo)
        poles = np.linalg.eigvals(np.asarray(loop.A))
        maxre[topo] = float(poles.real.max())
        stable[topo] = bool(maxre[topo] < 0)
        sim = ase_mod.simulate_closed_loop(m, ctl, step, topo, limits=lim, t_final=0.2)
        sims[topo] = sim
        y = sim.fin_root
        settle[topo] = float(metrics.settling_time(sim.t, y, step, step, band=0.02))
        err[topo] = float(abs(y[-1] - step) / step)
        over[topo] = {c: float(metrics.overshoot(sim.outputs[f"theta_{c}"], step))
                      for c in corners}
    cross = {i: ase_mod.crossovers(ase_mod.forward_path(m, ctl, i)) for i in (1, 2, 3)}
    return AseResult(m, ctl, a.mach, a.altitude, U, stable, maxre, cross, sims, settle, err,
                     over)


# ---------------------------------------------------------------------------------------------
# control surfaces (issue 25)
# ---------------------------------------------------------------------------------------------
_CONTROL = "check [[control_surface]] (panel, hinge_chord_fraction, span_fraction, hinge keys)"


@lru_cache(maxsize=8)
@_door("the control-surface boxes", _CONTROL)
def control_surface_mesh(case: Case):
    """The case's boxes cut along its control surfaces' hinge lines and side edges
    (:func:`asekit.aero.control_surface.hinged_mesh`), the panel's box counts as
    :func:`box_mesh`; one-panel cases. Memoised on the case."""
    from asekit.aero.control_surface import ControlSurface, hinged_mesh

    if not case.control_surfaces:
        raise CaseError(f"{case.name}: the case has no [[control_surface]]")
    if case.structure is not None:            # an imported deck: its one CAERO1 (AESURF)
        panels = case.structure.panels
        if len(panels) != 1:
            raise CaseError(f"control_surface: control surfaces need one lifting surface (the "
                            f"imported structure has {len(panels)} panels)")
        surface = panels[0]
    elif len(case.panels) != 1:
        raise CaseError(f"control_surface: control surfaces need a one-panel case file (this "
                        f"case has {len(case.panels)} panels)")
    else:
        surface = panel_surfaces(case.panels, box_counts(case.panels, case.aero))[0]
    specs = [ControlSurface(c.name, *c.hinge_chord_fraction, *c.span_fraction)
             for c in case.control_surfaces]
    try:
        return hinged_mesh(surface, specs)
    except ValueError as exc:
        raise CaseError(f"control_surface: {exc}") from None


@lru_cache(maxsize=8)
@_door("the modal model with the hinge coordinates", _CONTROL)
def control_surface_model(case: Case):
    """The wing's modal model (:func:`modal_model`, surfaces locked) with one hinge coordinate
    per control surface, its hinge spring, damper and balance masses
    (:func:`asekit.aeroelastic.control_surface.flap_modal_model`); for ``kind = "elastic"``
    the plate released along the hinge, reduced to fixed-hinge modes plus the hinge rotation
    (:func:`_elastic_surface_model`). Linked surfaces (``linked_to``, ``gear_ratio``: AELINK)
    are eliminated: each moves with its master, whose coordinate carries it
    (:func:`asekit.aeroelastic.control_surface.link_surfaces`; ``names`` the free surfaces).
    Memoised on the case."""
    hm = control_surface_mesh(case)
    if _surface_links(case):
        from asekit.aeroelastic.control_surface import link_surfaces
        return link_surfaces(_unlinked_surface_model(case, hm), _surface_links(case))
    return _unlinked_surface_model(case, hm)


def _unlinked_surface_model(case: Case, hm):
    """:func:`control_surface_model` with every surface free."""
    from asekit.aeroelastic.control_surface import BalanceMass, flap_modal_model

    cs = case.control_surfaces
    if any(c.kind == "elastic" for c in cs):
        return _elastic_surface_model(case, hm)
    _, m_fe = mass_and_stiffness(case)
    balance = tuple(BalanceMass(i, x, y, m) for i, c in enumerate(cs)
                    for (x, y), m in c.mass_balance)
    return flap_modal_model(modal_model(case), m_fe, hm, [c.hinge_stiffness for c in cs],
                            [c.hinge_damping for c in cs], balance)


def _surface_links(case: Case) -> tuple:
    """The case's AELINK links, (slave, master, gear_ratio) surface indices
    (``control_surface[i].linked_to``, :func:`asekit.aero.control_surface.gearing_matrix`)."""
    names = [c.name for c in case.control_surfaces]
    return tuple((i, names.index(c.linked_to), c.gear_ratio)
                 for i, c in enumerate(case.control_surfaces) if c.linked_to)


@dataclass(frozen=True)
class ControlSurfaceRow:
    """Steady results of one control surface at one Mach number (rigid derivatives per rad,
    C_h = H / (q S_f c_f); the flexible rolling-moment effectiveness against speed at
    ``density`` (kg/m^3), the first flight condition, the surfaces held at their deflection;
    reversal and divergence speeds in m/s, None when not found below ``speed_limit_ms``;
    pitching moment Cm = M_y / (q S c_ref) about the mean aerodynamic chord's quarter point,
    nose up positive (:func:`asekit.aero.control_surface.steady_control_derivatives`); the rigid
    rolling moment about y = 0 of the half model per unit dynamic pressure and per rad of the
    deflection, m^3, positive for lift at y > 0, with the antisymmetric image at a wall)."""

    name: str
    mach: float
    dCL_ddelta_per_rad: float
    dCL_dalpha_per_rad: float
    Ch_delta: float
    Ch_alpha: float
    density: float
    speeds_ms: np.ndarray
    effectiveness_ratio: np.ndarray
    reversal_speed_ms: float | None
    divergence_speed_ms: float | None
    speed_limit_ms: float
    inertia: float
    static_unbalance: float
    dCm_ddelta_per_rad: float = math.nan
    dCm_dalpha_per_rad: float = math.nan
    rolling_moment_per_rad_m3: float = math.nan


@_memo_with_warnings
@_door("the control-surface effectiveness and reversal (vortex lattice)", _CONTROL)
def control_surfaces(case: Case) -> tuple[ControlSurfaceRow, ...]:
    """Control effectiveness, hinge-moment derivatives and reversal of every control surface
    at every subsonic Mach of ``aero.machs`` (vortex lattice, :mod:`asekit.aero.vlm`).

    Rigid: dCL/d alpha, dCL/d delta, C_h alpha, C_h delta
    (:func:`asekit.aero.control_surface.steady_control_derivatives`, the wall's image when
    ``aero.symmetry = "wall"``). Flexible: the rolling moment about the root (y = 0) per unit
    deflection over its rigid value against speed, at the first flight condition's density,
    with the antisymmetric image at a wall (ailerons deflected in opposite senses), and the
    reversal speed where it crosses zero (:func:`asekit.aeroelastic.control_surface.
    static_effectiveness`), searched up to twice the highest flight velocity.

    Parameters
    ----------
    case : Case
        A one-panel case with ``[[control_surface]]``.

    Returns
    -------
    tuple of ControlSurfaceRow
        Surface by surface, Mach by Mach (Machs >= 1 are skipped: the vortex lattice is
        subsonic). Memoised on the case.
    """
    from asekit.aero.control_surface import steady_control_derivatives
    from asekit.aeroelastic.control_surface import static_effectiveness

    hm = control_surface_mesh(case)
    fm = control_surface_model(case)
    rho = flight_conditions(case)[0].density
    u_lim = 2.0 * float(max(case.flight.velocities))
    wall = case.aero.symmetry == "wall"
    rows = []
    for mach in case.aero.machs:
        if mach >= 1.0:
            continue
        d = steady_control_derivatives(hm, mach, symmetric=wall, links=_surface_links(case))
        se = static_effectiveness(fm, hm, mach, 0.5 * rho * u_lim ** 2, n_q=41,
                                  image="antisymmetric" if wall else "none")
        u_r = se.reversal_speed(rho)
        u_d = math.sqrt(2.0 * se.divergence_q / rho) if math.isfinite(se.divergence_q) else None
        for i, name in enumerate(fm.names):
            rows.append(ControlSurfaceRow(
                name, float(mach), float(d.dCL_ddelta[i]), float(d.dCL_dalpha),
                float(d.Ch_delta[i]), float(d.Ch_alpha[i]), float(rho),
                np.sqrt(2.0 * se.dynamic_pressure / rho), se.ratio[i],
                None if not math.isfinite(u_r[i]) else float(u_r[i]),
                None if u_d is None or u_d > u_lim else u_d, u_lim,
                float(fm.inertia[i]), float(fm.static_unbalance[i]),
                float(d.dCm_ddelta[i]), float(d.dCm_dalpha), float(se.rigid[i])))
    return tuple(rows)


@dataclass(frozen=True)
class ControlSurfaceFlutterRow:
    """Flutter with the hinge coordinates free (on their springs) at one Mach and flight
    condition: ``speed_ms`` and ``frequency_hz`` of the first flutter crossing (None: none in
    the sweep, or ``unstable_at_first_point``), ``mode`` its tracked column's name (the
    surface's name for a hinge coordinate, else the elastic mode number from 1)."""

    mach: float
    altitude: float | None
    density: float
    speed_ms: float | None
    frequency_hz: float | None
    mode: object
    unstable_at_first_point: bool


def _column_name(index: int, n_rigid: int, n_wing: int, names) -> object:
    from asekit.util.conventions import mode_number
    return names[index - n_wing] if index >= n_wing else mode_number(index, n_rigid)


@_memo_with_warnings
@_door("the flutter with the hinge degrees of freedom (p-k)", _CONTROL)
def control_surface_flutter(case: Case) -> tuple[ControlSurfaceFlutterRow, ...]:
    """p-k flutter of the case with its control surfaces free on their hinge springs
    (:func:`control_surface_model`), at every ``aero.machs`` x flight condition over
    ``flight.velocities``, the rigid modes held as in :func:`flutter`. The GAFs are those of the
    wing's modes and the surfaces' deflections (:func:`control_surface_mesh`, the case's
    ``aero.method``; computed, not cached). Memoised on the case.

    Returns
    -------
    tuple of ControlSurfaceFlutterRow
        Mach by Mach, condition by condition.
    """
    from asekit.aero.gaf import build_gaf_database
    from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities

    hm = control_surface_mesh(case)
    fm = control_surface_model(case)
    a = case.aero
    method = a.kernel if a.method == "dlm" else a.method
    db = build_gaf_database(fm.box_modes, hm.mesh, a.machs, reduced_frequencies(case),
                            a.reference_semichord, fm.modal.n_rigid,
                            symmetric=a.symmetry == "wall", method=method, progress=False)
    U = np.asarray(case.flight.velocities, float)
    rows = []
    for m in a.machs:
        gaf = db.at(m)
        for c in flight_conditions(case):
            res = pk_flutter(fm.modal, gaf, c.density, U)
            inst = pk_instabilities(res, fm.modal, gaf, c.density)
            start = [i for i in inst if i.at_first_point]
            f = first_of([i for i in inst if not i.at_first_point], "flutter")
            f = None if start else f
            # f.mode counts the modes solved (the rigid ones held): back to the model's index
            mode = None if f is None else _column_name(f.mode + fm.modal.n_rigid - res.n_rigid,
                                                       fm.modal.n_rigid, fm.n_wing, fm.names)
            rows.append(ControlSurfaceFlutterRow(
                float(m), c.altitude, c.density, None if f is None else float(f.speed),
                None if f is None else float(f.frequency_hz), mode, bool(start)))
    return tuple(rows)


def _elastic_splits(case: Case, hm, which=None):
    """Each elastic surface's plate elements and the mesh split at all their hinges
    (:func:`asekit.structure.hinge.split_at_hinges`), the case's errors naming the key;
    ``which`` the indices of the surfaces split (None: all)."""
    from asekit.aeroelastic.control_surface import surface_elements
    from asekit.structure.hinge import split_at_hinges

    mesh = structural_mesh(case)
    idx = list(range(len(case.control_surfaces))) if which is None else list(which)
    flaps = []
    for i in idx:
        try:
            flaps.append(surface_elements(mesh, hm, i))
        except ValueError as exc:
            raise CaseError(f"control_surface[{i}].hinge_chord_fraction / span_fraction: {exc} "
                            f"(choose panel.n_chord, n_span or their spacing so that node "
                            f"lines fall there)") from None
    for n in range(1, len(flaps) + 1):     # surface by surface, so the error names its key
        try:
            splits = split_at_hinges(mesh, flaps[:n], hm.hinge_point[idx[:n], :2],
                                     hm.hinge_axis[idx[:n], :2])
        except ValueError as exc:
            raise CaseError(f"control_surface[{idx[n - 1]}].hinge_chord_fraction / "
                            f"span_fraction: {exc} (choose panel.n_chord, n_span or their "
                            f"spacing so that node lines fall there)") from None
    return flaps, splits


def _elastic_surface_model(case: Case, hm):
    """``kind = "elastic"``: the plate released along each surface's hinge
    (:func:`asekit.structure.hinge.release_hinges`, one hinge rotation per surface on its own
    hinge spring and damper, the case's supports on the wing; the ``mass_balance`` masses on
    rigid arms from their surface's hinge line,
    :func:`asekit.structure.hinge.hinge_balance_mass`) reduced to the wing's ``modes`` count of
    fixed-hinge modes plus the hinge rotations
    (:func:`asekit.aeroelastic.control_surface.elastic_flap_modal_model`). Several elastic
    surfaces side by side are allowed, and rigid surfaces beside them
    (:func:`_mixed_surface_model`: only the elastic ones are split and released)."""
    from asekit.aeroelastic.control_surface import elastic_flap_modal_model
    from asekit.structure.hinge import hinge_balance_mass, release_hinges

    cs = case.control_surfaces
    el = [i for i, c in enumerate(cs) if c.kind == "elastic"]
    if case.structure is not None or modal_model(case).n_rigid:
        raise CaseError(f"control_surface[{el[0]}].kind = \"elastic\" needs a plate case file "
                        f"whose support has no rigid mode (clamped, or modes.keep_rigid = "
                        f"false)")
    mixed = len(el) < len(cs)
    flaps, splits = _elastic_splits(case, hm, el if mixed else None)
    system = supported_system(case)
    support = system.T
    held = np.asarray(abs(support).sum(axis=1)).ravel()[0::3] == 0     # w held, per node
    n0 = splits[0].n_original
    for i, flap, split in zip(el, flaps, splits):
        c = cs[i]
        own = np.unique(split.mesh.elements[flap])
        own = own[own < n0]
        if np.any(held[own]):
            raise CaseError(f"control_surface[{i}].span_fraction {list(c.span_fraction)}: the "
                            f"elastic surface reaches the support (support.kind = "
                            f"\"{case.support.kind}\"), which would hold it: end it short of "
                            f"the supported edge")
    mesh = splits[0].mesh
    K, M = assemble(mesh, case.material)
    if case.point_masses:
        M = (M + point_mass_matrix(mesh, [(p.position, p.mass, p.inertia)
                                          for p in case.point_masses])).tocsr()
    for i, split in zip(el, splits):
        for (x, y), m_b in cs[i].mass_balance:      # on rigid arms from the surface's hinge
            d_b = float(hm.distance_aft(i, np.array([[x, y, 0.0]]))[0])
            M = (M + hinge_balance_mass(split, (x, y), d_b, m_b)).tocsr()
    K0, M0 = mass_and_stiffness(case)          # the support's own springs and masses
    released = release_hinges(splits, K, M, [cs[i].hinge_stiffness for i in el],
                              [cs[i].hinge_damping for i in el], support=support,
                              support_stiffness=system.K - support.T @ K0 @ support,
                              support_mass=system.M - support.T @ M0 @ support)
    model = modal_model(case)
    d = case.damping
    try:
        if mixed:
            return _mixed_surface_model(case, hm, released, M, len(model.frequencies_hz))
        return elastic_flap_modal_model(released, M, hm, len(model.frequencies_hz),
                                        d.modal_damping_ratio, d.structural_g)
    except ValueError as exc:
        path = "control_surface[0]" if len(cs) == 1 else "control_surface"
        raise CaseError(f"{path}: {exc}") from None


def _mixed_surface_model(case: Case, hm, released, M, n_modes: int):
    """Rigid and elastic surfaces in one case (issue 25): the released plate of the elastic
    ones (:func:`_elastic_surface_model`) with the rigid surfaces' hinge rotations, springs,
    dampers and balance masses as the rigid kind builds them
    (:func:`asekit.aeroelastic.control_surface.mixed_flap_modal_model`)."""
    from asekit.aeroelastic.control_surface import BalanceMass, mixed_flap_modal_model

    cs = case.control_surfaces
    balance = tuple(BalanceMass(i, x, y, m) for i, c in enumerate(cs) if c.kind == "rigid"
                    for (x, y), m in c.mass_balance)
    d = case.damping
    return mixed_flap_modal_model(released, M, hm, [c.kind for c in cs], n_modes,
                                  [c.hinge_stiffness for c in cs],
                                  [c.hinge_damping for c in cs], balance,
                                  d.modal_damping_ratio, d.structural_g)


# ---------------------------------------------------------------------------------------------
# control surfaces: hinge moments over the envelope for servo sizing (issue 25)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HingeLoadRow:
    """The rigid hinge moments of one control surface at one flight point: ``mach``,
    ``altitude`` (m, None for a density-only condition), ``density`` (kg/m^3), ``speed_ms``
    (m/s), ``dynamic_pressure`` (Pa), ``hinge_moment_per_delta`` and
    ``hinge_moment_per_alpha`` (N m/rad, H = q S_f c_f C_h; the actuator holding the surface
    applies -H), ``basis`` "envelope" or "sweep top"."""

    name: str
    mach: float
    altitude: float | None
    density: float
    speed_ms: float
    dynamic_pressure: float
    hinge_moment_per_delta: float
    hinge_moment_per_alpha: float
    basis: str


def _hinge_load_points(case: Case) -> list[tuple[float, float | None, float, float, str]]:
    """(Mach, altitude, density, speed, basis) of the hinge-load points: with
    ``[flight.envelope]`` its Mach ends and the ``aero.machs`` inside it, at its altitude ends
    (else the case's altitudes), U = M a(h); without, every ``aero.machs`` at every flight
    condition at the top of the velocity sweep. Machs >= 1 are left out (vortex lattice)."""
    from asekit.atmosphere import standard_atmosphere

    env_m, env_h = case.flight.envelope_mach, case.flight.envelope_altitude
    conds = flight_conditions(case)
    if env_m is not None:
        machs = sorted({*env_m, *(m for m in case.aero.machs if env_m[0] <= m <= env_m[1])})
        alts = sorted(set(env_h)) if env_h is not None else sorted(
            {c.altitude for c in conds if c.altitude is not None})
        if alts:
            out = []
            for h in alts:
                atm = standard_atmosphere(h)
                out += [(float(m), float(h), float(atm.density), float(m * atm.speed_of_sound),
                         "envelope") for m in machs if m < 1.0]
            return out
    u = float(max(case.flight.velocities))
    return [(float(m), c.altitude, float(c.density), u, "sweep top")
            for m in case.aero.machs if m < 1.0 for c in conds]


@_memo_with_warnings
@_door("the hinge moments over the envelope (vortex lattice)", _CONTROL)
def control_surface_hinge_loads(case: Case) -> tuple[HingeLoadRow, ...]:
    """Rigid hinge moments of every control surface per unit deflection and per unit
    incidence over the flight envelope, for servo (actuator) sizing:
    H = q S_f c_f C_h (:func:`asekit.aero.control_surface.dimensional_hinge_moments`) with
    C_h from the vortex lattice at each point's Mach
    (:func:`asekit.aero.control_surface.steady_control_derivatives`, the wall's image when
    ``aero.symmetry = "wall"``) and q = rho U^2 / 2 at the points of
    :func:`_hinge_load_points` (the envelope's corners and the analysed Machs inside it, or
    the top of the velocity sweep without an envelope).

    Returns
    -------
    tuple of HingeLoadRow
        Point by point (altitude, then Mach), surface by surface. Memoised on the case.
    """
    from asekit.aero.control_surface import dimensional_hinge_moments, steady_control_derivatives

    hm = control_surface_mesh(case)
    wall = case.aero.symmetry == "wall"
    links = _surface_links(case)
    free = [i for i in range(len(hm.surfaces)) if i not in {k[0] for k in links}]
    derivs = {}
    rows = []
    for m, h, rho, u, basis in _hinge_load_points(case):
        if m not in derivs:
            derivs[m] = steady_control_derivatives(hm, m, symmetric=wall, links=links)
        q = 0.5 * rho * u * u
        if links:                       # the free surfaces, each with its geared surfaces
            sc = np.array([hm.surface_area(i) * hm.mean_chord(i) for i in free])
            h_d, h_a = q * sc * derivs[m].Ch_delta, q * sc * derivs[m].Ch_alpha
        else:
            h_d, h_a = dimensional_hinge_moments(hm, derivs[m], q)
        rows += [HingeLoadRow(hm.surfaces[i].name, m, h, rho, u, q, float(h_d[j]),
                              float(h_a[j]), basis) for j, i in enumerate(free)]
    return tuple(rows)


# ---------------------------------------------------------------------------------------------
# control surfaces: the ASE loop with the actuator on a surface's hinge (issue 25)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ControlSurfaceAseRow:
    """The closed loop of the actuator on control surface ``name`` at one flight condition
    (``[control_surface.actuator]``) for one ``topology`` (AEM1: hinge-angle feedback; AEM2:
    the surface's angle in the air): ``stable`` and ``max_real_pole`` (1/s) of the linear
    closed loop, ``effective_inertia`` J_eff (kg m^2) the actuator's load, the forward path's
    smallest ``phase_margin_deg``, ``gain_margin_db`` (inf: no phase crossover) and
    ``crossover_hz`` (FWTF 2 for AEM1, FWTF 3 for AEM2, thesis Sec. 5.2), and of a power-limited
    step of ``step_deg`` the 2 % ``settling_time_s`` of the fed-back angle (AEM1 the hinge
    angle, AEM2 the surface's angle; None: not settled in 0.2 s), the ``overshoot`` (fraction)
    and ``steady_error`` (fraction, at 0.2 s) of the surface's angle in the air (under AEM1 the
    wing's twist under the surface's load stays in it)."""

    name: str
    topology: str
    mach: float
    altitude: float
    speed_ms: float
    dynamic_pressure: float
    stable: bool
    max_real_pole: float
    effective_inertia: float
    phase_margin_deg: float
    gain_margin_db: float
    crossover_hz: float | None
    step_deg: float
    settling_time_s: float | None
    overshoot: float
    steady_error: float
    # for the report's loop figures (asekit.case.report_figures.fig_control_ase_*): the step
    # response (time s, the surface's angle in the air and the fed-back angle, rad), the open
    # loop (forward path) on a frequency grid (Hz, complex) and its crossovers
    time_s: np.ndarray | None = None
    surface_angle_rad: np.ndarray | None = None
    fed_back_rad: np.ndarray | None = None
    frequency_hz: np.ndarray | None = None
    open_loop: np.ndarray | None = None
    crossovers: object = None


_CONTROL_ASE = ("check [control_surface.actuator] (speed, mach, altitude) and the "
                "[[control_surface]] keys")


@_door("the control surface's actuator loop", _CONTROL_ASE)
def control_surface_ase_condition(case: Case):
    """The ASE model of the case's actuated control surface (:mod:`asekit.ase.flap`) at its
    ``[control_surface.actuator]`` condition: the GAFs of the wing's modes and the surfaces'
    deflections at that Mach (the case's ``aero.method``; computed, not cached), reordered
    hinge first and fitted by the case's RFA (``flutter.rfa``, ``flutter.lags``).

    Returns
    -------
    (index, spec, AeroservoelasticModel)
        The actuated surface's index, its ``[[control_surface]]`` spec and the model (thesis
        actuator, its load the surface's effective inertia).
    """
    from asekit.aero.gaf import build_gaf_database
    from asekit.ase import flap

    act = [i for i, c in enumerate(case.control_surfaces) if c.actuator is not None]
    if not act:
        raise CaseError(f"{case.name}: no [[control_surface]] has an actuator "
                        "([control_surface.actuator])")
    i = act[0]
    spec = case.control_surfaces[i]
    a = spec.actuator
    hm = control_surface_mesh(case)
    fm = control_surface_model(case)
    modal, order = flap.hinge_actuated_modal(fm, i)
    row = flap.surface_angle_row(modal_model(case), hm, i, order)
    ae = case.aero
    method = ae.kernel if ae.method == "dlm" else ae.method
    db = build_gaf_database(fm.box_modes, hm.mesh, [a.mach], reduced_frequencies(case),
                            ae.reference_semichord, 0, symmetric=ae.symmetry == "wall",
                            method=method, progress=False)
    g = db.at(a.mach)
    rfa = rfa_kind(case.flutter.rfa).fit(g.k, flap.reorder_modes(g.Q, order), db.b_ref, a.mach,
                                         case.flutter.lags)
    rho = float(standard_atmosphere(a.altitude).density)
    return i, spec, flap.flap_ase_model(modal, rfa, rho, a.speed, row, mach=a.mach)


@_memo_with_warnings
def control_surface_ase(case: Case) -> tuple[ControlSurfaceAseRow, ...]:
    """The AEM1 and AEM2 loops of the actuated control surface
    (:func:`control_surface_ase_condition`, System 3 PD of thesis Table 17, power limits of
    Table 16): linear closed-loop poles, forward-path margins and a power-limited step.
    Empty when no surface carries an actuator. Memoised on the case."""
    if not any(c.actuator is not None for c in case.control_surfaces):
        return ()
    _, spec, m = control_surface_ase_condition(case)
    a = spec.actuator
    f_plot = np.logspace(0, 3.5, 800)       # the report's Bode grid (Hz)
    step = math.radians(a.step_deg)
    rows = []
    for topo, which in (("AEM1", 2), ("AEM2", 3)):
        loop = ase_mod.closed_loop(m, SYSTEM_3, topo)
        maxre = float(np.linalg.eigvals(np.asarray(loop.A)).real.max())
        fw = ase_mod.forward_path(m, SYSTEM_3, which)
        cr = ase_mod.crossovers(fw)
        sim = ase_mod.simulate_closed_loop(m, SYSTEM_3, step, topo, limits=THESIS_LIMITS,
                                           t_final=0.2)
        y = sim.fin_root
        fed_back = sim.theta if topo == "AEM1" else y
        ts = float(metrics.settling_time(sim.t, fed_back, step, step, band=0.02))
        rows.append(ControlSurfaceAseRow(
            spec.name, topo, float(a.mach), float(a.altitude), float(a.speed),
            0.5 * m.density * m.velocity ** 2, maxre < 0, maxre, m.effective_fin_inertia,
            cr.phase_margin_deg, cr.gain_margin_db,
            float(cr.gain_crossovers_hz[-1]) if cr.gain_crossovers_hz.size else None,
            float(a.step_deg), ts if math.isfinite(ts) else None,
            float(metrics.overshoot(y, step)), float(abs(y[-1] - step) / step),
            np.asarray(sim.t, float), np.asarray(y, float), np.asarray(fed_back, float),
            f_plot, ase_mod.frequency_response(fw, f_plot), cr))
    return tuple(rows)


# ---------------------------------------------------------------------------------------------
# control surfaces: freeplay in the hinge (issue 25, asekit.aeroelastic.hinge_freeplay)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ControlSurfaceFreeplayRow:
    """Harmonic-balance LCOs of one control surface with a freeplay gap in its hinge spring at
    one Mach and the first flight condition's ``density`` (kg/m^3): ``freeplay_deg`` the gap's
    half-width; ``lco_onset_speed_ms`` the lowest airspeed of ``flight.velocities`` (refined
    to 0.01 m/s) with a limit cycle or an unstable rest position inside the gap (None: none
    in the sweep); ``lco_at_first_point`` True when already there at the sweep's first speed
    (the onset lies below the sweep); ``linear_flutter_speed_ms`` the flutter speed with the
    full hinge spring in the same state-space model (above it the oscillation is unbounded;
    None: none in the sweep)."""

    name: str
    mach: float
    density: float
    freeplay_deg: float
    lco_onset_speed_ms: float | None
    lco_at_first_point: bool
    linear_flutter_speed_ms: float | None


def _freeplay_onset(at, conn, speeds) -> tuple:
    """(onset speed or None, at the first point) of the harmonic-balance LCO over ``speeds``."""
    from asekit.aeroelastic.nonlinear import bisect_onset, harmonic_balance

    def has(u):
        r = harmonic_balance(at(u), conn)
        return bool(r.lcos) or r.inside_band_unstable
    if has(speeds[0]):
        return float(speeds[0]), True
    for lo, hi in zip(speeds[:-1], speeds[1:]):
        if has(hi):
            return float(bisect_onset(has, lo, hi, 0.01)), False
    return None, False


@_memo_with_warnings
@_door("the hinge-freeplay limit cycles", _CONTROL)
def control_surface_freeplay(case: Case) -> tuple[ControlSurfaceFreeplayRow, ...]:
    """LCO onset of every control surface with ``freeplay_deg`` > 0, at every ``aero.machs``,
    the first flight condition, over ``flight.velocities``: the wing with that surface's hinge
    spring as a freeplay :class:`~asekit.aeroelastic.nonlinear.Connection`
    (:func:`asekit.aeroelastic.hinge_freeplay.hinge_connected_system`, the other surfaces on
    their linear springs), the GAFs of :func:`control_surface_flutter`'s modes fitted by the
    case's RFA (``flutter.rfa``, ``flutter.lags``), harmonic balance per airspeed. Empty when
    no surface has freeplay. Memoised on the case."""
    from asekit.aero.gaf import build_gaf_database
    from asekit.aeroelastic import hinge_freeplay as hf

    spec = [(i, c) for i, c in enumerate(case.control_surfaces) if c.freeplay_deg > 0]
    if not spec:
        return ()
    hm = control_surface_mesh(case)
    fm = control_surface_model(case)
    if fm.modal.n_rigid:
        raise CaseError("control_surface[].freeplay_deg needs a wing without a rigid mode "
                        "(support.kind clamped)")
    a = case.aero
    method = a.kernel if a.method == "dlm" else a.method
    db = build_gaf_database(fm.box_modes, hm.mesh, a.machs, reduced_frequencies(case),
                            a.reference_semichord, 0, symmetric=a.symmetry == "wall",
                            method=method, progress=False)
    U = np.sort(np.asarray(case.flight.velocities, float))
    rho = flight_conditions(case)[0].density
    rows = []
    for mach in a.machs:
        g = db.at(mach)
        fit = rfa_kind(case.flutter.rfa).fit(g.k, g.Q, db.b_ref, mach, case.flutter.lags)
        for i, c in spec:
            h = fm.n_wing + i

            def at(u, h=h, fit=fit):
                return hf.hinge_connected_system(fm.modal, fit, rho, u, h)
            conn = hf.hinge_connection(fm.modal, h, math.radians(c.freeplay_deg))
            onset, first = _freeplay_onset(at, conn, U)
            try:
                uf, _ = hf.connected_flutter_speed(at, conn.stiffness, float(U[0]),
                                                   float(U[-1]), n=U.size)
            except ValueError:                    # unstable at the first speed already
                uf = float(U[0])
            rows.append(ControlSurfaceFreeplayRow(c.name, float(mach), float(rho),
                                                  float(c.freeplay_deg), onset, first, uf))
    return tuple(rows)


# --------------------------------------------------------------------------------------------
# issue 23 (p-k batched): every Mach x flight condition p-k sweep of a case solved together
# --------------------------------------------------------------------------------------------
@_door("the flutter solution", _FLUTTER)
def _conditions_together(case: Case, db: GafDatabase, pairs, model) -> list:
    """:func:`analyse_condition` of every (mach, condition) of ``pairs``, the same results:
    with the p-k method (``flutter.method = "pk"``) the sweeps are solved together
    (:func:`asekit.aeroelastic.flutter.pk_flutter_many`, then
    :func:`~asekit.aeroelastic.flutter.pk_instabilities_many`; each sweep's result equals its
    own p-k bit for bit), any other method condition by condition."""
    from asekit.aeroelastic.flutter import pk_flutter_many, pk_instabilities_many

    method = flutter_method(case.flutter.method)
    if getattr(method, "name", None) != "pk" or len(pairs) < 2:
        return [analyse_condition(case, db, m, c, model) for m, c in pairs]
    U = np.asarray(case.flight.velocities, float)
    gafs = [db.at(m) for m, _ in pairs]
    sweeps = pk_flutter_many(model, [(g, c.density) for g, (_, c) in zip(gafs, pairs)], U)
    results = []
    for (m, c), pk, inst in zip(pairs, sweeps, pk_instabilities_many(sweeps, model, gafs)):
        start = [i for i in inst if i.at_first_point]
        crossings = [i for i in inst if not i.at_first_point]
        results.append(ConditionResult(float(m), c, pk, tuple(inst),
                                       first_of(crossings, "flutter"),
                                       first_of(crossings, "divergence"), bool(start),
                                       start[0].mode if start else None))
    return results
