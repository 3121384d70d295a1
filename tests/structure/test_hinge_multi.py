"""Several elastic control surfaces side by side (asekit.structure.hinge.split_at_hinges,
release_hinges, hinge_constraint_modes; issue 25).

References: the tied limit of each hinge is the plate with the surfaces' side edges cut (the
mesh with the hinge copies merged back into their wing nodes, assembled directly: element
continuity in place of the constraints of Cook, Malkus, Plesha & Witt, *Concepts and
Applications of FEA*, 4th ed., 2002, Sec. 9.2), approached as 1/k_h (the penalty of a finite
spring); a surface on a soft spring on a stiffer clamped wing oscillates at sqrt(k_h / I_h) of
its own strip, I_h = rho h b c_f (c_f^2 / 3 + h^2 / 12) (a uniform plate strip of chord c_f and
span b, translation plus rotary inertia); Craig & Bampton's constraint modes ("Coupling of
substructures for dynamic analyses", AIAA J. 6(7), 1968, Eq. 5) of two surfaces that share no
element are mass-orthogonal on a clamped wing (the wing does not move under a surface's rigid
rotation); one aileron split into two halves with the same hinge stiffness per length and the
two rotations tied is the one aileron but for the cut between the halves.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from asekit.geometry import Material, Planform, Thickness
from asekit.structure.assembly import assemble, clamped_edge
from asekit.structure.hinge import (
    hinge_balance_mass,
    hinge_constraint_modes,
    release_hinge,
    release_hinges,
    released_modes,
    split_at_hinge,
    split_at_hinges,
)
from asekit.structure.mesh import panels_mesh

ALU = Material(70e9, 0.3, 2700.0)
X_H, C_F = 0.225, 0.075                       # hinge line and flap chord of the 0.3 m plate


def _plate(h):
    return panels_mesh([Planform((0, 0), 0.3, (0, 0.6), 0.3)], Thickness(h, h), 8, [8])


def _strips(pm, spans):
    c = pm.element_centroids()
    return [(c[:, 0] > X_H) & (c[:, 1] > a) & (c[:, 1] < b) for a, b in spans]


def _split(pm, spans):
    return split_at_hinges(pm, _strips(pm, spans), [(X_H, 0.0)] * len(spans),
                           [(0.0, 1.0)] * len(spans))


def _dense_f(K, M, n):
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)


def _strip_inertia(h, b):
    return ALU.density * h * b * C_F * (C_F**2 / 3 + h**2 / 12)


def test_split_matches_the_single_surface_split():
    """One surface through split_at_hinges is split_at_hinge's split, node for node."""
    pm = _plate(0.002)
    (a,) = _split(pm, [(0.3, 0.6)])
    b = split_at_hinge(pm, _strips(pm, [(0.3, 0.6)])[0], (X_H, 0.0), (0.0, 1.0))
    np.testing.assert_array_equal(a.mesh.elements, b.mesh.elements)
    np.testing.assert_array_equal(a.copy_of, b.copy_of)
    np.testing.assert_array_equal(a.weight, b.weight)


def test_stiff_hinges_give_the_cut_plate():
    """Two adjacent full-span halves of a 25 % flap on the free-free plate, both hinges very
    stiff: the elastic modes are the plate with the cut between the halves (the merged mesh),
    the error falling as 1/k_h (measured 1.9e-4 at 1e5 N m/rad, 1.9e-5 at 1e6). The cut itself
    lowers the plain plate's modes 2-5 % (measured): it is a real gap, not an error."""
    pm = _plate(0.002)
    parts = _split(pm, [(0.0, 0.3), (0.3, 0.6)])
    mesh = parts[0].mesh
    el = mesh.elements.copy()
    for p in parts:                       # merge every hinge copy back into its wing node
        for c in np.flatnonzero(p.on_hinge):
            el[el == p.copy_nodes[c]] = p.copy_of[c]
    used = np.unique(el)
    remap = np.full(mesh.n_nodes, -1)
    remap[used] = np.arange(used.size)
    K0, M0 = assemble(replace(mesh, nodes=mesh.nodes[used], elements=remap[el]), ALU)
    f0 = _dense_f(K0, M0, 11)
    K, M = assemble(mesh, ALU)
    err = []
    for k_h in (1e5, 1e6):
        f, _ = released_modes(release_hinges(parts, K, M, k_h), 11)
        err.append(np.max(np.abs(f[3:] / f0[3:] - 1.0)))
    assert err[1] < 1e-4
    assert 7.0 < err[0] / err[1] < 13.0                 # first order in 1 / k_h


