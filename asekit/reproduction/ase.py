"""Thesis Ch. 5 (aeroservoelasticity): computed quantities and figures (Figs 63-84).

:func:`compute` builds the fin's aeroservoelastic model at Mach 0.5, sea level (asekit's own
structure, DLM GAFs and Roger fit; the thesis's System 3 PD design) and runs every Ch. 5
analysis; :func:`run` turns it into the reproduce rows; the ``fig_*`` functions draw the thesis
figures (the chapter notebook calls them too).

Definitions used for the reported numbers:

* resonances of OPLOOP 3: the first two local maxima of |OPLOOP 3| above 10 Hz;
* FWTF phase margins and crossovers: at the first (lowest) gain crossover; FWTF 3's gain margin:
  at its first phase crossover (it has several), the thesis's reading of Fig 68;
* Nyquist margins (:func:`asekit.ase.margins.nyquist_margins`): the open-loop right-half-plane poles
  are counted (OPLOOP 2/3 and FWTF 2/3 have one, about +15.5 rad/s, from the de-centering hinge
  moment), so FWTF 2's lower gain margin (at zero frequency, where L(0) < 0) is found; the
  upper and lower gain margins bound the range of loop gain with a stable closed loop;
* AEM1 settling time: the transmission angle's 2 % band around its final value, power-limited
  unit (1 deg) step; corner overshoot: peak pitch rotation at the four planform corners past the
  command, as a fraction of the command (min and max over the corners); static elastic
  deflection: the closed loop's exact DC gain to the corner rotations minus one (max over the
  corners);
* spectrum peaks: the two largest peaks of the fin-root angle's spectrum after it first reaches
  95 % of the command, mean removed (Fig 73);
* AEM2 limit cycle: half the peak-to-peak fin-root angle and its zero-crossing frequency over the
  last 50 ms of a 0.3 s power-limited unit step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.ase import loop as ase
from asekit.ase import metrics
from asekit.ase.margins import NyquistMargins, nyquist_margins
from asekit.case import pipeline
from asekit.reproduction import afs as afs_study
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import CORNERS, fin_case
from asekit.servo.actuator import SYSTEM_3, PDController
from asekit.servo.simulate import THESIS_LIMITS, SimulationResult, simulate
from asekit.util.plotting import THESIS_COLOR, new_figure

#: Thesis Table 2 requirements checked on the elastic fin.
SETTLING_REQUIREMENT = 0.05      # s
ERROR_REQUIREMENT = 0.02         # fraction
UNIT_STEP = math.radians(1.0)
FULL_STEP = math.radians(15.0)


@dataclass(frozen=True)
class AseChapter:
    """Every computed Ch. 5 result (SI units)."""

    fin: pipeline.AseCondition
    controller: PDController
    oploops: dict                 # 1, 2, 3 -> StateSpace
    fwtfs: dict                   # 1, 2, 3 -> StateSpace
    crossovers: dict              # 1, 2, 3 -> Crossovers
    nyquist: dict                 # 1, 2, 3 -> NyquistMargins of FWTF i
    oploop3_resonances_hz: np.ndarray
    closed_loops: dict            # "AEM1", "AEM2" -> StateSpace
    aem1_linear: ase.AseSimulation
    aem1_nonlinear: ase.AseSimulation
    aem1_full: ase.AseSimulation
    aem2_linear: ase.AseSimulation
    aem2_nonlinear: ase.AseSimulation
    rigid_unit: SimulationResult  # the Ch. 4 design model (rigid fin, steady hinge moment)
    rigid_full: SimulationResult
    static_gains: dict            # AEM1 DC gains to the corner / root rotations
    aem1_spectrum: tuple
    aem2_spectrum: tuple
    aem2_limit_cycle: tuple       # (amplitude rad, frequency Hz)


def compute(mach: float = 0.5, altitude: float = 0.0,
            controller: PDController = SYSTEM_3) -> AseChapter:
    """Run the Ch. 5 analyses (a few seconds)."""
    fin = pipeline.ase_condition(fin_case(), mach=mach, altitude=altitude)
    m = fin.model
    oploops = {i: ase.open_loop(m, i) for i in (1, 2, 3)}
    fwtfs = {i: ase.forward_path(m, controller, i) for i in (1, 2, 3)}
    cross = {i: ase.crossovers(fwtfs[i]) for i in (1, 2, 3)}
    nyq = {i: nyquist_margins(fwtfs[i]) for i in (1, 2, 3)}
    loops = {t: ase.closed_loop(m, controller, t) for t in ase.TOPOLOGIES}
    sim = ase.simulate_closed_loop
    aem1_lin = sim(m, controller, UNIT_STEP, "AEM1", limits=None, t_final=0.2)
    aem1_nl = sim(m, controller, UNIT_STEP, "AEM1", limits=THESIS_LIMITS, t_final=0.2)
    aem1_full = sim(m, controller, FULL_STEP, "AEM1", limits=THESIS_LIMITS, t_final=0.2)
    aem2_lin = sim(m, controller, UNIT_STEP, "AEM2", limits=None, t_final=0.1)
    aem2_nl = sim(m, controller, UNIT_STEP, "AEM2", limits=THESIS_LIMITS, t_final=0.3)
    rigid = fin.rigid_fin_actuator()
    hm = fin.steady_hinge_moment()
    rigid_unit = simulate(rigid, controller, UNIT_STEP, t_final=0.2, limits=THESIS_LIMITS,
                          hinge_moment=hm)
    rigid_full = simulate(rigid, controller, FULL_STEP, t_final=0.2, limits=THESIS_LIMITS,
                          hinge_moment=hm)
    corner_names = [f"theta_{c}" for c in CORNERS]
    gains = ase.static_gains(loops["AEM1"], ["theta", ase.FIN_ROOT] + corner_names)
    spec1 = metrics.spectrum_after_rise(aem1_nl.t, aem1_nl.fin_root, UNIT_STEP)
    spec2 = metrics.spectrum_after_rise(aem2_nl.t, aem2_nl.fin_root, UNIT_STEP)
    return AseChapter(
        fin=fin, controller=controller, oploops=oploops, fwtfs=fwtfs, crossovers=cross,
        nyquist=nyq,
        oploop3_resonances_hz=ase.resonances(oploops[3]), closed_loops=loops,
        aem1_linear=aem1_lin, aem1_nonlinear=aem1_nl, aem1_full=aem1_full,
        aem2_linear=aem2_lin, aem2_nonlinear=aem2_nl, rigid_unit=rigid_unit,
        rigid_full=rigid_full, static_gains=gains, aem1_spectrum=spec1, aem2_spectrum=spec2,
        aem2_limit_cycle=metrics.limit_cycle(aem2_nl.t, aem2_nl.fin_root))


def corner_overshoots(ch: AseChapter) -> dict:
    """Overshoot (fraction) of each corner rotation in the power-limited AEM1 unit step."""
    r = ch.aem1_nonlinear
    return {c: metrics.overshoot(r.outputs[f"theta_{c}"], UNIT_STEP) for c in CORNERS}


def requirement_table(ch: AseChapter) -> list[tuple[str, str, str, bool]]:
    """Thesis Table 2 checked on the elastic fin (AEM1, power-limited unit step): rows of
    (requirement, limit, asekit value, pass)."""
    r = ch.aem1_nonlinear
    rows = []
    st = metrics.settling_time(r.t, r.theta, r.theta[-1], UNIT_STEP)
    rows.append(("settling time, transmission", "< 50 ms", f"{st * 1e3:.1f} ms",
                 st < SETTLING_REQUIREMENT))
    st_root = metrics.settling_time(r.t, r.fin_root, r.fin_root[-1], UNIT_STEP)
    rows.append(("settling time, fin root", "< 50 ms", f"{st_root * 1e3:.1f} ms",
                 st_root < SETTLING_REQUIREMENT))
    for name in ["theta", ase.FIN_ROOT] + [f"theta_{c}" for c in CORNERS]:
        err = abs(ch.static_gains[name] - 1.0)
        rows.append((f"steady error, {name}", "< 2 %", f"{100 * err:.2f} %",
                     err < ERROR_REQUIREMENT))
    ov = corner_overshoots(ch)
    rows.append(("overshoot at the corners", "none (Ch. 4 design: 0 %)",
                 f"{100 * min(ov.values()):.0f}-{100 * max(ov.values()):.0f} %",
                 max(ov.values()) < 0.005))
    rows.append(("max voltage", "<= 24 V", f"{np.max(np.abs(r.voltage)):.1f} V",
                 np.max(np.abs(r.voltage)) <= 24.0 + 1e-9))
    rows.append(("max current", "<= 10 A", f"{np.max(np.abs(r.current)):.2f} A",
                 np.max(np.abs(r.current)) <= 10.0 + 1e-9))
    return rows


def quantities(ch: AseChapter) -> tuple[Quantity, ...]:
    c1, c2, c3 = ch.crossovers[1], ch.crossovers[2], ch.crossovers[3]
    r = ch.aem1_nonlinear
    ov = corner_overshoots(ch)
    corner_gain = [ch.static_gains[f"theta_{c}"] for c in CORNERS]
    peaks1 = metrics.spectrum_peaks(*ch.aem1_spectrum, n=2)
    amp, freq = ch.aem2_limit_cycle
    note_struct = "asekit 6x7 MITC4 modes + own DLM, M 0.5 sea level"
    return (
        Quantity("ase.oploop3.resonances_hz", [float(f) for f in ch.oploop3_resonances_hz[:2]],
                 "Hz", note_struct),
        Quantity("ase.fwtf1.phase_margin_deg", float(c1.phase_margins_deg[0]), "deg",
                 "actuator with the fin's inertia carried by the hinge moment"),
        Quantity("ase.fwtf1.crossover_hz", float(c1.gain_crossovers_hz[0]), "Hz"),
        Quantity("ase.fwtf2.phase_margin_deg", float(c2.phase_margins_deg[0]), "deg",
                 "first gain crossover"),
        Quantity("ase.fwtf2.crossover_hz", float(c2.gain_crossovers_hz[0]), "Hz"),
        Quantity("ase.fwtf3.gain_margin_db", float(c3.gain_margin_db), "dB",
                 "first phase crossover"),
        Quantity("ase.fwtf2.open_loop_unstable_poles", ch.nyquist[2].open_loop_unstable_poles,
                 "-", "pole at +%.1f rad/s (de-centering hinge moment)"
                 % float(ch.nyquist[2].open_loop_rhp_poles.real.max())),
        Quantity("ase.fwtf2.lower_gain_margin_db", ch.nyquist[2].lower_gain_margin_db, "dB",
                 "Nyquist, at 0 Hz (L(0) < 0)"),
        Quantity("ase.fwtf2.upper_gain_margin_db", ch.nyquist[2].upper_gain_margin_db, "dB",
                 "Nyquist"),
        Quantity("ase.fwtf3.closed_loop_unstable_poles",
                 ch.nyquist[3].closed_loop_unstable_poles, "-", "AEM2 linear loop, Nyquist"),
        Quantity("ase.aem1.settling_ms",
                 1e3 * metrics.settling_time(r.t, r.theta, r.theta[-1], UNIT_STEP), "ms",
                 "transmission output, power-limited 1 deg step"),
        Quantity("ase.aem1.corner_overshoot_pct",
                 [100 * min(ov.values()), 100 * max(ov.values())], "%", "min, max of 4 corners"),
        Quantity("ase.aem1.static_elastic_deflection_pct",
                 100 * (max(corner_gain) - 1.0), "%", "largest corner, exact DC gain"),
        Quantity("ase.aem1.spectrum_peaks_hz", [float(f) for f in peaks1], "Hz"),
        Quantity("ase.aem2.linear_stable", ase.is_stable(ch.closed_loops["AEM2"]), "-"),
        Quantity("ase.aem2.lco_freq_hz", freq, "Hz", "power-limited 1 deg step"),
        Quantity("ase.aem2.lco_amplitude_deg", math.degrees(amp), "deg",
                 "half peak-to-peak at the fin root"),
    )


def run(figures: bool = False) -> ChapterResult:
    ch = compute()
    study = afs_study.compute()                     # issue 26: active flutter suppression
    figs = all_figures(ch) if figures else {}
    if figures:
        figs["afs_root_locus"] = afs_study.fig_root_locus(study)
    return ChapterResult("ase", tuple(quantities(ch)) + tuple(afs_study.quantities(study)), figs)


def all_figures(ch: AseChapter) -> dict:
    return {
        "fig63_oploop_bode": fig_bode(ch, "oploop"),
        "fig64_oploop3_resonances": fig_oploop3_zoom(ch),
        "fig65_fwtf1_bode": fig_fwtf(ch, 1),
        "fig66_fwtf2_outputs": fig_fwtf2_outputs(ch),
        "fig67_fwtf2_bode": fig_fwtf(ch, 2),
        "fig68_fwtf3_bode": fig_fwtf(ch, 3),
        "fig69_fwtf_bode": fig_bode(ch, "fwtf"),
        "fig70_aem1_transmission": fig_aem1_transmission(ch),
        "fig71_aem1_corners": fig_corners(ch),
        "fig72_corner_locations": fig_corner_locations(ch),
        "fig73_aem1_spectrum": fig_spectrum(ch, "AEM1"),
        "fig74_aem1_modal": fig_modal(ch, "AEM1"),
        "fig75_aem1_hinge_moment": fig_hinge_moment(ch),
        "fig76_aem1_15deg": fig_full_step(ch),
        "fig77_78_aem1_voltage_current": fig_voltage_current(ch, "AEM1"),
        "fig79_aem2_linear": fig_aem2(ch, linear=True),
        "fig80_aem2_limit_cycle": fig_aem2(ch, linear=False),
        "fig81_aem2_spectrum": fig_spectrum(ch, "AEM2"),
        "fig82_aem2_modal": fig_modal(ch, "AEM2"),
        "fig83_84_aem2_voltage_current": fig_voltage_current(ch, "AEM2"),
    }


# ---------------------------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------------------------
_F = np.logspace(0, np.log10(3000.0), 4000)


def _bode_axes(axes, sys, label, **kw):
    h = ase.frequency_response(sys, _F)
    axes[0].semilogx(_F, 20 * np.log10(np.abs(h)), label=label, **kw)
    axes[1].semilogx(_F, np.degrees(np.unwrap(np.angle(h))), label=label, **kw)


def fig_bode(ch: AseChapter, which: str):
    """Fig 63 (OPLOOP 1-3) or Fig 69 (FWTF 1-3)."""
    systems = ch.oploops if which == "oploop" else ch.fwtfs
    name = "OPLOOP" if which == "oploop" else "FWTF"
    fig, ax = new_figure(f"{name} 1/2/3, M {ch.fin.mach:g}, h {ch.fin.altitude:g} m",
                         "Fig 63" if which == "oploop" else "Fig 69", nrows=2,
                         figsize=(7.5, 6.5), sharex=True)
    for i, sys in systems.items():
        _bode_axes(ax, sys, f"{name} {i}", lw=1.2)
    ax[0].set_ylabel("magnitude (dB)")
    ax[1].set_ylabel("phase (deg)")
    ax[1].set_xlabel("frequency (Hz)")
    if which == "fwtf":
        ax[0].axhline(0.0, color=THESIS_COLOR, lw=0.8)
        c = ch.crossovers
        ax[0].set_title(f"PM: FWTF1 {c[1].phase_margins_deg[0]:.1f} deg at "
                        f"{c[1].gain_crossovers_hz[0]:.0f} Hz, FWTF2 "
                        f"{c[2].phase_margins_deg[0]:.1f} deg at {c[2].gain_crossovers_hz[0]:.0f}"
                        f" Hz; FWTF3 GM {c[3].gain_margin_db:.1f} dB", fontsize=9)
    ax[0].legend()
    return fig


_FWTF_FIGURE = {1: "Fig 65", 2: "Fig 67", 3: "Fig 68"}


def _margin_text(m: NyquistMargins) -> str:
    """One line: open-loop RHP poles, closed-loop stability and the Nyquist gain margins."""
    head = (f"P = {m.open_loop_unstable_poles} open-loop RHP pole(s); closed loop "
            + ("stable" if m.closed_loop_stable else
               f"UNSTABLE ({m.closed_loop_unstable_poles} RHP poles)"))
    if not m.closed_loop_stable:
        ranges = [(lo, hi) for lo, hi, z in zip(np.r_[0.0, m.boundary_gains],
                                                 np.r_[m.boundary_gains, np.inf],
                                                 m.unstable_counts) if z == 0]
        txt = ", ".join(f"{20 * np.log10(lo):.1f} to {20 * np.log10(hi):.1f} dB"
                        for lo, hi in ranges if lo > 0 and np.isfinite(hi))
        return head + (f"; stable for gains {txt}" if txt else "")
    return (head + f"; GM {m.lower_gain_margin_db:.1f} / +{m.upper_gain_margin_db:.1f} dB, "
            f"PM {m.phase_margin_deg:.1f} deg")


def fig_fwtf(ch: AseChapter, which: int):
    """Figs 65, 67, 68: Bode plot of FWTF ``which`` with its gain crossovers (phase margins),
    its phase crossovers (gain margins), the -180 deg lines and the Nyquist margins."""
    names = {1: "actuator + PD (Ch. 4 loop)", 2: "AEM1, transmission feedback",
             3: "AEM2, fin-root feedback"}
    fig, ax = new_figure(f"FWTF {which} ({names[which]}), M {ch.fin.mach:g}, "
                         f"h {ch.fin.altitude:g} m", _FWTF_FIGURE[which], nrows=2,
                         figsize=(7.5, 6.5), sharex=True)
    h = ase.frequency_response(ch.fwtfs[which], _F)
    mag = 20 * np.log10(np.abs(h))
    ph = np.degrees(np.unwrap(np.angle(h)))
    ax[0].semilogx(_F, mag, color=f"C{which - 1}")
    ax[1].semilogx(_F, ph, color=f"C{which - 1}")
    ax[0].axhline(0.0, color="k", lw=0.8)
    for n in range(int(np.floor((ph.min() + 180) / 360)), int(np.ceil((ph.max() + 180) / 360)) + 1):
        ax[1].axhline(-180.0 + 360.0 * n, color="k", lw=0.8, ls="--")
    m = ch.nyquist[which]
    for n_gc, (fc, pm) in enumerate(zip(m.gain_crossovers_hz, m.phase_margins_deg)):
        ax[0].plot(fc, 0.0, "o", color="C3", ms=5)
        p = np.interp(np.log(fc), np.log(_F), ph)
        ax[1].plot(fc, p, "o", color="C3", ms=5)
        if n_gc < 3:                 # the first three labelled; the rest marked only
            ax[1].annotate(f"PM {pm:.1f}$^\\circ$\n{fc:.0f} Hz", (fc, p),
                           textcoords="offset points", xytext=(4, 4 - 14 * n_gc), fontsize=7,
                           color="C3")
    inside = [(fc, gm) for fc, gm in zip(m.phase_crossovers_hz, m.gain_margins_db)
              if _F[0] <= fc <= _F[-1]]       # at 0 Hz or infinity: in the title
    for n_pc, (fc, gm) in enumerate(inside):
        g = np.interp(np.log(fc), np.log(_F), mag)
        ax[0].plot([fc, fc], [0.0, g], color="C2", lw=1.2)
        if n_pc < 3:
            ax[0].annotate(f"GM {gm:.1f} dB", (fc, g), textcoords="offset points",
                           xytext=(3, -9 if gm > 0 else 3), fontsize=7, color="C2")
    ax[0].set_ylabel("magnitude (dB)")
    ax[1].set_ylabel("phase (deg)")
    ax[1].set_xlabel("frequency (Hz)")
    ax[0].set_title(_margin_text(m), fontsize=8)
    return fig


def fig_fwtf2_outputs(ch: AseChapter):
    """Fig 66: FWTF 2 to the transmission's angle, rate and acceleration (the three outputs fed
    to the aeroelastic fin): PD x OPLOOP 2 times 1, j w, (j w)^2 (omega = theta', alpha =
    theta'' exactly in the actuator's state space)."""
    fig, ax = new_figure(f"FWTF 2 to the transmission angle, rate and acceleration, M "
                         f"{ch.fin.mach:g}, h {ch.fin.altitude:g} m", "Fig 66", nrows=2,
                         figsize=(7.5, 6.5), sharex=True)
    h = ase.frequency_response(ch.fwtfs[2], _F)
    jw = 2j * np.pi * _F
    for factor, lab in ((1.0, "angle (rad/rad)"), (jw, "rate (rad/s per rad)"),
                        (jw ** 2, "acceleration (rad/s$^2$ per rad)")):
        hh = h * factor
        ax[0].semilogx(_F, 20 * np.log10(np.abs(hh)), label=lab)
        ax[1].semilogx(_F, np.degrees(np.unwrap(np.angle(hh))), label=lab)
    ax[0].set_ylabel("magnitude (dB)")
    ax[1].set_ylabel("phase (deg)")
    ax[1].set_xlabel("frequency (Hz)")
    ax[0].legend(fontsize=8)
    return fig


def fig_oploop3_zoom(ch: AseChapter):
    fig, ax = new_figure("OPLOOP 3 resonances (thesis: 89.1, 152 Hz)", "Fig 64")
    f = np.linspace(40.0, 250.0, 3000)
    h = ase.frequency_response(ch.oploops[3], f)
    ax.plot(f, 20 * np.log10(np.abs(h)))
    for fr in ch.oploop3_resonances_hz[:2]:
        ax.axvline(fr, color=THESIS_COLOR, ls="--", lw=0.8)
        ax.annotate(f"{fr:.1f} Hz", (fr, ax.get_ylim()[1]), va="top", fontsize=8)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("|OPLOOP 3| (dB rad/V)")
    return fig


def fig_aem1_transmission(ch: AseChapter):
    fig, ax = new_figure("AEM1 unit step: transmission output", "Fig 70")
    for r, lab in ((ch.aem1_linear, "linear"), (ch.aem1_nonlinear, "power limited")):
        ax.plot(1e3 * r.t, np.degrees(r.theta), label=lab)
    ax.axhline(1.0, color=THESIS_COLOR, lw=0.8, ls=":")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("transmission angle (deg)")
    ax.legend()
    return fig


def fig_corners(ch: AseChapter):
    fig, ax = new_figure("AEM1 unit step (power limited): fin corners vs rigid fin", "Fig 71")
    r = ch.aem1_nonlinear
    for c in CORNERS:
        ax.plot(1e3 * r.t, np.degrees(r.outputs[f"theta_{c}"]), lw=1.0, label=c.replace("_", " "))
    ax.plot(1e3 * r.t, np.degrees(r.fin_root), "k", lw=1.0, label="fin root")
    ax.plot(1e3 * ch.rigid_unit.t, np.degrees(ch.rigid_unit.theta), color="g", lw=2,
            label="rigid fin, steady hinge moment (Ch. 4 model)")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("pitch rotation (deg)")
    ax.legend(fontsize=8)
    return fig


def fig_corner_locations(ch: AseChapter):
    """Fig 72: where the fin-corner rotations of Fig 71 are taken (planform corners), the fin
    root and the pitch axis."""
    case = fin_case()
    p = case.panels[0].planform
    fig, ax = new_figure("Fin positions of Fig 71", "Fig 72", figsize=(5.5, 5))
    c = np.asarray(p.corners) * 1e3
    ax.fill(c[:, 0], c[:, 1], color="0.9", edgecolor="k")
    for name, (xi, eta) in CORNERS.items():
        pt = np.asarray(p.point(np.array([xi]), np.array([eta])))[0] * 1e3
        ax.plot(pt[0], pt[1], "o", color="C3")
        ax.annotate(name.replace("_", " "), pt[:2], textcoords="offset points",
                    xytext=(6 if xi > 0.5 else -6, 6), ha="left" if xi > 0.5 else "right",
                    fontsize=8, color="C3")
    xa = case.support.axis_point[0] * 1e3
    ax.axvline(xa, color="C0", ls="--", lw=1, label=f"pitch axis x = {xa:g} mm")
    ax.plot(xa, 0.0, "s", color="C0", label="fin root (shaft)")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="upper left")
    return fig


