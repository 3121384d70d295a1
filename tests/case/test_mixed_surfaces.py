"""Rigid and elastic control surfaces in one case (issue 25): data/cases/aileron_wing_mixed.toml,
the wing of aileron_wing_two_elastic.toml with its inboard aileron (50-75 % of the span)
elastic and its outboard aileron (75-100 %) rigid, each on 0.25 N m/rad
(asekit.aeroelastic.control_surface.mixed_flap_modal_model through
asekit.case.pipeline.control_surface_model).

Reference numbers: the elastic aileron is a uniform 2 mm aluminium plate strip (2700 kg/m^3) of
chord c_f = 0.075 m aft of the hinge and span 0.3 m, m = 0.1215 kg, I_h = m (c_f^2 / 3 +
h^2 / 12), S = m c_f / 2 (exact for the consistent mass of a rigid rotation). The other
references are the single-kind models of the same wing, built here: the rigid outboard aileron
alone, both ailerons rigid, the elastic inboard aileron alone, both elastic.

The tests run on a coarse copy (8 x 8 elements and boxes, Mach 0, 2-30 m/s; the hinge and the
ailerons' edges still on element lines).
"""

import dataclasses
import math
import tomllib

import numpy as np
import pytest
from scipy import linalg

from asekit.case import case_from_dict, report
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

MIXED = CASES_DIR / "aileron_wing_mixed.toml"
TWO = CASES_DIR / "aileron_wing_two_elastic.toml"
RHO, H, C_F, B = 2700.0, 0.002, 0.075, 0.3
MASS = RHO * H * B * C_F


def _coarse(name, kinds=("elastic", "rigid"), keep=(0, 1), k_inboard=None):
    d = tomllib.loads(MIXED.read_text())
    d["case"]["name"] += f"_coarse_{name}"
    d["panel"][0].update(n_chord=8, n_span=8)
    d["aero"]["boxes"] = [{"n_chord": 8, "n_span": 8}]
    d["aero"]["machs"] = [0.0]
    d["flight"]["velocities"] = {"min": 2.0, "max": 30.0, "step": 2.0}
    for s, kind in zip(d["control_surface"], kinds):
        s["kind"] = kind
    if k_inboard is not None:
        d["control_surface"][0]["hinge_stiffness"] = k_inboard
    d["control_surface"] = [d["control_surface"][i] for i in keep]
    return case_from_dict(d)


def _frequencies(fm):
    return np.sqrt(linalg.eigh(fm.modal.K, fm.modal.M, eigvals_only=True)) / (2 * math.pi)


@pytest.fixture(scope="module")
def mixed():
    return _coarse("mixed")


def test_the_shipped_case_is_the_two_elastic_wing_with_a_rigid_outboard_aileron():
    mixed, two = tomllib.loads(MIXED.read_text()), tomllib.loads(TWO.read_text())
    a, b = mixed.pop("control_surface")
    a2, b2 = two.pop("control_surface")
    for d in (mixed, two):
        d.pop("case")
    assert mixed == two
    assert a == a2 and b == dict(b2, kind="rigid")
    case = case_from_dict(tomllib.loads(MIXED.read_text()))
    assert [s.kind for s in case.control_surfaces] == ["elastic", "rigid"]


def test_each_surface_keeps_its_single_kind_inertia_and_unbalance(mixed):
    """The rigid aileron's I_h and S equal the rigid kind's (alone, and with the inboard
    aileron rigid too) to round-off: the split only duplicates nodes, M = S^T M_split S.
    The elastic aileron's equal the elastic kind's alone and the exact strip integrals."""
    fm = P.control_surface_model(mixed)
    assert fm.names == ("inboard", "outboard")
    rigid_alone = P.control_surface_model(_coarse("rigid_alone", keep=(1,)))
    both_rigid = P.control_surface_model(_coarse("both_rigid", kinds=("rigid", "rigid")))
    for ref in (rigid_alone.inertia[-1], both_rigid.inertia[1]):
        assert fm.inertia[1] == pytest.approx(ref, rel=1e-12)
    for ref in (rigid_alone.static_unbalance[-1], both_rigid.static_unbalance[1]):
        assert fm.static_unbalance[1] == pytest.approx(ref, rel=1e-12)
    elastic_alone = P.control_surface_model(_coarse("elastic_alone", keep=(0,)))
    assert fm.inertia[0] == pytest.approx(elastic_alone.inertia[0], rel=1e-12)
    assert fm.static_unbalance[0] == pytest.approx(elastic_alone.static_unbalance[0], rel=1e-12)
    assert fm.inertia[0] == pytest.approx(MASS * (C_F ** 2 / 3 + H ** 2 / 12), rel=1e-7)
    assert fm.static_unbalance[0] == pytest.approx(MASS * C_F / 2, rel=1e-7)
    np.testing.assert_allclose(fm.hinge_frequency_hz,
                               np.sqrt(0.25 / fm.inertia) / (2 * math.pi), rtol=1e-12)


