"""Speed and memory of asekit's doublet-lattice method against DLR's PanelAero on the same boxes.

Run on demand (not collected by pytest):

    python tests/benchmarks/bench_dlm.py [--sizes 300 1200 3000] [--method quartic]
                                         [--skip-panelaero-above 1200] [--no-sweep]

For each grid (a swept, tapered wing of about 1 m chord: PanelAero's VLM uses an absolute
1e-5 tolerance and loses bound vortices on millimetre-sized boxes, so the fin itself is not
used here) it times the normalwash matrix D(M, k) = VLM + DLM increment at one (M 0.6, k 0.5)
and over a 12-k sweep, with the same kernel order in both codes, and prints the wall-clock
times (one untraced run each), their ratio and the peak memory of each call (a second,
traced run: tracemalloc sees numpy's allocations). Matrix inversion is excluded from both (it is
the same LAPACK call). PanelAero's sweep is 12 single calls (it has no geometry reuse). Above
``--skip-panelaero-above`` boxes PanelAero is not run (it needs about 5 GB at 3000 boxes).

Measured on the 2-core project machine, shared with other jobs (load ~2, so +-30 %), M 0.6,
asekit vs PanelAero 2025.8, same kernel order:
  300 boxes, quartic: single 0.07 s vs 0.26 s (4x), 12-k sweep 0.53 s vs 4.6 s (9x), 25 vs 50 MB;
  1200 boxes, quartic: single 0.85 s vs 7.6 s (9x), 12-k sweep 5.7 s vs 80 s (14x),
      peak 56 MB vs 801 MB; parabolic: single 0.56 s vs 4.1 s (7x), 49 vs 641 MB;
  3000 boxes, quartic: single 5.7 s, peak 231 MB (PanelAero not run: its 1200-box peak of
      0.8 GB scales to about 5 GB).
The single-(M, k) cost splits about evenly between the k-independent geometry (kernel
stations, integration weights, vortex lattice) and the kernel itself; a sweep pays the geometry
once per Mach. The 10x single-call goal is nearly met (9x quartic, 7x parabolic); the sweep
exceeds it.
Agreement of D between the two: 5e-14 (single) to 1.2e-13 (sweep), relative to max |D|.

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


def grid(n_boxes: int):
    nc, ns = GRIDS.get(n_boxes, (max(4, int(round((n_boxes / 3) ** 0.5))),
                                 max(1, int(round(n_boxes / max(4, int(round((n_boxes / 3) ** 0.5))))))))
    return mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.6, 3.0, 0.0), 0.5, nc, ns, "wing"))


def measure(fn, memory: bool = True):
    """(result, seconds of an untraced run, peak MB of a second traced run or nan)."""
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
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
    ap.add_argument("--method", choices=["parabolic", "quartic"], default="quartic")
    ap.add_argument("--skip-panelaero-above", type=int, default=1200)
    ap.add_argument("--no-sweep", action="store_true")
    args = ap.parse_args(argv)
    print(f"DLM benchmark, M {MACH}, kernel '{args.method}', numpy {np.__version__}, "
          f"{os.cpu_count()} CPUs")
    head = (f"{'boxes':>6s} {'case':>10s} {'asekit s':>9s} {'PanelAero s':>12s} {'ratio':>7s} "
            f"{'asekit MB':>10s} {'PanelAero MB':>13s} {'max |dD|/|D|':>13s}")
    print(head)
    print("-" * len(head))
    for n in args.sizes:
        mesh = grid(n)
        cases = [("single", [K_SINGLE])] + ([] if args.no_sweep else [("12-k sweep", list(K_SWEEP))])
        for name, ks in cases:
            d_a, t_a, m_a = measure(lambda: normalwash_matrices(mesh, MACH, ks, B_REF, args.method))
            if mesh.n <= args.skip_panelaero_above:
                # PanelAero's sweep memory is its single-call memory plus the stored results
                d_p, t_p, m_p = measure(lambda: panelaero_d(mesh, ks, args.method),
                                        memory=(name == "single"))
                err = max(np.abs(a - p).max() / np.abs(a).max() for a, p in zip(d_a, d_p))
                print(f"{mesh.n:6d} {name:>10s} {t_a:9.2f} {t_p:12.2f} {t_p / t_a:7.1f} "
                      f"{m_a:10.0f} {m_p:13.0f} {err:13.1e}")
                del d_p
            else:
                print(f"{mesh.n:6d} {name:>10s} {t_a:9.2f} {'-':>12s} {'-':>7s} {m_a:10.0f} "
                      f"{'-':>13s} {'-':>13s}")
            del d_a
    return 0


if __name__ == "__main__":
    sys.exit(main())
