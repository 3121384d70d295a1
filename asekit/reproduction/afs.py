"""Active flutter suppression of the fin (issue 26; the thesis's Sec. 6.2 outlook): the flutter
boundary of the aeroservoelastic loop against airspeed, open and closed loop, at Mach 0.5, sea
level.

:func:`compute` builds the fin's model family (:class:`asekit.ase.afs.SpeedFamily`: asekit's
structure, DLM GAFs at Mach 0.5 and their Roger fit, sea-level density, the thesis's actuator),
finds

* the open-loop boundary: the fin with its actuator locked (rigid pitch held), and the p-k
  flutter speed of the same fin, Mach and density beside it;
* the closed-loop boundary under two designs (:data:`DESIGNS`): the classical law
  (the thesis's System 3 PD on the transmission angle plus the fin-root pitch rate through a
  300 Hz low-pass, :func:`asekit.ase.afs.classical_controller`) and an LQG regulator designed at
  1.35 times the open-loop flutter speed (:func:`asekit.ase.afs.lqg_controller`, measuring the
  transmission angle and the fin-root pitch);

and, for each design, the Nyquist margins of the loop broken at the actuator input and a release
from a fin-root twist with the 24 V / 10 A voltage clip, both at :data:`CHECK_FACTOR` times the
open-loop flutter speed (just above it). Definitions of the reported numbers:

* ``ase.afs.open_loop_flutter_ms``: first right-half-plane root of the locked fin;
* ``ase.afs.closed_loop_flutter_ms``: first right-half-plane root of the classical loop;
* ``ase.afs.gain_margin_db``: the smaller of |lower| and upper Nyquist gain margins (dB) of the
  classical loop at the check speed; ``ase.afs.phase_margin_deg``: its phase margin;
* ``ase.afs.sampled_5khz_flutter_ms``: the classical loop's boundary with the controller run
  at 5 kHz (Tustin) and one sample of computational delay; ``ase.afs.stable_at_1khz``: whether
  it is stable at the check speed when run at the thesis's 1 kHz with one sample of delay;
* ``ase.afs.lqg.*``: the same for the LQG design;
* ``ase.afs.dlqg_1khz.*``: a discrete LQG designed on the 1 kHz zero-order-hold plant with its
  one sample of computational delay (:func:`asekit.ase.afs.discrete_lqg_controller`): its
  boundary, gain margins from the eigenvalues with its gain scaled, phase margin on the unit
  circle and the sampled release at the check speed; ``.quantised_*``: the quantisation-induced
  limit cycle of the same loop with the word lengths :data:`QUANTISERS`; ``ase.afs.*.peak_voltage_v`` /
  ``peak_current_a``: peaks of the release at the check speed;
* ``ase.afs.dlqg_1khz.sensed_*``: the same sampled release with the sensors :data:`SENSORS`
  (first-order bandwidth, seeded white measurement noise, :mod:`asekit.ase.sensors`): peak
  voltage and current, and the residual oscillation (RMS fin-root pitch and voltage over the
  last 0.1 s of a 0.5 s release; the ideal loop decays to rest).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from asekit.aeroelastic.flutter import first_of, pk_flutter, pk_instabilities
from asekit.aeroelastic.statespace import fin_outputs
from asekit.ase import afs
from asekit.ase.margins import nyquist_margins
from asekit.ase.metrics import limit_cycle
from asekit.ase.sensors import Sensors
from asekit.case import pipeline
from asekit.reproduction.driver import Quantity
from asekit.reproduction.fin import fin_case
from asekit.servo.actuator import SYSTEM_3
from asekit.util.blas import small_dense
from asekit.util.plotting import new_figure

MACH, ALTITUDE = 0.5, 0.0
#: Airspeeds (m/s) scanned for the first unstable root (each crossing is then bisected).
GRID = np.arange(150.0, 451.0, 25.0)
#: Where the margins and the release are checked, times the open-loop flutter speed.
CHECK_FACTOR = 1.05
#: Initial fin-root twist of the release (rad).
RELEASE_TWIST = math.radians(0.1)
#: The LQG's design airspeed, times the open-loop flutter speed.
LQG_DESIGN_FACTOR = 1.35
#: Rate gain (V s/rad) and low-pass corner (Hz) of the classical law (chosen on a grid of
#: gains 2-6 V s/rad, lead/lag -60..40 deg at 140 Hz and low-pass 300 Hz-none for the highest
#: boundary keeping 6 dB / 45 deg at the check speed).
RATE_GAIN, LOWPASS_HZ = 5.0, 300.0
#: LQG weights: fin-root elastic twist, transmission angle (1/rad^2), voltage (1/V^2).
LQG_WEIGHTS = (1e4, 1e4, 1.0)
#: The discrete LQG's weights: a cheaper voltage (chosen on voltage weights 0.1-10 and design
#: speeds 1.2-1.35 x open loop for the largest gain margins at 1.05 and 1.21 x open loop).
DLQG_WEIGHTS = (1e4, 1e4, 0.1)
#: Bisection tolerance (m/s).
TOL = 0.01
#: The processor's word lengths: a 2000-count motor encoder behind the 66:1 transmission, a
#: 12-bit ADC over +-pi rad for the fin-root potentiometer, a 12-bit DAC over +-24 V.
QUANTISERS = afs.Quantisers(encoder_resolution=2 * math.pi / (2000 * 66), adc_bits=12,
                            dac_bits=12)
#: Sensors of the processor loop (assumed, not the thesis's): 300 Hz first-order bandwidth and
#: 1e-4 rad RMS white noise on each measured angle (about 0.07 of a 12-bit ADC step over
#: +-pi rad), seed 26.
SENSORS = Sensors(bandwidth=300.0, noise_rms=1e-4, seed=26)
#: The processor: sample times (s) checked with one sample of computational delay.
FAST_SAMPLE, THESIS_SAMPLE = 2e-4, 1e-3


@dataclass(frozen=True)
class AfsDesign:
    """One design: ``controller`` (StateSpace), ``boundary`` (:class:`asekit.ase.afs.Boundary`),
    ``margins`` (:class:`asekit.ase.margins.NyquistMargins` at the check speed; None for the
    PD-only reference), ``release``
    (:class:`asekit.ase.afs.AfsSimulation` at the check speed), ``sampled_fast`` (the boundary
    with the controller run at :data:`FAST_SAMPLE` with one sample of delay, Tustin),
    ``stable_thesis_rate`` (the loop at :data:`THESIS_SAMPLE` with one sample of delay stable at
    the check speed)."""

    name: str
    controller: object
    boundary: afs.Boundary
    margins: object
    release: afs.AfsSimulation
    sampled_fast: afs.Boundary | None = None
    stable_thesis_rate: bool | None = None

    @property
    def gain_margin_db(self) -> float:
        """min(|lower|, upper) Nyquist gain margin (dB)."""
        lo = self.margins.lower_gain_margin_db
        return float(min(abs(lo) if lo is not None else math.inf,
                         self.margins.upper_gain_margin_db))


@dataclass(frozen=True)
class DigitalDesign:
    """The discrete LQG run at :data:`THESIS_SAMPLE` with one sample of delay: ``controller``
    (discrete StateSpace), ``boundary``, ``gain_margins`` (lower, upper linear factors, from
    the eigenvalues), ``phase_margin_deg`` (unit circle), ``release`` (sampled, at the check
    speed)."""

    controller: object
    boundary: afs.Boundary
    gain_margins: tuple
    phase_margin_deg: float | None
    release: afs.AfsSimulation
    quantised: afs.AfsSimulation | None = None
    sensed: afs.AfsSimulation | None = None

    @property
    def gain_margin_db(self) -> float:
        lo, hi = self.gain_margins
        return float(min(-20 * math.log10(lo) if lo > 0 else math.inf,
                         20 * math.log10(hi) if math.isfinite(hi) else math.inf))


@dataclass(frozen=True)
class AfsStudy:
    """``family``, ``open_loop`` (Boundary of the locked fin), ``pk_speed`` (m/s) and
    ``pk_frequency_hz`` of the same fin, ``check_speed`` (m/s), ``designs`` {name: AfsDesign}."""

    family: afs.SpeedFamily
    open_loop: afs.Boundary
    pk_speed: float | None
    pk_frequency_hz: float | None
    check_speed: float
    designs: dict
    digital: DigitalDesign | None = None


def family(mach: float = MACH, altitude: float = ALTITUDE) -> afs.SpeedFamily:
    """The fin's model family at (mach, altitude m): density of the standard atmosphere."""
    case = fin_case()
    cond = pipeline.ase_condition(case, mach=mach, altitude=altitude)
    corners = pipeline.corner_points(case)
    rows = fin_outputs(cond.modal, np.array(list(corners.values())), names=list(corners),
                       shaft_point=case.support.axis_point)
    return afs.SpeedFamily(cond.modal, cond.rfa, cond.density, rows, cond.model.actuator, mach)


