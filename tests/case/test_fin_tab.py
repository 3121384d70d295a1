"""The all-movable fin with a trailing-edge tab (data/cases/nalci2013_fin_tab.toml, issue 25)
and several control surfaces on one panel (inboard + outboard ailerons on the aileron wing)
through the case layer (asekit.case.pipeline.control_surfaces / control_surface_flutter)."""

import tomllib

import numpy as np
import pytest

from asekit.aero.control_surface import glauert_flap_effectiveness
from asekit.case import case_from_dict, load_case
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

FIN_TAB = CASES_DIR / "nalci2013_fin_tab.toml"
AILERON = CASES_DIR / "aileron_wing.toml"


def _fin(k_h=None, machs=(0.4,), altitudes=(0.0,)):
    d = tomllib.loads(FIN_TAB.read_text())
    d["aero"]["machs"] = list(machs)
    d["flight"]["altitudes"] = list(altitudes)
    if k_h is not None:
        d["control_surface"][0]["hinge_stiffness"] = k_h
    return case_from_dict(d)


def test_shipped_fin_tab_case_reads_and_its_tab_is_on_element_lines():
    """The thesis fin (one panel, shaft support, rigid pitch kept) with one tab aft of 5/6 of
    the chord over the inboard 4/7 of the span: the modes of the locked fin are the thesis
    fin's (the same structure: nalci2013_fin.toml); the tab's static unbalance and inertia
    are those of a thin plate strip (S = m c_f / 2, I = m c_f^2 / 3 with its mean chord
    c_f and mass m from its area and mean thickness), within 10 % (measured -5.3 % and -3.9 %:
    the 6 x 7 mesh's nodes on the hinge shared half-half, the thickness tapering across it)."""
    case = load_case(FIN_TAB)
    (cs,) = case.control_surfaces
    assert cs.name == "tab" and cs.panel == 0 and cs.hinge_stiffness == 20.0
    base = load_case(CASES_DIR / "nalci2013_fin.toml")
    assert np.allclose(P.modal_model(case).frequencies_hz, P.modal_model(base).frequencies_hz)
    fm = P.control_surface_model(case)
    hm = P.control_surface_mesh(case)
    area, c_f = hm.surface_area(0), hm.mean_chord(0)
    t_mean = 0.004 - 0.002 * (4 / 7) / 2              # root 4 mm to 2 mm at the tip, linear
    m = 2700.0 * t_mean * area
    assert fm.static_unbalance[0] == pytest.approx(m * c_f / 2, rel=0.10)
    assert fm.inertia[0] == pytest.approx(m * c_f ** 2 / 3, rel=0.10)


def test_fin_tab_derivatives():
    """The tab lifts (dCL/d delta > 0) less than the fin pitching (a part of its chord and
    span: measured (dCL/d delta) / (dCL/d alpha) = 0.364 at M 0.4, below Glauert's 2-D
    full-span tau(1/6) = 0.505), and both hinge moments oppose the motion (C_h < 0).
    Compressibility raises the slopes from M 0.4 to M 0.6 by less than the 2-D
    Prandtl-Glauert ratio sqrt(0.84 / 0.64) = 1.146."""
    rows = P.control_surfaces(_fin(machs=(0.4, 0.6)))
    assert [(r.name, r.mach) for r in rows] == [("tab", 0.4), ("tab", 0.6)]
    tau = glauert_flap_effectiveness(1 / 6)
    for r in rows:
        assert 0 < r.dCL_ddelta_per_rad < tau * r.dCL_dalpha_per_rad
        assert r.Ch_delta < 0 and r.Ch_alpha < 0
    for key in ("dCL_dalpha_per_rad", "dCL_ddelta_per_rad"):
        ratio = getattr(rows[1], key) / getattr(rows[0], key)
        assert 1.0 < ratio < (0.84 / 0.64) ** 0.5


