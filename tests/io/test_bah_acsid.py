"""AERO ACSID with axes other than basic's (issue 24): pyNastran's BAH plane deck as shipped
(data/benchmarks/bah_plane, AERO ACSID = 2: flow along basic -X, z down) against the same deck
rotated by 180 degrees about Y (tests/io/test_bah_plane_qhh.py's ``_rotated_deck``: ACSID 2 =
basic). A rigid rotation of the whole model changes no physics, so the two GAFs must agree to
round-off when both use the same modes (the rotated deck's modes are the original's rotated:
(u, v, w, rx, ry, rz) -> (-u, v, -w, -rx, ry, -rz) per grid; the free-free rigid pair is
degenerate, so each deck's own eigen solution could pick another basis of it).
"""

import os
from dataclasses import replace

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from test_bah_plane_qhh import _rotated_deck  # noqa: E402  (tests/io on sys.path)

from asekit.aero.gaf import gaf_from_box_modes  # noqa: E402
from asekit.io import bdf as B  # noqa: E402
from asekit.io.bdf_beam import (  # noqa: E402
    need_pynastran,
    read_stick_deck,
    spline2_box_modes,
    stick_modes,
)
from asekit.util.paths import DATA_DIR  # noqa: E402

BAH = DATA_DIR / "benchmarks" / "bah_plane" / "bah_plane_qhh.bdf"
KS = (0.05, 0.5, 1.5)


def _gaf(path, modes=None):
    model = need_pynastran()(debug=None)
    model.read_bdf(str(path), xref=True)
    sm = read_stick_deck(path)
    modes = stick_modes(sm, 8) if modes is None else modes
    mesh, ids, R = B.deck_boxes_aero(model, 1.0)
    bm = spline2_box_modes(model, sm, modes, mesh, ids, 1.0, R)
    return gaf_from_box_modes(bm, mesh, 0.2, KS, 2.0, True), mesh, R, sm, modes


def test_aero_axes_of_the_deck():
    model = need_pynastran()(debug=None)
    model.read_bdf(str(BAH), xref=True)
    np.testing.assert_allclose(B.aero_axes(model), np.diag([-1.0, 1.0, -1.0]), atol=1e-12)


def test_rotated_deck_and_original_give_the_same_gaf(tmp_path):
    q0, mesh0, R, sm0, modes0 = _gaf(BAH)
    rot = _rotated_deck(tmp_path)
    sm1 = read_stick_deck(rot)
    assert np.array_equal(sm1.node_ids, sm0.node_ids)
    assert np.allclose(sm0.cd_axes, np.eye(3)) and np.allclose(sm1.cd_axes, np.eye(3))
    T = np.tile([-1.0, 1.0, -1.0, -1.0, 1.0, -1.0], sm0.node_ids.size)
    q1, mesh1, R1, _, _ = _gaf(rot, replace(modes0, shapes=T[:, None] * modes0.shapes))
    np.testing.assert_allclose(R1, np.eye(3), atol=1e-12)
    # the same boxes: the original's aerodynamic axes are the rotated deck's basic ones
    np.testing.assert_allclose(mesh0.corners, mesh1.corners, atol=1e-12)
    scale = np.abs(q1).max()
    assert np.abs(q0 - q1).max() <= 1e-10 * scale, np.abs(q0 - q1).max() / scale
    # and the rotated modes are the rotated deck's own (elastic frequencies to 1e-9)
    f1 = stick_modes(sm1, 8).frequencies_hz
    np.testing.assert_allclose(f1[2:], modes0.frequencies_hz[2:], rtol=1e-9)


def test_the_tail_spline_smoothing_needs_rigid_grids(tmp_path):
    """SPLINE2 802 (tail) has DZ = 1.0: accepted because grids 18-20 hang on an RBAR chain
    (rigid); the wing's SPLINE2 801 with DZ = 1.0 is refused (its grids bend), in one line."""
    text = (BAH.parent / "interface_bah.inc").read_text()
    old = "SPLINE2,801,601,601,800,1001,0.,1.,0"
    assert text.count(old) == 1
    for name in ("structure_bah.inc", "aero_bah.inc", "bah_plane_qhh.bdf"):
        (tmp_path / name).write_text((BAH.parent / name).read_text())
    (tmp_path / "interface_bah.inc").write_text(text.replace(old, old.replace(",0.,1.,", ",1.,1.,")))
    with pytest.raises(B.BdfError, match=r"SPLINE2 801: DZ/DTHX/DTHY = 1\.0/") as err:
        _gaf(tmp_path / "bah_plane_qhh.bdf")
    assert "\n" not in str(err.value)


def test_what_asekit_still_refuses(tmp_path):
    """A cylindrical ACSID, and a surface across the ACSID's x-y planes (dihedral), are refused
    in one line naming the card and field."""
    d = BAH.parent
    for name in ("structure_bah.inc", "interface_bah.inc", "bah_plane_qhh.bdf"):
        (tmp_path / name).write_text((d / name).read_text())
    aero = (d / "aero_bah.inc").read_text()
    (tmp_path / "aero_bah.inc").write_text(aero.replace("CORD2R,2,0,", "CORD2C,2,0,"))
    model = need_pynastran()(debug=None)
    model.read_bdf(str(tmp_path / "bah_plane_qhh.bdf"), xref=True)
    with pytest.raises(B.BdfError, match=r"^AERO ACSID = 2: a CORD2C system; the aerodynamic "
                                         r"system must be rectangular"):
        B.aero_axes(model)
    # the wing tip raised by 1 m out of the ACSID's x-y plane: dihedral
    old = "+CAERO10,-2.,0.,0.,5.7,-1.11,12.7,0.,2.5"
    assert aero.count(old) == 1
    (tmp_path / "aero_bah.inc").write_text(aero.replace(old, old.replace("12.7,0.", "12.7,1.")))
    model = need_pynastran()(debug=None)
    model.read_bdf(str(tmp_path / "bah_plane_qhh.bdf"), xref=True)
    with pytest.raises(B.BdfError, match=r"^CAERO1 601: P1 and P4 are not in one x-y plane of "
                                         r"the aerodynamic system \(AERO ACSID = 2\)"):
        B.deck_boxes_aero(model, 1.0)
