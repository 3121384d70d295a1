"""What ``python -m asekit analyse`` prints and writes: the summary (a dict that is the JSON
output, the critical condition named first), a plain-text table of it, and an HTML report:
the summary first, a link to the JSON, then the figures of :mod:`asekit.case.report_figures`
(flutter and divergence speed against Mach with the envelope and match points; V-g, V-f and
root locus at every analysed Mach and flight condition; planform with FE mesh and aero boxes;
every kept mode shape; with an actuator the FWTF Bode and the step responses), each with an
alt text that says what it shows.

Conventions (docs/conventions.md): SI in the JSON and the table; every JSON key carries its
unit as a suffix (``_ms`` m/s, ``_hz`` Hz, ``_m`` m, ``_s`` s, ``_deg`` deg, ``_pct`` %), and
the document's ``units`` block (:data:`UNITS`) gives the unit of every numeric key;
modes are named as the user reads them: elastic modes 1, 2, ... (the rigid mode not counted)
and ``"rigid pitch"`` (:func:`asekit.util.conventions.mode_number`); every V-g axis is
g = 2 Re p / |Im p|, > 0 unstable.
"""

from __future__ import annotations

import contextlib
import html
import json
import math
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

from asekit.case import pipeline as P
from asekit.case import report_figures as RF
from asekit.case.envelope import across_sonic, start_kind
from asekit.case.gust_loads import gust_json, gust_loads, turbulence_json
from asekit.case.schema import Case
from asekit.util.conventions import mode_label, mode_number
from asekit.util.plotting import save_figure

#: The unit of every numeric key of the summary (the JSON's ``units`` block; docs/conventions.md).
#: Key suffixes name the unit too: ``_ms`` m/s, ``_hz`` Hz, ``_m`` m, ``_s`` s, ``_deg`` deg,
#: ``_pct`` %; the keys without a suffix are dimensionless or listed here with theirs.
UNITS = {
    "frequencies_hz": "Hz", "frequency_hz": "Hz",
    "altitude_m": "m",
    "speed_ms": "m/s", "matched_speed_ms": "m/s", "envelope_speed_ms": "m/s",
    "flutter_speed_ms": "m/s", "velocity_ms": "m/s", "speed_upper_bound_ms": "m/s",
    "flutter_at_or_below_ms": "m/s", "flutter_speed_upper_bound_ms": "m/s",
    "flutter_speed_lower_bound_ms": "m/s",
    "margin_upper_bound": "- (U_f / U_envelope - 1 is at most this)",
    "margin_lower_bound": "- (U_f / U_envelope - 1 is at least this)",
    "density": "kg/m^3",
    "mach": "-", "matched_mach": "-", "envelope_mach": "-",
    "margin": "- (U_f / U_envelope - 1)",
    "flutter_speed_index": "- (U_f / (b_s omega_alpha sqrt(mu)))",
    "frequency_ratio": "- (f_f / f_alpha)",
    "mode": "elastic mode number from 1 (the rigid mode not counted) or 'rigid pitch'",
    "labels": "mode names in array order: 'rigid pitch', then the elastic modes 1, 2, ...",
    "n_rigid": "count", "boxes": "count",
    "max_real_pole": "1/s (largest Re of the closed-loop poles, > 0 unstable)",
    "settling_s": "s", "steady_error_pct": "%", "corner_overshoot_pct": "%",
    "fwtf_phase_margin_deg": "deg",
    "seconds": "s (wall-clock time per step)",
    "gust_length_m": "m (the 1-cos gust's gradient distance H; the gust is 2 H long; null for "
                     "a gust.profile row)",
    "profile": "the gust.profile file of the row (null for a 1-cos row)",
    "stations": "{[[gust.station]] name: peak_ (gust rows: largest magnitude, signed) or "
                "rms_ (turbulence rows) shear_N in N, bending_Nm and torsion_Nm in N m "
                "(torsion nose up > 0)}",
    "peak_hinge_moment_Nm": "N m (largest |T_hinge@fin|, signed; actuator clamped)",
    "dynamic_pressure_pa": "Pa",
    "hinge_moment_per_delta_Nm_per_rad": "N m/rad (H = q S_f c_f C_h_delta, trailing edge down "
                                         "> 0; the actuator applies -H)",
    "hinge_moment_per_alpha_Nm_per_rad": "N m/rad (H = q S_f c_f C_h_alpha)",
    "max_abs_hinge_moment_per_delta_Nm_per_rad": "N m/rad (largest |H_delta| over the points, "
                                                 "signed)",
    "max_abs_hinge_moment_per_alpha_Nm_per_rad": "N m/rad (largest |H_alpha| over the points, "
                                                 "signed)",
    "basis": "'envelope' (the envelope's corners and Machs, U = M a(h)) or 'sweep top' (the "
             "top of the velocity sweep)",
    "peak_root_bending_Nm": "N m (largest |root bending moment|, signed; tip up > 0)",
    "peak_root_shear_N": "N (largest |root shear|, signed; up > 0)",
    "peak_current_A": "A (motor current of the linear AEM1 loop, no power limits; null "
                      "without an actuator)",
    # gust rows: the servo loops (issue 27)
    "peak_voltage_V": "V (PD voltage demand of the linear AEM1 loop)",
    "peak_current_limited_A": "A (motor current of the AEM1 loop with the actuator's supply "
                              "and current limits, time domain)",
    "peak_voltage_limited_V": "V (applied motor voltage of the power-limited AEM1 loop)",
    "peak_deflection_limited_deg": "deg (largest |transmission angle| of the power-limited "
                                   "AEM1 loop; beyond the 15 deg stop the actuator cannot "
                                   "hold the gust)",
    "saturated": "bool (a power limit bound in the AEM1 loop)",
    "peak_current_aem2_A": "A (the linear AEM2 loop, fin-root feedback; null where unstable)",
    "peak_current_aem2_limited_A": "A (the power-limited AEM2 loop; null where unstable)",
    "saturated_aem2": "bool (a power limit bound in the AEM2 loop; null where unstable)",
    "rms_current_A": "A (RMS motor current of the linear AEM1 loop in continuous turbulence)",
    "rms_hinge_moment_Nm": "N m (RMS in continuous turbulence)",
    "A_bar_hinge": "N m per m/s (RMS hinge moment / RMS gust velocity)",
    "N0_per_s": "1/s (zero up-crossings of the hinge moment per second)",
    "rms_root_bending_Nm": "N m (RMS in continuous turbulence)",
    "A_bar_root_bending": "N m per m/s (RMS root bending / RMS gust velocity)",
    "N0_root_bending_per_s": "1/s (zero up-crossings of the root bending per second)",
    "omega_max": "rad/s (upper end of the turbulence integrals: k_max U / b)",
    "dCL_ddelta_per_rad": "1/rad (lift coefficient on the panel area per rad of deflection)",
    "dCL_dalpha_per_rad": "1/rad",
    "dCm_ddelta_per_rad": "1/rad (pitching moment / (q S c_ref) about the mean aerodynamic "
                          "chord's quarter point, nose up > 0, per rad of deflection)",
    "dCm_dalpha_per_rad": "1/rad (pitching moment / (q S c_ref) about the mean aerodynamic "
                          "chord's quarter point, nose up > 0)",
    "rolling_moment_per_rad_m3": "m^3 (rigid rolling moment about the root chord line of the "
                                 "half model per unit dynamic pressure and per rad of "
                                 "deflection, > 0 for lift outboard; the opposite aileron's "
                                 "image at a wall)",
    "Ch_delta": "1/rad (hinge moment / (q S_f c_f), > 0 trailing edge down)",
    "Ch_alpha": "1/rad (hinge moment / (q S_f c_f), > 0 trailing edge down)",
    "reversal_speed_ms": "m/s", "divergence_speed_ms": "m/s",
    "kind": "'rigid' (a rigid surface rotating about its hinge) or 'elastic' (the plate "
            "region released along the hinge)",
    "hinge_inertia_kgm2": "kg m^2 (the surface's mass moment of inertia about its hinge line, "
                          "from the finite-element mass of its hinge mode)",
    "static_unbalance_kgm": "kg m (the surface's first mass moment about its hinge line; > 0: "
                            "centre of mass aft of the hinge)",
    "hinge_mass_matrix": "kg m^2 (the hinge coordinates' block of the modal mass, surfaces in "
                         "case order: the inertias I_h on the diagonal, the surfaces' inertial "
                         "coupling off it)",
}
# the actuator loop on a control surface (issue 25, control_surface_ase rows)
UNITS.update({
    "topology": "'AEM1' (hinge-angle feedback) or 'AEM2' (the surface's angle in the air)",
    "stable": "true when every closed-loop pole has Re < 0",
    "effective_inertia_kgm2": "kg m^2 (the surface's inertia about its hinge seen by the "
                              "actuator, the wing's modes and apparent air mass included)",
    "phase_margin_deg": "deg (smallest, of FWTF 2 for AEM1 and FWTF 3 for AEM2)",
    "gain_margin_db": "dB (at the first phase crossover; null: none)",
    "crossover_hz": "Hz (highest gain crossover of the forward path)",
    "step_deg": "deg (the power-limited step command)",
    "overshoot_pct": "% (of the surface's angle over the step)",
    "settling_ms": "ms (2 % settling time of the fed-back angle after the step; null: not "
                   "settled in 200 ms)",
})
# freeplay in a control surface's hinge (issue 25, control_surfaces rows with freeplay_deg > 0)
UNITS.update({
    "freeplay_deg": "deg (half-width of the hinge's freeplay gap)",
    "lco_onset_speed_ms": "m/s (lowest speed of the sweep with a harmonic-balance LCO)",
    "lco_at_first_point": "true when the LCO exists at the sweep's first speed already",
    "freeplay_linear_flutter_speed_ms": "m/s (state-space flutter with the full hinge spring; "
                                        "LCO unbounded above)",
})


