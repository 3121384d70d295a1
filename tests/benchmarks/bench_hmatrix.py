"""Dense LU against the hierarchical-matrix (ACA + GMRES) solve of the DLM, by model size.

Run on demand (not collected by pytest), once, on an otherwise idle machine:

    python tests/benchmarks/bench_hmatrix.py [--sizes 1000 2000 4000 10000] [--mach 0.8]
                                             [--k 0.5] [--modes 6] [--dense-max 10000]

For each size a swept, tapered wing (span 4 m, root chord 1 m, boxes ~ 1 : 10 chord : span
strips) is solved at one (M, k) for ``--modes`` smooth modal normalwash columns, in a fresh
subprocess with one BLAS thread: dense = D(M, k) (:func:`asekit.aero.dlm.normalwash_matrix`)
+ LU + solve; compressed = :func:`asekit.aero.hmatrix.build_hmatrix` +
:func:`asekit.aero.hmatrix.solve`. It prints CPU seconds, peak traced memory (tracemalloc sees
numpy's allocations) and, where the dense solve ran, the GAF error of the compressed solve
(max |dQ| / max |Q|), then the growth exponents between successive sizes and the crossover.
A 15-k sweep costs about 15 times one k for the compressed solve (each k is built afresh);
the dense path shares the k-independent geometry across the k of a batch.

Measured on the 2-core project machine (shared, load 2-9: CPU seconds are noisy by ~2x),
M 0.8, k 0.5, 6 modes, one BLAS thread, leaf size 160, eta 1, eps 1e-7, rtol 1e-9 (dense from
a run with the same dense code; the compressed column from a second run with
``--dense-max 0``; peak MB by tracemalloc, which does not see SuperLU's own allocations):

    boxes  dense s  dense MB    H s  (build)   H MB  compr  iters  rank  GAF err
     1000     0.45        36   2.88     2.51     49  0.774      5    35  1.1e-10 (*)
     2002     1.74        93   5.78     4.47    187  0.705      5    37  4.6e-09 (*)
     4000     9.11       368  24.66    21.12    447  0.485      6    51  3.4e-08 (*)
     8008    50.61      1471  83.52    64.01   1414  0.382      9    72  3.9e-08 (*)
    16000        -         -  264.3    206.9   3155  0.248     12    97  -

    (*) the GAF errors of the first run (leaf size 48, same eps and rtol); with the default
        leaf size 160 at 4000 boxes, a separate run: 9.6e-11 (dense 9.83 s, compressed 22.38 s)

Growth exponents, time: dense 1.95, 2.39, 2.47; compressed 1.01, 2.10, 1.76, 1.66 (memory
1.16 from 8000 to 16000). Dense at 16000 boxes is refused (one D is 4 GiB,
asekit.aero.boxes.MAX_MATRIX_BYTES); extrapolated at exponent 2.47 it would take ~280 s: the
crossover in time is near 16000 boxes; in memory the compressed solve is below dense from
8000 boxes. The build is bound by the fixed cost of each row / column evaluation (~1 ms).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

WORKER = r"""
import json, sys, time, tracemalloc
import numpy as np
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import factor_normalwash_matrix, normalwash_matrix
from asekit.aero import hmatrix as H
n, mach, k, n_modes, which = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), \
    int(sys.argv[4]), sys.argv[5]
