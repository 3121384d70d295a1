"""Speed of the supersonic lifting-surface method and of piston theory on the fin's box mesh,
against the DLM on the same boxes.

Run on demand (not collected by pytest):

    python tests/benchmarks/bench_supersonic.py [--repeat 3] [--k 0.5]

Times (best of ``--repeat``) at one reduced frequency on the fin's default box mesh
(``asekit.case.pipeline.box_mesh`` of the fin's case, 140 boxes):

- the DLM: the normalwash matrix D(M 0.75, k) and the AIC = D^-1;
- the supersonic method: the full pressure-per-normalwash matrix A(M, k) (140 grid solves,
  one per box) at M 1.2, 2 and 3, and the six modal columns the GAF builder actually needs
  (:func:`asekit.aero.supersonic.supersonic_pressures`, one grid solve per mode);
- piston theory: its matrix (a banded transfer, no solve).

Measured on the 2-core project machine (shared with other jobs, loaded: repeated runs vary by
up to 2x), k 0.5, best of 5, default grid (1.5 cells per mean box chord, Mach boxes
dx = beta dy), run of 2026-12-01 22:49 UTC:

    case                                              s      x DLM AIC
    DLM D (M 0.75)                                  0.0120     0.88
    DLM AIC (M 0.75)                                0.0136     1.00
    supersonic matrix M 1.2 (463 + 368 cells)       0.0193     1.42
    supersonic matrix M 2 (1125 + 302 cells)        0.0197     1.46
    supersonic matrix M 3 (1732 + 293 cells)        0.0244     1.80
    DLM 6 mode columns M 0.75 (GAF path)            0.0078     0.57
    supersonic 6 mode columns M 2 (GAF path)        0.0101     0.74
    piston matrix M 3                               0.0006     0.04

(wing + diaphragm cells in brackets.) The issue's target, the supersonic AIC within 3x the
DLM's time for the same boxes, is met at M 1.2-3 (1.4-1.8x). Before the direct-summation
matrix path (the full matrix was one FFT grid solve per box: 140 pairs of 2-D FFTs over the
padded Mach-box grid) the same bench gave 3.6x (M 1.2), 7.2x (M 2) and 6.4x (M 3) the DLM
(22:38 UTC, best of 3); old and new side by side in one process (22:49 UTC, best of 5):
M 1.2 0.067 -> 0.015 s, M 2 0.164 -> 0.026 s, M 3 0.118 -> 0.021 s (4.4-6.4x faster; DLM AIC
0.014 s). The new matrix path: one nx x ny kernel table per k, gathered into sparse influence
matrices over the cell pairs inside each other's Mach cone (their index pattern built once per
grid), sparse transfers, grid cells located per box instead of all cells against all boxes.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))

import numpy as np  # noqa: E402

from asekit.aero.dlm import aic_matrix, normalwash_matrix  # noqa: E402
from asekit.aero.gaf import gaf_from_box_modes  # noqa: E402
from asekit.aero.piston import piston_pressure_matrix  # noqa: E402
from asekit.aero.spline import fe_spline  # noqa: E402
from asekit.aero.supersonic import mach_grid, supersonic_pressure_matrix  # noqa: E402
from asekit.case import load_case, pipeline  # noqa: E402
from asekit.util.paths import FIN_FILE  # noqa: E402


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--k", type=float, default=0.5)
    args = ap.parse_args(argv)
    fin = load_case(FIN_FILE)
    mesh = pipeline.box_mesh(fin)
    b, k, r = 0.078, args.k, args.repeat
    bm = fe_spline(pipeline.modal_model(fin), mesh)
    rows = [("DLM D (M 0.75)", best(lambda: normalwash_matrix(mesh, 0.75, k, b), r))]
    t_aic = best(lambda: aic_matrix(mesh, 0.75, k, b), r)
    rows.append(("DLM AIC (M 0.75)", t_aic))
    for mach in (1.2, 2.0, 3.0):
        g = mach_grid(mesh, mach, k, b)
        rows.append((f"supersonic matrix M {mach:g} ({g.wing_i.size} + {g.dia_i.size} cells)",
                     best(lambda: supersonic_pressure_matrix(mesh, mach, k, b), r)))
    rows.append((f"DLM {bm.h_cp.shape[1]} mode columns M 0.75 (GAF path)",
                 best(lambda: gaf_from_box_modes(bm, mesh, 0.75, [k], b), r)))
    rows.append((f"supersonic {bm.h_cp.shape[1]} mode columns M 2 (GAF path)",
                 best(lambda: gaf_from_box_modes(bm, mesh, 2.0, [k], b, method="supersonic"), r)))
    rows.append(("piston matrix M 3", best(lambda: piston_pressure_matrix(mesh, 3.0, k, b,
                                                                          warn=False), r)))
    print(f"fin box mesh: {mesh.n} boxes, k = {k:g}, best of {r}")
    print(f"{'case':52s} {'s':>8s} {'x DLM AIC':>10s}")
    for name, t in rows:
        print(f"{name:52s} {t:8.4f} {t / t_aic:10.2f}")
    assert np.isfinite(t_aic)


if __name__ == "__main__":
    main()
