"""The thesis's reference fin as one case among the others: its definition (read from
``data/cases/nalci2013_fin.toml``), and the convenience layer the reproduction, the notebooks and
the benchmarks use on it -- the FN1/FN2 modal models on its default or a refined mesh, its box
mesh from the mesh rules, its GAF database (shipped read-only in ``data/gaf_fin.npz``, rebuilt
into the user cache), and its aeroservoelastic model of Ch. 5.

Everything here is a thin wrapper over the generic physics (:mod:`asekit.structure`,
:mod:`asekit.aero`, :mod:`asekit.ase.loop`) that knows no fin; a new surface goes through
:mod:`asekit.case` instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from asekit.aero.boxes import BoxMesh, TrapezoidSurface, check_matrix_memory, mesh_surfaces
from asekit.aero.gaf import cached_gaf_database, database_settings, default_reduced_frequencies
from asekit.ase.loop import AeroservoelasticModel, build_model
from asekit.geometry import Material, OrthotropicMaterial, Planform, Thickness
from asekit.util.paths import FIN_FILE
from asekit.servo.actuator import ActuatorParameters
from asekit.structure.assembly import SupportedSystem, assemble, shaft_support
from asekit.structure.mesh import PlateMesh, structured_mesh
from asekit.structure.modes import (ModalModel, elastic_modal_model, fictitious_mass_modal_model,
                                    modes_up_to)
from asekit.util.validate import finite, positive


#: Radius (m) of the fin's physical shaft region assumed for the distributed-shaft model when
#: the case file holds the single-node shaft (the thesis gives no radius).
DEFAULT_SHAFT_RADIUS = 0.005


@dataclass(frozen=True)
class Shaft:
    """The fin's pitch shaft: a spanwise axis through ``axis_point`` (x, y) in m.

    torsional_stiffness (N m/rad) is the FN1 spring; radius (m) the physical shaft region used by
    the distributed (rigid multi-point) shaft model; fictitious_inertia_factor the FN2 multiplier.
    """

    axis_point: tuple[float, float]
    torsional_stiffness: float
    radius: float
    fictitious_inertia_factor: float = 1.0e6

    def __post_init__(self):
        object.__setattr__(self, "axis_point", tuple(float(v) for v in self.axis_point))
        positive("torsional_stiffness", self.torsional_stiffness)
        positive("radius", self.radius)
        positive("fictitious_inertia_factor", self.fictitious_inertia_factor)


@dataclass(frozen=True)
class AeroSettings:
    """Aerodynamic analysis settings of a fin (SI): reference semi-chord b for k = omega b / U,
    Mach numbers of the GAF database, the highest structural frequency of interest (Hz), the
    analysis speed range (m/s) and altitudes (m)."""

    reference_semichord: float
    machs: tuple[float, ...]
    f_max: float
    u_min: float
    u_max: float
    altitudes: tuple[float, ...]

    @property
    def k_max(self) -> float:
        """Highest reduced frequency needed: 2 pi f_max b / U_min."""
        return 2.0 * math.pi * self.f_max * self.reference_semichord / self.u_min


@dataclass(frozen=True)
class FinDefinition:
    """Everything that defines a fin: planform, thickness law, material, shaft, default FE mesh
    (n_chord x n_span elements) and aerodynamic settings."""

    planform: Planform
    thickness: Thickness
    material: Material | OrthotropicMaterial
    shaft: Shaft
    n_chord: int
    n_span: int
    aero: AeroSettings


def fin_definition(case) -> FinDefinition:
    """The :class:`FinDefinition` of a one-panel shaft-supported case
    (:class:`asekit.case.Case`): planform, thickness, material, shaft, FE mesh, aero settings."""
    if len(case.panels) != 1 or case.support.kind != "shaft":
        raise ValueError(f"case {case.name!r}: a fin definition needs one panel and a shaft "
                         f"support, got {len(case.panels)} panel(s), support {case.support.kind!r}")
    s, a, f = case.support, case.aero, case.flight
    p = case.panels[0]
    altitudes = tuple(f.altitudes) if f.altitudes is not None else ()
    return FinDefinition(
        planform=p.planform, thickness=case.thickness, material=case.material,
        shaft=Shaft(s.axis_point, s.torsional_stiffness,
                    DEFAULT_SHAFT_RADIUS if s.radius is None else s.radius,
                    s.fictitious_inertia_factor),
        n_chord=p.n_chord, n_span=p.n_span,
        aero=AeroSettings(a.reference_semichord, tuple(a.machs), a.f_max, a.u_min,
                          float(f.velocities[-1]), altitudes))


def load_fin(path: str | Path = FIN_FILE) -> FinDefinition:
    """The fin definition of a case file (default: the reference fin,
    ``data/cases/nalci2013_fin.toml``), see :func:`fin_definition`."""
    from asekit.case.schema import load_case
    return fin_definition(load_case(path))


def fin_mesh(fin: FinDefinition, n_chord: int | None = None, n_span: int | None = None) -> PlateMesh:
    """The fin's structured mesh (default: the thesis's 6 x 7 from ``data/cases/nalci2013_fin.toml``)."""
    return structured_mesh(fin.planform, fin.thickness,
                           fin.n_chord if n_chord is None else n_chord,
                           fin.n_span if n_span is None else n_span)


def _region(shaft: str) -> str:
    if shaft not in ("single_node", "distributed"):
        raise ValueError(f"shaft must be 'single_node' or 'distributed', got {shaft!r}")
    return shaft


def fin_supported(fin: FinDefinition, mesh: PlateMesh, model: str, shaft: str = "single_node",
                  K=None, M=None) -> SupportedSystem:
    """The fin on its shaft: model "FN1" or "FN2" with the single-node or distributed shaft."""
    if K is None or M is None:
        K, M = assemble(mesh, fin.material)
    s = fin.shaft
    return shaft_support(mesh, K, M, s.axis_point, s.torsional_stiffness, model=model,
                         region=_region(shaft), radius=s.radius,
                         fictitious_inertia_factor=s.fictitious_inertia_factor)


def _copy_model(model: ModalModel) -> ModalModel:
    """A copy of ``model`` with its own arrays (what the memo hands out)."""
    return replace(model, **{f: np.array(getattr(model, f)) for f in
                             ("frequencies_hz", "M", "K", "C", "nodes", "shapes", "elements")})


@lru_cache(maxsize=32)
def _modal_model(fin: FinDefinition, n_chord: int, n_span: int, shaft: str, f_max_hz: float,
                 model: str):
    """(model, warnings): the FN2 (``model="FN2"``) or FN1 modal model and the warnings its
    computation gave; memoised on the (hashable, frozen) fin definition and the arguments, so
    a run that asks for the same model twice computes it once. Callers get copies
    (:func:`_copy_model`) and the warnings again (:func:`_memo_result`): the memo changes
    neither a result nor what the caller is told."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = _compute_modal_model(fin, n_chord, n_span, shaft, f_max_hz, model)
    return result, tuple((w.message, w.category) for w in caught)


