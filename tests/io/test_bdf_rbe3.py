"""RBE3 in stick-model decks (asekit.io.bdf_beam, issue 24).

References
----------
- MSC Nastran Quick Reference Guide, RBE3: the reference grid's REFC components are the
  weighted average of the independent grids' Ci components (a weighted least-squares fit of a
  rigid motion); the element transmits loads and mass without stiffness.
- A point mass m on a rigid extension d beyond the tip of a massless Euler-Bernoulli cantilever
  (length L, bending stiffness E I, axial E A): the flexibility at the mass
  (L^3 / 3 + d L^2 + d^2 L) / (E I) transversally (Roark, *Formulas for Stress and Strain*,
  7th ed., Table 8.1 case 1a with the tip slope P L^2 / (2 E I) carried over d) and L / (E A)
  axially, so omega^2 = 1 / (m flexibility). The cubic bar element is exact for end loads.
- Two parallel massless cantilevers of tip stiffness k = 3 E I / L^3 joined by an RBE3 whose
  reference grid (mass m) is at the weighted centroid of the two tips: the reference moves with
  the weighted mean a_1 w_1 + a_2 w_2 (a_i = WT_i / sum WT), the mass's force goes to tip i as
  a_i F (the transposed constraint), so omega^2 = k / (m (a_1^2 + a_2^2)).
"""

import os

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.io.bdf import BdfError  # noqa: E402
from asekit.io.bdf_beam import read_stick_deck, stick_modes  # noqa: E402

E, NU, RHO, LEN, NEL = 7.0e10, 0.33, 2700.0, 1.0, 8
A, I, J = 4e-4, 3e-9, 5e-9
CD5 = "CORD2R,5,,0.0,0.0,0.0,0.3,0.4,0.8\n,0.9,-0.1,0.2"      # a rotated displacement system


def _deck(path, extra=(), rho=RHO, spc=True, y=0.0, first=1):
    """A CBAR beam along x at height y (grids first..first+NEL), clamped at its root when
    ``spc``; I1 = I2 = I."""
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK"]
    lines += [f"GRID,{first + i},,{LEN * i / NEL!r},{y!r},0.0" for i in range(NEL + 1)]
    lines += [f"CBAR,{first + i},1,{first + i},{first + i + 1},0.0,0.0,1.0" for i in range(NEL)]
    lines += [f"PBAR,1,1,{A!r},{I!r},{I!r},{J!r}", f"MAT1,1,{E!r},,{NU!r},{rho!r}",
              "PARAM,COUPMASS,1", *extra, "ENDDATA"]
    if spc:
        lines.insert(-1, f"SPC1,1,123456,{first}")
    path.write_text("\n".join(lines) + "\n")
    return path


def _grid(gid, x, cd=""):
    return f"GRID,{gid},,{float(x[0])!r},{float(x[1])!r},{float(x[2])!r},{cd}"


def _rigid_values(sm, u_ind: dict) -> dict:
    """All dependent DOF values from independent DOF values (DOF -> value)."""
    return {d: sum(c * u_ind.get(i, 0.0) for i, c in row) for d, row in sm.rigid}


def _rigid_motion_cd(sm, gid, t, th, about):
    """Grid ``gid``'s six DOFs (its CD system) in the rigid motion (t, th) about ``about``."""
    k = int(np.flatnonzero(sm.node_ids == gid)[0])
    u = t + np.cross(th, sm.xyz[k] - about)
    R = sm.cd_axes[k]
    return np.r_[R @ u, R @ th]


def test_reference_follows_the_mean_translation_and_the_rigid_rotation(tmp_path):
    """Four equally weighted grids (translations 123, in a rotated CD system) around a
    reference grid at their centroid (in another CD system): the reference's translation is
    the mean of theirs for any motion; a rigid motion of the four is the reference's own."""
    c = np.array([LEN, 0.05, -0.02])
    pts = c + np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0], [0.03, 0.0, 0.07],
                        [-0.03, 0.0, -0.07]])
    ids = [101, 102, 103, 104]
    extra = [CD5, "CORD2R,6,,0.0,0.0,0.0,-0.5,0.2,0.3\n,0.1,0.9,-0.4", _grid(99, c, 6)]
    extra += [_grid(g, p, 5) for g, p in zip(ids, pts)]
    extra.append("RBE3,500,,99,123456,1.0,123,101,102\n,103,104")
    sm = read_stick_deck(_deck(tmp_path / "k.bdf", extra))
    assert len(sm.rigid) == 6
    ref = int(np.flatnonzero(sm.node_ids == 99)[0])
    R_ref = sm.cd_axes[ref]
    rng = np.random.default_rng(3)
    u_basic = rng.normal(size=(4, 3))                 # any translations of the four
    u_ind = {}
    for g, u in zip(ids, u_basic):
        k = int(np.flatnonzero(sm.node_ids == g)[0])
        u_ind.update({6 * k + j: float(v) for j, v in enumerate(sm.cd_axes[k] @ u)})
    dep = _rigid_values(sm, u_ind)
    u_ref = R_ref.T @ np.array([dep[6 * ref + j] for j in range(3)])
    np.testing.assert_allclose(u_ref, u_basic.mean(axis=0), rtol=0, atol=1e-12)
    t, th = np.array([0.01, -0.02, 0.03]), np.array([0.2, -0.1, 0.05])
    u_ind = {}
    for g in ids:
        k = int(np.flatnonzero(sm.node_ids == g)[0])
        u_ind.update({6 * k + j: float(v) for j, v in enumerate(
            _rigid_motion_cd(sm, g, t, th, c))})
    dep = _rigid_values(sm, u_ind)
    got = np.array([dep[6 * ref + j] for j in range(6)])
    np.testing.assert_allclose(got, np.r_[R_ref @ t, R_ref @ th], rtol=0, atol=1e-12)


