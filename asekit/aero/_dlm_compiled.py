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
the numpy path to rounding (tests/aero/test_dlm_compiled.py).
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, error_model="numpy", nogil=True)
def planar_increment(kd, e1s, sgn_r1sq, gc, r1, phase, neg2, k10, xr, xq, r_local, yz_class,
                     r1sq_groups, index_t, t1w, p_n, a_n, desmarais, out):
    """D1 of an all-planar row chunk at omega / U = kd (1/m), added into ``out`` (rows,
    senders) complex (zeros, or the rows of D already holding D0).

    Arrays (rows, points) from :func:`planar_geometry`: exp(-p_1 |u1|), sgn(u1) r1^2, gc, r1,
    the phase x0 + r1 u1, 2 [u1 < 0] and K10 (receivers on the doublet line are encoded there
    so that the same expression gives their limit); xr (rows,), xq (points,) streamwise
    coordinates; r1^2 per (receiver group, point group) ``r1sq_groups`` with the groups
    ``r_local`` (rows,) and ``yz_class`` (points,); index_t (stations, senders) point of each
    station; t1w (stations, rows, senders); p_n, a_n the exponents and coefficients of the
    kernel series (at most 12); ``desmarais``: p_n = 2^n b (powers by squaring) rather than
    n c.

    r1, and so k1 = kd r1, depends on the (y, z) groups only: the factors a_n / (p_n^2 + k1^2)
    and Re I1(0) are tabulated per point for each receiver group (no division per pair), and
    e^(-i kd x0) = e^(-i kd x_r) e^(i kd x_q) from per-row and per-point values; the steady
    part K10 is added per point before the gather, D1 = sum_j T1 W1_j (-K1_j e_j + K10_j).
    The series runs over 12 terms (Laschka's 11 plus a zero term) and the loop over the points
    has no branch. (A branch-free polynomial sine and cosine in place of libm's was tried: 2.44
    against 2.50 s CPU for a 15-k sweep at 1200 boxes, not worth its code.)
    """
    rows, nq = e1s.shape
    nst, ns = index_t.shape
    nterm = p_n.size
    kd2 = kd * kd
    a = np.zeros(12)
    p = np.ones(12)                                      # the zero term: a = 0, p = 1
    a[:nterm] = a_n
    p[:nterm] = p_n
    cq = np.empty(nq)
    sq = np.empty(nq)
    for q in range(nq):
        cq[q] = math.cos(kd * xq[q])
        sq[q] = math.sin(kd * xq[q])
    # a_n / (p_n^2 + k1^2) and Re I1(0) per (receiver group, point group) ([R71] Eq. A.5 at
    # u = 0), expanded to the points of a receiver group when the group changes
    ngr, ngq = r1sq_groups.shape
    inv_g = np.empty((ngr, 12, ngq))
    re0_g = np.empty((ngr, ngq))
    for g in range(ngr):
        for h in range(ngq):
            k1sq = kd2 * r1sq_groups[g, h]
            acc = 0.0
            for n in range(12):
                v = a[n] / (k1sq + p[n] * p[n])
                inv_g[g, n, h] = v
                acc += v
            re0_g[g, h] = 1.0 - k1sq * acc
    inv = np.empty((12, nq))
    re0 = np.empty(nq)
    fr = np.empty(nq)
    fi = np.empty(nq)
    g_prev = -1
    for i in range(rows):
        g = r_local[i]
        if g != g_prev:
            for n in range(12):
                for q in range(nq):
                    inv[n, q] = inv_g[g, n, yz_class[q]]
            for q in range(nq):
                re0[q] = re0_g[g, yz_class[q]]
            g_prev = g
        cr = math.cos(kd * xr[i])
        sr = math.sin(kd * xr[i])
        for q in range(nq):
            e_1 = e1s[i, q]
            e_n = e_1
            t = e_n * inv[0, q]
            s1 = t
            sp = t * p[0]
            for n in range(1, 12):                       # e^(-p_n u) = e^(-p_(n-1) u) x ...
                e_n = e_n * (e_n if desmarais else e_1)
                t = e_n * inv[n, q]
                s1 += t
                sp += t * p[n]
            re = gc[i, q] - (kd2 * sgn_r1sq[i, q]) * s1     # sgn Re A + c1
            im = -kd * r1[i, q] * sp                         # Im A = -k1 s_p
            x = kd * phase[i, q]
            c = math.cos(x)
            s = math.sin(x)
            vr = re * c + im * s
            vi = im * c - re * s
            # + 2 [u1 < 0] Re I1(0) e^(-i kd x0), e^(-i kd x0) = (cr cq + sr sq) - i (...)
            r0 = re0[q] * neg2[i, q]
            vr += r0 * (cr * cq[q] + sr * sq[q])
            vi -= r0 * (sr * cq[q] - cr * sq[q])
            fr[q] = vr + k10[i, q]
            fi[q] = vi
        # gather the stations of every sender (index_t: (stations, senders)), unrolled for
        # the 5 (quartic) and 3 (parabolic) stations so that the sender loop vectorises
        if nst == 5:
            for s_ in range(ns):
                q0, q1, q2, q3, q4 = (index_t[0, s_], index_t[1, s_], index_t[2, s_],
                                      index_t[3, s_], index_t[4, s_])
                w0, w1, w2, w3, w4 = (t1w[0, i, s_], t1w[1, i, s_], t1w[2, i, s_],
                                      t1w[3, i, s_], t1w[4, i, s_])
                accr = fr[q0] * w0 + fr[q1] * w1 + fr[q2] * w2 + fr[q3] * w3 + fr[q4] * w4
                acci = fi[q0] * w0 + fi[q1] * w1 + fi[q2] * w2 + fi[q3] * w3 + fi[q4] * w4
                out[i, s_] += complex(accr, acci)
        elif nst == 3:
            for s_ in range(ns):
                q0, q1, q2 = index_t[0, s_], index_t[1, s_], index_t[2, s_]
                w0, w1, w2 = t1w[0, i, s_], t1w[1, i, s_], t1w[2, i, s_]
                accr = fr[q0] * w0 + fr[q1] * w1 + fr[q2] * w2
                acci = fi[q0] * w0 + fi[q1] * w1 + fi[q2] * w2
                out[i, s_] += complex(accr, acci)
        else:
            for s_ in range(ns):
                accr = 0.0
                acci = 0.0
                for j in range(nst):
                    w = t1w[j, i, s_]
                    q = index_t[j, s_]
                    accr += fr[q] * w
                    acci += fi[q] * w
                out[i, s_] += complex(accr, acci)


