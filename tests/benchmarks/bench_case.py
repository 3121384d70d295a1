"""Speed target of the case pipeline (issue 9): a new case of 8 x 8 plate elements and about 200
boxes over 4 Machs x 15 reduced frequencies, analysed end to end (modes, GAF database, p-k at
every Mach and 3 altitudes, match points) in under 10 s with a cold cache and under 2 s warm.

Run on demand: ``python tests/benchmarks/bench_case.py``. Each run is a fresh process (imports
excluded from the timing) sharing one temporary cache folder: the first builds the GAF
database, the second reads it.
"""

import os
import subprocess
import sys
import tempfile
import time

CASE = """
[case]
name = "bench_swept_plate"
reference = "benchmark only"
[[panel]]
root_leading_edge = [0.0, 0.0]
root_chord = 0.30
tip_leading_edge = [0.134, 0.50]     # 15 deg leading-edge sweep
tip_chord = 0.20
n_chord = 8
n_span = 8
[thickness]
root = 0.004
tip = 0.003
profile = "biconvex"
[material]
youngs_modulus = 70e9
poisson_ratio = 0.3
density = 2700.0
[support]
kind = "clamped_root"
[modes]
count = 5
[aero]
machs = [0.3, 0.5, 0.7, 0.85]
reference_semichord = 0.15
f_max = 150.0
u_min = 60.0
boxes = [{ n_chord = 10, n_span = 20 }]
[flight]
altitudes = [0.0, 3000.0, 6000.0]
velocities = { min = 40.0, max = 400.0, step = 4.0 }
[flight.envelope]
mach = [0.3, 0.7]
altitude = [0.0, 6000.0]
"""

COLD_TARGET_S = 10.0
WARM_TARGET_S = 2.0


def inner(path: str) -> None:
    from asekit.case import load_case
    from asekit.case.pipeline import reduced_frequencies, box_mesh
    from asekit.case.report import run_analysis
    case = load_case(path)
    t = time.perf_counter()
    a = run_analysis(case)
    dt = time.perf_counter() - t
    print(f"{dt:.3f} {box_mesh(case).n} {len(reduced_frequencies(case))} "
          + " ".join(f"{k}={v:.3f}" for k, v in a.seconds.items()))


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "case.toml")
        with open(path, "w") as fh:
            fh.write(CASE)
        env = dict(os.environ, ASEKIT_CACHE_DIR=os.path.join(tmp, "cache"))
        out = {}
        for label in ("cold", "warm"):
            r = subprocess.run([sys.executable, __file__, "--inner", path], env=env,
                               capture_output=True, text=True, check=True)
            out[label] = r.stdout.split()
            print(f"{label}: {out[label][0]} s ({out[label][1]} boxes, {out[label][2]} k x 4 "
                  f"Machs; {' '.join(out[label][3:])})")
    cold, warm = float(out["cold"][0]), float(out["warm"][0])
    ok = cold < COLD_TARGET_S and warm < WARM_TARGET_S
    print(f"targets: cold < {COLD_TARGET_S:g} s, warm < {WARM_TARGET_S:g} s: "
          f"{'met' if ok else 'MISSED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--inner":
        inner(sys.argv[2])
    else:
        sys.exit(main())
