"""Speed target of the structural model (issue 3): a 100 x 100 mesh solves in seconds.

Run on demand: ``/work/venv/bin/python tests/benchmarks/bench_structure.py [--fine]``.
Not collected by pytest. ``--fine`` also solves the distributed-shaft model on 192 x 224
(about 130 000 DOFs) to show how far the 5 mm shaft region is from convergence at 96 x 112.
"""

import sys
import time
import warnings

from asekit.case import pipeline
from asekit.case.variants import with_mesh
from asekit.reproduction.fin import distributed_case, fin_case

TARGET_S = 10.0


def main(fine: bool = False) -> int:
    case = fin_case()
    pipeline.modal_model(case)                       # warm-up (imports, caches)
    t = time.perf_counter()
    m = pipeline.modal_model(with_mesh(case, 100, 100))
    dt = time.perf_counter() - t
    n_dof = 3 * m.nodes.shape[0]
    print(f"FN2 100x100 single-node: {n_dof} DOFs, {dt:.2f} s (target < {TARGET_S:g} s)")
    print("  elastic frequencies (Hz):", ", ".join(f"{f:.2f}" for f in m.frequencies_hz[1:]))
    ok = dt < TARGET_S
    if fine:
        for mesh in ((96, 112), (192, 224)):
            t = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                dcase = distributed_case(*mesh)
                d = pipeline.modal_model(dcase)
            print(f"FN2 {mesh[0]}x{mesh[1]} distributed r={dcase.support.radius * 1e3:g} mm: "
                  f"{time.perf_counter() - t:.1f} s, elastic (Hz):",
                  ", ".join(f"{f:.2f}" for f in d.frequencies_hz[1:]))
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(fine="--fine" in sys.argv))
