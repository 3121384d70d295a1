"""Analytic structural sensitivities (asekit.structure.sensitivity) against central finite
differences of the whole structural chain (assembly, supports, eigen-solution).

Tolerances: K and M are cubic polynomials in the thickness scales, so a central difference with
step eps has truncation error O(eps^2) ~ 1e-8 relative at eps = 1e-4. The eigen-solution's
central differences carry O(eps^2) truncation plus eigh's round-off / eps (measured: 1e-7 to
1e-6 relative at eps = 1e-4 for thickness, 1e-3 for density and a point mass, whose shape
changes are small). Every check asserts 1e-5 relative (the issue's requirement).
"""

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla

from asekit.geometry import LinearThickness, Material, Planform
from asekit.structure.assembly import assemble, clamped_edge, point_mass_matrix
from asekit.structure.mesh import rectangular_mesh, structured_mesh
from asekit.structure.plate import consistent_mass, mitc4_stiffness
from asekit.structure.sensitivity import (
    density_derivative,
    element_parts,
    element_scale_dh,
    mode_shape_derivatives,
    point_mass_derivative,
    point_mass_position_derivative,
    reduce,
    thickness_derivatives,
    youngs_modulus_derivative,
)
from asekit.structure.supports import edge_supports

ALU = Material(70e9, 0.3, 2700.0)
EPS = 1e-4
RTOL = 1e-5
N_MODES = 4


def _tapered_mesh():
    """A small swept, tapered clamped plate (3 x 4 elements, thickness 4 -> 2 mm) with its
    thickness held per element corner, so a thickness-scale variable is a corner scaling."""
    mesh = structured_mesh(Planform((0.0, 0.0), 0.156, (0.078, 0.15), 0.078),
                           LinearThickness(0.004, 0.002), 3, 4)
    ct = mesh.thickness_at(mesh.nodes[mesh.elements][:, :, 1])
    return dataclasses.replace(mesh, corner_thickness=ct)


def _groups(mesh):
    """Three thickness variables: spanwise bands of elements."""
    y = mesh.element_centroids()[:, 1]
    return np.digitize(y, np.quantile(y, [1 / 3, 2 / 3]))


def _scaled(mesh, groups, theta):
    return dataclasses.replace(mesh, corner_thickness=mesh.corner_thickness
                               * np.asarray(theta)[groups][:, None])


def _modes(mesh, material, extra_M=None):
    """Lowest modes of the root-clamped plate (dense eigh: tiny system), sign-fixed."""
    K, M = assemble(mesh, material)
    if extra_M is not None:
        M = M + extra_M
    sys_ = clamped_edge(mesh, K, M)
    lam, q = sla.eigh(sys_.K.toarray(), sys_.M.toarray(), subset_by_index=(0, N_MODES - 1))
    q = q * np.sign(q[np.argmax(np.abs(q), axis=0), np.arange(q.shape[1])])
    return sys_, lam, q


def test_parts_reproduce_the_element_matrices():
    mesh = _tapered_mesh()
    for rule in ("gauss", "centroid"):
        m = mesh if rule == "gauss" else dataclasses.replace(mesh, corner_thickness=None)
        p = element_parts(m, ALU, rule)
        K, M = mitc4_stiffness(m, ALU, rule), consistent_mass(m, ALU, rule)
        assert np.max(np.abs(p.stiffness() - K)) <= 1e-12 * np.max(np.abs(K))
        assert np.max(np.abs(p.mass() - M)) <= 1e-12 * np.max(np.abs(M))


def test_thickness_matrix_derivatives_match_central_differences():
    mesh = _tapered_mesh()
    g = _groups(mesh)
    parts = element_parts(mesh, ALU)
    dK, dM = thickness_derivatives(mesh, parts, *element_scale_dh(parts, g))
    for j in range(3):
        e = np.eye(3)[j] * EPS
        Kp, Mp = assemble(_scaled(mesh, g, 1 + e), ALU)
        Km, Mm = assemble(_scaled(mesh, g, 1 - e), ALU)
        for d, (a, b) in ((dK[j], (Kp, Km)), (dM[j], (Mp, Mm))):
            fd = ((a - b) / (2 * EPS)).toarray()
            assert np.max(np.abs(d.toarray() - fd)) <= RTOL * np.max(np.abs(fd))


def _check_eigen(dlam, dphi, fd_lam, fd_phi, floor=0.0):
    """1e-5 relative to the largest entry; ``floor`` (per unit variable) for a derivative that
    is exactly zero (the shapes do not depend on E), where the difference is round-off only."""
    assert np.max(np.abs(dlam - fd_lam) / np.abs(fd_lam).max()) <= RTOL
    for i in range(N_MODES):
        scale = max(np.abs(fd_phi[:, i]).max(), floor)
        assert np.max(np.abs(dphi[:, i] - fd_phi[:, i])) <= RTOL * scale, i


