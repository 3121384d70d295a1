"""What ``python -m asekit analyse`` prints and writes: the summary (a dict that is the JSON
output), a plain-text table of it, and an HTML report with the figures a user expects
(planform with FE and aero meshes, mode shapes, V-g and V-f with the flutter point marked,
root locus; with an actuator also the FWTF Bode with its margins and the step responses).

Conventions (docs/conventions.md): SI in the JSON and the table; every JSON key carries its
unit as a suffix (``_ms`` m/s, ``_hz`` Hz, ``_m`` m, ``_s`` s, ``_deg`` deg, ``_pct`` %), and
the document's ``units`` block (:data:`UNITS`) gives the unit of every numeric key;
modes are named as the user reads them: elastic modes 1, 2, ... (the rigid mode not counted)
and ``"rigid pitch"`` (:func:`asekit.util.conventions.mode_number`); every V-g axis is
g = 2 Re p / |Im p|, > 0 unstable.
"""

from __future__ import annotations

import html
import json
import math
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from asekit.ase import loop as ase_mod
from asekit.case import pipeline as P
from asekit.case.schema import Case
from asekit.util.conventions import mode_label, mode_number
from asekit.util.plotting import new_figure, plot_vg, save_figure

#: The unit of every numeric key of the summary (the JSON's ``units`` block; docs/conventions.md).
#: Key suffixes name the unit too: ``_ms`` m/s, ``_hz`` Hz, ``_m`` m, ``_s`` s, ``_deg`` deg,
#: ``_pct`` %; the keys without a suffix are dimensionless or listed here with theirs.
UNITS = {
    "frequencies_hz": "Hz", "frequency_hz": "Hz",
    "altitude_m": "m",
    "speed_ms": "m/s", "matched_speed_ms": "m/s", "envelope_speed_ms": "m/s",
    "flutter_speed_ms": "m/s", "velocity_ms": "m/s", "speed_upper_bound_ms": "m/s",
    "flutter_at_or_below_ms": "m/s", "flutter_speed_upper_bound_ms": "m/s",
    "flutter_speed_lower_bound_ms": "m/s",
    "margin_upper_bound": "- (U_f / U_envelope - 1 is at most this)",
    "margin_lower_bound": "- (U_f / U_envelope - 1 is at least this)",
    "density": "kg/m^3",
    "mach": "-", "matched_mach": "-", "envelope_mach": "-",
    "margin": "- (U_f / U_envelope - 1)",
    "flutter_speed_index": "- (U_f / (b_s omega_alpha sqrt(mu)))",
    "frequency_ratio": "- (f_f / f_alpha)",
    "mode": "elastic mode number from 1 (the rigid mode not counted) or 'rigid pitch'",
    "labels": "mode names in array order: 'rigid pitch', then the elastic modes 1, 2, ...",
    "n_rigid": "count", "boxes": "count",
    "max_real_pole": "1/s (largest Re of the closed-loop poles, > 0 unstable)",
    "settling_s": "s", "steady_error_pct": "%", "corner_overshoot_pct": "%",
    "fwtf_phase_margin_deg": "deg",
    "seconds": "s (wall-clock time per step)",
}


@dataclass(frozen=True)
class Analysis:
    """Everything one ``analyse`` run computed: the case, its modal model, GAF database,
    flutter analysis, ASE result (None without an actuator) and step timings (s)."""

    case: Case
    modal: object
    database: object
    flutter: object
    ase: object
    seconds: dict


def run_analysis(case: Case, progress: bool = False) -> Analysis:
    """Run the whole pipeline of ``case`` and time each step."""
    sec = {}
    t = time.perf_counter()
    modal = P.modal_model(case)
    sec["modes"] = time.perf_counter() - t
    t = time.perf_counter()
    db = P.gaf_database(case, progress=progress)
    sec["gaf_database"] = time.perf_counter() - t
    t = time.perf_counter()
    fa = P.flutter(case, db=db)
    sec["flutter"] = time.perf_counter() - t
    t = time.perf_counter()
    ase = P.ase(case, db=db)
    if ase is not None:
        sec["ase"] = time.perf_counter() - t
    return Analysis(case, modal, db, fa, ase, sec)


def _f(v):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else float(v)


