"""Steady vortex-lattice method (horseshoe vortices) with Prandtl-Glauert compressibility.

Each box of a :class:`~asekit.aero.boxes.BoxMesh` carries a horseshoe vortex: a bound segment on
the quarter-chord line from its inboard end P1 to its outboard end P3 and two trailing legs to
x = +infinity (Katz & Plotkin, *Low-Speed Aerodynamics*, 2nd ed., Sec. 10.4.5-10.4.7, Biot-Savart
law Eq. 10.115 for a straight segment). Compressibility enters by the Goethert / Prandtl-Glauert
transformation x -> x / beta, beta = sqrt(1 - M^2), of all points before the Biot-Savart law is
applied (Hedman 1965); the induced normal velocity is invariant under that transformation.

Sign and normalisation (shared with :mod:`asekit.aero.dlm`): the pressure jump Delta Cp of a box
is positive when it pushes the box along its normal (+z for a horizontal box). A box of chord c
and span 2e with uniform Delta Cp carries circulation Gamma = Delta Cp U c / 2 (Kutta-Joukowski,
rho U Gamma 2e = q Delta Cp c 2e). The matrix returned maps Delta Cp to the normalwash w/U at the
control points along the receiving box normal: w/U = D0 Delta Cp. Upward load induces a
downwash, so D0 has a negative diagonal.

This is the k = 0 part ("D0") of the doublet-lattice method (Albano & Rodden 1969, Eq. 21;
Rodden, Taylor & McIntosh 1998, Eq. 1).
"""

from __future__ import annotations

import math

import numpy as np

from asekit.aero.boxes import BoxMesh, check_matrix_memory
from asekit.aero.kernels import check_kernel
from asekit.aero.validity import SUBSONIC
from asekit.aero.validity import check_mach as _check_mach
from asekit.util.validate import positive

#: Upper bound (bytes) for the temporaries of one row chunk (VLM and DLM).
CHUNK_BYTES = 256 * 2**20
#: Receiver-sender pairs per row chunk of the vortex lattice (cache-sized).
VLM_PAIRS_PER_CHUNK = 32768


def check_mach(mach: float) -> float:
    """Validate a subsonic Mach number, 0 <= M < 1 (:data:`asekit.aero.validity.SUBSONIC`;
    raises ValueError)."""
    return _check_mach(mach, SUBSONIC, "the vortex and doublet lattices")


def _senders(mesh: BoxMesh, symmetric: bool):
    """Sending boxes: the mesh, plus its image in y = 0 when ``symmetric``."""
    return (mesh, mesh.mirrored()) if symmetric else (mesh,)


def _distinct_vertices(a: np.ndarray, b: np.ndarray):
    """The distinct corners of the horseshoes ``a -> b`` (spanwise neighbours share one: b of
    a box is a of the next) and the index of each box's a and b among them. Corners closer
    than 1e-13 of the mesh size are one (they differ by rounding only)."""
    ab = np.concatenate([a, b])
    scale = 1e-13 * max(float(np.abs(ab).max()), 1e-300)
    keys = np.round(ab / scale).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    return ab[first], inverse[:a.shape[0]], inverse[a.shape[0]:]


def _horseshoe_normalwash(p: np.ndarray, n_r: np.ndarray, v: np.ndarray, ia: np.ndarray,
                          ib: np.ndarray, scale: float) -> np.ndarray:
    """Normal velocity at points ``p`` (m, 3) along normals ``n_r`` (m, 3) induced by unit-strength
    horseshoe vortices ``inf -> a -> b -> inf`` with a = v[ia], b = v[ib] (legs along +x;
    v (q, 3) the distinct corners, ``scale`` the longest bound vortex). Returns (m, s).

    The trailing legs and the distances are evaluated once per corner and gathered per box.
    Points on a vortex line (the singular limit) receive zero from that segment, the usual
    VLM convention; control points never lie on their own box's vortices.
    """
    eps = (1e-10 * scale) ** 2
    rx = np.subtract.outer(p[:, 0], v[:, 0])
    ry = np.subtract.outer(p[:, 1], v[:, 1])
    rz = np.subtract.outer(p[:, 2], v[:, 2])
    ny, nz = n_r[:, 1:2], n_r[:, 2:3]
    d2 = ry * ry
    d2 += rz * rz
    nrm = rx * rx
    nrm += d2
    np.sqrt(nrm, out=nrm)
    nrm[nrm == 0.0] = 1.0            # only where r = 0, then every term below is masked
    # semi-infinite leg from a corner q to +inf: (x_hat x r)/|x_hat x r|^2 (1 + r_x/|r|),
    # x_hat x r = (0, -r_z, r_y); zero on the leg's line
    leg = rx / nrm
    leg += 1.0
    okl = d2 > eps
    leg /= np.where(okl, d2, 1.0)
    leg *= ry * nz - rz * ny
    leg[~okl] = 0.0
    take = lambda arr, idx: np.take(arr, idx, axis=1)  # noqa: E731
    r1x, r1y, r1z, n1 = (take(q, ia) for q in (rx, ry, rz, nrm))
    r2x, r2y, r2z, n2 = (take(q, ib) for q in (rx, ry, rz, nrm))
    r0 = v[ib] - v[ia]
    # bound segment a -> b, Katz & Plotkin Eq. (10.115): (r1 x r2)/|r1 x r2|^2 r0.(r1/|r1| - r2/|r2|)
    cx = r1y * r2z - r1z * r2y
    cy = r1z * r2x - r1x * r2z
    cz = r1x * r2y - r1y * r2x
    c2 = cx * cx + cy * cy + cz * cz
    ok = c2 > eps
    fac = ((r0[None, :, 0] * r1x + r0[None, :, 1] * r1y + r0[None, :, 2] * r1z) / n1
           - (r0[None, :, 0] * r2x + r0[None, :, 1] * r2y + r0[None, :, 2] * r2z) / n2)
    fac = np.where(ok, fac / np.where(ok, c2, 1.0), 0.0)
    w = fac * (cy * ny + cz * nz)
    w += take(leg, ib)               # leg b -> +inf (+Gamma)
    w -= take(leg, ia)               # leg +inf -> a (-Gamma)
    w *= 1.0 / (4.0 * np.pi)
    return w