def test_nelson_thickness_derivatives_of_frequencies_and_shapes():
    mesh = _tapered_mesh()
    g = _groups(mesh)
    parts = element_parts(mesh, ALU)
    dK, dM = thickness_derivatives(mesh, parts, *element_scale_dh(parts, g))
    sys_, lam, q = _modes(mesh, ALU)
    dKr = [reduce(sys_.T, a) for a in dK]
    dMr = [reduce(sys_.T, a) for a in dM]
    dlam, dphi = mode_shape_derivatives(sys_.K, sys_.M, lam, q, dKr, dMr)
    for j in range(3):
        e = np.eye(3)[j] * EPS
        _, lp, qp = _modes(_scaled(mesh, g, 1 + e), ALU)
        _, lm, qm = _modes(_scaled(mesh, g, 1 - e), ALU)
        _check_eigen(dlam[j], dphi[j], (lp - lm) / (2 * EPS), (qp - qm) / (2 * EPS))
    # the bending-dominated first mode stiffens faster than it gains mass: omega rises with h
    assert np.all(dlam.sum(axis=0)[:2] > 0)


def test_material_and_point_mass_derivatives():
    mesh = _tapered_mesh()
    K, M = assemble(mesh, ALU)
    pos = (0.10, 0.12)
    m0 = 0.01                                              # kg
    Mp0 = point_mass_matrix(mesh, [(pos, m0, (0.0, 0.0))])
    sys_, lam, q = _modes(mesh, ALU, Mp0)
    T = sys_.T
    zero = 0 * K
    dK = [reduce(T, youngs_modulus_derivative(K, ALU)), reduce(T, zero), reduce(T, zero)]
    dM = [reduce(T, zero), reduce(T, density_derivative(M, ALU)),
          reduce(T, point_mass_derivative(mesh, pos))]
    dlam, dphi = mode_shape_derivatives(sys_.K, sys_.M, lam, q, dK, dM)
    E, rho = ALU.youngs_modulus, ALU.density
    cases = [(lambda s: (Material(E * (1 + s), 0.3, rho), Mp0), E),
             (lambda s: (Material(E, 0.3, rho * (1 + s)), Mp0), rho),
             (lambda s: (ALU, point_mass_matrix(mesh, [(pos, m0 * (1 + s), (0.0, 0.0))])), m0)]
    # the shapes do not depend on E (K scales as a whole): the analytic derivative is zero to
    # round-off, and the finite difference is eigh's round-off (~1e-11 |phi| / eps), so E's
    # shape check is absolute: |dphi - fd| <= 1e-6 |phi| per unit relative change of E
    assert np.abs(dphi[0]).max() <= 1e-9 * np.abs(q).max() / E
    floors = (0.1 * np.abs(q).max() / E, 0.0, 0.0)
    eps = 1e-3        # the point mass changes the shapes little: a larger step beats eigh's noise
    for j, (make, x0) in enumerate(cases):
        _, lp, qp = _modes(mesh, *make(eps))
        _, lm, qm = _modes(mesh, *make(-eps))
        _check_eigen(dlam[j], dphi[j], (lp - lm) / (2 * eps * x0), (qp - qm) / (2 * eps * x0),
                     floor=floors[j])
    # analytic limits: omega^2 is proportional to E (dlam/dE = lam / E); mass lowers frequencies
    assert np.allclose(dlam[0], lam / E, rtol=1e-10)
    assert np.all(dlam[1] < 0) and np.all(dlam[2] <= 0)


def test_repeated_eigenvalues_are_refused():
    """A simply supported square plate has the repeated pair (1, 2) / (2, 1): Nelson's method
    does not apply there, and the error names the modes."""
    mesh = rectangular_mesh(0.2, 0.2, 0.002, 6, 6)
    K, M = assemble(mesh, ALU)
    sys_ = edge_supports(mesh, K, M)
    lam, q = sla.eigh(sys_.K.toarray(), sys_.M.toarray(), subset_by_index=(0, 3))
    assert abs(lam[2] - lam[1]) <= 1e-9 * lam[2]
    parts = element_parts(mesh, ALU)
    dK, dM = thickness_derivatives(mesh, parts, *element_scale_dh(parts, np.zeros(36, int)))
    dK, dM = [reduce(sys_.T, dK[0])], [reduce(sys_.T, dM[0])]
    with pytest.raises(ValueError, match=r"modes \[1, 2\] have repeated eigenvalues"):
        mode_shape_derivatives(sys_.K, sys_.M, lam, q, dK, dM)
    # the distinct fundamental mode is still differentiable (uniform scale: dlam = 2 lam approx)
    dlam, _ = mode_shape_derivatives(sys_.K, sys_.M, lam, q, dK, dM, modes=[0])
    assert dlam[0, 0] == pytest.approx(2 * lam[0], rel=0.02)


