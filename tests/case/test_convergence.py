"""The discretisation-error study of asekit.case.convergence (issue 23, "every flutter result
with an error bar"): Richardson extrapolation with the observed order (Celik et al. 2008) and
Roache's (1994) grid convergence index, the study's meshes, its case-file keys, and the study
on AGARD 445.6 (data/cases/agard445_6.toml) and on the fin with a graded mesh around its
distributed shaft (asekit.case.variants.with_shaft_grading).

Reference numbers: AGARD 445.6 weakened wing 3 at M 0.499, Yates (1987) AGARD R-765 / NASA
TM-100492 (the case file's comments and [flutter_speed_index]): measured flutter speed index
0.4459 at b_s = 0.2789 m, f_alpha = 38.10 Hz, mu = 33.465, i.e.
U_f = 0.4459 b_s 2 pi f_alpha sqrt(mu) = 172.2 m/s; omega_f / omega_alpha 0.5353.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from asekit.case import load_case, pipeline
from asekit.case.convergence import (
    FS_ASSUMED,
    FS_OBSERVED,
    add_to_summary,
    cell_size,
    check_study,
    convergence_study,
    extrapolate,
    format_study,
    observed_order,
    study_meshes,
)
from asekit.case.schema import CaseError, ConvergenceSpec, case_from_dict
from asekit.case.variants import with_boxes, with_mesh, with_shaft, with_shaft_grading
from asekit.structure.mesh import Grading, Stations
from asekit.util.paths import CASES_DIR, FIN_FILE

pytestmark = pytest.mark.usefixtures("session_gaf_cache")

AGARD = CASES_DIR / "agard445_6.toml"
#: Yates (1987): FSI 0.4459 -> U_f = 0.4459 * 0.2789 * 2 pi 38.10 * sqrt(33.465) m/s.
YATES_SPEED = 0.4459 * 0.2789 * 2 * math.pi * 38.10 * math.sqrt(33.465)


# ---------------------------------------------------------------------------------------------
# Richardson extrapolation and the GCI
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("p", [0.8, 1.0, 1.5, 2.0, 3.0])
@pytest.mark.parametrize("h", [(1.0, 2.0, 4.0), (1.0, 1.5, 2.25), (1.0, 1.3, 2.1)])
def test_observed_order_and_limit_of_a_power_law(p, h):
    """phi = 250 - 40 h^p: the observed order is p and the extrapolation the limit 250, also
    for unequal refinement ratios (Celik et al. 2008 Eq. 3b, q(p) != 0)."""
    phi = [250.0 - 40.0 * x ** p for x in h]
    assert observed_order(phi, h) == pytest.approx(p, rel=1e-8)
    e = extrapolate(phi, h)
    assert e.observed and e.order == pytest.approx(p, rel=1e-8)
    assert e.value == pytest.approx(250.0, abs=1e-8)
    assert e.error == pytest.approx(FS_OBSERVED * abs(250.0 - phi[0]), rel=1e-8)


def test_gci_bounds_the_error_of_a_power_law_with_a_higher_order_term():
    """With a second term (phi = 250 - 40 h - 10 h^2) the GCI (F_s = 1.25) still contains the
    exact value 250 around the finest result, and the extrapolation is closer than it."""
    h = (0.1, 0.15, 0.225)
    phi = [250.0 - 40.0 * x - 10.0 * x * x for x in h]
    e = extrapolate(phi, h)
    assert e.observed
    assert abs(250.0 - phi[0]) <= e.error
    assert abs(250.0 - e.value) < abs(250.0 - phi[0])


def test_two_meshes_assume_the_order_and_the_larger_safety_factor():
    e = extrapolate([250.0, 245.0], [1.0, 2.0], order=2.0)
    assert not e.observed and e.order == 2.0
    assert e.value == pytest.approx(250.0 + 5.0 / 3.0)
    assert e.error == pytest.approx(FS_ASSUMED * 5.0 / 3.0)


def test_oscillating_results_get_at_least_their_spread():
    """No observed order (e_32 / e_21 < 0): the assumed order and an error bar of at least the
    spread of the three values, never the small GCI of two meshes that happen to agree."""
    phi = [253.0, 253.02, 246.95]            # the fin at 48x32 / 32x21 / 21x14 (measured)
    assert observed_order(phi, [1.0, 1.5, 2.25]) is None
    e = extrapolate(phi, [1.0, 1.5, 2.25])
    assert not e.observed and e.error >= max(phi) - min(phi)


@pytest.mark.parametrize("phi", [[250.0, 250.0, 240.0], [250.0, 245.0, 244.0],
                                 [250.0, 245.0, 250.0]])
def test_no_order_without_monotone_convergence(phi):
    assert observed_order(phi, [1.0, 2.0, 4.0]) is None


@pytest.mark.parametrize("args, match", [(([1.0], [1.0]), "2 or 3 results"),
                                         (([1.0, 2.0], [2.0, 1.0]), "grow from the finest"),
                                         (([1.0, 2.0], [1.0, 2.0], 0.0), "order must be > 0")])
def test_extrapolate_refuses_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        extrapolate(*args)


# ---------------------------------------------------------------------------------------------
# the meshes and the case-file keys
# ---------------------------------------------------------------------------------------------
def test_study_meshes_divide_elements_and_boxes_and_keep_the_grading():
    fin = with_shaft(load_case(FIN_FILE), radius=0.005)
    case = with_boxes(with_shaft_grading(fin, 64, 48), 28, 20)
    cases = study_meshes(case, ConvergenceSpec(meshes=3, ratio=2.0))
    assert [(c.panels[0].n_chord, c.panels[0].n_span) for c in cases] == [(64, 48), (32, 24),
                                                                          (16, 12)]
    assert [c.aero.boxes for c in cases] == [((28, 20),), ((14, 10),), ((7, 5),)]
    assert all(c.panels[0].chord_spacing == case.panels[0].chord_spacing for c in cases)
    assert isinstance(cases[2].panels[0].span_spacing, Grading)
    h = [cell_size(c) for c in cases]
    assert h[1] / h[0] == pytest.approx(2.0) and h[2] / h[1] == pytest.approx(2.0)


def test_automatic_boxes_are_coarsened_from_the_mesh_rules():
    fin = load_case(FIN_FILE)                    # aero.boxes automatic: 14 x 10 (thesis rules)
    cases = study_meshes(with_mesh(fin, 12, 14), ConvergenceSpec(meshes=2, ratio=2.0))
    assert cases[1].aero.boxes == ((7, 5),)


def test_too_coarse_a_study_is_refused_before_any_computation():
    fin = load_case(FIN_FILE)                    # 6 x 7 elements
    with pytest.raises(CaseError, match=r"convergence.meshes = 3 with convergence.ratio = 3: "
                                        r"the coarsest mesh would have panel\[0\].n_chord = 1"):
        check_study(fin, ConvergenceSpec(meshes=3, ratio=3.0))


def test_a_coarse_mesh_its_support_cannot_hold_is_refused_first():
    """The thesis's fin (6 x 7, single-node shaft at mid-chord): ratio 1.5 makes its third
    mesh 3 x 3, with no node on the shaft axis."""
    with pytest.raises(CaseError, match=r"convergence.ratio = 1.5: mesh 3 of the study "
                                        r"\(panel\[0\] 3 x 3 elements\) fails: .*axis_point"):
        check_study(load_case(FIN_FILE), ConvergenceSpec(meshes=3, ratio=1.5))
    assert check_study(load_case(FIN_FILE), ConvergenceSpec(meshes=2, ratio=1.5))


def test_explicit_stations_are_refused():
    fin = load_case(FIN_FILE)
    case = with_mesh(fin, 4, 7, Stations((0.0, 0.2, 0.5, 0.8, 1.0)))
    with pytest.raises(CaseError, match=r"panel\[0\].chord_stations: explicit stations"):
        check_study(case, ConvergenceSpec(meshes=2))


def _agard_dict():
    import tomllib
    return tomllib.loads(AGARD.read_text())


def test_convergence_table_is_read_and_checked():
    d = _agard_dict()
    assert case_from_dict(d).convergence == ConvergenceSpec()          # default: off, 3 x 1.5
    d["convergence"] = {"enabled": True, "meshes": 2, "ratio": 2.0, "order": 2.0}
    c = case_from_dict(d)
    assert c.convergence == ConvergenceSpec(True, 2, 2.0, 2.0)
    assert c.fingerprint() == case_from_dict(_agard_dict()).fingerprint()   # not the physics


@pytest.mark.parametrize("table, match", [
    ({"meshes": 4}, r"convergence.meshes must be an integer in \[2, 3\], got 4"),
    ({"ratio": 1.0}, r"convergence.ratio"),
    ({"order": 0.0}, r"convergence.order"),
    ({"enabled": 1}, r"convergence.enabled must be true or false"),
    ({"mesh": 2}, r"convergence.mesh")])
def test_convergence_table_errors_name_the_key(table, match):
    d = _agard_dict()
    d["convergence"] = table
    with pytest.raises(CaseError, match=match):
        case_from_dict(d)


# ---------------------------------------------------------------------------------------------
# the study on AGARD 445.6 and on the fin
# ---------------------------------------------------------------------------------------------
def _consistent(e):
    """The extrapolated value lies beyond the finest, away from the coarser, by
    |phi_1 - phi_2| / (r_21^p - 1) (Celik et al. Eq. 4a)."""
    e21 = e.values[0] - e.values[1]
    r = e.h[1] / e.h[0]
    assert (e.value - e.values[0]) * e21 > 0
    assert abs(e.value - e.values[0]) == pytest.approx(abs(e21) / (r ** e.order - 1), rel=1e-9)


@pytest.fixture(scope="module")
def agard_studies():
    """AGARD 445.6's default study (3 meshes, ratio 1.5) on its own 20 x 20 / 16 x 16 meshes
    and on the next coarser base 13 x 13 / 11 x 11."""
    case = load_case(AGARD)
    coarse = with_boxes(with_mesh(case, 13, 13), 11, 11)
    return convergence_study(case), convergence_study(coarse)


def test_agard_converged_flutter_against_yates(agard_studies):
    """The extrapolated flutter speed with its error bar, and how far it lies from Yates's
    (1987) measured 172.2 m/s: the DLM's 6 % above it (the case's documented difference,
    asekit.case.pipeline.flutter's example) is a modelling difference, not a discretisation
    error: the error bar is a fraction of the gap."""
    (row,) = agard_studies[0].rows
    e = row.speed
    assert e.observed and 1.0 <= e.order <= 3.0             # measured 1.74
    assert e.error < 3.0                                    # m/s; measured 1.04
    gap = e.value / YATES_SPEED - 1
    assert 0.03 < gap < 0.09                                # measured +6.1 %
    assert e.error < 0.3 * (e.value - YATES_SPEED)
    assert row.frequency.value / 38.10 == pytest.approx(0.5353, rel=0.12)   # 0.595 measured


def test_agard_extrapolation_is_consistent_and_its_error_shrinks(agard_studies):
    fine, coarse = agard_studies
    for s in (fine, coarse):
        _consistent(s.rows[0].speed)
    assert fine.rows[0].speed.error < coarse.rows[0].speed.error
    # the finer study's extrapolation lies within the coarser one's error bar
    assert abs(fine.rows[0].speed.value - coarse.rows[0].speed.value) \
        <= coarse.rows[0].speed.error


def test_summary_gains_the_extrapolated_fields(agard_studies):
    from asekit.case.report import run_analysis, summary
    case = load_case(AGARD)
    study = agard_studies[0]
    s = add_to_summary(summary(run_analysis(case)), study)
    (row,) = s["flutter"]
    assert row["speed_extrapolated_ms"] == study.rows[0].speed.value
    assert row["speed_error_ms"] == study.rows[0].speed.error
    assert row["frequency_extrapolated_hz"] == study.rows[0].frequency.value
    assert row["frequency_error_hz"] == study.rows[0].frequency.error
    assert row["speed_ms"] == study.rows[0].speed.values[0]       # the finest is the case's
    for k in ("speed_extrapolated_ms", "speed_error_ms", "frequency_extrapolated_hz",
              "frequency_error_hz"):
        assert k in s["units"]
    assert s["convergence"]["structure"] == [[[20, 20]], [[13, 13]], [[9, 9]]]
    assert s["seconds"]["convergence"] == study.seconds
    text = format_study(study)
    assert f"{row['speed_extrapolated_ms']:.2f} +- {row['speed_error_ms']:.2f}" in text
    assert max(len(ln) for ln in text.splitlines()) <= 100
    assert "note: flutter on mode 1, 1, 2" in text     # the 9 x 9 mesh: the other branch


def _graded_fin(n_chord, n_span, boxes):
    fin = with_shaft(load_case(FIN_FILE), radius=0.005)
    fin = replace(fin, aero=replace(fin.aero, machs=(0.75,)),
                  flight=replace(fin.flight, altitudes=(0.0,),
                                 velocities=tuple(np.arange(140.0, 340.0 + 1e-9, 4.0))))
    return with_boxes(with_shaft_grading(fin, n_chord, n_span), *boxes)


@pytest.mark.slow
def test_fin_graded_study_error_bar_holds_the_finer_mesh():
    """The fin with the 5 mm distributed shaft on meshes graded toward it, M 0.75 sea level
    (the default ``reproduce`` rows ``flutter.extrapolated.*``): on 64 x 48 elements / 28 x 20
    boxes and two coarser meshes (ratio 1.5) the order is observed (measured 1.46), the
    extrapolation lies beyond the finest mesh consistently with it, and an independent finer
    run (96 x 72 / 42 x 30, measured 256.87 m/s) lies inside its error bar (measured
    257.32 +- 3.03 m/s).

    On the fin the error bar does not shrink steadily with refinement (unlike AGARD 445.6):
    the study on 96 x 72 / 42 x 30 sees 256.87, 254.89, 252.93 m/s (equal steps, no observed
    order: 260.8 +- 11.8 m/s at the assumed order 1) because the shaft region's effective
    radius, which moves the flutter speed by about 18 m/s per mm, converges irregularly with
    the node lines near it (tests/benchmarks/bench_converged.py)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # coarse meshes under-resolve the shaft region
        study = convergence_study(_graded_fin(64, 48, (28, 20)))
        finer = pipeline.flutter(_graded_fin(96, 72, (42, 30))).results[0].flutter
    e = study.rows[0].speed
    assert e is not None and e.observed and 1.0 <= e.order <= 2.5
    _consistent(e)
    assert 1.0 < e.error < 6.0                   # m/s
    assert abs(finer.speed - e.value) <= e.error
    assert finer.speed > e.values[0]             # the finer mesh moves toward the limit
