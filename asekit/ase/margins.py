"""Stability margins from the Nyquist criterion, open-loop unstable poles counted.

Classical gain and phase margins read off a Bode plot (``control.stability_margins``, and
:func:`asekit.ase.loop.crossovers`) assume a stable open loop. With an open-loop pole in the right
half plane (the fin's de-centering hinge moment gives OPLOOP 2/3 one at +15.5 rad/s) the
closed loop can be stable only for gains *above* some value, and that lower gain margin sits
where the Nyquist curve meets the negative real axis — for FWTF 2 at zero frequency, where no
Bode-plot phase crossover exists.

:func:`nyquist_margins` evaluates the Nyquist criterion for the negative-feedback loop
``1 + k L(s) = 0`` for every gain ``k > 0`` at once:

    Z(k) = P - N(k)                                                             (1)

with P the open-loop poles in the open right half plane, N(k) the net counter-clockwise
encirclements of -1/k by L(s) along the Nyquist contour (up the imaginary axis, indented to the
right around poles at the origin, closed through the right half plane), and Z(k) the closed-loop
poles in the right half plane [Nyquist 1932; Astrom & Murray, *Feedback Systems*, 2nd ed. 2021,
Sec. 10.2, Theorem 10.3 (Nyquist criterion) and its extension to open-loop unstable systems].
N(k) is counted from the signed crossings of the ray (-inf, -1/k) by the curve: a crossing at
frequency w_i with L(j w_i) = x_i < 0 lies on that ray exactly when k > k_i = -1/x_i, so N(k) is
a step function of k that changes only at the k_i, and the closed loop's stability can change
only there (closed-loop poles cross the imaginary axis, at j w_i). By the conjugate symmetry of
L(j w), a crossing at 0 < w_i < inf counts twice (once for -w_i), the end points w = 0 and
w = inf once; the indentation around n poles at the origin maps to an arc of n half-turns at
infinity (L ~ c/s^n), clockwise.

The gain margins are the ends of the range of k containing k = 1 in which Z(k) = 0: the lower
gain margin k_lo < 1 (0 when none: the loop is stable down to zero gain) and the upper k_hi > 1
(inf when none); in dB, 20 log10 k (lower negative). As a guard against a frequency grid too
coarse to see a crossing, Z(1) from (1) is compared with the eigenvalues of the closed loop;
a mismatch raises RuntimeError.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np
from scipy.optimize import brentq

__all__ = ["NyquistMargins", "nyquist_margins"]


@dataclass(frozen=True)
class NyquistMargins:
    """Margins of the negative-feedback loop ``1 + k L(s)`` (k = 1 nominal), Nyquist-counted.

    Attributes
    ----------
    open_loop_unstable_poles : P, open-loop poles with Re > 0 (the poles themselves in
        ``open_loop_rhp_poles``, rad/s).
    origin_poles : open-loop poles at s = 0 (integrators; the contour passes them on the right).
    closed_loop_unstable_poles : Z(1), closed-loop poles with Re > 0 at the nominal gain.
    boundary_gains : the gains k_i > 0 at which Z(k) can change, ascending (linear).
    unstable_counts : Z(k) on each of the len(boundary_gains) + 1 intervals between them.
    lower_gain_margin, upper_gain_margin : ends (linear gain factors) of the interval of k that
        contains 1 with Z = 0; 0 / inf when unbounded; None when the nominal loop is unstable.
    gain_crossovers_hz, phase_margins_deg : every |L| = 1 frequency and the phase margin there,
        180 deg + arg L wrapped to (-180, 180].
    phase_crossovers_hz, gain_margins_db : every negative-real-axis crossing (including
        w = 0 and w = inf when L is real and negative there) and -20 log10 |L| at it.
    """

    open_loop_unstable_poles: int
    open_loop_rhp_poles: np.ndarray
    origin_poles: int
    closed_loop_unstable_poles: int
    boundary_gains: np.ndarray
    unstable_counts: tuple
    lower_gain_margin: float | None
    upper_gain_margin: float | None
    gain_crossovers_hz: np.ndarray
    phase_margins_deg: np.ndarray
    phase_crossovers_hz: np.ndarray
    gain_margins_db: np.ndarray

    @property
    def open_loop_unstable(self) -> bool:
        """True when the open loop has a pole in the open right half plane."""
        return self.open_loop_unstable_poles > 0

    @property
    def closed_loop_stable(self) -> bool:
        """True when the nominal (k = 1) closed loop has no right-half-plane pole."""
        return self.closed_loop_unstable_poles == 0

    @property
    def lower_gain_margin_db(self) -> float | None:
        """20 log10 of the lower gain margin (dB, <= 0; -inf when stable down to k = 0)."""
        g = self.lower_gain_margin
        return None if g is None else (-math.inf if g == 0 else 20 * math.log10(g))

    @property
    def upper_gain_margin_db(self) -> float | None:
        """20 log10 of the upper gain margin (dB, >= 0; inf when stable for every k > 1)."""
        g = self.upper_gain_margin
        return None if g is None else (math.inf if math.isinf(g) else 20 * math.log10(g))

    @property
    def phase_margin_deg(self) -> float:
        """The phase margin of smallest magnitude (deg, sign kept); inf without a gain
        crossover."""
        pm = self.phase_margins_deg
        return float(pm[np.argmin(np.abs(pm))]) if pm.size else math.inf

    def stable_at(self, k: float) -> bool:
        """Whether the closed loop ``1 + k L`` is stable (k > 0, not a boundary gain)."""
        if not (k > 0 and math.isfinite(k)):
            raise ValueError(f"k must be a positive finite gain, got {k!r}")
        return self.unstable_counts[int(np.searchsorted(self.boundary_gains, k))] == 0


def _frequency_grid(poles, zeros, points_per_decade: int):
    """Positive frequencies (rad/s) covering every pole and zero: a log grid two decades beyond
    the smallest and largest nonzero magnitudes, plus dense local grids across every lightly
    damped pole or zero (|Im| +- 30 |Re|), where the phase turns quickly."""
    roots = np.concatenate([poles, zeros])
    mag = np.abs(roots[np.abs(roots) > 1e-9])
    lo = 1e-2 * mag.min() if mag.size else 1e-2
    hi = 1e2 * mag.max() if mag.size else 1e2
    n = max(int(points_per_decade * math.log10(hi / lo)), 200)
    parts = [np.logspace(math.log10(lo), math.log10(hi), n)]
    for r in roots:
        if r.imag > 0 and abs(r.real) < 0.2 * r.imag:
            half = 30 * max(abs(r.real), 1e-6 * r.imag)
            parts.append(np.linspace(max(r.imag - half, lo), r.imag + half, 401))
    return np.unique(np.concatenate(parts))


def nyquist_margins(loop, points_per_decade: int = 400) -> NyquistMargins:
    """Nyquist-counted stability margins of the SISO loop ``loop`` under negative feedback.

    Parameters
    ----------
    loop : control.StateSpace or control.TransferFunction, SISO, continuous time: L(s).
    points_per_decade : density of the frequency grid on which the crossings are bracketed
        (each is then located by Brent's method); the closed-loop eigenvalue check (see module
        docstring) catches a grid too coarse.

    Returns
    -------
    :class:`NyquistMargins` (gains linear, frequencies Hz, angles deg).

    Raises
    ------
    TypeError if ``loop`` is not a continuous-time SISO LTI system; ValueError if it has no
    state, poles on the imaginary axis away from the origin (undamped modes: the margins are
    then not defined) or ``points_per_decade`` < 10; RuntimeError if the Nyquist count
    disagrees with the closed-loop eigenvalues.
    """
    if not isinstance(loop, (ct.StateSpace, ct.TransferFunction)):
        raise TypeError(f"loop must be a control.StateSpace or TransferFunction, got "
                        f"{type(loop).__name__}")
    if loop.ninputs != 1 or loop.noutputs != 1:
        raise TypeError(f"loop must be SISO, got {loop.noutputs}x{loop.ninputs}")
    if not loop.isctime():
        raise TypeError("loop must be continuous time")
    if points_per_decade < 10:
        raise ValueError(f"points_per_decade must be >= 10, got {points_per_decade}")
    ss = ct.ss(loop)
    if ss.nstates == 0:
        raise ValueError("loop must have at least one state (a static gain has no Nyquist "
                         "margins)")
    A, B, C = np.asarray(ss.A), np.asarray(ss.B), np.asarray(ss.C)
    D = float(np.asarray(ss.D).real.ravel()[0])
    poles = np.linalg.eigvals(A) if A.size else np.zeros(0)
    scale = max(1.0, float(np.max(np.abs(poles)))) if poles.size else 1.0
    tol = 1e-9 * scale
    on_axis = np.abs(poles.real) <= tol
    origin = on_axis & (np.abs(poles) <= 1e3 * tol)
    if np.any(on_axis & ~origin):
        w = np.abs(poles[on_axis & ~origin].imag)
        raise ValueError(f"loop has undamped poles on the imaginary axis at +-{w.min():.6g} "
                         "rad/s: the Nyquist margins are not defined")
    n0 = int(np.sum(origin))
    rhp = poles[poles.real > tol]
    P = int(rhp.size)
    zeros = np.asarray(ct.zeros(ss)) if A.size else np.zeros(0)
    zeros = zeros[np.isfinite(zeros)]

    def L(w):
        """L(j w) at the frequencies w (rad/s): C (j w I - A)^-1 B + D, in blocks."""
        w = np.atleast_1d(np.asarray(w, float))
        if not A.size:
            return np.full(w.shape, D, complex)
        n = A.shape[0]
        out = np.empty(w.shape, complex)
        for s in range(0, w.size, 1024):
            wb = w[s:s + 1024]
            m = 1j * wb[:, None, None] * np.eye(n) - A
            x = np.linalg.solve(m, np.broadcast_to(B, (wb.size, n, 1)))
            out[s:s + 1024] = (C @ x)[:, 0, 0] + D
        return out

    w = _frequency_grid(poles, zeros, points_per_decade)
    h = L(w)

    # crossings of the real axis at 0 < w < inf: (w_i, Re L(j w_i), direction)
    crossings = []           # (w, x, ccw weight on the ray when k > -1/x)
    im = h.imag
    # brackets between consecutive grid points of nonzero Im L of opposite signs: a grid point
    # that lands exactly on a crossing (Im L = 0, e.g. w = sqrt(10) of a logspace grid) lies
    # inside its bracket instead of hiding the sign change
    nz = np.nonzero(np.sign(im) != 0)[0]
    for i, j in zip(nz[:-1], nz[1:]):
        if np.sign(im[i]) * np.sign(im[j]) >= 0:
            continue
        wc = brentq(lambda v: L(v)[0].imag, w[i], w[j], xtol=1e-12 * w[i], rtol=1e-12)
        x = L(wc)[0].real
        if x < 0:
            # downward crossing (Im + -> -) of the leftward ray is counter-clockwise: +1;
            # counted twice (w and -w, conjugate symmetry)
            crossings.append((wc, x, 2 * (1 if im[i] > 0 else -1)))
    # w = 0 end point: L(0) finite and real
    if n0 == 0:
        x0 = L(0.0)[0].real
        if x0 < 0 and im[0] != 0:
            crossings.append((0.0, x0, 1 if im[0] < 0 else -1))
    # w = inf end point: L -> D, approached with the sign of Im L at the top of the grid
    if D < 0 and im[-1] != 0:
        crossings.append((math.inf, D, 1 if im[-1] > 0 else -1))
    # the arc around n0 origin poles: arg L turns by -n0 pi from w = -eps to +eps; each pass
    # through the negative real direction (at infinity, on every ray) is clockwise: -1
    arc = 0
    if n0:
        th_e = float(np.angle(h[0]))
        th_s = -th_e
        m = round((th_s - th_e - n0 * math.pi) / (2 * math.pi))
        th_e_path = th_e + 2 * math.pi * m
        lo_, hi_ = min(th_e_path, th_s), max(th_e_path, th_s)
        j = math.ceil((lo_ - math.pi) / (2 * math.pi))
        while math.pi + 2 * math.pi * j < hi_:
            arc -= 1
            j += 1

    gains = np.array(sorted({-1.0 / x for _, x, _ in crossings}))
    weights = {}
    for _, x, s in crossings:
        weights[-1.0 / x] = weights.get(-1.0 / x, 0) + s
    counts = []
    n_ccw = arc
    counts.append(P - n_ccw)
    for g in gains:
        n_ccw += weights[g]
        counts.append(P - n_ccw)
    counts = tuple(int(c) for c in counts)
    if any(c < 0 for c in counts):
        raise RuntimeError(f"Nyquist count gives a negative number of unstable closed-loop poles "
                           f"{counts}: the frequency grid (points_per_decade="
                           f"{points_per_decade}) misses a crossing")

    idx = int(np.searchsorted(gains, 1.0))
    if idx < gains.size and math.isclose(gains[idx], 1.0, rel_tol=1e-9):
        raise ValueError("the nominal loop is marginally stable (L passes through -1)")
    z1 = counts[idx]
    # guard: the closed-loop eigenvalues at k = 1
    if A.size:
        if math.isclose(1.0 + D, 0.0, abs_tol=1e-12):
            raise ValueError("1 + D = 0: the closed loop is not proper")
        acl = A - B @ C / (1.0 + D)
        z_eig = int(np.sum(np.linalg.eigvals(acl).real > tol))
        if z_eig != z1:
            raise RuntimeError(f"Nyquist count Z(1) = {z1} disagrees with the closed-loop "
                               f"eigenvalues ({z_eig} unstable): refine points_per_decade")
    lower = upper = None
    if z1 == 0:
        j = idx
        while j > 0 and counts[j - 1] == 0:
            j -= 1
        lower = 0.0 if j == 0 else float(gains[j - 1])
        j = idx
        while j < gains.size and counts[j + 1] == 0:
            j += 1
        upper = math.inf if j == gains.size else float(gains[j])

    # gain crossovers and phase margins
    mag = np.abs(h)
    gc, pm = [], []
    lm = np.log(mag)
    for i in np.nonzero(np.sign(lm[:-1]) * np.sign(lm[1:]) < 0)[0]:
        wc = brentq(lambda v: math.log(abs(L(v)[0])), w[i], w[i + 1], xtol=1e-12 * w[i])
        gc.append(wc / (2 * math.pi))
        pm.append(((math.degrees(np.angle(L(wc)[0])) + 180.0 + 180.0) % 360.0) - 180.0)
    pm = [p if p != -180.0 else 180.0 for p in pm]
    cr = sorted(crossings, key=lambda c: c[0])
    return NyquistMargins(
        open_loop_unstable_poles=P, open_loop_rhp_poles=np.sort_complex(rhp), origin_poles=n0,
        closed_loop_unstable_poles=z1, boundary_gains=gains, unstable_counts=counts,
        lower_gain_margin=lower, upper_gain_margin=upper,
        gain_crossovers_hz=np.array(gc), phase_margins_deg=np.array(pm),
        phase_crossovers_hz=np.array([c[0] / (2 * math.pi) for c in cr]),
        gain_margins_db=np.array([-20 * math.log10(abs(c[1])) for c in cr]))
