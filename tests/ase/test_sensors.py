"""Sensor model of the processor loop (issue 26): first-order bandwidth and seeded white
measurement noise in :func:`asekit.ase.afs.simulate_release_sampled`.

Reference numbers: the stationary variance of held white noise through a first-order lag,
sigma^2 (1 - a) / (1 + a), a = exp(-T / tau) (-> sigma^2 T / (2 tau)), from the discrete
Lyapunov equation of x(k+1) = a x(k) + (1 - a) n(k) (Astrom & Wittenmark, Computer-Controlled
Systems, 3rd ed., Sec. 10.4); the p-k flutter speed of the fin is computed in the fixture.
"""

import math

import numpy as np
import pytest

from asekit.ase import afs
from asekit.ase.sensors import (
    Sensors,
    lagged_noise_variance,
    measurement_noise,
    sensed_discretisation,
)


@pytest.fixture(scope="module")
def setup(afs_family, afs_open_loop):
    """conftest's fin speed family at 1.05 times its open-loop boundary, and the discrete LQG
    designed at 1.35 times it (1 kHz)."""
    u = afs_open_loop.speed
    K = afs.discrete_lqg_controller(afs_family.model(1.35 * u), 1e-3, 1e4, 1e4, 0.1)
    return afs_family.model(1.05 * u), K


KW = dict(root_twist=math.radians(0.1), t_final=0.05)


def _same(a, b):
    for f in ("t", "fin_root", "theta", "voltage", "voltage_demand", "current"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


def test_ideal_sensors_are_the_sensor_free_loop_bit_for_bit(setup):
    m, K = setup
    ref = afs.simulate_release_sampled(m, K, 1e-3, 1, **KW)
    _same(afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=Sensors(), **KW), ref)
    _same(afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=Sensors(None, 0.0, 7), **KW), ref)


def test_wide_sensor_bandwidth_converges_to_the_ideal_loop(setup):
    # a lag tau delays the measurement by ~tau: the history difference falls like tau
    m, K = setup
    ref = afs.simulate_release_sampled(m, K, 1e-3, 1, **KW)
    scale = np.max(np.abs(ref.fin_root))
    err = [np.max(np.abs(afs.simulate_release_sampled(
        m, K, 1e-3, 1, sensors=Sensors(bandwidth=f), **KW).fin_root - ref.fin_root)) / scale
        for f in (1e3, 1e4)]
    assert err[1] < 0.2 * err[0] and err[1] < 0.02


def test_same_seed_same_run_other_seed_other_run(setup):
    m, K = setup
    s = Sensors(bandwidth=500.0, noise_rms=(1e-4, 1e-3, 1e-4, 1e-2)[:len(K.input_labels)],
                seed=11)
    a = afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=s, **KW)
    b = afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=s, **KW)
    _same(a, b)
    c = afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=Sensors(500.0, s.noise_rms, 12),
                                     **KW)
    assert not np.array_equal(a.voltage, c.voltage)


@pytest.mark.parametrize("tau_over_t", [5.0, 50.0])
def test_lagged_noise_rms_is_the_analytic_value(tau_over_t):
    # zero plant signal: the sampled sensor output is the noise through the lag (1); its
    # variance over N samples has a relative sampling error ~ sqrt(2 (1 + a) / ((1 - a) N))
    ts, sigma, n = 1e-3, 0.3, 60_000
    s = Sensors(bandwidth=1 / (2 * math.pi * tau_over_t * ts), noise_rms=sigma, seed=5)
    Ad, _, Bn, Cs = sensed_discretisation([[-1.0]], [[0.0]], [[0.0]], s, ts)
    noise = measurement_noise(s, n, 1)
    a = Ad[1, 1]
    x, out = np.zeros(2), np.empty(n)
    for k in range(n):
        out[k] = Cs[0] @ x
        x = Ad @ x + Bn @ noise[k]
    var = np.var(out[int(20 * tau_over_t):])
    exact = lagged_noise_variance(sigma, ts, s.time_constant)
    rel = math.sqrt(2 * (1 + a) / ((1 - a) * n))
    assert abs(var / exact - 1) < 4 * rel
    assert abs(exact / (sigma ** 2 * ts / (2 * s.time_constant)) - 1) < 1 / tau_over_t


def test_sensor_refusals():
    with pytest.raises(ValueError, match="bandwidth"):
        Sensors(bandwidth=0.0)
    with pytest.raises(ValueError, match="noise_rms"):
        Sensors(noise_rms=-1.0)
    with pytest.raises(ValueError, match="seed"):
        Sensors(seed=-2)


def test_noise_driven_residual_scales_with_the_noise(setup):
    # below the clip the loop is linear: with the same seed the residual (history minus the
    # noise-free history) is proportional to the noise RMS
    m, K = setup
    kw = dict(root_twist=math.radians(0.1), t_final=0.2)
    clean = afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=Sensors(bandwidth=300.0), **kw)
    r = [afs.simulate_release_sampled(m, K, 1e-3, 1, sensors=Sensors(300.0, s, 4), **kw)
         for s in (1e-5, 1e-4)]
    assert not any(x.saturated for x in r)
    d1, d2 = (x.fin_root - clean.fin_root for x in r)
    assert np.max(np.abs(d1)) > 0
    np.testing.assert_allclose(d2, 10 * d1, rtol=0, atol=1e-9 * np.max(np.abs(d2)))
