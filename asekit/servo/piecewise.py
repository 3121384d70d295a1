"""Exact propagation of the servo loop with its power limits: x' = F x + g V(x), where the
applied voltage V = clip(clip(V_cmd, lo1, hi1), lo2, hi2) is piecewise affine in the state (the
current limit of Eqs. 4.14-4.15 and the supply clip, thesis Sec. 4). Between region changes the
flow is linear and is propagated with the matrix exponential; region changes are located
(Hermite interpolation of the step, then bisection). Used by the rigid-fin simulation
(:mod:`asekit.servo.simulate`) and the aeroservoelastic loop (:mod:`asekit.ase.loop`)."""

from __future__ import annotations

import math

import numpy as np


def voltage_bounds(actuator, limits, n: int) -> list:
    """The limits of :func:`asekit.servo.simulate.applied_voltage` as affine functions of the state
    (row, constant): V = clip(clip(V_cmd, lo1, hi1), lo2, hi2) with, in order, the current
    limit (voltage clip +-I_lim R, Eqs. 4.14-4.15; or the regulator's bounds
    +-(R + L/tau) I_lim + K_b N omega - (L/tau) I) and the supply clip +-V_s. Absent limits are
    None. Returns [lo1, hi1, lo2, hi2]."""
    m, N = actuator.motor, actuator.transmission.ratio
    zero = np.zeros(n)
    lo1 = hi1 = lo2 = hi2 = None
    if limits.current_limit is not None:
        il = limits.current_limit
        if limits.current_limit_model == "voltage_clip":
            lo1, hi1 = (zero, -il * m.resistance), (zero, il * m.resistance)
        else:
            gain = m.inductance / limits.current_loop_time_constant
            row = zero.copy()
            row[1], row[2] = m.back_emf_constant * N, -gain
            lo1, hi1 = (row, -(m.resistance + gain) * il), (row, (m.resistance + gain) * il)
    if limits.supply_voltage is not None:
        vs = limits.supply_voltage
        lo2, hi2 = (zero, -vs), (zero, vs)
    return [lo1, hi1, lo2, hi2]


_TAU = np.linspace(0.0, 1.0, 33)[1:-1]
_H00, _H10 = 2 * _TAU**3 - 3 * _TAU**2 + 1, _TAU**3 - 2 * _TAU**2 + _TAU
_H01, _H11 = -2 * _TAU**3 + 3 * _TAU**2, _TAU**3 - _TAU**2


