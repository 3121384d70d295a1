"""The p-k sweeps of the supersonic envelope (issue 23: "p-k batched"), run on demand:
``python tests/benchmarks/bench_pk_batched.py``.

Times the 33 p-k sweeps (11 Machs x 3 altitudes, 151 airspeeds 100-1600 m/s) that the
thesis reproduction's supersonic chapter solves on the fin's modal model, from the envelope's
cached GAFs (built on the first run), in CPU seconds (``time.process_time``, one BLAS thread as
the solver runs) and in wall seconds, and counts the eigenproblems solved. Prints a checksum of
the flutter speeds so that two commits can be compared for identical results.
"""

import time

import numpy as np

from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    _PkProblem,
    first_of,
    pk_flutter,
    pk_instabilities,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline
from asekit.reproduction import supersonic
from asekit.reproduction.fin import fin_case


def main():
    env = supersonic.envelope()
    model = pipeline.modal_model(fin_case())
    ks, b_ref = np.asarray(env["k"]), fin_case().aero.reference_semichord
    calls = {"eig": 0, "matrices": 0}
    orig = _PkProblem.eig_batch if hasattr(_PkProblem, "eig_batch") else _PkProblem.eig

    def counted(self, U, k):
        calls["eig"] += 1
        calls["matrices"] += np.size(k)
        return orig(self, U, k)

    setattr(_PkProblem, orig.__name__, counted)
    speeds = []
    t_cpu, t_wall = time.process_time(), time.perf_counter()
    for im, mach in enumerate(supersonic.MACHS):
        gaf = TabulatedGaf(ks, env["Q"][im], b_ref, mach=mach)
        for h in supersonic.ALTITUDES:
            rho = float(standard_atmosphere(h).density)
            res = pk_flutter(model, gaf, rho, supersonic.VELOCITIES)
            fl = first_of(pk_instabilities(res, model, gaf), "flutter")
            speeds.append(np.nan if fl is None else fl.speed)
    t_cpu, t_wall = time.process_time() - t_cpu, time.perf_counter() - t_wall
    setattr(_PkProblem, orig.__name__, orig)
    print(f"33 p-k sweeps: {t_cpu:.2f} s CPU, {t_wall:.2f} s wall; {calls['eig']} eigen calls "
          f"({calls['matrices']} eigenproblems)")
    print("flutter speeds (m/s):", np.round(speeds, 6).tolist())


if __name__ == "__main__":
    main()