@pytest.fixture(scope="module")
def clamped_pair():
    """A clamped 0.3 x 0.6 m, 4 mm plate with two adjacent 25 % ailerons of spans 0.15 m and
    0.3 m (y in [0.15, 0.3] and [0.3, 0.6])."""
    h = 0.004
    pm = _plate(h)
    K0, M0 = assemble(pm, ALU)
    spans = [(0.15, 0.3), (0.3, 0.6)]
    parts = _split(pm, spans)
    K, M = assemble(parts[0].mesh, ALU)
    inertia = np.array([_strip_inertia(h, b - a) for a, b in spans])
    return pm, parts, K, M, clamped_edge(pm, K0, M0).T, inertia


def test_soft_hinges_each_at_sqrt_k_over_its_own_inertia(clamped_pair):
    """Each aileron on a soft spring of its own (0.6 and 0.9 Hz targets): the two lowest modes
    are the two ailerons' rotations at sqrt(k_h,k / I_h,k) of their own strips, each mode
    moving its own hinge only (mass-normalised: r_k sqrt(I_k) = 1); the error is the wing's
    quasi-static flexibility (measured -7.5e-5 and -9.1e-4 against the wing's 10 Hz bending)."""
    _, parts, K, M, S, inertia = clamped_pair
    f_h = np.array([0.6, 0.9])
    rh = release_hinges(parts, K, M, inertia * (2 * math.pi * f_h) ** 2, support=S)
    f, q = released_modes(rh, 3)
    np.testing.assert_allclose(f[:2], f_h, rtol=2e-3)
    assert f[2] > 10.0 * f_h[1]
    r = rh.hinge_rotation(q[:, :2]) * np.sqrt(inertia)[:, None]      # (surface, mode)
    np.testing.assert_allclose(np.abs(np.diag(r)), 1.0, atol=3e-3)
    assert np.max(np.abs(r[[0, 1], [1, 0]])) < 3e-3
    np.testing.assert_allclose(rh.hinge_moment(q[:, :2]),
                               rh.hinge_stiffness[:, None] * rh.hinge_rotation(q[:, :2]))


def test_constraint_modes_have_the_strip_inertias_and_no_coupling(clamped_pair):
    """Craig-Bampton constraint modes of the two ailerons: each is its own strip's rigid
    rotation (w = -(x - x_h) on it, nothing elsewhere), its inertia the exact strip integral,
    and the two are mass-orthogonal (no shared element, the wing still)."""
    _, parts, K, M, S, inertia = clamped_pair
    rh = release_hinges(parts, K, M, 1.0, support=S)
    psi = hinge_constraint_modes(rh)
    m = psi.T @ (rh.M @ psi)
    np.testing.assert_allclose(np.diag(m), inertia, rtol=1e-9)
    assert abs(m[0, 1]) < 1e-9 * inertia[0]
    u = (rh.T @ psi).reshape(-1, 3, 2)
    nodes = parts[0].mesh.nodes
    for k, p in enumerate(parts):
        own = np.unique(p.mesh.elements[p.flap_elements])
        np.testing.assert_allclose(u[own, 0, k], -(nodes[own, 0] - X_H), atol=1e-9)
        rest = np.setdiff1d(np.arange(len(nodes)), own)
        np.testing.assert_allclose(u[rest, :, k], 0.0, atol=1e-9)