def _pk(fam: afs.SpeedFamily):
    g = pipeline.gaf_database(fin_case(), progress=False).at(fam.mach, interpolate=True)
    res = pk_flutter(fam.modal, g, fam.density, GRID)
    f = first_of(pk_instabilities(res, fam.modal, g), "flutter")
    return (None, None) if f is None else (float(f.speed), float(f.frequency_hz))


def _design(fam, name, K, check_speed, margins: bool = True) -> AfsDesign:
    b = afs.stability_boundary(lambda u: afs.closed_loop_matrix(fam.model(u), K), GRID, tol=TOL)
    m = fam.model(check_speed)
    marg = (nyquist_margins(afs.loop_at_input(m, K), points_per_decade=50) if margins
            else None)
    sim = afs.simulate_release(m, K, root_twist=RELEASE_TWIST, t_final=0.1)
    if not margins:
        return AfsDesign(name, K, b, marg, sim)
    fast = afs.stability_boundary(
        lambda u: afs.sampled_closed_loop_matrix(fam.model(u), K, FAST_SAMPLE, 1), GRID,
        tol=TOL, sample_time=FAST_SAMPLE)
    slow = afs.sampled_growth_rate(afs.sampled_closed_loop_matrix(m, K, THESIS_SAMPLE, 1),
                                   THESIS_SAMPLE)[0] < 0
    return AfsDesign(name, K, b, marg, sim, fast, bool(slow))


