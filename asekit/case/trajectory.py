"""Flutter and divergence margins, dynamic pressure and steady hinge moment along a flight
trajectory (``asekit trajectory CASE PROFILE``), beside the NACA TN 4197 screening boundary.

A profile is a CSV file with the columns ``time_s`` (s, strictly increasing), ``mach`` (0 < M
<= 10) and ``altitude_m`` (m, the 1976 standard atmosphere's range), and optionally
``alpha_deg`` and ``deflection_deg`` (deg, within [-90, 90]): :func:`read_profile` checks every
column and row and names the file, row and column of a bad value.

:func:`trajectory` analyses the case at every altitude of the profile through the case pipeline
(:func:`asekit.case.pipeline.flutter` with the profile's altitudes as ``flight.altitudes``: the
same GAF database at the case's ``aero.machs``, the same flutter method and sweep), and at each
point takes the flutter speed at the point's Mach as the pipeline's margins do
(:func:`asekit.case.envelope.flutter_margin`: linear in Mach between the analysed Machs, extrapolated
at most 0.05 beyond them, never across M 1). So at a case's own altitude and envelope top Mach
the trajectory's margin is the pipeline's. A point in the transonic gap
(:data:`asekit.aero.methods.DLM_MACH_MAX` < M < :data:`asekit.aero.methods.SUPERSONIC_MACH_MIN`)
that the case's ``aero.method`` refuses gets no flutter speed and is marked.
"""

from __future__ import annotations

import csv
import dataclasses
import logging
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from asekit.aero.methods import DLM_MACH_MAX, SUPERSONIC_MACH_MIN, TransonicWarning, resolve_method
from asekit.atmosphere import MAX_ALTITUDE, MIN_ALTITUDE, standard_atmosphere
from asekit.case.envelope import across_sonic, flutter_margin, flutter_points, interpolate_speed
from asekit.case.schema import Case, CaseError

_log = logging.getLogger(__name__)

#: The profile's columns: (name, required, low, high) with the valid closed range (Mach: 0
#: excluded).
PROFILE_COLUMNS = (("time_s", True, -math.inf, math.inf),
                   ("mach", True, 0.0, 10.0),
                   ("altitude_m", True, MIN_ALTITUDE, MAX_ALTITUDE),
                   ("alpha_deg", False, -90.0, 90.0),
                   ("deflection_deg", False, -90.0, 90.0))

#: TN 4197's constants: the ratio of specific heats of air and the sea-level pressure (Pa).
GAMMA_AIR = 1.4
SEA_LEVEL_PRESSURE = 101325.0


class ProfileError(ValueError):
    """A trajectory profile the reader refuses (the message names file, row and column)."""


@dataclass(frozen=True)
class ProfilePoint:
    """One point of a trajectory profile: time (s), Mach, altitude (m), angle of attack and
    commanded deflection (deg; None when the profile has no such column)."""

    time_s: float
    mach: float
    altitude_m: float
    alpha_deg: float | None = None
    deflection_deg: float | None = None


def _cell(path, row: int, name: str, text: str, low: float, high: float) -> float:
    """One checked cell: a finite number in [low, high] (Mach: > 0)."""
    where = f"{path}, row {row}, column {name}"
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise ProfileError(f"{where}: not a number: {text!r}") from None
    bad_low = v <= low if name == "mach" else v < low
    if not math.isfinite(v) or bad_low or v > high:
        lb = "(" if name == "mach" else "["
        rng = "any finite number" if not math.isfinite(high) else f"{lb}{low:g}, {high:g}]"
        raise ProfileError(f"{where}: {v!r} outside the valid range {rng}")
    return v


def _header(path, fields) -> None:
    known = [c[0] for c in PROFILE_COLUMNS]
    if not fields:
        raise ProfileError(f"{path}: empty file; the first line names the columns "
                           f"{', '.join(known)}")
    unknown = [f for f in fields if f not in known]
    if unknown:
        raise ProfileError(f"{path}, row 1: unknown column(s) {', '.join(map(repr, unknown))}; "
                           f"the columns are {', '.join(known)}")
    missing = [c[0] for c in PROFILE_COLUMNS if c[1] and c[0] not in fields]
    if missing:
        raise ProfileError(f"{path}, row 1: missing column(s) {', '.join(missing)} (required: "
                           "time_s, mach, altitude_m)")
    if len(set(fields)) != len(fields):
        raise ProfileError(f"{path}, row 1: a column is named twice: {', '.join(fields)}")