def fig_spectrum(ch: AseChapter, topology: str):
    f, amp = ch.aem1_spectrum if topology == "AEM1" else ch.aem2_spectrum
    fig, ax = new_figure(f"{topology}: fin-root spectrum after 95 % rise, mean removed",
                         "Fig 73" if topology == "AEM1" else "Fig 81")
    sel = f <= 1000
    ax.plot(f[sel], np.degrees(amp[sel]))
    for n, p in enumerate(metrics.spectrum_peaks(f, amp, n=2)):
        a_p = float(np.degrees(np.interp(p, f, amp)))
        ax.plot(p, a_p, "v", color="C3", ms=6)
        ax.annotate(f"{p:.1f} Hz", (p, a_p), textcoords="offset points",
                    xytext=(8, 2 - 12 * n), fontsize=8, color="C3")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("amplitude (deg)")
    return fig


def fig_modal(ch: AseChapter, topology: str):
    r = ch.aem1_nonlinear if topology == "AEM1" else ch.aem2_nonlinear
    fig, ax = new_figure(f"{topology} unit step (power limited): elastic generalised coordinates",
                         "Fig 74" if topology == "AEM1" else "Fig 82")
    for name in (n for n in r.outputs if n.startswith("zeta")):
        ax.plot(1e3 * r.t, r.outputs[name], lw=1.0, label=name)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("modal coordinate (kg$^{1/2}$ m)")
    ax.legend(fontsize=8)
    return fig


