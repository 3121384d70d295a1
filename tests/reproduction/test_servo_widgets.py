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


def test_ase_readout_explains_a_stable_loop_with_an_unstable_open_loop():
    """Issue 30: the Ch. 5 panel's readout says why a loop with a Bode phase margin to be read
    on an unstable open loop is closed-loop stable: P = 1 (the de-centering hinge moment's real
    pole, about +15.5 rad/s: asekit/ase/margins.py docstring), N = 1, Z = P - N = 0; the Nyquist
    count agrees with the closed-loop eigenvalues (``snap.stable``) for AEM1 and AEM2."""
    from asekit.case import pipeline
    from asekit.reproduction.fin import fin_case
    from asekit.reproduction.widgets import ase_readout, ase_snapshot

    fin = pipeline.ase_condition(fin_case(), mach=0.5, altitude=0.0)
    s1 = ase_snapshot(SYSTEM_3.gain, SYSTEM_3.kp, SYSTEM_3.kd, fin=fin)
    text = ase_readout(s1)
    assert s1.stable and s1.nyquist.closed_loop_stable
    assert s1.nyquist.open_loop_unstable_poles == 1
    assert 10.0 < s1.nyquist.open_loop_rhp_poles.real.max() < 20.0
    for part in ("P = 1", "N = 1", "Z = P - N = 0", "closed loop stable", "lower gain"):
        assert part in " ".join(text.split()), part
    assert all(len(line) <= 110 for line in text.splitlines())
    s2 = ase_snapshot(SYSTEM_3.gain, SYSTEM_3.kp, SYSTEM_3.kd, topology="AEM2", fin=fin)
    assert not s2.stable and s2.nyquist.closed_loop_unstable_poles > 0
    assert "UNSTABLE" in ase_readout(s2) and "lower gain" not in ase_readout(s2)
