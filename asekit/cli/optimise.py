"""``python -m asekit optimise CASE.toml DESIGN.toml [--json PATH] [--out-case PATH]
[--report DIR] [--no-gradient-check]``: minimise the mass of a case's surface subject to its flutter margin
(a design file, :mod:`asekit.case.design`), write the optimised case file and re-analyse it.

The optimised design's margin is not the optimiser's own number: the written case (or, without
``--out-case``, the same case built in memory) is analysed again by the case pipeline
(:func:`asekit.case.pipeline.flutter`), like ``asekit analyse`` would. The JSON holds
``design.baseline`` and ``design.optimised`` (``mass_kg``, ``flutter_margin_pct``,
``divergence_speed_ms``, ``divergence_margin_pct`` and ``meets_constraints`` from the pipeline,
``predicted_margin_pct`` and ``predicted_divergence_speeds_ms`` from the optimiser's chain, the
variables' ``values``), ``design.divergence_margin_required_pct`` (None: divergence checked
against the flutter margin in the re-analysis only, not a constraint),
``design.gradient_check`` (``max_rel_error`` of the analytic gradients against central
differences at the baseline, ``seconds``), ``design.objective``, ``design.gain`` (mass saved,
the smallest flutter margin's gain in points, the flutter speeds' in %), ``design.constraints``
(per constraint at the optimum: ``name``, ``value``, ``bound``, ``active``, ``multiplier``;
:func:`asekit.case.design.constraint_activity`) and ``design.history`` (one row per
iteration).
``--report DIR`` writes the thickness field, V-g / V-f before and after (the pipeline's
re-analysis) and the history as an HTML page (:mod:`asekit.case.design_report`). Bad input
gets one line and exit status 2.
"""

from __future__ import annotations

import json
import logging
import sys
from pathlib import Path

from asekit.cli import outputs

_log = logging.getLogger(__name__)


def add_parser(sub) -> None:
    p = sub.add_parser("optimise", aliases=["optimize"],
                       help="minimum-mass design of a case under its flutter margin")
    p.add_argument("case", metavar="CASE.toml", help="the case file (see data/cases/)")
    p.add_argument("design", metavar="DESIGN.toml", help="the design file (see data/designs/)")
    p.add_argument("--json", metavar="PATH", help="write the results as JSON ('-': stdout)")
    p.add_argument("--out-case", metavar="PATH", help="write the optimised case file (TOML)")
    p.add_argument("--report", metavar="DIR",
                   help="write index.html, the figures (thickness, V-g, history) and summary.json")
    p.add_argument("--no-gradient-check", dest="gradient_check", action="store_false",
                   help="skip the finite-difference check of the gradients at the baseline")
    p.set_defaults(func=run)


def _error(msg: str) -> int:
    return outputs.print_error(f"error: {msg}", 2, _log)


