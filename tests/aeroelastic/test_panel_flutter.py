"""Panel flutter with piston theory on the plate FE and box mesh (asekit.structure.supports,
asekit.aero.piston), the classic linear problem of a panel with supersonic flow on one side.

Nondimensional dynamic pressure lambda = 2 q a^3 / (M D) (piston theory; with the Ackeret
coefficient 2q/beta it is the usual 2 q a^3 / (beta D): the critical value is the same number),
a the panel length along the flow, D = E h^3 / (12 (1 - nu^2)); aerodynamic damping neglected
(the k -> 0 stiffness part only), so flutter is the coalescence of two frequencies.

References:
- 2-D simply supported panel: lambda_cr = 343 and 2-D clamped panel: lambda_cr = 636 (Dowell
  1970, AIAA J. 8(3), 385-399, "Panel flutter: a review of the aeroelastic stability of plates
  and shells"; Dowell, *Aeroelasticity of Plates and Shells*, Noordhoff 1975, Ch. 2);
- square simply supported panel (a/b = 1, flow along a side): lambda_cr = 512 (the issue's
  number; it belongs to the square panel, not to the 2-D one: the converged series below gives
  343.4 for a/b = 0 and 512.7 for a/b = 1);
- both simply supported values are recomputed here by an independent Galerkin series in
  sin(m pi x / a) sin(pi y / b) (Hedgepeth 1957, J. Aeronaut. Sci. 24(8), 563-573: the spanwise
  half-wave separates exactly under the local piston law), converged to 1e-4 with 30 terms.
"""

import math

import numpy as np
import pytest
import scipy.linalg as sla

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import fe_spline
from asekit.geometry import Material
from asekit.structure.assembly import assemble
from asekit.structure.mesh import rectangular_mesh
from asekit.structure.modes import ModalModel
from asekit.structure.supports import edge_nodes, edge_supports

E, NU, RHO, H = 70e9, 0.3, 2700.0, 0.002
D = E * H**3 / (12 * (1 - NU**2))


