"""Derivatives of a loop's gain and phase margins with respect to design parameters, by implicit
differentiation at the crossover frequencies (issue 28).

For the SISO open loop L(s) = C (s I - A)^-1 B + D (negative feedback, ``1 + L = 0``), with
R(w) = (j w I - A)^-1 and the parameter derivatives dA, dB, dC, dD of its state-space matrices,

    dL/dtheta = dC R B + C R dA R B + C R dB + dD,     dL/dw = -j C R R B.            (1)

Write l = log L = ln|L| + j arg L, so dl = dL / L.

* Gain crossover w_c, where ln|L| = 0: its shift with theta follows from
  d(ln|L|) = Re(L_theta / L) + Re(L_w / L) dw_c = 0, and the phase margin
  PM = 180 deg + arg L(j w_c) (wrapped to (-180, 180]) moves by

      dPM = (180 / pi) [Im(L_theta / L) + Im(L_w / L) dw_c/dtheta],
      dw_c/dtheta = -Re(L_theta / L) / Re(L_w / L).                                   (2)

* Phase crossover w_p, where arg L = -180 deg (Im L = 0, Re L < 0): from
  d(arg L) = Im(L_theta / L) + Im(L_w / L) dw_p = 0, the gain margin
  GM = -20 log10 |L(j w_p)| (dB) moves by

      dGM = -(20 / ln 10) [Re(L_theta / L) + Re(L_w / L) dw_p/dtheta],
      dw_p/dtheta = -Im(L_theta / L) / Im(L_w / L).                                   (3)

(The implicit-function theorem on the crossover conditions; e.g. the margin sensitivities of
Astrom & Murray, *Feedback Systems*, 2nd ed., 2021, Sec. 10.3, written for a state-space loop.)
Exact for simple crossings (Re(L_w / L) != 0 at w_c, Im(L_w / L) != 0 at w_p); a tangency
is refused. The crossovers are located on a logarithmic frequency grid and refined by
Brent's method to ``rtol``.

The plant's modal matrices enter through dA: for an aeroservoelastic loop built from the modal
mass, stiffness and the rational approximation of the GAFs, dA follows from the design chain's
dlambda, dQ (:mod:`asekit.aeroelastic.sensitivity`) through the fit; that wiring is not part of
this module, which differentiates any state-space loop given its matrix derivatives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["MarginSensitivity", "loop_response", "margin_sensitivities"]


@dataclass(frozen=True)
class MarginSensitivity:
    """Margins of ``1 + L`` at every crossover and their parameter derivatives.

    Attributes
    ----------
    gain_crossovers_rad_s : (n_c,) w_c (rad/s); phase_margins_deg : (n_c,) PM at each;
    d_phase_margins_deg : (n_var, n_c) dPM/dtheta (deg per unit theta);
    d_gain_crossovers_rad_s : (n_var, n_c) dw_c/dtheta;
    phase_crossovers_rad_s : (n_p,) w_p (rad/s); gain_margins_db : (n_p,) GM at each (dB);
    d_gain_margins_db : (n_var, n_p) dGM/dtheta (dB per unit theta);
    d_phase_crossovers_rad_s : (n_var, n_p) dw_p/dtheta.
    """

    gain_crossovers_rad_s: np.ndarray
    phase_margins_deg: np.ndarray
    d_phase_margins_deg: np.ndarray
    d_gain_crossovers_rad_s: np.ndarray
    phase_crossovers_rad_s: np.ndarray
    gain_margins_db: np.ndarray
    d_gain_margins_db: np.ndarray
    d_phase_crossovers_rad_s: np.ndarray


def _as_2d(x, shape, name: str) -> np.ndarray:
    a = np.atleast_2d(np.asarray(x, float))
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    return a


def loop_response(A, B, C, D, w: float, dA=(), dB=(), dC=(), dD=()):
    """L(j w), dL/dw and dL/dtheta_k (Eq. 1) of a SISO state-space loop at w (rad/s).

    Parameters
    ----------
    A (n, n), B (n, 1), C (1, n), D (1, 1) : the loop's matrices;
    dA, dB, dC, dD : sequences of their derivatives, one per parameter (empty: zero; the
        sequences that are given must have the same length).

    Returns
    -------
    L (complex), L_w (complex, per rad/s), L_theta ((n_var,) complex).

    Examples
    --------
    L(s) = 2 / (s + 1) at s = j: L = 1 - j, dL/dw = -2 j / (j + 1)^2 = -2 j / 2 j = -1.

    >>> L, Lw, _ = loop_response([[-1.0]], [[1.0]], [[2.0]], [[0.0]], 1.0)
    >>> complex(L), complex(np.round(Lw, 12))
    ((1-1j), (-1+0j))
    """
    A = np.atleast_2d(np.asarray(A, float))
    n = A.shape[0]
    B, C, D = _as_2d(B, (n, 1), "B"), _as_2d(C, (1, n), "C"), _as_2d(D, (1, 1), "D")
    M = 1j * w * np.eye(n) - A
    RB = np.linalg.solve(M, B)                     # R B
    CR = np.linalg.solve(M.T, C.T).T               # C R
    L = complex((C @ RB + D)[0, 0])
    Lw = complex(-1j * (CR @ RB)[0, 0])
    n_var = max(len(dA), len(dB), len(dC), len(dD))
    Lt = np.zeros(n_var, complex)
    for k in range(n_var):
        if len(dA):
            Lt[k] += (CR @ np.asarray(dA[k], float) @ RB)[0, 0]
        if len(dB):
            Lt[k] += (CR @ _as_2d(dB[k], (n, 1), "dB"))[0, 0]
        if len(dC):
            Lt[k] += (_as_2d(dC[k], (1, n), "dC") @ RB)[0, 0]
        if len(dD):
            Lt[k] += np.asarray(dD[k], float).ravel()[0]
    return L, Lw, Lt


def _roots(fun, w: np.ndarray, rtol: float, keep) -> list[float]:
    """Sign changes of ``fun`` on the grid ``w``, refined by Brent's method; ``keep(w)`` filters."""
    v = np.array([fun(x) for x in w])
    out = []
    for i in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
        r = brentq(fun, w[i], w[i + 1], xtol=1e-300, rtol=rtol)
        if keep(r):
            out.append(r)
    return out


