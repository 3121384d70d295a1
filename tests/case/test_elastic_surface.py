"""``[[control_surface]] kind = "elastic"`` (issue 25): the aileron wing (data/cases/
aileron_wing.toml) with the aileron's plate released along its hinge
(asekit.structure.hinge, asekit.aeroelastic.control_surface.elastic_flap_modal_model,
asekit.case.pipeline.control_surface_model).

Reference numbers: the aileron is a uniform 2 mm aluminium plate strip of chord c_f = 0.075 m
and span b = 0.6 m, so its mass m = rho h b c_f = 0.243 kg, its static unbalance about the
hinge S = m c_f / 2 and its inertia I_h = m (c_f^2 / 3 + h^2 / 12) (translation plus the plate's
rotary inertia), integrals that the consistent mass matrix reproduces exactly for the linear
displacement of a rigid rotation.
"""

import math
import tomllib
import warnings

import numpy as np
import pytest
import scipy.linalg as sla

from asekit.case import CaseError, case_from_dict, load_case
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

AILERON = CASES_DIR / "aileron_wing.toml"
RHO, H, C_F, B = 2700.0, 0.002, 0.075, 0.6


def _elastic(**changes):
    d = tomllib.loads(AILERON.read_text())
    d["control_surface"][0].update({"kind": "elastic", **changes})
    return d


@pytest.fixture(scope="module")
def elastic_case():
    return case_from_dict(_elastic())


@pytest.fixture(scope="module")
def models(elastic_case):
    return P.control_surface_model(elastic_case), P.control_surface_model(load_case(AILERON))


def test_kind_is_read_and_checked():
    assert case_from_dict(_elastic()).control_surfaces[0].kind == "elastic"
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.kind must be one of 'rigid', "
                                        r"'elastic'"):
        case_from_dict(_elastic(kind="flexible"))
    d = _elastic()
    d["control_surface"].append(dict(d["control_surface"][0], name="inboard", kind="rigid",
                                     span_fraction=[0.1, 0.4]))
    d["control_surface"][1].pop("actuator")             # (one actuator per case)
    assert [c.kind for c in case_from_dict(d).control_surfaces] == ["elastic", "rigid"]
    d["control_surface"][1]["kind"] = "elastic"          # several elastic surfaces: allowed
    assert [c.kind for c in case_from_dict(d).control_surfaces] == ["elastic", "elastic"]


def test_mesh_and_support_are_checked():
    d = _elastic()
    d["panel"][0]["n_chord"] = 6                     # no node line at 75 % of the chord
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.hinge_chord_fraction / "
                                        r"span_fraction: .*element lines on its hinge"):
        P.control_surface_model(case_from_dict(d))
    with pytest.raises(CaseError, match=r"control_surface\[0\]\.span_fraction \[0\.0, 1\.0\]: "
                                        r"the elastic surface reaches the support"):
        P.control_surface_model(case_from_dict(_elastic(span_fraction=[0.0, 1.0])))


def test_inertia_and_unbalance_are_the_plate_strip_integrals(models):
    """The elastic kind's I_h and S from its computed hinge mode equal the exact integrals
    (module docstring) to round-off; the rigid kind's lumped hinge line gives 4.2 % and 6.3 %
    more on this 8 x 16 mesh (measured; they converge as the mesh is refined)."""
    el, rg = models
    m = RHO * H * B * C_F
    assert el.inertia[0] == pytest.approx(m * (C_F**2 / 3 + H**2 / 12), rel=1e-7)
    assert el.static_unbalance[0] == pytest.approx(m * C_F / 2, rel=1e-7)
    assert 1.0 < rg.inertia[0] / el.inertia[0] < 1.06


def test_mass_balance_adds_its_exact_moments_about_the_hinge():
    """``mass_balance`` on an elastic surface: 0.4 kg on a rigid arm 5 cm ahead of the hinge
    (d = -0.05 m, the rigid kind's balance of tests/case/test_control_surfaces.py) adds exactly
    m d = -0.02 kg m to the plate strip's static unbalance and m d^2 = 1 g m^2 to its inertia
    (the point-mass moments about the hinge line; the strip's exact integrals as above)."""
    m_b, d = 0.4, -0.05
    c = _elastic(mass_balance=[{"position": [0.175, 0.9], "mass": m_b}])
    c["panel"][0].update(n_chord=4, n_span=8)          # coarse: the integrals stay exact
    c["aero"]["boxes"] = [{"n_chord": 4, "n_span": 8}]
    fm = P.control_surface_model(case_from_dict(c))
    m = RHO * H * B * C_F
    assert fm.static_unbalance[0] == pytest.approx(m * C_F / 2 + m_b * d, rel=1e-7)
    assert fm.inertia[0] == pytest.approx(m * (C_F**2 / 3 + H**2 / 12) + m_b * d * d, rel=1e-7)
    assert fm.static_unbalance[0] < 0                   # over-balanced: centre of mass ahead


