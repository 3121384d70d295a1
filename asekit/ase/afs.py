"""Active flutter suppression: the closed-loop aeroservoelastic model against airspeed (issue 26).

At a fixed Mach number and air density (the rational fit of the generalised aerodynamic forces
belongs to one Mach number; the density is the matched-point one of the flight condition) the
aeroservoelastic model of :func:`asekit.ase.loop.build_model` is rebuilt at each airspeed U: the
aerodynamic stiffness, damping and lag terms of Eq. (2.63) scale with q = rho U^2 / 2 and b / U.
Three systems come from it:

* the **locked** fin -- the aeroelastic model with its rigid pitch input held at zero (the
  transmission does not move): the state matrix ``A`` of Eq. (2.63); its first right-half-plane
  root is the open-loop flutter boundary of the rational-function model, to be compared with the
  p-k solution of the same case (:func:`asekit.aeroelastic.flutter.pk_flutter`), which uses the
  tabulated GAFs at the k of each root instead of the fit;
* the **plant** -- actuator and fin with the hinge moment fed back (Fig 58), voltage in, the
  transmission angle ``theta``, its rate ``omega``, the fin-root pitch ``fin_root_pitch`` and
  its rate ``fin_root_rate`` out (:func:`plant`);
* the **closed loop** -- the plant with a linear controller u = K(s) y (voltage from the
  measurements, positive feedback written into K), state matrix

      A_cl = [[A_p + B_p D_k C_p, B_p C_k], [B_k C_p, A_k]]                            (1)

  (strictly proper plant measurements, D_p = 0), :func:`closed_loop_matrix`.

The stability boundary of any of them is the first airspeed at which the largest real part of
the eigenvalues, g(U) = max Re lambda(A(U)), becomes positive: bracketed on the given airspeed
grid (the first grid point where g > 0 and the one before it) and bisected to ``tol``
(:func:`stability_boundary`), so the answer does not depend on the grid's spacing as long as the
grid brackets the first crossing (a root that crosses and returns between two grid points is not
seen).

A processor running the controller (sampled every T, its voltage applied one or more samples
later) changes the loop: :func:`sampled_closed_loop_matrix` gives the exact one-sample
transition matrix (zero-order-hold plant, Tustin controller, delay chain), whose eigenvalues z
take the place of lambda (growth rate ln|z| / T, :func:`sampled_growth_rate`).

Margins are those of the loop broken at the actuator input: L(s) = -K(s) P(s) (voltage to
voltage), SISO whatever the number of sensors, so Nyquist-counted margins
(:func:`asekit.ase.margins.nyquist_margins`, open-loop unstable poles counted) apply
(:func:`loop_at_input`).

SI units (m/s, rad, V, A); Hz only in reported frequencies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from asekit.ase.loop import (
    FIN_ROOT,
    AeroservoelasticModel,
    _plant,
    build_model,
    with_fin_root_rate,
)
from asekit.ase.sensors import Sensors, sensed_loop
from asekit.util.blas import small_dense
from asekit.util.validate import finite, positive

__all__ = ["SpeedFamily", "Boundary", "MEASUREMENTS", "AfsSimulation", "locked_matrix",
           "plant", "closed_loop_matrix", "sampled_closed_loop_matrix", "growth_rate",
           "sampled_growth_rate", "stability_boundary", "loop_at_input",
           "classical_controller", "lqg_controller", "discrete_lqg_controller",
           "sampled_loop_at_input", "sampled_phase_margin", "sampled_gain_margins",
           "simulate_release", "simulate_release_sampled", "Quantisers", "quantise"]

#: Plant outputs a flutter-suppression controller may measure (rad, rad/s).
MEASUREMENTS = ("theta", "omega", FIN_ROOT, "fin_root_rate")


@dataclass(frozen=True)
class SpeedFamily:
    """The aeroservoelastic model of one surface at a fixed Mach number and density, any speed.

    Attributes
    ----------
    modal : ModalModel-like
        Modal model with one rigid (actuator) pitch mode first (see
        :func:`asekit.ase.loop.build_model`).
    rfa : RogerFit or MinimumStateFit
        Rational fit of the GAFs at ``mach``.
    density : float
        Air density (kg/m^3), > 0.
    point_outputs : dict
        ``{name: row}`` modal output rows; must contain ``"fin_root_pitch"``.
    actuator : ActuatorParameters or None
        Motor and transmission (None: the thesis's).
    mach : float or None
        The Mach number of ``rfa`` (informational).
    """

    modal: object
    rfa: object
    density: float
    point_outputs: dict
    actuator: object = None
    mach: float | None = None

    def __post_init__(self):
        positive("density", self.density)

    def model(self, velocity: float) -> AeroservoelasticModel:
        """The aeroservoelastic model at airspeed ``velocity`` (m/s, > 0)."""
        positive("velocity", velocity)
        return build_model(self.modal, self.rfa, self.density, float(velocity),
                           self.point_outputs, actuator=self.actuator, mach=self.mach)


@dataclass(frozen=True)
class Boundary:
    """A stability boundary against airspeed.

    Attributes
    ----------
    speed : float or None
        First airspeed (m/s) with a root in the right half plane; None when none on the grid.
    frequency_hz : float or None
        |Im lambda| / (2 pi) of the crossing root at ``speed`` (Hz; 0 for a real root).
    bracket : tuple
        (last stable, first unstable) grid airspeeds (m/s) of the crossing.
    at_first_point : bool
        The system is already unstable at the first airspeed of the grid (``speed`` is then that
        airspeed, an upper bound).
    """

    speed: float | None
    frequency_hz: float | None
    bracket: tuple = ()
    at_first_point: bool = False


def locked_matrix(family: SpeedFamily, velocity: float) -> np.ndarray:
    """State matrix of the fin with its actuator locked (rigid pitch input held at zero):
    ``A`` of Eq. (2.63) at ``velocity`` (m/s)."""
    return np.array(family.model(velocity).A)


def plant(model: AeroservoelasticModel) -> ct.StateSpace:
    """Actuator + fin with the hinge moment fed back, input ``voltage`` (V), outputs
    :data:`MEASUREMENTS` (``fin_root_rate`` = d/dt of the fin-root pitch, from the states).

    The fin-root rate is C_r (A z + B u) + D_r0 omega (the root row C_r z + D_r0 theta
    differentiated along Eq. 2.63), the construction of :func:`asekit.ase.loop.closed_loop`.
    """
    p = _plant(model, with_fin_root_rate(model.aeroelastic))
    names = list(p.output_labels)
    idx = [names.index(o) for o in MEASUREMENTS + ("current",)]
    C, D = np.array(p.C)[idx], np.array(p.D)[idx]
    return ct.ss(p.A, p.B, C, D, inputs=["voltage"], outputs=list(MEASUREMENTS) + ["current"],
                 name="afs_plant")


def _controller_rows(controller: ct.StateSpace, p: ct.StateSpace):
    """Controller matrices with its inputs mapped onto the plant's outputs by name."""
    names = list(p.output_labels)
    unknown = [n for n in controller.input_labels if n not in MEASUREMENTS]
    if unknown or controller.noutputs != 1:
        raise ValueError(f"controller must map measurements among {MEASUREMENTS} (input "
                         f"names) to one output (voltage); got inputs "
                         f"{list(controller.input_labels)}, {controller.noutputs} outputs")
    sel = np.zeros((controller.ninputs, len(names)))
    for i, n in enumerate(controller.input_labels):
        sel[i, names.index(n)] = 1.0
    return sel


def closed_loop_matrix(model: AeroservoelasticModel, controller: ct.StateSpace) -> np.ndarray:
    """State matrix (1) of the plant under the voltage law u = K(s) y.

    Parameters
    ----------
    model : AeroservoelasticModel
        The plant at one airspeed.
    controller : control.StateSpace
        Continuous, inputs named among :data:`MEASUREMENTS`, one output (voltage, V); the sign
        of the feedback is part of K (u = +K y).

    Returns
    -------
    ndarray (n_plant + n_controller, n_plant + n_controller)
    """
    p = plant(model)
    sel = _controller_rows(controller, p)
    Ap, Bp = np.array(p.A), np.array(p.B)
    Cy = sel @ np.array(p.C)
    if np.any(sel @ np.array(p.D) != 0):
        raise ValueError("a measurement has a direct voltage term; not supported")
    Ak, Bk, Ck, Dk = (np.array(m, dtype=float) for m in
                      (controller.A, controller.B, controller.C, controller.D))
    nk = Ak.shape[0]
    top = np.hstack([Ap + Bp @ Dk @ Cy, Bp @ Ck]) if nk else Ap + Bp @ Dk @ Cy
    if not nk:
        return top
    return np.vstack([top, np.hstack([Bk @ Cy, Ak])])


def sampled_closed_loop_matrix(model: AeroservoelasticModel, controller: ct.StateSpace,
                               sample_time: float, delay_samples: int = 1) -> np.ndarray:
    """One-sample transition matrix of the plant under the controller run by a processor.

    The plant is discretised exactly with a zero-order hold over ``sample_time`` T
    (x_{k+1} = Ad x_k + Bd d_k, Ad = e^{A T}, Bd = int_0^T e^{A s} ds B, from the matrix
    exponential of [[A, B], [0, 0]] T), the continuous controller by Tustin's rule
    (:func:`control.c2d`), and the voltage computed from the sample y_k is applied
    ``delay_samples`` samples later (one sample of computation, exact in discrete time: a chain
    of held voltages d). State [x, x_k, d_1 .. d_nd] (Franklin, Powell & Workman, "Digital
    Control of Dynamic Systems", 3rd ed., Secs. 4.3 and 6.3). Stable when every eigenvalue lies
    inside the unit circle; ln|z| / T is the growth rate comparable with Re lambda.

    Parameters
    ----------
    model : AeroservoelasticModel
    controller : control.StateSpace
        Continuous (see :func:`closed_loop_matrix`; discretised by Tustin's rule) or discrete
        with dt = ``sample_time`` (used as it is).
    sample_time : float
        T (s), > 0.
    delay_samples : int
        Computational delay in samples, >= 0.

    Returns
    -------
    ndarray (n_plant + n_controller + delay_samples, same)
    """
    from scipy.linalg import expm

    ts = positive("sample_time", sample_time)
    nd = int(delay_samples)
    if nd != delay_samples or nd < 0:
        raise ValueError(f"delay_samples must be an integer >= 0, got {delay_samples!r}")
    p = plant(model)
    sel = _controller_rows(controller, p)
    A, B, Cy = np.array(p.A), np.array(p.B), sel @ np.array(p.C)
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = A * ts, B * ts
    E = expm(M)
    Ad, Bd = E[:n, :n], E[:n, n:]
    if controller.isdtime(strict=True):
        if abs(float(controller.dt) - ts) > 1e-12 * ts:
            raise ValueError(f"controller.dt must equal sample_time = {ts:g} s, got "
                             f"{controller.dt}")
        kd = controller
    else:
        kd = ct.c2d(ct.ss(controller.A, controller.B, controller.C, controller.D), ts,
                    "tustin")
    Ak, Bk, Ck, Dk = (np.array(m, dtype=float) for m in (kd.A, kd.B, kd.C, kd.D))
    nk = Ak.shape[0]
    u_row = np.hstack([(Dk @ Cy)[0], Ck[0] if nk else np.zeros(0)])   # u_k on [x, x_k]
    N = n + nk + nd
    P = np.zeros((N, N))
    P[:n, :n] = Ad
    if nk:
        P[n:n + nk, :n] = Bk @ Cy
        P[n:n + nk, n:n + nk] = Ak
    if nd == 0:
        P[:n, :n + nk] += Bd @ u_row[None, :]
        return P
    i_d = n + nk                     # d_1: the voltage applied during this sample
    P[:n, i_d] = Bd[:, 0]
    for q in range(nd - 1):
        P[i_d + q, i_d + q + 1] = 1.0
    P[i_d + nd - 1, :n + nk] = u_row
    return P


def growth_rate(A: np.ndarray) -> tuple[float, float]:
    """(max Re lambda (1/s), |Im| / (2 pi) of that root (Hz)) of the eigenvalues of ``A``.

    Examples
    --------
    >>> g, f = growth_rate([[0.0, 1.0], [-(2 * math.pi) ** 2, 0.2]])
    >>> round(g, 6), round(f, 4)
    (0.1, 0.9999)
    """
    lam = np.linalg.eigvals(np.asarray(A, float))
    i = int(np.argmax(lam.real))
    return float(lam[i].real), float(abs(lam[i].imag) / (2 * math.pi))


def sampled_growth_rate(P: np.ndarray, sample_time: float) -> tuple[float, float]:
    """(max ln|z| / T (1/s), |arg z| / (2 pi T) of that root (Hz)) of the eigenvalues z of a
    one-sample transition matrix: the discrete counterpart of :func:`growth_rate`.

    Examples
    --------
    >>> import numpy as np
    >>> z = np.exp((0.5 + 2j * np.pi * 10.0) * 1e-3)
    >>> g, f = sampled_growth_rate(np.diag([z, z.conjugate()]), 1e-3)
    >>> round(g, 9), round(f, 9)
    (0.5, 10.0)
    """
    z = np.linalg.eigvals(np.asarray(P, complex))
    i = int(np.argmax(np.abs(z)))
    return (float(math.log(abs(z[i])) / sample_time),
            float(abs(np.angle(z[i])) / (2 * math.pi * sample_time)))


@small_dense
def stability_boundary(matrix_at, velocities, tol: float = 1e-3,
                       sample_time: float | None = None) -> Boundary:
    """First airspeed at which ``matrix_at(U)`` has an eigenvalue with Re > 0.

    Parameters
    ----------
    matrix_at : callable
        ``matrix_at(U) -> ndarray`` state matrix at airspeed U (m/s).
    velocities : array_like
        Ascending airspeeds (m/s, > 0) scanned for the first unstable one.
    tol : float
        Bisection tolerance on the airspeed (m/s), > 0.
    sample_time : float, optional
        When given, ``matrix_at`` returns one-sample transition matrices
        (:func:`sampled_closed_loop_matrix`) and the growth rate is ln|z| / T.

    Returns
    -------
    Boundary
        The crossing, bisected inside its grid bracket; ``speed`` None when every grid
        airspeed is stable.

    Examples
    --------
    >>> import numpy as np
    >>> A = lambda U: np.array([[0.0, 1.0], [-100.0, U - 30.0]])   # damping 30 - U
    >>> b = stability_boundary(A, [10.0, 20.0, 50.0])
    >>> round(b.speed, 3), b.bracket
    (30.0, (20.0, 50.0))
    """
    U = np.asarray(velocities, dtype=float).ravel()
    if U.size < 1 or np.any(~np.isfinite(U)) or np.any(U <= 0) or np.any(np.diff(U) <= 0):
        raise ValueError("velocities must be ascending, finite and > 0")
    positive("tol", tol)
    if sample_time is None:
        rate = growth_rate
    else:
        positive("sample_time", sample_time)

        def rate(P):
            return sampled_growth_rate(P, sample_time)
    prev = None
    for u in U:
        g, f = rate(matrix_at(float(u)))
        if g > 0:
            if prev is None:
                return Boundary(float(u), f, (), True)
            lo, hi = prev, float(u)
            while hi - lo > tol:
                mid = 0.5 * (lo + hi)
                gm, fm = rate(matrix_at(mid))
                lo, hi, f = (lo, mid, fm) if gm > 0 else (mid, hi, f)
            return Boundary(hi, f, (prev, float(u)), False)
        prev = float(u)
    return Boundary(None, None, (), False)


def loop_at_input(model: AeroservoelasticModel, controller: ct.StateSpace) -> ct.StateSpace:
    """The loop broken at the actuator input, L(s) = -K(s) P(s) (V -> V), for
    :func:`asekit.ase.margins.nyquist_margins` (negative-feedback convention 1 + L)."""
    p = plant(model)
    sel = _controller_rows(controller, p)
    py = ct.ss(p.A, p.B, sel @ np.array(p.C), sel @ np.array(p.D))
    k = ct.ss(controller.A, controller.B, -np.array(controller.C), -np.array(controller.D))
    return ct.series(py, k)


# ---------------------------------------------------------------------------------------------
# controllers
# ---------------------------------------------------------------------------------------------
def classical_controller(gain: float, kp: float, kd: float, rate_gain: float,
                         lowpass_hz: float | None = None, lowpass_damping: float = 0.7
                         ) -> ct.StateSpace:
    """Position loop plus phase-stabilised fin-root rate feedback (a classical AFS law).

        u = -K_c (K_P theta + K_D omega) + g_r F(s) d/dt(theta_root),
        F(s) = w^2 / (s^2 + 2 zeta w s + w^2)                                     (2)

    The first term is the thesis's PD on the transmission angle (AEM1, Eq. 4.16, command
    omitted); the second feeds the measured fin-root pitch rate (a potentiometer at the shaft,
    differentiated, or a rate sensor) back into the voltage so that the actuator supplies the
    flutter mode with damping (the rate-feedback flutter suppression of Nissim, NASA TP-1137,
    1977, in its simplest one-sensor form); the low-pass F rolls the rate path off above the
    flutter frequency and sets its phase there (phase stabilisation; Zimmermann, "Aeroservo-
    elasticity", Comput. Methods Appl. Mech. Eng. 90, 1991, Sec. 4).

    Parameters
    ----------
    gain, kp, kd : float
        K_c (V/rad), K_P (-), K_D (s) of the position loop.
    rate_gain : float
        g_r (V s/rad), the sign included (positive: voltage in the direction of the root rate).
    lowpass_hz : float, optional
        Corner of F (Hz), > 0; None: no filter.
    lowpass_damping : float
        zeta of F, > 0.

    Returns
    -------
    control.StateSpace
        Inputs ``theta``, ``omega``, ``fin_root_rate``; output ``voltage``.

    Examples
    --------
    >>> K = classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    >>> K.nstates, list(K.input_labels)
    (2, ['theta', 'omega', 'fin_root_rate'])
    """
    for n, v in (("gain", gain), ("kp", kp), ("kd", kd), ("rate_gain", rate_gain)):
        finite(n, v)
    d = [[-gain * kp, -gain * kd, 0.0]]
    if lowpass_hz is None:
        return ct.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)),
                     [[d[0][0], d[0][1], rate_gain]], inputs=["theta", "omega", "fin_root_rate"],
                     outputs=["voltage"], name="classical AFS")
    w = 2 * math.pi * positive("lowpass_hz", lowpass_hz)
    z = positive("lowpass_damping", lowpass_damping)
    A = np.array([[0.0, 1.0], [-w * w, -2 * z * w]])
    B = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    C = np.array([[rate_gain * w * w, 0.0]])
    return ct.ss(A, B, C, d, inputs=["theta", "omega", "fin_root_rate"], outputs=["voltage"],
                 name="classical AFS")