def test_a_balance_mass_on_the_rigid_surface_is_the_rigid_kinds():
    """0.1 kg 3 cm ahead of the rigid aileron's hinge (d = -0.03 m): its I_h and S gain
    exactly m d^2 and m d, as the rigid kind alone with the same mass; the elastic one's stay."""
    def with_mass(name, **kw):
        c = _coarse(name, **kw)
        cs = list(c.control_surfaces)
        cs[-1] = dataclasses.replace(cs[-1], mass_balance=(((0.195, 1.05), 0.1),))
        return P.control_surface_model(dataclasses.replace(c, control_surfaces=tuple(cs)))
    bare = P.control_surface_model(_coarse("mixed"))
    fm = with_mass("mixed_balanced")
    alone = with_mass("rigid_alone_balanced", keep=(1,))
    assert fm.inertia[1] - bare.inertia[1] == pytest.approx(0.1 * 0.03 ** 2, rel=1e-9)
    assert fm.static_unbalance[1] - bare.static_unbalance[1] == pytest.approx(-0.003, rel=1e-9)
    assert fm.inertia[0] == bare.inertia[0]
    assert fm.inertia[1] == pytest.approx(alone.inertia[0], rel=1e-12)
    assert fm.static_unbalance[1] == pytest.approx(alone.static_unbalance[0], rel=1e-12)
    assert np.all(np.linalg.eigvalsh(fm.modal.M) > 0)


def test_the_elastic_block_is_the_elastic_kind_alone(mixed):
    """The wing modes and the elastic hinge coordinate of the mixed model are the elastic
    aileron's model alone (the same released plate, the rigid aileron part of it); the rigid
    coordinate couples to them through the mass only, its stiffness the hinge spring."""
    fm = P.control_surface_model(mixed)
    alone = P.control_surface_model(_coarse("elastic_alone", keep=(0,)))
    n = fm.n_wing + 1
    for a, b in ((fm.modal.M, alone.modal.M), (fm.modal.K, alone.modal.K)):
        np.testing.assert_allclose(np.asarray(a)[:n, :n], b, rtol=0,
                                   atol=1e-12 * np.abs(b).max())
    K = np.asarray(fm.modal.K)
    assert K[-1, -1] == 0.25 and not np.any(K[-1, :-1]) and not np.any(K[:-1, -1])
    M = np.asarray(fm.modal.M)
    assert np.all(np.abs(M[:fm.n_wing, -1]) > 1e-6 * math.sqrt(fm.inertia[1]))
    np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-15)
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_a_stiff_elastic_hinge_approaches_the_all_rigid_model():
    """With the inboard hinge stiffened (k_h = 1e2 ... 1e6 N m/rad), its hinge mode leaves
    (f ~ sqrt(k_h)) and the other frequencies converge as 1/k_h (measured: the change of the
    third from k_h = 1e2 to 1e3 is 9-11 times that from 1e3 to 1e4) to within 2 % of the
    all-rigid model's (the rigid outboard aileron on the locked wing; measured on the fine
    mesh: -0.33, -0.34, -1.69, -0.90, -1.76 %). What is left is the elastic aileron's free
    side edges (slits the locked wing has not): the elastic aileron alone, stiff, differs
    from the locked wing by the same -0.33 to -1.76 % (measured)."""
    f = {k: _frequencies(P.control_surface_model(_coarse(f"k{k:g}", k_inboard=k)))
         for k in (1e2, 1e3, 1e4, 1e6)}
    ref = _frequencies(P.control_surface_model(_coarse("rigid_alone", keep=(1,))))
    n = ref.size
    assert f[1e6][n] / f[1e4][n] == pytest.approx(10.0, rel=1e-3)     # the stiff hinge mode
    d1, d2 = np.abs(f[1e2][:n] - f[1e3][:n]), np.abs(f[1e3][:n] - f[1e4][:n])
    assert 9.0 < d1[2] / d2[2] < 11.0
    err = f[1e6][:n] / ref - 1.0
    assert np.all(np.abs(err) < 0.02), err
    assert np.all(np.abs(f[1e2][:n] / ref - 1.0) >= np.abs(err) - 1e-6)


