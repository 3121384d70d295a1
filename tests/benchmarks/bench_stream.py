"""Aircraft-scale k sweep in bounded memory (issue 12): a wing + horizontal tail of about
``--boxes`` boxes, 15 reduced frequencies, 6 modal normalwashes, projected per k onto the modes
and the matrix dropped (:func:`asekit.aero.dlm.map_normalwash_matrices`, the streamed sweep the
GAF database builder uses).

Run on demand, in a fresh process (the peak RSS is that of the whole process):

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 python tests/benchmarks/bench_stream.py \
        [--boxes 10000] [--nk 15] [--kernel numpy|compiled] [--blas-threads 1]

Per k it prints the CPU and wall time of D(M, k) (kernel geometry, VLM part reused) and of the
LU + 6-column solve + projection, and the peak resident memory so far
(resource.getrusage ru_maxrss); at the end the totals. One D of n boxes is 16 n^2 bytes
(1.6 GB at 10,000 boxes): the stream holds one D (factored in place), the vortex-lattice
matrix D0 (8 n^2) and one chunk of kernel arrays. All matrices at once would be 15 x 16 n^2
(24 GB at 10,000 boxes). The wing and the tail lie in one plane (the all-planar DLM path);
BLAS runs on ``--blas-threads`` threads (threadpoolctl).

Measured once (``OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 python tests/benchmarks/bench_stream.py
--boxes 10000``, code of commit 9a511d5: compiled k loop, numpy geometry and vortex lattice;
2-core machine shared with other jobs, load ~3): 10,002 boxes, 15 k: 1496 s CPU, 2917 s wall
(D 631 s CPU, 31-55 s per k; LU + 6-column solve 866 s CPU, 53-63 s per k), peak RSS
2.59 GiB (one D is 1.49 GiB, all 15 would be 22.4 GiB). A first run whose stream kept the
previous batch alive while computing the next reached 3.92 GiB after two k (fixed in
:func:`asekit.aero.dlm.map_normalwash_matrices`). One D at one k on these 10,002 boxes
(vortex lattice included), measured separately: numpy kernel 62.2 s CPU, compiled kernel of
commit fe53c0c 52.4 s CPU, peak RSS 2.42 GiB.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time

import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from asekit.aero import dlm, kernels  # noqa: E402
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces  # noqa: E402
from asekit.aero.gaf import default_reduced_frequencies  # noqa: E402
from asekit.aero.spline import analytic_modes, modal_forces  # noqa: E402

B_REF = 1.0
MACH = 0.7


def wing_tail(n_boxes: int):
    """Swept tapered wing (chord 2 m, semi-span 10 m) with 80 % of the boxes and a horizontal
    tail (chord 1.2 m, semi-span 3.37 m, 8 m behind the wing apex, same plane) with 20 %.
    (The spans are chosen so that no control point lies on the spanwise line of a box edge of
    the other surface: there the DLM kernel integrals are singular, see asekit.aero.dlm.)"""
    n_w, n_t = 0.8 * n_boxes, 0.2 * n_boxes
    nc_w = max(4, int(round((n_w / 5) ** 0.5)))       # chordwise boxes: strips ~ 5 x chordwise
    ns_w = max(1, int(round(n_w / nc_w)))
    nc_t = max(4, int(round((n_t / 3) ** 0.5)))
    ns_t = max(1, int(round(n_t / nc_t)))
    return mesh_surfaces([
        TrapezoidSurface((0, 0, 0), 2.0, (2.5, 10.0, 0.0), 0.8, nc_w, ns_w, "wing"),
        TrapezoidSurface((8.0, 0, 0), 1.2, (9.0, 3.37, 0.0), 0.6, nc_t, ns_t, "tail")])


def modes(mesh):
    """Six analytic mode shapes (plunge, pitch, wing bending and torsion, ...): (h, dh/dx)."""
    return analytic_modes(mesh, [
        lambda x, y: (1 + 0 * x, 0 * x),
        lambda x, y: (-(x - 3.0), -1 + 0 * x),
        lambda x, y: ((y / 10) ** 2, 0 * x),
        lambda x, y: ((x - 1.5) * y / 10, y / 10),
        lambda x, y: ((y / 10) ** 3, 0 * x),
        lambda x, y: (np.sin(np.pi * x / 10), np.pi / 10 * np.cos(np.pi * x / 10))])


def rss_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20     # kB -> GiB (Linux)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--boxes", type=int, default=10000)
    ap.add_argument("--nk", type=int, default=15)
    ap.add_argument("--kernel", default=None, help="DLM kernel: numpy or compiled (default: "
                    "asekit's default)")
    ap.add_argument("--blas-threads", type=int, default=1)
    args = ap.parse_args(argv)
    if args.kernel is not None:
        os.environ["ASEKIT_DLM_KERNEL"] = args.kernel
    mesh = wing_tail(args.boxes)
    bm = modes(mesh)
    ks = default_reduced_frequencies(2.0)[:args.nk]
    print(f"streamed sweep: {mesh.n} boxes (wing + tail, one plane), M {MACH}, {ks.size} k, "
          f"6 modes, BLAS threads {args.blas_threads}, kernel "
          f"{kernels.default_kernel()}, one D = "
          f"{16 * mesh.n ** 2 / 2**30:.2f} GiB, all D = {ks.size * 16 * mesh.n ** 2 / 2**30:.1f} "
          f"GiB; start RSS {rss_gb():.2f} GiB", flush=True)
    rows = []
    mark = [time.perf_counter(), time.process_time()]

    def project(i, kk, d):
        w0, c0 = time.perf_counter(), time.process_time()
        t_d = (w0 - mark[0], c0 - mark[1])
        cp = dlm.factor_normalwash_matrix(d, overwrite=True).pressures(bm.normalwash(kk, B_REF))
        q = modal_forces(bm, cp, mesh.area)
        w1, c1 = time.perf_counter(), time.process_time()
        rows.append((kk, *t_d, w1 - w0, c1 - c0))
        print(f"  k {kk:7.4f}: D {t_d[1]:7.1f} s CPU {t_d[0]:7.1f} s wall; LU + solve "
              f"{c1 - c0:6.1f} s CPU {w1 - w0:6.1f} s wall; peak RSS {rss_gb():.2f} GiB",
              flush=True)
        mark[:] = [time.perf_counter(), time.process_time()]
        return q

    t0, c0 = time.perf_counter(), time.process_time()
    with threadpool_limits(limits=args.blas_threads, user_api="blas"):
        q = np.stack(dlm.map_normalwash_matrices(mesh, MACH, ks, B_REF, project,
                                                 max_bytes=16 * mesh.n ** 2))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    r = np.array(rows)
    assert q.shape == (ks.size, 6, 6) and np.all(np.isfinite(q))
    print(f"total: {cpu:.0f} s CPU, {wall:.0f} s wall for {ks.size} k ({r[:, 2].sum():.0f} s CPU "
          f"in D, {r[:, 4].sum():.0f} s CPU in LU + solve); peak RSS {rss_gb():.2f} GiB; "
          f"Q[0] (k {ks[0]}) diag {np.round(np.diag(q[0]).real, 4).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
