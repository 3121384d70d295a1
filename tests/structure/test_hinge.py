"""The released hinge of an elastic control surface (asekit.structure.hinge, issue 25).

References: the tied limit is the plain plate (the constraints of Cook et al., Concepts and
Applications of FEA, Sec. 9.2, become the element continuity when the spring is infinite); the
free hinge adds one rigid-body mode; a flap on a soft spring on a much stiffer clamped wing
oscillates at sqrt(k_h / I_h) with the flap's plate inertia about its hinge integrated exactly,
I_h = rho h b c_f (c_f^2 / 3 + h^2 / 12) (a uniform plate strip of chord c_f and span b,
translation plus the plate's rotary inertia).
"""

import math

import numpy as np
import pytest
import scipy.linalg as sla

from asekit.geometry import Material, Planform, Thickness
from asekit.structure.assembly import assemble, clamped_edge
from asekit.structure.hinge import (
    hinge_constraint_mode,
    release_hinge,
    released_modes,
    split_at_hinge,
)
from asekit.structure.mesh import panels_mesh

ALU = Material(70e9, 0.3, 2700.0)


def _plate(h, span=0.6, n_span=8):
    return panels_mesh([Planform((0, 0), 0.3, (0, span), 0.3)], Thickness(h, h), 8, [n_span])


def _dense_f(K, M, n):
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)


@pytest.fixture(scope="module")
def free_free():
    """A free-free 0.3 m x 0.6 m, 2 mm aluminium plate with a full-span 25 % flap (no side
    edges: the tied limit is exactly the plain plate)."""
    pm = _plate(0.002)
    hs = split_at_hinge(pm, pm.element_centroids()[:, 0] > 0.225, (0.225, 0.0), (0.0, 1.0))
    K, M = assemble(hs.mesh, ALU)
    K0, M0 = assemble(pm, ALU)
    return hs, K, M, _dense_f(K0, M0, 11)


@pytest.mark.parametrize("release", ["single", "distributed"])
def test_stiff_hinge_gives_the_plain_plate(free_free, release):
    """(a) A very stiff hinge spring: the elastic modes are the plain plate's to 1e-4 (the
    penalty error falls as 1/k_h: measured 3.8e-4 at 1e5 N m/rad, 3.8e-5 at 1e6)."""
    hs, K, M, f0 = free_free
    err = []
    for k_h in (1e5, 1e6):
        f, _ = released_modes(release_hinge(hs, K, M, k_h, release=release), 11)
        err.append(np.max(np.abs(f[3:] / f0[3:] - 1.0)))
    assert err[1] < 1e-4
    assert 7.0 < err[0] / err[1] < 13.0                 # first order in 1 / k_h


def test_free_hinge_adds_a_rigid_mode(free_free):
    """(b) Zero spring on the free-free plate: four zero-frequency modes (plunge, roll, pitch
    and the flap's rotation) where the plain plate has three, and the next elastic modes stay
    above them (zero to the round-off of the dense eigen-solution: lambda_max ~ 1e13 rad^2/s^2
    gives |lambda| ~ 1e-3, 0.01 Hz)."""
    hs, K, M, f0 = free_free
    f, q = released_modes(release_hinge(hs, K, M, 0.0), 6)
    assert np.all(f[:4] < 1e-3 * f0[3])
    assert f[4] > 0.5 * f0[3]
    assert np.all(f0[:3] < 1e-3 * f0[3]) and f0[3] > 10.0


def _clamped_flap(k_of_inertia, release="single"):
    """A clamped 0.3 x 0.6 m, 4 mm plate, a 25 % flap on the outboard half; the spring set by
    ``k_of_inertia(I_h)``."""
    h = 0.004
    pm = _plate(h)
    c = pm.element_centroids()
    hs = split_at_hinge(pm, (c[:, 0] > 0.225) & (c[:, 1] > 0.3), (0.225, 0.3), (0.0, 1.0))
    K, M = assemble(hs.mesh, ALU)
    K0, M0 = assemble(pm, ALU)
    c_f, b = 0.075, 0.3
    inertia = ALU.density * h * b * c_f * (c_f**2 / 3 + h**2 / 12)
    k_h = k_of_inertia(inertia)
    return (release_hinge(hs, K, M, k_h, release=release, support=clamped_edge(pm, K0, M0).T),
            k_h, inertia)