def _reanalysis(case, margin: float, div_margin: float | None = None,
                separation: float | None = None, n_sep: int = 2) -> dict:
    """The case pipeline's verdict: the smallest flutter margin (%) over the envelope altitudes
    (an altitude without flutter in the sweep counts with its lower bound, the sweep's last
    speed over M a - 1; ``flutter_margin_is_lower_bound`` says when that bound is the smallest),
    the lowest divergence speed at the envelope's top Mach (None: none in the sweep), the
    smallest divergence margin U_D / (M a) - 1 (%, None: no divergence), and whether the flutter
    speeds clear (1 + margin) M a and the divergence speeds (1 + div_margin) M a (div_margin
    None: the flutter margin), and, with a ``separation``, the first ``n_sep`` elastic modes'
    f_{i+1} / f_i - 1 of the pipeline's modal model (``frequency_separation_pct``, the smallest)
    against it."""
    div_margin = margin if div_margin is None else div_margin
    from asekit.case import pipeline as P
    fa = P.flutter(case)
    # an altitude without flutter up to the sweep's last speed counts with its lower bound
    vals = [m["margin"] if m["margin"] is not None else m.get("margin_lower_bound")
            for m in fa.margins]
    vals = [v for v in vals if v is not None]
    exact = [m["margin"] for m in fa.margins if m["margin"] is not None]
    top = case.flight.envelope_mach[1]
    lo, hi = case.flight.envelope_altitude or (-float("inf"), float("inf"))
    div = [d["speed_ms"] for d in fa.divergence if d["speed_ms"] is not None
           and abs(d["mach"] - top) < 1e-12 and lo <= d["altitude_m"] <= hi]
    env = {m["altitude_m"]: m["envelope_speed_ms"] for m in fa.margins}
    dm = [d["speed_ms"] / env[d["altitude_m"]] - 1 for d in fa.divergence
          if d["speed_ms"] is not None and abs(d["mach"] - top) < 1e-12
          and d["altitude_m"] in env]
    div_ok = all(m >= div_margin - 1e-9 for m in dm)
    pct = 100.0 * min(vals) if len(vals) == len(fa.margins) and vals else None
    sep = None
    if separation is not None:
        model = P.modal_model(case)
        f = model.frequencies_hz[model.n_rigid:][:n_sep]
        sep = 100.0 * float(min(f[1:] / f[:-1] - 1.0))
    return {"flutter_margin_pct": pct,
            "flutter_margin_is_lower_bound": bool(pct is not None
                                                  and (not exact or min(vals) < min(exact))),
            "divergence_speed_ms": min(div) if div else None,
            "divergence_margin_pct": 100.0 * min(dm) if dm else None,
            "frequency_separation_pct": sep,
            "meets_constraints": bool(pct is not None and pct >= 100 * margin - 1e-9
                                      and div_ok and (sep is None
                                                      or sep >= 100 * separation - 1e-7))}


def _ase_verdict(case, problem, verdict: dict) -> dict:
    """With ``design.phase_margin_deg`` / ``design.gain_margin_db``: the pipeline's own AEM1
    margins (FWTF 2 of :func:`asekit.case.pipeline.ase`, FN2 modes) as ``phase_margin_deg`` and
    ``gain_margin_db`` (None: no crossover, i.e. infinite), and ``meets_constraints`` also
    requiring them (issue 28). Without those keys ``verdict`` unchanged."""
    pm_req, gm_req = problem.phase_margin_deg, problem.gain_margin_db
    if pm_req is None and gm_req is None:
        return verdict
    import math

    from asekit.case import pipeline as P
    c = P.ase(case).crossovers[2]
    pm, gm = c.phase_margin_deg, c.gain_margin_db
    ok = (pm_req is None or pm >= pm_req - 1e-6) and (gm_req is None or gm >= gm_req - 1e-6)
    return {**verdict, "phase_margin_deg": pm if math.isfinite(pm) else None,
            "gain_margin_db": gm if math.isfinite(gm) else None,
            "meets_constraints": bool(verdict["meets_constraints"] and ok)}


def _block(ev, paths, verdict: dict) -> dict:
    import numpy as np
    return {"mass_kg": ev.mass_kg, **verdict,
            "predicted_margin_pct": float(np.nanmin(ev.margins) * 100),
            "predicted_divergence_speeds_ms": [None if not np.isfinite(u) else float(u)
                                               for u in ev.divergence_speeds_ms],
            "flutter_speeds_ms": [None if not np.isfinite(u) else float(u) for u in ev.speeds_ms],
            "envelope_speeds_ms": ev.envelope_ms.tolist(),
            "values": dict(zip(paths, ev.values.tolist()))}


def _pct(v) -> str:
    return "none" if v is None else f"{v:+.2f} %"


def _gain(base: dict, opt: dict) -> dict:
    """Mass saved (kg, %) and the smallest flutter margin's gain (percentage points, re-analysed;
    None where a margin is undefined) and the flutter speed's at each envelope altitude (%, the
    optimiser's chain)."""
    bm, om = base["flutter_margin_pct"], opt["flutter_margin_pct"]
    speeds = [None if b is None or o is None else 100.0 * (o / b - 1.0)
              for b, o in zip(base["flutter_speeds_ms"], opt["flutter_speeds_ms"])]
    return {"mass_kg": base["mass_kg"] - opt["mass_kg"],
            "mass_pct": 100 * (1 - opt["mass_kg"] / base["mass_kg"]),
            "flutter_margin_points": None if bm is None or om is None else om - bm,
            "flutter_speeds_pct": speeds}


