"""Speed and memory of asekit's doublet-lattice method against DLR's PanelAero on the same boxes.

Run on demand (not collected by pytest):

    python tests/benchmarks/bench_dlm.py [--sizes 300 1200 3000] [--method quartic parabolic]
                                         [--skip-panelaero-above 1200] [--no-sweep] [--repeat 3]

For each grid (a swept, tapered wing of about 1 m chord: PanelAero's VLM uses an absolute
1e-5 tolerance and loses bound vortices on millimetre-sized boxes, so the fin itself is not
used here) it times the normalwash matrix D(M, k) = VLM + DLM increment at one (M 0.6, k 0.5)
and over a 12-k sweep, with the same kernel order in both codes, and prints the wall-clock
times (best of ``--repeat`` untraced runs for a single (M, k), one run for a sweep), their
ratio and the peak memory of each call (a further, traced run: tracemalloc sees numpy's
allocations). Matrix inversion is excluded from both (it is
the same LAPACK call). PanelAero's sweep is 12 single calls (it has no geometry reuse). Above
``--skip-panelaero-above`` boxes PanelAero is not run (it needs about 5 GB at 3000 boxes).

Measured on the 2-core project machine (shared, load ~0.6), M 0.6, best of 3 runs per single
case, asekit vs PanelAero 2025.8 with the same kernel order:

    kernel     boxes  case        asekit s  PanelAero s  ratio  asekit MB  PanelAero MB
    quartic      300  single          0.04         0.26    6.5          9            50
    quartic      300  12-k sweep      0.23         2.72   12.0         24             -
    quartic     1200  single          0.45         6.03   13.4         40           801
    quartic     1200  12-k sweep      3.28        72.5    22.1        281             -
    quartic     3000  single          2.95            -      -        213             -
    quartic     3000  12-k sweep     25.9             -      -       1724             -
    parabolic    300  single          0.02         0.13    7.4          8            40
    parabolic    300  12-k sweep      0.11         1.59   15.1         23             -
    parabolic   1200  single          0.27         3.74   14.0         39           641
    parabolic   1200  12-k sweep      1.73        42.9    24.7        281             -
    parabolic   3000  single          1.74            -      -        213             -
    parabolic   3000  12-k sweep     14.8             -      -       1723             -
    --nonplanar (wing + vertical fin):
    quartic     1200  single          0.96         6.48    6.7         83           805
    parabolic   1200  single          0.62         3.71    6.0         65           630

(PanelAero is not run at 3000 boxes: its 1200-box peak of 0.8 GB scales to about 5 GB. The
sweep peaks are dominated by the 12 returned matrices, 12 x 3000^2 x 16 B = 1.7 GB; one 3000-box
matrix needs 213 MB in all.) Before the planar path of asekit.aero.dlm (same script, same day):
quartic 1200 single 0.75 s (7.8x), parabolic 0.45 s (7.7x), quartic 3000 single 4.3 s,
parabolic 2.8 s; wing + fin 1200 quartic 2.0 s, parabolic 1.2 s. The flat wing takes the
all-planar path; the wing + fin mesh takes it for its coplanar blocks (wing-wing, fin-fin)
and the pairwise path for the rest. Agreement of D between the two codes: 5e-14 (single) to
1.2e-13 (sweep), 4.4e-13 with the fin, relative to max |D|.

Issue target: asekit >= 10x faster than PanelAero per (M, k) at 1200 boxes, the sweep faster
still; a 3000-box AIC in under about 2 GB.
"""

from __future__ import annotations

import argparse
import copy
import os
import sys
import time
import tracemalloc

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces  # noqa: E402
from asekit.aero.dlm import normalwash_matrices  # noqa: E402

B_REF = 0.5
MACH = 0.6
K_SINGLE = 0.5
K_SWEEP = np.concatenate([[0.001], np.geomspace(0.01, 2.7, 11)])
GRIDS = {300: (10, 30), 1200: (20, 60), 3000: (30, 100)}