def summary(a: Analysis) -> dict:
    """The JSON document of an analysis (schema in docs/case-format.md)."""
    c = a.case
    fl = []
    for r in a.flutter.results:
        f = None if r.unstable_at_start else r.flutter     # "at or below U0" has no speed
        row = {"mach": r.mach, "altitude_m": r.condition.altitude, "density": r.condition.density,
               "speed_ms": None if f is None else float(f.speed),
               "frequency_hz": None if f is None else float(f.frequency_hz),
               "mode": None if f is None else mode_number(f.mode, f.n_rigid),
               "unstable_at_first_point": bool(r.unstable_at_start),
               "speed_upper_bound_ms": None}
        if r.unstable_at_start:
            kind = P._start_kind(r)
            row["speed_upper_bound_ms"] = float(c.flight.velocities[0])
            row["mode"] = mode_number(r.start_mode, r.pk.n_rigid)
            row["note"] = (f"unstable at the first point of the sweep: {kind} at or below "
                           f"{c.flight.velocities[0]:g} m/s")
        if c.flutter_index is not None and f is not None:
            fs = c.flutter_index
            w_a = 2 * math.pi * fs.f_alpha
            row["flutter_speed_index"] = float(f.speed / (fs.semichord * w_a * math.sqrt(fs.mass_ratio)))
            row["frequency_ratio"] = float(f.frequency_hz / fs.f_alpha)
        fl.append(row)
    n_r = int(a.modal.n_rigid)
    out = {"case": c.name, "reference": c.reference,
           "units": dict(UNITS),
           "modes": {"frequencies_hz": [float(v) for v in a.modal.frequencies_hz],
                     "n_rigid": n_r,
                     "labels": [mode_number(j, n_r) for j in range(len(a.modal.frequencies_hz))]},
           "boxes": int(a.database.metadata.get("boxes", 0)) or None,
           "flutter": fl,
           "divergence": [{"mach": d["mach"], "altitude_m": d["altitude_m"],
                           "speed_ms": _f(d["speed_ms"])} for d in a.flutter.divergence],
           "match_points": [dict(m) for m in a.flutter.match_points],
           "flutter_margins": [dict(m) for m in a.flutter.margins],
           "notes": list(a.flutter.notes),
           "seconds": {k: float(v) for k, v in a.seconds.items()}}
    if a.ase is not None:
        s = a.ase
        out["ase"] = {"mach": s.mach, "altitude_m": s.altitude, "velocity_ms": s.velocity,
                      "stable": dict(s.stable), "max_real_pole": dict(s.max_real_pole),
                      "settling_s": {k: _f(v) for k, v in s.settling_s.items()},
                      "steady_error_pct": {k: _f(v * 100) for k, v in s.steady_error.items()},
                      "corner_overshoot_pct": {k: {c: _f(x * 100) for c, x in v.items()}
                                               for k, v in s.corner_overshoot.items()},
                      "fwtf_phase_margin_deg": {str(i): _f(x.phase_margin_deg)
                                                for i, x in s.crossovers.items()}}
    return out


def _cell(v, fmt="{:.4g}"):
    if v is None:
        return "-"
    if isinstance(v, float):
        return fmt.format(v)
    return str(v)


def _speed_cell(row: dict) -> str:
    """The U_f cell of a flutter row: the speed, '<=U0' when unstable at the first point."""
    if row.get("speed_upper_bound_ms") is not None:
        return f"<={row['speed_upper_bound_ms']:.2f}"
    return _cell(row["speed_ms"], "{:.2f}")


def _margin_text(m: dict) -> str:
    """A margin line's value: the margin, its bound ('at most' / 'at least') or '-', with the
    note."""
    env = m["envelope_speed_ms"]
    if m["margin"] is not None:
        where = ("flutter inside the envelope by" if m["margin"] < 0 else
                 "flutter outside the envelope by")
        return (f"{100 * m['margin']:+.1f} % ({where} {abs(100 * m['margin']):.1f} %: U_f "
                f"{m['flutter_speed_ms']:.1f} vs {env:.1f} m/s)")
    if m.get("margin_upper_bound") is not None:
        u = m["flutter_speed_upper_bound_ms"]
        return (f"at most {100 * m['margin_upper_bound']:+.1f} % (flutter at or below {u:.1f} "
                f"m/s, the first point of the sweep, vs {env:.1f} m/s"
                + (": inside the envelope)" if u < env else "; start the sweep lower)"))
    if m.get("margin_lower_bound") is not None:
        return (f"at least {100 * m['margin_lower_bound']:+.1f} % (no flutter up to "
                f"{m['flutter_speed_lower_bound_ms']:.1f} m/s vs {env:.1f} m/s)")
    return "-" + (f" ({m['note']})" if m.get("note") else "")


