"""The gust input of the aeroelastic state space, discrete 1-cos gusts and their responses
(issue 27).

The modal equation of :mod:`asekit.aeroelastic.statespace` (thesis Eq. 2.44) gains the gust
force of the Roger-fitted gust column (:mod:`asekit.rfa.gust`, Q~_g with coefficients A_g)::

    (s^2 M + s C + K - q Q~(s)) zeta = T_act + q Q~_g(s) w_g(s) / U,

    q Q~_g(s) w_g / U = q/U A0g w_g + (rho b / 2) A1g w_g' + (rho b^2 / (2 U)) A2g w_g''
                        + q sum_n A_{g,n+2} x_gn,
    x_gn' = -(U/b) beta_n x_gn + w_g' / U         (one lag state per lag root, all modes),

(q = rho U^2 / 2, b the fits' reference semi-chord, w_g the upward gust velocity in m/s at the
gust reference station x0 of the column). So the state vector of Eq. (2.63) is extended by the
N_g gust lag states, and the gust enters through

    z' = A z + B [theta, theta', theta''] + B_g [w_g, w_g', w_g''],

B_g holding M_bar_ss^-1 F_g,s in the elastic acceleration rows (F_g = q [A0g/U, A1g b/U^2,
A2g b^2/U^3]) and 1/U in the gust-lag rows. The hinge moment T_hinge@fin (Eqs. 2.68-2.70) gains
the gust force on the rigid row, F_g,c - M_bar_cs M_bar_ss^-1 F_g,s (the feed-through D_g) and
the lag states' q (A_gc - M_bar_cs M_bar_ss^-1 A_gs) (its C columns). With theta held at zero
(the actuator clamped, FN2) it is the torque the actuator must hold.

Discrete gust: the "1-cos" gust of gradient distance H (m; the gust is 2H long) and design
velocity U_ds (m/s) (CS-25.341(a), FAR 25.341(a); the gust front reaches x0 at t = 0),

    w_g(t) = U_ds / 2 (1 - cos(pi U t / H)),     0 <= U t <= 2 H,     0 otherwise.

Units SI: rho kg/m^3, U m/s, b m, w_g m/s, the hinge moment N m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aeroelastic.statespace import ModalArrays, aeroelastic_matrices, modal_arrays
from asekit.util.validate import finite_array, finite_result, positive

#: Names of the gust inputs (m/s, m/s^2, m/s^3).
GUST_INPUT_NAMES = ("w_gust", "w_gust_dot", "w_gust_ddot")


@dataclass(frozen=True)
class GustStateSpace:
    """The aeroelastic state space with gust input at one (rho, U) (module docstring).

    Attributes
    ----------
    A : (n_z, n_z) with n_z = 2 n_s + modal lag states + N_g gust lag states.
    B : (n_z, 3) inputs theta, theta', theta'' (rad, rad/s, rad/s^2; (n_z, 0) without a rigid
        mode); B_g : (n_z, 3) inputs w_g, w_g', w_g'' (m/s, m/s^2, m/s^3).
    C_hinge, D_hinge, Dg_hinge : hinge moment T_hinge@fin (N m) = C_hinge z + D_hinge theta-
        inputs + Dg_hinge gust inputs ((0, .) arrays without a rigid mode).
    state_names : Eq. (2.63)'s names, then ``gust_lag<n>``.
    n_elastic, n_rigid : modes; velocity (m/s), density (kg/m^3).
    """

    A: np.ndarray
    B: np.ndarray
    B_g: np.ndarray
    C_hinge: np.ndarray
    D_hinge: np.ndarray
    Dg_hinge: np.ndarray
    state_names: tuple
    n_elastic: int
    n_rigid: int
    velocity: float
    density: float

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def acceleration_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(C, D, D_g) of the elastic modal accelerations zeta_s'' (n_s rows): the rows of
        A, B, B_g that give zeta_s_dot' (for inertial loads)."""
        r = slice(self.n_elastic, 2 * self.n_elastic)
        return self.A[r], self.B[r], self.B_g[r]


