"""The reference fin across its whole envelope, M 0.4 to 3 at sea level, 2500 m and 5000 m
(beyond the thesis, which stops at M 0.75): flutter and divergence against Mach with the
transonic gap marked, the steady hinge coefficient Q_cc(M) and the centre of pressure, and the
Section 4.1.1 torque requirement at the worst supersonic condition.

Aerodynamics per Mach by :mod:`asekit.aero.methods` ``method="auto"``: the DLM up to M 0.9
(the cached database for M 0.4-0.75), the supersonic Mach-box method from M 1.15; nothing in
the gap between (linear theory is not trusted there). Structure: the fin case's ``pipeline.modal_model`` (FN2,
rigid pitch + elastic modes), GAFs over :func:`asekit.case.pipeline.reduced_frequencies`.

Reproduce keys: ``aero.Qcc_steady_m3.M12/.M20/.M30`` (Re Q_cc at k 0.001, m^3/rad, positive
de-centering), ``flutter.pk.M12.h0.speed_ms`` (and ``.M20.``, ``.M30.``; None when no flutter is
found in the sweep, with the first instability in ``flutter.first_instability.pk.M..``),
``supersonic.torque.required_stall_Nm`` and ``supersonic.torque.worst_mach``; the transonic
gap by the TSD (issue 29, :mod:`asekit.reproduction.transonic`, computed with ``--transonic``):
``flutter.envelope.tsd.M080.h0.speed_ms`` ... ``.M120.``, ``.freq_hz``,
``aero.Qcc_steady_m3.tsd.M..`` and the joins ``flutter.envelope.tsd.join.M..``.

The GAFs and p-k results (about 30 s to compute) are cached outside the repository, in
the user cache directory (``$ASEKIT_CACHE_DIR``, default ``~/.cache/asekit``; ``supersonic_envelope.npz``), keyed by a fingerprint of
the mode set, the box mesh and the settings.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from pathlib import Path

import numpy as np

from asekit.aero.boxes import MeshRuleWarning
from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.methods import DLM_MACH_MAX, SUPERSONIC_MACH_MIN, pressures
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    divergence_speeds,
    first_of,
    pk_flutter_many,
    pk_instabilities_many,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline
from asekit.reproduction.driver import ChapterResult, Quantity
from asekit.reproduction.fin import fin_case
from asekit.servo.actuator import THESIS_FIN_INERTIA
from asekit.servo.torque_requirement import profile_step, required_stall_torque, tune_rate_limit
from asekit.util.cache import CacheError, load_npz, save_npz
from asekit.util.paths import user_cache_dir
from asekit.util.plotting import new_figure
from asekit.util.version import __version__

MACHS = (0.4, 0.5, 0.6, 0.75, 0.9, 1.15, 1.2, 1.5, 2.0, 2.5, 3.0)
ALTITUDES = (0.0, 2500.0, 5000.0)
VELOCITIES = np.arange(100.0, 1600.0 + 1e-9, 10.0)     # m/s
KEY_MACHS = {"M12": 1.2, "M20": 2.0, "M30": 3.0}
CACHE_FORMAT = 3


def cache_dir() -> Path:
    """The user cache directory (:func:`asekit.util.paths.user_cache_dir`, never the repository)."""
    return user_cache_dir()


def _fingerprint(model, boxes, ks) -> str:
    h = hashlib.sha256()
    for a in (model.frequencies_hz, model.shapes, boxes.corners, ks, np.array(MACHS),
              np.array(ALTITUDES), VELOCITIES):
        h.update(np.round(np.asarray(a, float), 8).tobytes())
    h.update(json.dumps({"format": CACHE_FORMAT, "version": __version__,
                         "dlm_max": DLM_MACH_MAX, "sup_min": SUPERSONIC_MACH_MIN}).encode())
    return h.hexdigest()


def _compute(model, boxes, ks, b_ref) -> dict:
    """GAFs, steady loads and p-k / divergence results over MACHS x ALTITUDES."""
    db = pipeline.gaf_database(fin_case(), progress=False)
    bm = fe_spline(model, boxes)
    nm = model.frequencies_hz.size
    q = np.empty((len(MACHS), ks.size, nm, nm), complex)
    lift = np.empty(len(MACHS))
    xcp = np.empty(len(MACHS))
    coarse = []
    for im, mach in enumerate(MACHS):
        hit = np.flatnonzero(np.isclose(db.machs, mach))
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always", MeshRuleWarning)
            if hit.size and np.allclose(db.k, ks):
                q[im] = db.Q[hit[0]]
            else:
                q[im] = gaf_from_box_modes(bm, boxes, mach, ks, b_ref, method="auto")
            cp = pressures(boxes, mach, [ks[0]], b_ref,
                           lambda kk: bm.normalwash(kk, b_ref)[:, :1], method="auto")[0][:, 0]
        if any(issubclass(w.category, MeshRuleWarning) for w in rec):
            coarse.append(mach)
        force = cp.real * boxes.area
        lift[im] = force.sum()
        xcp[im] = float(np.sum(force * boxes.load_point[:, 0]) / force.sum())
    n_h = len(ALTITUDES)
    flutter = np.full((len(MACHS), n_h, 2), np.nan)        # speed, frequency
    first = np.full((len(MACHS), n_h), np.nan)
    first_kind = np.zeros((len(MACHS), n_h), int)          # 0 none, 1 flutter, 2 divergence
    diverg = np.full((len(MACHS), n_h), np.nan)
    gafs = [TabulatedGaf(ks, q[im], b_ref, mach=mach) for im, mach in enumerate(MACHS)]
    rhos = [float(standard_atmosphere(h).density) for h in ALTITUDES]
    # the 33 sweeps solved together (issue 23: pk_flutter_many, each equal to its pk_flutter)
    sweeps = pk_flutter_many(model, [(g, rho) for g in gafs for rho in rhos], VELOCITIES)
    found = pk_instabilities_many(sweeps, model, [g for g in gafs for _ in rhos])
    for im, mach in enumerate(MACHS):
        for ih, h in enumerate(ALTITUDES):
            rho = rhos[ih]
            inst = found[im * len(ALTITUDES) + ih]
            fl, fi = first_of(inst, "flutter"), first_of(inst)
            if fl is not None:
                flutter[im, ih] = (fl.speed, fl.frequency_hz)
            if fi is not None:
                first[im, ih] = fi.speed
                first_kind[im, ih] = 1 if fi.kind == "flutter" else 2
            dv = divergence_speeds(model, q[im, 0], rho)
            if dv.size:
                diverg[im, ih] = dv[0]
    return {"Q": q, "lift": lift, "xcp": xcp, "flutter": flutter, "first": first,
            "first_kind": first_kind, "divergence": diverg,
            "coarse_machs": np.array(coarse, float),
            "peak_acceleration": np.array(_peak_acceleration())}


def _peak_acceleration() -> float:
    """|theta''|_max of the Section 4.1.1 command profile (as in the servo chapter)."""
    profile = tune_rate_limit(natural_frequency=157.0, damping_ratio=1.0,
                              step=math.radians(15.0), settling_time=0.05, band=0.02)
    return float(profile_step(profile, math.radians(15.0), t_final=0.08).peak_acceleration)


def envelope(rebuild: bool = False) -> dict:
    """The envelope results (see :func:`_compute`), from the cache when it matches.

    Returns a dict with ``machs``, ``altitudes``, ``k``, ``Q`` (n_mach, n_k, n, n), ``lift``
    (m^2/rad per unit q), ``xcp`` (m), ``Qcc`` (m^3/rad), ``flutter`` (n_mach, n_alt, 2: speed
    m/s, frequency Hz; NaN none), ``first`` / ``first_kind`` (first instability of any kind),
    ``divergence`` (m/s, NaN none), ``peak_acceleration`` (rad/s^2, the Section 4.1.1
    profile's), ``flight_speed`` (M a(h), m/s), ``x_axis`` (m), ``model``.
    """
    case = fin_case()
    model = pipeline.modal_model(case)
    boxes = pipeline.box_mesh(case)
    ks = pipeline.reduced_frequencies(case)
    b_ref = case.aero.reference_semichord
    fp = _fingerprint(model, boxes, ks)
    path = cache_dir() / "supersonic_envelope.npz"
    data = None
    if not rebuild:
        try:
            arrays, meta = load_npz(path)
            if meta.get("fingerprint") == fp:
                data = arrays
        except CacheError:
            pass
    if data is None:
        data = _compute(model, boxes, ks, b_ref)
        try:
            save_npz(path, data, {"fingerprint": fp, "asekit_version": __version__})
        except OSError:          # a read-only home: compute every time
            pass
    out = dict(data)
    out.update(machs=np.array(MACHS), altitudes=np.array(ALTITUDES), k=ks, model=model,
               x_axis=case.support.axis_point[0], Qcc=np.asarray(data["Q"])[:, 0, 0, 0].real,
               flight_speed=np.array([[m * float(standard_atmosphere(h).speed_of_sound)
                                       for h in ALTITUDES] for m in MACHS]))
    return out


def torque_at_worst_supersonic(env: dict) -> dict:
    """Section 4.1.1 stall torque (Eqs. 4.1, 4.7, 4.10-4.12) re-evaluated with Q_cc(M) at the
    supersonic (Mach, altitude) of the largest steady hinge moment |q Q_cc| (q = rho (M a)^2/2);
    the command profile and fin inertia as in the servo chapter."""
    best = None
    for im, mach in enumerate(env["machs"]):
        if mach < SUPERSONIC_MACH_MIN:
            continue
        for h in env["altitudes"]:
            atm = standard_atmosphere(h)
            hm = 0.5 * float(atm.density) * (mach * float(atm.speed_of_sound)) ** 2 \
                * abs(env["Qcc"][im])
            if best is None or hm > best[0]:
                best = (hm, float(mach), float(h), float(env["Qcc"][im]), atm)
    _, mach, h, qcc, atm = best
    tr = required_stall_torque(float(env["peak_acceleration"]), fin_inertia=THESIS_FIN_INERTIA,
                               q_cc=qcc,
                               mach=mach, density=float(atm.density),
                               speed_of_sound=float(atm.speed_of_sound))
    return {"mach": mach, "altitude": h, "q_cc": qcc, "torque": tr}


def _num(x):
    return None if (x is None or not np.isfinite(x)) else float(x)


def run(figures: bool = False) -> ChapterResult:
    env = envelope()
    machs = list(env["machs"])
    q = []
    for key, mach in KEY_MACHS.items():
        im = machs.index(mach)
        q.append(Quantity(f"aero.Qcc_steady_m3.{key}", float(env["Qcc"][im]), "m^3",
                          f"supersonic Mach box, k {env['k'][0]:g}; x_cp {env['xcp'][im]:.4f} m "
                          f"(shaft {env['x_axis']:.3f} m); positive = de-centering"))
    kinds = {0: "none", 1: "flutter", 2: "divergence"}
    for key, mach in KEY_MACHS.items():
        im = machs.index(mach)
        fl = env["flutter"][im, 0]
        first = env["first"][im, 0]
        kind = kinds[int(env["first_kind"][im, 0])]
        note = (f"sea level, sweep {VELOCITIES[0]:.0f}-{VELOCITIES[-1]:.0f} m/s, "
                f"GAFs at M {mach:g} "
                f"(flight speed M a = {env['flight_speed'][im, 0]:.0f} m/s); first instability "
                f"{kind}" + (f" at {first:.0f} m/s" if np.isfinite(first) else ""))
        if not np.isfinite(fl[0]):
            note += "; no flutter in the sweep"
        q.append(Quantity(f"flutter.pk.{key}.h0.speed_ms", _num(fl[0]), "m/s", note))
        q.append(Quantity(f"flutter.first_instability.pk.{key}.h0.speed_ms", _num(first), "m/s",
                          kind))
    tq = torque_at_worst_supersonic(env)
    q.append(Quantity("supersonic.torque.required_stall_Nm", tq["torque"].required, "N m",
                      f"Eq 4.10 at M {tq['mach']:g}, {tq['altitude']:.0f} m, Q_cc "
                      f"{tq['q_cc']:.3g} m^3 (thesis design point M 0.6 sea level)"))
    q.append(Quantity("supersonic.torque.worst_mach", tq["mach"], "-",
                      f"largest |q Q_cc| among supersonic Mach numbers, at {tq['altitude']:.0f} m"))
    # issue 29 (tsdfin): the transonic gap by the TSD, computed only when asked (--transonic)
    from asekit.reproduction import transonic
    tsd = transonic.transonic_envelope()
    q.extend(transonic.quantities(tsd))
    figs = {}
    if figures:
        figs = {"supersonic_flutter_vs_mach": fig_flutter_vs_mach(env, tsd=tsd),
                "supersonic_qcc_vs_mach": fig_qcc_vs_mach(env)}
    return ChapterResult("supersonic", tuple(q), figs)


# ---- figures -----------------------------------------------------------------------------------
def _gap(ax):
    ax.axvspan(DLM_MACH_MAX, SUPERSONIC_MACH_MIN, color="0.85", zorder=0,
               label="transonic gap (linear theory not trusted)")


def fig_flutter_vs_mach(env=None, tsd=None):
    """Flutter and divergence speed vs Mach at each altitude, with the flight speed M a(h);
    with ``tsd`` (:func:`asekit.reproduction.transonic.transonic_envelope`) the TSD's flutter
    speeds through the gap and the linear methods' with its root wall at the joins."""
    env = envelope() if env is None else env
    fig, ax = new_figure("Fin flutter and divergence across the envelope")
    m = env["machs"]
    for ih, h in enumerate(env["altitudes"]):
        line, = ax.plot(m, env["flutter"][:, ih, 0], "o-", label=f"flutter, {h:.0f} m")
        ax.plot(m, env["divergence"][:, ih], "s--", color=line.get_color(), mfc="none",
                label=f"divergence, {h:.0f} m")
        ax.plot(m, env["flight_speed"][:, ih], ":", color=line.get_color(),
                label=f"flight speed M a, {h:.0f} m")
    _gap(ax)
    if tsd is not None:                      # issue 29 (tsdfin)
        from asekit.reproduction.transonic import fig_gap
        fig_gap(tsd, ax)
    ax.set_xlabel("Mach number (-)")
    ax.set_ylabel("speed (m/s)")
    ax.set_ylim(0, 1700)
    ax.legend(fontsize=7, ncol=2)
    return fig


def fig_qcc_vs_mach(env=None):
    """Steady hinge coefficient Q_cc(M) and the centre of pressure."""
    env = envelope() if env is None else env
    fig, axes = new_figure("Steady hinge coefficient and centre of pressure vs Mach", ncols=2)
    m = env["machs"]
    axes[0].plot(m, env["Qcc"] * 1e4, "o-")
    axes[0].axhline(0, color="k", lw=0.5)
    axes[0].set_ylabel("Re Q_cc (1e-4 m^3/rad), > 0 de-centering")
    axes[1].plot(m, env["xcp"] * 1e3, "o-", label="centre of pressure")
    axes[1].axhline(env["x_axis"] * 1e3, color="k", ls="--", label="shaft axis")
    axes[1].set_ylabel("x (mm from the root leading edge)")
    axes[1].legend()
    for ax in axes:
        _gap(ax)
        ax.set_xlabel("Mach number (-)")
    return fig
