"""Freeplay in the actuator-fin connection of the reference fin (thesis Sec. 6.2, future work;
asekit issue 14): LCO amplitude and frequency versus airspeed, fin alone and in the AEM1 loop.

Model (see :mod:`asekit.aeroelastic.nonlinear` for the fictitious-mass argument). The FN2 modal model of
the fin (rigid pitch mode first, then the elastic modes computed with the 120 N m/rad shaft
spring, Sec. 3.1.1) is used as a Ritz basis of the *fin alone*: coordinates xi = [theta_f,
zeta_1..zeta_n], with the plate's own stiffness K_plate = blockdiag(0, K_ss - k_s r r^T) (r: the
elastic modes' rotation of the shaft node) and the connection moment f(d) acting across

    d = theta_f + r . zeta - theta_t = (fin-root pitch) - (transmission angle),

on the fin as the generalised force -[1, r] f(d) and on the transmission as the hinge moment
+f(d). The aerodynamics are the fin's Roger RFA over the same modes (all treated as free
coordinates, n_rigid = 0 in :func:`asekit.aeroelastic.statespace.aeroelastic_matrices`). With the linear
spring this reproduces the thesis's clamped-actuator flutter model (checked in the tests).

* fin alone: theta_t = 0 (actuator locked, rigid transmission); d = fin-root pitch.
* AEM1: the actuator (:func:`asekit.servo.actuator.actuator_state_space`, no power limits) with its own
  inertia only (the fin is reached through the spring), PD on the transmission angle and rate
  (``voltage = K_c (K_P (theta_cmd - theta_t) - K_D omega_t)``, thesis Sec. 5.1).

Airspeed sweeps are at fixed Mach (the RFA of that Mach) and sea-level density, as the thesis's
p-k tables (unmatched). Reported amplitudes are the fin-root pitch amplitude (deg) of the
describing-function LCO, freeplay half-width delta (total freeplay 2 delta).

What the analysis finds (tests/aeroelastic/test_nonlinear.py, notebooks/freeplay.ipynb): a softer connection
raises the fin's flutter speed (zero stiffness: no flutter below 900 m/s at Mach 0.5), but makes
the fin statically unstable inside the band (pressure centre ahead of the shaft). So below the
linear flutter speed the fin rests against a stop, offset by d_e ~ delta k / (k - k_aero), and
does not oscillate; the LCO is born at the linear flutter speed as an oscillation about that
offset (dual-input describing function; confirmed by the time domain just above onset).

Also here: the Conner, Tang, Dowell & Virgin (1997) typical-section study of the notebook
(:func:`conner_study`) and the figure helpers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.aeroelastic.nonlinear import (
    ConnectedSystem,
    Connection,
    biased_harmonic_balance,
    bisect_onset,
    equilibria,
    growth_rate,
    harmonic_balance,
    multi_harmonic_balance,
    simulate_exact,
    steady_oscillation,
)
from asekit.aeroelastic.statespace import aeroelastic_matrices, fin_outputs, modal_arrays
from asekit.aeroelastic.typical_section import (
    CONNER_FREEPLAY_HALF_WIDTH_DEG,
    connected_system,
    conner_1997,
    flutter_speed,
    flutter_speed_exact,
)
from asekit.atmosphere import standard_atmosphere
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import CORNERS, fin_case
from asekit.reproduction.flutter import fin_rfa, load_fin_gafs
from asekit.servo.actuator import SYSTEM_3, ActuatorParameters, PDController, actuator_state_space
from asekit.util.plotting import new_figure

MACHS = {"M05": 0.5, "M075": 0.75}
FREEPLAYS_DEG = (0.05, 0.1, 0.25, 0.5)
VELOCITIES = np.linspace(100.0, 420.0, 41)          # m/s
KEY_FREEPLAY_DEG = 0.1
KEY_VELOCITY = 200.0
AMPLITUDE_LIMIT_DEG = 0.1
N_LAGS = 4


@dataclass(frozen=True)
class FinFreeplayModel:
    """The fin's Ritz model around the actuator connection at one Mach.

    M (n x n) modal mass (rigid first), K_plate (n x n), c (n,) = [1, r]: fin-root pitch row,
    k_s : nominal connection stiffness (N m/rad), rfa : RogerFit at ``mach``, outputs
    {name: row (n,)} fin rotations/displacements, modal : the FN2 ModalModel.
    """

    M: np.ndarray
    K_plate: np.ndarray
    c: np.ndarray
    k_s: float
    rfa: object
    mach: float
    outputs: dict
    modal: object

    @property
    def n_modes(self) -> int:
        return self.M.shape[0]

    def fin_alone(self, density: float, velocity: float) -> ConnectedSystem:
        """The fin on a locked actuator (theta_t = 0) at (density, velocity) as a
        :class:`ConnectedSystem`: d = fin-root pitch."""
        z = self._fin(density, velocity)
        A, b_f, c_f, rows = z
        outs = {name: (row, np.zeros(0)) for name, row in rows.items()}
        return ConnectedSystem(A, b_f, c_f, outputs=outs, velocity=float(velocity))

    def _fin(self, density, velocity):
        m = modal_arrays(M=self.M, K=self.K_plate, n_rigid=0)
        mats = aeroelastic_matrices(m, self.rfa, density, velocity)
        n = self.n_modes
        nz = mats.n_states
        Mb = self.M - 0.5 * density * self.rfa.b_ref ** 2 * self.rfa.A[2]     # Eq. (2.60)
        b_f = np.zeros(nz)
        b_f[n:2 * n] = -np.linalg.solve(Mb, self.c)
        c_f = np.zeros(nz)
        c_f[:n] = self.c
        rows = {}
        for name, row in self.outputs.items():
            r = np.zeros(nz)
            r[:n] = row
            rows[name] = r
        return mats.A, b_f, c_f, rows

    def aem1(self, density: float, velocity: float, controller: PDController = SYSTEM_3,
             actuator: ActuatorParameters | None = None) -> ConnectedSystem:
        """The AEM1 loop (PD on the transmission angle): :meth:`loop` with "AEM1"."""
        return self.loop(density, velocity, "AEM1", controller, actuator)

    def loop(self, density: float, velocity: float, topology: str = "AEM1",
             controller: PDController = SYSTEM_3,
             actuator: ActuatorParameters | None = None) -> ConnectedSystem:
        """The closed ASE loop with the connection between the transmission and the fin:
        states [theta_t, omega_t, current, fin states], input theta_cmd (rad); d = fin-root
        pitch - theta_t; outputs ``theta`` (transmission), ``fin_root_pitch`` and the fin
        outputs. The PD (thesis Sec. 5.1) acts on the transmission angle and rate (AEM1) or on
        the fin-root pitch and its rate (AEM2, potentiometer at the fin shaft):
        voltage = K_c (K_P (theta_cmd - y) - K_D y'). Linear actuator (no power limits), its
        own inertia only (the fin is reached through the connection)."""
        if topology not in ("AEM1", "AEM2"):
            raise ValueError(f"topology must be 'AEM1' or 'AEM2', got {topology!r}")
        act = ActuatorParameters(fin_inertia=0.0) if actuator is None else actuator
        ss = actuator_state_space(act)
        Aa, Ba = np.array(ss.A), np.array(ss.B)          # inputs: voltage, hinge_moment
        A_f, b_f, c_f, rows = self._fin(density, velocity)
        na, nz, n = 3, A_f.shape[0], self.n_modes
        kc, kp, kd = controller.gain, controller.kp, controller.kd
        y_row = np.zeros(na + nz)
        yd_row = np.zeros(na + nz)
        if topology == "AEM1":
            y_row[0], yd_row[1] = 1.0, 1.0
        else:
            y_row[na:na + n] = self.c                     # fin-root pitch c . xi
            yd_row[na + n:na + 2 * n] = self.c            # its rate c . xi'
        A = np.zeros((na + nz, na + nz))
        A[:na, :na] = Aa
        A[na:, na:] = A_f
        A[:na, :] -= np.outer(Ba[:, 0], kc * (kp * y_row + kd * yd_row))
        b = np.concatenate([Ba[:, 1], b_f])              # +f on the transmission, -c f on the fin
        c = np.concatenate([[-1.0, 0.0, 0.0], c_f])
        B_u = np.concatenate([Ba[:, 0] * kc * kp, np.zeros(nz)]).reshape(-1, 1)
        outs = {"theta": (np.eye(na + nz)[0], np.zeros(1))}
        for name, row in rows.items():
            outs[name] = (np.concatenate([np.zeros(na), row]), np.zeros(1))
        return ConnectedSystem(A, b, c, B_u=B_u, outputs=outs, velocity=float(velocity))


def fin_freeplay_model(mach: float, data=None, n_lags: int = N_LAGS) -> FinFreeplayModel:
    """Build :class:`FinFreeplayModel` from the cached GAF database (``data`` = (db, modal) as
    :func:`asekit.reproduction.flutter.load_fin_gafs` returns; loaded when None)."""

    if data is None:
        data, reason = load_fin_gafs()
        if data is None:
            raise RuntimeError(reason)
    db, modal = data
    if getattr(modal, "n_rigid", 0) != 1:
        raise ValueError("the fin model needs the FN2 modal model (one rigid pitch mode first)")
    case = fin_case()
    rows = fin_outputs(modal, np.zeros((0, 2)), names=[], shaft_point=case.support.axis_point)
    pts = case.panels[0].planform.point(np.array([v[0] for v in CORNERS.values()]),
                             np.array([v[1] for v in CORNERS.values()]))
    rows.update(fin_outputs(modal, pts, names=list(CORNERS)))
    c = np.asarray(rows["fin_root_pitch"], float)
    if abs(c[0] - 1.0) > 1e-12:
        raise ValueError("the fin-root pitch row must carry the rigid mode with unit weight")
    k_s = float(case.support.torsional_stiffness)
    r = c[1:]
    K = np.array(modal.K, float)
    K_plate = np.zeros_like(K)
    K_plate[1:, 1:] = K[1:, 1:] - k_s * np.outer(r, r)
    fit = fin_rfa(db, mach, n_lags=n_lags)
    outputs = {k: np.asarray(v, float) for k, v in rows.items()}
    return FinFreeplayModel(M=np.array(modal.M, float), K_plate=K_plate, c=c, k_s=k_s, rfa=fit,
                            mach=float(mach), outputs=outputs, modal=modal)


def linear_flutter(system_at, k: float, u_lo: float, u_hi: float, n: int = 65):
    """Lowest airspeed (m/s) in [u_lo, u_hi] where the linear system with connection
    stiffness k has an unstable oscillatory root, and its frequency (Hz); (None, None) if
    none."""
    from scipy.optimize import brentq
    us = np.linspace(u_lo, u_hi, n)
    s = np.array([growth_rate(system_at(u), k)[0] for u in us])
    if s[0] > 0:
        raise ValueError(f"already unstable at {u_lo:g} m/s with k = {k:g} N m/rad")
    idx = np.nonzero(s > 0)[0]
    if idx.size == 0:
        return None, None
    i = idx[0]
    uf = brentq(lambda u: growth_rate(system_at(u), k)[0], us[i - 1], us[i], xtol=1e-4)
    return float(uf), float(growth_rate(system_at(uf), k)[1] / (2 * math.pi))


def fin_amplitude(lco, name: str = "fin_root_pitch") -> float:
    """An LCO's fin-root pitch amplitude (rad) from its eigenvector."""
    return float(lco.output_amplitudes[name])


@dataclass(frozen=True)
class ConfigResult:
    """One configuration ("alone" or "aem1") at one Mach, per unit freeplay half-width
    (multiply by delta: the problem is scale-invariant).

    velocities (m/s); flutter (U, Hz) of the linear model with k_s, flutter_zero (U, Hz) with
    zero connection stiffness (None: none in 20-900 m/s); offset (per speed: the stable static
    offset d_e / delta of the fin against a stop, 0 if the rest position is stable, nan if no
    stable equilibrium); symmetric (per speed: HarmonicBalance at delta = 1 rad); biased (per
    speed: tuple of BiasedLco at delta = 1 rad); rest_unstable (per speed: the rest position
    d = 0 inside the band is statically unstable).
    """

    config: str
    velocities: np.ndarray
    flutter: tuple
    flutter_zero: tuple
    offset: np.ndarray
    symmetric: tuple
    biased: tuple
    rest_unstable: np.ndarray

    def biased_amplitude(self, name: str = "fin_root_pitch") -> np.ndarray:
        """Fin-root amplitude per unit delta of the stable biased LCO per speed (0 if none)."""
        out = []
        for lcs in self.biased:
            st = [lc for lc in lcs if lc.stable]
            out.append(st[0].output_amplitudes[name] if st else 0.0)
        return np.array(out)

    def biased_bias(self) -> np.ndarray:
        """Bias of d per unit delta of the stable biased LCO per speed (nan if none)."""
        return np.array([next((lc.bias for lc in lcs if lc.stable), math.nan)
                         for lcs in self.biased])

    def biased_frequency_hz(self) -> np.ndarray:
        return np.array([next((lc.frequency_hz for lc in lcs if lc.stable), math.nan)
                         for lcs in self.biased])

    def onset_speed(self) -> float | None:
        """Lowest speed of the sweep with a stable LCO (biased or symmetric); None if none."""
        for u, lcs, hb in zip(self.velocities, self.biased, self.symmetric):
            if any(lc.stable for lc in lcs) or hb.stable_lcos:
                return float(u)
        return None


def analyse_config(model: FinFreeplayModel, cfg: str, density: float,
                   velocities=VELOCITIES) -> ConfigResult:
    """Every analysis of one configuration per unit freeplay (delta = 1 rad, then scaled):
    linear flutter (with k_s and with zero stiffness), static equilibria, symmetric and biased
    harmonic balance at each speed."""
    if cfg not in ("alone", "aem1"):
        raise ValueError(f"cfg must be 'alone' or 'aem1', got {cfg!r}")
    at = (lambda u: model.fin_alone(density, u)) if cfg == "alone" else \
        (lambda u: model.aem1(density, u))
    unit = Connection(model.k_s, freeplay=1.0)
    offs, sym, bia, rest = [], [], [], []
    for u in velocities:
        s = at(float(u))
        eq = equilibria(s, unit)
        stable = [e for e in eq if e.stable]
        if any(e.region == 0 and e.stable for e in eq):
            offs.append(0.0)
        elif stable:
            offs.append(max(abs(e.d) for e in stable))
        else:
            offs.append(math.nan)
        rest.append(any(e.region == 0 and not e.stable and e.max_real > 0
                        and _static(s, e) for e in eq))
        sym.append(harmonic_balance(s, unit))
        bia.append(biased_harmonic_balance(s, unit, amplitudes=np.geomspace(0.01, 30.0, 40))
                   if rest[-1] else ())
    return ConfigResult(config=cfg, velocities=np.asarray(velocities, float),
                        flutter=linear_flutter(at, model.k_s, 50.0, 900.0),
                        flutter_zero=linear_flutter(at, 0.0, 20.0, 900.0),
                        offset=np.array(offs), symmetric=tuple(sym), biased=tuple(bia),
                        rest_unstable=np.array(rest))


def _static(system, eq) -> bool:
    """The rest position's instability is static (a real root)."""
    return growth_rate(system, 0.0)[2] > 0


def excursion_deg(res: ConfigResult, delta_deg: float) -> np.ndarray:
    """Largest fin-root excursion (deg) per speed for freeplay half-width ``delta_deg``:
    |bias| + amplitude of the stable biased LCO, else the static offset (proportional to
    delta; inf where no stable state exists)."""
    amp = res.biased_amplitude()
    bias = np.nan_to_num(np.abs(res.biased_bias()))
    off = np.where(np.isnan(res.offset), np.inf, res.offset)
    ex = np.where(amp > 0, bias + amp, off)
    return delta_deg * ex


def freeplay_limit_deg(res: ConfigResult, u_max: float, limit_deg: float = AMPLITUDE_LIMIT_DEG):
    """The largest freeplay half-width (deg) keeping the fin-root excursion below
    ``limit_deg`` at every swept speed <= ``u_max`` (m/s); 0 if some speed has no bounded
    state (linear flutter inside the envelope)."""
    sel = res.velocities <= u_max
    worst = float(np.max(excursion_deg(res, 1.0)[sel])) if sel.any() else 0.0
    if not math.isfinite(worst):
        return 0.0
    return math.inf if worst == 0 else limit_deg / worst


def time_domain(model: FinFreeplayModel, cfg: str, density: float, velocity: float,
                delta_deg: float = KEY_FREEPLAY_DEG, t_final: float = 1.0,
                start: float = 0.5, step: float = 5e-5):
    """Exact piecewise-linear simulation of the fin (``cfg`` "alone" or "aem1") from rest with
    the fin-root pitch displaced by ``start`` x delta (AEM1: the fin coordinate theta_f)."""
    conn = Connection(model.k_s, freeplay=math.radians(delta_deg))
    s = model.fin_alone(density, velocity) if cfg == "alone" else model.aem1(density, velocity)
    x0 = np.zeros(s.n_states)
    x0[0 if cfg == "alone" else 3] = start * conn.freeplay
    return simulate_exact(s, conn, x0, t_final, step=step)


def lco_onset(model: FinFreeplayModel, cfg: str, density: float, u_lo: float, u_hi: float,
              xtol: float = 0.25) -> float | None:
    """Lowest airspeed (m/s) in [u_lo, u_hi] with a stable (symmetric or biased) LCO, by
    bisection to ``xtol``; None if there is none at u_hi; ValueError if there is one at u_lo
    (the bracket does not contain the onset)."""
    at = (lambda u: model.fin_alone(density, u)) if cfg == "alone" else \
        (lambda u: model.aem1(density, u))
    unit = Connection(model.k_s, freeplay=1.0)

    def has(u):
        s = at(u)
        if harmonic_balance(s, unit).stable_lcos:
            return True
        return any(lc.stable for lc in biased_harmonic_balance(
            s, unit, amplitudes=np.geomspace(0.01, 30.0, 40)))
    if not has(u_hi):
        return None
    if has(u_lo):
        raise ValueError(f"a stable LCO exists already at {u_lo:g} m/s; lower u_lo")
    return bisect_onset(has, u_lo, u_hi, xtol)


def run(figures: bool = False) -> ChapterResult:
    """The freeplay quantities (and figures) at Mach 0.5, sea-level density, delta = 0.1 deg:
    LCO onset speed and amplitude at 200 m/s (fin alone and AEM1), linear flutter speeds,
    the static offset at 200 m/s and the freeplay limit for a 0.1 deg excursion up to the
    matched flight speed."""

    data, reason = load_fin_gafs()
    keys = ["freeplay.M05.h0.lco_onset_ms", "freeplay.M05.h0.amplitude_deg_at_200ms",
            "freeplay.M05.h0.linear_flutter_ms", "freeplay.M05.h0.aem1.lco_onset_ms",
            "freeplay.M05.h0.aem1.amplitude_deg_at_200ms",
            "freeplay.M05.h0.aem1.linear_flutter_ms",
            "freeplay.M05.h0.static_offset_deg_at_200ms", "freeplay.M05.h0.freeplay_limit_deg"]
    if data is None:
        return ChapterResult("freeplay", tuple(Quantity(k, None, "-", reason) for k in keys))
    atm = standard_atmosphere(0.0)
    rho = float(atm.density)
    model = fin_freeplay_model(0.5, data)
    dd = KEY_FREEPLAY_DEG
    q = []
    for cfg, tag in (("alone", ""), ("aem1", "aem1.")):
        at = (lambda u: model.fin_alone(rho, u)) if cfg == "alone" else \
            (lambda u: model.aem1(rho, u))
        uf = linear_flutter(at, model.k_s, 50.0, 900.0)[0]
        onset = None if uf is None else lco_onset(model, cfg, rho, uf - 5.0, uf + 7.0, xtol=0.5)
        q.append(Quantity(f"freeplay.M05.h0.{tag}lco_onset_ms", onset, "m/s",
                          f"{'fin alone' if cfg == 'alone' else 'AEM1 loop'}; lowest speed "
                          "with a stable (biased) DF LCO, to 0.5 m/s"))
        r200 = analyse_config(model, cfg, rho, [KEY_VELOCITY])
        amp = float(r200.biased_amplitude()[0])
        if amp == 0 and r200.symmetric[0].stable_lcos:
            amp = fin_amplitude(r200.symmetric[0].largest_stable())
        q.append(Quantity(f"freeplay.M05.h0.{tag}amplitude_deg_at_200ms", dd * amp, "deg",
                          "fin-root LCO amplitude; 0: no LCO at 200 m/s (the fin rests "
                          "against a stop)" if amp == 0 else "fin-root LCO amplitude"))
        q.append(Quantity(f"freeplay.M05.h0.{tag}linear_flutter_ms", uf, "m/s",
                          "connection 120 N m/rad, Mach 0.5 RFA, sea-level density"))
        if cfg == "alone":
            q.append(Quantity("freeplay.M05.h0.static_offset_deg_at_200ms",
                              dd * float(r200.offset[0]), "deg",
                              "fin alone: stable rest position against a stop"))
    u_env = 0.5 * float(atm.speed_of_sound)
    env = analyse_config(model, "alone", rho, np.linspace(100.0, u_env, 6))
    q.append(Quantity("freeplay.M05.h0.freeplay_limit_deg", freeplay_limit_deg(env, u_env),
                      "deg", f"largest delta keeping the fin-root excursion below "
                      f"{AMPLITUDE_LIMIT_DEG} deg up to Mach 0.5 at sea level (fin alone)"))
    figs = {}
    if figures:
        figs["freeplay_M05_excursion"] = fig_excursion({("alone", dd): env}, "M 0.5")
    return ChapterResult(chapter="freeplay", quantities=tuple(q), figures=figs)


# --------------------------------------------------------------------------------------------
# figures (also used by notebooks/freeplay.ipynb)
# --------------------------------------------------------------------------------------------
def fig_excursion(results: dict, label: str):
    """Fin-root LCO amplitude (biased LCO) and static offset (deg) vs airspeed for each
    ``(config, delta_deg) -> ConfigResult`` entry, with the linear flutter speeds."""
    fig, (a1, a2) = new_figure(f"Freeplay: fin-root motion, {label}, sea-level density", None,
                               nrows=2, figsize=(6.4, 6.5))
    for j, ((cfg, dd), res) in enumerate(sorted(results.items())):
        ls = "-" if cfg == "alone" else "--"
        col = f"C{FREEPLAYS_DEG.index(dd) if dd in FREEPLAYS_DEG else j}"
        lab = f"{'fin alone' if cfg == 'alone' else 'AEM1'}, delta {dd} deg"
        amp = dd * res.biased_amplitude()
        ok = amp > 0
        a1.plot(res.velocities[ok], amp[ok], ls, color=col, label=lab)
        a2.plot(res.velocities, dd * res.offset, ls, color=col, label=lab)
        if res.flutter[0] is not None:
            for a in (a1, a2):
                a.axvline(res.flutter[0], color="k", ls=ls, lw=0.8)
    a1.set_ylabel("biased LCO amplitude, fin root (deg)")
    a1.legend(fontsize=7, ncol=2)
    a2.set_xlabel("airspeed (m/s)")
    a2.set_ylabel("static offset on the stop (deg)")
    return fig


def fig_fin_lco(results: dict, freeplays_deg=FREEPLAYS_DEG):
    """Biased-LCO fin-root amplitude (deg, top) and frequency (Hz, bottom) vs airspeed for
    ``{(label, config): ConfigResult}``, one line per freeplay (amplitude proportional to
    delta), with each configuration's linear flutter speed (vertical line)."""
    fig, (a1, a2) = new_figure("Freeplay LCO of the fin (dual-input DF), sea-level density",
                               None, nrows=2, figsize=(7.0, 7.0))
    styles = ["-", "--", ":", "-."]
    for j, ((label, cfg), res) in enumerate(results.items()):
        ls = styles[j % 4]
        amp = res.biased_amplitude()
        ok = amp > 0
        for i, dd in enumerate(freeplays_deg):
            a1.plot(res.velocities[ok], dd * amp[ok], ls, color=f"C{i}",
                    label=f"{label} {'fin alone' if cfg == 'alone' else 'AEM1'}, "
                          f"delta {dd} deg" if j == 0 or i == 0 else None)
        a2.plot(res.velocities[ok], res.biased_frequency_hz()[ok], ls, color="k",
                label=f"{label} {'fin alone' if cfg == 'alone' else 'AEM1'}")
        if res.flutter[0] is not None:
            a1.axvline(res.flutter[0], color="0.5", ls=ls, lw=0.8)
    a1.set_yscale("log")
    a1.set_ylabel("fin-root LCO amplitude (deg)")
    a1.legend(fontsize=6, ncol=2)
    a2.set_xlabel("airspeed (m/s)")
    a2.set_ylabel("LCO frequency (Hz)")
    a2.legend(fontsize=7)
    return fig


def fig_history(sim, delta: float, title: str, t_window: float | None = None):
    """d / delta vs time of a :class:`asekit.aeroelastic.nonlinear.PiecewiseSimulation` (last
    ``t_window`` s, default all), band edges dashed."""
    fig, ax = new_figure(title, None, figsize=(7.0, 3.0))
    sel = sim.t >= (sim.t[-1] - t_window if t_window else 0.0)
    ax.plot(sim.t[sel], sim.d[sel] / delta, lw=0.6)
    for e in (-1, 1):
        ax.axhline(e, color="k", ls="--", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("connection rotation d / delta (-)")
    return fig


def fig_growth_map(system_at, k: float, velocities, kappas=np.linspace(0.0, 1.0, 41),
                   title: str = "growth rate of the quasi-linear system"):
    """Largest real part of the oscillatory roots (1/s) over (airspeed, equivalent stiffness
    ratio N/k): the harmonic-balance LCOs lie on its zero contour."""
    fig, ax = new_figure(title, None, figsize=(6.4, 4.2))
    v = np.asarray(velocities, float)
    sig = np.array([[growth_rate(system_at(u), kp * k)[0] for u in v] for kp in kappas])
    lim = np.nanmax(np.abs(sig[np.isfinite(sig)]))
    cs = ax.contourf(v, kappas, sig, levels=np.linspace(-lim, lim, 21), cmap="RdBu_r")
    ax.contour(v, kappas, sig, levels=[0.0], colors="k")
    fig.colorbar(cs, ax=ax, label="max Re of oscillatory roots (1/s)")
    ax.set_xlabel("airspeed (m/s)")
    ax.set_ylabel("equivalent stiffness N / k (-)")
    return fig


# --------------------------------------------------------------------------------------------
# the Conner, Tang, Dowell & Virgin (1997) typical section
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ConnerStudy:
    """Describing function, multi-harmonic balance and time domain on the Conner et al. section.

    delta (rad, half-width); velocities and hb (HarmonicBalance per speed); mhb (per speed, the
    MultiHarmonicLco started from the largest stable DF LCO, None where there is none);
    td_velocities and td (TimeDomainLco of the flap angle per speed, from beta = 1.5 x the DF
    amplitude); td_mhb (the same, started on the balanced orbit); flutter (U, Hz) with Jones'
    and the exact C(k); flutter_zero (U) of the section with zero flap stiffness (flap damping
    kept)."""

    delta: float
    velocities: np.ndarray
    hb: tuple
    mhb: tuple
    td_velocities: np.ndarray
    td: tuple
    td_mhb: tuple
    flutter_jones: tuple
    flutter_exact: tuple
    flutter_zero: float

    def mhb_at(self, u: float):
        """The multi-harmonic LCO of the sweep speed nearest ``u`` (m/s)."""
        return self.mhb[int(np.argmin(np.abs(self.velocities - u)))]

    def df_at(self, u: float):
        return self.hb[int(np.argmin(np.abs(self.velocities - u)))].largest_stable()


def conner_study(delta_half_deg: float | None = None, velocities=np.arange(3.0, 24.01, 0.5),
                 td_velocities=(5.0, 6.0, 7.0, 8.0, 10.0, 14.0, 18.0, 22.0, 23.0),
                 t_final: float = 30.0, step: float = 1e-3, n_harmonics: int = 11) -> ConnerStudy:
    """Harmonic balance (describing function and ``n_harmonics`` multi-harmonic balance) over
    ``velocities`` and exact piecewise time integration at ``td_velocities`` (``t_final`` s,
    output every ``step`` s; :func:`asekit.aeroelastic.nonlinear.simulate_exact`) of the Conner section with
    a flap freeplay of half-width ``delta_half_deg`` (default: Conner et al., +-2.12 deg)."""
    from scipy.optimize import brentq

    sec = conner_1997()
    dl = math.radians(CONNER_FREEPLAY_HALF_WIDTH_DEG if delta_half_deg is None
                      else delta_half_deg)
    conn = Connection(sec.stiffness_beta, freeplay=dl)
    v = np.asarray(velocities, float)
    hb = tuple(harmonic_balance(connected_system(sec, u), conn) for u in v)
    mhb = []
    for u, r in zip(v, hb):
        st = r.largest_stable()
        mhb.append(None if st is None else
                   multi_harmonic_balance(connected_system(sec, u), conn, st.amplitude,
                                          st.frequency_hz, n_harmonics=n_harmonics))
    td, td_m = [], []
    for u in td_velocities:
        s = connected_system(sec, u)
        st = harmonic_balance(s, conn).largest_stable()
        x0 = np.zeros(8)
        x0[2] = 1.5 * (st.amplitude if st is not None else 3 * dl)
        sim = simulate_exact(s, conn, x0, t_final, step=step)
        td.append(steady_oscillation(sim.t, sim.d, floor=1e-3 * dl, diverged=sim.diverged))
        m = mhb[int(np.argmin(np.abs(v - u)))]
        if m is not None and m.converged and abs(v[int(np.argmin(np.abs(v - u)))] - u) < 1e-9:
            sim = simulate_exact(s, conn, m.state, t_final, step=step)
            td_m.append(steady_oscillation(sim.t, sim.d, floor=1e-3 * dl,
                                           diverged=sim.diverged))
        else:
            td_m.append(None)
    fj = flutter_speed(sec, 1.0, 60.0, 120)
    fe = flutter_speed_exact(sec, *fj)
    u0 = brentq(lambda u: growth_rate(connected_system(sec, u), 0.0)[0], 2.0, 23.0)
    return ConnerStudy(delta=dl, velocities=v, hb=hb, mhb=tuple(mhb),
                       td_velocities=np.asarray(td_velocities, float), td=tuple(td),
                       td_mhb=tuple(td_m), flutter_jones=fj, flutter_exact=fe,
                       flutter_zero=float(u0))


def repeat_period(t: np.ndarray, y: np.ndarray, frequency_hz: float, window: float,
                  max_period: int = 8, rel_tol: float = 0.02) -> int | None:
    """The smallest p in 1..``max_period`` for which the end of a uniformly sampled history
    repeats after p fundamental periods: max |y(t + p T) - y(t)| <= ``rel_tol`` max |y| over the
    last ``window`` s before the final p T (T = 1 / ``frequency_hz``). p = 1 is a period-one
    motion, 2 a period-doubled one; None: no repetition up to ``max_period`` (quasi-periodic,
    chaotic or not settled)."""
    if frequency_hz <= 0 or window <= 0:
        raise ValueError(f"frequency_hz and window must be > 0, got {frequency_hz}, {window}")
    period = 1.0 / frequency_hz
    scale = float(np.max(np.abs(y[t >= t[-1] - window - max_period * period]))) or 1.0
    for p in range(1, int(max_period) + 1):
        t1 = t[-1] - p * period
        sel = (t >= t1 - window) & (t <= t1)
        if not np.any(sel):
            raise ValueError("the history is shorter than window + max_period periods")
        err = np.max(np.abs(np.interp(t[sel] + p * period, t, y) - y[sel]))
        if err <= rel_tol * scale:
            return p
    return None


@dataclass(frozen=True)
class PathPoint:
    """One airspeed of :func:`conner_path_following`: ``flap`` the steady oscillation of the
    flap angle (rad; :func:`asekit.aeroelastic.nonlinear.steady_oscillation`), r.m.s. of flap, pitch (rad)
    and plunge (m) over the last ``tail`` s (Conner et al. 1997, Eq. 7), ``period`` from
    :func:`repeat_period` (None when not periodic or not an LCO), ``maxima_per_cycle``: flap
    maxima (prominence > 0.05 delta) per fundamental period over the last ``tail`` s (1 for a
    simple oscillation, 2 for a flap motion with two maxima a cycle), ``restarted``: the run
    started from the disturbance rather than from the previous speed's end state."""

    velocity: float
    flap: object
    flap_rms: float
    pitch_rms: float
    plunge_rms: float
    period: int | None
    maxima_per_cycle: float
    restarted: bool


def conner_path_following(velocities, delta_half_deg: float | None = None,
                          t_final: float = 20.0, tail: float = 5.0,
                          plunge_kick: float = 1.0, step: float = 1e-3) -> tuple:
    """Path following in airspeed on the Conner et al. section, as Conner et al. (1997,
    Sec. 11.2) ran their model and experiment: at each airspeed of the increasing sequence
    ``velocities`` (m/s) the exact piecewise integration (:func:`asekit.aeroelastic.nonlinear.
    simulate_exact`, ``t_final`` s) starts from the end state of the previous speed; at the
    first speed, and after a run that decayed to rest, it starts from the disturbance "flap
    resting on a band edge" (beta = delta, as in the experiment) plus a plunge displacement of
    ``plunge_kick`` delta b (Tang et al. 1998: plunge is the degree of freedom that most easily
    starts the LCO). Returns a tuple of :class:`PathPoint`."""
    from scipy.signal import find_peaks

    v = np.asarray(velocities, float)
    if v.size == 0 or np.any(np.diff(v) <= 0):
        raise ValueError("velocities must be a non-empty increasing sequence")
    sec = conner_1997()
    dl = math.radians(CONNER_FREEPLAY_HALF_WIDTH_DEG if delta_half_deg is None
                      else delta_half_deg)
    conn = Connection(sec.stiffness_beta, freeplay=dl)
    kick = np.zeros(8)
    kick[0], kick[2] = plunge_kick * dl * sec.semichord, dl
    x, out = None, []
    for u in v:
        restarted = x is None
        sim = simulate_exact(connected_system(sec, u), conn, kick if restarted else x,
                             t_final, step=step)
        td = steady_oscillation(sim.t, sim.d, floor=1e-3 * dl, diverged=sim.diverged)
        last = sim.t >= sim.t[-1] - tail
        rms = np.sqrt(np.mean(sim.x[:3, last] ** 2, axis=1))
        osc = td.kind in ("lco", "not settled") and td.frequency_hz > 0
        per = repeat_period(sim.t, sim.d, td.frequency_hz, window=1.0) if osc else None
        n_max = (len(find_peaks(sim.d[last], prominence=0.05 * dl)[0])
                 / (tail * td.frequency_hz) if osc else 0.0)
        out.append(PathPoint(velocity=float(u), flap=td, flap_rms=float(rms[2]),
                             pitch_rms=float(rms[1]), plunge_rms=float(rms[0]), period=per,
                             maxima_per_cycle=float(n_max), restarted=restarted))
        x = None if td.kind in ("decayed", "diverged") else sim.x[:, -1].copy()
    return tuple(out)


def fig_conner(cs: ConnerStudy):
    """Flap LCO amplitude / delta (DF; time domain first harmonic and half peak-to-peak) and
    frequency vs airspeed for the Conner et al. section."""
    fig, (a1, a2) = new_figure("Conner et al. (1997) section with flap freeplay", None,
                               nrows=2, figsize=(6.4, 6.5))
    for branch, mk in ((True, "-"), (False, ":")):
        u = [v for v, r in zip(cs.velocities, cs.hb) for lc in r.lcos if lc.stable == branch]
        a = [lc.amplitude / cs.delta for r in cs.hb for lc in r.lcos if lc.stable == branch]
        f = [lc.frequency_hz for r in cs.hb for lc in r.lcos if lc.stable == branch]
        lab = "DF, stable" if branch else "DF, unstable"
        a1.plot(u, a, mk, color="C0", label=lab)
        a2.plot(u, f, mk, color="C0", label=lab)
    for stab, mk in ((True, "^"), (False, "v")):
        sel = [(u, m) for u, m in zip(cs.velocities, cs.mhb)
               if m is not None and m.converged and m.stable == stab]
        if sel:
            lab = f"multi-harmonic balance, {'stable' if stab else 'unstable'}"
            a1.plot([u for u, _ in sel], [m.amplitude / cs.delta for _, m in sel], mk,
                    color="C2", ms=4, mfc="C2" if stab else "none", label=lab)
            a2.plot([u for u, _ in sel], [m.frequency_hz for _, m in sel], mk, color="C2",
                    ms=4, mfc="C2" if stab else "none", label=lab)
    ok = [i for i, t in enumerate(cs.td) if t.kind == "lco"]
    a1.plot(cs.td_velocities[ok], [cs.td[i].amplitude / cs.delta for i in ok], "o", color="C1",
            label="time domain, first harmonic")
    a1.plot(cs.td_velocities[ok], [cs.td[i].peak / cs.delta for i in ok], "s", mfc="none",
            color="C1", label="time domain, half peak-to-peak")
    a2.plot(cs.td_velocities[ok], [cs.td[i].frequency_hz for i in ok], "o", color="C1",
            label="time domain")
    okm = [i for i, t in enumerate(cs.td_mhb) if t is not None and t.kind == "lco"]
    a1.plot(cs.td_velocities[okm], [cs.td_mhb[i].amplitude / cs.delta for i in okm], "x",
            color="C3", label="time domain from the balanced orbit")
    a2.plot(cs.td_velocities[okm], [cs.td_mhb[i].frequency_hz for i in okm], "x", color="C3",
            label="time domain from the balanced orbit")
    for a in (a1, a2):
        a.axvline(cs.flutter_exact[0], color="k", lw=0.8, ls="--")
        a.axvline(cs.flutter_zero, color="0.5", lw=0.8, ls="--")
    a1.set_yscale("log")
    a1.set_ylabel("flap LCO amplitude / delta (-)")
    a1.legend(fontsize=7)
    a2.set_xlabel("airspeed (m/s)")
    a2.set_ylabel("LCO frequency (Hz)")
    a2.legend(fontsize=7)
    return fig