def lqg_controller(model: AeroservoelasticModel, weight_root: float, weight_theta: float,
                   weight_voltage: float = 1.0, input_noise: float = 1.0,
                   measurement_noise: float = 1e-8,
                   measurements: tuple = ("theta", FIN_ROOT)) -> ct.StateSpace:
    """Continuous LQG regulator of the plant at one airspeed (the design point).

    LQR: u = -K x minimising the integral of weight_root (theta_root - theta)^2 +
    weight_theta theta^2 + weight_voltage u^2 (the elastic root twist and the transmission
    angle), K = R^-1 B^T P from the control Riccati equation; Kalman filter
    x^' = A x^ + B u + L (y - C x^) for white voltage noise of intensity ``input_noise`` (V^2 s)
    on the plant input and measurement noise ``measurement_noise`` (rad^2 s) on each of
    ``measurements`` (Anderson & Moore, "Optimal Control: Linear Quadratic Methods", 1990,
    Ch. 8; the LQG flutter suppression of Mukhopadhyay, J. Guid. Control 5 (1982)). The
    controller is x^' = (A - B K - L C) x^ + L y, u = -K x^.

    Parameters
    ----------
    model : AeroservoelasticModel
        The plant at the design airspeed.
    weight_root, weight_theta : float
        State weights (1/rad^2), >= 0 (not both zero).
    weight_voltage : float
        Voltage weight (1/V^2), > 0.
    input_noise, measurement_noise : float
        Noise intensities, > 0.
    measurements : tuple
        Plant outputs measured, among :data:`MEASUREMENTS`.

    Returns
    -------
    control.StateSpace
        Inputs ``measurements``, output ``voltage``, the plant's order.
    """
    from scipy.linalg import solve_continuous_are

    positive("weight_voltage", weight_voltage)
    positive("input_noise", input_noise)
    positive("measurement_noise", measurement_noise)
    for n, v in (("weight_root", weight_root), ("weight_theta", weight_theta)):
        if not (math.isfinite(v) and v >= 0):
            raise ValueError(f"{n} must be finite and >= 0, got {v!r}")
    if weight_root + weight_theta <= 0:
        raise ValueError("weight_root and weight_theta must not both be zero")
    bad = [m for m in measurements if m not in MEASUREMENTS]
    if bad or not measurements:
        raise ValueError(f"measurements must be among {MEASUREMENTS}, got {measurements}")
    p = plant(model)
    names = list(p.output_labels)
    A, B, C = np.array(p.A), np.array(p.B), np.array(p.C)
    c_th, c_r = C[names.index("theta")], C[names.index(FIN_ROOT)]
    n = A.shape[0]
    Q = weight_root * np.outer(c_r - c_th, c_r - c_th) + weight_theta * np.outer(c_th, c_th)
    Q += 1e-12 * np.eye(n)
    R = np.array([[weight_voltage]])
    P = solve_continuous_are(A, B, Q, R)
    K = np.linalg.solve(R, B.T @ P)
    Cm = C[[names.index(m) for m in measurements]]
    V = measurement_noise * np.eye(len(measurements))
    S = solve_continuous_are(A.T, Cm.T, input_noise * B @ B.T + 1e-12 * np.eye(n), V)
    L = S @ Cm.T @ np.linalg.inv(V)
    return ct.ss(A - B @ K - L @ Cm, L, -K, np.zeros((1, len(measurements))),
                 inputs=list(measurements), outputs=["voltage"], name="LQG AFS")