def fig_hinge_moment(ch: AseChapter):
    r = ch.aem1_nonlinear
    fig, ax = new_figure("AEM1 unit step: hinge moment, aeroelastic vs steady estimate", "Fig 75")
    ax.plot(1e3 * r.t, r.outputs["hinge_moment"], label="aeroelastic (Eq. 2.68)")
    ax.plot(1e3 * r.t, ch.fin.dynamic_pressure * ch.fin.q_cc * r.theta, label="q Q_cc theta")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("hinge moment (N m)")
    ax.legend()
    return fig


def fig_full_step(ch: AseChapter):
    """Fig 76: +15 deg step; the rigid-fin curve is drawn first (wide, light) so that the
    elastic transmission output on top of it stays visible where they coincide."""
    fig, ax = new_figure("AEM1 +15 deg step: transmission output", "Fig 76")
    ax.plot(1e3 * ch.rigid_full.t, np.degrees(ch.rigid_full.theta), color="g", lw=4, alpha=0.4,
            label="rigid fin (Ch. 4 model)")
    ax.plot(1e3 * ch.aem1_full.t, np.degrees(ch.aem1_full.theta), color="C0",
            label="transmission, elastic fin, power limited")
    ax.plot(1e3 * ch.aem1_full.t, np.degrees(ch.aem1_full.fin_root), color="C1", ls="--",
            label="fin root, elastic fin")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("angle (deg)")
    ax.legend()
    return fig


