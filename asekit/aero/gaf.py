"""Generalised aerodynamic force matrices Q_mm(M, k) and the fin's cached GAF database
(thesis Section 2.2.1.3, Eqs. 2.10-2.12; Section 3.2).

For modes phi_j with normal displacement h_j on the boxes, the doublet-lattice pressure jumps
DeltaCp_j = D(M, k)^-1 (dh_j/dx + i k h_j / b) (see :mod:`asekit.aero.dlm`) give

    Q_ij(M, k) = sum_boxes h_i(load point) DeltaCp_j A_box         (Eqs. 2.10-2.11)

so that the modal aerodynamic force is F_i = q sum_j Q_ij zeta_j (Eq. 2.12), per unit dynamic
pressure and unit modal coordinate. For the fin's rigid pitch mode (a unit nose-up rotation,
h = -(x - x_axis)) Q_cc is in m^3 and is positive (de-centering) when the centre of pressure
lies ahead of the shaft. k = omega b / U with b = ``fin.aero.reference_semichord`` = 0.078 m,
the fin's root semi-chord.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .. import __version__
from ..cache import CacheError, load_npz, save_npz
from ..paths import DATA_DIR
from .boxes import BoxMesh, fin_boxes
from .dlm import check_k, normalwash_matrices
from .spline import BoxModes, fe_spline, modal_forces
from .vlm import check_mach

#: Where the fin's database lives (committed, so CI does not rebuild it).
GAF_FILE = DATA_DIR / "gaf_fin.npz"
#: Format version of the database file; bump when its layout or meaning changes.
GAF_FORMAT = 1


@dataclass(frozen=True)
class GafDatabase:
    """GAF matrices over Mach and reduced frequency.

    machs : (n_mach,); k : (n_k,) ascending reduced frequencies (first ~0.001);
    Q : (n_mach, n_k, n_modes, n_modes) complex, per unit dynamic pressure;
    b_ref : reference semi-chord of k (m); n_rigid : rigid modes at the front of the mode set;
    metadata : mesh, mode-set fingerprint, asekit version, symmetry flag, kernel, ...
    """

    machs: np.ndarray
    k: np.ndarray
    Q: np.ndarray
    b_ref: float
    n_rigid: int
    metadata: dict


def gaf_from_box_modes(box_modes: BoxModes, mesh: BoxMesh, mach: float, k, b_ref: float,
                       symmetric: bool = False, method: str = "quartic",
                       progress=None, aero_options: dict | None = None) -> np.ndarray:
    """Q(M, k) (n_k, n_modes, n_modes) for mode shapes already interpolated to the boxes.

    One LU factorisation of D(M, k) per k solves for all modes at once; the kernel geometry
    is shared by all k (:func:`asekit.aero.dlm.normalwash_matrices`). ``method`` "auto",
    "dlm", "supersonic" or "piston" chooses the aerodynamics per Mach
    (:mod:`asekit.aero.methods`; ``aero_options`` go to its pressure matrices); "quartic" and
    "parabolic" are the DLM kernels.
    """
    ks = check_k(k)
    if method not in ("quartic", "parabolic"):
        from .methods import pressures, resolve_method
        if resolve_method(method, mach) != "dlm" or aero_options:
            cp = pressures(mesh, mach, ks, b_ref, lambda kk: box_modes.normalwash(kk, b_ref),
                           method, symmetric, **(aero_options or {}))
            if progress is not None:
                progress(ks.size)
            return np.stack([modal_forces(box_modes, c, mesh.area) for c in cp])
        method = "quartic"
    d = normalwash_matrices(mesh, mach, ks, b_ref, method, symmetric)
    out = np.empty((ks.size, box_modes.h_cp.shape[1], box_modes.h_cp.shape[1]), complex)
    for ik, kk in enumerate(ks):
        cp = sla.lu_solve(sla.lu_factor(d[ik], check_finite=False), box_modes.normalwash(kk, b_ref))
        out[ik] = modal_forces(box_modes, cp, mesh.area)
        if progress is not None:
            progress(1)
    return out


def gaf_matrix(model, boxes: BoxMesh, mach: float, k: float, b_ref: float,
               symmetric: bool = False, method: str = "quartic") -> np.ndarray:
    """Q_mm(M, k) (n_modes, n_modes) complex of a structural ``ModalModel`` on ``boxes``
    (Eqs. 2.10-2.12), the modes interpolated with the finite-element shape functions.

    Parameters
    ----------
    model : :class:`asekit.structure.modes.ModalModel`.
    boxes : :class:`~asekit.aero.boxes.BoxMesh` in the structure's plane.
    mach : 0 <= M < 1; k : reduced frequency omega b_ref / U >= 0; b_ref : m.
    symmetric : wall (symmetry plane) at the root y = 0; default isolated.
    method : DLM kernel approximation, "quartic" (default) or "parabolic".
    """
    if np.ndim(k) != 0:
        raise ValueError(f"k must be a scalar reduced frequency, got shape {np.shape(k)}")
    return gaf_from_box_modes(fe_spline(model, boxes), boxes, mach, [k], b_ref, symmetric,
                              method)[0]


def database_k(fin) -> np.ndarray:
    """The database's reduced frequencies: 15 values from 0.001 to k_max = 2 pi f_max b / U_min
    (fin.md; about 2.72 for the reference fin), dense at low k where the GAFs curve most."""
    k_max = fin.aero.k_max
    base = np.array([0.001, 0.01, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.45, 0.65, 0.9,
                     1.25, 1.75])
    return np.concatenate([base[base < 0.95 * k_max], [k_max]])


def _fingerprint(arrays: dict, settings: dict) -> str:
    """SHA-256 over the mode set and the settings. Each array is scaled by its largest magnitude
    and rounded to 8 decimals first, so round-off differences between machines (including the
    sign of values that are zero in exact arithmetic) do not invalidate the file."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.asarray(arrays[name], float)
        scale = float(np.max(np.abs(a))) if a.size else 1.0
        r = np.round(a / (scale if scale > 0 else 1.0), 8) + 0.0       # -0.0 -> 0.0
        h.update(name.encode())
        h.update(str(a.shape).encode())
        h.update(np.ascontiguousarray(r).tobytes())
    h.update(json.dumps(settings, sort_keys=True).encode())
    return h.hexdigest()


