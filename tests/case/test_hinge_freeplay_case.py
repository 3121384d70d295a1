"""control_surface[i].freeplay_deg (asekit.case.schema), the pipeline's hinge-freeplay LCO
onset (asekit.case.pipeline.control_surface_freeplay) and its keys in the control_surfaces
JSON rows (asekit.case.report)."""

import tomllib

import pytest

from asekit.case import CaseError, case_from_dict, load_case, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

AILERON = CASES_DIR / "aileron_wing.toml"


def _case(**changes):
    d = tomllib.loads(AILERON.read_text())
    d["control_surface"][0].update(changes)
    d["control_surface"][0].pop("actuator", None)
    return d


@pytest.mark.parametrize("changes, match", [
    ({"freeplay_deg": -0.1}, r"control_surface\[0\]\.freeplay_deg"),
    ({"freeplay_deg": 12.0}, r"control_surface\[0\]\.freeplay_deg"),
    ({"freeplay_deg": "x"}, r"control_surface\[0\]\.freeplay_deg"),
    ({"freeplay_deg": 0.5, "hinge_stiffness": 0.0},
     r"control_surface\[0\]\.freeplay_deg = 0\.5 needs control_surface\[0\]\.hinge_stiffness"),
])
def test_freeplay_key_is_checked(changes, match):
    with pytest.raises(CaseError, match=match):
        case_from_dict(_case(**changes))


def test_default_is_no_freeplay_and_no_rows():
    case = load_case(AILERON)
    assert case.control_surfaces[0].freeplay_deg == 0.0
    assert P.control_surface_freeplay(case) == ()
    assert report.freeplay_json((), "aileron", 0.0) == {}


@pytest.fixture(scope="module")
def rows():
    d = _case(freeplay_deg=0.5)
    d["aero"]["machs"] = [0.0]
    d["flight"]["velocities"] = {"min": 0.5, "max": 20.0, "step": 0.5}
    return P.control_surface_freeplay(case_from_dict(d))


def test_freeplay_rows(rows):
    """The shipped aileron wing with a 0.5 deg gap at Mach 0, swept from 0.5 m/s: the
    unbalanced aileron is unstable inside the gap (no hinge stiffness) from a very low speed
    (measured onset 1.22 m/s; below the shipped sweep's first speed, 2 m/s, so analyse reports
    it at its first point), far below the linear flutter; the linear flutter with the full spring (state space, measured 12.99
    m/s) lies within 3 % of the hinge-free p-k flutter speed 12.75 m/s (data/cases/
    aileron_wing.toml, tests/case/test_control_surfaces.py) and above the onset."""
    (r,) = rows
    assert (r.name, r.mach, r.freeplay_deg) == ("aileron", 0.0, 0.5)
    assert not r.lco_at_first_point and 0.5 < r.lco_onset_speed_ms < 2.0
    assert r.linear_flutter_speed_ms == pytest.approx(12.75, rel=0.03)
    assert r.lco_onset_speed_ms < r.linear_flutter_speed_ms
    j = report.freeplay_json(rows, "aileron", 0.0)
    assert j == {"freeplay_deg": 0.5, "lco_onset_speed_ms": r.lco_onset_speed_ms,
                 "lco_at_first_point": False,
                 "freeplay_linear_flutter_speed_ms": r.linear_flutter_speed_ms}
    assert report.freeplay_json(rows, "aileron", 0.3) == {}
    for k in j:
        assert k in report.UNITS
