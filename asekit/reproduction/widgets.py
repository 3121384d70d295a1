"""Interactive ipywidgets panels for the notebooks.

:func:`servo_panel` shows the PD design of thesis Sec. 4.3 live: sliders for K_c, K_P, K_D and
the supply-voltage limit redraw the 14 deg step response (linear Eq. 4.18 and power limited),
the closed-loop poles and the forward-path margins. The numbers behind the drawing come from
:func:`servo_snapshot`, a plain function. The panel builds without a front-end (the widgets
then simply are not displayed), so notebooks run under nbval and in a plain Python session.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass

import numpy as np

from asekit.ase import loop as ase
from asekit.ase.margins import NyquistMargins, nyquist_margins
from asekit.case import pipeline
from asekit.reproduction.fin import CORNERS, fin_case
from asekit.servo.actuator import (
    SYSTEM_3,
    ActuatorParameters,
    Margins,
    PDController,
    closed_loop_poles,
    margins,
    step_response,
)
from asekit.servo.simulate import PowerLimits, SimulationResult, SteadyHingeMoment, simulate
from asekit.util.plotting import THESIS_COLOR, new_figure


@dataclass(frozen=True)
class ServoSnapshot:
    """What the panel shows for one set of gains: ``poles`` (rad/s), ``margins``, ``stable``,
    the linear step (``t_linear`` s, ``theta_linear`` rad) and the power-limited ``simulation``
    (None when the loop is unstable)."""

    controller: PDController
    poles: np.ndarray
    stable: bool
    margins: Margins
    t_linear: np.ndarray
    theta_linear: np.ndarray
    simulation: SimulationResult | None


def servo_snapshot(gain: float, kp: float, kd: float, supply_voltage: float = 24.0,
                   command: float = math.radians(14.0), t_final: float = 0.08,
                   params: ActuatorParameters | None = None,
                   hinge_moment: SteadyHingeMoment | None = None) -> ServoSnapshot:
    """Poles, margins, linear and power-limited step for PD gains (SI; command in rad)."""
    params = ActuatorParameters() if params is None else params
    ctrl = PDController(gain, kp, kd, name="panel")
    poles = closed_loop_poles(params, ctrl, require_stable=False)
    stable = bool(np.all(np.real(poles) < 0))
    t, y = step_response(params, ctrl, t_final=t_final, amplitude=command, n=801)
    sim = None
    if stable:
        sim = simulate(params, ctrl, command, t_final=t_final, n_out=801,
                       limits=PowerLimits(supply_voltage=supply_voltage),
                       hinge_moment=hinge_moment)
    return ServoSnapshot(ctrl, poles, stable, margins(params, ctrl), t, y, sim)


def _draw(snap: ServoSnapshot, supply_voltage: float):
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = new_figure(
        f"K_c {snap.controller.gain:g}, K_P {snap.controller.kp:g}, K_D {snap.controller.kd:g}",
        "Figs 50-54 (live)", ncols=2, figsize=(11, 4))
    ax1.plot(1e3 * snap.t_linear, np.degrees(snap.theta_linear), color=THESIS_COLOR, ls="--",
             label="linear (Eq 4.18)")
    if snap.simulation is not None:
        s = snap.simulation
        ax1.plot(1e3 * s.t, np.degrees(s.theta), label=f"{supply_voltage:g} V, hinge moment")
        ax1.set_title(f"settling {1e3 * s.settling_time():.1f} ms, "
                      f"error {100 * s.steady_error:.2f} %", fontsize=9)
    else:
        ax1.set_title("unstable loop: no nonlinear simulation", fontsize=9, color="C3")
    ax1.set(xlabel="time (ms)", ylabel="fin angle (deg)")
    ax1.legend(loc="lower right")
    p = snap.poles
    ax2.plot(np.real(p), np.imag(p), "x", ms=9)
    ax2.axvline(-628.32, color="k", ls=":", lw=0.8)
    m = snap.margins
    ax2.set_title(f"PM {m.phase_margin_deg:.1f} deg, GM {m.gain_margin_db:.1f} dB", fontsize=9)
    ax2.set(xlabel="real (rad/s)", ylabel="imaginary (rad/s)", xscale="symlog")
    plt.show()
    return fig


def _pd_sliders(controller: PDController) -> dict:
    """Sliders for K_c, K_P, K_D starting at ``controller``'s gains (released-value updates)."""
    import ipywidgets as w

    return {
        "gain": w.FloatSlider(value=controller.gain, min=0.5, max=30.0, step=0.5,
                              description="K_c", continuous_update=False),
        "kp": w.FloatSlider(value=controller.kp, min=10.0, max=600.0, step=5.0,
                            description="K_P", continuous_update=False),
        "kd": w.FloatSlider(value=controller.kd, min=0.0, max=3.0, step=0.05,
                            description="K_D", continuous_update=False),
    }