def test_the_control_derivatives_are_the_single_kind_ones(mixed):
    """Each aileron's rigid dCL/d delta and C_h delta (vortex lattice on the same boxes) equal
    the all-rigid and the all-elastic case's; the steady lift of each hinge coordinate (the
    box mode it carries: the rigid deflection or the splined elastic rotation) equals the
    single-kind model's."""
    from asekit.aeroelastic.control_surface import steady_generalised_forces

    rows = {r.name: r for r in P.control_surfaces(mixed)}
    hm = P.control_surface_mesh(mixed)
    fm = P.control_surface_model(mixed)
    _, lift, _ = steady_generalised_forces(fm, hm, 0.0, "symmetric")
    for kinds in (("rigid", "rigid"), ("elastic", "elastic")):
        other = _coarse("_".join(kinds), kinds=kinds)
        for r in P.control_surfaces(other):
            assert rows[r.name].dCL_ddelta_per_rad == pytest.approx(r.dCL_ddelta_per_rad,
                                                                    rel=1e-12)
            assert rows[r.name].Ch_delta == pytest.approx(r.Ch_delta, rel=1e-12)
        if kinds[0] == "rigid":
            fo = P.control_surface_model(other)
            _, lift_o, _ = steady_generalised_forces(fo, P.control_surface_mesh(other), 0.0,
                                                     "symmetric")
            assert lift[-1] == pytest.approx(lift_o[-1], rel=1e-12)
    alone = _coarse("elastic_alone", keep=(0,))
    fa = P.control_surface_model(alone)
    ha = P.control_surface_mesh(alone)
    _, lift_a, _ = steady_generalised_forces(fa, ha, 0.0, "symmetric")
    if ha.mesh.n == hm.mesh.n and np.allclose(ha.mesh.control_point, hm.mesh.control_point):
        assert lift[fm.n_wing] == pytest.approx(lift_a[fa.n_wing], rel=1e-9)
    else:                                    # other boxes: the same lift to the lattice's error
        assert lift[fm.n_wing] == pytest.approx(lift_a[fa.n_wing], rel=0.02)


def test_analyse_json_has_both_kinds_the_flutter_rows_and_the_hinge_mass_matrix(mixed):
    """``analyse``'s JSON: one row per surface with its kind, I_h and S; the hinge-free
    flutter rows; the case-level hinge_mass_matrix equal to FlapModel.hinge_mass_matrix
    (surfaces in case order), its off-diagonal the edge nodes the rigid rotation lumps."""
    out = report.summary(report.run_analysis(mixed, progress=False))
    fm = P.control_surface_model(mixed)
    rows = out["control_surfaces"]
    assert [(r["name"], r["kind"]) for r in rows] == [("inboard", "elastic"),
                                                     ("outboard", "rigid")]
    for r, i, s in zip(rows, fm.inertia, fm.static_unbalance):
        assert (r["hinge_inertia_kgm2"], r["static_unbalance_kgm"]) == (i, s)
    np.testing.assert_array_equal(out["hinge_mass_matrix"], fm.hinge_mass_matrix)
    np.testing.assert_array_equal(np.diag(out["hinge_mass_matrix"]), fm.inertia)
    assert "hinge_mass_matrix" in out["units"]
    (fl,) = out["control_surface_flutter"]
    (locked,) = out["flutter"]
    assert not fl["unstable_at_first_point"] and fl["speed_ms"] is not None
    assert fl["mode"] in ("inboard", "outboard") or isinstance(fl["mode"], int)
    assert fl["speed_ms"] < 0.6 * locked["speed_ms"]       # measured 10.1 against 24.1 m/s


def test_the_inertial_coupling_is_the_lumped_edge_column_and_vanishes_with_the_mesh(mixed):
    """The two ailerons share no element, yet the rigid rotation lumps the whole node column
    on its side edge (the elastic aileron's edge copies included, as flap_modal_model does for
    two adjacent rigid surfaces): M_io = psi_in^T M U_out is that column's O(h) share,
    halving when the spanwise element width halves (the shipped case's 16 against the coarse
    copy's 8; measured 0.02848 against 0.05696 g m^2)."""
    coarse = P.control_surface_model(mixed).hinge_mass_matrix[0, 1]
    fine = P.control_surface_model(case_from_dict(tomllib.loads(MIXED.read_text())))
    assert coarse / fine.hinge_mass_matrix[0, 1] == pytest.approx(2.0, rel=0.01)
    assert fine.hinge_mass_matrix[0, 1] < 0.15 * min(fine.inertia)
