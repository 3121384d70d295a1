"""Chapter 3.2.2-3.3 reproduction: RFA fit, p-k (Tables 9-10), root locus, time domain
(Table 11) and divergence for the reference fin, plus the HA145B cross-check.

The fin's GAF database comes from :func:`asekit.aero.gaf.fin_gaf_database` (rigid pitch mode
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

from ..atmosphere import standard_atmosphere
from ..flutter import (TabulatedGaf, divergence_speeds, first_of, pk_flutter, pk_instabilities,
                       root_locus, root_locus_instabilities, time_domain_sweep)
from ..reproduce import ChapterResult, Quantity

VELOCITIES = np.arange(100.0, 460.0 + 1e-9, 2.0)      # m/s
ALTITUDES = (0.0, 2500.0, 5000.0)                       # m
MACHS = {"M075": 0.75, "M06": 0.6}
N_LAGS = 4


def load_fin_gafs():
    """(GafDatabase, ModalModel) of the fin, or (None, reason) when not available."""
    try:
        from ..aero.gaf import fin_gaf_database
    except ImportError as exc:           # the aerodynamics module is not there yet
        return None, f"asekit.aero.gaf not available ({exc.__class__.__name__})"
    try:
        db, modal = fin_gaf_database(rebuild=False, progress=False)
    except Exception as exc:             # noqa: BLE001 - report any build/cache failure as a note
        return None, f"fin GAF database unavailable: {exc}"
    return (db, modal), ""


def fin_gaf(db, mach: float) -> TabulatedGaf:
    """The database's GAFs at one Mach as a :class:`TabulatedGaf` (exact Mach required)."""
    from ..rfa import gaf_at_mach
    k, q = gaf_at_mach(db, mach)
    return TabulatedGaf(k, q, db.b_ref, mach=mach)


def fin_rfa(db, mach: float, n_lags: int = N_LAGS, constrain_k0: bool = False, lag_roots=None):
    """Roger fit of the fin's GAFs at ``mach`` (default lag roots over the database's k)."""
    from ..rfa import roger_fit_database
    return roger_fit_database(db, mach, n_lags=n_lags, constrain_k0=constrain_k0,
                              lag_roots=lag_roots)


def analyse_condition(modal, db, mach: float, altitude: float, velocities=VELOCITIES,
                      density: float | None = None) -> dict:
    """p-k at one (Mach, altitude): result, instabilities, first flutter and first of any kind."""
    rho = float(standard_atmosphere(altitude).density) if density is None else density
    gaf = fin_gaf(db, mach)
    res = pk_flutter(modal, gaf, rho, velocities)
    inst = pk_instabilities(res, modal, gaf)
    return {"density": rho, "gaf": gaf, "pk": res, "instabilities": inst,
            "flutter": first_of(inst, "flutter"), "divergence": first_of(inst, "divergence"),
            "first": first_of(inst)}


def time_domain_first(modal, fit, rho: float, velocities=np.arange(100.0, 461.0, 10.0)):
    """Time-domain growth sweep and the onset kind (flutter if the A_sys root crossing near the
    onset is oscillatory, else divergence)."""
    from ..aeroelastic import aeroelastic_matrices
    td = time_domain_sweep(modal, fit, rho, velocities, coordinate=1)
    kind = None
    if td.onset_speed is not None:
        ev = np.linalg.eigvals(aeroelastic_matrices(modal, fit, rho, td.onset_speed).A)
        crit = ev[np.argmin(np.abs(ev.real))]
        kind = "flutter" if abs(crit.imag) > 1e-3 * max(abs(crit), 1.0) else "divergence"
    return td, kind


def ha145b_check() -> dict | None:
    """p-k, root locus and time domain on Nastran's HA145B (None if the file is absent)."""
    from ..aeroelastic import modal_arrays
    from ..nastran import ha145b_path, load_ha145b
    from ..rfa import roger_fit
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
    if data is None:
        for key in fin_keys:
            unit = "Hz" if key.endswith("freq_hz") else ("-" if "fit_error" in key else "m/s")
            q.append(Quantity(key, None, unit, reason))
        if figures and ha is not None:
            figs.update(ha145b_figures(ha))
        return ChapterResult(chapter="flutter", quantities=tuple(q), figures=figs,
                             failures=(reason,))

    db, modal = data
    sweep_note = "1976 std atm; sweep 100-460 m/s"
    conds = {}
    for mk, mach in MACHS.items():
        for h in ALTITUDES:
            c = analyse_condition(modal, db, mach, h)
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
    from ..plotting import new_figure
    fig, ax = new_figure(f"RFA fit of Q_{i + 1}{j + 1} (Mach {fit.mach})", thesis_figure)
    kk = np.geomspace(max(fit.k[0], 1e-4), fit.k[-1], 300)
    qf = fit.evaluate(kk)[:, i, j]
    ax.plot(fit.Q[:, i, j].real, fit.Q[:, i, j].imag, "o", label="GAF data")
    ax.plot(qf.real, qf.imag, "-", label=f"Roger, {fit.n_lags} lags")
    qd = fit.evaluate(fit.k)[:, i, j]
    ax.plot(qd.real, qd.imag, "x", color="C1", label="fit at the data k")
    for a, b in zip(fit.Q[:, i, j], qd):
        ax.plot([a.real, b.real], [a.imag, b.imag], color="0.6", lw=0.6)
    ax.set_xlabel("Re Q (per unit q)")
    ax.set_ylabel("Im Q (per unit q)")
    ax.legend()
    return fig