def _panel(sliders: dict, out, redraw, per_row: int):
    """Wire ``redraw`` to every slider, lay the sliders out ``per_row`` to a row above the
    output area, draw once, and return the VBox (with ``.redraw`` and ``.sliders``)."""
    import ipywidgets as w

    for s in sliders.values():
        s.observe(redraw, names="value")
    items = list(sliders.values())
    rows = [w.HBox(items[i:i + per_row]) for i in range(0, len(items), per_row)]
    panel = w.VBox(rows + [out])
    panel.redraw = redraw
    panel.sliders = sliders
    redraw()
    return panel


def servo_panel(controller: PDController = SYSTEM_3, supply_voltage: float = 24.0,
                params: ActuatorParameters | None = None,
                hinge_moment: SteadyHingeMoment | None = None):
    """An ipywidgets panel: sliders K_c, K_P, K_D, supply voltage; redraws step, poles, margins.

    Returns the ``ipywidgets.VBox``; display it in a notebook (a bare last-line expression).
    Constructing it needs no front-end. The drawn figure is redrawn on every slider release.
    """
    import ipywidgets as w

    sliders = {
        **_pd_sliders(controller),
        "supply_voltage": w.FloatSlider(value=supply_voltage, min=6.0, max=60.0, step=1.0,
                                        description="V limit", continuous_update=False),
    }
    out = w.Output()

    def redraw(*_):
        vals = {k: s.value for k, s in sliders.items()}
        snap = servo_snapshot(vals["gain"], vals["kp"], vals["kd"], vals["supply_voltage"],
                              params=params, hinge_moment=hinge_moment)
        out.clear_output(wait=True)
        with out:
            _draw(snap, vals["supply_voltage"])
        return snap

    return _panel(sliders, out, redraw, per_row=2)


# ---------------------------------------------------------------------------------------------
# Ch. 5: controller design with the elastic fin in the loop
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AseSnapshot:
    """What the Ch. 5 panel shows: the forward path ``fwtf`` (FWTF 2 for AEM1, FWTF 3 for
    AEM2), its Bode ``crossovers`` and its Nyquist count ``nyquist`` (open-loop right-half-plane
    poles, encirclements, gain margins: :func:`asekit.ase.margins.nyquist_margins`), closed-loop
    ``stable``, the linear unit step of the elastic fin (``t`` s, ``outputs`` name -> rad:
    transmission, fin root, corners) and of the rigid-fin design model (``theta_rigid``,
    Eq. 4.18 with the fin's J_fin)."""

    controller: PDController
    topology: str
    mach: float
    altitude: float
    fwtf: object
    crossovers: object
    nyquist: NyquistMargins
    stable: bool
    t: np.ndarray
    outputs: dict
    theta_rigid: np.ndarray


