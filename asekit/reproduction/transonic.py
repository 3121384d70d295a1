"""The fin through the transonic gap (issue 29, tsdfin): flutter and the steady hinge
coefficient from M 0.8 to 1.2 with ``method = "tsd"``, and the linear methods at the joins.

The supersonic chapter's envelope (:mod:`asekit.reproduction.supersonic`) has the DLM up to
M 0.9 and the Mach-box method from M 1.15, and nothing between (``method = "auto"`` refuses
the gap). Here the same fin (the case's structure, FN2 model) is run with the time-linearised
transonic small-disturbance method (:mod:`asekit.aero.tsd3d`) at :data:`MACHS`, on a variant
of the fin's case (:func:`tsd_case`) that differs from the envelope's in four stated ways:

- the section: the case's fin is a flat plate of 4 mm at the root (chord 156 mm) and 2 mm at
  the tip (chord 78 mm), thickness ratio 2.56 % at both; the TSD knows biconvex sections
  only, so a biconvex arc of the same thickness ratio stands in (the thesis gives no edge
  shape; its DLM and this chapter's linear methods see no thickness at all);
- a reflection plane at the root (``aero.symmetry = "wall"``, the fin on the missile body):
  the TSD's half wing is mirrored there; the envelope's fin is isolated ("none"), so the
  joins are checked against the DLM and the Mach-box method with the same wall, and the wall's
  own effect is reported beside them;
- the boxes :data:`BOXES` (the TSD grid 2 cells per chordwise box, 1 per strip, far field 6
  root chords) and the reduced frequencies :data:`REDUCED_FREQUENCIES`: each k costs one
  sparse LU of the complex system, so fewer k than the case's 15 (all linear methods at the
  joins use the same boxes and k);
- the modes below :data:`MODE_F_MAX` Hz (the case keeps 6 up to 948 Hz) and k up to 1: the
  TSD grid (8 x 4 cells, 2.4 cm cells mid-chord) does not resolve the upstream-running
  acoustic wave of a high k at high subsonic Mach (wavelength 2 pi b (1 - M) / (k M): 6.4 cm at
  M 0.8, k 1.9): with the 540 and 602 Hz modes and k up to 1.9 the TSD's Q of the 602 Hz mode
  turns its aerodynamic damping destabilising at k 1.9 (Im Q_55 +7.3 against -3.3 at k 1.0)
  and that mode "flutters" at the sweep's first speed, 100 m/s, at M 0.8 and 0.9 (measured).
  The envelope's flutter is the 110-140 Hz coupling of the rigid pitch with the first two
  elastic modes (89 and 158 Hz), whose k stays below 0.8 above 100 m/s; dropping the 540 and
  602 Hz modes moves the DLM's flutter speed by 0.02 % (224.55 against 224.50 m/s, M 0.8,
  wall, measured).

Results (2026-12-04; sea level; the TSD on 4 x 4 boxes, 8 x 4 cells; flutter speed m/s,
frequency Hz, Re Q_cc 1e-4 m^3/rad, similarity K of the background, supersonic nodes):

====  =====  =====  =====  =====  ====
M     U_f    f_f    Q_cc   K      sup.
====  =====  =====  =====  =====  ====
0.80  230.5  126.4  10.68   5.57     0
0.90  223.4  125.3  11.61   2.51     0
0.95  217.9  117.8  11.81   1.20    41
1.00  227.3  122.0  10.63   0.00  1842
1.05  233.5  119.6   8.52  -1.10  6871
1.10  236.9  116.6   5.11  -2.13  6912
1.15  234.3  113.3   2.30  -3.08  6912
1.20  230.5  111.3   0.54  -3.97  6912
====  =====  =====  =====  =====  ====

Joins (same wall, boxes, k, modes): the DLM 224.6 m/s at M 0.8 (TSD +2.6 %), 222.6 at
M 0.9 (+0.3 %); the Mach box 223.0 at M 1.15 (+5.1 %), 217.5 at M 1.2 (+6.0 %). The TSD's
linear limit (zero thickness) gives 228.5, 218.2, 226.1, 211.8 m/s at M 0.8, 0.95, 1.05, 1.2
(+1.8 % and -2.6 % from the joins): the dip at M 0.95 (-5.5 % from M 0.8) is there without
thickness too (compressibility, not a shock: the 2.56 % section's pocket at M 0.95 is 41
nodes); the thickness raises the supersonic flutter speeds (+3.3 % at M 1.05, +8.9 % at 1.2).
Q_cc: TSD 10.68 against the DLM's 10.33 at M 0.8 (+3.4 %); at M 1.2 0.54 against the Mach
box's -5.04 (zero thickness: -2.0): the centre of pressure lies near the shaft there, so
Q_cc is a small difference, and the TSD puts it further forward (not explained yet; the
first-order supersonic operator's one-cell lag would move it aft).
Grid check (6 x 6 boxes, a 12 x 6-cell grid, same k and modes; 58, 67, 160 CPU-s at M 0.8,
0.95, 1.2): the TSD 229.0, 218.3, 237.3 m/s (128.6, 120.9, 114.1 Hz) against the DLM's 228.4
at M 0.8 (+0.2 %) and the Mach box's 220.2 at M 1.2 (+7.8 %) on those boxes: the subsonic
join converges, the supersonic one does not close (the thickness background's excess stays;
its Q_cc 0.0035 against -4.50). The dip at M 0.95 stays (218.3 m/s).
The isolated fin (no wall) flutters at 210.8 m/s (M 0.8, DLM) and 259.6 m/s (M 1.2, Mach
box) with these boxes: the wall lowers the supersonic flutter speed by 16 % and raises the
subsonic one by 7 %, so the TSD curve sits apart from the envelope's isolated-fin curves.

The GAFs come from :func:`asekit.case.pipeline.gaf_database` of :func:`tsd_case` (cached in
the user cache, entry by entry, like every case's GAFs; the steady backgrounds too); the p-k
results of :func:`transonic_envelope` are cached as ``transonic_envelope.npz`` keyed by a
fingerprint. The first computation takes 11-18 CPU-seconds per Mach for the GAFs (7 k, the
grid's 38 x 12 x 16 = 7296 nodes; more above M 1, where the steady continuation takes more
steps), about 9 min wall in all with the p-k on the loaded shared 2-core machine of
2026-12-04; it runs only when asked for (:func:`transonic_study_requested`:
``python -m asekit reproduce --transonic`` or ``ASEKIT_TRANSONIC_STUDY=1``); otherwise a
cached result is used or the rows say how to compute them.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import replace

import numpy as np

from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.flutter import TabulatedGaf, first_of, pk_flutter, pk_instabilities
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline
from asekit.case.variants import with_modes
from asekit.reproduction.fin import fin_case
from asekit.util.cache import CacheError, load_npz, save_npz
from asekit.util.paths import user_cache_dir
from asekit.util.version import __version__

#: Mach numbers of the TSD through the gap (and 0.1 / 0.05 into each linear range: the joins).
MACHS = (0.8, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2)
#: Altitudes (m) and p-k speed sweep (m/s), as the supersonic envelope's.
ALTITUDES = (0.0, 2500.0, 5000.0)
VELOCITIES = np.arange(100.0, 1600.0 + 1e-9, 10.0)
#: Boxes (chordwise, spanwise) of the TSD variant: an 8 x 4-cell TSD grid (38 x 12 x 16 nodes).
BOXES = (4, 4)
#: Reduced frequencies k = omega b / U (b the case's 0.078 m): the flutter lies near k 0.2-0.4.
REDUCED_FREQUENCIES = (0.001, 0.1, 0.2, 0.3, 0.45, 0.65, 1.0)
#: Elastic modes kept (Hz), see the module docstring.
MODE_F_MAX = 400.0
#: The linear methods at the joins: Mach -> method (same boxes, k, modes and wall).
JOINS = {0.8: "dlm", 0.9: "dlm", 1.15: "supersonic", 1.2: "supersonic"}
_FORMAT = 2          # 2: the validity per Mach


def transonic_study_requested() -> bool:
    """Whether the (minutes-long) transonic study may be computed in this run:
    ``ASEKIT_TRANSONIC_STUDY=1`` (set by ``python -m asekit reproduce --transonic``). Without
    it a cached result is still used."""
    return os.environ.get("ASEKIT_TRANSONIC_STUDY", "") == "1"


#: How to ask for the study when it is not cached.
TRANSONIC_HINT = ("python -m asekit reproduce --transonic, or ASEKIT_TRANSONIC_STUDY=1 for the "
                  "notebooks")


def section_thickness_ratio(case) -> float:
    """The fin's thickness ratio t / c from its case: root thickness over root chord (the
    fin's 4 mm / 156 mm = 2 mm / 78 mm at the tip; one panel).

    >>> round(section_thickness_ratio(fin_case()), 5)
    0.02564
    """
    return float(case.thickness.root) / float(case.panels[0].planform.root_chord)


def tsd_case(case=None, machs=MACHS, thickness_ratio: float | None = None):
    """The fin's case (default :func:`asekit.reproduction.fin.fin_case`) with
    ``aero.method = "tsd"`` over ``machs``: the biconvex stand-in section of the fin's
    thickness ratio (or ``thickness_ratio``; 0 the linear limit), a wall at the root,
    :data:`BOXES`, :data:`REDUCED_FREQUENCIES`, modes below :data:`MODE_F_MAX`.

    >>> c = tsd_case(machs=(0.95,))
    >>> c.aero.method, c.aero.symmetry, c.aero.boxes, c.modes.f_max
    ('tsd', 'wall', ((4, 4),), 400.0)
    """
    case = fin_case() if case is None else case
    tau = section_thickness_ratio(case) if thickness_ratio is None else float(thickness_ratio)
    aero = replace(case.aero, machs=tuple(float(m) for m in machs), method="tsd",
                   symmetry="wall", section=("biconvex", tau), boxes=(BOXES,),
                   reduced_frequencies=tuple(REDUCED_FREQUENCIES))
    return replace(with_modes(case, f_max=MODE_F_MAX), aero=aero)


def _flutter_rows(model, ks, b_ref, mach, q) -> np.ndarray:
    """(n_alt, 3): first flutter speed (m/s), its frequency (Hz) and the first instability
    of any kind (m/s); NaN when none in the sweep."""
    gaf = TabulatedGaf(ks, q, b_ref, mach=mach)
    out = np.full((len(ALTITUDES), 3), np.nan)
    for ih, h in enumerate(ALTITUDES):
        rho = float(standard_atmosphere(h).density)
        res = pk_flutter(model, gaf, rho, VELOCITIES)
        inst = pk_instabilities(res, model, gaf)
        fl, fi = first_of(inst, "flutter"), first_of(inst)
        if fl is not None:
            out[ih, :2] = fl.speed, fl.frequency_hz
        if fi is not None:
            out[ih, 2] = fi.speed
    return out


def _fingerprint(case) -> str:
    h = hashlib.sha256()
    model = pipeline.modal_model(case)
    for a in (model.frequencies_hz, model.shapes, pipeline.box_mesh(case).corners,
              np.array(case.aero.machs), np.array(ALTITUDES), VELOCITIES,
              np.array(REDUCED_FREQUENCIES)):
        h.update(np.round(np.asarray(a, float), 8).tobytes())
    h.update(json.dumps({"format": _FORMAT, "version": __version__,
                         "section": list(case.aero.section),
                         "joins": sorted(JOINS.items())}).encode())
    return h.hexdigest()


def _tsd_gafs(case) -> tuple[np.ndarray, np.ndarray, list]:
    """The TSD GAFs per Mach of ``case`` (:func:`asekit.case.pipeline.gaf_database` of the
    case at that one Mach: the user cache's (Mach, k) entries are shared), their CPU seconds,
    and the reason per Mach when the steady background does not converge (NaN GAFs then)."""
    ks = np.asarray(case.aero.reduced_frequencies, float)
    nm = pipeline.modal_model(case).frequencies_hz.size
    q = np.full((len(case.aero.machs), ks.size, nm, nm), np.nan, complex)
    cpu = np.zeros(len(case.aero.machs))
    failed = []
    for im, m in enumerate(case.aero.machs):
        one = replace(case, aero=replace(case.aero, machs=(m,)))
        t0 = time.process_time()
        try:
            q[im] = pipeline.gaf_database(one, progress=False).Q[0]
        except ValueError as exc:      # the background did not converge: stated, not hidden
            if "did not converge" not in str(exc):
                raise
            failed.append(f"M {m:g}: {exc}")
        cpu[im] = time.process_time() - t0
    return q, cpu, failed


def _compute(case) -> dict:
    """The TSD GAFs, p-k per Mach and altitude, and the linear methods with the same wall,
    boxes, k and modes at :data:`JOINS`, plus the isolated fin's (no wall) to show the wall's
    effect."""
    model = pipeline.modal_model(case)
    boxes = pipeline.box_mesh(case)
    ks = np.asarray(case.aero.reduced_frequencies, float)
    b_ref = case.aero.reference_semichord
    q, cpu, failed = _tsd_gafs(case)
    flutter = np.full((q.shape[0], len(ALTITUDES), 3), np.nan)
    for im, m in enumerate(case.aero.machs):
        if np.all(np.isfinite(q[im])):
            flutter[im] = _flutter_rows(model, ks, b_ref, m, q[im])
    bm = fe_spline(model, boxes)
    join_machs = np.array(sorted(JOINS), float)
    linear = np.full((join_machs.size, 2, len(ALTITUDES), 3), np.nan)   # [wall, none]
    linear_qcc = np.full((join_machs.size, 2), np.nan)
    for ij, m in enumerate(join_machs):
        for iw, wall in enumerate((True, False)):
            ql = gaf_from_box_modes(bm, boxes, m, ks, b_ref, symmetric=wall,
                                    method=JOINS[float(m)])
            linear[ij, iw] = _flutter_rows(model, ks, b_ref, m, ql)
            linear_qcc[ij, iw] = ql[0, 0, 0].real
    valid = pipeline.tsd_validity(case)      # the cached backgrounds' similarity and pockets
    return {"machs": np.asarray(case.aero.machs, float), "Q": q, "flutter": flutter,
            "similarity": np.array([v.similarity for v in valid]),
            "supersonic_points": np.array([v.supersonic_points for v in valid]),
            "Qcc": q[:, 0, 0, 0].real, "join_machs": join_machs, "linear": linear,
            "linear_Qcc": linear_qcc, "gaf_cpu_s": cpu, "failed": np.array(failed, str),
            "mode_hz": np.asarray(model.frequencies_hz, float)}


def transonic_envelope(compute: bool | None = None, case=None) -> dict | None:
    """The fin through the gap (see the module docstring), from the cache when it matches.

    Parameters
    ----------
    compute : compute when not cached (default :func:`transonic_study_requested`); False and
        nothing cached: None.
    case : the TSD case (default :func:`tsd_case`).

    Returns
    -------
    dict or None
        ``machs`` (n_M,), ``flutter`` (n_M, n_alt, 3: flutter speed m/s, its frequency Hz,
        first instability m/s; NaN none), ``Qcc`` (n_M,) steady hinge coefficient Re Q_cc at
        k 0.001 (m^3/rad, > 0 de-centering), ``join_machs``, ``linear`` (n_join, 2 [wall,
        none], n_alt, 3) and ``linear_Qcc`` (n_join, 2) of the linear methods, ``gaf_cpu_s``
        (n_M,) (CPU seconds of each Mach's GAFs when computed; near 0 when cached),
        ``failed`` (reasons of the Machs without a converged background: NaN rows),
        ``similarity`` and ``supersonic_points`` per Mach (the background's
        :class:`asekit.aero.tsd3d.TsdValidity`),
        ``altitudes``, ``thickness_ratio``.
    """
    case = tsd_case() if case is None else case
    compute = transonic_study_requested() if compute is None else bool(compute)
    fp = _fingerprint(case)
    path = user_cache_dir() / "transonic_envelope.npz"
    try:
        data, _ = load_npz(path, expect_metadata={"fingerprint": fp})
    except CacheError:
        data = None
    if data is None:
        if not compute:
            return None
        data = _compute(case)
        try:
            save_npz(path, data, {"fingerprint": fp, "asekit_version": __version__})
        except OSError:          # a read-only cache: computed every time
            pass
    out = dict(data)
    out.update(altitudes=np.array(ALTITUDES), thickness_ratio=case.aero.section[1])
    return out


def _key(mach: float) -> str:
    """``M080`` for M 0.8, ``M105`` for M 1.05 (the reproduce keys' Mach tag)."""
    return f"M{int(round(float(mach) * 100)):03d}"


def quantities(env: dict | None) -> list:
    """The reproduce rows of the gap (:class:`asekit.reproduction.driver.Quantity`), sea level:
    ``flutter.envelope.tsd.M<..>.h0.speed_ms`` / ``.freq_hz`` and
    ``aero.Qcc_steady_m3.tsd.M<..>`` per Mach of :data:`MACHS`, and the linear methods' speeds
    with the same wall at the joins, ``flutter.envelope.tsd.join.M<..>.h0.speed_ms``. With
    ``env`` None (not cached and not requested) every row is "not computed" with
    :data:`TRANSONIC_HINT`.

    >>> rows = quantities(None)
    >>> rows[0].key, rows[0].computed
    ('flutter.envelope.tsd.M080.h0.speed_ms', False)
    """
    from asekit.reproduction.driver import Quantity

    def num(x):
        return None if (x is None or not np.isfinite(x)) else float(x)

    rows = []
    if env is None:
        for m in MACHS:
            for key, unit in ((f"flutter.envelope.tsd.{_key(m)}.h0.speed_ms", "m/s"),
                              (f"flutter.envelope.tsd.{_key(m)}.h0.freq_hz", "Hz"),
                              (f"aero.Qcc_steady_m3.tsd.{_key(m)}", "m^3")):
                rows.append(Quantity(key, None, unit, f"not computed: {TRANSONIC_HINT}",
                                     computed=False))
        for m in sorted(JOINS):
            rows.append(Quantity(f"flutter.envelope.tsd.join.{_key(m)}.h0.speed_ms", None,
                                 "m/s", f"not computed: {TRANSONIC_HINT}", computed=False))
        return rows
    tau = float(env["thickness_ratio"])
    failed = {s.split(":")[0]: s for s in np.atleast_1d(env["failed"]).tolist()}
    for im, m in enumerate(env["machs"]):
        fl = env["flutter"][im, 0]
        note = (f"TSD, biconvex {100 * tau:.2f} % stand-in, root wall, {BOXES[0]} x {BOXES[1]}"
                f" boxes; GAF CPU this run {float(env['gaf_cpu_s'][im]):.0f} s")
        note = failed.get(f"M {m:g}", note)
        rows.append(Quantity(f"flutter.envelope.tsd.{_key(m)}.h0.speed_ms", num(fl[0]), "m/s",
                             note))
        rows.append(Quantity(f"flutter.envelope.tsd.{_key(m)}.h0.freq_hz", num(fl[1]), "Hz",
                             note))
        rows.append(Quantity(f"aero.Qcc_steady_m3.tsd.{_key(m)}", num(env["Qcc"][im]), "m^3",
                             "Re Q_cc at k 0.001, positive de-centering; " + note))
    for ij, m in enumerate(env["join_machs"]):
        rows.append(Quantity(f"flutter.envelope.tsd.join.{_key(m)}.h0.speed_ms",
                             num(env["linear"][ij, 0, 0, 0]), "m/s",
                             f"{JOINS[float(m)]} with the TSD rows' wall, boxes, k and modes"))
    return rows


def fig_gap(env: dict, ax) -> None:
    """Draw the TSD's flutter speeds per altitude (crosses) and the linear methods' with the
    same wall at the joins (open diamonds) onto ``ax`` (the supersonic chapter's flutter-vs-Mach
    axes)."""
    colors = [line.get_color() for line in ax.get_lines()[::3]]
    for ih, h in enumerate(env["altitudes"]):
        c = colors[ih] if ih < len(colors) else None
        ax.plot(env["machs"], env["flutter"][:, ih, 0], "x-", color=c, lw=1.2,
                label=f"flutter TSD (root wall), {h:.0f} m")
        ax.plot(env["join_machs"], env["linear"][:, 0, ih, 0], "d", color=c, mfc="none",
                label=f"flutter DLM / Mach box (root wall), {h:.0f} m")
