"""Margins along a trajectory (asekit.case.trajectory): the profile reader's errors, the
margins against the case pipeline's at the case's own flight points, the steady hinge moment,
the transonic gap and Mach extrapolation, and the NACA TN 4197 formula by hand."""

import dataclasses
import math

import pytest

from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline as P
from asekit.case.trajectory import (
    ProfileError,
    ProfilePoint,
    method_refuses,
    plot_trajectory,
    read_profile,
    tn4197_flutter_speed,
    tn4197_inputs,
    trajectory,
    trajectory_json,
)
from asekit.util.paths import DATA_DIR

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


# --------------------------------------------------------------------------------------------
# the profile reader
# --------------------------------------------------------------------------------------------
def _profile(tmp_path, text, name="p.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_shipped_profile_reads():
    pts = read_profile(DATA_DIR / "profiles" / "fin_boost.csv")
    assert len(pts) == 8
    assert all(b.time_s > a.time_s for a, b in zip(pts[:-1], pts[1:]))
    assert pts[0].alpha_deg == 2.0 and pts[0].deflection_deg == 1.0


def test_optional_columns_absent_are_none(tmp_path):
    (p,) = read_profile(_profile(tmp_path, "mach,time_s,altitude_m\n0.5,1,100\n"))
    assert (p.time_s, p.mach, p.altitude_m, p.alpha_deg, p.deflection_deg) == \
        (1.0, 0.5, 100.0, None, None)


@pytest.mark.parametrize("text, words", [
    ("time_s,mach\n0,0.5\n", ["p.csv", "row 1", "missing column", "altitude_m"]),
    ("time_s,mach,altitude_m,beta\n0,0.5,0,1\n", ["p.csv", "row 1", "unknown column", "'beta'"]),
    ("time_s,mach,altitude_m\n0,0.5,0\n1,abc,0\n", ["p.csv", "row 3", "column mach",
                                                    "not a number"]),
    ("time_s,mach,altitude_m\n0,0,0\n", ["row 2", "column mach", "(0, 10]"]),
    ("time_s,mach,altitude_m\n0,11,0\n", ["row 2", "column mach", "(0, 10]"]),
    ("time_s,mach,altitude_m\n0,0.5,60000\n", ["row 2", "column altitude_m", "[-5000, 47000]"]),
    ("time_s,mach,altitude_m,alpha_deg\n0,0.5,0,95\n", ["row 2", "column alpha_deg",
                                                       "[-90, 90]"]),
    ("time_s,mach,altitude_m,deflection_deg\n0,0.5,0,nan\n", ["row 2", "deflection_deg"]),
    ("time_s,mach,altitude_m\n1,0.5,0\n1,0.6,0\n", ["row 3", "column time_s",
                                                   "strictly increasing"]),
    ("time_s,mach,altitude_m\n0,0.5\n", ["row 2", "2 cells", "header has 3"]),
    ("# only a comment\ntime_s,mach,altitude_m\n", ["p.csv", "no data row"]),
    ("", ["p.csv", "empty file"]),
])
def test_profile_errors_name_file_row_column(tmp_path, text, words):
    with pytest.raises(ProfileError) as err:
        read_profile(_profile(tmp_path, text))
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_byte_order_mark_and_crlf_accepted(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes("time_s,mach,altitude_m\r\n0,0.5,10\r\n".encode("utf-8-sig"))
    (p,) = read_profile(path)
    assert (p.time_s, p.mach, p.altitude_m) == (0.0, 0.5, 10.0)


def test_comment_lines_keep_row_numbers(tmp_path):
    text = "# a comment\ntime_s,mach,altitude_m\n0,0.5,0\n1,-1,0\n"
    with pytest.raises(ProfileError, match="row 4, column mach"):
        read_profile(_profile(tmp_path, text))


def test_missing_profile_file(tmp_path):
    with pytest.raises(ProfileError, match="no such profile file"):
        read_profile(tmp_path / "none.csv")


# --------------------------------------------------------------------------------------------
# NACA TN 4197
# --------------------------------------------------------------------------------------------
def test_tn4197_against_hand_computation():
    """By hand (calculator): the fin's A = 0.15^2 / (0.15 (0.156 + 0.078) / 2) = 1.28205,
    lambda = 0.5, t/c = 0.004 / 0.156 = 0.025641, G = 70e9 / 2.6 = 26.923 GPa, sea level
    p = 101325 Pa, a = 340.294 m/s. 12 eps gamma / pi = 12 * 0.25 * 1.4 / pi = 1.336902;
    denominator 1.336902 * 101325 * 1.28205^3 * 1.5 / (0.025641^3 * 3.28205)
    = 428 177 / 5.53288e-5 = 7.73877e9 Pa; V_f = 340.294 sqrt(26.923e9 / 7.73877e9)
    = 340.294 * 1.865204 = 634.72 m/s."""
    v = tn4197_flutter_speed(70e9 / 2.6, 0.15 ** 2 / (0.15 * 0.117), 0.5, 0.004 / 0.156,
                             101325.0, 340.294)
    assert v == pytest.approx(634.72, abs=0.05)


def test_tn4197_scaling_laws():
    """V_f ~ sqrt(G / p) (t/c)^1.5 at fixed planform: the formula's structure."""
    base = tn4197_flutter_speed(27e9, 1.3, 0.5, 0.03, 1e5, 340.0)
    assert tn4197_flutter_speed(27e9, 1.3, 0.5, 0.03, 2.5e4, 340.0) == pytest.approx(2 * base)
    assert tn4197_flutter_speed(27e9, 1.3, 0.5, 0.06, 1e5, 340.0) == \
        pytest.approx(2 ** 1.5 * base)
    with pytest.raises(ValueError, match="thickness_ratio"):
        tn4197_flutter_speed(27e9, 1.3, 0.5, 0.0, 1e5, 340.0)


def test_tn4197_inputs_of_the_fin(fin_case):
    p = tn4197_inputs(fin_case)
    assert p["aspect_ratio"] == pytest.approx(0.15 ** 2 / (0.15 * 0.117))
    assert p["taper_ratio"] == pytest.approx(0.5)
    assert p["thickness_ratio"] == pytest.approx(0.004 / 0.156)
    assert p["shear_modulus"] == pytest.approx(70e9 / 2.6)


# --------------------------------------------------------------------------------------------
# the trajectory against the pipeline
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small_fin(fin_case):
    """The fin at two Machs, sea level only, a coarser sweep (a fast p-k)."""
    flight = dataclasses.replace(fin_case.flight, altitudes=(0.0,),
                                 velocities=tuple(float(v) for v in range(150, 300, 2)))
    aero = dataclasses.replace(fin_case.aero, machs=(0.5, 0.6))
    return dataclasses.replace(fin_case, flight=flight, aero=aero)


@pytest.fixture(scope="module")
def small_run(small_fin):
    pts = [ProfilePoint(0.0, 0.6, 0.0, 2.0, 1.0), ProfilePoint(1.0, 0.5, 0.0),
           ProfilePoint(2.0, 0.63, 0.0, 1.0, None), ProfilePoint(3.0, 0.7, 0.0),
           ProfilePoint(4.0, 0.95, 0.0), ProfilePoint(5.0, 0.55, 0.0, -1.0, 0.0)]
    return trajectory(small_fin, pts), P.flutter(small_fin)


def test_margins_equal_the_pipelines_at_its_flight_point(small_run):
    rows, fa = small_run
    (m,) = fa.margins                              # sea level, envelope top Mach 0.6
    r = rows[0]
    assert r.flutter_speed_ms == pytest.approx(m["flutter_speed_ms"], rel=1e-12)
    assert r.flutter_margin_pct == pytest.approx(100 * m["margin"], rel=1e-12)
    (d,) = [d for d in fa.divergence if d["mach"] == 0.6]
    a = float(standard_atmosphere(0.0).speed_of_sound)
    assert r.divergence_margin_pct == pytest.approx(100 * (d["speed_ms"] / (0.6 * a) - 1),
                                                    rel=1e-12)
    assert not r.transonic_gap and not r.mach_extrapolated


def test_flutter_speed_at_analysed_mach_is_the_crossing(small_run):
    rows, fa = small_run
    (res,) = [x for x in fa.results if x.mach == 0.5]
    assert rows[1].flutter_speed_ms == pytest.approx(res.flutter.speed, rel=1e-12)


def test_dynamic_pressure_and_hinge_moment(small_fin, small_run):
    rows, _ = small_run
    atm = standard_atmosphere(0.0)
    q = 0.5 * float(atm.density) * (0.6 * float(atm.speed_of_sound)) ** 2
    assert rows[0].dynamic_pressure_Pa == pytest.approx(q, rel=1e-12)
    q_cc = P.ase_condition(small_fin, 0.6, 0.0).q_cc     # the ASE model's steady Re Q_cc
    assert rows[0].hinge_moment_Nm == pytest.approx(q * q_cc * math.radians(3.0), rel=1e-12)
    # linear in the incidence alpha + delta, sign included
    q55 = 0.5 * float(atm.density) * (0.55 * float(atm.speed_of_sound)) ** 2
    q_cc55 = float(P.gaf_database(small_fin).at(0.55, interpolate=True).Q[0, 0, 0].real)
    assert rows[5].hinge_moment_Nm == pytest.approx(q55 * q_cc55 * math.radians(-1.0),
                                                    rel=1e-12)
    assert rows[1].hinge_moment_Nm is None         # no alpha / deflection column


def test_extrapolation_marked_and_bounded(small_run):
    rows, fa = small_run
    u5, u6 = (next(x.flutter.speed for x in fa.results if x.mach == m) for m in (0.5, 0.6))
    r = rows[2]                                    # M 0.63: 0.03 beyond M 0.6
    assert r.mach_extrapolated and "extrapolated" in r.note
    assert r.flutter_speed_ms == pytest.approx(u6 + (u6 - u5) * 0.3, rel=1e-9)
    assert r.hinge_moment_Nm is None and "outside the GAF database" in r.note
    far = rows[3]                                  # M 0.7: 0.1 beyond, not extrapolated
    assert far.flutter_speed_ms is None and far.flutter_margin_pct is None
    assert "not known at M 0.7" in far.note


def test_transonic_gap_marked(small_fin, small_run):
    rows, _ = small_run
    gap = rows[4]
    assert gap.transonic_gap and gap.flutter_speed_ms is None
    assert "transonic gap" in gap.note
    assert [r.transonic_gap for r in rows] == [False, False, False, False, True, False]
    # "dlm" accepts M 0.95 with a warning; "auto" refuses it
    auto = dataclasses.replace(small_fin, aero=dataclasses.replace(small_fin.aero,
                                                                   method="auto"))
    assert not method_refuses(small_fin, 0.95) and method_refuses(auto, 0.95)


def test_tn4197_beside_asekit_on_the_fin(small_run):
    """Where they disagree: the fin pivots on a 120 N m/rad shaft spring, and its flutter
    (rigid pitch with bending) lies far below TN 4197's clamped-plate boundary."""
    rows, _ = small_run
    r = rows[0]
    assert r.tn4197_flutter_speed_ms == pytest.approx(634.72, abs=0.1)
    assert r.flutter_speed_ms < 0.5 * r.tn4197_flutter_speed_ms


def test_no_points_refused(small_fin):
    with pytest.raises(ValueError, match="points"):
        trajectory(small_fin, [])


def test_refused_gap_point_has_no_values(small_fin):
    auto = dataclasses.replace(small_fin, aero=dataclasses.replace(small_fin.aero,
                                                                   method="auto"))
    (r,) = trajectory(auto, [ProfilePoint(0.0, 1.0, 0.0, 1.0, 1.0)])
    assert r.transonic_gap and "refuses it" in r.note
    assert (r.flutter_speed_ms, r.divergence_margin_pct, r.hinge_moment_Nm) == (None,) * 3
    assert r.tn4197_flutter_speed_ms is not None and r.dynamic_pressure_Pa > 0


@pytest.mark.slow
def test_margins_equal_the_pipelines_on_the_whole_fin(fin_case):
    """The shipped fin at its three altitudes and envelope top Mach 0.6: the trajectory's
    margins are the pipeline's (``asekit analyse``'s margins table)."""
    fa = P.flutter(fin_case)
    rows = trajectory(fin_case, [ProfilePoint(float(i), 0.6, h)
                                 for i, h in enumerate(fin_case.flight.altitudes)])
    for r, m in zip(rows, fa.margins):
        assert r.altitude_m == m["altitude_m"]
        assert r.flutter_margin_pct == pytest.approx(100 * m["margin"], rel=1e-12)


# --------------------------------------------------------------------------------------------
# the actuator's power demand (issue 27)
# --------------------------------------------------------------------------------------------
def test_actuator_power_demand_by_hand(small_fin, small_run):
    # The quasi-steady motor of thesis Eqs. (2.30)-(2.37) (acceleration and dI/dt zero):
    # K_t I = c N omega - T_hinge / (N eta), V = R I + K_b N omega, P = V I. small_run's
    # commanded deflections are 1, 0, 0, 0, 0, 0 deg at t = 0..5 s, so the rate at t = 0 is
    # the one-sided difference -1 deg/s and at t = 5 s it is 0: there the motor only holds
    # the hinge moment and the power is the copper loss R I^2 with I = -T_hinge / (K_t N eta).
    rows, _ = small_run
    act, _, _ = P.actuator_setup(small_fin)
    m, tr = act.motor, act.transmission
    N, eta = tr.ratio, tr.efficiency
    r0, r5 = rows[0], rows[5]
    assert r0.deflection_rate_deg_s == pytest.approx(-1.0, rel=1e-12)
    om = math.radians(-1.0)
    cur = (m.viscous_damping * N * om - r0.hinge_moment_Nm / (N * eta)) / m.torque_constant
    volt = m.resistance * cur + m.back_emf_constant * N * om
    assert r0.motor_current_A == pytest.approx(cur, rel=1e-12)
    assert r0.motor_voltage_V == pytest.approx(volt, rel=1e-12)
    assert r0.actuator_power_W == pytest.approx(volt * cur, rel=1e-12)
    assert r5.deflection_rate_deg_s == 0.0
    hold = -r5.hinge_moment_Nm / (m.torque_constant * N * eta)
    assert r5.actuator_power_W == pytest.approx(m.resistance * hold ** 2, rel=1e-12)
    assert rows[1].actuator_power_W is None        # no hinge moment, no power
    j = trajectory_json(small_fin, rows)
    assert j["units"]["actuator_power_W"].startswith("W")
    assert j["trajectory"][0]["actuator_power_W"] == r0.actuator_power_W
    import matplotlib.pyplot as plt
    fig, axes = plot_trajectory(rows)
    assert len(axes) == 3 and axes[2].get_ylabel() == "actuator power V I (W)"
    plt.close(fig)