@pytest.mark.slow
def test_mass_balance_lifts_the_elastic_aileron_flutter_to_the_wings():
    """The elastic aileron free on its hinge flutters far below the locked wing (measured at
    M 0: 11.5 against 24.6 m/s, tests/case/test_elastic_case.py); over-balanced by 0.4 kg 5 cm
    ahead of the hinge, as the rigid kind in tests/case/test_control_surfaces.py, the first
    flutter is the wing's own again, within 5 % of the locked wing's."""
    free = P.control_surface_flutter(case_from_dict(_elastic()))
    locked = P.flutter(case_from_dict(_elastic())).results
    balanced = P.control_surface_flutter(case_from_dict(_elastic(
        mass_balance=[{"position": [0.175, 0.9], "mass": 0.4}])))
    for f, lk, b in zip(free, locked, balanced):
        assert f.speed_ms < 0.7 * lk.flutter.speed
        assert b.speed_ms == pytest.approx(lk.flutter.speed, rel=0.05)


def test_hinge_coordinate_is_the_rigid_deflection(models, elastic_case):
    """The hinge coordinate's box mode (splined from the computed constraint mode) is the
    rigid deflection of the hinged boxes, so its generalised force is the pressure integral's
    hinge moment -int dp d dA, the same as the rigid kind's; K_dd = k_h, so the spring's hinge
    moment is k_h delta."""
    from asekit.aero.control_surface import deflection_modes
    from asekit.aeroelastic.control_surface import steady_generalised_forces

    el, rg = models
    hm = P.control_surface_mesh(elastic_case)
    ref = deflection_modes(hm)
    n = el.n_wing
    np.testing.assert_allclose(el.box_modes.h_cp[:, n], ref.h_cp[:, 0], atol=1e-9)
    np.testing.assert_allclose(el.box_modes.dhdx_cp[:, n], ref.dhdx_cp[:, 0], atol=1e-9)
    np.testing.assert_allclose(el.box_modes.h_lp[:, n], ref.h_lp[:, 0], atol=1e-9)
    q_el, _, _ = steady_generalised_forces(el, hm, 0.0)
    q_rg, _, _ = steady_generalised_forces(rg, hm, 0.0)
    assert q_el[n, n] == pytest.approx(q_rg[rg.n_wing, rg.n_wing], rel=1e-7)
    # the constraint mode strains only the spring: psi^T K psi = k_h (the K-orthogonality to
    # the fixed-hinge modes is checked inside elastic_flap_modal_model, 1e-6 of K's diagonal)
    assert el.modal.K[n, n] == pytest.approx(0.5, rel=1e-6)     # hinge_stiffness 0.5 N m/rad


def test_stiff_plate_rigid_and_elastic_hinge_frequencies_agree():
    """(c) With the plate made stiff (E x 100: the flap rotates rigidly in both kinds), the
    coupled flap frequency of the rigid kind and of the elastic kind agree once the rigid
    kind's lumped inertia is accounted for: f_r / f_e = sqrt(I_e / I_r) (measured 0.98059
    against 0.97981)."""
    from asekit.aero.boxes import TrapezoidSurface
    from asekit.aero.control_surface import ControlSurface, hinged_mesh
    from asekit.aeroelastic.control_surface import (
        elastic_flap_modal_model,
        flap_modal_model,
        surface_elements,
    )
    from asekit.geometry import Material, Planform, Thickness
    from asekit.structure.assembly import assemble, clamped_edge
    from asekit.structure.hinge import release_hinge, split_at_hinge
    from asekit.structure.mesh import panels_mesh
    from asekit.structure.modes import fixed_modal_model

    mat = Material(70e11, 0.3, RHO)
    pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(H, H), 8, [16])
    K, M = assemble(pm, mat)
    hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
                     ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    rg = flap_modal_model(fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=8), M, hm, 0.5)
    hs = split_at_hinge(pm, surface_elements(pm, hm, 0), (0.225, 0.6), (0.0, 1.0))
    Ks, Ms = assemble(hs.mesh, mat)
    el = elastic_flap_modal_model(release_hinge(hs, Ks, Ms, 0.5,
                                                support=clamped_edge(pm, K, M).T), Ms, hm, 8)

    def flap_frequency(fm):
        lam, v = sla.eigh(fm.modal.K, fm.modal.M)
        i = int(np.argmax(np.abs(v[-1]) * np.sqrt(np.diag(fm.modal.M))[-1]))
        return math.sqrt(lam[i]) / (2 * math.pi)

    f_r, f_e = flap_frequency(rg), flap_frequency(el)
    assert f_e < 0.5 * math.sqrt(el.modal.K[0, 0]) / (2 * math.pi)   # below the wing's modes
    assert f_r / f_e == pytest.approx(math.sqrt(el.inertia[0] / rg.inertia[0]), rel=3e-3)


