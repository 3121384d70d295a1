"""The flutter envelope of a case from its per-condition results: the flutter speed at each
analysed Mach as a value or a bound, the match point U_f(M) = M a, the flutter margin at the
envelope's top Mach, and the rule that nothing is interpolated across M 1.

Used by :func:`asekit.case.pipeline.flutter` and by the applications that re-read its results
(the report, the trajectory, the sweeps).
"""

from __future__ import annotations

import numpy as np

from asekit.util.conventions import mode_label

# The per-condition results and flight conditions are asekit.case.pipeline's ConditionResult and
# FlightCondition (read by attribute here: this module is imported by the pipeline).


def start_kind(r) -> str:
    """'flutter', 'divergence' or 'flutter or divergence': what is unstable at the first point
    of the sweep of ``r``."""
    kinds = sorted({i.kind for i in r.instabilities if i.at_first_point})
    return " or ".join(kinds) if kinds else "flutter or divergence"


def start_note(r, velocities) -> str:
    """The note of a condition unstable at the first point of the sweep."""
    return (f"M {r.mach:g}, rho {r.condition.density:.4g} kg/m^3: {start_kind(r)} at or "
            f"below {velocities[0]:g} m/s (the first point of the sweep, "
            f"{mode_label(r.start_mode, r.pk.n_rigid)}): start the sweep lower "
            f"(flight.velocities.min) to locate it")


def flutter_points(here: list, velocities) -> list[tuple[float, float, str]]:
    """(Mach, speed m/s, bound) of the flutter speed at each analysed Mach of one condition:
    bound "value" (a crossing), "upper" (flutter at or below the first point of the sweep:
    U_f <= speed) or "lower" (no flutter in the sweep: U_f > speed, its last point). A Mach
    whose sweep starts with divergence only gives no point (its flutter speed is unknown)."""
    pts = []
    for r in sorted(here, key=lambda r: r.mach):
        if r.unstable_at_start:
            if "flutter" in start_kind(r):
                pts.append((r.mach, float(velocities[0]), "upper"))
        elif r.flutter is not None:
            pts.append((r.mach, float(r.flutter.speed), "value"))
        else:
            pts.append((r.mach, float(velocities[-1]), "lower"))
    return pts


def _machs(pts) -> str:
    return ", ".join(f"{m:g}" for m, _, _ in pts)


def match_point(c, pts) -> dict:
    """The match point at one altitude: the Mach where U_f(M) = M a, interpolated between
    consecutive Machs with flutter crossings; otherwise None with the reason, which states
    what the bounds say (flutter at or below the first point of the sweep, no flutter up to
    its last point) against the flight speed M a."""
    a = c.speed_of_sound
    d = [(m, u / a - m) for m, u, kind in pts if kind == "value"]
    mm, across = None, None
    for (m0, d0), (m1, d1) in zip(d[:-1], d[1:]):
        if d0 == 0 or d0 * d1 < 0:
            if across_sonic(m0, m1):       # never interpolated through the transonic range
                across = across or (m0, m1)
                continue
            mm = m0 + (m1 - m0) * d0 / (d0 - d1)
            break
    upper = [p for p in pts if p[2] == "upper"]
    why = None
    if mm is None:
        parts = []
        inside = [p for p in upper if p[1] < p[0] * a]
        unknown = [p for p in upper if p[1] >= p[0] * a]
        if inside:
            parts.append(f"flutter at or below {inside[0][1]:g} m/s (the first point of the "
                         f"sweep) at M {_machs(inside)}, below the flight speed M a: inside "
                         "the envelope")
        if unknown:
            parts.append(f"flutter at or below {unknown[0][1]:g} m/s (the first point of the "
                         f"sweep) at M {_machs(unknown)}, the flight speed M a below it: not "
                         "located, start the sweep lower (flight.velocities.min)")
        if d and all(v > 0 for _, v in d):
            parts.append(f"U_f > M a at every analysed Mach with a crossing: no match up to "
                         f"M {d[-1][0]:g} (flutter-free there)")
        elif d and all(v < 0 for _, v in d):
            parts.append(f"U_f < M a at every analysed Mach with a crossing: the match lies "
                         f"below M {d[0][0]:g}")
        if across:
            parts.append(f"U_f - M a changes sign between M {across[0]:g} and M "
                         f"{across[1]:g}, across M 1: the match lies in the transonic range, "
                         "which is not interpolated (analyse Machs nearer M 1 on each side)")
        if not parts:
            parts.append("no flutter in the sweep at any analysed Mach")
        why = "; ".join(parts)
        if not upper and len(d) == len(pts) and d:      # every Mach a crossing: as before
            why = why.replace(" with a crossing", "")
    return {"altitude_m": c.altitude, "matched_mach": mm,
            "matched_speed_ms": None if mm is None else mm * a,
            "match_across_sonic": None if across is None or mm is not None else list(across),
            "flutter_at_or_below_ms": upper[0][1] if upper else None,
            "no_match": why}


