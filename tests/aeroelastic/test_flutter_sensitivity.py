"""Flutter sensitivities (asekit.aeroelastic.sensitivity) against central finite differences of
the whole chain: plate thickness -> FE matrices -> modes (Nelson) -> GAFs through the spline and
the doublet lattice -> p-k root at a fixed speed -> flutter speed and frequency.

The structure is the reference fin's planform (root chord 156 mm, tip 78 mm, span 150 mm,
4 -> 2 mm aluminium) on a coarse 4 x 4 MITC4 mesh, held by the FN1 single-node shaft spring
(120 N m/rad, thesis Sec. 3.1.1), 3 modes; 6 x 6 doublet-lattice boxes at M 0.5, 7 reduced
frequencies, sea level. Small on purpose: the chain is the point, not the numbers.

Tolerance: central differences with step 1e-4 (relative) carry O(1e-8) truncation error; the
roots are converged to 1e-13 and the crossing to 1e-12 relative, the eigen-solution's round-off
gives ~1e-7 in the differences. The checks assert 1e-5 relative (issue 28).
"""

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import TabulatedGaf, gaf_from_box_modes
from asekit.aero.spline import fe_spline
from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
from asekit.aeroelastic.sensitivity import (
    converge_root,
    extended_shapes,
    flutter_point,
    flutter_speed_sensitivity,
    gaf_derivative,
    modal_matrix_derivative,
    pk_root_sensitivity,
)
from asekit.aeroelastic.statespace import modal_arrays
from asekit.geometry import LinearThickness, Material, Planform
from asekit.structure.assembly import assemble, shaft_support
from asekit.structure.mesh import structured_mesh
from asekit.structure.modes import ModalModel
from asekit.structure.sensitivity import (
    element_parts,
    element_scale_dh,
    mode_shape_derivatives,
    reduce,
    thickness_derivatives,
)

ALU = Material(70e9, 0.3, 2700.0)
PLANFORM = Planform((0.0, 0.0), 0.156, (0.078, 0.15), 0.078)
RHO = 1.225                   # kg/m^3, sea level
B_REF = 0.078                 # m, the fin's root semi-chord
KS = np.array([0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8])
N_MODES = 3
EPS = 1e-4
RTOL = 1e-5


def _base_mesh():
    mesh = structured_mesh(PLANFORM, LinearThickness(0.004, 0.002), 4, 4)
    ct = mesh.thickness_at(mesh.nodes[mesh.elements][:, :, 1])
    return dataclasses.replace(mesh, corner_thickness=ct)


MESH = _base_mesh()
GROUPS = (MESH.element_centroids()[:, 1] > 0.075).astype(int)     # inboard / outboard halves
BOXES = mesh_surfaces(TrapezoidSurface((0.0, 0.0), 0.156, (0.078, 0.15), 0.078, 6, 6))


def _chain(theta, derivatives=False):
    """Modal matrices and GAF table of the design ``theta`` (thickness scales of the inboard and
    outboard halves); with ``derivatives`` also dM, dK, dC, dQ (analytic)."""
    mesh = dataclasses.replace(MESH, corner_thickness=MESH.corner_thickness
                               * np.asarray(theta)[GROUPS][:, None])
    K, M = assemble(mesh, ALU)
    sys_ = shaft_support(mesh, K, M, (0.078, 0.0), 120.0, model="FN1")
    lam, q = sla.eigh(sys_.K.toarray(), sys_.M.toarray(), subset_by_index=(0, N_MODES - 1))
    Phi = sys_.T @ q
    shapes = Phi.reshape(mesh.n_nodes, 3, N_MODES)
    n = N_MODES
    Mm, Km, Cm = q.T @ sys_.M @ q, q.T @ sys_.K @ q, np.zeros((n, n))
    out = {"M": 0.5 * (Mm + Mm.T), "K": 0.5 * (Km + Km.T), "C": Cm}
    if derivatives:
        parts = element_parts(mesh, ALU)
        dh_k, dh_m = element_scale_dh(parts, GROUPS)
        dK, dM = thickness_derivatives(mesh, parts, dh_k / np.asarray(theta)[:, None, None],
                                       dh_m / np.asarray(theta)[:, None, None])
        dKr = [reduce(sys_.T, a) for a in dK]
        dMr = [reduce(sys_.T, a) for a in dM]
        _, dq = mode_shape_derivatives(sys_.K, sys_.M, lam, q, dKr, dMr)
        dshapes = np.array([(sys_.T @ d).reshape(mesh.n_nodes, 3, n) for d in dq])
        shapes = extended_shapes(shapes, dshapes)
        out["dM"] = modal_matrix_derivative(q, sys_.M, dq, dMr)
        out["dK"] = modal_matrix_derivative(q, sys_.K, dq, dKr)
        out["dC"] = np.zeros_like(out["dK"])
    model = ModalModel(frequencies_hz=np.zeros(shapes.shape[2]), M=None, K=None, C=None,
                       n_rigid=0, J_fin=0.0, nodes=mesh.nodes, shapes=shapes,
                       elements=mesh.elements, label="")
    Q = gaf_from_box_modes(fe_spline(model, BOXES), BOXES, 0.5, KS, B_REF)
    out["gaf"] = TabulatedGaf(KS, Q[:, :n, :n], B_REF, 0.5)
    if derivatives:
        out["dQ"] = gaf_derivative(Q, n)
    return out


