"""[[control_surface]] in the case file (asekit.case.schema), the pipeline's control-surface
outputs (asekit.case.pipeline.control_surfaces) and their summary lines and JSON."""

import math
import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, load_case, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

AILERON = CASES_DIR / "aileron_wing.toml"


def _with_surface(**changes):
    d = tomllib.loads(AILERON.read_text())
    d["control_surface"][0].update(changes)
    return d


def test_shipped_aileron_case_reads():
    case = load_case(AILERON)
    (cs,) = case.control_surfaces
    assert (cs.name, cs.panel, cs.hinge_chord_fraction, cs.span_fraction, cs.kind) == \
        ("aileron", 0, (0.75, 0.75), (0.5, 1.0), "rigid")
    assert cs.hinge_stiffness == 0.5 and cs.hinge_damping == 0.0 and cs.mass_balance == ()


@pytest.mark.parametrize("changes, match", [
    ({"hinge_chord_fraction": [0.75, 1.0]}, r"control_surface\[0\]\.hinge_chord_fraction\[1\]"),
    ({"hinge_chord_fraction": [0.75]}, r"control_surface\[0\]\.hinge_chord_fraction must hold 2"),
    ({"span_fraction": [0.6, 0.5]}, r"control_surface\[0\]\.span_fraction must be \[start, end\]"),
    ({"span_fraction": [0.5, 1.2]}, r"control_surface\[0\]\.span_fraction\[1\]"),
    ({"panel": 1}, r"control_surface\[0\]\.panel must be an integer in \[0, 0\]"),
    ({"kind": "flexible"}, r"control_surface\[0\]\.kind must be one of 'rigid'"),
    ({"hinge_stiffness": -1.0}, r"control_surface\[0\]\.hinge_stiffness"),
    ({"hinge_damping": "x"}, r"control_surface\[0\]\.hinge_damping"),
    ({"name": ""}, r"control_surface\[0\]\.name is missing"),
    ({"hinge": 0.7}, r"control_surface\[0\]\.hinge is not a known key"),
    ({"mass_balance": [{"position": [0.2, 5.0], "mass": 0.1}]},
     r"control_surface\[0\]\.mass_balance\[0\]\.position .* off the planform"),
    ({"mass_balance": [{"position": [0.2, 0.9], "mass": 0.0}]},
     r"control_surface\[0\]\.mass_balance\[0\]\.mass"),
])
def test_every_key_is_checked(changes, match):
    with pytest.raises(CaseError, match=match):
        case_from_dict(_with_surface(**changes))


def test_missing_keys_and_overlapping_surfaces():
    d = _with_surface()
    del d["control_surface"][0]["hinge_stiffness"]
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.hinge_stiffness is missing"):
        case_from_dict(d)
    d = _with_surface()
    d["control_surface"].append(dict(d["control_surface"][0], name="inboard",
                                     span_fraction=[0.2, 0.6]))
    with pytest.raises(CaseError, match=r"control_surface\[1\]\.span_fraction .* overlaps"):
        case_from_dict(d)
    d["control_surface"][1]["name"] = "aileron"
    with pytest.raises(CaseError, match="unique"):
        case_from_dict(d)


def test_fingerprint_without_control_surfaces_is_unchanged_by_the_new_key():
    """A case without [[control_surface]] (and without [[beam]]) hashes as before the keys
    existed (its GAF and result caches stay valid): the empty tuple is left out of the digest."""
    import dataclasses
    import hashlib
    import json
    case = load_case(CASES_DIR / "agard445_6.toml")
    d = dataclasses.asdict(dataclasses.replace(case, structure=None))
    for k in ("name", "reference", "source", "convergence", "control_surfaces", "gust", "beam"):
        d.pop(k)
    for k in ("solver", "section"):     # aero.solver (default "dense"), aero.section (tsd only)
        d["aero"].pop(k)
    old = hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()
    assert case.fingerprint() == old
    assert load_case(AILERON).fingerprint() != case_from_dict(
        _with_surface(hinge_stiffness=1.0)).fingerprint()


@pytest.fixture(scope="module")
def rows():
    return P.control_surfaces(load_case(AILERON))


def test_pipeline_rows_physics(rows):
    """The aileron wing: per Mach, the aileron lifts (dCL/d delta > 0, below dCL/d alpha),
    its hinge moments oppose the deflection and the incidence (C_h < 0, thin-airfoil signs);
    compressibility raises the slopes (M 0.3 over M 0: between 1 and the 2-D Prandtl-Glauert
    factor 1/sqrt(1 - 0.09) = 1.048); the flexible rolling moment ratio is 1 at zero speed and
    reverses below the (antisymmetric) divergence speed."""
    assert [(r.name, r.mach) for r in rows] == [("aileron", 0.0), ("aileron", 0.3)]
    for r in rows:
        assert 0 < r.dCL_ddelta_per_rad < r.dCL_dalpha_per_rad
        assert r.Ch_delta < 0 and r.Ch_alpha < 0
        assert r.effectiveness_ratio[0] == pytest.approx(1.0)
        assert r.reversal_speed_ms is not None and r.divergence_speed_ms is not None
        assert 0 < r.reversal_speed_ms < r.divergence_speed_ms
        assert r.static_unbalance > 0 and r.inertia > 0
        # the flap's lift acts aft of the quarter chord (nose down), the plate's at it; the
        # outboard aileron's lift rolls the wing, its centre of pressure on the half span
        # (0 < roll < the half wing's symmetric lift per rad x its span of 1.2 m)
        assert r.dCm_ddelta_per_rad < 0 and abs(r.dCm_dalpha_per_rad) < 0.05 * r.dCL_dalpha_per_rad
        s_half = 0.3 * 1.2
        assert 0 < r.rolling_moment_per_rad_m3 < r.dCL_ddelta_per_rad * s_half * 1.2
    pg = rows[1].dCL_dalpha_per_rad / rows[0].dCL_dalpha_per_rad
    assert 1.0 < pg < 1.0 / math.sqrt(1 - 0.09) + 1e-9
    assert rows[1].reversal_speed_ms < rows[0].reversal_speed_ms
    i = np.searchsorted(rows[0].speeds_ms, rows[0].reversal_speed_ms)
    assert rows[0].effectiveness_ratio[i - 1] > 0 > rows[0].effectiveness_ratio[i]


