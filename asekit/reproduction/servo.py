"""Thesis Ch. 4 (servo-actuator): computed quantities and figures (Figs 40-43, 47-57).

:func:`compute` runs every Ch. 4 analysis with asekit and returns a :class:`ServoChapter`;
:func:`run` turns it into the reproduce rows; the ``fig_*`` functions draw the thesis figures
from a :class:`ServoChapter` (the chapter notebook calls them too).

Reproduction inputs (the thesis's own values, documented as inputs, not results): J_fin =
2.958e-4 kg m^2, Q_cc = 5.825e-4 m^3/rad at M 0.6 sea level (1976 standard atmosphere), the
motor and transmission of Table 12 / Eq. 4.13 with c = 0 and K_b = K_t.

Interpretation of Figs 55-57: the thesis presents "a -15 deg command when the initial condition
is 15 deg", the condition "that would slow down the servo most" because the de-centering hinge
moment opposes the motion. asekit reads this as a -15 deg *step* from +15 deg (final command
0 deg): the fin moves against the de-centering moment all the way, the worst case argued in
Sec. 4.1.1. A full reversal to -15 deg (30 deg of travel) cannot settle in 50 ms at about
500 deg/s; the notebook shows it too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from asekit.aero.gaf import GAF_FILE, GafDatabase, steady_hinge_coefficient
from asekit.case import pipeline
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import fin_case
from asekit.servo.actuator import (
    NO_CONTROLLER,
    SYSTEM_1,
    SYSTEM_2,
    SYSTEM_3,
    ActuatorParameters,
    Margins,
    PDController,
    closed_loop,
    closed_loop_poles,
    forward_path,
    margins,
    open_loop_poles,
    root_locus_data,
    step_response,
)
from asekit.servo.simulate import THESIS_LIMITS, SimulationResult, SteadyHingeMoment, simulate
from asekit.servo.torque_requirement import (
    ProfileResponse,
    SecondOrderProfile,
    TorqueRequirement,
    profile_step,
    required_stall_torque,
    tune_rate_limit,
)
from asekit.util.cache import CacheError, load_npz
from asekit.util.plotting import THESIS_COLOR, new_figure

#: Thesis Table 2: the settling-time and steady-state error requirements.
SETTLING_REQUIREMENT = 0.05      # s
ERROR_REQUIREMENT = 0.02         # fraction


@dataclass(frozen=True)
class ServoChapter:
    """Every computed Ch. 4 result (SI units)."""

    params: ActuatorParameters
    profile: SecondOrderProfile
    profile_response: ProfileResponse
    torque: TorqueRequirement
    open_loop_poles: np.ndarray
    no_controller_poles: np.ndarray
    system_poles: dict
    system3_margins: Margins
    step14: dict            # controller name -> SimulationResult (power limited, hinge moment)
    reversal: SimulationResult
    full_reversal: SimulationResult
    hinge_moment: SteadyHingeMoment


def compute(params: ActuatorParameters | None = None,
            hinge_moment: SteadyHingeMoment | None = None) -> ServoChapter:
    """Run the Ch. 4 analyses (about 3 s)."""
    params = ActuatorParameters() if params is None else params
    hm = SteadyHingeMoment() if hinge_moment is None else hinge_moment
    profile = tune_rate_limit(natural_frequency=157.0, damping_ratio=1.0,
                              step=math.radians(15.0), settling_time=SETTLING_REQUIREMENT,
                              band=ERROR_REQUIREMENT)
    resp = profile_step(profile, math.radians(15.0), t_final=0.08)
    torque = required_stall_torque(resp.peak_acceleration, fin_inertia=params.fin_inertia,
                                   q_cc=hm.q_cc, mach=hm.mach, density=hm.density,
                                   speed_of_sound=hm.speed_of_sound)
    step14 = {c.name: simulate(params, c, math.radians(14.0), t_final=0.1, limits=THESIS_LIMITS,
                               hinge_moment=hm) for c in (SYSTEM_2, SYSTEM_3)}
    reversal = simulate(params, SYSTEM_3, 0.0, t_final=0.1, theta0=math.radians(15.0),
                        limits=THESIS_LIMITS, hinge_moment=hm)
    full = simulate(params, SYSTEM_3, math.radians(-15.0), t_final=0.12,
                    theta0=math.radians(15.0), limits=THESIS_LIMITS, hinge_moment=hm)
    return ServoChapter(
        params=params, profile=profile, profile_response=resp, torque=torque,
        open_loop_poles=open_loop_poles(params),
        no_controller_poles=closed_loop_poles(params, NO_CONTROLLER),
        system_poles={c.name: closed_loop_poles(params, c) for c in (SYSTEM_1, SYSTEM_2, SYSTEM_3)},
        system3_margins=margins(params, SYSTEM_3), step14=step14, reversal=reversal,
        full_reversal=full, hinge_moment=hm)


@dataclass(frozen=True)
class FinInputs:
    """asekit's own values of the two fin inputs of Ch. 4: ``fin_inertia`` (kg m^2, exact
    integral over the reference geometry, :func:`asekit.case.pipeline.pitch_inertia_exact`)
    and ``q_cc`` (Re Q_cc at M 0.6, k 0.001 from the cached DLM database, m^3/rad; None when the
    database file is not available). ``source`` says where each came from."""

    fin_inertia: float | None
    q_cc: float | None
    source: str


def asekit_fin_inputs(mach: float = 0.6) -> FinInputs:
    """asekit's J_fin and steady Q_cc for the design check beside the thesis's inputs.

    Reads only what is cheap: the exact plate integral and, if present, the cached GAF database
    ``data/gaf_fin.npz`` (never rebuilt here)."""
    notes = []
    j_fin = q_cc = None
    try:
        j_fin = pipeline.pitch_inertia_exact(fin_case())
        notes.append("J_fin: exact plate integral")
    except (ImportError, AttributeError, ValueError) as exc:      # structure not available
        notes.append(f"J_fin unavailable ({exc})")
    try:
        try:
            arrays, meta = load_npz(GAF_FILE)
            db = GafDatabase(arrays["machs"], arrays["k"], arrays["Q"], float(meta["b_ref"]),
                             int(meta["n_rigid"]), meta)
            q_cc = steady_hinge_coefficient(db, mach)
            notes.append(f"Q_cc: DLM database {GAF_FILE.name}, k = {float(db.k[0]):g}")
        except (CacheError, KeyError, OSError, ValueError) as exc:
            notes.append(f"Q_cc unavailable ({type(exc).__name__})")
    except ImportError as exc:
        notes.append(f"Q_cc unavailable ({exc})")
    return FinInputs(j_fin, q_cc, "; ".join(notes))


def _floats(a) -> list[float]:
    return [float(np.real(v)) for v in a]


def quantities(ch: ServoChapter) -> tuple[Quantity, ...]:
    """The reproduce rows of Ch. 4."""
    s3 = ch.step14[SYSTEM_3.name]
    rev = ch.reversal
    rate_dps = math.degrees(ch.profile.rate_limit)
    return (
        Quantity("servo.open_loop_poles", _floats(ch.open_loop_poles), "rad/s",
                 "Eq 2.41, c = 0, K_b = K_t"),
        Quantity("servo.system1.closed_loop_poles", _floats(ch.system_poles[SYSTEM_1.name]),
                 "rad/s", "Eq 4.18 with K_c in the constant term"),
        Quantity("servo.system2.closed_loop_poles", _floats(ch.system_poles[SYSTEM_2.name]),
                 "rad/s", ""),
        Quantity("servo.system3.closed_loop_poles", _floats(ch.system_poles[SYSTEM_3.name]),
                 "rad/s", ""),
        Quantity("servo.system3.phase_margin_deg", ch.system3_margins.phase_margin_deg, "deg",
                 f"at {ch.system3_margins.gain_crossover:.0f} rad/s"),
        Quantity("servo.system3.gain_margin_db", ch.system3_margins.gain_margin_db, "dB",
                 "phase never reaches -180 deg"),
        Quantity("servo.torque.max_accel_deg_s2", math.degrees(ch.torque.max_acceleration),
                 "deg/s^2", f"zeta 1, rate limit {rate_dps:.0f} deg/s tuned for 2 % in 50 ms; "
                            "500 deg/s would give 157000"),
        Quantity("servo.torque.required_stall_Nm", ch.torque.required, "N m",
                 f"q = {ch.torque.dynamic_pressure:.0f} Pa (ISA sea level, M 0.6)"),
        Quantity("servo.torque.design_stall_Nm", ch.torque.design, "N m",
                 f"1.25 x required = {1.25 * ch.torque.required:.2f}, rounded up"),
        Quantity("servo.step14.settling_ms", 1e3 * s3.settling_time(ERROR_REQUIREMENT), "ms",
                 "System 3, 24 V, steady hinge moment; 2 % band about the final value"),
        Quantity("servo.step14.steady_error_pct", 100 * s3.steady_error, "%",
                 "de-centering moment: settles above the command"),
        Quantity("servo.reversal.peak_rate_deg_s", math.degrees(rev.peak_rate), "deg/s",
                 "-15 deg step from +15 deg (to 0 deg)"),
        Quantity("servo.reversal.peak_torque_Nm", rev.peak_torque, "N m",
                 f"motor torque at fin; settles in {1e3 * rev.settling_time():.1f} ms"),
    )


def run(figures: bool = False) -> ChapterResult:
    """Reproduce thesis Ch. 4: the rows of ``python -m asekit reproduce`` and, if ``figures``,
    Figs 40-43 and 47-57 as matplotlib figures."""
    ch = compute()
    figs = all_figures(ch) if figures else {}
    return ChapterResult(chapter="servo", quantities=quantities(ch), figures=figs)


# ---- figures ---------------------------------------------------------------------------------

def _registry() -> dict:
    """Figure name -> function of a :class:`ServoChapter` drawing it."""
    return {
        "fig40_41_profile_position": fig_profile_position,
        "fig42_profile_rate": fig_profile_rate,
        "fig43_profile_acceleration": fig_profile_acceleration,
        "fig47_root_locus_open_loop": lambda ch: fig_root_locus_open_loop(ch, dominant=False),
        "fig48_root_locus_dominant": lambda ch: fig_root_locus_open_loop(ch, dominant=True),
        "fig49_step_no_controller": fig_step_no_controller,
        "fig50_root_locus_pd": fig_root_locus_pd,
        "fig51_step_systems12": fig_step_systems12,
        "fig52_step14_system2": lambda ch: fig_step14(ch, SYSTEM_2),
        "fig53_step14_system3": lambda ch: fig_step14(ch, SYSTEM_3),
        "fig54_bode_system3": fig_bode,
        "fig55_reversal_position": lambda ch: fig_reversal(ch, "position"),
        "fig56_reversal_rate": lambda ch: fig_reversal(ch, "rate"),
        "fig57_reversal_torque": lambda ch: fig_reversal(ch, "torque"),
    }


def figure(ch: ServoChapter, name: str):
    """Draw the Ch. 4 figure ``name`` (a key of :func:`all_figures`) and return it."""
    reg = _registry()
    if name not in reg:
        raise ValueError(f"name must be one of {sorted(reg)}, got {name!r}")
    return reg[name](ch)


def all_figures(ch: ServoChapter) -> dict:
    """Every Ch. 4 figure, keyed by a stable name."""
    return {name: draw(ch) for name, draw in _registry().items()}


def _linear_profile(ch: ServoChapter) -> ProfileResponse:
    p = ch.profile
    return profile_step(SecondOrderProfile(p.natural_frequency, p.damping_ratio),
                        math.radians(15.0), t_final=ch.profile_response.t[-1])


def fig_profile_position(ch: ServoChapter):
    fig, ax = new_figure("second-order profile, 15 deg command (reconstructed)", "Figs 40-41")
    r, lin = ch.profile_response, _linear_profile(ch)
    ax.plot(1e3 * lin.t, np.degrees(lin.theta), color=THESIS_COLOR, ls="--",
            label="linear Eq 4.8, omega_n 157 rad/s, zeta 1")
    ax.plot(1e3 * r.t, np.degrees(r.theta), label=f"rate limit {math.degrees(ch.profile.rate_limit):.0f} deg/s")
    ax.axhspan(15 * 0.98, 15 * 1.02, color="0.9")
    ax.axvline(50, color="k", lw=0.8, ls=":")
    ax.set(xlabel="time (ms)", ylabel="fin angle (deg)")
    ax.legend()
    return fig


def fig_profile_rate(ch: ServoChapter):
    fig, ax = new_figure("angular velocity of the limited second-order system", "Fig 42")
    r, lin = ch.profile_response, _linear_profile(ch)
    ax.plot(1e3 * lin.t, np.degrees(lin.omega), color=THESIS_COLOR, ls="--", label="linear")
    ax.plot(1e3 * r.t, np.degrees(r.omega), label="position and rate/acceleration limits")
    ax.set(xlabel="time (ms)", ylabel="angular velocity (deg/s)")
    ax.legend()
    return fig


def fig_profile_acceleration(ch: ServoChapter):
    fig, ax = new_figure("angular acceleration of the limited second-order system", "Fig 43")
    r = ch.profile_response
    ax.plot(1e3 * r.t, np.degrees(r.alpha), label="asekit")
    ax.axhline(157100, color=THESIS_COLOR, ls="--", label="thesis peak 157100 deg/s^2")
    ax.set(xlabel="time (ms)", ylabel="angular acceleration (deg/s^2)")
    ax.legend()
    return fig


def fig_root_locus_open_loop(ch: ServoChapter, dominant: bool):
    title = ("open-loop actuator root locus, dominant poles" if dominant
             else "open-loop actuator root locus")
    fig, ax = new_figure(title, "Fig 48" if dominant else "Fig 47")
    gains, poles = root_locus_data(ch.params, None, np.logspace(-1, 6, 1200))
    for k in range(3):
        ax.plot(poles[:, k].real, poles[:, k].imag, ".", ms=2, color="C0")
    ol = ch.open_loop_poles
    ax.plot(np.real(ol), np.imag(ol), "x", color="k", ms=8, label="open-loop poles (Table 13)")
    if dominant:
        ax.set_xlim(-400, 100)
        ax.set_ylim(-1500, 1500)
    else:
        ax.set_xlim(-12000, 4000)
        ax.set_ylim(-12000, 12000)
    ax.set(xlabel="real (rad/s)", ylabel="imaginary (rad/s)")
    ax.legend()
    return fig


def fig_step_no_controller(ch: ServoChapter):
    fig, ax = new_figure("unit step, unity feedback without controller (Eq 4.16)", "Fig 49")
    t, y = step_response(ch.params, NO_CONTROLLER, t_final=15.0, n=3001)
    ax.plot(t, y)
    ax.set(xlabel="time (s)", ylabel="fin angle / command (-)")
    return fig


def fig_root_locus_pd(ch: ServoChapter):
    fig, ax = new_figure("root locus of the PD-compensated systems, K_c from 0", "Fig 50")
    for c, col in ((SYSTEM_1, "C0"), (SYSTEM_2, "C1")):
        _, poles = root_locus_data(ch.params, c, np.logspace(-2, 3, 600))
        for k in range(3):
            ax.plot(poles[:, k].real, poles[:, k].imag, ".", ms=2, color=col,
                    label=f"zero at {c.zero:.0f} rad/s" if k == 0 else None)
        p9 = ch.system_poles[c.name]
        ax.plot(np.real(p9), np.imag(p9), "s", color=col, mfc="none", ms=7)
    ax.axvline(-628.32, color="k", ls=":", lw=0.8, label="s_min = -628.32 (Eq 4.19)")
    ax.set_xlim(-1200, 50)
    ax.set_ylim(-800, 800)
    ax.set(xlabel="real (rad/s)", ylabel="imaginary (rad/s)")
    ax.legend()
    return fig


def fig_step_systems12(ch: ServoChapter):
    fig, ax = new_figure("unit step of the linear closed loops, Systems 1, 2 (and 3)", "Fig 51")
    for c in (SYSTEM_1, SYSTEM_2, SYSTEM_3):
        t, y = step_response(ch.params, c, t_final=0.05)
        ax.plot(1e3 * t, y, label=f"{c.name} (K_c {c.gain:g}, zero {c.zero:.0f})")
    ax.set(xlabel="time (ms)", ylabel="fin angle / command (-)")
    ax.legend()
    return fig


def fig_step14(ch: ServoChapter, controller: PDController):
    num = "Fig 52" if controller is SYSTEM_2 else "Fig 53"
    fig, ax = new_figure(f"{controller.name}, 14 deg step: linear vs power limited", num)
    sim = ch.step14[controller.name]
    t, y = step_response(ch.params, controller, t_final=sim.t[-1], amplitude=14.0)
    ax.plot(1e3 * t, y, color=THESIS_COLOR, ls="--", label="linear (Eq 4.18)")
    ax.plot(1e3 * sim.t, np.degrees(sim.theta),
            label="24 V, 10 A, steady hinge moment (Table 16)")
    ax.axhspan(14 * 0.98, 14 * 1.02, color="0.9", label="2 % of command")
    ax.set(xlabel="time (ms)", ylabel="fin angle (deg)")
    ax.legend(loc="lower right")
    return fig


def fig_bode(ch: ServoChapter):
    fig, axes = new_figure("Bode plot, System 3: closed loop and forward path", "Fig 54",
                           nrows=2, figsize=(6.4, 6.0))
    w = np.logspace(0, 5, 600)
    for sys, lab in ((closed_loop(ch.params, SYSTEM_3), "closed loop (Eq 4.18)"),
                     (forward_path(ch.params, SYSTEM_3), "forward path (Eq 4.17)")):
        resp = ct.frequency_response(sys, w)
        mag = np.squeeze(resp.magnitude)
        phase = np.degrees(np.unwrap(np.squeeze(resp.phase)))
        axes[0].semilogx(w, 20 * np.log10(mag), label=lab)
        axes[1].semilogx(w, phase, label=lab)
    m = ch.system3_margins
    axes[1].axvline(m.gain_crossover, color="k", ls=":", lw=0.8)
    axes[1].set_title(f"phase margin {m.phase_margin_deg:.2f} deg at {m.gain_crossover:.0f} "
                      f"rad/s (thesis 78.4); gain margin {m.gain_margin_db} dB", fontsize=9)
    axes[0].set(ylabel="magnitude (dB)")
    axes[1].set(xlabel="frequency (rad/s)", ylabel="phase (deg)")
    axes[0].legend()
    return fig


def fig_reversal(ch: ServoChapter, what: str):
    num = {"position": "Fig 55", "rate": "Fig 56", "torque": "Fig 57"}[what]
    title = {"position": "angular position, -15 deg step from +15 deg (power limited)",
             "rate": "angular velocity, power-limited System 3",
             "torque": "applied torque at the fin (K_t I N eta), power-limited System 3"}[what]
    fig, ax = new_figure(title, num)
    for sim, lab, style in ((ch.reversal, "+15 -> 0 deg (asekit's reading)", "-"),
                            (ch.full_reversal, "+15 -> -15 deg", ":")):
        y = {"position": np.degrees(sim.theta), "rate": np.degrees(sim.omega),
             "torque": sim.torque}[what]
        ax.plot(1e3 * sim.t, y, ls=style, label=lab)
    if what == "rate":
        ax.axhline(-500, color=THESIS_COLOR, ls="--", label="thesis about 500 deg/s")
    if what == "torque":
        ax.axhline(-6.6, color=THESIS_COLOR, ls="--", label="thesis about 6.6 N m")
    if what == "position":
        ax.axvline(50, color="k", lw=0.8, ls=":")
    ax.set(xlabel="time (ms)", ylabel={"position": "fin angle (deg)",
                                       "rate": "angular velocity (deg/s)",
                                       "torque": "torque (N m)"}[what])
    ax.legend()
    return fig
