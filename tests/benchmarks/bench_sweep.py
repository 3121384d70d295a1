"""Benchmark of asekit.sweep (run on demand, not in the test suite):

    PYTHONPATH=. OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python tests/benchmarks/bench_sweep.py
        [--samples 1000] [--workers 2] [--skip-serial]

The fin's Monte Carlo sweep (data/sweeps/fin_monte_carlo.toml: E, density, root thickness, shaft
stiffness, modal damping; p-k at Mach 0.6, sea level, 100-400 m/s every 10 m/s with Brent-refined
crossings) with ``--samples`` samples:

1. the AIC factors once (D(M, k) of the base boxes at Mach 0.6, LU per k);
2. serially with the AIC reused;
3. the same sweep on a 2-worker dask LocalCluster (1 thread per worker), the table checked
   identical to the serial one, the speed-up, and the peak resident memory of each worker
   (getrusage ru_maxrss inside the worker process);
4. for comparison, a few samples the way a sweep without reuse would run them: the GAF database
   rebuilt (DLM + LU) per sample at the analysed Mach.

Target (issue 16): 1000 p-k samples in under 2 minutes on this 2-core machine with the AIC reused.

Measured 2026-12-01 on the shared 2-core machine (load average 2-3 from other jobs), default
options: AIC factors 0.27 s (4.7 MB); serial 65.9 s (66 ms/sample, CPU = wall); 2-worker
LocalCluster 58.7 s + 0.7 s start, speed-up 1.12x (the workers averaged 114 ms/sample: the
other jobs took part of the two cores), tables identical, peak RSS 154 MB per worker; CPU per
sample 71 ms with the AIC reused vs 122 ms with the GAFs rebuilt per sample (1.72x). Target met.
Under a load average of ~6-10 the same run took 188-203 s serially and 163-195 s on the cluster.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from asekit import sweep as S


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _identical(a, b) -> bool:
    a, b = a.drop(columns=["wall_s"]), b.drop(columns=["wall_s"])
    if list(a.columns) != list(b.columns) or len(a) != len(b):
        return False
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if x.dtype.kind == "f":
            nan = np.isnan(x)
            if not (np.array_equal(nan, np.isnan(y))
                    and np.array_equal(x[~nan].view(np.uint64), y[~nan].view(np.uint64))):
                return False
        elif list(map(str, x)) != list(map(str, y)):
            return False
    return True


def without_reuse(sw: S.Sweep, n: int) -> float:
    """CPU seconds per sample when each sample rebuilds its GAFs (DLM + LU) at the analysed
    Mach (CPU time, so that the comparison does not depend on the machine's load)."""
    from asekit.aero.gaf import cached_gaf_database
    from asekit.atmosphere import standard_atmosphere
    from asekit.case import case_from_dict
    from asekit.case import pipeline as P
    rows = sw.design()[:n]
    atm = standard_atmosphere(sw.altitude)
    cond = P.FlightCondition(sw.altitude, float(atm.density), float(atm.speed_of_sound))
    t0 = time.process_time()
    with tempfile.TemporaryDirectory() as tmp:
        for v in rows:
            d, mach, _ = sw.case_dict(v)
            case = case_from_dict(d)
            model = P.modal_model(case)
            db = cached_gaf_database(model, P.box_mesh(case), [mach], P.reduced_frequencies(case),
                                     case.aero.reference_semichord, progress=False, rebuild=True,
                                     cache_dir=tmp)
            P.analyse_condition(case, db, mach, cond, model)
    return (time.process_time() - t0) / n


def with_reuse(sw: S.Sweep, fac, n: int) -> float:
    """CPU seconds per sample of the same samples with the AIC factors reused."""
    rows = sw.design()[:n]
    t0 = time.process_time()
    for i, v in enumerate(rows):
        S.evaluate(sw, fac, i, v)
    return (time.process_time() - t0) / n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-serial", action="store_true")
    ap.add_argument("--velocities", metavar="MIN:MAX:STEP",
                    help="override the p-k velocity sweep (m/s), e.g. 150:350:10")
    args = ap.parse_args(argv)
    sw = dataclasses.replace(S.load_sweep(ROOT / "data/sweeps/fin_monte_carlo.toml"),
                             samples=args.samples)
    if args.velocities:
        lo, hi, st = (float(x) for x in args.velocities.split(":"))
        base = dict(sw.base)
        base["flight"] = {**base["flight"], "velocities": {"min": lo, "max": hi, "step": st}}
        sw = dataclasses.replace(sw, base=base)
    v = sw.base["flight"]["velocities"]
    print(f"p-k velocities {v['min']:g}-{v['max']:g} m/s every {v['step']:g} m/s")
    print(f"sweep {sw.name}: {sw.n_samples} samples, outputs {', '.join(sw.outputs)}; "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    t = time.perf_counter()
    fac = S.base_factors(sw)
    t_fac = time.perf_counter() - t
    print(f"AIC factors (D(M, k) at M {sorted(fac.operators)}, {fac.k.size} k, LU): {t_fac:.2f} s, "
          f"{fac.nbytes / 1e6:.1f} MB")

    serial = None
    if not args.skip_serial:
        t, c = time.perf_counter(), time.process_time()
        serial = S.run_sweep(sw, factors=fac)
        t_serial, c_serial = time.perf_counter() - t, time.process_time() - c
        print(f"serial: {t_serial:.1f} s wall, {c_serial:.1f} s CPU "
              f"({t_serial / len(serial) * 1e3:.0f} ms/sample; "
              f"{int((serial.status != 'ok').sum())} failed); peak RSS {_peak_rss_mb():.0f} MB")
        print(f"  -> on {args.workers} idle cores the sweep would take about "
              f"{c_serial / args.workers:.0f} s (serial CPU time / workers; an estimate)")

    from dask.distributed import Client, LocalCluster
    t = time.perf_counter()
    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    t_start = time.perf_counter() - t
    try:
        t = time.perf_counter()
        dask_df = S.run_sweep(sw, executor="dask", client=client, factors=fac)
        t_dask = time.perf_counter() - t
        peaks = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
    finally:
        client.close()
        cluster.close()
    print(f"per-sample compute (mean wall_s): serial "
          f"{'-' if serial is None else f'{serial.wall_s.mean() * 1e3:.0f} ms'}, dask workers "
          f"{dask_df.wall_s.mean() * 1e3:.0f} ms (a larger value = the workers did not get "
          f"their cores)")
    print(f"dask LocalCluster ({args.workers} workers x 1 thread): {t_dask:.1f} s "
          f"(+ {t_start:.1f} s cluster start); peak RSS per worker "
          + ", ".join(f"{v:.0f} MB" for v in peaks.values()))
    if serial is not None:
        print(f"speed-up dask / serial: {t_serial / t_dask:.2f}x; tables identical (all columns "
              f"but wall_s): {_identical(serial, dask_df)}")
    n_cmp = 20
    t_no, t_re = without_reuse(sw, n_cmp), with_reuse(sw, fac, n_cmp)
    print(f"CPU per sample, {n_cmp} samples: AIC reused {t_re * 1e3:.0f} ms, GAFs rebuilt per "
          f"sample (DLM + LU) {t_no * 1e3:.0f} ms ({t_no / t_re:.2f}x)")
    best = min(x for x in (t_dask, t_serial if serial is not None else None) if x is not None)
    target = 120.0 * sw.n_samples / 1000
    print(f"target: {sw.n_samples} samples < {target:.0f} s: best {best:.1f} s -> "
          f"{'met' if best < target else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