n_chord = max(4, int(round((n / 10) ** 0.5)))
n_span = int(round(n / n_chord))
mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.6, 4, 0), 0.4, n_chord, n_span)])
b = 0.5
x, y = mesh.control_point[:, 0], mesh.control_point[:, 1] / 4.0
xl, yl = mesh.load_point[:, 0], mesh.load_point[:, 1] / 4.0
h_c = np.column_stack([y ** j * (x - 0.4) ** i for i in (0, 1) for j in range(n_modes // 2)])
dh = np.column_stack([(y ** j * i * (x - 0.4) ** max(i - 1, 0)) for i in (0, 1)
                      for j in range(n_modes // 2)])
h_l = np.column_stack([yl ** j * (xl - 0.4) ** i for i in (0, 1) for j in range(n_modes // 2)])
w = dh + 1j * k * h_c / b
out = {"n": mesh.n}
tiny = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.6, 4, 0), 0.4, 4, 30)])
normalwash_matrix(tiny, mach, k, b)                 # warm-up: load the compiled kernels
H.build_hmatrix(tiny, mach, k, b, leaf_size=8)
tracemalloc.start()
t = time.process_time()
if which == "dense":
    d = normalwash_matrix(mesh, mach, k, b)
    cp = factor_normalwash_matrix(d, overwrite=True).pressures(w)
else:
    h = H.build_hmatrix(mesh, mach, k, b)
    t_build = time.process_time() - t
    cp, info = H.solve(h, w)
    out.update(build_s=t_build, compression=h.compression, iterations=max(info.iterations),
               far_blocks=len(h.far), max_rank=max(min(u.shape[1], v.shape[0]) for *_, u, v in h.far))
out["cpu_s"] = time.process_time() - t
out["peak_mb"] = tracemalloc.get_traced_memory()[1] / 2**20
out["Q"] = [[[c.real, c.imag] for c in row] for row in (h_l.T @ (mesh.area[:, None] * cp))]
print(json.dumps(out))
"""


def _run(n, args, which) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    res = subprocess.run([sys.executable, "-c", WORKER, str(n), str(args.mach), str(args.k),
                          str(args.modes), which], capture_output=True, text=True, env=env,
                         check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def _q(r):
    import numpy as np
    a = np.array(r["Q"])
    return a[..., 0] + 1j * a[..., 1]


def main(argv=None) -> None:
    import numpy as np
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 4000, 10000])
    p.add_argument("--mach", type=float, default=0.8)
    p.add_argument("--k", type=float, default=0.5)
    p.add_argument("--modes", type=int, default=6)
    p.add_argument("--dense-max", type=int, default=10000)
    args = p.parse_args(argv)
    rows = []
    print(f"M {args.mach}, k {args.k}, {args.modes} modes, one BLAS thread, CPU seconds")
    print(f"{'boxes':>6} {'dense s':>8} {'dense MB':>9} {'H s':>8} {'(build)':>8} {'H MB':>7} "
          f"{'compr':>6} {'iters':>5} {'rank':>4} {'GAF err':>8}")
    for n in args.sizes:
        dn = _run(n, args, "dense") if n <= args.dense_max else None
        hm = _run(n, args, "hmatrix")
        err = float("nan")
        if dn is not None:
            qd, qh = _q(dn), _q(hm)
            err = float(np.abs(qh - qd).max() / np.abs(qd).max())
        rows.append((hm["n"], dn, hm))
        print(f"{hm['n']:>6} {dn['cpu_s'] if dn else float('nan'):>8.2f} "
              f"{dn['peak_mb'] if dn else float('nan'):>9.0f} {hm['cpu_s']:>8.2f} "
              f"{hm['build_s']:>8.2f} {hm['peak_mb']:>7.0f} {hm['compression']:>6.3f} "
              f"{hm['iterations']:>5d} {hm['max_rank']:>4d} {err:>8.1e}", flush=True)
    print("growth exponents (log time ratio / log size ratio):")
    for (n0, d0, h0), (n1, d1, h1) in zip(rows, rows[1:]):
        r = np.log(n1 / n0)
        de = np.log(d1["cpu_s"] / d0["cpu_s"]) / r if d0 and d1 else float("nan")
        print(f"  {n0}->{n1}: dense {de:.2f}, hmatrix {np.log(h1['cpu_s'] / h0['cpu_s']) / r:.2f}"
              f" (memory {np.log(h1['peak_mb'] / h0['peak_mb']) / r:.2f})")
    faster = [n for n, d, h in rows if d and h["cpu_s"] < d["cpu_s"]]
    print("crossover: hmatrix faster from", faster[0] if faster else "none of these sizes")


if __name__ == "__main__":
    main()
