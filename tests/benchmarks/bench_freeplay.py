"""Benchmark (run on demand): `python tests/benchmarks/bench_freeplay.py`.

Issue 14 targets: a describing-function LCO curve (40 airspeeds) in under 5 s; one 1 s
time-domain LCO simulation in under 10 s. Prints the best of three wall-clock times and the
machine load (the machine is shared; CPU time is printed too).

Measured 2026-12-01 (load average 3.6 on 2 cores; wall / CPU): fin-alone DF curve 0.51 / 0.34 s,
AEM1 0.63 / 0.42 s, fin biased DF 1.72 / 1.14 s, Conner DF curve 0.14 / 0.09 s, Conner
multi-harmonic balance (11 harmonics, 40 speeds) 3.35 / 2.23 s; 1 s time domain: fin (exact,
20000 steps) 0.50 / 0.34 s, Conner with solve_ivp events 0.12 / 0.08 s, Conner exact 0.012 s.
"""

import math
import os
import time

import numpy as np

from asekit.aeroelastic.nonlinear import (Connection, biased_harmonic_balance, lco_curve,
                              multi_harmonic_balance, simulate, simulate_exact,
                              steady_oscillation)
from asekit.reproduction.flutter import load_fin_gafs
from asekit.reproduction.freeplay import fin_freeplay_model
from asekit.aeroelastic.typical_section import (CONNER_FREEPLAY_HALF_WIDTH_DEG, conner_1997,
                                    connected_system)


def best_of(fn, n=3):
    wall, cpu = [], []
    for _ in range(n):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return min(wall), min(cpu), out


def main():
    print(f"load average: {os.getloadavg()}")
    data, reason = load_fin_gafs()
    if data is None:
        raise SystemExit(reason)
    model = fin_freeplay_model(0.5, data)
    rho = 1.225
    dl = math.radians(0.1)
    conn = Connection(model.k_s, freeplay=dl)
    speeds = np.linspace(150.0, 300.0, 40)

    w, c, _ = best_of(lambda: lco_curve(lambda u: model.fin_alone(rho, u), speeds, conn))
    print(f"fin alone, symmetric DF LCO curve, 40 airspeeds ({model.fin_alone(rho, 200.0).n_states}"
          f" states): {w:.3f} s wall, {c:.3f} s CPU   (target < 5 s)")
    w, c, _ = best_of(lambda: lco_curve(lambda u: model.aem1(rho, u), speeds, conn))
    print(f"AEM1, symmetric DF LCO curve, 40 airspeeds: {w:.3f} s wall, {c:.3f} s CPU")
    w, c, _ = best_of(lambda: [biased_harmonic_balance(model.fin_alone(rho, u), conn,
                                                       amplitudes=dl * np.geomspace(0.01, 30, 40))
                               for u in speeds], n=1)
    print(f"fin alone, biased (dual-input) DF LCO curve, 40 airspeeds: {w:.3f} s wall, "
          f"{c:.3f} s CPU")
    sec = conner_1997()
    cc = Connection(sec.stiffness_beta, freeplay=math.radians(CONNER_FREEPLAY_HALF_WIDTH_DEG))
    cspeeds = np.linspace(5, 23.5, 40)
    w, c, curve = best_of(lambda: lco_curve(lambda u: connected_system(sec, u), cspeeds, cc))
    print(f"Conner section, DF LCO curve, 40 airspeeds: {w:.3f} s wall, {c:.3f} s CPU   "
          "(target < 5 s)")

    def mhb_curve():
        out = []
        for u, r in zip(cspeeds, curve.results):
            st = r.largest_stable()
            if st is not None:
                out.append(multi_harmonic_balance(connected_system(sec, u), cc, st.amplitude,
                                                  st.frequency_hz, n_harmonics=11))
        return out
    w, c, mh = best_of(mhb_curve)
    print(f"Conner section, multi-harmonic balance (11 harmonics, Floquet stability) at the "
          f"{len(mh)} speeds with a stable DF LCO: {w:.3f} s wall, {c:.3f} s CPU "
          f"(plus the DF curve it starts from)")

    # one 1 s time-domain LCO simulation of the fin just above the LCO onset (210 m/s)
    s = model.fin_alone(rho, 210.0)
    x0 = np.zeros(s.n_states)
    x0[0] = 1.33 * dl
    w, c, sim = best_of(lambda: simulate_exact(s, conn, x0, 1.0, step=5e-5))
    td = steady_oscillation(sim.t, sim.d, n_cycles=30, rel_tol=0.02)
    print(f"fin alone 1 s LCO, exact piecewise integration (20000 steps, "
          f"{sim.switch_times.size} switches): {w:.3f} s wall, {c:.3f} s CPU   (target < 10 s); "
          f"{td.message}")
    w, c, sim = best_of(lambda: simulate(s, conn, x0, 0.05, n_out=1001, method="DOP853",
                                         rtol=1e-8, atol=1e-13), n=1)
    print(f"fin alone 0.05 s with solve_ivp events (DOP853): {w:.3f} s wall, {c:.3f} s CPU "
          f"(x 20 for 1 s: too slow on the stiff Ritz model, hence simulate_exact)")
    sc = connected_system(sec, 20.0)
    x0 = np.zeros(8)
    x0[2] = 3 * cc.freeplay
    w, c, _ = best_of(lambda: simulate(sc, cc, x0, 1.0, n_out=2001))
    print(f"Conner section 1 s with solve_ivp events (RK45): {w:.3f} s wall, {c:.3f} s CPU   "
          "(target < 10 s)")
    w, c, _ = best_of(lambda: simulate_exact(sc, cc, x0, 1.0, step=1e-3))
    print(f"Conner section 1 s, exact piecewise integration (1 ms output): {w:.3f} s wall, "
          f"{c:.3f} s CPU")


if __name__ == "__main__":
    main()
