"""Linear servo-actuator model: DC motor, transmission, PD controller (thesis Sec. 2.3, Ch. 4).

The actuator is a permanent-magnet DC motor (Faulhaber 2642 024CR, thesis Table 12) driving the
fin shaft through a combined transmission (ratio ``N``, efficiency ``eta``, inertia ``J_tr`` at
the motor, thesis Eq. 4.13). A PD controller ``K_c (K_P + K_D s)`` closes a unity feedback loop
on the fin angle (Eqs. 2.42, 4.17, 4.18).

Equations implemented (thesis numbering)::

    theta_m = N theta_fin                                             (2.30)-(2.32)
    J_total@motor = J_rotor + J_tr + J_fin / (N^2 eta)                (2.33)
    T_hinge@motor = T_hinge@fin / (N eta)                             (2.34)
    J_total theta_m'' = K_t I + T_hinge@motor - c theta_m'            (2.35), (2.37)
    L I' = V - R I - K_b theta_m'                                     (2.36)
    theta_m / V  = K_t / (s ((J s + c)(L s + R) + K_b K_t))           (2.40)
    theta_fin / V = K_t / (N s ((J s + c)(L s + R) + K_b K_t))        (2.41)
    G_forward = K_c (K_P + K_D s) theta_fin / V                       (4.17)
    closed loop = G_forward / (1 + G_forward)                         (4.18, corrected)

Eq. (4.18) as printed lacks K_c in the constant term of the denominator; the closed-loop poles
of Table 17 follow from the corrected form ``... + K_c K_P K_t`` (see shared/reference/fin.md),
which is what :func:`closed_loop` computes. The viscous damping ``c`` is not listed in the thesis;
``c = 0`` and ``K_b = K_t`` (SI units) reproduce the open-loop poles of Table 13.

Sign convention: a positive hinge moment at the fin acts in the direction of positive fin
rotation (the steady hinge moment ``q Q_cc theta`` with ``Q_cc > 0`` is de-centering).

All quantities are SI (rad, rad/s, N m, V, A, kg m^2) inside this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from asekit.util.validate import finite, finite_result, in_range, integer


@dataclass(frozen=True)
class DCMotor:
    """Permanent-magnet DC motor constants (thesis Sec. 2.3.1.2, Table 12).

    The defaults are the Faulhaber 2642 024CR of thesis Table 12.

    Parameters
    ----------
    resistance : terminal resistance R (ohm), > 0.
    inductance : rotor inductance L (H), > 0.
    torque_constant : K_t (N m/A), > 0.
    back_emf_constant : K_b (V s/rad), > 0. Equal to K_t in SI units for an ideal motor.
    rotor_inertia : J_rotor (kg m^2), > 0. Table 12: 11 g cm^2 = 1.1e-6 kg m^2.
    viscous_damping : c (N m s/rad), >= 0. Not given by the thesis; 0 reproduces Table 13.
    """

    resistance: float = 5.78
    inductance: float = 550e-6
    torque_constant: float = 34.6e-3
    back_emf_constant: float = 34.6e-3
    rotor_inertia: float = 11e-7
    viscous_damping: float = 0.0

    def __post_init__(self):
        for name in ("resistance", "inductance", "torque_constant", "back_emf_constant",
                     "rotor_inertia"):
            in_range(name, getattr(self, name))
        in_range("viscous_damping", self.viscous_damping, inclusive=True)


@dataclass(frozen=True)
class Transmission:
    """Combined gearbox and linkage (thesis Sec. 2.3.1.1, Eq. 4.13).

    Parameters
    ----------
    ratio : N_tr, motor angle / fin angle, > 0 (thesis: 66).
    efficiency : eta_tr in (0, 1] (thesis: 0.7).
    inertia : J_tr referred to the motor shaft (kg m^2), >= 0 (thesis: 0.5e-7).
    """

    ratio: float = 66.0
    efficiency: float = 0.7
    inertia: float = 0.5e-7

    def __post_init__(self):
        in_range("ratio", self.ratio)
        in_range("efficiency", self.efficiency, high=1.0)
        in_range("inertia", self.inertia, inclusive=True)


#: The thesis's fin pitch inertia about the shaft (kg m^2, Eq. 4.11, from its PATRAN model).
THESIS_FIN_INERTIA = 2.958e-4


@dataclass(frozen=True)
class ActuatorParameters:
    """Motor, transmission and the inertia of the load on the transmission output.

    Parameters
    ----------
    motor, transmission : see :class:`DCMotor`, :class:`Transmission`.
    fin_inertia : J_fin about the shaft (kg m^2), >= 0. Default: the thesis's 2.958e-4
        (its PATRAN value). asekit's own structural value (about 2.5e-4 for 2700 kg/m^3) can be
        passed instead. Use 0 when the fin's inertia is supplied through the hinge moment
        instead (e.g. the aeroelastic model of Ch. 5, whose hinge moment contains -M_cc theta'').
    """

    motor: DCMotor = DCMotor()
    transmission: Transmission = Transmission()
    fin_inertia: float = THESIS_FIN_INERTIA

    def __post_init__(self):
        if not isinstance(self.motor, DCMotor):
            raise ValueError(f"motor must be a DCMotor, got {type(self.motor).__name__}")
        if not isinstance(self.transmission, Transmission):
            raise ValueError(
                f"transmission must be a Transmission, got {type(self.transmission).__name__}")
        in_range("fin_inertia", self.fin_inertia, inclusive=True)

    @property
    def inertia_at_motor(self) -> float:
        """J_total@motor (kg m^2), Eq. (2.33): J_rotor + J_tr + J_fin / (N^2 eta)."""
        n, eta = self.transmission.ratio, self.transmission.efficiency
        return self.motor.rotor_inertia + self.transmission.inertia + self.fin_inertia / (n * n * eta)

    def hinge_moment_at_motor(self, hinge_moment_fin):
        """T_hinge@motor (N m) from T_hinge@fin (N m), Eq. (2.34)."""
        return np.asarray(hinge_moment_fin) / (self.transmission.ratio * self.transmission.efficiency)

    def stall_torque_at_fin(self, voltage: float) -> float:
        """Torque at the fin (N m) at zero speed for a terminal voltage (V): K_t (V/R) N eta."""
        m, t = self.motor, self.transmission
        return m.torque_constant * voltage / m.resistance * t.ratio * t.efficiency

    def no_load_rate_at_fin(self, voltage: float) -> float:
        """Fin rate (rad/s) at zero load torque for a terminal voltage (V), from Eqs. 2.35-2.36
        in steady state: V K_t / (N (K_b K_t + c R))."""
        m = self.motor
        return voltage * m.torque_constant / (self.transmission.ratio
                                              * (m.back_emf_constant * m.torque_constant
                                                 + m.viscous_damping * m.resistance))


@dataclass(frozen=True)
class PDController:
    """PD controller ``K_c (K_P + K_D s)`` on the fin-angle error (Eqs. 2.42, 4.17).

    Parameters
    ----------
    gain : K_c (V/V scale), finite.
    kp : K_P (V/rad before K_c), finite.
    kd : K_D (V s/rad before K_c), finite. The zero sits at -K_P/K_D.
    name : a label for plots and tables.
    """

    gain: float
    kp: float
    kd: float
    name: str = ""

    def __post_init__(self):
        for n in ("gain", "kp", "kd"):
            v = float(getattr(self, n))
            if not math.isfinite(v):
                raise ValueError(f"{n} must be a finite number, got {v!r}")

    @property
    def zero(self) -> float:
        """The controller zero -K_P/K_D (rad/s); -inf for K_D = 0."""
        return -self.kp / self.kd if self.kd != 0 else -math.inf

    def transfer_function(self) -> ct.TransferFunction:
        """K_c (K_D s + K_P) as a python-control transfer function (V/rad)."""
        return ct.tf([self.gain * self.kd, self.gain * self.kp], [1.0],
                     inputs="error", outputs="voltage", name=self.name or None)

    def voltage(self, error, error_rate):
        """Controller output (V) for an angle error (rad) and its rate (rad/s)."""
        return self.gain * (self.kp * np.asarray(error) + self.kd * np.asarray(error_rate))


#: The thesis's PD designs (Tables 15, 17). K_D = 1 with the zero at -K_P/K_D as listed.
SYSTEM_1 = PDController(gain=9.0, kp=200.0, kd=1.0, name="System 1")
SYSTEM_2 = PDController(gain=9.0, kp=250.0, kd=1.0, name="System 2")
SYSTEM_3 = PDController(gain=10.0, kp=275.0, kd=1.0, name="System 3")
#: Unity feedback without a controller (K_c = K_P = 1, K_D = 0; Eq. 4.16, Table 14, Fig 49).
NO_CONTROLLER = PDController(gain=1.0, kp=1.0, kd=0.0, name="no controller")
SYSTEMS = {c.name: c for c in (SYSTEM_1, SYSTEM_2, SYSTEM_3)}


def motor_transfer_function(params: ActuatorParameters) -> ct.TransferFunction:
    """theta_m(s) / V(s) (rad/V), Eq. (2.40)."""
    m = params.motor
    j = params.inertia_at_motor
    # s ((J s + c)(L s + R) + K_b K_t)
    den = np.polymul([j, m.viscous_damping], [m.inductance, m.resistance])
    den = np.polyadd(den, [m.back_emf_constant * m.torque_constant])
    den = np.polymul(den, [1.0, 0.0])
    return ct.tf([m.torque_constant], den, inputs="voltage", outputs="theta_motor")


def actuator_transfer_function(params: ActuatorParameters) -> ct.TransferFunction:
    """theta_fin(s) / V(s) (rad/V), Eq. (2.41): Eq. (2.40) divided by N."""
    g = motor_transfer_function(params)
    return ct.tf(g.num[0][0], params.transmission.ratio * np.asarray(g.den[0][0]),
                 inputs="voltage", outputs="theta")


def open_loop_poles(params: ActuatorParameters) -> np.ndarray:
    """Poles of Eq. (2.41) (rad/s), sorted from the origin outwards (thesis Table 13)."""
    return _sorted_poles(ct.poles(actuator_transfer_function(params)))


def forward_path(params: ActuatorParameters, controller: PDController) -> ct.TransferFunction:
    """G_forward(s) = K_c (K_P + K_D s) theta_fin/V (rad/rad), Eq. (4.17)."""
    g = controller.transfer_function() * actuator_transfer_function(params)
    return ct.tf(g.num[0][0], g.den[0][0], inputs="error", outputs="theta")


def closed_loop_polynomial(params: ActuatorParameters, controller: PDController) -> np.ndarray:
    """Characteristic polynomial of the unity-feedback loop (Eq. 4.18, corrected), highest power
    first: N J L s^3 + N (J R + c L) s^2 + (N (K_b K_t + c R) + K_c K_D K_t) s + K_c K_P K_t."""
    m, n = params.motor, params.transmission.ratio
    j = params.inertia_at_motor
    with np.errstate(over="ignore", invalid="ignore"):
        c = np.array([
            n * j * m.inductance,
            n * (j * m.resistance + m.viscous_damping * m.inductance),
            n * (m.back_emf_constant * m.torque_constant + m.viscous_damping * m.resistance)
            + controller.gain * controller.kd * m.torque_constant,
            controller.gain * controller.kp * m.torque_constant,
        ])
    if not np.all(np.isfinite(c)) or c[0] <= 0.0 or np.max(np.abs(c / c[0])) > 1e200:
        raise ValueError(f"controller gains (gain {controller.gain:g}, kp {controller.kp:g}, kd "
                         f"{controller.kd:g}) with this motor give a characteristic polynomial "
                         f"{c} that overflows or degenerates")
    return c


def stable_kp_range(params: ActuatorParameters, controller: PDController) -> tuple[float, float]:
    """Open interval of K_c K_P that keeps the loop stable for the given K_c K_D (Routh-Hurwitz
    on the cubic of Eq. 4.18): 0 < K_c K_P < a2 a1 / (a3 K_t), with a_i the coefficients of
    :func:`closed_loop_polynomial` without the K_P term. Empty (upper <= 0) when K_c K_D makes
    a1 <= 0."""
    a3, a2, a1, _ = closed_loop_polynomial(params, controller)
    return 0.0, a2 * a1 / (a3 * params.motor.torque_constant) if a1 > 0 else 0.0


def closed_loop(params: ActuatorParameters, controller: PDController,
                require_stable: bool = True) -> ct.TransferFunction:
    """theta_fin / theta_com (rad/rad), Eq. (4.18) with K_c in the constant term.

    Parameters
    ----------
    require_stable : if True (default), raise ValueError when the gains give a closed-loop
        pole with non-negative real part, naming the gains and the stable K_c K_P range.
    """
    m = params.motor
    num = [controller.gain * controller.kd * m.torque_constant,
           controller.gain * controller.kp * m.torque_constant]
    sys = ct.tf(num, closed_loop_polynomial(params, controller), inputs="theta_cmd",
                outputs="theta")
    if require_stable:
        poles = ct.poles(sys)
        if np.any(poles.real >= 0.0):
            lo, hi = stable_kp_range(params, controller)
            raise ValueError(
                f"controller gains (gain K_c={controller.gain:g}, kp K_P={controller.kp:g}, "
                f"kd K_D={controller.kd:g}) give an unstable loop (poles {np.round(poles, 3)}); "
                f"a stable loop needs K_c*K_D > {-_a1_without_kd(params) / m.torque_constant:g} "
                f"and K_c*K_P in ({lo:g}, {hi:g})")
    return sys


def _a1_without_kd(params: ActuatorParameters) -> float:
    m = params.motor
    return params.transmission.ratio * (m.back_emf_constant * m.torque_constant
                                        + m.viscous_damping * m.resistance)


def closed_loop_poles(params: ActuatorParameters, controller: PDController,
                      require_stable: bool = True) -> np.ndarray:
    """Closed-loop poles (rad/s) of Eq. (4.18), sorted from the origin outwards (Tables 14, 15,
    17). Raises ValueError for an unstable loop when ``require_stable``."""
    return _sorted_poles(ct.poles(closed_loop(params, controller, require_stable)))


def _sorted_poles(p) -> np.ndarray:
    p = np.asarray(p, dtype=complex)
    p = p[np.argsort(np.abs(p), kind="stable")]
    return p.real if np.all(np.abs(p.imag) < 1e-9 * np.maximum(1.0, np.abs(p.real))) else p


@dataclass(frozen=True)
class Margins:
    """Stability margins of the forward path (Fig 54).

    gain_margin_db : gain margin (dB); inf when the phase never crosses -180 deg.
    phase_margin_deg : phase margin (deg).
    phase_crossover : frequency of the gain margin (rad/s), nan if none.
    gain_crossover : frequency of the phase margin (rad/s).
    """

    gain_margin_db: float
    phase_margin_deg: float
    phase_crossover: float
    gain_crossover: float


def margins(params: ActuatorParameters, controller: PDController) -> Margins:
    """Gain and phase margins of the forward path of Eq. (4.17) (thesis Sec. 4.3, Fig 54)."""
    gm, pm, wcg, wcp = ct.margin(forward_path(params, controller))
    gm_db = math.inf if not math.isfinite(gm) else 20.0 * math.log10(gm)
    return Margins(float(gm_db), float(pm), float(wcg), float(wcp))


#: Names of the linear actuator's signals (:func:`actuator_state_space`).
STATES = ("theta", "omega", "current")
INPUTS = ("voltage", "hinge_moment")
OUTPUTS = ("theta", "omega", "alpha", "current")


def actuator_state_space(params: ActuatorParameters, name: str = "actuator") -> ct.StateSpace:
    """The linear actuator (motor + transmission, no controller) as a named StateSpace.

    States: ``theta`` (transmission output angle, rad), ``omega`` (its rate, rad/s),
    ``current`` (armature current, A). Inputs: ``voltage`` (V), ``hinge_moment`` (hinge moment
    at the fin, N m, positive in the direction of positive rotation). Outputs: ``theta``,
    ``omega``, ``alpha`` (transmission output acceleration, rad/s^2), ``current``.

    From Eqs. (2.30)-(2.37) written at the transmission output (theta_m = N theta)::

        theta'' = (K_t I + T_hinge@fin / (N eta) - c N omega) / (N J_total@motor)
        I'      = (V - R I - K_b N omega) / L

    The voltage-to-theta transfer function equals Eq. (2.41). Use it with
    :func:`control.interconnect` (signal names above).
    """
    m, tr = params.motor, params.transmission
    n, eta = tr.ratio, tr.efficiency
    nj = n * params.inertia_at_motor
    a = np.array([[0.0, 1.0, 0.0],
                  [0.0, -m.viscous_damping * n / nj, m.torque_constant / nj],
                  [0.0, -m.back_emf_constant * n / m.inductance, -m.resistance / m.inductance]])
    b = np.array([[0.0, 0.0],
                  [0.0, 1.0 / (n * eta * nj)],
                  [1.0 / m.inductance, 0.0]])
    c = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], a[1], [0.0, 0.0, 1.0]])
    d = np.array([[0.0, 0.0], [0.0, 0.0], b[1], [0.0, 0.0]])
    return ct.ss(a, b, c, d, states=list(STATES), inputs=list(INPUTS), outputs=list(OUTPUTS),
                 name=name)


def pd_state_space(controller: PDController, name: str = "pd") -> ct.StateSpace:
    """The PD controller as a static python-control system for :func:`control.interconnect`.

    ``voltage = K_c (K_P (theta_cmd - theta_fb) + K_D (theta_cmd_rate - omega_fb))`` with inputs
    ``theta_cmd`` (rad), ``theta_cmd_rate`` (rad/s), ``theta_fb`` (rad), ``omega_fb`` (rad/s) and
    output ``voltage`` (V). Feeding the derivative from the measured rate keeps the system proper;
    with ``theta_cmd_rate`` = d(theta_cmd)/dt it equals Eq. (4.17)'s K_c (K_P + K_D s) on the error.
    """
    k, kp, kd = controller.gain, controller.kp, controller.kd
    return ct.ss(np.zeros((0, 0)), np.zeros((0, 4)), np.zeros((1, 0)),
                 [[k * kp, k * kd, -k * kp, -k * kd]],
                 inputs=["theta_cmd", "theta_cmd_rate", "theta_fb", "omega_fb"],
                 outputs=["voltage"], name=name)


def root_locus_data(params: ActuatorParameters, controller: PDController | None = None,
                    gains=None) -> tuple[np.ndarray, np.ndarray]:
    """Closed-loop poles of the unity loop as K_c varies (Figs 47, 48, 50).

    Parameters
    ----------
    controller : PD shape (K_P, K_D) of the forward path; None for the bare actuator (Fig 47).
        Its ``gain`` is ignored; the locus is over ``gains``.
    gains : K_c values (>= 0); default 400 values log-spaced over 1e-3 ... 1e3.

    Returns
    -------
    (gains, poles) with poles of shape (len(gains), 3), complex (rad/s).
    """
    gains = np.logspace(-3, 3, 400) if gains is None else np.asarray(gains, dtype=float)
    if np.any(~np.isfinite(gains)) or np.any(gains < 0):
        raise ValueError("gains must be finite and >= 0")
    shape = controller if controller is not None else PDController(1.0, 1.0, 0.0)
    poles = np.empty((gains.size, 3), dtype=complex)
    for i, k in enumerate(gains):
        c = PDController(float(k), shape.kp, shape.kd)
        poles[i] = np.sort_complex(np.roots(closed_loop_polynomial(params, c)))
    return gains, poles


#: largest time step x fastest closed-loop pole |p| dt of :func:`step_response`: the matrix
#: exponential e^{A dt} of the sampled response loses all accuracy (NaN from about 1e50 on;
#: 1e20 still exact) far beyond any useful sampling.
MAX_STEP_POLE_PRODUCT = 1e12
#: largest growth sigma t_final of an unstable loop's response (e^700 ~ 1e304, near the
#: largest double).
MAX_GROWTH_EXPONENT = 700.0


def _step_horizon(poles: np.ndarray, n: int) -> float:
    """The longest t_final (s) of :func:`step_response` with ``n`` samples whose response is
    representable: (n - 1) MAX_STEP_POLE_PRODUCT / max|p|, and MAX_GROWTH_EXPONENT / max Re p
    for an unstable loop."""
    fastest = float(np.max(np.abs(poles))) if poles.size else 0.0
    limit = (n - 1) * MAX_STEP_POLE_PRODUCT / fastest if fastest > 0 else np.inf
    growth = float(np.max(poles.real)) if poles.size else 0.0
    if growth > 0:
        limit = min(limit, MAX_GROWTH_EXPONENT / growth)
    return limit


def step_response(params: ActuatorParameters, controller: PDController, t_final: float = 0.05,
                  amplitude: float = 1.0, n: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """Linear closed-loop step response of Eq. (4.18) (Figs 49, 51, 52, 53).

    ``t_final`` (s) > 0 at most the representable horizon: the time step t_final / (n - 1)
    times the fastest closed-loop pole |p| at most :data:`MAX_STEP_POLE_PRODUCT`, and for an
    unstable loop (max Re p > 0) the growth max Re p t_final at most
    :data:`MAX_GROWTH_EXPONENT` (ValueError naming t_final, n and the range otherwise);
    ``n`` an integer in [2, 1e7]; ``amplitude`` a finite real number.

    Returns (t in s, theta in the unit of ``amplitude``), both finite."""
    t_final = in_range("t_final", t_final)
    amplitude = finite("amplitude", amplitude)
    n = integer("n", n, low=2, high=10_000_000)
    loop = closed_loop(params, controller, require_stable=False)
    horizon = _step_horizon(np.asarray(ct.poles(loop)), n)
    if t_final > horizon:
        raise ValueError(f"t_final must be in (0, {horizon:.4g}] s with n = {n} samples (time "
                         f"step t_final / (n - 1) <= {horizon / (n - 1):.4g} s; an unstable "
                         f"loop grows past the float range beyond it), got {t_final:g}")
    t = np.linspace(0.0, t_final, n)
    resp = ct.step_response(loop, T=t)
    theta = finite_result("the step response", amplitude * np.squeeze(resp.outputs),
                          f"t_final = {t_final:g} s with n = {n} samples is too coarse or too "
                          "long for this loop; shorten t_final or give more samples")
    return resp.time, theta
