"""Derivatives of the aeroservoelastic loop's state-space matrices, and of its gain and phase
margins, with respect to design parameters (issue 28).

The loop is the AEM1 loop of :mod:`asekit.ase.loop` broken where its margins are read: at the
controller, FWTF 2 = K_c (K_P + K_D s) x OPLOOP 2 (voltage -> transmission angle with the
aeroelastic hinge moment fed back), i.e. with the plant of :func:`asekit.ase.loop._loop_matrices`
(x = [theta, omega, I, z], x' = F x + g V)

    L(s) = c (s I - F)^-1 g,    c = K_c (K_P e_theta + K_D e_omega),                      (1)

negative feedback (closed loop x' = (F - g c) x).  F is assembled from the modal mass, damping
and stiffness M, K, C (rigid pitch mode first), the Roger coefficients A_j
(:mod:`asekit.rfa.roger`), the flight condition and the actuator, exactly as
:func:`asekit.aeroelastic.statespace.aeroelastic_matrices` (thesis Eqs. 2.60-2.70) and
:func:`asekit.ase.loop.build_model` do it: the effective fin inertia -D_hinge[2] becomes the
actuator's load inertia, J_total@motor = J_r + J_tr + J_eff / (N^2 eta) (Eq. 2.33), and the
remaining hinge moment C_h z + D_h0 theta + D_h1 omega loads the transmission (Eq. 2.71).

Derivatives. F is an analytic (rational) function of (M, K, C, A_j); its directional
derivative along (dM, dK, dC, dA_j) is taken by the complex step

    dF = Im F(M + i h dM, K + i h dK, C + i h dC, A_j + i h dA_j) / h,   h = 1e-30,       (2)

(Squire & Trapp, SIAM Rev. 40(1), 1998; Martins, Sturdza & Alonso, ACM TOMS 29(3), 2003,
Eq. 5): no subtraction, so the derivative is exact to round-off, not a finite difference.
The Roger lag realization (the E matrix of Eq. 2.63) is linear in A_j, so
E(A + i h dA) = E(A) + i h E(dA). dM, dK are the generalized (modal) mass and stiffness
derivatives of the design chain, dA_j = fit(dQ) (:func:`asekit.rfa.roger.roger_fit_derivative`).
The margins' derivatives then follow from :func:`asekit.ase.margin_sensitivity.\
margin_sensitivities` (implicit differentiation at the crossovers).

Only AEM1 (transmission-angle feedback) is differentiated here: AEM2 feeds back the fin-root
angle, whose output row also depends on the mode shapes at the shaft.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from asekit.ase.loop import actuated_state_matrix
from asekit.ase.margin_sensitivity import MarginSensitivity, margin_sensitivities
from asekit.rfa.roger import RogerFit
from asekit.servo.actuator import ActuatorParameters, PDController
from asekit.util.validate import positive

__all__ = ["LoopMatrices", "aem1_loop", "aem1_loop_derivatives", "aem1_margin_sensitivity"]

_H = 1e-30


@dataclass(frozen=True)
class LoopMatrices:
    """The SISO open loop L(s) = C (s I - A)^-1 B + D of Eq. (1) (negative feedback).

    Attributes
    ----------
    A : (n, n) F; B : (n, 1) g (1/H); C : (1, n) controller row (V/rad, V s/rad); D : (1, 1) 0.
    effective_fin_inertia : J_eff = -D_hinge[2] (kg m^2).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    effective_fin_inertia: float