@dataclass(frozen=True)
class Analysis:
    """Everything one ``analyse`` run computed: the case, its modal model, GAF database,
    flutter analysis, ASE result (None without an actuator), step timings (s) and the
    discrete-gust loads (:class:`asekit.case.gust_loads.GustLoads`; None without ``[gust]``)."""

    case: Case
    modal: object
    database: object
    flutter: object
    ase: object
    seconds: dict
    gust: object = None
    control: tuple = ()
    control_flutter: tuple = ()
    control_hinge: tuple = ()
    control_ase: tuple = ()
    control_freeplay: tuple = ()
    tsd_validity: tuple = ()     # issue 29: asekit.aero.tsd3d.TsdValidity per Mach ("tsd")
    control_hinge_mass: object = None    # issue 25: FlapModel.hinge_mass_matrix (kg m^2)


@contextlib.contextmanager
def _stage(desc: str, progress: bool):
    """A one-step tqdm bar on standard error around a stage without an inner loop (shown
    while it runs, removed when done; nothing when ``progress`` is False)."""
    if not progress:
        yield
        return
    from tqdm.auto import tqdm
    with tqdm(total=1, desc=desc, leave=False, bar_format="{desc}: {elapsed}") as bar:
        yield
        bar.update(1)


def run_analysis(case: Case, progress: bool = False) -> Analysis:
    """Run the whole pipeline of ``case`` and time each step (s).

    ``progress`` shows a tqdm bar on standard error for every stage: the modes, the GAF
    database (Mach x k), the p-k flutter solutions (Mach x flight condition) and the ASE loop.
    """
    sec = {}
    t = time.perf_counter()
    with _stage("modes", progress):
        modal = P.modal_model(case)
    sec["modes"] = time.perf_counter() - t
    t = time.perf_counter()
    db = P.gaf_database(case, progress=progress)
    sec["gaf_database"] = time.perf_counter() - t
    t = time.perf_counter()
    fa = P.flutter(case, db=db, progress=progress)
    sec["flutter"] = time.perf_counter() - t
    t = time.perf_counter()
    with _stage("ASE loop", progress and case.actuator is not None):
        ase = P.ase(case, db=db)
    if ase is not None:
        sec["ase"] = time.perf_counter() - t
    gust = None
    if case.gust is not None:
        t = time.perf_counter()
        with _stage("gust loads", progress):
            gust = gust_loads(case)
        sec["gust"] = time.perf_counter() - t
    control = ()
    if case.control_surfaces:
        t = time.perf_counter()
        with _stage("control surfaces", progress):
            control = P.control_surfaces(case)
        sec["control_surfaces"] = time.perf_counter() - t
        t = time.perf_counter()
        with _stage("flutter with the hinge degrees of freedom", progress):
            control_flutter = P.control_surface_flutter(case)
        sec["control_surface_flutter"] = time.perf_counter() - t
        t = time.perf_counter()
        with _stage("hinge moments over the envelope", progress):
            control_hinge = P.control_surface_hinge_loads(case)
        sec["control_surface_hinge_loads"] = time.perf_counter() - t
        control_freeplay = ()
        if any(c.freeplay_deg > 0 for c in case.control_surfaces):
            t = time.perf_counter()
            with _stage("hinge freeplay limit cycles", progress):
                control_freeplay = P.control_surface_freeplay(case)
            sec["control_surface_freeplay"] = time.perf_counter() - t
    else:
        control_flutter = control_hinge = control_freeplay = ()
    control_ase = ()
    if any(c.actuator is not None for c in case.control_surfaces):
        t = time.perf_counter()
        with _stage("the actuator loop on the control surface", progress):
            control_ase = P.control_surface_ase(case)
        sec["control_surface_ase"] = time.perf_counter() - t
    hinge_mass = (P.control_surface_model(case).hinge_mass_matrix if case.control_surfaces
                  else None)
    return Analysis(case, modal, db, fa, ase, sec, gust=gust, control=control,
                    control_flutter=control_flutter, control_hinge=control_hinge,
                    control_ase=control_ase, control_freeplay=control_freeplay,
                    tsd_validity=P.tsd_validity(case), control_hinge_mass=hinge_mass)