def test_fin_flutter_with_a_stiff_tab_linkage_is_the_locked_fins():
    """A linkage of 1e6 N m/rad (tab frequency 95 kHz) locks the tab: flutter at M 0.4, sea
    level within 1 % of the locked fin's (P.flutter; the boxes differ, cut along the tab's
    hinge and edge: measured 208.2 against 207.6 m/s, +0.3 %), the same mode (2)."""
    stiff = _fin(k_h=1e6)
    (row,) = P.control_surface_flutter(stiff)
    locked = P.flutter(stiff).results[0].flutter
    assert row.speed_ms == pytest.approx(locked.speed, rel=0.01)
    assert row.mode == 2 and locked.mode - locked.n_rigid + 1 == 2


@pytest.mark.slow
def test_fin_flutter_falls_as_the_tab_linkage_softens():
    """The tab's hinge frequency falling toward the fin's modes (424 Hz at 20 N m/rad, 134 Hz
    at 2 N m/rad) lowers the flutter speed at M 0.4, sea level: measured 208.2 (locked),
    205.2 (the shipped 20 N m/rad), 173.3 m/s (2 N m/rad); at 0.5 N m/rad (67 Hz, below the
    fin's pitch mode) the fin is unstable from the first speed of the sweep (100 m/s)."""
    speeds = [P.control_surface_flutter(_fin(k_h=k))[0].speed_ms for k in (1e6, 20.0, 2.0)]
    assert speeds[0] > speeds[1] > speeds[2]
    assert speeds[1] > 0.95 * speeds[0] and speeds[2] < 0.9 * speeds[0]
    assert P.control_surface_flutter(_fin(k_h=0.5))[0].unstable_at_first_point


def test_inboard_and_outboard_ailerons_superpose_to_the_full_span_one():
    """Two ailerons on one panel, inboard (0-0.5 of the span) and outboard (0.5-1): the
    hinged boxes are those of a single full-span aileron (the cut at half span is an element
    line of both), so by linearity the two lift slopes add up to the full-span one (1e-9),
    dCL/d alpha is unchanged; the modal model carries one hinge coordinate each. Rolling
    (antisymmetric image): the outboard aileron reverses below the divergence speed
    (measured 27.3 against 29.7 m/s), the inboard one, near the stiff root, gains
    effectiveness up to divergence (measured ratio 8.0 at 0.999 q_D)."""
    d = tomllib.loads(AILERON.read_text())
    d["aero"]["machs"] = [0.0]
    full = dict(d["control_surface"][0], span_fraction=[0.0, 1.0])
    full.pop("actuator")                        # (one surface only may carry it)
    inboard = dict(full, name="inboard", span_fraction=[0.0, 0.5])
    outboard = dict(full, name="outboard", span_fraction=[0.5, 1.0])
    two = case_from_dict(dict(d, control_surface=[inboard, outboard]))
    one = case_from_dict(dict(d, control_surface=[full]))
    r_two, (r_one,) = P.control_surfaces(two), P.control_surfaces(one)
    assert [r.name for r in r_two] == ["inboard", "outboard"]
    assert P.control_surface_mesh(two).mesh.n == P.control_surface_mesh(one).mesh.n
    assert r_two[0].dCL_ddelta_per_rad + r_two[1].dCL_ddelta_per_rad == \
        pytest.approx(r_one.dCL_ddelta_per_rad, rel=1e-9)
    assert r_two[0].dCL_dalpha_per_rad == pytest.approx(r_one.dCL_dalpha_per_rad, rel=1e-9)
    fm = P.control_surface_model(two)
    assert fm.names == ("inboard", "outboard") and fm.modal.M.shape[0] == fm.n_wing + 2
    assert r_two[0].reversal_speed_ms is None and r_two[0].effectiveness_ratio[-1] > 1.0
    assert 0 < r_two[1].reversal_speed_ms < r_two[1].divergence_speed_ms
