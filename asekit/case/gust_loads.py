"""Discrete-gust loads of a case (issue 27): the ``[gust]`` table's 1-cos gusts over their
gradient distances, with the hinge moment (actuator clamped), root shear and root bending
moment by force summation, and their peaks (the "tuned" gust: the worst over the lengths).

For the case's flight condition (``gust.mach``, ``gust.altitude``; 1976 standard atmosphere,
U = M a): one pressure solve per reduced frequency gives the modal GAFs, the gust column and
the aerodynamic load rows (:func:`asekit.aero.gust.gust_aero_tables`, gust referred to
``gust.x0``, default the most upstream leading edge); each is fitted in Roger form with the
modal fit's lag roots (:mod:`asekit.rfa.gust`; the modal fit is the case's ``flutter.rfa``);
the gust state space (:func:`asekit.aeroelastic.gust.gust_state_space`) is integrated through
each gust (:func:`~asekit.aeroelastic.gust.one_minus_cosine`) and the loads are summed
(:func:`~asekit.aeroelastic.gust.load_histories`):

- root shear (N): the sum of the normal forces on the surface, aerodynamic + inertial
  (-u^T M Phi zeta'' with u the unit translation w = 1);
- root bending moment (N m): their moment about the root chord line y = y_root, positive when
  an upward load bends the tip up (u: w = y - y_root, theta_x = 1);
- at each ``[[gust.station]]`` cut (:func:`station_cuts`): the shear, the bending moment about
  the cut's chord line y = y_cut and the torsion about the line x = x_axis (parallel to y,
  nose up > 0: u is w = -(x - x_axis), theta_y = 1) of the boxes and nodes on or outboard of
  the cut, aerodynamic + inertial as at the root (a station at eta = 0 is the root);
- hinge moment (N m): T_hinge@fin of the shaft (docs/conventions.md), the rigid pitch held
  at zero (a stiff actuator); None without a rigid pitch mode.

A user-given gust profile (``gust.profile``, :class:`asekit.case.schema.GustProfile`) runs
through the same path: its rows are interpolated by a not-a-knot cubic spline, which gives
w_g and its derivatives w_g', w_g'' (the Roger form's gust terms need them); before the first
row the air is at rest, after the last row the last velocity holds; the time step is that of a
1-cos gust of the profile's duration (features shorter than it are smoothed by the
first-order hold).

- motor current (A) and voltage (V): with ``[actuator]``, the gust in the closed AEM1 loop
  (motor-angle feedback) and the AEM2 loop (fin-root feedback) (:mod:`asekit.ase.gust`),
  linear (without the voltage and current limits, so a peak above ``actuator.current_limit``
  says the actuator would saturate) and with the actuator's supply and current limits (as
  the servo chapter models them: the voltage clip |V| <= I_lim R, then the supply clip;
  time domain, exact piecewise-affine propagation). None without an actuator or for a loop
  that is unstable at the gust's condition.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from asekit.aero.gust import gust_aero_tables
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.gust import (
    gust_frequency_response,
    gust_response,
    gust_state_space,
    load_histories,
    one_minus_cosine,
    response_covariance,
    spectral_statistics,
    turbulence_psd,
)
from asekit.ase.gust import (
    closed_loop_gust,
    closed_loop_gust_frequency_response,
    closed_loop_gust_response,
    limited_gust_response,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case.pipeline import (
    actuator_setup,
    ase_condition,
    box_mesh,
    mass_and_stiffness,
    modal_model,
    reduced_frequencies,
)
from asekit.case.schema import Case, CaseError
from asekit.rfa.gust import gust_fit
from asekit.rfa.methods import rfa_kind

#: Time steps per gust gradient time H / U in the simulation.
STEPS_PER_GRADIENT = 40
#: Time steps per period of the model's highest mode (the first-order hold is exact for the
#: piecewise-linear gust; this resolves the output's peaks).
STEPS_PER_PERIOD = 20


@dataclass(frozen=True)
class GustLoadCase:
    """One gust's loads: ``gradient_length`` H (m; None for a user profile, then ``profile``
    is its file name), ``t`` (s), ``w_gust`` (m/s), and the
    histories ``hinge_moment`` (N m, None without a rigid mode), ``root_shear`` (N),
    ``root_bending`` (N m), ``current`` (A, the AEM1 loop's motor current; None without an
    actuator), with their peaks (largest magnitude, signed); ``stations``: {name: (3, n_t)
    shear (N), bending (N m), torsion (N m)} at the ``[[gust.station]]`` cuts; ``servo``:
    {"AEM1", "AEM2": {"current", "voltage" (linear loop: A, V demand), "current_limited",
    "voltage_limited", "theta_limited" (with the actuator's power limits: A, applied V), "saturated" (bool)}}
    for each loop that is stable at the gust's condition (empty without an actuator)."""

    gradient_length: float | None
    t: np.ndarray
    w_gust: np.ndarray
    hinge_moment: np.ndarray | None
    root_shear: np.ndarray
    root_bending: np.ndarray
    current: np.ndarray | None = None
    profile: str | None = None
    stations: dict = field(default_factory=dict)
    servo: dict = field(default_factory=dict)

    @staticmethod
    def _peak(y) -> float | None:
        return None if y is None else float(y[int(np.argmax(np.abs(y)))])

    @property
    def peak_hinge_moment(self) -> float | None:
        return self._peak(self.hinge_moment)

    @property
    def peak_current(self) -> float | None:
        return self._peak(self.current)

    def servo_peak(self, topology: str, what: str):
        """Peak (largest magnitude, signed) of ``servo[topology][what]``; the ``saturated``
        flag as is; None when that loop was not run (no actuator, or unstable)."""
        h = self.servo.get(topology, {}).get(what)
        return h if what == "saturated" or h is None else self._peak(h)

    @property
    def peak_root_shear(self) -> float:
        return self._peak(self.root_shear)

    @property
    def peak_root_bending(self) -> float:
        return self._peak(self.root_bending)

    @property
    def station_peaks(self) -> dict:
        """{station name: {"peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm"}}."""
        keys = ("peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm")
        return {n: {k: self._peak(h) for k, h in zip(keys, v)} for n, v in self.stations.items()}


@dataclass(frozen=True)
class GustLoads:
    """The ``[gust]`` analysis: flight condition (``mach``, ``altitude`` m, ``velocity`` m/s,
    ``density`` kg/m^3), ``design_velocity`` (m/s), ``x0`` (m), one :class:`GustLoadCase` per
    gradient distance, the Roger fits' errors (``fit_errors``: modal, gust, loads) and, with
    ``[gust.turbulence]``, ``turbulence``: {"hinge_moment", "root_shear", "root_bending"} ->
    :func:`asekit.aeroelastic.gust.spectral_statistics` (rms, A_bar, N0_per_s), plus
    ``omega_max`` (rad/s, the integration's upper end: k_max U / b, the fits' range)."""

    mach: float
    altitude: float
    velocity: float
    density: float
    design_velocity: float
    x0: float
    cases: tuple
    fit_errors: dict
    turbulence: dict | None = None

    def tuned(self, which: str = "root_bending") -> GustLoadCase:
        """The gust of the largest peak ``which`` ("root_bending", "root_shear",
        "hinge_moment")."""
        return max(self.cases, key=lambda c: abs(getattr(c, f"peak_{which}") or 0.0))


def station_cuts(boxes, stations) -> list:
    """The cuts of the monitoring stations (:class:`asekit.case.schema.GustStation`) on the
    box mesh ``boxes``: one (y_cut, x_axis) in m per station, y_cut = y_root + eta (y_tip -
    y_root) and x_axis = x_le + axis (x_te - x_le) at y_cut, the leading and trailing edges
    interpolated linearly between the box corners' spanwise stations (exact for straight
    edges).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from asekit.case.schema import GustStation
    >>> c = np.array([[[0, 0, 0], [1, 0, 0], [1.5, 1, 0], [0.5, 1, 0]]], float)
    >>> station_cuts(SimpleNamespace(corners=c), [GustStation("mid", 0.5, 0.5)])
    [(0.5, 0.75)]
    """
    xy = boxes.corners[:, :, :2].reshape(-1, 2)
    y0, y1 = float(xy[:, 1].min()), float(xy[:, 1].max())
    ys = np.unique(np.round(xy[:, 1], 12))
    yr = np.round(xy[:, 1], 12)
    le = np.array([xy[yr == y, 0].min() for y in ys])
    te = np.array([xy[yr == y, 0].max() for y in ys])
    out = []
    for st in stations:
        y = y0 + st.eta * (y1 - y0)
        xl, xt = float(np.interp(y, ys, le)), float(np.interp(y, ys, te))
        out.append((y, xl + st.axis * (xt - xl)))
    return out


def _outboard(y, y_cut: float, span: float) -> np.ndarray:
    """1 where y lies on or outboard of the cut (within 1e-9 of the span), else 0."""
    return (np.asarray(y) >= y_cut - 1e-9 * span).astype(float)


def _load_weights(boxes, y_root: float, cuts=()) -> np.ndarray:
    """Per-box weights of the summed loads: root shear, root bending, then per station cut
    (y_cut, x_axis) the shear, bending about y = y_cut and torsion about x = x_axis (nose up
    > 0) of the boxes on or outboard of the cut."""
    p = boxes.load_point
    cols = [np.ones(boxes.n), p[:, 1] - y_root]
    span = float(np.ptp(boxes.corners[:, :, 1]))
    for y_cut, x_a in cuts:
        m = _outboard(p[:, 1], y_cut, span)
        cols += [m, m * (p[:, 1] - y_cut), m * (x_a - p[:, 0])]
    return np.column_stack(cols)


def _inertial_rows(case: Case, modal, y_root: float, cuts=(), span: float = 1.0) -> np.ndarray:
    _, M = mass_and_stiffness(case)
    nodes = modal.nodes
    n = nodes.shape[0]
    u = np.zeros((2 + 3 * len(cuts), 3 * n))
    u[0, 0::3] = 1.0                                    # unit translation w = 1
    u[1, 0::3] = nodes[:, 1] - y_root                  # rotation about the root line:
    u[1, 1::3] = 1.0                                    # w = y - y_root, theta_x = dw/dy = 1
    for i, (y_cut, x_a) in enumerate(cuts):            # the same, outboard of each cut, and
        m = _outboard(nodes[:, 1], y_cut, span)        # a nose-up rotation about x = x_a:
        r = 2 + 3 * i                                   # w = -(x - x_a), theta_y = 1
        u[r, 0::3] = m
        u[r + 1, 0::3], u[r + 1, 1::3] = m * (nodes[:, 1] - y_cut), m
        u[r + 2, 0::3], u[r + 2, 2::3] = m * (x_a - nodes[:, 0]), m
    phi = modal.shapes.reshape(3 * n, -1)[:, modal.n_rigid:]
    return -(M @ u.T).T @ phi


def _servo_loops(case: Case, g, rfa, ss) -> dict:
    """The AEM1 and AEM2 loops with the gust (:func:`asekit.ase.gust.closed_loop_gust`) at the
    gust's condition, with the same fit as ``ss``, each with its actuator and power limits:
    {topology: (loop, actuator, limits)} for the loops that are stable; empty without an
    actuator."""
    if case.actuator is None:
        return {}
    act, ctl, lim = actuator_setup(case)
    cond = ase_condition(case, g.mach, g.altitude, actuator=act, fit=lambda *_: rfa)
    out = {}
    for topology in ("AEM1", "AEM2"):
        loop = closed_loop_gust(cond.model, ctl, ss, topology)
        if np.max(np.linalg.eigvals(loop.A).real) < 0:
            out[topology] = (loop, cond.model.actuator, lim)
    return out


def _servo_histories(loops: dict, t, w) -> dict:
    """Linear and power-limited current and voltage of each loop of :func:`_servo_loops`."""
    out = {}
    for topology, (loop, act, lim) in loops.items():
        lin = closed_loop_gust_response(loop, t, w)
        sat = limited_gust_response(loop, act, lim, t, w)
        out[topology] = {"current": lin["current"], "voltage": lin["voltage"],
                         "current_limited": sat["current"], "voltage_limited": sat["voltage"],
                         "theta_limited": sat["theta"], "saturated": sat["saturated"]}
    return out


def _time_grid(t0: float, t1: float, settle: float, f_max: float) -> np.ndarray:
    """Uniform times (s) from ``t0`` through a gust ending at ``t1`` and ``settle`` s beyond:
    STEPS_PER_GRADIENT steps per half the gust's duration, STEPS_PER_PERIOD per period of the
    highest mode (``f_max`` Hz), at most 200001 points."""
    dt = min((t1 - t0) / (2 * STEPS_PER_GRADIENT), 1.0 / (STEPS_PER_PERIOD * max(f_max, 1e-9)))
    nt = min(int(math.ceil((t1 - t0 + settle) / dt)) + 1, 200001)
    return np.linspace(t0, t1 + settle, nt)


def profile_gust(time, velocity, t) -> np.ndarray:
    """A sampled gust velocity history and its derivatives at the times ``t`` (s): the
    not-a-knot cubic spline through the rows (``time`` s, strictly ascending; ``velocity``
    m/s); zero before the first row, the last velocity (and zero derivatives) after the last.

    Returns
    -------
    (3, len(t)) array: w_g (m/s), w_g' (m/s^2), w_g'' (m/s^3), as
    :func:`asekit.aeroelastic.gust.one_minus_cosine`.

    Examples
    --------
    >>> w = profile_gust([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 4.0, 9.0], [0.5, 2.5, 4.0])
    >>> np.round(w, 12) + 0.0                  # the spline is exact for t^2
    array([[0.25, 6.25, 9.  ],
           [1.  , 5.  , 0.  ],
           [2.  , 2.  , 0.  ]])
    """
    from scipy.interpolate import CubicSpline

    tp, wp = np.asarray(time, float), np.asarray(velocity, float)
    tt = np.asarray(t, float).ravel()
    spline = CubicSpline(tp, wp, bc_type="not-a-knot" if tp.size > 3 else "natural")
    out = np.zeros((3, tt.size))
    inside = (tt >= tp[0]) & (tt <= tp[-1])
    for d in range(3):
        out[d, inside] = spline(tt[inside], d)
    out[0, tt > tp[-1]] = wp[-1]
    return out


def gust_loads(case: Case) -> GustLoads | None:
    """The discrete-gust loads of ``case`` (module docstring); None without ``[gust]``.

    Parameters
    ----------
    case : Case with a ``[gust]`` table (:class:`asekit.case.schema.GustSpec`).

    Returns
    -------
    GustLoads or None

    Raises
    ------
    CaseError
        The case is an imported deck (no plate mesh for the inertial loads) or has no
        aerodynamics, or the aeroelastic system is unstable at the gust's condition.
    """
    g = case.gust
    if g is None:
        return None
    if case.structure is not None or case.aero is None:
        raise CaseError("gust: discrete-gust loads need a case-file surface with [aero] "
                        "(imported decks are not supported yet)")
    modal, boxes, a = modal_model(case), box_mesh(case), case.aero
    b = a.reference_semichord
    y_root = float(np.min(boxes.corners[:, :, 1]))
    x0 = float(np.min(boxes.corners[:, :, 0])) if g.x0 is None else g.x0
    ks = reduced_frequencies(case)
    method = a.kernel if a.method == "dlm" else a.method
    cuts = station_cuts(boxes, g.stations)
    span = float(np.ptp(boxes.corners[:, :, 1]))
    tab = gust_aero_tables(fe_spline(modal, boxes), boxes, g.mach, ks, b,
                           _load_weights(boxes, y_root, cuts), x0, method, a.symmetry == "wall")
    rfa = rfa_kind(case.flutter.rfa).fit(ks, tab.Q, b, g.mach, case.flutter.lags)
    gfit = gust_fit(ks, tab.Qg, b, lag_roots=rfa.lag_roots, mach=g.mach)
    nk, nl, n = tab.QL.shape
    lfit = gust_fit(ks, np.hstack([tab.QL.reshape(nk, nl * n), tab.QLg]), b,
                    lag_roots=rfa.lag_roots, mach=g.mach)
    atm = standard_atmosphere(g.altitude)
    rho, U = float(atm.density), g.mach * float(atm.speed_of_sound)
    ss = gust_state_space(modal, rfa, gfit, rho, U)
    growth = float(np.max(np.linalg.eigvals(ss.A).real))
    if growth >= 0:
        raise CaseError(f"gust.mach = {g.mach:g}, gust.altitude = {g.altitude:g} m: the "
                        f"aeroelastic system (actuator clamped) is unstable there (largest "
                        f"Re pole {growth:.3g} 1/s: beyond flutter or divergence), so its gust "
                        f"loads are unbounded; choose a stable flight condition")
    inert = _inertial_rows(case, modal, y_root, cuts, span)
    loops = _servo_loops(case, g, rfa, ss)
    loop = loops.get("AEM1", (None,))[0]
    f_max = float(np.max(modal.frequencies_hz))

    def run(t, w, H=None, name=None):
        resp = gust_response(ss, t, w)
        loads = load_histories(resp, lfit, inert, modal.n_rigid)
        servo = _servo_histories(loops, t, w)
        cur = servo["AEM1"]["current"] if "AEM1" in servo else None
        st = {s.name: loads[:, 2 + 3 * i:5 + 3 * i].T for i, s in enumerate(g.stations)}
        return GustLoadCase(H, t, w[0], resp.hinge_moment if modal.n_rigid else None,
                            loads[:, 0], loads[:, 1], cur, name, st, servo)

    out = []
    for H in g.gradient_lengths:
        t = _time_grid(0.0, 2 * H / U, g.settle_time, f_max)
        out.append(run(t, one_minus_cosine(t, U, H, g.design_velocity), float(H)))
    if g.profile is not None:
        p = g.profile
        t = _time_grid(p.time[0], p.time[-1], g.settle_time, f_max)
        out.append(run(t, profile_gust(p.time, p.velocity, t), None, p.name))
    errs = {"modal": float(rfa.fit_error), "gust": gfit.fit_error, "loads": lfit.fit_error}
    turb = None
    if g.turbulence_sigma is not None:
        turb = _turbulence(ss, lfit, inert, modal.n_rigid, g, float(np.max(ks)) * U / b, loop)
    return GustLoads(g.mach, g.altitude, U, rho, g.design_velocity, x0, tuple(out), errs, turb)


#: Frequencies of the turbulence integrals: 0, then geometric from 1e-3 U / L (well inside
#: the spectrum's knee U / (1.339 L)) to k_max U / b.
TURBULENCE_POINTS = 4000


def _turbulence(ss, lfit, inert, n_rigid, g, omega_max: float, loop=None) -> dict:
    """RMS, A-bar, N0 of the loads in continuous turbulence (module docstring); with the AEM1
    ``loop`` the motor current's too. Also ``spectra`` ({"omega" rad/s, "psd" the gust's,
    and per load its one-sided response PSD |H|^2 Phi per rad/s}) and ``covariance`` ({"names",
    "matrix"}: the joint covariance of the hinge moment (when present) and the root bending,
    :func:`asekit.aeroelastic.gust.response_covariance`, for the correlated-load ellipse)."""
    w0 = min(1e-3 * ss.velocity / g.scale_length, 1e-6 * omega_max)
    w = np.concatenate([[0.0], np.geomspace(w0, omega_max, TURBULENCE_POINTS)])
    fr = gust_frequency_response(ss, w, lfit, inert, n_rigid)
    psd = turbulence_psd(w, ss.velocity, g.scale_length, g.turbulence_sigma, g.spectrum)
    out = {"omega_max": omega_max}
    H = {"root_bending": fr["loads"][:, 1]}
    if "hinge_moment" in fr:
        H = {"hinge_moment": fr["hinge_moment"], **H}
        out["hinge_moment"] = spectral_statistics(w, fr["hinge_moment"], psd)
    out["root_shear"] = spectral_statistics(w, fr["loads"][:, 0], psd)
    out["root_bending"] = spectral_statistics(w, fr["loads"][:, 1], psd)
    if loop is not None:
        H["current"] = closed_loop_gust_frequency_response(loop, w)["current"]
        out["current"] = spectral_statistics(w, H["current"], psd)
    out["stations"] = {
        st.name: {k: spectral_statistics(w, fr["loads"][:, 2 + 3 * i + j], psd)
                  for j, k in enumerate(("shear", "bending", "torsion"))}
        for i, st in enumerate(g.stations)}
    out["spectra"] = {"omega": w, "psd": psd, **{k: np.abs(h) ** 2 * psd for k, h in H.items()}}
    pair = [k for k in ("hinge_moment", "root_bending") if k in H]
    out["covariance"] = {"names": tuple(pair), "matrix": response_covariance(
        w, np.column_stack([H[k] for k in pair]), psd)}
    return out


def turbulence_json(result: GustLoads | None) -> list:
    """The ``analyse --json`` ``"turbulence"`` rows (one per flight condition): ``mach``,
    ``altitude_m``, ``rms_hinge_moment_Nm``, ``A_bar_hinge`` (N m per m/s), ``N0_per_s`` (of
    the hinge moment; null without a rigid mode), ``rms_root_bending_Nm``,
    ``A_bar_root_bending`` (N m per m/s), ``N0_root_bending_per_s``, ``omega_max`` (rad/s),
    ``rms_current_A`` (the linear AEM1 loop's motor current; null without an actuator or when
    that loop is unstable), ``stations`` ({name: {"rms_shear_N", "rms_bending_Nm",
    "rms_torsion_Nm"}} at the ``[[gust.station]]`` cuts). The turbulence's own parameters
    (sigma, scale length, spectrum) are the case's ``[gust.turbulence]`` inputs."""
    if result is None or result.turbulence is None:
        return []
    t = result.turbulence
    h = t.get("hinge_moment")
    bend = t["root_bending"]
    g = {"mach": result.mach, "altitude_m": result.altitude,
         "rms_hinge_moment_Nm": None if h is None else h["rms"],
         "A_bar_hinge": None if h is None else h["A_bar"],
         "N0_per_s": None if h is None else h["N0_per_s"],
         "rms_root_bending_Nm": bend["rms"], "A_bar_root_bending": bend["A_bar"],
         "N0_root_bending_per_s": bend["N0_per_s"], "omega_max": t["omega_max"],
         "rms_current_A": t["current"]["rms"] if "current" in t else None,
         "stations": {n: {"rms_shear_N": v["shear"]["rms"], "rms_bending_Nm": v["bending"]["rms"],
                          "rms_torsion_Nm": v["torsion"]["rms"]}
                      for n, v in t.get("stations", {}).items()}}
    return [g]


def _deg(v):
    return None if v is None else math.degrees(v)


def gust_json(result: GustLoads | None) -> list:
    """The ``analyse --json`` ``"gust"`` rows: one per gradient distance, then one for the
    ``gust.profile`` (``gust_length_m`` null, ``profile`` its file name; null in the 1-cos
    rows), ``mach``, ``altitude_m``, ``gust_length_m`` (the gradient distance H),
    ``peak_hinge_moment_Nm``
    (null without a rigid mode), ``peak_root_bending_Nm``, ``peak_root_shear_N``,
    ``peak_current_A`` (the linear AEM1 loop's motor current; null without an actuator),
    ``peak_voltage_V`` (its PD voltage demand), ``peak_current_limited_A`` and
    ``peak_voltage_limited_V``, ``peak_deflection_limited_deg`` (the AEM1 loop with the actuator's supply and current limits,
    :func:`asekit.ase.gust.limited_gust_response`; applied voltage), ``saturated`` (a limit
    bound), ``peak_current_aem2_A``, ``peak_current_aem2_limited_A``, ``saturated_aem2`` (the
    same for the AEM2 loop; null where a loop is unstable or there is no actuator),
    ``stations`` ({name: {"peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm"}}, the
    ``[[gust.station]]`` cuts' peaks; empty without stations)."""
    if result is None:
        return []
    return [{"mach": result.mach, "altitude_m": result.altitude,
             "gust_length_m": c.gradient_length,
             "peak_hinge_moment_Nm": c.peak_hinge_moment,
             "peak_root_bending_Nm": c.peak_root_bending,
             "peak_root_shear_N": c.peak_root_shear,
             "peak_current_A": c.peak_current, "profile": c.profile,
             "peak_voltage_V": c.servo_peak("AEM1", "voltage"),
             "peak_current_limited_A": c.servo_peak("AEM1", "current_limited"),
             "peak_voltage_limited_V": c.servo_peak("AEM1", "voltage_limited"),
             "peak_deflection_limited_deg": _deg(c.servo_peak("AEM1", "theta_limited")),
             "saturated": c.servo_peak("AEM1", "saturated"),
             "peak_current_aem2_A": c.servo_peak("AEM2", "current"),
             "peak_current_aem2_limited_A": c.servo_peak("AEM2", "current_limited"),
             "saturated_aem2": c.servo_peak("AEM2", "saturated"),
             "stations": c.station_peaks} for c in result.cases]