def _f(v):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else float(v)


def summary(a: Analysis) -> dict:
    """The JSON document of an analysis (schema in docs/case-format.md)."""
    c = a.case
    fl = []
    for r in a.flutter.results:
        f = None if r.unstable_at_start else r.flutter     # "at or below U0" has no speed
        row = {"mach": r.mach, "altitude_m": r.condition.altitude, "density": r.condition.density,
               "speed_ms": None if f is None else float(f.speed),
               "frequency_hz": None if f is None else float(f.frequency_hz),
               "mode": None if f is None else mode_number(f.mode, f.n_rigid),
               "unstable_at_first_point": bool(r.unstable_at_start),
               "speed_upper_bound_ms": None}
        if r.unstable_at_start:
            kind = start_kind(r)
            row["speed_upper_bound_ms"] = float(c.flight.velocities[0])
            row["mode"] = mode_number(r.start_mode, r.pk.n_rigid)
            row["note"] = (f"unstable at the first point of the sweep: {kind} at or below "
                           f"{c.flight.velocities[0]:g} m/s")
        if c.flutter_index is not None and f is not None:
            fs = c.flutter_index
            w_a = 2 * math.pi * fs.f_alpha
            row["flutter_speed_index"] = float(f.speed / (fs.semichord * w_a * math.sqrt(fs.mass_ratio)))
            row["frequency_ratio"] = float(f.frequency_hz / fs.f_alpha)
        fl.append(row)
    n_r = int(a.modal.n_rigid)
    out = {"case": c.name, "reference": c.reference,
           "units": dict(UNITS),
           "modes": {"frequencies_hz": [float(v) for v in a.modal.frequencies_hz],
                     "n_rigid": n_r,
                     "labels": [mode_number(j, n_r) for j in range(len(a.modal.frequencies_hz))]},
           "boxes": int(a.database.metadata.get("boxes", 0)) or None,
           "flutter": fl,
           "divergence": [{"mach": d["mach"], "altitude_m": d["altitude_m"],
                           "speed_ms": _f(d["speed_ms"])} for d in a.flutter.divergence],
           "match_points": [dict(m) for m in a.flutter.match_points],
           "flutter_margins": [dict(m) for m in a.flutter.margins],
           "notes": list(a.flutter.notes),
           "seconds": {k: float(v) for k, v in a.seconds.items()}}
    if a.ase is not None:
        s = a.ase
        out["ase"] = {"mach": s.mach, "altitude_m": s.altitude, "velocity_ms": s.velocity,
                      "stable": dict(s.stable), "max_real_pole": dict(s.max_real_pole),
                      "settling_s": {k: _f(v) for k, v in s.settling_s.items()},
                      "steady_error_pct": {k: _f(v * 100) for k, v in s.steady_error.items()},
                      "corner_overshoot_pct": {k: {c: _f(x * 100) for c, x in v.items()}
                                               for k, v in s.corner_overshoot.items()},
                      "fwtf_phase_margin_deg": {str(i): _f(x.phase_margin_deg)
                                                for i, x in s.crossovers.items()}}
    if a.gust is not None:
        out["gust"] = gust_json(a.gust)
        if a.gust.turbulence is not None:
            out["turbulence"] = turbulence_json(a.gust)
    if getattr(c, "control_surfaces", ()):   # (surfaces at supersonic Machs only: no rows)
        out["control_surfaces"] = control_surfaces_json(
            c, a.control, getattr(a, "control_freeplay", ()))
        out["control_surface_flutter"] = [
            {"mach": r.mach, "altitude_m": r.altitude, "density": r.density,
             "speed_ms": _f(r.speed_ms), "frequency_hz": _f(r.frequency_hz), "mode": r.mode,
             "unstable_at_first_point": r.unstable_at_first_point}
            for r in a.control_flutter]
        out.update(hinge_load_json(getattr(a, "control_hinge", ())))
        if getattr(a, "control_hinge_mass", None) is not None:    # issue 25: inertial coupling
            out["hinge_mass_matrix"] = [[float(x) for x in row] for row in a.control_hinge_mass]
        out.update(control_ase_json(getattr(a, "control_ase", ())))
    if getattr(a, "tsd_validity", ()):         # issue 29: the TSD's validity per Mach
        out["tsd_validity"] = [tsd_validity_json(v) for v in a.tsd_validity]
    out["critical"] = critical_condition(out)
    return out


