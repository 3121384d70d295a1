"""The analysis pipeline of a :class:`~asekit.case.schema.Case`:
structure (plate FE -> modes) -> boxes -> GAF database (cached) -> p-k flutter at every Mach
and flight condition -> match points and flutter margin -> (with an actuator) the ASE loop.

Every step is a plain function of the frozen case; :func:`modal_model` and :func:`box_mesh` are
memoised on the case (frozen, hashable) so that one run computes each once.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import GafDatabase, cached_gaf_database, default_reduced_frequencies
from asekit.atmosphere import standard_atmosphere
from asekit.aeroelastic.flutter import (Instability, PkResult, TabulatedGaf, divergence_speeds,
                                        first_of)
from asekit.aeroelastic.methods import flutter_method
from asekit.rfa.methods import rfa_kind
from asekit.rfa.roger import gaf_at_mach
from asekit.structure.assembly import assemble, clamped_edge, point_mass_matrix, shaft_support
from asekit.structure.mesh import PlateMesh, panels_mesh
from asekit.structure.modes import (ModalModel, fictitious_mass_modal_model, fixed_modal_model,
                                    with_damping)
from asekit.case.schema import Case, CaseError


# ---------------------------------------------------------------------------------------------
# structure
# ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=16)
def structural_mesh(case: Case) -> PlateMesh:
    """The plate mesh of all panels (``panel[i].n_chord x n_span`` elements each), or the
    imported model's mesh (``case.structure``)."""
    if case.structure is not None:
        return case.structure.mesh
    return panels_mesh([p.planform for p in case.panels], case.thickness,
                       case.panels[0].n_chord, [p.n_span for p in case.panels])


def mass_and_stiffness(case: Case):
    """Global sparse K (plate) and M (plate + point masses) of the case's mesh (the imported
    model's K and M when ``case.structure`` is given, plus the case's point masses)."""
    mesh = structural_mesh(case)
    K, M = _imported_matrices(case) if case.structure is not None else assemble(mesh,
                                                                                 case.material)
    if case.point_masses:
        M = (M + point_mass_matrix(mesh, [(p.position, p.mass, p.inertia)
                                          for p in case.point_masses])).tocsr()
    return K, M


@lru_cache(maxsize=16)
def modal_model(case: Case) -> ModalModel:
    """The case's modal model (thesis Eqs. 2.45-2.46): for a shaft with ``model = "FN2"`` and
    ``modes.keep_rigid`` the rigid pitch mode first (n_rigid = 1), otherwise the elastic modes
    only; damping from ``[damping]``. An imported structure: :func:`imported_modal_model`."""
    if case.structure is not None:
        return imported_modal_model(case)
    mesh = structural_mesh(case)
    K, M = mass_and_stiffness(case)
    s, md = case.support, case.modes
    try:
        if s.kind == "clamped_root":
            model = fixed_modal_model(clamped_edge(mesh, K, M), M, md.f_max, md.count)
        elif s.kind == "edges":
            from asekit.structure.supports import planform_edge_supports
            model = fixed_modal_model(planform_edge_supports(mesh, K, M, **dict(s.edges)), M,
                                      md.f_max, md.count)
        else:
            region = "single_node" if s.radius is None else "distributed"
            radius = 0.0 if s.radius is None else s.radius
            if s.model == "FN2" and md.keep_rigid:
                model = fictitious_mass_modal_model(
                    mesh, K, M, s.axis_point, s.torsional_stiffness, region=region,
                    radius=radius, fictitious_inertia_factor=s.fictitious_inertia_factor,
                    bending_stiffness=s.bending_stiffness, f_max_hz=md.f_max, n_modes=md.count)
            else:
                fn1 = shaft_support(mesh, K, M, s.axis_point, s.torsional_stiffness, "FN1",
                                    region, radius, bending_stiffness=s.bending_stiffness)
                model = fixed_modal_model(fn1, M, md.f_max, md.count, axis_x=s.axis_point[0])
    except ValueError as exc:
        raise CaseError(f"support / modes: {exc}") from None
    if len(model.frequencies_hz) - model.n_rigid < 1:
        raise CaseError(f"modes: no elastic mode below modes.f_max = {md.f_max:g} Hz; raise "
                        f"f_max or give modes.count")
    d = case.damping
    try:
        return with_damping(model, d.modal_damping_ratio, d.structural_g)
    except ValueError as exc:
        raise CaseError(str(exc)) from None