def test_mass_on_a_reference_grid_of_a_rigid_tip_is_the_offset_mass(tmp_path):
    """A point mass on the RBE3 reference grid at the weighted centroid (WT 1, 1, 2, 2) of
    four grids tied rigidly (RBE2) to the tip of a massless cantilever: the three frequencies
    of the mass at distance d = 2 e beyond the tip (module docstring), and the modes of the
    same CONM2 on the tip with that offset."""
    tip, m, e = NEL + 1, 3.0, 0.05
    off = np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0], [3 * e, 0.0, 0.1], [3 * e, 0.0, -0.1]])
    wt = np.array([1.0, 1.0, 2.0, 2.0])
    cen = wt @ off / wt.sum()
    np.testing.assert_allclose(cen, [2 * e, 0.0, 0.0], atol=1e-15)
    x_tip = np.array([LEN, 0.0, 0.0])
    extra = [CD5, _grid(99, x_tip + cen, 5), f"CONM2,9,99,,{m!r}",
             *[_grid(101 + i, x_tip + o) for i, o in enumerate(off)],
             f"RBE2,400,{tip},123456,101,102,103,104",
             "RBE3,500,,99,123456,1.0,123,101,102\n,2.0,123,103,104"]
    sm = read_stick_deck(_deck(tmp_path / "r.bdf", extra, rho=0.0))
    f = stick_modes(sm, 3).frequencies_hz
    d = 2 * e
    w_bend = np.sqrt(E * I / (m * (LEN ** 3 / 3 + d * LEN ** 2 + d * d * LEN)))
    w_axial = np.sqrt(E * A / (m * LEN))
    np.testing.assert_allclose(2 * np.pi * f, [w_bend, w_bend, w_axial], rtol=1e-9)
    direct = _deck(tmp_path / "d.bdf", [f"CONM2,9,{tip},,{m!r},{d!r},0.0,0.0"], rho=0.0)
    np.testing.assert_allclose(f, stick_modes(read_stick_deck(direct), 3).frequencies_hz,
                               rtol=1e-9)


@pytest.mark.parametrize("w1,w2", [(1.0, 1.0), (3.0, 1.0)])
def test_reference_mass_between_two_cantilevers_is_their_weighted_mean(tmp_path, w1, w2):
    """Two parallel massless cantilevers (tips at y = b1 and y = -b2, w1 b1 = w2 b2) with an
    RBE3 (all six components of both tips) whose reference grid carries a point mass at their
    weighted centroid: omega^2 = k / (m (a1^2 + a2^2)) in both bending planes and E A / L in
    place of k axially (module docstring)."""
    b1 = 0.2
    b2 = w1 * b1 / w2
    m = 2.0
    lines = _deck(tmp_path / "a.bdf", rho=0.0, y=b1).read_text().splitlines()
    other = _deck(tmp_path / "b.bdf", rho=0.0, y=-b2, first=21).read_text().splitlines()
    bulk = [x for x in other[4:] if x.startswith(("GRID", "CBAR"))] + ["SPC1,1,123456,21"]
    extra = [_grid(99, [LEN, 0.0, 0.0]), f"CONM2,9,99,,{m!r}",
             f"RBE3,500,,99,123456,{w1!r},123456,{NEL + 1},{w2!r}\n,123456,{21 + NEL}"]
    lines[-1:-1] = bulk + extra
    (tmp_path / "two.bdf").write_text("\n".join(lines) + "\n")
    sm = read_stick_deck(tmp_path / "two.bdf")
    f = stick_modes(sm, 3).frequencies_hz
    a = np.array([w1, w2]) / (w1 + w2)
    s = float(a @ a)
    k = 3 * E * I / LEN ** 3
    w = np.sqrt(np.array([k, k, E * A / LEN]) / (m * s))
    np.testing.assert_allclose(2 * np.pi * f, w, rtol=1e-9)