@numba.njit(cache=True, error_model="numpy", nogil=True)
def planar_geometry(pr, xyz, e, mach, p1):
    """k-independent kernel geometry of receivers ``pr`` (rows, 3) against the station points
    ``xyz`` (points, 3) of half-widths ``e``, all pairs planar: the arrays of
    :class:`asekit.aero.dlm._PlanarChunk` in one pass ([R71] Eqs. 4, 7, 10-12, 15).

    Returns (rows, points) arrays exp(-p1 |u1|), sgn(u1) r1^2, gc = sgn(u1) (1 - |u1| /
    sqrt(1 + u1^2)) + M r1 / (R sqrt(1 + u1^2)), r1, the phase x0 + r1 u1, 2 [u1 < 0] and
    K10 = -1 - x0 / R. A receiver on the doublet line (r1 <= 1e-12 e) gets r1 = sgn r1^2 =
    [u1 < 0] = 0, gc = 2 [x0 >= 0] and the phase x0, so that :func:`planar_increment`'s
    expression gives the limit -K1 e^(-i kd x0) = 2 e^(-i kd x0) downstream, 0 upstream
    ([R71]).
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
            r1o[i, q] = r1
            sgn_r1sq[i, q] = math.copysign(r1sq, u1)
            phase[i, q] = t / beta2 + x0                  # k1 u1 + kd x0 = kd * phase
            e1s[i, q] = math.exp(-p1 * absu)
            if sm:            # r1 -> 0: -K1 e^(-i kd x0) = 2 e^(-i kd x0) downstream, 0 up
                r1o[i, q] = 0.0
                sgn_r1sq[i, q] = 0.0
                gc[i, q] = 2.0 if x0 >= 0.0 else 0.0
                phase[i, q] = x0
                neg2[i, q] = 0.0
    return e1s, sgn_r1sq, gc, r1o, phase, neg2, k10


@numba.njit(cache=True, error_model="numpy", nogil=True)
def horseshoe_normalwash(p, n_r, v, ia, ib, scale, weight, out):
    """Add to ``out`` (m, s) the normal velocity at points ``p`` (m, 3) along normals ``n_r``
    induced by horseshoe vortices inf -> a -> b -> inf (a = v[ia], b = v[ib], legs along +x),
    times ``weight`` (s,): the loop form of :func:`asekit.aero.vlm._horseshoe_normalwash`
    (Katz & Plotkin Eq. 10.115 for the bound segment, the semi-infinite legs per corner;
    points on a vortex line receive zero from that segment)."""
    m = p.shape[0]
    nv = v.shape[0]
    ns = ia.size
    eps = (1e-10 * scale) ** 2
    rx = np.empty(nv)
    ry = np.empty(nv)
    rz = np.empty(nv)
    nrm = np.empty(nv)
    leg = np.empty(nv)
    c4 = 1.0 / (4.0 * np.pi)
    for i in range(m):
        ny = n_r[i, 1]
        nz = n_r[i, 2]
        for q in range(nv):
            x = p[i, 0] - v[q, 0]
            y = p[i, 1] - v[q, 1]
            z = p[i, 2] - v[q, 2]
            d2 = y * y + z * z
            r = math.sqrt(x * x + d2)
            if r == 0.0:
                r = 1.0
            rx[q] = x
            ry[q] = y
            rz[q] = z
            nrm[q] = r
            # leg from corner q to +inf: (x_hat x r) / |x_hat x r|^2 (1 + r_x / |r|)
            leg[q] = (x / r + 1.0) / d2 * (y * nz - z * ny) if d2 > eps else 0.0
        for s in range(ns):
            a = ia[s]
            b = ib[s]
            r1x, r1y, r1z, n1 = rx[a], ry[a], rz[a], nrm[a]
            r2x, r2y, r2z, n2 = rx[b], ry[b], rz[b], nrm[b]
            r0x = v[b, 0] - v[a, 0]
            r0y = v[b, 1] - v[a, 1]
            r0z = v[b, 2] - v[a, 2]
            cx = r1y * r2z - r1z * r2y
            cy = r1z * r2x - r1x * r2z
            cz = r1x * r2y - r1y * r2x
            c2 = cx * cx + cy * cy + cz * cz
            w = 0.0
            if c2 > eps:
                fac = ((r0x * r1x + r0y * r1y + r0z * r1z) / n1
                       - (r0x * r2x + r0y * r2y + r0z * r2z) / n2)
                w = fac / c2 * (cy * ny + cz * nz)
            w += leg[b]
            w -= leg[a]
            out[i, s] += (w * c4) * weight[s]
