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

Measured (issue 23) on the project's 2-core machine, shared with five other engineers' jobs
(load average 7-10, so every CPU figure is inflated by contention; compare ratios within one
run), one BLAS thread, the fin's 6 modes (5 elastic: 10 x 10 first-order eigenproblems).
"before" is ec4989b (a555367's per-sweep batching: every tracked root of one sweep at one
airspeed in one eig), run from a copy of that commit in the same session:

=============================================  =========  ==========  ===============
run (same session, back to back)               before     batched     ratio (CPU)
=============================================  =========  ==========  ===============
33 sweeps + first flutter, CPU s               10.19      4.26        2.39x
the same, wall s                               17.32      8.56        2.02x
eigen calls (eigenproblems)                    17211      851         (68967 both)
LAPACK floor: 67600 eig 10x10 alone, CPU s     --         3.34        --
=============================================  =========  ==========  ===============

Other runs: before 8.99 / 9.45 s CPU vs batched 3.70 / 3.60 s (2.4-2.6x); before 11.38 s vs
4.22 s (2.7x, floor 3.28 s). The flutter speeds are identical (the printed checksum) before and
after. The 5x goal is out of reach while every k-iteration solves a full LAPACK eigenproblem:
the eigenproblems alone (the "LAPACK floor" line, the same count in stacks of 130) take 3.3 s
of the 4.3 s, so no grouping of them can make the sweeps more than 10.19 / 3.34 = 3.1x faster
than before; what is left above the floor is each sweep's step control (MAC and root-identity
tests, about 0.5 s) and the crossings' refinement. Going further needs fewer or cheaper
eigenproblems (eigenvalues only inside the k-iteration, or a Newton / inverse iteration on the
one tracked root), which changes the iterates and so the results at the k-iteration's
tolerance: not done, since the results must stay those of the one-sweep solver.
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
