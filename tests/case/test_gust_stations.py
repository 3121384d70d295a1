"""Loads at user-defined monitoring stations (``[[gust.station]]``, issue 27): shear, bending
and torsion at a spanwise cut by force summation (aerodynamic + inertial)."""

import dataclasses
import tomllib

import numpy as np
import pytest

from asekit.aero.gust import gust_aero_tables
from asekit.aero.spline import fe_spline
from asekit.atmosphere import standard_atmosphere
from asekit.case import CaseError, case_from_dict
from asekit.case import pipeline as P
from asekit.case.gust_loads import (
    _load_weights,
    gust_json,
    gust_loads,
    station_cuts,
    turbulence_json,
)
from asekit.case.schema import GustSpec, GustStation
from asekit.util.paths import FIN_FILE

pytestmark = pytest.mark.usefixtures("session_gaf_cache")

STATIONS = (GustStation("root", 0.0, 0.5), GustStation("mid", 0.5), GustStation("outer", 0.8))


@pytest.fixture(scope="module")
def fin_stations(fin_case):
    case = dataclasses.replace(fin_case, gust=GustSpec((0.3, 40.0), 10.0, 0.5, 0.0,
                                                       turbulence_sigma=1.0,
                                                       stations=STATIONS))
    return case, gust_loads(case)


def test_station_at_the_root_is_the_root_load(fin_stations):
    # eta = 0: every box and node lies on or outboard of the cut and the bending axis is the
    # root chord line, so the station's shear and bending histories are the root loads
    _, res = fin_stations
    for c in res.cases:
        shear, bending, _ = c.stations["root"]
        np.testing.assert_allclose(shear, c.root_shear, rtol=1e-9,
                                   atol=1e-12 * np.abs(c.root_shear).max())
        np.testing.assert_allclose(bending, c.root_bending, rtol=1e-9,
                                   atol=1e-12 * np.abs(c.root_bending).max())


def test_root_torsion_about_the_shaft_is_the_hinge_moment(fin_stations):
    # The fin's shaft axis is the root chord's mid-point (axis_point in the case file), the
    # "root" station's torsion axis (eta 0, axis 0.5). With the actuator clamped the hinge
    # moment is the rigid pitch's generalised force (aerodynamic from the modal fit, inertial
    # from the modal mass coupling), the torsion a separate force summation with the loads fit:
    # both must agree to the fits' difference (measured: 9e-6 relative, short gust; 2e-9 long).
    case, res = fin_stations
    cut = station_cuts(P.box_mesh(case), STATIONS[:1])[0]
    assert cut[1] == pytest.approx(case.support.axis_point[0], abs=1e-12)
    for c in res.cases:
        torsion = c.stations["root"][2]
        scale = np.abs(c.hinge_moment).max()
        assert np.abs(torsion - c.hinge_moment).max() < 1e-4 * scale


def test_station_turbulence_at_the_root_is_the_root_rms(fin_stations):
    # the same transfer functions as the root loads (eta = 0) and, about the shaft axis, as
    # the hinge moment (to the fits' difference): the same RMS in turbulence (measured:
    # torsion 0.08110 N m against the hinge moment's to 3e-12); loads fall outboard
    _, res = fin_stations
    t = res.turbulence
    row = turbulence_json(res)[0]["stations"]
    assert row["root"]["rms_shear_N"] == pytest.approx(t["root_shear"]["rms"], rel=1e-9)
    assert row["root"]["rms_bending_Nm"] == pytest.approx(t["root_bending"]["rms"], rel=1e-9)
    assert row["root"]["rms_torsion_Nm"] == pytest.approx(t["hinge_moment"]["rms"], rel=1e-3)
    assert row["root"]["rms_shear_N"] > row["mid"]["rms_shear_N"] > row["outer"]["rms_shear_N"]


