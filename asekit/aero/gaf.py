"""Generalised aerodynamic force matrices Q_mm(M, k) and their cached databases
(thesis Section 2.2.1.3, Eqs. 2.10-2.12; Section 3.2).

For modes phi_j with normal displacement h_j on the boxes, the doublet-lattice pressure jumps
DeltaCp_j = D(M, k)^-1 (dh_j/dx + i k h_j / b) (see :mod:`asekit.aero.dlm`) give

    Q_ij(M, k) = sum_boxes h_i(load point) DeltaCp_j A_box         (Eqs. 2.10-2.11)

so that the modal aerodynamic force is F_i = q sum_j Q_ij zeta_j (Eq. 2.12), per unit dynamic
pressure and unit modal coordinate. For a rigid pitch mode (a unit nose-up rotation,
h = -(x - x_axis)) Q_cc is in m^3 and is positive (de-centering) when the centre of pressure
lies ahead of the shaft. k = omega b / U with the database's reference semi-chord b
(``GafDatabase.b_ref``, stated by the caller).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asekit.aero.boxes import BoxMesh
from asekit.aero.dlm import factor_normalwash_matrix, map_normalwash_matrices
from asekit.aero.hmatrix import compressed_pressures, resolve_solver
from asekit.aero.methods import DLM_KERNELS, check_mach, pressures, resolve_method
from asekit.aero.spline import BoxModes, fe_spline, modal_forces
from asekit.aero.validity import check_k, mach_number
from asekit.util.blas import blas_threads_for
from asekit.util.cache import CacheError, load_npz, save_npz
from asekit.util.paths import DATA_DIR, user_cache_dir
from asekit.util.validate import finite_array, positive, real
from asekit.util.version import __version__

_log = logging.getLogger(__name__)

#: The reference fin's database, shipped read-only with the repository (so CI does not rebuild
#: it). Rebuilt databases go to the user cache directory (:func:`asekit.util.paths.user_cache_dir`).
GAF_FILE = DATA_DIR / "gaf_fin.npz"
#: Databases shipped with asekit: any whose fingerprint matches a request is used as is.
SHIPPED_DATABASES = (GAF_FILE,)
#: Format version of the database file; bump when its layout or meaning changes.
GAF_FORMAT = 1
#: The folder of the per-(Mach, k) entries (:class:`GafEntryCache`), next to the databases.
ENTRY_FOLDER = "gaf_entries"


def _finite_table(Q, k: np.ndarray) -> np.ndarray:
    """Q (n_k, n, n) as a complex array, every entry finite, else ValueError naming the first
    bad (mode, k) entry: ``Q[i, r, c]`` at k = k[i], row mode r, column mode c (0-based)."""
    try:
        return finite_array("Q", Q, complex_values=True)
    except ValueError:
        a = np.asarray(Q)
        if a.ndim != 3 or a.dtype.kind not in "iufc":
            raise
        a = a.astype(complex)
    i, r, c = (int(j) for j in np.argwhere(~np.isfinite(a))[0])
    kk = f"k = {k[i]:g}" if k.ndim == 1 and i < k.size else f"k index {i}"
    raise ValueError(f"Q must be finite: Q[{i}, {r}, {c}] = {a[i, r, c].item()!r} at {kk}, modes "
                     f"({r}, {c}) (0-based; {int(np.sum(~np.isfinite(a)))} non-finite entries)")


@dataclass(frozen=True)
class TabulatedGaf:
    """Complex GAFs Q (n_k, n, n) at reduced frequencies k (ascending, >= 0) of one Mach,
    per unit dynamic pressure (F = q Q zeta), reference semi-chord ``b_ref`` (m); ``mach``
    the Mach number they belong to (None: not stated). :meth:`GafDatabase.at` gives one from a
    database; the flutter solvers (:mod:`asekit.aeroelastic.flutter`) read it."""

    k: np.ndarray
    Q: np.ndarray
    b_ref: float
    mach: float | None = None

    def __post_init__(self):
        k = finite_array("k", self.k)
        Q = _finite_table(self.Q, k)
        if k.ndim != 1 or Q.shape[0] != k.size or Q.ndim != 3 or Q.shape[1] != Q.shape[2]:
            raise ValueError(f"Q must be (n_k, n, n) with n_k = len(k); got k {k.shape}, "
                             f"Q {Q.shape}")
        if k.size < 2 or np.any(np.diff(k) <= 0) or k[0] < 0:
            raise ValueError(f"k must hold >= 2 ascending values >= 0, got {k}")
        object.__setattr__(self, "b_ref", positive("b_ref", self.b_ref))
        if self.mach is not None:
            object.__setattr__(self, "mach", mach_number(self.mach))
        object.__setattr__(self, "k", k)
        object.__setattr__(self, "Q", Q)

    def parts(self, k: float, method: str = "linear") -> tuple[np.ndarray, np.ndarray]:
        """(Q^R(k), Q^I(k)/k): real part and imaginary part divided by k, interpolated in k.

        Linear interpolation (Nastran's IMETH=L) or ``method="cubic"`` (not-a-knot spline).
        Outside the table: Q^R and Q^I/k are held at the end values (k below the first point
        uses Q^I(k_1)/k_1, the finite k -> 0 limit of a smooth Q^I).
        """
        kk = self.k
        qi_over_k = self.Q.imag / np.where(kk > 0, kk, 1.0)[:, None, None]
        if kk[0] == 0:
            qi_over_k[0] = qi_over_k[1]
        kq = float(np.clip(real("k", k), kk[0], kk[-1]))
        if method == "linear":
            j = int(np.clip(np.searchsorted(kk, kq) - 1, 0, kk.size - 2))
            t = (kq - kk[j]) / (kk[j + 1] - kk[j])
            qr = (1 - t) * self.Q.real[j] + t * self.Q.real[j + 1]
            qik = (1 - t) * qi_over_k[j] + t * qi_over_k[j + 1]
        elif method == "cubic":
            from scipy.interpolate import CubicSpline
            qr = CubicSpline(kk, self.Q.real, axis=0)(kq)
            qik = CubicSpline(kk, qi_over_k, axis=0)(kq)
        else:
            raise ValueError(f"method must be 'linear' or 'cubic', got {method!r}")
        return qr, qik


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

    def at(self, mach: float, interpolate: bool = False, atol: float = 1e-9) -> TabulatedGaf:
        """The tabulated GAFs at one Mach number.

        Parameters
        ----------
        mach : Mach number (-), within ``atol`` of one of :attr:`machs`, or, with
            ``interpolate``, inside [min(machs), max(machs)].
        interpolate : False (default): an exact Mach of the database is required.
            True: between two tabulated Machs M_0 < M < M_1, Q is interpolated linearly,
            Q(M) = (1 - t) Q(M_0) + t Q(M_1), t = (M - M_0) / (M_1 - M_0) (never extrapolated).
        atol : tolerance of an exact match.

        Returns
        -------
        TabulatedGaf : k, Q (n_k, n, n) at ``mach``, :attr:`b_ref`, ``mach``.

        Raises ValueError naming ``mach``, the database's Machs and its range otherwise.

        Examples
        --------
        >>> import numpy as np
        >>> db = GafDatabase(np.array([0.5, 0.7]), np.array([0.0, 1.0]),
        ...                  np.array([np.ones((2, 1, 1)), 3 * np.ones((2, 1, 1))]), 1.0, 0, {})
        >>> db.at(0.7).Q[0, 0, 0]
        np.complex128(3+0j)
        >>> db.at(0.6, interpolate=True).Q[0, 0, 0]
        np.complex128(2+0j)
        """
        machs = np.asarray(self.machs, dtype=float)
        m = mach_number(mach)
        hit = np.nonzero(np.abs(machs - m) <= atol)[0]
        if hit.size:
            return TabulatedGaf(self.k, self.Q[hit[0]], self.b_ref, mach=m)
        if not interpolate or m < machs.min() or m > machs.max():
            raise ValueError(f"mach {m} is not in the GAF database {machs.tolist()}"
                             + ("" if interpolate else " (pass interpolate=True to interpolate "
                                "between its Machs)")
                             + f"; valid range [{machs.min()}, {machs.max()}]")
        order = np.argsort(machs)
        m_sorted = machs[order]
        j = int(np.searchsorted(m_sorted, m))
        m0, m1 = m_sorted[j - 1], m_sorted[j]
        t = (m - m0) / (m1 - m0)
        q = (1 - t) * self.Q[order[j - 1]] + t * self.Q[order[j]]
        return TabulatedGaf(self.k, q, self.b_ref, mach=m)


def gaf_from_box_modes(box_modes: BoxModes, mesh: BoxMesh, mach: float, k, b_ref: float,
                       symmetric: bool = False, method: str = "quartic",
                       progress=None, aero_options: dict | None = None,
                       max_bytes: int | None = None, on_k=None,
                       solver: str = "dense") -> np.ndarray:
    """Q(M, k) (n_k, n_modes, n_modes) for mode shapes already interpolated to the boxes.

    The k sweep is streamed (:func:`asekit.aero.dlm.map_normalwash_matrices`): one LU
    factorisation of D(M, k) per k, in place, solves for all modes at once and the matrix is
    dropped after its projection, so at most ``max_bytes`` of normalwash matrices (default
    :data:`asekit.aero.dlm.STREAM_BYTES`, at least one matrix) are held; the kernel geometry is
    shared by the k of a batch (all k on small meshes). ``method`` "auto",
    "dlm", "supersonic" or "piston" chooses the aerodynamics per Mach
    (:mod:`asekit.aero.methods`; ``aero_options`` go to its pressure matrices); "quartic" and
    "parabolic" are the DLM kernels. ``on_k(ik, Q_k)``, when given, is called with each k's
    (n_modes, n_modes) result as soon as it is computed (the per-entry cache of
    :func:`build_gaf_database`). ``solver`` (DLM only): "dense" (LU, default), "hmatrix" (the
    compressed matrix and GMRES of :mod:`asekit.aero.hmatrix`, GAFs within 1e-6 relative of
    the dense ones) or "auto" (:func:`asekit.aero.hmatrix.resolve_solver`: by box count).
    """
    ks = check_k(k)
    if resolve_solver(solver, mesh.n) == "hmatrix" and (
            method in DLM_KERNELS or resolve_method(method, mach) == "dlm"):
        return _gaf_compressed(box_modes, mesh, mach, ks, b_ref, symmetric,
                               method if method in DLM_KERNELS else "quartic", progress, on_k)
    if method not in DLM_KERNELS:
        if resolve_method(method, mach) != "dlm" or aero_options:
            cp = pressures(mesh, mach, ks, b_ref, lambda kk: box_modes.normalwash(kk, b_ref),
                           method, symmetric, **(aero_options or {}))
            if progress is not None:
                progress(ks.size)
            out = np.stack([modal_forces(box_modes, c, mesh.area) for c in cp])
            if on_k is not None:
                for ik in range(ks.size):
                    on_k(ik, out[ik])
            return out
        method = "quartic"
    out = np.empty((ks.size, box_modes.h_cp.shape[1], box_modes.h_cp.shape[1]), complex)

    def project(ik, kk, d):
        cp = factor_normalwash_matrix(d, overwrite=True).pressures(box_modes.normalwash(kk, b_ref))
        out[ik] = modal_forces(box_modes, cp, mesh.area)
        if on_k is not None:
            on_k(ik, out[ik])
        if progress is not None:
            progress(1)

    map_normalwash_matrices(mesh, mach, ks, b_ref, project, method, symmetric, max_bytes)
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


def default_reduced_frequencies(k_max: float) -> np.ndarray:
    """Reduced frequencies for a database up to ``k_max``: the values 0.001, 0.01, 0.025, 0.05,
    0.075, 0.1, 0.15, 0.2, 0.3, 0.45, 0.65, 0.9, 1.25, 1.75 below 0.95 k_max, then k_max
    (15 values for the reference fin), dense at low k where the GAFs curve most."""
    k_max = float(k_max)
    if not math.isfinite(k_max) or k_max <= 0.001:
        raise ValueError(f"k_max must be > 0.001, got {k_max!r}")
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


#: Below this many boxes the dense LU solves of a database run on one BLAS thread: on a shared
#: 2-core machine OpenBLAS's threads stall on small matrices (the fin's 140-box rebuild: 2.4-5.5 s
#: wall with 2 threads, 0.8-0.9 s with one, measured on the project machine in issue 12).
SMALL_SOLVE_BOXES = 2000


def _blas_threads_for(n_boxes: int):
    """A context limiting BLAS to one thread for small systems (threadpoolctl), else a no-op."""
    return blas_threads_for(n_boxes, SMALL_SOLVE_BOXES)


@dataclass(frozen=True, eq=False)
class GafEntryCache:
    """Per-(Mach, k) GAF entries of one database request, cached as they are computed so that
    a failed or interrupted build resumes where it stopped (:func:`build_gaf_database`).

    ``folder`` holds one file per entry, ``gafk_<key>_M<mach>_k<k>.npz``, written atomically
    and verified on load (:mod:`asekit.util.cache`: checksum, the ``key``, the Mach, k, the
    grid's k and the Q shape); ``key`` is the fingerprint of everything an entry depends on
    but the Mach list (the mode set, the boxes, the k list, b_ref, symmetry, method:
    :func:`entry_fingerprint`), so a database over more Machs reuses the entries of the others.
    A file that fails a check is recomputed; an entry that cannot be written is only not cached.
    ``computed`` counts the entries computed (not loaded) through this object.
    """

    folder: Path
    key: str
    n_modes: int
    k_grid: float
    computed: list = field(default_factory=list)

    def path(self, mach: float, k: float) -> Path:
        """The entry's file."""
        return Path(self.folder) / f"gafk_{self.key[:32]}_M{float(mach)!r}_k{float(k)!r}.npz"

    def _meta(self, mach: float, k: float) -> dict:
        return {"entry_fingerprint": self.key, "mach": float(mach), "k": float(k),
                "k_grid": float(self.k_grid), "format": GAF_FORMAT}

    def load(self, mach: float, k: float) -> np.ndarray | None:
        """Q (n_modes, n_modes) of the entry if its file exists and passes every check."""
        try:
            arrays, _ = load_npz(self.path(mach, k), expect_metadata=self._meta(mach, k),
                                 expect_shapes={"Q": (self.n_modes, self.n_modes)})
        except (CacheError, OSError, ValueError):
            return None
        q = arrays["Q"]
        return q if q.dtype.kind == "c" and np.all(np.isfinite(q)) else None

    def save(self, mach: float, k: float, q: np.ndarray) -> None:
        """Write the entry (atomically); a folder that cannot be written is skipped."""
        self.computed.append((float(mach), float(k)))
        try:
            save_npz(self.path(mach, k), {"Q": np.asarray(q, complex)}, self._meta(mach, k))
        except OSError:
            pass


class _FreshEntries(GafEntryCache):
    """The entries of a rebuild: never read, written as they are computed."""

    def load(self, mach: float, k: float) -> None:
        return None


def _gaf_compressed(box_modes, mesh, mach, ks, b_ref, symmetric, kernel, progress, on_k):
    """Q per k by :func:`asekit.aero.hmatrix.compressed_pressures` (the k swept in batches
    that share the block structure, every kernel evaluation and a near-field LU; one GMRES
    solve of all modes per k)."""
    out = np.empty((ks.size, box_modes.h_cp.shape[1], box_modes.h_cp.shape[1]), complex)

    def project(ik, cp):
        out[ik] = modal_forces(box_modes, cp, mesh.area)
        if on_k is not None:
            on_k(ik, out[ik])
        if progress is not None:
            progress(1)

    compressed_pressures(mesh, mach, ks, b_ref, lambda kk: box_modes.normalwash(kk, b_ref),
                         kernel, symmetric, on_k=project)
    return out


def _mach_entries(box_modes, mesh, mach, ks, b_ref, symmetric, method, bar, aero_options,
                  entries: GafEntryCache | None, solver: str = "dense") -> np.ndarray:
    """Q (n_k, n, n) at one Mach: the cached entries loaded, the others computed (and cached
    as each is done). Computed k by k where needed, so a resumed Mach gives the numbers of an
    uninterrupted one bit for bit (the Mach-box grid always resolves the list's largest k)."""
    update = None if bar is None else bar.update
    if entries is None:
        return gaf_from_box_modes(box_modes, mesh, mach, ks, b_ref, symmetric, method,
                                  progress=update, aero_options=aero_options, solver=solver)
    n = box_modes.h_cp.shape[1]
    q = np.empty((ks.size, n, n), complex)
    missing = []
    for ik, kk in enumerate(ks):
        got = entries.load(mach, kk)
        if got is None:
            missing.append(ik)
        else:
            q[ik] = got
            if update is not None:
                update(1)
    if not missing:
        return q
    todo = ks[missing]

    def keep(j, qk):
        q[missing[j]] = qk
        entries.save(mach, todo[j], qk)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")       # given where the method is used
        name = "dlm" if method in DLM_KERNELS else resolve_method(method, mach)
    if name == "supersonic":       # the grid of the whole list's largest k, entry by entry
        def project(j, cp):        # the operations of gaf_from_box_modes, k by k
            keep(j, modal_forces(box_modes, cp, mesh.area))
            if update is not None:
                update(1)
        pressures(mesh, mach, todo, b_ref, lambda kk: box_modes.normalwash(kk, b_ref), method,
                  symmetric, **dict(aero_options or {}, k_grid=float(ks.max()), on_k=project))
    else:
        gaf_from_box_modes(box_modes, mesh, mach, todo, b_ref, symmetric, method,
                           progress=update, aero_options=aero_options, on_k=keep,
                           solver=solver)
    return q


def build_gaf_database(box_modes: BoxModes, mesh: BoxMesh, machs, ks, b_ref: float, n_rigid: int,
                       symmetric: bool = False, method: str = "quartic", progress: bool = True,
                       metadata: dict | None = None, aero_options: dict | None = None,
                       entries: GafEntryCache | None = None,
                       solver: str = "dense") -> GafDatabase:
    """Compute Q over ``machs`` x ``ks`` (tqdm bar over Mach x k when ``progress``); ``method``,
    ``aero_options`` and ``solver`` as in :func:`gaf_from_box_modes` (e.g. "auto" over subsonic and
    supersonic Mach numbers, refusing the transonic gap). With ``entries``
    (:class:`GafEntryCache`) each (Mach, k) entry is read from it when cached and written to
    it as soon as it is computed: an interrupted build resumes where it stopped and gives the
    same numbers, bit for bit, as an uninterrupted one."""
    # the Mach range of the method (asekit.aero.methods); an explicit method warns in the gap
    machs = np.array([float(m) for m in np.atleast_1d(machs)])
    for i, m in enumerate(machs):
        if method in DLM_KERNELS:
            check_mach(m, method, f"machs[{i}]")
        else:
            resolve_method(method, m, f"machs[{i}]")
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
        with _blas_threads_for(mesh.n):
            for im, mach in enumerate(machs):
                q[im] = _mach_entries(box_modes, mesh, mach, ks, b_ref, symmetric, method, bar,
                                      aero_options, entries, solver)
    finally:
        if bar is not None:
            bar.close()
    return GafDatabase(machs, ks, q, float(b_ref), int(n_rigid), dict(metadata or {}))


def database_settings(machs, ks, b_ref: float, boxes: BoxMesh, symmetric: bool,
                      method: str) -> dict:
    """What a GAF database depends on besides the mode set (part of its fingerprint)."""
    return {"format": GAF_FORMAT, "machs": [float(m) for m in machs],
            "k": [float(v) for v in ks], "b_ref": float(b_ref),
            "symmetric": bool(symmetric), "method": method, "boxes": int(boxes.n),
            "box_corners_sha256": hashlib.sha256(np.round(boxes.corners, 12).tobytes()).hexdigest()}


def mode_set_fingerprint(model, settings: dict) -> str:
    """Fingerprint of a database request: the mode set (shapes, nodes, frequencies) of a
    ``ModalModel`` and the ``settings`` (see :func:`database_settings`)."""
    return _fingerprint({"shapes": model.shapes, "nodes": model.nodes,
                         "frequencies_hz": model.frequencies_hz}, settings)


def entry_fingerprint(model, settings: dict) -> str:
    """Fingerprint of the per-(Mach, k) entries of a database request
    (:class:`GafEntryCache`): :func:`mode_set_fingerprint` of the settings without the Mach
    list (an entry at one Mach does not depend on the others; it does on the k list, whose
    largest k sets the Mach-box grid)."""
    return mode_set_fingerprint(model, {key: v for key, v in settings.items() if key != "machs"})


def _load_matching(path: Path, fp: str, settings: dict, n_modes: int):
    """The database at ``path`` if it exists, passes its checksum and matches the fingerprint
    and the settings it claims (Mach and k arrays, b_ref, shape); else None."""
    try:
        arrays, meta = load_npz(path)
    except (CacheError, FileNotFoundError, OSError, KeyError, ValueError):
        return None
    try:
        if meta.get("fingerprint") != fp:
            return None
        machs, k, Q = arrays["machs"], arrays["k"], arrays["Q"]
        ok = (np.allclose(machs, settings["machs"], rtol=0, atol=1e-12)
              and np.allclose(k, settings["k"], rtol=1e-12, atol=0)
              and math.isclose(float(meta["b_ref"]), settings["b_ref"], rel_tol=1e-12)
              and Q.shape == (machs.size, k.size, n_modes, n_modes)
              and np.all(np.isfinite(Q)))
        if not ok:
            return None
        return GafDatabase(machs, k, Q, float(meta["b_ref"]), int(meta["n_rigid"]), meta)
    except (KeyError, TypeError, ValueError, AttributeError):
        return None


def cached_gaf_database(model, boxes: BoxMesh, machs, ks, b_ref: float, symmetric: bool = False,
                        method: str = "quartic", progress: bool = True, rebuild: bool = False,
                        cache_dir=None, path=None, metadata: dict | None = None,
                        entries: GafEntryCache | None = None, spline=None,
                        solver: str = "dense", aero_options: dict | None = None) -> GafDatabase:
    """The GAF database of a ``ModalModel`` on ``boxes`` over ``machs`` x ``ks``, from a cache
    when one matches, else computed (tqdm bar) and written atomically.

    Lookup order: ``path`` if given, else the shipped databases (:data:`SHIPPED_DATABASES`,
    read-only) and ``cache_dir`` / ``gaf_<fingerprint>.npz`` (default
    :func:`asekit.util.paths.user_cache_dir`). A file is used only if its checksum passes and its
    fingerprint (mode set + settings), Mach and k arrays, b_ref and array shape all match.
    A rebuild that cannot be written (read-only folder) is returned all the same, with a warning.

    A build caches each (Mach, k) entry as it is computed (:class:`GafEntryCache`, in
    ``gaf_entries/`` next to the database file, or ``entries``): a failed or interrupted build
    resumes where it stopped, and a database over other Machs of the same request reuses
    them. ``rebuild`` recomputes the entries too.

    ``spline`` : a named pair ``(name, fn)`` with ``fn(model, boxes) -> BoxModes`` in place of
    :func:`asekit.aero.spline.fe_spline` (e.g. a stick model's beam-to-box spline,
    :func:`asekit.aero.beam_spline.beam_box_modes`); its name enters the fingerprint.

    ``solver`` : the DLM solve (:func:`gaf_from_box_modes`); when it resolves to "hmatrix"
    (:func:`asekit.aero.hmatrix.resolve_solver`) it enters the fingerprint with its tolerances
    (the dense default leaves the fingerprint as it was).
    ``aero_options`` : the method's options (:func:`build_gaf_database`, e.g. the TSD's
    ``section``); they enter the fingerprint when given.
    """
    settings = database_settings(machs, ks, b_ref, boxes, symmetric, method)
    if spline is not None:
        settings = {**settings, "spline": spline[0]}
    if resolve_solver(solver, boxes.n) == "hmatrix":
        from asekit.aero import hmatrix
        settings = {**settings, "solver": "hmatrix", "hmatrix_eps": hmatrix.DEFAULT_EPS,
                    "hmatrix_rtol": hmatrix.DEFAULT_RTOL}
    if aero_options:
        settings = {**settings, "aero_options": {key: aero_options[key]
                                                 for key in sorted(aero_options)}}
    fp = mode_set_fingerprint(model, settings)
    n = len(model.frequencies_hz)
    if path is not None:
        candidates, target = [Path(path)], Path(path)
    else:
        cdir = Path(user_cache_dir() if cache_dir is None else cache_dir)
        target = cdir / f"gaf_{fp[:32]}.npz"
        candidates = [*SHIPPED_DATABASES, target]
    if entries is None and rebuild:         # recompute every entry (and cache it afresh)
        entries = _FreshEntries(target.parent / ENTRY_FOLDER, entry_fingerprint(model, settings),
                                n, float(np.max(ks)))
    if not rebuild:
        for c in candidates:
            db = _load_matching(c, fp, settings, n)
            if db is not None:
                _log.info("GAF database read from %s (fingerprint and checksum verified)", c)
                return db
            _log.debug("GAF cache %s: no matching database", c)
    meta = dict(settings)
    meta.update({"fingerprint": fp, "asekit_version": __version__, "n_rigid": model.n_rigid,
                 "mode_set": model.label, "frequencies_hz": [float(f) for f in model.frequencies_hz],
                 "Q_units": "per unit dynamic pressure; rigid-pitch row/column in m^3 per rad",
                 "sign": "F_i = q sum_j Q_ij zeta_j; Q_cc > 0 de-centering"})
    meta.update(metadata or {})
    if entries is None:
        entries = GafEntryCache(target.parent / ENTRY_FOLDER, entry_fingerprint(model, settings),
                                n, float(np.max(ks)))
    _log.info("GAF database: computing %d Mach x %d reduced frequencies (%s)",
              np.size(machs), np.size(ks), method)
    t0 = time.perf_counter()
    box_modes = fe_spline(model, boxes) if spline is None else spline[1](model, boxes)
    db = build_gaf_database(box_modes, boxes, machs, ks, b_ref, model.n_rigid,
                            symmetric, method, progress, meta, entries=entries, solver=solver,
                            aero_options=aero_options)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        save_npz(target, {"machs": db.machs, "k": db.k, "Q": db.Q}, meta)
        written = _load_matching(target, fp, settings, n)      # what a later run will read
        _log.info("GAF database built in %.1f s, cached at %s", time.perf_counter() - t0, target)
        if written is not None:
            return written
    except OSError as exc:
        warnings.warn(f"GAF database computed but not cached ({target}: {exc}); set "
                      f"ASEKIT_CACHE_DIR to a writable folder to keep it", RuntimeWarning,
                      stacklevel=2)
    return db


def steady_hinge_coefficient(db: GafDatabase, mach: float) -> float:
    """Re Q_cc at the database's lowest k (0.001) and ``mach`` (m^3/rad; thesis Eq. 4.6)."""
    return float(db.at(mach).Q[0, 0, 0].real)
