"""Control surfaces in Nastran decks (issue 25): AESURF / AELIST / AESURFS / AELINK and the
hinge's CORD2R read by asekit.io.bdf and written by its export.

The deck is hand-written here (:func:`_aileron_deck`, asekit's own example, no external
source): the aileron_wing case of data/cases/aileron_wing.toml (aluminium plate wing, chord
0.3 m, half span 1.2 m, 2 mm, clamped root, a wall at the root) on a coarser 4 x 8 mesh, with a
25 %-chord aileron over the outboard half (boxes 1020, 1024, 1028, 1032 of CAERO1 1001) whose
hinge system CORD2R 10 has its y axis along the hinge line x = 0.225 m (MSC Nastran Quick
Reference Guide, AESURF: "CIDi ... a y-axis that defines the hinge line").
"""

import dataclasses
import json
import os
import warnings

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    # .ci/run's Nastran environment (environment-nastran.txt): there a missing reader fails
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.case import load_case  # noqa: E402
from asekit.case import pipeline as pl  # noqa: E402
from asekit.io import bdf as B  # noqa: E402
from asekit.util.paths import DATA_DIR  # noqa: E402

CHORD, SPAN, NC, NS = 0.3, 1.2, 4, 8

AILERON = ("CORD2R,10,,0.225,0.6,0.0,0.225,0.6,1.0,\n,1.225,0.6,0.0",
           "AELIST,20,1020,1024,1028,1032",
           "AESURF,1,AILERON,10,20,,,1.0,LDW,\n,0.075,0.045,-0.35,0.35,-5.0,5.0",
           "SET1,30,41,42,43,44,45",
           "AESURFS,2,AILERON,,30,,30",
           "AELINK,ALWAYS,AILERON,AILERON,1.0")


def _free(name, *fields) -> str:
    """One free-field card, continued every 8 fields (a free-field line holds 9 fields)."""
    f = [str(v) for v in fields]
    rows = [f[i:i + 8] for i in range(0, max(len(f), 1), 8)]
    return "\n".join([",".join([name] + rows[0])] + [",".join([""] + r) for r in rows[1:]])


VELOCITIES = tuple(float(v) for v in range(4, 41, 2))


def _aileron_deck(tmp_path, cards=AILERON, name="aileron.bdf"):
    """The hand-written aileron deck (module docstring), free-field, SI; ``cards`` the
    control-surface cards."""
    lines = ["SOL 145", "CEND", "SPC = 1", "METHOD = 10", "FMETHOD = 20", "BEGIN BULK",
             "MAT1,1,70.0E9,,0.3,2700.0", "PSHELL,1,1,0.002,1,,1",
             "EIGRL,10,,,4",
             "PARAM,COUPMASS,1"]       # the consistent plate mass, as the case file's
    nid = lambda i, j: 1 + j * (NC + 1) + i                      # i chordwise, j spanwise
    for j in range(NS + 1):
        for i in range(NC + 1):
            lines.append(f"GRID,{nid(i, j)},,{CHORD * i / NC!r},{SPAN * j / NS!r},0.0")
    eid = 1
    for j in range(NS):
        for i in range(NC):
            lines.append(f"CQUAD4,{eid},1,{nid(i, j)},{nid(i + 1, j)},{nid(i + 1, j + 1)},"
                         f"{nid(i, j + 1)}")
            eid += 1
    lines += [_free("SPC1", 1, 345, *[nid(i, 0) for i in range(NC + 1)]),
              f"CAERO1,1001,1,,{NS},{NC},,,1\n,0.0,0.0,0.0,{CHORD},0.0,{SPAN},0.0,{CHORD}",
              "PAERO1,1",
              _free("SET1", 1001, *range(1, (NC + 1) * (NS + 1) + 1)),
              f"SPLINE1,1001,1001,1001,{1000 + NC * NS},1001",
              f"AERO,,1.0,{2 * 0.15},1.0,1",
              "MKAERO1,0.0,0.3\n,0.001,0.05,0.1,0.2,0.4,0.8,1.5",
              "FLFACT,1,1.225", "FLFACT,2,0.0",
              _free("FLFACT", 3, *VELOCITIES),
              "FLUTTER,20,PK,1,2,3,L", *cards, "ENDDATA"]
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return p


