"""End-to-end cost of the fin's thickness-field optimisation (issue 28): 50 thickness-table
variables, analytic gradients, against the cost of the same gradients by central differences.

Run on demand (not collected by pytest):

    OPENBLAS_NUM_THREADS=1 python tests/benchmarks/bench_design_field.py

The problem is the shipped one: ``data/cases/nalci2013_fin_field.toml`` (the reference fin with
a 10 x 5 thickness table, 8 x 9 plate mesh) and ``data/designs/fin_min_mass_field.toml`` (the
50 table values in [1, 8] mm, adjacent values within 0.5 mm, 15 % flutter margin at M 0.6 over
0, 2500 and 5000 m). Wall time (time.perf_counter) of :func:`asekit.case.design.optimise` with
the analytic gradients (set-up included: modes, aerodynamic operators), then of one gradient
by central differences (2 x 50 chain evaluations, :func:`asekit.case.design.gradient_check` at
the baseline) and its agreement with the analytic one; the finite-difference optimisation is
estimated as (optimiser chain evaluations) x (one FD gradient): each evaluation SLSQP asks for
comes with its gradient, which FD would replace by 2 x 50 more evaluations. The chain of
:func:`asekit.case.design.evaluate` always forms its derivative terms, so the FD evaluations
timed here are dearer than value-only ones would be (bench_design_gradients.py: 0.28 s without,
0.73 s with the derivative terms on its 100-element fin): the FD estimate is an upper bound,
about 2.5 times the value-only cost.

Measured (commit after 62a073d, 2-core machine shared with three other sessions,
OPENBLAS_NUM_THREADS=1):

    50 variables; set-up (modes, aerodynamic operators) 1.7 s
    analytic: 42.2 s end to end (40.5 s optimiser, 27 chain evaluations with gradients,
      27 iterations); Optimization terminated successfully
      mass 0.14742 -> 0.11235 kg (-23.79 %); min margin -1.944 -> 15.012 %
    one chain evaluation with analytic gradient 1.49 s; one central-difference gradient
      109.0 s (100 evaluations, step 0.001); max rel |analytic - FD| 7.23e-06
    finite-difference optimisation estimate: 27 x 109.0 s = 49.1 min (vs 0.7 min analytic)

(value-only FD evaluations would bring the estimate to roughly 20 min: still ~25 x slower.)
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from asekit.case import load_case
from asekit.case.design import Evaluator, case_value, gradient_check, load_design, optimise
from asekit.util.paths import DATA_DIR


def main():
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    case = load_case(DATA_DIR / "cases" / "nalci2013_fin_field.toml")
    problem = load_design(DATA_DIR / "designs" / "fin_min_mass_field.toml")
    t0 = time.perf_counter()
    ev = Evaluator(case, problem)
    t_setup = time.perf_counter() - t0
    print(f"{len(ev.paths)} variables; set-up (modes, aerodynamic operators) {t_setup:.1f} s",
          flush=True)
    t1 = time.perf_counter()
    res = optimise(case, problem, check_gradients=False, evaluator=ev,
                   progress=lambda r: print(f"  it {r['iteration']:3d}  mass {r['mass_kg']:.5f} kg"
                                            f"  min margin {r['min_margin_pct']:7.3f} %",
                                            flush=True))
    t_opt = time.perf_counter() - t1
    n_eval = ev.calls
    b, o = res.baseline, res.optimised
    print(f"analytic: {t_setup + t_opt:.1f} s end to end ({t_opt:.1f} s optimiser, {n_eval} "
          f"chain evaluations with gradients, {len(res.history)} iterations); {res.message}")
    print(f"  mass {b.mass_kg:.5f} -> {o.mass_kg:.5f} kg ({100 * (o.mass_kg / b.mass_kg - 1):+.2f} "
          f"%); min margin {100 * np.nanmin(b.margins):.3f} -> {100 * np.nanmin(o.margins):.3f} %")
    x0 = np.array([case_value(case, p) for p in ev.paths])
    fresh = Evaluator(case, problem)
    t2 = time.perf_counter()
    fresh(x0)
    t_one = time.perf_counter() - t2
    t3 = time.perf_counter()
    err = gradient_check(fresh, x0, problem.gradient_step)
    t_fd = time.perf_counter() - t3
    print(f"one chain evaluation with analytic gradient {t_one:.2f} s; one central-difference "
          f"gradient {t_fd:.1f} s ({2 * x0.size} evaluations, step {problem.gradient_step:g}); "
          f"max rel |analytic - FD| {err.max():.2e}")
    print(f"finite-difference optimisation estimate: {n_eval} x {t_fd:.1f} s = "
          f"{n_eval * t_fd / 60:.1f} min (vs {(t_setup + t_opt) / 60:.1f} min analytic)")


if __name__ == "__main__":
    main()
