"""Factor-and-solve AIC objects and the streamed k sweep (asekit.aero.dlm, issue 12).

The references here are asekit's own explicit paths, which tests/aero/test_dlm.py ties to
Theodorsen and PanelAero: the factored AIC must equal aic_matrix(...) @ w (= solve(D, I) @ w)
to rounding, and the streamed sweep must give the very matrices of normalwash_matrices.
"""

import tracemalloc

import numpy as np
import pytest
from test_dlm import _nonplanar, _planar  # the same planar and non-planar meshes

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import (
    AicFactor,
    aic_matrix,
    factor_aic,
    factor_normalwash_matrix,
    iter_normalwash_matrices,
    map_normalwash_matrices,
    normalwash_matrices,
    normalwash_matrix,
    pressure_jump,
)
from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.methods import pressure_matrices, pressures
from asekit.aero.spline import analytic_modes


def _modal_wash(mesh, k, b, n_modes=6):
    """w/U of plunge, pitch and four bending/torsion-like shapes (h and dh/dx analytic)."""
    x, y = mesh.control_point[:, 0], mesh.control_point[:, 1]
    h = np.column_stack([np.ones_like(x), -(x - 0.3), y ** 2, (x - 0.3) * y, y ** 3,
                         np.sin(3 * y)])[:, :n_modes]
    dhdx = np.column_stack([0 * x, -np.ones_like(x), 0 * x, y, 0 * x, 0 * x])[:, :n_modes]
    return dhdx + 1j * k * h / b


@pytest.mark.parametrize("geom,mach,k,sym", [("planar", 0.5, 0.3, False),
                                             ("planar", 0.0, 2.0, True),
                                             ("nonplanar", 0.8, 0.7, False),
                                             ("nonplanar", 0.3, 0.001, True)])
def test_factor_and_solve_equals_explicit_aic(geom, mach, k, sym):
    m = _planar() if geom == "planar" else _nonplanar()
    b = 0.5
    fac = factor_aic(m, mach, k, b, symmetric=sym)
    aic = aic_matrix(m, mach, k, b, symmetric=sym)
    w = _modal_wash(m, k, b)
    ref = aic @ w
    for got, want in ((fac.pressures(w), ref), (fac.pressures(w[:, 1]), ref[:, 1]),
                      (fac.pressures(w.real), aic @ w.real)):
        assert got.shape == want.shape
        # both are backward-stable solves of the same D; cond(D) ~ 1e2 here
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    assert isinstance(fac, AicFactor) and fac.n == m.n
    assert (fac.mach, fac.k, fac.b_ref, fac.symmetric) == (mach, k, b, sym)
    # pressure_jump goes through the same factor
    assert np.array_equal(pressure_jump(m, mach, k, b, w, symmetric=sym), fac.pressures(w))


def test_factor_of_any_memory_order_and_no_side_effect():
    m = _nonplanar()
    d = normalwash_matrix(m, 0.6, 0.5, 0.5)
    keep = d.copy()
    w = _modal_wash(m, 0.5, 0.5)
    ref = np.linalg.solve(d, w)
    for dd in (d, np.asfortranarray(d), d[::1, ::1].copy(order="K")):
        fac = factor_normalwash_matrix(dd)
        assert np.abs(fac.pressures(w) - ref).max() <= 1e-12 * np.abs(ref).max()
    assert np.array_equal(d, keep)                          # overwrite=False: d untouched
    fac = factor_normalwash_matrix(d, overwrite=True)       # in place: the factors live in d
    assert fac.transposed and np.shares_memory(fac.lu, d)
    assert np.abs(fac.pressures(w) - ref).max() <= 1e-12 * np.abs(ref).max()
    with pytest.raises(ValueError):                         # frozen factors
        fac.lu[0, 0] = 1.0


def test_factor_bad_input_names_the_argument():
    m = _planar()
    fac = factor_aic(m, 0.5, 0.3, 0.5)
    with pytest.raises(ValueError, match="normalwash"):
        fac.pressures(np.ones(m.n + 1))
    with pytest.raises(ValueError, match="normalwash"):
        fac.pressures(np.full(m.n, np.nan))
    with pytest.raises(ValueError, match="normalwash"):
        fac.pressures(np.ones((m.n, 2, 2)))
    with pytest.raises(ValueError, match="normalwash"):
        fac.pressures(np.array(["a"] * m.n))
    with pytest.raises(ValueError, match="d must"):
        factor_normalwash_matrix(np.ones((3, 4)))
    with pytest.raises(ValueError, match="d must be finite"):
        factor_normalwash_matrix(np.full((3, 3), np.inf))
    with pytest.raises(np.linalg.LinAlgError, match="singular"):
        factor_normalwash_matrix(np.ones((3, 3)))
    for kw, name in ((dict(k=-1.0), "k"), (dict(mach=1.2), "mach"), (dict(b_ref=0.0), "b_ref"),
                     (dict(method="cubic"), "method")):
        args = dict(mach=0.5, k=0.3, b_ref=0.5)
        args.update(kw)
        with pytest.raises(ValueError, match=name):
            factor_aic(m, **args)
    with pytest.raises(TypeError, match="mesh"):
        factor_aic("boxes", 0.5, 0.3, 0.5)


