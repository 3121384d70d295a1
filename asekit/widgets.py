"""Interactive ipywidgets panels for the notebooks.

:func:`servo_panel` shows the PD design of thesis Sec. 4.3 live: sliders for K_c, K_P, K_D and
the supply-voltage limit redraw the 14 deg step response (linear Eq. 4.18 and power limited),
the closed-loop poles and the forward-path margins. The numbers behind the drawing come from
:func:`servo_snapshot`, a plain function. The panel builds without a front-end (the widgets
then simply are not displayed), so notebooks run under nbval and in a plain Python session.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .servo import (SYSTEM_3, ActuatorParameters, Margins, PDController, closed_loop_poles,
                    margins, step_response)
from .simulate import PowerLimits, SimulationResult, SteadyHingeMoment, simulate


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

    from .plotting import THESIS_COLOR, new_figure
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


def servo_panel(controller: PDController = SYSTEM_3, supply_voltage: float = 24.0,
                params: ActuatorParameters | None = None,
                hinge_moment: SteadyHingeMoment | None = None):
    """An ipywidgets panel: sliders K_c, K_P, K_D, supply voltage; redraws step, poles, margins.

    Returns the ``ipywidgets.VBox``; display it in a notebook (a bare last-line expression).
    Constructing it needs no front-end. The drawn figure is redrawn on every slider release.
    """
    import ipywidgets as w

    sliders = {
        "gain": w.FloatSlider(value=controller.gain, min=0.5, max=30.0, step=0.5,
                              description="K_c", continuous_update=False),
        "kp": w.FloatSlider(value=controller.kp, min=10.0, max=600.0, step=5.0,
                            description="K_P", continuous_update=False),
        "kd": w.FloatSlider(value=controller.kd, min=0.0, max=3.0, step=0.05,
                            description="K_D", continuous_update=False),
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

    for s in sliders.values():
        s.observe(redraw, names="value")
    panel = w.VBox([w.HBox(list(sliders.values())[:2]), w.HBox(list(sliders.values())[2:]), out])
    panel.redraw = redraw
    panel.sliders = sliders
    redraw()
    return panel