def read_profile(path) -> tuple[ProfilePoint, ...]:
    """Read and check a trajectory profile (CSV).

    Parameters
    ----------
    path : str or Path
        The CSV file: a header line with ``time_s``, ``mach``, ``altitude_m`` and optionally
        ``alpha_deg``, ``deflection_deg`` (any order), then one row per point; lines starting
        with ``#`` are comments.

    Returns
    -------
    tuple of ProfilePoint
        The points in time order.

    Raises
    ------
    ProfileError
        A missing, unknown or repeated column, a row with the wrong number of cells, a value
        that is not a number or outside its range (time any finite s, strictly increasing;
        0 < M <= 10; altitude within the 1976 standard atmosphere's [-5000, 47000] m; angles
        within [-90, 90] deg), or no row; the message names the file, row (1 = the header)
        and column.

    Examples
    --------
    >>> from asekit.util.paths import DATA_DIR
    >>> pts = read_profile(DATA_DIR / "profiles" / "fin_boost.csv")
    >>> pts[0].time_s, pts[0].mach, pts[0].altitude_m
    (0.5, 0.4, 0.0)
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except FileNotFoundError:
        raise ProfileError(f"{path}: no such profile file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProfileError(f"{path}: unreadable ({exc})") from None
    numbered = [(i + 1, s) for i, s in enumerate(lines) if s.strip() and not s.lstrip()
                .startswith("#")]
    if not numbered:
        _header(path, [])
    rows = list(csv.reader([s for _, s in numbered]))
    fields = [f.strip() for f in rows[0]]
    _header(path, fields)
    ranges = {c[0]: (c[2], c[3]) for c in PROFILE_COLUMNS}
    points = []
    for (line, _), cells in zip(numbered[1:], rows[1:]):
        if len(cells) != len(fields):
            raise ProfileError(f"{path}, row {line}: {len(cells)} cells, the header has "
                               f"{len(fields)} ({', '.join(fields)})")
        vals = {f: _cell(path, line, f, c.strip(), *ranges[f]) for f, c in zip(fields, cells)}
        if points and vals["time_s"] <= points[-1].time_s:
            raise ProfileError(f"{path}, row {line}, column time_s: {vals['time_s']!r} must be "
                               f"greater than the previous row's {points[-1].time_s!r} "
                               "(strictly increasing)")
        points.append(ProfilePoint(**vals))
    if not points:
        raise ProfileError(f"{path}: no data row under the header")
    return tuple(points)


# ---------------------------------------------------------------------------------------------
# NACA TN 4197
# ---------------------------------------------------------------------------------------------
def tn4197_flutter_speed(shear_modulus: float, aspect_ratio: float, taper_ratio: float,
                         thickness_ratio: float, pressure: float, speed_of_sound: float,
                         epsilon: float = 0.25, gamma: float = GAMMA_AIR) -> float:
    """The empirical flutter speed of a clamped fin of NACA TN 4197 (Martin 1958).

    Martin's flutter boundary, as written in his Eq. for the flutter parameter and quoted with
    ``D_N = 24 epsilon gamma p_0 / pi`` (NACA TN 4197, "Summary of flutter experiences as a
    guide to the preliminary design of lifting surfaces on missiles", 1958)::

        V_f = a sqrt( G / ( D_N A^3 / ((t/c)^3 (A + 2)) * (lambda + 1) / 2 * p / p_0 ) )
            = a sqrt( G (t/c)^3 (A + 2) / ( (12 epsilon gamma / pi) A^3 (lambda + 1) p ) )

    With epsilon = 0.25 (the elastic axis a quarter chord behind the aerodynamic centre) and
    gamma = 1.4, D_N = 39.3 psi and 12 epsilon gamma / pi = 1.337: the form
    ``V_f = a sqrt(G / (1.337 A^3 p (lambda + 1) / ((A + 2) (t/c)^3)))``. This is the form
    used here. The often-copied "Peak of Flight" newsletter 291 (Apogee, 2011) divides the
    denominator by a further 2 (``1.337 A^3 p (lambda + 1) / (2 (A + 2) (t/c)^3)``), which
    gives speeds sqrt(2) higher than TN 4197's; the constants do not depend on the unit
    system as long as G and p share one.

    Parameters
    ----------
    shear_modulus : float
        The fin material's shear modulus G (Pa).
    aspect_ratio : float
        A = s^2 / S of the exposed fin (semi-span s m, area S m^2).
    taper_ratio : float
        lambda = tip chord / root chord.
    thickness_ratio : float
        t/c, thickness over the root chord.
    pressure : float
        Ambient static pressure p (Pa).
    speed_of_sound : float
        a (m/s).
    epsilon : float, optional
        Martin's epsilon, the elastic axis's distance behind the quarter chord (chord
        fractions); 0.25 by default (his value for the popular form).
    gamma : float, optional
        Ratio of specific heats (1.4).

    Returns
    -------
    float
        The flutter speed V_f (m/s).

    Examples
    --------
    A 2024-aluminium-like fin (G 26.9 GPa), A 1.282, lambda 0.5, t/c 0.02564, sea level:

    >>> round(tn4197_flutter_speed(26.92e9, 1.282, 0.5, 0.02564, 101325.0, 340.3))
    635
    """
    for name, v in (("shear_modulus", shear_modulus), ("aspect_ratio", aspect_ratio),
                    ("thickness_ratio", thickness_ratio), ("pressure", pressure),
                    ("speed_of_sound", speed_of_sound), ("epsilon", epsilon),
                    ("gamma", gamma)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
    if not (math.isfinite(taper_ratio) and taper_ratio >= 0):
        raise ValueError(f"taper_ratio must be a finite number >= 0, got {taper_ratio!r}")
    d_n = 24.0 * epsilon * gamma * SEA_LEVEL_PRESSURE / math.pi
    term = (d_n * aspect_ratio ** 3 / (thickness_ratio ** 3 * (aspect_ratio + 2.0))
            * (taper_ratio + 1.0) / 2.0 * pressure / SEA_LEVEL_PRESSURE)
    return float(speed_of_sound * math.sqrt(shear_modulus / term))


def tn4197_inputs(case: Case) -> dict | None:
    """TN 4197's fin parameters of a declarative single-panel case: ``shear_modulus`` (Pa:
    E / (2 (1 + nu)) of an isotropic material, g12 of an orthotropic one), ``aspect_ratio``
    (span^2 / area), ``taper_ratio`` (tip / root chord) and ``thickness_ratio`` (root thickness
    / root chord); None for an imported or multi-panel case (the formula is for one trapezoid).

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> p = tn4197_inputs(load_case(FIN_FILE))
    >>> round(p["aspect_ratio"], 3), p["taper_ratio"], round(p["thickness_ratio"], 4)
    (1.282, 0.5, 0.0256)
    """
    if case.structure is not None or len(case.panels) != 1 or case.material is None:
        return None
    pf = case.panels[0].planform
    span = pf.tip_le[1] - pf.root_le[1]
    area = 0.5 * (pf.root_chord + pf.tip_chord) * span
    m = case.material
    g = (m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio)) if hasattr(m, "youngs_modulus")
         else m.g12)
    return {"shear_modulus": float(g), "aspect_ratio": span ** 2 / area,
            "taper_ratio": pf.tip_chord / pf.root_chord,
            "thickness_ratio": case.thickness.root / pf.root_chord}


# ---------------------------------------------------------------------------------------------
# the trajectory
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TrajectoryRow:
    """The case at one point of the trajectory.

    Attributes
    ----------
    time_s, mach, altitude_m : float
        The profile's point (s, -, m).
    dynamic_pressure_Pa : float
        q = rho (M a)^2 / 2 (Pa), 1976 standard atmosphere.
    flutter_speed_ms : float or None
        asekit's flutter speed at the point's Mach and altitude (m/s); None when not known
        (see ``note``).
    flutter_margin_pct : float or None
        100 (U_f / (M a) - 1) (%); negative: flutter at this point.
    divergence_margin_pct : float or None
        100 (U_D / (M a) - 1) (%); None: no static divergence found or not known.
    hinge_moment_Nm : float or None
        The steady hinge moment q Q_cc (alpha + delta) about the shaft (N m; thesis Eq. 4.6);
        None without a rigid pitch mode, without alpha/deflection columns or outside the GAF
        database's Machs.
    tn4197_flutter_speed_ms : float or None
        The NACA TN 4197 boundary (m/s) at the point's altitude (:func:`tn4197_flutter_speed`).
    transonic_gap : bool
        0.9 < M < 1.15 (:func:`in_transonic_gap`): linear theory is not trusted there; when
        the case's ``aero.method`` refuses the Mach (:func:`method_refuses`, e.g. ``"auto"``)
        the point has no flutter, divergence or hinge-moment value.
    mach_extrapolated : bool
        The flutter speed is extrapolated (at most 0.05) beyond the analysed Machs.
    deflection_rate_deg_s : float or None
        The commanded deflection's rate (deg/s; :func:`deflection_rates`), None without an
        actuator power demand.
    motor_current_A, motor_voltage_V, actuator_power_W : float or None
        The actuator's quasi-steady demand to drive the fin at that rate against the steady
        hinge moment (:func:`asekit.servo.simulate.quasi_steady_demand`: the case's
        ``[actuator]`` motor and transmission; P = V I, W); None without ``[actuator]`` or
        without a hinge moment.
    note : str or None
        Why a value is missing, or a bound of the margin.
    """

    time_s: float
    mach: float
    altitude_m: float
    dynamic_pressure_Pa: float
    flutter_speed_ms: float | None
    flutter_margin_pct: float | None
    divergence_margin_pct: float | None
    hinge_moment_Nm: float | None
    tn4197_flutter_speed_ms: float | None
    transonic_gap: bool
    mach_extrapolated: bool = False
    note: str | None = None
    deflection_rate_deg_s: float | None = None
    motor_current_A: float | None = None
    motor_voltage_V: float | None = None
    actuator_power_W: float | None = None

    def to_json(self) -> dict:
        """The row as a JSON-ready dict (the names of the attributes)."""
        return dataclasses.asdict(self)


def in_transonic_gap(mach: float) -> bool:
    """Whether ``mach`` lies in the transonic gap DLM_MACH_MAX < M < SUPERSONIC_MACH_MIN
    (0.9 < M < 1.15) where linear theory is not trusted.

    Examples
    --------
    >>> in_transonic_gap(0.95), in_transonic_gap(0.9), in_transonic_gap(1.2)
    (True, False, False)
    """
    return bool(DLM_MACH_MAX < mach < SUPERSONIC_MACH_MIN)


def method_refuses(case: Case, mach: float) -> bool:
    """Whether the case's ``aero.method`` refuses ``mach`` (``"auto"`` in the transonic gap,
    an explicit method outside its Mach range); a method that accepts it with a
    :class:`~asekit.aero.methods.TransonicWarning` does not refuse it.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> c = load_case(FIN_FILE)                      # aero.method "dlm": warns, not refuses
    >>> auto = dataclasses.replace(c, aero=dataclasses.replace(c.aero, method="auto"))
    >>> method_refuses(c, 0.95), method_refuses(auto, 0.95)
    (False, True)
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        try:
            resolve_method(case.aero.method, mach)
        except ValueError:
            return True
    return False