@pytest.mark.parametrize("release", ["single", "distributed"])
def test_soft_hinge_frequency_is_sqrt_k_over_inertia(release):
    """(b) A soft spring on a stiff wing: the lowest mode is the flap's rotation at
    sqrt(k_h / I_h) (I_h integrated exactly, module docstring); the error is the wing's
    quasi-static flexibility, first order in k_h (measured -8.5e-4 at 0.9 Hz, -1.9e-4 at
    0.45 Hz against the wing's first bending at 9.4 Hz). The distributed release (k_h shared
    along the hinge by length) gives the same uniform-rotation mode; the flap's twist on its
    distributed springs is resisted by its plate, so its next mode is far above."""
    errs = []
    for f_h in (0.9, 0.45):
        rh, k_h, inertia = _clamped_flap(lambda i, f_h=f_h: i * (2 * math.pi * f_h) ** 2,
                                         release)
        f, q = released_modes(rh, 2)
        errs.append(abs(f[0] / f_h - 1.0))
        assert f[1] > 10.0 * f_h
        # the mode is the flap's rotation: mass-normalised, its hinge rotation is 1 / sqrt(I_h)
        assert abs(rh.hinge_rotation(q[:, 0])) * math.sqrt(inertia) == pytest.approx(1.0,
                                                                                     abs=2e-3)
        # the hinge moment is the spring's: H = k_h r for a uniform rotation
        assert rh.hinge_moment(q[:, 0]) == pytest.approx(k_h * rh.hinge_rotation(q[:, 0]),
                                                         rel=1e-3)
    assert errs[0] < 2e-3 and errs[1] < 0.5 * errs[0]


def test_constraint_mode_is_the_rigid_flap_rotation():
    """The static shape of a unit hinge rotation on the clamped wing is the flap's rigid
    rotation, w = -(x - x_h) on the flap, zero on the wing, and its inertia is I_h."""
    rh, _, inertia = _clamped_flap(lambda i: 1.0)
    q = hinge_constraint_mode(rh)
    u = (rh.T @ q).reshape(-1, 3)
    nodes = rh.split.mesh.nodes
    flap_nodes = np.unique(rh.split.mesh.elements[rh.split.flap_elements])
    wing = np.setdiff1d(np.arange(len(nodes)), flap_nodes)
    np.testing.assert_allclose(u[flap_nodes, 0], -(nodes[flap_nodes, 0] - 0.225), atol=1e-9)
    np.testing.assert_allclose(u[flap_nodes, 2], 1.0, atol=1e-9)
    np.testing.assert_allclose(u[wing], 0.0, atol=1e-9)
    assert float(q @ (rh.M @ q)) == pytest.approx(inertia, rel=1e-9)


def test_bad_inputs():
    pm = _plate(0.002)
    c = pm.element_centroids()
    with pytest.raises(ValueError, match="flap_elements"):
        split_at_hinge(pm, np.zeros(pm.n_elements, bool), (0.225, 0.0), (0.0, 1.0))
    with pytest.raises(ValueError, match="aft of the hinge"):
        split_at_hinge(pm, c[:, 0] > 0.1, (0.225, 0.0), (0.0, 1.0))
    with pytest.raises(ValueError, match="no element edge on the hinge"):
        split_at_hinge(pm, c[:, 0] > 0.25, (0.25, 0.0), (0.0, 1.0))
    hs = split_at_hinge(pm, c[:, 0] > 0.225, (0.225, 0.0), (0.0, 1.0))
    K, M = assemble(hs.mesh, ALU)
    with pytest.raises(ValueError, match="hinge_stiffness"):
        release_hinge(hs, K, M, -1.0)
    with pytest.raises(ValueError, match="release"):
        release_hinge(hs, K, M, 1.0, release="hinged")