def _coalescence(kmat, qmat, q_hi):
    """Smallest q with a complex pair among the eigenvalues of K - q Q (unit modal mass)."""
    def complex_pair(q):
        ev = sla.eigvals(kmat - q * qmat)
        return np.max(np.abs(ev.imag) / np.abs(ev)) > 1e-9
    lo, hi = 0.0, q_hi
    assert not complex_pair(lo) and complex_pair(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if complex_pair(mid) else (mid, hi)
    return 0.5 * (lo + hi)


def galerkin_lambda_cr(aspect: float, n_terms: int = 30) -> float:
    """lambda_cr of a simply supported panel (all four edges) by a Galerkin series in
    sin(m pi x / a) sin(pi y / b): Omega = eig(diag(K_m) + 2 lambda B), K_m = ((m pi)^2 +
    (aspect pi)^2)^2, B_mn = 2 m n / (m^2 - n^2) for m + n odd (integrals of sin x cos x),
    a = 1, D = 1. ``aspect`` = a / b (0: the 2-D panel)."""
    m = np.arange(1, n_terms + 1)
    km = ((m * np.pi) ** 2 + (aspect * np.pi) ** 2) ** 2
    mm, nn = np.meshgrid(m, m, indexing="ij")
    with np.errstate(divide="ignore", invalid="ignore"):
        b = np.where((mm + nn) % 2 == 1, 2.0 * mm * nn / (mm**2 - nn**2), 0.0)
    return _coalescence(np.diag(km), -2.0 * b, 5000.0)


def fe_lambda_cr(a, b, nx, ny, edges, n_box_x, n_box_y, n_modes=12, mach=3.0):
    """lambda_cr from the plate FE + box mesh + one-sided first-order piston theory."""
    mesh = rectangular_mesh(a, b, H, nx, ny)
    k, m = assemble(mesh, Material(E, NU, RHO))
    sys = edge_supports(mesh, k, m, **edges)
    w2, vec = sla.eigh(sys.K.toarray(), sys.M.toarray())
    w2, vec = w2[:n_modes], vec[:, :n_modes]
    shapes = (sys.T @ vec).reshape(mesh.n_nodes, 3, n_modes)
    model = ModalModel(np.sqrt(w2) / (2 * np.pi), np.eye(n_modes), np.diag(w2),
                       np.zeros((n_modes, n_modes)), 0, 0.0, mesh.nodes, shapes, mesh.elements,
                       "panel")
    boxes = mesh_surfaces([TrapezoidSurface((0, 0), a, (0, b), a, n_box_x, n_box_y)])
    q2 = gaf_from_box_modes(fe_spline(model, boxes), boxes, mach, [0.0], a / 2, method="piston",
                            aero_options={"warn": False})[0]
    q_one_side = 0.5 * q2.real          # flow on the upper side only, still air below
    q_cr = _coalescence(np.diag(w2), q_one_side, 2000.0 * mach * D / a**3)
    return 2 * q_cr * a**3 / (mach * D)


def test_galerkin_reference_reproduces_literature():
    assert galerkin_lambda_cr(0.0) == pytest.approx(343, rel=0.005)
    assert galerkin_lambda_cr(1.0) == pytest.approx(512, rel=0.005)


def test_two_dimensional_simply_supported_panel():
    """Plate strip with sliding side edges (cylindrical bending), simply supported at the
    leading and trailing edges: lambda_cr within 3 % of 343 (and of the series)."""
    lam = fe_lambda_cr(0.5, 0.05, 32, 1, {"x0": "simply_supported", "x1": "simply_supported",
                                          "y0": "sliding", "y1": "sliding"}, 32, 1)
    assert lam == pytest.approx(343, rel=0.03)
    assert lam == pytest.approx(galerkin_lambda_cr(0.0), rel=0.03)


def test_two_dimensional_clamped_panel():
    lam = fe_lambda_cr(0.5, 0.05, 32, 1, {"x0": "clamped", "x1": "clamped", "y0": "sliding",
                                          "y1": "sliding"}, 32, 1)
    assert lam == pytest.approx(636, rel=0.03)


def test_square_simply_supported_panel():
    """All four edges simply supported, a/b = 1: within 3 % of 512 and of the series."""
    lam = fe_lambda_cr(0.3, 0.3, 20, 10, {}, 20, 10)
    assert lam == pytest.approx(512, rel=0.03)
    assert lam == pytest.approx(galerkin_lambda_cr(1.0), rel=0.03)


def test_edge_supports_frequencies_and_bad_input():
    """Simply supported square plate: first frequency (pi^2 / a^2) 2 sqrt(D / (rho h))
    (Leissa, *Vibration of Plates*, NASA SP-160, 1969, Eq. 4.25) within 1 %; a clamped plate is
    stiffer (Leissa Table 4.23: 35.99 / 19.74 for the fundamental); unknown edge type raises."""
    a = 0.3
    mesh = rectangular_mesh(a, a, H, 16, 16)
    k, m = assemble(mesh, Material(E, NU, RHO))
    f_ss = sla.eigh(edge_supports(mesh, k, m).K.toarray(),
                    edge_supports(mesh, k, m).M.toarray(), eigvals_only=True)[0]
    exact = (2 * np.pi**2 / a**2) ** 2 * D / (RHO * H)
    assert f_ss == pytest.approx(exact, rel=0.02)
    cl = edge_supports(mesh, k, m, "clamped", "clamped", "clamped", "clamped")
    f_cl = sla.eigh(cl.K.toarray(), cl.M.toarray(), eigvals_only=True)[0]
    assert math.sqrt(f_cl / f_ss) == pytest.approx(35.99 / 19.74, rel=0.02)
    assert edge_nodes(mesh, "x0").size == 17
    with pytest.raises(ValueError, match="x0 must be one of"):
        edge_supports(mesh, k, m, x0="pinned")
    with pytest.raises(ValueError, match="edge must be one of"):
        edge_nodes(mesh, "z0")