def _trajectory_case(case: Case, altitudes) -> Case:
    """The case with the profile's altitudes as its flight conditions (sweep and envelope
    kept)."""
    if case.flight is None or case.aero is None:
        raise CaseError(f"{case.name}: a trajectory needs [aero] and [flight] (its velocity "
                        "sweep)")
    flight = dataclasses.replace(case.flight, altitudes=tuple(float(h) for h in altitudes),
                                 densities=None, speeds_of_sound=None)
    return dataclasses.replace(case, flight=flight)


def _q_cc(case: Case, db, modal, mach: float):
    """Re Q_cc at ``mach`` (m^3/rad), the database's lowest k, interpolated between the
    database's Machs on the same side of M 1; None without a rigid pitch mode or outside."""
    if modal.n_rigid < 1 or case.support.kind != "shaft":
        return None, "no rigid pitch mode (a shaft support with modes.keep_rigid)"
    side = [m for m in db.machs if not across_sonic(m, mach)]
    if not side or not min(side) <= mach <= max(side):
        return None, f"M {mach:g} outside the GAF database's Machs on its side of M 1"
    return float(db.at(mach, interpolate=True).Q[0, 0, 0].real), None


def _divergence_margin(fa, cond, mach: float, u: float):
    """100 (U_D / U - 1) at ``mach`` from the pipeline's divergence speeds at ``cond``
    (linear in Mach as the flutter speeds, :func:`asekit.case.envelope.interpolate_speed`)."""
    pts = [(d["mach"], d["speed_ms"]) for d in fa.divergence
           if d["density"] == cond.density and d["speed_ms"] is not None]
    if not pts:
        return None, "no static divergence at the analysed Machs"
    ud = interpolate_speed(pts, mach)
    if ud is None:
        return None, "divergence speed not known at this Mach"
    return 100.0 * (ud / u - 1.0), None


