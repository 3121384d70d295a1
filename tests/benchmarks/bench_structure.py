"""Speed target of the structural model (issue 3): a 100 x 100 mesh solves in seconds.

Run on demand: ``/work/venv/bin/python tests/benchmarks/bench_structure.py [--fine]``.
Not collected by pytest. ``--fine`` also solves the distributed-shaft model on 192 x 224
(about 130 000 DOFs) to show how far the 5 mm shaft region is from convergence at 96 x 112.
"""

import sys
import time
import warnings
from dataclasses import replace

from asekit.case import load_case, pipeline
from asekit.util.paths import FIN_FILE

TARGET_S = 10.0
SHAFT_RADIUS = 0.005          # m, the distributed shaft region of the fine study


def fin_on(case, n_chord, n_span, radius=None):
    """The fin's case on an n_chord x n_span FE mesh, single-node shaft or a rigid shaft region
    of ``radius`` (m)."""
    return replace(case, panels=(replace(case.panels[0], n_chord=n_chord, n_span=n_span),),
                   support=replace(case.support, radius=radius))


def main(fine: bool = False) -> int:
    fin = load_case(FIN_FILE)
    pipeline.modal_model(fin)                        # warm-up (imports, caches)
    t = time.perf_counter()
    m = pipeline.modal_model(fin_on(fin, 100, 100))
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
                d = pipeline.modal_model(fin_on(fin, *mesh, radius=SHAFT_RADIUS))
            print(f"FN2 {mesh[0]}x{mesh[1]} distributed r={SHAFT_RADIUS * 1e3:g} mm: "
                  f"{time.perf_counter() - t:.1f} s, elastic (Hz):",
                  ", ".join(f"{f:.2f}" for f in d.frequencies_hz[1:]))
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(fine="--fine" in sys.argv))