def build_gaf_database(box_modes: BoxModes, mesh: BoxMesh, machs, ks, b_ref: float, n_rigid: int,
                       symmetric: bool = False, method: str = "quartic", progress: bool = True,
                       metadata: dict | None = None,
                       aero_options: dict | None = None) -> GafDatabase:
    """Compute Q over ``machs`` x ``ks`` (tqdm bar over Mach x k when ``progress``); ``method``
    and ``aero_options`` as in :func:`gaf_from_box_modes` (e.g. "auto" over subsonic and
    supersonic Mach numbers, refusing the transonic gap)."""
    if method in ("quartic", "parabolic"):
        machs = np.array([check_mach(m) for m in np.atleast_1d(machs)])
    else:
        from .methods import resolve_method
        machs = np.array([float(m) for m in np.atleast_1d(machs) if resolve_method(method, m)])
    ks = check_k(ks)
    if np.any(np.diff(ks) <= 0):
        raise ValueError("ks must be strictly ascending")
    n_m = box_modes.h_cp.shape[1]
    q = np.empty((machs.size, ks.size, n_m, n_m), complex)
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=machs.size * ks.size, desc="GAF database (Mach x k)", leave=False)
    try:
        for im, mach in enumerate(machs):
            q[im] = gaf_from_box_modes(box_modes, mesh, mach, ks, b_ref, symmetric, method,
                                       progress=None if bar is None else bar.update,
                                       aero_options=aero_options)
    finally:
        if bar is not None:
            bar.close()
    return GafDatabase(machs, ks, q, float(b_ref), int(n_rigid), dict(metadata or {}))