@pytest.mark.parametrize("axis", [0, 1])
def test_point_mass_position_derivative(axis):
    """dM/dx and dM/dy of a point mass (with rotary inertia) inside an element against central
    differences of point_mass_matrix, then the frequencies' and shapes' derivatives
    (Fox-Kapoor, Nelson) against differences of the clamped plate's eigenproblem. The tapered
    element's map is not affine, so (r, s) is nonlinear in (x, y): the central difference's
    truncation error, measured 7.9e-6 relative at h = 1e-4 m falling as h^2 (7.9e-10 at
    1e-6 m), sets the steps: 1e-6 m for the matrix (checked to 1e-8), 1e-5 m for the modes."""
    mesh = _tapered_mesh()
    pos, m0, inertia = np.array([0.10, 0.12]), 0.05, (2e-6, 3e-6)

    def pm(p):
        return point_mass_matrix(mesh, [(tuple(p), m0, inertia)])
    dM = point_mass_position_derivative(mesh, pos, m0, inertia, axis)
    h = 1e-6                                                # m, well inside the element
    e = np.eye(2)[axis] * h
    fd = ((pm(pos + e) - pm(pos - e)) / (2 * h)).toarray()
    assert np.abs(dM.toarray() - fd).max() <= 1e-8 * np.abs(fd).max()
    assert abs(dM.sum()) <= 1e-9                            # moving a mass keeps its total
    sys_, lam, q = _modes(mesh, ALU, pm(pos))
    dlam, dphi = mode_shape_derivatives(sys_.K, sys_.M, lam, q, [reduce(sys_.T, 0 * dM)],
                                        [reduce(sys_.T, dM)])
    h = 1e-5
    _, lp, qp = _modes(mesh, ALU, pm(pos + np.eye(2)[axis] * h))
    _, lm, qm = _modes(mesh, ALU, pm(pos - np.eye(2)[axis] * h))
    _check_eigen(dlam[0], dphi[0], (lp - lm) / (2 * h), (qp - qm) / (2 * h))
    # moving the mass outboard (y) lowers the first (bending) frequency of the clamped plate,
    # whose amplitude grows with the span (higher modes have node lines: not a general rule)
    if axis == 1:
        assert dlam[0][0] < 0


def test_point_mass_position_axis_is_checked():
    with pytest.raises(ValueError, match="axis must be 0"):
        point_mass_position_derivative(_tapered_mesh(), (0.1, 0.12), 0.01, axis=2)


@pytest.mark.parametrize("name", ["e1", "e2", "g12", "g13", "g23", "fibre_angle"])
def test_orthotropic_stiffness_derivatives_match_central_differences(name):
    """dK/dp of an orthotropic lamina (a unidirectional glass-epoxy-like ply at 30 deg on a
    tapered plate) for each modulus and the fibre angle against central differences of the
    plate module's assembled K (step 1e-4 relative, 1e-4 rad for the angle): K is linear in
    the moduli (differences exact to round-off) and smooth in the angle (truncation
    O(eps^2) ~ 1e-8), asserted to 1e-5 relative in the Frobenius norm."""
    from asekit.geometry import OrthotropicMaterial
    from asekit.structure.sensitivity import orthotropic_stiffness_derivative
    mesh = _tapered_mesh()
    mat = OrthotropicMaterial(40e9, 10e9, 4e9, 0.28, 1900.0, g13=3.5e9, g23=3e9,
                              fibre_angle=np.radians(30.0))
    dK = orthotropic_stiffness_derivative(mesh, mat, name)
    p = getattr(mat, name)
    h = EPS * (p if name != "fibre_angle" else 1.0)
    Kp = mitc4_stiffness(mesh, dataclasses.replace(mat, **{name: p + h}))
    Km = mitc4_stiffness(mesh, dataclasses.replace(mat, **{name: p - h}))
    from asekit.structure.sensitivity import scatter
    fd = (scatter(mesh, Kp) - scatter(mesh, Km)) / (2 * h)
    err = abs(dK - fd).max() / abs(fd).max()
    assert abs(fd).max() > 0 and err <= RTOL, err