def grid(n_boxes: int, nonplanar: bool = False):
    """The flat swept wing of about ``n_boxes`` boxes, or (``nonplanar``) three quarters of
    them on the wing and one quarter on a vertical fin behind it (pairwise DLM path)."""
    if nonplanar:
        nc = max(4, int(round((n_boxes / 3) ** 0.5)))
        ns_w = max(1, int(round(0.75 * n_boxes / nc)))
        ns_f = max(1, int(round(0.25 * n_boxes / nc)))
        return mesh_surfaces([
            TrapezoidSurface((0, 0, 0), 1.0, (0.6, 3.0, 0.0), 0.5, nc, ns_w, "wing"),
            TrapezoidSurface((1.5, 0, 0.05), 0.8, (1.9, 0.0, 1.0), 0.5, nc, ns_f, "fin")])
    default = (max(4, int(round((n_boxes / 3) ** 0.5))),
               max(1, int(round(n_boxes / max(4, int(round((n_boxes / 3) ** 0.5)))))))
    nc, ns = GRIDS.get(n_boxes, default)
    return mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.6, 3.0, 0.0), 0.5, nc, ns, "wing"))


def measure(fn, memory: bool = True, repeat: int = 1):
    """(result, best seconds of ``repeat`` untraced runs, peak MB of a further traced run or
    nan)."""
    dt = float("inf")
    for _ in range(repeat):
        out = None
        t0 = time.perf_counter()
        out = fn()
        dt = min(dt, time.perf_counter() - t0)
    peak = float("nan")
    if memory:
        del out
        tracemalloc.start()
        out = fn()
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    return out, dt, peak


def panelaero_d(mesh, ks, method):
    from panelaero import DLM, VLM
    from panelaero_grid import panelaero_grid
    g = panelaero_grid(mesh)
    d0 = VLM.calc_Ajj(copy.deepcopy(g), MACH)[0]
    return [d0 + DLM.calc_Ajj(copy.deepcopy(g), MACH, k / B_REF, method=method) for k in ks]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[300, 1200, 3000])
    ap.add_argument("--method", choices=["parabolic", "quartic"], nargs="+", default=["quartic"])
    ap.add_argument("--repeat", type=int, default=3,
                    help="untraced runs of each single-(M, k) case, best taken (sweeps: 1)")
    ap.add_argument("--skip-panelaero-above", type=int, default=1200)
    ap.add_argument("--no-sweep", action="store_true")
    ap.add_argument("--nonplanar", action="store_true",
                    help="wing plus vertical fin (the pairwise, nonplanar DLM path)")
    args = ap.parse_args(argv)
    print(f"DLM benchmark, M {MACH}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
          f"best of {args.repeat} runs per single case")
    head = (f"{'kernel':>9s} {'boxes':>6s} {'case':>10s} {'asekit s':>9s} {'PanelAero s':>12s} "
            f"{'ratio':>7s} {'asekit MB':>10s} {'PanelAero MB':>13s} {'max |dD|/|D|':>13s}")
    print(head)
    print("-" * len(head))
    normalwash_matrices(grid(300), MACH, [K_SINGLE], B_REF)          # warm-up
    for method in args.method:
        for n in args.sizes:
            mesh = grid(n, args.nonplanar)
            cases = [("single", [K_SINGLE])] + ([] if args.no_sweep else
                                                 [("12-k sweep", list(K_SWEEP))])
            for name, ks in cases:
                rep = args.repeat if name == "single" else 1
                d_a, t_a, m_a = measure(lambda: normalwash_matrices(mesh, MACH, ks, B_REF, method),
                                        repeat=rep)
                if mesh.n <= args.skip_panelaero_above:
                    # PanelAero's sweep memory is its single-call memory plus the stored results
                    d_p, t_p, m_p = measure(lambda: panelaero_d(mesh, ks, method),
                                            memory=(name == "single"), repeat=rep)
                    err = max(np.abs(a - p).max() / np.abs(a).max() for a, p in zip(d_a, d_p))
                    print(f"{method:>9s} {mesh.n:6d} {name:>10s} {t_a:9.2f} {t_p:12.2f} "
                          f"{t_p / t_a:7.1f} {m_a:10.0f} {m_p:13.0f} {err:13.1e}", flush=True)
                    del d_p
                else:
                    print(f"{method:>9s} {mesh.n:6d} {name:>10s} {t_a:9.2f} {'-':>12s} {'-':>7s} "
                          f"{m_a:10.0f} {'-':>13s} {'-':>13s}", flush=True)
                del d_a
    return 0


if __name__ == "__main__":
    sys.exit(main())