def _fin_settings(fin, boxes: BoxMesh, symmetric: bool, method: str) -> dict:
    return {"format": GAF_FORMAT, "machs": [float(m) for m in fin.aero.machs],
            "k": [float(v) for v in database_k(fin)], "b_ref": fin.aero.reference_semichord,
            "symmetric": bool(symmetric), "method": method, "boxes": int(boxes.n),
            "box_corners_sha256": hashlib.sha256(np.round(boxes.corners, 12).tobytes()).hexdigest()}


def fin_gaf_database(rebuild: bool = False, progress: bool = True, path=None,
                     symmetric: bool = False, method: str = "quartic"):
    """The reference fin's GAF database and its modal model.

    Loads ``data/gaf_fin.npz`` if it is present, passes its checksum
    (:func:`asekit.cache.load_npz`) and matches the current mode set and settings fingerprint;
    otherwise (or with ``rebuild``) computes it -- Mach 0.4, 0.5, 0.6, 0.75 x
    :func:`database_k`, isolated fin, default structure ``fin_modal_model()`` (FN2, 6 x 7
    single-node shaft) on :func:`~asekit.aero.boxes.fin_boxes` -- and writes it atomically.

    ``symmetric`` (a wall at the root) or ``method="parabolic"`` select another database, kept in
    its own file (``data/gaf_fin_wall_quartic.npz`` etc.) unless ``path`` is given.

    Returns
    -------
    (GafDatabase, ModalModel)
    """
    from ..geometry import load_fin
    from ..structure.modes import fin_modal_model
    fin = load_fin()
    model = fin_modal_model(fin)
    boxes = fin_boxes(fin)
    settings = _fin_settings(fin, boxes, symmetric, method)
    fp = _fingerprint({"shapes": model.shapes, "nodes": model.nodes,
                       "frequencies_hz": model.frequencies_hz}, settings)
    if path is None:      # only the default settings live in the committed file
        default = not symmetric and method == "quartic"
        path = GAF_FILE if default else DATA_DIR / (
            f"gaf_fin_{'wall' if symmetric else 'isolated'}_{method}.npz")
    if not rebuild:
        try:
            arrays, meta = load_npz(path)
            if meta.get("fingerprint") == fp:
                return (GafDatabase(arrays["machs"], arrays["k"], arrays["Q"],
                                    float(meta["b_ref"]), int(meta["n_rigid"]), meta), model)
        except (CacheError, KeyError):
            pass
    meta = dict(settings)
    meta.update({"fingerprint": fp, "asekit_version": __version__, "n_rigid": model.n_rigid,
                 "mode_set": model.label, "frequencies_hz": [float(f) for f in model.frequencies_hz],
                 "reference_semichord": "root semi-chord, fin.aero.reference_semichord (m)",
                 "Q_units": "per unit dynamic pressure; rigid-pitch row/column in m^3 per rad",
                 "sign": "F_i = q sum_j Q_ij zeta_j; Q_cc > 0 de-centering"})
    db = build_gaf_database(fe_spline(model, boxes), boxes, fin.aero.machs, database_k(fin),
                            fin.aero.reference_semichord, model.n_rigid, symmetric, method,
                            progress, meta)
    save_npz(path, {"machs": db.machs, "k": db.k, "Q": db.Q}, meta)
    arrays, meta = load_npz(path)
    return GafDatabase(arrays["machs"], arrays["k"], arrays["Q"], float(meta["b_ref"]),
                       int(meta["n_rigid"]), meta), model


def steady_hinge_coefficient(db: GafDatabase, mach: float) -> float:
    """Re Q_cc at the database's lowest k (0.001) and ``mach`` (m^3/rad; thesis Eq. 4.6)."""
    i = int(np.argmin(np.abs(db.machs - mach)))
    if not math.isclose(db.machs[i], mach, abs_tol=1e-9):
        raise ValueError(f"mach {mach} is not in the database {db.machs.tolist()}")
    return float(db.Q[i, 0, 0, 0].real)