class PiecewiseAffineLoop:
    """x' = F x + g V(x) with the applied voltage V(x) = clip(clip(u(x), lo1, hi1), lo2, hi2),
    every piece affine in x: u the demand (row k, constant k0; for a held demand row 0,
    constant V_k), the bounds of :func:`voltage_bounds`. In the region where piece a is the
    applied voltage the loop is linear, x' = (F + g r_a) x + g c_a, and is propagated exactly
    over a step h by the matrix exponential of the augmented matrix (Van Loan 1978, "Computing
    integrals involving the matrix exponential", IEEE TAC 23(3); the ZOH discretisation):

        expm([[F + g r_a, g], [0, 0]] h) = [[Phi_a, Gamma_a], [0, 1]],
        x(t + h) = Phi_a x(t) + Gamma_a c_a,

    computed once per (region, step length). V(x) is continuous, so x' is continuous where the
    region changes; a change can only happen where two pieces are equal, so every difference
    of two pieces is watched: a sign change over a step (or an interior extremum through zero,
    found by cubic Hermite interpolation of the difference and confirmed exactly) is located
    by Brent's method on the exact solution, and the step resumes there in the new region."""

    def __init__(self, F, g, demand_row, bounds):
        self.F, self.g = F, g
        self.n = F.shape[0]
        rows = [np.asarray(demand_row, float)] + [b[0] if b is not None else None
                                                  for b in bounds]
        self.present = [0] + [i + 1 for i, b in enumerate(bounds) if b is not None]
        self.rows = rows
        self.bounds = bounds
        self.const = np.zeros(5)
        for i, b in enumerate(bounds):
            if b is not None:
                self.const[i + 1] = b[1]
        pairs = [(i, j) for ii, i in enumerate(self.present) for j in self.present[ii + 1:]]
        # pairs whose difference can change within a step (a row); constant ones cannot
        self.pairs = [(i, j) for i, j in pairs if np.any(rows[i] != rows[j])]
        self.Dm = (np.array([rows[i] - rows[j] for i, j in self.pairs])
                   if self.pairs else np.zeros((0, self.n)))
        self.absDm = np.abs(self.Dm)
        self.M = {a: F + np.outer(g, rows[a]) for a in self.present}
        self.DmM = {a: self.Dm @ self.M[a] for a in self.present}
        self.Dmg = self.Dm @ g
        self._maps = {}

    def set_demand_constant(self, c0: float):
        self.const[0] = c0

    def dconst(self):
        return np.array([self.const[i] - self.const[j] for i, j in self.pairs])

    def values(self, X):
        """Every present piece at the states X (n,) or (n, q): dict a -> values."""
        return {a: self.rows[a] @ X + self.const[a] for a in self.present}

    def active(self, x) -> int:
        """Index of the piece that is the applied voltage at x (the order of
        :func:`asekit.servo.simulate.applied_voltage`: current limit, then supply)."""
        val = self.values(x)
        a, v = 0, val[0]
        for lo, hi in ((1, 2), (3, 4)):
            if lo in val and v < val[lo]:
                a, v = lo, val[lo]
            if hi in val and v > val[hi]:
                a, v = hi, val[hi]
        return a

    def applied(self, X, demand=None):
        """The applied voltage at the states X (n, q), vectorised; ``demand`` (q,) replaces
        the demand piece's values."""
        val = self.values(X)
        if demand is not None:
            val[0] = np.asarray(demand, float)
        v = np.array(val[0], float, copy=True)
        for lo, hi in ((1, 2), (3, 4)):
            if lo in val:
                v = np.where(v < val[lo], val[lo], v)
            if hi in val:
                v = np.where(v > val[hi], val[hi], v)
        return v

    def _expm(self, a, h):
        from scipy.linalg import expm
        n = self.n
        E = np.zeros((n + 1, n + 1))
        E[:n, :n] = self.M[a] * h
        E[:n, n] = self.g * h
        E = expm(E)
        return E[:n, :n], E[:n, n]

    def maps(self, a, h, key):
        k = (a, key)
        if k not in self._maps:
            self._maps[k] = self._expm(a, h)
        return self._maps[k]

    def xdot(self, a, x):
        return self.M[a] @ x + self.g * self.const[a]

    def _signs(self, D, R, dc, X, just):
        """Reference signs of the piece differences D (q, p) at the states X (q, n): the sign
        of the difference, or of its rate R where it is zero to round-off (on a boundary) and
        for the pair ``just`` crossed at the first state (its direction)."""
        tiny = 1e-13 * (1.0 + np.abs(dc) + np.abs(X) @ self.absDm.T)
        S = np.where(np.abs(D) > tiny, np.sign(D), np.sign(R))
        if just >= 0:
            S[0, just] = np.sign(R[0, just])
        return S

    def _suspect(self, S0, D0, D1, R0, R1, h):
        """(q, p) flags of the steps that may change region: a sign change of a piece
        difference, or an interior extremum toward zero whose cubic Hermite interpolant
        passes zero (confirmed exactly by :meth:`step`)."""
        cross = (S0 != 0) & (np.sign(D1) == -S0)
        ext = (S0 * R0 < 0) & (S0 * R1 > 0) & ~cross
        if ext.any():
            q, p = np.nonzero(ext)
            dh = (np.outer(D0[q, p], _H00) + np.outer(h * R0[q, p], _H10)
                  + np.outer(D1[q, p], _H01) + np.outer(h * R1[q, p], _H11))
            hit = np.min(S0[q, p][:, None] * dh, axis=1) < 0
            cross = cross.copy()
            cross[q[hit], p[hit]] = True
        return cross

    def powers(self, a, h, key, K):
        """Stacked Phi_a^j (K n, n) and sum_{i<j} Phi_a^i Gamma_a (K, n), j = 1..K: K steps
        of one region in one product."""
        k = ("powers", a, key)
        if k not in self._maps or self._maps[k][1].shape[0] < K:
            Phi, Gam = self.maps(a, h, key)
            n = self.n
            P = np.empty((K, n, n))
            G = np.empty((K, n))
            P[0], G[0] = Phi, Gam
            for j in range(1, K):
                P[j] = Phi @ P[j - 1]
                G[j] = Phi @ G[j - 1] + Gam
            self._maps[k] = (P.reshape(K * n, n), G)
        P, G = self._maps[k]
        return P[:K * self.n], G[:K]

    def block(self, x, a, h, key, K, just=-1):
        """Up to K steps of h from x in region a at once: returns the states (k, n) of the
        first k steps in which no piece difference may change sign (k = K if none)."""
        P, G = self.powers(a, h, key, K)
        c = self.const[a]
        Xb = (P @ x).reshape(K, self.n) + G * c
        if not self.pairs:
            return Xb
        Xa = np.vstack([x, Xb])
        dc = self.dconst()
        D = Xa @ self.Dm.T + dc
        R = Xa @ self.DmM[a].T + self.Dmg * c
        S = self._signs(D, R, dc, Xa, just)
        bad = self._suspect(S[:-1], D[:-1], D[1:], R[:-1], R[1:], h).any(axis=1)
        return Xb[:int(np.argmax(bad))] if bad.any() else Xb

    def _at(self, a, x, c, t):
        """The exact state at t in region a from x, and its rate."""
        P_, G_ = self._expm(a, t)
        xt = P_ @ x + G_ * c
        return xt, self.xdot(a, xt)

    def _root(self, a, x, c, p, dcp, lo, flo, rlo, hi, fhi, rhi, tol):
        """Zero of the piece difference p on the exact solution in [lo, hi] (values flo, fhi
        of opposite signs and rates rlo, rhi at the ends): started at the zero of the cubic
        Hermite interpolant, then Newton's method with the exact rate, kept inside the bracket
        (bisection when it leaves it). Returns (t, x(t)), |t - root| <= tol."""
        w = hi - lo
        u = flo / (flo - fhi)                       # secant guess, then Newton on the cubic
        for _ in range(8):
            hv = (((2 * u - 3) * u) * u + 1) * flo + ((u - 2) * u + 1) * u * w * rlo \
                + ((3 - 2 * u) * u * u) * fhi + ((u - 1) * u * u) * w * rhi
            dv = ((6 * u - 6) * u) * flo + ((3 * u - 4) * u + 1) * w * rlo \
                + ((6 - 6 * u) * u) * fhi + ((3 * u - 2) * u) * w * rhi
            if dv == 0:
                break
            u_new = min(max(u - hv / dv, 0.0), 1.0)
            if abs(u_new - u) < 1e-15:
                break
            u = u_new
        t = lo + u * w
        xt = None
        for _ in range(60):
            xt, xd = self._at(a, x, c, t)
            f, fp = self.Dm[p] @ xt + dcp, self.Dm[p] @ xd
            if f == 0.0:
                return t, xt
            if np.sign(f) == np.sign(flo):
                lo, flo = t, f
            else:
                hi, fhi = t, f
            t_new = t - f / fp if fp != 0 else 0.5 * (lo + hi)
            if not lo < t_new < hi:
                t_new = 0.5 * (lo + hi)
            if abs(t_new - t) <= tol or hi - lo <= tol:
                return t, xt          # within tol of the root: the state is exact at t
            t = t_new
        return t, xt

    def step(self, x, a, h, key, just=-1, max_events: int = 200):
        """Advance x (in region a) exactly by h, locating every change of region; returns
        (x(h), region at the end, index of the last pair crossed or ``just``)."""
        if not self.pairs:
            Phi, Gam = self.maps(a, h, key)
            return Phi @ x + Gam * self.const[a], a, just
        dc = self.dconst()
        rem, full = h, True
        for _ in range(max_events):
            Phi, Gam = self.maps(a, h, key) if full else self._expm(a, rem)
            c = self.const[a]
            x1 = Phi @ x + Gam * c
            xd0, xd1 = self.xdot(a, x), self.xdot(a, x1)
            d0, d1 = self.Dm @ x + dc, self.Dm @ x1 + dc
            r0, r1 = self.Dm @ xd0, self.Dm @ xd1
            s0 = self._signs(d0[None], r0[None], dc, x[None], just)[0]
            crossed = (s0 != 0) & (np.sign(d1) == -s0)
            cand = [(p, rem, d1[p], r1[p]) for p in np.nonzero(crossed)[0]]
            ext = self._suspect(s0[None], d0[None], d1[None], r0[None], r1[None], rem)[0]
            for p in np.nonzero(ext & ~crossed)[0]:
                # interior extremum toward zero: confirm at the Hermite interpolant's extreme
                dh = (_H00 * d0[p] + _H10 * rem * r0[p] + _H01 * d1[p]
                      + _H11 * rem * r1[p])
                tm = _TAU[int(np.argmin(s0[p] * dh))] * rem
                xm, xdm = self._at(a, x, c, tm)
                fm = self.Dm[p] @ xm + dc[p]
                if np.sign(fm) == -s0[p]:
                    cand.append((p, tm, fm, self.Dm[p] @ xdm))
            if not cand:
                return x1, a, just
            best = None
            for p, tb, fb, rb in cand:
                # the start value on the side of its reference sign (zero on a boundary)
                f0 = d0[p] if np.sign(d0[p]) == s0[p] else s0[p] * 1e-300
                tr, xr = self._root(a, x, c, p, dc[p], 0.0, f0, r0[p], tb, fb, rb,
                                    1e-13 * h)
                if best is None or tr < best[1]:
                    best = (p, tr, xr)
            p, tr, x = best
            xd = self.xdot(a, x)
            a = self.active(x + 1e-8 * h * xd)       # the region the flow enters
            just = p
            rem -= tr
            full = False
            if rem <= 1e-13 * h:
                return x, a, just
        raise RuntimeError(f"more than {max_events} region changes of the power limits within "
                           f"one output step of {h:g} s: refine n_out")