def test_congruent_surfaces_have_equal_inertia_and_balance_adds_to_its_own():
    """Two congruent ailerons (0.15 m each, side by side): equal inertias to round-off; a
    balance mass on the outboard one (0.05 kg, 2 cm ahead of its hinge) adds m d^2 to its
    inertia only."""
    h = 0.004
    pm = _plate(h)
    K0, M0 = assemble(pm, ALU)
    parts = _split(pm, [(0.3, 0.45), (0.45, 0.6)])
    K, M = assemble(parts[0].mesh, ALU)
    M = (M + hinge_balance_mass(parts[1], (0.205, 0.525), -0.02, 0.05)).tocsr()
    rh = release_hinges(parts, K, M, 1.0, support=clamped_edge(pm, K0, M0).T)
    psi = hinge_constraint_modes(rh)
    i0, i1 = np.diag(psi.T @ (rh.M @ psi))
    assert i0 == pytest.approx(_strip_inertia(h, 0.15), rel=1e-9)
    assert i1 == pytest.approx(i0 + 0.05 * 0.02**2, rel=1e-9)


def test_tied_halves_are_the_one_aileron():
    """One 0.3 m aileron on k_h against its two 0.15 m halves on k_h / 2 each (the same
    stiffness per length): with the two rotations tied (r_1 = r_0) the hinge mode is the one
    aileron's to 1e-4 (measured 2.0e-5 at 0.9 Hz; the cut between the halves changes the
    higher, flap-bending modes by up to 4 %), and the untied pair's in-phase mode is it to 2e-4
    (measured 7e-5), its anti-phase partner close by (soft hinges, rigid strips)."""
    h = 0.004
    pm = _plate(h)
    K0, M0 = assemble(pm, ALU)
    S = clamped_edge(pm, K0, M0).T
    k_h = _strip_inertia(h, 0.3) * (2 * math.pi * 0.9) ** 2
    one = _split(pm, [(0.3, 0.6)])
    K1, M1 = assemble(one[0].mesh, ALU)
    f_one, _ = released_modes(release_hinge(one[0], K1, M1, k_h, support=S), 2)
    two = _split(pm, [(0.3, 0.45), (0.45, 0.6)])
    K2, M2 = assemble(two[0].mesh, ALU)
    rh = release_hinges(two, K2, M2, [k_h / 2, k_h / 2], support=S)
    n, (r0, r1) = rh.K.shape[0], rh.hinge_index
    keep = np.setdiff1d(np.arange(n), [r1])
    G = sp.csr_matrix((np.ones(n), (np.r_[keep, r1], np.r_[np.arange(n - 1),
                                                             np.searchsorted(keep, r0)])),
                      shape=(n, n - 1))
    f_tied = _dense_f(G.T @ rh.K @ G, G.T @ rh.M @ G, 2)
    assert f_tied[0] == pytest.approx(f_one[0], rel=1e-4)
    f_two, q = released_modes(rh, 3)
    r = rh.hinge_rotation(q[:, :2])
    in_phase = int(np.argmax(r[0] * r[1]))
    assert r[0, in_phase] * r[1, in_phase] > 0
    assert f_two[in_phase] == pytest.approx(f_one[0], rel=2e-4)


def test_bad_inputs():
    pm = _plate(0.002)
    a, b = _strips(pm, [(0.0, 0.4), (0.3, 0.6)])
    with pytest.raises(ValueError, match="two surfaces share an element"):
        split_at_hinges(pm, [a, b], [(X_H, 0.0)] * 2, [(0.0, 1.0)] * 2)
    with pytest.raises(ValueError, match="one entry per surface"):
        split_at_hinges(pm, [a], [(X_H, 0.0)] * 2, [(0.0, 1.0)])
    c = pm.element_centroids()
    with pytest.raises(ValueError, match=r"no element edge on the hinge line \(surface 1\)"):
        split_at_hinges(pm, [a, (c[:, 0] > 0.25) & (c[:, 1] > 0.45)], [(X_H, 0.0), (0.25, 0.0)],
                        [(0.0, 1.0)] * 2)
