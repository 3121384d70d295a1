"""Step-response and oscillation metrics of simulated time histories (SI units).

Shared by the rigid-fin servo simulation (:mod:`asekit.servo.simulate`, thesis Ch. 4) and the
aeroservoelastic loop (:mod:`asekit.ase.loop`, Ch. 5): settling time, overshoot, the amplitude
spectrum after the rise (thesis Figs 73, 81) and limit-cycle amplitude and frequency.
"""

from __future__ import annotations

import math

import numpy as np


# ---------------------------------------------------------------------------------------------
def settling_time(t: np.ndarray, y: np.ndarray, target: float, step: float,
                  band: float = 0.02) -> float:
    """Time (s) after which ``y`` stays within ``band`` |step| of ``target``; inf if it is
    outside at the end."""
    outside = np.abs(y - target) > band * abs(step)
    if outside[-1]:
        return math.inf
    if not outside.any():
        return 0.0
    return float(t[int(np.nonzero(outside)[0][-1]) + 1])


def overshoot(y: np.ndarray, command: float, theta0: float = 0.0) -> float:
    """Largest excursion past ``command`` as a fraction of the step (0 if none)."""
    step = command - theta0
    return float(max(0.0, np.max(np.sign(step) * (y - command))) / abs(step))


def spectrum_after_rise(t: np.ndarray, y: np.ndarray, command: float, fraction: float = 0.95,
                        theta0: float = 0.0, pad: int = 8):
    """Amplitude spectrum of ``y`` after it first reaches ``fraction`` of the step, mean removed
    (thesis Figs 73, 81). Returns (f_hz, amplitude) with a Hann window and zero padding
    (``pad`` x the record length); amplitudes are single-sided, window-corrected."""
    step = command - theta0
    reached = np.nonzero(np.sign(step) * (y - theta0) >= fraction * abs(step))[0]
    if reached.size == 0:
        raise ValueError(f"the response never reaches {fraction:.0%} of the command")
    seg = y[reached[0]:] - np.mean(y[reached[0]:])
    if seg.size < 16:
        raise ValueError("too few samples after the rise for a spectrum")
    dt = float(t[1] - t[0])
    w = np.hanning(seg.size)
    n_fft = int(2 ** math.ceil(math.log2(seg.size * pad)))
    spec = np.fft.rfft(seg * w, n_fft)
    amp = 2.0 * np.abs(spec) / np.sum(w)
    return np.fft.rfftfreq(n_fft, dt), amp


def spectrum_peaks(f_hz: np.ndarray, amp: np.ndarray, n: int = 2, f_min: float = 20.0,
                   rel_height: float = 0.02) -> np.ndarray:
    """The ``n`` largest spectral peaks above ``f_min`` Hz (at least ``rel_height`` of the
    largest), returned in ascending frequency."""
    from scipy.signal import find_peaks

    sel = f_hz >= f_min
    idx, props = find_peaks(amp[sel], height=rel_height * amp[sel].max())
    if idx.size == 0:
        return np.array([])
    best = idx[np.argsort(props["peak_heights"])[::-1][:n]]
    return np.sort(f_hz[sel][best])


def limit_cycle(t: np.ndarray, y: np.ndarray, window: float = 0.05):
    """Amplitude (half peak-to-peak, same unit as y) and frequency (Hz, from zero crossings of
    the mean-removed signal) of a sustained oscillation over the last ``window`` s."""
    sel = t >= t[-1] - window
    seg = y[sel] - np.mean(y[sel])
    amp = 0.5 * (np.max(seg) - np.min(seg))
    ts = t[sel]
    up = np.nonzero((seg[:-1] < 0) & (seg[1:] >= 0))[0]
    if up.size < 2:
        return float(amp), math.nan
    tc = ts[up] - seg[up] * (ts[up + 1] - ts[up]) / (seg[up + 1] - seg[up])
    return float(amp), float((up.size - 1) / (tc[-1] - tc[0]))
