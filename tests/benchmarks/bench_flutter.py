"""Speed targets of the flutter solvers (run on demand: python tests/benchmarks/bench_flutter.py).

Issue target: a full p-k sweep (5 modes, 160 speeds) and a root-locus sweep well under a second
each. Uses the fin's GAF database when asekit.aero.gaf is available, else a synthetic 6-mode
model (1 rigid + 5 elastic, fin-like frequencies) with Roger-type GAFs, plus Nastran's HA145B.
"""

import time

import numpy as np

from asekit.aeroelastic.statespace import modal_arrays
from asekit.aeroelastic.flutter import (TabulatedGaf, pk_flutter, root_locus, time_domain_sweep)
from asekit.rfa import roger_fit


def synthetic_fin(seed=0):
    rng = np.random.default_rng(seed)
    f = np.array([87.0, 160.0, 566.0, 627.0, 972.0])
    n = 6
    M = np.eye(n)
    M[0, 0] = 2.5e-4
    K = np.zeros((n, n))
    K[1:, 1:] = np.diag((2 * np.pi * f) ** 2)
    k = np.concatenate([[0.001], np.geomspace(0.02, 2.7, 13)])
    A = 1e-4 * rng.normal(size=(7, n, n))
    ik = 1j * k[:, None, None]
    Q = A[0] + ik * A[1] + ik ** 2 * A[2] + sum(ik * A[3 + j] / (ik + b)
                                                 for j, b in enumerate((0.1, 0.4, 1.0, 1.8)))
    return modal_arrays(M=M, K=K, C=np.zeros((n, n)), n_rigid=1), TabulatedGaf(k, Q, 0.078)


def timed(label, fn, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    print(f"{label:55s} {best * 1e3:8.1f} ms")
    return out


def main():
    try:
        from asekit.case import load_case, pipeline
        from asekit.util.paths import FIN_FILE
        case = load_case(FIN_FILE)
        db, modal = pipeline.gaf_database(case, progress=False), pipeline.modal_model(case)
        gaf = db.at(0.75)
        modal = modal_arrays(modal)
        label = "fin GAF database"
    except Exception as exc:  # noqa: BLE001
        modal, gaf = synthetic_fin()
        label = f"synthetic fin ({exc.__class__.__name__})"
    print(f"model: {label}, {modal.n_elastic} elastic modes")
    U = np.linspace(180.0, 340.0, 160)
    timed("p-k sweep (all elastic modes, 160 speeds)", lambda: pk_flutter(modal, gaf, 1.225, U))
    fit = timed("Roger fit (4 lags)", lambda: roger_fit(gaf.k, gaf.Q, gaf.b_ref, n_lags=4))
    timed("root locus (160 speeds + continuation)", lambda: root_locus(modal, fit, 1.225, U))
    timed("time-domain growth sweep (17 speeds, expm)",
          lambda: time_domain_sweep(modal, fit, 1.225, U[::10], refine=False), repeat=1)

    from asekit.io.op4 import ha145b_path, load_ha145b
    if ha145b_path().exists():
        case = load_ha145b()
        m = modal_arrays(M=case.M, K=case.K)
        g = TabulatedGaf(case.k, case.Q, case.b_ref)
        Uh = np.linspace(4800, 25200, 160)
        timed("HA145B p-k (10 modes, 160 speeds)", lambda: pk_flutter(m, g, case.rho, Uh))


if __name__ == "__main__":
    main()
