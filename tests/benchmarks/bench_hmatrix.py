"""Dense LU against the hierarchical-matrix (ACA + GMRES) solve of the DLM over a k sweep.

Run on demand (not collected by pytest), once, on an otherwise idle machine:

    python tests/benchmarks/bench_hmatrix.py [--sizes 1000 2000 4000 8000] [--mach 0.8]
        [--ks 0 0.1 ... 1.4] [--modes 6] [--dense-max 10000] [--perk-max 4000]
        [--only dense perk sweep] [--save-dir DIR]

For each size a swept, tapered wing (span 4 m, root chord 1 m, boxes ~ 1 : 10 chord : span
strips) is solved at one Mach number over ``--ks`` (default 15 k, 0 to 1.4) for ``--modes``
smooth modal normalwash columns, each kind in a fresh subprocess with one BLAS thread:

- dense: the streamed dense path of :func:`asekit.aero.gaf.gaf_from_box_modes`
  (:func:`asekit.aero.dlm.map_normalwash_matrices`: D per k, the geometry shared by a batch,
  LU in place);
- per-k ("before"): :func:`asekit.aero.hmatrix.build_hmatrix` + :func:`~asekit.aero.hmatrix.solve`
  afresh at every k, as ``compressed_pressures`` did before the sweep reuse;
- sweep ("after"): :func:`asekit.aero.hmatrix.compressed_pressures` (one block structure,
  batches of k sharing every kernel evaluation, the batch's middle-k near-field LU as every k's
  preconditioner, GMRES of all modes in lockstep).

It prints CPU seconds, peak memory (tracemalloc's traced peak, which does not see SuperLU's
own allocations, and the subprocess's peak RSS), the GMRES iterations of the sweep (range over
k, lockstep iterations for all modes) and the GAF error of the compressed solves against dense
(max over k of max |dQ| / max |Q|), then the growth exponents and the crossover.
``--save-dir`` keeps each run's result and reuses it, so that sizes and kinds can be run in
separate invocations and tabulated together.

Measured on the 2-core project machine (shared, load 5-12: CPU seconds noisy by ~20 %), M 0.8,
15 k in [0, 1.4], 6 modes, one BLAS thread, leaf 160, eta 1, eps 1e-7, rtol 1e-9 (one
invocation for 1000 and 2002 boxes, a second for 4000 with ``--only dense sweep``; MB traced /
RSS):

    boxes  dense s       MB  per-k s      MB  sweep s       MB  iters  err per-k  err sweep
     1000      4.9  257/454     31.3  40/249     10.4  289/491   5-18    5.5e-11    1.7e-10
     2002     21.5 1005/1209    67.2 103/375     31.3  708/936   5-14    2.0e-10    2.0e-10
     4000    107.0 1160/1389       -       -    141.9  870/1225   6-11          -    1.2e-10

Growth exponents, time: dense 2.13, 2.31; sweep 1.59, 2.18. A separate run of the 4000-box
sweep gave 118.5 s (build 90.2 s, LU + GMRES 28.3 s; RSS 1.18 GB) against dense 117.3 s.
Before the sweep reuse one k at 4000 boxes cost 15.8 s (build 12.6 s, near-field LU 1.4 s,
GMRES 1.8 s), so 15 k ~ 237 s: the sweep is 2-3x faster than the per-k path, but dense LU is
still as fast or faster up to 4000 boxes; 8000+ boxes were not measured in the slot.

Where the time goes (cProfile, one BLAS thread). One k, 4000 boxes: the build is bound by the
kernel evaluations of rows, columns and near blocks (76 %: the compiled planar kernel 4.1 s,
its geometry 2.2 s, index bookkeeping -- np.unique, sub-point tables -- ~5 s, steady horseshoe
part 1.9 s), ACA arithmetic ~2.5 s; near field 31 % of the n^2 entries. 15-k sweep at 4000
boxes with the batched build and scipy's one-column GMRES: build 63 % (compiled kernel the
largest item), GMRES 29 % (single-vector SuperLU solves 46 s and CSR products 36 s of the
profiled 318 s), LU 5 % (one per batch of ~4 k under the 1 GiB budget); GMRES then runs all
modes in lockstep (matrix-matrix products). Evaluating a row for 15 k costs 3.3x one k, a
column 5.8x, a near block 2.7x: the build of 15 k costs ~7x one k's.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

WORKER = r"""
import json, resource, sys, time, tracemalloc
import numpy as np
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import factor_normalwash_matrix, map_normalwash_matrices, normalwash_matrix
from asekit.aero import hmatrix as H
n, mach, n_modes, which = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
ks = [float(s) for s in sys.argv[5].split(",")]
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


def w(k):
    return dh + 1j * k * h_c / b


def q(cp):
    return [[[c.real, c.imag] for c in row] for row in (h_l.T @ (mesh.area[:, None] * cp))]


out = {"n": mesh.n, "Q": [None] * len(ks)}
tiny = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.6, 4, 0), 0.4, 4, 30)])
normalwash_matrix(tiny, mach, 0.5, b)               # warm-up: load the compiled kernels
H.build_hmatrix(tiny, mach, 0.5, b, leaf_size=8)
tracemalloc.start()
t = time.process_time()
if which == "dense":                                # the streamed path of gaf_from_box_modes
    def project(ik, kk, d):
        out["Q"][ik] = q(factor_normalwash_matrix(d, overwrite=True).pressures(w(kk)))
    map_normalwash_matrices(mesh, mach, ks, b, project)
