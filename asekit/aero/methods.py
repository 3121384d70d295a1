"""Choice of the unsteady aerodynamic method per Mach number, and one entry point for the
pressure-per-normalwash matrices of every method.

``method``:

- ``"dlm"``: subsonic doublet lattice (:mod:`asekit.aero.dlm`, M < 1; ``"quartic"`` and
  ``"parabolic"`` name its two kernel approximations and are accepted too);
- ``"supersonic"``: the Mach-box lifting-surface method (:mod:`asekit.aero.supersonic`, M > 1);
- ``"piston"``: piston theory (:mod:`asekit.aero.piston`, M > 1, warns outside its bound);
- ``"tsd"``: the time-linearised transonic small-disturbance method
  (:mod:`asekit.aero.tsd3d`, 0 < M < 1.3, the transonic gap 0.9 < M < 1.15 included without the
  gap's warning: it models the nonlinear steady background; options ``section`` (a
  (shape, thickness_ratio) pair, "biconvex" only) and ``grid_options``);
- ``"auto"``: the DLM for M <= DLM_MACH_MAX (0.9), the supersonic method for
  M >= SUPERSONIC_MACH_MIN (1.15), and a :class:`TransonicGapError` in between.

Why the gap. Linear (small-disturbance) potential theory assumes that the perturbation
velocities are small against |U - a|; as M -> 1 the linearised equation loses its
beta^2 phi_xx term, shocks and their motion dominate the unsteady loads, and the subsonic
kernel (Prandtl-Glauert factor 1/sqrt(1 - M^2)) and the supersonic one (1/sqrt(M^2 - 1),
Mach cones that collapse onto the wing, kernel wavelength 2 pi b (M - 1)/(k M) -> 0) both
diverge. Transonic unsteady loads need a nonlinear (transonic small-disturbance, Euler or
Navier-Stokes) solution or test data; asekit does not extrapolate into the gap.

The registry. :data:`AERO_METHODS` maps each method name to its :class:`AeroMethod`: its valid
Mach range (:mod:`asekit.aero.validity`), its builder of the pressure-per-normalwash matrices
and whether those matrices are structure-independent (they depend on the boxes, Mach and k
only, so a sweep over the structure factors or forms them once per Mach and projects each
sample's modes, :mod:`asekit.sweep`). The case schema (``aero.method``, ``aero.machs``), the
pipeline and the sweep check a method and a Mach number here (:func:`check_method`,
:func:`check_mach`, :func:`resolve_method`); an unknown method fails with the list of the known
ones. Adding a method: its kernel module and one :data:`AERO_METHODS` entry.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from asekit.aero.boxes import BoxMesh, dlm_max_box_chord
from asekit.aero.dlm import factor_normalwash_matrix, map_normalwash_matrices, normalwash_matrices
from asekit.aero.piston import piston_pressure_matrices
from asekit.aero.supersonic import max_box_chord as _mach_box_chord
from asekit.aero.supersonic import supersonic_pressure_matrices, supersonic_pressures
from asekit.aero.validity import SUBSONIC, SUPERSONIC, MachRange, check_k, mach_number
from asekit.aero.validity import check_mach as _check_mach_range

__all__ = ["AERO_METHODS", "AeroMethod", "DLM_KERNELS", "DLM_MACH_MAX", "METHODS",
           "SUPERSONIC_MACH_MIN", "TransonicGapError", "TransonicWarning", "check_k",
           "check_mach", "check_method", "max_box_chord", "method_spec", "pressure_matrices", "pressures",
           "PressureMatrix", "resolve_method", "TSD_MACHS", "TSD_SECTIONS"]

#: auto: highest Mach number given to the DLM, lowest given to the supersonic method.
DLM_MACH_MAX = 0.9
SUPERSONIC_MACH_MIN = 1.15
DLM_KERNELS = ("quartic", "parabolic")


class TransonicGapError(ValueError):
    """The Mach number lies in the transonic gap where linear theory is not trusted."""


class TransonicWarning(UserWarning):
    """An explicitly chosen linear method is used close to M = 1."""


def _dlm_matrices(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic", **options):
    """A = D^-1 (n_k, n, n), the DLM's AIC formed explicitly (:mod:`asekit.aero.dlm`; it has
    no aero options: ``options`` are ignored)."""
    d = normalwash_matrices(mesh, mach, ks, b_ref, kernel, symmetric)
    return np.linalg.solve(d, np.broadcast_to(np.eye(mesh.n), d.shape))


def _supersonic_matrices(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic", **options):
    """The Mach-box matrices (:func:`asekit.aero.supersonic.supersonic_pressure_matrices`)."""
    return supersonic_pressure_matrices(mesh, mach, ks, b_ref, symmetric, **options)


def _piston_matrices(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic", **options):
    """Piston theory (:func:`asekit.aero.piston.piston_pressure_matrices`; a local law: the
    wall image has no effect, ``symmetric`` is ignored)."""
    return piston_pressure_matrices(mesh, mach, ks, b_ref, **options)


#: The TSD method's Mach range: 0 < M < 1.3 (:func:`asekit.aero.tsd.tsd_mach`), the whole
#: transonic gap included: supersonic free streams since issue 29's tsdfin step (type-dependent
#: differencing upwind everywhere, the time term too; the lift of a rectangular wing at M 1.2
#: within 6 % of the exact linear value on 8 chordwise cells, tests/aero/test_tsd_supersonic.py).
TSD_MACHS = MachRange(0.0, 1.3, False, False, "subsonic, transonic and low supersonic")
#: The aerofoil sections the TSD accepts (``aero.section.shape``).
TSD_SECTIONS = ("biconvex",)


def _tsd_matrices(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic",
                  section=None, grid_options=None, cross_flow=True, tsd_format=None,
                  **options):
    """The time-linearised TSD's matrices (:func:`asekit.aero.tsd3d.tsd_pressure_matrices`)
    about the steady flow over ``section`` = (shape, thickness_ratio) (biconvex:
    :func:`asekit.aero.tsd3d.biconvex_thickness`), on the grid of
    :func:`asekit.aero.tsd3d.mesh_grid_options` unless ``grid_options`` are given, the steady
    background cached (:func:`asekit.aero.tsd3d.tsd_background`; ``cross_flow`` the
    cross-flow terms of swept wings, on by default, issue 29 tsdswept; ``tsd_format`` the
    version :data:`asekit.aero.tsd3d.TSD_GAF_FORMAT` a case's database fingerprint carries). The TSD
    half wing is mirrored at its root: ``symmetric`` must be True (aero.symmetry = "wall")."""
    from asekit.aero.tsd3d import TSD_GAF_FORMAT, tsd_background, tsd_pressure_matrices

    if tsd_format not in (None, TSD_GAF_FORMAT):
        raise ValueError(f"tsd_format must be {TSD_GAF_FORMAT} (this asekit's TSD GAFs), got "
                         f"{tsd_format!r}")

    if options:
        raise ValueError(f"method='tsd' takes the options section, grid_options, "
                         f"cross_flow and tsd_format, got "
                         f"{sorted(options)}")
    if not symmetric:
        raise ValueError("method='tsd' models a half wing mirrored at its root: it needs "
                         "symmetric=True (aero.symmetry = \"wall\")")
    if section is None:
        raise ValueError("method='tsd' needs the option section = (shape, thickness_ratio), "
                         "e.g. ('biconvex', 0.04) (case key aero.section)")
    shape, tau = section
    if shape not in TSD_SECTIONS:
        raise ValueError(f"section shape must be one of {list(TSD_SECTIONS)}, got {shape!r}")
    background = tsd_background(mesh, mach, tau, grid_options, cross_flow=bool(cross_flow))
    if not background.converged:
        raise ValueError(f"the steady TSD background did not converge at M {mach:g} (residual "
                         f"{background.residual:.2g}; a strong shock on a coarse grid can stall "
                         f"the type-dependent switches); in a case: aero.section.thickness_ratio,"
                         f" aero.machs or aero.boxes, which set the TSD grid")
    return tsd_pressure_matrices(mesh, mach, ks, b_ref, background=background)


@dataclass(frozen=True)
class PressureMatrix:
    """A pressure-per-normalwash matrix A (n, n) as an operator: DeltaCp = A (w/U), the
    counterpart of :class:`asekit.aero.dlm.AicFactor` for the methods whose matrix is formed
    explicitly."""

    a: np.ndarray

    def pressures(self, w: np.ndarray) -> np.ndarray:
        """DeltaCp (n, m) = A w for normalwash columns ``w`` (n, m)."""
        return self.a @ w


def _dlm_operators(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic", **options):
    """One :class:`asekit.aero.dlm.AicFactor` (LU of D(M, k), in place, streamed) per k: the
    operations of :func:`asekit.aero.gaf.gaf_from_box_modes`, so pressures applied through
    them are bit-identical to a database built from scratch."""
    return tuple(map_normalwash_matrices(
        mesh, mach, check_k(ks), b_ref, lambda i, kk, d: factor_normalwash_matrix(d, overwrite=True),
        kernel, symmetric))


def _matrix_operators(builder):
    def operators(mesh, mach, ks, b_ref, symmetric=False, kernel="quartic", **options):
        a = builder(mesh, mach, ks, b_ref, symmetric, kernel, **options)
        return tuple(PressureMatrix(np.ascontiguousarray(x)) for x in a)
    operators.__doc__ = f"One :class:`PressureMatrix` per k of {builder.__name__}."
    return operators


@dataclass(frozen=True)
class AeroMethod:
    """One unsteady aerodynamic method of the registry.

    Attributes
    ----------
    name : str
        The ``aero.method`` value.
    summary : str
        One line.
    mach_range : MachRange or None
        Its valid Mach numbers (None for ``auto``, which picks a method per Mach).
    who : str
        How error messages name it.
    hint : str
        What a message suggests outside the range.
    structure_independent : bool
        Its pressure operator depends on the boxes, Mach and k only (not on the mode shapes or
        the thickness), so one operator per (M, k) serves every structure on the same boxes
        (:mod:`asekit.sweep` forms it once per sweep).
    pressure_matrices : callable or None
        Builder ``(mesh, mach, ks, b_ref, symmetric, kernel, **options) -> A`` of the
        (n_k, n, n) matrices with DeltaCp = A (w/U) (None for ``auto``).
    operators : callable or None
        Builder with the same arguments of one operator per k, each with a
        ``pressures(w) -> DeltaCp`` method (the DLM: LU factors of D; the others:
        :class:`PressureMatrix`).
    reuse_break_even : float
        Forming the operators costs about as much as computing the pressures of
        ``reuse_break_even * n_boxes`` normalwash columns one sample at a time; a sweep forms
        them once when its samples x modes reach that (0: always worth it). The Mach-box
        method: 0.1, measured on the AGARD 445.6 case (256 boxes, 4 modes, 10 k, one BLAS
        thread: the matrices 6.6 s at M 1.072 and 13.1 s at M 1.141, one sample's pressures
        1.15 s and 2.26 s, so break-even near 6 samples = 24 columns).
    box_chord : its mesh rule, ``(mach, k_max, b_ref, u_min, f_max) -> dx`` the longest box
        chord (m) it accepts (None for ``auto``: :func:`max_box_chord` resolves it per Mach).
        The DLM: 15 boxes per wavelength U_min / f_max (thesis Eq. 3.5); the Mach box: 6 per
        shortest kernel wavelength 2 pi b (M - 1) / (k_max M)
        (:func:`asekit.aero.supersonic.max_box_chord`); piston theory, a local law with no
        kernel wavelength: the DLM's rule, which resolves the convected wavelength U / f of the
        normalwash i k h / b (asekit's choice).
    transonic : bool
        It models the transonic flow (the TSD): allowed in the gap DLM_MACH_MAX < M <
        SUPERSONIC_MACH_MIN within its range without :class:`TransonicWarning`.
    """

    name: str
    summary: str
    mach_range: MachRange | None
    who: str
    hint: str
    structure_independent: bool
    pressure_matrices: Callable | None
    operators: Callable | None
    reuse_break_even: float = 0.0
    box_chord: Callable | None = None
    transonic: bool = False


def _dlm_box_chord(mach, k_max, b_ref, u_min, f_max):
    """The DLM's rule (thesis Eq. 3.5): 15 boxes per wavelength U_min / f_max."""
    return dlm_max_box_chord(u_min, f_max)


def _supersonic_box_chord(mach, k_max, b_ref, u_min, f_max):
    """The Mach-box rule: 6 boxes per kernel wavelength 2 pi b (M - 1) / (k_max M)."""
    return _mach_box_chord(mach, k_max, b_ref)


#: The aero-method registry: ``aero.method`` name -> :class:`AeroMethod`.
AERO_METHODS: dict[str, AeroMethod] = {
    "auto": AeroMethod("auto", f"the DLM for M <= {DLM_MACH_MAX:g}, the Mach-box method for "
                       f"M >= {SUPERSONIC_MACH_MIN:g}, refused in between", None, "auto", "",
                       True, None, None),
    "dlm": AeroMethod("dlm", "doublet lattice (Albano & Rodden), subsonic", SUBSONIC, "the DLM",
                      "; use method='supersonic' or 'piston' above M 1", True, _dlm_matrices,
                      _dlm_operators, 0.0, _dlm_box_chord),
    "supersonic": AeroMethod("supersonic", "Mach-box lifting-surface method, supersonic",
                             SUPERSONIC, "method='supersonic'", "; use method='dlm' below M 1",
                             True, _supersonic_matrices, _matrix_operators(_supersonic_matrices),
                             0.1, _supersonic_box_chord),
    "piston": AeroMethod("piston", "piston theory (Lighthill; Ashley & Zartarian), supersonic",
                         SUPERSONIC, "method='piston'", "; use method='dlm' below M 1", True,
                         _piston_matrices, _matrix_operators(_piston_matrices), 0.0,
                         _dlm_box_chord),
    "tsd": AeroMethod("tsd", "time-linearised transonic small disturbance (Batina 1989), "
                      "0 < M < 1.3 including the transonic gap", TSD_MACHS, "method='tsd'",
                      "; use method='supersonic' or 'piston' above M 1.3", False, _tsd_matrices,
                      _matrix_operators(_tsd_matrices), 0.0, _dlm_box_chord, True),
}
#: The method names (the registry's keys).
METHODS = tuple(AERO_METHODS)


def check_method(method: str, name: str = "method") -> str:
    """Validate a method name (a key of :data:`AERO_METHODS` or a DLM kernel name); ValueError
    listing the known ones otherwise."""
    if method not in METHODS + DLM_KERNELS:
        raise ValueError(f"{name} must be one of {list(METHODS + DLM_KERNELS)}, got {method!r}")
    return method


def method_spec(method: str, mach: float | None = None) -> AeroMethod:
    """The :class:`AeroMethod` of ``method`` (a DLM kernel name is the DLM); for ``auto`` with
    a ``mach``, the method it resolves to there (:func:`resolve_method`)."""
    check_method(method)
    if method == "auto" and mach is not None:
        return AERO_METHODS[resolve_method(method, mach)]
    return AERO_METHODS["dlm" if method in DLM_KERNELS else method]


def resolve_method(method: str, mach: float, name: str = "mach") -> str:
    """The method used at ``mach``: 'dlm', 'supersonic' or 'piston' (DLM kernel names map to
    'dlm'). ``auto`` raises :class:`TransonicGapError` for DLM_MACH_MAX < M <
    SUPERSONIC_MACH_MIN; an explicit method outside its Mach range raises ValueError (naming
    ``name``, the argument or key path, and the method), and one inside the gap warns
    (:class:`TransonicWarning`)."""
    check_method(method)
    m = mach_number(mach, name)
    if method == "auto":
        if m <= DLM_MACH_MAX:
            return "dlm"
        if m >= SUPERSONIC_MACH_MIN:
            return "supersonic"
        raise TransonicGapError(
            f"{name}={m:g} lies in the transonic gap {DLM_MACH_MAX:g} < M < "
            f"{SUPERSONIC_MACH_MIN:g} of method 'auto': "
            "linear potential theory is not trusted there (the linearised equation degenerates "
            "as M -> 1, shocks and their motion carry the unsteady loads, and both the subsonic "
            "and the supersonic kernels diverge); asekit does not extrapolate. Use Mach numbers "
            f"<= {DLM_MACH_MAX:g} or >= {SUPERSONIC_MACH_MIN:g}, or transonic loads from "
            "elsewhere")
    spec = AERO_METHODS["dlm" if method in DLM_KERNELS else method]
    _check_mach_range(mach, spec.mach_range, spec.who, name, spec.hint)
    if DLM_MACH_MAX < m < SUPERSONIC_MACH_MIN and not spec.transonic:
        warnings.warn(f"method={spec.name!r} at mach={m:g}, inside the transonic gap "
                      f"({DLM_MACH_MAX:g}, {SUPERSONIC_MACH_MIN:g}) where linear theory is not "
                      "trusted: shocks and their motion, not modelled, carry the unsteady loads "
                      "there, and linear theory usually overpredicts the flutter speed (the "
                      "transonic dip); treat the result as doubtful", TransonicWarning,
                      stacklevel=2)
    return spec.name


def max_box_chord(method: str, mach: float, k_max: float, b_ref: float, u_min: float,
                  f_max: float) -> float:
    """The longest box chord (m) the mesh rule of the method used at ``mach`` accepts
    (:attr:`AeroMethod.box_chord`; ``auto`` resolved per Mach, the transonic gap's explicit
    methods without their warning): k_max the largest reduced frequency, b_ref (m), u_min
    (m/s), f_max (Hz).

    Examples
    --------
    >>> round(max_box_chord("auto", 0.8, 12.57, 0.1, 100.0, 2000.0), 5)   # DLM: U / (15 f)
    0.00333
    >>> round(max_box_chord("auto", 1.5, 12.57, 0.1, 100.0, 2000.0), 5)   # Mach box
    0.00278
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        spec = AERO_METHODS[resolve_method(method, mach)]
    return float(spec.box_chord(mach, k_max, b_ref, u_min, f_max))


def check_mach(mach: float, method: str = "dlm", name: str = "mach") -> float:
    """``float(mach)`` if ``method`` can be used at ``mach`` (:func:`resolve_method`: the
    method's Mach range, the transonic gap of ``auto``), else ValueError naming ``name`` (an
    argument or a case-file key path), the method and its range.

    Examples
    --------
    >>> check_mach(0.6)
    0.6
    >>> check_mach(1.2, "dlm", "aero.machs[0]")
    Traceback (most recent call last):
    ...
    ValueError: aero.machs[0] must be < 1 for the DLM (subsonic: 0 <= M < 1), got 1.2; use \
method='supersonic' or 'piston' above M 1
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        resolve_method(method, mach, name)
    return float(mach)


def pressure_matrices(mesh: BoxMesh, mach: float, k, b_ref: float, method: str = "auto",
                      symmetric: bool = False, dlm_kernel: str = "quartic",
                      **options) -> np.ndarray:
    """Pressure-per-normalwash matrices A (n_k, n, n) complex, DeltaCp = A (w/U), of the method
    chosen by :func:`resolve_method` (its :data:`AERO_METHODS` builder; for the DLM, A = D^-1,
    its AIC, formed explicitly: to apply it to a few normalwash columns, :func:`pressures` is
    cheaper). ``options`` go to the supersonic (``cells_per_box``, ...) or piston (``order``,
    ``thickness_slope``, ...) function; ``symmetric`` is not available for piston theory (a
    local law: it has no images).
    """
    spec = AERO_METHODS[resolve_method(method, mach)]
    kernel = method if method in DLM_KERNELS else dlm_kernel
    return spec.pressure_matrices(mesh, mach, k, b_ref, symmetric, kernel, **options)


def pressures(mesh: BoxMesh, mach: float, k, b_ref: float, normalwash, method: str = "auto",
              symmetric: bool = False, dlm_kernel: str = "quartic", **options) -> np.ndarray:
    """DeltaCp (n_k, n, m) for the normalwash columns ``normalwash`` (callable k -> (n, m), or
    an (n_k, n, m) array): ``pressure_matrices(...)[ik] @ normalwash(k)`` without forming the
    supersonic matrices (:func:`asekit.aero.supersonic.supersonic_pressures`) or the DLM's
    inverse (:class:`asekit.aero.dlm.AicFactor`, one LU per k, streamed)."""
    name = resolve_method(method, mach)
    if name == "supersonic":
        return supersonic_pressures(mesh, mach, k, b_ref, normalwash, symmetric, **options)
    ks = check_k(k)

    def wash(ik, kk):
        return np.asarray(normalwash(float(kk)) if callable(normalwash) else normalwash[ik])

    if name == "dlm":               # factor and solve per k, streamed (no explicit inverse)
        kernel = method if method in DLM_KERNELS else dlm_kernel
        return np.stack(map_normalwash_matrices(
            mesh, mach, ks, b_ref,
            lambda ik, kk, d: factor_normalwash_matrix(d, overwrite=True).pressures(wash(ik, kk)),
            kernel, symmetric))
    a = pressure_matrices(mesh, mach, ks, b_ref, method, symmetric, dlm_kernel, **options)
    ws = [np.asarray(normalwash(float(kk)) if callable(normalwash) else normalwash[ik])
          for ik, kk in enumerate(ks)]
    return np.stack([a[ik] @ w for ik, w in enumerate(ws)])