def _check(M, K, C, rfa, density, velocity, actuator, controller):
    if not isinstance(rfa, RogerFit):
        raise ValueError(f"rfa must be a RogerFit (the minimum-state fit's D, E are not "
                         f"linear in its data), got {type(rfa).__name__}")
    M, K, C = (np.atleast_2d(np.asarray(a, float)) for a in (M, K, C))
    n = rfa.n_modes
    for name, a in (("M", M), ("K", K), ("C", C)):
        if a.shape != (n, n) or not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be finite ({n}, {n}) like the fit's modes, "
                             f"got {a.shape}")
    if n < 2:
        raise ValueError("the modal model needs the rigid pitch mode first and >= 1 elastic "
                         "mode")
    positive("density", density)
    positive("velocity", velocity)
    if not isinstance(actuator, ActuatorParameters):
        raise ValueError(f"actuator must be ActuatorParameters, got {type(actuator).__name__}")
    if not isinstance(controller, PDController):
        raise ValueError(f"controller must be a PDController, got {type(controller).__name__}")
    return M, K, C


def _aeroelastic(M, K, C, A, Dl, El, roots, b, rho, U):
    """A_sys, B_sys, C_h, D_h of Eqs. (2.60)-(2.70) for one rigid mode, complex-safe."""
    q = 0.5 * rho * U ** 2
    Mb, Cb, Kb = M - 0.5 * rho * b ** 2 * A[2], C - 0.5 * rho * b * U * A[1], K - q * A[0]
    c, s = slice(0, 1), slice(1, M.shape[0])
    ns, nL = M.shape[0] - 1, roots.size
    Mi = np.linalg.inv(Mb[s, s])
    nz = 2 * ns + nL
    As = np.zeros((nz, nz), dtype=Mb.dtype)
    Bs = np.zeros((nz, 3), dtype=Mb.dtype)
    As[:ns, ns:2 * ns] = np.eye(ns)
    As[ns:2 * ns, :ns] = -Mi @ Kb[s, s]
    As[ns:2 * ns, ns:2 * ns] = -Mi @ Cb[s, s]
    As[ns:2 * ns, 2 * ns:] = q * Mi @ Dl[s]
    As[2 * ns:, ns:2 * ns] = El[:, s]
    As[2 * ns:, 2 * ns:] = -np.diag(U / b * roots)
    Bs[2 * ns:, 1:2] = El[:, c]
    Bs[ns:2 * ns, 0:1] = -Mi @ Kb[s, c]
    Bs[ns:2 * ns, 1:2] = -Mi @ Cb[s, c]
    Bs[ns:2 * ns, 2:3] = -Mi @ Mb[s, c]
    row = np.hstack([-Kb[c, s], -Cb[c, s], q * Dl[c]])
    acc = np.hstack([-Kb[s, s], -Cb[s, s], q * Dl[s]])
    Ch = (row - Mb[c, s] @ Mi @ acc)[0]
    Dh = (np.hstack([-Kb[c, c], -Cb[c, c], -Mb[c, c]])
          - Mb[c, s] @ Mi @ np.hstack([-Kb[s, c], -Cb[s, c], -Mb[s, c]]))[0]
    return As, Bs, Ch, Dh


def _loop(M, K, C, A, Dl, El, roots, b, rho, U, actuator, controller):
    """F, g, c of Eq. (1) (complex-safe: F from :func:`asekit.ase.loop.actuated_state_matrix`,
    the matrix of the time simulation, with J_eff = -D_h[2] from the complex-step model)."""
    As, Bs, Ch, Dh = _aeroelastic(M, K, C, A, Dl, El, roots, b, rho, U)
    m, tr = actuator.motor, actuator.transmission
    N, eta = tr.ratio, tr.efficiency
    j_eff = -Dh[2]
    j_motor = m.rotor_inertia + tr.inertia + j_eff / (N * N * eta)          # Eq. (2.33)
    F, _, _ = actuated_state_matrix(As, Bs, Ch, Dh, m, N, eta, j_motor)
    n = F.shape[0]
    g = np.zeros((n, 1))
    g[2, 0] = 1.0 / m.inductance
    c = np.zeros((1, n))
    kc, kp, kd = controller.gain, controller.kp, controller.kd
    c[0, 0], c[0, 1] = kc * kp, kc * kd
    return F, g, c, j_eff


