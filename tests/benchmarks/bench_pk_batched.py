"""The p-k sweeps of the supersonic envelope (issue 23: "p-k batched"), run on demand:
``python tests/benchmarks/bench_pk_batched.py``.

Times the 33 p-k sweeps (11 Machs x 3 altitudes, 151 airspeeds 100-1600 m/s: the grid of the
thesis reproduction's supersonic chapter) on the fin's modal model, from GAFs built first by the
case pipeline's aerodynamics (method "auto", not timed), in CPU seconds (``time.process_time``, one BLAS thread as
the solver runs) and in wall seconds, and counts the eigenproblems solved. Prints a checksum of
the flutter speeds so that two commits can be compared for identical results.
"""

import time

import numpy as np

from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    _PkProblem,
    first_of,
    pk_flutter,
    pk_instabilities,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case import load_case, pipeline
from asekit.util.paths import FIN_FILE

MACHS = (0.4, 0.5, 0.6, 0.75, 0.9, 1.15, 1.2, 1.5, 2.0, 2.5, 3.0)
ALTITUDES = (0.0, 2500.0, 5000.0)
VELOCITIES = np.arange(100.0, 1600.0 + 1e-9, 10.0)     # m/s


def main():
    case = load_case(FIN_FILE)
    model, boxes = pipeline.modal_model(case), pipeline.box_mesh(case)
    ks, b_ref = pipeline.reduced_frequencies(case), case.aero.reference_semichord
    bm = fe_spline(model, boxes)
    Q = [gaf_from_box_modes(bm, boxes, m, ks, b_ref, method="auto") for m in MACHS]
    calls = {"eig": 0, "matrices": 0}
    orig = _PkProblem.eig_batch if hasattr(_PkProblem, "eig_batch") else _PkProblem.eig

    def counted(self, U, k):
        calls["eig"] += 1
        calls["matrices"] += np.size(k)
        return orig(self, U, k)

    setattr(_PkProblem, orig.__name__, counted)
    speeds = []
    t_cpu, t_wall = time.process_time(), time.perf_counter()
    for im, mach in enumerate(MACHS):
        gaf = TabulatedGaf(ks, Q[im], b_ref, mach=mach)
        for h in ALTITUDES:
            rho = float(standard_atmosphere(h).density)
            res = pk_flutter(model, gaf, rho, VELOCITIES)
            fl = first_of(pk_instabilities(res, model, gaf), "flutter")
            speeds.append(np.nan if fl is None else fl.speed)
    t_cpu, t_wall = time.process_time() - t_cpu, time.perf_counter() - t_wall
    setattr(_PkProblem, orig.__name__, orig)
    print(f"33 p-k sweeps: {t_cpu:.2f} s CPU, {t_wall:.2f} s wall; {calls['eig']} eigen calls "
          f"({calls['matrices']} eigenproblems)")
    print("flutter speeds (m/s):", np.round(speeds, 6).tolist())


if __name__ == "__main__":
    main()