def fig_voltage_current(ch: AseChapter, topology: str):
    runs = ([(ch.aem1_nonlinear, "1 deg"), (ch.aem1_full, "15 deg")] if topology == "AEM1"
            else [(ch.aem2_nonlinear, "1 deg")])
    fig, ax = new_figure(f"{topology} (power limited): voltage and current",
                         "Figs 77-78" if topology == "AEM1" else "Figs 83-84", nrows=2,
                         sharex=True, figsize=(7.0, 6.0))
    for r, lab in runs:
        ax[0].plot(1e3 * r.t, r.voltage, label=lab)
        ax[1].plot(1e3 * r.t, r.current, label=lab)
    ax[0].set_ylabel("voltage (V)")
    ax[1].set_ylabel("current (A)")
    ax[1].set_xlabel("time (ms)")
    ax[0].legend()
    return fig


def fig_aem2(ch: AseChapter, linear: bool):
    r = ch.aem2_linear if linear else ch.aem2_nonlinear
    fig, ax = new_figure("AEM2 unit step, " + ("linear (unstable)" if linear else
                                              "power limited (limit cycle)"),
                         "Fig 79" if linear else "Fig 80")
    ax.plot(1e3 * r.t, np.degrees(r.fin_root), label="fin root")
    ax.plot(1e3 * r.t, np.degrees(r.theta), lw=1.0, label="transmission")
    if linear:
        ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("angle (deg)")
    ax.legend()
    return fig