def tsd_validity_json(v) -> dict:
    """One Mach's :class:`asekit.aero.tsd3d.TsdValidity` as JSON (issue 29)."""
    return {"mach": v.mach, "thickness_ratio": v.thickness_ratio,
            "similarity_parameter": _f(v.similarity),
            "supersonic_points": v.supersonic_points, "shock": v.shock, "cp_min": v.cp_min,
            "cp_critical": v.cp_critical, "converged": v.converged, "text": v.text()}


def _where(alt, rho=None) -> str:
    """A flight condition in words: its altitude, else its density (when known)."""
    if alt is not None:
        return f"{alt:g} m"
    return f"rho {rho:.4g} kg/m^3" if rho is not None else "the given density"


def _nearest_row(rows, altitude, mach):
    """The flutter row at ``altitude`` nearest in Mach to ``mach`` on the same side of M 1."""
    here = [r for r in rows if r["altitude_m"] == altitude and r["mode"] is not None
            and (r["mach"] == mach or not across_sonic(r["mach"], mach))]
    return min(here, key=lambda r: abs(r["mach"] - mach), default=None)


def _critical_margin(s: dict) -> dict | None:
    """The lowest flutter margin of ``s["flutter_margins"]`` (a value or its bound)."""
    def value(m):
        for key, bound in (("margin", "value"), ("margin_upper_bound", "at most"),
                           ("margin_lower_bound", "at least")):
            if m.get(key) is not None:
                return m[key], bound
        return None, None
    ms = [(value(m), m) for m in s.get("flutter_margins", ()) if value(m)[0] is not None]
    if not ms:
        return None
    (margin, bound), m = min(ms, key=lambda x: x[0][0])
    speed = {"value": m.get("flutter_speed_ms"), "at most": m.get("flutter_speed_upper_bound_ms"),
             "at least": m.get("flutter_speed_lower_bound_ms")}[bound]
    row = _nearest_row(s.get("flutter", ()), m["altitude_m"], m["envelope_mach"])
    where = "inside" if margin < 0 else "outside"
    # a bound on the margin words the distance from the envelope the other way round inside it
    qual = {"value": "", "at most": "at least " if margin < 0 else "at most ",
            "at least": "at most " if margin < 0 else "at least "}[bound]
    found = {"value": f"flutter at {speed:.1f} m/s",
             "at most": f"flutter at or below {speed:.1f} m/s",
             "at least": f"no flutter up to {speed:.1f} m/s"}[bound]
    place = _where(m["altitude_m"], None if row is None else row["density"])
    text = (f"M {m['envelope_mach']:g} (the envelope's top), {place}: {found} vs the flight "
            f"speed {m['envelope_speed_ms']:.1f} m/s")
    if row is not None and row["frequency_hz"] is not None:
        text += (f", {row['frequency_hz']:.4g} Hz, {mode_label_of(row['mode'])}"
                 + ("" if row["mach"] == m["envelope_mach"] else f" (at M {row['mach']:g})"))
    text += f": flutter {where} the envelope by {qual}{abs(100 * margin):.1f} %"
    return {"mach": m["envelope_mach"], "altitude_m": m["altitude_m"], "speed_ms": speed,
            "frequency_hz": None if row is None else row["frequency_hz"],
            "mode": None if row is None else row["mode"], "margin": margin,
            "margin_bound": bound, "envelope_speed_ms": m["envelope_speed_ms"], "text": text}


def mode_label_of(number) -> str:
    """The text label of a JSON ``mode`` (an elastic number or "rigid pitch")."""
    return number if isinstance(number, str) else f"mode {number}"


def critical_condition(s: dict) -> dict:
    """The critical condition of a summary :func:`summary` (a dict, so the JSON works too):
    the lowest flutter margin against the envelope (docs/case-format.md ``flight.envelope_*``),
    else, without an envelope, the condition unstable at the first point of the sweep or the
    lowest flutter speed. Returns ``{"mach", "altitude_m", "speed_ms", "frequency_hz", "mode",
    "margin", "text"}`` (None where unknown); ``text`` words it for a person, e.g. "M 0.6 (the
    envelope's top), 0 m: flutter at 213.0 m/s vs the flight speed 204.2 m/s, 142.4 Hz, mode 2:
    flutter outside the envelope by 4.3 %".

    Examples
    --------
    >>> row = {"mach": 0.5, "altitude_m": 0.0, "density": 1.225, "speed_ms": 150.0,
    ...        "frequency_hz": 20.0, "mode": 2, "unstable_at_first_point": False,
    ...        "speed_upper_bound_ms": None}
    >>> margin = {"altitude_m": 0.0, "envelope_mach": 0.5, "envelope_speed_ms": 170.1,
    ...           "margin": 150.0 / 170.1 - 1, "flutter_speed_ms": 150.0}
    >>> print(critical_condition({"flutter": [row], "flutter_margins": [margin]})["text"])
    ... # doctest: +NORMALIZE_WHITESPACE
    M 0.5 (the envelope's top), 0 m: flutter at 150.0 m/s vs the flight speed 170.1 m/s,
    20 Hz, mode 2: flutter inside the envelope by 11.8 %
    """
    c = _critical_margin(s)
    if c is not None:
        return c
    rows = list(s.get("flutter", ()))
    first = [r for r in rows if r.get("unstable_at_first_point")]
    found = [r for r in rows if r.get("speed_ms") is not None]
    none = {"mach": None, "altitude_m": None, "speed_ms": None, "frequency_hz": None,
            "mode": None, "margin": None}
    if first:
        r = first[0]
        text = (f"M {r['mach']:g}, {_where(r['altitude_m'], r['density'])}: unstable at the "
                f"first point of the sweep ({mode_label_of(r['mode'])} at or below "
                f"{r['speed_upper_bound_ms']:g} m/s): start the sweep lower")
        return {**none, "mach": r["mach"], "altitude_m": r["altitude_m"],
                "speed_ms": r["speed_upper_bound_ms"], "mode": r["mode"], "text": text}
    if found:
        r = min(found, key=lambda r: r["speed_ms"])
        text = (f"M {r['mach']:g}, {_where(r['altitude_m'], r['density'])}: the lowest flutter "
                f"speed, {r['speed_ms']:.1f} m/s, {r['frequency_hz']:.4g} Hz, "
                f"{mode_label_of(r['mode'])} (no envelope in the case: no margin)")
        return {**none, **{k: r[k] for k in ("mach", "altitude_m", "speed_ms", "frequency_hz",
                                              "mode")}, "text": text}
    return {**none, "text": "no flutter in the sweep at any analysed condition"}


