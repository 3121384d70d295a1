"""Torque requirement of the fin actuator (thesis Sec. 4.1.1, Eqs. 4.1-4.12, Figs 40-43).

The stall torque at the fin must exceed the worst-case sum of the fin's inertial torque and the
steady aerodynamic hinge moment (Eqs. 4.1, 4.7, 4.10)::

    T_stall@fin >= J_fin |theta''_max| + |q Q_cc theta_max|

The maximum acceleration ``theta''_max`` comes from an assumed command-following profile: a
second-order system (Eq. 4.8) with natural frequency 157 rad/s, made nonlinear by position and
rate/acceleration limits, tuned to settle a 15 deg step within 50 ms without overshoot.

Reconstruction (the thesis text lost Eq. 4.9 and Figs 40-41) -- what asekit assumes
------------------------------------------------------------------------------------
The thesis says the profile is a second-order system "involving a dynamic acceleration limit
which also limits the angular velocity" plus a position limit. asekit writes Eq. (4.8) in the
velocity-loop form and saturates the velocity demand (this is :func:`profile_rhs`)::

    omega_dem = sat( omega_n / (2 zeta) * (r - y),  +-rate_limit )
    y''       = 2 zeta omega_n (omega_dem - y')
    r         = sat(command, +-position_limit)

Without the limit this is exactly y'' = omega_n^2 (r - y) - 2 zeta omega_n y' (Eq. 4.8). With it,
the acceleration is limited dynamically to 2 zeta omega_n (rate_limit - |y'|), which also caps
the rate at ``rate_limit``: the "dynamic acceleration limit" of the thesis. Assumptions:

1. ``zeta = 1`` (critical damping: the fastest linear response without overshoot);
2. ``omega_n = 157 rad/s`` (thesis text);
3. the position limit is 15 deg (thesis Table 2), applied to the command;
4. "settles in 50 ms" means the response stays inside a band of 2 % of the step (the thesis's
   steady-state error requirement, Table 2) from 50 ms on;
5. the rate limit is *tuned*: the smallest one that meets assumption 4 ("a reasonable maximum
   acceleration", thesis Sec. 4.1.1), found by :func:`tune_rate_limit`.

The peak acceleration of this profile is 2 zeta omega_n rate_limit, reached at t = 0.

Inputs and outputs are SI (rad, rad/s, rad/s^2, N m, Pa).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from asekit.servo.actuator import THESIS_FIN_INERTIA
from asekit.util.validate import in_range

#: Sea-level standard atmosphere (ISA / US 1976): density (kg/m^3), speed of sound (m/s).
SEA_LEVEL_DENSITY = 1.225
SEA_LEVEL_SPEED_OF_SOUND = 340.294
#: The thesis's steady hinge-moment coefficient Q_cc^real(M 0.6, k 0.001) (m^3 per rad).
THESIS_Q_CC = 5.825e-4


def dynamic_pressure(mach: float, density: float = SEA_LEVEL_DENSITY,
                     speed_of_sound: float = SEA_LEVEL_SPEED_OF_SOUND) -> float:
    """q = 0.5 rho (M a)^2 (Pa) for a Mach number (>= 0), density (kg/m^3, > 0) and speed of
    sound (m/s, > 0)."""
    mach = in_range("mach", mach, inclusive=True)
    density = in_range("density", density)
    speed_of_sound = in_range("speed_of_sound", speed_of_sound)
    return 0.5 * density * (mach * speed_of_sound) ** 2


@dataclass(frozen=True)
class SecondOrderProfile:
    """The rate/acceleration-limited second-order command profile (reconstructed Eq. 4.9).

    Parameters
    ----------
    natural_frequency : omega_n (rad/s), > 0 (thesis: 157).
    damping_ratio : zeta, > 0 (asekit assumes 1: fastest without overshoot).
    rate_limit : maximum |y'| (rad/s), > 0; inf for the linear Eq. (4.8).
    position_limit : maximum |y| (rad), > 0 (thesis Table 2: 15 deg).
    """

    natural_frequency: float = 157.0
    damping_ratio: float = 1.0
    rate_limit: float = math.inf
    position_limit: float = math.radians(15.0)

    def __post_init__(self):
        in_range("natural_frequency", self.natural_frequency)
        in_range("damping_ratio", self.damping_ratio)
        if not (float(self.rate_limit) > 0.0):
            raise ValueError(f"rate_limit must be > 0 (inf allowed), got {self.rate_limit!r}")
        in_range("position_limit", self.position_limit)

    @property
    def peak_acceleration_bound(self) -> float:
        """2 zeta omega_n rate_limit (rad/s^2): the largest acceleration the limit allows."""
        return 2.0 * self.damping_ratio * self.natural_frequency * self.rate_limit


def profile_rhs(profile: SecondOrderProfile, command: float, state) -> np.ndarray:
    """Right-hand side [y', y''] of the limited second-order profile (module docstring)."""
    y, v = state
    wn, z = profile.natural_frequency, profile.damping_ratio
    r = min(max(command, -profile.position_limit), profile.position_limit)
    v_dem = min(max(wn / (2.0 * z) * (r - y), -profile.rate_limit), profile.rate_limit)
    return np.array([v, 2.0 * z * wn * (v_dem - v)])


@dataclass(frozen=True)
class ProfileResponse:
    """Step response of the profile: t (s), theta (rad), omega (rad/s), alpha (rad/s^2) and
    ``settling_time`` (s; inf if it never settles within t_final)."""

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    settling_time: float

    @property
    def peak_acceleration(self) -> float:
        """max |alpha| (rad/s^2)."""
        return float(np.max(np.abs(self.alpha)))

    @property
    def overshoot(self) -> float:
        """max(theta) - final command as a fraction of the command (0 if none)."""
        return float(max(0.0, (np.max(self.theta) - self.theta[-1]) / abs(self.theta[-1])))


def profile_step(profile: SecondOrderProfile, step: float = math.radians(15.0),
                 t_final: float = 0.1, band: float = 0.02, n: int = 4001) -> ProfileResponse:
    """Response of the profile to a step ``step`` (rad) from rest at 0 (Figs 40-43).

    Parameters
    ----------
    step : commanded angle (rad), non-zero.
    t_final : simulated time (s), > 0.
    band : settling band as a fraction of the step, in (0, 1).
    n : number of output samples.
    """
    step = float(step)
    if not math.isfinite(step) or step == 0.0:
        raise ValueError(f"step must be a finite non-zero angle, got {step!r}")
    in_range("t_final", t_final)
    in_range("band", band, high=1.0, high_inclusive=False)
    sol = solve_ivp(lambda t, x: profile_rhs(profile, step, x), (0.0, t_final), [0.0, 0.0],
                    method="RK45", rtol=1e-10, atol=1e-12, dense_output=True,
                    max_step=t_final / 2000)
    t = np.linspace(0.0, t_final, n)
    y, v = sol.sol(t)
    alpha = np.array([profile_rhs(profile, step, (yi, vi))[1] for yi, vi in zip(y, v)])
    target = min(max(step, -profile.position_limit), profile.position_limit)
    ts = _settling_time(sol.sol, t, y, target, band * abs(target))
    return ProfileResponse(t, y, v, alpha, ts)


def _settling_time(dense, t, y, target, tol) -> float:
    """Last time |y - target| crosses tol (refined on the dense solution)."""
    outside = np.abs(y - target) > tol
    if outside[-1]:
        return math.inf
    if not outside.any():
        return 0.0
    i = int(np.nonzero(outside)[0][-1])
    f = lambda s: abs(dense(s)[0] - target) - tol  # noqa: E731
    return float(brentq(f, t[i], t[i + 1], xtol=1e-12))


def tune_rate_limit(natural_frequency: float = 157.0, damping_ratio: float = 1.0,
                    step: float = math.radians(15.0), settling_time: float = 0.05,
                    band: float = 0.02, bracket=(0.5, 100.0)) -> SecondOrderProfile:
    """The profile with the smallest rate limit that settles ``step`` within ``settling_time``.

    Parameters
    ----------
    natural_frequency, damping_ratio : of Eq. (4.8).
    step : commanded angle (rad). settling_time : required (s), > 0. band : settling band.
    bracket : rate limits (rad/s) bracketing the answer.

    Raises ValueError if even the upper bracket (nearly linear) cannot settle in time.

    Memoised on its arguments (the result is an immutable dataclass of floats): the servo and
    supersonic chapters of one reproduction tune the same profile once.
    """
    in_range("settling_time", settling_time)
    args = (natural_frequency, damping_ratio, step, settling_time, band, tuple(bracket))
    try:
        hash(args)
    except TypeError:                       # unhashable arguments: not memoised
        return _tune_rate_limit.__wrapped__(*args)
    return _tune_rate_limit(*args)


@lru_cache(maxsize=64)
def _tune_rate_limit(natural_frequency, damping_ratio, step, settling_time, band, bracket):
    def excess(rate):
        prof = SecondOrderProfile(natural_frequency, damping_ratio, rate)
        return profile_step(prof, step, t_final=4.0 * settling_time, band=band,
                            n=2001).settling_time - settling_time

    lo, hi = bracket
    if excess(hi) > 0:
        raise ValueError(
            f"settling_time {settling_time:g} s cannot be met with natural_frequency "
            f"{natural_frequency:g} rad/s and damping_ratio {damping_ratio:g} even for a rate "
            f"limit of {hi:g} rad/s; increase natural_frequency or settling_time")
    rate = brentq(excess, lo, hi, xtol=1e-6)
    return SecondOrderProfile(natural_frequency, damping_ratio, rate)


@dataclass(frozen=True)
class TorqueRequirement:
    """Result of Eqs. (4.10)-(4.12): ``inertial`` = J_fin alpha_max, ``aerodynamic`` =
    q Q_cc theta_max, ``required`` = their sum, ``design`` = with safety factor (all N m at the
    fin); ``max_acceleration`` (rad/s^2) and ``dynamic_pressure`` (Pa) used."""

    max_acceleration: float
    dynamic_pressure: float
    inertial: float
    aerodynamic: float
    required: float
    design: float


def required_stall_torque(max_acceleration: float, fin_inertia: float = THESIS_FIN_INERTIA,
                          q_cc: float = THESIS_Q_CC, mach: float = 0.6,
                          density: float = SEA_LEVEL_DENSITY,
                          speed_of_sound: float = SEA_LEVEL_SPEED_OF_SOUND,
                          theta_max: float = math.radians(15.0), safety_factor: float = 1.25,
                          round_up_to: float = 1.0) -> TorqueRequirement:
    """Stall torque at the fin, Eqs. (4.7), (4.10)-(4.12).

    Parameters
    ----------
    max_acceleration : |theta''|_max of the profile (rad/s^2), >= 0.
    fin_inertia : J_fin (kg m^2), >= 0 (thesis: 2.958e-4).
    q_cc : steady hinge-moment coefficient Q_cc^real (m^3/rad) (thesis: 5.825e-4 at M 0.6).
    mach, density, speed_of_sound : flight condition (thesis: M 0.6 at sea level).
    theta_max : largest fin angle (rad) (thesis: 15 deg).
    safety_factor : >= 1 (thesis: 1.25). round_up_to : the design torque is the factored one
        rounded up to a multiple of this (N m; thesis: 4.74 x 1.25 "taken as 6"); 0 for none.
    """
    in_range("max_acceleration", max_acceleration, inclusive=True)
    in_range("fin_inertia", fin_inertia, inclusive=True)
    in_range("safety_factor", safety_factor, low=1.0, inclusive=True)
    in_range("round_up_to", round_up_to, inclusive=True)
    q = dynamic_pressure(mach, density, speed_of_sound)
    inertial = fin_inertia * max_acceleration
    aero = abs(q * float(q_cc) * theta_max)
    required = inertial + aero
    design = required * safety_factor
    if round_up_to > 0:
        design = math.ceil(design / round_up_to - 1e-12) * round_up_to
    return TorqueRequirement(max_acceleration, q, inertial, aero, required, design)
