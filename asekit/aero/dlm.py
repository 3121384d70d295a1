"""Subsonic doublet-lattice method (DLM) for harmonically oscillating lifting surfaces.

References (equation numbers below refer to these):

- [AR69] E. Albano, W. P. Rodden, "A doublet-lattice method for calculating lift distributions
  on oscillating surfaces in subsonic flows", AIAA J. 7(2), 1969, 279-285.
- [R71] W. P. Rodden, J. P. Giesing, T. P. Kalman, "New developments and applications of the
  subsonic doublet-lattice method for nonplanar configurations", AGARD CP-80-71, 1971
  (refined kernel, parabolic approximation of the numerator, Laschka's approximation of the
  kernel integrals, Appendix A).
- [R98] W. P. Rodden, P. F. Taylor, S. C. McIntosh, "Further refinement of the subsonic
  doublet-lattice method", J. Aircraft 35(5), 1998, 720-727 (quartic approximation, Desmarais'
  12-term approximation of the integrals).

Formulation. Every box carries a line of acceleration-potential doublets of constant strength on
its quarter chord (from P1 to P3, half-width e, sweep Lambda, dihedral gamma) and a control point
at three-quarter chord, mid-span. The normalwash at control point r due to the pressure jump of
box s is ([R98] Eq. 1-3)

    w_r / U = sum_s D_rs DeltaCp_s,     D_rs = D0_rs + D1_rs + D2_rs,

where D0 is the steady (k = 0) part, computed by the horseshoe vortex lattice
(:mod:`asekit.aero.vlm`), and D1, D2 are the planar and nonplanar *incremental* oscillatory
parts, ([R71] Eqs. 22, 27, 36; [R98] Eqs. 4-5)

    D1_rs = dx_s / (8 pi) int_{-e}^{e} P1(eta) / r1^2 d eta,
    D2_rs = dx_s / (8 pi) int_{-e}^{e} P2(eta) / r1^4 d eta,
    P1 = -(K1 exp(-i omega x0 / U) - K10) T1,      P2 = -(K2 exp(-i omega x0 / U) - K20) T2*,

with x0 = xbar - eta tan(Lambda), r1^2 = (ybar - eta)^2 + zbar^2 in the sending box's local
axes, T1 = cos(gamma_r - gamma_s), T2* = zbar (zbar cos(gamma_s - gamma_r) + (ybar - eta)
sin(gamma_s - gamma_r)) ([R71] Eqs. 5, 21), K1, K2 Landahl's kernel functions ([R71] Eqs. 7-8,
with R, u1, k1 of Eqs. 9-12) and K10, K20 their steady values ([R71] Eqs. 15-16). The kernel
integrals I1, I2 are approximated by Laschka's 11-term ([R71] Eqs. A.1-A.9) or Desmarais'
12-term ([R98] Eq. 11 and the table following it) exponential series.

The numerators P1, P2 are replaced by the polynomial through their values at eta = -e, 0, e
(parabolic, [R71] Eqs. 28-30 and 37-39) or -e, -e/2, 0, e/2, e (quartic, [R98] Eqs. 15-19 and
28-32), and the remaining integrals of eta^m / r1^(2p) are done exactly. asekit writes that
step as a fixed, k-independent quadrature: D1_rs = sum_j P1(eta_j) W1_j with weights
W1_j = dx/(8 pi) sum_m V^-1[m, j] e^-m int eta^m / r1^2 d eta (V the Vandermonde matrix of the
normalised points); the closed forms of the integrals are those of [R71] Eqs. 31-34, 40-41 and
[R98] Eqs. 20-34 in expanded form. Pairs whose receiver is farther than 4e from the doublet
line use 6-point Gauss-Legendre quadrature for the same integrals (error about 1e-11 there,
and free of the cancellation of the closed forms far away). The weights and all kernel
geometry depend on the Mach number but not on k: they are computed once per row chunk and
reused for every reduced frequency of a sweep.

Conventions. x downstream, y span, z up; time dependence exp(i omega t); reduced frequency
k = omega b / U with the reference semi-chord ``b_ref`` given by the caller (for the reference
fin, 0.078 m: the root semi-chord). Delta Cp is positive when it pushes the box along its normal
(+z for a horizontal box); w/U is the normalwash along the receiving box normal that the
surface motion imposes, w/U = dh/dx + i k h / b for a normal displacement h(x, y). The
aerodynamic influence matrix returned by :func:`aic_matrix` is AIC = D^-1, so
DeltaCp = AIC (w/U). A flat plate at incidence alpha has w/U = -alpha and a positive Delta Cp.
To apply the AIC without forming it, :func:`factor_aic` returns its LU factors
(:class:`AicFactor`, ``.pressures(w)``); :func:`iter_normalwash_matrices` and
:func:`map_normalwash_matrices` stream a k sweep in bounded memory.

Planar pairs (|zbar| <= 0.001 e, the threshold of [R71] and NASTRAN) use zbar = 0 in the
integrals and have no nonplanar part; the limit r1 -> 0 of the kernel is taken explicitly
([R71]: K1 -> -2, K2 -> 4 downstream, 0 upstream).

All-planar meshes (every pair planar: one flat surface such as the fin, with or without its
image) take a cheaper path with the same equations: D2 is skipped; the planar kernel depends
on the receiver and the station point only, so it is evaluated once per distinct station
(spanwise neighbours share their end stations) and gathered per sender; the weights, which
depend on ybar, zbar and e only, come from a table over (receiver strip, sender strip); and
Re I1(0) of Eq. A.5, a function of r1 only, from a table over the (y, z) groups. Meshes with
surfaces in several planes are cut into blocks of (receivers in one plane, senders in one
plane): coplanar blocks take this path, the others the pairwise one. The result equals the
pairwise path to rounding (tests/aero/test_dlm.py).

Implementations. The all-planar path has two implementations of the same equations: numpy
array expressions (always available) and a compiled numba loop (:mod:`asekit.aero._dlm_compiled`,
used by default when numba is installed; ``kernel=`` or ``$ASEKIT_DLM_KERNEL`` choose). They
agree to about 1e-14 relative to max |D| (tests/aero/test_dlm_compiled.py). The pairwise path is
numpy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from asekit.aero.boxes import BoxMesh, check_matrix_memory
from asekit.aero.kernels import check_kernel
from asekit.aero.validity import check_k
from asekit.aero.vlm import CHUNK_BYTES, check_mach, vlm_normalwash_matrix
from asekit.util.validate import real

#: Laschka's approximation of u / sqrt(1 + u^2) ~ 1 - sum a_n exp(-n c u) ([R71] Eq. A.4;
#: coefficients as tabulated by Blair 1992, WL-TR-92-3028, p. 89).
LASCHKA_C = 0.372
LASCHKA_A = np.array([+0.24186198, -2.7918027, +24.991079, -111.59196, +271.43549, -305.75288,
                      -41.183630, +545.98537, -644.78155, +328.72755, -64.279511])
#: Desmarais' 12-term approximation, exponents 2^n b ([R98] Eq. 11 and its coefficient table).
DESMARAIS_B = 0.009054814793
DESMARAIS_A = np.array([0.000319759140, -0.000055461471, 0.002726074362, 0.005749551566,
                        0.031455895072, 0.106031126212, 0.406838011567, 0.798112357155,
                        -0.417749229098, 0.077480713894, -0.012677284771, 0.001787032960])

_METHODS = {
    # name: (normalised kernel stations, exponents p_n, coefficients a_n)
    "parabolic": (np.array([-1.0, 0.0, 1.0]), LASCHKA_C * np.arange(1, 12), LASCHKA_A),
    "quartic": (np.array([-1.0, -0.5, 0.0, 0.5, 1.0]), DESMARAIS_B * 2.0 ** np.arange(1, 13),
                DESMARAIS_A),
}
_PLANAR_TOL = 1e-3          # |zbar| / e below which a pair is planar ([R71], NASTRAN)
_FAR = 4.0                  # receiver farther than _FAR * e from the doublet line: quadrature
_GAUSS = np.polynomial.legendre.leggauss(6)
#: Receiver-sender pairs per row chunk: small enough for the arrays to stay in the CPU cache.
PAIRS_PER_CHUNK = 32768
#: (Receiver, station point) pairs per row chunk of the planar path (:class:`_PlanarChunk`).
PLANAR_POINTS_PER_CHUNK = 32768
#: The same for the compiled kernel: larger chunks amortise its per-chunk tables (a 15-k
#: sweep at 1200 boxes: 2.39 s CPU at 32768, 1.9-2.1 s at 131072-524288).
COMPILED_POINTS_PER_CHUNK = 262144
#: ... but at least this many rows (its per-chunk tables are per point: at 5000 boxes, 2 k,
#: 20.1 s CPU with 13 rows per chunk, 14.8 s with 48; numpy path 24.1 s)
COMPILED_MIN_ROWS = 48
#: Largest table of planar weights per (receiver group, sender group) (:class:`_PlanarWeights`).
PLANAR_WEIGHT_TABLE_BYTES = 64 * 2**20


def _check_bref(b_ref: float) -> float:
    b = real("b_ref", b_ref)
    if not math.isfinite(b) or b <= 0:
        raise ValueError(f"b_ref must be a finite reference semi-chord > 0 m, got {b_ref!r}")
    return b


def _check_method(method: str):
    if method not in _METHODS:
        raise ValueError(f"method must be one of {sorted(_METHODS)}, got {method!r}")
    return _METHODS[method]




# ---------------------------------------------------------------------------------------------
# k-independent geometry of a row chunk
# ---------------------------------------------------------------------------------------------
class _Senders:
    """Sending-box arrays (isolated mesh, or mesh plus its image in y = 0)."""

    def __init__(self, mesh: BoxMesh, symmetric: bool):
        parts = (mesh, mesh.mirrored()) if symmetric else (mesh,)
        cat = lambda f: np.concatenate([f(p) for p in parts])  # noqa: E731
        self.mid = cat(lambda p: p.load_point)
        self.e = cat(lambda p: p.half_width)
        self.tan_sweep = cat(lambda p: p.tan_sweep)
        self.gamma = cat(lambda p: p.dihedral)
        self.chord = cat(lambda p: p.chord)
        self.n_images = len(parts)

    def subset(self, idx: np.ndarray) -> "_Senders":
        """The senders ``idx`` (indices into the concatenated list) as a _Senders."""
        new = object.__new__(_Senders)
        for name in ("mid", "e", "tan_sweep", "gamma", "chord"):
            setattr(new, name, getattr(self, name)[idx])
        new.n_images = 1
        return new


class _Receivers:
    """The receiving boxes ``idx`` of a mesh (what the kernel needs of them)."""

    def __init__(self, mesh: BoxMesh, idx: np.ndarray):
        self.control_point = mesh.control_point[idx]
        self.dihedral = mesh.dihedral[idx]
        self.n = idx.size


def _line_integrals(ybar, zbar, e, planar, power, m_max):
    """Closed forms of int_{-e}^{e} eta^m / ((ybar-eta)^2 + zbar^2)^power d eta, m = 0..m_max.

    Written with t = eta - ybar: int t^j / (t^2 + z^2) (J_j) and / (t^2 + z^2)^2 (L_j) by the
    recurrences J_j = [t^(j-1)]/(j-1) - z^2 J_(j-2), L_j = J_(j-2) - z^2 L_(j-2) and the
    binomial expansion of eta^m. Planar pairs (z = 0) take the finite-part values of [R71]
    (F = 2e / (ybar^2 - e^2), Eq. 31a). Returns a list of arrays (one per m).
    """
    ta = -e - ybar
    tb = e - ybar
    z = np.where(planar, 0.0, zbar)
    z2 = z * z
    da = ta * ta + z2
    db = tb * tb + z2
    with np.errstate(divide="ignore", invalid="ignore"):
        # F: [R71] Eq. 31 (arctan form) and its planar limit
        az = np.abs(z)
        f_np = np.arctan2(2.0 * e * az, ybar * ybar + z2 - e * e) / np.where(planar, 1.0, az)
        f_pl = 2.0 * e / (ybar * ybar - e * e)
        j = [np.where(planar, f_pl, f_np), 0.5 * np.log(db / da)]
        pa, pb = ta, tb                                         # t^(n-1) at both ends
        for n in range(2, m_max + 1):
            if n > 2:
                pa, pb = pa * ta, pb * tb
            j.append((pb - pa) / (n - 1) - z2 * j[n - 2])
        if power == 1:
            base = j
        else:
            inv2z2 = 0.5 / np.where(planar, 1.0, z2)
            lst = [inv2z2 * (tb / db - ta / da + j[0]), -0.5 / db + 0.5 / da]
            for n in range(2, m_max + 1):
                lst.append(j[n - 2] - z2 * lst[n - 2])
            base = lst
    ypow = _powers(ybar, m_max)
    out = []
    for m in range(m_max + 1):
        acc = np.zeros_like(ybar)
        for jj in range(m + 1):
            acc = acc + math.comb(m, jj) * ypow[m - jj] * base[jj]
        out.append(acc)
    return out


def _powers(x, m_max):
    """[1, x, x^2, ..., x^m_max] by repeated multiplication."""
    out = [np.ones_like(x), x]
    for _ in range(2, m_max + 1):
        out.append(out[-1] * x)
    return out[:m_max + 1]


def _far_weights(ybar, zbar, e, chord, stations, power):
    """Weights W_j for distant pairs by 6-point Gauss-Legendre quadrature of the interpolating
    polynomial over r1^(2 power): W_j = dx/(8 pi) sum_g w_g e l_j(xi_g) / r1(xi_g e)^(2 power),
    l_j the Lagrange basis of the stations (the integrand's poles lie at least 4e from the
    doublet line, a Bernstein ellipse rho >= 8: relative error about rho^-12 ~ 1e-11)."""
    xg, wg = _GAUSS
    ns = stations.size
    # Lagrange basis of the stations at the Gauss points, lag[g, j]
    vinv = np.linalg.inv(np.vander(stations, ns, increasing=True))
    lag = np.vander(xg, ns, increasing=True) @ vinv
    # e / r1^(2 power) at the Gauss points (n_gauss, ...), then W_j = sum_g wg lag[g, j] (...)_g
    r2 = ybar[None] - xg.reshape((-1,) + (1,) * ybar.ndim) * e[None]   # e may broadcast
    r2 *= r2
    r2 += zbar * zbar
    if power == 2:
        r2 *= r2
    np.divide(e, r2, out=r2)
    coef = (wg[:, None] * lag).T / (8.0 * np.pi)                 # (ns, n_gauss)
    w = (coef @ r2.reshape(xg.size, -1)).reshape((ns,) + ybar.shape)
    w *= chord
    return list(w)


def _weights(ybar, zbar, e, chord, stations, planar, power):
    """Quadrature weights W_j (n_stations arrays) of [module docstring]: the exact integral of the
    interpolating polynomial of the numerator through the stations, times dx / (8 pi).
    ``e`` and ``chord`` may be per-sender rows (1, n_senders) that broadcast against ybar."""
    ns = stations.size
    dist2 = np.maximum(np.abs(ybar) - e, 0.0) ** 2 + zbar * zbar
    near = np.nonzero(dist2 <= (_FAR * e) ** 2)
    w = _far_weights(ybar, zbar, e, chord, stations, power)
    if near[0].size:
        vinv = np.linalg.inv(np.vander(stations, ns, increasing=True))   # a_m = vinv[m, j] P_j
        yb, zb = ybar[near], zbar[near]
        en = np.broadcast_to(e, ybar.shape)[near]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            closed = _line_integrals(yb, zb, en, planar[near], power, ns - 1)
            fac = np.broadcast_to(chord, ybar.shape)[near] / (8.0 * np.pi)
            epow = _powers(en, ns - 1)
            for jst in range(ns):
                acc = np.zeros_like(yb)
                for m in range(ns):
                    acc = acc + vinv[m, jst] * closed[m] / epow[m]
                w[jst][near] = fac * acc
    return w


class _ChunkGeometry:
    """Everything k-independent for receivers ``rows`` against all senders at one Mach."""

    def __init__(self, mesh: BoxMesh, snd: _Senders, rows: slice, mach: float, method: str):
        stations, _, _ = _METHODS[method]
        beta2 = 1.0 - mach * mach
        pr = mesh.control_point[rows]
        gr = mesh.dihedral[rows]
        d = pr[:, None, :] - snd.mid[None, :, :]
        cg, sg = np.cos(snd.gamma)[None, :], np.sin(snd.gamma)[None, :]
        xbar = d[..., 0]
        ybar = d[..., 1] * cg + d[..., 2] * sg               # [R71] Eq. 4 (local axes)
        zbar = d[..., 2] * cg - d[..., 1] * sg
        e = np.broadcast_to(snd.e[None, :], xbar.shape)
        chord = np.broadcast_to(snd.chord[None, :], xbar.shape)
        gsr = snd.gamma[None, :] - gr[:, None]
        planar = np.abs(zbar) <= _PLANAR_TOL * e
        self.nonplanar = bool(np.any(~planar))
        self.t1 = np.cos(gsr)                                 # [R71] Eq. 5
        self.w1 = _weights(ybar, zbar, e, chord, stations, planar, 1)
        self.w2 = _weights(ybar, zbar, e, chord, stations, planar, 2) if self.nonplanar else None
        if self.nonplanar:
            self.w2 = [np.where(planar, 0.0, w) for w in self.w2]
        self.points = []
        self.k10_sum = np.zeros(xbar.shape)      # sum_j K10_j T1 W1_j: the k-independent part
        tl = snd.tan_sweep[None, :]
        z2 = zbar * zbar
        coplanar = not np.any(gsr)                            # T1 = 1 everywhere
        for s, w1 in zip(stations, self.w1):
            eta_row = (s * snd.e)[None, :]                    # eta of this station, per sender
            x0 = xbar - eta_row * tl
            r1 = ybar - eta_row
            r1 *= r1
            r1 += z2
            big_r = x0 * x0
            big_r += beta2 * r1
            np.sqrt(big_r, out=big_r)                         # [R71] Eq. 10
            np.sqrt(r1, out=r1)                               # [R71] Eq. 4
            eta = np.broadcast_to(eta_row, xbar.shape)
            small = r1 <= 1e-12 * e
            any_small = bool(small.any())
            if any_small:                                     # receiver on the doublet line
                r1 = np.where(small, 1.0, r1)
                big_r = np.where(big_r > 0, big_r, 1.0)
            t = mach * big_r - x0
            u1 = t / (beta2 * r1)                             # [R71] Eq. 11
            if any_small:
                u1[small] = 0.0
            sq = np.sqrt(1.0 + u1 * u1)
            neg = u1 < 0.0
            p = {"small": np.nonzero(small), "down": np.where(x0[small] >= 0.0, 1.0, 0.0)}
            p["neg_idx"] = np.nonzero(neg)
            p["x0_neg"] = x0[p["neg_idx"]]
            p["x0_small"] = x0[p["small"]]
            c1 = mach * r1 / (big_r * sq)                     # second term of [R71] Eq. 7
            k10 = -1.0 - x0 / big_r                           # [R71] Eq. 15
            if any_small:
                r1[small] = 0.0
            t1w = w1 if coplanar else self.t1 * w1            # T1 W1_j
            self.k10_sum += k10 * t1w
            absu = np.abs(u1)
            p.update(r1=r1, absu=absu, c1=c1, t1w=t1w,
                     g=1.0 - absu / sq, sgn=np.where(neg, -1.0, 1.0),
                     phase=t / beta2 + x0)                    # k1 u1 + kd x0 = kd * phase
            if self.nonplanar:
                p.update(x0=x0, u1=u1, neg=neg, k10=k10)
                t2 = zbar * (zbar * np.cos(gsr) + (ybar - eta) * np.sin(gsr))   # [R71] Eq. 21
                p["t2"] = np.where(planar, 0.0, t2)
                rr = r1 / big_r
                p["k20"] = 2.0 + x0 * (2.0 + beta2 * rr * rr) / big_r          # [R71] Eq. 16
                p["c2a"] = mach * mach * rr * rr / sq                          # [R71] Eq. 8 terms
                p["c2b"] = (mach * rr * ((1.0 + u1 * u1) * beta2 * rr * rr + 2.0 + mach * rr * u1)
                            / (sq ** 3))
            self.points.append(p)


# ---------------------------------------------------------------------------------------------
# k-dependent kernel
# ---------------------------------------------------------------------------------------------
def _i0_j0(u, k1, p_n, a_n, need_j):
    """Series approximations of I0 and J0 ([R71] Eqs. A.4, A.8) for u >= 0: returns
    (I0 real, I0 imag, J0 real, J0 imag) (J0 parts None if not needed). Powers of one
    exponential give all terms (exp(-n c u) = exp(-c u)^n; exp(-2^n b u) by squaring).

    I0 = sum a_n exp(-p_n u) (p_n - i k1) / (p_n^2 + k1^2),
    J0 = sum a_n exp(-p_n u) / (p_n^2 + k1^2)^2 [p_n^2 - k1^2 + p_n u (p_n^2 + k1^2)
         - i k1 (2 p_n + u (p_n^2 + k1^2))].
    """
    k1sq = k1 * k1
    s_p = np.zeros_like(u)      # sum a e p / den
    s_1 = np.zeros_like(u)      # sum a e / den
    s_3 = np.zeros_like(u) if need_j else None   # sum a e (p^2 - k1^2) / den^2
    s_5 = np.zeros_like(u) if need_j else None   # sum a e p / den^2
    desmarais = p_n.size == 12
    en = np.exp(-p_n[0] * u)
    base = None if desmarais else en.copy()
    t = np.empty_like(u)
    den = np.empty_like(u)
    for i, (p, a) in enumerate(zip(p_n, a_n)):
        if i > 0:
            if desmarais:
                np.multiply(en, en, out=en)
            else:
                np.multiply(en, base, out=en)
        np.add(k1sq, p * p, out=den)
        np.divide(en, den, out=t)
        t *= a
        s_1 += t
        if need_j:
            np.divide(t, den, out=den)       # a e / den^2 (den no longer needed)
            s_5 += p * den
            s_3 += den * (p * p - k1sq)
        t *= p
        s_p += t
    i0r, i0i = s_p, -k1 * s_1
    if not need_j:
        return i0r, i0i, None, None
    j0r = s_3 + u * s_p
    j0i = -k1 * (2.0 * s_5 + u * s_1)
    return i0r, i0i, j0r, j0i


def _re_at_zero(k1, p_n, a_n, need_i2):
    """Re I1(0) and Re I2(0) ([R71] Eqs. A.5, A.9 need them for u1 < 0):
    Re I1(0) = 1 - k1^2 S, Re I2(0) = (2 - k1^2 S + k1^2 Re J0(0)) / 3 with
    S = sum a/(p^2+k1^2), Re J0(0) = sum a (p^2 - k1^2)/(p^2+k1^2)^2."""
    k1sq = k1 * k1
    s = np.zeros_like(k1)
    sj = np.zeros_like(k1) if need_i2 else None
    den = np.empty_like(k1)
    for p, a in zip(p_n, a_n):
        np.add(k1sq, p * p, out=den)
        np.divide(a, den, out=den)
        s += den
        if need_i2:
            sj += den * (p * p - k1sq) / (p * p + k1sq)
    re1 = 1.0 - k1sq * s
    re2 = (2.0 - k1sq * s + k1sq * sj) / 3.0 if need_i2 else None
    return re1, re2


def _integrals(u1, k1, p_n, a_n, need_i2, eku_abs):
    """I1 (and I2) of [R71] Eqs. A.1, A.6 at u1 of either sign (Eqs. A.5, A.9 for u1 < 0).
    ``eku_abs`` = exp(-i k1 |u1|)."""
    neg = u1 < 0.0
    u = np.abs(u1)
    any_neg = bool(neg.any())
    sq = np.sqrt(1.0 + u * u)
    g = 1.0 - u / sq
    i0r, i0i, j0r, j0i = _i0_j0(u, k1, p_n, a_n, need_i2)
    # I1(u) = (1 - u/sqrt(1+u^2) - i k1 I0) exp(-i k1 u)
    i1 = (g + k1 * i0i) + 1j * (-k1 * i0r)
    i1 *= eku_abs
    i2 = None
    if need_i2:
        # I2(u) = ((2 + i k1 u) g - u/(1+u^2)^1.5 - i k1 I0 + k1^2 J0) exp(-i k1 u) / 3
        i2 = ((2.0 * g - u / sq ** 3 + k1 * i0i + k1 * k1 * j0r)
              + 1j * (k1 * u * g - k1 * i0r + k1 * k1 * j0i)) * eku_abs / 3.0
    if any_neg:                                   # Re I(u1) = 2 Re I(0) - Re I(|u1|)
        idx = np.nonzero(neg)
        re1, re2 = _re_at_zero(k1[idx], p_n, a_n, need_i2)
        i1.real[idx] = 2.0 * re1 - i1.real[idx]
        if need_i2:
            i2.real[idx] = 2.0 * re2 - i2.real[idx]
    return i1, i2


def _i0_sums(u, k1sq, p_n, a_n):
    """s_p = sum a_n p_n e^(-p_n u) / (p_n^2 + k1^2) and s_1 = sum a_n e^(-p_n u) / (p_n^2 + k1^2):
    I0 = s_p - i k1 s_1 ([R71] Eq. A.4), with powers of one exponential for the terms."""
    s_p = np.zeros_like(u)
    s_1 = np.zeros_like(u)
    desmarais = p_n.size == 12
    en = np.exp(-p_n[0] * u)
    base = None if desmarais else en.copy()
    t = np.empty_like(u)
    for i, (pp, a) in enumerate(zip(p_n, a_n)):
        if i > 0:
            np.multiply(en, en if desmarais else base, out=en)
        np.add(k1sq, pp * pp, out=t)
        np.divide(en, t, out=t)
        t *= a
        s_1 += t
        t *= pp
        s_p += t
    return s_p, s_1


def _increment_planar(geo: _ChunkGeometry, kd: float, p_n, a_n) -> np.ndarray:
    """D1 of a chunk without nonplanar pairs at omega / U = kd (1/m).

    With A = 1 - u/sqrt(1+u^2) - i k1 I0 evaluated at |u1|, [R71] Eqs. A.1 and A.5 give
    I1 = A e^(-i k1 u1) for u1 >= 0 and I1 = 2 Re I1(0) - conj(A) e^(-i k1 u1) for u1 < 0, so
    -K1 e^(-i kd x0) = (sgn Re A + i Im A + M r1/(R sqrt(1+u1^2))) e^(-i kd (r1 u1 + x0))
    + [u1 < 0] 2 Re I1(0) e^(-i kd x0): one complex exponential per pair and station.
    """
    out = geo.k10_sum.astype(complex)                       # sum_j K10_j T1 W1_j
    for p in geo.points:
        k1 = kd * p["r1"]                                   # [R71] Eq. 12
        k1sq = k1 * k1
        s_p, s_1 = _i0_sums(p["absu"], k1sq, p_n, a_n)
        re = k1sq * s_1
        np.subtract(p["g"], re, out=re)                     # Re A = g - k1^2 s_1
        re *= p["sgn"]
        re += p["c1"]
        im = np.multiply(k1, s_p, out=s_p)
        np.negative(im, out=im)                             # Im A = -k1 s_p
        ph = kd * p["phase"]
        c, sn = np.cos(ph), np.sin(ph, out=ph)
        v = np.empty(k1.shape, complex)                     # (re + i im)(cos - i sin)
        v.real = re * c + im * sn
        v.imag = im * c - re * sn
        ni = p["neg_idx"]
        if ni[0].size:
            kn = k1sq[ni]
            acc = np.zeros_like(kn)
            for pp, a in zip(p_n, a_n):
                acc += a / (kn + pp * pp)
            v[ni] += 2.0 * (1.0 - kn * acc) * np.exp(-1j * (kd * p["x0_neg"]))  # 2 Re I1(0)
        si = p["small"]
        if si[0].size:                                      # r1 -> 0: -K1 = 2 downstream
            v[si] = 2.0 * p["down"] * np.exp(-1j * (kd * p["x0_small"]))
        v *= p["t1w"]                                       # P1 = -(K1 e - K10) T1, Eq. 27b
        out += v
    return out


def _increment(geo: _ChunkGeometry, mach: float, kd: float, method: str) -> np.ndarray:
    """D1 + D2 of the chunk at omega / U = kd (1/m)."""
    _, p_n, a_n = _METHODS[method]
    if not geo.nonplanar:
        return _increment_planar(geo, kd, p_n, a_n)
    out = np.zeros(geo.t1.shape, complex)
    for p, w1, w2 in zip(geo.points, geo.w1, geo.w2 or [None] * len(geo.points)):
        k1 = kd * p["r1"]                                   # [R71] Eq. 12
        eku_abs = _cis_minus(k1 * np.abs(p["u1"]))
        i1, i2 = _integrals(p["u1"], k1, p_n, a_n, geo.nonplanar, eku_abs)
        eku = np.where(p["neg"], eku_abs.conj(), eku_abs)
        # K1 = -I1 - exp(-i k1 u1) M r1 / (R sqrt(1 + u1^2))      [R71] Eq. 7
        k1v = eku * p["c1"]
        k1v += i1
        k1v[p["small"]] = 2.0 * p["down"]                  # r1 -> 0 limit; k1v holds -K1
        px = _cis_minus(kd * p["x0"])
        # P1 = -(K1 exp(-i kd x0) - K10) T1                      [R71] Eq. 27b
        k1v *= px
        k1v += p["k10"]
        k1v *= p["t1w"]
        out += k1v
        k2v = (3.0 * i2 + 1j * k1 * eku * p["c2a"] + eku * p["c2b"])   # [R71] Eq. 8
        k2v[p["small"]] = 4.0 * p["down"]
        out += (-(k2v * px - p["k20"]) * p["t2"]) * w2      # [R71] Eq. 36b
    return out


def _fold(d: np.ndarray, n: int, n_images: int) -> np.ndarray:
    return d if n_images == 1 else d[..., :n] + d[..., n:]


# ---------------------------------------------------------------------------------------------
# planar meshes: the kernel on the distinct kernel stations only
# ---------------------------------------------------------------------------------------------
def _all_planar(mesh: BoxMesh, snd: _Senders) -> bool:
    """True if every (receiver, sender) pair is planar (|zbar| <= 0.001 e, [R71]): then the
    nonplanar part D2 vanishes identically and :class:`_PlanarChunk` applies."""
    cg, sg = np.cos(snd.gamma), np.sin(snd.gamma)
    zs = snd.mid[:, 2] * cg - snd.mid[:, 1] * sg                # zbar = z_r' - z_s', Eq. 4
    tol = _PLANAR_TOL * snd.e
    rows = max(1, PAIRS_PER_CHUNK * 8 // snd.mid.shape[0])
    for i0 in range(0, mesh.n, rows):
        p = mesh.control_point[i0:i0 + rows]
        zbar = np.multiply.outer(p[:, 2], cg)
        zbar -= np.multiply.outer(p[:, 1], sg)
        zbar -= zs
        if np.any(np.abs(zbar, out=zbar) > tol):
            return False
    return True


def _classes(a: np.ndarray):
    """Distinct rows of ``a`` (exact equality) and the class index of every row."""
    uniq, inverse = np.unique(a, axis=0, return_inverse=True)
    return uniq, inverse.reshape(-1)


class _StationPoints:
    """The distinct kernel stations of all senders.

    Station j of sender s sits at mid_s + s_j e_s (tan Lambda_s, cos gamma_s, sin gamma_s). In
    the planar case the kernel K1 of [R71] Eqs. 7-12 depends on the receiver and the station
    point only (x0 is their streamwise distance and r1 their distance in the y-z plane), and
    the end stations of spanwise neighbours coincide (P3 of one box is P1 of the next): the
    kernel is evaluated once per distinct point (about 4 instead of 5 per box for the quartic
    kernel, 2 instead of 3 for the parabolic one) and gathered per sender with ``index``.
    Points closer than 1e-13 of the mesh size are taken as one (their coordinates differ by
    rounding only). Points and receivers are also grouped by their exact (y, z) (``yz``,
    ``yz_class``; the receivers' in ``r_yz``, ``r_class``): r1, and hence Re I1(0), is a
    function of the pair of groups only.
    """

    def __init__(self, mesh: BoxMesh, snd: _Senders, stations: np.ndarray):
        direction = np.stack([snd.tan_sweep, np.cos(snd.gamma), np.sin(snd.gamma)], axis=1)
        pts = (snd.mid[:, None, :]
               + (stations[None, :, None] * snd.e[:, None, None]) * direction[:, None, :])
        flat = pts.reshape(-1, 3)
        scale = 1e-13 * max(float(np.abs(flat).max()), float(snd.e.max()))
        keys = np.round(flat / scale).astype(np.int64)
        _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        self.xyz = flat[first]                                  # (nq, 3)
        self.e = np.repeat(snd.e, stations.size)[first]         # half-width of the first owner
        self.index = inverse.reshape(pts.shape[:2])             # (n_senders, n_stations)
        self.yz, self.yz_class = _classes(self.xyz[:, 1:])
        self.r_yz, self.r_class = _classes(mesh.control_point[:, 1:])


def _planar_weights(mesh: BoxMesh, snd: _Senders, rows: slice, stations) -> list:
    """T1 W1_j (one (rows, n_senders) array per station) of all-planar pairs: the weights of
    :func:`_weights` times T1 = cos(gamma_s - gamma_r) ([R71] Eq. 5)."""
    pr = mesh.control_point[rows]
    cg, sg = np.cos(snd.gamma), np.sin(snd.gamma)
    dy = np.subtract.outer(pr[:, 1], snd.mid[:, 1])
    dz = np.subtract.outer(pr[:, 2], snd.mid[:, 2])
    ybar = dy * cg                                              # [R71] Eq. 4 (local axes)
    ybar += dz * sg
    zbar = dz * cg
    zbar -= dy * sg
    w1 = _weights(ybar, zbar, snd.e[None, :], snd.chord[None, :], stations,
                  np.ones(ybar.shape, bool), 1)
    gsr = snd.gamma[None, :] - mesh.dihedral[rows][:, None]
    if np.any(gsr):
        t1 = np.cos(gsr)
        w1 = [t1 * w for w in w1]
    return w1


class _PlanarWeights:
    """T1 W1_j of all-planar pairs from a table over (receiver group, sender group).

    W1_j / dx_s depends on ybar, zbar and e only, and T1 on the two dihedrals: receivers with
    equal (y, z, gamma) and senders with equal (y, z, e, gamma) -- the boxes of one strip --
    share them. The table (n_stations, receiver groups, sender groups) is computed once per
    call (the weights do not depend on Mach or k) and expanded per row chunk. If it would
    exceed ``max_bytes`` (meshes without strips), the weights are computed per row block by
    :func:`_planar_weights` instead.
    """

    def __init__(self, mesh: BoxMesh, snd: _Senders, stations: np.ndarray, max_bytes: int):
        self.mesh, self.snd, self.stations = mesh, snd, stations
        r_uniq, self.r_group = _classes(np.column_stack([mesh.control_point[:, 1:],
                                                         mesh.dihedral]))
        s_uniq, self.s_group = _classes(np.column_stack([snd.mid[:, 1:], snd.e, snd.gamma]))
        self.table = None
        if 8 * stations.size * r_uniq.shape[0] * s_uniq.shape[0] > max_bytes:
            return
        ry, rz, rgam = r_uniq.T
        sy, sz, se, sgam = s_uniq.T
        cg, sg = np.cos(sgam), np.sin(sgam)
        dy = np.subtract.outer(ry, sy)
        dz = np.subtract.outer(rz, sz)
        ybar = dy * cg                                          # [R71] Eq. 4 (local axes)
        ybar += dz * sg
        zbar = dz * cg
        zbar -= dy * sg
        w1 = _weights(ybar, zbar, se[None, :], np.ones((1, se.size)), stations,
                      np.ones(ybar.shape, bool), 1)
        t1 = np.cos(sgam[None, :] - rgam[:, None])              # [R71] Eq. 5
        self.table = [w * t1 for w in w1]

    def rows(self, rows: slice) -> list:
        """T1 W1_j for receivers ``rows``: one (rows, n_senders) array per station."""
        if self.table is None:
            return _planar_weights(self.mesh, self.snd, rows, self.stations)
        rg = self.r_group[rows]
        return [np.take(tab[rg], self.s_group, axis=1) * self.snd.chord for tab in self.table]


class _PlanarChunk:
    """k-independent data of a row chunk of an all-planar mesh at one Mach.

    Per (receiver, distinct station point), [R71] Eqs. 4, 7, 10-12 and 15, with
    s = sign(u1): r1^2, s r1^2, |u1|, gc = s (1 - |u1| / sqrt(1 + u1^2)) + M r1 / (R
    sqrt(1 + u1^2)), the phase x0 + r1 u1 of exp(-i k1 u1 - i kd x0) and 2 [u1 < 0]. Per
    (receiver, sender) pair: the weights T1 W1_j of each station and sum_j K10_j T1 W1_j with
    K10 = -1 - x0 / R (the steady part of P1 that the incremental kernel subtracts, Eq. 27b).
    """

    def __init__(self, mesh: BoxMesh, pts: _StationPoints, rows: slice, mach: float,
                 t1w: list):
        beta2 = 1.0 - mach * mach
        pr = mesh.control_point[rows]
        self.t1w = t1w
        self.index = pts.index
        shape = t1w[0].shape
        # kernel geometry per distinct station point
        x0 = np.subtract.outer(pr[:, 0], pts.xyz[:, 0])         # xbar - eta tan(Lambda)
        r1sq = np.subtract.outer(pr[:, 1], pts.xyz[:, 1])
        r1sq *= r1sq
        dz = np.subtract.outer(pr[:, 2], pts.xyz[:, 2])
        dz *= dz
        r1sq += dz                                              # r1^2, [R71] Eq. 4
        big_r = np.multiply(x0, x0, out=dz)
        big_r += beta2 * r1sq
        np.sqrt(big_r, out=big_r)                               # R, [R71] Eq. 10
        r1 = np.sqrt(r1sq)
        small = r1 <= 1e-12 * pts.e                             # receiver on the doublet line
        self.small = np.nonzero(small) if small.any() else None
        if self.small is not None:
            r1[small] = 1.0
            big_r[big_r <= 0.0] = 1.0
        t = mach * big_r
        t -= x0                                                 # M R - x0
        u1 = np.multiply(r1, beta2)
        np.divide(t, u1, out=u1)                                # u1, [R71] Eq. 11
        if self.small is not None:
            u1[small] = 0.0
        u1 += 0.0                                               # no -0.0: sign(u1) = [u1 >= 0]
        # steady part sum_j K10_j T1 W1_j per pair, K10 = -1 - x0 / R, [R71] Eq. 15
        k10 = np.divide(x0, big_r)
        k10 += 1.0
        np.negative(k10, out=k10)
        self.k10_sum = np.zeros(shape)
        for j, w in enumerate(self.t1w):
            self.k10_sum += np.take(k10, pts.index[:, j], axis=1) * w
        sq = np.multiply(u1, u1, out=k10)
        sq += 1.0
        np.sqrt(sq, out=sq)                                     # sqrt(1 + u1^2)
        c1 = np.multiply(r1, mach)                              # M r1 / (R sqrt(1 + u1^2))
        big_r *= sq
        c1 /= big_r
        absu = np.abs(u1)
        g = np.divide(absu, sq, out=sq)
        np.subtract(1.0, g, out=g)                              # 1 - |u1| / sqrt(1 + u1^2)
        np.copysign(g, u1, out=g)
        g += c1                                                 # gc
        self.neg2 = np.less(u1, 0.0).astype(float)
        self.neg2 *= 2.0                                        # 2 [u1 < 0]
        if self.small is not None:
            r1[small] = 0.0
            r1sq[small] = 0.0
            self.down_small = np.where(x0[small] >= 0.0, 2.0, 0.0)   # -K1 -> 2 downstream
            self.x0_small = x0[small]
        self.gc, self.r1sq, self.r1, self.absu = g, r1sq, r1, absu
        self.sgn_r1sq = np.copysign(r1sq, u1)
        t /= beta2
        t += x0
        self.phase = t                                          # k1 u1 + kd x0 = kd * phase
        # Re I1(0) needs r1 only: per (receiver group, point group)
        rc, self.r_local = np.unique(pts.r_class[rows], return_inverse=True)
        ryz = pts.r_yz[rc]
        tab = np.subtract.outer(ryz[:, 0], pts.yz[:, 0])
        tab *= tab
        dz = np.subtract.outer(ryz[:, 1], pts.yz[:, 1])
        tab += dz * dz
        self.r1sq_groups = tab                                  # (receiver groups, point groups)
        self.yz_class = pts.yz_class
        self.xr, self.xq = pr[:, 0], pts.xyz[:, 0]


def _re_i1_zero(k1sq: np.ndarray, p_n, a_n) -> np.ndarray:
    """Re I1(0) = 1 - k1^2 sum a_n / (p_n^2 + k1^2) ([R71] Eqs. A.4, A.5 at u = 0)."""
    acc = np.zeros_like(k1sq)
    for pp, a in zip(p_n, a_n):
        acc += a / (k1sq + pp * pp)
    acc *= k1sq
    return np.subtract(1.0, acc, out=acc)


def _cos_sin(ph: np.ndarray):
    """cos(ph), sin(ph) from one tangent of the half angle, t = tan(ph / 2):
    cos = (1 - t^2) / (1 + t^2), sin = 2 t / (1 + t^2) (numpy's float64 tan is vectorised,
    its sin and cos are several times slower). The absolute error is that of the argument
    rounding, eps |ph|, as for sin and cos themselves; |t| < 1e17 in floating point, so t^2
    cannot overflow. ``ph`` is overwritten."""
    ph *= 0.5
    t = np.tan(ph, out=ph)
    den = t * t
    c = np.subtract(1.0, den)
    den += 1.0
    np.divide(1.0, den, out=den)
    c *= den                                                    # (1 - t^2) / (1 + t^2)
    t *= 2.0
    t *= den                                                    # 2 t / (1 + t^2)
    return c, t


def _cis_minus(ph: np.ndarray) -> np.ndarray:
    """exp(-i ph) (complex) via :func:`_cos_sin`; ``ph`` is overwritten."""
    c, s = _cos_sin(ph)
    out = np.empty(c.shape, complex)
    out.real = c
    np.negative(s, out=out.imag)
    return out


def _planar_increment(geo: _PlanarChunk, kd: float, p_n, a_n) -> np.ndarray:
    """D1 of an all-planar row chunk at omega / U = kd (1/m).

    With A = 1 - u/sqrt(1+u^2) - i k1 I0 at u = |u1| ([R71] Eqs. A.1, A.4), Eqs. A.1 and A.5
    give I1 = A e^(-i k1 u1) for u1 >= 0 and 2 Re I1(0) - conj(A) e^(-i k1 u1) for u1 < 0, so
    with Eq. 7, -K1 e^(-i kd x0) = (sgn Re A + i Im A + M r1 / (R sqrt(1+u1^2)))
    e^(-i kd (r1 u1 + x0)) + [u1 < 0] 2 Re I1(0) e^(-i kd x0), Re A = g - k1^2 s_1,
    Im A = -k1 s_p (s_1, s_p of :func:`_i0_sums`). This is evaluated once per distinct station
    point and summed per sender with the weights: D1 = sum_j T1 W1_j (-K1_j e_j + K10_j).
    """
    s_p, s_1 = _i0_sums(geo.absu, (kd * kd) * geo.r1sq, p_n, a_n)
    re = np.multiply(geo.sgn_r1sq, kd * kd)
    re *= s_1
    np.subtract(geo.gc, re, out=re)                             # sgn Re A + c1
    im = np.multiply(geo.r1, -kd, out=s_1)
    im *= s_p                                                   # Im A = -k1 s_p
    c, sn = _cos_sin(kd * geo.phase)
    f = np.empty(re.shape, complex)                             # (re + i im)(cos - i sin)
    fr, fi = f.real, f.imag
    np.multiply(re, c, out=fr)
    np.multiply(im, sn, out=s_p)
    fr += s_p
    np.multiply(im, c, out=fi)
    np.multiply(re, sn, out=s_p)
    fi -= s_p
    # + [u1 < 0] 2 Re I1(0) e^(-i kd x0), Re I1(0) per (y, z) group, e^(-i kd x0) = e_r conj(e_q)
    re0 = _re_i1_zero((kd * kd) * geo.r1sq_groups, p_n, a_n)
    re0 = np.take(re0, geo.yz_class, axis=1)[geo.r_local]
    re0 *= geo.neg2
    cr, sr = np.cos(kd * geo.xr), np.sin(kd * geo.xr)
    cq, sq = np.cos(kd * geo.xq), np.sin(kd * geo.xq)
    tmp = np.multiply.outer(cr, cq)
    tmp += np.multiply.outer(sr, sq)                            # cos(kd x0)
    tmp *= re0
    fr += tmp
    np.multiply.outer(sr, cq, out=tmp)
    tmp -= np.multiply.outer(cr, sq)                            # sin(kd x0)
    tmp *= re0
    fi -= tmp
    if geo.small is not None:                                   # r1 -> 0: -K1 = 2 downstream
        f[geo.small] = geo.down_small * np.exp(-1j * (kd * geo.x0_small))
    out = geo.k10_sum.astype(complex)
    for j, w in enumerate(geo.t1w):
        v = np.take(f, geo.index[:, j], axis=1)
        v *= w
        out += v
    return out


# ---------------------------------------------------------------------------------------------
# public API
# ---------------------------------------------------------------------------------------------
def _check_request(mesh, mach, k, b_ref, method):
    """Validated (mach, ks, b) of a normalwash-matrix request (ValueError/TypeError naming the
    argument)."""
    mach = check_mach(mach)
    ks = check_k(k)
    b = _check_bref(b_ref)
    _check_method(method)
    if not isinstance(mesh, BoxMesh):
        raise TypeError(f"mesh must be a BoxMesh, got {type(mesh).__name__}")
    extent = float(np.ptp(mesh.corners.reshape(-1, 3), axis=0).max())
    if ks.max() / b * extent > 1e6:
        raise ValueError(f"k / b_ref = {ks.max() / b:.3g} 1/m puts {ks.max() / b * extent:.3g} "
                         f"rad of phase across the {extent:.3g} m mesh (> 1e6: the kernel "
                         "overflows and the result would be noise); check k and b_ref")
    return mach, ks, b


def normalwash_matrices(mesh: BoxMesh, mach: float, k, b_ref: float, method: str = "quartic",
                        symmetric: bool = False, progress=None, kernel: str | None = None
                        ) -> np.ndarray:
    """DLM normalwash matrices D(M, k) for several reduced frequencies at one Mach number.

    Parameters
    ----------
    mesh : the boxes (:class:`~asekit.aero.boxes.BoxMesh`).
    mach : Mach number, 0 <= M < 1.
    k : reduced frequencies k = omega b_ref / U (>= 0), scalar or 1-D.
    b_ref : reference semi-chord (m) of k.
    method : "quartic" ([R98], Desmarais integrals; default) or "parabolic" ([R71], Laschka).
    symmetric : add the mirror image in y = 0 (wall/symmetry plane at the root).
    progress : optional callable(n_done, n_total) called after each row chunk.
    kernel : implementation of the all-planar kernel loop, "numpy" or "compiled" (numba, a
        fused loop, 2-3x faster; same equations, agreement to rounding); None:
        :func:`asekit.aero.kernels.default_kernel`. The pairwise (nonplanar) path is numpy in both.

    Returns
    -------
    D (n_k, n, n) complex with w/U = D DeltaCp (module docstring). The steady part D0 is the
    vortex lattice; the kernel geometry of each row chunk is computed once and reused for all k.
    Memory: the result plus one chunk of about ``asekit.aero.vlm.CHUNK_BYTES``; for many k on
    a large mesh use :func:`iter_normalwash_matrices` (bounded memory).
    """
    mach, ks, b = _check_request(mesh, mach, k, b_ref, method)
    check_matrix_memory(mesh.n, ks.size, 16, "the DLM normalwash matrices",
                        "use fewer boxes or fewer reduced frequencies per call, or "
                        "asekit.aero.dlm.iter_normalwash_matrices (one k at a time)")
    return _normalwash_batch(mesh, mach, ks, b, method, symmetric, progress,
                             kernel=check_kernel(kernel))


def _normalwash_batch(mesh: BoxMesh, mach: float, ks: np.ndarray, b: float, method: str,
                      symmetric: bool, progress=None, d0: np.ndarray | None = None,
                      kernel: str = "numpy") -> np.ndarray:
    """D (n_k, n, n) of validated arguments; ``d0`` the vortex lattice D0 if already known.
    Raises ValueError for a mesh whose matrix is not finite (:func:`_check_finite`)."""
    out = _normalwash_batch_unchecked(mesh, mach, ks, b, method, symmetric, progress, d0,
                                      kernel)
    _check_finite(mesh, out)
    return out


def _check_finite(mesh: BoxMesh, d: np.ndarray) -> None:
    """Refuse a non-finite D: the one configuration known to give it is a control point on the
    spanwise line of a sending box's side edge in its plane (|ybar| = e, zbar = 0), where the
    closed-form line integrals of [R71] Eq. 31 (F = 2e / (ybar^2 - e^2)) are infinite; the
    kernel numerator there is zero upstream (inf * 0 = NaN) and PanelAero gives NaN too."""
    if np.isfinite(d).all():
        return
    _, r, s = (int(v) for v in np.argwhere(~np.isfinite(d))[0])
    raise ValueError(
        f"mesh: the DLM normalwash matrix is not finite at receiver {r} (control point "
        f"{np.round(mesh.control_point[r], 6).tolist()}) and sender {s} (doublet line "
        f"{np.round(mesh.doublet_p1[s], 6).tolist()} to {np.round(mesh.doublet_p3[s], 6).tolist()}): "
        "a control point on the spanwise line of another box's side edge makes the kernel "
        "integrals singular; shift the strip edges of one surface so that no control point is "
        "spanwise-aligned with a box edge of another surface in its plane")


def _normalwash_batch_unchecked(mesh, mach, ks, b, method, symmetric, progress, d0, kernel):
    snd = _Senders(mesh, symmetric)
    n = mesh.n
    out = np.empty((ks.size, n, n), complex)
    out[:] = (vlm_normalwash_matrix(mesh, mach, symmetric, kernel) if d0 is None else d0)[None]
    ik_nz = np.flatnonzero(ks > 0.0)
    if ik_nz.size == 0:
        if progress is not None:
            progress(n, n)
        return out
    kds = ks / b

    def add_all(ik, sl, d1):
        out[ik, sl] += _fold(d1, n, snd.n_images)

    if _all_planar(mesh, snd):
        # the compiled kernel accumulates into D itself when there are no images to fold
        direct = (lambda ik, sl: out[ik, sl]) if snd.n_images == 1 else None
        _planar_rows(mesh, snd, mach, method, kds, ik_nz, add_all, progress, kernel, direct)
        return out
    blocks = _plane_blocks(mesh, snd)
    if blocks is None:
        _pairwise_rows(mesh, snd, mach, method, kds, ik_nz, add_all, progress)
        return out
    # surfaces in different planes: all-planar blocks (receivers and senders in one plane)
    # by the planar path, the others pairwise
    done, total = 0, n * snd.mid.shape[0]
    for r_idx, s_idx in blocks:
        rec, sub = _Receivers(mesh, r_idx), snd.subset(s_idx)
        cols, original = s_idx % n, s_idx < n

        def add_block(ik, sl, d1, r_idx=r_idx, cols=cols, original=original):
            rows = r_idx[sl]
            for part in (original, ~original):       # a box and its image: separate columns
                if part.any():
                    out[ik][np.ix_(rows, cols[part])] += d1[:, part]

        if _all_planar(rec, sub):
            _planar_rows(rec, sub, mach, method, kds, ik_nz, add_block, None, kernel)
        else:
            _pairwise_rows(rec, sub, mach, method, kds, ik_nz, add_block, None)
        done += r_idx.size * s_idx.size
        if progress is not None:
            progress(int(round(n * done / total)), n)
    return out


#: Default memory for the matrices that :func:`iter_normalwash_matrices` holds at once (bytes).
STREAM_BYTES = 2**30


def iter_normalwash_matrices(mesh: BoxMesh, mach: float, k, b_ref: float,
                             method: str = "quartic", symmetric: bool = False,
                             max_bytes: int | None = None, kernel: str | None = None):
    """Stream the normalwash matrices D(M, k) of a k sweep: yields ``(k_i, D_i)`` in the order
    of ``k``, holding at most ``max_bytes`` of matrices (default :data:`STREAM_BYTES`, 1 GiB;
    at least one matrix, 16 n^2 bytes) plus the vortex lattice D0 (8 n^2 bytes, computed once).

    The reduced frequencies are computed in batches of ``max(1, max_bytes // (16 n^2))``: the
    k-independent kernel geometry is shared within a batch (as in
    :func:`normalwash_matrices`) and recomputed per batch, so a batch of all k (small meshes)
    costs what one :func:`normalwash_matrices` call does and a batch of one k (aircraft-scale
    meshes) costs the geometry once per k. A yielded D_i is a view into the batch: factor it
    in place (:func:`factor_normalwash_matrix` with ``overwrite=True``) or copy it before the
    next step, and drop your reference (``del D``) before asking for the next one: a reference
    kept across a batch boundary keeps that batch alive while the next is computed.
    :func:`map_normalwash_matrices` is the callback form that does this. Arguments and
    conventions as :func:`normalwash_matrices`; ``max_bytes`` must be a positive integer.
    """
    mach, ks, b = _check_request(mesh, mach, k, b_ref, method)
    if max_bytes is None:
        max_bytes = STREAM_BYTES
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, (int, np.integer)) \
            or max_bytes <= 0:
        raise ValueError(f"max_bytes must be a positive integer number of bytes, got "
                         f"{max_bytes!r}")
    check_matrix_memory(mesh.n, 1, 16, "one DLM normalwash matrix", "use fewer boxes")
    per_batch = max(1, int(max_bytes) // (16 * mesh.n * mesh.n))
    return _stream(mesh, mach, ks, b, method, symmetric, per_batch, check_kernel(kernel))


def map_normalwash_matrices(mesh: BoxMesh, mach: float, k, b_ref: float, fn,
                            method: str = "quartic", symmetric: bool = False,
                            max_bytes: int | None = None, kernel: str | None = None) -> list:
    """``[fn(i, k_i, D_i) for each k_i]`` over the streamed matrices of
    :func:`iter_normalwash_matrices` (same arguments), dropping each D_i after ``fn`` returns:
    the callback form of the stream, e.g. ``fn`` factors D_i in place, projects the pressures
    onto the modes and returns the small modal matrix. ``fn`` may overwrite D_i but must not
    keep it (or a view of it) if memory is to stay bounded by one batch."""
    if not callable(fn):
        raise TypeError(f"fn must be callable (i, k, D) -> result, got {type(fn).__name__}")
    out = []
    # no enumerate(): its reused result tuple would keep the last D (and so its whole batch)
    # alive while the generator computes the next batch
    for kk, d in iter_normalwash_matrices(mesh, mach, k, b_ref, method, symmetric, max_bytes,
                                          kernel):
        out.append(fn(len(out), kk, d))
        del d                           # before the next batch is computed
    return out


def _stream(mesh, mach, ks, b, method, symmetric, per_batch, kernel):
    d0 = vlm_normalwash_matrix(mesh, mach, symmetric, kernel)
    for i0 in range(0, ks.size, per_batch):
        batch = ks[i0:i0 + per_batch]
        d = _normalwash_batch(mesh, mach, batch, b, method, symmetric, d0=d0, kernel=kernel)
        for i, kk in enumerate(batch):
            yield float(kk), d[i]
        del d


def _plane_blocks(mesh: BoxMesh, snd: _Senders, max_blocks: int = 64):
    """(receiver indices, sender indices) of the blocks of boxes by plane (|normal . x| and
    the normal up to sign, to 1e-6), or None for a single plane or more than ``max_blocks``
    blocks. Only a partition: each block is checked for planarity before the planar path."""
    scale = float(np.abs(snd.mid).max()) + float(snd.e.max())

    def groups(points, gamma):
        nrm = np.column_stack([-np.sin(gamma), np.cos(gamma)])      # (y, z) of the normal
        flip = (nrm[:, 0] < -1e-12) | ((np.abs(nrm[:, 0]) <= 1e-12) & (nrm[:, 1] < 0.0))
        nrm[flip] *= -1.0
        offset = nrm[:, 0] * points[:, 1] + nrm[:, 1] * points[:, 2]
        key = np.round(np.column_stack([nrm / 1e-6, offset / (1e-6 * scale)]))
        _, inverse = _classes(key.astype(np.int64))
        return [np.flatnonzero(inverse == g) for g in range(inverse.max() + 1)]

    r_groups = groups(mesh.control_point, mesh.dihedral)
    s_groups = groups(snd.mid, snd.gamma)
    if len(r_groups) * len(s_groups) > max_blocks or len(r_groups) * len(s_groups) == 1:
        return None
    return [(r, s) for r in r_groups for s in s_groups]


def _pairwise_rows(rec, snd: _Senders, mach: float, method: str, kds, ik_nz, add, progress):
    """D1 + D2 of receivers ``rec`` against senders ``snd`` by row chunks of pairs
    (:class:`_ChunkGeometry`, :func:`_increment`): ``add(ik, rows, d1)`` per chunk and k."""
    stations = _METHODS[method][0]
    n, ns = rec.n, snd.mid.shape[0]
    # bytes per (receiver, sender) pair held by one chunk: geometry (~14 arrays per station,
    # more if nonplanar) + kernel temporaries (~20 complex)
    per_pair = 8 * (stations.size * 22 + 40)
    rows = max(1, min(n, int(CHUNK_BYTES // (ns * per_pair)), PAIRS_PER_CHUNK // ns))
    for i0 in range(0, n, rows):
        sl = slice(i0, min(n, i0 + rows))
        geo = _ChunkGeometry(rec, snd, sl, mach, method)
        for ik in ik_nz:
            add(ik, sl, _increment(geo, mach, kds[ik], method))
        if progress is not None:
            progress(sl.stop, n)


def _compiled_planar(rec, pts: "_StationPoints", rows: slice, mach: float, t1w: list, kds,
                     ik_nz, p_n, a_n, add, target=None) -> None:
    """One planar row chunk by the compiled kernel (:mod:`asekit.aero._dlm_compiled`): the
    geometry of :class:`_PlanarChunk` in one compiled pass, then per k ``add(ik, d1)``, or, if
    ``target`` is given, D1 added into the array ``target(ik)`` by the kernel itself."""
    from asekit.aero import _dlm_compiled as C  # numba is optional: imported only here
    pr = np.ascontiguousarray(rec.control_point[rows])
    e1, sgn_r1sq, gc, r1, phase, neg2, k10 = C.planar_geometry(pr, pts.xyz, pts.e, mach,
                                                               float(p_n[0]))
    rc, r_local = np.unique(pts.r_class[rows], return_inverse=True)
    ryz = pts.r_yz[rc]
    tab = np.subtract.outer(ryz[:, 0], pts.yz[:, 0])
    tab *= tab
    dz = np.subtract.outer(ryz[:, 1], pts.yz[:, 1])
    tab += dz * dz                                              # r1^2 per group pair
    t1w = np.stack(t1w)
    xq = np.ascontiguousarray(pts.xyz[:, 0])
    index_t = np.ascontiguousarray(pts.index.T)
    for ik in ik_nz:
        d1 = np.zeros(t1w.shape[1:], complex) if target is None else target(ik)
        C.planar_increment(float(kds[ik]), e1, sgn_r1sq, gc, r1, phase, neg2, k10,
                           pr[:, 0].copy(), xq, r_local.reshape(-1), pts.yz_class, tab,
                           index_t, t1w, p_n, a_n, p_n.size == 12, d1)
        if target is None:
            add(ik, d1)


def _planar_rows(rec, snd: _Senders, mach: float, method: str, kds, ik_nz, add, progress,
                 kernel: str = "numpy", direct=None, pts=None, weights=None):
    """D1 of receivers ``rec`` against senders ``snd``, all pairs planar (module docstring):
    kernel per distinct station point in row chunks of about PLANAR_POINTS_PER_CHUNK
    (receiver, point) pairs, weights per block of chunks; ``add(ik, rows, d1)``. ``kernel``
    "compiled": the k loop by :func:`asekit.aero._dlm_compiled.planar_increment`, which adds
    into ``direct(ik, rows)`` (a C-contiguous view of D) instead of calling ``add`` if given.
    ``pts``, ``weights``: the station points and weights of (rec, snd) if already known
    (:class:`NormalwashBlocks`)."""
    stations, p_n, a_n = _METHODS[method]
    n, ns = rec.n, snd.mid.shape[0]
    if pts is None:
        pts = _StationPoints(rec, snd, stations)
    if weights is None:
        weights = _PlanarWeights(rec, snd, stations, PLANAR_WEIGHT_TABLE_BYTES)
    nq = pts.xyz.shape[0]
    # the chunk holds ~12 real arrays per (row, point) and ~stations + 4 per (row, sender)
    if kernel == "compiled":
        per_row = max(COMPILED_POINTS_PER_CHUNK // nq, COMPILED_MIN_ROWS)
    else:
        per_row = PLANAR_POINTS_PER_CHUNK // nq
    rows = max(1, min(n, per_row,
                      int(CHUNK_BYTES // (8 * (16 * nq + (stations.size + 6) * ns)))))
    block = rows * max(1, PAIRS_PER_CHUNK // (ns * rows))
    for i0 in range(0, n, block):
        bl = slice(i0, min(n, i0 + block))
        t1w = weights.rows(bl)
        for j0 in range(bl.start, bl.stop, rows):
            sl = slice(j0, min(bl.stop, j0 + rows))
            sub = slice(sl.start - i0, sl.stop - i0)
            if kernel == "compiled":
                _compiled_planar(rec, pts, sl, mach, [w[sub] for w in t1w], kds, ik_nz, p_n,
                                 a_n, lambda ik, d1: add(ik, sl, d1),
                                 None if direct is None else (lambda ik: direct(ik, sl)))
                continue
            geo = _PlanarChunk(rec, pts, sl, mach, [w[sub] for w in t1w])
            for ik in ik_nz:
                add(ik, sl, _planar_increment(geo, kds[ik], p_n, a_n))
        if progress is not None:
            progress(bl.stop, n)


def normalwash_matrix(mesh: BoxMesh, mach: float, k: float, b_ref: float,
                      method: str = "quartic", symmetric: bool = False) -> np.ndarray:
    """DLM normalwash matrix D(M, k) (n, n) complex, w/U = D DeltaCp; see
    :func:`normalwash_matrices` for the arguments and conventions."""
    if np.ndim(k) != 0:
        raise ValueError(f"k must be a scalar reduced frequency, got shape {np.shape(k)}")
    return normalwash_matrices(mesh, mach, [k], b_ref, method, symmetric)[0]


@dataclass(frozen=True, eq=False)
class AicFactor:
    """The LU factors of one DLM normalwash matrix D(M, k): the aerodynamic influence matrix
    AIC = D^-1 as an operator, DeltaCp = AIC (w/U) = D^-1 (w/U), applied by two triangular
    solves per normalwash column (LAPACK getrs) without forming D^-1.

    Attributes
    ----------
    lu, piv : LAPACK getrf factors (read-only) of D^T when ``transposed`` (the factorisation of
        a C-ordered D in place: D^T is its Fortran-ordered view) or of D otherwise.
    transposed : see ``lu``; :meth:`pressures` solves (D^T)^T x = D x = w then.
    mach, k, b_ref, method, symmetric : what D was computed for (:func:`normalwash_matrices`);
        NaN / "" where unknown (a factor of a user-given matrix).

    Build with :func:`factor_aic` (mesh and flight condition) or
    :func:`factor_normalwash_matrix` (a D already computed, e.g. from
    :func:`iter_normalwash_matrices`).
    """

    lu: np.ndarray
    piv: np.ndarray
    transposed: bool
    mach: float = float("nan")
    k: float = float("nan")
    b_ref: float = float("nan")
    method: str = ""
    symmetric: bool = False

    @property
    def n(self) -> int:
        """Number of boxes (the order of D)."""
        return self.lu.shape[0]

    def pressures(self, normalwash) -> np.ndarray:
        """DeltaCp = D^-1 (w/U) for the normalwash ``normalwash`` (n,) or (n, m), any number of
        columns m (real or complex w/U at the control points): the solution of
        D DeltaCp = w/U by the stored LU factors ([AR69] Eq. 1 inverted), same shape as
        ``normalwash``, complex. Raises ValueError if ``normalwash`` is not a finite numeric
        array with first dimension n."""
        w = np.asarray(normalwash)
        if w.dtype.kind not in "biufc" or w.ndim not in (1, 2) or w.shape[0] != self.n:
            raise ValueError(f"normalwash must be a numeric (n,) or (n, m) array with n = "
                             f"{self.n} boxes, got shape {w.shape} dtype {w.dtype}")
        if not np.all(np.isfinite(w)):
            raise ValueError("normalwash must be finite (it has NaN or inf entries)")
        return sla.lu_solve((self.lu, self.piv), w.astype(complex, copy=False),
                            trans=1 if self.transposed else 0, check_finite=False)


def factor_normalwash_matrix(d: np.ndarray, overwrite: bool = False, **condition) -> AicFactor:
    """The :class:`AicFactor` (LU with partial pivoting, LAPACK getrf) of a normalwash matrix
    ``d`` (n, n) complex. ``overwrite=True`` factors ``d`` in place (no copy of a C- or
    Fortran-ordered ``d``; ``d`` then holds the factors and must not be used as D again).
    ``condition`` (mach, k, b_ref, method, symmetric) is recorded in the factor. Raises
    ValueError for a non-square or non-finite ``d`` and numpy.linalg.LinAlgError for an exactly
    singular one (a zero pivot)."""
    a = np.asarray(d)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0 or a.dtype.kind not in "fc":
        raise ValueError(f"d must be a square (n, n) float or complex matrix, got shape "
                         f"{a.shape} dtype {a.dtype}")
    if not np.all(np.isfinite(a)):
        raise ValueError("d must be finite (the normalwash matrix has NaN or inf entries)")
    a = a.astype(complex, copy=False)
    transposed = not a.flags.f_contiguous and a.flags.c_contiguous
    src = a.T if transposed else a
    lu, piv, info = sla.lapack.zgetrf(src, overwrite_a=overwrite)
    if info > 0:
        raise np.linalg.LinAlgError(f"d is singular: zero pivot U[{info - 1}, {info - 1}] in its "
                                    "LU factorisation (coincident boxes, or a surface on its "
                                    "own mirror image?)")
    lu.setflags(write=False)
    piv.setflags(write=False)
    return AicFactor(lu, piv, transposed, **condition)


def factor_aic(mesh: BoxMesh, mach: float, k: float, b_ref: float, method: str = "quartic",
               symmetric: bool = False) -> AicFactor:
    """The factored AIC of ``mesh`` at (M, k): :func:`normalwash_matrix` then its LU in place
    (:func:`factor_normalwash_matrix`). ``factor_aic(...).pressures(w)`` equals
    ``aic_matrix(...) @ w`` to rounding at a fraction of the cost (no explicit inverse: one LU,
    (8/3) n^3 real flops, instead of LU plus inversion, about 8 n^3; then 8 n^2 per
    normalwash column). Arguments and conventions as :func:`normalwash_matrices`."""
    d = normalwash_matrix(mesh, mach, k, b_ref, method, symmetric)
    return factor_normalwash_matrix(d, overwrite=True, mach=float(mach), k=float(k),
                                    b_ref=float(b_ref), method=method, symmetric=bool(symmetric))


def aic_matrix(mesh: BoxMesh, mach: float, k: float, b_ref: float, method: str = "quartic",
               symmetric: bool = False) -> np.ndarray:
    """Aerodynamic influence matrix AIC = D^-1 (n, n) complex: DeltaCp = AIC (w/U) with the
    normalwash w/U = dh/dx + i k h / b_ref at the control points (module docstring).

    Cost: this forms the explicit inverse, solve(D, I): an LU and n right-hand sides (about
    8 n^3 real flops for complex D against (8/3) n^3 for the LU alone) and a second n x n
    complex matrix. To apply the AIC to a few normalwash columns, use
    :func:`factor_aic` and :meth:`AicFactor.pressures` instead: measured at 1200 boxes, one
    (M, k), 6 columns, one BLAS thread (``tests/benchmarks/bench_aero_speed.py --only aic``),
    aic_matrix followed by the product took 1.7-2.0 times the CPU time of factor-and-solve
    (four runs: 1.68, 1.66, 1.92, 1.96; e.g. 0.98 s against 0.50 s, D about 0.35-0.45 s of
    each), the solve part alone 4.1-4.7 times (e.g. 0.55 s against 0.12 s).
    """
    d = normalwash_matrix(mesh, mach, k, b_ref, method, symmetric)
    return np.linalg.solve(d, np.eye(d.shape[0]))


def pressure_jump(mesh: BoxMesh, mach: float, k: float, b_ref: float, normalwash: np.ndarray,
                  method: str = "quartic", symmetric: bool = False) -> np.ndarray:
    """DeltaCp (n,) or (n, m) for the normalwash w/U (n,) or (n, m): solves D DeltaCp = w/U
    (:func:`factor_aic`, :meth:`AicFactor.pressures`)."""
    w = np.asarray(normalwash)
    if w.ndim not in (1, 2) or w.shape[0] != mesh.n or not np.all(np.isfinite(w)):
        raise ValueError(f"normalwash must be finite with first dimension {mesh.n}, got {w.shape}")
    return factor_aic(mesh, mach, k, b_ref, method, symmetric).pressures(w)


# ---------------------------------------------------------------------------------------------
# sub-blocks of D (for the compressed solve of asekit.aero.hmatrix)
# ---------------------------------------------------------------------------------------------
def _index_array(name: str, idx, n: int) -> np.ndarray:
    """``idx`` as a 1-D int array of distinct box indices in [0, n) (ValueError naming it)."""
    a = np.asarray(idx)
    if a.ndim != 1 or a.size == 0 or a.dtype.kind not in "iu":
        raise ValueError(f"{name} must be a non-empty 1-D integer array of box indices, got "
                         f"shape {a.shape} dtype {a.dtype}")
    if a.min() < 0 or a.max() >= n or np.unique(a).size != a.size:
        raise ValueError(f"{name} must hold distinct box indices in [0, {n - 1}]")
    return a.astype(np.intp, copy=False)


def _vlm_block(mesh: BoxMesh, mach: float, rows: np.ndarray, cols: np.ndarray,
               symmetric: bool) -> np.ndarray:
    """D0[rows][:, cols] of :func:`asekit.aero.vlm.vlm_normalwash_matrix` (same horseshoe
    sums, numpy loop; the masking scale is the whole mesh's longest bound vortex, as there)."""
    from asekit.aero.vlm import _distinct_vertices, _horseshoe_normalwash, _senders
    beta = math.sqrt(1.0 - mach * mach)
    sx = np.array([1.0 / beta, 1.0, 1.0])
    p = mesh.control_point[rows] * sx
    n_r = mesh.normal[rows]
    d = np.zeros((rows.size, cols.size))
    for img in _senders(mesh, symmetric):
        scale = float(np.max(np.linalg.norm((img.doublet_p3 - img.doublet_p1) * sx, axis=1)))
        v, ia, ib = _distinct_vertices(img.doublet_p1[cols] * sx, img.doublet_p3[cols] * sx)
        d += _horseshoe_normalwash(p, n_r, v, ia, ib, scale) * (0.5 * img.chord[cols])[None, :]
    return d


def normalwash_block(mesh: BoxMesh, mach: float, k, b_ref: float, rows, cols,
                     method: str = "quartic", symmetric: bool = False,
                     kernel: str | None = None) -> np.ndarray:
    """The sub-block D(M, k)[rows][:, cols] of the DLM normalwash matrix, computed from the
    kernel for those receivers and senders only (cost proportional to len(rows) len(cols)).

    Same equations as :func:`normalwash_matrices` ([R71] Eqs. 22, 27, 36; [R98] Eqs. 1-5):
    the steady part D0 by the horseshoe lattice, the increments D1 (+ D2 for nonplanar pairs)
    by the all-planar path when every pair of the block is planar, else pairwise; with
    ``symmetric`` each sending box and its image in y = 0 are summed into one column. The
    result equals the corresponding entries of the full matrix to rounding
    (tests/aero/test_hmatrix.py). This is the entry point that
    :mod:`asekit.aero.hmatrix` uses to generate single rows and columns of admissible blocks.

    Parameters
    ----------
    mesh, mach, k, b_ref, method, symmetric, kernel : as :func:`normalwash_matrices`
        (k scalar or 1-D, b_ref in m).
    rows, cols : 1-D integer arrays of distinct receiver and sender box indices.

    Returns
    -------
    (n_k, len(rows), len(cols)) complex.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 1, 0), 1.0, 4, 3)])
    >>> full = normalwash_matrices(m, 0.5, [0.3], 0.5)[0]
    >>> blk = normalwash_block(m, 0.5, [0.3], 0.5, [1, 5], [0, 2, 7])[0]
    >>> bool(np.allclose(blk, full[np.ix_([1, 5], [0, 2, 7])], rtol=0, atol=1e-13))
    True
    """
    mach, ks, b = _check_request(mesh, mach, k, b_ref, method)
    rows = _index_array("rows", rows, mesh.n)
    cols = _index_array("cols", cols, mesh.n)
    kernel = check_kernel(kernel)
    snd_all = _Senders(mesh, symmetric)
    s_idx = np.concatenate([cols + i * mesh.n for i in range(snd_all.n_images)])
    rec, snd = _Receivers(mesh, rows), snd_all.subset(s_idx)
    out = np.empty((ks.size, rows.size, cols.size), complex)
    out[:] = _vlm_block(mesh, mach, rows, cols, symmetric)[None]
    ik_nz = np.flatnonzero(ks > 0.0)
    if ik_nz.size:
        def add(ik, sl, d1):
            out[ik, sl] += _fold(d1, cols.size, snd_all.n_images)

        if _all_planar(rec, snd):
            _planar_rows(rec, snd, mach, method, ks / b, ik_nz, add, None, kernel)
        else:
            _pairwise_rows(rec, snd, mach, method, ks / b, ik_nz, add, None)
    if not np.isfinite(out).all():
        raise ValueError("mesh: the DLM normalwash block is not finite (a control point on the "
                         "spanwise line of a box side edge; see normalwash_matrices)")
    return out


class NormalwashBlocks:
    """Evaluator of sub-blocks D(M, k)[rows][:, cols] of one mesh at one Mach number and a set
    of reduced frequencies, for many small requests (the rows and columns that adaptive cross
    approximation asks for, :mod:`asekit.aero.hmatrix`).

    The k-independent data of all senders -- the distinct kernel station points, the planar
    weight table and the horseshoe corners -- are computed once here, and each call takes the
    subset it needs; the equations and so the entries are those of :func:`normalwash_block`
    and :func:`normalwash_matrices` (agreement to rounding, tests/aero/test_hmatrix.py).
    Meshes with nonplanar pairs are evaluated by :func:`normalwash_block` per call.

    Parameters
    ----------
    mesh, mach, k, b_ref, method, symmetric, kernel : as :func:`normalwash_matrices`.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    >>> m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 1, 0), 1.0, 4, 3)])
    >>> ev = NormalwashBlocks(m, 0.5, [0.3], 0.5, symmetric=True)
    >>> blk = normalwash_block(m, 0.5, [0.3], 0.5, [1, 5], [0, 2, 7], symmetric=True)
    >>> bool(np.allclose(ev([1, 5], [0, 2, 7]), blk, rtol=0, atol=1e-13))
    True
    """

    def __init__(self, mesh: BoxMesh, mach: float, k, b_ref: float, method: str = "quartic",
                 symmetric: bool = False, kernel: str | None = None):
        self.mach, self.ks, self.b = _check_request(mesh, mach, k, b_ref, method)
        self.mesh, self.method, self.symmetric = mesh, method, bool(symmetric)
        self.kernel = check_kernel(kernel)
        self.snd = _Senders(mesh, symmetric)
        self.planar = _all_planar(mesh, self.snd)
        stations = _METHODS[method][0]
        if self.planar:
            self.pts = _StationPoints(mesh, self.snd, stations)
            self.weights = _PlanarWeights(mesh, self.snd, stations, PLANAR_WEIGHT_TABLE_BYTES)
        from asekit.aero.vlm import _distinct_vertices, _senders
        beta = math.sqrt(1.0 - self.mach ** 2)
        self.sx = np.array([1.0 / beta, 1.0, 1.0])
        self.lattice = []
        for img in _senders(mesh, symmetric):
            a, b = img.doublet_p1 * self.sx, img.doublet_p3 * self.sx
            scale = float(np.max(np.linalg.norm(b - a, axis=1)))
            self.lattice.append((_distinct_vertices(a, b), scale, 0.5 * img.chord))

    def _steady(self, rows, cols) -> np.ndarray:
        from asekit.aero.vlm import _horseshoe_normalwash
        p = self.mesh.control_point[rows] * self.sx
        n_r = self.mesh.normal[rows]
        d = np.zeros((rows.size, cols.size))
        for (v, ia, ib), scale, half_chord in self.lattice:
            used, inv = np.unique(np.concatenate([ia[cols], ib[cols]]), return_inverse=True)
            inv = inv.reshape(-1)
            if self.kernel == "compiled":       # the loop form of the same sums
                from asekit.aero import _dlm_compiled
                _dlm_compiled.horseshoe_normalwash(
                    np.ascontiguousarray(p), np.ascontiguousarray(n_r), v[used],
                    inv[:cols.size], inv[cols.size:], scale, half_chord[cols], d)
                continue
            d += (_horseshoe_normalwash(p, n_r, v[used], inv[:cols.size], inv[cols.size:],
                                        scale) * half_chord[cols][None, :])
        return d

    def _sub_points(self, rows, s_idx):
        """The station points and weights of receivers ``rows`` and senders ``s_idx``."""
        pts = self.pts
        used, inv = np.unique(pts.index[s_idx], return_inverse=True)
        sub = object.__new__(_StationPoints)
        sub.xyz, sub.e = pts.xyz[used], pts.e[used]
        sub.index = inv.reshape(s_idx.size, -1)
        sub.yz, sub.yz_class = pts.yz, pts.yz_class[used]
        sub.r_yz, sub.r_class = pts.r_yz, pts.r_class[rows]
        wt = self.weights
        sw = object.__new__(_PlanarWeights)
        sw.mesh, sw.snd, sw.stations = _Receivers(self.mesh, rows), self.snd.subset(s_idx), \
            wt.stations
        sw.r_group, sw.s_group, sw.table = wt.r_group[rows], wt.s_group[s_idx], wt.table
        return sub, sw

    def __call__(self, rows, cols) -> np.ndarray:
        """D[rows][:, cols] for every k, (n_k, len(rows), len(cols)) complex (``rows``,
        ``cols``: 1-D arrays of distinct box indices)."""
        mesh = self.mesh
        if not self.planar:
            return normalwash_block(mesh, self.mach, self.ks, self.b, rows, cols, self.method,
                                    self.symmetric, self.kernel)
        rows = _index_array("rows", rows, mesh.n)
        cols = _index_array("cols", cols, mesh.n)
        n_img = self.snd.n_images
        s_idx = np.concatenate([cols + i * mesh.n for i in range(n_img)])
        out = np.empty((self.ks.size, rows.size, cols.size), complex)
        out[:] = self._steady(rows, cols)[None]
        ik_nz = np.flatnonzero(self.ks > 0.0)
        if ik_nz.size:
            def add(ik, sl, d1):
                out[ik, sl] += _fold(d1, cols.size, n_img)

            pts, weights = self._sub_points(rows, s_idx)
            _planar_rows(_Receivers(mesh, rows), self.snd.subset(s_idx), self.mach,
                         self.method, self.ks / self.b, ik_nz, add, None, self.kernel,
                         pts=pts, weights=weights)
        if not np.isfinite(out).all():
            raise ValueError("mesh: the DLM normalwash block is not finite (a control point "
                             "on the spanwise line of a box side edge; see "
                             "normalwash_matrices)")
        return out