def format_summary(s: dict, width: int = 100) -> str:
    """A plain-text summary of :func:`summary` that fits ``width`` columns."""
    lines = textwrap.wrap(f"case {s['case']}" + (f"  ({s['reference']})" if s.get("reference")
                                                  else ""), width, subsequent_indent="  ")
    f = s["modes"]["frequencies_hz"]
    r = s["modes"]["n_rigid"]
    lines.append("modes (Hz): " + ", ".join(f"{mode_label(j, r)} {v:.4g}"
                                            for j, v in enumerate(f) if j >= r)
                 + (f"  (+ {mode_label(0, r)})" if r else ""))
    has_fsi = any("flutter_speed_index" in row for row in s["flutter"])
    head = f"{'Mach':>6} {'altitude m':>10} {'rho kg/m3':>10} {'U_f m/s':>9} {'f_f Hz':>8} {'mode':>4}"
    if has_fsi:
        head += f" {'FSI':>7} {'w_f/w_a':>7}"
    head += "  note"
    lines += ["", "flutter (p-k, rigid modes held)", head]
    for row in s["flutter"]:
        ln = (f"{row['mach']:>6.3g} {_cell(row['altitude_m'], '{:.0f}'):>10} "
              f"{row['density']:>10.4g} {_speed_cell(row):>9} "
              f"{_cell(row['frequency_hz'], '{:.2f}'):>8} {_cell(row['mode']):>4}")
        if has_fsi:
            ln += (f" {_cell(row.get('flutter_speed_index'), '{:.4f}'):>7}"
                   f" {_cell(row.get('frequency_ratio'), '{:.4f}'):>7}")
        if row["unstable_at_first_point"]:
            ln += "  UNSTABLE AT FIRST POINT"
        elif row["speed_ms"] is None:
            ln += "  none in sweep"
        lines.append(ln[:width])
    div = [d for d in s["divergence"] if d["speed_ms"] is not None]
    if div:
        lines += [""] + textwrap.wrap("static divergence (m/s): " + ", ".join(
            f"M {d['mach']:g} {_cell(d['altitude_m'], '{:.0f} m')} {d['speed_ms']:.1f}"
            for d in div), width, subsequent_indent="  ")
    for m in s["match_points"]:
        lines.append(f"match point at {_cell(m['altitude_m'], '{:.0f}')} m: "
                     + (f"none ({m['no_match']})" if m["matched_mach"] is None else
                        f"M {m['matched_mach']:.3f} ({m['matched_speed_ms']:.1f} m/s)"))
    for m in s["flutter_margins"]:
        lines.append(f"flutter margin at {_cell(m['altitude_m'], '{:.0f}')} m, envelope top "
                     f"M {m['envelope_mach']:g}: " + _margin_text(m))
    if "ase" in s:
        a = s["ase"]
        lines += ["", f"ASE loop at M {a['mach']:g}, {a['altitude_m']:g} m:"]
        for t in a["stable"]:
            ov = a["corner_overshoot_pct"][t]
            st = a["settling_s"][t]
            lines += textwrap.wrap(
                f"{t}: {'stable' if a['stable'][t] else 'UNSTABLE'} (max Re pole "
                f"{a['max_real_pole'][t]:.3g} 1/s); fin root "
                + ("never inside the 2 % band" if st is None else f"settles in {1e3 * st:.1f} ms")
                + f", final error {_cell(a['steady_error_pct'][t], '{:.2f}')} %; corner "
                f"overshoot {min(ov.values()):.0f}-{max(ov.values()):.0f} %", width,
                initial_indent="  ", subsequent_indent="    ")
    for n in s["notes"]:
        lines += textwrap.wrap("note: " + n, width, subsequent_indent="  ")
    lines.append("")
    lines.append("times (s): " + ", ".join(f"{k} {v:.2f}" for k, v in s["seconds"].items()))
    out = []
    for ln in lines:
        out += textwrap.wrap(ln, width, subsequent_indent="    ") if len(ln) > width else [ln]
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# figures and the HTML report
# ---------------------------------------------------------------------------------------------
def fig_planform(a: Analysis):
    fig, ax = new_figure(f"{a.case.name}: planform, FE mesh (black) and aerodynamic boxes (blue)")
    mesh = P.structural_mesh(a.case)
    for e in mesh.elements:
        xy = mesh.nodes[np.r_[e, e[0]]]
        ax.plot(xy[:, 1], xy[:, 0], "k-", lw=0.6)
    for c in P.box_mesh(a.case).corners:
        xy = c[[0, 1, 2, 3, 0]]
        ax.plot(xy[:, 1], xy[:, 0], "C0-", lw=0.4, alpha=0.7)
    s = a.case.support
    if s.kind == "shaft":
        ax.plot(s.axis_point[1], s.axis_point[0], "rs", label="pitch axis")
        ax.legend()
    ax.set_xlabel("y (m, span)")
    ax.set_ylabel("x (m, downstream)")
    ax.invert_yaxis()
    ax.set_aspect("equal")
    return fig


