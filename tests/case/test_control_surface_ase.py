"""The actuator on a control surface in the case file ([control_surface.actuator], issue 25):
schema keys and their errors, pipeline.control_surface_ase and its JSON rows.

The loops run on a coarse copy of the shipped aileron wing (4 x 8 elements and boxes, the
hinge and the aileron's inboard edge still on element lines) so the test stays fast."""

import math
import tomllib

import pytest

from asekit.case import CaseError, case_from_dict, load_case, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

AILERON = CASES_DIR / "aileron_wing.toml"


def _coarse(**actuator):
    d = tomllib.loads(AILERON.read_text())
    d["case"]["name"] = "aileron_wing_coarse"
    d["panel"][0].update(n_chord=4, n_span=8)
    d["aero"]["boxes"] = [{"n_chord": 4, "n_span": 8}]
    d["control_surface"][0]["actuator"] = actuator
    return d


def test_shipped_aileron_case_carries_the_actuator():
    case = load_case(AILERON)
    a = case.control_surfaces[0].actuator
    assert a is not None and a.speed > 0 and a.mach == 0.0


@pytest.mark.parametrize("actuator, path", [
    ({}, "control_surface[0].actuator.speed"),
    ({"speed": -1.0}, "control_surface[0].actuator.speed"),
    ({"speed": 15.0, "mach": 0.5}, "control_surface[0].actuator.mach"),
    ({"speed": 15.0, "altitude": -1.0e5}, "control_surface[0].actuator.altitude"),
    ({"speed": 15.0, "gain": 3.0}, "control_surface[0].actuator.gain"),
])
def test_actuator_key_errors_name_the_path(actuator, path):
    with pytest.raises(CaseError, match=path.replace("[", r"\[").replace("]", r"\]")):
        case_from_dict(_coarse(**actuator))


def test_without_an_actuator_the_fingerprint_is_unchanged():
    d = _coarse(speed=15.0)
    d["control_surface"][0].pop("actuator")
    plain = case_from_dict(d)
    assert plain.control_surfaces[0].actuator is None
    assert P.control_surface_ase(plain) == ()
    assert case_from_dict(_coarse(speed=15.0)).fingerprint() != plain.fingerprint()


@pytest.fixture(scope="module")
def rows_15():
    return P.control_surface_ase(case_from_dict(_coarse(speed=15.0, step_deg=2.0)))


def test_low_speed_loops_are_stable_with_thesis_like_margins(rows_15):
    """At 15 m/s (below the locked-aileron flutter speed, about 24 m/s) both loops are
    stable; the actuator's forward path keeps the servo chapter's phase margin (System 3:
    78.4 deg with J_fin, thesis Table 17; the aileron's inertia is close to the fin's)."""
    assert [r.topology for r in rows_15] == ["AEM1", "AEM2"]
    hinge_inertia = P.control_surface_model(
        case_from_dict(_coarse(speed=15.0))).inertia[0]
    for r in rows_15:
        assert r.stable and r.max_real_pole < 0
        assert 0 < r.effective_inertia < hinge_inertia
        assert 70 < r.phase_margin_deg < 85
        assert r.dynamic_pressure == pytest.approx(0.5 * 1.225 * 15.0 ** 2, rel=1e-3)
    for r in rows_15:                        # the fed-back angle settles (2 %) fast
        assert r.settling_time_s is not None and r.settling_time_s < 0.05
    aem1, aem2 = rows_15
    # AEM2 feeds back the surface's own angle: it holds it; AEM1 holds the hinge angle, the
    # wing's twist under the aileron's load stays in the surface's angle (2.6 % measured)
    assert aem2.steady_error < 0.01 < aem1.steady_error


def test_above_the_locked_aileron_flutter_speed_the_loop_is_unstable():
    rows = P.control_surface_ase(case_from_dict(_coarse(speed=30.0)))
    assert not any(r.stable for r in rows)


def test_json_rows_and_units(rows_15):
    j = report.control_ase_json(rows_15)["control_surface_ase"]
    assert [r["topology"] for r in j] == ["AEM1", "AEM2"]
    for r in j:
        for k in r:
            assert k in report.UNITS or k == "name", k
        assert math.isfinite(r["phase_margin_deg"])
    assert report.control_ase_json(()) == {}


def test_summary_lines(rows_15):
    j = report.control_ase_json(rows_15)["control_surface_ase"]
    lines = report._control_ase_lines(j)
    assert lines[1].startswith("actuator on aileron") and "15 m/s" in lines[1]
    assert lines[3].split()[:2] == ["AEM1", "yes"] and lines[4].split()[:2] == ["AEM2", "yes"]
    assert report._control_ase_lines(()) == []


def test_actuated_surface_on_a_fin_with_its_rigid_pitch_mode_is_refused():
    """The thesis fin with a tab keeps its rigid pitch mode (the shaft's actuator): the tab's
    actuator cannot be a second prescribed coordinate; the error names the key."""
    d = tomllib.loads((CASES_DIR / "nalci2013_fin_tab.toml").read_text())
    d["control_surface"][0]["actuator"] = {"speed": 100.0, "mach": 0.5}
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.actuator needs a wing without"):
        case_from_dict(d)
