"""Digital fin-position controllers designed with the elastic fin in the loop (issue 15).

A controller here is a :class:`DigitalController`: a discrete state space sampled every
``sample_time`` (thesis Table 2: 1 kHz processor) with inputs ``cmd`` (commanded angle, rad),
``fb`` (the sampled feedback angle, rad) and ``v_applied`` (the voltage the amplifier applies,
after the supply clip, V; used by observer-based designs) and output ``voltage`` (the demand,
V), plus the indices of its integrator states, held while the demand is clipped
(conditional-integration anti-windup). :func:`asekit.ase.loop.simulate_sampled` and
:func:`asekit.ase.loop.closed_loop_sampled_matrix` run them against the aeroservoelastic plant.

Designs:

* :func:`pd_controller` -- the thesis's PD K_c (K_P + K_D s) as a digital controller (backward
  difference of the sampled feedback, the thesis's System 3 with the processor).
* :func:`pid_filtered` -- (a) the practitioners' extension: K_P + K_I/s + K_D s/(tau s + 1),
  followed by a second-order low-pass and notch filters on the aeroelastic modes; each filter
  discretised by Tustin's rule prewarped at its own frequency (Franklin, Powell & Workman,
  "Digital control of dynamic systems", 3rd ed., Sec. 6.3). :func:`design_filtered_pid`
  designs it from the open-loop frequency response (the notch frequencies are the resonances
  of the open loop) and sizes the gains for the largest stable bandwidth.
* :func:`lqg_integral` -- (b) a model-based design: LQG with integral action on the sampled
  (ZOH + computational delay) plant built with the minimum-state aerodynamics: discrete LQR
  on [x; x_delay; integral of error] (Franklin, Powell & Workman, Sec. 9.5) and a
  steady-state Kalman predictor driven by the applied voltage (which is the anti-windup).

Filters (continuous prototypes, s in rad/s):

    low-pass   w^2 / (s^2 + 2 zeta w s + w^2)
    notch      (s^2 + 2 zeta_z w s + w^2) / (s^2 + 2 zeta_p w s + w^2),  depth zeta_z / zeta_p

SI units (rad, V, s); Hz only in arguments named ``*_hz``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control as ct
import numpy as np

from asekit.util.validate import finite, positive

INPUTS = ("cmd", "fb", "v_applied")


@dataclass(frozen=True)
class DigitalController:
    """A sampled controller: ``ss`` discrete StateSpace (dt = sample period, inputs
    :data:`INPUTS`, output ``voltage``), ``integrator_states`` (indices held while the demand
    is clipped), ``name``, ``continuous`` (optional continuous prototype from the error to
    the voltage, for Bode plots), ``meta`` (design parameters)."""

    ss: ct.StateSpace
    integrator_states: tuple = ()
    name: str = ""
    continuous: ct.StateSpace | None = None
    meta: dict = field(default_factory=dict)

    @property
    def sample_time(self) -> float:
        return float(self.ss.dt)


def _dss(A, B, C, D, ts, name):
    return ct.ss(np.atleast_2d(A), np.atleast_2d(B), np.atleast_2d(C), np.atleast_2d(D), ts,
                 inputs=list(INPUTS), outputs=["voltage"], name=name)


def lowpass(f_hz: float, zeta: float = 0.7) -> ct.TransferFunction:
    """Second-order low-pass w^2 / (s^2 + 2 zeta w s + w^2), w = 2 pi f_hz."""
    w = 2 * np.pi * positive("f_hz", f_hz)
    positive("zeta", zeta)
    return ct.tf([w * w], [1.0, 2 * zeta * w, w * w])


def notch(f_hz: float, zeta_zero: float = 0.02, zeta_pole: float = 0.5) -> ct.TransferFunction:
    """Notch (s^2 + 2 zeta_z w s + w^2) / (s^2 + 2 zeta_p w s + w^2), w = 2 pi f_hz: unit gain
    far from w, depth zeta_z / zeta_p at w, width set by zeta_p."""
    w = 2 * np.pi * positive("f_hz", f_hz)
    positive("zeta_pole", zeta_pole)
    if not (0 <= zeta_zero < zeta_pole):
        raise ValueError(f"zeta_zero must be in [0, zeta_pole), got {zeta_zero}")
    return ct.tf([1.0, 2 * zeta_zero * w, w * w], [1.0, 2 * zeta_pole * w, w * w])


def _tustin(tf, ts, f_hz=None):
    w = None if f_hz is None else 2 * np.pi * f_hz
    return ct.sample_system(ct.ss(tf), ts, method="tustin", prewarp_frequency=w)


def pd_controller(gain: float, kp: float, kd: float, sample_time: float = 1e-3,
                  name: str = "PD") -> DigitalController:
    """The thesis's PD K_c (K_P e + K_D e') with e' the backward difference of the sampled
    feedback (the derivative acts on the measurement only, as in :mod:`asekit.ase.loop`):
    u_k = K_c K_P (r_k - y_k) - K_c K_D (y_k - y_{k-1}) / T. Its ``continuous`` prototype is
    K_c (K_P + K_D s) made proper by a 1 ns pole (for frequency responses only)."""
    for n, v in (("gain", gain), ("kp", kp), ("kd", kd)):
        finite(n, v)
    ts = positive("sample_time", sample_time)
    kc = gain
    # state: y_{k-1}
    A = [[0.0]]
    B = [[0.0, 1.0, 0.0]]
    C = [[kc * kd / ts]]
    D = [[kc * kp, -kc * kp - kc * kd / ts, 0.0]]
    cont = ct.ss(ct.tf([kc * kd, kc * kp], [1.0]) * ct.tf([1.0], [1e-9, 1.0])) \
        if kd else ct.ss(ct.tf([kc * kp], [1.0]))
    return DigitalController(ss=_dss(A, B, C, D, ts, name), integrator_states=(), name=name,
                             continuous=cont, meta={"gain": gain, "kp": kp, "kd": kd})


def pid_filtered(kp: float, ki: float, kd: float, tau_d: float, lowpass_hz: float | None,
                 notches=(), sample_time: float = 1e-3, lowpass_zeta: float = 0.7,
                 setpoint_weight: float = 0.0, name: str = "PID + filters") -> DigitalController:
    """(a) u = F(s) [b K_P r + K_I/s (r - y) - (K_P + K_D s/(tau_d s + 1)) y]: integral action
    on the error, proportional and (filtered) derivative on the measurement with set-point
    weight b (``setpoint_weight``; b = 1 puts K_P on the error), F the product of a low-pass
    (``lowpass_hz``; None: none) and the ``notches`` ((f_hz, zeta_zero, zeta_pole) each).

    Why the two-degree-of-freedom form: with an open-loop unstable real pole p (here the
    de-centering hinge moment, p ~ 15 rad/s) every one-degree-of-freedom loop has
    S(p) = 0, so the error of a step obeys int_0^inf e(t) exp(-p t) dt = 0 and must change sign:
    overshoot is unavoidable (Middleton, "Trade-offs in linear control system design",
    Automatica 27(2), 1991). The reference path b K_P + K_I/s differs from the feedback path,
    which removes that constraint from the reference response.

    The integrator is a separate forward-Euler state x_i (state 0, held for anti-windup); the
    PD part and each filter are Tustin-discretised (prewarped at the filter's frequency) and
    cascaded. kp (V/rad), ki (V/(rad s)), kd (V s/rad), tau_d (s, > 0), sample_time (s).
    """
    for n, v in (("kp", kp), ("ki", ki), ("kd", kd), ("setpoint_weight", setpoint_weight)):
        finite(n, v)
    positive("tau_d", tau_d)
    ts = positive("sample_time", sample_time)
    pd_c = ct.tf([kd + kp * tau_d, kp], [tau_d, 1.0])          # K_P + K_D s/(tau s + 1)
    pd_d = _tustin(pd_c, ts, None)
    filt_c = ct.tf([1.0], [1.0])
    chain = None
    parts = []
    if lowpass_hz is not None:
        parts.append((lowpass(lowpass_hz, lowpass_zeta), lowpass_hz))
    for f, zz, zp in notches:
        parts.append((notch(f, zz, zp), f))
    for tf_, f in parts:
        filt_c = filt_c * tf_
        d = _tustin(tf_, ts, f)
        chain = d if chain is None else ct.series(chain, d)
    if chain is None:
        chain = ct.ss([], [], [], [[1.0]], ts)

    def mats(sys):
        A, B, C, D = (np.array(x, float) for x in (sys.A, sys.B, sys.C, sys.D))
        n = A.shape[0] if A.size else 0
        return A.reshape(n, n), B.reshape(n, 1), C.reshape(1, n), float(D.ravel()[0]), n

    Ap, Bp, Cp, Dp, npd = mats(pd_d)
    Af, Bf, Cf, Df, nf = mats(chain)
    n = 1 + npd + nf
    ip, jf = slice(1, 1 + npd), slice(1 + npd, n)
    A = np.zeros((n, n))
    B = np.zeros((n, 3))
    A[0, 0] = 1.0
    B[0, 0], B[0, 1] = ts, -ts                                  # x_i += T (r - y)
    A[ip, ip] = Ap
    B[ip, 1:2] = Bp                                             # PD acts on y
    # chain input w = K_I x_i - (Cp x_pd + Dp y) + b K_P r
    wx = np.zeros((1, n))
    wx[0, 0] = ki
    wx[0, ip] = -Cp[0]
    wr, wy = setpoint_weight * kp, -Dp
    A[jf, :] += Bf @ wx
    A[jf, jf] += Af
    B[jf, 0:1] = Bf * wr
    B[jf, 1:2] = Bf * wy
    C = Df * wx
    C[0, jf] += Cf[0]
    D = np.array([[Df * wr, Df * wy, 0.0]])
    cont = ct.ss(filt_c * (pd_c + ct.tf([ki], [1.0, 0.0])))    # loop: error -> voltage
    return DigitalController(ss=_dss(A, B, C, D, ts, name), integrator_states=(0,), name=name,
                             continuous=cont,
                             meta={"kp": kp, "ki": ki, "kd": kd, "tau_d": tau_d,
                                   "lowpass_hz": lowpass_hz, "notches": tuple(notches),
                                   "setpoint_weight": setpoint_weight})



def lqg_integral(plant, weight_error: float, weight_integral: float, weight_voltage: float,
                 input_noise: float = 1.0, measurement_noise: float = 1e-4,
                 reference_time_constant: float | None = None,
                 name: str = "LQG + integral") -> DigitalController:
    """(b) LQG with integral action on a sampled plant (ZOH, one sample of computational delay).

    Design model (from :func:`asekit.ase.loop.sampled_plant`, built with any RFA -- the minimum-state
    fit keeps it small): x_{k+1} = A x_k + B d_k, y_k = C x_k, with d_k the voltage applied
    during sample k (computed at k - 1: d_{k+1} = u_k) and the integral of the fin-root error
    x_i,k+1 = x_i,k + T (r_k - y_k). Discrete LQR (Franklin, Powell & Workman, Sec. 9.5) on
    [x; d; x_i] with J = sum (weight_error y^2 + weight_integral x_i^2 + weight_voltage u^2)
    gives u = -K_x x - K_d d - K_i x_i; the reference enters through the steady state
    (x_ss, u_ss) that holds y = r (a two-degree-of-freedom servo, so the unstable pole's
    overshoot constraint on one-degree-of-freedom loops does not apply):

        u_k = -K_x (x^_k - x_ss r) - K_d (d_k - u_ss r) - K_i x_i,k + u_ss r.

    The state comes from the steady-state Kalman predictor x^_{k+1} = A x^_k + B d_k +
    L (y_k - C x^_k) for voltage noise of variance ``input_noise`` (V^2) on the plant input and
    measurement noise ``measurement_noise`` (rad^2), driven by the applied voltage d_k (the
    controller's ``v_applied`` input), which is its anti-windup; x_i is held while the demand
    is clipped.

    With ``reference_time_constant`` tau (s) the command first passes a critically damped
    second-order reference model (two discrete first-order lags exp(-T/tau)), so the servo
    follows a smooth trajectory instead of a step.

    Parameters: ``plant`` a :class:`asekit.ase.loop.SampledPlant`; weights (1/rad^2, 1/(rad s)^2,
    1/V^2) > 0. Returns a :class:`DigitalController` with states [x^, x_i (, r_1, r_2)].
    """
    from scipy.linalg import solve_discrete_are

    for n_, v in (("weight_error", weight_error), ("weight_integral", weight_integral),
                  ("weight_voltage", weight_voltage), ("input_noise", input_noise),
                  ("measurement_noise", measurement_noise)):
        positive(n_, v)
    A, B = np.asarray(plant.Ad_sample), np.asarray(plant.Bd_sample)
    Cm = np.asarray(plant.C[plant.i_meas:plant.i_meas + 1])
    ts = float(plant.sample_time)
    n = A.shape[0]
    # augmented [x; d; x_i], input u
    Aa = np.zeros((n + 2, n + 2))
    Aa[:n, :n], Aa[:n, n:n + 1] = A, B
    Aa[n + 1, :n] = -ts * Cm[0]
    Aa[n + 1, n + 1] = 1.0
    Ba = np.zeros((n + 2, 1))
    Ba[n, 0] = 1.0
    Q = np.zeros((n + 2, n + 2))
    Q[:n, :n] = weight_error * Cm.T @ Cm
    Q[n + 1, n + 1] = weight_integral
    Q += 1e-9 * np.eye(n + 2) * max(weight_error, 1.0)
    R = np.array([[weight_voltage]])
    P = solve_discrete_are(Aa, Ba, Q, R)
    K = np.linalg.solve(R + Ba.T @ P @ Ba, Ba.T @ P @ Aa)         # (1, n + 2)
    Kx, Kd, Ki = K[:, :n], float(K[0, n]), float(K[0, n + 1])
    # steady state holding y = 1: (A - I) x + B u = 0, C x = 1
    M = np.block([[A - np.eye(n), B], [Cm, np.zeros((1, 1))]])
    sol = np.linalg.solve(M, np.concatenate([np.zeros(n), [1.0]]))
    x_ss, u_ss = sol[:n], float(sol[n])
    # Kalman predictor gain
    W = input_noise * B @ B.T + 1e-12 * np.eye(n)
    Pk = solve_discrete_are(A.T, Cm.T, W, np.array([[measurement_noise]]))
    L = A @ Pk @ Cm.T @ np.linalg.inv(Cm @ Pk @ Cm.T + measurement_noise)   # (n, 1)
    Ac = np.zeros((n + 1, n + 1))
    Ac[:n, :n] = A - L @ Cm
    Ac[n, n] = 1.0
    Bc = np.zeros((n + 1, 3))
    Bc[:n, 1:2] = L
    Bc[:n, 2:3] = B
    Bc[n, 0], Bc[n, 1] = ts, -ts
    Cc = np.hstack([-Kx, [[-Ki]]])
    Nr = float((Kx @ x_ss)[0]) + Kd * u_ss + u_ss
    Dc = np.array([[Nr, 0.0, -Kd]])
    if reference_time_constant is not None:
        a = math.exp(-ts / positive("reference_time_constant", reference_time_constant))
        # r_1' = a r_1 + (1 - a) r, r_2' = a r_2 + (1 - a) r_1; the servo uses r_2
        m = n + 1
        Ac2 = np.zeros((m + 2, m + 2))
        Ac2[:m, :m] = Ac
        Ac2[m, m] = a
        Ac2[m + 1, m + 1], Ac2[m + 1, m] = a, 1 - a
        Ac2[:m, m + 1] = Bc[:, 0]                       # the reference input now r_2
        Bc2 = np.zeros((m + 2, 3))
        Bc2[:m, 1:] = Bc[:, 1:]
        Bc2[m, 0] = 1 - a
        Cc2 = np.hstack([Cc, [[0.0, Dc[0, 0]]]])
        Dc2 = np.array([[0.0, 0.0, Dc[0, 2]]])
        Ac, Bc, Cc, Dc = Ac2, Bc2, Cc2, Dc2
    return DigitalController(ss=_dss(Ac, Bc, Cc, Dc, ts, name), integrator_states=(n,),
                             name=name,
                             meta={"weight_error": weight_error,
                                   "weight_integral": weight_integral,
                                   "weight_voltage": weight_voltage, "input_noise": input_noise,
                                   "measurement_noise": measurement_noise,
                                   "reference_time_constant": reference_time_constant,
                                   "design_states": n, "u_ss": u_ss})
