"""The notebooks' interactive panels (asekit.reproduction.widgets): built without a front end, the
servo panel's snapshot agrees with asekit.servo.actuator."""

import numpy as np
import pytest

from asekit.servo.actuator import SYSTEM_3, ActuatorParameters, closed_loop_poles

P = ActuatorParameters()


def test_widget_panel_builds_without_a_front_end():
    pytest.importorskip("ipywidgets")
    import matplotlib.pyplot as plt

    from asekit.reproduction.widgets import servo_panel, servo_snapshot
    panel = servo_panel()
    assert set(panel.sliders) == {"gain", "kp", "kd", "supply_voltage"}
    snap = panel.redraw()
    np.testing.assert_allclose(snap.poles, closed_loop_poles(P, SYSTEM_3), rtol=1e-9)
    # gains outside the Routh range: reported as unstable, no simulation, no exception
    bad = servo_snapshot(1.0, 1e6, 0.0)
    assert not bad.stable and bad.simulation is None
    plt.close("all")