@pytest.mark.parametrize("geom,sym", [("planar", True), ("nonplanar", False)])
@pytest.mark.parametrize("max_bytes", [1, 3 * 16 * 80 ** 2, None])
def test_stream_gives_the_sweep_matrices(geom, sym, max_bytes):
    # batches of 1 and of 3 matrices (the geometry recomputed per batch) and one batch of all
    m = _planar() if geom == "planar" else _nonplanar()
    ks = [0.0, 0.001, 0.4, 1.1, 2.5]
    full = normalwash_matrices(m, 0.7, ks, 0.3, symmetric=sym)
    got = list(iter_normalwash_matrices(m, 0.7, ks, 0.3, symmetric=sym, max_bytes=max_bytes))
    assert [kk for kk, _ in got] == ks
    for (_, d), ref in zip(got, full):
        assert np.array_equal(d, ref)


def test_stream_bad_input_is_refused_before_any_work():
    m = _planar()
    for bad in (0, -5, 1.5, True, "1GB"):
        with pytest.raises(ValueError, match="max_bytes"):
            iter_normalwash_matrices(m, 0.5, [0.1], 0.5, max_bytes=bad)
    with pytest.raises(ValueError, match="k must"):
        iter_normalwash_matrices(m, 0.5, [0.1, -0.1], 0.5)
    with pytest.raises(TypeError, match="fn"):
        map_normalwash_matrices(m, 0.5, [0.1], 0.5, fn=None)


def test_streamed_sweep_memory_is_one_batch():
    # 12 matrices of 600 boxes (one D: 5.5 MiB): all at once the traced peak is 76 MiB; streamed
    # one at a time it must stay below 3.5 D (measured 16 MiB: one D, D0 = 0.5 D and the kernel
    # chunk; a stream that kept the previous D alive while computing the next measured 21.5)
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.5, 3, 0.0), 0.6, 12, 50))
    ks = np.linspace(0.05, 1.5, 12)
    one = 16 * m.n ** 2
    w = _modal_wash(m, 0.1, 0.5)
    # (numpy kernel: its chunk is the smaller one; the compiled kernel's chunks are larger)
    tracemalloc.start()
    q = map_normalwash_matrices(m, 0.6, ks, 0.5,
                                lambda i, kk, d: factor_normalwash_matrix(d, True).pressures(w),
                                max_bytes=one, kernel="numpy")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert len(q) == ks.size
    assert peak < 3.5 * one, (peak / 2**20, one / 2**20)


def test_gaf_builder_streams_to_the_same_matrices():
    m = _planar()
    modes = analytic_modes(m, [lambda x, y: (np.ones_like(x), np.zeros_like(x)),
                               lambda x, y: (-(x - 0.3), -np.ones_like(x)),
                               lambda x, y: (y ** 2, np.zeros_like(x))])
    ks = [0.001, 0.3, 1.0, 2.0]
    q_all = gaf_from_box_modes(modes, m, 0.6, ks, 0.5)
    q_one = gaf_from_box_modes(modes, m, 0.6, ks, 0.5, max_bytes=1)
    assert np.array_equal(q_all, q_one)
    # against the explicit path: Q = H_lp^T diag(A) D^-1 w per k (Eqs. 2.10-2.11)
    d = normalwash_matrices(m, 0.6, ks, 0.5)
    for ik, kk in enumerate(ks):
        cp = np.linalg.solve(d[ik], modes.normalwash(kk, 0.5))
        ref = modes.h_lp.T @ (cp * m.area[:, None])
        assert np.abs(q_all[ik] - ref).max() <= 1e-12 * np.abs(ref).max()


def test_method_pressures_dlm_equals_pressure_matrices():
    m = _nonplanar()
    ks = [0.01, 0.8]
    w = lambda kk: _modal_wash(m, kk, 0.5)  # noqa: E731
    got = pressures(m, 0.5, ks, 0.5, w, method="dlm")
    a = pressure_matrices(m, 0.5, ks, 0.5, method="dlm")
    for ik, kk in enumerate(ks):
        ref = a[ik] @ w(kk)
        assert np.abs(got[ik] - ref).max() <= 1e-12 * np.abs(ref).max()
    with pytest.raises(ValueError, match="normalwash"):
        pressures(m, 0.5, ks, 0.5, lambda kk: np.ones(3), method="dlm")


def test_control_point_on_a_side_edge_line_is_refused_not_nan():
    # the wing's control points (y = 1) lie on the spanwise line of the tail boxes' tip edges
    # (y = 1): the closed-form kernel integrals are infinite there ([R71] Eq. 31, F = 2e /
    # (ybar^2 - e^2)) and D would hold NaN (PanelAero 2025.8 gives NaN on these boxes as well)
    m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, 2, 1, "wing"),
                       TrapezoidSurface((3, 0, 0), 1.0, (3, 1, 0), 1.0, 2, 1, "tail")])
    with pytest.raises(ValueError, match="mesh: the DLM normalwash matrix is not finite"):
        normalwash_matrix(m, 0.5, 0.5, 0.5)
    with pytest.raises(ValueError, match="mesh"):
        list(iter_normalwash_matrices(m, 0.5, [0.1, 0.5], 0.5))
    # shifting the tail tip off the line gives a finite matrix
    m2 = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, 2, 1, "wing"),
                        TrapezoidSurface((3, 0, 0), 1.0, (3, 0.9, 0), 1.0, 2, 1, "tail")])
    assert np.isfinite(normalwash_matrix(m2, 0.5, 0.5, 0.5)).all()