def fig_modes(a: Analysis, n: int = 4):
    m = a.modal
    idx = list(range(m.n_rigid, min(len(m.frequencies_hz), m.n_rigid + n)))
    fig, axes = new_figure(f"{a.case.name}: mode shapes (w, contours)", ncols=len(idx),
                           figsize=(3.2 * len(idx), 3.6))
    axes = np.atleast_1d(axes)
    tri = np.concatenate([m.elements[:, [0, 1, 2]], m.elements[:, [0, 2, 3]]])
    for ax, j in zip(axes, idx):
        w = m.shapes[:, 0, j]
        ax.tricontourf(m.nodes[:, 1], m.nodes[:, 0], tri, w / np.abs(w).max(), levels=15,
                       cmap="RdBu_r")
        ax.set_title(f"{mode_label(j, m.n_rigid)}: {m.frequencies_hz[j]:.4g} Hz")
        ax.set_xlabel("y (m)")
        ax.set_ylabel("x (m)")
        ax.invert_yaxis()
        ax.set_aspect("equal")
    return fig


def fig_vg(a: Analysis, result):
    """V-g and V-f of the p-k roots at one condition (:func:`asekit.util.plotting.plot_vg`: g = 2 Re
    p / |Im p|, > 0 unstable; modes named "mode 1", ...), the flutter point starred."""
    pk = result.pk
    alt = result.condition.altitude
    where = f"{alt:g} m" if alt is not None else f"rho {result.condition.density:.4g} kg/m^3"
    fig, (ax1, ax2) = new_figure(f"{a.case.name}: V-g and V-f, M {result.mach:g}, {where}",
                                 nrows=2, figsize=(6.4, 6.4), sharex=True)
    plot_vg(ax1, ax2, pk.velocities, pk.p, pk.mode_labels, g_limits=None)
    f = result.flutter
    if f is not None:
        ax1.plot(f.speed, 0.0, "r*", ms=12, label=f"flutter {f.speed:.1f} m/s ({f.mode_name})")
        ax2.plot(f.speed, f.frequency_hz, "r*", ms=12)
    ax1.set_ylim(-0.5, 0.3)
    ax1.legend(ncol=2)
    ax2.set_xlabel("airspeed U (m/s)")
    return fig


def fig_root_locus(a: Analysis, result):
    pk = result.pk
    fig, ax = new_figure(f"{a.case.name}: root locus of the p-k roots, M {result.mach:g}")
    for j, name in enumerate(pk.mode_labels):
        ax.plot(pk.p[:, j].real, pk.p[:, j].imag / (2 * math.pi), ".-", ms=2, label=name)
    f = result.flutter
    if f is not None:
        ax.plot(0.0, f.frequency_hz, "r*", ms=12, label=f"flutter {f.speed:.1f} m/s")
    ax.legend(ncol=2, fontsize=8)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("Re p (1/s), > 0 unstable")
    ax.set_ylabel("Im p / 2 pi (Hz)")
    return fig