def _memo_result(memo) -> ModalModel:
    """A copy of a memoised model, its computation's warnings issued again (as from the
    public function's caller, under the caller's warning filters)."""
    import warnings

    result, caught = memo
    for message, category in caught:
        warnings.warn(message, category, stacklevel=3)
    return _copy_model(result)


def _compute_modal_model(fin, n_chord, n_span, shaft, f_max_hz, model) -> ModalModel:
    mesh = fin_mesh(fin, n_chord, n_span)
    K, M = assemble(mesh, fin.material)
    s = fin.shaft
    if model == "FN2":
        return fictitious_mass_modal_model(mesh, K, M, s.axis_point, s.torsional_stiffness,
                                           region=_region(shaft), radius=s.radius,
                                           fictitious_inertia_factor=s.fictitious_inertia_factor,
                                           f_max_hz=f_max_hz)
    fn1 = fin_supported(fin, mesh, "FN1", shaft, K, M)
    return elastic_modal_model(modes_up_to(fn1, f_max_hz, M_fin=M), M, f_max_hz,
                               axis_x=fin.shaft.axis_point[0])


def _model_key(fin, n_chord, n_span, shaft, f_max_hz):
    fin = load_fin() if fin is None else fin
    positive("f_max_hz", f_max_hz)
    _region(shaft)
    n_c = fin.n_chord if n_chord is None else n_chord
    n_s = fin.n_span if n_span is None else n_span
    return fin, n_c, n_s, shaft, f_max_hz