def discrete_lqg_controller(model: AeroservoelasticModel, sample_time: float,
                            weight_root: float, weight_theta: float, weight_voltage: float = 1.0,
                            input_noise: float = 1.0, measurement_noise: float = 1e-8,
                            measurements: tuple = ("theta", FIN_ROOT)) -> ct.StateSpace:
    """LQG regulator of the sampled plant with one sample of computational delay.

    Design model: the plant discretised with a zero-order hold over T, x_{k+1} = Ad x_k + Bd d_k,
    with d_k the voltage applied during sample k, computed one sample earlier: d_{k+1} = u_k.
    Discrete LQR on [x; d] (weights as :func:`lqg_controller`), u_k = -K [x^_k; d_k], and the
    steady-state Kalman predictor [x^; d]_{k+1} = Aa [x^; d]_k + Ba u_k + L (y_k - Ca [x^; d]_k)
    (Franklin, Powell & Workman, "Digital Control of Dynamic Systems", 3rd ed., Secs. 8.3 and
    9.5). The delay is in the design model, so the loop is the one
    :func:`sampled_closed_loop_matrix` builds with ``delay_samples=1``.

    Parameters
    ----------
    model : AeroservoelasticModel
        The plant at the design airspeed.
    sample_time : float
        T (s), > 0.
    weight_root, weight_theta, weight_voltage, input_noise, measurement_noise, measurements
        As :func:`lqg_controller`.

    Returns
    -------
    control.StateSpace
        Discrete (dt = T), inputs ``measurements``, output ``voltage`` (to apply next sample).
    """
    from scipy.linalg import expm, solve_discrete_are

    ts = positive("sample_time", sample_time)
    cont = lqg_controller(model, weight_root, weight_theta, weight_voltage, input_noise,
                          measurement_noise, measurements)          # checks every argument
    del cont
    p = plant(model)
    names = list(p.output_labels)
    A, B, C = np.array(p.A), np.array(p.B), np.array(p.C)
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = A * ts, B * ts
    E = expm(M)
    Aa = np.zeros((n + 1, n + 1))
    Aa[:n, :n], Aa[:n, n:] = E[:n, :n], E[:n, n:]
    Ba = np.zeros((n + 1, 1))
    Ba[n, 0] = 1.0
    c_th, c_r = C[names.index("theta")], C[names.index(FIN_ROOT)]
    Q = np.zeros((n + 1, n + 1))
    Q[:n, :n] = (weight_root * np.outer(c_r - c_th, c_r - c_th)
                 + weight_theta * np.outer(c_th, c_th))
    Q += 1e-12 * np.eye(n + 1)
    R = np.array([[weight_voltage]])
    P = solve_discrete_are(Aa, Ba, Q, R)
    K = np.linalg.solve(R + Ba.T @ P @ Ba, Ba.T @ P @ Aa)
    Ca = np.hstack([C[[names.index(m) for m in measurements]], np.zeros((len(measurements), 1))])
    bd = np.concatenate([E[:n, n], [0.0]])
    W = input_noise * np.outer(bd, bd) + 1e-12 * np.eye(n + 1)
    V = measurement_noise * np.eye(len(measurements))
    S = solve_discrete_are(Aa.T, Ca.T, W, V)
    L = Aa @ S @ Ca.T @ np.linalg.inv(Ca @ S @ Ca.T + V)
    return ct.ss(Aa - Ba @ K - L @ Ca, L, -K, np.zeros((1, len(measurements))), ts,
                 inputs=list(measurements), outputs=["voltage"], name="discrete LQG AFS")