def propagate_exact(mats: dict, bounds: list, controller, command: float, t_out, x0,
                    sample_time: float | None = None):
    """Exact propagation of x' = F x + g V(x) (:class:`PiecewiseAffineLoop`) from x0 over the
    grid ``t_out`` (uniform, from 0): ``mats`` as :func:`_loop_matrices` (F, g, k, k0, fb_row,
    om_row), ``bounds`` as :func:`voltage_bounds`. The demand is the continuous PD
    V_cmd = k x + k0, or with ``sample_time`` the ZOH digital PD ``controller.voltage(command -
    y_k, -(y_k - y_k-1) / T)`` of the sampled feedback y = fb_row x (the first backward
    difference consistent with the initial rate om_row x0). Returns (x (n, n_out), V_cmd
    (n_out,))."""
    F, g = mats["F"], mats["g"]
    n = F.shape[0]
    t_final = float(t_out[-1])
    if sample_time is None:
        loop = PiecewiseAffineLoop(F, g, mats["k"], bounds)
        loop.set_demand_constant(mats["k0"])
        times = t_out
        samples = np.zeros(t_out.size, bool)
    else:
        loop = PiecewiseAffineLoop(F, g, np.zeros(n), bounds)
        n_samples = int(math.ceil(t_final / sample_time - 1e-9))
        ts = np.arange(n_samples) * sample_time
        merged = np.concatenate([t_out, ts])
        order = np.argsort(merged, kind="stable")
        merged = merged[order]
        tol = 1e-9 * min(sample_time, t_final / max(t_out.size - 1, 1))
        keep = np.concatenate([[True], np.diff(merged) > tol])
        times = merged[keep]
        samples = np.zeros(times.size, bool)
        samples[np.clip(np.searchsorted(times, ts - tol), 0, times.size - 1)] = True
    out_idx = np.clip(np.searchsorted(times, t_out - 1e-9 * t_final / max(t_out.size, 1)),
                      0, times.size - 1)
    X = np.empty((n, times.size))
    x = x0.astype(float).copy()
    X[:, 0] = x
    fb = mats["fb_row"]
    y_prev = None
    v_hold = []                                    # the held demand of each sample
    scale = 2.0 ** 40 / t_final
    hs = np.diff(times)
    keys = np.round(hs * scale).astype(np.int64)
    # index of the next sample instant (or the end) after each grid point
    nxt = np.full(times.size, times.size - 1)
    idx_s = np.nonzero(samples)[0]
    if idx_s.size:
        pos = np.searchsorted(idx_s, np.arange(times.size), side="right")
        has = pos < idx_s.size
        nxt[has] = idx_s[pos[has]]
    a, just, i, sampled = None, -1, 0, -1
    while i < times.size - 1:
        if samples[i] and sampled != i:
            sampled = i
            y = float(fb @ x)
            if y_prev is None:
                # at rest: consistent with the initial feedback rate (as _integrate_zoh)
                y_prev = y - float(mats["om_row"] @ x) * sample_time
            v_k = float(controller.voltage(command - y, -(y - y_prev) / sample_time))
            y_prev = y
            v_hold.append(v_k)
            loop.set_demand_constant(v_k)
            a, just = None, -1
        if a is None:
            a = loop.active(x)
            a = loop.active(x + 1e-12 * t_final * loop.xdot(a, x))
        # a block of equal steps up to the next sample instant, then one located step
        stop = int(nxt[i])
        j, j_max = i, min(stop, i + 256)
        while j < j_max and keys[j] == keys[i]:
            j += 1
        K = min(j - i, 256)
        if K >= 2:
            Xb = loop.block(x, a, float(hs[i]), int(keys[i]), K, just)
            if len(Xb):
                X[:, i + 1:i + 1 + len(Xb)] = Xb.T
                i += len(Xb)
                x = Xb[-1]
                just = -1
                if len(Xb) == K:
                    continue
        if i >= times.size - 1:
            break
        if samples[i] and sampled != i:
            continue                               # a sample instant: update the demand first
        x, a, just = loop.step(x, a, float(hs[i]), int(keys[i]), just)
        i += 1
        X[:, i] = x
    x_out = X[:, out_idx]
    if sample_time is None:
        v_out = mats["k"] @ x_out + mats["k0"]
    else:
        # the demand held at each output time (t in [t_k, t_k+1) belongs to sample k, as
        # _integrate_zoh; the last sample keeps t_final)
        k_out = np.clip(np.searchsorted(ts, t_out, side="right") - 1, 0, len(ts) - 1)
        v_out = np.asarray(v_hold)[k_out]
    return x_out, v_out
