"""The 1976 U.S. Standard Atmosphere (troposphere to 86 km geopotential layers used up to 32 km).

Implements the hydrostatic layer model of the U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562,
Eqs. 23, 33a, 33b and Table 4): temperature linear in geopotential altitude within each layer,
pressure from the barometric equation, density from the ideal gas law and the speed of sound
a = sqrt(gamma R T). Geometric altitude z is converted to geopotential H = r0 z / (r0 + z).

Also the equivalent airspeed of thesis Eq. (3.10), ``U_eq = U sqrt(rho / rho_0)``, and the
Mach - airspeed - altitude relation of thesis Fig 25.

All inputs and outputs SI (m, K, Pa, kg/m^3, m/s); every function is vectorised over altitude.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asekit.util.validate import real_array

#: Constants of the 1976 standard (Table 2 of NOAA-S/T 76-1562).
G0 = 9.80665            # m/s^2
R_AIR = 287.05287       # J/(kg K), R* / M0 = 8314.32 / 28.9644
GAMMA = 1.4
R_EARTH = 6356766.0     # m, effective Earth radius for geopotential altitude
T0 = 288.15             # K
P0 = 101325.0           # Pa
RHO0 = P0 / (R_AIR * T0)  # 1.2250 kg/m^3

#: Layer bases (geopotential m) and temperature lapse rates (K/m), Table 4 up to 47 km.
_H_BASE = np.array([0.0, 11000.0, 20000.0, 32000.0, 47000.0])
_LAPSE = np.array([-0.0065, 0.0, 0.0010, 0.0028, 0.0])
#: The geometric altitudes (m) this model covers: the 1976 standard's tables start at -5 km and
#: the layers implemented end at 47 km. The one source of the altitude range: the case file
#: (``flight.altitudes``, ``flight.envelope.altitude``, ``actuator.condition.altitude``) and
#: the sweep file (``flight.altitude``) refuse altitudes outside it.
MIN_ALTITUDE = -5000.0
MAX_ALTITUDE = 47000.0


def _layer_bases():
    t = [T0]
    p = [P0]
    for i in range(len(_H_BASE) - 1):
        dh = _H_BASE[i + 1] - _H_BASE[i]
        tb, pb, lr = t[-1], p[-1], _LAPSE[i]
        tt = tb + lr * dh
        if lr == 0.0:
            pt = pb * np.exp(-G0 * dh / (R_AIR * tb))
        else:
            pt = pb * (tt / tb) ** (-G0 / (R_AIR * lr))
        t.append(tt)
        p.append(pt)
    return np.array(t), np.array(p)


_T_BASE, _P_BASE = _layer_bases()


@dataclass(frozen=True)
class AtmosphereState:
    """Standard-atmosphere properties at one or more altitudes (arrays of the input's shape).

    altitude (m, geometric), temperature (K), pressure (Pa), density (kg/m^3),
    speed_of_sound (m/s).
    """

    altitude: np.ndarray
    temperature: np.ndarray
    pressure: np.ndarray
    density: np.ndarray
    speed_of_sound: np.ndarray


def _altitude(h) -> np.ndarray:
    h = real_array("altitude", h)
    if not np.all(np.isfinite(h)) or np.any(h < MIN_ALTITUDE) or np.any(h > MAX_ALTITUDE):
        raise ValueError(f"altitude must be finite and within [{MIN_ALTITUDE:.0f}, "
                         f"{MAX_ALTITUDE:.0f}] m, "
                         f"got {h}")
    return h


def standard_atmosphere(altitude) -> AtmosphereState:
    """1976 U.S. Standard Atmosphere at geometric ``altitude`` (m, scalar or array, -5 to 47 km).

    Returns an :class:`AtmosphereState` with arrays of ``altitude``'s shape.
    Raises ValueError for altitudes outside the implemented layers.
    """
    z = _altitude(altitude)
    hgp = R_EARTH * z / (R_EARTH + z)       # geopotential altitude
    i = np.clip(np.searchsorted(_H_BASE, hgp, side="right") - 1, 0, len(_H_BASE) - 1)
    tb, pb, lr, hb = _T_BASE[i], _P_BASE[i], _LAPSE[i], _H_BASE[i]
    t = tb + lr * (hgp - hb)
    iso = lr == 0.0
    safe_lr = np.where(iso, 1.0, lr)
    p = np.where(iso, pb * np.exp(-G0 * (hgp - hb) / (R_AIR * tb)),
                 pb * (t / tb) ** (-G0 / (R_AIR * safe_lr)))
    rho = p / (R_AIR * t)
    a = np.sqrt(GAMMA * R_AIR * t)
    return AtmosphereState(altitude=z, temperature=t, pressure=p, density=rho, speed_of_sound=a)


def density(altitude) -> np.ndarray:
    """Air density (kg/m^3) at geometric ``altitude`` (m)."""
    return standard_atmosphere(altitude).density


def speed_of_sound(altitude) -> np.ndarray:
    """Speed of sound (m/s) at geometric ``altitude`` (m)."""
    return standard_atmosphere(altitude).speed_of_sound


def equivalent_airspeed(true_airspeed, altitude) -> np.ndarray:
    """Equivalent airspeed U_eq = U sqrt(rho(h)/rho_0) (m/s), thesis Eq. (3.10)."""
    u = real_array("true_airspeed", true_airspeed)
    if np.any(u < 0) or not np.all(np.isfinite(u)):
        raise ValueError(f"true_airspeed must be finite and >= 0 m/s, got {u}")
    return u * np.sqrt(density(altitude) / RHO0)


def true_airspeed(mach, altitude) -> np.ndarray:
    """True airspeed (m/s) of Mach number ``mach`` at ``altitude`` (m): U = M a(h) (Fig 25)."""
    m = real_array("mach", mach)
    if np.any(m < 0) or not np.all(np.isfinite(m)):
        raise ValueError(f"mach must be finite and >= 0, got {m}")
    with np.errstate(over="ignore"):
        u = m * speed_of_sound(altitude)
    if not np.all(np.isfinite(u)):
        raise ValueError(f"mach = {m} is too large: the airspeed overflows")
    return u


def mach_number(true_airspeed_ms, altitude) -> np.ndarray:
    """Mach number of ``true_airspeed_ms`` (m/s) at ``altitude`` (m)."""
    u = real_array("true_airspeed_ms", true_airspeed_ms)
    if np.any(u < 0) or not np.all(np.isfinite(u)):
        raise ValueError(f"true_airspeed_ms must be finite and >= 0 m/s, got {u}")
    return u / speed_of_sound(altitude)


def dynamic_pressure(true_airspeed_ms, altitude) -> np.ndarray:
    """Dynamic pressure q = rho U^2 / 2 (Pa)."""
    u = real_array("true_airspeed_ms", true_airspeed_ms)
    if np.any(u < 0) or not np.all(np.isfinite(u)):
        raise ValueError(f"true_airspeed_ms must be finite and >= 0 m/s, got {u}")
    with np.errstate(over="ignore"):
        q = 0.5 * density(altitude) * u ** 2
    if not np.all(np.isfinite(q)):
        raise ValueError(f"true_airspeed_ms = {u} is too large: q overflows")
    return q