def _row(case, fa, db, modal, p: ProfilePoint, cond, tn) -> TrajectoryRow:
    u = p.mach * cond.speed_of_sound
    q = 0.5 * cond.density * u ** 2
    notes = []
    gap = in_transonic_gap(p.mach)
    refused = method_refuses(case, p.mach)
    uf = margin = None
    extrap = False
    if gap:
        notes.append(f"M {p.mach:g} in the transonic gap {DLM_MACH_MAX:g} < M < "
                     f"{SUPERSONIC_MACH_MIN:g}: " + (f"aero.method {case.aero.method!r} "
                     "refuses it, not analysed" if refused else "linear theory not trusted"))
    if refused:
        if not gap:
            notes.append(f"aero.method {case.aero.method!r} refuses M {p.mach:g} (outside its "
                         "Mach range): not analysed")
    else:
        pts = flutter_points([r for r in fa.results if r.condition == cond],
                              case.flight.velocities)
        m = flutter_margin(cond, pts, p.mach)
        uf = m["flutter_speed_ms"]
        margin = None if m["margin"] is None else 100.0 * m["margin"]
        side = [x for x, _, _ in pts if not across_sonic(x, p.mach)]
        extrap = bool(side) and uf is not None and not min(side) <= p.mach <= max(side)
        if extrap:
            notes.append(f"U_f extrapolated from the analysed Machs {min(side):g}-"
                         f"{max(side):g}")
        if m["note"]:
            notes.append(m["note"])
    div = None
    if not refused:
        div, why = _divergence_margin(fa, cond, p.mach, u)
        if why:
            notes.append(why)
    hinge = None
    if p.alpha_deg is not None or p.deflection_deg is not None:
        q_cc, why = _q_cc(case, db, modal, p.mach)
        if q_cc is not None and not refused:
            theta = math.radians((p.alpha_deg or 0.0) + (p.deflection_deg or 0.0))
            hinge = q * q_cc * theta
        elif why:
            notes.append(f"no hinge moment: {why}")
    v_tn = None
    if tn is not None:
        atm = standard_atmosphere(p.altitude_m)
        v_tn = tn4197_flutter_speed(**tn, pressure=float(atm.pressure),
                                    speed_of_sound=cond.speed_of_sound)
    return TrajectoryRow(p.time_s, p.mach, p.altitude_m, q, uf, margin, div, hinge, v_tn, gap,
                         extrap, "; ".join(notes) or None)


