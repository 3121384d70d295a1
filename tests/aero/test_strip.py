"""Theodorsen strip theory (asekit/aero/strip.py).

References: C(k) values of Bisplinghoff, Ashley & Halfman, *Aeroelasticity* (1955), Table 5-1
(F, G at k = 0.5 and 1.0; the limit 1/2 as k -> infinity); the steady thin-airfoil lift
2 pi per radian with the centre of pressure at the quarter chord; and the pitch-plunge flutter
of a typical section solved independently by asekit.aeroelastic.typical_section (Theodorsen's
T-functions, exact C(k), the flutter determinant solved for real U and omega).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from asekit.aero.gaf import TabulatedGaf
from asekit.aero.strip import strip_gaf, theodorsen
from asekit.aeroelastic.flutter import FlutterConvergenceWarning, pk_flutter, pk_instabilities
from asekit.aeroelastic.statespace import ModalArrays
from asekit.aeroelastic.typical_section import TypicalSection, flutter_speed_exact


def test_theodorsen_function_table_values():
    c = theodorsen([0.5, 1.0, 200.0])
    np.testing.assert_allclose(c[:2], [0.5979 - 0.1507j, 0.5394 - 0.1003j], atol=1e-4)
    assert abs(c[2] - 0.5) < 2e-3


def test_steady_lift_and_moment_of_a_pitching_strip():
    """k = 0: a unit pitch gives lift 2 pi c q per unit span at any axis, and a moment about
    the axis of 2 pi c q (x_ac-arm) with the aerodynamic centre at the quarter chord."""
    b = 0.8
    for a in (-0.5, 0.0, 0.3):
        Q = strip_gaf([[0.0, 1.0]], [[1.0, 0.0]], [2.0], b, a, [0.0])[0].real
        lift = Q[1, 0] / 2.0                 # work on the unit plunge: the lift per span / q
        moment = Q[0, 0] / 2.0
        assert lift == pytest.approx(2 * math.pi * 2 * b, rel=1e-12)
        arm = b * (a + 0.5)                  # axis behind the quarter chord
        assert moment == pytest.approx(lift * arm, rel=1e-12, abs=1e-12)


def test_typical_section_flutter_matches_the_independent_theodorsen_solution():
    rho, b, a = 1.225, 0.5, -0.3
    mu, x_a, r2, w_h, w_a = 20.0, 0.2, 0.25, 20.0, 50.0
    m = mu * math.pi * rho * b * b
    s_a, i_a = m * x_a * b, m * r2 * b * b
    sec = TypicalSection(b, a, 0.95, m, s_a, 1e-9, i_a, 1e-9, m * w_h ** 2, i_a * w_a ** 2,
                         1e3, density=rho)
    u_ref, f_ref = flutter_speed_exact(sec, 40.0, 6.0)
    # the same section as a two-mode model: q = (w up, theta nose-up); the mass centre x_a b
    # aft of the axis moves by w - x_a b theta
    modal = ModalArrays(np.array([[m, -s_a], [-s_a, i_a]]),
                        np.diag([m * w_h ** 2, i_a * w_a ** 2]), np.zeros((2, 2)))
    ks = np.linspace(0.0, 1.5, 61)
    gaf = TabulatedGaf(ks, strip_gaf([[1.0, 0.0]], [[0.0, 1.0]], [1.0], b, a, ks), b)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlutterConvergenceWarning)
        res = pk_flutter(modal, gaf, rho, np.arange(5.0, 120.0, 5.0), interpolation="cubic")
        found = [s for s in pk_instabilities(res, modal, gaf, interpolation="cubic")
                 if s.kind == "flutter"]
    assert found
    assert found[0].speed == pytest.approx(u_ref, rel=2e-3)
    assert found[0].frequency_hz == pytest.approx(f_ref, rel=2e-3)


def test_strip_gaf_refuses_bad_input():
    with pytest.raises(ValueError, match="widths"):
        strip_gaf([[1.0]], [[0.0]], [-1.0], 0.5, 0.0, [0.1])
    with pytest.raises(ValueError, match="theta"):
        strip_gaf([[1.0, 0.0]], [[0.0]], [1.0], 0.5, 0.0, [0.1])
    with pytest.raises(ValueError, match="semichord"):
        strip_gaf([[1.0]], [[0.0]], [1.0], 0.0, 0.0, [0.1])
    with pytest.raises(ValueError, match="a must be a finite number"):
        strip_gaf([[1.0]], [[0.0]], [1.0], 0.5, float("nan"), [0.1])
    with pytest.raises(ValueError, match="k"):
        strip_gaf([[1.0]], [[0.0]], [1.0], 0.5, 0.0, [-0.1])
