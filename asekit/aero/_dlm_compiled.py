"""Compiled (numba) kernel of the all-planar DLM path: the optional accelerator of
:func:`asekit.aero.dlm._planar_increment`, same equations, float64 throughout.

Imported only when numba is installed and the compiled kernel is chosen
(:func:`asekit.aero.dlm.default_kernel`). One fused loop per receiver row evaluates, per
distinct kernel station point q ([R71] Eqs. A.1, A.4, A.5, 7, 12 in the form of
:func:`asekit.aero.dlm._planar_increment`):

    k1^2 = kd^2 r1^2,  s_1 = sum_n a_n e^(-p_n |u1|) / (p_n^2 + k1^2),  s_p = sum_n p_n (...),
    -K1 e^(-i kd x0) = (gc - kd^2 sgn(u1) r1^2 s_1 - i kd r1 s_p) e^(-i kd (x0 + r1 u1))
                       + [u1 < 0] 2 (1 - k1^2 sum_n a_n / (p_n^2 + k1^2)) e^(-i kd x0),

(the Re I1(0) term shares the denominators p_n^2 + k1^2 with s_1), and then gathers the
stations of every sender with the weights T1 W1_j: D1 = sum_j T1 W1_j (-K1_j e_j + K10_j)
([R71] Eq. 27b). ``error_model="numpy"`` (division by zero gives inf/nan as in numpy, no
Python exception checks in the loop); no fastmath (no reassociation): the result agrees with
the numpy path to rounding (tests/test_dlm_compiled.py).
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, error_model="numpy", nogil=True)
def planar_increment(kd, e1s, sgn_r1sq, gc, r1, phase, neg2, small, k10, xr, xq, r_local,
                     yz_class, r1sq_groups, index, t1w, p_n, a_n, desmarais, out):
    """D1 of an all-planar row chunk at omega / U = kd (1/m), written into ``out`` (rows,
    senders) complex.

    Arrays (rows, points): exp(-p_1 |u1|) (k-independent, computed once per chunk), sgn(u1) r1^2, gc, r1, the phase x0 + r1 u1, 2 [u1 < 0],
    r1 ~ 0 (bool), K10 (:func:`planar_geometry`); xr (rows,), xq (points,) streamwise
    coordinates; r1^2 per (receiver
    group, point group) ``r1sq_groups`` with the groups ``r_local`` (rows,) and ``yz_class``
    (points,); index (senders, stations) point of each station; t1w (stations, rows, senders);
    p_n, a_n the exponents and coefficients of the kernel series;
    ``desmarais``: p_n = 2^n b (powers by squaring) rather than n c.

    r1, and so k1 = kd r1, depends on the (y, z) groups only: the factors a_n / (p_n^2 +
    k1^2) and Re I1(0) are tabulated per group pair (no division per pair), and
    e^(-i kd x0) = e^(-i kd x_r) e^(i kd x_q) from per-row and per-point values; the steady
    part K10 is added per point before the gather, D1 = sum_j T1 W1_j (-K1_j e_j + K10_j).
    """
    rows, nq = e1s.shape
    ns, nst = index.shape
    nterm = p_n.size
    kd2 = kd * kd
    ngr, ngq = r1sq_groups.shape
    inv = np.empty((ngr, ngq, nterm))
    re0 = np.empty((ngr, ngq))
    for a in range(ngr):
        for b in range(ngq):
            k1sq = kd2 * r1sq_groups[a, b]
            acc = 0.0
            for n in range(nterm):
                v = a_n[n] / (k1sq + p_n[n] * p_n[n])
                inv[a, b, n] = v
                acc += v
            re0[a, b] = 1.0 - k1sq * acc                 # Re I1(0), [R71] Eq. A.5 at u = 0
    cr = np.empty(rows)
    sr = np.empty(rows)
    for i in range(rows):
        cr[i] = math.cos(kd * xr[i])
        sr[i] = math.sin(kd * xr[i])
    cq = np.empty(nq)
    sq = np.empty(nq)
    for q in range(nq):
        cq[q] = math.cos(kd * xq[q])
        sq[q] = math.sin(kd * xq[q])
    fr = np.empty(nq)
    fi = np.empty(nq)
    for i in range(rows):
        g = r_local[i]
        for q in range(nq):
            # e^(-i kd x0) = (cr cq + sr sq) - i (sr cq - cr sq)
            cx = cr[i] * cq[q] + sr[i] * sq[q]
            sx = sr[i] * cq[q] - cr[i] * sq[q]
            if small[i, q]:                              # r1 -> 0: -K1 = 2 downstream, 0 up
                down = 2.0 if xr[i] - xq[q] >= 0.0 else 0.0
                fr[q] = down * cx + k10[i, q]
                fi[q] = -down * sx
                continue
            h = yz_class[q]
            e1 = e1s[i, q]
            en = e1
            s1 = 0.0
            sp = 0.0
            for n in range(nterm):
                if n > 0:
                    en = en * en if desmarais else en * e1
                t = en * inv[g, h, n]
                s1 += t
                sp += t * p_n[n]
            re = gc[i, q] - (kd2 * sgn_r1sq[i, q]) * s1          # sgn Re A + c1
            im = -kd * r1[i, q] * sp                             # Im A = -k1 s_p
            # cos, sin of kd * phase from t = tan(kd phase / 2) (one libm call instead of two)
            t = math.tan(0.5 * kd * phase[i, q])
            den = 1.0 / (1.0 + t * t)
            c = (1.0 - t * t) * den
            s = 2.0 * t * den
            vr = re * c + im * s
            vi = im * c - re * s
            w0 = neg2[i, q]
            if w0 != 0.0:                                        # + 2 Re I1(0) e^(-i kd x0)
                r0 = re0[g, h] * w0
                vr += r0 * cx
                vi -= r0 * sx
            fr[q] = vr + k10[i, q]
            fi[q] = vi
        for s_ in range(ns):
            accr = 0.0
            acci = 0.0
            for j in range(nst):
                w = t1w[j, i, s_]
                q = index[s_, j]
                accr += fr[q] * w
                acci += fi[q] * w
            out[i, s_] = complex(accr, acci)


@numba.njit(cache=True, error_model="numpy", nogil=True)
def planar_geometry(pr, xyz, e, mach, p1):
    """k-independent kernel geometry of receivers ``pr`` (rows, 3) against the station points
    ``xyz`` (points, 3) of half-widths ``e``, all pairs planar: the arrays of
    :class:`asekit.aero.dlm._PlanarChunk` in one pass ([R71] Eqs. 4, 7, 10-12, 15).

    Returns (rows, points) arrays exp(-p1 |u1|), sgn(u1) r1^2, gc = sgn(u1) (1 - |u1| /
    sqrt(1 + u1^2)) + M r1 / (R sqrt(1 + u1^2)), r1, the phase x0 + r1 u1, 2 [u1 < 0],
    r1 ~ 0 (r1 <= 1e-12 e: receiver on the doublet line; r1 and r1^2 are then 0) and
    K10 = -1 - x0 / R.
    """
    rows = pr.shape[0]
    nq = xyz.shape[0]
    beta2 = 1.0 - mach * mach
    e1s = np.empty((rows, nq))
    sgn_r1sq = np.empty((rows, nq))
    gc = np.empty((rows, nq))
    r1o = np.empty((rows, nq))
    phase = np.empty((rows, nq))
    neg2 = np.empty((rows, nq))
    small = np.empty((rows, nq), np.bool_)
    k10 = np.empty((rows, nq))
    for i in range(rows):
        for q in range(nq):
            x0 = pr[i, 0] - xyz[q, 0]                    # xbar - eta tan(Lambda)
            dy = pr[i, 1] - xyz[q, 1]
            dz = pr[i, 2] - xyz[q, 2]
            r1sq = dy * dy + dz * dz                     # r1^2, [R71] Eq. 4
            big_r = math.sqrt(x0 * x0 + beta2 * r1sq)    # R, Eq. 10
            r1 = math.sqrt(r1sq)
            sm = r1 <= 1e-12 * e[q]
            if sm:
                r1 = 1.0
                if big_r <= 0.0:
                    big_r = 1.0
            t = mach * big_r - x0
            u1 = 0.0 if sm else t / (r1 * beta2)         # u1, Eq. 11
            u1 += 0.0                                    # no -0.0
            k10[i, q] = -(x0 / big_r + 1.0)              # K10, Eq. 15
            sq = math.sqrt(u1 * u1 + 1.0)
            c1 = mach * r1 / (big_r * sq)
            absu = abs(u1)
            gc[i, q] = math.copysign(1.0 - absu / sq, u1) + c1
            neg2[i, q] = 2.0 if u1 < 0.0 else 0.0
            if sm:
                r1 = 0.0
                r1sq = 0.0
            small[i, q] = sm
            r1o[i, q] = r1
            sgn_r1sq[i, q] = math.copysign(r1sq, u1)
            phase[i, q] = t / beta2 + x0                  # k1 u1 + kd x0 = kd * phase
            e1s[i, q] = math.exp(-p1 * absu)
    return e1s, sgn_r1sq, gc, r1o, phase, neg2, small, k10