def sampled_loop_at_input(model: AeroservoelasticModel, controller: ct.StateSpace,
                          sample_time: float, delay_samples: int = 1) -> ct.StateSpace:
    """The sampled loop broken at the actuator input, L(z) = -z^-nd K(z) P(z) (V -> V,
    discrete, dt = T): ZOH plant, the controller as in :func:`sampled_closed_loop_matrix`,
    ``delay_samples`` = nd samples of delay. Its closed loop 1 / (1 + L) has the eigenvalues of
    :func:`sampled_closed_loop_matrix`."""
    ts = positive("sample_time", sample_time)
    nd = int(delay_samples)
    if nd != delay_samples or nd < 0:
        raise ValueError(f"delay_samples must be an integer >= 0, got {delay_samples!r}")
    p = plant(model)
    sel = _controller_rows(controller, p)
    pd = ct.c2d(ct.ss(p.A, p.B, sel @ np.array(p.C), sel @ np.array(p.D)), ts, "zoh")
    if controller.isdtime(strict=True):
        kd = ct.ss(controller.A, controller.B, controller.C, controller.D, ts)
    else:
        kd = ct.c2d(ct.ss(controller.A, controller.B, controller.C, controller.D), ts, "tustin")
    loop = ct.series(pd, ct.ss(kd.A, kd.B, -np.array(kd.C), -np.array(kd.D), ts))
    if nd:
        delay = ct.ss(np.eye(nd, k=1), np.eye(nd)[:, -1:], np.eye(nd)[:1], 0.0, ts)
        loop = ct.series(loop, delay)
    return loop