def margin_sensitivities(A, B, C, D, dA=(), dB=(), dC=(), dD=(),
                         w_range=(1e-2, 1e4), points: int = 2000,
                         rtol: float = 1e-13) -> MarginSensitivity:
    """Gain and phase margins of the loop ``1 + L`` and their derivatives (Eqs. 2 and 3).

    Parameters
    ----------
    A, B, C, D : the SISO open loop L(s) (negative feedback);
    dA, dB, dC, dD : their derivatives per design parameter (sequences, see
        :func:`loop_response`);
    w_range : (w_min, w_max) rad/s searched for crossovers (logarithmic grid of ``points``);
    rtol : Brent's relative tolerance on the crossover frequencies.

    Returns
    -------
    :class:`MarginSensitivity`.

    Raises
    ------
    ValueError
        A crossover is a tangency (the derivative of the crossing condition vanishes).

    Examples
    --------
    L(s) = 30 / ((s + 1)(s + 2)(s + 3)): the phase crosses -180 deg at w = sqrt(11) where
    |L| = 30 / 60, a gain margin of 20 log10 2 = 6.02 dB; dGM/dK = -20 / (K ln 10) per unit of
    the gain K = 30 (carried by C).

    >>> A = [[0, 1, 0], [0, 0, 1], [-6, -11, -6]]
    >>> s = margin_sensitivities(A, [[0], [0], [1]], [[30, 0, 0]], [[0]], dC=[[[1, 0, 0]]])
    >>> round(float(s.phase_crossovers_rad_s[0]) ** 2, 9), round(float(s.gain_margins_db[0]), 6)
    (11.0, 6.0206)
    >>> round(float(s.d_gain_margins_db[0, 0]), 6), round(-20 / (30 * math.log(10)), 6)
    (-0.28953, -0.28953)
    """
    w = np.geomspace(w_range[0], w_range[1], points)

    def resp(x):
        return loop_response(A, B, C, D, x, dA, dB, dC, dD)

    def ln_mag(x):
        return math.log(abs(resp(x)[0]))

    def imag(x):
        return resp(x)[0].imag

    wc = _roots(ln_mag, w, rtol, lambda x: True)
    wp = _roots(imag, w, rtol, lambda x: resp(x)[0].real < 0)
    n_var = max(len(dA), len(dB), len(dC), len(dD))
    pm, dpm, dwc = [], np.zeros((n_var, len(wc))), np.zeros((n_var, len(wc)))
    for i, x in enumerate(wc):
        L, Lw, Lt = resp(x)
        gw, gt = Lw / L, Lt / L
        if gw.real == 0:
            raise ValueError(f"the gain crossover at {x:g} rad/s is a tangency (|L| = 1 touched)")
        dwc[:, i] = -gt.real / gw.real
        dpm[:, i] = math.degrees(1) * (gt.imag + gw.imag * dwc[:, i])
        p = 180.0 + math.degrees(np.angle(L))
        pm.append(p - 360.0 if p > 180.0 else p)
    gm, dgm, dwp = [], np.zeros((n_var, len(wp))), np.zeros((n_var, len(wp)))
    for i, x in enumerate(wp):
        L, Lw, Lt = resp(x)
        gw, gt = Lw / L, Lt / L
        if gw.imag == 0:
            raise ValueError(f"the phase crossover at {x:g} rad/s is a tangency (-180 deg "
                             f"touched)")
        dwp[:, i] = -gt.imag / gw.imag
        dgm[:, i] = -20.0 / math.log(10.0) * (gt.real + gw.real * dwp[:, i])
        gm.append(-20.0 * math.log10(abs(L)))
    return MarginSensitivity(np.array(wc), np.array(pm), dpm, dwc, np.array(wp), np.array(gm),
                             dgm, dwp)