def test_effectiveness_and_reversal_run_for_the_elastic_kind(elastic_case):
    """The steady outputs: the rigid derivatives are the boxes' (the same for both kinds); the
    flexible effectiveness and reversal use the elastic model (measured reversal 26.9 m/s,
    rigid kind 27.3 m/s: the released wing's fixed-hinge modes differ little from the locked
    wing's in the steady problem)."""
    (el,) = P.control_surfaces(elastic_case)[:1]
    rg = P.control_surfaces(load_case(AILERON))[0]
    assert el.Ch_delta == pytest.approx(rg.Ch_delta, rel=1e-12)
    assert el.reversal_speed_ms == pytest.approx(rg.reversal_speed_ms, rel=0.03)
    assert el.reversal_speed_ms < el.divergence_speed_ms
    assert el.inertia == pytest.approx(RHO * H * B * C_F * (C_F**2 / 3 + H**2 / 12), rel=1e-7)


@pytest.mark.slow
def test_elastic_and_rigid_flutter_on_the_aileron_wing(elastic_case):
    """Flutter with the aileron free on its 0.5 N m/rad spring (measured at M 0: elastic 11.5,
    12.0, 11.9 m/s with 4, 8, 12 wing modes, 12.0 on a 16 x 32 mesh with 8; rigid kind 12.7,
    13.2, 13.0, and 12.9 on 16 x 32). Both far below the locked wing (24.6 m/s); the elastic
    kind converges in modes and mesh to 1 %, and flutters below the rigid kind: about half of
    the gap is the rigid kind's lumped hinge-line mass (it shrinks as that kind's mesh is
    refined), the rest the basis (the released plate's fixed-hinge modes, the aileron free
    along its inboard edge, against the locked plate's modes)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        el = P.control_surface_flutter(elastic_case)
        rg = P.control_surface_flutter(load_case(AILERON))
        d = _elastic()
        d["modes"]["count"] = 8
        el8 = P.control_surface_flutter(case_from_dict(d))
    for e, r, e8 in zip(el, rg, el8):
        assert e.speed_ms < r.speed_ms < 0.7 * 24.6
        assert e.speed_ms == pytest.approx(e8.speed_ms, rel=0.05)


def test_spring_hinge_moment_equals_the_pressure_integral(models, elastic_case):
    """The hinge moment two ways: with the wing held in its first mode (zeta_1 = 1) at
    q = 200 Pa and the aileron floating on its spring, the spring's moment k_h delta (the
    structure's output) equals the pressure integral -q sum dp_i d_i A_i over the aileron's
    boxes (the vortex lattice's pressures of the deformed wing, d the load points' distance
    aft of the hinge, asekit.aero.control_surface.HingedMesh.distance_aft)."""
    from asekit.aero.vlm import vlm_normalwash_matrix
    from asekit.aeroelastic.control_surface import steady_generalised_forces

    el, _ = models
    hm = P.control_surface_mesh(elastic_case)
    q, n = 200.0, el.n_wing
    q0, _, _ = steady_generalised_forces(el, hm, 0.0)
    k_h = el.modal.K[n, n]
    delta = q * q0[n, 0] / (k_h - q * q0[n, n])             # equilibrium of the hinge row
    x = np.zeros(n + 1)
    x[0], x[n] = 1.0, delta
    mesh = hm.mesh
    cp = np.linalg.solve(vlm_normalwash_matrix(mesh, 0.0, False),
                         el.box_modes.normalwash(0.0, 1.0).real @ x)
    on = hm.on_surface[0]
    d = hm.distance_aft(0, mesh.load_point[on])
    h_pressure = -q * float(np.sum(cp[on] * mesh.area[on] * d))
    assert abs(delta) > 1e-3
    assert k_h * delta == pytest.approx(h_pressure, rel=1e-6)


def test_hinge_damper_and_modal_damping_reach_the_model():
    """hinge_damping (N m s/rad) on the hinge coordinate, [damping] modal_damping_ratio on the
    fixed-hinge modes (C_ii = 2 zeta omega_i for unit modal masses), nothing coupling them."""
    d = _elastic(hinge_damping=0.02)
    d["damping"] = {"modal_damping_ratio": 0.01}
    fm = P.control_surface_model(case_from_dict(d))
    n, c = fm.n_wing, fm.modal.C
    assert c[n, n] == pytest.approx(0.02, rel=1e-12)
    # omega_i from the eigenvalues against sqrt(K_ii) of the projected stiffness: equal to the
    # eigen-solution's round-off (measured 1.2e-5 for the 1.2 Hz mode, lambda_max / lambda_1
    # ~ 1e9 in the reduced plate)
    np.testing.assert_allclose(np.diag(c)[:n], 0.02 * np.sqrt(np.diag(fm.modal.K)[:n]),
                               rtol=1e-4)
    assert np.max(np.abs(c[:n, n])) < 1e-12


def test_sparse_and_dense_fixed_hinge_modes_agree(elastic_case):
    """The shift-invert Lanczos branch (large meshes) gives the dense branch's model: the
    eigenvalues to 1e-7 (measured 2.3e-9) and the mass matrix (mode signs aside) to 1e-8."""
    from asekit.aeroelastic.control_surface import elastic_flap_modal_model, surface_elements
    from asekit.geometry import Material
    from asekit.structure.assembly import assemble
    from asekit.structure.hinge import release_hinge, split_at_hinge

    hm = P.control_surface_mesh(elastic_case)
    mesh = P.structural_mesh(elastic_case)
    hs = split_at_hinge(mesh, surface_elements(mesh, hm, 0), (0.225, 0.6), (0.0, 1.0))
    K, M = assemble(hs.mesh, Material(70e9, 0.3, RHO))
    rh = release_hinge(hs, K, M, 0.5, support=P.supported_system(elastic_case).T)
    dense, sparse = (elastic_flap_modal_model(rh, M, hm, 4, dense_limit=lim)
                     for lim in (10**6, 0))
    np.testing.assert_allclose(np.diag(sparse.modal.K), np.diag(dense.modal.K), rtol=1e-7)
    np.testing.assert_allclose(np.abs(sparse.modal.M), np.abs(dense.modal.M), atol=1e-8)


def test_the_support_keeps_its_own_spring():
    """On a shaft (FN1: the actuator's torsional spring added to the supported system, not to
    the plate's K) the elastic model keeps that spring: with the aileron held on its hinge the
    lowest modes are the plain plate's on the same shaft (measured within 0.5 %; the aileron's
    free inboard edge is the difference), not a free pitch at 0 Hz."""
    d = _elastic()
    del d["control_surface"][0]["actuator"]
    d["support"] = {"kind": "shaft", "axis_point": [0.15, 0.0], "torsional_stiffness": 1.0,
                    "model": "FN1", "region": "single_node"}
    case = case_from_dict(d)
    fm = P.control_surface_model(case)
    n = fm.n_wing
    f_el = np.sqrt(np.diag(fm.modal.K)[:n] / np.diag(fm.modal.M)[:n]) / (2 * math.pi)
    f_plain = P.modal_model(case).frequencies_hz
    np.testing.assert_allclose(f_el[:2], f_plain[:2], rtol=0.02)


def test_hinge_freeplay_runs_for_the_elastic_kind():
    """The hinge row is a hinge coordinate for asekit.aeroelastic.hinge_freeplay: with a
    0.5 deg freeplay the state-space flutter speed with the full spring is the p-k one of
    control_surface_flutter to the RFA's accuracy (measured 11.90 against 11.52 m/s at M 0;
    the rigid kind 12.99 against 12.75)."""
    case = case_from_dict(_elastic(freeplay_deg=0.5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = P.control_surface_freeplay(case)
        pk = P.control_surface_flutter(case)
    for r, f in zip(rows, pk):
        assert r.linear_flutter_speed_ms == pytest.approx(f.speed_ms, rel=0.05)
        assert r.lco_at_first_point       # unbalanced: LCOs from the first speed (2 m/s) on
