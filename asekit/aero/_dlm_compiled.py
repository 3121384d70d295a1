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
def planar_increment(kd, e1s, sgn_r1sq, gc, r1, phase, neg2, small, xr, xq, r_local, yz_class,
                     r1sq_groups, index, t1w, k10_sum, p_n, a_n, desmarais, out):
    """D1 of an all-planar row chunk at omega / U = kd (1/m), written into ``out`` (rows,
    senders) complex.

    Arrays (rows, points): exp(-p_1 |u1|) (k-independent, computed once per chunk), sgn(u1) r1^2, gc, r1, the phase x0 + r1 u1, 2 [u1 < 0],
    r1 ~ 0 (bool); xr (rows,), xq (points,) streamwise coordinates; r1^2 per (receiver
    group, point group) ``r1sq_groups`` with the groups ``r_local`` (rows,) and ``yz_class``
    (points,); index (senders, stations) point of each station; t1w (stations, rows, senders);
    k10_sum (rows, senders); p_n, a_n the exponents and coefficients of the kernel series;
    ``desmarais``: p_n = 2^n b (powers by squaring) rather than n c.

    r1, and so k1 = kd r1, depends on the (y, z) groups only: the factors a_n / (p_n^2 +
    k1^2) and Re I1(0) are tabulated per group pair (no division per pair), and
    e^(-i kd x0) = e^(-i kd x_r) e^(i kd x_q) from per-row and per-point values.
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
                fr[q] = down * cx
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
            fr[q] = vr
            fi[q] = vi
        for s_ in range(ns):
            accr = k10_sum[i, s_]
            acci = 0.0
            for j in range(nst):
                w = t1w[j, i, s_]
                q = index[s_, j]
                accr += fr[q] * w
                acci += fi[q] * w
            out[i, s_] = complex(accr, acci)
