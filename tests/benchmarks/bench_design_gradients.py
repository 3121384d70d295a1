"""Cost of the flutter-speed gradient with many thickness variables (issue 28): analytic
(Nelson mode-shape derivatives, the GAFs of the extended mode set, implicit differentiation of
the p-k flutter point) against central finite differences of the same chain.

Run on demand (not collected by pytest):

    OPENBLAS_NUM_THREADS=1 python tests/benchmarks/bench_design_gradients.py [--n-var 50]

The structure is the reference fin's planform on a 10 x 10 MITC4 mesh (100 elements) held by
its FN1 shaft spring, 5 elastic modes; the thickness variables scale the thickness of spanwise
x chordwise element groups (``--n-var`` of them); the aerodynamics are the case's 140 DLM boxes
at M 0.6 and its 15 reduced frequencies, operators factored once (as the optimiser does); the
flutter point at sea level. CPU time (time.process_time). The central differences cost 2 n_var
chain evaluations; the analytic gradient one evaluation with its derivative terms.

Measured (commit after c57173f, 2-core machine shared with four other jobs, OPENBLAS_NUM_THREADS=1,
``--n-var 50``):

    50 thickness variables, U_f 192.16 m/s: one evaluation 0.28 s; with the analytic gradient
    0.73 s; central differences 21.5 s (100 evaluations); max |analytic - FD| / max |FD| = 2.92e-07
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from asekit.aero.gaf import TabulatedGaf
from asekit.aero.methods import AERO_METHODS
from asekit.aero.spline import fe_spline, modal_forces
from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
from asekit.aeroelastic.sensitivity import (
    extended_shapes,
    flutter_point,
    flutter_speed_sensitivity,
    gaf_derivative,
)
from asekit.aeroelastic.statespace import modal_arrays
from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.structure.assembly import assemble, shaft_support
from asekit.structure.mesh import structured_mesh
from asekit.structure.modes import ModalModel, normal_modes
from asekit.structure.sensitivity import (
    element_parts,
    element_scale_dh,
    mode_shape_derivatives,
    reduce,
    thickness_derivatives,
)
from asekit.util.paths import FIN_FILE

N_MODES = 5
RHO = 1.225


def setup(n_var: int):
    case = load_case(FIN_FILE)
    p = case.panels[0]
    mesh = structured_mesh(p.planform, case.thickness, 10, 10)
    mesh = dataclasses.replace(mesh, corner_thickness=mesh.thickness_at(
        mesh.nodes[mesh.elements][:, :, 1]))
    groups = np.arange(mesh.n_elements) * n_var // mesh.n_elements
    boxes, ks = P.box_mesh(case), P.reduced_frequencies(case)
    ops = AERO_METHODS["dlm"].operators(boxes, 0.6, ks, 0.078, False, "quartic")
    return case, mesh, groups, boxes, ks, ops


def chain(ctx, theta, derivatives):
    case, mesh0, groups, boxes, ks, ops = ctx
    mesh = dataclasses.replace(mesh0, corner_thickness=mesh0.corner_thickness
                               * theta[groups][:, None])
    K, M = assemble(mesh, case.material)
    sys_ = shaft_support(mesh, K, M, (0.078, 0.0), 120.0, model="FN1")
    modes = normal_modes(sys_, N_MODES)
    lam, q = modes.eigenvalues, modes.q
    shapes = (sys_.T @ q).reshape(mesh.n_nodes, 3, N_MODES)
    n = N_MODES
    if derivatives:
        parts = element_parts(mesh, case.material)
        dh_k, dh_m = element_scale_dh(parts, groups)
        dK, dM = thickness_derivatives(mesh, parts, dh_k / theta[:, None, None],
                                       dh_m / theta[:, None, None])
        dKr = [reduce(sys_.T, a) for a in dK]
        dMr = [reduce(sys_.T, a) for a in dM]
        dlam, dq = mode_shape_derivatives(sys_.K, sys_.M, lam, q, dKr, dMr)
        shapes = extended_shapes(shapes, [(sys_.T @ d).reshape(mesh.n_nodes, 3, n) for d in dq])
    model = ModalModel(np.zeros(shapes.shape[2]), None, None, None, 0, 0.0, mesh.nodes, shapes,
                       mesh.elements, "")
    bm = fe_spline(model, boxes)
    Q = np.array([modal_forces(bm, op.pressures(bm.normalwash(k, 0.078)), boxes.area)
                  for k, op in zip(ks, ops)])
    gaf = TabulatedGaf(ks, Q[:, :n, :n], 0.078, 0.6)
    Mm, Km, Cm = np.eye(n), np.diag(lam), np.zeros((n, n))
    modal = modal_arrays(M=Mm, K=Km, C=Cm)
    res = pk_flutter(modal, gaf, RHO, np.linspace(100.0, 460.0, 37))
    f = min((i for i in pk_instabilities(res, modal, gaf) if i.kind == "flutter"),
            key=lambda i: i.speed)
    col = list(res.modes).index(f.mode)
    iu = int(np.searchsorted(res.velocities, f.speed)) - 1
    U, p, _ = flutter_point(Mm, Km, Cm, gaf, RHO, f.speed, res.p[iu, col], res.vectors[iu, col])
    if not derivatives:
        return U, None
    nv = theta.size
    s = flutter_speed_sensitivity(Mm, Km, Cm, gaf, RHO, U, p, np.zeros((nv, n, n)),
                                  np.array([np.diag(d) for d in dlam]), np.zeros((nv, n, n)),
                                  gaf_derivative(Q, n))
    return U, s.d_speed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n-var", type=int, default=50)
    args = ap.parse_args()
    ctx = setup(args.n_var)
    theta = np.ones(args.n_var)
    chain(ctx, theta, False)                                # warm-up
    t = time.process_time()
    U0, _ = chain(ctx, theta, False)
    t_plain = time.process_time() - t
    t = time.process_time()
    _, grad = chain(ctx, theta, True)
    t_analytic = time.process_time() - t
    h = 1e-4
    t = time.process_time()
    fd = np.array([(chain(ctx, theta + h * e, False)[0] - chain(ctx, theta - h * e, False)[0])
                   / (2 * h) for e in np.eye(args.n_var)])
    t_fd = time.process_time() - t
    err = np.max(np.abs(grad - fd)) / np.max(np.abs(fd))
    print(f"{args.n_var} thickness variables, U_f {U0:.2f} m/s: one evaluation {t_plain:.2f} s; "
          f"with the analytic gradient {t_analytic:.2f} s; central differences {t_fd:.1f} s "
          f"({2 * args.n_var} evaluations); max |analytic - FD| / max |FD| = {err:.2e}")


if __name__ == "__main__":
    main()