def _cell(v, fmt="{:.4g}"):
    if v is None:
        return "-"
    if isinstance(v, float):
        return fmt.format(v)
    return str(v)


def _speed_cell(row: dict) -> str:
    """The U_f cell of a flutter row: the speed, '<=U0' when unstable at the first point."""
    if row.get("speed_upper_bound_ms") is not None:
        return f"<={row['speed_upper_bound_ms']:.2f}"
    return _cell(row["speed_ms"], "{:.2f}")


def _margin_text(m: dict) -> str:
    """A margin line's value: the margin, its bound ('at most' / 'at least') or '-', with the
    note."""
    env = m["envelope_speed_ms"]
    if m["margin"] is not None:
        where = ("flutter inside the envelope by" if m["margin"] < 0 else
                 "flutter outside the envelope by")
        return (f"{100 * m['margin']:+.1f} % ({where} {abs(100 * m['margin']):.1f} %: U_f "
                f"{m['flutter_speed_ms']:.1f} vs {env:.1f} m/s)")
    if m.get("margin_upper_bound") is not None:
        u = m["flutter_speed_upper_bound_ms"]
        return (f"at most {100 * m['margin_upper_bound']:+.1f} % (flutter at or below {u:.1f} "
                f"m/s, the first point of the sweep, vs {env:.1f} m/s"
                + (": inside the envelope)" if u < env else "; start the sweep lower)"))
    if m.get("margin_lower_bound") is not None:
        return (f"at least {100 * m['margin_lower_bound']:+.1f} % (no flutter up to "
                f"{m['flutter_speed_lower_bound_ms']:.1f} m/s vs {env:.1f} m/s)")
    return "-" + (f" ({m['note']})" if m.get("note") else "")


def _gust_lines(rows) -> list:
    """The summary's lines of the ``"gust"`` rows (none without them)."""
    if not rows:
        return []
    lines = ["", f"1-cos gusts at M {rows[0]['mach']:g}, {rows[0]['altitude_m']:g} m (peaks; "
             "loads with the actuator clamped, current in the AEM1 loop, linear and "
             "power-limited):",
             "  H (m)   hinge moment (N m)   root bending (N m)   root shear (N)   current (A)"
             "   limited (A)"]
    for r in rows:
        h = f"{r['gust_length_m']:<7g}" if r["gust_length_m"] is not None else r["profile"]
        sat = " saturated" if r.get("saturated") else ""
        lines.append(f"  {h} {_cell(r['peak_hinge_moment_Nm']):>18}   "
                     f"{_cell(r['peak_root_bending_Nm']):>18}   "
                     f"{_cell(r['peak_root_shear_N']):>14}   "
                     f"{_cell(r['peak_current_A']):>11}   "
                     f"{_cell(r.get('peak_current_limited_A')):>11}{sat}")
    return lines + _station_lines(rows)


def _station_lines(rows) -> list:
    """The summary's lines of the ``[[gust.station]]`` peaks: per station the largest
    magnitude (signed) over the gusts (none without stations)."""
    names = list(rows[0].get("stations") or {})
    if not names:
        return []
    lines = ["  station          shear (N)   bending (N m)   torsion (N m)   (worst gust)"]
    for n in names:
        worst = [max((r["stations"][n][k] for r in rows), key=abs)
                 for k in ("peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm")]
        lines.append(f"  {n:<14} {_cell(worst[0]):>11}   {_cell(worst[1]):>13}   "
                     f"{_cell(worst[2]):>13}")
    return lines


def _turbulence_lines(rows) -> list:
    """The summary's line of the ``"turbulence"`` rows (none without them)."""
    out = []
    for r in rows or []:
        out.append(f"turbulence at M {r['mach']:g}, {r['altitude_m']:g} m: hinge moment RMS "
                   f"{_cell(r['rms_hinge_moment_Nm'])} N m (A-bar {_cell(r['A_bar_hinge'])}, "
                   f"N0 {_cell(r['N0_per_s'])} /s); root bending RMS "
                   f"{_cell(r['rms_root_bending_Nm'])} N m (A-bar "
                   f"{_cell(r['A_bar_root_bending'])}, N0 {_cell(r['N0_root_bending_per_s'])} /s)")
    return out


def _control_lines(rows) -> list[str]:
    """The control-surface block of the summary: one line per surface and Mach."""
    if not rows:
        return []
    out = ["", "control surfaces (rigid derivatives per rad; rolling-moment reversal; "
               "I_h, S about the hinge)",
           f"{'surface':>10} {'kind':>7} {'Mach':>6} {'dCL/dd':>8} {'dCL/da':>8} {'Ch_d':>8} "
           f"{'Ch_a':>8} {'U_rev m/s':>10} {'I_h g m2':>9} {'S g m':>8}"]
    for r in rows:
        rev = r["reversal_speed_ms"]
        i_h, s_h = r.get("hinge_inertia_kgm2"), r.get("static_unbalance_kgm")
        out.append(f"{r['name'][:10]:>10} {(r.get('kind') or '-')[:7]:>7} {r['mach']:>6.3g} "
                   f"{r['dCL_ddelta_per_rad']:>8.4f} {r['dCL_dalpha_per_rad']:>8.4f} "
                   f"{r['Ch_delta']:>8.4f} {r['Ch_alpha']:>8.4f} "
                   f"{'none' if rev is None else f'{rev:.1f}':>10} "
                   f"{'-' if i_h is None else f'{1e3 * i_h:.4g}':>9} "
                   f"{'-' if s_h is None else f'{1e3 * s_h:.4g}':>8}")
    return out