def trajectory(case: Case, points, progress: bool = False) -> tuple[TrajectoryRow, ...]:
    """The case's margins, dynamic pressure and hinge moment at every point of a trajectory.

    The case is analysed by :func:`asekit.case.pipeline.flutter` with ``flight.altitudes`` the
    profile's altitudes (its velocity sweep, GAF database at ``aero.machs``, flutter method
    unchanged); at each point the flutter speed at the point's Mach is the pipeline's
    (:func:`asekit.case.envelope.flutter_margin`), the divergence speed is interpolated in Mach
    between the analysed Machs alike, and the margins are U / (M a) - 1 with a the speed of
    sound at the point's altitude. The steady hinge moment is q Re Q_cc(M, k_min) (alpha +
    delta) (thesis Eq. 4.6) for a case with a rigid pitch mode: an all-movable fin's incidence
    is the body's angle of attack plus its deflection.

    Parameters
    ----------
    case : Case
        The case; it needs ``[aero]`` and ``[flight]`` (its ``velocities``).
    points : sequence of ProfilePoint
        The trajectory (:func:`read_profile`).
    progress : bool, optional
        Progress bars of the pipeline.

    Returns
    -------
    tuple of TrajectoryRow
        One per point, in the profile's order.

    Examples
    --------
    The AGARD 445.6 wing at M 0.499 and 6 km (its analysed Mach; a clamped wing: no hinge
    moment; the p-k flutter speed beside TN 4197's, which for this clamped plate-like wing
    agree within 1 %):

    >>> from asekit.case import load_case
    >>> from asekit.util.paths import CASES_DIR
    >>> (r,) = trajectory(load_case(CASES_DIR / "agard445_6.toml"),
    ...                   [ProfilePoint(0.0, 0.499, 6000.0)])
    >>> r.transonic_gap, r.hinge_moment_Nm, round(r.dynamic_pressure_Pa)
    (False, None, 8230)
    >>> round(r.flutter_speed_ms), round(r.flutter_margin_pct, 1), round(r.tn4197_flutter_speed_ms)
    (149, -5.5, 148)
    """
    from asekit.case import pipeline as P
    points = tuple(points)
    if not points:
        raise ValueError("points: the trajectory has no point")
    alts = sorted({p.altitude_m for p in points})
    tc = _trajectory_case(case, alts)
    modal = P.modal_model(tc)
    db = P.gaf_database(tc, progress=progress)
    fa = P.flutter(tc, progress=progress, db=db)
    conds = {c.altitude: c for c in P.flight_conditions(tc)}
    tn = tn4197_inputs(case)
    rows = tuple(_row(tc, fa, db, modal, p, conds[p.altitude_m], tn) for p in points)
    rows = _with_power(case, points, rows)
    _log.info("trajectory of %s: %d points at %d altitudes", case.name, len(points), len(alts))
    return rows


