"""Where the fin's flutter discretisation error comes from (issue 23, first goal, step 1):
the structural mesh near the shaft region, the structural mesh elsewhere, the aerodynamic boxes,
and the shaft region's rim, each varied alone.

Run on demand (not collected by pytest), one process, warm numba cache (times are of the
analyses only, not cold runs: for those see ``bench_converged.py``):

    /work/venv/bin/python tests/benchmarks/bench_converged_sources.py [structure|boxes|rim|fit]

The model is ``bench_converged.py``'s: the fin with the distributed shaft of radius 5 mm, p-k at
M 0.75, 0 m over 140-340 m/s in 2 m/s steps, GAFs on the database's reduced frequencies.

* ``structure``: from the graded 64 x 48 mesh (``with_shaft_grading``, boxes 14 x 10), every
  element interval is split in two (128 x 96), or only the intervals within 1.5 and 3 shaft
  radii of the axis (chordwise and spanwise), or only those beyond;
* ``boxes``: the same structure with 7 x 5, 14 x 10, 28 x 20, 56 x 40 boxes (ratio 2: observed
  order and Richardson limit as in ``bench_converged.py``);
* ``rim``: the radius 4.9, 5.0, 5.1 mm (the speed's sensitivity to where the region ends);
* ``fit``: the region as every node within r (``support.region_fit = "nodes"``, a staircase)
  and fitted by the nodes (``"snap"``) on the graded meshes 32 x 24 .. 128 x 96.

Measured 2026-12-03 (2 shared cores, warm; speed m/s):

=============================================== ========= ============
variation (boxes 14 x 10 unless said)           speed     change
=============================================== ========= ============
graded 64 x 48                                  252.81
  every interval split (128 x 96)               254.29    +1.48
  only within 3 r of the axis split (108 x 75)  254.32    +1.51
  only within 1.5 r split (98 x 69)             254.37    +1.56
  only beyond 3 r split (84 x 69)               252.77    -0.04
  only beyond 1.5 r split (94 x 75)             252.73    -0.08
  boxes 7 x 5 / 14 x 10 / 28 x 20 / 56 x 40     248.52 / 252.81 / 254.89 / 255.85
  r = 4.9 / 5.0 / 5.1 mm                        251.25 / 252.81 / 254.57
graded 64 x 48, region fitted ("snap")          255.05
  boxes 7 x 5 / 14 x 10 / 28 x 20 / 56 x 40     250.79 / 255.05 / 257.12 / 258.07
graded 32 x 24 / 64 x 48 / 128 x 96, "nodes"    251.43 / 252.81 / 254.10  (order 0.10)
graded 32 x 24 / 64 x 48 / 128 x 96, "snap"     254.79 / 255.05 / 255.24  (order 0.46)
=============================================== ========= ============

So the structural error is the shaft region's rim (within 1.5 r of the axis): refining there
alone gives the whole change, refining everywhere else nothing. The flutter speed moves about
17 m/s per mm of radius, and a region made of the nodes within r is a staircase whose
effective radius changes by up to an element size from mesh to mesh (order 1, erratic: the
"nodes" sequence's three-mesh order 0.10 and "limit" 271.6 m/s are meaningless). Fitting the
region's circle by the nodes (``support.region_fit = "snap"``) leaves 0.45 m/s (0.18 %)
between 32 x 24 and 128 x 96; its three-mesh limit is 255.75 m/s at 14 x 10 boxes.

The boxes are the other half of the error, independent of the structure (the same +2.07 m/s
from 14 x 10 to 28 x 20 with and without the fit, and on the uniform 96 x 112 mesh,
``bench_converged.py``): order 1.04 (boxes 7 x 5 .. 28 x 20) and 1.12 (14 x 10 .. 56 x 40),
limit 256.85 / 256.67 m/s on the unfitted structure and 259.07 / 258.88 m/s on the fitted one,
+4.0 m/s beyond 14 x 10. The fully converged flutter speed (structure and boxes) is so about
259 m/s, 2.3 % above the 253.1 m/s that issue 23 quotes (the limit of uniform structural meshes
at 14 x 10 boxes, from a pre-asymptotic sequence: the structural limit at 14 x 10 boxes is
255.5-256.0 m/s, +0.9-1.2 %).
"""

from __future__ import annotations

import sys
import time
import warnings
from dataclasses import replace

import numpy as np

from asekit.case import load_case, pipeline
from asekit.case.variants import with_boxes, with_mesh, with_shaft, with_shaft_grading
from asekit.structure.mesh import Stations
from asekit.util.paths import FIN_FILE

RADIUS = 0.005                    # m, asekit.reproduction.fin.DEFAULT_SHAFT_RADIUS
MACH = 0.75
VELOCITIES = np.arange(140.0, 340.0 + 1e-9, 2.0)     # m/s, the converged study's sweep


