"""Chapter 3.2.2-3.3 reproduction: RFA fit, p-k (Tables 9-10), root locus, time domain
(Table 11) and divergence for the reference fin, plus the HA145B cross-check.

The fin's GAF database comes from :func:`asekit.case.pipeline.gaf_database` on the fin's case (rigid pitch mode
first). When that module or its cache is not available the fin quantities are reported as None
with a note, and only the Nastran HA145B validation is computed.

Conventions: densities from the 1976 standard atmosphere (the thesis's Table 9/10 densities at
2500 m and 5000 m, 1.173 and 0.902 kg/m^3, are not standard: 0.957 and 0.736); rigid pitch mode
held (actuator clamped, Eq. 3.12 s-set); airspeed sweep 100-460 m/s (the thesis swept 180-340
m/s; the first instability of any kind is searched up to 460 m/s). Flutter keys report the first
oscillatory instability in the sweep, None if there is none.
"""

from __future__ import annotations

import numpy as np

from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import InfinitePlateSpline, fe_spline
from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    divergence_speeds,
    first_of,
    initial_state,
    matched_mach,
    pk_flutter,
    pk_flutter_many,
    pk_instabilities,
    pk_instabilities_many,
    root_locus,
    root_locus_instabilities,
    simulate_free_response,
    time_domain_sweep,
)
from asekit.aeroelastic.statespace import ModalArrays, aeroelastic_matrices, modal_arrays
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline
from asekit.case.schema import ConvergenceSpec
from asekit.case.variants import with_boxes, with_mesh
from asekit.io.op4 import ha145b_path, load_ha145b
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import distributed_case, fin_case
from asekit.rfa import default_lag_roots, roger_fit, roger_fit_database
from asekit.util.cache import CacheError, load_npz, save_npz
from asekit.util.paths import FIN_FILE, user_cache_dir
from asekit.util.plotting import THESIS_COLOR, new_figure, plot_vg

VELOCITIES = np.arange(100.0, 460.0 + 1e-9, 2.0)      # m/s
ALTITUDES = (0.0, 2500.0, 5000.0)                       # m
MACHS = {"M075": 0.75, "M06": 0.6}
N_LAGS = 4


def load_fin_gafs():
    """(GafDatabase, ModalModel) of the fin, or (None, reason) when not available."""
    try:
        case = fin_case()
        db, modal = pipeline.gaf_database(case, progress=False), pipeline.modal_model(case)
    except Exception as exc:             # noqa: BLE001 - report any build/cache failure as a note
        return None, f"fin GAF database unavailable: {exc}"
    return (db, modal), ""


def fin_rfa(db, mach: float, n_lags: int = N_LAGS, constrain_k0: bool = False, lag_roots=None):
    """Roger fit of the fin's GAFs at ``mach`` (default lag roots over the database's k)."""
    return roger_fit_database(db, mach, n_lags=n_lags, constrain_k0=constrain_k0,
                              lag_roots=lag_roots)


def analyse_condition(modal, db, mach: float, altitude: float, velocities=VELOCITIES,
                      density: float | None = None) -> dict:
    """p-k at one (Mach, altitude): result, instabilities, first flutter and first of any kind."""
    rho = float(standard_atmosphere(altitude).density) if density is None else density
    gaf = db.at(mach)
    res = pk_flutter(modal, gaf, rho, velocities)
    inst = pk_instabilities(res, modal, gaf)
    return {"density": rho, "gaf": gaf, "pk": res, "instabilities": inst,
            "flutter": first_of(inst, "flutter"), "divergence": first_of(inst, "divergence"),
            "first": first_of(inst)}


def analyse_conditions(modal, db, points, velocities=VELOCITIES) -> list[dict]:
    """:func:`analyse_condition` at every (Mach, altitude) of ``points``, the p-k sweeps
    solved together (issue 23: :func:`asekit.aeroelastic.flutter.pk_flutter_many` and
    :func:`~asekit.aeroelastic.flutter.pk_instabilities_many`; each equal to its own sweep)."""
    rhos = [float(standard_atmosphere(h).density) for _, h in points]
    gafs = [db.at(mach) for mach, _ in points]
    sweeps = pk_flutter_many(modal, list(zip(gafs, rhos)), velocities)
    found = pk_instabilities_many(sweeps, modal, gafs)
    return [{"density": rho, "gaf": gaf, "pk": res, "instabilities": inst,
             "flutter": first_of(inst, "flutter"), "divergence": first_of(inst, "divergence"),
             "first": first_of(inst)} for rho, gaf, res, inst in zip(rhos, gafs, sweeps, found)]


def time_domain_first(modal, fit, rho: float, velocities=np.arange(100.0, 461.0, 10.0)):
    """Time-domain growth sweep and the onset kind (flutter if the A_sys root crossing near the
    onset is oscillatory, else divergence)."""
    td = time_domain_sweep(modal, fit, rho, velocities, coordinate=1)
    kind = None
    if td.onset_speed is not None:
        ev = np.linalg.eigvals(aeroelastic_matrices(modal, fit, rho, td.onset_speed).A)
        crit = ev[np.argmin(np.abs(ev.real))]
        kind = "flutter" if abs(crit.imag) > 1e-3 * max(abs(crit), 1.0) else "divergence"
    return td, kind


def ha145b_check() -> dict | None:
    """p-k, root locus and time domain on Nastran's HA145B (None if the file is absent)."""
    if not ha145b_path().exists():
        return None
    case = load_ha145b()
    modal = modal_arrays(M=case.M, K=case.K, n_rigid=0)
    gaf = TabulatedGaf(case.k, case.Q, case.b_ref, mach=0.0)
    U = np.linspace(4800.0, 25200.0, 69)
    res = pk_flutter(modal, gaf, case.rho, U)
    pk = first_of(pk_instabilities(res, modal, gaf), "flutter")
    fit = roger_fit(case.k, case.Q, case.b_ref, n_lags=4)
    rl = root_locus(modal, fit, case.rho, U)
    rlf = first_of(root_locus_instabilities(rl, modal, fit), "flutter")
    td = time_domain_sweep(modal, fit, case.rho, np.linspace(11500, 14000, 6), t_end=3.0)
    return {"case": case, "pk_result": res, "pk": pk, "fit": fit, "root_locus": rl,
            "rl": rlf, "td": td}


def _val(x, attr):
    return None if x is None else float(getattr(x, attr))