elif which == "perk":                               # before: one build and one LU per k
    its = []
    for ik, kk in enumerate(ks):
        h = H.build_hmatrix(mesh, mach, kk, b)
        cp, info = H.solve(h, w(kk))
        del h
        its.append(max(info.iterations))
        out["Q"][ik] = q(cp)
    out["iterations"] = its
else:                                               # after: the batched sweep
    its = []

    def on_k(ik, cp):
        out["Q"][ik] = q(cp)
    H.compressed_pressures(mesh, mach, ks, b, w, on_k=on_k,
                           on_info=lambda ik, info, again: its.append(max(info.iterations)))
    out["iterations"] = its
out["cpu_s"] = time.process_time() - t
out["peak_mb"] = tracemalloc.get_traced_memory()[1] / 2**20
out["rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""

KINDS = ("dense", "perk", "sweep")


def _run(n, args, which) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    ks = ",".join(repr(float(k)) for k in args.ks)
    saved = os.path.join(args.save_dir, f"{which}_{n}_{args.mach}_{ks}.json") \
        if args.save_dir else None
    if saved and os.path.exists(saved):
        with open(saved) as f:
            return json.load(f)
    res = subprocess.run([sys.executable, "-c", WORKER, str(n), str(args.mach),
                          str(args.modes), which, ks], capture_output=True, text=True, env=env,
                         check=True)
    out = json.loads(res.stdout.strip().splitlines()[-1])
    if saved:
        os.makedirs(args.save_dir, exist_ok=True)
        with open(saved + ".tmp", "w") as f:
            json.dump(out, f)
        os.replace(saved + ".tmp", saved)
    return out


def _q(r):
    import numpy as np
    a = np.array(r["Q"])
    return a[..., 0] + 1j * a[..., 1]


def _err(ref, r) -> float:
    import numpy as np
    if ref is None or r is None:
        return float("nan")
    qd, qh = _q(ref), _q(r)
    return float(max(np.abs(qh[i] - qd[i]).max() / np.abs(qd[i]).max() for i in range(len(qd))))


def _fmt(r, key, spec):
    return format(r[key], spec) if r is not None else format(float("nan"), spec)


def main(argv=None) -> None:
    import numpy as np
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 4000, 8000])
    p.add_argument("--mach", type=float, default=0.8)
    p.add_argument("--ks", type=float, nargs="+",
                   default=[round(float(k), 4) for k in np.linspace(0.0, 1.4, 15)])
    p.add_argument("--modes", type=int, default=6)
    p.add_argument("--dense-max", type=int, default=10000)
    p.add_argument("--perk-max", type=int, default=4000,
                   help="largest size for the per-k compressed solve (the 'before')")
    p.add_argument("--only", choices=KINDS, nargs="+", default=list(KINDS))
    p.add_argument("--save-dir", default=None,
                   help="keep each run's result here and reuse it (runs split over sessions)")
    args = p.parse_args(argv)
    rows = []
    print(f"M {args.mach}, {len(args.ks)} k in [{min(args.ks)}, {max(args.ks)}], {args.modes} "
          f"modes, one BLAS thread, CPU seconds, peak MB traced / RSS")
    print(f"{'boxes':>6} {'dense s':>8} {'MB':>11} {'per-k s':>8} {'MB':>11} {'sweep s':>8} "
          f"{'MB':>11} {'iters':>9} {'err per-k':>9} {'err sweep':>9}")
    for n in args.sizes:
        res = {}
        for kind, limit in (("dense", args.dense_max), ("perk", args.perk_max),
                            ("sweep", None)):
            if kind in args.only and (limit is None or n <= limit):
                res[kind] = _run(n, args, kind)
        d, pk, sw = res.get("dense"), res.get("perk"), res.get("sweep")
        nn = next(r["n"] for r in res.values())
        rows.append((nn, d, pk, sw))
        its = f"{min(sw['iterations'])}-{max(sw['iterations'])}" if sw else "-"
        mb = [f"{_fmt(r, 'peak_mb', '.0f')}/{_fmt(r, 'rss_mb', '.0f')}" for r in (d, pk, sw)]
        print(f"{nn:>6} {_fmt(d, 'cpu_s', '.1f'):>8} {mb[0]:>11} {_fmt(pk, 'cpu_s', '.1f'):>8} "
              f"{mb[1]:>11} {_fmt(sw, 'cpu_s', '.1f'):>8} {mb[2]:>11} {its:>9} "
              f"{_err(d, pk):>9.1e} {_err(d, sw):>9.1e}", flush=True)
    print("growth exponents (log time ratio / log size ratio):")
    for (n0, d0, _, s0), (n1, d1, _, s1) in zip(rows, rows[1:]):
        r = np.log(n1 / n0)
        de = np.log(d1["cpu_s"] / d0["cpu_s"]) / r if d0 and d1 else float("nan")
        se = np.log(s1["cpu_s"] / s0["cpu_s"]) / r if s0 and s1 else float("nan")
        print(f"  {n0}->{n1}: dense {de:.2f}, sweep {se:.2f}")
    faster = [n for n, d, _, s in rows if d and s and s["cpu_s"] < d["cpu_s"]]
    print("crossover: the compressed sweep faster from", faster[0] if faster else
          "none of these sizes")


if __name__ == "__main__":
    main()
