"""Robust fin-position control (issue 26): a two-degree-of-freedom H-infinity design, its order
reduction and discretisation, and a structured-singular-value certificate of robust stability.

Design (two-degree-of-freedom H-infinity model matching; Limebeer, Kasenally & Perkins, "On
the design of robust two degree of freedom controllers", Automatica 29(1), 1993; Skogestad &
Postlethwaite, "Multivariable feedback control", 2nd ed., 2005, Sec. 9.3.6). The controller
sees the command r and the measured angle y and drives the voltage u; the generalised plant
(:func:`generalized_plant`) has exogenous inputs [r, d, n] (command, input voltage disturbance
weighted by ``disturbance``, measurement noise weighted by ``noise``) and errors

    z1 = W_e (T_ref r - y),   z2 = W_u u,   z3 = W_t y (robustness roll-off, optional)

with T_ref = w_r^2 / (s^2 + 2 w_r s + w_r^2) (critically damped: no overshoot), W_e = (s / M_s
+ w_b) / (s + eps w_b) (a near-integrator: steady error <= eps of the error scale), W_u a
constant 1/V, W_t = (s / w_t + 1/2) / (s / (20 w_t) + 1) (high-frequency bound on the
complementary sensitivity, above the elastic modes). The plant carries the ZOH half sample and
the computational delay as a second-order Pade approximant (continuous time only for the
synthesis; the checks use the exact sampled loop). :func:`hinf_2dof` calls python-control's
``hinfsyn`` (SLICOT SB10AD through slycot) for the gamma-optimal controller.

The controller is reduced by balanced truncation of its stable part (the unstable part, if any,
kept; Hsu & Hou 1991, python-control ``balred``), discretised by Tustin's rule at the sampling
rate and put in a form whose first state is its near-integrator (ordered real Schur form and a
Sylvester decoupling), held while the voltage demand is clipped (conditional-integration
anti-windup, as the other designs of :mod:`asekit.servo.controllers`).

Robust stability (:func:`loop_matrix`, :func:`robust_stability`): uncertain parameters that
enter the plant's state matrix as A + delta_i dA_i (|delta_i| <= 1) are pulled out as real scalar
blocks through the rank factorisation dA_i = U_i V_i^T (a repeated real scalar of size
rank(dA_i)); an uncertainty given only as a set of plants (flight conditions) enters as a complex
output-multiplicative block y = (1 + w_f(j w) Delta) y_0 with |w_f(j w)| covering the relative
change of the frequency response (Skogestad & Postlethwaite, Sec. 7.4). The loop matrix M(j w)
from the blocks' outputs to their inputs, with the continuous controller and the exact delay
exp(-j w tau), is bounded by :func:`asekit.ase.mu.mu_frequency`: robust stability for the stated
uncertainty if the nominal loop is stable and sup_w mu < 1; the loop tolerates 1 / sup mu times
the stated uncertainty (Packard & Doyle 1993, Theorem 4.3 / small-mu theorem).

Real parameters that enter A polynomially (flight condition: Mach, altitude) are pulled out as
a linear fractional transformation (:func:`fit_polynomial` on sampled plants, then
:func:`polynomial_lft`; Zhou, Doyle & Glover, "Robust and optimal control", 1996, Sec. 10.2;
Lind & Brenner, "Robust aeroservoelastic stability analysis", 1999, Ch. 5): each monomial's
coefficient matrix is rank-factorised and a degree-two monomial becomes a chain of two
scalars, so every parameter is one repeated real scalar block (``Uncertainty.lft``). A
parameter's block size is the rank of the coefficient matrices it multiplies;
:func:`lowrank_polynomial_lft` shares one column space among the terms with the same first
factor and truncates every SVD at a stated relative tolerance, with a bound on the dropped part
(which then belongs in the complex fit-error cover), and
:func:`asekit.ase.mu.full_dg_upper_bound` bounds mu with full D and G on those smaller blocks.

SI units (rad, V, s, rad/s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from asekit.ase.mu import Block, mu_frequency
from asekit.servo.controllers import INPUTS, DigitalController
from asekit.util.extras import require
from asekit.util.validate import positive

#: 2 % settling time of a critically damped second-order model, times its natural frequency
#: (solve (1 + w t) exp(-w t) = 0.02: w t = 5.834).
CRITICAL_SETTLING = 5.834


@dataclass(frozen=True)
class HinfWeights:
    """Weights of the two-degree-of-freedom design (module docstring), SI.

    reference_rad_s : w_r of the reference model T_ref. error_bandwidth : w_b of W_e (rad/s).
    peak : M_s, the high-frequency bound of the model-matching error. integral : eps of W_e.
    voltage : W_u (1/V). rolloff : w_t of W_t (rad/s; None: no W_t). rolloff_cap : W_t's
    pole at rolloff_cap x w_t (its high-frequency gain rolloff_cap / 2). disturbance : input
    disturbance scale (V). noise : measurement noise scale (rad).
    """

    reference_rad_s: float
    error_bandwidth: float
    peak: float = 2.0
    integral: float = 1e-3
    voltage: float = 1e-3
    rolloff: float | None = 250.0
    rolloff_cap: float = 20.0
    disturbance: float = 1.0
    noise: float = 1e-3


def weights_from_requirements(settling: float = 0.05, steady_error: float = 0.02,
                              model_fraction: float = 0.47, voltage_limit: float = 24.0,
                              voltage_weight: float = 1e-3,
                              rolloff: float | None = 250.0) -> HinfWeights:
    """Weights from thesis Table 2: the reference model settles (2 %) in ``model_fraction`` x
    ``settling`` (the rest is left to the power-limited large step): w_r = 5.834 / (fraction
    t_s); the error weight's bandwidth w_b = w_r / 2; its integral eps = steady_error / 20 (the
    near-integrator's DC gain 1/eps keeps the steady error well inside the requirement);
    W_u = ``voltage_weight`` (1/V; 1 mrad of model-matching error weighs as 1 V), capped at
    1 deg / ``voltage_limit`` from below (a 1 deg step may use the whole supply). Tuned on the
    fin (design chapter, 45 conditions): W_u = 1 deg / 24 V = 7.3e-4 passes 35, 1e-3 passes
    40. ``rolloff``: w_t (rad/s) of the complementary-sensitivity bound (tuned on the fin:
    500 rad/s lets more +10 % elastic-frequency cases go unstable).

    Examples
    --------
    >>> w = weights_from_requirements()
    >>> round(w.reference_rad_s), round(w.error_bandwidth), w.integral
    (248, 124, 0.001)
    """
    positive("settling", settling)
    positive("steady_error", steady_error)
    positive("voltage_limit", voltage_limit)
    positive("voltage_weight", voltage_weight)
    if not 0 < model_fraction < 1:
        raise ValueError(f"model_fraction must be in (0, 1), got {model_fraction}")
    wr = CRITICAL_SETTLING / (model_fraction * settling)
    return HinfWeights(reference_rad_s=wr, error_bandwidth=wr / 2, integral=steady_error / 20,
                       voltage=max(voltage_weight, math.radians(1.0) / voltage_limit),
                       rolloff=rolloff)


def _gain(k, i, o, name):
    return ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[k]], inputs=[i],
                 outputs=[o], name=name)


def generalized_plant(plant: ct.StateSpace, weights: HinfWeights, delay: float = 1.5e-3,
                      pade_order: int = 2) -> ct.StateSpace:
    """The generalised plant of the module docstring: inputs [r, d, n, u], outputs
    [z1, z2, (z3), r, y_meas]. ``plant``: SISO voltage -> measured angle (rad/V), continuous;
    ``delay``: the input delay (s; ZOH half sample + computation) as a Pade approximant."""
    if plant.ninputs != 1 or plant.noutputs != 1 or plant.isdtime(strict=True):
        raise ValueError("plant must be a continuous SISO StateSpace (voltage -> angle)")
    w = weights
    P = ct.ss(plant)
    if delay > 0:
        num, den = ct.pade(delay, int(pade_order))
        P = ct.ss(ct.series(ct.tf2ss(num, den), P))
    P = ct.ss(P.A, P.B, P.C, P.D, inputs=["up"], outputs=["y"], name="P")
    wr = w.reference_rad_s
    parts = [P,
             ct.ss(ct.tf([1 / w.peak, w.error_bandwidth], [1, w.error_bandwidth * w.integral]),
                   inputs=["e"], outputs=["z1"], name="We"),
             _gain(w.voltage, "u", "z2", "Wu"),
             ct.ss(ct.tf([wr * wr], [1, 2 * wr, wr * wr]), inputs=["r"], outputs=["ym"],
                   name="Tref"),
             _gain(w.disturbance, "d", "dd", "Wd"), _gain(w.noise, "n", "nn", "Wn"),
             _gain(1.0, "r", "rm", "R"),
             ct.summing_junction(inputs=["u", "dd"], output="up", name="s1"),
             ct.summing_junction(inputs=["ym", "-y"], output="e", name="s2"),
             ct.summing_junction(inputs=["y", "nn"], output="ymeas", name="s3")]
    outs = ["z1", "z2"]
    if w.rolloff is not None:
        wt = w.rolloff
        parts.append(ct.ss(ct.tf([1 / wt, 0.5], [1 / (w.rolloff_cap * wt), 1]), inputs=["y"],
                           outputs=["z3"], name="Wt"))
        outs.append("z3")
    G = ct.interconnect(parts, inplist=["r", "d", "n", "u"], outlist=outs + ["rm", "ymeas"])
    return ct.ss(G.A, G.B, G.C, G.D)


@dataclass(frozen=True)
class HinfDesign:
    """A synthesised controller: ``continuous`` (inputs [r, y], output u, full order),
    ``gamma`` (the closed-loop H-infinity norm reached), ``weights``."""

    continuous: ct.StateSpace
    gamma: float
    weights: HinfWeights


def hinf_2dof(plant: ct.StateSpace, weights: HinfWeights, delay: float = 1.5e-3,
              design_order: int | None = 14) -> HinfDesign:
    """Two-degree-of-freedom H-infinity controller for ``plant`` (module docstring): the plant
    reduced by balanced truncation to ``design_order`` states (None: as is), then
    ``hinfsyn`` on :func:`generalized_plant`. Needs slycot (the ``robust`` extra).

    Examples
    --------
    >>> import control as ct
    >>> P = ct.ss(ct.tf([1.0], [1.0, 10.0, 0.0]))          # a motor: 1 / (s (s + 10))
    >>> d = hinf_2dof(P, weights_from_requirements(rolloff=None), delay=0.0, design_order=None)
    >>> d.continuous.ninputs, d.continuous.noutputs, bool(d.gamma < 5)
    (2, 1, True)
    """
    require("slycot", "H-infinity synthesis (asekit.ase.robust)")
    P = ct.ss(plant)
    if design_order is not None and P.nstates > design_order:
        P = ct.balred(P, int(design_order))
    G = generalized_plant(P, weights, delay)
    K, _, gamma, _ = ct.hinfsyn(G, 2, 1)
    return HinfDesign(continuous=ct.ss(K.A, K.B, K.C, K.D, inputs=["r", "y"],
                                       outputs=["u"]),
                      gamma=float(gamma), weights=weights)


def reduce_controller(K: ct.StateSpace, order: int) -> ct.StateSpace:
    """Balanced truncation of the stable part of ``K`` to ``order`` states (the unstable part
    kept; python-control ``balred``, SLICOT AB09MD). Returns K itself if it is not larger.

    Examples
    --------
    >>> import control as ct
    >>> K = ct.ss(ct.tf([1.0], [1.0, 1.0]) + ct.tf([1e-6], [1.0, 1e3]))
    >>> reduce_controller(K, 1).nstates
    1
    """
    require("slycot", "controller order reduction (asekit.ase.robust)")
    return K if K.nstates <= order else ct.balred(K, int(order))


def _split_integrator(A, B, C, tol):
    """Similarity transform putting the one eigenvalue of A within ``tol`` of 1 into state 0,
    decoupled from the rest (ordered real Schur form, then a Sylvester equation). Returns
    (A, B, C, found)."""
    from scipy.linalg import schur, solve_sylvester

    T, Z, sdim = schur(A, output="real",
                       sort=lambda re, im: abs(re - 1.0) < tol and im == 0.0)
    if sdim != 1:
        return A, B, C, False
    X = solve_sylvester(T[:1, :1], -T[1:, 1:], -T[:1, 1:])
    S = np.eye(len(T))
    S[:1, 1:] = X
    Si = np.linalg.inv(S)
    return Si @ T @ S, Si @ Z.T @ B, C @ Z @ S, True


def discretise(K: ct.StateSpace, sample_time: float, name: str = "H-infinity 2-DOF",
               integrator_tol: float = 1e-2) -> DigitalController:
    """Tustin discretisation of a continuous controller with inputs [r, y] and output u as a
    :class:`asekit.servo.controllers.DigitalController` (inputs cmd, fb, v_applied): its
    near-integrator (the discrete eigenvalue within ``integrator_tol`` of 1) becomes state 0,
    held while the demand is clipped.

    Examples
    --------
    >>> import control as ct
    >>> K = ct.ss(ct.tf([[[1.0], [-1.0]]], [[[1.0, 1e-3], [1.0, 1e-3]]]))   # (r - y) / s
    >>> c = discretise(K, 1e-3)
    >>> c.integrator_states, c.ss.ninputs, float(c.ss.dt)
    ((0,), 3, 0.001)
    """
    ts = positive("sample_time", sample_time)
    if K.ninputs != 2 or K.noutputs != 1:
        raise ValueError(f"K must have inputs [r, y] and one output, got {K.ninputs} inputs, "
                         f"{K.noutputs} outputs")
    Kd = ct.sample_system(ct.ss(K), ts, method="tustin")
    A, B, C, D = (np.array(x, float) for x in (Kd.A, Kd.B, Kd.C, Kd.D))
    A, B, C, found = _split_integrator(A, B, C, integrator_tol)
    B3 = np.hstack([B, np.zeros((A.shape[0], 1))])
    D3 = np.hstack([D, [[0.0]]])
    ss = ct.ss(A, B3, C, D3, ts, inputs=list(INPUTS), outputs=["voltage"], name=name)
    return DigitalController(ss=ss, integrator_states=(0,) if found else (), name=name,
                             continuous=K, meta={"order": int(A.shape[0])})


# ---------------------------------------------------------------------------------------------
# structured uncertainty and the mu certificate
# ---------------------------------------------------------------------------------------------
def rank_factors(dA: np.ndarray, rtol: float = 1e-8):
    """dA = U V^T with U, V (n, r), r the numerical rank (singular values above rtol x the
    largest), split sqrt(sigma) to each side.

    Examples
    --------
    >>> import numpy as np
    >>> U, V = rank_factors(np.outer([1.0, 2.0], [3.0, 0.0]))
    >>> U.shape, bool(np.allclose(U @ V.T, [[3.0, 0.0], [6.0, 0.0]]))
    ((2, 1), True)
    """
    u, s, vh = np.linalg.svd(np.asarray(dA, float))
    if s[0] == 0:
        raise ValueError("dA is zero: the parameter does not enter the plant")
    r = int(np.sum(s > rtol * s[0]))
    sq = np.sqrt(s[:r])
    return u[:, :r] * sq, vh[:r].T * sq


@dataclass(frozen=True)
class Uncertainty:
    """The stated uncertainty of a plant (A, B, C) with a scalar input and measurement.

    ``parameters``: ((name, dA), ...), each a real parameter delta in [-1, 1] entering as
    A + delta dA (dA the full range). ``cover_hz``, ``cover``: the frequency grid (Hz) and the
    magnitude |w_f| of a complex output-multiplicative block (None: none), named
    ``cover_name``."""

    parameters: tuple = ()
    cover_hz: np.ndarray | None = None
    cover: np.ndarray | None = None
    cover_name: str = "flight condition"
    #: real parameters entering A as a :class:`ParametricLFT` (about the same A; None: none);
    #: its blocks follow those of ``parameters``, before the cover's
    lft: ParametricLFT | None = None


def loop_matrix(A, B, C, K_y, uncertainty: Uncertainty, f_hz, delay: float = 1.5e-3):
    """M(j w) seen by the uncertainty blocks (module docstring) at each frequency of ``f_hz``,
    and the block structure. ``K_y``: a function w (rad/s) -> the controller's complex gain from
    the measured angle to the voltage (sign included: u = K_y y); ``delay``: exp(-j w delay) on
    the voltage. Returns (Ms (n_f, m, m), blocks)."""
    A, B, C = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C))
    n = A.shape[0]
    Us, Vs, blocks = [], [], []
    for _, dA in uncertainty.parameters:
        U, V = rank_factors(dA)
        Us.append(U)
        Vs.append(V)
        blocks.append(Block(U.shape[1], "real"))
    U = np.hstack(Us) if Us else np.zeros((n, 0))
    V = np.hstack(Vs) if Vs else np.zeros((n, 0))
    Dzz = np.zeros((U.shape[1], U.shape[1]))
    lft = uncertainty.lft
    if lft is not None:
        if lft.A0.shape != A.shape:
            raise ValueError(f"uncertainty.lft.A0 is {lft.A0.shape}, the plant's A {A.shape}")
        m0 = U.shape[1]
        U, V = np.hstack([U, lft.Bw]), np.hstack([V, lft.Cz.T])
        Dzz = np.zeros((U.shape[1], U.shape[1]))
        Dzz[m0:, m0:] = lft.Dzw
        blocks.extend(lft.blocks)
    cover = uncertainty.cover is not None
    if cover:
        blocks.append(Block(1, "complex"))
        wf = np.interp(f_hz, uncertainty.cover_hz, uncertainty.cover)
    out = []
    for i, f in enumerate(np.atleast_1d(f_hz)):
        s = 2j * np.pi * f
        L = complex(K_y(2 * np.pi * f)) * np.exp(-s * delay)
        G = np.linalg.solve(s * np.eye(n) - A, np.hstack([B, U]))     # (sI - A)^-1 [B U]
        GB, GU = G[:, :1], G[:, 1:]
        H = np.linalg.inv(np.eye(n) - L * GB @ C)
        x_w = H @ GU                                                   # x per parameter input
        x_f = H @ GB * L                                               # x per cover input
        rows = [np.hstack([V.T @ x_w + Dzz, V.T @ x_f] if cover else [V.T @ x_w + Dzz])]
        if cover:
            rows.append(wf[i] * np.hstack([C @ x_w, C @ x_f]))
        out.append(np.vstack(rows))
    return np.array(out), tuple(blocks)


def digital_gain(controller: DigitalController):
    """The function w (rad/s) -> the sampled controller's gain from the measured angle to the
    voltage, K_fb(exp(j w T)), times the zero-order hold's magnitude sin(w T/2) / (w T/2)
    (the hold's half-sample lag belongs to the delay of :func:`loop_matrix`, 1.5 T with one
    sample of computation): the continuous-time equivalent of the sampled loop below the
    Nyquist frequency, aliasing neglected (Franklin, Powell & Workman, Sec. 6.2)."""
    ss = controller.ss
    A, B, C, D = (np.array(x, float) for x in (ss.A, ss.B, ss.C, ss.D))
    T = controller.sample_time

    def K_y(w):
        z = np.exp(1j * w * T)
        k = (C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B[:, 1]) + D[0, 1])[0]
        x = w * T / 2
        return k * (1.0 if x == 0 else math.sin(x) / x)
    return K_y


def robust_stability(A, B, C, K_y, uncertainty: Uncertainty, f_hz, delay: float = 1.5e-3):
    """Upper and lower bounds of mu over ``f_hz`` for :func:`loop_matrix` (the nominal loop's
    stability is the caller's to check; real parameters get the mixed D-G bound of
    :func:`asekit.ase.mu.mixed_upper_bound`). Returns ``{"f_hz", "upper", "lower", "mu_peak",
    "f_peak_hz", "margin", "blocks", "M"}`` (M the loop matrices), margin = 1 / mu_peak: the loop is stable for that multiple of the
    stated uncertainty.

    Examples
    --------
    >>> import numpy as np
    >>> A, B, C = np.array([[-1.0]]), np.array([[1.0]]), np.array([[1.0]])
    >>> unc = Uncertainty(parameters=(("pole", np.array([[0.5]])),))
    >>> r = robust_stability(A, B, C, lambda w: -1.0, unc, np.linspace(0, 2, 21), delay=0.0)
    >>> round(r["mu_peak"], 6)         # x' = -(2 + 0.5 delta) x: stable up to |delta| = 4
    0.25
    """
    f = np.atleast_1d(np.asarray(f_hz, float))
    Ms, blocks = loop_matrix(A, B, C, K_y, uncertainty, f, delay)
    r = mu_frequency(Ms, blocks)
    peak = r["peak_upper"]
    return {"f_hz": f, "upper": r["upper"], "lower": r["lower"], "mu_peak": peak,
            "mu_peak_lower": float(np.max(r["lower"])),
            "f_peak_hz": float(f[r["i_peak"]]),
            "margin": math.inf if peak == 0 else 1.0 / peak, "blocks": blocks, "M": Ms}


def mu_subsets(Ms, blocks, f_hz, subsets: dict) -> dict:
    """Which uncertainty drives mu: the bounds of mu over frequency with only some blocks kept
    (the others set to zero, i.e. the rows and columns of M that belong to them dropped: the
    loop seen by the remaining blocks). ``Ms`` (n_f, n, n) and ``blocks`` as returned by
    :func:`loop_matrix`; ``subsets``: {name: indices of the blocks kept}. Returns {name:
    {"mu_peak", "mu_peak_lower", "f_peak_hz", "upper"}}; 1 / mu_peak is the multiple of that
    part of the uncertainty the loop tolerates alone.

    Examples
    --------
    >>> import numpy as np
    >>> from asekit.ase.mu import Block
    >>> Ms = np.array([[[0.5, 3.0], [0.0, 2.0j]]])          # real block 0.5, complex 2j
    >>> r = mu_subsets(Ms, (Block(1, "real"), Block(1)), [10.0], {"real": [0], "cx": [1]})
    >>> round(r["real"]["mu_peak"], 6), round(r["cx"]["mu_peak"], 6)
    (0.5, 2.0)
    """
    Ms = np.asarray(Ms, complex)
    f = np.atleast_1d(np.asarray(f_hz, float))
    starts = np.cumsum([0] + [b.size for b in blocks])
    out = {}
    for name, keep in subsets.items():
        keep = sorted(int(k) for k in keep)
        if not keep or keep[0] < 0 or keep[-1] >= len(blocks):
            raise ValueError(f"subsets[{name!r}] must list block indices in 0..{len(blocks) - 1}")
        idx = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in keep])
        r = mu_frequency(Ms[:, idx][:, :, idx], [blocks[k] for k in keep])
        out[name] = {"mu_peak": r["peak_upper"], "mu_peak_lower": float(np.max(r["lower"])),
                     "f_peak_hz": float(f[r["i_peak"]]), "upper": r["upper"]}
    return out


# ---------------------------------------------------------------------------------------------
# real-parameter LFT of a parameter-dependent state matrix (issue 26)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ParametricLFT:
    """A(delta) = A0 + Bw Delta (I - Dzw Delta)^-1 Cz, Delta = diag(delta_i I_{r_i}) (each real
    parameter delta_i in [-1, 1] a repeated real scalar of size ``sizes[i]``, its channels
    contiguous in the order of ``names``): the upper linear fractional transformation of a
    polynomial matrix (Zhou, Doyle & Glover, "Robust and optimal control", 1996, Sec. 10.2;
    Lind & Brenner, "Robust aeroservoelastic stability analysis", 1999, Ch. 5 for the flight
    parameters). Built by :func:`polynomial_lft`."""

    A0: np.ndarray
    Bw: np.ndarray
    Cz: np.ndarray
    Dzw: np.ndarray
    names: tuple
    sizes: tuple
    #: an upper bound of the 2-norm of A_poly(delta) - A(delta) over the unit box (the
    #: singular values dropped by :func:`lowrank_polynomial_lft`; 0 for :func:`polynomial_lft`
    #: at its numerical-rank tolerance)
    truncation: float = 0.0

    @property
    def blocks(self) -> tuple:
        """One real repeated-scalar :class:`asekit.ase.mu.Block` per parameter."""
        return tuple(Block(int(s), "real") for s in self.sizes)


def _monomial(powers, k):
    p = tuple(int(x) for x in powers)
    if len(p) != k or min(p) < 0 or not 1 <= sum(p) <= 2:
        raise ValueError(f"monomial powers must be {k} non-negative integers of total degree 1 "
                         f"or 2, got {powers!r}")
    return [i for i in range(k) for _ in range(p[i])]        # parameter index per factor


def polynomial_lft(A0, terms, names, rtol: float = 1e-8) -> ParametricLFT:
    """The LFT of A(delta) = A0 + sum_k m_k(delta) dA_k, m_k a monomial of degree 1 or 2 in the
    real parameters (Zhou, Doyle & Glover 1996, Sec. 10.2): each dA_k = U_k V_k^T
    (:func:`rank_factors`, rank r_k) is pulled out as z = V_k^T x, w = delta_i z,
    x' += U_k w for delta_i; for delta_i delta_j a chain z1 = V_k^T x, w1 = delta_j z1,
    z2 = w1 (the Dzw entry), w2 = delta_i z2, x' += U_k w2. ``terms``: ((powers, dA), ...)
    with powers one integer per parameter; ``names``: the parameters.

    Examples
    --------
    >>> import numpy as np
    >>> A0 = np.array([[-1.0, 0.0], [0.0, -2.0]])
    >>> lft = polynomial_lft(A0, [((1, 0), np.diag([1.0, 0.0])),
    ...                           ((1, 1), np.array([[0.0, 1.0], [0.0, 0.0]]))], ("a", "b"))
    >>> lft.sizes
    (2, 1)
    >>> A = lft_state_matrix(lft, [0.5, -0.4])
    >>> bool(np.allclose(A, [[-0.5, -0.2], [0.0, -2.0]]))
    True
    """
    A0 = np.atleast_2d(np.asarray(A0, float))
    n, k = A0.shape[0], len(names)
    chans = []                     # (param, column of U or None, row of V or None, feeds chan)
    for powers, dA in terms:
        idx = _monomial(powers, k)
        U, V = rank_factors(np.asarray(dA, float), rtol)
        for c in range(U.shape[1]):
            prev = None
            for j, p in enumerate(reversed(idx)):       # the last factor acts on V^T x first
                last = j == len(idx) - 1
                chans.append((p, U[:, c] if last else None, V[:, c] if prev is None else None,
                              prev))
                prev = len(chans) - 1
    order = sorted(range(len(chans)), key=lambda i: chans[i][0])      # stable: by parameter
    pos = {old: new for new, old in enumerate(order)}
    m = len(chans)
    Bw, Cz, Dzw = np.zeros((n, m)), np.zeros((m, n)), np.zeros((m, m))
    for old, (p, u, v, prev) in enumerate(chans):
        i = pos[old]
        if u is not None:
            Bw[:, i] = u
        if v is not None:
            Cz[i] = v
        if prev is not None:
            Dzw[i, pos[prev]] = 1.0
    sizes = tuple(sum(1 for c in chans if c[0] == p) for p in range(k))
    if min(sizes) == 0:
        raise ValueError("every parameter must appear in a term with a non-zero dA")
    return ParametricLFT(A0=A0, Bw=Bw, Cz=Cz, Dzw=Dzw, names=tuple(names), sizes=sizes)


def lft_state_matrix(lft: ParametricLFT, deltas) -> np.ndarray:
    """A(delta) = A0 + Bw Delta (I - Dzw Delta)^-1 Cz for one value of the real parameters
    (``deltas``, one per parameter; Zhou, Doyle & Glover 1996, Eq. 10.3)."""
    d = np.asarray(deltas, float)
    if d.shape != (len(lft.sizes),):
        raise ValueError(f"deltas must have one value per parameter {lft.names}, got {d.shape}")
    D = np.diag(np.repeat(d, lft.sizes))
    return lft.A0 + lft.Bw @ D @ np.linalg.solve(np.eye(len(D)) - lft.Dzw @ D, lft.Cz)


def fit_polynomial(deltas, As, monomials):
    """Least-squares fit of sampled state matrices by a polynomial in the normalised
    parameters: As[s] ~ A0 + sum_k m_k(deltas[s]) dA_k, entry by entry (ordinary least
    squares on the monomial basis). ``deltas`` (n_s, k), ``As`` (n_s, n, n), ``monomials``:
    powers per parameter (degree 1 or 2). Returns (A0, ((powers, dA_k), ...), residual
    (n_s, n, n) = As - fit).

    Examples
    --------
    >>> import numpy as np
    >>> d = np.array([[-1.0], [0.0], [1.0]])
    >>> As = np.array([[[1.0 + 2 * x + 3 * x * x]] for x in d[:, 0]])
    >>> A0, terms, res = fit_polynomial(d, As, [(1,), (2,)])
    >>> round(float(A0[0, 0]), 9), [round(float(t[1][0, 0]), 9) for t in terms]
    (1.0, [2.0, 3.0])
    """
    d = np.atleast_2d(np.asarray(deltas, float))
    As = np.asarray(As, float)
    if As.ndim != 3 or len(As) != len(d):
        raise ValueError("As must be (n_samples, n, n) with one sample per row of deltas")
    mons = [tuple(int(x) for x in p) for p in monomials]
    for p in mons:
        _monomial(p, d.shape[1])
    Phi = np.column_stack([np.ones(len(d))] + [np.prod(d ** np.array(p), axis=1) for p in mons])
    if np.linalg.matrix_rank(Phi) < Phi.shape[1]:
        raise ValueError("the samples do not determine every monomial (rank-deficient basis)")
    coef = np.linalg.lstsq(Phi, As.reshape(len(d), -1), rcond=None)[0]
    coef = coef.reshape(-1, *As.shape[1:])
    return coef[0], tuple(zip(mons, coef[1:])), As - (Phi @ coef.reshape(len(coef), -1)
                                                      ).reshape(As.shape)


def _truncated_svd(X, rtol):
    """X ~ U S V^T kept to the singular values above rtol x the largest; returns (U, S V^T,
    the first dropped singular value (0 if none))."""
    u, s, vh = np.linalg.svd(np.asarray(X, float), full_matrices=False)
    if s[0] == 0:
        raise ValueError("a coefficient matrix is zero: the parameter does not enter the plant")
    r = int(np.sum(s > rtol * s[0]))
    return u[:, :r], s[:r, None] * vh[:r], float(s[r]) if r < len(s) else 0.0


def lowrank_polynomial_lft(A0, terms, names, rtol: float = 1e-3) -> ParametricLFT:
    """A low-order LFT of A(delta) = A0 + sum_k m_k(delta) dA_k (monomials of degree 1 or 2, as
    :func:`polynomial_lft`): a real parameter's repeated-block size is the rank of the
    coefficient matrices it multiplies (Zhou, Doyle & Glover 1996, Sec. 10.2; Morton & McAfoos,
    "A mu-test for robustness analysis of a real-parameter variation problem", ACC 1985;
    Belcastro's LFT order reduction), so the matrices are factored by a truncated SVD and the
    terms sharing their first parameter share one column space:

        A(delta) ~ A0 + sum_i delta_i U_i [ sum_{k: m_k = delta_i} W_k
                                            + sum_{k: m_k = delta_i delta_j, j >= i} delta_j P_k Q_k^T ],

    with H_i = [dA_k for the terms whose lowest-index factor is i] ~ U_i U_i^T H_i (U_i its
    left singular vectors above ``rtol`` x its largest singular value), W_k = U_i^T dA_k, and
    for a degree-two term W_k ~ P_k Q_k^T (truncated likewise). Channels: an outer delta_i
    channel (size rank U_i: z = sum W_k x + sum P_k w_inner, x' += U_i w) and one inner delta_j
    channel per degree-two term (z = Q_k^T x); the inner channels feed only outer ones, so
    I - Dzw Delta is always invertible. Block size of delta_i: rank(U_i) + the ranks of the
    degree-two terms whose second factor is delta_i.

    The dropped part is bounded over the unit box |delta_i| <= 1 by ``truncation`` =
    sum_i sigma_drop(H_i) sqrt(n_i) + sum_k sigma_drop(W_k) (n_i the number of terms in H_i;
    ||(I - U U^T) H_i [m_1 I; ...]|| <= sigma_drop(H_i) ||m||_2, |m_k| <= 1): it belongs in
    the complex cover of the fit error (measured against this LFT, never the exact
    polynomial), so the mu bound stays a bound. ``rtol``: the relative tolerance of every
    truncation (1e-8: the numerical rank, no truncation to speak of).

    Examples
    --------
    >>> import numpy as np
    >>> u, v = np.array([[1.0], [2.0]]), np.array([[1.0], [-1.0]])
    >>> terms = [((1, 0), u @ v.T), ((0, 1), 3 * u @ v.T), ((1, 1), u @ v.T)]
    >>> lft = lowrank_polynomial_lft(np.eye(2), terms, ("a", "b"))
    >>> lft.sizes, polynomial_lft(np.eye(2), terms, ("a", "b")).sizes
    ((1, 2), (2, 2))
    >>> A = np.eye(2) + (0.5 + 3 * -0.2 + 0.5 * -0.2) * (u @ v.T)
    >>> bool(np.allclose(lft_state_matrix(lft, [0.5, -0.2]), A)), bool(lft.truncation < 1e-12)
    (True, True)
    """
    A0 = np.atleast_2d(np.asarray(A0, float))
    n, k = A0.shape[0], len(names)
    if not 0 < rtol < 1:
        raise ValueError(f"rtol must be in (0, 1), got {rtol}")
    groups = {}                                    # outer parameter -> [(inner or None, dA)]
    for powers, dA in terms:
        idx = sorted(_monomial(powers, k))
        groups.setdefault(idx[0], []).append((idx[1] if len(idx) == 2 else None,
                                              np.asarray(dA, float)))
    outer, inner, bound = {}, [], 0.0              # inner: (param j, outer i, P, Q)
    for i, items in groups.items():
        U, _, drop = _truncated_svd(np.hstack([dA for _, dA in items]), rtol)
        bound += drop * math.sqrt(len(items))
        lin = np.zeros((U.shape[1], n))
        for j, dA in items:
            W = U.T @ dA
            if j is None:
                lin += W
            elif np.any(W):
                P, Qt, drop = _truncated_svd(W, rtol)
                bound += drop
                inner.append((j, i, P, Qt))
        outer[i] = (U, lin)
    # channel order: by parameter; within one, the outer channel first, then the inner ones
    chans = []                                     # (param, kind, ref)
    for p in range(k):
        if p in outer:
            chans.append((p, "outer", p))
        chans.extend((p, "inner", c) for c, t in enumerate(inner) if t[0] == p)
    start, pos = {}, 0
    for ch in chans:
        start[ch[1:]] = pos
        pos += outer[ch[2]][0].shape[1] if ch[1] == "outer" else inner[ch[2]][2].shape[1]
    Bw, Cz, Dzw = np.zeros((n, pos)), np.zeros((pos, n)), np.zeros((pos, pos))
    for i, (U, lin) in outer.items():
        s = slice(start["outer", i], start["outer", i] + U.shape[1])
        Bw[:, s], Cz[s] = U, lin
    for c, (j, i, P, Qt) in enumerate(inner):
        s = slice(start["inner", c], start["inner", c] + P.shape[1])
        Cz[s] = Qt
        Dzw[start["outer", i]:start["outer", i] + P.shape[0], s] = P
    sizes = tuple(sum(outer[p][0].shape[1] if kind == "outer" else inner[ref][2].shape[1]
                      for q, kind, ref in chans if q == p) for p in range(k))
    if min(sizes) == 0:
        raise ValueError("every parameter must appear in a term with a non-zero dA")
    return ParametricLFT(A0=A0, Bw=Bw, Cz=Cz, Dzw=Dzw, names=tuple(names), sizes=sizes,
                         truncation=bound)
