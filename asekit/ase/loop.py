"""The aeroservoelastic model: servo-actuator + aeroelastic fin through the hinge moment
(thesis Ch. 5, Figs 58-84).

Interconnection (Fig 58). The actuator (:func:`asekit.servo.actuator.actuator_state_space`: inputs
``voltage`` and ``hinge_moment`` at the fin; outputs transmission angle ``theta``, rate
``omega``, acceleration ``alpha``, ``current``) drives the rigid-mode inputs ``theta``,
``theta_dot``, ``theta_ddot`` of the aeroelastic model (:func:`asekit.aeroelastic.statespace.aeroelastic_model`,
Eq. 2.63), whose hinge-moment output (Eqs. 2.68-2.70) loads the transmission (Eq. 2.71).

The hinge moment has a direct term in the rigid acceleration, ``D_hinge[2] theta''``, and the
actuator's acceleration depends directly on the hinge moment: an algebraic loop. It is removed
exactly, not approximated: ``-D_hinge[2] = M_bar_cc - M_bar_cs M_bar_ss^-1 M_bar_sc`` is the
effective inertia of the elastic fin (plus its apparent air mass) about the shaft, so it is moved
into the actuator as its load inertia, and the aeroelastic model feeds back the remaining hinge
moment ``C_hinge z + D_hinge[0] theta + D_hinge[1] theta'``. The fin's inertia therefore enters
once, through the aeroelastic model. With the single-node shaft the first elastic mode is largely
the fin pitching on the 120 N m/rad shaft spring, so this effective inertia is tiny (the
transmission feels the fin through the spring). Counting J_fin in J_total@motor (Eq. 2.33) as
well as in the hinge moment would count it twice; ``count_fin_inertia_twice=True`` does so, for
comparison. (The thesis's FWTF 1 phase margin, 79.5 deg at 131 Hz against 78.4 deg for the
Ch. 4 design with J_fin, is what the actuator gives without the fin's inertia: its Ch. 5 model,
too, carried the fin's inertia through the hinge moment only.)

Topologies (Section 5.1): ``"AEM1"`` closes the PD loop on the transmission output (motor
encoder, Fig 60); ``"AEM2"`` on the fin-root pitch angle (potentiometer at the fin shaft,
Fig 61), which includes the elastic rotation at the root.

Open-loop and forward-path functions (Section 5.2): OPLOOP 1 = voltage -> transmission angle of
the actuator alone (Eq. 2.41); OPLOOP 2 = the same with the aeroelastic hinge moment fed back;
OPLOOP 3 = voltage -> fin-root angle with the hinge moment fed back; FWTF i = PD x OPLOOP i.

All quantities SI (rad, rad/s, V, A, N m); Hz and degrees only in the reporting helpers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import control as ct
import numpy as np
from scipy.integrate import solve_ivp

from asekit.aeroelastic.statespace import aeroelastic_matrices, aeroelastic_model
from asekit.servo.actuator import ActuatorParameters, PDController, actuator_state_space
from asekit.servo.piecewise import PiecewiseAffineLoop, propagate_exact, voltage_bounds
from asekit.servo.simulate import (
    THESIS_LIMITS,
    PowerLimits,
    applied_voltage,
    controller_voltage,
    motor_rhs,
)
from asekit.util.blas import small_dense
from asekit.util.validate import finite, positive

TOPOLOGIES = ("AEM1", "AEM2")
#: Name of the aeroelastic output that the AEM2 potentiometer measures.
FIN_ROOT = "fin_root_pitch"


def _check_topology(topology: str) -> str:
    if topology not in TOPOLOGIES:
        raise ValueError(f"topology must be one of {TOPOLOGIES}, got {topology!r}")
    return topology


def _check_controller(controller: PDController) -> PDController:
    if not isinstance(controller, PDController):
        raise ValueError(f"controller must be a PDController, got {type(controller).__name__}")
    for n in ("gain", "kp", "kd"):
        finite(f"controller.{n}", getattr(controller, n))
    return controller


@dataclass(frozen=True)
class AeroservoelasticModel:
    """The actuator and the aeroelastic fin at one flight condition, ready to interconnect.

    Attributes
    ----------
    actuator : the actuator with its load inertia set to the fin's effective inertia
        (``-D_hinge[2]``; see the module docstring).
    aeroelastic : python-control StateSpace, inputs ``theta``, ``theta_dot``, ``theta_ddot``;
        outputs ``hinge_moment`` (without the acceleration term), the elastic modal coordinates
        ``zeta1..``, ``fin_root_pitch`` and any named point outputs.
    A, B : the aeroelastic state matrices (Eq. 2.63), for the nonlinear simulation.
    output_C, output_D : rows of the aeroelastic outputs (same order as
        ``aeroelastic.output_labels``).
    effective_fin_inertia : -D_hinge[2] (kg m^2).
    mach, density (kg/m^3), velocity (m/s) : the flight condition.
    """

    actuator: ActuatorParameters
    aeroelastic: ct.StateSpace
    A: np.ndarray
    B: np.ndarray
    output_C: np.ndarray
    output_D: np.ndarray
    effective_fin_inertia: float
    mach: float | None
    density: float
    velocity: float
    meta: dict = field(default_factory=dict)

    @property
    def output_names(self) -> list[str]:
        return list(self.aeroelastic.output_labels)

    def output_index(self, name: str) -> int:
        names = self.output_names
        if name not in names:
            raise ValueError(f"unknown output {name!r}; available: {names}")
        return names.index(name)

    @property
    def n_elastic(self) -> int:
        return sum(1 for n in self.output_names if n.startswith("zeta"))


def build_model(modal, rfa, density: float, velocity: float, point_outputs: dict,
                actuator: ActuatorParameters | None = None, mach: float | None = None,
                count_fin_inertia_twice: bool = False) -> AeroservoelasticModel:
    """Assemble actuator and aeroelastic fin at (density, velocity).

    Parameters
    ----------
    modal : ModalModel-like (M, K, C, n_rigid = 1: the rigid pitch mode first, unit rotation).
    rfa : :class:`asekit.rfa.RogerFit` of the fin's GAFs at the flight Mach.
    density : air density (kg/m^3), > 0. velocity : true airspeed (m/s), > 0.
    point_outputs : ``{name: row (n_modes,)}`` modal-superposition rows (Eq. 2.64) of the
        outputs to carry; must contain ``"fin_root_pitch"`` (the AEM2 feedback). See
        :func:`asekit.aeroelastic.statespace.fin_outputs`.
    actuator : motor and transmission (default thesis values); its ``fin_inertia`` is replaced
        by the fin's effective inertia unless ``count_fin_inertia_twice``.
    mach : the Mach number the RFA belongs to (informational).
    count_fin_inertia_twice : reproduce the thesis's Simulink choice (J_fin in the actuator and
        the full hinge moment fed back).
    """
    if getattr(modal, "n_rigid", 0) != 1:
        raise ValueError("the modal model needs exactly one rigid (actuator) mode first, "
                         f"got n_rigid = {getattr(modal, 'n_rigid', None)}")
    if FIN_ROOT not in point_outputs:
        raise ValueError(f"point_outputs must contain {FIN_ROOT!r} (the AEM2 feedback)")
    actuator = ActuatorParameters() if actuator is None else actuator
    mats = aeroelastic_matrices(modal, rfa, density, velocity)
    j_eff = float(-mats.D_hinge[0, 2])
    if not j_eff > 0:
        raise ValueError(f"effective fin inertia -D_hinge[2] = {j_eff:g} is not positive: the "
                         "modal mass matrix or the RFA's A2 term is inconsistent")
    sys = aeroelastic_model(modal, rfa, density, velocity, outputs=point_outputs)
    C, D = np.array(sys.C), np.array(sys.D)
    ih = list(sys.output_labels).index("hinge_moment")
    if count_fin_inertia_twice:
        act = actuator
    else:
        D = D.copy()
        D[ih, 2] = 0.0            # the acceleration term moves into the actuator's inertia
        act = replace(actuator, fin_inertia=j_eff)
    sys = ct.ss(sys.A, sys.B, C, D, states=list(sys.state_labels),
                inputs=list(sys.input_labels), outputs=list(sys.output_labels),
                name="aeroelastic")
    return AeroservoelasticModel(actuator=act, aeroelastic=sys, A=np.array(sys.A),
                                 B=np.array(sys.B), output_C=C, output_D=D,
                                 effective_fin_inertia=j_eff, mach=mach, density=float(density),
                                 velocity=float(velocity),
                                 meta={"count_fin_inertia_twice": bool(count_fin_inertia_twice)})


# ---------------------------------------------------------------------------------------------
# linear interconnections (python-control, named signals)
# ---------------------------------------------------------------------------------------------
def _plant(model: AeroservoelasticModel, fin: ct.StateSpace | None = None) -> ct.StateSpace:
    """Actuator + aeroelastic fin with the hinge moment fed back (Fig 58); input ``voltage``,
    outputs every actuator output (``theta``, ``omega``, ``alpha``, ``current``) and every fin
    output.

    Built in two python-control steps, both exact: :func:`control.interconnect` joins the
    actuator's transmission angle, rate and acceleration to the fin's rigid-mode inputs (an open
    chain, named signals), then :func:`control.feedback` closes the hinge-moment path. (A single
    ``interconnect`` of the loop trips python-control's static-signal iteration, which allows
    one pass per subsystem: both ends of this loop have direct feedthrough.)
    """
    act = actuator_state_space(model.actuator, name="actuator")
    fin = model.aeroelastic if fin is None else fin
    outs = list(act.output_labels) + list(fin.output_labels)
    chain = ct.interconnect(
        [act, fin],
        connections=[["aeroelastic.theta", "actuator.theta"],
                     ["aeroelastic.theta_dot", "actuator.omega"],
                     ["aeroelastic.theta_ddot", "actuator.alpha"]],
        inplist=["actuator.voltage", "actuator.hinge_moment"],
        inputs=["voltage", "hinge_moment"],
        outlist=[f"actuator.{o}" for o in act.output_labels]
        + [f"aeroelastic.{o}" for o in fin.output_labels],
        outputs=outs, name="chain", check_unused=False)
    k = np.zeros((2, len(outs)))
    k[1, outs.index("hinge_moment")] = 1.0      # hinge-moment output -> hinge-moment input
    gain = ct.ss(np.zeros((0, 0)), np.zeros((0, len(outs))), np.zeros((2, 0)), k)
    loop = ct.feedback(chain, gain, sign=+1)
    return ct.ss(loop.A, loop.B[:, :1], loop.C, loop.D[:, :1], inputs=["voltage"],
                 outputs=outs, states=list(chain.state_labels), name="plant")


def open_loop(model: AeroservoelasticModel, which: int) -> ct.StateSpace:
    """OPLOOP ``which`` (Section 5.2) from voltage (V) to an angle (rad).

    1: transmission angle of the actuator alone (rigid fin, no hinge moment; Eq. 2.41 with the
       actuator's own load inertia); 2: transmission angle with the aeroelastic hinge moment fed
       back; 3: fin-root pitch angle with the hinge moment fed back.
    """
    if which == 1:
        act = actuator_state_space(model.actuator, name="actuator")
        return ct.ss(act.A, act.B[:, :1], act.C[:1], act.D[:1, :1], inputs=["voltage"],
                     outputs=["theta"], states=list(act.state_labels), name="OPLOOP1")
    if which not in (2, 3):
        raise ValueError(f"which must be 1, 2 or 3, got {which!r}")
    sys = _plant(model)
    name = "theta" if which == 2 else FIN_ROOT
    i = list(sys.output_labels).index(name)
    return ct.ss(sys.A, sys.B, sys.C[i:i + 1], sys.D[i:i + 1], inputs=["voltage"],
                 outputs=[name], states=list(sys.state_labels), name=f"OPLOOP{which}")


def forward_path(model: AeroservoelasticModel, controller: PDController, which: int):
    """FWTF ``which`` = K_c (K_P + K_D s) x OPLOOP ``which`` (Section 5.2), rad -> rad.

    The PD is improper, so the product is formed in state space: for a strictly proper
    OPLOOP (A, B, C, 0), s y = C A x + C B u, hence FWTF = (A, B, K_c (K_P C + K_D C A),
    K_c K_D C B) -- exact, without a transfer-function round trip.
    """
    _check_controller(controller)
    ol = open_loop(model, which)
    A, B, C, D = (np.array(m) for m in (ol.A, ol.B, ol.C, ol.D))
    if np.any(D != 0):
        raise ValueError(f"OPLOOP{which} is not strictly proper; cannot apply the PD exactly")
    kc, kp, kd = controller.gain, controller.kp, controller.kd
    return ct.ss(A, B, kc * (kp * C + kd * C @ A), kc * kd * C @ B, inputs=["error"],
                 outputs=list(ol.output_labels), states=list(ol.state_labels),
                 name=f"FWTF{which}")


def with_fin_root_rate(fin: ct.StateSpace) -> ct.StateSpace:
    """The aeroelastic system ``fin`` (Eq. 2.63, inputs [theta, omega, alpha]) with one more
    output, ``fin_root_rate`` (rad/s): the fin-root pitch row C_r z + D_r0 theta differentiated
    along the state equation,

        d/dt (C_r z + D_r0 theta) = C_r (A z + B u) + D_r0 omega,

    so that a rate feedback stays proper (used by :func:`closed_loop` for AEM2 and by the active
    flutter suppression plant).

    Examples
    --------
    >>> import control as ct
    >>> fin = ct.ss([[-1.0]], [[1.0, 0.0, 0.0]], [[2.0]], [[0.5, 0.0, 0.0]],
    ...             inputs=["theta", "omega", "alpha"], outputs=["fin_root_pitch"])
    >>> out = with_fin_root_rate(fin)
    >>> out.output_labels, float(out.C[1, 0]), out.D[1].tolist()
    (['fin_root_pitch', 'fin_root_rate'], -2.0, [2.0, 0.5, 0.0])
    """
    ir = list(fin.output_labels).index(FIN_ROOT)
    Cr, Dr = np.array(fin.C[ir:ir + 1]), np.array(fin.D[ir:ir + 1])
    rate_C = Cr @ np.array(fin.A)
    rate_D = Cr @ np.array(fin.B) + np.array([[0.0, Dr[0, 0], 0.0]])
    return ct.ss(fin.A, fin.B, np.vstack([fin.C, rate_C]), np.vstack([fin.D, rate_D]),
                 states=list(fin.state_labels), inputs=list(fin.input_labels),
                 outputs=list(fin.output_labels) + ["fin_root_rate"], name="aeroelastic")


def closed_loop(model: AeroservoelasticModel, controller: PDController, topology: str,
                outputs: list[str] | None = None) -> ct.StateSpace:
    """Linear closed loop from ``theta_cmd`` (rad) to ``outputs`` (default: transmission angle,
    fin-root angle, hinge moment, voltage, current and every aeroelastic output).

    The PD acts on the error ``theta_cmd - feedback`` with feedback the transmission angle
    (AEM1) or the fin-root angle (AEM2); the derivative term is K_c K_D d/dt(error), realised
    exactly by using the feedback rate (transmission ``omega``, or the fin-root rate from the
    aeroelastic states) so the interconnection stays proper.
    """
    _check_topology(topology)
    _check_controller(controller)
    fin = model.aeroelastic
    plant = _plant(model, with_fin_root_rate(fin))
    fb, fb_rate = ("theta", "omega") if topology == "AEM1" else (FIN_ROOT, "fin_root_rate")
    kc, kp, kd = controller.gain, controller.kp, controller.kd
    # PD with the derivative on the feedback rate only (a step's derivative impulse is absent):
    # voltage = Kc Kp (cmd - fb) - Kc Kd fb_rate (+ Kc Kd cmd_rate, zero for steps)
    pd = ct.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)),
               [[kc * kp, -kc * kp, -kc * kd]], inputs=["cmd", "fb", "fb_rate"],
               outputs=["voltage"], name="pd")
    default = (["theta", "omega", "current", "voltage", FIN_ROOT, "hinge_moment"]
               + [o for o in fin.output_labels if o not in (FIN_ROOT, "hinge_moment")])
    outputs = default if outputs is None else list(outputs)
    outlist = []
    for o in outputs:
        if o == "voltage":
            outlist.append("pd.voltage")
        elif o in plant.output_labels:
            outlist.append(f"plant.{o}")
        else:
            raise ValueError(f"unknown output {o!r}; available: voltage, "
                             f"{list(plant.output_labels)}")
    return ct.interconnect(
        [plant, pd],
        connections=[["plant.voltage", "pd.voltage"], ["pd.fb", f"plant.{fb}"],
                     ["pd.fb_rate", f"plant.{fb_rate}"]],
        inplist=["pd.cmd"], inputs=["theta_cmd"], outlist=outlist, outputs=outputs,
        name=f"{topology}_closed_loop", check_unused=False)


def is_stable(sys) -> bool:
    """All poles in the open left half plane."""
    return bool(np.all(np.real(ct.poles(sys)) < 0))


# ---------------------------------------------------------------------------------------------
# frequency-domain reporting
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Crossovers:
    """All crossovers of a loop L(j omega) on a frequency grid (Hz, deg, dB).

    gain_crossovers_hz with phase_margins_deg (phase + 180 deg, wrapped to (-180, 180]);
    phase_crossovers_hz (phase = -180 deg mod 360) with gain_margins_db (-20 log10 |L|).
    """

    gain_crossovers_hz: np.ndarray
    phase_margins_deg: np.ndarray
    phase_crossovers_hz: np.ndarray
    gain_margins_db: np.ndarray

    @property
    def phase_margin_deg(self) -> float:
        """Smallest phase margin (deg); inf without a gain crossover."""
        return float(np.min(self.phase_margins_deg)) if self.phase_margins_deg.size else math.inf

    @property
    def gain_margin_db(self) -> float:
        """Gain margin at the first phase crossover (dB); inf without one."""
        return float(self.gain_margins_db[0]) if self.gain_margins_db.size else math.inf


@small_dense
def state_space_response(A, B, C, D, s, block: int = 4096) -> np.ndarray:
    """G(s) = C (s I - A)^-1 B + D of the state space (A, B, C, D) at every complex ``s``,
    shape (n_outputs, n_inputs, len(s)): all frequencies in one batched pass.

    Method (Laub 1981, "Efficient multivariable frequency response computations", IEEE TAC
    26(2), the approach of SLICOT TB05AD with the Schur instead of the Hessenberg form):
    A is balanced by an exact power-of-two diagonal similarity T (``scipy.linalg.matrix_balance``;
    A_b = T^-1 A T, B_b = T^-1 B, C_b = C T) and reduced once to complex Schur form
    A_b = U R U^H (R upper triangular, U unitary), so that

        G(s) = (C_b U) (s I - R)^-1 (U^H B_b) + D,

    and the triangular systems of all frequencies are solved together by back substitution,
    x_i = (b_i + sum_{j>i} R_ij x_j) / (s - R_ii), n vectorised steps instead of one O(n^3)
    LU per frequency. One step of iterative refinement on the balanced system
    (r = B_b - (s I - A_b) x, solved again through the Schur form) brings the error to that of a
    pivoted LU solve of each frequency (agreement with python-control's per-frequency solve
    to about 1e-14 relative on the fin's 37-state loops; tests/ase/test_ase.py).

    Parameters
    ----------
    A (n, n), B (n, m), C (p, n), D (p, m) : real or complex arrays; n = 0 gives D.
    s : complex frequencies (rad/s for continuous systems, s = j omega), any shape, flattened.
    block : frequencies per batch (bounds the memory to about 3 n m block complex numbers).

    Raises ValueError if some s is numerically an eigenvalue of A (the response is infinite
    there), naming that s.
    """
    import scipy.linalg as sla

    A, B, C, D = (np.atleast_2d(np.asarray(x)) for x in (A, B, C, D))
    s = np.asarray(s, complex).ravel()
    n = A.shape[0]
    p, m = D.shape
    if n == 0:
        return np.broadcast_to(D[:, :, None].astype(complex), (p, m, s.size)).copy()
    if A.shape != (n, n) or B.shape != (n, m) or C.shape != (p, n):
        raise ValueError(f"inconsistent state-space shapes A {A.shape}, B {B.shape}, "
                         f"C {C.shape}, D {D.shape}")
    Ab, (scale, _) = sla.matrix_balance(A, permute=False, separate=True)
    Bb = B / scale[:, None]
    Cb = C * scale[None, :]
    R, U = sla.schur(Ab.astype(complex), output="complex")
    Uh = U.conj().T
    diag = np.diag(R)

    def tri_solve(rhs, sw):
        """(s I - R)^-1 rhs for rhs (n, q): q = m nb columns, column c at frequency sw[c]."""
        X = np.empty_like(rhs)
        for i in range(n - 1, -1, -1):
            acc = rhs[i] + R[i, i + 1:] @ X[i + 1:] if i < n - 1 else rhs[i]
            X[i] = acc / (sw - diag[i])
        return X

    out = np.empty((p, m, s.size), complex)
    bt = (Uh @ Bb).astype(complex)
    for k0 in range(0, s.size, block):
        sb = s[k0:k0 + block]
        nb = sb.size
        sw = np.tile(sb, m)                       # columns ordered input-major: (m, nb)
        rhs = np.repeat(bt, nb, axis=1)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = U @ tri_solve(rhs, sw)
            # one refinement step: residual of the balanced system, solved again
            res = np.repeat(Bb, nb, axis=1) - (sw * Z - Ab @ Z)
            Z = Z + U @ tri_solve(Uh @ res, sw)
            out[:, :, k0:k0 + nb] = (Cb @ Z).reshape(p, m, nb) + D[:, :, None]
    bad = ~np.all(np.isfinite(out), axis=(0, 1))
    for k in np.nonzero(bad)[0]:
        try:                                   # on (or numerically at) a pole: decide exactly
            x = np.linalg.solve(s[k] * np.eye(n) - A, B)
            out[:, :, k] = C @ x + D
        except np.linalg.LinAlgError:
            pass
        if not np.all(np.isfinite(out[:, :, k])):
            raise ValueError(f"frequency s = {s[k]:.6g} is a pole of the system (sI - A "
                             "singular): the frequency response is infinite there")
    return out


def frequency_response(sys, f_hz: np.ndarray) -> np.ndarray:
    """Complex frequency response of a SISO system at frequencies ``f_hz`` (Hz).

    State-space systems (continuous, s = j 2 pi f, or discrete, z = exp(j 2 pi f dt)) go
    through the batched :func:`state_space_response`; other LTI objects (transfer functions)
    through :func:`control.frequency_response`."""
    w = 2 * np.pi * np.asarray(f_hz, float).ravel()
    if isinstance(sys, ct.StateSpace):
        if sys.ninputs != 1 or sys.noutputs != 1:
            raise ValueError(f"sys must be SISO, got {sys.noutputs}x{sys.ninputs}")
        s = 1j * w if sys.isctime() else np.exp(1j * w * float(sys.dt))
        return state_space_response(sys.A, sys.B, sys.C, sys.D, s)[0, 0]
    return np.asarray(ct.frequency_response(sys, w).complex).ravel()


def crossovers(loop, f_hz: np.ndarray | None = None) -> Crossovers:
    """Every gain and phase crossover of the SISO loop ``loop`` over ``f_hz`` (default
    1 Hz - 10 kHz, 20000 log-spaced points), each refined by linear interpolation.

    The phase is unwrapped along the grid, so a phase crossover is where it passes an odd
    multiple of -180 deg.
    """
    f = np.logspace(0, 4, 20000) if f_hz is None else np.asarray(f_hz, float)
    h = frequency_response(loop, f)
    mag_db = 20 * np.log10(np.abs(h))
    ph = np.degrees(np.unwrap(np.angle(h)))
    gc, pm = [], []
    for i in np.nonzero(np.sign(mag_db[:-1]) != np.sign(mag_db[1:]))[0]:
        t = mag_db[i] / (mag_db[i] - mag_db[i + 1])
        fc = f[i] * (f[i + 1] / f[i]) ** t
        p = ph[i] + t * (ph[i + 1] - ph[i])
        gc.append(fc)
        pm.append((p + 180.0 + 180.0) % 360.0 - 180.0)
    pc, gm = [], []
    shifted = (ph + 180.0) / 360.0            # integer where phase = -180 + 360 n
    level = np.floor(shifted)
    for i in np.nonzero(level[:-1] != level[1:])[0]:
        target = max(level[i], level[i + 1])
        t = (target - shifted[i]) / (shifted[i + 1] - shifted[i])
        fc = f[i] * (f[i + 1] / f[i]) ** t
        pc.append(fc)
        gm.append(-(mag_db[i] + t * (mag_db[i + 1] - mag_db[i])))
    return Crossovers(np.array(gc), np.array(pm), np.array(pc), np.array(gm))


def resonances(sys, f_hz: np.ndarray | None = None, min_prominence_db: float = 1.0) -> np.ndarray:
    """Frequencies (Hz) of the local maxima of |sys(j 2 pi f)| over ``f_hz`` (default
    10 Hz - 2 kHz), keeping peaks at least ``min_prominence_db`` above the neighbouring minima."""
    from scipy.signal import find_peaks

    f = np.logspace(1, np.log10(2000.0), 40000) if f_hz is None else np.asarray(f_hz, float)
    mag_db = 20 * np.log10(np.abs(frequency_response(sys, f)))
    idx, _ = find_peaks(mag_db, prominence=min_prominence_db)
    return f[idx]


# ---------------------------------------------------------------------------------------------
# nonlinear (power-limited) closed loop
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AseSimulation:
    """Time histories of a closed-loop aeroservoelastic simulation (SI).

    t (s); command, theta (transmission angle), omega, alpha, current (A), voltage (applied, V);
    outputs: ``{name: history}`` for every aeroelastic output (hinge_moment in N m without the
    acceleration term is replaced by the full hinge moment; fin_root_pitch; zeta*; points);
    topology, limits.
    """

    t: np.ndarray
    command: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    outputs: dict
    topology: str
    limits: PowerLimits | None
    theta0: float = 0.0

    @property
    def fin_root(self) -> np.ndarray:
        return self.outputs[FIN_ROOT]


def _fb_rows(model: AeroservoelasticModel):
    ir = model.output_index(FIN_ROOT)
    Cr, Dr = model.output_C[ir], model.output_D[ir]
    return Cr, Dr


# ---------------------------------------------------------------------------------------------
# exact (matrix-exponential) integration of the piecewise-affine power-limited loop
# ---------------------------------------------------------------------------------------------
def actuated_state_matrix(A, B, Ch, Dh, motor, ratio: float, efficiency: float,
                          inertia_at_motor: float):
    """The actuator + aeroelastic state matrix F of x' = F x + g V, x = [theta, omega, I, z]
    (Eqs. 2.30-2.37 with Eq. 2.63), dtype-generic so that a complex step can pass through it.

    With the hinge moment T0 = C_h z + D_h0 theta + D_h1 omega (the acceleration term already in
    the motor-side inertia ``inertia_at_motor``, kg m^2, Eq. 2.33):

        theta' = omega
        omega' = alpha = (K_t I + T0 / (N eta) - c N omega) / (N J_total@motor)
        I'     = (-R I - K_b N omega) / L           (+ V / L, the input)
        z'     = A z + B [theta, omega, alpha]

    Parameters
    ----------
    A, B : (nz, nz), (nz, 3) the aeroelastic system (inputs theta, omega, alpha).
    Ch, Dh : (nz,), (3,) the hinge-moment row (N m).
    motor : :class:`asekit.servo.actuator.DCMotor` (R, L, K_t, K_b, c).
    ratio, efficiency : the transmission's N and eta.
    inertia_at_motor : kg m^2.

    Returns
    -------
    F : (3 + nz, 3 + nz); arow : (3 + nz,) alpha = arow x; hm_row : (3 + nz,) T0 = hm_row x.

    Examples
    --------
    >>> from asekit.servo.actuator import DCMotor
    >>> F, arow, hm = actuated_state_matrix(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros(0),
    ...                                     np.zeros(3), DCMotor(), 10.0, 1.0, 1e-5)
    >>> F.shape, float(F[0, 1])
    ((3, 3), 1.0)
    """
    m, N, eta = motor, ratio, efficiency
    nz = A.shape[0]
    n = 3 + nz
    dtype = np.result_type(A, B, Ch, Dh, float)
    hm_row = np.zeros(n, dtype=dtype)
    hm_row[0], hm_row[1], hm_row[3:] = Dh[0], Dh[1], Ch
    nj = N * inertia_at_motor
    arow = hm_row / (N * eta) / nj
    arow[1] -= m.viscous_damping * N / nj
    arow[2] += m.torque_constant / nj
    F = np.zeros((n, n), dtype=np.result_type(dtype, arow))
    F[0, 1] = 1.0
    F[1] = arow
    F[2, 1] = -m.back_emf_constant * N / m.inductance
    F[2, 2] = -m.resistance / m.inductance
    F[3:, 3:] = A
    F[3:, 0] += B[:, 0]
    F[3:, 1] += B[:, 1]
    F[3:] += np.outer(B[:, 2], arow)
    return F, arow, hm_row


def _loop_matrices(model: AeroservoelasticModel, controller: PDController, command: float,
                   topology: str):
    """The closed loop of :func:`simulate_closed_loop` as x' = F x + g V (V the applied
    voltage), state x = [theta, omega, I, z] (z the aeroelastic states of Eq. 2.63), and the
    rows of the derived signals.

    From Eqs. (2.30)-(2.37) with the hinge moment T0 = C_h z + D_h0 theta + D_h1 omega (the
    acceleration term moved into the actuator, :func:`build_model`):

        theta' = omega
        omega' = alpha = (K_t I + T0 / (N eta) - c N omega) / (N J_total@motor)
        I'     = (V - R I - K_b N omega) / L
        z'     = A z + B [theta, omega, alpha]

    and the continuous PD demand V_cmd = K_c (K_P (theta_cmd - theta_fb) - K_D omega_fb), with
    (theta_fb, omega_fb) = (theta, omega) for AEM1 and (C_r z + D_r0 theta, C_r z' + D_r0 omega)
    for AEM2: V_cmd = k x + k0. Returns a dict with F, g, arow (alpha = arow x), k, k0,
    fb_row, om_row (theta_fb = fb_row x, omega_fb = om_row x), hm_row (T0 = hm_row x)."""
    act = model.actuator
    m, tr = act.motor, act.transmission
    N, eta = tr.ratio, tr.efficiency
    A, B = model.A, model.B
    ih = model.output_index("hinge_moment")
    Ch, Dh = model.output_C[ih], model.output_D[ih]
    Cr, Dr = _fb_rows(model)
    F, arow, hm_row = actuated_state_matrix(A, B, Ch, Dh, m, N, eta, act.inertia_at_motor)
    n = F.shape[0]
    g = np.zeros(n)
    g[2] = 1.0 / m.inductance
    if topology == "AEM2":
        fb = np.zeros(n)
        fb[0], fb[3:] = Dr[0], Cr
        om = Cr @ F[3:]
        om[1] += Dr[0]
    else:
        fb, om = np.zeros(n), np.zeros(n)
        fb[0], om[1] = 1.0, 1.0
    kc, kp, kd = controller.gain, controller.kp, controller.kd
    return {"F": F, "g": g, "arow": arow, "k": -kc * (kp * fb + kd * om),
            "k0": kc * kp * command, "fb_row": fb, "om_row": om, "hm_row": hm_row}


def _simulate_exact(model, controller, command, topology, lim, t_out, x0, sample_time):
    """x (n, n_out) and the voltage demand (n_out,) of :func:`simulate_closed_loop` by exact
    piecewise-linear propagation (:class:`PiecewiseAffineLoop`). With ``sample_time`` the
    demand is the ZOH digital PD of :func:`_integrate_zoh` (same sampling, same derivative)."""
    mats = _loop_matrices(model, controller, command, topology)
    bounds = voltage_bounds(model.actuator, lim, mats["F"].shape[0])
    return propagate_exact(mats, bounds, controller, command, t_out, x0, sample_time)


@small_dense
def simulate_closed_loop(model: AeroservoelasticModel, controller: PDController, command: float,
                         topology: str = "AEM1", limits: PowerLimits | None = THESIS_LIMITS,
                         t_final: float = 0.2, theta0: float = 0.0, n_out: int = 4001,
                         max_step: float = 5e-5, angle_limit: float = math.radians(15.0),
                         method: str = "exact", sample_time: float | None = None) -> AseSimulation:
    """Closed-loop step response of the actuator + aeroelastic fin (Figs 70-84).

    The nonlinear actuator of :mod:`asekit.servo.simulate` (``limits``: supply and current limits,
    None for the linear model) is integrated together with the linear aeroelastic states of
    Eq. (2.63). The PD acts on the transmission angle (AEM1) or the fin-root angle (AEM2) and
    their rates.

    The loop is linear wherever no limit binds and linear again (with the voltage held at the
    binding limit, itself affine in the state) where one does: ``method="exact"`` (default)
    propagates each region exactly by the matrix exponential (one per region and step length)
    and locates every change of region on the exact solution
    (:class:`PiecewiseAffineLoop`); a ``solve_ivp`` method name (``"RK45"``, ``"LSODA"``, ...)
    integrates the same right-hand side numerically instead (rtol 1e-7, atol 1e-10,
    ``max_step``), which agrees within that tolerance (tests/ase/test_ase.py).

    Parameters
    ----------
    command : commanded fin angle (rad); |command| must not exceed ``angle_limit`` (thesis
        Table 2: 15 deg) -- a larger command is refused with ValueError.
    t_final : simulated time (s), > 0. theta0 : initial angle (rad), the system at rest.
    n_out : output samples (uniform); the exact method also watches the limits between them.
    max_step : largest integrator step (s) of a ``solve_ivp`` method; the lag roots and the
        motor's electrical pole are near 1e4 rad/s.
    method : ``"exact"`` or a ``scipy.integrate.solve_ivp`` method.
    sample_time : None for a continuous PD; else a digital PD with zero-order hold sampling
        every ``sample_time`` s (thesis Table 2: 1 kHz -> 1e-3), its derivative the backward
        difference of the sampled feedback (as :func:`asekit.servo.simulate.simulate`).
    """
    _check_topology(topology)
    _check_controller(controller)
    command = finite("command", command)
    if abs(command) > angle_limit + 1e-12:
        raise ValueError(f"command {math.degrees(command):.3g} deg exceeds the angular position "
                         f"limit of {math.degrees(angle_limit):.3g} deg (thesis Table 2)")
    positive("t_final", t_final)
    if sample_time is not None:
        positive("sample_time", sample_time)
    lim = limits if limits is not None else PowerLimits(supply_voltage=None, current_limit=None)
    act = model.actuator
    A, B = model.A, model.B
    ih = model.output_index("hinge_moment")
    Ch, Dh = model.output_C[ih], model.output_D[ih]
    Cr, Dr = _fb_rows(model)
    nz = A.shape[0]
    aem2 = topology == "AEM2"

    def derivatives(x, v_hold=None):
        """(dx/dt, feedback angle, feedback rate, voltage demand) at state x; ``v_hold``: a
        held (sampled) voltage demand instead of the continuous PD."""
        z = x[3:]
        hm = Ch @ z + Dh[0] * x[0] + Dh[1] * x[1]
        # the acceleration does not depend on the voltage (it acts through the current state)
        alpha = motor_rhs(act, lim, x[:3], 0.0, hm)[1]
        zdot = A @ z + B @ np.array([x[0], x[1], alpha])
        if aem2:
            th_fb = Cr @ z + Dr[0] * x[0]
            om_fb = Cr @ zdot + Dr[0] * x[1]
        else:
            th_fb, om_fb = x[0], x[1]
        v_cmd = (controller_voltage(controller, command, th_fb, om_fb) if v_hold is None
                 else v_hold)
        dx_act = motor_rhs(act, lim, x[:3], v_cmd, hm)
        return np.concatenate([dx_act, zdot]), th_fb, om_fb, v_cmd

    x0 = np.zeros(3 + nz)
    x0[0] = float(theta0)
    t_out = np.linspace(0.0, t_final, n_out)
    opts = dict(method=method, max_step=max_step, rtol=1e-7, atol=1e-10)
    v_out = None
    if method == "exact":
        x, v_dem = _simulate_exact(model, controller, command, topology, lim, t_out, x0,
                                   sample_time)
        return _closed_loop_result(model, topology, limits, lim, t_out, x, v_dem, command,
                                   theta0, _loop_matrices(model, controller, command,
                                                          topology)["arow"])
    if sample_time is None:
        sol = solve_ivp(lambda t, x: derivatives(x)[0], (0.0, t_final), x0, t_eval=t_out,
                        **opts)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        x = sol.y
    else:
        x, v_out = _integrate_zoh(derivatives, controller, command, x0, t_out, sample_time,
                                  opts)
    # derived histories
    volt = np.empty(n_out)
    alpha = np.empty(n_out)
    for i in range(n_out):
        dx, _, _, v_cmd = derivatives(x[:, i], None if v_out is None else v_out[i])
        alpha[i] = dx[1]
        volt[i] = applied_voltage(act, lim, x[:3, i], v_cmd)
    return AseSimulation(t=t_out, command=np.full(n_out, command), theta=x[0], omega=x[1],
                         alpha=alpha, current=x[2], voltage=volt,
                         outputs=_output_histories(model, x, alpha), topology=topology,
                         limits=limits, theta0=float(theta0))


def _output_histories(model: AeroservoelasticModel, x: np.ndarray, alpha: np.ndarray) -> dict:
    """The model's outputs over states x (n, n_out) with fin accelerations alpha (n_out,); the
    hinge moment in full, its acceleration term (moved into the actuator) included."""
    z = x[3:]
    ih = model.output_index("hinge_moment")
    Ch, Dh = model.output_C[ih], model.output_D[ih]
    hm_part = Ch @ z + Dh[0] * x[0] + Dh[1] * x[1]
    u = np.vstack([x[0], x[1], alpha])
    y = model.output_C @ z + model.output_D @ u
    outputs = {name: y[j] for j, name in enumerate(model.output_names)}
    outputs["hinge_moment"] = hm_part - model.effective_fin_inertia * alpha \
        if not model.meta.get("count_fin_inertia_twice") else hm_part
    return outputs


def _closed_loop_result(model, topology, limits, lim, t_out, x, v_dem, command, theta0, arow):
    """The :class:`AseSimulation` of states x (n, n_out) and voltage demands v_dem (n_out,):
    the derived histories vectorised (alpha = arow x; the applied voltage by the clips of
    :func:`asekit.servo.simulate.applied_voltage`)."""
    n = x.shape[0]
    loop = PiecewiseAffineLoop(np.zeros((n, n)), np.zeros(n), np.zeros(n),
                                voltage_bounds(model.actuator, lim, n))
    volt = loop.applied(x, demand=v_dem)
    alpha = arow @ x
    return AseSimulation(t=t_out, command=np.full(t_out.size, command), theta=x[0].copy(),
                         omega=x[1].copy(), alpha=alpha, current=x[2].copy(), voltage=volt,
                         outputs=_output_histories(model, x, alpha), topology=topology,
                         limits=limits, theta0=float(theta0))


def _integrate_zoh(derivatives, controller, command, x0, t_out, ts, opts):
    """Digital PD with zero-order hold: integrate sample interval by sample interval, the
    voltage demand held over each interval. Returns (x (n_states, n_out), held demand)."""
    t_final = float(t_out[-1])
    n_samples = int(math.ceil(t_final / ts - 1e-9))
    x = np.empty((x0.size, t_out.size))
    v_out = np.empty(t_out.size)
    state = x0.copy()
    y_prev = None
    for k in range(n_samples):
        t0, t1 = k * ts, min((k + 1) * ts, t_final)
        _, y, yd, _ = derivatives(state)
        if y_prev is None:
            y_prev = y - yd * ts                   # at rest: consistent with the initial rate
        v_k = float(controller.voltage(command - y, -(y - y_prev) / ts))
        y_prev = y
        sol = solve_ivp(lambda t, s: derivatives(s, v_k)[0], (t0, t1), state,
                        dense_output=True, **opts)
        if not sol.success:
            raise RuntimeError(f"integration failed: {sol.message}")
        last = k == n_samples - 1
        mask = (t_out >= t0) & ((t_out < t1) | (last & (t_out <= t1)))
        if mask.any():
            x[:, mask] = sol.sol(t_out[mask])
            v_out[mask] = v_k
        state = sol.y[:, -1]
    return x, v_out


# ---------------------------------------------------------------------------------------------
# the reference fin (thesis Ch. 5: Mach 0.5, sea level)
# ---------------------------------------------------------------------------------------------
def static_gains(sys, outputs: list[str]) -> dict:
    """DC gains of a stable closed loop from ``theta_cmd`` to each named output."""
    g = np.asarray(ct.dcgain(sys)).ravel()
    names = list(sys.output_labels)
    return {o: float(g[names.index(o)]) for o in outputs}


# ---------------------------------------------------------------------------------------------
# general (state-space) controllers, sampled by a processor (issue 15)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SensorModel:
    """Measurement chain of the feedback angle: a first-order low-pass filter (the
    potentiometer's or the encoder interface's anti-aliasing filter) of corner
    ``cutoff_hz`` (None: no filter), white measurement noise of RMS ``noise_rms`` (rad, >= 0;
    0: none) added to each sample, drawn from ``numpy.random.default_rng(seed)`` so that the
    same seed gives the same response bit for bit, and a quantisation step ``resolution``
    (rad; None: ideal) applied to the noisy sample when the processor samples. A motor encoder
    of ``c`` counts per motor revolution seen at the fin through the transmission ratio N has
    resolution 2 pi / (c N); a 12-bit potentiometer over 2 pi rad, 2 pi / 4096."""

    cutoff_hz: float | None = None
    resolution: float | None = None
    noise_rms: float = 0.0
    seed: int = 0

    def __post_init__(self):
        if self.cutoff_hz is not None:
            positive("cutoff_hz", self.cutoff_hz)
        if self.resolution is not None:
            positive("resolution", self.resolution)
        if not (math.isfinite(self.noise_rms) and self.noise_rms >= 0):
            raise ValueError(f"noise_rms must be finite and >= 0 rad, got {self.noise_rms!r}")
        if not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")

    def noise(self, samples: int) -> np.ndarray:
        """The measurement noise (rad) of ``samples`` successive samples: zeros without a draw
        if ``noise_rms`` is 0, else ``noise_rms`` times standard normal draws of
        ``default_rng(seed)``.

        >>> SensorModel(noise_rms=1e-4, seed=1).noise(3).shape
        (3,)
        >>> SensorModel().noise(2).tolist()
        [0.0, 0.0]
        """
        if self.noise_rms == 0:
            return np.zeros(samples)
        return self.noise_rms * np.random.default_rng(self.seed).standard_normal(samples)


@dataclass(frozen=True)
class SampledPlant:
    """The actuator + aeroelastic fin + sensor filter, continuous (``sys``: input ``voltage``,
    outputs every plant output and ``measured`` the filtered feedback angle) and its exact
    zero-order-hold discretisation over one ``substep`` (``Ad``, ``Bd``) with ``substeps`` per
    sample period ``sample_time`` (``Ad_sample``, ``Bd_sample`` over a whole sample); ``C``,
    ``D`` the output rows, ``i_meas`` the measured output's index, ``topology``, the motor
    ``resistance`` (ohm, for the current limit's voltage clip I_lim R)."""

    sys: ct.StateSpace
    Ad: np.ndarray
    Bd: np.ndarray
    Ad_sample: np.ndarray
    Bd_sample: np.ndarray
    C: np.ndarray
    D: np.ndarray
    i_meas: int
    sample_time: float
    substeps: int
    topology: str
    resistance: float = 5.78

    @property
    def output_names(self) -> list[str]:
        return list(self.sys.output_labels)


@small_dense
def sampled_plant(model: AeroservoelasticModel, topology: str, sample_time: float = 1e-3,
                  sensor: SensorModel | None = None, substeps: int = 10) -> SampledPlant:
    """The plant seen by a digital controller: voltage in (held over each sample, ZOH),
    the feedback angle of ``topology`` (AEM1: transmission angle, encoder; AEM2: fin-root
    angle, potentiometer) through the sensor filter out. The discretisation is exact for the
    linear plant (matrix exponential of the augmented [A B; 0 0] over sample_time / substeps).
    """
    from scipy.linalg import expm

    _check_topology(topology)
    positive("sample_time", sample_time)
    if int(substeps) < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    sensor = SensorModel() if sensor is None else sensor
    p = _plant(model)
    A, B, C, D = (np.array(x) for x in (p.A, p.B, p.C, p.D))
    names = list(p.output_labels)
    fb = "theta" if topology == "AEM1" else FIN_ROOT
    j = names.index(fb)
    if sensor.cutoff_hz is not None:
        w = 2 * np.pi * sensor.cutoff_hz
        n = A.shape[0]
        A = np.block([[A, np.zeros((n, 1))], [w * C[j:j + 1], -w * np.ones((1, 1))]])
        B = np.vstack([B, w * D[j:j + 1]])
        C = np.hstack([C, np.zeros((C.shape[0], 1))])
        C = np.vstack([C, np.zeros((1, n + 1))])
        C[-1, -1] = 1.0
        D = np.vstack([D, np.zeros((1, 1))])
    else:
        C = np.vstack([C, C[j:j + 1]])
        D = np.vstack([D, D[j:j + 1]])
    names = names + ["measured"]
    sys = ct.ss(A, B, C, D, inputs=["voltage"], outputs=names, name="sampled_plant")
    n = A.shape[0]

    def zoh(h):
        M = np.zeros((n + 1, n + 1))
        M[:n, :n], M[:n, n:] = A * h, B * h
        E = expm(M)
        return E[:n, :n], E[:n, n:]

    Ad, Bd = zoh(sample_time / int(substeps))
    Ads, Bds = zoh(sample_time)
    return SampledPlant(sys=sys, Ad=Ad, Bd=Bd, Ad_sample=Ads, Bd_sample=Bds, C=C, D=D,
                        i_meas=len(names) - 1, sample_time=float(sample_time),
                        substeps=int(substeps), topology=topology,
                        resistance=float(model.actuator.motor.resistance))


def _check_digital(controller, sample_time):
    for name in ("ss", "integrator_states"):
        if not hasattr(controller, name):
            raise ValueError("controller must be a digital controller with attributes ss "
                             "(discrete StateSpace, inputs cmd, fb, v_applied; output voltage) "
                             "and integrator_states (see asekit.servo.controllers.DigitalController)")
    ss = controller.ss
    if not ss.isdtime() or abs(float(ss.dt) - sample_time) > 1e-12 * sample_time:
        raise ValueError(f"controller.ss must be discrete with dt = sample_time = "
                         f"{sample_time:g} s, got dt = {ss.dt}")
    if ss.ninputs != 3 or ss.noutputs != 1:
        raise ValueError("controller.ss must have 3 inputs (cmd, fb, v_applied) and 1 output")
    return ss


def closed_loop_sampled_matrix(plant: SampledPlant, controller, delay_samples: int = 1):
    """State-transition matrix and command column of the linear sampled loop (no
    saturation, no quantisation): state [x_plant, x_controller, held voltages (delay)], one
    step per sample. Its eigenvalues inside the unit circle <=> the sampled loop is stable
    (the ground truth, whatever the open loop's unstable poles). Returns (Phi, Gamma)."""
    ss = _check_digital(controller, plant.sample_time)
    Ap, Bp = plant.Ad_sample, plant.Bd_sample
    cm = plant.C[plant.i_meas:plant.i_meas + 1]
    if np.any(plant.D[plant.i_meas] != 0):
        raise ValueError("the measured output has a direct voltage term; not supported")
    Ac, Bc, Cc, Dc = (np.array(x) for x in (ss.A, ss.B, ss.C, ss.D))
    npl, nc, nd = Ap.shape[0], Ac.shape[0], int(delay_samples)
    if nd < 0:
        raise ValueError(f"delay_samples must be >= 0, got {delay_samples}")
    if nd == 0:
        # u_k = Cc xc + Dc [r, y, u_k] -> u_k (1 - Dc[2]) = Cc xc + Dc0 r + Dc1 y
        g = 1.0 / (1.0 - Dc[0, 2])
        Ku_x, Ku_c, Ku_r = g * Dc[0, 1] * cm, g * Cc, g * Dc[0, 0]
        n = npl + nc
        Phi = np.zeros((n, n))
        Gam = np.zeros((n, 1))
        Phi[:npl, :npl] = Ap + Bp @ Ku_x
        Phi[:npl, npl:] = Bp @ Ku_c
        Gam[:npl, 0] = Bp[:, 0] * Ku_r
        Phi[npl:, :npl] = Bc[:, 1:2] @ cm + Bc[:, 2:3] @ Ku_x
        Phi[npl:, npl:] = Ac + Bc[:, 2:3] @ Ku_c
        Gam[npl:, 0] = Bc[:, 0] + Bc[:, 2] * Ku_r
        return Phi, Gam
    n = npl + nc + nd
    Phi = np.zeros((n, n))
    Gam = np.zeros((n, 1))
    i_d = npl + nc                          # held voltages: d_1 (applied now) .. d_nd
    Phi[:npl, :npl] = Ap
    Phi[:npl, i_d:i_d + 1] = Bp
    # the controller sees the voltage applied now (d_1) as its v_applied input
    Phi[npl:i_d, :npl] = Bc[:, 1:2] @ cm
    Phi[npl:i_d, npl:i_d] = Ac
    Phi[npl:i_d, i_d:i_d + 1] += Bc[:, 2:3]
    Gam[npl:i_d, 0] = Bc[:, 0]
    for q in range(nd - 1):
        Phi[i_d + q, i_d + q + 1] = 1.0
    u_row = np.zeros(n)
    u_row[:npl] = Dc[0, 1] * cm[0]
    u_row[npl:i_d] = Cc[0]
    u_row[i_d] += Dc[0, 2]
    Phi[i_d + nd - 1] = u_row
    Gam[i_d + nd - 1, 0] = Dc[0, 0]
    return Phi, Gam


def is_stable_sampled(plant: SampledPlant, controller, delay_samples: int = 1) -> bool:
    """All eigenvalues of :func:`closed_loop_sampled_matrix` strictly inside the unit
    circle."""
    Phi, _ = closed_loop_sampled_matrix(plant, controller, delay_samples)
    return bool(np.max(np.abs(np.linalg.eigvals(Phi))) < 1.0)


@dataclass(frozen=True)
class SampledSimulation:
    """Histories of a sampled (digital-controller) closed-loop simulation, SI: ``t`` (s, on
    the substep grid), ``outputs`` {name: history} of every plant output (``theta``,
    ``omega``, ``alpha``, ``current``, ``fin_root_pitch``, corners, ``hinge_moment`` without
    the acceleration term, ``measured``), ``voltage`` (applied, V), ``voltage_demand`` (V),
    ``command`` (rad), ``topology``."""

    t: np.ndarray
    outputs: dict
    voltage: np.ndarray
    voltage_demand: np.ndarray
    command: float
    topology: str

    @property
    def fin_root(self) -> np.ndarray:
        return self.outputs[FIN_ROOT]


def simulate_sampled(plant: SampledPlant, controller, command: float,
                     limits: PowerLimits | None = THESIS_LIMITS, t_final: float = 0.1,
                     delay_samples: int = 1, sensor: SensorModel | None = None,
                     angle_limit: float = math.radians(15.0)) -> SampledSimulation:
    """Step response of the plant under a digital controller sampled every
    ``plant.sample_time`` (thesis Table 2: 1 kHz), its voltage applied ``delay_samples``
    samples later (one sample of computation) and held (ZOH).

    Power limits: with ``limits`` of the ``"voltage_clip"`` kind (thesis Eqs. 4.14-4.15, the
    default) the applied voltage is the demand clipped to +-min(V_supply, I_lim R); the plant
    is linear in the voltage, so the response is computed exactly by the discretised plant.
    The controller's ``integrator_states`` are held while the demand is clipped
    (conditional-integration anti-windup) and the controller is told the applied voltage
    (its third input). ``sensor.noise_rms`` adds seeded white noise to each sample of the
    measured angle and ``sensor.resolution`` then quantises it (:class:`SensorModel`).
    """
    ss = _check_digital(controller, plant.sample_time)
    command = finite("command", command)
    if abs(command) > angle_limit + 1e-12:
        raise ValueError(f"command {math.degrees(command):.3g} deg exceeds the angular position "
                         f"limit of {math.degrees(angle_limit):.3g} deg (thesis Table 2)")
    positive("t_final", t_final)
    lim = limits if limits is not None else PowerLimits(supply_voltage=None, current_limit=None)
    if lim.current_limit_model != "voltage_clip":
        raise ValueError("simulate_sampled supports the voltage_clip current-limit model only")
    vmax = math.inf
    if lim.supply_voltage is not None:
        vmax = min(vmax, lim.supply_voltage)
    if lim.current_limit is not None:
        vmax = min(vmax, lim.current_limit * plant.resistance)        # Eqs. (4.14)-(4.15)
    res = None if sensor is None else sensor.resolution
    Ac, Bc, Cc, Dc = (np.array(x) for x in (ss.A, ss.B, ss.C, ss.D))
    if Dc[0, 2] != 0 and delay_samples == 0:
        raise ValueError("a controller with a direct v_applied term needs delay_samples >= 1")
    integ = np.array(sorted(controller.integrator_states), dtype=int)
    n_s = int(math.ceil(t_final / plant.sample_time - 1e-9))
    m = plant.substeps
    x = np.zeros(plant.Ad.shape[0])
    xc = np.zeros(Ac.shape[0])
    held = [0.0] * max(int(delay_samples), 0)
    # the m substeps of a sample at once: x_j = Ad^j x + (sum_{i<j} Ad^i Bd) v, j = 0..m
    n = plant.Ad.shape[0]
    Pw = np.empty((m + 1, n, n))
    Gw = np.empty((m + 1, n))
    Pw[0], Gw[0] = np.eye(n), 0.0
    for j in range(1, m + 1):
        Pw[j] = plant.Ad @ Pw[j - 1]
        Gw[j] = plant.Ad @ Gw[j - 1] + plant.Bd[:, 0]
    P_sub, G_sub = Pw[:m].reshape(m * n, n), Gw[:m]
    P_m, G_m = Pw[m], Gw[m]
    X = np.empty((n_s * m, n))
    vs = np.empty(n_s * m)
    vds = np.empty(n_s * m)
    cm = plant.C[plant.i_meas]
    v_app = 0.0
    noise = np.zeros(n_s) if sensor is None else sensor.noise(n_s)
    for k in range(n_s):
        y = float(cm @ x) + float(noise[k])
        if res is not None:
            y = res * round(y / res)
        if delay_samples == 0:
            u = float(Cc[0] @ xc + Dc[0, 0] * command + Dc[0, 1] * y)
            v_now = float(np.clip(u, -vmax, vmax))
        else:
            v_now = held[0]
            u = float(Cc[0] @ xc + Dc[0, 0] * command + Dc[0, 1] * y + Dc[0, 2] * v_now)
        sat = abs(u) > vmax
        xc_new = Ac @ xc + Bc[:, 0] * command + Bc[:, 1] * y + Bc[:, 2] * v_now
        if sat and integ.size:
            xc_new[integ] = xc[integ]
        xc = xc_new
        if delay_samples:
            held = held[1:] + [float(np.clip(u, -vmax, vmax))]
        v_app = v_now
        X[k * m:(k + 1) * m] = (P_sub @ x).reshape(m, n) + G_sub * v_app
        vs[k * m:(k + 1) * m] = v_app
        vds[k * m:(k + 1) * m] = u
        x = P_m @ x + G_m * v_app
    t = np.arange(n_s * m) * plant.sample_time / m
    Y = plant.C @ X.T + plant.D[:, :1] * vs[None, :]
    outs = {nm: Y[i] for i, nm in enumerate(plant.output_names)}
    return SampledSimulation(t=t, outputs=outs, voltage=vs, voltage_demand=vds,
                             command=float(command), topology=plant.topology)