@small_dense
def sampled_phase_margin(loop: ct.StateSpace, points: int = 5000) -> float | None:
    """Smallest phase margin (deg) of a discrete SISO loop L(e^{j w T}) over its gain crossovers
    |L| = 1 in 0 < w < pi / T (located on a grid of ``points`` and refined by Brent's method);
    None when |L| never crosses 1. PM = 180 deg + arg L, wrapped to (-180, 180].

    Examples
    --------
    >>> import control as ct
    >>> L = ct.ss([[0.5]], [[1.0]], [[0.8]], [[0.0]], 0.01)   # 0.8 / (z - 0.5)
    >>> round(sampled_phase_margin(L), 2)      # |e^{j theta} - 0.5| = 0.8 at cos theta = 0.61
    97.9
    """
    from scipy.optimize import brentq

    if not loop.isdtime() or loop.ninputs != 1 or loop.noutputs != 1:
        raise ValueError("loop must be a discrete SISO system")
    ts = float(loop.dt)
    A, B, C = np.array(loop.A), np.array(loop.B), np.array(loop.C)
    D = float(np.array(loop.D).ravel()[0])
    n = A.shape[0]

    def L(w):
        w = np.atleast_1d(np.asarray(w, float))
        out = np.empty(w.shape, complex)
        for s in range(0, w.size, 512):
            z = np.exp(1j * w[s:s + 512] * ts)
            m = z[:, None, None] * np.eye(n) - A
            out[s:s + 512] = (C @ np.linalg.solve(m, np.broadcast_to(B, (z.size, n, 1))))[:, 0, 0]
        return out + D

    w = np.linspace(1e-6, 1.0, points) * (math.pi / ts)
    mag = np.abs(L(w)) - 1.0
    pms = []
    for i in np.nonzero(np.sign(mag[:-1]) != np.sign(mag[1:]))[0]:
        wc = brentq(lambda x: abs(L(x)[0]) - 1.0, w[i], w[i + 1], xtol=1e-10)
        pm = 180.0 + math.degrees(np.angle(L(wc)[0]))
        pms.append((pm + 180.0) % 360.0 - 180.0)
    return None if not pms else float(min(pms, key=abs))