def fig_mach_airspeed_altitude(points=(), thesis_figure: str = "Fig 25"):
    """Mach lines in the airspeed-altitude plane (Fig 25), optional (U, h, label) points."""
    from ..plotting import new_figure
    fig, ax = new_figure("Mach - airspeed - altitude (1976 standard atmosphere)", thesis_figure)
    h = np.linspace(0, 12000, 100)
    a = standard_atmosphere(h).speed_of_sound
    for m in (0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.9, 1.0):
        ax.plot(m * a, h / 1000, lw=1, label=f"M {m}")
    for u, hh, lab in points:
        ax.plot(u, hh / 1000, "k*", ms=10)
        ax.annotate(lab, (u, hh / 1000))
    ax.set_xlabel("true airspeed (m/s)")
    ax.set_ylabel("altitude (km)")
    ax.legend(ncol=2, fontsize=8)
    return fig


def fig_pk(res, title="p-k damping and frequency", thesis_figure="Figs 30-31", unit="m/s"):
    """Damping g and frequency vs airspeed of every tracked mode (Figs 30-31)."""
    from ..plotting import new_figure
    fig, (a1, a2) = new_figure(title, thesis_figure, nrows=2, figsize=(6.4, 6.5))
    for j in range(res.p.shape[1]):
        a1.plot(res.velocities, res.damping_g[:, j], label=f"mode {j + 1}")
        a2.plot(res.velocities, res.frequency_hz[:, j])
    a1.axhline(0, color="k", lw=0.8)
    a1.set_ylabel("damping g = 2 Re p / |p|")
    a1.set_ylim(max(a1.get_ylim()[0], -1.0), min(a1.get_ylim()[1], 0.5))
    a1.legend(fontsize=8)
    a2.set_xlabel(f"airspeed ({unit})")
    a2.set_ylabel("frequency (Hz)")
    return fig


def fig_root_locus(rl, thesis_figure="Figs 32, 35"):
    """Aeroelastic roots over airspeed in the complex plane (Figs 32, 35)."""
    from ..plotting import new_figure
    fig, ax = new_figure("Root locus of A_sys (aeroelastic roots)", thesis_figure)
    for j in range(rl.elastic.shape[1]):
        ax.plot(rl.elastic[:, j].real, rl.elastic[:, j].imag / (2 * np.pi), ".-", ms=3,
                label=f"mode {j + 1}")
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("Re lambda (1/s)")
    ax.set_ylabel("Im lambda / 2 pi (Hz)")
    ax.legend(fontsize=8)
    return fig


def fig_root_locus_damping(rl, thesis_figure="Figs 33-34", unit="m/s"):
    """Damping ratio and natural frequency of the aeroelastic roots vs airspeed (Eq. 3.13)."""
    from ..plotting import new_figure
    fig, (a1, a2) = new_figure("Root locus: damping ratio and frequency", thesis_figure,
                               nrows=2, figsize=(6.4, 6.5))
    for j in range(rl.elastic.shape[1]):
        a1.plot(rl.velocities, rl.damping_ratio[:, j], label=f"mode {j + 1}")
        a2.plot(rl.velocities, rl.frequency_hz[:, j])
    a1.axhline(0, color="k", lw=0.8)
    a1.set_ylabel("damping ratio xi")
    a1.legend(fontsize=8)
    a2.set_xlabel(f"airspeed ({unit})")
    a2.set_ylabel("frequency (Hz)")
    return fig


def fig_time_response(resp, coordinate=1, speed=None, thesis_figure="Figs 36-38"):
    """Elastic coordinate history (Figs 36-38)."""
    from ..plotting import new_figure
    fig, ax = new_figure(f"Free response, zeta_{coordinate + 1}"
                         + (f" at {speed:.0f} m/s" if speed else ""), thesis_figure)
    ax.plot(resp.t, resp.z[:, coordinate], lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"zeta_{coordinate + 1}")
    return fig


