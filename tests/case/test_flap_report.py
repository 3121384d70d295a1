"""The control surfaces in the analysis JSON and report (issue 25): each row names the surface's
``kind`` and gives its hinge inertia and static unbalance about the hinge, and the report shows
the actuator-on-flap loop (AEM1, AEM2: the power-limited step and the open-loop Bode plot with
its margins) with the loop's margins in the JSON.

Reference numbers: the aileron of data/cases/aileron_wing.toml is a uniform 2 mm aluminium
plate strip (density 2700 kg/m^3) of chord c_f = 0.075 m aft of the hinge and span b = 0.6 m,
so its mass m = rho h b c_f = 0.243 kg; the strip integrals about the hinge line are
S = int x dm = m c_f / 2 and I_h = int (x^2 + z^2) dm = m (c_f^2 / 3 + h^2 / 12) (translation
plus the plate's rotary inertia), exact for the elastic kind's consistent mass. The rigid
kind's hinge rotation (the surface's nodes rotated rigidly, the edge nodes included) also moves
part of the wing elements that touch its inboard side edge, a strip one element wide that
shrinks as the spanwise mesh is refined (measured: the excess does not change with the
chordwise mesh).

The runs use a coarse copy of the shipped case (4 x 8 elements and boxes, the hinge and the
aileron's inboard edge still on element lines) so the tests stay fast."""

import json
import math
import tomllib

import numpy as np
import pytest

from asekit.case import case_from_dict, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

AILERON = CASES_DIR / "aileron_wing.toml"
RHO, H, C_F, B = 2700.0, 0.002, 0.075, 0.6
MASS = RHO * H * B * C_F
S_EXACT = MASS * C_F / 2
I_EXACT = MASS * (C_F ** 2 / 3 + H ** 2 / 12)


def _coarse(n_chord=4, n_span=8, **surface):
    d = tomllib.loads(AILERON.read_text())
    d["case"]["name"] = "aileron_wing_coarse"
    d["panel"][0].update(n_chord=n_chord, n_span=n_span)
    d["aero"]["boxes"] = [{"n_chord": n_chord, "n_span": n_span}]
    d["flight"]["velocities"] = {"min": 2.0, "max": 40.0, "step": 2.0}
    d["control_surface"][0].update(surface)
    return d


def _rows(d):
    case = case_from_dict(d)
    return report.control_surfaces_json(case, P.control_surfaces(case))


def test_elastic_rows_name_the_kind_and_hold_the_exact_strip_integrals():
    d = _coarse(kind="elastic")
    d["control_surface"][0].pop("actuator")
    rows = _rows(d)
    assert [(r["name"], r["kind"], r["mach"]) for r in rows] == [("aileron", "elastic", 0.0),
                                                                 ("aileron", "elastic", 0.3)]
    for r in rows:
        assert r["hinge_inertia_kgm2"] == pytest.approx(I_EXACT, rel=1e-7)
        assert r["static_unbalance_kgm"] == pytest.approx(S_EXACT, rel=1e-7)
        for k in r:
            assert k in report.UNITS or k == "name", k


def test_rigid_rows_converge_to_the_strip_integrals():
    """The rigid kind's inertia and unbalance exceed the exact strip integrals by the wing
    elements at the surface's inboard edge; the excess shrinks as the spanwise mesh is refined
    (8 -> 16 elements: halved, since the strip is one element wide; measured I_h 8.3 % -> 4.2 %
    and S 12.5 % -> 6.25 % over the exact values)."""
    errs = []
    for n in (8, 16):
        d = _coarse(n_span=n)
        d["control_surface"][0].pop("actuator")
        r = _rows(d)[0]
        assert r["kind"] == "rigid"
        errs.append((r["hinge_inertia_kgm2"] / I_EXACT - 1,
                     r["static_unbalance_kgm"] / S_EXACT - 1))
    (ei4, es4), (ei8, es8) = errs
    assert ei8 == pytest.approx(0.5 * ei4, rel=0.1) and es8 == pytest.approx(0.5 * es4, rel=0.1)
    assert 0 < ei8 < 0.05 and 0 < es8 < 0.07


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    a = report.run_analysis(case_from_dict(_coarse()))
    d = tmp_path_factory.mktemp("flap_report")
    index = report.write_report(a, d / "report")
    return a, index.read_text(), json.loads((index.parent / "summary.json").read_text())


def test_summary_table_names_the_kind_and_the_hinge_moments_of_mass(written):
    _, page, s = written
    lines = report._control_lines(s["control_surfaces"])
    r = s["control_surfaces"][0]
    assert lines[2].split()[:2] == ["surface", "kind"]
    cells = lines[3].split()
    assert cells[:2] == ["aileron", "rigid"]
    assert cells[-2:] == [f"{1e3 * r['hinge_inertia_kgm2']:.4g}",
                          f"{1e3 * r['static_unbalance_kgm']:.4g}"]
    assert all(len(x) <= 100 for x in lines)               # format_summary's width
    assert lines[3] in page                                 # the report's summary table


def test_report_shows_the_actuator_on_flap_loop(written):
    a, page, _ = written
    figs = report.figures(a)
    for name in ("control_ase_steps", "control_ase_bode"):
        assert f"src='{name}.png'" in page
        f = figs[name]
        assert f.section == "Control surfaces"
        title = f.figure._suptitle.get_text()
        assert title.startswith("aileron_wing_coarse: actuator on aileron")
        for ax in f.figure.axes:
            assert "(" in ax.get_ylabel()                           # every axis with its unit
        assert "(ms)" in f.figure.axes[0].get_xlabel() or name == "control_ase_bode"
    bode_alt = figs["control_ase_bode"].alt
    for r in a.control_ase:                                         # the margins in the alt text
        assert f"{r.topology} PM {r.phase_margin_deg:.1f} deg" in bode_alt


def test_json_holds_each_topologys_margins_and_settling(written):
    a, _, s = written
    assert [r["kind"] for r in s["control_surfaces"]] == ["rigid", "rigid"]
    rows = s["control_surface_ase"]
    assert [(r["name"], r["topology"]) for r in rows] == [("aileron", "AEM1"), ("aileron", "AEM2")]
    for r, row in zip(rows, a.control_ase):
        # thesis System 3 keeps ~78 deg (Table 17: 78.4 deg with J_fin) on the aileron's hinge
        assert 70 < r["phase_margin_deg"] < 85
        assert r["settling_ms"] == pytest.approx(1e3 * r["settling_s"])
        assert 0 < r["settling_ms"] < 50
        gm = row.gain_margin_db
        assert r["gain_margin_db"] == (gm if math.isfinite(gm) else None)
        # the margin is the open loop's: |L| at the stored gain crossover is 1 (0 dB)
        f_c = r["crossover_hz"]
        mag = abs(_interp(row.frequency_hz, row.open_loop, f_c))
        assert 20 * math.log10(mag) == pytest.approx(0.0, abs=0.2)
        for k in r:
            assert k in report.UNITS or k == "name", k


def _interp(f, h, x):
    """h (complex) at x, linear in log f."""
    lf = np.log(f)
    return complex(np.interp(math.log(x), lf, h.real), np.interp(math.log(x), lf, h.imag))