def deflection_rates(points) -> np.ndarray:
    """The commanded deflection's rate (deg/s) at each point: ``numpy.gradient`` of the
    deflection (deg; a point without one counts 0, as the hinge moment does) against time
    (second-order differences inside, one-sided at the ends; exact for a linear ramp); zero
    for a single point.

    Examples
    --------
    >>> pts = [ProfilePoint(t, 0.5, 0.0, 0.0, d) for t, d in ((0, 0), (1, 2), (2, 4))]
    >>> deflection_rates(pts)
    array([2., 2., 2.])
    """
    t = np.array([p.time_s for p in points], float)
    d = np.array([p.deflection_deg or 0.0 for p in points], float)
    return np.gradient(d, t) if t.size > 1 else np.zeros(t.size)


def _with_power(case: Case, points, rows) -> tuple:
    """The rows with the actuator's quasi-steady power demand (:class:`TrajectoryRow`)."""
    if case.actuator is None:
        return rows
    from asekit.case.pipeline import actuator_setup
    from asekit.servo.simulate import quasi_steady_demand
    act, _, _ = actuator_setup(case)
    out = []
    for r, rate in zip(rows, deflection_rates(points)):
        if r.hinge_moment_Nm is None:
            out.append(r)
            continue
        d = quasi_steady_demand(act, r.hinge_moment_Nm, math.radians(rate))
        out.append(dataclasses.replace(
            r, deflection_rate_deg_s=float(rate), motor_current_A=float(d["current"]),
            motor_voltage_V=float(d["voltage"]), actuator_power_W=float(d["power"])))
    return tuple(out)


def min_margin(rows, key: str = "flutter_margin_pct"):
    """The smallest value of ``key`` over the rows and its row (None, None if none known)."""
    vals = [(getattr(r, key), r) for r in rows if getattr(r, key) is not None]
    return min(vals, key=lambda t: t[0]) if vals else (None, None)


def gap_spans(rows) -> list[tuple[float, float]]:
    """The time intervals (s) in which the Mach number, linear in time between the rows, lies
    in the transonic gap DLM_MACH_MAX < M < SUPERSONIC_MACH_MIN.

    Examples
    --------
    >>> rows = [TrajectoryRow(t, m, 0.0, 0.0, None, None, None, None, None, False)
    ...         for t, m in ((0.0, 0.8), (1.0, 1.0), (2.0, 1.3))]
    >>> [(round(a, 3), round(b, 3)) for a, b in gap_spans(rows)]
    [(0.5, 1.0), (1.0, 1.5)]
    """
    out = []
    for r0, r1 in zip(rows[:-1], rows[1:]):
        m0, m1 = r0.mach, r1.mach
        if m0 == m1:
            lo, hi = (0.0, 1.0) if in_transonic_gap(m0) else (1.0, 0.0)
        else:
            a, b = ((DLM_MACH_MAX - m0) / (m1 - m0), (SUPERSONIC_MACH_MIN - m0) / (m1 - m0))
            lo, hi = max(0.0, min(a, b)), min(1.0, max(a, b))
        if hi > lo:
            dt = r1.time_s - r0.time_s
            out.append((r0.time_s + lo * dt, r0.time_s + hi * dt))
    return out