def aem1_loop(M, K, C, rfa: RogerFit, density: float, velocity: float,
              actuator: ActuatorParameters, controller: PDController) -> LoopMatrices:
    """The AEM1 open loop of Eq. (1) at (density kg/m^3, velocity m/s).

    Parameters
    ----------
    M, K, C : (n, n) modal mass (kg m^2 units of the modes), stiffness, damping, the rigid pitch
        mode (unit rotation, rad) first.
    rfa : :class:`asekit.rfa.RogerFit` of the same n modes at the flight Mach.
    density, velocity : > 0.
    actuator : the motor and transmission (its ``fin_inertia`` is replaced by J_eff).
    controller : the PD (gain K_c, K_P, K_D).

    Returns
    -------
    :class:`LoopMatrices`, whose transfer function is FWTF 2 of :func:`asekit.ase.loop.\
forward_path`.

    Examples
    --------
    >>> from asekit.servo.actuator import ActuatorParameters
    >>> from asekit.servo.actuator import SYSTEM_3
    >>> k = np.linspace(0.0, 1.0, 6)
    >>> Q = np.zeros((6, 2, 2), complex); Q[:, 0, 0] = 1e-4 * (1 + 0.3j * k)
    >>> from asekit.rfa.roger import roger_fit
    >>> fit = roger_fit(k, Q, 0.05, n_lags=1)
    >>> lm = aem1_loop(np.diag([1e-4, 1.0]), np.diag([0.0, 4e5]), np.zeros((2, 2)), fit,
    ...                1.2, 150.0, ActuatorParameters(), SYSTEM_3)
    >>> lm.A.shape, lm.effective_fin_inertia > 0
    ((7, 7), True)
    """
    M, K, C = _check(M, K, C, rfa, density, velocity, actuator, controller)
    Dl, El, roots, _ = rfa.lag_realization(1)
    F, g, c, j = _loop(M, K, C, rfa.A, Dl, El, roots, rfa.b_ref, float(density),
                       float(velocity), actuator, controller)
    if not j > 0:
        raise ValueError(f"effective fin inertia -D_hinge[2] = {j:g} is not positive: the "
                         "modal mass matrix or the RFA's A2 term is inconsistent")
    return LoopMatrices(F, g, c, np.zeros((1, 1)), float(j))


def _seq(x, n_var, shape, name):
    if x is None or len(x) == 0:
        return [np.zeros(shape)] * n_var
    if len(x) != n_var:
        raise ValueError(f"{name} has {len(x)} derivatives, expected {n_var} (one per parameter)")
    out = [np.asarray(a, float) for a in x]
    for a in out:
        if a.shape != shape or not np.all(np.isfinite(a)):
            raise ValueError(f"each {name} must be finite with shape {shape}, got {a.shape}")
    return out