# ---------------------------------------------------------------------------------------------
# an imported structure (case.structure: asekit.case.imported.ImportedModel)
# ---------------------------------------------------------------------------------------------
def _imported_matrices(case: Case):
    """(K, M) of the imported model, CSR."""
    return case.structure.K.tocsr(), case.structure.M.tocsr()


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
        raise CaseError(f"structure / modes: {exc}") from None
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


def imported_box_mesh(case: Case):
    """The imported structure's boxes; CaseError if it has none."""
    if case.structure.boxes is None:
        raise CaseError(f"{case.name}: the imported structure has no aerodynamic boxes "
                        f"(a deck without CAERO1): modes only")
    return case.structure.boxes


# ---------------------------------------------------------------------------------------------
# aerodynamics
# ---------------------------------------------------------------------------------------------
def _auto_boxes(planform, u_min: float, f_max: float, bpw_min: float = 15.0,
                ar_max: float = 3.0) -> tuple[int, int]:
    """Box counts of one panel from the mesh rules (thesis Sec. 3.2.1): the smallest
    n_chord >= 4 with boxes per wavelength U_min / (f_max dx) > ``bpw_min`` on the root strip
    and the smallest n_span keeping the tip boxes' aspect ratio below 0.9 ``ar_max``."""
    dx_max = u_min / (bpw_min * f_max)
    n_chord = max(4, math.floor(planform.root_chord / dx_max) + 1)
    dx_tip = planform.tip_chord / n_chord
    n_span = max(1, math.ceil(planform.span / (0.9 * ar_max * dx_tip)))
    return n_chord, n_span


@lru_cache(maxsize=16)
def box_mesh(case: Case):
    """The doublet-lattice boxes, per panel ``aero.boxes`` or automatic (mesh rules), or the
    imported structure's boxes."""
    if case.structure is not None:
        return imported_box_mesh(case)
    a = case.aero
    surfaces = []
    for i, p in enumerate(case.panels):
        pf = p.planform
        nc, ns = a.boxes[i] if a.boxes is not None else _auto_boxes(pf, a.u_min, a.f_max)
        surfaces.append(TrapezoidSurface(pf.root_le + (0.0,), pf.root_chord, pf.tip_le + (0.0,),
                                         pf.tip_chord, nc, ns,
                                         name=f"panel{i}" if len(case.panels) > 1 else "surface"))
    return mesh_surfaces(surfaces)


def reduced_frequencies(case: Case) -> np.ndarray:
    """``aero.reduced_frequencies`` or, automatically, :func:`default_reduced_frequencies` up
    to k_max = 2 pi f_max b / u_min (thesis Sec. 3.2.1)."""
    a = case.aero
    if a.reduced_frequencies is not None:
        return np.asarray(a.reduced_frequencies, float)
    return default_reduced_frequencies(2 * math.pi * a.f_max * a.reference_semichord / a.u_min)


def gaf_database(case: Case, progress: bool = True, cache: bool = True) -> GafDatabase:
    """Q_mm(M, k) over ``aero.machs`` x the reduced frequencies, cached per fingerprint in the
    user cache directory (:func:`asekit.aero.gaf.cached_gaf_database`)."""
    a = case.aero
    if a is None:
        raise CaseError(f"{case.name}: the case has no aerodynamics (an imported deck without "
                        f"CAERO1 / MKAERO1)")
    # the database's method: the DLM kernel name, or the aerodynamic method (asekit.aero.methods)
    method = a.kernel if a.method == "dlm" else a.method
    return cached_gaf_database(modal_model(case), box_mesh(case), a.machs,
                               reduced_frequencies(case), a.reference_semichord,
                               symmetric=a.symmetry == "wall", method=method,
                               progress=progress, rebuild=not cache,
                               metadata={"case": case.name})


def gaf_at(db: GafDatabase, mach: float) -> TabulatedGaf:
    """The database's GAFs at one of its Mach numbers."""
    i = int(np.argmin(np.abs(db.machs - mach)))
    if not math.isclose(db.machs[i], mach, abs_tol=1e-9):
        raise ValueError(f"mach {mach} is not in the database {db.machs.tolist()}")
    return TabulatedGaf(db.k, db.Q[i], db.b_ref, mach=float(mach))


# ---------------------------------------------------------------------------------------------
# flutter
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlightCondition:
    """An analysed condition: altitude (m, None when the density was given), density
    (kg/m^3) and speed of sound (m/s, None when unknown)."""

    altitude: float | None
    density: float
    speed_of_sound: float | None