def plot_trajectory(rows, title: str = "Margins along the trajectory"):
    """Flutter and divergence margins (%) and the TN 4197 margin against time, the transonic
    gap shaded, the dynamic pressure (kPa) below, and with an actuator power demand
    (``actuator_power_W``) a third panel of it (W), in the project's style
    (:func:`asekit.util.plotting.new_figure`); returns (fig, axes)."""
    from asekit.util.plotting import ASEKIT_COLOR, THESIS_COLOR, new_figure
    power = any(r.actuator_power_W is not None for r in rows)
    fig, axes = new_figure(title, nrows=3 if power else 2, figsize=(7.0, 8.4 if power else 6.0),
                           sharex=True)
    ax, axq = axes[0], axes[1]
    t = np.array([r.time_s for r in rows])

    def series(vals):
        return np.array([np.nan if v is None else v for v in vals], float)

    speed = np.array([r.dynamic_pressure_Pa for r in rows])
    flight = np.array([r.mach * float(standard_atmosphere(r.altitude_m).speed_of_sound)
                       for r in rows])
    tn = series([r.tn4197_flutter_speed_ms for r in rows])
    ax.plot(t, series([r.flutter_margin_pct for r in rows]), "o-", color=ASEKIT_COLOR,
            label="flutter margin (asekit)")
    ax.plot(t, series([r.divergence_margin_pct for r in rows]), "s--", color="C1",
            label="divergence margin (asekit)")
    ax.plot(t, 100 * (tn / flight - 1), "^:", color=THESIS_COLOR,
            label="flutter margin (NACA TN 4197)")
    ax.axhline(0.0, color="k", lw=0.8)
    spans = gap_spans(rows)
    for t0, t1 in spans:
        for a in axes:
            a.axvspan(t0, t1, color="0.85", lw=0)
    if spans:
        ax.axvspan(np.nan, np.nan, color="0.85", label=f"transonic gap {DLM_MACH_MAX:g} < M < "
                                                       f"{SUPERSONIC_MACH_MIN:g}")
    ax.set_ylabel("margin (%)")
    ax.legend(loc="best")
    axq.plot(t, speed / 1e3, "-", color=ASEKIT_COLOR)
    axq.set_ylabel("dynamic pressure (kPa)")
    if power:
        axp = axes[2]
        axp.plot(t, series([r.actuator_power_W for r in rows]), "o-", color=ASEKIT_COLOR)
        axp.axhline(0.0, color="k", lw=0.8)
        axp.set_ylabel("actuator power V I (W)")
    axes[-1].set_xlabel("time (s)")
    return fig, tuple(axes)


#: The units of a row's JSON keys.
UNITS = {"time_s": "s", "mach": "-", "altitude_m": "m", "dynamic_pressure_Pa": "Pa",
         "flutter_speed_ms": "m/s", "flutter_margin_pct": "%", "divergence_margin_pct": "%",
         "hinge_moment_Nm": "N m", "tn4197_flutter_speed_ms": "m/s",
         "deflection_rate_deg_s": "deg/s", "motor_current_A": "A", "motor_voltage_V": "V",
         "actuator_power_W": "W (V I, quasi-steady; > 0 drawn from the supply)"}


def trajectory_json(case: Case, rows, profile: str = "") -> dict:
    """The JSON document of ``asekit trajectory``: ``trajectory`` (one dict per row,
    :meth:`TrajectoryRow.to_json`), ``units``, the case's name, the profile path, the smallest
    margins and TN 4197's inputs and form."""
    f_min, f_row = min_margin(rows)
    d_min, d_row = min_margin(rows, "divergence_margin_pct")
    return {"case": case.name, "profile": str(profile),
            "analysed_machs": [float(m) for m in case.aero.machs],
            "extrapolated_times_s": [r.time_s for r in rows if r.mach_extrapolated],
            "trajectory": [r.to_json() for r in rows], "units": UNITS,
            "min_flutter_margin_pct": f_min,
            "min_flutter_margin_time_s": None if f_row is None else f_row.time_s,
            "min_divergence_margin_pct": d_min,
            "min_divergence_margin_time_s": None if d_row is None else d_row.time_s,
            "tn4197": {"inputs": tn4197_inputs(case),
                       "comparison": tn4197_comparison(case, rows),
                       "form": "NACA TN 4197 (Martin 1958) with D_N = 24 eps gamma p0 / pi, "
                               "eps = 0.25: V_f = a sqrt(G (t/c)^3 (A + 2) / (1.337 A^3 "
                               "(lambda + 1) p)); clamped root assumed"}}


