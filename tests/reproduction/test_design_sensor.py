"""The ``ase.design.pid_notch.sensor_300hz.*`` rows (issue 26, sensors): the PID design's
Table-2 step check at Mach 0.5, sea level with its measured angle through a first-order sensor.

Physics asserted: the sensor's lag only costs phase, so the step settles later and overshoots
more than with the ideal sensor (computed here, not typed in: 42.8 ms / 0.58 % ideal, 47.2 ms /
2.17 % at 300 Hz when written); the filter has unit DC gain and the loop integrates the fin-root
error, so the steady error stays at roundoff; a wider sensor moves the check back toward the
ideal one.
"""

import pytest

from asekit.ase import loop as ase
from asekit.reproduction import design as dz


@pytest.fixture(scope="module")
def setup():
    data = dz.load()
    model = dz.fin_model(0.5, 0.0, data=data)
    ctl, topo = dz.designs(data)["pid_notch"]
    return data, model, dz.controller_at(ctl, 0.5, 0.0), topo


def test_sensor_lag_slows_the_step_and_keeps_zero_steady_error(setup):
    data, model, ctl, topo = setup
    ideal = dz.check(ctl, model, topo)
    rows = {q.key: q for q in dz.sensor_bandwidth_quantities(data, model)}
    key = f"ase.design.pid_notch.sensor_{dz.SENSOR_BANDWIDTH_HZ:g}hz"
    st = rows[f"{key}.settling_ms"].asekit
    assert rows[f"{key}.settling_ms"].computed and st > ideal.settling_ms
    assert abs(rows[f"{key}.steady_error_pct"].asekit) < 1e-9
    wide = dz.check(ctl, model, topo, sensor=ase.SensorModel(cutoff_hz=1e4))
    assert abs(wide.settling_ms - ideal.settling_ms) < abs(st - ideal.settling_ms)
    assert wide.overshoot_pct < dz.check(ctl, model, topo, sensor=ase.SensorModel(
        cutoff_hz=dz.SENSOR_BANDWIDTH_HZ)).overshoot_pct


def test_measurement_noise_enters_the_step_loop_linearly_and_reproducibly(setup):
    """Issue 26 (sensors): white noise on the measured angle in the Table-2 step loop
    (``SensorModel.noise_rms``). Below the voltage clip and without quantisation the sampled
    loop is linear, so the response to command + noise is the noise-free step plus a response
    proportional to the noise: doubling ``noise_rms`` (same seed) doubles the deviation, to
    roundoff. The same seed gives the same response bit for bit; zero noise is the ideal loop."""
    import math

    import numpy as np
    _, model, ctl, topo = setup
    sens = [ase.SensorModel(cutoff_hz=dz.SENSOR_BANDWIDTH_HZ, noise_rms=s, seed=7)
            for s in (0.0, 1e-5, 2e-5)]
    plant = ase.sampled_plant(model, topo, dz.SAMPLE_TIME, sensor=sens[0])
    cmd = math.radians(1.0)
    r0, r1, r2 = (ase.simulate_sampled(plant, ctl, cmd, t_final=0.1, sensor=s) for s in sens)
    assert np.max(np.abs(r0.voltage)) < 20.0                 # below the clip: the loop is linear
    d1, d2 = r1.fin_root - r0.fin_root, r2.fin_root - r0.fin_root
    assert np.max(np.abs(d1)) > 1e-7                         # the noise moves the fin
    np.testing.assert_allclose(d2, 2 * d1, rtol=0, atol=1e-9 * np.max(np.abs(d1)) + 1e-15)
    again = ase.simulate_sampled(plant, ctl, cmd, t_final=0.1, sensor=sens[1])
    assert np.array_equal(again.fin_root, r1.fin_root)
    bare = ase.simulate_sampled(plant, ctl, cmd, t_final=0.1,
                                sensor=ase.SensorModel(cutoff_hz=dz.SENSOR_BANDWIDTH_HZ))
    assert np.array_equal(bare.fin_root, r0.fin_root)
    for bad in (dict(noise_rms=-1e-4), dict(noise_rms=math.nan), dict(seed=-1)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            ase.SensorModel(**bad)