@pytest.fixture(scope="module")
def base():
    c = _chain(np.ones(2), derivatives=True)
    modal = modal_arrays(M=c["M"], K=c["K"], C=c["C"])
    res = pk_flutter(modal, c["gaf"], RHO, np.arange(100.0, 461.0, 10.0))
    flut = [i for i in pk_instabilities(res, modal, c["gaf"]) if i.kind == "flutter"
            and not i.at_first_point]
    assert flut, "the small fin must flutter in 100-460 m/s (the reference fin does at ~220)"
    f = flut[0]
    col = list(res.modes).index(f.mode)
    iu = int(np.searchsorted(res.velocities, f.speed)) - 1
    U_f, p_f, v_f = flutter_point(c["M"], c["K"], c["C"], c["gaf"], RHO, f.speed,
                                  res.p[iu, col], res.vectors[iu, col])
    return c, U_f, p_f, v_f


def _args(c):
    return c["M"], c["K"], c["C"], c["gaf"], RHO


def test_modal_and_gaf_derivatives(base):
    c, *_ = base
    for j in range(2):
        e = np.eye(2)[j] * EPS
        cp, cm = _chain(1 + e), _chain(1 - e)
        # mass-normalised modes: d(M_mm) = 0 exactly; d(K_mm) = diag(dlambda)
        assert np.abs(c["dM"][j]).max() <= 1e-7          # round-off of the Nelson solves
        fd_k = (cp["K"] - cm["K"]) / (2 * EPS)
        assert np.abs(c["dK"][j] - fd_k).max() <= RTOL * np.abs(fd_k).max()
        # GAFs (eigh keeps each mode's sign under a small perturbation)
        fd_q = (cp["gaf"].Q - cm["gaf"].Q) / (2 * EPS)
        assert np.abs(c["dQ"][j] - fd_q).max() <= RTOL * np.abs(fd_q).max()


def test_pk_root_derivative_at_fixed_speed(base):
    c, U_f, p_f, v_f = base
    U = 0.9 * U_f
    p, v = converge_root(*_args(c), U, abs(p_f.imag), v_f)
    r = pk_root_sensitivity(*_args(c), U, p, c["dM"], c["dK"], c["dC"], c["dQ"])
    for j in range(2):
        e = np.eye(2)[j] * EPS
        pp, _ = converge_root(*_args(_chain(1 + e)), U, abs(p.imag), v)
        pm, _ = converge_root(*_args(_chain(1 - e)), U, abs(p.imag), v)
        fd = (pp - pm) / (2 * EPS)
        assert abs(r.dp[j] - fd) <= RTOL * abs(fd), (j, r.dp[j], fd)
    # and with respect to the airspeed
    pp, _ = converge_root(*_args(c), U * (1 + EPS), abs(p.imag), v)
    pm, _ = converge_root(*_args(c), U * (1 - EPS), abs(p.imag), v)
    fd = (pp - pm) / (2 * EPS * U)
    assert abs(r.dp_du - fd) <= RTOL * abs(fd)


def test_flutter_speed_and_frequency_derivatives(base):
    c, U_f, p_f, v_f = base
    assert abs(p_f.real) <= 1e-9 * abs(p_f)
    s = flutter_speed_sensitivity(*_args(c), U_f, p_f, c["dM"], c["dK"], c["dC"], c["dQ"])
    for j in range(2):
        e = np.eye(2)[j] * EPS
        up, pp, _ = flutter_point(*_args(_chain(1 + e)), U_f, p_f, v_f)
        um, pm, _ = flutter_point(*_args(_chain(1 - e)), U_f, p_f, v_f)
        fd_u = (up - um) / (2 * EPS)
        fd_f = (abs(pp.imag) - abs(pm.imag)) / (2 * EPS) / (2 * np.pi)
        assert s.d_speed[j] == pytest.approx(fd_u, rel=RTOL)
        assert s.d_frequency_hz[j] == pytest.approx(fd_f, rel=RTOL)
    # a thicker plate flutters later (both halves together: the whole fin stiffer)
    assert s.d_speed.sum() > 0
