"""The [[beam]] keys of converted stick decks (issue 24): in_plane, point_masses,
spline_extension, and zero in-plane stiffness; each bad value refused in one line naming the
key path. Checks: the point mass's inertia given along (axis, aft, up) is the global
tensor's axis component after the rotation (to round-off) and lowers the torsion mode; fixing
the in-plane motion leaves the Goland wing's three (out-of-plane) modes unchanged (the
in-plane and out-of-plane motion of a planar beam are decoupled, tests/structure/
test_beam_in_plane.py)."""

import copy
import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

RAW = tomllib.loads((CASES_DIR / "goland_wing.toml").read_text())


def _with(**beam):
    d = copy.deepcopy(RAW)
    d["beam"][0].update(beam)
    return d


@pytest.mark.parametrize("beam,match", [
    ({"in_plane": "locked"}, r"beam\[0\]\.in_plane must be one of \['free', 'fixed'\]"),
    ({"ea": 0.0}, r"beam\[0\]\.ea must be > 0 unless in_plane = \"fixed\""),
    ({"point_masses": [{"s": 0.1, "mass": 1.0}]},
     r"beam\[0\]\.point_masses\[0\]\.s = 0\.1 m is not a node"),
    ({"point_masses": [{"s": 6.096, "mass": -1.0}]}, r"point_masses\[0\]\.mass"),
    ({"point_masses": [{"s": 6.096, "inertia": [1.0, 2.0]}]}, r"point_masses\[0\]\.inertia"),
    ({"spline_extension": "yes"}, r"beam\[0\]\.spline_extension must be true or false"),
])
def test_bad_values_are_named(beam, match):
    with pytest.raises(CaseError, match=match):
        case_from_dict(_with(**beam))


def test_fixed_in_plane_case_has_the_out_of_plane_modes_of_the_free_one():
    free = P.modal_model(case_from_dict(_with()))
    fixed = P.modal_model(case_from_dict(_with(in_plane="fixed", ea=0.0, ei_chord=0.0)))
    np.testing.assert_allclose(fixed.frequencies_hz, free.frequencies_hz, rtol=1e-9)
    assert "in-plane motion fixed" in fixed.label


def test_tip_rotary_inertia_lowers_the_torsion_mode():
    base = case_from_dict(_with())
    heavy = case_from_dict(_with(point_masses=[{"s": 6.096, "inertia": [2.0, 0.0, 0.0]}]))
    beam = P.case_beam(heavy)
    (pm,) = beam.point_masses
    e1 = beam.direction
    assert pm.node == beam.n_nodes - 1
    assert e1 @ np.asarray(pm.inertia) @ e1 == pytest.approx(2.0, rel=1e-12)
    f0, f1 = P.modal_model(base).frequencies_hz, P.modal_model(heavy).frequencies_hz
    assert f1[1] < f0[1] and f1[0] == pytest.approx(f0[0], rel=0.02)