def fin_modal_model(fin: FinDefinition | None = None, n_chord: int | None = None,
                    n_span: int | None = None, shaft: str = "single_node",
                    f_max_hz: float = 1000.0) -> ModalModel:
    """The FN2 modal model of a fin definition: rigid pitch mode + elastic modes below
    ``f_max_hz`` with out-of-plane motion (thesis Sec. 3.1, Table 6, Eqs. (2.45)-(2.46)); see
    :func:`fictitious_mass_modal_model`. Computed once per definition and arguments within a
    process (memoised; every call returns its own copy).

    Parameters
    ----------
    fin : fin definition (default ``load_fin()``).
    n_chord, n_span : elements per direction (default the fin's 6 x 7).
    shaft : "single_node" (thesis) or "distributed" (rigid region of radius fin.shaft.radius).
    f_max_hz : frequency limit for the elastic modes kept (Hz), > 0.
    """
    return _memo_result(_modal_model(*_model_key(fin, n_chord, n_span, shaft, f_max_hz), "FN2"))


def fin_fn1_modal_model(fin: FinDefinition | None = None, n_chord: int | None = None,
                        n_span: int | None = None, shaft: str = "single_node",
                        f_max_hz: float = 1000.0) -> ModalModel:
    """The thesis's model FN1 (shaft spring to ground, no rigid mode; thesis Sec. 3.1.1, Fig 12)
    as a ModalModel with n_rigid = 0; arguments as :func:`fin_modal_model` (memoised too)."""
    return _memo_result(_modal_model(*_model_key(fin, n_chord, n_span, shaft, f_max_hz), "FN1"))


