"""Power-limited nonlinear simulation of the servo-actuator (thesis Secs. 4.2.1, 4.3; Figs 44-46,
52, 53, 55-57).

The actuator states, at the transmission output, are ``x_act = [theta, omega, current]``
(rad, rad/s, A), the same as :func:`asekit.servo.actuator.actuator_state_space`. The motor and
transmission obey Eqs. (2.30)-(2.37)::

    theta'  = omega
    omega'  = (K_t I + T_hinge@fin / (N eta) - c N omega) / (N J_total@motor)
    I'      = (V - R I - K_b N omega) / L

with the applied voltage ``V`` limited by the power supply and the current limit
(:class:`PowerLimits`):

* ``"voltage_clip"`` -- the thesis's implementation, Eqs. (4.14)-(4.15): the voltage is clipped
  to +-I_lim R (57.8 V), which never binds below the 24 V supply clip;
* ``"regulator"`` -- a true current limit: a fast current regulator (time constant
  ``current_loop_time_constant``) lowers |V| just enough to hold |I| <= I_lim.

The PD controller acts on the command and a *feedback signal passed in by the caller*, so the
same right-hand side serves the rigid-fin loop of Ch. 4 (feedback = transmission output) and the
aeroservoelastic loops of Ch. 5 (AEM1: motor-shaft encoder; AEM2: fin-root potentiometer)::

    V_cmd = K_c (K_P (theta_cmd - theta_fb) + K_D (theta_cmd' - omega_fb))

The derivative acts on the feedback rate (and on ``theta_cmd_rate`` if given): a step command's
derivative impulse, present in the linear Eq. (4.18), is clipped to zero duration by the supply
limit and is omitted here.

The public right-hand sides :func:`motor_rhs` and :func:`actuator_rhs` are pure functions of
their arguments, meant to be called inside a larger ``solve_ivp`` right-hand side (Ch. 5);
:func:`actuator_signals` returns the applied voltage, current and torque for a state.

Coupling to an aeroelastic fin (Ch. 5)
--------------------------------------
* AEM1 (encoder on the motor shaft): ``theta_feedback = x_act[0]``, ``omega_feedback = x_act[1]``
  (the motor angle divided by N). AEM2 (potentiometer at the fin root): pass the fin-root angle
  and rate computed from the aeroelastic states.
* The aeroelastic hinge moment (thesis Eq. 2.68) contains the fin's own inertia through its
  acceleration input, ``T = T0(z, theta, theta') - M_eff theta''``. Do not count the fin twice
  and avoid the algebraic loop: build the actuator with ``fin_inertia = M_eff`` (the coefficient
  of theta'' in D_hinge@fin, thesis Eq. 2.70) and pass ``hinge_moment_fin = T0``; Eqs. 2.33 and
  2.34 reflect both identically (M_eff theta'' / (N eta) at the motor).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np
from scipy.integrate import solve_ivp

from asekit.ase import metrics
from asekit.servo.actuator import ActuatorParameters, PDController, closed_loop_polynomial
from asekit.servo.piecewise import propagate_exact, voltage_bounds
from asekit.servo.torque_requirement import (
    SEA_LEVEL_DENSITY,
    SEA_LEVEL_SPEED_OF_SOUND,
    THESIS_Q_CC,
    dynamic_pressure,
)
from asekit.util.blas import small_dense
from asekit.util.validate import in_range, integer

_CURRENT_MODELS = ("voltage_clip", "regulator")


@dataclass(frozen=True)
class PowerLimits:
    """Power-source limits of the drive (thesis Table 2, Table 16, Eqs. 4.14-4.15).

    Parameters
    ----------
    supply_voltage : |V| <= supply_voltage (V), > 0; None for no limit (thesis: 24 V).
    current_limit : I_lim (A), > 0; None for no limit (thesis: 10 A).
    current_limit_model : ``"voltage_clip"`` (thesis Eqs. 4.14-4.15: |V| <= I_lim R) or
        ``"regulator"`` (true current limit, |I| held at I_lim by a fast current loop).
    current_loop_time_constant : time constant of the regulator's current loop (s), > 0.
    """

    supply_voltage: float | None = 24.0
    current_limit: float | None = 10.0
    current_limit_model: str = "voltage_clip"
    current_loop_time_constant: float = 1e-4

    def __post_init__(self):
        if self.supply_voltage is not None:
            in_range("supply_voltage", self.supply_voltage)
        if self.current_limit is not None:
            in_range("current_limit", self.current_limit)
        if self.current_limit_model not in _CURRENT_MODELS:
            raise ValueError(f"current_limit_model must be one of {_CURRENT_MODELS}, "
                             f"got {self.current_limit_model!r}")
        in_range("current_loop_time_constant", self.current_loop_time_constant)

    @property
    def is_linear(self) -> bool:
        return self.supply_voltage is None and self.current_limit is None


#: No power limits: the linear actuator.
NO_LIMITS = PowerLimits(supply_voltage=None, current_limit=None)
#: The thesis's power-limited model (Table 16): 24 V supply, 10 A limit as a voltage clip.
THESIS_LIMITS = PowerLimits()
#: 24 V supply and a true 10 A current limit.
CURRENT_REGULATED_LIMITS = PowerLimits(current_limit_model="regulator")


def controller_voltage(controller: PDController, theta_cmd: float, theta_feedback: float,
                       omega_feedback: float, theta_cmd_rate: float = 0.0) -> float:
    """PD voltage demand K_c (K_P e + K_D e') (V) before any limit, e = theta_cmd - theta_fb
    (rad), e' = theta_cmd_rate - omega_fb (rad/s). Eq. (2.42) with K_c of Eq. (4.17)."""
    return float(controller.voltage(theta_cmd - theta_feedback, theta_cmd_rate - omega_feedback))


def applied_voltage(params: ActuatorParameters, limits: PowerLimits, x_act,
                    voltage_command: float) -> float:
    """Terminal voltage (V) applied to the motor for a demand, after the current limit and the
    supply clip of ``limits`` (see module docstring). ``x_act = [theta, omega, current]``."""
    m = params.motor
    v = float(voltage_command)
    _, omega, current = x_act
    if limits.current_limit is not None:
        i_lim = limits.current_limit
        if limits.current_limit_model == "voltage_clip":          # Eqs. (4.14)-(4.15)
            v = min(max(v, -i_lim * m.resistance), i_lim * m.resistance)
        else:                                                       # true current limit
            emf = m.back_emf_constant * params.transmission.ratio * omega
            gain = m.inductance / limits.current_loop_time_constant
            v_up = m.resistance * i_lim + emf + gain * (i_lim - current)
            v_low = -m.resistance * i_lim + emf + gain * (-i_lim - current)
            v = min(max(v, v_low), v_up)
    if limits.supply_voltage is not None:
        v = min(max(v, -limits.supply_voltage), limits.supply_voltage)
    return v


def motor_rhs(params: ActuatorParameters, limits: PowerLimits, x_act, voltage_command: float,
              hinge_moment_fin: float) -> np.ndarray:
    """d x_act / dt for a voltage demand (V) and the hinge moment at the fin (N m).

    Eqs. (2.30)-(2.37) at the transmission output; the demand passes through
    :func:`applied_voltage`. Returns [omega, alpha, dI/dt] (rad/s, rad/s^2, A/s). Use this one
    when the controller is sampled (zero-order hold) or supplied by the caller.
    """
    m, tr = params.motor, params.transmission
    n = tr.ratio
    _, omega, current = x_act
    v = applied_voltage(params, limits, x_act, voltage_command)
    nj = n * params.inertia_at_motor
    alpha = (m.torque_constant * current + hinge_moment_fin / (n * tr.efficiency)
             - m.viscous_damping * n * omega) / nj
    di = (v - m.resistance * current - m.back_emf_constant * n * omega) / m.inductance
    return np.array([omega, alpha, di])


def actuator_rhs(params: ActuatorParameters, controller: PDController, limits: PowerLimits,
                 x_act, theta_cmd: float, theta_feedback: float, omega_feedback: float,
                 hinge_moment_fin: float, theta_cmd_rate: float = 0.0) -> np.ndarray:
    """d x_act / dt of the PD-controlled, power-limited actuator (continuous controller).

    Parameters
    ----------
    params : motor, transmission, load inertia. controller : the PD gains.
    limits : supply and current limits (:data:`NO_LIMITS` for the linear actuator).
    x_act : [theta (rad), omega (rad/s), current (A)] at the transmission output.
    theta_cmd : commanded angle (rad); theta_cmd_rate : its rate (rad/s), default 0.
    theta_feedback, omega_feedback : the measured angle (rad) and rate (rad/s) the controller
        closes the loop on (``x_act[0], x_act[1]`` for the rigid fin; another signal for AEM2).
    hinge_moment_fin : external moment at the fin (N m), positive along positive rotation.

    Returns [omega, alpha, dI/dt].
    """
    v_cmd = controller_voltage(controller, theta_cmd, theta_feedback, omega_feedback,
                               theta_cmd_rate)
    return motor_rhs(params, limits, x_act, v_cmd, hinge_moment_fin)


@dataclass(frozen=True)
class ActuatorSignals:
    """Signals of the actuator at one instant (SI): ``voltage_command`` (PD demand, V),
    ``voltage`` (applied, V), ``current`` (A), ``torque`` (motor torque at the fin, N m),
    ``alpha`` (transmission output acceleration, rad/s^2)."""

    voltage_command: float
    voltage: float
    current: float
    torque: float
    alpha: float


def actuator_signals(params: ActuatorParameters, controller: PDController, limits: PowerLimits,
                     x_act, theta_cmd: float, theta_feedback: float, omega_feedback: float,
                     hinge_moment_fin: float, theta_cmd_rate: float = 0.0) -> ActuatorSignals:
    """Applied voltage, current, motor torque and acceleration for a state; same arguments as
    :func:`actuator_rhs` (use it to post-process a solution, e.g. Ch. 5's Figs 77-78)."""
    v_cmd = controller_voltage(controller, theta_cmd, theta_feedback, omega_feedback,
                               theta_cmd_rate)
    v = applied_voltage(params, limits, x_act, v_cmd)
    alpha = motor_rhs(params, limits, x_act, v_cmd, hinge_moment_fin)[1]
    current = float(x_act[2])
    return ActuatorSignals(v_cmd, v, current, float(motor_torque_at_fin(params, current)),
                           float(alpha))


def motor_torque_at_fin(params: ActuatorParameters, current):
    """Torque the motor delivers at the fin (N m): K_t I N eta (the 'applied torque', Fig 57)."""
    tr = params.transmission
    return params.motor.torque_constant * np.asarray(current) * tr.ratio * tr.efficiency


def holding_current(params: ActuatorParameters, hinge_moment_fin: float) -> float:
    """Current (A) that holds the actuator at rest against a hinge moment at the fin (N m)."""
    tr = params.transmission
    return -hinge_moment_fin / (tr.ratio * tr.efficiency * params.motor.torque_constant)


def quasi_steady_demand(params: ActuatorParameters, hinge_moment_fin, rate) -> dict:
    """Motor current, voltage and electrical power that drive the fin at the angular rate
    ``rate`` against the hinge moment ``hinge_moment_fin``, quasi-steady: Eqs. (2.30)-(2.37)
    with the acceleration and dI/dt set to zero (inertia and inductance neglected, as the
    thesis's Sec. 4 torque sizing),

        K_t I = c N omega - T_hinge / (N eta),     V = R I + K_b N omega,     P = V I,

    omega the transmission output (= fin) rate, T_hinge positive along positive rotation.

    Parameters
    ----------
    params : motor and transmission; hinge_moment_fin : N m (scalar or array);
    rate : fin rate omega (rad/s), broadcast with ``hinge_moment_fin``.

    Returns
    -------
    dict ``current`` (A), ``voltage`` (V), ``power`` (W: V I, > 0 drawn from the supply).

    Examples
    --------
    >>> from asekit.servo.actuator import ActuatorParameters
    >>> d = quasi_steady_demand(ActuatorParameters(), -1.0, 0.0)     # holding 1 N m
    >>> round(float(d["current"]), 4) == round(holding_current(ActuatorParameters(), -1.0), 4)
    True
    """
    m, tr = params.motor, params.transmission
    N, eta = tr.ratio, tr.efficiency
    om = np.asarray(rate, float)
    cur = (m.viscous_damping * N * om - np.asarray(hinge_moment_fin, float) / (N * eta)) \
        / m.torque_constant
    volt = m.resistance * cur + m.back_emf_constant * N * om
    return {"current": cur, "voltage": volt, "power": volt * cur}


@dataclass(frozen=True)
class SteadyHingeMoment:
    """Steady aerodynamic hinge moment q Q_cc theta (N m) (thesis Eqs. 4.6, Sec. 4.3).

    Parameters
    ----------
    q_cc : Q_cc^real (m^3/rad); positive is de-centering (thesis: 5.825e-4 at M 0.6, k 0.001).
    mach, density (kg/m^3), speed_of_sound (m/s) : flight condition (thesis: M 0.6, sea level).
    """

    q_cc: float = THESIS_Q_CC
    mach: float = 0.6
    density: float = SEA_LEVEL_DENSITY
    speed_of_sound: float = SEA_LEVEL_SPEED_OF_SOUND

    def __post_init__(self):
        if not math.isfinite(float(self.q_cc)):
            raise ValueError(f"q_cc must be finite, got {self.q_cc!r}")
        dynamic_pressure(self.mach, self.density, self.speed_of_sound)   # validates

    @cached_property
    def stiffness(self) -> float:
        """q Q_cc (N m/rad)."""
        return dynamic_pressure(self.mach, self.density, self.speed_of_sound) * self.q_cc

    def __call__(self, t: float, theta_fin: float, omega_fin: float) -> float:
        return self.stiffness * theta_fin


def no_hinge_moment(t: float, theta_fin: float, omega_fin: float) -> float:
    """Zero external moment (the linear design case of Ch. 4)."""
    return 0.0


@dataclass(frozen=True)
class SimulationResult:
    """Time histories of a simulation (SI): t (s), command, theta (rad), omega (rad/s), alpha
    (rad/s^2), current (A), voltage (applied, V), voltage_command (V), torque (motor torque at
    the fin, N m), hinge_moment (N m)."""

    t: np.ndarray
    command: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    voltage_command: np.ndarray
    torque: np.ndarray
    hinge_moment: np.ndarray
    theta0: float = 0.0
    meta: dict = field(default_factory=dict)

    def settling_time(self, band: float = 0.02, reference: str = "final") -> float:
        """Time (s) after which theta stays within ``band`` x |step| of the ``reference``:
        ``"final"`` (the last simulated value, the usual definition) or ``"command"``.
        The step is command[-1] - theta0. inf if it leaves the band at the end."""
        target = self.theta[-1] if reference == "final" else self.command[-1]
        return metrics.settling_time(self.t, self.theta, target, self.command[-1] - self.theta0,
                                     band)

    @property
    def steady_error(self) -> float:
        """|theta(end) - command(end)| / |command(end)| (fraction)."""
        return float(abs(self.theta[-1] - self.command[-1]) / abs(self.command[-1]))

    @property
    def peak_rate(self) -> float:
        """max |omega| (rad/s)."""
        return float(np.max(np.abs(self.omega)))

    @property
    def peak_torque(self) -> float:
        """max |motor torque at the fin| (N m)."""
        return float(np.max(np.abs(self.torque)))

    @property
    def overshoot(self) -> float:
        """Largest excursion past the command, as a fraction of |step| (0 if none)."""
        return metrics.overshoot(self.theta, self.command[-1], self.theta0)


#: largest estimated integrator step count a single :func:`simulate` call may take.
MAX_SIM_STEPS = 200_000


def estimate_steps(params: ActuatorParameters, controller: PDController, t_final: float,
                   max_step: float, sample_time: float | None = None) -> tuple[int, float]:
    """Up-front estimate of the RK45 steps of :func:`simulate` and the fastest pole (1/s).

    The explicit integrator's step is bounded by ``max_step`` and by stability, dt <~ 3.3 /
    |lambda_max| (the RK45 stability interval on the negative real axis, Hairer & Wanner, Solving
    ODEs II, Sec. IV.2), lambda_max the largest-magnitude root of the linear closed loop (Eq.
    4.18, :func:`asekit.servo.actuator.closed_loop_polynomial`) or of the open-loop motor (when the supply
    clips the voltage or between zero-order-hold samples). A zero-order-hold controller adds at
    least 6 steps per sample. Returns (steps, |lambda_max|)."""
    cl = closed_loop_polynomial(params, controller)
    ol = closed_loop_polynomial(params, PDController(0.0, 0.0, 0.0))
    lam = 0.0
    for poly in (cl, ol):
        with np.errstate(all="ignore"):
            r = np.roots(poly / np.max(np.abs(poly)))
        r = r[np.isfinite(r)]
        if r.size:
            lam = max(lam, float(np.abs(r).max()))
    steps = max(t_final / max_step, t_final * lam / 3.3)
    if sample_time is not None:
        steps = max(steps, 6.0 * t_final / sample_time)
    return int(min(steps, 1e18)), lam


@small_dense
def simulate(params: ActuatorParameters, controller: PDController,
             command: float | Callable[[float], float], t_final: float = 0.1,
             theta0: float = 0.0, limits: PowerLimits = THESIS_LIMITS,
             hinge_moment: Callable[[float, float, float], float] | None = None,
             sample_time: float | None = None, n_out: int = 2001,
             max_step: float = 5e-5, method: str = "auto") -> SimulationResult:
    """Simulate the PD-controlled actuator on a rigid fin (thesis Figs 46, 52, 53, 55-57).

    Parameters
    ----------
    params, controller, limits : see :func:`actuator_rhs`.
    command : commanded fin angle (rad), constant for t >= 0 or a callable ``command(t)``.
    t_final : simulated time (s), > 0.
    theta0 : initial fin angle (rad). The actuator starts at rest, carrying the current that
        holds it against the hinge moment at theta0 (as after a long hold at theta0).
    hinge_moment : callable ``hinge_moment(t, theta_fin, omega_fin) -> N m`` at the fin;
        default :class:`SteadyHingeMoment` (q Q_cc theta at M 0.6, sea level, thesis Q_cc).
    sample_time : None for the continuous controller; else a zero-order-hold controller
        sampling every ``sample_time`` s (thesis Table 2: 1 kHz -> 1e-3), its derivative the
        backward difference of the sampled feedback.
    n_out : number of output samples. max_step : integrator's largest step (s) of RK45.
    method : ``"auto"`` (default): exact piecewise-linear propagation (matrix exponential per
        limit region, region changes located on the exact solution,
        :func:`asekit.servo.piecewise.propagate_exact`) when the loop is piecewise linear -- a constant
        command and a :class:`SteadyHingeMoment` or :func:`no_hinge_moment` -- else RK45;
        ``"RK45"``: always ``solve_ivp`` RK45 (rtol 1e-8; the two agree within it,
        tests/servo/test_simulate.py); ``"exact"``: refuse (ValueError) what is not piecewise linear.

    Raises ValueError/TypeError naming the argument for bad input, and ValueError before any
    work when the estimated step count (:func:`estimate_steps`) exceeds :data:`MAX_SIM_STEPS`.
    """
    if not isinstance(params, ActuatorParameters):
        raise TypeError(f"params must be an ActuatorParameters, got {type(params).__name__}")
    if not isinstance(controller, PDController):
        raise TypeError(f"controller must be a PDController, got {type(controller).__name__}")
    if not isinstance(limits, PowerLimits):
        raise TypeError(f"limits must be a PowerLimits (e.g. THESIS_LIMITS, NO_LIMITS), got "
                        f"{limits!r}")
    in_range("t_final", t_final)
    in_range("max_step", max_step)
    if sample_time is not None:
        in_range("sample_time", sample_time)
    n_out = integer("n_out", n_out, low=2, high=10_000_000)
    steps, lam = estimate_steps(params, controller, t_final, max_step, sample_time)
    if steps > MAX_SIM_STEPS:
        raise ValueError(
            f"simulate would take about {steps:.3g} integrator steps (limit {MAX_SIM_STEPS}, "
            f"asekit.servo.simulate.MAX_SIM_STEPS): t_final = {t_final:g} s, max_step = "
            f"{max_step:g} s, sample_time = {sample_time}, fastest pole |lambda| = {lam:.3g} "
            "1/s (from the motor inductance and the controller gains). Shorten t_final, raise "
            "max_step or sample_time, or use a less stiff motor/controller.")
    hm = SteadyHingeMoment() if hinge_moment is None else hinge_moment
    if not callable(hm):
        raise ValueError("hinge_moment must be a callable hinge_moment(t, theta, omega)")
    if callable(command):
        cmd = command
    else:
        cmd = (lambda t, c=in_range("command", command, -math.inf): c)
    theta0 = in_range("theta0", theta0, -math.inf)
    x0 = np.array([theta0, 0.0, holding_current(params, hm(0.0, theta0, 0.0))])
    t_out = np.linspace(0.0, t_final, n_out)
    if method not in ("auto", "exact", "RK45"):
        raise ValueError(f"method must be 'auto', 'exact' or 'RK45', got {method!r}")
    linear_hm = isinstance(hm, SteadyHingeMoment) or hm is no_hinge_moment
    exact = method != "RK45" and linear_hm and not callable(command)
    if method == "exact" and not exact:
        raise ValueError("method='exact' needs a constant command and a SteadyHingeMoment or "
                         "no_hinge_moment (a piecewise-linear loop); use 'auto' or 'RK45'")

    if exact:
        stiffness = hm.stiffness if isinstance(hm, SteadyHingeMoment) else 0.0
        mats = _rigid_loop_matrices(params, controller, cmd(0.0), stiffness)
        x, v_cmd = propagate_exact(mats, voltage_bounds(params, limits, 3), controller,
                                   cmd(0.0), t_out, x0, sample_time)
    elif sample_time is None:
        def rhs(t, x):
            return actuator_rhs(params, controller, limits, x, cmd(t), x[0], x[1],
                                hm(t, x[0], x[1]))
        sol = solve_ivp(rhs, (0.0, t_final), x0, method="RK45", rtol=1e-8,
                        atol=[1e-10, 1e-8, 1e-8], max_step=max_step, dense_output=True)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        x = sol.sol(t_out)
        v_cmd = np.array([controller_voltage(controller, cmd(t), th, om)
                          for t, th, om in zip(t_out, x[0], x[1])])
    else:
        x, v_cmd = _simulate_zoh(params, controller, limits, cmd, hm, x0, t_out, sample_time,
                                 max_step)
    hinge = np.array([hm(t, th, om) for t, th, om in zip(t_out, x[0], x[1])])
    volt = np.array([applied_voltage(params, limits, xi, vc) for xi, vc in zip(x.T, v_cmd)])
    alpha = np.array([motor_rhs(params, limits, xi, vc, h)[1]
                      for xi, vc, h in zip(x.T, v_cmd, hinge)])
    return SimulationResult(
        t=t_out, command=np.array([cmd(t) for t in t_out]), theta=x[0], omega=x[1],
        alpha=alpha, current=x[2], voltage=volt, voltage_command=v_cmd,
        torque=motor_torque_at_fin(params, x[2]), hinge_moment=hinge, theta0=theta0,
        meta={"controller": controller, "limits": limits, "sample_time": sample_time})


def _rigid_loop_matrices(params: ActuatorParameters, controller: PDController, command: float,
                         stiffness: float) -> dict:
    """The PD loop of :func:`simulate` on the rigid fin with the hinge moment ``stiffness``
    theta (N m) as x' = F x + g V, x = [theta, omega, I] (Eqs. 2.30-2.37, module docstring),
    and the PD demand V_cmd = k x + k0 on the transmission angle and rate, in the form of
    :func:`asekit.servo.piecewise.propagate_exact`."""
    m, tr = params.motor, params.transmission
    n, eta = tr.ratio, tr.efficiency
    nj = n * params.inertia_at_motor
    arow = np.array([stiffness / (n * eta) / nj, -m.viscous_damping * n / nj,
                     m.torque_constant / nj])
    F = np.array([[0.0, 1.0, 0.0], arow,
                  [0.0, -m.back_emf_constant * n / m.inductance, -m.resistance / m.inductance]])
    g = np.array([0.0, 0.0, 1.0 / m.inductance])
    fb, om = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    kc, kp, kd = controller.gain, controller.kp, controller.kd
    return {"F": F, "g": g, "arow": arow, "k": -kc * (kp * fb + kd * om),
            "k0": kc * kp * command, "fb_row": fb, "om_row": om}


def _simulate_zoh(params, controller, limits, cmd, hm, x0, t_out, ts, max_step):
    """Zero-order-hold PD: integrate sample interval by sample interval."""
    t_final = t_out[-1]
    n_samples = max(1, int(math.ceil(t_final / ts - 1e-9)))   # t_final < ts: one sample
    x = np.empty((3, t_out.size))
    v_hold = np.empty(t_out.size)
    state = x0.copy()
    y_prev = x0[0] - x0[1] * ts
    for k in range(n_samples):
        t0, t1 = k * ts, min((k + 1) * ts, t_final)
        y = state[0]
        v_k = float(controller.voltage(cmd(t0) - y, -(y - y_prev) / ts))
        y_prev = y
        sol = solve_ivp(lambda t, s: motor_rhs(params, limits, s, v_k, hm(t, s[0], s[1])),
                        (t0, t1), state, method="RK45", rtol=1e-8, atol=[1e-10, 1e-8, 1e-8],
                        max_step=max_step, dense_output=True)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        mask = (t_out >= t0) & ((t_out < t1) | ((k == n_samples - 1) & (t_out <= t1)))
        if mask.any():
            x[:, mask] = sol.sol(t_out[mask])
            v_hold[mask] = v_k
        state = sol.y[:, -1]
    return x, v_hold