def _control_flutter_lines(rows) -> list[str]:
    """The flutter rows with the hinge degrees of freedom free: one line per Mach and
    condition, the mode named (a surface by its name)."""
    if not rows:
        return []
    out = ["", "flutter with the control surfaces free on their hinges (p-k, rigid modes held)",
           f"{'Mach':>6} {'rho kg/m3':>10} {'U_f m/s':>9} {'f_f Hz':>8}  mode"]
    for r in rows:
        sp = ("UNSTABLE AT FIRST POINT" if r["unstable_at_first_point"] else
              "none" if r["speed_ms"] is None else f"{r['speed_ms']:.2f}")
        mode = "-" if r["mode"] is None else (f"mode {r['mode']}" if isinstance(r["mode"], int)
                                              else str(r["mode"]))
        out.append(f"{r['mach']:>6.3g} {r['density']:>10.4g} {sp:>9} "
                   f"{_cell(r['frequency_hz'], '{:.2f}'):>8}  {mode}")
    return out


def control_surfaces_json(case, rows, freeplay=()) -> list[dict]:
    """The ``control_surfaces`` rows of the analysis JSON (issue 25): per surface and Mach of
    :func:`asekit.case.pipeline.control_surfaces` ``rows``, its ``kind`` (the case's
    ``[[control_surface]]``), derivatives, reversal and divergence speeds, the hinge inertia and
    static unbalance about the hinge (kg m^2, kg m; computed from the finite-element mass of
    the surface's hinge mode) and, with freeplay, the ``freeplay`` rows' keys
    (:func:`freeplay_json`)."""
    kinds = {cs.name: cs.kind for cs in case.control_surfaces}
    return [{"name": r.name, "kind": kinds.get(r.name), "mach": r.mach,
             "dCL_ddelta_per_rad": r.dCL_ddelta_per_rad,
             "dCL_dalpha_per_rad": r.dCL_dalpha_per_rad, "Ch_delta": r.Ch_delta,
             "Ch_alpha": r.Ch_alpha, "dCm_ddelta_per_rad": _f(r.dCm_ddelta_per_rad),
             "dCm_dalpha_per_rad": _f(r.dCm_dalpha_per_rad),
             "rolling_moment_per_rad_m3": _f(r.rolling_moment_per_rad_m3),
             "reversal_speed_ms": _f(r.reversal_speed_ms),
             "divergence_speed_ms": _f(r.divergence_speed_ms), "density": r.density,
             "hinge_inertia_kgm2": r.inertia, "static_unbalance_kgm": r.static_unbalance,
             **freeplay_json(freeplay, r.name, r.mach)} for r in rows]


def freeplay_json(rows, name: str, mach: float) -> dict:
    """The hinge-freeplay keys of the control_surfaces row of surface ``name`` at ``mach``
    (:func:`asekit.case.pipeline.control_surface_freeplay`); {} when it has no freeplay."""
    for r in rows:
        if r.name == name and r.mach == mach:
            return {"freeplay_deg": r.freeplay_deg, "lco_onset_speed_ms": _f(r.lco_onset_speed_ms),
                    "lco_at_first_point": r.lco_at_first_point,
                    "freeplay_linear_flutter_speed_ms": _f(r.linear_flutter_speed_ms)}
    return {}


def hinge_load_json(rows) -> dict:
    """The hinge-moment keys of the analysis JSON (issue 25, servo sizing) from
    :func:`asekit.case.pipeline.control_surface_hinge_loads` rows:
    ``control_surface_hinge_moments`` (one row per surface and point) and
    ``control_surface_servo_sizing`` (per surface, the largest |H_delta| and |H_alpha| over
    the points, signed, and where). Empty without rows."""
    if not rows:
        return {}
    pts = [{"name": r.name, "mach": r.mach, "altitude_m": r.altitude, "density": r.density,
            "speed_ms": r.speed_ms, "dynamic_pressure_pa": r.dynamic_pressure,
            "hinge_moment_per_delta_Nm_per_rad": r.hinge_moment_per_delta,
            "hinge_moment_per_alpha_Nm_per_rad": r.hinge_moment_per_alpha, "basis": r.basis}
           for r in rows]
    sizing = []
    for name in dict.fromkeys(r.name for r in rows):
        mine = [r for r in rows if r.name == name]
        wd = max(mine, key=lambda r: abs(r.hinge_moment_per_delta))
        wa = max(mine, key=lambda r: abs(r.hinge_moment_per_alpha))
        sizing.append({"name": name, "basis": wd.basis,
                       "max_abs_hinge_moment_per_delta_Nm_per_rad": wd.hinge_moment_per_delta,
                       "mach": wd.mach, "altitude_m": wd.altitude,
                       "dynamic_pressure_pa": wd.dynamic_pressure,
                       "max_abs_hinge_moment_per_alpha_Nm_per_rad": wa.hinge_moment_per_alpha})
    return {"control_surface_hinge_moments": pts, "control_surface_servo_sizing": sizing}


def control_ase_json(rows) -> dict:
    """The ``control_surface_ase`` key of the analysis JSON (issue 25): one row per topology
    of :func:`asekit.case.pipeline.control_surface_ase` (empty without an actuated surface)."""
    if not rows:
        return {}
    return {"control_surface_ase": [
        {"name": r.name, "topology": r.topology, "mach": r.mach, "altitude_m": r.altitude,
         "speed_ms": r.speed_ms, "dynamic_pressure_pa": r.dynamic_pressure,
         "stable": r.stable, "max_real_pole": r.max_real_pole,
         "effective_inertia_kgm2": r.effective_inertia,
         "phase_margin_deg": _f(r.phase_margin_deg), "gain_margin_db": _f(r.gain_margin_db),
         "crossover_hz": _f(r.crossover_hz), "step_deg": r.step_deg,
         "settling_s": _f(r.settling_time_s),
         "settling_ms": None if r.settling_time_s is None else 1e3 * r.settling_time_s,
         "overshoot_pct": 100.0 * r.overshoot,
         "steady_error_pct": 100.0 * r.steady_error} for r in rows]}


