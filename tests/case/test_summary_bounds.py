"""Issue 22, "contradictory summaries": a sweep that starts above the flutter speed must give
match points, margins, notes and JSON that agree with its flutter rows (flutter at or below the
first point of the sweep, the margin as an upper bound), never "no flutter in the sweep".

Cases: AGARD 445.6 (data/cases/agard445_6.toml, flutter at 181.94 m/s, asekit's fine sweep) and
the reference fin (data/cases/nalci2013_fin.toml, flutter 213-276 m/s over its envelope), both
swept from 300 m/s.
"""

import dataclasses
import json

import pytest

from asekit.atmosphere import standard_atmosphere
from asekit.case import envelope as E
from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.case import report as R
from asekit.util.paths import CASES_DIR


def _from(case, lo, hi, step):
    n = int(round((hi - lo) / step))
    U = tuple(lo + step * i for i in range(n + 1))
    return dataclasses.replace(case, flight=dataclasses.replace(case.flight, velocities=U))


def _summary(case):
    fa = P.flutter(case)
    a = R.Analysis(case, P.modal_model(case), P.gaf_database(case, progress=False), fa, None,
                   {})
    return fa, R.summary(a)


def test_agard_sweep_above_flutter_rows_and_notes_agree():
    case = _from(load_case(CASES_DIR / "agard445_6.toml"), 300.0, 460.0, 20.0)
    fa, s = _summary(case)
    (row,) = s["flutter"]
    assert row["unstable_at_first_point"] and row["speed_ms"] is None
    assert row["speed_upper_bound_ms"] == 300.0 and row["mode"] == 1
    assert row["note"] == "unstable at the first point of the sweep: flutter at or below 300 m/s"
    (note,) = s["notes"]
    assert "flutter at or below 300 m/s (the first point of the sweep, mode 1)" in note
    text = R.format_summary(s)
    assert "<=300.00" in text and "no flutter" not in text
    json.dumps(s)                                          # the JSON document holds


@pytest.fixture(scope="module")
def fin_from_300():
    case = _from(load_case(CASES_DIR / "nalci2013_fin.toml"), 300.0, 460.0, 2.0)
    return case, _summary(case)


def test_fin_sweep_above_flutter_match_points_say_at_or_below(fin_from_300):
    case, (fa, s) = fin_from_300
    assert all(r["unstable_at_first_point"] for r in s["flutter"])
    for m in s["match_points"]:
        assert m["matched_mach"] is None
        assert m["flutter_at_or_below_ms"] == 300.0
        assert "flutter at or below 300 m/s (the first point of the sweep)" in m["no_match"]
        assert "no flutter" not in m["no_match"]
    text = R.format_summary(s, width=200)
    assert "no flutter" not in text


def test_fin_sweep_above_flutter_margin_is_an_upper_bound(fin_from_300):
    case, (fa, s) = fin_from_300
    for m in s["flutter_margins"]:
        a = float(standard_atmosphere(m["altitude_m"]).speed_of_sound)
        assert m["margin"] is None and m["flutter_speed_ms"] is None
        assert m["flutter_speed_upper_bound_ms"] == 300.0
        assert m["margin_upper_bound"] == pytest.approx(300.0 / (0.6 * a) - 1, rel=1e-12)
        assert "start the sweep lower" in m["note"]         # 300 m/s > M 0.6 a: not located
        assert "(flight.velocities.min)" in m["note"]       # issue 30: the key that takes it
    lines = [ln for ln in R.format_summary(s, width=300).splitlines()
             if ln.startswith("flutter margin")]
    assert len(lines) == 3 and all("at most +" in ln and " -" not in ln for ln in lines)


def test_margin_inside_the_envelope_when_the_bound_is_below_the_envelope_speed():
    """An upper bound below the envelope speed: flutter inside the envelope, margin < 0."""
    c = P.FlightCondition(0.0, 1.225, 340.3)
    m = E.flutter_margin(c, [(0.6, 150.0, "upper")], 0.6)
    assert m["margin_upper_bound"] == pytest.approx(150.0 / (0.6 * 340.3) - 1)
    assert m["note"].endswith("inside the envelope")
    assert E.match_point(c, [(0.6, 150.0, "upper")])["no_match"].endswith(
        "inside the envelope")
    m = E.flutter_margin(c, [(0.4, 500.0, "lower"), (0.6, 480.0, "lower")], 0.6)
    assert m["margin_lower_bound"] == pytest.approx(480.0 / (0.6 * 340.3) - 1)
    assert E.flutter_margin(c, [(0.4, 250.0, "value"), (0.6, 230.0, "value")], 0.6)["margin"] == \
        pytest.approx(230.0 / (0.6 * 340.3) - 1, rel=1e-12)


# ---- issue 30: no interpolation across the transonic range (a match at M 1.424 from 0.9 / 1.5) --
def test_match_point_is_never_interpolated_across_mach_one():
    """U_f - M a changes sign between M 0.9 and M 1.5 only: no match point (the issue's clipped
    delta gave M 1.424 by interpolating across the gap), the reason names both Machs; a sign
    change on one side is still matched, with the usual linear interpolation."""
    c = P.FlightCondition(0.0, 1.225, 340.3)
    a = c.speed_of_sound
    pts = [(0.5, 400.0, "value"), (0.9, 350.0, "value"), (1.5, 420.0, "value")]
    m = E.match_point(c, pts)      # d = U/a - M: +0.675, +0.129, -0.266
    assert m["matched_mach"] is None
    assert m["match_across_sonic"] == [0.9, 1.5]
    assert "between M 0.9 and M 1.5, across M 1" in m["no_match"]
    pts = [(0.5, 400.0, "value"), (0.9, 280.0, "value"), (1.5, 420.0, "value")]
    m = E.match_point(c, pts)      # d: +0.675, -0.077: the crossing lies below M 0.9
    d0, d1 = 400.0 / a - 0.5, 280.0 / a - 0.9
    assert m["matched_mach"] == pytest.approx(0.5 + 0.4 * d0 / (d0 - d1), rel=1e-12)
    assert m["match_across_sonic"] is None


def test_margin_is_never_interpolated_or_extrapolated_across_mach_one():
    c = P.FlightCondition(0.0, 1.225, 340.3)
    pts = [(0.8, 300.0, "value"), (1.2, 500.0, "value")]
    assert E.flutter_margin(c, pts, 1.0)["margin"] is None            # M 1 itself: unknown
    m = E.flutter_margin(c, pts, 0.84)                                 # 0.8 on its side, 0.04 away
    assert m["flutter_speed_ms"] == pytest.approx(300.0)
    assert E.flutter_margin(c, pts, 0.95)["margin"] is None            # 0.15 from 0.8: too far
    assert "same side of M 1" in E.flutter_margin(c, pts, 0.95)["note"]


def test_margin_text_says_inside_or_outside_the_envelope():
    c = P.FlightCondition(0.0, 1.225, 340.3)
    inside = R._margin_text(E.flutter_margin(c, [(0.6, 150.0, "value")], 0.6))
    assert "flutter inside the envelope by 26.5 %" in inside     # 150 / 204.18 - 1 = -26.5 %
    outside = R._margin_text(E.flutter_margin(c, [(0.6, 250.0, "value")], 0.6))
    assert "flutter outside the envelope by 22.4 %" in outside   # 250 / 204.18 - 1 = +22.4 %