def run(figures: bool = False) -> ChapterResult:
    """Compute the chapter's quantities (and figures when ``figures``)."""
    q = []
    figs = {}
    ha = ha145b_check()
    note_ha = "" if ha is not None else "HA145B benchmark file not present"
    q.append(Quantity("flutter.ha145b.pk.speed_ins", _val(ha and ha["pk"], "speed"), "in/s",
                      "Nastran HA145B: published ~12672 in/s" if ha else note_ha))
    q.append(Quantity("flutter.ha145b.pk.freq_hz", _val(ha and ha["pk"], "frequency_hz"), "Hz",
                      "Nastran HA145B: published ~3.1 Hz" if ha else note_ha))
    q.append(Quantity("flutter.ha145b.root_locus.speed_ins", _val(ha and ha["rl"], "speed"),
                      "in/s", "Roger RFA, 4 lags" if ha else note_ha))
    q.append(Quantity("flutter.ha145b.time_domain.speed_ins",
                      None if ha is None else ha["td"].onset_speed, "in/s", note_ha))

    data, reason = load_fin_gafs()
    fin_keys = [f"flutter.pk.{mk}.h{int(h)}.{s}" for mk in MACHS for h in ALTITUDES
                for s in ("speed_ms", "freq_hz")]
    fin_keys += ["flutter.root_locus.M075.h0.speed_ms", "flutter.root_locus.M075.h0.freq_hz",
                 "flutter.time_domain.M075.h0.speed_ms", "rfa.M075.fit_error",
                 "flutter.divergence.M075.h0.speed_ms",
                 "flutter.first_instability.pk.M075.h0.speed_ms",
                 "flutter.first_instability.root_locus.M075.h0.speed_ms",
                 "flutter.first_instability.time_domain.M075.h0.speed_ms"]
    fin_keys += [f"flutter.extrapolated.pk.M075.h0.{s}"
                 for s in ("speed_ms", "speed_error_ms", "freq_hz", "freq_error_hz")]
    if data is None:
        for key in fin_keys:
            unit = "Hz" if key.endswith("_hz") else ("-" if "fit_error" in key else "m/s")
            q.append(Quantity(key, None, unit, reason))
        if figures and ha is not None:
            figs.update(ha145b_figures(ha))
        return ChapterResult(chapter="flutter", quantities=tuple(q), figures=figs,
                             failures=(reason,))

    db, modal = data
    sweep_note = "1976 std atm; sweep 100-460 m/s"
    conds = {}
    together = iter(analyse_conditions(modal, db, [(mach, h) for mach in MACHS.values()
                                                   for h in ALTITUDES]))
    for mk, mach in MACHS.items():
        for h in ALTITUDES:
            c = next(together)
            conds[(mk, h)] = c
            fl = c["flutter"]
            note = sweep_note if fl is None else f"{fl.describe()}; {sweep_note}"
            q.append(Quantity(f"flutter.pk.{mk}.h{int(h)}.speed_ms", _val(fl, "speed"), "m/s",
                              note + ("; none found" if fl is None else "")))
            q.append(Quantity(f"flutter.pk.{mk}.h{int(h)}.freq_hz", _val(fl, "frequency_hz"),
                              "Hz", note))
    c0 = conds[("M075", 0.0)]
    fit = fin_rfa(db, 0.75)
    rl = root_locus(modal, fit, c0["density"], VELOCITIES)
    rl_inst = root_locus_instabilities(rl, modal, fit)
    rl_fl = first_of(rl_inst, "flutter")
    q.append(Quantity("flutter.root_locus.M075.h0.speed_ms", _val(rl_fl, "speed"), "m/s",
                      f"Roger, {fit.n_lags} lags"))
    q.append(Quantity("flutter.root_locus.M075.h0.freq_hz", _val(rl_fl, "frequency_hz"), "Hz",
                      ""))
    td, td_kind = time_domain_first(modal, fit, c0["density"])
    q.append(Quantity("flutter.time_domain.M075.h0.speed_ms",
                      td.onset_speed if td_kind == "flutter" else None, "m/s",
                      f"{td.describe()} ({td_kind})" if td_kind else td.describe()))
    q.append(Quantity("rfa.M075.fit_error", fit.fit_error, "-",
                      "||Q - Q~||_F / ||Q||_F over all k"))
    gaf0 = c0["gaf"]
    dv = divergence_speeds(modal, gaf0.Q[0], c0["density"])
    q.append(Quantity("flutter.divergence.M075.h0.speed_ms",
                      float(dv[0]) if dv.size else None, "m/s",
                      "static, det(K_ss - q Q_ss^R(k_min)) = 0"))
    q.append(Quantity("flutter.first_instability.pk.M075.h0.speed_ms",
                      _val(c0["first"], "speed"), "m/s",
                      c0["first"].kind if c0["first"] else "none up to 460 m/s"))
    rl_first = first_of(rl_inst)
    q.append(Quantity("flutter.first_instability.root_locus.M075.h0.speed_ms",
                      _val(rl_first, "speed"), "m/s",
                      rl_first.kind if rl_first else "none up to 460 m/s"))
    q.append(Quantity("flutter.first_instability.time_domain.M075.h0.speed_ms",
                      td.onset_speed, "m/s", td_kind or "none up to 460 m/s"))
    conv = converged_flutter_study(db, compute=converged_study_requested())
    if conv is None:
        conv_note = (f"not computed (about 8 min, 7 GB the first time): {CONVERGED_HINT}")
        speed = freq = None
    else:
        (sc, ss), (ac, asp) = conv["structure"], conv["aero"]
        cs, ca = conv["change_structure"], conv["change_aero"]
        conv_note = (f"distributed shaft, FE {sc}x{ss}, boxes {ac}x{asp}; last refinements "
                     f"{'-' if cs is None else f'{100 * cs:.2f}'} % (FE), "
                     f"{'-' if ca is None else f'{100 * ca:.2f}'} % (boxes)"
                     + ("" if conv["converged"] else "; NOT converged to 1 %"))
        speed, freq = conv["speed"], conv["freq"]
    q.append(Quantity("flutter.converged.pk.M075.h0.speed_ms", speed, "m/s", conv_note,
                      computed=conv is not None))
    q.append(Quantity("flutter.converged.pk.M075.h0.freq_hz", freq, "Hz", conv_note,
                      computed=conv is not None))
    q.extend(extrapolated_quantities(extrapolated_flutter(db)))
    damp = damping_study(modal, db, velocities=DAMPING_VELOCITIES)
    q.append(Quantity("flutter.damping.pk.M075.h0.speed_ms",
                      [r["speed"] for r in damp if r["kind"] == "zeta"], "m/s",
                      "6x7 model; modal damping ratio "
                      + ", ".join(f"{100 * z:g}" for z in DAMPING_RATIOS) + " %"))
    q.append(Quantity("flutter.structural_g.pk.M075.h0.speed_ms",
                      [r["speed"] for r in damp if r["kind"] == "g"], "m/s",
                      "6x7 model; structural damping g = "
                      + ", ".join(f"{g:g}" for g in STRUCTURAL_G)
                      + " (viscous equivalent g K / omega_f at the flutter frequency)"))
    if figures:
        figs.update(fin_figures(modal, db, fit, conds, rl, td))
        if ha is not None:
            figs.update(ha145b_figures(ha))
    return ChapterResult(chapter="flutter", quantities=tuple(q), figures=figs)


# --------------------------------------------------------------------------------------------
# figures (also used by notebooks/ch3_flutter.ipynb)
# --------------------------------------------------------------------------------------------
def fig_rfa_element(fit, i: int, j: int, thesis_figure: str = "Fig 23"):
    """Data vs Roger fit of element Q_ij in the complex plane (Figs 23-24)."""
    fig, ax = new_figure(f"RFA fit of Q_{i + 1}{j + 1} (Mach {fit.mach})", thesis_figure)
    kk = np.geomspace(max(fit.k[0], 1e-4), fit.k[-1], 300)
    qf = fit.evaluate(kk)[:, i, j]
    ax.plot(fit.Q[:, i, j].real, fit.Q[:, i, j].imag, "o", label="GAF data")
    ax.plot(qf.real, qf.imag, "-", label=f"Roger, {fit.n_lags} lags")
    qd = fit.evaluate(fit.k)[:, i, j]
    ax.plot(qd.real, qd.imag, "x", color="C1", label="fit at the data k")
    for a, b in zip(fit.Q[:, i, j], qd):
        ax.plot([a.real, b.real], [a.imag, b.imag], color="0.6", lw=0.6)
    for n, (kk_, a) in enumerate(zip(fit.k, fit.Q[:, i, j])):
        if n % 2 == 0 or n == fit.k.size - 1:        # every other k labelled: no overprint
            ax.annotate(f"k={kk_:.3g}", (a.real, a.imag), textcoords="offset points",
                        xytext=(4, 4 if n % 4 == 0 else -10), fontsize=6, color="C0")
    err = getattr(fit, "element_error", None)
    if err is not None:
        ax.set_title(f"element fit error {float(np.asarray(err)[i, j]):.3f}", fontsize=9)
    ax.set_xlabel("Re Q (per unit q)")
    ax.set_ylabel("Im Q (per unit q)")
    ax.legend()
    return fig


#: The thesis's flight envelope (Table 3): Mach 0.4-0.6, altitude 0-5000 m.
FLIGHT_MACH = (0.4, 0.6)
FLIGHT_ALTITUDE = (0.0, 5000.0)
#: The customary flutter margin: flutter-free up to 1.15 x the envelope's limit speed
#: (e.g. 14 CFR 25.629(b)(1), 1.15 V_D), applied here to the Mach limit at each altitude.
FLUTTER_MARGIN = 0.15