def _hinge_load_lines(rows) -> list[str]:
    """The servo-sizing block of the summary: per surface the largest hinge moments per degree
    of deflection and of incidence over the envelope (or the sweep's top)."""
    if not rows:
        return []
    out = ["", "hinge moments for servo sizing (rigid; largest over the envelope, N m per deg)",
           f"{'surface':>10} {'H/delta':>9} {'H/alpha':>9} {'Mach':>6} {'alt m':>7} "
           f"{'q Pa':>9}  basis"]
    deg = math.pi / 180.0
    for r in rows:
        alt = "-" if r["altitude_m"] is None else f"{r['altitude_m']:.0f}"
        out.append(f"{r['name'][:10]:>10} "
                   f"{r['max_abs_hinge_moment_per_delta_Nm_per_rad'] * deg:>9.4g} "
                   f"{r['max_abs_hinge_moment_per_alpha_Nm_per_rad'] * deg:>9.4g} "
                   f"{r['mach']:>6.3g} {alt:>7} {r['dynamic_pressure_pa']:>9.4g}  {r['basis']}")
    return out


def _control_ase_lines(rows) -> list[str]:
    """The summary block of the actuator loop on a control surface (issue 25): one line per
    topology of the ``control_surface_ase`` JSON rows."""
    if not rows:
        return []
    r0 = rows[0]
    out = ["", f"actuator on {r0['name']} (thesis servo, System 3) at {r0['speed_ms']:g} m/s, "
               f"Mach {r0['mach']:g}, {r0['altitude_m']:g} m",
           f"{'loop':>5} {'stable':>6} {'max Re p':>9} {'PM deg':>7} {'f_c Hz':>7} "
           f"{'settle ms':>9} {'over %':>7} {'error %':>7}"]
    for r in rows:
        pm = "-" if r["phase_margin_deg"] is None else f"{r['phase_margin_deg']:.1f}"
        fc = "-" if r["crossover_hz"] is None else f"{r['crossover_hz']:.1f}"
        ts = "-" if r["settling_s"] is None else f"{1e3 * r['settling_s']:.1f}"
        out.append(f"{r['topology']:>5} {'yes' if r['stable'] else 'NO':>6} "
                   f"{r['max_real_pole']:>9.3g} {pm:>7} {fc:>7} {ts:>9} "
                   f"{r['overshoot_pct']:>7.2f} {r['steady_error_pct']:>7.2f}")
    return out


def format_summary(s: dict, width: int = 100) -> str:
    """A plain-text summary of :func:`summary` that fits ``width`` columns."""
    lines = textwrap.wrap(f"case {s['case']}" + (f"  ({s['reference']})" if s.get("reference")
                                                  else ""), width, subsequent_indent="  ")
    f = s["modes"]["frequencies_hz"]
    r = s["modes"]["n_rigid"]
    lines.append("modes (Hz): " + ", ".join(f"{mode_label(j, r)} {v:.4g}"
                                            for j, v in enumerate(f) if j >= r)
                 + (f"  (+ {mode_label(0, r)})" if r else ""))
    if s.get("critical"):
        lines += textwrap.wrap("critical: " + s["critical"]["text"], width,
                               subsequent_indent="  ")
    has_fsi = any("flutter_speed_index" in row for row in s["flutter"])
    head = f"{'Mach':>6} {'altitude m':>10} {'rho kg/m3':>10} {'U_f m/s':>9} {'f_f Hz':>8} {'mode':>4}"
    if has_fsi:
        head += f" {'FSI':>7} {'w_f/w_a':>7}"
    head += "  note"
    methods = sorted({f"FLUTTER {r['sid']} {r['method']}" for r in s["flutter"] if "method" in r})
    lines += ["", f"flutter ({', '.join(methods) if methods else 'p-k'}, rigid modes held)",
              head]
    for row in s["flutter"]:
        ln = (f"{row['mach']:>6.3g} {_cell(row['altitude_m'], '{:.0f}'):>10} "
              f"{row['density']:>10.4g} {_speed_cell(row):>9} "
              f"{_cell(row['frequency_hz'], '{:.2f}'):>8} {_cell(row['mode']):>4}")
        if has_fsi:
            ln += (f" {_cell(row.get('flutter_speed_index'), '{:.4f}'):>7}"
                   f" {_cell(row.get('frequency_ratio'), '{:.4f}'):>7}")
        if row["unstable_at_first_point"]:
            ln += "  UNSTABLE AT FIRST POINT"
        elif row["speed_ms"] is None:
            ln += "  none in sweep"
        lines.append(ln[:width])
    div = [d for d in s["divergence"] if d["speed_ms"] is not None]
    if div:
        lines += [""] + textwrap.wrap("static divergence (m/s): " + ", ".join(
            f"M {d['mach']:g} {_cell(d['altitude_m'], '{:.0f} m')} {d['speed_ms']:.1f}"
            for d in div), width, subsequent_indent="  ")
    for m in s["match_points"]:
        lines.append(f"match point at {_cell(m['altitude_m'], '{:.0f}')} m: "
                     + (f"none ({m['no_match']})" if m["matched_mach"] is None else
                        f"M {m['matched_mach']:.3f} ({m['matched_speed_ms']:.1f} m/s)"))
    for m in s["flutter_margins"]:
        lines.append(f"flutter margin at {_cell(m['altitude_m'], '{:.0f}')} m, envelope top "
                     f"M {m['envelope_mach']:g}: " + _margin_text(m))
    if "ase" in s:
        a = s["ase"]
        lines += ["", f"ASE loop at M {a['mach']:g}, {a['altitude_m']:g} m:"]
        for t in a["stable"]:
            ov = a["corner_overshoot_pct"][t]
            st = a["settling_s"][t]
            lines += textwrap.wrap(
                f"{t}: {'stable' if a['stable'][t] else 'UNSTABLE'} (max Re pole "
                f"{a['max_real_pole'][t]:.3g} 1/s); fin root "
                + ("never inside the 2 % band" if st is None else f"settles in {1e3 * st:.1f} ms")
                + f", final error {_cell(a['steady_error_pct'][t], '{:.2f}')} %; corner "
                f"overshoot {min(ov.values()):.0f}-{max(ov.values()):.0f} %", width,
                initial_indent="  ", subsequent_indent="    ")
    lines += _gust_lines(s.get("gust")) + _turbulence_lines(s.get("turbulence"))
    lines += _control_lines(s.get("control_surfaces", ()))
    lines += _control_flutter_lines(s.get("control_surface_flutter", ()))
    lines += _hinge_load_lines(s.get("control_surface_servo_sizing", ()))
    lines += _control_ase_lines(s.get("control_surface_ase", ()))
    for v in s.get("tsd_validity", ()):           # issue 29
        lines += textwrap.wrap("validity: " + v["text"], width, subsequent_indent="  ")
    for n in s["notes"]:
        lines += textwrap.wrap("note: " + n, width, subsequent_indent="  ")
    lines.append("")
    lines.append("times (s): " + ", ".join(f"{k} {v:.2f}" for k, v in s["seconds"].items()))
    out = []
    for ln in lines:
        out += textwrap.wrap(ln, width, subsequent_indent="    ") if len(ln) > width else [ln]
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# figures and the HTML report
# ---------------------------------------------------------------------------------------------
def fig_planform(a: Analysis):
    """The planform figure (FE mesh; aerodynamic boxes over it): a matplotlib figure."""
    return RF.fig_planform(a).figure