def _check_gust_fit(gust, rfa, n_modes: int):
    Ag = finite_array("gust.A", gust.A)
    if Ag.ndim != 2 or Ag.shape[1] != n_modes:
        raise ValueError(f"gust fit has shape {Ag.shape}; expected (N + 3, n_modes = {n_modes})")
    if not np.isclose(float(gust.b_ref), float(rfa.b_ref), rtol=1e-12):
        raise ValueError(f"gust.b_ref = {gust.b_ref} differs from rfa.b_ref = {rfa.b_ref}: both "
                         "fits must use the same reference semi-chord")
    roots = finite_array("gust.lag_roots", gust.lag_roots)
    if np.any(roots <= 0):
        raise ValueError(f"gust.lag_roots must all be > 0, got {roots}")
    return Ag, np.atleast_1d(roots)


def gust_state_space(modal, rfa, gust, rho: float, velocity: float) -> GustStateSpace:
    """The state space of Eq. (2.63) with the gust input (module docstring).

    Parameters
    ----------
    modal : ModalArrays or any object with M, K, C, n_rigid (rigid mode first).
    rfa : the modal fit (:class:`asekit.rfa.RogerFit` or ``MinimumStateFit``).
    gust : :class:`asekit.rfa.gust.GustFit` of the same modes and b_ref.
    rho : density (kg/m^3) > 0; velocity : true airspeed U (m/s) > 0.

    Returns
    -------
    :class:`GustStateSpace`

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.rfa.gust import GustFit
    >>> from asekit.rfa.roger import RogerFit
    >>> k = np.array([0.0, 1.0])
    >>> rfa = RogerFit(np.zeros((4, 1, 1)), np.array([0.2]), 0.5, k, np.zeros((2, 1, 1)),
    ...                np.zeros((1, 1)), 0.0)
    >>> g = GustFit(np.array([[2.0], [0.0], [0.0], [0.0]]), np.array([0.2]), 0.5, k,
    ...             np.ones((2, 1)))
    >>> model = type("M", (), {"M": [[1.0]], "K": [[100.0]], "C": None, "n_rigid": 0})()
    >>> ss = gust_state_space(model, rfa, g, 1.0, 10.0)
    >>> float(ss.B_g[1, 0])            # q A0g / (U M) = 50 * 2 / 10
    10.0
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    mats = aeroelastic_matrices(m, rfa, rho, velocity)
    Ag, roots = _check_gust_fit(gust, rfa, m.n_modes)
    rho, U, b = mats.density, mats.velocity, float(rfa.b_ref)
    q = 0.5 * rho * U ** 2
    A = finite_array("rfa.A", rfa.A)
    Mb = m.M - 0.5 * rho * b ** 2 * A[2]
    c, s = slice(0, m.n_rigid), slice(m.n_rigid, m.n_modes)
    ns, nz0, ng = mats.n_elastic, mats.n_states, roots.size
    Mss_inv = np.linalg.inv(Mb[s, s])
    Fg = q * np.column_stack([Ag[0] / U, Ag[1] * b / U ** 2, Ag[2] * b ** 2 / U ** 3])  # (n, 3)
    Flag = q * Ag[3:].T                                                                  # (n, N_g)
    nz = nz0 + ng
    Asys = np.zeros((nz, nz))
    Asys[:nz0, :nz0] = mats.A
    acc = slice(ns, 2 * ns)
    Asys[acc, nz0:] = Mss_inv @ Flag[s]
    Asys[nz0:, nz0:] = -np.diag(U / b * roots)
    Bg = np.zeros((nz, 3))
    Bg[acc] = Mss_inv @ Fg[s]
    Bg[nz0:, 1] = 1.0 / U
    B = np.vstack([mats.B, np.zeros((ng, mats.B.shape[1]))])
    if m.n_rigid:
        couple = Mb[c, s] @ Mss_inv
        C_h = np.hstack([mats.C_hinge, Flag[c] - couple @ Flag[s]])
        Dg_h = Fg[c] - couple @ Fg[s]
    else:
        C_h, Dg_h = np.zeros((0, nz)), np.zeros((0, 3))
    for what, a in (("A", Asys), ("B_g", Bg), ("C_hinge", C_h), ("Dg_hinge", Dg_h)):
        finite_result(f"the gust state space's {what}", a,
                      f"rho = {rho:g} kg/m^3, velocity = {U:g} m/s: give a physical condition")
    names = tuple(mats.state_names) + tuple(f"gust_lag{n + 1}" for n in range(ng))
    return GustStateSpace(A=Asys, B=B, B_g=Bg, C_hinge=C_h, D_hinge=mats.D_hinge,
                          Dg_hinge=Dg_h, state_names=names, n_elastic=ns, n_rigid=m.n_rigid,
                          velocity=U, density=rho)


def one_minus_cosine(t, velocity: float, gradient_length: float, design_velocity: float,
                     delay: float = 0.0) -> np.ndarray:
    """The discrete 1-cos gust and its time derivatives at times ``t`` (s):
    w_g = U_ds/2 (1 - cos(pi U (t - delay) / H)) for 0 <= U (t - delay) <= 2 H, else 0
    (CS-25.341(a); H the gradient distance, the gust 2 H long).

    Parameters
    ----------
    t : times (s); velocity : U (m/s) > 0; gradient_length : H (m) > 0;
    design_velocity : U_ds (m/s), finite (its sign the gust's: > 0 up);
    delay : time (s) the gust front reaches the reference station.

    Returns
    -------
    (3, len(t)) array: w_g (m/s), w_g' (m/s^2), w_g'' (m/s^3).

    Examples
    --------
    >>> w = one_minus_cosine([0.0, 0.5, 1.0, 1.5], 10.0, 5.0, 2.0)
    >>> np.round(w[0], 12) + 0.0
    array([0., 2., 0., 0.])
    """
    tt = finite_array("t", t).ravel()
    U = positive("velocity", velocity)
    H = positive("gradient_length", gradient_length)
    wd = float(finite_array("design_velocity", design_velocity))
    d = float(finite_array("delay", delay))
    om = np.pi * U / H
    tau = tt - d
    inside = (tau >= 0) & (tau <= 2 * H / U)
    out = np.zeros((3, tt.size))
    out[0] = np.where(inside, 0.5 * wd * (1 - np.cos(om * tau)), 0.0)
    out[1] = np.where(inside, 0.5 * wd * om * np.sin(om * tau), 0.0)
    out[2] = np.where(inside, 0.5 * wd * om ** 2 * np.cos(om * tau), 0.0)
    return out


@dataclass(frozen=True)
class GustResponse:
    """Time histories of a gust response: ``t`` (s), ``states`` (n_t, n_z), ``gust``
    (3, n_t: w_g, w_g', w_g''), ``modal`` (n_t, n_s) elastic coordinates,
    ``acceleration`` (n_t, n_s) their second derivatives, ``hinge_moment`` (n_t,) N m (zeros
    without a rigid mode; theta held at zero); ``velocity`` (m/s), ``density`` (kg/m^3)."""

    t: np.ndarray
    states: np.ndarray
    gust: np.ndarray
    modal: np.ndarray
    acceleration: np.ndarray
    hinge_moment: np.ndarray
    velocity: float = 0.0
    density: float = 0.0


def gust_response(ss: GustStateSpace, t, gust) -> GustResponse:
    """Response of :class:`GustStateSpace` from rest to the gust inputs ``gust`` (3, n_t) at
    the uniformly spaced times ``t`` (s), theta held at zero (the actuator clamped), by the
    exact discretisation of a first-order hold (scipy.signal.lsim).

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.rfa.gust import GustFit
    >>> from asekit.rfa.roger import RogerFit
    >>> k = np.array([0.0, 1.0])
    >>> rfa = RogerFit(np.zeros((4, 1, 1)), np.array([0.2]), 0.5, k, np.zeros((2, 1, 1)),
    ...                np.zeros((1, 1)), 0.0)
    >>> g = GustFit(np.array([[2.0], [0.0], [0.0], [0.0]]), np.array([0.2]), 0.5, k,
    ...             np.ones((2, 1)))
    >>> model = type("M", (), {"M": [[1.0]], "K": [[100.0]], "C": [[20.0]], "n_rigid": 0})()
    >>> ss = gust_state_space(model, rfa, g, 1.0, 10.0)
    >>> t = np.linspace(0, 5, 501)
    >>> r = gust_response(ss, t, np.vstack([np.ones(501), np.zeros((2, 501))]))
    >>> round(float(r.modal[-1, 0]), 4)       # static: q A0g (w/U) / K = 100 * 0.1 / 100
    0.1
    """
    from scipy.signal import lsim

    tt = finite_array("t", t).ravel()
    if tt.size < 2 or np.any(np.diff(tt) <= 0):
        raise ValueError("t must hold >= 2 ascending times (s)")
    g = finite_array("gust", gust)
    if g.shape != (3, tt.size):
        raise ValueError(f"gust must be (3, len(t)) = (3, {tt.size}): w_g, w_g', w_g''; got "
                         f"{g.shape}")
    nz, ns = ss.n_states, ss.n_elastic
    _, _, x = lsim((ss.A, ss.B_g, np.eye(nz), np.zeros((nz, 3))), g.T, tt, interp=True)
    x = np.atleast_2d(x).reshape(tt.size, nz)
    Ca, _, Dga = ss.acceleration_rows()
    acc = x @ Ca.T + g.T @ Dga.T
    hinge = (x @ ss.C_hinge.T + g.T @ ss.Dg_hinge.T)[:, 0] if ss.n_rigid else np.zeros(tt.size)
    return GustResponse(tt, x, g, x[:, :ns], acc, hinge, ss.velocity, ss.density)


def first_order_filter(t, u, rates) -> np.ndarray:
    """y' = -a y + u(t) from y(t_0) = 0 for each rate a > 0 (1/s), u linear between samples
    (first-order hold, exact recurrence):

        y_{j+1} = e^{-a h} y_j + u_j (1 - e^{-a h}) / a + (u_{j+1} - u_j) / h
                  (h / a - (1 - e^{-a h}) / a^2).

    ``t`` (n_t,) ascending; ``u`` (n_t, m); ``rates`` (m,) or scalar. Returns (n_t, m).

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> y = first_order_filter(t, np.ones((1001, 1)), 2.0)   # step: (1 - e^{-2 t}) / 2
    >>> round(float(y[-1, 0]), 6)
    0.5
    """
    from scipy.signal import lfilter

    tt = finite_array("t", t).ravel()
    uu = finite_array("u", u)
    uu = uu.reshape(tt.size, -1)
    a = np.broadcast_to(finite_array("rates", rates), (uu.shape[1],)).astype(float)
    if np.any(a <= 0):
        raise ValueError(f"rates must be > 0 (1/s), got {a}")
    steps = np.diff(tt)
    if tt.size < 2 or np.any(steps <= 0):
        raise ValueError("t must hold >= 2 ascending times (s)")
    y = np.zeros_like(uu)
    if np.allclose(steps, steps[0], rtol=1e-9, atol=0):
        # uniform steps: the recurrence is the IIR filter y_j - e y_{j-1} = c1 u_j + (c0 - c1)
        # u_{j-1}, started from y_0 = 0
        h = float(steps[0])
        for i, ai in enumerate(a):
            e = math.exp(-ai * h)
            g0 = (1 - e) / ai
            c1 = h / ai - g0 / ai
            c1 /= h
            y[:, i] = lfilter([c1, g0 - c1], [1.0, -e], uu[:, i], zi=[-c1 * uu[0, i]])[0]
        return y
    for j, h in enumerate(steps):
        e = np.exp(-a * h)
        g0 = (1 - e) / a
        y[j + 1] = e * y[j] + uu[j] * g0 + (uu[j + 1] - uu[j]) / h * (h / a - g0 / a)
    return y


def load_histories(resp: GustResponse, load_fit, inertial_rows, n_rigid: int = 0
                   ) -> np.ndarray:
    """Loads by force summation (aerodynamic + inertial) along a gust response.

    The aerodynamic load rows Q_L (n_loads, n) and their gust part Q_Lg (n_loads) (from
    :func:`asekit.aero.gust.gust_aero_tables`) are fitted together in Roger form, ``load_fit``
    a :class:`asekit.rfa.gust.GustFit` of the columns ``[Q_L.reshape(n_k, -1), Q_Lg]`` (row
    major: load r, mode j at column r n + j; then the n_loads gust columns). In time (p = s b/U)::

        L_aero = q [A0 zeta + (b/U) A1 zeta' + (b/U)^2 A2 zeta'' + sum_n y_n]
                 + q [A0g w/U + A1g b w'/U^2 + A2g b^2 w''/U^3 + sum_n A_gn x_gn],
        y_n' = -(U/b) beta_n y_n + A_n zeta',   x_gn' = -(U/b) beta_n x_gn + w'/U,

    (only the elastic coordinates: the rigid one is held at zero), and the inertial load is
    ``inertial_rows`` (n_loads, n_s) times zeta_s'' (-u_r^T M Phi_s for a load whose rigid
    displacement field is u_r). Returns (n_t, n_loads) in N and N m.

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.rfa.gust import GustFit
    >>> from asekit.rfa.roger import RogerFit
    >>> k = np.array([0.0, 1.0])
    >>> rfa = RogerFit(np.zeros((4, 1, 1)), np.array([0.2]), 0.5, k, np.zeros((2, 1, 1)),
    ...                np.zeros((1, 1)), 0.0)
    >>> g = GustFit(np.array([[2.0], [0.0], [0.0], [0.0]]), np.array([0.2]), 0.5, k,
    ...             np.ones((2, 1)))
    >>> model = type("M", (), {"M": [[1.0]], "K": [[100.0]], "C": [[20.0]], "n_rigid": 0})()
    >>> ss = gust_state_space(model, rfa, g, 1.0, 10.0)
    >>> t = np.linspace(0, 5, 501)
    >>> r = gust_response(ss, t, np.vstack([np.ones(501), np.zeros((2, 501))]))
    >>> lf = GustFit(np.array([[0.0, 2.0], [0, 0], [0, 0], [0, 0]]), np.array([0.2]), 0.5, k,
    ...              np.ones((2, 2)))
    >>> shear = load_histories(r, lf, [[-1.0]])            # aero 10 N, inertia -zeta''
    >>> round(float(shear[-1, 0]), 4)                       # = the spring force K zeta
    10.0
    """
    ns = resp.modal.shape[1]
    inert = np.atleast_2d(finite_array("inertial_rows", inertial_rows))
    nl = inert.shape[0]
    A = finite_array("load_fit.A", load_fit.A)
    n = ns + int(n_rigid)
    if inert.shape[1] != ns or A.shape[1] != nl * (n + 1):
        raise ValueError(f"inertial_rows must be (n_loads, n_s = {ns}) and load_fit (N + 3, "
                         f"n_loads (n + 1)) with n = {n} modes; got {inert.shape}, {A.shape}")
    roots = np.atleast_1d(load_fit.lag_roots)
    b = float(load_fit.b_ref)
    U = float(resp.velocity)
    q = 0.5 * resp.density * U ** 2
    Am = A[:, :nl * n].reshape(A.shape[0], nl, n)[:, :, n_rigid:]        # (N + 3, nl, ns)
    Ag = A[:, nl * n:]                                                   # (N + 3, nl)
    t, w = resp.t, resp.gust
    z, zd, zdd = resp.modal, resp.states[:, ns:2 * ns], resp.acceleration
    aero = (z @ Am[0].T + (b / U) * zd @ Am[1].T + (b / U) ** 2 * zdd @ Am[2].T
            + np.outer(w[0] / U, Ag[0]) + np.outer(w[1] * b / U ** 2, Ag[1])
            + np.outer(w[2] * b ** 2 / U ** 3, Ag[2]))
    rates = U / b * roots
    xg = first_order_filter(t, np.repeat((w[1] / U)[:, None], roots.size, 1), rates)
    yl = first_order_filter(t, np.hstack([zd @ Am[3 + i].T for i in range(roots.size)]),
                            np.repeat(rates, nl))
    for i in range(roots.size):
        aero = aero + yl[:, i * nl:(i + 1) * nl] + np.outer(xg[:, i], Ag[3 + i])
    return q * aero + zdd @ inert.T


# ---------------------------------------------------------------------------------------------
# continuous turbulence (frequency domain)
# ---------------------------------------------------------------------------------------------
#: von Karman's constant a of the vertical-gust spectrum (1.339 L omega / U).
VON_KARMAN_A = 1.339


def turbulence_psd(omega, velocity: float, scale_length: float, sigma: float,
                   spectrum: str = "von_karman") -> np.ndarray:
    """One-sided PSD of the vertical gust velocity, Phi(omega) ((m/s)^2 / (rad/s)), with
    int_0^inf Phi d omega = sigma^2 (Hoblit, *Gust Loads on Aircraft*, AIAA 1988, Eqs. 2.7-2.8;
    MIL-F-8785C):

    von Karman: Phi = sigma^2 L / (pi U) (1 + 8/3 (a L omega/U)^2) / (1 + (a L omega/U)^2)^(11/6),
    a = 1.339; Dryden: Phi = sigma^2 L / (pi U) (1 + 3 (L omega/U)^2) / (1 + (L omega/U)^2)^2.

    Parameters
    ----------
    omega : frequencies (rad/s) >= 0; velocity : U (m/s) > 0; scale_length : L (m) > 0;
    sigma : RMS gust velocity (m/s) > 0; spectrum : "von_karman" or "dryden".

    Examples
    --------
    >>> float(np.round(turbulence_psd(0.0, 100.0, 762.0, 1.0) * np.pi * 100 / 762, 12))
    1.0
    """
    w = finite_array("omega", omega)
    if np.any(w < 0):
        raise ValueError("omega must be >= 0 rad/s")
    U, L, s = positive("velocity", velocity), positive("scale_length", scale_length), \
        positive("sigma", sigma)
    base = s ** 2 * L / (np.pi * U)
    if spectrum == "von_karman":
        x2 = (VON_KARMAN_A * L * w / U) ** 2
        return base * (1 + 8 / 3 * x2) / (1 + x2) ** (11 / 6)
    if spectrum == "dryden":
        x2 = (L * w / U) ** 2
        return base * (1 + 3 * x2) / (1 + x2) ** 2
    raise ValueError(f"spectrum must be 'von_karman' or 'dryden', got {spectrum!r}")


def gust_frequency_response(ss: GustStateSpace, omega, load_fit=None, inertial_rows=None,
                            n_rigid: int = 0) -> dict:
    """Frequency responses per unit gust velocity (w_g = e^{i omega t} m/s at x0) of
    :class:`GustStateSpace`: ``"modal"`` (n_w, n_s) elastic coordinates, ``"hinge_moment"``
    (n_w,) N m per m/s (with a rigid mode), and with ``load_fit``/``inertial_rows`` (as in
    :func:`load_histories`) ``"loads"`` (n_w, n_loads): q [Q~_L(k) zeta + Q~_Lg(k) / U]
    - omega^2 inertial_rows zeta, k = omega b / U.

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.rfa.gust import GustFit
    >>> from asekit.rfa.roger import RogerFit
    >>> k = np.array([0.0, 1.0])
    >>> rfa = RogerFit(np.zeros((4, 1, 1)), np.array([0.2]), 0.5, k, np.zeros((2, 1, 1)),
    ...                np.zeros((1, 1)), 0.0)
    >>> g = GustFit(np.array([[2.0], [0.0], [0.0], [0.0]]), np.array([0.2]), 0.5, k,
    ...             np.ones((2, 1)))
    >>> model = type("M", (), {"M": [[1.0]], "K": [[100.0]], "C": [[20.0]], "n_rigid": 0})()
    >>> ss = gust_state_space(model, rfa, g, 1.0, 10.0)
    >>> h = gust_frequency_response(ss, [0.0])["modal"][0, 0]   # q A0g (1/U) / K = 10 / 100
    >>> complex(np.round(h, 12))
    (0.1+0j)
    """
    w = finite_array("omega", omega).ravel()
    nz, ns = ss.n_states, ss.n_elastic
    u = np.stack([np.ones_like(w), 1j * w, -w ** 2], axis=1).astype(complex)     # (n_w, 3)
    x = np.stack([np.linalg.solve(1j * wi * np.eye(nz) - ss.A, ss.B_g @ ui)
                  for wi, ui in zip(w, u)])
    out = {"modal": x[:, :ns]}
    if ss.n_rigid:
        out["hinge_moment"] = x @ ss.C_hinge[0] + u @ ss.Dg_hinge[0]
    if load_fit is not None:
        inert = np.atleast_2d(finite_array("inertial_rows", inertial_rows))
        nl = inert.shape[0]
        n = ns + int(n_rigid)
        U, b = ss.velocity, float(load_fit.b_ref)
        q = 0.5 * ss.density * U ** 2
        ev = load_fit.evaluate(w * b / U)                                        # (n_w, cols)
        QL = ev[:, :nl * n].reshape(w.size, nl, n)[:, :, n_rigid:]
        out["loads"] = (q * (np.einsum("wls,ws->wl", QL, x[:, :ns]) + ev[:, nl * n:] / U)
                        - (w ** 2)[:, None] * (x[:, :ns] @ inert.T))
    return out


def spectral_statistics(omega, transfer, psd) -> dict:
    """RMS, A-bar and N0 of a response to continuous turbulence (Hoblit 1988, Eqs. 2.13-2.16):
    sigma_y^2 = int |H|^2 Phi d omega, A-bar = sigma_y / sigma_w, N0 = (1 / 2 pi)
    sqrt(int omega^2 |H|^2 Phi / int |H|^2 Phi) (zero up-crossings per second), by the
    trapezoidal rule over the given ``omega`` grid (rad/s; its upper end is a cut-off, which
    N0 depends on when |H|^2 Phi falls slowly).

    Parameters
    ----------
    omega : (n_w,) ascending rad/s; transfer : (n_w,) response per unit gust velocity;
    psd : (n_w,) one-sided gust PSD ((m/s)^2 / (rad/s)).

    Returns
    -------
    dict ``rms`` (unit of the response), ``A_bar`` (rms over the gust RMS of ``psd`` on the
    same grid: response per m/s), ``N0_per_s`` (1/s).

    Examples
    --------
    >>> w = np.linspace(0, 10, 10001)
    >>> s = spectral_statistics(w, 2.0 * np.ones(w.size), np.where(w <= 1, 1.0, 0.0))
    >>> round(s["rms"], 3), round(s["A_bar"], 3)
    (2.0, 2.0)
    """
    from scipy.integrate import trapezoid

    w = finite_array("omega", omega).ravel()
    h2 = np.abs(np.asarray(transfer).ravel()) ** 2
    p = finite_array("psd", psd).ravel()
    if not (w.size == h2.size == p.size) or w.size < 2 or np.any(np.diff(w) <= 0):
        raise ValueError("omega, transfer and psd must have the same length >= 2, omega "
                         "strictly ascending")
    m0 = trapezoid(h2 * p, w)
    m2 = trapezoid(w ** 2 * h2 * p, w)
    sig_w = math.sqrt(trapezoid(p, w))
    rms = math.sqrt(m0)
    return {"rms": rms, "A_bar": rms / sig_w if sig_w > 0 else float("nan"),
            "N0_per_s": math.sqrt(m2 / m0) / (2 * np.pi) if m0 > 0 else float("nan")}


def dryden_realisation(t, velocity: float, scale_length: float, sigma: float,
                       seed: int | None = 0) -> np.ndarray:
    """A time-domain realisation of Dryden vertical turbulence by its shaping filter, with a
    seed (MIL-F-8785C; Hoblit 1988, Sec. 2.6):

        H(s) = sigma sqrt(L / U) (1 + sqrt(3) tau s) / (1 + tau s)^2,   tau = L / U,

    driven by white noise of unit intensity (two-sided PSD 1 / (2 pi)), so that the output's
    one-sided PSD is :func:`turbulence_psd` (``spectrum="dryden"``). The noise is held over each
    step (variance 1 / dt) and the filter discretised exactly for it (zero-order hold); the
    derivatives are the numerical ones of the samples (``numpy.gradient``), as the gust state
    space's inputs need them.

    Parameters
    ----------
    t : (n_t,) uniformly spaced times (s), dt well below tau; velocity : U (m/s) > 0;
    scale_length : L (m) > 0; sigma : RMS gust velocity (m/s) > 0; seed : the random seed.

    Returns
    -------
    (3, n_t) w_g (m/s), w_g' (m/s^2), w_g'' (m/s^3).

    Examples
    --------
    >>> w = dryden_realisation(np.linspace(0, 10, 1001), 100.0, 50.0, 2.0, seed=1)
    >>> w.shape
    (3, 1001)
    """
    from scipy.signal import cont2discrete, lfilter

    tt = finite_array("t", t).ravel()
    steps = np.diff(tt)
    if tt.size < 3 or np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-9):
        raise ValueError("t must hold >= 3 uniformly spaced ascending times (s)")
    U, L, s = positive("velocity", velocity), positive("scale_length", scale_length), \
        positive("sigma", sigma)
    dt, tau = float(steps[0]), L / U
    num = s * math.sqrt(tau) * np.array([math.sqrt(3.0) * tau, 1.0])
    den = np.array([tau ** 2, 2 * tau, 1.0])
    numd, dend, _ = cont2discrete((num, den), dt, method="zoh")
    noise = np.random.default_rng(seed).standard_normal(tt.size) / math.sqrt(dt)
    w = lfilter(np.ravel(numd), dend, noise)
    wd = np.gradient(w, dt)
    return np.vstack([w, wd, np.gradient(wd, dt)])


# ---------------------------------------------------------------------------------------------
# correlated loads in continuous turbulence
# ---------------------------------------------------------------------------------------------
def response_covariance(omega, transfers, psd) -> np.ndarray:
    """Joint covariance of several responses to the same continuous turbulence (Hoblit,
    *Gust Loads on Aircraft*, AIAA 1988, Ch. 7, correlated loads):

        C_ij = int_0^inf Re(H_i(omega) conj(H_j(omega))) Phi(omega) d omega,

    (the one-sided cross-spectrum's real part; its diagonal is sigma_i^2 of
    :func:`spectral_statistics`), by the trapezoidal rule over ``omega``.

    Parameters
    ----------
    omega : (n_w,) ascending rad/s; transfers : (n_w, m) responses per unit gust velocity;
    psd : (n_w,) one-sided gust PSD ((m/s)^2 / (rad/s)).

    Returns
    -------
    (m, m) symmetric covariance (products of the responses' units).

    Examples
    --------
    >>> w = np.linspace(0, 1, 1001)
    >>> H = np.column_stack([np.ones(w.size), 2j * np.ones(w.size)])   # 90 deg apart
    >>> np.round(response_covariance(w, H, np.ones(w.size)), 12) + 0.0
    array([[1., 0.],
           [0., 4.]])
    """
    from scipy.integrate import trapezoid

    w = finite_array("omega", omega).ravel()
    H = np.asarray(transfers)
    H = H.reshape(w.size, -1) if H.ndim == 1 else H
    p = finite_array("psd", psd).ravel()
    if H.shape[0] != w.size or p.size != w.size or w.size < 2 or np.any(np.diff(w) <= 0):
        raise ValueError("omega, transfers (n_w, m) and psd must have the same length n_w >= "
                         "2, omega strictly ascending")
    cross = np.einsum("wi,wj->wij", H, np.conj(H)).real * p[:, None, None]
    C = trapezoid(cross, w, axis=0)
    return 0.5 * (C + C.T)


def correlated_load_ellipse(covariance, n_points: int = 361, scale: float = 1.0
                            ) -> np.ndarray:
    """The equal-probability ellipse of two jointly Gaussian loads (Hoblit 1988, Ch. 7: the
    design-load ellipse of the correlated-load method), x^T C^-1 x = scale^2:

        x(t) = scale sigma_x cos t,
        y(t) = scale sigma_y (rho cos t + sqrt(1 - rho^2) sin t),   0 <= t <= 2 pi,

    rho = C_xy / (sigma_x sigma_y). Its extreme projection on x is scale sigma_x (at
    y = rho scale sigma_y) and on y scale sigma_y (at x = rho scale sigma_x); on any direction
    u it is scale sqrt(u^T C u).

    Parameters
    ----------
    covariance : (2, 2) covariance (:func:`response_covariance`), positive semi-definite;
    n_points : points on the closed curve (>= 4); scale : the ellipse's level in sigmas (> 0).

    Returns
    -------
    (2, n_points) x and y, the first point repeated at the end.

    Examples
    --------
    >>> e = correlated_load_ellipse([[4.0, 3.0], [3.0, 9.0]], 721)
    >>> round(float(e[0].max()), 6), round(float(e[1].max()), 6)     # sigma_x, sigma_y
    (2.0, 3.0)
    """
    C = finite_array("covariance", covariance)
    if C.shape != (2, 2):
        raise ValueError(f"covariance must be (2, 2), got {C.shape}")
    if int(n_points) < 4:
        raise ValueError(f"n_points must be >= 4, got {n_points}")
    s = positive("scale", scale)
    sx, sy = math.sqrt(max(C[0, 0], 0.0)), math.sqrt(max(C[1, 1], 0.0))
    if sx == 0 or sy == 0:
        rho = 0.0
    else:
        rho = float(np.clip(0.5 * (C[0, 1] + C[1, 0]) / (sx * sy), -1.0, 1.0))
    t = np.linspace(0.0, 2 * np.pi, int(n_points))
    return s * np.vstack([sx * np.cos(t),
                          sy * (rho * np.cos(t) + math.sqrt(1 - rho ** 2) * np.sin(t))])