@dataclass(frozen=True)
class InPlaneModes:
    """In-plane (membrane) modes of the fin pinned at one node (u = v = 0), the situation of the
    thesis's discarded mode (Fig. 16).

    frequencies_hz : (n,) ascending; the first is the in-plane rigid rotation about the pinned
        node (0 Hz up to round-off: nothing but an artificial drilling stiffness restrains it).
    shapes : (n_nodes, 2, n) u, v per node (mass-normalised).
    J_z : in-plane rotational inertia of the fin about the pinned node (kg m^2).
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    J_z: float


def fin_inplane_modes(fin: FinDefinition | None = None, n_chord: int | None = None,
                      n_span: int | None = None, n_modes: int = 4) -> InPlaneModes:
    """In-plane modes of the fin held only at the shaft node (plane-stress Q4 membrane, see
    :func:`asekit.structure.plate.membrane_matrices`). Not part of the modal model: a flat fin's
    in-plane motion does not couple with bending or with the aerodynamics."""
    import scipy.sparse as sp

    from asekit.structure.plate import membrane_matrices
    fin = load_fin() if fin is None else fin
    mesh = fin_mesh(fin, n_chord, n_span)
    Ke, Me = membrane_matrices(mesh, fin.material)
    dofs = (2 * mesh.elements[:, :, None] + np.arange(2)).reshape(-1, 8)
    rows, cols = np.repeat(dofs, 8, axis=1).ravel(), np.tile(dofs, (1, 8)).ravel()
    n = 2 * mesh.n_nodes
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    M = sp.csr_matrix((Me.ravel(), (rows, cols)), shape=(n, n))
    node = mesh.node_at(fin.shaft.axis_point, name="shaft axis_point")
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


def pitch_inertia_exact(fin: FinDefinition) -> float:
    """Pitch inertia (kg m^2) of the flat trapezoidal plate about the shaft axis, by exact
    integration: J = int_y rho h(y) int_x [(x - x_a)^2 + h^2 / 12] dx dy (the second term is the
    plate's own rotary inertia). Gauss-Legendre in y is exact for this polynomial integrand."""
    p, t, rho = fin.planform, fin.thickness, fin.material.density
    x_a = fin.shaft.axis_point[0]
    g, wg = np.polynomial.legendre.leggauss(8)
    eta = 0.5 * (g + 1)
    h = t.at(eta)
    x0 = p.root_le[0] + eta * (p.tip_le[0] - p.root_le[0]) - x_a
    c = p.root_chord + eta * (p.tip_chord - p.root_chord)
    x1 = x0 + c
    inner = (x1**3 - x0**3) / 3 + h**2 / 12 * c
    return float(0.5 * p.span * np.sum(wg * rho * h * inner))


def fin_surface(fin, n_chord: int | None = None, n_span: int | None = None,
                bpw_min: float = 15.0, ar_max: float = 3.0) -> TrapezoidSurface:
    """The reference fin's planform as a :class:`TrapezoidSurface` (z = 0).

    Without ``n_chord``/``n_span`` the box counts follow the mesh rules with a margin: the
    smallest ``n_chord >= 4`` giving ``BPW > bpw_min`` (strictly) on the root strip (Eq. 3.5
    with the fin's U_min and f_max; 14 for the reference fin: BPW 16.6 on the root strip
    with its mid-span box chord), and the smallest ``n_span`` keeping every box aspect ratio below
    ``ar_max`` with a 10 % margin.
    """
    p = fin.planform
    bpw_min, ar_max = positive("bpw_min", bpw_min), positive("ar_max", ar_max)
    if n_chord is None:
        dx_max = positive("fin.aero.u_min", fin.aero.u_min) / (
            bpw_min * positive("fin.aero.f_max", fin.aero.f_max))
        n_chord = max(4, math.floor(p.root_chord / dx_max) + 1)
    if n_span is None:
        dx_tip = p.tip_chord / n_chord
        n_span = max(1, math.ceil(p.span / (0.9 * ar_max * dx_tip)))
    n_boxes = int(n_chord) * int(n_span)
    check_matrix_memory(n_boxes, 1, 16, f"one DLM matrix of the fin ({n_chord} x {n_span} boxes "
                        f"from f_max = {fin.aero.f_max:g} Hz, u_min = {fin.aero.u_min:g} m/s, "
                        f"bpw_min = {bpw_min:g})", "lower f_max, raise u_min or pass n_chord / "
                        "n_span")
    return TrapezoidSurface(p.root_le + (0.0,), p.root_chord, p.tip_le + (0.0,), p.tip_chord,
                            n_chord, n_span, name="fin")


def fin_boxes(fin=None, n_chord: int | None = None, n_span: int | None = None) -> BoxMesh:
    """Box mesh of the reference fin (default: :func:`load_fin`), see
    :func:`fin_surface` for the default box counts."""
    if fin is None:
        fin = load_fin()
    return mesh_surfaces([fin_surface(fin, n_chord, n_span)])


def database_k(fin) -> np.ndarray:
    """The fin database's reduced frequencies, :func:`default_reduced_frequencies` up to
    k_max = 2 pi f_max b / U_min (fin.md; about 2.72 for the reference fin)."""
    return default_reduced_frequencies(fin.aero.k_max)


def _fin_settings(fin, boxes: BoxMesh, symmetric: bool, method: str) -> dict:
    return database_settings(fin.aero.machs, database_k(fin), fin.aero.reference_semichord,
                             boxes, symmetric, method)


def fin_gaf_database(rebuild: bool = False, progress: bool = True, path=None,
                     symmetric: bool = False, method: str = "quartic"):
    """The reference fin's GAF database and its modal model.

    Mach 0.4, 0.5, 0.6, 0.75 x :func:`database_k`, isolated fin (``symmetric``: a wall at the
    root), DLM ``method`` kernel, default structure ``fin_modal_model()`` (FN2, 6 x 7
    single-node shaft) on :func:`fin_boxes`; loaded from the shipped
    ``data/gaf_fin.npz`` or the user cache when one matches, else rebuilt into the user cache
    (see :func:`cached_gaf_database`; ``path`` overrides the location).

    Returns
    -------
    (GafDatabase, ModalModel)
    """
    fin = load_fin()
    model = fin_modal_model(fin)
    boxes = fin_boxes(fin)
    db = cached_gaf_database(
        model, boxes, fin.aero.machs, database_k(fin), fin.aero.reference_semichord,
        symmetric, method, progress, rebuild, path=path,
        metadata={"reference_semichord": "root semi-chord, fin.aero.reference_semichord (m)"})
    return db, model


#: The fin corners reported in Fig 71-72, as planform fractions (chord xi, span eta).
CORNERS = {"root_le": (0.0, 0.0), "root_te": (1.0, 0.0), "tip_le": (0.0, 1.0),
           "tip_te": (1.0, 1.0)}


@dataclass(frozen=True)
class FinAse:
    """The reference fin's aeroservoelastic model at one flight condition and what it was
    built from: ``model`` (:class:`AeroservoelasticModel`), ``modal`` (ModalModel), ``rfa``
    (RogerFit at ``mach``), ``q_cc`` (steady Re Q_cc at ``mach``, m^3), ``mach``, ``altitude``
    (m), ``density`` (kg/m^3), ``velocity`` (m/s), ``dynamic_pressure`` (Pa)."""

    model: AeroservoelasticModel
    modal: object
    rfa: object
    q_cc: float
    mach: float
    altitude: float
    density: float
    velocity: float

    @property
    def dynamic_pressure(self) -> float:
        return 0.5 * self.density * self.velocity ** 2

    def rigid_fin_actuator(self) -> ActuatorParameters:
        """The Ch. 4 design model: the actuator with the rigid fin's inertia J_fin (asekit's
        structural value) as its load."""
        return replace(self.model.actuator, fin_inertia=float(self.modal.J_fin))

    def steady_hinge_moment(self):
        """The Ch. 4 steady hinge moment q Q_cc theta at this flight condition (asekit's Q_cc)."""
        from asekit.servo.simulate import SteadyHingeMoment
        from asekit.atmosphere import standard_atmosphere

        atm = standard_atmosphere(self.altitude)
        return SteadyHingeMoment(q_cc=self.q_cc, mach=self.mach, density=float(atm.density),
                                 speed_of_sound=float(atm.speed_of_sound))


def fin_ase(mach: float = 0.5, altitude: float = 0.0, actuator: ActuatorParameters | None = None,
            count_fin_inertia_twice: bool = False, n_lags: int = 4, database=None,
            modal=None, fit=None) -> FinAse:
    """The reference fin's aeroservoelastic model at (mach, altitude) (thesis Ch. 5).

    Uses the cached GAF database (:func:`fin_gaf_database`, single-node shaft,
    6 x 7 FE mesh as the thesis), a Roger fit with ``n_lags`` lag roots at ``mach`` (Machs
    between the database's are interpolated linearly; outside them a ValueError), the 1976
    standard atmosphere at ``altitude`` (m) and U = mach x speed of sound. Outputs: the fin-root
    pitch (AEM2 feedback), the pitch rotations ``theta_<corner>`` and normal displacements
    ``w_<corner>`` at the four planform corners (:data:`CORNERS`), and the modal coordinates.
    ``fit``: optional callable ``fit(k, Q, b_ref, mach) -> RFA`` replacing the Roger fit (e.g.
    a :func:`asekit.rfa.minimum_state_fit`).
    """
    from asekit.aeroelastic.statespace import fin_outputs
    from asekit.atmosphere import standard_atmosphere
    from asekit.rfa import roger_fit, gaf_at_mach

    mach = finite("mach", mach)
    altitude = finite("altitude", altitude)
    if database is None or modal is None:
        database, modal = fin_gaf_database(progress=False)
    lo, hi = float(np.min(database.machs)), float(np.max(database.machs))
    if not lo <= mach <= hi:
        raise ValueError(f"mach must lie within the GAF database's range [{lo}, {hi}], "
                         f"got {mach}")
    k, q = gaf_at_mach(database, mach, interpolate=True)
    rfa = (roger_fit(k, q, database.b_ref, n_lags=n_lags, mach=mach) if fit is None
           else fit(k, q, database.b_ref, mach))
    atm = standard_atmosphere(altitude)
    rho, a = float(atm.density), float(atm.speed_of_sound)
    fin = load_fin()
    pts = fin.planform.point(np.array([c[0] for c in CORNERS.values()]),
                             np.array([c[1] for c in CORNERS.values()]))
    rows = fin_outputs(modal, pts, names=list(CORNERS), shaft_point=fin.shaft.axis_point)
    model = build_model(modal, rfa, rho, mach * a, rows, actuator=actuator, mach=mach,
                        count_fin_inertia_twice=count_fin_inertia_twice)
    q_cc = float(np.real(q[0, 0, 0]))
    return FinAse(model=model, modal=modal, rfa=rfa, q_cc=q_cc, mach=mach, altitude=altitude,
                  density=rho, velocity=mach * a)
