"""Cost of the transonic small-disturbance method (issue 29: "a benchmark: the AGARD wing's
steady solution and 15 reduced frequencies for 4 modes in under 10 min on this 2-core machine
(state the grid)"). Run on demand (not collected by pytest):

    python tests/benchmarks/bench_tsd.py [--boxes 8 10] [--mach 0.96]

For each box count n (n x n boxes on the AGARD 445.6 weakened-wing-3 planform of
``data/cases/agard445_6_tsd.toml``, 4 modes, its 4 % biconvex section), in a fresh cache
directory:

1. the steady TSD background (:func:`asekit.aero.tsd3d.tsd_background`: Newton iterations on
   the modified TSD equation with the cross-flow terms), and
2. the GAF database over 15 reduced frequencies k = 0.001 ... 0.6 (the case pipeline's
   :func:`asekit.case.pipeline.gaf_database`: one sparse LU of the time-linearised operator
   per k, all box right-hand sides at once),

timed in CPU seconds (``time.process_time``; one BLAS thread) and wall seconds, with the grid
(cells and nodes) and the process's peak resident memory (``ru_maxrss``) printed.

Measured on the 2-core project machine, run of 2026-12-04 03:30-03:53 UTC, shared with six
other jobs (load average 6-9, so wall times are 3x the CPU times; on an idle machine wall is
close to CPU):

    boxes    cells   nodes  steady s CPU/wall  15-k GAFs s CPU/wall  peak MB
    8 x 8   16 x 8   17784      6.8 / 20.4        197.0 / 588.9          838
   10 x 10  20 x 10   24360     20.5 / 59.5        455.7 / 1533.1        1179

The issue's target (steady solution + 15 k x 4 modes under 10 min) is met in CPU on both
grids (204 s and 476 s); the shipped case's grid (8 x 8 boxes) also in wall time under this
load. The GAFs dominate: one sparse LU of the time-linearised operator per k (13 s per k on
17,784 nodes, 30 s on 24,360), so time grows about as nodes^2.6 between the two grids. (The
12 x 12-box grid, 33,396 nodes, 6 k through ``asekit analyse``: 376 s CPU, 2.1 GB.)
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from dataclasses import replace

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

import numpy as np  # noqa: E402

from asekit.aero.tsd3d import (  # noqa: E402
    grid_nodes,
    mesh_grid_options,
    planform_of_boxes,
    tsd_background,
)
from asekit.case import load_case, pipeline  # noqa: E402
from asekit.case.variants import with_boxes  # noqa: E402
from asekit.util.paths import CASES_DIR  # noqa: E402

K15 = (0.001, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.6)


def run(n: int, mach: float) -> dict:
    case = with_boxes(load_case(CASES_DIR / "agard445_6_tsd.toml"), n, n)
    case = replace(case, aero=replace(case.aero, machs=(float(mach),), reduced_frequencies=K15))
    mesh = pipeline.box_mesh(case)
    opts = mesh_grid_options(mesh)
    nodes = grid_nodes(planform_of_boxes(mesh), dict(opts, edges="faces"))
    pipeline.modal_model(case)                                     # the structure: not timed
    t0, w0 = time.process_time(), time.perf_counter()
    bg = tsd_background(mesh, mach, case.aero.section[1])
    t1, w1 = time.process_time(), time.perf_counter()
    db = pipeline.gaf_database(case, progress=False)
    t2, w2 = time.process_time(), time.perf_counter()
    return dict(n=n, cells=(opts["n_chord"], opts["n_span"]), nodes=nodes,
                steady_cpu=t1 - t0, steady_wall=w1 - w0, gaf_cpu=t2 - t1, gaf_wall=w2 - w1,
                converged=bool(bg.converged), q_norm=float(np.abs(db.Q).sum()),
                rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--boxes", type=int, nargs="+", default=[8, 10])
    ap.add_argument("--mach", type=float, default=0.96)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as cache:
        os.environ["ASEKIT_CACHE_DIR"] = cache
        print(f"AGARD 445.6 weakened wing 3, M {args.mach:g}, 4 modes, 15 k, 4 % biconvex")
        print(f"{'boxes':>7} {'cells':>8} {'nodes':>7} {'steady s CPU/wall':>18} "
              f"{'15-k GAFs s CPU/wall':>21} {'peak MB':>8}")
        for n in args.boxes:
            r = run(n, args.mach)
            print(f"{n:>3} x {n:<2} {r['cells'][0]:>3} x {r['cells'][1]:<3} {r['nodes']:>7} "
                  f"{r['steady_cpu']:>8.1f} / {r['steady_wall']:<7.1f} "
                  f"{r['gaf_cpu']:>9.1f} / {r['gaf_wall']:<9.1f} {r['rss_mb']:>8.0f}"
                  f"{'' if r['converged'] else '  (steady NOT converged)'}")


if __name__ == "__main__":
    main()