def _envelope():
    """(u_min, u_max, h_max) of the analysis envelope in data/fin.toml (m/s, m/s, m)."""
    c = fin_case()
    return float(c.aero.u_min), float(c.flight.velocities[-1]), float(max(c.flight.altitudes))


def fig_mach_airspeed_altitude(points=(), thesis_figure: str = "Fig 25"):
    """Mach lines in the airspeed-altitude plane (Fig 25) with the analysis envelope of
    data/fin.toml shaded; optional (U, h, label) points, one marker style per label."""
    fig, ax = new_figure("Mach - airspeed - altitude (1976 standard atmosphere)", thesis_figure)
    h = np.linspace(0, 12000, 100)
    a = standard_atmosphere(h).speed_of_sound
    for m in (0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.9, 1.0):
        ax.plot(m * a, h / 1000, lw=1, color="0.55")
        ax.annotate(f"M {m}", (m * a[-1], h[-1] / 1000), textcoords="offset points",
                    xytext=(0, 3), ha="center", fontsize=7, color="0.35")
    u0, u1, hmax = _envelope()
    ax.fill_between([u0, u1], 0, hmax / 1000, color="C0", alpha=0.10,
                    label=f"analysis envelope {u0:.0f}-{u1:.0f} m/s, 0-{hmax / 1000:g} km")
    hf = np.linspace(*FLIGHT_ALTITUDE, 30)
    af = standard_atmosphere(hf).speed_of_sound
    ax.fill_betweenx(hf / 1000, FLIGHT_MACH[0] * af, FLIGHT_MACH[1] * af, color="C2", alpha=0.3,
                     label=f"flight envelope (Table 3): M {FLIGHT_MACH[0]}-{FLIGHT_MACH[1]}, "
                           f"0-{FLIGHT_ALTITUDE[1] / 1000:g} km")
    labels = sorted({lab for _, _, lab in points})
    for n, lab in enumerate(labels):
        pts = [(u, hh) for u, hh, lb in points if lb == lab]
        ax.plot([u for u, _ in pts], [hh / 1000 for _, hh in pts], "*^sD"[n % 4], ms=9,
                color=f"C{n + 1}", label=f"p-k flutter, {lab}")
    ax.set_xlabel("true airspeed (m/s)")
    ax.set_ylabel("altitude (km)")
    ax.set_ylim(0, 12.8)
    ax.legend(fontsize=8, loc="upper left")
    return fig


def fig_match_points(table, thesis_figure: str = "Figs 26-28"):
    """The match-point check (Sec. 3.3.1.1), one panel per altitude: the flight Mach M = U/a(h)
    of the standard atmosphere and the p-k flutter speed at each analysis Mach (rows of
    :func:`asekit.aeroelastic.flutter.match_point_table`); where the two meet is the matched flutter point.
    The flight envelope's Mach band (Table 3) and the customary +15 % margin are drawn."""
    alts = sorted({r.altitude for r in table})
    fig, axes = new_figure("Match point: flutter speed per analysis Mach vs flight Mach",
                           thesis_figure, ncols=len(alts), figsize=(4.2 * len(alts), 4.2),
                           sharey=True)
    axes = np.atleast_1d(axes)
    for ax, h in zip(axes, alts):
        a = float(standard_atmosphere(h).speed_of_sound)
        u = np.linspace(100, 460, 50)
        ax.plot(u, u / a, color="k", lw=1, label="flight Mach U/a(h)")
        ax.axhspan(*FLIGHT_MACH, color="C2", alpha=0.25, label="flight envelope (Table 3)")
        ax.axhline(FLIGHT_MACH[1] * (1 + FLUTTER_MARGIN), color="C2", ls="--", lw=0.8,
                   label=f"+{100 * FLUTTER_MARGIN:.0f} % margin")
        rows = sorted((r for r in table if r.altitude == h and r.speed is not None),
                      key=lambda r: r.mach)
        ax.plot([r.speed for r in rows], [r.mach for r in rows], "o-", color="C3",
                label="p-k flutter speed")
        for r in rows:
            ax.annotate(f"{r.speed:.0f}", (r.speed, r.mach), textcoords="offset points",
                        xytext=(5, -3), fontsize=7, color="C3")
        mm = matched_mach(table, h)
        if mm is not None:
            ax.plot(mm * a, mm, "*", color="C2", ms=12, label=f"matched M {mm:.3f}")
        ax.set_title(f"h = {h:g} m", fontsize=9)
        ax.set_xlim(120, 380)
        ax.set_ylim(0.3, 1.05)
        ax.set_xlabel("true airspeed (m/s)")
        ax.legend(fontsize=7, loc="upper left")
    axes[0].set_ylabel("Mach")
    return fig


#: The thesis's p-k flutter point at Mach 0.75, sea level (Table 10) and its root-locus point
#: (Table 11), drawn beside asekit's for comparison only.
THESIS_PK_POINT = (251.12, 143.55)
THESIS_RL_POINT = (253.11, 144.1)


def _low_modes_ylim(freq_hz, n: int = 2):
    """Frequency-axis limits showing the first ``n`` tracked modes (the flutter coupling)."""
    f = np.asarray(freq_hz)[:, :n]
    f = f[np.isfinite(f)]
    return (0.0, 1.15 * float(f.max())) if f.size else None


def _damping_frequency_figure(title, thesis_figure, velocities, roots, labels, root: str,
                              flutter, thesis_point, unit):
    """V-g damping g = 2 Re/|Im| (> 0 unstable, docs/conventions.md) and frequency of every
    tracked root vs airspeed (two panels, :func:`asekit.util.plotting.plot_vg`), the flutter point
    marked beside the thesis's; ``root`` names the eigenvalue in the axis label. (The thesis's
    figures plot the damping ratio xi = -Re/|.| instead, ~ -g/2: its curves are mirrored and
    halved; the zero crossing, the flutter point, is the same.)"""
    fig, (a1, a2) = new_figure(title, thesis_figure, nrows=2, figsize=(6.4, 6.5), sharex=True)
    plot_vg(a1, a2, velocities, roots, labels, root=root, g_limits=(-1.0, 0.5))
    lim = _low_modes_ylim(np.abs(np.asarray(roots).imag) / (2 * np.pi))
    if lim:
        a2.set_ylim(*lim)
    _mark_flutter(a1, a2, flutter, thesis_point, unit)
    a1.legend(fontsize=8, ncol=2)
    a2.set_xlabel(f"airspeed ({unit})")
    return fig


def fig_pk(res, title="p-k damping and frequency", thesis_figure="Figs 30-31", unit="m/s",
           flutter=None, thesis_point=None):
    """V-g damping g = 2 Re p / |Im p| (> 0 unstable; the thesis's Figs 30-31 plot the damping
    ratio xi = -Re p / |p| of Eq. 3.13 instead) and frequency vs airspeed of every tracked mode.
    ``flutter``: an :class:`asekit.aeroelastic.flutter.Instability` to mark; ``thesis_point``: (speed, Hz)
    drawn beside it. The frequency axis shows the first two modes, whose coalescence is the
    flutter."""
    return _damping_frequency_figure(title, thesis_figure, res.velocities, res.p,
                                     res.mode_labels, "p", flutter, thesis_point, unit)