def sampled_gain_margins(matrix_for_gain, k_max: float = 100.0, tol: float = 1e-4):
    """Gain margins of a sampled loop from its eigenvalues: the interval of controller gain
    factors k around 1 in which ``matrix_for_gain(k)`` (a one-sample transition matrix with the
    controller's output scaled by k) has every eigenvalue inside the unit circle, bisected on
    |ln k| to ``tol`` (no frequency response needed; phase margins are not defined this way).

    Returns
    -------
    (lower, upper) : linear factors (lower 0 when stable down to k = 1 / k_max, upper inf when
    stable up to k_max), or None when the loop is unstable at k = 1.

    Examples
    --------
    >>> import numpy as np
    >>> lo, hi = sampled_gain_margins(lambda k: np.array([[0.5 - 0.3 * k]]))
    >>> round(lo, 3), round(hi, 3)
    (0.0, 5.0)
    """
    def stable(k):
        return np.max(np.abs(np.linalg.eigvals(matrix_for_gain(k)))) < 1.0

    if not stable(1.0):
        return None
    ends = []
    for far in (1.0 / k_max, k_max):
        if stable(far):
            ends.append(0.0 if far < 1 else math.inf)
            continue
        a, b = 0.0, math.log(far)                  # stable at exp(a), unstable at exp(b)
        while abs(b - a) > tol:
            m = 0.5 * (a + b)
            a, b = (m, b) if stable(math.exp(m)) else (a, m)
        ends.append(math.exp(a))
    return tuple(ends)


# ---------------------------------------------------------------------------------------------
# time simulation with the power limits
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AfsSimulation:
    """Histories of :func:`simulate_release` (SI): ``t`` (s), ``fin_root`` and ``theta`` (rad),
    ``voltage`` (applied, V), ``voltage_demand`` (V), ``current`` (A), ``voltage_limit`` (V,
    the clip +-min(V_supply, I_lim R))."""

    t: np.ndarray
    fin_root: np.ndarray
    theta: np.ndarray
    voltage: np.ndarray
    voltage_demand: np.ndarray
    current: np.ndarray
    voltage_limit: float

    @property
    def saturated(self) -> bool:
        """Whether the voltage demand ever exceeded the clip."""
        return bool(np.any(np.abs(self.voltage_demand) > self.voltage_limit))

    def amplitude_ratio(self, window: float = 0.02) -> float:
        """Peak |fin-root pitch| over the last ``window`` s over that of the first ``window``
        s (< 1: the motion decays)."""
        a = np.max(np.abs(self.fin_root[self.t <= self.t[0] + window]))
        b = np.max(np.abs(self.fin_root[self.t >= self.t[-1] - window]))
        return float(b / a)


