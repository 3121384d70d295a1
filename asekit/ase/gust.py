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
With AEM2 (fin-root feedback) the rate feedback would also depend on the gust terms of z';
only AEM1 is built. Without power limits the current is the linear demand: compare its peak
with the actuator's current limit.
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
    """The AEM1 loop with the gust input: ``A`` (n, n), ``G`` (n, 3) over [w_g, w_g', w_g'']
    (m/s, m/s^2, m/s^3), ``current_row`` (n,) (A per state), ``theta_row`` (n,) (rad),
    ``hinge_row`` (n,) and ``hinge_gust`` (3,) (N m: T0 without the fin-inertia term)."""

    A: np.ndarray
    G: np.ndarray
    current_row: np.ndarray
    theta_row: np.ndarray
    hinge_row: np.ndarray
    hinge_gust: np.ndarray


def closed_loop_gust(model: AeroservoelasticModel, controller: PDController,
                     gust_ss: GustStateSpace) -> ClosedLoopGust:
    """The AEM1 closed loop with the gust input (module docstring).

    Parameters
    ----------
    model : :func:`asekit.ase.loop.build_model`'s model (modal model with one rigid mode).
    controller : the PD controller.
    gust_ss : :func:`asekit.aeroelastic.gust.gust_state_space` of the same modal model, fit,
        density and velocity (checked: its first block must equal ``model.A``).

    Returns
    -------
    :class:`ClosedLoopGust`
    """
    nz0 = model.A.shape[0]
    if (gust_ss.n_rigid != 1 or gust_ss.A.shape[0] < nz0
            or not np.allclose(gust_ss.A[:nz0, :nz0], model.A, rtol=1e-10,
                               atol=1e-10 * np.abs(model.A).max())):
        raise ValueError("gust_ss must be the gust state space of the model's modal model, fit "
                         "and flight condition (its aeroelastic block differs from model.A)")
    mats = _loop_matrices(model, controller, 0.0, "AEM1")
    F, g, k = mats["F"], mats["g"], mats["k"]
    act = model.actuator
    N, eta = act.transmission.ratio, act.transmission.efficiency
    nj = N * act.inertia_at_motor
    n0 = F.shape[0]
    ng = gust_ss.n_states - nz0
    n = n0 + ng
    B = model.B
    z = slice(3, 3 + nz0)
    A = np.zeros((n, n))
    A[:n0, :n0] = F + np.outer(g, k)
    alpha_lag = gust_ss.C_hinge[0, nz0:] / (N * eta) / nj
    A[1, n0:] = alpha_lag
    A[z, n0:] = gust_ss.A[:nz0, nz0:] + np.outer(B[:, 2], alpha_lag)
    A[n0:, n0:] = gust_ss.A[nz0:, nz0:]
    G = np.zeros((n, 3))
    alpha_w = gust_ss.Dg_hinge[0] / (N * eta) / nj
    G[1] = alpha_w
    G[z] = gust_ss.B_g[:nz0] + np.outer(B[:, 2], alpha_w)
    G[n0:] = gust_ss.B_g[nz0:]
    cur, th = np.zeros(n), np.zeros(n)
    cur[2], th[0] = 1.0, 1.0
    hinge = np.concatenate([mats["hm_row"], gust_ss.C_hinge[0, nz0:]])
    return ClosedLoopGust(A, G, cur, th, hinge, gust_ss.Dg_hinge[0].copy())


def closed_loop_gust_response(loop: ClosedLoopGust, t, gust) -> dict:
    """Response from rest to the gust inputs ``gust`` (3, n_t) at the ascending times ``t``
    (s): ``current`` (A), ``theta`` (rad), ``hinge_moment`` (N m, T0) histories (n_t,).

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
    return {"current": x @ loop.current_row, "theta": x @ loop.theta_row,
            "hinge_moment": x @ loop.hinge_row + gu.T @ loop.hinge_gust}


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