def test_rbe3_adds_no_stiffness_and_carries_its_mass_rigidly(tmp_path):
    """A free-free beam with a point mass on an RBE3 reference grid off the beam (independent:
    three collinear beam grids, components 1234, the rotation about the line added as the QRG
    remark says): six rigid-body modes remain (zero frequency to the shifted eigen-solution's
    round-off: the RBE3 adds no stiffness), and the rigid-body mass matrix equals that of the same CONM2 on a beam
    grid with the offset (a rigid motion of the beam moves the reference grid rigidly)."""
    m, x_ref = 1.5, np.array([0.6, 0.2, -0.1])
    extra = [CD5, _grid(99, x_ref, 5), f"CONM2,9,99,,{m!r}", "RBE3,500,,99,123456,1.0,1234,2,5,9"]
    sm = read_stick_deck(_deck(tmp_path / "f.bdf", extra, spc=False))
    f = stick_modes(sm, 8).frequencies_hz
    assert np.all(f[:6] < 1e-4 * f[6]) and f[6] > 1.0        # omega^2 < 1e-8 of the 7th
    off = (x_ref - np.array([LEN * 4 / NEL, 0.0, 0.0])).tolist()
    direct = read_stick_deck(_deck(tmp_path / "d.bdf", [
        f"CONM2,9,5,,{m!r},{off[0]!r},{off[1]!r},{off[2]!r}"], spc=False))

    def rigid_mass(s):
        Tr = s.reduction()
        Mr = Tr.T @ s.M @ Tr
        free = s.free
        Phi = np.zeros((free.size, 6))
        for j in range(6):
            t, th = np.eye(6)[j, :3], np.eye(6)[j, 3:]
            full = np.concatenate([_rigid_motion_cd(s, g, t, th, np.zeros(3))
                                   for g in s.node_ids])
            Phi[:, j] = full[free]
        return Phi.T @ Mr @ Phi

    Mrb, Md = rigid_mass(sm), rigid_mass(direct)
    np.testing.assert_allclose(Mrb, Md, rtol=0, atol=1e-9 * np.abs(Md).max())
    assert Mrb[0, 0] == pytest.approx(RHO * A * LEN + m, rel=1e-12)


@pytest.mark.parametrize("card,match", [
    ("RBE3,500,,99,123,1.0,123,2,3\n,4\n,UM,99,1", r"RBE3 500: UM \(GM1 = 99\)"),
    ("RBE3,500,,99,123,1.0,123,2,3", r"RBE3 500: the independent grids' components cannot"),
    ("RBE3,500,,99,123,1.0,123,2,3\n,99", r"RBE3 500: REFGRID 99 is also an independent"),
])
def test_unsupported_rbe3_is_named(tmp_path, card, match):
    """The UM alternative, collinear translations (QRG remark: they cannot react the
    reference's rigid motion) and a reference grid among the independents: one line naming
    RBE3 and its id."""
    deck = _deck(tmp_path / "u.bdf", [_grid(99, [0.3, 0.1, 0.0]), card])
    with pytest.raises(BdfError, match=match):
        read_stick_deck(deck)


@pytest.mark.parametrize("extra,match", [
    ("GRID,99,1,0.3,5.72,0.0,1\nRBE3,500,,99,345,1.0,345,10,11", r"RBE3 500: a case's"),
    ("CMASS2,30,1.0-6,10,3,11,3", r"CMASS2 30: .*only a one-grid CMASS2 on a rotation"),
])
def test_convert_refuses_what_a_case_cannot_hold(tmp_path, capsys, extra, match):
    """``asekit convert`` of PT145 with an RBE3 (its out-of-plane components on the planar
    deck: read, N singular in-plane only) or a two-grid CMASS2 (read as the scalar element
    m [[1, -1], [-1, 1]]): the deck reads, the case format has neither (one line, exit 2)."""
    import re

    from asekit.cli.main import main
    from asekit.util.paths import DATA_DIR

    text = (DATA_DIR / "benchmarks" / "pt145" / "pt145.bdf").read_text()
    deck = tmp_path / "p.bdf"
    deck.write_text(text.replace("PARAM   COUPMASS1", extra + "\nPARAM   COUPMASS1", 1))
    sm = read_stick_deck(deck, units="in-lbf-s")
    if "RBE3" in extra:
        assert len(sm.rigid) == 3
    else:                                  # 1e-6 lbf s^2/in between the two z translations
        (tmp_path / "b.bdf").write_text(text)
        dM = sm.M - read_stick_deck(tmp_path / "b.bdf", units="in-lbf-s").M
        i, j = sm.dof(10, 3), sm.dof(11, 3)
        m = 1e-6 * 4.4482216152605 / 0.0254
        np.testing.assert_allclose(dM[np.ix_([i, j], [i, j])], m * np.array([[1, -1], [-1, 1]]),
                                   rtol=1e-9)
        dM[np.ix_([i, j], [i, j])] = 0.0
        assert np.abs(dM).max() == 0.0
    assert main(["convert", str(deck), str(tmp_path / "x.toml"), "--units", "in-lbf-s"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(match, err[0])
    assert not (tmp_path / "x.toml").exists()
