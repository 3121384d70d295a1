"""Sensor model of the processor loop: first-order bandwidth and white measurement noise (issue 26).

Each measured channel y_i (rad, rad/s) of the sampled flutter-suppression loop
(:func:`asekit.ase.afs.simulate_release_sampled`) passes a sensor before the processor samples
it. The sensor is modelled as

* a first-order lag of corner frequency f_c (Hz), time constant tau = 1 / (2 pi f_c),

      tau ds_i/dt = -s_i + y_i + n_i(t)                                                   (1)

  propagated exactly with the plant (the sensor states join the plant state; zero-order hold);
* white measurement noise n_i of RMS sigma_i: an independent Gaussian number per channel and
  per sample, held over the sample (ZOH) and drawn from :func:`numpy.random.default_rng` with a
  fixed ``seed`` (PCG64), so a run is bit-reproducible. With a finite bandwidth the noise enters
  the lag (1) (sensor-element noise, band-limited by the sensor); with an infinite bandwidth it
  is added to the sample directly.

Noise held over T through the lag (1): at the samples s_{k+1} = a s_k + (1 - a) n_k,
a = exp(-T / tau), a first-order autoregression whose stationary variance solves the discrete
Lyapunov equation P = a^2 P + (1 - a)^2 sigma^2 (Astrom & Wittenmark, *Computer-Controlled
Systems*, 3rd ed., Sec. 10.4, Eq. 10.17 for x(k+1) = Phi x(k) + v(k)):

      P = sigma^2 (1 - a) / (1 + a)  ->  sigma^2 T / (2 tau)   (T << tau)                    (2)

(:func:`lagged_noise_variance`).

The Table-2 step loop's single feedback angle has its own measurement chain
(:class:`asekit.ase.loop.SensorModel`: first-order filter and quantisation, no noise); this
module is the multi-channel one of the flutter-suppression loop.

SI units inside; the bandwidth in Hz at the edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.util.validate import finite, positive

__all__ = ["Sensors", "measurement_noise", "sensed_discretisation", "lagged_noise_variance",
           "sensed_loop"]


@dataclass(frozen=True)
class Sensors:
    """Sensor bandwidth and measurement noise of the processor loop (defaults: ideal).

    Attributes
    ----------
    bandwidth : float or None
        First-order corner frequency f_c (Hz) of every measured channel, > 0; None: infinite.
    noise_rms : float or tuple of float
        RMS sigma of the white measurement noise, in the units of each measured channel (rad,
        rad/s), >= 0: one value for every channel or one per channel (in the controller's
        input order). 0: no noise.
    seed : int
        Seed of the noise generator (:func:`numpy.random.default_rng`), >= 0.
    """

    bandwidth: float | None = None
    noise_rms: float | tuple = 0.0
    seed: int = 0

    def __post_init__(self):
        if self.bandwidth is not None:
            positive("bandwidth", self.bandwidth)
        rms = np.atleast_1d(np.asarray(self.noise_rms, dtype=float))
        if rms.ndim != 1 or not np.all(np.isfinite(rms)) or np.any(rms < 0):
            raise ValueError(f"noise_rms must be finite and >= 0, got {self.noise_rms!r}")
        if not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")

    @property
    def ideal(self) -> bool:
        """Whether the sensors change nothing (infinite bandwidth, zero noise)."""
        return self.bandwidth is None and not np.any(np.asarray(self.noise_rms, float) > 0)

    @property
    def time_constant(self) -> float:
        """tau = 1 / (2 pi f_c) (s); 0 for an infinite bandwidth."""
        return 0.0 if self.bandwidth is None else 1.0 / (2.0 * math.pi * self.bandwidth)


def measurement_noise(sensors: Sensors, samples: int, channels: int) -> np.ndarray:
    """White Gaussian measurement noise, one row per sample, one column per channel.

    Parameters
    ----------
    sensors : Sensors
    samples, channels : int
        Number of samples and of measured channels, >= 0 and >= 1.

    Returns
    -------
    numpy.ndarray
        (samples, channels), column i of RMS ``noise_rms[i]``; zeros (no draw) if the noise
        is zero. The same ``seed`` gives the same array, bit for bit.

    Examples
    --------
    >>> s = Sensors(noise_rms=0.5, seed=3)
    >>> bool(np.array_equal(measurement_noise(s, 4, 2), measurement_noise(s, 4, 2)))
    True
    >>> measurement_noise(Sensors(), 2, 1).tolist()
    [[0.0], [0.0]]
    """
    rms = np.broadcast_to(np.atleast_1d(np.asarray(sensors.noise_rms, float)), (channels,))
    if not np.any(rms > 0):
        return np.zeros((samples, channels))
    rng = np.random.default_rng(sensors.seed)
    return rng.standard_normal((samples, channels)) * rms


def sensed_discretisation(A, B, C, sensors: Sensors, step: float):
    """Exact zero-order-hold one-step matrices of a plant with first-order sensors, Eq. (1).

    The augmented state is [x; s] with s the sensor outputs (one per row of ``C``); the inputs,
    held over ``step``, are the plant input u and the noise n (one per row of ``C``).

    Parameters
    ----------
    A, B, C : array_like
        Plant state (n, n), input (n, 1) and measurement (p, n) matrices (SI).
    sensors : Sensors
        With a finite ``bandwidth``.
    step : float
        Hold step h (s), > 0.

    Returns
    -------
    Ad, Bu, Bn, Cs : numpy.ndarray
        x_{j+1} = Ad x_j + Bu u_j + Bn n_j over one step; the sampled measurement is Cs x
        (the sensor states).

    Examples
    --------
    >>> Ad, Bu, Bn, Cs = sensed_discretisation([[0.0]], [[0.0]], [[1.0]],
    ...                                        Sensors(bandwidth=1 / (2 * math.pi)), 0.1)
    >>> round(float(Ad[1, 1]), 6), round(float(Bn[1, 0]), 6)  # exp(-0.1), 1 - exp(-0.1)
    (0.904837, 0.095163)
    """
    from scipy.linalg import expm

    if sensors.bandwidth is None:
        raise ValueError("sensors.bandwidth must be finite for sensed_discretisation")
    h = positive("step", step)
    A, B, C = (np.atleast_2d(np.asarray(m, float)) for m in (A, B, C))
    n, p, m = A.shape[0], C.shape[0], B.shape[1]
    w = 1.0 / sensors.time_constant
    na = n + p
    M = np.zeros((na + m + p, na + m + p))
    M[:n, :n], M[:n, na:na + m] = A, B
    M[n:na, :n] = w * C
    M[n:na, n:na] = -w * np.eye(p)
    M[n:na, na + m:] = w * np.eye(p)
    E = expm(M * h)
    Cs = np.hstack([np.zeros((p, n)), np.eye(p)])
    return E[:na, :na], E[:na, na:na + m], E[:na, na + m:], Cs


def lagged_noise_variance(noise_rms: float, sample_time: float, time_constant: float) -> float:
    """Stationary variance of white noise (RMS sigma, held over T) seen through a first-order
    lag tau at the samples, Eq. (2): sigma^2 (1 - a) / (1 + a), a = exp(-T / tau).

    Examples
    --------
    >>> v = lagged_noise_variance(1.0, 1e-4, 1e-2)
    >>> abs(v / (1e-4 / (2 * 1e-2)) - 1) < 1e-5  # sigma^2 T / (2 tau)
    True
    """
    finite("noise_rms", noise_rms)
    positive("sample_time", sample_time)
    positive("time_constant", time_constant)
    a = math.exp(-sample_time / time_constant)
    return noise_rms ** 2 * (1.0 - a) / (1.0 + a)


def sensed_loop(A, B, Cy, Cp, Ad, Bd, x0, sensors: Sensors | None, sample_time: float,
                substeps: int, samples: int):
    """Matrices and noise of the processor loop of
    :func:`asekit.ase.afs.simulate_release_sampled` with ``sensors`` in it.

    Parameters
    ----------
    A, B : array_like
        Continuous plant matrices (n, n), (n, 1).
    Cy, Cp : array_like
        Measured rows (p, n) and all output rows (q, n) of the plant.
    Ad, Bd : array_like
        The plant's ZOH matrices over T / ``substeps`` (n, n), (n,) (used as they are without
        a finite bandwidth, so an ideal sensor reproduces the sensor-free loop bit for bit).
    x0 : array_like
        Initial plant state (n,); the sensors start settled on it (s = Cy x0).
    sensors : Sensors or None
    sample_time : float
        T (s).
    substeps, samples : int
        Plant steps per sample and number of samples.

    Returns
    -------
    Ad, Bd, Cy, Cp, x0, direct, lagged
        The (augmented) step matrices, measured and output rows and initial state; ``direct``
        (samples, p) the noise added to each sample, ``lagged`` (samples, len(x0)) the noise
        increment of the state over each plant step (zeros when absent).

    Examples
    --------
    >>> out = sensed_loop([[0.0]], [[1.0]], [[1.0]], [[1.0]], [[1.0]], [0.1], [0.0], None,
    ...                   0.1, 1, 3)
    >>> out[5].shape, float(np.abs(out[6]).max())
    ((3, 1), 0.0)
    """
    s = sensors if sensors is not None else Sensors()
    Cy, Cp, x0 = np.atleast_2d(Cy), np.atleast_2d(Cp), np.asarray(x0, float)
    p = Cy.shape[0]
    noise = measurement_noise(s, samples, p)
    if s.bandwidth is None:
        return (np.asarray(Ad), np.asarray(Bd), Cy, Cp, x0, noise,
                np.zeros((samples, x0.size)))
    Ad, Bu, Bn, Cs = sensed_discretisation(A, B, Cy, s, sample_time / substeps)
    x0 = np.concatenate([x0, Cy @ x0])
    Cp = np.hstack([Cp, np.zeros((Cp.shape[0], p))])
    return Ad, Bu[:, 0], Cs, Cp, x0, np.zeros((samples, p)), noise @ Bn.T