def ase_snapshot(gain: float, kp: float, kd: float, mach: float = 0.5, altitude: float = 0.0,
                 topology: str = "AEM1", t_final: float = 0.1, fin=None) -> AseSnapshot:
    """Forward path, margins and the linear closed-loop unit step of the elastic fin for PD
    gains at (mach, altitude) (SI; altitude in m). ``fin``: a prebuilt
    :class:`asekit.case.pipeline.AseCondition` to reuse (else built with
    :func:`asekit.case.pipeline.ase_condition` on the fin's case)."""
    import control as ct


    ctrl = PDController(gain, kp, kd, name="panel")
    fin = pipeline.ase_condition(fin_case(), mach=mach, altitude=altitude) if fin is None else fin
    which = 2 if topology == "AEM1" else 3
    fwtf = ase.forward_path(fin.model, ctrl, which)
    names = ["theta", ase.FIN_ROOT] + [f"theta_{c}" for c in CORNERS]
    cl = ase.closed_loop(fin.model, ctrl, topology, outputs=names)
    t = np.linspace(0.0, t_final, 1001)
    y = np.asarray(ct.forced_response(cl, t, np.ones_like(t)).outputs)
    _, theta_rigid = step_response(fin.rigid_fin_actuator(), ctrl, t_final=t_final,
                                   amplitude=1.0, n=t.size)
    return AseSnapshot(ctrl, topology, float(mach), float(altitude), fwtf, ase.crossovers(fwtf),
                       nyquist_margins(fwtf), ase.is_stable(cl), t, dict(zip(names, y)),
                       np.asarray(theta_rigid))


def _db(value: float | None) -> str:
    """A gain margin in dB for the readout ("none" for None, "+inf"/"-inf" kept)."""
    return "none" if value is None else f"{value:+.1f} dB"


def _describe_rhp(poles) -> str:
    """The open-loop right-half-plane poles in words: a real one is static (the de-centering
    steady hinge moment), a complex pair an aeroelastic oscillation (flutter) at its frequency."""
    real = [p for p in poles if abs(p.imag) <= 1e-6 * max(1.0, abs(p))]
    pairs = [p for p in poles if p.imag > 1e-6 * max(1.0, abs(p))]
    parts = [f"{p.real:+.1f} rad/s, static: the fin's de-centering hinge moment" for p in real]
    parts += [f"{p.real:+.1f} +- {p.imag:.0f}j rad/s, flutter at {p.imag / (2 * math.pi):.1f} Hz"
              for p in pairs]
    return "; ".join(parts)


def ase_readout(snap: AseSnapshot, width: int = 110) -> str:
    """The Ch. 5 panel's stability readout: why the Bode margins and the closed-loop verdict
    agree (or seem not to), by the Nyquist criterion Z = P - N.

    P is the number of open-loop poles of the forward path in the right half plane, N the net
    counter-clockwise encirclements of -1 by its Nyquist curve and Z the closed-loop poles in the
    right half plane (Astrom & Murray, *Feedback Systems*, 2nd ed. 2021, Thm 10.3). With P > 0
    (the fin's de-centering steady hinge moment gives FWTF 2 a pole near +15 rad/s) a negative
    Bode phase margin does not mean instability: the loop is stable when N = P, and its gain
    margins are a lower and an upper bound on the loop gain (dB).

    Returns the readout, its lines wrapped at ``width`` characters (no trailing newline).
    """
    n = snap.nyquist
    name = f"FWTF{2 if snap.topology == 'AEM1' else 3}"
    P, Z = n.open_loop_unstable_poles, n.closed_loop_unstable_poles
    N = P - Z
    if P:
        head = (f"{name} open loop UNSTABLE: P = {P} right-half-plane pole{'s' if P > 1 else ''} "
                f"({_describe_rhp(n.open_loop_rhp_poles)}), so the Bode phase margin is no "
                "stability test.")
    else:
        head = f"{name} open loop stable (P = 0): the Bode margins apply as usual."
    verdict = "closed loop stable" if Z == 0 else f"closed loop UNSTABLE ({Z} poles in the RHP)"
    mid = (f"Nyquist: N = {N} counter-clockwise encirclement{'s' if abs(N) != 1 else ''} of -1, "
           f"Z = P - N = {Z}: {verdict}.")
    x = snap.crossovers
    bode = ", ".join(f"{pm:.1f} deg at {fc:.1f} Hz"
                     for fc, pm in zip(x.gain_crossovers_hz, x.phase_margins_deg))
    lines = [head, mid, f"Bode: |L| = 1 with phase margin {bode or 'none (no gain crossover)'};"
             " Bode reads the smallest; only N decides stability."]
    if Z == 0:
        lines.append(f"Stable for loop-gain changes from {_db(n.lower_gain_margin_db)} (lower gain "
                     f"margin) to {_db(n.upper_gain_margin_db)} (upper gain margin).")
    return "\n".join(textwrap.fill(line, width=width, subsequent_indent="  ") for line in lines)