def _mark_flutter(a1, a2, flutter, thesis_point, unit):
    if flutter is not None:
        a1.plot(flutter.speed, 0.0, "*", color="C3", ms=12, zorder=5,
                label=f"asekit {flutter.speed:.1f} {unit}")
        a2.plot(flutter.speed, flutter.frequency_hz, "*", color="C3", ms=12, zorder=5)
        a2.annotate(f"asekit {flutter.speed:.1f} {unit}, {flutter.frequency_hz:.1f} Hz",
                    (flutter.speed, flutter.frequency_hz), textcoords="offset points",
                    xytext=(-10, -16), ha="right", fontsize=8, color="C3")
    if thesis_point is not None:
        u, f = thesis_point
        a1.plot(u, 0.0, "D", color=THESIS_COLOR, ms=7, zorder=5, label=f"thesis {u:g} {unit}")
        a2.plot(u, f, "D", color=THESIS_COLOR, ms=7, zorder=5)
        a2.annotate(f"thesis {u:g} {unit}, {f:g} Hz", (u, f), textcoords="offset points",
                    xytext=(8, 6), fontsize=8, color=THESIS_COLOR)


def fig_root_locus(rl, thesis_figure="Figs 32, 35", flutter=None):
    """Aeroelastic roots over airspeed in the complex plane (Figs 32, 35); the flutter root
    marked when ``flutter`` is given."""
    fig, ax = new_figure("Root locus of A_sys (aeroelastic roots)", thesis_figure)
    for j, name in enumerate(rl.mode_labels):
        ax.plot(rl.elastic[:, j].real, rl.elastic[:, j].imag / (2 * np.pi), ".-", ms=3,
                label=name)
    ax.axvline(0, color="k", lw=0.8)
    if flutter is not None:
        ax.plot(0.0, flutter.frequency_hz, "*", color="C3", ms=12,
                label=f"flutter {flutter.speed:.1f} m/s, {flutter.frequency_hz:.1f} Hz")
    ax.set_xlabel("Re lambda (1/s)")
    ax.set_ylabel("Im lambda / 2 pi (Hz)")
    ax.legend(fontsize=8)
    return fig


def fig_root_locus_damping(rl, thesis_figure="Figs 33-34", unit="m/s", flutter=None,
                           thesis_point=None):
    """V-g damping g = 2 Re lambda / |Im lambda| (> 0 unstable; the thesis's Figs 33-34 plot
    the damping ratio of Eq. 3.13) and frequency of the aeroelastic roots vs airspeed, flutter
    point marked (asekit's and the thesis's)."""
    return _damping_frequency_figure("Root locus: damping and frequency", thesis_figure,
                                     rl.velocities, rl.elastic, rl.mode_labels, "lambda",
                                     flutter, thesis_point, unit)


def fig_time_responses(responses, coordinate=1, thesis_figure="Figs 36-38"):
    """Free responses of one elastic coordinate, one panel per (label, speed, response), filled
    column by column (Figs 36-38: the thesis's speeds left, asekit's onset speeds right)."""
    n = len(responses)
    fig, axes = new_figure(f"Free response of zeta_{coordinate + 1} (Eq. 3.15)", thesis_figure,
                           nrows=(n + 1) // 2, ncols=2, figsize=(11, 2.6 * ((n + 1) // 2) + 0.8),
                           sharex=True)
    axes = np.atleast_2d(axes)
    for ax, (label, speed, resp) in zip(np.ravel(axes, order="F"), responses):   # by column
        ax.plot(resp.t, resp.z[:, coordinate], lw=0.7)
        ax.set_title(f"{label}: {speed:.1f} m/s", fontsize=9)
        ax.set_ylabel(f"zeta_{coordinate + 1}")
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    return fig


def fig_time_response(resp, coordinate=1, speed=None, thesis_figure="Figs 36-38"):
    """Elastic coordinate history (Figs 36-38)."""
    fig, ax = new_figure(f"Free response, zeta_{coordinate + 1}"
                         + (f" at {speed:.0f} m/s" if speed else ""), thesis_figure)
    ax.plot(resp.t, resp.z[:, coordinate], lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"zeta_{coordinate + 1}")
    return fig