def flight_conditions(case: Case) -> list[FlightCondition]:
    """The analysed conditions: per altitude (standard atmosphere) or per density."""
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
    """p-k at one (Mach, flight condition).

    pk : the sweep; instabilities : every crossing found; flutter / divergence : the first of
    each kind (None if none in the sweep); unstable_at_start : the lowest speed of the sweep is
    already unstable (flutter or divergence at or below it: the sweep must start lower);
    start_mode : the index of the mode unstable there.
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
    """All conditions, the static divergence speeds per Mach and density, the match points
    (Mach at which the flutter speed equals M a, per altitude) and the flutter margins
    (U_f / U_envelope - 1 at the envelope's top Mach, per altitude inside the envelope)."""

    results: tuple[ConditionResult, ...]
    divergence: tuple[dict, ...]
    match_points: tuple[dict, ...]
    margins: tuple[dict, ...]
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)


def rfa_at(case: Case, db: GafDatabase, mach: float):
    """The case's rational function approximation (``flutter.rfa`` with ``flutter.lags`` lag
    roots, :data:`asekit.rfa.methods.RFA_FITS`) of the GAFs at ``mach`` (interpolated linearly
    between the database's Mach numbers)."""
    k, q = gaf_at_mach(db, mach, interpolate=True)
    return rfa_kind(case.flutter.rfa).fit(k, q, db.b_ref, mach, case.flutter.lags)


def analyse_condition(case: Case, db: GafDatabase, mach: float, cond: FlightCondition,
                      model: ModalModel | None = None) -> ConditionResult:
    """The case's flutter method (``flutter.method``, :data:`FLUTTER_METHODS`) at one Mach and
    flight condition: the tracked roots over ``flight.velocities`` and their instabilities."""
    model = modal_model(case) if model is None else model
    gaf = gaf_at(db, mach)
    U = np.asarray(case.flight.velocities, float)
    method = flutter_method(case.flutter.method)
    rfa = rfa_at(case, db, mach) if method.needs_rfa else None
    pk, inst = method.solve(model, gaf, rfa, cond.density, U)
    inst = tuple(inst)
    start = [i for i in inst if i.at_first_point]          # unstable at U0 (asekit.aeroelastic.flutter)
    crossings = [i for i in inst if not i.at_first_point]
    return ConditionResult(float(mach), cond, pk, inst, first_of(crossings, "flutter"),
                           first_of(crossings, "divergence"), bool(start),
                           start[0].mode if start else None)


def _interp_speed(points: list[tuple[float, float]], mach: float,
                  reach: float = 0.05) -> float | None:
    """U_f at ``mach`` from (Mach, U_f) points: linear between them, linear extrapolation of
    the end segment at most ``reach`` in Mach beyond them; None farther out."""
    pts = sorted(points)
    if not pts or not pts[0][0] - reach <= mach <= pts[-1][0] + reach:
        return None
    ms, us = np.array(pts).T
    if ms.size == 1:
        return float(us[0])
    i = int(np.clip(np.searchsorted(ms, mach) - 1, 0, ms.size - 2))   # segment [i, i+1]
    return float(us[i] + (us[i + 1] - us[i]) * (mach - ms[i]) / (ms[i + 1] - ms[i]))


