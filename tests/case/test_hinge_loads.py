"""Hinge moments over the flight envelope for servo sizing (issue 25):
asekit.aero.control_surface.dimensional_hinge_moments, asekit.case.pipeline.
control_surface_hinge_loads, the analysis JSON keys control_surface_hinge_moments /
control_surface_servo_sizing and their summary lines (asekit.case.report)."""

import math
import tomllib

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.control_surface import (
    ControlSurface,
    dimensional_hinge_moments,
    hinge_moments,
    hinged_mesh,
    steady_control_derivatives,
)
from asekit.atmosphere import standard_atmosphere
from asekit.case import case_from_dict, load_case, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

FIN_TAB = CASES_DIR / "nalci2013_fin_tab.toml"
AILERON = CASES_DIR / "aileron_wing.toml"


def test_rigid_hinge_moment_is_the_pressure_integral_and_scales_with_q():
    """A 1 m x 3 m wing (wall image) with a 25 % flap: H_delta / q equals the box sum
    -sum d DeltaCp A of the deflection's pressures (asekit.aero.control_surface.hinge_moments,
    the work-conjugate of delta), and doubling q doubles H (a rigid surface, fixed Mach)."""
    hm = hinged_mesh(TrapezoidSurface((0, 0), 1.0, (0, 3.0), 1.0, 8, 12),
                     ControlSurface("f", 0.75, 0.75))
    d = steady_control_derivatives(hm, 0.0, symmetric=True)
    from asekit.aero.control_surface import deflection_modes
    from asekit.aero.vlm import steady_pressure
    cp = steady_pressure(hm.mesh, 0.0, deflection_modes(hm).normalwash(0.0, 1.0).real, True)
    h_box = hinge_moments(hm, cp)[0, 0]                       # H / q, m^3
    h1, a1 = dimensional_hinge_moments(hm, d, 1000.0)
    h2, a2 = dimensional_hinge_moments(hm, d, 2000.0)
    assert h1[0] == pytest.approx(1000.0 * h_box, rel=1e-12)
    assert h2[0] == pytest.approx(2.0 * h1[0], rel=1e-14) and a2[0] == pytest.approx(2.0 * a1[0])
    assert h1[0] < 0 and a1[0] < 0
    assert dimensional_hinge_moments(hm, d, 0.0)[0][0] == 0.0
    with pytest.raises(ValueError, match="dynamic_pressure"):
        dimensional_hinge_moments(hm, d, -1.0)


@pytest.fixture(scope="module")
def fin_rows():
    return P.control_surface_hinge_loads(load_case(FIN_TAB))


def test_fin_tab_hinge_moments_over_the_envelope(fin_rows):
    """The fin's envelope (M 0.4-0.6, 0-5000 m; the analysed Machs 0.4, 0.6 are its ends):
    four corner points, U = M a(h) and q = rho U^2 / 2 from the 1976 standard atmosphere;
    at one Mach the two altitudes' hinge moments are in the ratio of their dynamic pressures
    (rigid surface: H = q S_f c_f C_h(M)); the largest |H| is at the highest q
    (M 0.6, sea level: 25.5 kPa)."""
    pts = [(r.mach, r.altitude) for r in fin_rows]
    assert pts == [(0.4, 0.0), (0.6, 0.0), (0.4, 5000.0), (0.6, 5000.0)]
    for r in fin_rows:
        atm = standard_atmosphere(r.altitude)
        assert r.speed_ms == pytest.approx(r.mach * float(atm.speed_of_sound), rel=1e-12)
        assert r.dynamic_pressure == pytest.approx(0.5 * r.density * r.speed_ms ** 2)
        assert r.basis == "envelope" and r.hinge_moment_per_delta < 0
    for m in (0.4, 0.6):
        lo, hi = [r for r in fin_rows if r.mach == m]
        assert hi.hinge_moment_per_delta / lo.hinge_moment_per_delta == pytest.approx(
            hi.dynamic_pressure / lo.dynamic_pressure, rel=1e-12)
        assert hi.hinge_moment_per_alpha / lo.hinge_moment_per_alpha == pytest.approx(
            hi.dynamic_pressure / lo.dynamic_pressure, rel=1e-12)
    s = report.hinge_load_json(fin_rows)
    (size,) = s["control_surface_servo_sizing"]
    assert (size["mach"], size["altitude_m"]) == (0.6, 0.0)
    assert size["max_abs_hinge_moment_per_delta_Nm_per_rad"] == min(
        r.hinge_moment_per_delta for r in fin_rows)
    assert len(s["control_surface_hinge_moments"]) == 4
    for row in s["control_surface_hinge_moments"] + s["control_surface_servo_sizing"]:
        for k in row:
            assert k in report.UNITS or k in ("name", "mach"), k
    lines = report._hinge_load_lines(s["control_surface_servo_sizing"])
    assert lines[1].startswith("hinge moments for servo sizing")
    assert f"{size['max_abs_hinge_moment_per_delta_Nm_per_rad'] * math.pi / 180:.4g}" in lines[3]
    assert report.hinge_load_json(()) == {} and report._hinge_load_lines(()) == []


def test_without_an_envelope_the_top_of_the_sweep_and_no_supersonic_points():
    """The aileron wing has no [flight.envelope]: every subsonic analysed Mach at the top of
    the velocity sweep (40 m/s, sea level); a Mach >= 1 added to aero.machs gives no point (the
    vortex lattice is subsonic); with an envelope its altitudes are used."""
    rows = P.control_surface_hinge_loads(load_case(AILERON))
    assert [(r.mach, r.speed_ms, r.basis) for r in rows] == [(0.0, 40.0, "sweep top"),
                                                             (0.3, 40.0, "sweep top")]
    d = tomllib.loads(AILERON.read_text())
    d["aero"]["machs"], d["aero"]["method"] = [0.3, 1.2], "auto"
    d["control_surface"][0].pop("actuator")     # (its Mach 0 now outside aero.machs)
    d["flight"]["envelope"] = {"mach": [0.1, 0.3], "altitude": [0.0, 1000.0]}
    env = P.control_surface_hinge_loads(case_from_dict(d))
    assert sorted({r.mach for r in env}) == [0.1, 0.3]
    assert sorted({r.altitude for r in env}) == [0.0, 1000.0]
    assert np.all([r.basis == "envelope" for r in env])


def test_report_figure_of_the_hinge_moments(fin_rows):
    """The report's servo-sizing figure: one series per surface and Mach through the origin,
    its last point the largest q of that Mach, the alt text quoting the largest |H|."""
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from asekit.case.report_figures import SECTIONS, fig_control_hinge_moments
    a = SimpleNamespace(case=SimpleNamespace(name="nalci2013_fin_tab"), control_hinge=fin_rows)
    rf = fig_control_hinge_moments(a)
    try:
        assert rf.section == SECTIONS[-1]
        lines = rf.figure.axes[0].get_lines()
        series = [ln for ln in lines if ln.get_label().startswith("tab")]
        assert [ln.get_label() for ln in series] == ["tab, M 0.4", "tab, M 0.6"]
        x, y = series[1].get_data()
        assert x[0] == 0.0 and y[0] == 0.0
        assert y[-1] == pytest.approx(fin_rows[1].hinge_moment_per_delta * math.pi / 180)
        assert "largest" in rf.alt and "M 0.6" in rf.alt
    finally:
        plt.close(rf.figure)