def _write_case(args, raw: dict, result) -> None:
    from asekit.case.design import set_case_values
    from asekit.case.toml_writer import dumps
    text = dumps(set_case_values(raw, result.paths, result.optimised.values))
    Path(args.out_case).write_text(f"# optimised by asekit optimise {Path(args.design).name} "
                                   f"from {Path(args.case).name}\n" + text)


def run(args) -> int:
    for opt, value in (("--json", args.json), ("--out-case", args.out_case)):
        reason = outputs.check_file(opt, value, dash=opt == "--json")
        if reason:
            return _error(reason)
    reason = outputs.check_dir("--report", getattr(args, "report", None), "the HTML report")
    if reason:
        return _error(reason)
    from asekit.case import load_case
    from asekit.case.design import DesignError, load_design, optimise, with_values
    from asekit.util.validate import read_toml
    try:
        case = load_case(args.case)
        raw = read_toml(args.case)
        problem = load_design(args.design)
    except FileNotFoundError as exc:
        return _error(f"{exc.filename} not found")
    except (DesignError, ValueError) as exc:
        return _error(str(exc))
    quiet = getattr(args, "quiet", False)

    def show(row):
        if not quiet:
            vals = ", ".join(f"{v:.5g}" for v in row["values"])
            print(f"iteration {row['iteration']:3d}: mass {row['mass_kg']:.5g} kg, min margin "
                  f"{row['min_margin_pct']:+.2f} %, [{vals}]", file=sys.stderr)

    result = optimise(case, problem, check_gradients=args.gradient_check, progress=show)
    if args.out_case:
        _write_case(args, raw, result)
        reanalysed = load_case(args.out_case)
    else:
        reanalysed = with_values(case, result.paths, result.optimised.values)
    speed = problem.objective == "flutter_speed"
    # with the flutter_speed objective the flutter margin is maximised, not required
    need = -1.0 if speed else problem.flutter_margin
    margins = (need, problem.divergence_margin if problem.divergence_margin is not None
               or not speed else problem.flutter_margin, problem.frequency_separation,
               problem.frequency_separation_modes)
    base = _block(result.baseline, result.paths,
                  _ase_verdict(case, problem, _reanalysis(case, *margins)))
    opt = _block(result.optimised, result.paths,
                 _ase_verdict(reanalysed, problem, _reanalysis(reanalysed, *margins)))
    doc = {"design": {"objective": problem.objective, "baseline": base, "optimised": opt,
                      "gain": _gain(base, opt),
                      "constraints": list(result.constraints),
                      "gradient_check": {"max_rel_error": result.max_rel_error,
                                         "per_variable": None if result.gradient_check is None
                                         else dict(zip(result.paths,
                                                       result.gradient_check.tolist())),
                                         "seconds": result.gradient_check_seconds},
                      "optimiser": {"method": "SLSQP", "success": result.success,
                                    "message": result.message,
                                    "iterations": len(result.history),
                                    "evaluations": result.evaluations,
                                    "seconds": result.seconds},
                      "flutter_margin_required_pct": None if speed
                      else 100 * problem.flutter_margin,
                      "divergence_margin_required_pct": None
                      if problem.divergence_margin is None else 100 * problem.divergence_margin,
                      "history": list(result.history)},
           "units": {"mass_kg": "kg", "flutter_margin_pct": "%", "seconds": "s",
                     "values": "the unit of each case key (thickness m, point mass kg, "
                               "point-mass position m)"}}
    text = json.dumps(doc, indent=2)
    if getattr(args, "report", None):
        from asekit.case import pipeline as P
        from asekit.case.design_report import write_design_report
        write_design_report(args.report, case, reanalysed, P.flutter(case),
                            P.flutter(reanalysed), list(result.history), doc)
    if args.json == "-":
        print(text)
    elif args.json:
        Path(args.json).write_text(text + "\n")
    need_text = "maximised" if speed else f"required {100 * problem.flutter_margin:+.0f} %"
    print(f"mass {base['mass_kg']:.5g} -> {opt['mass_kg']:.5g} kg, min flutter margin "
          f"{_pct(base['flutter_margin_pct'])} -> {_pct(opt['flutter_margin_pct'])} "
          f"({need_text}, re-analysed), gradient check "
          f"{result.max_rel_error if result.max_rel_error is not None else float('nan'):.2g}",
          file=sys.stderr)
    return 0