def fig_ase_bode(a: Analysis):
    s = a.ase
    f = np.logspace(0, 3.5, 800)
    fig, (ax1, ax2) = new_figure(f"{a.case.name}: forward paths FWTF 1-3, M {s.mach:g}",
                                 nrows=2, figsize=(6.4, 6.4), sharex=True)
    for i in (1, 2, 3):
        h = ase_mod.frequency_response(ase_mod.forward_path(s.model, s.controller, i), f)
        ax1.semilogx(f, 20 * np.log10(np.abs(h)), label=f"FWTF {i}")
        ax2.semilogx(f, np.degrees(np.unwrap(np.angle(h))))
        c = s.crossovers[i]
        if c.gain_crossovers_hz.size:
            ax1.plot(c.gain_crossovers_hz[0], 0.0, "k|", ms=12)
    ax1.axhline(0.0, color="k", lw=0.8)
    ax2.axhline(-180.0, color="k", lw=0.8)
    ax1.set_ylabel("gain (dB)")
    ax2.set_ylabel("phase (deg)")
    ax2.set_xlabel("frequency (Hz)")
    ax1.legend()
    return fig


def fig_ase_steps(a: Analysis):
    s = a.ase
    fig, ax = new_figure(f"{a.case.name}: power-limited step, fin-root pitch")
    for t, sim in s.simulations.items():
        ax.plot(sim.t * 1e3, np.degrees(sim.fin_root), label=t)
    ax.axhline(a.case.actuator.step_deg, color="k", lw=0.8, ls="--", label="command")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("fin-root pitch (deg)")
    ax.set_ylim(-0.5 * a.case.actuator.step_deg, 2.5 * a.case.actuator.step_deg)
    ax.legend()
    return fig


def figures(a: Analysis) -> dict:
    """{name: figure} of the report (V-g / V-f and root locus for the first Mach at each flight
    condition, plus the ASE figures with an actuator)."""
    figs = {"planform": fig_planform(a), "modes": fig_modes(a)}
    first_mach = a.case.aero.machs[-1]
    for i, r in enumerate(x for x in a.flutter.results if x.mach == first_mach):
        figs[f"vg_{i}"] = fig_vg(a, r)
        if i == 0:
            figs["root_locus"] = fig_root_locus(a, r)
    if a.ase is not None:
        figs["ase_bode"] = fig_ase_bode(a)
        figs["ase_steps"] = fig_ase_steps(a)
    return figs


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder and
    :func:`os.replace`: a reader (or an interrupted run) sees the old file or the new one,
    never half of it."""
    import os
    import tempfile
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _report_page(s: dict, names) -> str:
    body = "\n".join(f'<figure><img src="{html.escape(n)}" alt="{html.escape(n)}"></figure>'
                     for n in names)
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>asekit: "
            f"{html.escape(s['case'])}</title><style>body{{font-family:sans-serif;max-width:70em;"
            f"margin:auto}} img{{max-width:100%}} pre{{background:#f4f4f4;padding:1em}}</style>"
            f"</head><body><h1>{html.escape(s['case'])}</h1><pre>"
            f"{html.escape(format_summary(s, width=120))}</pre>{body}</body></html>")


def write_report(a: Analysis, directory) -> Path:
    """Write ``directory/index.html`` (summary table and figures) with the PNGs beside it and
    ``summary.json``; returns the index path.

    The report is written into a temporary folder next to ``directory`` and moved into place
    when complete (an existing report there is replaced), so an interrupted run (SIGINT) leaves
    the previous report or none, never PNGs without their ``index.html``."""
    import os
    import shutil
    import tempfile
    d = Path(directory)
    d.parent.mkdir(parents=True, exist_ok=True)
    if d.exists() and not d.is_dir():
        raise NotADirectoryError(f"--report {d}: exists and is not a directory")
    tmp = Path(tempfile.mkdtemp(prefix=f".{d.name}.", suffix=".partial", dir=d.parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)           # mkdtemp's folder is private (0700)
    old = None
    try:
        s = summary(a)
        (tmp / "summary.json").write_text(json.dumps(s, indent=2))
        names = [save_figure(f, tmp, n).name for n, f in figures(a).items()]
        (tmp / "index.html").write_text(_report_page(s, names))
        if d.exists():
            old = d.with_name(f".{d.name}.{os.getpid()}.old")
            os.replace(d, old)
        os.replace(tmp, d)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and not d.exists():
            os.replace(old, d)              # put the previous report back
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return d / "index.html"