def test_summary_lines_and_json_keys(rows):
    a = report.Analysis(None, None, None, None, None, {}, control=rows)
    s = {"control_surfaces": [
        {"name": r.name, "mach": r.mach, "dCL_ddelta_per_rad": r.dCL_ddelta_per_rad,
         "dCL_dalpha_per_rad": r.dCL_dalpha_per_rad, "Ch_delta": r.Ch_delta,
         "Ch_alpha": r.Ch_alpha, "reversal_speed_ms": r.reversal_speed_ms} for r in a.control]}
    lines = report._control_lines(s["control_surfaces"])
    assert lines[1].startswith("control surfaces")
    assert len(lines) == 3 + len(rows)
    assert f"{rows[0].reversal_speed_ms:.1f}" in lines[3]
    for k in ("dCL_ddelta_per_rad", "dCL_dalpha_per_rad", "Ch_delta", "Ch_alpha",
              "reversal_speed_ms"):
        assert k in report.UNITS


@pytest.mark.slow
def test_analyse_json_holds_the_control_surfaces(tmp_path):
    """`asekit analyse aileron_wing --json`: the issue's keys, one row per surface and Mach,
    the summary's control-surface block."""
    import json

    from asekit.cli.main import main
    out = tmp_path / "out.json"
    assert main(["analyse", str(AILERON), "--json", str(out), "--quiet"]) == 0
    s = json.loads(out.read_text())
    rows = s["control_surfaces"]
    assert [r["mach"] for r in rows] == [0.0, 0.3]
    for r in rows:
        assert set(r) >= {"name", "mach", "dCL_ddelta_per_rad", "dCL_dalpha_per_rad",
                          "Ch_delta", "Ch_alpha", "reversal_speed_ms"}
    assert "control_surfaces" in s["seconds"]
    (f0, f1) = s["control_surface_flutter"]
    assert f0["speed_ms"] < s["flutter"][0]["speed_ms"]


def test_control_flutter_lines_name_the_surface():
    rows = [{"mach": 0.0, "density": 1.225, "speed_ms": 12.75, "frequency_hz": 12.08,
             "mode": "aileron", "unstable_at_first_point": False},
            {"mach": 0.3, "density": 1.225, "speed_ms": None, "frequency_hz": None,
             "mode": 2, "unstable_at_first_point": True}]
    lines = report._control_flutter_lines(rows)
    assert lines[1].startswith("flutter with the control surfaces free")
    assert lines[3].split()[-1] == "aileron" and "12.75" in lines[3]
    assert "UNSTABLE AT FIRST POINT" in lines[4] and lines[4].endswith("mode 2")
    assert report._control_flutter_lines(()) == []


@pytest.mark.slow
def test_pipeline_flutter_with_the_hinge_and_a_mass_balance():
    """The shipped aileron wing: free on its hinge spring, the unbalanced aileron flutters far
    below the locked wing (measured at M 0: 12.8 against 24.6 m/s); over-balanced by 0.4 kg
    5 cm ahead of the hinge (case key control_surface[0].mass_balance) the first flutter is the
    wing's own again (measured 24.7 m/s), within 5 % of the locked wing's."""
    free = P.control_surface_flutter(load_case(AILERON))
    locked = P.flutter(load_case(AILERON)).results
    balanced = P.control_surface_flutter(case_from_dict(_with_surface(
        mass_balance=[{"position": [0.175, 0.9], "mass": 0.4}])))
    for f, lk, b in zip(free, locked, balanced):
        assert f.speed_ms < 0.7 * lk.flutter.speed
        assert b.speed_ms == pytest.approx(lk.flutter.speed, rel=0.05)


def test_report_figure_of_the_effectiveness(rows):
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from asekit.case.report_figures import SECTIONS, fig_control_effectiveness
    a = SimpleNamespace(case=SimpleNamespace(name="aileron_wing"), control=rows)
    rf = fig_control_effectiveness(a)
    try:
        assert rf.section == SECTIONS[-1] == "Control surfaces"
        assert f"reversal at {rows[0].reversal_speed_ms:.1f} m/s" in rf.alt
        assert len(rf.figure.axes[0].lines) >= len(rows)
    finally:
        plt.close(rf.figure)
