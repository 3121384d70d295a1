"""Issue 22: p-k flutter that does not depend on the velocity grid.

The p-k roots are continued with step control (asekit.aeroelastic.flutter.pk_flutter): a step is
split when a root moves by more than half its spacing, when its eigenvector's MAC with the
previous point drops below 0.8, or when two tracked columns land on the same root; crossings are
bracketed and refined on that path. Reproducers of the issue: AGARD 445.6 weakened wing 3 at
M 0.499 (data/cases/agard445_6.toml) on coarse grids reported the mode-4 crossing at 558 m/s as
the flutter speed, or one root twice at 181.94 m/s. Reference: the first flutter of the case's own
fine sweep (100-260 m/s, step 2), 181.94 m/s, mode 1 (the docstring of pipeline.flutter: 182 m/s;
Yates 1987 measured 172 m/s).
"""

import dataclasses
import warnings

import numpy as np
import pytest
from property_targets import AGARD_FIRST_FLUTTER, agard_pk_model

from asekit.aeroelastic.flutter import (
    _same_root,
    first_of,
    pk_flutter,
    pk_instabilities,
)
from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

#: the issue's grids: (min, max, step) or explicit points
GRIDS = {"100:900:200": (100.0, 900.0, 200.0), "10:2000:300": (10.0, 2000.0, 300.0),
         "10:2000:400": (10.0, 2000.0, 400.0), "50:650:300": (50.0, 650.0, 300.0),
         "100:600:100": (100.0, 600.0, 100.0), "two points 100, 260": (100.0, 260.0)}


def _velocities(spec):
    if len(spec) == 2:
        return np.array(spec)
    lo, hi, step = spec
    return np.arange(lo, hi + 1e-9, step)


@pytest.fixture(scope="module")
def agard():
    return agard_pk_model()


def _check_first_flutter(inst, where):
    f = first_of(inst, "flutter")
    assert f is not None and not f.at_first_point, where
    assert f.mode == 0, where
    assert f.speed == pytest.approx(AGARD_FIRST_FLUTTER, abs=f.speed_tolerance + 1e-6 * f.speed)
    assert 0 < f.speed_tolerance < 1e-2
    near = [i for i in inst if abs(i.speed - f.speed) < 1e-3]
    assert len(near) == 1, (where, inst)                   # reported once


@pytest.mark.parametrize("name", list(GRIDS))
def test_agard_coarse_grid_finds_the_first_flutter(agard, name):
    modal, gaf, rho = agard
    U = _velocities(GRIDS[name])
    res = pk_flutter(modal, gaf, rho, U)
    inst = pk_instabilities(res, modal, gaf)
    _check_first_flutter(inst, name)
    assert res.substeps > 0 and res.path_velocities.size == U.size + res.substeps
    assert np.all(np.isin(U, res.path_velocities))         # reported at the requested points
    np.testing.assert_array_equal(res.velocities, U)
    assert res.p.shape == (U.size, 4)
    for i in range(U.size):                                # no two columns on one root
        r = dataclasses.make_dataclass("R", ["p", "v"])(res.p[i], res.vectors[i])
        assert _same_root(r) == [], (name, U[i])
    if U[-1] > 600:                                        # the mode-4 crossing is still there
        assert any(i.mode == 3 and i.speed == pytest.approx(558.14, abs=0.01) for i in inst)


@pytest.mark.parametrize("name", list(GRIDS))
def test_agard_case_pipeline_on_coarse_grid(name):
    """The same grids through the case layer (issue reproducer: `step = 200` printed 558 m/s)."""
    case = load_case(CASES_DIR / "agard445_6.toml")
    U = tuple(float(u) for u in _velocities(GRIDS[name]))
    case = dataclasses.replace(case, flight=dataclasses.replace(case.flight, velocities=U))
    (r,) = P.flutter(case).results
    assert not r.unstable_at_start
    assert r.flutter.speed == pytest.approx(AGARD_FIRST_FLUTTER, abs=1e-3)
    assert r.flutter.mode_name == "mode 1"


def test_fine_grid_needs_no_substep(agard):
    """The case's fine sweep is solved as before: no sub-step, the same roots bit for bit as
    with the step control off (max_halvings=0)."""
    modal, gaf, rho = agard
    U = np.arange(100.0, 260.0 + 1e-9, 2.0)
    res = pk_flutter(modal, gaf, rho, U)
    assert res.substeps == 0 and res.forced_steps == 0
    off = pk_flutter(modal, gaf, rho, U, max_halvings=0)
    np.testing.assert_array_equal(res.p, off.p)
    _check_first_flutter(pk_instabilities(res, modal, gaf), "fine")


def test_two_columns_on_one_root_are_reassigned(agard):
    """With the step control off, the step 100 -> 260 m/s puts modes 1 and 2 on the same
    (unstable) root: the Hungarian reassignment gives them distinct roots, and the crossing is
    reported once."""
    modal, gaf, rho = agard
    res = pk_flutter(modal, gaf, rho, [100.0, 260.0], max_halvings=0)
    assert res.forced_steps == 1 and res.substeps == 0
    r = dataclasses.make_dataclass("R", ["p", "v"])(res.p[1], res.vectors[1])
    assert _same_root(r) == []
    assert len({round(p.real, 3) for p in res.p[1]}) == 4
    inst = pk_instabilities(res, modal, gaf)
    assert len([i for i in inst if i.kind == "flutter" and abs(i.speed - 181.94) < 0.01]) <= 1


def test_step_control_arguments_are_checked(agard):
    modal, gaf, rho = agard
    for kw in ({"step_fraction": 0.0}, {"step_fraction": 1.5}, {"min_mac": 1.0},
               {"min_mac": -0.1}, {"max_halvings": -1}, {"max_halvings": 31}):
        with pytest.raises(ValueError, match=list(kw)[0]):
            pk_flutter(modal, gaf, rho, [100.0, 200.0], **kw)
    for kw in ({"step_fraction": "0.5"}, {"max_halvings": 2.5}, {"min_mac": None}):
        with pytest.raises(TypeError, match=list(kw)[0]):
            pk_flutter(modal, gaf, rho, [100.0, 200.0], **kw)


def test_sweep_above_flutter_is_at_or_below_the_first_point(agard):
    modal, gaf, rho = agard
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inst = pk_instabilities(pk_flutter(modal, gaf, rho, [300.0, 500.0]), modal, gaf)
    f = first_of(inst, "flutter")
    assert f.at_first_point and f.speed == 300.0 and f.speed_tolerance == 300.0
    assert f.mode == 0


def test_unconverged_warning_names_only_what_failed():
    """Issue 30: a k-iteration that failed only between the requested velocities is worded so
    (no "at 0 of 524 requested points: ;"); a failure at a requested point names it in m/s (points: mode x velocity)."""
    from asekit.aeroelastic.flutter import FlutterConvergenceWarning, _warn_unconverged
    U = np.array([100.0, 200.0, 300.0])
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        _warn_unconverged(U, np.ones((3, 2), bool), np.arange(2), 0, 30, 1e-6, n_path_bad=4)
        conv = np.ones((3, 2), bool)
        conv[1, 0] = False
        _warn_unconverged(U, conv, np.arange(2), 0, 30, 1e-6, n_path_bad=1)
    first, second = (str(r.message) for r in rec)
    assert all(issubclass(r.category, FlutterConvergenceWarning) for r in rec)
    assert "at 4 sub-step points" in first and "all 6 requested points converged" in first
    assert "0 of" not in first
    assert "at 1 of 6 requested points" in second and "U = 200 m/s" in second