def flutter(case: Case, progress: bool = False, db: GafDatabase | None = None) -> FlutterAnalysis:
    """p-k flutter with mode tracking at every ``aero.machs`` x flight condition, divergence
    speeds (Eq. 3.13 eigenproblem on the steady GAFs), match points and flutter margins."""
    t0 = time.perf_counter()
    model = modal_model(case)
    db = gaf_database(case, progress=progress) if db is None else db
    conds = flight_conditions(case)
    results = [analyse_condition(case, db, m, c, model) for m in case.aero.machs for c in conds]
    div = []
    for m in case.aero.machs:
        Q0 = gaf_at(db, m).Q[0].real
        for c in conds:
            sp = divergence_speeds(model, Q0, c.density)
            div.append({"mach": float(m), "altitude_m": c.altitude, "density": c.density,
                        "speed_ms": float(sp[0]) if sp.size else None})
    matches, margins, notes = [], [], []
    env_m, env_h = case.flight.envelope_mach, case.flight.envelope_altitude
    for c in conds:
        if c.speed_of_sound is None:
            continue
        here = [r for r in results if r.condition == c]
        pts = [(r.mach, r.flutter.speed) for r in here
               if r.flutter is not None and not r.unstable_at_start]
        # matched Mach: M_f(M) = U_f(M) / a crosses M
        d = [(m, u / c.speed_of_sound - m) for m, u in sorted(pts)]
        mm = None
        for (m0, d0), (m1, d1) in zip(d[:-1], d[1:]):
            if d0 == 0 or d0 * d1 < 0:
                mm = m0 + (m1 - m0) * d0 / (d0 - d1)
                break
        why = None
        if mm is None:
            if not d:
                why = "no flutter in the sweep at any analysed Mach"
            elif all(v > 0 for _, v in d):
                why = (f"U_f > M a at every analysed Mach: no match up to M {d[-1][0]:g} "
                       f"(flutter-free there)")
            else:
                why = (f"U_f < M a at every analysed Mach: the match lies below M {d[0][0]:g}")
        matches.append({"altitude_m": c.altitude, "matched_mach": mm,
                        "matched_speed_ms": None if mm is None else mm * c.speed_of_sound,
                        "no_match": why})
        if env_m is not None and (env_h is None or c.altitude is None
                                  or env_h[0] <= c.altitude <= env_h[1]):
            u_env = env_m[1] * c.speed_of_sound
            uf = _interp_speed(pts, env_m[1])
            margins.append({"altitude_m": c.altitude, "envelope_mach": env_m[1],
                            "envelope_speed_ms": u_env, "flutter_speed_ms": uf,
                            "margin": None if uf is None else uf / u_env - 1.0})
    for r in results:
        if r.unstable_at_start:
            notes.append(f"M {r.mach:g}, rho {r.condition.density:.4g}: unstable at the first "
                         f"point of the sweep ({case.flight.velocities[0]:g} m/s, mode "
                         f"{r.start_mode}): flutter or divergence at or below it")
    return FlutterAnalysis(tuple(results), tuple(div), tuple(matches), tuple(margins),
                           time.perf_counter() - t0, tuple(notes))


# ---------------------------------------------------------------------------------------------
# aeroservoelasticity (thesis Ch. 5)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AseResult:
    """The ASE loop at the actuator's flight condition: the model, closed-loop stability of
    AEM1 / AEM2 (and their largest closed-loop pole real parts, 1/s), FWTF 1-3 crossovers and
    the power-limited step responses (settling time s, steady error and corner overshoot as
    fractions of the command)."""

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


def corner_points(case: Case) -> dict:
    """The surface's four corners (root LE/TE of the first panel, tip LE/TE of the last; of an
    imported structure: :func:`imported_corner_points`)."""
    if case.structure is not None:
        return imported_corner_points(case)
    r, t = case.panels[0].planform, case.panels[-1].planform
    return {"root_le": r.root_le, "root_te": (r.root_le[0] + r.root_chord, r.root_le[1]),
            "tip_le": t.tip_le, "tip_te": (t.tip_le[0] + t.tip_chord, t.tip_le[1])}


def actuator_setup(case: Case):
    """(ActuatorParameters, PDController, PowerLimits) of the case's ``[actuator]``: the keys
    it sets, asekit's defaults (thesis Tables 12, 16, 17) for the rest. The actuator's load
    inertia is 0: the fin's inertia enters through its modal model (:func:`asekit.ase.loop.build_model`)."""
    from asekit.servo.actuator import SYSTEM_3, ActuatorParameters, DCMotor, Transmission
    from asekit.servo.simulate import THESIS_LIMITS
    from asekit.case.schema import MOTOR_KEYS, TRANSMISSION_KEYS
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


def ase(case: Case, db: GafDatabase | None = None) -> AseResult | None:
    """The Ch. 5 analysis of the case's actuator (None without ``[actuator]``)."""
    if case.actuator is None:
        return None
    from asekit.ase import loop as ase_mod
    from asekit.ase import metrics
    from asekit.aeroelastic.statespace import fin_outputs

    a = case.actuator
    model = modal_model(case)
    db = gaf_database(case, progress=False) if db is None else db
    rfa = rfa_at(case, db, a.mach)
    atm = standard_atmosphere(a.altitude)
    rho, U = float(atm.density), a.mach * float(atm.speed_of_sound)
    corners = corner_points(case)
    rows = fin_outputs(model, np.array(list(corners.values())), names=list(corners),
                       shaft_point=case.support.axis_point)
    act, ctl, lim = actuator_setup(case)
    m = ase_mod.build_model(model, rfa, rho, U, rows, actuator=act, mach=a.mach)
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
