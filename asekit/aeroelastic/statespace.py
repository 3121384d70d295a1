"""The state-space aeroelastic model of thesis Section 2.4 (Eqs. 2.44-2.70).

The modal equation of motion (Eq. 2.44) with Roger aerodynamics (Eq. 2.28),

    (s^2 M + s C + K - q Q~(s)) zeta_m = T_act,

is partitioned into the rigid (actuator) coordinate c = theta and the elastic coordinates s
(Eq. 2.46). With the aeroelastic matrices of Eq. (2.60),

    M_bar = M - rho b^2/2 A2,   C_bar = C - rho b U/2 A1,   K_bar = K - rho U^2/2 A0,

and the lag states (Eqs. 2.61-2.62) zeta_san = s A_{n+2} / (s + (U/b) beta_n) zeta, the elastic
equations become the first-order system of Eq. (2.63):

    z = [zeta_s, zeta_s_dot, zeta_sa1..zeta_saN, zeta_ca1..zeta_caN],  u = [theta, theta_dot,
    theta_ddot],   z_dot = A_sys z + B_sys u,

and the hinge moment T_hinge@fin = -T_fin is the output of Eqs. (2.68)-(2.70); modal
superposition (Eq. 2.64) gives displacements and rotations at chosen points.

Sign note: the thesis prints the theta and theta_dot columns of B_sys (second block row) as
+M_bar_ss^-1 K_bar_sc and +M_bar_ss^-1 C_bar_sc, and Eq. (2.70) correspondingly. Moving the
theta terms of Eq. (2.60) to the right-hand side gives -M_bar_ss^-1 K_bar_sc and
-M_bar_ss^-1 C_bar_sc (the theta_ddot column, -M_bar_ss^-1 M_bar_sc, is printed with that sign);
this module implements the derived signs, and a test checks the model against the frequency-
domain equation (2.44) directly.

Units: SI (or any consistent set); rho (kg/m^3), U (m/s), b (m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asekit.structure.modes import mode_shapes_at  # lazy: the structure module
from asekit.util.validate import finite_array, finite_result, integer, positive

INPUT_NAMES = ("theta", "theta_dot", "theta_ddot")


@dataclass(frozen=True)
class ModalArrays:
    """The modal structural model as plain arrays: M, K, C (n x n), ``n_rigid`` rigid modes in
    front (0 or 1). Any object with attributes M, K, C, n_rigid (e.g. asekit's ModalModel)
    converts with :func:`modal_arrays`."""

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    n_rigid: int = 0

    @property
    def n_modes(self) -> int:
        return self.M.shape[0]

    @property
    def n_elastic(self) -> int:
        return self.M.shape[0] - self.n_rigid


def modal_arrays(model=None, *, M=None, K=None, C=None, n_rigid=None) -> ModalArrays:
    """Validate and bundle a modal model (object with M, K, C, n_rigid, or keyword arrays).

    Raises ValueError for non-square or mismatched matrices, non-finite entries, ``n_rigid``
    outside {0, 1}, or no elastic mode.
    """
    if model is not None:
        M = getattr(model, "M") if M is None else M
        K = getattr(model, "K") if K is None else K
        C = getattr(model, "C", None) if C is None else C
        n_rigid = getattr(model, "n_rigid", 0) if n_rigid is None else n_rigid
    M = np.atleast_2d(np.asarray(M, dtype=float))
    K = np.atleast_2d(np.asarray(K, dtype=float))
    C = np.zeros_like(M) if C is None else np.atleast_2d(np.asarray(C, dtype=float))
    n_rigid = 0 if n_rigid is None else integer("n_rigid", n_rigid, low=0, high=1)
    n = M.shape[0]
    for name, a in (("M", M), ("K", K), ("C", C)):
        if a.shape != (n, n):
            raise ValueError(f"{name} must be square and match M ({n} x {n}); got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be finite")
    if n_rigid not in (0, 1):
        raise ValueError(f"n_rigid must be 0 or 1, got {n_rigid}")
    if n - n_rigid < 1:
        raise ValueError("the modal model needs at least one elastic mode")
    return ModalArrays(M=M, K=K, C=C, n_rigid=n_rigid)


@dataclass(frozen=True)
class AeroelasticMatrices:
    """Matrices of Eqs. (2.63), (2.68)-(2.70) at one (rho, U).

    A (n_z x n_z), B (n_z x 3; zero columns when there is no rigid mode), C_hinge (1 x n_z),
    D_hinge (1 x 3) (empty when n_rigid = 0), state_names, and the sizes n_elastic, n_lags,
    n_rigid.
    """

    A: np.ndarray
    B: np.ndarray
    C_hinge: np.ndarray
    D_hinge: np.ndarray
    state_names: tuple
    n_elastic: int
    n_lags: int
    n_rigid: int
    velocity: float
    density: float
    n_lag_states: int = 0

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def elastic_state_slice(self) -> slice:
        """States zeta_s and zeta_s_dot (the structural part of z)."""
        return slice(0, 2 * self.n_elastic)


def aeroelastic_matrices(modal, rfa, rho: float, velocity: float) -> AeroelasticMatrices:
    """A_sys, B_sys of Eq. (2.63) and the hinge-moment C, D of Eqs. (2.69)-(2.70).

    Parameters
    ----------
    modal : ModalArrays or any object with M, K, C, n_rigid (n_modes x n_modes, rigid first).
    rfa : :class:`asekit.rfa.RogerFit` (coefficients A0..A_{N+2}) or
        :class:`asekit.rfa.MinimumStateFit` over the same n_modes (anything with ``A[0:3]``,
        ``b_ref`` and ``lag_realization(n_rigid)``).
    rho : air density (kg/m^3), > 0.
    velocity : true airspeed U (m/s), > 0.
    """
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    rho = positive("rho", rho)
    U = positive("velocity", velocity)
    A = finite_array("rfa.A", rfa.A)
    if A.shape[1] != m.n_modes:
        raise ValueError(f"rfa has {A.shape[1]} modes, the modal model {m.n_modes}")
    b = positive("rfa.b_ref", rfa.b_ref)
    with np.errstate(over="ignore"):
        q = 0.5 * rho * np.float64(U) ** 2
    if not np.isfinite(q):
        raise ValueError(f"rho = {rho:g} and velocity = {U:g} give an infinite dynamic pressure "
                         "(rho U^2 / 2 must be finite)")
    Mb = m.M - 0.5 * rho * b ** 2 * A[2]                    # Eq. (2.60) definitions
    Cb = m.C - 0.5 * rho * b * U * A[1]
    Kb = m.K - q * A[0]
    c, s = slice(0, m.n_rigid), slice(m.n_rigid, m.n_modes)
    ns, nc = m.n_elastic, m.n_rigid
    # lag terms as D (p I + diag(beta))^-1 E p: Roger's (Eqs. 2.61-2.63, D a 0/1 selection) or
    # the minimum-state fit's (Karpel 1982), x_a' = -(U/b) diag(beta) x_a + E zeta'
    Dl, El, roots, lag_names = rfa.lag_realization(nc)
    roots = finite_array("rfa.lag_roots", roots)
    nL = roots.size
    try:
        Mss_inv = np.linalg.inv(Mb[s, s])
    except np.linalg.LinAlgError:
        raise ValueError(f"M - rho b^2 / 2 A2 is singular at rho = {rho:g}: the apparent mass "
                         "cancels the structural mass; check rho and the fit's A2") from None
    nz = 2 * ns + nL
    Asys = np.zeros((nz, nz))
    Bsys = np.zeros((nz, 3))
    i_q, i_qd, i_sa = 0, ns, 2 * ns
    Asys[i_q:i_qd, i_qd:i_sa] = np.eye(ns)
    Asys[i_qd:i_sa, i_q:i_qd] = -Mss_inv @ Kb[s, s]
    Asys[i_qd:i_sa, i_qd:i_sa] = -Mss_inv @ Cb[s, s]
    Asys[i_qd:i_sa, i_sa:] = q * Mss_inv @ Dl[s]
    Asys[i_sa:, i_qd:i_sa] = El[:, s]                          # E_s (E_ss, E_cs of Eq. 2.63)
    Asys[i_sa:, i_sa:] = -np.diag(U / b * roots)               # (U/b) R
    if nc:
        Bsys[i_sa:, 1:2] = El[:, c]                            # E_c (E_sc, E_cc)
        Bsys[i_qd:i_sa, 0:1] = -Mss_inv @ Kb[s, c]
        Bsys[i_qd:i_sa, 1:2] = -Mss_inv @ Cb[s, c]
        Bsys[i_qd:i_sa, 2:3] = -Mss_inv @ Mb[s, c]
        row_state = np.hstack([-Kb[c, s], -Cb[c, s], q * Dl[c]])
        acc_state = np.hstack([-Kb[s, s], -Cb[s, s], q * Dl[s]])
        C_h = row_state - Mb[c, s] @ Mss_inv @ acc_state                     # Eq. (2.69)
        D_h = (np.hstack([-Kb[c, c], -Cb[c, c], -Mb[c, c]])
               - Mb[c, s] @ Mss_inv @ np.hstack([-Kb[s, c], -Cb[s, c], -Mb[s, c]]))  # (2.70)
    else:
        Bsys = np.zeros((nz, 0))
        C_h = np.zeros((0, nz))
        D_h = np.zeros((0, 0))
    names = ([f"zeta{j + 1}" for j in range(ns)] + [f"zeta{j + 1}_dot" for j in range(ns)]
             + list(lag_names))
    hint = (f"rho = {rho:g} kg/m^3 and velocity = {U:g} m/s overflow the model; give a "
            "physical flight condition")
    for what, a in (("A_sys", Asys), ("B_sys", Bsys), ("C_hinge", C_h), ("D_hinge", D_h)):
        finite_result(f"the aeroelastic {what}", a, hint)
    return AeroelasticMatrices(A=Asys, B=Bsys, C_hinge=C_h, D_hinge=D_h,
                               state_names=tuple(names), n_elastic=ns, n_lags=rfa.n_lags,
                               n_rigid=nc, velocity=U, density=rho, n_lag_states=nL)


def rotation_rows(dw_dx: np.ndarray, n_rigid: int, sign: float = -1.0) -> np.ndarray:
    """Output rows (n_points, n_modes) giving the pitch rotation theta_y at points from the
    modal slopes dw/dx (n_points, n_modes).

    With a rigid mode (n_rigid = 1) the rows are scaled so that the rigid mode contributes
    exactly its pitch angle theta (its slope is uniform, +-1 per rad), so the output is
    ``theta + elastic rotation`` in the rigid mode's sign convention. Without a rigid mode,
    ``sign * dw/dx`` (default -1: a positive rotation about +y moves the trailing edge down,
    w = -theta_y x, as in :mod:`asekit.geometry`).
    """
    d = np.atleast_2d(np.asarray(dw_dx, dtype=float))
    if n_rigid:
        slope = d[:, 0]
        if np.any(np.abs(slope) < 1e-12):
            raise ValueError("the rigid mode has zero slope at an output point; cannot scale")
        return d / slope[:, None]
    return sign * d


def aeroelastic_model(modal, rfa, rho: float, velocity: float, outputs: dict | None = None,
                      modal_outputs: bool = True):
    """The aeroelastic model of Eqs. (2.63), (2.64), (2.68) as a :class:`control.StateSpace`.

    Parameters
    ----------
    modal : ModalArrays or a ModalModel-like object (M, K, C, n_rigid).
    rfa : :class:`asekit.rfa.RogerFit` or :class:`asekit.rfa.MinimumStateFit` of the same
        modes.
    rho, velocity : density (kg/m^3) and true airspeed (m/s), both > 0.
    outputs : optional ``{name: row}`` where ``row`` (n_modes,) maps the modal coordinates
        (rigid first) to a physical quantity by modal superposition, Eq. (2.64): a displacement
        (modal w at a point) or a rotation (see :func:`rotation_rows`). The rigid part of the
        row multiplies the input theta (feed-through D).
    modal_outputs : include the elastic modal coordinates ``zeta1..zeta_ns`` as outputs.

    Returns
    -------
    control.StateSpace with inputs ``theta``, ``theta_dot``, ``theta_ddot`` (rad, rad/s,
    rad/s^2; none when n_rigid = 0) and outputs ``hinge_moment`` (N m, T_hinge@fin = -T_fin,
    positive de-centering for a positive Q_cc; only with a rigid mode), the modal coordinates and
    the named ``outputs``. States are named as in Eq. (2.63).
    """
    import control

    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    mats = aeroelastic_matrices(m, rfa, rho, velocity)
    ns, nz = mats.n_elastic, mats.n_states
    ni = mats.B.shape[1]
    C_rows, D_rows, names = [], [], []
    if m.n_rigid:
        C_rows.append(mats.C_hinge)
        D_rows.append(mats.D_hinge)
        names.append("hinge_moment")
    if modal_outputs:
        C_rows.append(np.hstack([np.eye(ns), np.zeros((ns, nz - ns))]))
        D_rows.append(np.zeros((ns, ni)))
        names += [f"zeta{j + 1}" for j in range(ns)]
    for name, row in (outputs or {}).items():
        row = np.asarray(row, dtype=float).ravel()
        if row.size != m.n_modes:
            raise ValueError(f"output {name!r} row has {row.size} entries; expected n_modes = "
                             f"{m.n_modes}")
        cr = np.zeros((1, nz))
        cr[0, :ns] = row[m.n_rigid:]
        dr = np.zeros((1, ni))
        if m.n_rigid:
            dr[0, 0] = row[0]
        C_rows.append(cr)
        D_rows.append(dr)
        names.append(str(name))
    if not C_rows:
        raise ValueError("no outputs: a model without a rigid mode needs modal_outputs=True "
                         "or named outputs")
    C = np.vstack(C_rows)
    D = np.vstack(D_rows) if ni else np.zeros((C.shape[0], 0))
    return control.ss(mats.A, mats.B, C, D, states=list(mats.state_names),
                      inputs=list(INPUT_NAMES[:ni]), outputs=names,
                      name=f"aeroelastic_U{velocity:g}".replace(".", "p"))


def fin_outputs(modal_model, points, names=None, shaft_point=None) -> dict:
    """Output rows for :func:`aeroelastic_model` from an asekit ModalModel: the normal
    displacement ``w_<name>`` (m) and pitch rotation ``theta_<name>`` (rad, rigid angle +
    elastic rotation) at each of ``points`` ((n, 2) x, y in m), and, when ``shaft_point`` is
    given, ``fin_root_pitch`` (rad) there. Uses ``asekit.structure.modes.mode_shapes_at``.
    """

    pts = np.atleast_2d(np.asarray(points, dtype=float))
    names = [f"p{i + 1}" for i in range(len(pts))] if names is None else list(names)
    w, dwdx = mode_shapes_at(modal_model, pts)
    w, dwdx = np.atleast_2d(w), np.atleast_2d(dwdx)
    rot = rotation_rows(dwdx, modal_model.n_rigid)
    out = {}
    for i, nm in enumerate(names):
        out[f"w_{nm}"] = w[i]
        out[f"theta_{nm}"] = rot[i]
    if shaft_point is not None:
        _, d0 = mode_shapes_at(modal_model, np.atleast_2d(np.asarray(shaft_point, float)))
        out["fin_root_pitch"] = rotation_rows(np.atleast_2d(d0), modal_model.n_rigid)[0]
    return out