@small_dense
def compute() -> AfsStudy:
    """Run the study (about ten seconds)."""
    fam = family()
    ol = afs.stability_boundary(lambda u: afs.locked_matrix(fam, u), GRID, tol=TOL)
    if ol.speed is None or ol.at_first_point:
        raise RuntimeError(f"the locked fin's flutter is not bracketed by {GRID[0]:g}-"
                           f"{GRID[-1]:g} m/s")
    check = CHECK_FACTOR * ol.speed
    classical = afs.classical_controller(SYSTEM_3.gain, SYSTEM_3.kp, SYSTEM_3.kd, RATE_GAIN,
                                         lowpass_hz=LOWPASS_HZ)
    lqg = afs.lqg_controller(fam.model(LQG_DESIGN_FACTOR * ol.speed), *LQG_WEIGHTS)
    pd = afs.classical_controller(SYSTEM_3.gain, SYSTEM_3.kp, SYSTEM_3.kd, 0.0)
    designs = {n: _design(fam, n, K, check, margins=n != "pd") for n, K in
               (("classical", classical), ("lqg", lqg), ("pd", pd))}
    pk_speed, pk_f = _pk(fam)
    return AfsStudy(fam, ol, pk_speed, pk_f, check, designs,
                    _digital(fam, LQG_DESIGN_FACTOR * ol.speed, check))


def _digital(fam, design_speed, check_speed) -> DigitalDesign:
    ts = THESIS_SAMPLE
    K = afs.discrete_lqg_controller(fam.model(design_speed), ts, *DLQG_WEIGHTS)
    b = afs.stability_boundary(lambda u: afs.sampled_closed_loop_matrix(fam.model(u), K, ts, 1),
                               GRID, tol=TOL, sample_time=ts)
    m = fam.model(check_speed)

    def scaled(k):
        Kk = ct.ss(K.A, K.B, k * np.array(K.C), k * np.array(K.D), ts,
                   inputs=list(K.input_labels))
        return afs.sampled_closed_loop_matrix(m, Kk, ts, 1)

    gm = afs.sampled_gain_margins(scaled, tol=1e-4)
    pm = afs.sampled_phase_margin(afs.sampled_loop_at_input(m, K, ts, 1))
    sim = afs.simulate_release_sampled(m, K, ts, 1, root_twist=RELEASE_TWIST, t_final=0.1)
    quant = afs.simulate_release_sampled(m, K, ts, 1, root_twist=RELEASE_TWIST, t_final=0.5,
                                         quantisers=QUANTISERS)
    sensed = afs.simulate_release_sampled(m, K, ts, 1, root_twist=RELEASE_TWIST, t_final=0.5,
                                          sensors=SENSORS)
    return DigitalDesign(K, b, gm, pm, sim, quant, sensed)