def vlm_normalwash_matrix(mesh: BoxMesh, mach: float, symmetric: bool = False,
                          kernel: str | None = None) -> np.ndarray:
    """Steady normalwash matrix D0 (n, n): w/U at control points per unit Delta Cp of each box.

    Parameters
    ----------
    mesh : the boxes.
    mach : free-stream Mach number, 0 <= M < 1 (Prandtl-Glauert x -> x / beta).
    symmetric : add the image of every box in the plane y = 0 with the same loading (a wall
        or symmetry plane at the root, e.g. a fin mounted on a body); default isolated.
    kernel : "numpy" or "compiled" (numba loop, :mod:`asekit.aero._dlm_compiled`; same
        equations); None: :func:`asekit.aero.kernels.default_kernel`.

    Returns
    -------
    D0 (n, n) float: ``w_r / U = sum_s D0[r, s] DeltaCp_s`` (module docstring for the signs).
    """
    mach = check_mach(mach)
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    check_matrix_memory(mesh.n, 1, 8, "the VLM normalwash matrix", "use fewer boxes")
    compiled = check_kernel(kernel) == "compiled"
    beta = math.sqrt(1.0 - mach * mach)
    sx = np.array([1.0 / beta, 1.0, 1.0])
    p = mesh.control_point * sx
    n_r = mesh.normal
    d = np.zeros((mesh.n, mesh.n))
    rows = max(1, min(mesh.n, VLM_PAIRS_PER_CHUNK // mesh.n))
    for img in _senders(mesh, symmetric):
        a = img.doublet_p1 * sx
        b = img.doublet_p3 * sx
        scale = float(np.max(np.linalg.norm(b - a, axis=1)))
        v, ia, ib = _distinct_vertices(a, b)
        half_chord = 0.5 * img.chord
        if compiled:
            from asekit.aero import _dlm_compiled  # numba is optional: imported only here
            _dlm_compiled.horseshoe_normalwash(np.ascontiguousarray(p), np.ascontiguousarray(n_r),
                                               v, ia, ib, scale, half_chord, d)
            continue
        for i0 in range(0, mesh.n, rows):
            sl = slice(i0, min(mesh.n, i0 + rows))
            d[sl] += _horseshoe_normalwash(p[sl], n_r[sl], v, ia, ib, scale) * half_chord[None, :]
    return d


def steady_pressure(mesh: BoxMesh, mach: float, normalwash: np.ndarray,
                    symmetric: bool = False) -> np.ndarray:
    """Steady Delta Cp (n,) or (n, m) for the normalwash ``w/U`` (n,) or (n, m) at the control
    points (for a flat surface at angle of attack alpha: w/U = -alpha). Solves D0 Cp = w/U."""
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    w = np.asarray(normalwash, float)
    if w.ndim not in (1, 2) or w.shape[0] != mesh.n or not np.all(np.isfinite(w)):
        raise ValueError(f"normalwash must be finite with first dimension {mesh.n}, got {w.shape}")
    return np.linalg.solve(vlm_normalwash_matrix(mesh, mach, symmetric), w)


def lift_curve_slope(mesh: BoxMesh, mach: float, reference_area: float | None = None,
                     symmetric: bool = False) -> float:
    """Lift-curve slope CL_alpha (1/rad) of a flat mesh at Mach ``mach`` from the VLM.

    The lift is the sum of Delta Cp A n_z for a unit angle of attack (w/U = -n_z at every
    control point); the reference area defaults to the mesh area (doubled if ``symmetric``).
    """
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    nz = mesh.normal[:, 2]
    cp = steady_pressure(mesh, mach, -nz, symmetric)
    lift = float(np.sum(cp * mesh.area * nz))
    s = float(np.sum(mesh.area)) if reference_area is None else positive("reference_area",
                                                                          reference_area)
    if symmetric:
        lift *= 2.0
        if reference_area is None:
            s *= 2.0
    return lift / s