def fin_case(radius: float = RADIUS):
    fin = with_shaft(load_case(FIN_FILE), radius=radius)
    return replace(fin, aero=replace(fin.aero, machs=(MACH,)),
                   flight=replace(fin.flight, altitudes=(0.0,),
                                  velocities=tuple(float(v) for v in VELOCITIES)))


def flutter(case, label: str) -> float:
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # coarse meshes under-resolve the region
        model = pipeline.modal_model(case)
        db = pipeline.gaf_database(case, progress=False, cache=False)
        r = pipeline.analyse_condition(case, db, MACH, pipeline.flight_conditions(case)[0])
    fl = r.flutter
    print(f"  {label:46s} {model.nodes.shape[0]:6d} nodes {fl.speed:8.2f} m/s "
          f"{fl.frequency_hz:7.2f} Hz {time.process_time() - t0:6.1f} s", flush=True)
    return fl.speed


def split(stations, chosen) -> np.ndarray:
    """``stations`` with every interval (a, b) for which ``chosen(a, b)`` halved."""
    out = [stations[0]]
    for a, b in zip(stations[:-1], stations[1:]):
        if chosen(a, b):
            out.append(0.5 * (a + b))
        out.append(b)
    return np.array(out)


def structure_study(fin) -> None:
    base = with_shaft_grading(fin, 64, 48)
    p = base.panels[0]
    pf = p.planform
    xi_a = (fin.support.axis_point[0] - pf.root_le[0]) / pf.root_chord
    sc, ss = p.chord_spacing.stations(64), p.span_spacing.stations(48)

    def case(c, s):
        return with_boxes(with_mesh(fin, len(c) - 1, len(s) - 1, Stations(tuple(c)),
                                    Stations(tuple(s))), 14, 10)

    def near_x(a, b, k):
        return (a - xi_a) * (b - xi_a) <= 0 or \
            min(abs(a - xi_a), abs(b - xi_a)) * pf.root_chord <= k * RADIUS

    def near_y(a, b, k):
        return min(a, b) * pf.span <= k * RADIUS

    flutter(case(sc, ss), "graded 64x48")
    everywhere = (split(sc, lambda a, b: True), split(ss, lambda a, b: True))
    flutter(case(*everywhere), "every interval split")
    for k in (3.0, 1.5):
        c = split(sc, lambda a, b: near_x(a, b, k))
        s = split(ss, lambda a, b: near_y(a, b, k))
        flutter(case(c, s), f"only within {k:g} r split ({len(c) - 1}x{len(s) - 1})")
        c = split(sc, lambda a, b: not near_x(a, b, k))
        s = split(ss, lambda a, b: not near_y(a, b, k))
        flutter(case(c, s), f"only beyond {k:g} r split ({len(c) - 1}x{len(s) - 1})")


def richardson(u1: float, u2: float, u3: float) -> tuple[float, float]:
    """(observed order p, limit) of three values on meshes refined by 2 each time."""
    d1, d2 = u2 - u1, u3 - u2
    if d1 * d2 <= 0 or abs(d2) >= abs(d1):
        return float("nan"), float("nan")
    p = np.log2(d1 / d2)
    return float(p), float(u3 + d2 / (2.0 ** p - 1.0))


def boxes_study(fin) -> None:
    for fit in ("nodes", "snap"):
        base = with_shaft(with_shaft_grading(fin, 64, 48), region_fit=fit)
        u = [flutter(with_boxes(base, *b), f"graded 64x48 {fit}, boxes {b[0]}x{b[1]}")
             for b in ((7, 5), (14, 10), (28, 20), (56, 40))]
        for i in (0, 1):
            p, lim = richardson(*u[i:i + 3])
            print(f"  boxes ({fit}), meshes {i + 1}-{i + 3}: order {p:.2f}, limit {lim:.2f} m/s "
                  f"({lim - u[1]:+.2f} beyond 14x10)")


def rim_study() -> None:
    for r in (0.0049, 0.005, 0.0051):
        flutter(with_boxes(with_shaft_grading(fin_case(r), 64, 48), 14, 10),
                f"graded 64x48, r = {r * 1e3:g} mm")


def fit_study(fin) -> None:
    for fit in ("nodes", "snap"):
        u = [flutter(with_boxes(with_shaft(with_shaft_grading(fin, *n), region_fit=fit), 14, 10),
                     f"graded {n[0]}x{n[1]}, region_fit {fit}")
             for n in ((32, 24), (64, 48), (128, 96))]
        p, lim = richardson(*u)
        print(f"  region_fit {fit}: order {p:.2f}, limit {lim:.2f} m/s")


def main(argv) -> int:
    fin = fin_case()
    which = argv or ["structure", "boxes", "rim", "fit"]
    for w in which:
        print(f"{w}:", flush=True)
        {"structure": lambda: structure_study(fin), "boxes": lambda: boxes_study(fin),
         "rim": rim_study, "fit": lambda: fit_study(fin)}[w]()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