def _gain(study: AfsStudy, d: AfsDesign):
    return None if d.boundary.speed is None else 100 * (d.boundary.speed / study.open_loop.speed
                                                        - 1)


def quantities(study: AfsStudy) -> list[Quantity]:
    """The ``ase.afs.*`` rows."""
    ol, c, lq, pd = (study.open_loop, study.designs["classical"], study.designs["lqg"],
                     study.designs["pd"])
    where = f"at {study.check_speed:.1f} m/s ({CHECK_FACTOR:g} x open loop), loop broken at " \
            "the actuator input, Nyquist"
    rel = f"{RELEASE_TWIST * 180 / math.pi:g} deg root-twist release at {study.check_speed:.1f}" \
          " m/s, 24 V / 10 A clip"
    pk = "n/a" if study.pk_speed is None else f"{study.pk_speed:.1f}"
    q = [Quantity("ase.afs.open_loop_flutter_ms", ol.speed, "m/s",
                  f"actuator locked, Roger fit, M 0.5 sea level, {ol.frequency_hz:.1f} Hz; "
                  f"p-k of the same fin {pk} m/s (tabulated GAFs)"),
         Quantity("ase.afs.pk_flutter_ms", study.pk_speed, "m/s",
                  "p-k, same fin, Mach and density (rigid pitch held)"),
         Quantity("ase.afs.pd_only_flutter_ms", pd.boundary.speed, "m/s",
                  "System 3 PD on the transmission angle alone (actuator free, not locked)")]
    for key, d, what in (("", c, "System 3 PD + fin-root rate through a 300 Hz low-pass"),
                         ("lqg.", lq, f"LQG designed at {LQG_DESIGN_FACTOR:g} x open loop")):
        gain = _gain(study, d)
        q += [Quantity(f"ase.afs.{key}closed_loop_flutter_ms", d.boundary.speed, "m/s",
                       f"{what}; +{gain:.1f} % over the open loop" if gain is not None
                       else what),
              Quantity(f"ase.afs.{key}gain_margin_db", d.gain_margin_db, "dB",
                       f"min(|lower|, upper) {where}"),
              Quantity(f"ase.afs.{key}phase_margin_deg", float(d.margins.phase_margin_deg),
                       "deg", where),
              Quantity(f"ase.afs.{key}peak_voltage_v", float(np.max(np.abs(d.release.voltage))),
                       "V", rel + ("; demand clipped" if d.release.saturated else "")),
              Quantity(f"ase.afs.{key}peak_current_a", float(np.max(np.abs(d.release.current))),
                       "A", rel),
              Quantity(f"ase.afs.{key}sampled_5khz_flutter_ms", d.sampled_fast.speed, "m/s",
                       "controller at 5 kHz (Tustin), one sample of delay"
                       + ("; unstable at the first airspeed" if d.sampled_fast.at_first_point
                          else "")),
              Quantity(f"ase.afs.{key}stable_at_1khz", d.stable_thesis_rate, "-",
                       f"at {study.check_speed:.1f} m/s, 1 kHz with one sample of delay (the "
                       "thesis's processor)" + ("" if d.stable_thesis_rate else
                                                ": the continuous design does not survive it"))]
    q += _digital_rows(study)
    return q


def _digital_rows(study: AfsStudy) -> list[Quantity]:
    d = study.digital
    gain = _gain(study, d)
    at = f"at {study.check_speed:.1f} m/s, 1 kHz with one sample of delay"
    r = d.release
    rel = f"{math.degrees(RELEASE_TWIST):g} deg root-twist release {at}, 24 V / 10 A clip"
    return [Quantity("ase.afs.dlqg_1khz.closed_loop_flutter_ms", d.boundary.speed, "m/s",
                     f"discrete LQG on the 1 kHz ZOH plant with its delay, designed at "
                     f"{LQG_DESIGN_FACTOR:g} x open loop"
                     + (f"; +{gain:.1f} % over the open loop" if gain is not None else "")),
            Quantity("ase.afs.dlqg_1khz.gain_margin_db", d.gain_margin_db, "dB",
                     f"min(|lower|, upper) {at}, from the eigenvalues with the gain scaled"),
            Quantity("ase.afs.dlqg_1khz.phase_margin_deg", d.phase_margin_deg, "deg",
                     f"{at}, loop broken at the actuator input, unit circle"),
            Quantity("ase.afs.dlqg_1khz.peak_voltage_v", float(np.max(np.abs(r.voltage))), "V",
                     rel + ("; demand clipped" if r.saturated else "")),
            Quantity("ase.afs.dlqg_1khz.peak_current_a", float(np.max(np.abs(r.current))), "A",
                     rel)] + _quantised_rows(study) + _sensed_rows(study)