def test_long_gust_station_loads_are_the_static_distribution(fin_stations):
    # A long gust (H = 40 m at 170 m/s, 0.24 s to its peak, the first elastic mode near
    # 100 Hz) loads the fin quasi-statically: each station's peaks must approach the static
    # aeroelastic equilibrium at the incidence U_ds / U, from the k = 0 tables with the same
    # cut weights, without any fit or time integration (inertia vanishes in the static limit):
    #   (K_ss - q Q_ss(0)) zeta_s = q Qg_s(0) alpha,  load = q (QL_s(0) zeta_s + QLg(0) alpha)
    case, res = fin_stations
    modal, boxes = P.modal_model(case), P.box_mesh(case)
    y_root = float(np.min(boxes.corners[:, :, 1]))
    cuts = station_cuts(boxes, STATIONS)
    t = gust_aero_tables(fe_spline(modal, boxes), boxes, 0.5, [0.0], 0.078,
                         _load_weights(boxes, y_root, cuts), res.x0, "quartic")
    U = 0.5 * float(standard_atmosphere(0.0).speed_of_sound)
    q = 0.5 * float(standard_atmosphere(0.0).density) * U ** 2
    alpha = 10.0 / U
    s = slice(1, None)
    zeta = np.linalg.solve(modal.K[s, s] - q * t.Q[0, s, s].real, q * t.Qg[0, s].real * alpha)
    static = q * (t.QL[0, :, s].real @ zeta + t.QLg[0].real * alpha)
    # measured: every peak within 0.03 % of the static load (outer torsion 0.11 %)
    peaks = res.cases[1].station_peaks
    for i, st in enumerate(STATIONS):
        got = [peaks[st.name][k] for k in ("peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm")]
        np.testing.assert_allclose(got, static[2 + 3 * i:5 + 3 * i], rtol=0.01, err_msg=st.name)
    # the loads fall outboard: shear and bending decrease from the root to the tip
    sh = [peaks[n]["peak_shear_N"] for n in ("root", "mid", "outer")]
    bm = [peaks[n]["peak_bending_Nm"] for n in ("root", "mid", "outer")]
    assert sh[0] > sh[1] > sh[2] > 0 and bm[0] > bm[1] > bm[2] > 0


def test_station_json_rows(fin_stations):
    _, res = fin_stations
    for r in gust_json(res):
        assert set(r["stations"]) == {"root", "mid", "outer"}
        for v in r["stations"].values():
            assert set(v) == {"peak_shear_N", "peak_bending_Nm", "peak_torsion_Nm"}
            assert all(np.isfinite(x) for x in v.values())
    from asekit.case.report import _gust_lines
    lines = _gust_lines(gust_json(res))
    assert lines[-4].startswith("  station") and lines[-1].startswith("  outer")
    worst = max((c.station_peaks["outer"]["peak_shear_N"] for c in res.cases), key=abs)
    assert f"{worst:.4g}" in lines[-1]


def test_station_cuts_of_a_trapezoid():
    # a trapezoid: LE from (0, 0) to (0.5, 1), TE from (1, 0) to (1.5, 1) (two boxes)
    from types import SimpleNamespace
    c = np.array([[[0, 0, 0], [1, 0, 0], [1.25, 0.5, 0], [0.25, 0.5, 0]],
                  [[0.25, 0.5, 0], [1.25, 0.5, 0], [1.5, 1, 0], [0.5, 1, 0]]], float)
    cuts = station_cuts(SimpleNamespace(corners=c),
                        [GustStation("a", 0.0, 0.0), GustStation("b", 0.75, 0.25)])
    assert cuts[0] == pytest.approx((0.0, 0.0)) and cuts[1] == pytest.approx((0.75, 0.625))


def _with_stations(stations):
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    d["gust"] = {"gradient_lengths": [1.0], "design_velocity": 5.0, "station": stations}
    return d


def test_station_tables_are_read():
    case = case_from_dict(_with_stations([{"name": "a", "eta": 0.3},
                                          {"name": "b", "eta": 0.6, "axis": 0.4}]))
    assert case.gust.stations == (GustStation("a", 0.3), GustStation("b", 0.6, 0.4))


@pytest.mark.parametrize("stations, message", [
    ([{"eta": 0.3}], r"gust.station\[0\].name must be a non-empty string"),
    ([{"name": "a"}], r"gust.station\[0\].eta is missing"),
    ([{"name": "a", "eta": 1.0}], r"gust.station\[0\].eta"),
    ([{"name": "a", "eta": -0.1}], r"gust.station\[0\].eta"),
    ([{"name": "a", "eta": 0.5, "axis": 1.5}], r"gust.station\[0\].axis"),
    ([{"name": "a", "eta": 0.5, "chord": 1}], r"gust.station\[0\].chord is not a known key"),
    ([{"name": "a", "eta": 0.1}, {"name": "a", "eta": 0.2}], "name must be unique"),
    ({"name": "a"}, r"array of 1 to 50 tables"),
])
def test_station_errors(stations, message):
    with pytest.raises(CaseError, match=message):
        case_from_dict(_with_stations(stations))
