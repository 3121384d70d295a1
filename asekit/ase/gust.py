"""The gust in the closed aeroservoelastic loop (issue 27): motor current and fin motion of the
AEM1 loop (motor-angle feedback, thesis Ch. 5) in a gust, linear (no voltage or current
limits).

The loop of :func:`asekit.ase.loop.simulate_closed_loop` (its matrices
``asekit.ase.loop._loop_matrices``: x = [theta, omega, I, z], x' = F x + g V, V = k x for a
zero command) gains the gust of :class:`asekit.aeroelastic.gust.GustStateSpace` built with
the same modal model and fit: its gust lag states x_g extend the state, and with the gust
inputs u_g = [w_g, w_g', w_g''] the hinge moment becomes T0 = hm_row x + C_hg x_g + D_hg u_g,
so (thesis Eqs. 2.30-2.37)

    omega' = alpha = (K_t I + T0 / (N eta) - c N omega) / (N J_total@motor),
    z'     = A z + B [theta, omega, alpha] + A_zg x_g + B_g,z u_g,
    x_g'   = A_gg x_g + B_g,g u_g.

The result is x_cl' = A_cl x_cl + G u_g, integrated by a first-order hold (scipy.signal.lsim).
With AEM2 (fin-root feedback, thesis Ch. 5) the PD acts on theta_fb = C_r z + D_r0 theta and
its rate C_r z' + D_r0 omega, and z' carries the gust terms, so the demand gains a gust
feed-through: V_cmd = k x_cl + k_g u_g.

Power limits (:func:`limited_gust_response`): the applied voltage is the PD demand clipped as
in the servo chapter (:func:`asekit.servo.simulate.applied_voltage`: the current limit as the
voltage clip |V| <= I_lim R of thesis Eqs. 4.14-4.15 or a current regulator, then the supply
clip), a piecewise-affine loop propagated exactly (:class:`asekit.servo.piecewise.
PiecewiseAffineLoop`) with the gust input held first-order (linear over each step, as
scipy.signal.lsim's first-order hold) by an exosystem u' = du, du' = 0 appended to the state
and reset at every step; without binding limits it is the linear response. Up to the sample
before the linear demand first comes within 5 % of a limit (:data:`NEAR_LIMIT`) the loop is
linear and lsim's states are kept; the exact propagation starts there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asekit.aeroelastic.gust import GustStateSpace
from asekit.ase.loop import AeroservoelasticModel, _loop_matrices
from asekit.servo.actuator import PDController
from asekit.util.validate import finite_array


@dataclass(frozen=True)
class ClosedLoopGust:
    """The AEM1 or AEM2 loop with the gust input: ``A`` (n, n), ``G`` (n, 3) over [w_g, w_g',
    w_g''] (m/s, m/s^2, m/s^3), ``current_row`` (n,) (A per state), ``theta_row`` (n,) (rad),
    ``hinge_row`` (n,) and ``hinge_gust`` (3,) (N m: T0 without the fin-inertia term).

    The loop opened at the motor voltage V (for the power limits): x' = F x + g V + G_open u_g,
    with the PD demand V_cmd = k x + k_gust u_g (``k_gust`` zero for AEM1), so that
    A = F + g k and G = G_open + g k_gust; None when not built (a loop given by A, G only)."""

    A: np.ndarray
    G: np.ndarray
    current_row: np.ndarray
    theta_row: np.ndarray
    hinge_row: np.ndarray
    hinge_gust: np.ndarray
    F: np.ndarray | None = None
    g: np.ndarray | None = None
    G_open: np.ndarray | None = None
    k: np.ndarray | None = None
    k_gust: np.ndarray | None = None
    topology: str = "AEM1"


def _check_gust_ss(model: AeroservoelasticModel, gust_ss: GustStateSpace) -> int:
    nz0 = model.A.shape[0]
    if (gust_ss.n_rigid != 1 or gust_ss.A.shape[0] < nz0
            or not np.allclose(gust_ss.A[:nz0, :nz0], model.A, rtol=1e-10,
                               atol=1e-10 * np.abs(model.A).max())):
        raise ValueError("gust_ss must be the gust state space of the model's modal model, fit "
                         "and flight condition (its aeroelastic block differs from model.A)")
    return nz0


def closed_loop_gust(model: AeroservoelasticModel, controller: PDController,
                     gust_ss: GustStateSpace, topology: str = "AEM1") -> ClosedLoopGust:
    """The AEM1 or AEM2 closed loop with the gust input (module docstring).

    Parameters
    ----------
    model : :func:`asekit.ase.loop.build_model`'s model (modal model with one rigid mode).
    controller : the PD controller.
    gust_ss : :func:`asekit.aeroelastic.gust.gust_state_space` of the same modal model, fit,
        density and velocity (checked: its first block must equal ``model.A``).
    topology : ``"AEM1"`` (motor-angle feedback) or ``"AEM2"`` (fin-root pitch feedback,
        whose rate C_r z' carries the gust terms of z').

    Returns
    -------
    :class:`ClosedLoopGust`
    """
    if topology not in ("AEM1", "AEM2"):
        raise ValueError(f"topology must be 'AEM1' or 'AEM2', got {topology!r}")
    nz0 = _check_gust_ss(model, gust_ss)
    mats = _loop_matrices(model, controller, 0.0, topology)
    F0, g0 = mats["F"], mats["g"]
    act = model.actuator
    N, eta = act.transmission.ratio, act.transmission.efficiency
    nj = N * act.inertia_at_motor
    n0 = F0.shape[0]
    ng = gust_ss.n_states - nz0
    n = n0 + ng
    B = model.B
    z = slice(3, 3 + nz0)
    F = np.zeros((n, n))
    F[:n0, :n0] = F0
    alpha_lag = gust_ss.C_hinge[0, nz0:] / (N * eta) / nj
    F[1, n0:] = alpha_lag
    F[z, n0:] = gust_ss.A[:nz0, nz0:] + np.outer(B[:, 2], alpha_lag)
    F[n0:, n0:] = gust_ss.A[nz0:, nz0:]
    G_open = np.zeros((n, 3))
    alpha_w = gust_ss.Dg_hinge[0] / (N * eta) / nj
    G_open[1] = alpha_w
    G_open[z] = gust_ss.B_g[:nz0] + np.outer(B[:, 2], alpha_w)
    G_open[n0:] = gust_ss.B_g[nz0:]
    g = np.concatenate([g0, np.zeros(ng)])
    k = np.concatenate([mats["k"], np.zeros(ng)])
    k_gust = np.zeros(3)
    if topology == "AEM2":
        # omega_fb = C_r z' + D_r0 omega: z' gains the gust lag and input terms
        Cr = mats["fb_row"][3:]
        kc, kd = controller.gain, controller.kd
        k[n0:] = -kc * kd * (Cr @ F[z, n0:])
        k_gust = -kc * kd * (Cr @ G_open[z])
    cur, th = np.zeros(n), np.zeros(n)
    cur[2], th[0] = 1.0, 1.0
    hinge = np.concatenate([mats["hm_row"], gust_ss.C_hinge[0, nz0:]])
    return ClosedLoopGust(F + np.outer(g, k), G_open + np.outer(g, k_gust), cur, th, hinge,
                          gust_ss.Dg_hinge[0].copy(), F, g, G_open, k, k_gust, topology)


def closed_loop_gust_response(loop: ClosedLoopGust, t, gust) -> dict:
    """Response from rest to the gust inputs ``gust`` (3, n_t) at the ascending times ``t``
    (s): ``current`` (A), ``theta`` (rad), ``hinge_moment`` (N m, T0) histories (n_t,).

    With the open-loop matrices (a loop of :func:`closed_loop_gust`) also ``voltage`` (V),
    the linear PD demand k x + k_gust u_g.

    Raises ValueError for a loop that is not asymptotically stable (no bounded response)."""
    from scipy.signal import lsim

    tt = finite_array("t", t).ravel()
    gu = finite_array("gust", gust)
    if gu.shape != (3, tt.size):
        raise ValueError(f"gust must be (3, len(t)) = (3, {tt.size}), got {gu.shape}")
    if np.max(np.linalg.eigvals(loop.A).real) >= 0:
        raise ValueError("the AEM1 loop with the gust is unstable at this flight condition")
    n = loop.A.shape[0]
    _, _, x = lsim((loop.A, loop.G, np.eye(n), np.zeros((n, 3))), gu.T, tt, interp=True)
    x = np.atleast_2d(x).reshape(tt.size, n)
    out = {"current": x @ loop.current_row, "theta": x @ loop.theta_row,
           "hinge_moment": x @ loop.hinge_row + gu.T @ loop.hinge_gust}
    if loop.k is not None:
        out["voltage"] = x @ loop.k + gu.T @ loop.k_gust
    return out


def closed_loop_gust_frequency_response(loop: ClosedLoopGust, omega) -> dict:
    """Frequency responses of the loop per unit gust velocity (w_g = e^{i omega t} m/s, so
    u_g = [1, i omega, -omega^2] w_g): ``current`` (A per m/s), ``theta`` (rad per m/s),
    ``hinge_moment`` (N m per m/s), each (n_w,) complex, from
    x = (i omega I - A)^-1 G u_g.

    Examples
    --------
    >>> import numpy as np
    >>> loop = ClosedLoopGust(np.array([[-2.0]]), np.array([[4.0, 0.0, 0.0]]),
    ...                       np.array([1.0]), np.array([0.0]), np.array([0.0]), np.zeros(3))
    >>> complex(closed_loop_gust_frequency_response(loop, [0.0])["current"][0])   # 4 / 2
    (2+0j)
    """
    w = finite_array("omega", omega).ravel()
    n = loop.A.shape[0]
    u = np.stack([np.ones_like(w), 1j * w, -w ** 2], axis=1).astype(complex)
    x = np.stack([np.linalg.solve(1j * wi * np.eye(n) - loop.A, loop.G @ ui)
                  for wi, ui in zip(w, u)])
    return {"current": x @ loop.current_row, "theta": x @ loop.theta_row,
            "hinge_moment": x @ loop.hinge_row + u @ loop.hinge_gust}


#: A limit counts as near when the linear demand comes within this fraction of the half-width
#: of its band (lo, hi) at a sample: from the sample before, the loop is propagated exactly.
NEAR_LIMIT = 0.05


def _first_near_limit(pw, X, loop, t, gust):
    """Fill X[:, :n] with the linear loop's states (lsim, first-order hold) and return the
    first sample before the PD demand comes within NEAR_LIMIT of a bound (None if never)."""
    from scipy.signal import lsim

    n = loop.A.shape[0]
    _, _, x = lsim((loop.A, loop.G, np.eye(n), np.zeros((n, 3))), gust.T, t, interp=True)
    X[:, :n] = np.atleast_2d(x).reshape(t.size, n)
    val = pw.values(X.T)
    near = np.zeros(t.size, bool)
    for lo, hi in ((1, 2), (3, 4)):
        if lo in val:
            m = NEAR_LIMIT * 0.5 * np.abs(val[hi] - val[lo])
            near |= (val[0] < val[lo] + m) | (val[0] > val[hi] - m)
    if not near.any():
        return None
    return max(int(np.argmax(near)) - 1, 0)


def limited_gust_response(loop: ClosedLoopGust, actuator, limits, t, gust) -> dict:
    """Response from rest of the loop with the actuator's power limits to the gust inputs
    ``gust`` (3, n_t) at the uniformly spaced times ``t`` (s) (module docstring).

    Parameters
    ----------
    loop : :func:`closed_loop_gust`'s loop (with its open-loop matrices).
    actuator : :class:`asekit.servo.actuator.ActuatorParameters` of the loop's model.
    limits : :class:`asekit.servo.simulate.PowerLimits` (supply voltage, current limit).
    t : (n_t,) uniform ascending times (s); gust : (3, n_t) w_g, w_g', w_g''.

    Returns
    -------
    dict ``current`` (A), ``voltage`` (applied, V), ``demand`` (PD demand, V), ``theta``
    (rad) histories (n_t,), and ``saturated`` (bool: a limit bound at some time).

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from asekit.servo.simulate import PowerLimits
    >>> motor = SimpleNamespace(resistance=1.0, inductance=1.0, back_emf_constant=0.0)
    >>> act = SimpleNamespace(motor=motor, transmission=SimpleNamespace(ratio=1.0))
    >>> F = np.diag([-1.0, -1.0, -1.0])            # I' = V - I (R = L = 1), V = 10 w_g
    >>> g = np.array([0.0, 0.0, 1.0])
    >>> loop = ClosedLoopGust(F, np.zeros((3, 3)), np.eye(3)[2], np.eye(3)[0], np.zeros(3),
    ...                       np.zeros(3), F, g, np.zeros((3, 3)), np.zeros(3),
    ...                       np.array([10.0, 0.0, 0.0]))
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> w = np.vstack([np.ones(101), np.zeros((2, 101))])
    >>> r = limited_gust_response(loop, act, PowerLimits(supply_voltage=2.0), t, w)
    >>> round(float(r["current"][-1]), 3), bool(r["saturated"])   # V clipped at 2 V
    (2.0, True)
    """
    from asekit.servo.piecewise import PiecewiseAffineLoop, voltage_bounds

    if loop.F is None:
        raise ValueError("loop must come from closed_loop_gust (its open-loop matrices)")
    tt = finite_array("t", t).ravel()
    gu = finite_array("gust", gust)
    steps = np.diff(tt)
    if tt.size < 2 or np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-9):
        raise ValueError("t must hold >= 2 uniformly spaced ascending times (s)")
    if gu.shape != (3, tt.size):
        raise ValueError(f"gust must be (3, len(t)) = (3, {tt.size}), got {gu.shape}")
    n = loop.F.shape[0]
    Fa = np.zeros((n + 6, n + 6))                 # [x, u_g, du_g]: u_g' = du_g, du_g' = 0
    Fa[:n, :n], Fa[:n, n:n + 3], Fa[n:n + 3, n + 3:] = loop.F, loop.G_open, np.eye(3)
    ga = np.concatenate([loop.g, np.zeros(6)])
    demand = np.concatenate([loop.k, loop.k_gust, np.zeros(3)])
    pw = PiecewiseAffineLoop(Fa, ga, demand, voltage_bounds(actuator, limits, n + 6))
    h = float(steps[0])
    X = np.zeros((tt.size, n + 6))
    du = np.diff(gu, axis=1).T / h
    X[:, n:n + 3] = gu.T
    X[:-1, n + 3:] = du
    j0 = _first_near_limit(pw, X, loop, tt, gu)
    if j0 is None:                                  # no limit comes near: the linear loop
        volt = X @ demand
        return {"current": X[:, :n] @ loop.current_row, "voltage": volt, "demand": volt,
                "theta": X[:, :n] @ loop.theta_row, "saturated": False}
    x = X[j0].copy()
    saturated = False
    for j in range(j0, tt.size - 1):
        x = np.concatenate([x[:n], gu[:, j], du[j]])
        X[j] = x
        a = pw.active(x)
        a = pw.active(x + 1e-9 * h * pw.xdot(a, x))
        x, a_end, _ = pw.step(x, a, h, 0)
        saturated = saturated or a != 0 or a_end != 0
    X[-1] = np.concatenate([x[:n], gu[:, -1], np.zeros(3)])
    volt = pw.applied(X.T)
    dem = X @ demand
    return {"current": X[:, :n] @ loop.current_row, "voltage": volt, "demand": dem,
            "theta": X[:, :n] @ loop.theta_row, "saturated": bool(saturated)}