def _sensed_rows(study: AfsStudy) -> list[Quantity]:
    r = study.digital.sensed
    last = r.t >= r.t[-1] - 0.1
    what = (f"{SENSORS.bandwidth:g} Hz first-order sensors, {SENSORS.noise_rms:g} rad RMS "
            f"white noise (seed {SENSORS.seed}); 0.5 s release at {study.check_speed:.1f} m/s, "
            "1 kHz, one sample of delay, 24 V / 10 A clip")
    res = "last 0.1 s (the ideal loop decays to rest); " + what
    return [Quantity("ase.afs.dlqg_1khz.sensed_peak_voltage_v", float(np.max(np.abs(r.voltage))),
                     "V", what + ("; demand clipped" if r.saturated else "")),
            Quantity("ase.afs.dlqg_1khz.sensed_peak_current_a", float(np.max(np.abs(r.current))),
                     "A", what),
            Quantity("ase.afs.dlqg_1khz.sensed_residual_rms_deg",
                     math.degrees(float(np.sqrt(np.mean(r.fin_root[last] ** 2)))), "deg",
                     "RMS fin-root pitch, " + res),
            Quantity("ase.afs.dlqg_1khz.sensed_residual_voltage_rms_v",
                     float(np.sqrt(np.mean(r.voltage[last] ** 2))), "V", "RMS voltage, " + res)]


def _quantised_rows(study: AfsStudy) -> list[Quantity]:
    r = study.digital.quantised
    amp, _ = limit_cycle(r.t, r.fin_root, window=0.1)
    last = r.t >= r.t[-1] - 0.1
    quantum = 2 * QUANTISERS.adc_range / 2 ** QUANTISERS.adc_bits
    what = ("2000-count motor encoder, 12-bit ADC (+-pi) and DAC (+-24 V); last 0.1 s of a 0.5 s "
            f"release at {study.check_speed:.1f} m/s (the ideal loop decays to rest); the "
            "oscillation is irregular, so its amplitude moves with the window and the speed "
            "(0.04-0.09 deg, 2.8-5.3 V between 1.0 and 1.1 x open loop, 0.5 and 1 s)")
    return [Quantity("ase.afs.dlqg_1khz.quantised_lco_amplitude_deg", math.degrees(amp), "deg",
                     f"half peak-to-peak fin-root pitch, {amp / quantum:.2f} ADC steps; " + what),
            Quantity("ase.afs.dlqg_1khz.quantised_peak_voltage_v",
                     float(np.max(np.abs(r.voltage[last]))), "V", what)]


@small_dense
def fig_root_locus(study: AfsStudy, velocities=None):
    """Eigenvalues of the locked fin and of the classical and LQG closed loops against airspeed
    (the flutter branch crossing into the right half plane), in Hz against 1/s."""
    U = np.linspace(150.0, 330.0, 19) if velocities is None else np.asarray(velocities)
    fig, ax = new_figure(f"Root locus over {U[0]:.0f}-{U[-1]:.0f} m/s, M 0.5 sea level")
    sets = [("locked fin (open loop)", lambda u: afs.locked_matrix(study.family, u))]
    for n in ("classical", "lqg"):
        K = study.designs[n].controller
        sets.append((f"{n} AFS", lambda u, K=K: afs.closed_loop_matrix(study.family.model(u), K)))
    for (label, A_of), mk in zip(sets, ("o", "s", "^")):
        lam = np.concatenate([np.linalg.eigvals(A_of(u)) for u in U])
        keep = (lam.imag > 2 * math.pi * 50) & (lam.imag < 2 * math.pi * 250)
        ax.scatter(lam.real[keep], lam.imag[keep] / (2 * math.pi), s=8, marker=mk, label=label)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlim(-400, 200)
    ax.set_xlabel("real part (1/s)")
    ax.set_ylabel("frequency (Hz)")
    ax.legend()
    return fig
