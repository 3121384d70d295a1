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