def fig_modes(a: Analysis):
    """Every kept mode shape with a colour bar and the node lines: a matplotlib figure."""
    return RF.fig_modes(a).figure


def fig_vg(a: Analysis, result):
    """V-g and V-f of one analysed condition (a ``ConditionResult`` of ``a.flutter.results``),
    the flutter point starred: a matplotlib figure."""
    return RF.fig_vg_mach(a, result.mach, [result]).figure


def fig_root_locus(a: Analysis, result):
    """The root locus of the p-k roots of one analysed condition: a matplotlib figure."""
    return RF.fig_root_locus_mach(a, result.mach, [result]).figure


def figures(a: Analysis) -> dict:
    """{file name: :class:`~asekit.case.report_figures.ReportFigure`} of the report
    (:func:`asekit.case.report_figures.figures`: the flutter-against-Mach figure, V-g / V-f and
    root locus at every analysed Mach for every flight condition, planform, every kept mode
    shape, and with an actuator the ASE figures)."""
    return RF.figures(a)


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder and
    :func:`os.replace`: a reader (or an interrupted run) sees the old file or the new one,
    never half of it."""
    import os
    import tempfile
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


_CSS = ("body{font-family:sans-serif;max-width:75em;margin:auto;padding:0 1em} "
        "img{max-width:100%;height:auto} pre{background:#f4f4f4;padding:1em;overflow-x:auto} "
        ".critical{background:#fff4e5;border-left:4px solid #e8a33d;padding:.6em 1em} "
        "figcaption{font-size:90%;color:#444}")


def _item(v):
    """A ``figures`` value as (figure, alt, section): a ReportFigure, or a bare figure."""
    if isinstance(v, RF.ReportFigure):
        return v.figure, v.alt, v.section
    return v, None, "Figures"


def _report_page(s: dict, saved) -> str:
    """The HTML page: the summary first (the critical condition, a link to the JSON, the
    table), then the figures by section; ``saved`` is [(file name, alt text, section)]."""
    e = html.escape
    name = s.get("case", "")
    crit = s.get("critical")
    head = [f"<h1>{e(name)}</h1>"]
    if s.get("reference"):
        head.append(f"<p>{e(s['reference'])}</p>")
    head.append("<h2 id='summary'>Summary</h2>")
    if crit:
        head.append(f"<p class='critical'><strong>Critical condition:</strong> "
                    f"{e(crit['text'])}</p>")
    head.append("<p>Every number of this page, with the unit of each key: "
                "<a href='summary.json'>summary.json</a>.</p>")
    head.append(f"<pre>{e(format_summary(s, width=120))}</pre>")
    sections = []
    for _, _, sec in saved:
        if sec not in sections:
            sections.append(sec)
    body = []
    for sec in sections:
        body.append(f"<h2>{e(sec)}</h2>")
        body += [f"<figure><img src='{e(f)}' alt='{e(alt or f)}'>"
                 + (f"<figcaption>{e(alt)}</figcaption>" if alt else "") + "</figure>"
                 for f, alt, x in saved if x == sec]
    return (f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>asekit: "
            f"{e(name)}</title><style>{_CSS}</style></head><body>" + "\n".join(head + body)
            + "</body></html>\n")


def _save_figures(a, directory, progress: bool):
    """Save every figure of :func:`figures` into ``directory``; [(file, alt, section)]."""
    items = list(figures(a).items())
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(items), desc="report figures", leave=False)
    saved = []
    try:
        for name, v in items:
            fig, alt, sec = _item(v)
            saved.append((save_figure(fig, directory, name).name, alt, sec))
            if bar is not None:
                bar.update(1)
    finally:
        import matplotlib.pyplot as plt
        for _, v in items:
            plt.close(_item(v)[0])
        if bar is not None:
            bar.close()
    return saved


def write_report(a: Analysis, directory, progress: bool = False, s: dict | None = None) -> Path:
    """Write ``directory/index.html`` (the summary first: the critical condition, a link to
    ``summary.json`` and the table; then the figures, each with an alt text saying what it
    shows) with the PNGs beside it and ``summary.json``; returns the index path. ``progress``
    shows a tqdm bar over the figures; ``s`` the summary to show and write (default
    :func:`summary` of ``a``; a Nastran deck's adds its FLUTTER cards' rows).

    The report is written into a temporary folder next to ``directory`` and moved into place
    when complete (an existing report there is replaced), so an interrupted run (SIGINT) leaves
    the previous report or none, never PNGs without their ``index.html``."""
    import os
    import shutil
    import tempfile
    d = Path(directory)
    d.parent.mkdir(parents=True, exist_ok=True)
    if d.exists() and not d.is_dir():
        raise NotADirectoryError(f"--report {d}: exists and is not a directory")
    tmp = Path(tempfile.mkdtemp(prefix=f".{d.name}.", suffix=".partial", dir=d.parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)           # mkdtemp's folder is private (0700)
    old = None
    try:
        s = summary(a) if s is None else s
        (tmp / "summary.json").write_text(json.dumps(s, indent=2))
        saved = _save_figures(a, tmp, progress)
        (tmp / "index.html").write_text(_report_page(s, saved))
        if d.exists():
            old = d.with_name(f".{d.name}.{os.getpid()}.old")
            os.replace(d, old)
        os.replace(tmp, d)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and not d.exists():
            os.replace(old, d)              # put the previous report back
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return d / "index.html"
