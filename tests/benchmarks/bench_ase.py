"""Benchmark (run on demand): `python tests/benchmarks/bench_ase.py`.

Issue targets: one power-limited 0.2 s closed-loop simulation of AEM1 in a few seconds at most;
a linear one in well under a second. Prints the best of three wall-clock times.
"""

import math
import time

import control as ct
import numpy as np

from asekit.ase import loop as ase
from asekit.aeroelastic.statespace import fin_outputs
from asekit.atmosphere import standard_atmosphere
from asekit.case import load_case, pipeline
from asekit.util.paths import FIN_FILE
from asekit.rfa import roger_fit
from asekit.servo.actuator import SYSTEM_3


def fin_ase_model(mach: float = 0.5, altitude: float = 0.0):
    """The fin's Ch. 5 model at (mach, altitude) from its case, as asekit.case.pipeline.ase builds
    it (without its step simulations): Roger fit with 4 lags, 1976 atmosphere, U = M a, the
    fin-root pitch and corner outputs."""
    case = load_case(FIN_FILE)
    modal, db = pipeline.modal_model(case), pipeline.gaf_database(case, progress=False)
    g = db.at(mach, interpolate=True)
    k, q = g.k, g.Q
    rfa = roger_fit(k, q, db.b_ref, n_lags=4, mach=mach)
    atm = standard_atmosphere(altitude)
    corners = pipeline.corner_points(case)
    rows = fin_outputs(modal, np.array(list(corners.values())), names=list(corners),
                       shaft_point=case.support.axis_point)
    return ase.build_model(modal, rfa, float(atm.density), mach * float(atm.speed_of_sound),
                           rows, actuator=pipeline.actuator_setup(case)[0], mach=mach)


def best_of(fn, n=3):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    t0 = time.perf_counter()
    model = fin_ase_model(mach=0.5, altitude=0.0)
    print(f"model build (GAF cache load, RFA, interconnect data): {time.perf_counter() - t0:.3f} s")
    cmd = math.radians(1.0)
    t_nl = best_of(lambda: ase.simulate_closed_loop(model, SYSTEM_3, cmd, "AEM1",
                                                    t_final=0.2))
    t_rk = best_of(lambda: ase.simulate_closed_loop(model, SYSTEM_3, cmd, "AEM1",
                                                    t_final=0.2, method="RK45"))
    print(f"AEM1 power-limited 0.2 s (solve_ivp RK45, method='RK45'): {t_rk:.3f} s")
    print(f"AEM1 power-limited 0.2 s (exact piecewise-linear, {model.A.shape[0] + 3} states): "
          f"{t_nl:.3f} s   (target: a few seconds)")

    def linear():
        cl = ase.closed_loop(model, SYSTEM_3, "AEM1", outputs=["theta", ase.FIN_ROOT])
        t = np.linspace(0.0, 0.2, 4001)
        ct.forced_response(cl, t, np.full(t.size, cmd))

    t_lin = best_of(linear)
    print(f"AEM1 linear 0.2 s (interconnect + forced_response): {t_lin:.3f} s   "
          f"(target: well under 1 s)")
    t_bode = best_of(lambda: ase.crossovers(ase.forward_path(model, SYSTEM_3, 3)))
    print(f"FWTF 3 with all crossovers (20000 frequencies): {t_bode:.3f} s")


if __name__ == "__main__":
    main()