def aem1_loop_derivatives(M, K, C, rfa: RogerFit, density: float, velocity: float,
                          actuator: ActuatorParameters, controller: PDController,
                          dM=(), dK=(), dC=(), dA=()) -> list[np.ndarray]:
    """dF/dtheta of the AEM1 loop for each design parameter, by the complex step (Eq. 2).

    Parameters
    ----------
    M, K, C, rfa, density, velocity, actuator, controller : as :func:`aem1_loop`.
    dM, dK, dC : sequences (one per parameter) of (n, n) modal-matrix derivatives (empty: 0).
    dA : sequence of (N + 3, n, n) Roger-coefficient derivatives
        (:func:`asekit.rfa.roger.roger_fit_derivative`).

    Returns
    -------
    list of (n_x, n_x) real dF/dtheta (g and c do not depend on the fin).

    Examples
    --------
    One parameter stiffening the elastic mode (dK = e2 e2^T): one (n_x, n_x) dF.

    >>> from asekit.servo.actuator import ActuatorParameters
    >>> from asekit.servo.actuator import SYSTEM_3
    >>> from asekit.rfa.roger import roger_fit
    >>> k = np.linspace(0.0, 1.0, 6)
    >>> Q = np.zeros((6, 2, 2), complex); Q[:, 0, 0] = 1e-4 * (1 + 0.3j * k)
    >>> fit = roger_fit(k, Q, 0.05, n_lags=1)
    >>> M, K = np.diag([1e-4, 1.0]), np.diag([0.0, 4e5])
    >>> d = aem1_loop_derivatives(M, K, 0 * M, fit, 1.2, 150.0, ActuatorParameters(), SYSTEM_3,
    ...                           dK=[np.diag([0.0, 1.0])])
    >>> len(d), d[0].shape
    (1, (7, 7))
    """
    M, K, C = _check(M, K, C, rfa, density, velocity, actuator, controller)
    n, shapeA = M.shape[0], rfa.A.shape
    n_var = max(len(dM), len(dK), len(dC), len(dA))
    dM, dK, dC = (_seq(x, n_var, (n, n), nm) for x, nm in ((dM, "dM"), (dK, "dK"), (dC, "dC")))
    dA = _seq(dA, n_var, shapeA, "dA")
    Dl, El, roots, _ = rfa.lag_realization(1)
    out = []
    for i in range(n_var):
        dEl = replace(rfa, A=dA[i]).lag_realization(1)[1]
        F = _loop(M + 1j * _H * dM[i], K + 1j * _H * dK[i], C + 1j * _H * dC[i],
                  rfa.A + 1j * _H * dA[i], Dl, El + 1j * _H * dEl, roots, rfa.b_ref,
                  float(density), float(velocity), actuator, controller)[0]
        out.append(F.imag / _H)
    return out


def aem1_margin_sensitivity(M, K, C, rfa: RogerFit, density: float, velocity: float,
                            actuator: ActuatorParameters, controller: PDController,
                            dM=(), dK=(), dC=(), dA=(), f_range_hz=(1.0, 1e4),
                            points: int = 4000) -> MarginSensitivity:
    """Gain and phase margins of the AEM1 loop (FWTF 2) and their design derivatives.

    Parameters
    ----------
    as :func:`aem1_loop_derivatives`; ``f_range_hz`` (Hz) and ``points`` set the logarithmic
    grid on which the crossovers are bracketed (then refined, :func:`asekit.ase.\
margin_sensitivity.margin_sensitivities`).

    Returns
    -------
    :class:`asekit.ase.margin_sensitivity.MarginSensitivity` (rad/s, deg, dB per unit of each
    parameter).

    Examples
    --------
    A heavier fin about the shaft (dM_cc = 1e-5 kg m^2 per unit parameter) loads the motor
    more: the phase margin at the ~128 Hz crossover drops.

    >>> from asekit.servo.actuator import ActuatorParameters, SYSTEM_3
    >>> from asekit.rfa.roger import roger_fit
    >>> k = np.linspace(0.0, 1.0, 6)
    >>> Q = np.zeros((6, 2, 2), complex); Q[:, 0, 0] = 1e-4 * (1 + 0.3j * k)
    >>> fit = roger_fit(k, Q, 0.05, n_lags=1)
    >>> M, K = np.diag([1e-4, 1.0]), np.diag([0.0, 4e5])
    >>> s = aem1_margin_sensitivity(M, K, 0 * M, fit, 1.2, 150.0, ActuatorParameters(),
    ...                             SYSTEM_3, dM=[np.diag([1e-5, 0.0])])
    >>> round(float(s.phase_margins_deg[0]), 2), bool(s.d_phase_margins_deg[0, 0] < 0)
    (79.15, True)
    """
    lm = aem1_loop(M, K, C, rfa, density, velocity, actuator, controller)
    dF = aem1_loop_derivatives(M, K, C, rfa, density, velocity, actuator, controller,
                               dM, dK, dC, dA)
    w = (2 * np.pi * f_range_hz[0], 2 * np.pi * f_range_hz[1])
    return margin_sensitivities(lm.A, lm.B, lm.C, lm.D, dA=dF, w_range=w, points=points)