def tn4197_comparison(case: Case, rows, tolerance: float = 0.2) -> str | None:
    """One sentence comparing TN 4197's flutter speed with asekit's over the rows where both
    are known: their ratio's range and the times where they differ by more than
    ``tolerance`` (a fraction), with the likely reason (TN 4197 assumes a clamped plate: a
    pitch-shaft support or a heavy point mass is outside its data). None without such rows.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> row = TrajectoryRow(1.0, 0.6, 0.0, 24800.0, 215.6, 5.9, 185.5, 0.88, 642.4, False)
    >>> tn4197_comparison(load_case(FIN_FILE), [row])[:54]
    'TN 4197 / asekit flutter speed 2.98 (2.98-2.98): they '
    """
    both = [(r.tn4197_flutter_speed_ms / r.flutter_speed_ms, r) for r in rows
            if r.tn4197_flutter_speed_ms is not None and r.flutter_speed_ms is not None]
    if not both:
        return None
    ratios = [x for x, _ in both]
    off = [r.time_s for x, r in both if abs(x - 1.0) > tolerance]
    text = (f"TN 4197 / asekit flutter speed {float(np.median(ratios)):.2f} "
            f"({min(ratios):.2f}-{max(ratios):.2f}): ")
    if not off:
        return text + f"they agree within {100 * tolerance:g} % at every point"
    why = ("TN 4197 is an empirical boundary for clamped-root plates; this case's "
           f"{case.support.kind} support" + (" (its pitch spring's rigid-pitch flutter)"
                                             if case.support.kind == "shaft" else "")
           + " is outside its data")
    return (text + f"they disagree by more than {100 * tolerance:g} % at t = "
            + ", ".join(f"{t:g}" for t in off) + f" s; {why}")


def _fmt(v, spec: str) -> str:
    width = int(spec.lstrip("+").split(".")[0])
    return "-".rjust(width) if v is None else format(v, spec)


def format_trajectory(case: Case, rows) -> str:
    """The table of ``asekit trajectory``: one line per point (time s, Mach, altitude m, q kPa,
    U_f m/s, flutter and divergence margins %, hinge moment N m, TN 4197 U_f m/s, actuator
    power W, flags: G
    transonic gap, X extrapolated in Mach), then the smallest margins, then the notes.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> row = TrajectoryRow(1.0, 0.6, 0.0, 24800.0, 215.6, 5.9, 185.5, 0.88, 642.4, False)
    >>> print(format_trajectory(load_case(FIN_FILE), [row]).splitlines()[2])
         1.00  0.600      0    24.80    215.6     +5.9   +185.5    0.880    642.4        -
    """
    head = (f"trajectory of {case.name}: flutter and divergence margins U / (M a) - 1, "
            "NACA TN 4197 beside asekit\n"
            f"{'time s':>9} {'Mach':>6} {'alt m':>6} {'q kPa':>8} {'U_f m/s':>8} "
            f"{'flut %':>8} {'div %':>8} {'M_h N m':>8} {'TN4197':>8} {'P W':>8} flags")
    lines = [head]
    for r in rows:
        flags = ("G" if r.transonic_gap else "") + ("X" if r.mach_extrapolated else "")
        lines.append(f"{r.time_s:9.2f} {r.mach:6.3f} {r.altitude_m:6.0f} "
                     f"{r.dynamic_pressure_Pa / 1e3:8.2f} {_fmt(r.flutter_speed_ms, '8.1f')} "
                     f"{_fmt(r.flutter_margin_pct, '+8.1f')} "
                     f"{_fmt(r.divergence_margin_pct, '+8.1f')} "
                     f"{_fmt(r.hinge_moment_Nm, '8.3f')} "
                     f"{_fmt(r.tn4197_flutter_speed_ms, '8.1f')} "
                     f"{_fmt(r.actuator_power_W, '8.3f')} {flags}".rstrip())
    f_min, f_row = min_margin(rows)
    if f_min is not None:
        lines.append(f"smallest flutter margin {f_min:+.1f} % at t = {f_row.time_s:g} s "
                     f"(M {f_row.mach:g}, {f_row.altitude_m:g} m)"
                     + (": flutter on the trajectory" if f_min < 0 else ""))
    cmp = tn4197_comparison(case, rows)
    if cmp:
        lines.append(cmp)
    lines.append("analysed Machs " + ", ".join(f"{m:g}" for m in case.aero.machs)
                 + f" (aero.method {case.aero.method!r}); flutter speeds interpolated between "
                 "them, extrapolated at most 0.05 beyond (flag X)")
    lines.append("flags: G transonic gap 0.9 < M < 1.15, X flutter speed extrapolated in Mach")
    lines += [f"t = {r.time_s:g} s: {r.note}" for r in rows if r.note]
    return "\n".join(lines)
