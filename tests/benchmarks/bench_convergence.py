"""Cost of the flutter error bar (issue 23, "every flutter result with an error bar"):
``analyse --convergence`` (:func:`asekit.case.convergence.convergence_study`, the default three
meshes at ratio 1.5) against one plain run, on AGARD 445.6 and on the fin with its 5 mm shaft
region on the graded 64 x 48 mesh / 28 x 20 boxes at M 0.75, sea level (the default
``reproduce`` rows ``flutter.extrapolated.*``).

Run on demand (not collected by pytest), each measurement a fresh process with an empty
ASEKIT_CACHE_DIR (cold: modes and GAFs computed; numba's on-disk cache warm):

    python tests/benchmarks/bench_convergence.py [agard] [fin]

Prints CPU time (user + system of the process, imports included) and peak resident memory of
the plain run and of the run with the study, their ratio (goal: under 3), and the
extrapolated speed with its error bar. Measured 2026-12-03 on the shared 2-core machine: see
the issue 23 note of this session.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

GOAL_RATIO = 3.0

_CHILD = r"""
import json, resource, sys, warnings
from dataclasses import replace
import numpy as np
from asekit.case import load_case
from asekit.case.report import run_analysis
from asekit.util.paths import CASES_DIR, FIN_FILE

which, study = sys.argv[1], sys.argv[2] == "1"
if which == "agard":
    case = load_case(CASES_DIR / "agard445_6.toml")
else:
    from asekit.case.variants import with_boxes, with_shaft, with_shaft_grading
    fin = with_shaft(load_case(FIN_FILE), radius=0.005)
    fin = replace(fin, actuator=None, aero=replace(fin.aero, machs=(0.75,)),
                  flight=replace(fin.flight, altitudes=(0.0,), velocities=tuple(
                      np.arange(140.0, 340.0 + 1e-9, 2.0))))
    case = with_boxes(with_shaft_grading(fin, 64, 48), 28, 20)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    a = run_analysis(case)
    out = {"speed": a.flutter.results[0].flutter.speed}
    if study:
        from asekit.case.convergence import convergence_study
        s = convergence_study(case, finest=a.flutter)
        e = s.rows[0].speed
        out.update(extrapolated=e.value, error=e.error, order=e.order, observed=e.observed)
ru = resource.getrusage(resource.RUSAGE_SELF)
out.update(cpu_s=ru.ru_utime + ru.ru_stime, rss_mb=ru.ru_maxrss / 1024.0)
print(json.dumps(out))
"""


def run(which: str, study: bool) -> dict:
    """One cold run in a fresh process with its own empty cache directory."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, ASEKIT_CACHE_DIR=cache, MPLBACKEND="Agg")
        out = subprocess.run([sys.executable, "-c", _CHILD, which, "1" if study else "0"],
                             env=env, capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(f"{which} run failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    ok = True
    for which in sys.argv[1:] or ("agard", "fin"):
        plain, conv = run(which, False), run(which, True)
        ratio = conv["cpu_s"] / plain["cpu_s"]
        ok = ok and ratio < GOAL_RATIO
        print(f"{which}: plain {plain['speed']:.2f} m/s, {plain['cpu_s']:.1f} s CPU, "
              f"{plain['rss_mb']:.0f} MB; --convergence {conv['extrapolated']:.2f} +- "
              f"{conv['error']:.2f} m/s (order {conv['order']:.2f} "
              f"{'observed' if conv['observed'] else 'assumed'}), {conv['cpu_s']:.1f} s CPU, "
              f"{conv['rss_mb']:.0f} MB; ratio {ratio:.2f} (goal < {GOAL_RATIO:g})", flush=True)
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