@small_dense
def simulate_release(model: AeroservoelasticModel, controller: ct.StateSpace,
                     root_twist: float = math.radians(1.0), t_final: float = 0.2,
                     step: float = 2e-5, supply_voltage: float = 24.0,
                     current_limit: float = 10.0) -> AfsSimulation:
    """Free response of the closed loop after the fin is released from an elastic root twist,
    with the voltage clipped to +-min(V_supply, I_lim R) (thesis Eqs. 4.14-4.15).

    The initial state is the first elastic modal displacement alone, scaled so the fin-root
    pitch is ``root_twist`` (rad) with the transmission at rest. Plant and controller states
    are propagated exactly (matrix exponential, zero-order hold) over ``step`` with the
    clipped voltage held over each step (a continuous controller sampled at 1/step).

    Parameters
    ----------
    model : AeroservoelasticModel
    controller : control.StateSpace (see :func:`closed_loop_matrix`)
    root_twist : float
        Initial fin-root pitch (rad), nonzero.
    t_final, step : float
        Duration and propagation step (s), > 0.
    supply_voltage, current_limit : float
        V_supply (V) and I_lim (A), > 0.

    Returns
    -------
    AfsSimulation
    """
    from scipy.linalg import expm

    finite("root_twist", root_twist)
    if root_twist == 0:
        raise ValueError("root_twist must be nonzero")
    for n, v in (("t_final", t_final), ("step", step), ("supply_voltage", supply_voltage),
                 ("current_limit", current_limit)):
        positive(n, v)
    p = plant(model)
    sel = _controller_rows(controller, p)
    names = list(p.output_labels)
    Ap, Bp, Cp = np.array(p.A), np.array(p.B), np.array(p.C)
    Cy = sel @ Cp
    Ak, Bk, Ck, Dk = (np.array(m, dtype=float) for m in
                      (controller.A, controller.B, controller.C, controller.D))
    npl, nk = Ap.shape[0], Ak.shape[0]
    n = npl + nk
    M = np.zeros((n + 1, n + 1))
    M[:npl, :npl] = Ap
    M[:npl, n:] = Bp
    if nk:
        M[npl:n, :npl] = Bk @ Cy
        M[npl:n, npl:n] = Ak
    E = expm(M * step)
    Phi, Gam = E[:n, :n], E[:n, n]
    u_row = np.hstack([(Dk @ Cy)[0], Ck[0] if nk else np.zeros(0)])
    x = np.zeros(n)
    i_root = names.index(FIN_ROOT)
    x[_first_elastic_state(model)] = 1.0
    x *= root_twist / float(Cp[i_root] @ x[:npl])
    vmax = min(supply_voltage, current_limit * model.actuator.motor.resistance)
    k = int(math.ceil(t_final / step - 1e-9)) + 1
    X = np.empty((k, n))
    ud = np.empty(k)
    for j in range(k):
        X[j] = x
        ud[j] = u_row @ x
        x = Phi @ x + Gam * float(np.clip(ud[j], -vmax, vmax))
    Y = X[:, :npl] @ Cp.T
    return AfsSimulation(t=np.arange(k) * step, fin_root=Y[:, i_root],
                         theta=Y[:, names.index("theta")], voltage=np.clip(ud, -vmax, vmax),
                         voltage_demand=ud, current=Y[:, names.index("current")],
                         voltage_limit=float(vmax))


@dataclass(frozen=True)
class Quantisers:
    """Digital word lengths of the processor loop (None: ideal).

    Attributes
    ----------
    encoder_resolution : float or None
        Step (rad) of the transmission angle ``theta`` (a motor encoder of c counts per motor
        revolution behind the ratio N: 2 pi / (c N)); ``omega`` is then the backward difference
        of the quantised angle over one sample.
    adc_bits, adc_range : int or None, float
        Word length and full scale +-adc_range (rad) of the converter reading the fin-root
        pitch (and its rate, full scale adc_range / T).
    dac_bits, dac_range : int or None, float
        Word length and full scale +-dac_range (V) of the voltage demand.
    """

    encoder_resolution: float | None = None
    adc_bits: int | None = None
    adc_range: float = math.pi
    dac_bits: int | None = None
    dac_range: float = 24.0

    def __post_init__(self):
        if self.encoder_resolution is not None:
            positive("encoder_resolution", self.encoder_resolution)
        for n, b in (("adc_bits", self.adc_bits), ("dac_bits", self.dac_bits)):
            if b is not None and not (isinstance(b, int) and 2 <= b <= 32):
                raise ValueError(f"{n} must be an integer in [2, 32], got {b!r}")
        positive("adc_range", self.adc_range)
        positive("dac_range", self.dac_range)


def quantise(x, step: float, full_scale: float = math.inf):
    """Mid-tread quantiser: ``step`` round(x / step), saturated at +-full_scale.

    Examples
    --------
    >>> float(quantise(0.26, 0.1)), float(quantise(-3.0, 0.5, full_scale=1.0))
    (0.30000000000000004, -1.0)
    """
    return np.clip(step * np.round(np.asarray(x, float) / step), -full_scale, full_scale)


def _measure(y, names, q: Quantisers, ts, prev_theta):
    """The processor's sample of the measurements ``y`` (named ``names``) under ``q``."""
    y = np.array(y, float)
    th = None
    for i, n in enumerate(names):
        if n == "theta" and q.encoder_resolution is not None:
            y[i] = th = float(quantise(y[i], q.encoder_resolution))
        elif n in (FIN_ROOT, "fin_root_rate") and q.adc_bits is not None:
            fs = q.adc_range if n == FIN_ROOT else q.adc_range / ts
            y[i] = float(quantise(y[i], 2 * fs / 2 ** q.adc_bits, fs))
    if q.encoder_resolution is not None and "omega" in names:
        th = th if th is not None else float(quantise(y[names.index("theta")],
                                                      q.encoder_resolution))
        y[names.index("omega")] = (th - prev_theta) / ts
    return y, th