def fig_step_sizes(resp, speed: float, thesis_figure="Fig 39"):
    """RK45 step sizes of one free-response run (Fig 39), as 1/step on a log axis."""
    fig, ax = new_figure(f"RK45 step sizes of the free response at {speed:.1f} m/s",
                         thesis_figure)
    ax.semilogy(np.cumsum(resp.steps), 1.0 / resp.steps, ".", ms=2)
    ax.axhline(1e4, color="k", lw=0.8, ls="--", label="1e4 Hz cap (thesis: step <= 1e-4 s)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("1 / step (Hz)")
    ax.legend(fontsize=8)
    return fig


def fig_flutter_mode(modal, flutter, thesis_figure="Fig 29"):
    """Flutter mode shape (Fig 29): magnitude and phase of the out-of-plane displacement of the
    flutter eigenvector expanded on the elastic mode shapes (normalised to its largest value)."""
    v = flutter.vector / flutter.vector[np.argmax(np.abs(flutter.vector))]
    w = modal.shapes[:, 0, modal.n_rigid:] @ v
    w = w / w[np.argmax(np.abs(w))]
    fig, (a1, a2) = new_figure(f"Flutter mode shape, {flutter.speed:.1f} m/s, "
                               f"{flutter.frequency_hz:.1f} Hz", thesis_figure, ncols=2,
                               figsize=(12.5, 4.5))
    x, y = modal.nodes[:, 0] * 1e3, modal.nodes[:, 1] * 1e3
    c1 = a1.tricontourf(x, y, np.abs(w), 20, cmap="viridis")
    fig.colorbar(c1, ax=a1, label="|w| (normalised)")
    c2 = a2.tricontourf(x, y, np.degrees(np.angle(w)), 20, cmap="twilight")
    fig.colorbar(c2, ax=a2, label="phase of w (deg)")
    for ax, t in ((a1, "magnitude"), (a2, "phase")):
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_aspect("equal")
        ax.set_title(t, fontsize=9)
    return fig


def fig_growth(td, thesis_figure="Table 11", unit="m/s"):
    """Growth rate of the free response vs airspeed."""
    fig, ax = new_figure("Time domain: growth rate vs airspeed", thesis_figure)
    ax.plot(td.velocities, td.growth, "o-")
    ax.axhline(0, color="k", lw=0.8)
    if td.onset_speed:
        ax.axvline(td.onset_speed, color="C3", ls="--", label=f"onset {td.onset_speed:.1f}")
        ax.legend()
    ax.set_xlabel(f"airspeed ({unit})")
    ax.set_ylabel("growth rate (1/s), > 0 unstable")
    return fig


def fig_damping_study(rows, thesis_speed: float | None = None):
    """Flutter speed vs modal damping ratio zeta and vs structural damping g (its viscous
    equivalent g K / omega_f at the flutter frequency; plotted at zeta = g / 2)."""
    fig, ax = new_figure("Flutter speed vs structural damping, Mach 0.75, sea level, 6x7 model")
    z = [(r["value"], r["speed"]) for r in rows if r["kind"] == "zeta" and r["speed"]]
    g = [(r["value"], r["speed"]) for r in rows if r["kind"] == "g" and r["speed"]]
    ax.plot([100 * a for a, _ in z], [b for _, b in z], "o-", label="modal damping ratio zeta")
    ax.plot([50 * a for a, _ in g], [b for _, b in g], "s--",
            label="structural damping g at the flutter frequency (plotted at g/2)")
    if thesis_speed:
        ax.axhline(thesis_speed, color=THESIS_COLOR, ls=":", label=f"thesis {thesis_speed} m/s")
    ax.set_xlabel("modal damping ratio zeta = g/2 (%), > 0 stable")
    ax.set_ylabel("p-k flutter speed (m/s)")
    ax.legend(fontsize=8)
    return fig


def free_responses(modal, fit, rho: float, onset: float | None, t_end: float = 0.25):
    """Free responses (Eq. 3.15, unit initial zeta_2, RK45 with steps <= 1e-4 s) at the thesis's
    248 / 254 / 260 m/s (Figs 36-38) and at asekit's onset -6 / 0 / +6 m/s: a list of
    (label, speed, FreeResponse)."""
    cases = [("thesis Fig 36", 248.0), ("thesis Fig 37", 254.0), ("thesis Fig 38", 260.0)]
    if onset:
        cases += [("asekit onset - 6", onset - 6.0), ("asekit onset", onset),
                  ("asekit onset + 6", onset + 6.0)]
    out = []
    for label, u in cases:
        A = aeroelastic_matrices(modal, fit, rho, u).A
        out.append((label, u, simulate_free_response(A, initial_state(A.shape[0], 1), t_end,
                                                      1e-4, "RK45")))
    return out


def fin_figures(modal, db, fit, conds, rl, td) -> dict:
    c0 = conds[("M075", 0.0)]
    fit06 = fin_rfa(db, 0.6)
    figs = {"fig23_rfa_q45": fig_rfa_element(fit06, min(3, fit06.n_modes - 1),
                                             min(4, fit06.n_modes - 1), "Fig 23"),
            "fig24_rfa_q12": fig_rfa_element(fit06, 0, 1, "Fig 24")}
    pts = [(c["flutter"].speed, h, f"M {mk[1]}.{mk[2:]}") for (mk, h), c in conds.items()
           if c["flutter"] is not None]
    figs["fig25_mach_airspeed_altitude"] = fig_mach_airspeed_altitude(pts)
    figs["fig30_31_pk"] = fig_pk(c0["pk"], "p-k, Mach 0.75, sea level", flutter=c0["flutter"],
                                 thesis_point=THESIS_PK_POINT)
    rl_fl = first_of(root_locus_instabilities(rl, modal, fit), "flutter")
    figs["fig32_35_root_locus"] = fig_root_locus(rl, flutter=rl_fl)
    figs["fig33_34_root_locus_damping"] = fig_root_locus_damping(
        rl, flutter=rl_fl, thesis_point=THESIS_RL_POINT)
    if c0["flutter"] is not None:
        figs["fig29_flutter_mode"] = fig_flutter_mode(modal, c0["flutter"])
    figs["fig_growth"] = fig_growth(td)
    resp = free_responses(modal, fit, c0["density"], td.onset_speed)
    figs["fig36_38_time_response"] = fig_time_responses(resp)
    label, u, r = resp[4] if len(resp) > 4 else resp[1]
    figs["fig39_step_sizes"] = fig_step_sizes(r, u)
    return figs


def ha145b_figures(ha) -> dict:
    return {"ha145b_pk": fig_pk(ha["pk_result"], "HA145B p-k (Nastran matrices)", "HA145B",
                                unit="in/s"),
            "ha145b_root_locus": fig_root_locus(ha["root_locus"], "HA145B")}


def root_locus_panel(modal, db, mach: float = 0.75, n_lags: int = N_LAGS):
    """Interactive airspeed/altitude panel over the root locus (ipywidgets). Returns the widget
    box, or None when ipywidgets is not installed. Safe without a front-end."""
    try:
        import ipywidgets as w
    except ImportError:
        return None
    import matplotlib.pyplot as plt

    fit = fin_rfa(db, mach, n_lags=n_lags)
    out = w.Output()
    speed = w.FloatSlider(value=250.0, min=100.0, max=460.0, step=2.0, description="U (m/s)")
    alt = w.FloatSlider(value=0.0, min=0.0, max=10000.0, step=500.0, description="h (m)")

    def draw(*_):
        rho = float(standard_atmosphere(alt.value).density)
        ev = np.linalg.eigvals(aeroelastic_matrices(modal, fit, rho, speed.value).A)
        with out:
            out.clear_output(wait=True)
            fig, ax = plt.subplots(figsize=(6, 4))
            ax.plot(ev.real, ev.imag / (2 * np.pi), "x")
            ax.axvline(0, color="k", lw=0.8)
            ax.set_xlabel("Re lambda (1/s)")
            ax.set_ylabel("Im lambda / 2 pi (Hz)")
            ax.set_title(f"A_sys roots, M {mach}, U {speed.value:.0f} m/s, h {alt.value:.0f} m")
            plt.show()

    speed.observe(draw, "value")
    alt.observe(draw, "value")
    draw()
    return w.VBox([speed, alt, out])


# --------------------------------------------------------------------------------------------
# sensitivity of the fin's flutter point to modelling choices (notebook investigation)
# --------------------------------------------------------------------------------------------
#: The thesis's FN2 elastic frequencies (Table 6 via fin.md), Hz, and its fin pitch inertia.
THESIS_ELASTIC_HZ = (86.8891, 159.6022, 566.0895, 627.1564, 972.5351)
THESIS_J_FIN = 2.958e-4
#: Table 9/10 densities (kg/m^3) the thesis used at 0, 2500, 5000 m (not the standard ones).
THESIS_DENSITIES = (1.226, 1.173, 0.902)


def scaled_modal(modal, mass_scale: float = 1.0, elastic_hz=None):
    """A variant of the modal model (as :class:`ModalArrays`): all masses scaled by
    ``mass_scale`` (a different material density with the same mode shapes: M -> s M, K and
    the GAFs unchanged), and/or the elastic stiffnesses set so that the elastic frequencies
    become ``elastic_hz`` (same shapes, K_ss diagonal rescaled; assumes M_ss diagonal)."""
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    M = m.M * mass_scale
    K = m.K.copy()
    if elastic_hz is not None:
        s = slice(m.n_rigid, m.n_modes)
        f = np.asarray(elastic_hz, float)[: m.n_elastic]
        K[s, s] = np.diag((2 * np.pi * f) ** 2 * np.diag(M[s, s]))
    return ModalArrays(M=M, K=K, C=m.C, n_rigid=m.n_rigid)


def sensitivity_study(modal, db, mach: float = 0.75, altitude: float = 0.0,
                      velocities=VELOCITIES) -> list[dict]:
    """p-k (and root-locus) flutter speed of the fin under modelling variants that the thesis
    leaves open or states differently. Returns rows {label, speed, freq, first, first_kind}."""
    rho0 = float(standard_atmosphere(altitude).density)
    gaf = db.at(mach)
    base = modal_arrays(modal)
    J = float(base.M[0, 0]) if base.n_rigid else None
    variants = [
        ("baseline (asekit structure + GAFs, 1976 atm, linear k-interp.)", base, gaf, rho0, {}),
        ("cubic interpolation of Q in k", base, gaf, rho0, {"interpolation": "cubic"}),
        ("thesis density 1.226 kg/m^3", base, gaf, 1.226, {}),
        ("mass x J_thesis/J_asekit (heavier plate, same shapes)",
         scaled_modal(base, THESIS_J_FIN / J) if J else base, gaf, rho0, {}),
        ("elastic frequencies set to the thesis's", scaled_modal(base, 1.0, THESIS_ELASTIC_HZ),
         gaf, rho0, {}),
        ("both: thesis mass and thesis frequencies",
         scaled_modal(base, THESIS_J_FIN / J if J else 1.0, THESIS_ELASTIC_HZ), gaf, rho0, {}),
        ("first two elastic modes only", None, None, rho0, {"modes": [0, 1]}),
    ]
    other = [mm for mm in np.asarray(db.machs, float) if abs(mm - mach) > 1e-9]
    for mm in other:
        variants.append((f"GAFs at Mach {mm:g}", base, db.at(float(mm)), rho0, {}))
    rows = []
    for label, mod, g, rho, kw in variants:
        if mod is None:      # truncated modal basis
            n = base.n_rigid + 2
            mod = ModalArrays(M=base.M[:n, :n], K=base.K[:n, :n], C=base.C[:n, :n],
                              n_rigid=base.n_rigid)
            g = TabulatedGaf(gaf.k, gaf.Q[:, :n, :n], gaf.b_ref, gaf.mach)
            kw = {}
        interp = kw.get("interpolation", "linear")
        res = pk_flutter(mod, g, rho, velocities, interpolation=interp)
        inst = pk_instabilities(res, mod, g, interpolation=interp)
        fl, first = first_of(inst, "flutter"), first_of(inst)
        rows.append({"label": label, "speed": _val(fl, "speed"),
                     "freq": _val(fl, "frequency_hz"), "first": _val(first, "speed"),
                     "first_kind": None if first is None else first.kind})
    return rows


def rfa_sensitivity(modal, db, mach: float = 0.75, altitude: float = 0.0,
                    velocities=VELOCITIES) -> list[dict]:
    """Root-locus flutter speed for several Roger fits (lag count, lag spread, steady-load
    constraint): the RFA-side spread the thesis names in Section 3.3.4."""
    rho = float(standard_atmosphere(altitude).density)
    kmax = float(np.max(db.k))
    cases = [("2 lags", {"n_lags": 2}), ("4 lags (default)", {"n_lags": 4}),
             ("6 lags", {"n_lags": 6}),
             ("4 lags, roots x0.5", {"lag_roots": 0.5 * default_lag_roots(kmax, 4)}),
             ("4 lags, constrained at k_min", {"n_lags": 4, "constrain_k0": True})]
    rows = []
    for label, kw in cases:
        fit = fin_rfa(db, mach, **kw)
        rl = root_locus(modal, fit, rho, velocities)
        inst = root_locus_instabilities(rl, modal, fit)
        fl = first_of(inst, "flutter")
        rows.append({"label": label, "fit_error": fit.fit_error, "speed": _val(fl, "speed"),
                     "freq": _val(fl, "frequency_hz"), "first": _val(first_of(inst), "speed")})
    return rows


def aero_variant_gafs(modal, db, mach: float = 0.75, symmetric: bool = False,
                      n_chord: int | None = None, n_span: int | None = None,
                      spline: str = "fe") -> TabulatedGaf:
    """The fin's GAFs at one Mach recomputed with another aerodynamic model choice: a
    symmetry wall at the root (``symmetric``), another box mesh (``n_chord`` x ``n_span``), or
    the infinite-plate spline (``spline="ips"``, Harder & Desmarais) through the structural
    nodes instead of the finite-element shape functions, on the database's k and b_ref (uses
    asekit.aero; a few seconds per variant). ``modal`` is the ModalModel whose shapes are used.
    """
    case = fin_case()
    boxes = pipeline.box_mesh(case if (n_chord, n_span) == (None, None)
                              else with_boxes(case, n_chord, n_span))
    if spline == "fe":
        bm = fe_spline(modal, boxes)
    elif spline == "ips":
        bm = InfinitePlateSpline(modal.nodes).box_modes(boxes, modal.shapes[:, 0, :])
    else:
        raise ValueError(f"spline must be 'fe' or 'ips', got {spline!r}")
    q = gaf_from_box_modes(bm, boxes, mach, db.k, db.b_ref, symmetric=symmetric)
    return TabulatedGaf(db.k, q, db.b_ref, mach=mach)


#: Modelling variants of :func:`model_sensitivity`: (label, structure kwargs for
#: :func:`structure_variant`, aerodynamic kwargs for :func:`aero_variant_gafs`).
MODEL_VARIANTS = (
    ("symmetry wall at the root (fin on a body)", {}, {"symmetric": True}),
    ("finer aerodynamic mesh 20 x 14 boxes", {}, {"n_chord": 20, "n_span": 14}),
    ("infinite-plate spline instead of FE shape functions", {}, {"spline": "ips"}),
    ("finer structural mesh 12 x 14 elements", {"n_chord": 12, "n_span": 14}, {}),
)


def structure_variant(n_chord: int | None = None, n_span: int | None = None,
                      shaft: str = "single_node"):
    """The fin's case on an ``n_chord x n_span`` structural mesh (default the case's) with the
    ``"single_node"`` (thesis) or ``"distributed"`` shaft
    (:func:`asekit.reproduction.fin.distributed_case`)."""
    if shaft == "single_node":
        return with_mesh(fin_case(), n_chord, n_span)
    if shaft == "distributed":
        return distributed_case(n_chord, n_span)
    raise ValueError(f"shaft must be 'single_node' or 'distributed', got {shaft!r}")


def model_sensitivity(db, mach: float = 0.75, altitude: float = 0.0, velocities=VELOCITIES,
                      variants=MODEL_VARIANTS) -> list[dict]:
    """p-k flutter speed with the structure and/or GAFs rebuilt for modelling variants (support
    model, structural mesh, spline, symmetry plane, aerodynamic mesh) at one Mach and altitude.
    Rows: label, elastic frequencies (Hz), Q_cc(k_min), speed, freq, first, first_kind."""
    rho = float(standard_atmosphere(altitude).density)
    rows = []
    for label, skw, akw in variants:
        model = pipeline.modal_model(structure_variant(**skw))
        g = aero_variant_gafs(model, db, mach, **akw)
        m = modal_arrays(model)
        res = pk_flutter(m, g, rho, velocities)
        inst = pk_instabilities(res, m, g)
        fl, first = first_of(inst, "flutter"), first_of(inst)
        rows.append({"label": label, "elastic_hz": model.frequencies_hz[model.n_rigid:].tolist(),
                     "speed": _val(fl, "speed"), "freq": _val(fl, "frequency_hz"),
                     "first": _val(first, "speed"),
                     "first_kind": None if first is None else first.kind,
                     "Q_cc": float(g.Q[0, 0, 0].real)})
    return rows


# --------------------------------------------------------------------------------------------
# damping: how the flutter speed moves with structural damping (issue 10)
# --------------------------------------------------------------------------------------------
#: Modal (viscous) damping ratios of the damping study, fractions of critical.
DAMPING_RATIOS = (0.0, 0.0025, 0.005, 0.01, 0.02)
#: Structural (hysteretic) damping coefficients g of the damping study.
STRUCTURAL_G = (0.0, 0.005, 0.01, 0.02, 0.04)
#: Airspeeds of the damping study (m/s): coarser than VELOCITIES (each crossing is refined by
#: Brent's method, so the step sets only the bracketing), covering 150-340 m/s.
DAMPING_VELOCITIES = np.arange(150.0, 342.0 + 1e-9, 4.0)


def damped_modal(modal, zeta: float = 0.0, g: float = 0.0, omega_ref: float | None = None):
    """The modal model with damping on its elastic modes (as :class:`ModalArrays`).

    ``zeta``: viscous modal damping ratio, C_ss,ii = 2 zeta omega_i M_ss,ii (M_ss, K_ss diagonal
    in the modal basis). ``g``: hysteretic (structural) damping i g K_ss, represented by its
    equivalent viscous damping (g / omega_ref) K_ss, exact for harmonic motion at omega_ref
    (rad/s) — at the flutter point when omega_ref is the flutter frequency (p = i omega_f:
    p (g/omega_f) K = i g K). The rigid mode stays undamped. ``zeta`` in [0, 1), ``g`` >= 0.
    """
    if not (0.0 <= zeta < 1.0):
        raise ValueError(f"zeta must be in [0, 1), got {zeta!r}")
    if not (g >= 0.0 and np.isfinite(g)):
        raise ValueError(f"g must be >= 0, got {g!r}")
    if g > 0 and not (omega_ref is not None and omega_ref > 0):
        raise ValueError(f"omega_ref must be > 0 (rad/s) when g > 0, got {omega_ref!r}")
    m = modal if isinstance(modal, ModalArrays) else modal_arrays(modal)
    s = slice(m.n_rigid, m.n_modes)
    C = m.C.copy()
    Mss, Kss = np.diag(m.M[s, s]), np.diag(m.K[s, s])
    C[s, s] += np.diag(2.0 * zeta * np.sqrt(Kss / Mss) * Mss)
    if g > 0:
        C[s, s] += (g / omega_ref) * m.K[s, s]
    return ModalArrays(M=m.M, K=m.K, C=C, n_rigid=m.n_rigid)


def damping_study(modal, db, mach: float = 0.75, altitude: float = 0.0,
                  ratios=DAMPING_RATIOS, gs=STRUCTURAL_G, velocities=VELOCITIES) -> list[dict]:
    """p-k flutter speed and frequency versus modal damping ratio and structural g.

    Rows {kind: "zeta" | "g", value, speed (m/s), freq (Hz)}; speed None when no flutter in the
    sweep. For g the equivalent viscous damping is evaluated at the flutter frequency, iterated
    until it changes by < 0.1 % (at most 6 passes; starts from the undamped flutter frequency).
    """
    rho = float(standard_atmosphere(altitude).density)
    gaf = db.at(mach)

    def flutter(mod):
        res = pk_flutter(mod, gaf, rho, velocities)
        return first_of(pk_instabilities(res, mod, gaf), "flutter")

    rows = []
    for z in ratios:
        fl = flutter(damped_modal(modal, zeta=z))
        rows.append({"kind": "zeta", "value": float(z), "speed": _val(fl, "speed"),
                     "freq": _val(fl, "frequency_hz")})
    f_ref = next((r["freq"] for r in rows if r["value"] == 0.0 and r["freq"]), None)
    for g in gs:
        if g == 0:
            fl = flutter(damped_modal(modal))
        else:
            fl, f = None, f_ref
            for _ in range(6):
                if f is None:
                    break
                fl = flutter(damped_modal(modal, g=g, omega_ref=2 * np.pi * f))
                if fl is None or abs(fl.frequency_hz / f - 1) < 1e-3:
                    break
                f = fl.frequency_hz
        rows.append({"kind": "g", "value": float(g), "speed": _val(fl, "speed"),
                     "freq": _val(fl, "frequency_hz")})
    return rows


# --------------------------------------------------------------------------------------------
# converged flutter: distributed shaft, structural and aerodynamic meshes refined (issue 10)
# --------------------------------------------------------------------------------------------
#: Structural meshes (elements chordwise x spanwise) of the convergence study, distributed shaft.
CONVERGENCE_STRUCTURE = ((24, 28), (48, 56), (96, 112), (192, 224), (384, 448))
#: Aerodynamic box meshes (chordwise x spanwise); the first is the mesh-rule default.
CONVERGENCE_AERO = ((14, 10), (28, 20), (56, 40))
#: Convergence criterion: relative change of the flutter speed on the last refinement.
CONVERGENCE_TOL = 0.01
_STUDY_VERSION = 1


#: How to ask for the converged study when it is not cached.
CONVERGED_HINT = ("python -m asekit reproduce --converged, or ASEKIT_CONVERGED_STUDY=1 for the "
                  "notebooks and tests")


def converged_study_requested() -> bool:
    """Whether the (minutes-long, 7 GB) converged study may be computed in this run:
    ``ASEKIT_CONVERGED_STUDY=1`` (set by ``python -m asekit reproduce --converged``). Without
    it a cached result is still used."""
    import os
    return os.environ.get("ASEKIT_CONVERGED_STUDY", "") == "1"


def _study_fingerprint(db, mach, altitude, velocities, structure, aero) -> str:
    """SHA-256 over everything the converged study depends on: the fin definition, the GAF
    database's k and b_ref, the condition, the sweep, the meshes and the source of the modules
    that compute it (so an edit to the physics invalidates the cached result)."""
    import hashlib
    from pathlib import Path

    h = hashlib.sha256()
    h.update(f"v{_STUDY_VERSION} {mach!r} {altitude!r} {structure!r} {aero!r}".encode())
    h.update(np.ascontiguousarray(np.asarray(velocities, float)).tobytes())
    h.update(np.ascontiguousarray(np.asarray(db.k, float)).tobytes())
    h.update(repr(float(db.b_ref)).encode())
    h.update(Path(FIN_FILE).read_bytes())
    pkg = Path(__file__).resolve().parent.parent
    for rel in sorted(["aeroelastic/flutter.py", "aeroelastic/statespace.py", "atmosphere.py",
                       "geometry.py"]
                      + [f"structure/{p.name}" for p in (pkg / "structure").glob("*.py")]
                      + [f"aero/{p.name}" for p in (pkg / "aero").glob("*.py")]):
        h.update(rel.encode())
        h.update((pkg / rel).read_bytes())
    return h.hexdigest()


def _distributed_model(structure):
    """The FN2 modal model with the distributed shaft region on a ``structure`` mesh."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # unresolved shaft region on the coarse meshes
        return pipeline.modal_model(structure_variant(structure[0], structure[1], "distributed"))


def _mesh_flutter(model, db, mach, rho, velocities, aero):
    """(elastic Hz (first 3), speed, freq) of ``model`` with GAFs on the ``aero`` box mesh."""
    g = aero_variant_gafs(model, db, mach, n_chord=aero[0], n_span=aero[1])
    m = modal_arrays(model)
    fl = first_of(pk_instabilities(pk_flutter(m, g, rho, velocities), m, g), "flutter")
    f = model.frequencies_hz[model.n_rigid:model.n_rigid + 3]
    return (list(map(float, f)) + [np.nan] * (3 - len(f)), _val(fl, "speed"),
            _val(fl, "frequency_hz"))


def converged_flutter_study(db, mach: float = 0.75, altitude: float = 0.0,
                            velocities=np.arange(140.0, 340.0 + 1e-9, 2.0),
                            structure=CONVERGENCE_STRUCTURE, aero=CONVERGENCE_AERO,
                            tol: float = CONVERGENCE_TOL, cache: bool = True,
                            compute: bool = True) -> dict | None:
    """p-k flutter of the fin with the distributed shaft region (rigid disc of the shaft radius)
    on successively refined structural meshes (at the default box mesh), then on refined box
    meshes at the finest structure; each refinement stops once the flutter speed moves by less
    than ``tol``.

    Returns ``{"rows": [(structure, aero, elastic_hz, speed, freq), ...], "speed", "freq",
    "structure", "aero", "change_structure", "change_aero", "converged"}`` where speed/freq
    (m/s, Hz) belong to the finest mesh pair and change_* are the relative speed changes of its
    last structural and aerodynamic refinement.

    The finest meshes take minutes (about 8 min and 7 GB for 384 x 448), so with ``cache`` the
    result is stored (atomically, with a checksum, :mod:`asekit.util.cache`) in the user cache
    directory (:func:`asekit.util.paths.user_cache_dir`) under a fingerprint of all its inputs and
    the physics source, and reused while the fingerprint matches. With ``compute=False`` a
    missing or stale cache returns None instead of computing.
    """
    key = _study_fingerprint(db, mach, altitude, velocities, structure, aero)
    path = user_cache_dir() / f"flutter_convergence_{key[:16]}.npz"
    if cache:
        try:
            arrays, meta = load_npz(path)
            if meta.get("fingerprint") == key:
                return _study_from_arrays(arrays, meta)
        except CacheError:
            pass                                    # missing or corrupt: recompute
    if not compute:
        return None
    rho = float(standard_atmosphere(altitude).density)
    rows = []

    def run(model, s, a):
        f, u, fr = _mesh_flutter(model, db, mach, rho, velocities, a)
        rows.append((tuple(s), tuple(a), f, u, fr))
        return u

    def rel(u_new, u_old):
        return None if (u_new is None or u_old is None) else abs(u_new / u_old - 1)

    a0 = aero[0]
    prev = change_s = model = None
    s_final = structure[0]
    for s in structure:
        model = _distributed_model(s)
        u = run(model, s, a0)
        s_final = s
        change_s = rel(u, prev) if prev is not None else None
        if change_s is not None and change_s < tol:
            break
        prev = u
    prev, change_a, a_final = rows[-1][3], None, a0
    for a in aero[1:]:                       # the box mesh refined on the finest structure
        u = run(model, s_final, a)
        a_final = a
        change_a = rel(u, prev)
        if change_a is not None and change_a < tol:
            break
        prev = u
    out = {"rows": rows, "speed": rows[-1][3], "freq": rows[-1][4], "structure": s_final,
           "aero": a_final, "change_structure": change_s, "change_aero": change_a,
           "converged": bool(change_s is not None and change_s < tol
                             and (change_a is None or change_a < tol))}
    if cache:
        arr = {"structure": np.array([r[0] for r in rows], float),
               "aero": np.array([r[1] for r in rows], float),
               "elastic_hz": np.array([r[2] for r in rows], float),
               "speed": np.array([np.nan if r[3] is None else r[3] for r in rows], float),
               "freq": np.array([np.nan if r[4] is None else r[4] for r in rows], float)}
        meta = {"fingerprint": key, "mach": mach, "altitude": altitude, "tol": tol,
                "final_structure": list(s_final), "final_aero": list(a_final),
                "change_structure": change_s, "change_aero": change_a,
                "converged": out["converged"]}
        save_npz(path, arr, meta)
    return out


def _study_from_arrays(arrays, meta) -> dict:
    def opt(x):
        return None if np.isnan(x) else float(x)
    rows = [(tuple(int(v) for v in s), tuple(int(v) for v in a), list(map(float, f)), opt(u),
             opt(fr)) for s, a, f, u, fr in zip(arrays["structure"], arrays["aero"],
                                                  arrays["elastic_hz"], arrays["speed"],
                                                  arrays["freq"])]
    return {"rows": rows, "speed": rows[-1][3], "freq": rows[-1][4],
            "structure": tuple(meta["final_structure"]), "aero": tuple(meta["final_aero"]),
            "change_structure": meta["change_structure"], "change_aero": meta["change_aero"],
            "converged": meta["converged"]}


# --------------------------------------------------------------------------------------------
# the converged answer by default: graded meshes, extrapolated, with an error bar (issue 23)
# --------------------------------------------------------------------------------------------
#: The finest meshes of the default extrapolated flutter: structure graded toward the shaft
#: region (asekit.case.variants.with_shaft_grading), boxes; the study adds two coarser ones.
EXTRAPOLATED_STRUCTURE = (64, 48)
EXTRAPOLATED_AERO = (28, 20)
#: Its convergence settings (asekit.case.convergence): three meshes, each 1.5x coarser.
EXTRAPOLATED_SPEC = ConvergenceSpec(meshes=3, ratio=1.5)
_EXTRAPOLATED_VERSION = 1


def extrapolated_case(structure=EXTRAPOLATED_STRUCTURE, aero=EXTRAPOLATED_AERO,
                      mach: float = 0.75, altitude: float = 0.0,
                      velocities=np.arange(140.0, 340.0 + 1e-9, 2.0)):
    """The fin with the distributed shaft of :data:`asekit.reproduction.fin.DEFAULT_SHAFT_RADIUS`
    on a ``structure`` mesh graded toward it and an ``aero`` box mesh, at one Mach and
    altitude (the converged study's sweep)."""
    from dataclasses import replace

    from asekit.case.variants import with_shaft_grading
    case = distributed_case()
    case = replace(case, aero=replace(case.aero, machs=(float(mach),)),
                   flight=replace(case.flight, altitudes=(float(altitude),),
                                  velocities=tuple(float(v) for v in velocities)))
    return with_boxes(with_shaft_grading(case, *structure), *aero)


def extrapolated_flutter(db, cache: bool = True, **kw) -> dict:
    """The fin's converged flutter by default (issue 23): p-k at M 0.75, sea level, of
    :func:`extrapolated_case` on its graded mesh and two coarser ones
    (:data:`EXTRAPOLATED_SPEC`), Richardson-extrapolated with the observed order and Roache's
    GCI as the error bar (:func:`asekit.case.convergence.convergence_study`).

    Returns ``{"speeds", "freqs"}`` (per mesh, finest first: m/s, Hz), ``"speed"``,
    ``"speed_error"``, ``"freq"``, ``"freq_error"`` (m/s, Hz; None without flutter on a mesh),
    ``"order"``, ``"observed"``, ``"meshes"``. Stored in the user cache under a fingerprint of
    its inputs and the source of the physics and of the case layer's study (like
    :func:`converged_flutter_study`); ``db`` (the fin's
    GAF database) enters the fingerprint only. About 9 s CPU and 350 MB cold.
    """
    import warnings

    from asekit.case.convergence import convergence_study
    case = extrapolated_case(**kw)
    spec = EXTRAPOLATED_SPEC
    key = _study_fingerprint(db, case.aero.machs[0], case.flight.altitudes[0],
                             case.flight.velocities,
                             ("graded", _EXTRAPOLATED_VERSION, case.panels[0]),
                             (case.aero.boxes, spec))
    key = _with_source(key, "case/convergence.py", "case/pipeline.py", "case/variants.py")
    path = user_cache_dir() / f"flutter_extrapolated_{key[:16]}.npz"
    if cache:
        try:
            arrays, meta = load_npz(path)
            if meta.get("fingerprint") == key:
                return {**meta["result"], "speeds": arrays["speeds"].tolist(),
                        "freqs": arrays["freqs"].tolist()}
        except CacheError:
            pass                                    # missing or corrupt: recompute
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")             # coarse meshes under-resolve the region
        (row,) = convergence_study(case, spec).rows
    sp, fr = row.speed, row.frequency
    out = {"speed": None if sp is None else sp.value,
           "speed_error": None if sp is None else sp.error,
           "freq": None if fr is None else fr.value,
           "freq_error": None if fr is None else fr.error,
           "order": None if sp is None else sp.order,
           "observed": None if sp is None else sp.observed,
           "meshes": [list(m) for m in _study_meshes_of(case, spec)], "note": row.note}
    speeds = [np.nan] if sp is None else list(sp.values)
    freqs = [np.nan] if fr is None else list(fr.values)
    if cache:
        save_npz(path, {"speeds": np.array(speeds, float), "freqs": np.array(freqs, float)},
                 {"fingerprint": key, "result": out})
    return {**out, "speeds": speeds, "freqs": freqs}


def _with_source(key: str, *modules: str) -> str:
    """``key`` extended by the source of asekit's ``modules`` (paths under the package)."""
    import hashlib
    from pathlib import Path

    h = hashlib.sha256(key.encode())
    pkg = Path(__file__).resolve().parent.parent
    for rel in modules:
        h.update(rel.encode())
        h.update((pkg / rel).read_bytes())
    return h.hexdigest()


def _study_meshes_of(case, spec):
    from asekit.case.convergence import study_meshes
    return [(c.panels[0].n_chord, c.panels[0].n_span, *c.aero.boxes[0])
            for c in study_meshes(case, spec)]


def extrapolated_quantities(r: dict) -> list:
    """The four ``flutter.extrapolated.pk.M075.h0.*`` quantities of
    :func:`extrapolated_flutter`'s result (the 6x7 thesis-mesh rows stay the like-for-like
    comparison)."""
    meshes = ", ".join(f"{a}x{b}/{c}x{d}" for a, b, c, d in r["meshes"])
    order = ("-" if r["order"] is None else
             f"order {r['order']:.2f} {'observed' if r['observed'] else 'assumed'}")

    def per(vals, unit):
        return "no flutter on a mesh" if r["speed"] is None else \
            ", ".join(f"{v:.2f}" for v in vals) + f" {unit}"

    fs = "1.25 (order observed)" if r["observed"] else "3 (order assumed)"
    gci = f"Roache's (1994) grid convergence index, safety factor {fs}"
    extra = f"; {r['note']}" if r["note"] else ""
    base = "flutter.extrapolated.pk.M075.h0"
    return [Quantity(f"{base}.speed_ms", r["speed"], "m/s",
                     f"distributed shaft, graded FE / boxes {meshes}: "
                     f"{per(r['speeds'], 'm/s')}; {order}{extra}"),
            Quantity(f"{base}.speed_error_ms", r["speed_error"], "m/s", gci),
            Quantity(f"{base}.freq_hz", r["freq"], "Hz",
                     f"same meshes: {per(r['freqs'], 'Hz')}"),
            Quantity(f"{base}.freq_error_hz", r["freq_error"], "Hz", gci)]