def fig_growth(td, thesis_figure="Table 11", unit="m/s"):
    """Growth rate of the free response vs airspeed."""
    from ..plotting import new_figure
    fig, ax = new_figure("Time domain: growth rate vs airspeed", thesis_figure)
    ax.plot(td.velocities, td.growth, "o-")
    ax.axhline(0, color="k", lw=0.8)
    if td.onset_speed:
        ax.axvline(td.onset_speed, color="C3", ls="--", label=f"onset {td.onset_speed:.1f}")
        ax.legend()
    ax.set_xlabel(f"airspeed ({unit})")
    ax.set_ylabel("growth rate (1/s)")
    return fig


def fin_figures(modal, db, fit, conds, rl, td) -> dict:
    from ..aeroelastic import aeroelastic_matrices
    from ..flutter import initial_state, simulate_free_response
    figs = {"fig23_rfa_q45": fig_rfa_element(fit, min(3, fit.n_modes - 1),
                                             min(4, fit.n_modes - 1), "Fig 23"),
            "fig24_rfa_q12": fig_rfa_element(fit, 0, 1, "Fig 24")}
    pts = [(c["flutter"].speed, h, f"{mk}") for (mk, h), c in conds.items()
           if c["flutter"] is not None]
    figs["fig25_mach_airspeed_altitude"] = fig_mach_airspeed_altitude(pts)
    figs["fig30_31_pk"] = fig_pk(conds[("M075", 0.0)]["pk"], "p-k, Mach 0.75, sea level")
    figs["fig32_35_root_locus"] = fig_root_locus(rl)
    figs["fig33_34_root_locus_damping"] = fig_root_locus_damping(rl)
    figs["fig_growth"] = fig_growth(td)
    u = td.onset_speed or 300.0
    mats = aeroelastic_matrices(modal, fit, conds[("M075", 0.0)]["density"], u)
    resp = simulate_free_response(mats.A, initial_state(mats.n_states, 1), 0.25, 1e-4, "RK45")
    figs["fig37_time_response"] = fig_time_response(resp, 1, u, "Fig 37")
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
    from ..aeroelastic import aeroelastic_matrices
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
    from ..aeroelastic import ModalArrays, modal_arrays
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
    from ..aeroelastic import modal_arrays
    rho0 = float(standard_atmosphere(altitude).density)
    gaf = fin_gaf(db, mach)
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
        variants.append((f"GAFs at Mach {mm:g}", base, fin_gaf(db, float(mm)), rho0, {}))
    rows = []
    for label, mod, g, rho, kw in variants:
        if mod is None:      # truncated modal basis
            n = base.n_rigid + 2
            from ..aeroelastic import ModalArrays
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
    from ..rfa import default_lag_roots
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
    from ..aero.boxes import fin_boxes
    from ..aero.gaf import gaf_from_box_modes
    from ..aero.spline import InfinitePlateSpline, fe_spline
    from ..geometry import load_fin
    boxes = fin_boxes(load_fin(), n_chord, n_span)
    if spline == "fe":
        bm = fe_spline(modal, boxes)
    elif spline == "ips":
        bm = InfinitePlateSpline(modal.nodes).box_modes(boxes, modal.shapes[:, 0, :])
    else:
        raise ValueError(f"spline must be 'fe' or 'ips', got {spline!r}")
    q = gaf_from_box_modes(bm, boxes, mach, db.k, db.b_ref, symmetric=symmetric)
    return TabulatedGaf(db.k, q, db.b_ref, mach=mach)


#: Modelling variants of :func:`model_sensitivity`: (label, structure kwargs for
#: ``fin_modal_model``, aerodynamic kwargs for :func:`aero_variant_gafs`).
MODEL_VARIANTS = (
    ("symmetry wall at the root (fin on a body)", {}, {"symmetric": True}),
    ("finer aerodynamic mesh 20 x 14 boxes", {}, {"n_chord": 20, "n_span": 14}),
    ("infinite-plate spline instead of FE shape functions", {}, {"spline": "ips"}),
    ("finer structural mesh 12 x 14 elements", {"n_chord": 12, "n_span": 14}, {}),
)


def model_sensitivity(db, mach: float = 0.75, altitude: float = 0.0, velocities=VELOCITIES,
                      variants=MODEL_VARIANTS) -> list[dict]:
    """p-k flutter speed with the structure and/or GAFs rebuilt for modelling variants (support
    model, structural mesh, spline, symmetry plane, aerodynamic mesh) at one Mach and altitude.
    Rows: label, elastic frequencies (Hz), Q_cc(k_min), speed, freq, first, first_kind."""
    from ..aeroelastic import modal_arrays
    from ..structure.modes import fin_modal_model
    rho = float(standard_atmosphere(altitude).density)
    rows = []
    for label, skw, akw in variants:
        model = fin_modal_model(**skw)
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
