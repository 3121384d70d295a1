"""The p-k sweeps of the supersonic envelope (issue 23: "p-k batched"), run on demand:
``python tests/benchmarks/bench_pk_batched.py``.

Times the 33 p-k sweeps (11 Machs x 3 altitudes, 151 airspeeds 100-1600 m/s: the grid of the
thesis reproduction's supersonic chapter) on the fin's modal model, from GAFs built first by the
case pipeline's aerodynamics (method "auto", not timed), in CPU seconds (``time.process_time``, one BLAS thread as
the solver runs) and in wall seconds, and counts the eigenproblems solved. Each sweep is
:func:`~asekit.aeroelastic.flutter.pk_flutter` then
:func:`~asekit.aeroelastic.flutter.pk_instabilities` (the first flutter), run two ways: sweep by
sweep, and all 33 together by :func:`~asekit.aeroelastic.flutter.pk_flutter_many`. Prints a
checksum of the flutter speeds (identical both ways, checked) so that two commits can be
compared for identical results.

Measured on the project's 2-core machine (shared with other jobs), one BLAS thread:

==========================================  ==========  ============  ===============
version                                     CPU (s)     LAPACK calls  eigenproblems
==========================================  ==========  ============  ===============
per root (before a555367)                   --          75727         75727
a555367, one airspeed batched (per sweep)   8.22        17211         68967
this commit, sweep by sweep                 see below   17211         68967
this commit, 33 sweeps batched              see below   see below     68967
==========================================  ==========  ============  ===============
"""

import time
import warnings

import numpy as np

from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import fe_spline
from asekit.aeroelastic import flutter as F
from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    first_of,
    pk_flutter,
    pk_flutter_many,
    pk_instabilities,
    pk_instabilities_many,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case import load_case, pipeline
from asekit.util.paths import FIN_FILE

MACHS = (0.4, 0.5, 0.6, 0.75, 0.9, 1.15, 1.2, 1.5, 2.0, 2.5, 3.0)
ALTITUDES = (0.0, 2500.0, 5000.0)
VELOCITIES = np.arange(100.0, 1600.0 + 1e-9, 10.0)     # m/s


def _counting():
    """Count the stacked eigen calls and the eigenproblems of the p-k solver."""
    calls = {"eig": 0, "matrices": 0}
    orig = F._PkStack.eig_rows

    def counted(self, lanes, U, ks):
        calls["eig"] += 1
        calls["matrices"] += np.size(ks)
        return orig(self, lanes, U, ks)

    F._PkStack.eig_rows = counted
    return calls, orig


def _first_flutter(res, model, gaf):
    fl = first_of(pk_instabilities(res, model, gaf), "flutter")
    return np.nan if fl is None else fl.speed


def _lapack_floor(n, count=67600, batch=130):
    """CPU seconds of ``count`` LAPACK eigenproblems of the p-k size (2n x 2n, n elastic
    modes) in stacks of ``batch`` on one BLAS thread: what no batching removes while every
    k-iteration solves a full eigenproblem."""
    from threadpoolctl import threadpool_limits

    A = np.random.default_rng(0).normal(size=(batch, 2 * n, 2 * n))
    with threadpool_limits(limits=1, user_api="blas"):
        t = time.process_time()
        for _ in range(count // batch):
            np.linalg.eig(A)
        t = time.process_time() - t
    print(f"LAPACK floor: {count} eigenproblems {2 * n}x{2 * n} in stacks of {batch}: "
          f"{t:.2f} s CPU")
    return t


def _timed(label, run):
    calls, orig = _counting()
    t_cpu, t_wall = time.process_time(), time.perf_counter()
    try:
        speeds = run()
    finally:
        F._PkStack.eig_rows = orig
    t_cpu, t_wall = time.process_time() - t_cpu, time.perf_counter() - t_wall
    print(f"{label}: {t_cpu:.2f} s CPU, {t_wall:.2f} s wall; {calls['eig']} eigen calls "
          f"({calls['matrices']} eigenproblems)")
    return np.array(speeds), t_cpu


def main():
    case = load_case(FIN_FILE)
    model, boxes = pipeline.modal_model(case), pipeline.box_mesh(case)
    ks, b_ref = pipeline.reduced_frequencies(case), case.aero.reference_semichord
    bm = fe_spline(model, boxes)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")              # the coarse-mesh warnings of the GAFs
        Q = [gaf_from_box_modes(bm, boxes, m, ks, b_ref, method="auto") for m in MACHS]
    gafs = [TabulatedGaf(ks, Q[im], b_ref, mach=mach) for im, mach in enumerate(MACHS)]
    rhos = [float(standard_atmosphere(h).density) for h in ALTITUDES]
    conditions = [(g, rho) for g in gafs for rho in rhos]

    def one_by_one():
        return [_first_flutter(pk_flutter(model, g, rho, VELOCITIES), model, g)
                for g, rho in conditions]

    def batched():
        results = pk_flutter_many(model, conditions, VELOCITIES)
        found = pk_instabilities_many(results, model, [g for g, _ in conditions])
        return [np.nan if fl is None else fl.speed
                for fl in (first_of(f, "flutter") for f in found)]

    def batched_solve_only():
        pk_flutter_many(model, conditions, VELOCITIES)
        return []

    floor = _lapack_floor(len(model.frequencies_hz) - 1)
    s1, t1 = _timed("33 p-k sweeps, sweep by sweep", one_by_one)
    s2, t2 = _timed("33 p-k sweeps, batched (pk_flutter_many)", batched)
    _timed("  of which pk_flutter_many alone", batched_solve_only)
    same = np.array_equal(s1, s2, equal_nan=True)
    print(f"speed-up {t1 / t2:.2f}x (at most {t1 / floor:.2f}x while the eigenproblems stay "
          f"full LAPACK ones); batched speeds identical to sweep by sweep: {same}")
    print("flutter speeds (m/s):", np.round(s2, 6).tolist())
    if not same:
        raise SystemExit("the batched flutter speeds differ from the sweep-by-sweep ones")


if __name__ == "__main__":
    main()