def interpolate_bounded(pts, mach: float, reach: float = 0.05):
    """U_f at ``mach`` from (Mach, speed, bound) points (:func:`interpolate_speed` on all of
    them) and its bound: "value" when every point it uses is a value, "upper" / "lower" when
    the used points are values and upper (lower) bounds, interpolated (not extrapolated);
    (None, None) otherwise.

    Examples
    --------
    >>> interpolate_bounded([(0.4, 300.0, "value"), (0.6, 280.0, "lower")], 0.5)
    (290.0, 'lower')
    """
    pts = sorted(p for p in pts if not across_sonic(p[0], mach))
    u = interpolate_speed([(m, s) for m, s, _ in pts], mach, reach)
    if u is None:
        return None, None
    ms = [m for m, _, _ in pts]
    if len(pts) == 1:
        return u, pts[0][2]
    i = int(np.clip(np.searchsorted(ms, mach) - 1, 0, len(ms) - 2))
    t = (mach - ms[i]) / (ms[i + 1] - ms[i])
    used = {kind for kind, w in ((pts[i][2], 1 - t), (pts[i + 1][2], t)) if w != 0}
    bounds = used - {"value"}
    if not bounds:
        return u, "value"
    if len(bounds) > 1 or not 0 <= t <= 1:
        return None, None
    return u, bounds.pop()


def flutter_margin(c, pts, env_mach: float) -> dict:
    """The flutter margin U_f / U_env - 1 at the envelope's top Mach, or its bound: at most
    (U_f at or below the first point of the sweep) or at least (no flutter up to its last
    point), with a note saying which.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sea = SimpleNamespace(altitude=0.0, density=1.225, speed_of_sound=340.3)
    >>> m = flutter_margin(sea, [(0.4, 250.0, "value"), (0.6, 230.0, "value")], 0.6)
    >>> round(m["margin"], 4), m["note"]
    (0.1265, None)
    """
    u_env = env_mach * c.speed_of_sound
    uf, kind = interpolate_bounded(pts, env_mach)
    out = {"altitude_m": c.altitude, "envelope_mach": env_mach, "envelope_speed_ms": u_env,
           "flutter_speed_ms": uf if kind == "value" else None,
           "margin": uf / u_env - 1.0 if kind == "value" else None,
           "margin_upper_bound": uf / u_env - 1.0 if kind == "upper" else None,
           "margin_lower_bound": uf / u_env - 1.0 if kind == "lower" else None,
           "flutter_speed_upper_bound_ms": uf if kind == "upper" else None,
           "flutter_speed_lower_bound_ms": uf if kind == "lower" else None, "note": None}
    if kind == "upper":
        out["note"] = (f"flutter at or below {uf:.4g} m/s (the first point of the sweep)"
                       + (": inside the envelope" if uf < u_env else
                          ": the margin is at most this; start the sweep lower "
                          "(flight.velocities.min)"))
    elif kind == "lower":
        out["note"] = f"no flutter up to {uf:.4g} m/s (the last point of the sweep)"
    elif kind is None:
        out["note"] = (f"U_f not known at M {env_mach:g}: no analysed Mach within 0.05 on "
                       "the same side of M 1, or bounds of both kinds around it")
    return out


def across_sonic(m0: float, m1: float) -> bool:
    """Whether M 1 lies between (or at) two Mach numbers that are not both on one side of it.

    Flutter speeds are never interpolated or extrapolated through the transonic range: linear
    theory changes character at M 1 (subsonic DLM below, supersonic theory above, the gap
    :data:`asekit.aero.methods.DLM_MACH_MAX` < M < :data:`asekit.aero.methods.SUPERSONIC_MACH_MIN`
    unanalysed by ``aero.method = "auto"``) and the transonic dip lies there.

    Examples
    --------
    >>> across_sonic(0.9, 1.5), across_sonic(0.6, 0.9), across_sonic(1.2, 2.0)
    (True, False, False)
    """
    return (m0 - 1.0) * (m1 - 1.0) <= 0.0


def interpolate_speed(points: list[tuple[float, float]], mach: float,
                  reach: float = 0.05) -> float | None:
    """U_f at ``mach`` from (Mach, U_f) points on its side of M 1 (:func:`across_sonic`):
    linear between them, linear extrapolation of the end segment at most ``reach`` in Mach
    beyond them; None farther out.

    Examples
    --------
    >>> interpolate_speed([(0.4, 300.0), (0.6, 280.0)], 0.5)
    290.0
    >>> interpolate_speed([(0.4, 300.0), (0.6, 280.0)], 0.7) is None      # beyond the reach
    True
    """
    pts = sorted(p for p in points if not across_sonic(p[0], mach))
    if not pts or not pts[0][0] - reach <= mach <= pts[-1][0] + reach:
        return None
    ms, us = np.array(pts).T
    if ms.size == 1:
        return float(us[0])
    i = int(np.clip(np.searchsorted(ms, mach) - 1, 0, ms.size - 2))   # segment [i, i+1]
    return float(us[i] + (us[i + 1] - us[i]) * (mach - ms[i]) / (ms[i + 1] - ms[i]))