def _draw_ase(snap: AseSnapshot):
    import matplotlib.pyplot as plt

    c = snap.controller
    fig, axes = new_figure(f"{snap.topology}, M {snap.mach:g}, h {snap.altitude:g} m, K_c {c.gain:g}"
                           f", K_P {c.kp:g}, K_D {c.kd:g}", "Figs 65-71 (live)", nrows=1, ncols=2,
                           figsize=(13, 5.2))
    ax1, ax2 = axes
    f = np.logspace(0, np.log10(3000.0), 3000)
    h = ase.frequency_response(snap.fwtf, f)
    ax1.semilogx(f, 20 * np.log10(np.abs(h)))
    ax1.axhline(0.0, color=THESIS_COLOR, lw=0.8)
    x = snap.crossovers
    unstable_ol = snap.nyquist.open_loop_unstable_poles > 0
    ax1.set_title(f"FWTF{2 if snap.topology == 'AEM1' else 3} (Bode): PM {x.phase_margin_deg:.1f} deg,"
                  f" GM {x.gain_margin_db:.1f} dB" + (" - open loop unstable, see below"
                                                      if unstable_ol else ""), fontsize=9)
    ax1.set(xlabel="frequency (Hz)", ylabel="|forward path| (dB)")
    for name, y in snap.outputs.items():
        ax2.plot(1e3 * snap.t, y, lw=1.0 if name != "theta" else 1.8, label=name)
    ax2.plot(1e3 * snap.t, snap.theta_rigid, color="g", lw=2, ls="--", label="rigid-fin design")
    ax2.set_title("closed loop " + ("stable" if snap.stable else "UNSTABLE")
                  + f" (Nyquist: Z = {snap.nyquist.closed_loop_unstable_poles})", fontsize=9,
                  color="k" if snap.stable else "C3")
    if not snap.stable:
        ax2.set_yscale("symlog", linthresh=1.0)
    ax2.set(xlabel="time (ms)", ylabel="unit-step response (rad/rad)")
    # the legend beside the axes, never over the curves
    ax2.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    readout = ase_readout(snap)
    fig.subplots_adjust(left=0.06, right=0.84, top=0.86, wspace=0.22,
                        bottom=0.12 + 0.037 * (readout.count("\n") + 1))
    fig.text(0.06, 0.01, readout, ha="left", va="bottom", fontsize=9,
             color="k" if snap.stable else "C3", family="monospace")
    plt.show()
    return fig


def ase_panel(controller: PDController = SYSTEM_3, mach: float = 0.5, altitude: float = 0.0,
              topology: str = "AEM1"):
    """An ipywidgets panel for Ch. 5: sliders K_c, K_P, K_D, Mach, altitude and the feedback
    topology; redraws the forward-path Bode magnitude with margins and the closed-loop unit step
    of the elastic fin beside the rigid-fin design response. Returns the ``ipywidgets.VBox``;
    builds without a front-end. Models are kept per (Mach, altitude) inside the panel."""
    import ipywidgets as w


    sliders = {
        **_pd_sliders(controller),
        "mach": w.FloatSlider(value=mach, min=0.4, max=0.75, step=0.05, description="Mach",
                              continuous_update=False),
        "altitude": w.FloatSlider(value=altitude, min=0.0, max=5000.0, step=500.0,
                                  description="h (m)", continuous_update=False),
        "topology": w.Dropdown(options=list(ase.TOPOLOGIES), value=topology,
                               description="feedback"),
    }
    out = w.Output()
    fins = {}

    def redraw(*_):
        v = {k: s.value for k, s in sliders.items()}
        key = (round(v["mach"], 4), round(v["altitude"], 1))
        if key not in fins:
            fins[key] = pipeline.ase_condition(fin_case(), mach=key[0], altitude=key[1])
        snap = ase_snapshot(v["gain"], v["kp"], v["kd"], key[0], key[1], v["topology"],
                            fin=fins[key])
        out.clear_output(wait=True)
        with out:
            _draw_ase(snap)
        return snap

    return _panel(sliders, out, redraw, per_row=3)
