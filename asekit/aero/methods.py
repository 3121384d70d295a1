"""Choice of the unsteady aerodynamic method per Mach number, and one entry point for the
pressure-per-normalwash matrices of every method.

``method``:

- ``"dlm"``: subsonic doublet lattice (:mod:`asekit.aero.dlm`, M < 1; ``"quartic"`` and
  ``"parabolic"`` name its two kernel approximations and are accepted too);
- ``"supersonic"``: the Mach-box lifting-surface method (:mod:`asekit.aero.supersonic`, M > 1);
- ``"piston"``: piston theory (:mod:`asekit.aero.piston`, M > 1, warns outside its bound);
- ``"auto"``: the DLM for M <= DLM_MACH_MAX (0.9), the supersonic method for
  M >= SUPERSONIC_MACH_MIN (1.15), and a :class:`TransonicGapError` in between.

Why the gap. Linear (small-disturbance) potential theory assumes that the perturbation
velocities are small against |U - a|; as M -> 1 the linearised equation loses its
beta^2 phi_xx term, shocks and their motion dominate the unsteady loads, and the subsonic
kernel (Prandtl-Glauert factor 1/sqrt(1 - M^2)) and the supersonic one (1/sqrt(M^2 - 1),
Mach cones that collapse onto the wing, kernel wavelength 2 pi b (M - 1)/(k M) -> 0) both
diverge. Transonic unsteady loads need a nonlinear (transonic small-disturbance, Euler or
Navier-Stokes) solution or test data; asekit does not extrapolate into the gap.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from asekit.aero.boxes import BoxMesh

#: auto: highest Mach number given to the DLM, lowest given to the supersonic method.
DLM_MACH_MAX = 0.9
SUPERSONIC_MACH_MIN = 1.15
METHODS = ("auto", "dlm", "supersonic", "piston")
DLM_KERNELS = ("quartic", "parabolic")


class TransonicGapError(ValueError):
    """The Mach number lies in the transonic gap where linear theory is not trusted."""


class TransonicWarning(UserWarning):
    """An explicitly chosen linear method is used close to M = 1."""


def check_method(method: str) -> str:
    """Validate a method name (:data:`METHODS` or a DLM kernel name)."""
    if method not in METHODS + DLM_KERNELS:
        raise ValueError(f"method must be one of {list(METHODS + DLM_KERNELS)}, got {method!r}")
    return method


def resolve_method(method: str, mach: float) -> str:
    """The method used at ``mach``: 'dlm', 'supersonic' or 'piston' (DLM kernel names map to
    'dlm'). ``auto`` raises :class:`TransonicGapError` for DLM_MACH_MAX < M <
    SUPERSONIC_MACH_MIN; an explicit method outside its Mach range raises ValueError, and one
    inside the gap warns (:class:`TransonicWarning`)."""
    check_method(method)
    m = float(mach)
    if not math.isfinite(m) or m < 0:
        raise ValueError(f"mach must be a finite Mach number >= 0, got {mach!r}")
    if method == "auto":
        if m <= DLM_MACH_MAX:
            return "dlm"
        if m >= SUPERSONIC_MACH_MIN:
            return "supersonic"
        raise TransonicGapError(
            f"mach={m:g} lies in the transonic gap {DLM_MACH_MAX:g} < M < {SUPERSONIC_MACH_MIN:g}: "
            "linear potential theory is not trusted there (the linearised equation degenerates "
            "as M -> 1, shocks and their motion carry the unsteady loads, and both the subsonic "
            "and the supersonic kernels diverge); asekit does not extrapolate. Use Mach numbers "
            f"<= {DLM_MACH_MAX:g} or >= {SUPERSONIC_MACH_MIN:g}, or transonic loads from "
            "elsewhere")
    name = "dlm" if method in DLM_KERNELS else method
    if name == "dlm" and m >= 1.0:
        raise ValueError(f"mach must be < 1 for the DLM (subsonic), got {mach!r}; use "
                         "method='supersonic' or 'piston' above M 1")
    if name in ("supersonic", "piston") and m <= 1.0:
        raise ValueError(f"mach must be > 1 for method={name!r} (supersonic), got {mach!r}; use "
                         "method='dlm' below M 1")
    if DLM_MACH_MAX < m < SUPERSONIC_MACH_MIN:
        warnings.warn(f"method={name!r} at mach={m:g}, inside the transonic gap "
                      f"({DLM_MACH_MAX:g}, {SUPERSONIC_MACH_MIN:g}) where linear theory is not "
                      "trusted: shocks and their motion, not modelled, carry the unsteady loads "
                      "there, and linear theory usually overpredicts the flutter speed (the "
                      "transonic dip); treat the result as doubtful", TransonicWarning,
                      stacklevel=2)
    return name


def pressure_matrices(mesh: BoxMesh, mach: float, k, b_ref: float, method: str = "auto",
                      symmetric: bool = False, dlm_kernel: str = "quartic",
                      **options) -> np.ndarray:
    """Pressure-per-normalwash matrices A (n_k, n, n) complex, DeltaCp = A (w/U), of the method
    chosen by :func:`resolve_method` (for the DLM, A = D^-1, its AIC, formed explicitly: to
    apply it to a few normalwash columns, :func:`pressures` is cheaper). ``options`` go to the
    supersonic (``cells_per_box``, ...) or piston (``order``, ``thickness_slope``, ...)
    function; ``symmetric`` is not available for piston theory (a local law: it has no images).
    """
    name = resolve_method(method, mach)
    if name == "dlm":
        from asekit.aero.dlm import normalwash_matrices
        kernel = method if method in DLM_KERNELS else dlm_kernel
        d = normalwash_matrices(mesh, mach, k, b_ref, kernel, symmetric)
        return np.linalg.solve(d, np.broadcast_to(np.eye(mesh.n), d.shape))
    if name == "supersonic":
        from asekit.aero.supersonic import supersonic_pressure_matrices
        return supersonic_pressure_matrices(mesh, mach, k, b_ref, symmetric, **options)
    from asekit.aero.piston import piston_pressure_matrices
    return piston_pressure_matrices(mesh, mach, k, b_ref, **options)


def pressures(mesh: BoxMesh, mach: float, k, b_ref: float, normalwash, method: str = "auto",
              symmetric: bool = False, dlm_kernel: str = "quartic", **options) -> np.ndarray:
    """DeltaCp (n_k, n, m) for the normalwash columns ``normalwash`` (callable k -> (n, m), or
    an (n_k, n, m) array): ``pressure_matrices(...)[ik] @ normalwash(k)`` without forming the
    supersonic matrices (:func:`asekit.aero.supersonic.supersonic_pressures`) or the DLM's
    inverse (:class:`asekit.aero.dlm.AicFactor`, one LU per k, streamed)."""
    name = resolve_method(method, mach)
    if name == "supersonic":
        from asekit.aero.supersonic import supersonic_pressures
        return supersonic_pressures(mesh, mach, k, b_ref, normalwash, symmetric, **options)
    ks = np.atleast_1d(np.asarray(k, float))

    def wash(ik, kk):
        return np.asarray(normalwash(float(kk)) if callable(normalwash) else normalwash[ik])

    if name == "dlm":               # factor and solve per k, streamed (no explicit inverse)
        from asekit.aero.dlm import factor_normalwash_matrix, map_normalwash_matrices
        kernel = method if method in DLM_KERNELS else dlm_kernel
        return np.stack(map_normalwash_matrices(
            mesh, mach, ks, b_ref,
            lambda ik, kk, d: factor_normalwash_matrix(d, overwrite=True).pressures(wash(ik, kk)),
            kernel, symmetric))
    a = pressure_matrices(mesh, mach, ks, b_ref, method, symmetric, dlm_kernel, **options)
    ws = [np.asarray(normalwash(float(kk)) if callable(normalwash) else normalwash[ik])
          for ik, kk in enumerate(ks)]
    return np.stack([a[ik] @ w for ik, w in enumerate(ws)])