def _read_deck(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", B.UnsupportedCardWarning)
        warnings.filterwarnings("ignore", ".*AESURF gives no hinge stiffness", B.BdfWarning)
        return B.read_deck(path)


def _declarative(k_h=0.0):
    """The same wing as a case file (data/cases/aileron_wing.toml on the deck's mesh)."""
    src = load_case(DATA_DIR / "cases" / "aileron_wing.toml")
    panel = dataclasses.replace(src.panels[0], n_chord=NC, n_span=NS)
    aero = dataclasses.replace(src.aero, boxes=((NC, NS),))
    cs = dataclasses.replace(src.control_surfaces[0], hinge_stiffness=k_h)
    flight = dataclasses.replace(src.flight, velocities=VELOCITIES)
    return dataclasses.replace(src, panels=(panel,), aero=aero, control_surfaces=(cs,),
                               flight=flight)


def test_aesurf_reads_as_the_control_surface_of_its_boxes(tmp_path):
    """AESURF AILERON: hinge at the chord fraction of its AELIST's front edge (3/4), span
    fractions of its strips (4/8 to 8/8), the CORD2R's origin and y axis, CREFC / CREFS /
    limits kept; AESURFS and AELINK kept; the case gets the [[control_surface]] spec."""
    bdf = _read_deck(_aileron_deck(tmp_path))
    (s,) = bdf.control_surfaces
    assert s.label == "AILERON" and (s.aesurf_id, s.cid, s.aelist_id) == (1, 10, 20)
    assert (s.caero_id, s.caero_index) == (1001, 0)
    assert s.hinge_chord_fraction == pytest.approx((0.75, 0.75), abs=1e-12)
    assert s.span_fraction == pytest.approx((0.5, 1.0), abs=1e-12)
    assert s.hinge_point == pytest.approx((0.225, 0.6, 0.0))
    assert s.hinge_axis == pytest.approx((0.0, 1.0, 0.0))
    assert (s.crefc, s.crefs, s.pllim, s.pulim) == pytest.approx((0.075, 0.045, -0.35, 0.35))
    assert (s.hmllim, s.hmulim) == pytest.approx((-5.0, 5.0))
    assert s.aesurfs == (30, 30)
    assert bdf.aelinks == (("AILERON", (("AILERON", 1.0),)),)
    assert any("AELINK" in n for n in bdf.notes)
    with pytest.warns(B.BdfWarning, match=r"AESURF AILERON: AESURF gives no hinge stiffness"):
        B.read_deck(_aileron_deck(tmp_path, name="again.bdf"))
    (spec,) = B.deck_case(bdf).control_surfaces
    assert (spec.name, spec.panel, spec.kind, spec.hinge_stiffness) == ("AILERON", 0,
                                                                        "rigid", 0.0)
    assert spec.hinge_chord_fraction == pytest.approx((0.75, 0.75), abs=1e-12)


def test_caero1_numbered_from_the_tip_gives_the_same_surface(tmp_path):
    """A CAERO1 whose P1 is at the tip (its boxes numbered from the tip): the same aileron
    (span fractions from the root), its AELIST the boxes of the first four strips."""
    cards = tuple(c.replace("AELIST,20,1020,1024,1028,1032", "AELIST,20,1004,1008,1012,1016")
                  for c in AILERON)
    text = _aileron_deck(tmp_path, cards).read_text().replace(
        f",0.0,0.0,0.0,{CHORD},0.0,{SPAN},0.0,{CHORD}", f",0.0,{SPAN},0.0,{CHORD},0.0,0.0,0.0,"
                                                      f"{CHORD}")
    assert f",0.0,{SPAN},0.0,{CHORD}," in text
    p = tmp_path / "flipped.bdf"
    p.write_text(text)
    (s,) = _read_deck(p).control_surfaces
    assert s.hinge_chord_fraction == pytest.approx((0.75, 0.75), abs=1e-12)
    assert s.span_fraction == pytest.approx((0.5, 1.0), abs=1e-12)


def test_imported_aileron_has_the_case_files_derivatives(tmp_path):
    """The deck's aileron through the pipeline: the hinged boxes are the deck's own CAERO1
    boxes, and the rigid derivatives (dCL/d delta, C_h delta), hinge inertia and reversal
    speed equal those of the same wing written as a case file (same MITC4 mesh, same boxes:
    equal to round-off)."""
    case = B.deck_case(_read_deck(_aileron_deck(tmp_path)))
    hm = pl.control_surface_mesh(case)
    np.testing.assert_allclose(hm.mesh.corners, case.structure.boxes.corners, atol=1e-12)
    ref = pl.control_surfaces(_declarative())
    got = pl.control_surfaces(case)
    assert len(ref) == 2 and len(got) == 1           # the deck's FLUTTER runs Mach 0 only
    for g, r in zip(got, ref):
        assert g.mach == r.mach
        for k in ("dCL_ddelta_per_rad", "dCL_dalpha_per_rad", "Ch_delta", "Ch_alpha",
                  "inertia", "static_unbalance"):
            assert getattr(g, k) == pytest.approx(getattr(r, k), rel=1e-9, abs=1e-15), k
        assert (g.reversal_speed_ms is None) == (r.reversal_speed_ms is None)
        if r.reversal_speed_ms is not None:
            assert g.reversal_speed_ms == pytest.approx(r.reversal_speed_ms, rel=1e-6)
    assert got[0].dCL_ddelta_per_rad > 0 and got[0].Ch_delta < 0      # TE down: lift up


@pytest.mark.parametrize("old, new, match", [
    ("AELIST,20,1020,1024,1028,1032", "AELIST,20,1019,1023,1027,1031",
     r"AESURF 1 ALID1 = 20: AELIST 20 must list a rectangular block"),
    ("AELIST,20,1020,1024,1028,1032", "AELIST,20,1020,1024,1032",
     r"AESURF 1 ALID1 = 20: AELIST 20 must list a rectangular block"),
    ("AELIST,20,1020,1024,1028,1032", "AELIST,20,1020,1024,1028,1032,2000",
     r"AESURF 1 ALID1 = 20: the AELIST boxes .* are not all boxes of one CAERO1"),
    ("CORD2R,10,,0.225,", "CORD2R,10,,0.2,", r"AESURF 1 CID1 = 10: the y axis of CORD2R 10"),
    ("\n,1.225,0.6,0.0", "\n,-0.775,0.6,0.0", r"AESURF 1 CID1 = 10: .* pointing outboard"),
    ("AESURF,1,AILERON,10,20,,,", "AESURF,1,AILERON,10,20,10,20,",
     r"AESURF 1 CID2 / ALID2: a second component is not supported"),
    ("AELINK,ALWAYS,AILERON,AILERON,1.0", "AELINK,ALWAYS,AILERON,RUDDER,1.0",
     r"RUDDER"),
])
def test_aesurf_errors_name_card_and_field(tmp_path, old, new, match):
    """An AESURF asekit cannot map to a hinged region of one CAERO1 is refused with the card,
    its id and the field (BdfError, one line), never silently moved."""
    cards = tuple(c.replace(old, new) for c in AILERON)
    assert cards != AILERON
    with pytest.raises(B.BdfError, match=match):
        _read_deck(_aileron_deck(tmp_path, cards))


def test_analyse_cli_shows_the_deck_aileron(tmp_path, capsys):
    """``asekit analyse DECK.bdf``: the AESURF's control-surface rows in the JSON and the
    printed summary."""
    from asekit.cli.main import main
    out = tmp_path / "s.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["analyse", str(_aileron_deck(tmp_path)), "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["control_surfaces"]
    assert [(r["name"], r["mach"]) for r in rows] == [("AILERON", 0.0)]
    assert "AILERON" in capsys.readouterr().out


@pytest.mark.parametrize("hinge, span", [((0.75, 0.75), (0.5, 1.0)),
                                         ((0.7, 0.7), (0.3, 0.85))])
def test_control_surface_case_exports_and_reads_back(tmp_path, hinge, span):
    """A case with [[control_surface]] written as CAERO1 (its hinged boxes) + CORD2R + AELIST +
    AESURF reads back to the same surface: hinge and span fractions equal to 1e-9, the hinge
    line the same; the exported deck exported again gives the same cards' surface."""
    src = _declarative(k_h=0.5)
    cs = dataclasses.replace(src.control_surfaces[0], hinge_chord_fraction=hinge,
                             span_fraction=span)
    case = dataclasses.replace(src, control_surfaces=(cs,))
    hm = pl.control_surface_mesh(case)
    path = B.write_case_bdf(case, tmp_path / "cs.bdf")
    bdf = _read_deck(path)
    (s,) = bdf.control_surfaces
    assert s.label == "AILERON"
    assert s.hinge_chord_fraction == pytest.approx(hinge, abs=1e-9)
    assert s.span_fraction == pytest.approx(span, abs=1e-9)
    np.testing.assert_allclose(s.hinge_point, hm.hinge_point[0], atol=1e-12)
    np.testing.assert_allclose(s.hinge_axis, hm.hinge_axis[0], atol=1e-12)
    assert s.crefs == pytest.approx(hm.surface_area(0), rel=1e-6)
    again = _read_deck(B.write_case_bdf(B.deck_case(bdf), tmp_path / "again.bdf"))
    (s2,) = again.control_surfaces
    assert s2.hinge_chord_fraction == pytest.approx(hinge, abs=1e-9)
    assert s2.span_fraction == pytest.approx(span, abs=1e-9)


def test_two_surfaces_export_and_read_back(tmp_path):
    """An inboard flap and an outboard aileron on one hinge line: two CORD2R / AELIST /
    AESURF, read back to the same fractions (1e-9), in order."""
    src = _declarative(k_h=0.5)
    a = src.control_surfaces[0]
    flap = dataclasses.replace(a, name="flap", span_fraction=(0.1, 0.45))
    case = dataclasses.replace(src, control_surfaces=(flap, a))
    bdf = _read_deck(B.write_case_bdf(case, tmp_path / "two.bdf"))
    assert [s.label for s in bdf.control_surfaces] == ["FLAP", "AILERON"]
    for s, c in zip(bdf.control_surfaces, case.control_surfaces):
        assert s.hinge_chord_fraction == pytest.approx(c.hinge_chord_fraction, abs=1e-9)
        assert s.span_fraction == pytest.approx(c.span_fraction, abs=1e-9)


@pytest.mark.parametrize("name", ["inboard_aileron", "flap 1", "1flap"])
def test_export_refuses_a_name_that_is_no_aesurf_label(name):
    """AESURF LABEL is 1-8 characters, a letter first: the export names the key."""
    src = _declarative()
    cs = dataclasses.replace(src.control_surfaces[0], name=name)
    with pytest.raises(ValueError, match=r"control_surface\[0\]\.name .* AESURF LABEL"):
        B.case_bdf(dataclasses.replace(src, control_surfaces=(cs,)))


def test_export_refuses_a_hinge_that_is_not_one_caero1(tmp_path):
    """A tapered hinge (inboard chord fraction != outboard) cannot be the AELIST boxes of one
    CAERO1: the export names the key."""
    src = _declarative()
    cs = dataclasses.replace(src.control_surfaces[0], hinge_chord_fraction=(0.7, 0.8))
    with pytest.raises(ValueError, match=r"control_surface\[\]\.hinge_chord_fraction"):
        B.case_bdf(dataclasses.replace(src, control_surfaces=(cs,)))


def test_a_geared_surface_exports_as_aelink_and_reads_back_geared(tmp_path):
    """``linked_to`` / ``gear_ratio`` (issue 25) is written as AELINK ALWAYS (LABLD the geared
    surface, LABL1 its master, C1 the ratio) and read back as the same link; an AELINK that
    is not one surface geared to one other (the module's self-link) stays a note."""
    src = _declarative(k_h=0.5)
    a = src.control_surfaces[0]
    flap = dataclasses.replace(a, name="flap", span_fraction=(0.1, 0.45))
    geared = dataclasses.replace(a, linked_to="flap", gear_ratio=-0.5)
    case = dataclasses.replace(src, control_surfaces=(flap, geared))
    path = B.write_case_bdf(case, tmp_path / "geared.bdf")
    assert any(line.startswith("AELINK") for line in path.read_text().splitlines())
    bdf = _read_deck(path)
    assert bdf.aelinks == (("AILERON", (("FLAP", -0.5),)),)
    assert any(n.startswith("AELINK applied: AILERON geared to FLAP") for n in bdf.notes)
    specs = B.deck_case(bdf).control_surfaces
    assert [(s.name, s.linked_to, s.gear_ratio) for s in specs] == [
        ("FLAP", "", 0.0), ("AILERON", "FLAP", -0.5)]
    self_link = B.deck_case(_read_deck(_aileron_deck(tmp_path))).control_surfaces
    assert [(s.linked_to, s.gear_ratio) for s in self_link] == [("", 0.0)]


def test_export_refuses_an_elastic_surface():
    """AESURF is a rigid surface on the plate's boxes; the export does not release the plate
    along an elastic surface's hinge, so it refuses the case naming the key (it used to write
    the unreleased plate silently)."""
    src = _declarative(k_h=0.5)
    cs = dataclasses.replace(src.control_surfaces[0], kind="elastic")
    with pytest.raises(ValueError, match=r"control_surface\[0\]\.kind = 'elastic'"):
        B.case_bdf(dataclasses.replace(src, control_surfaces=(cs,)))
