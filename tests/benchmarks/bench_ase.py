"""Benchmark (run on demand): `python tests/benchmarks/bench_ase.py`.

Issue targets: one power-limited 0.2 s closed-loop simulation of AEM1 in a few seconds at most;
a linear one in well under a second. Prints the best of three wall-clock times.
"""

import math
import time

import control as ct
import numpy as np

from asekit.ase import loop as ase
from asekit.servo.actuator import SYSTEM_3
from asekit.case import pipeline
from asekit.reproduction.fin import fin_case


def best_of(fn, n=3):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    t0 = time.perf_counter()
    fin = pipeline.ase_condition(fin_case(), mach=0.5, altitude=0.0)
    print(f"model build (GAF cache load, RFA, interconnect data): {time.perf_counter() - t0:.3f} s")
    cmd = math.radians(1.0)
    t_nl = best_of(lambda: ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1",
                                                    t_final=0.2))
    t_rk = best_of(lambda: ase.simulate_closed_loop(fin.model, SYSTEM_3, cmd, "AEM1",
                                                    t_final=0.2, method="RK45"))
    print(f"AEM1 power-limited 0.2 s (solve_ivp RK45, method='RK45'): {t_rk:.3f} s")
    print(f"AEM1 power-limited 0.2 s (exact piecewise-linear, {fin.model.A.shape[0] + 3} states): "
          f"{t_nl:.3f} s   (target: a few seconds)")

    def linear():
        cl = ase.closed_loop(fin.model, SYSTEM_3, "AEM1", outputs=["theta", ase.FIN_ROOT])
        t = np.linspace(0.0, 0.2, 4001)
        ct.forced_response(cl, t, np.full(t.size, cmd))

    t_lin = best_of(linear)
    print(f"AEM1 linear 0.2 s (interconnect + forced_response): {t_lin:.3f} s   "
          f"(target: well under 1 s)")
    t_bode = best_of(lambda: ase.crossovers(ase.forward_path(fin.model, SYSTEM_3, 3)))
    print(f"FWTF 3 with all crossovers (20000 frequencies): {t_bode:.3f} s")


if __name__ == "__main__":
    main()