@small_dense
def simulate_release_sampled(model: AeroservoelasticModel, controller: ct.StateSpace,
                             sample_time: float, delay_samples: int = 1,
                             root_twist: float = math.radians(1.0), t_final: float = 0.2,
                             substeps: int = 10, supply_voltage: float = 24.0,
                             current_limit: float = 10.0,
                             quantisers: Quantisers | None = None,
                             sensors: Sensors | None = None) -> AfsSimulation:
    """:func:`simulate_release` with the controller run by a processor: sampled every
    ``sample_time`` T (a discrete controller with dt = T, or a continuous one discretised by
    Tustin's rule), its voltage clipped to +-min(V_supply, I_lim R) and applied
    ``delay_samples`` samples later, held over each sample (ZOH); the plant propagated exactly
    over T / ``substeps`` (histories on that grid). With ``quantisers`` the samples pass the
    encoder and the ADC and the demand the DAC (:class:`Quantisers`): the loop is then
    nonlinear and may settle in a quantisation limit cycle instead of at rest. With ``sensors``
    the measurements pass first-order sensors and carry seeded white noise
    (:mod:`asekit.ase.sensors`); None or ideal sensors give the sensor-free loop bit for bit.

    Returns
    -------
    AfsSimulation
        ``voltage_demand`` is the controller's output (before the clip) in force over each
        sample.
    """
    from scipy.linalg import expm

    ts = positive("sample_time", sample_time)
    nd = int(delay_samples)
    if nd != delay_samples or nd < 0:
        raise ValueError(f"delay_samples must be an integer >= 0, got {delay_samples!r}")
    finite("root_twist", root_twist)
    if root_twist == 0:
        raise ValueError("root_twist must be nonzero")
    for n_, v in (("t_final", t_final), ("supply_voltage", supply_voltage),
                  ("current_limit", current_limit)):
        positive(n_, v)
    m_sub = int(substeps)
    if m_sub < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps!r}")
    p = plant(model)
    sel = _controller_rows(controller, p)
    names = list(p.output_labels)
    A, B, Cp = np.array(p.A), np.array(p.B), np.array(p.C)
    Cy = sel @ Cp
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = A * ts / m_sub, B * ts / m_sub
    E = expm(M)
    Ad, Bd = E[:n, :n], E[:n, n]
    if controller.isdtime(strict=True):
        if abs(float(controller.dt) - ts) > 1e-12 * ts:
            raise ValueError(f"controller.dt must equal sample_time = {ts:g} s")
        kd = controller
    else:
        kd = ct.c2d(ct.ss(controller.A, controller.B, controller.C, controller.D), ts,
                    "tustin")
    Ak, Bk, Ck, Dk = (np.array(x, dtype=float) for x in (kd.A, kd.B, kd.C, kd.D))
    x = np.zeros(n)
    x[_first_elastic_state(model)] = 1.0
    x *= root_twist / float(Cp[names.index(FIN_ROOT)] @ x)
    xk = np.zeros(Ak.shape[0])
    held = [0.0] * nd
    vmax = min(supply_voltage, current_limit * model.actuator.motor.resistance)
    n_s = int(math.ceil(t_final / ts - 1e-9))
    X = np.empty((n_s * m_sub, n))
    v_app = np.empty(n_s * m_sub)
    v_dem = np.empty(n_s * m_sub)
    meas = list(kd.input_labels) if controller.isdtime(strict=True) else list(
        controller.input_labels)
    Ad, Bd, Cy, Cp, x, direct, lagged = sensed_loop(A, B, Cy, Cp, Ad, Bd, x, sensors, ts,
                                                    m_sub, n_s)
    X = np.empty((n_s * m_sub, x.size))
    prev_th = 0.0
    for k in range(n_s):
        y = Cy @ x + direct[k]
        if quantisers is not None:
            y, th = _measure(y, meas, quantisers, ts, prev_th)
            prev_th = prev_th if th is None else th
        u = float((Ck @ xk + Dk @ y)[0]) if Ak.size else float((Dk @ y)[0])
        if quantisers is not None and quantisers.dac_bits is not None:
            u = float(quantise(u, 2 * quantisers.dac_range / 2 ** quantisers.dac_bits,
                               quantisers.dac_range))
        xk = Ak @ xk + Bk @ y
        if nd:
            d, held = held[0], held[1:] + [u]
        else:
            d = u
        va = float(np.clip(d, -vmax, vmax))
        for j in range(m_sub):
            X[k * m_sub + j] = x
            x = Ad @ x + Bd * va + lagged[k]
        v_app[k * m_sub:(k + 1) * m_sub] = va
        v_dem[k * m_sub:(k + 1) * m_sub] = d
    Y = X @ Cp.T
    return AfsSimulation(t=np.arange(n_s * m_sub) * ts / m_sub, fin_root=Y[:, names.index(FIN_ROOT)],
                         theta=Y[:, names.index("theta")], voltage=v_app, voltage_demand=v_dem,
                         current=Y[:, names.index("current")], voltage_limit=float(vmax))


def _first_elastic_state(model: AeroservoelasticModel) -> int:
    """Index, in the state vector of :func:`plant`, of the first elastic modal displacement
    (the state that the plant's output ``zeta1`` reads alone)."""
    p = _plant(model)
    row = np.array(p.C[list(p.output_labels).index("zeta1")])
    j = int(np.argmax(np.abs(row)))
    if not (abs(row[j]) == 1.0 and np.count_nonzero(row) == 1):
        raise RuntimeError("the aeroelastic output zeta1 is not a state")
    return j
