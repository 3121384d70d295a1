"""Gust aerodynamics (asekit.aero.gust): the Sears function in the 2-D limit of the DLM, the
piston-theory gust column in closed form, the steady limit, and input checks."""

import numpy as np
import pytest
from scipy.special import hankel2, j0, j1

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import pressure_jump
from asekit.aero.gust import GustGafTable, gust_columns, gust_normalwash, gust_table
from asekit.aero.spline import analytic_modes


def theodorsen(k):
    """Theodorsen's C(k) = H1(k) / (H1(k) + i H0(k)) (Hankel functions of the 2nd kind)."""
    return hankel2(1, k) / (hankel2(1, k) + 1j * hankel2(0, k))


def sears(k):
    """Sears's function, gust referred to mid-chord (Sears 1941; Bisplinghoff, Ashley & Halfman
    1955, Eq. 5-338): S(k) = [J0(k) - i J1(k)] C(k) + i J1(k), time dependence e^{i omega t}."""
    return (j0(k) - 1j * j1(k)) * theodorsen(k) + 1j * j1(k)


def _strip_wing(n_chord=8):
    # chord 1 m (b = 0.5 m), semi-span 400 chords with a wall at the root (the mesh of
    # tests/aero/test_dlm.py's Theodorsen limit): the root strip is two-dimensional
    return mesh_surfaces([
        TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, n_chord, 16, "inner"),
        TrapezoidSurface((0, 2, 0), 1.0, (0, 20, 0), 1.0, n_chord, 18, "mid"),
        TrapezoidSurface((0, 20, 0), 1.0, (0, 400, 0), 1.0, n_chord, 19, "outer")])


#: The 2-D strip's reduced frequencies: the Sears points and the Kussner fit's grid.
STRIP_K = np.array([0.0, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0])


@pytest.fixture(scope="module")
def strip_lift():
    """c_l per unit W/U of the root strip of the 2-D wing at STRIP_K, gust referred to the
    leading edge x0 = 0 (the DLM's gust column of the root strip's plunge row over its area)."""
    m = _strip_wing()
    strip = analytic_modes(m, [lambda x, y: (1.0 * (y < 2.0 / 16 + 1e-9) + 0 * x, 0 * x)])
    q = gust_columns(strip, m, 0.0, STRIP_K, 0.5, x0=0.0, method="dlm", symmetric=True)[:, 0]
    return q / m.area[m.strip == 0].sum()               # chord 1 m: lift / (q c W/U)


def test_two_dimensional_limit_is_sears(strip_lift):
    # The lift of a sinusoidal gust W exp(i omega (t - (x - x_mid)/U)) on a 2-D flat plate is
    # c_l = 2 pi (W/U) S(k) with the gust referred to mid-chord (Sears 1941; BAH 1955 Eq.
    # 5-336); referred to the leading edge (x0 = 0, half a chord = k rad earlier) it is
    # 2 pi S(k) exp(-i k). The DLM's root strip of a 400-chord wing with a wall (8 x 53 boxes).
    # Measured: complex error 0.2-1.4 % over k = 0.05-1 (1.4 % at k = 1).
    for k, got in zip(STRIP_K, strip_lift):
        if not 0.05 <= k <= 1.0:
            continue
        want = 2 * np.pi * sears(k) * np.exp(-1j * k)
        assert abs(got) == pytest.approx(abs(want), rel=0.03), (k, got, want)
        assert abs(np.angle(got / want)) < 0.03, (k, got, want)     # rad, 3 % of a radian
        assert abs(got / want - 1) < 0.03, (k, got, want)


def kussner_exact(s):
    """Kussner's function from Sears's: psi(s) = (2/pi) int_0^inf Re[S(k) e^{-ik}] / k sin(k s)
    dk (the step response of the causal transfer function S_LE(k) = S(k) e^{-ik}, gust front at
    the leading edge at s = 0; s = U t / b), by adaptive quadrature to k = 200 (the integrand
    falls as k^-1.5; truncation < 1e-3)."""
    from scipy.integrate import quad
    return np.array([2 / np.pi * quad(lambda k: (sears(k) * np.exp(-1j * k)).real / k
                                      * np.sin(k * si), 1e-9, 200, limit=2000)[0] for si in s])


def test_two_dimensional_limit_is_kussner(strip_lift):
    # The sharp-edged gust: the DLM's 2-D gust column (gust front at the leading edge), fitted
    # in Roger form with 4 lags (asekit.rfa.gust), gives the indicial lift A0 + sum A_n
    # exp(-beta_n s) / (2 pi), Kussner's function. References: (a) the exact Kussner function
    # computed above from Sears's function; (b) the classical approximation
    # psi(s) = 1 - 0.5 exp(-0.13 s) - 0.5 exp(-s) (Sears & Sparks 1941 / R. T. Jones, NACA
    # Rep. 681, 1940). Jones's form is itself 4 % off the exact function at s = 1 and 3.3 % at
    # s = 20-30 (measured here), so it is held to 3 % on s in [2, 12] only, where it is within
    # 1.5 % of the exact function. Measured: |psi - exact| <= 0.012 on s in [0.5, 30]
    # (4 lags, fit error 2.0 %).
    from asekit.rfa.gust import gust_fit
    fit = gust_fit(STRIP_K, strip_lift, 0.5, n_lags=4, quasi_steady_terms=1)
    s = np.array([0.5, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0, 30.0])
    psi = fit.indicial(s)[:, 0] / (2 * np.pi)
    assert np.all(np.abs(psi - kussner_exact(s)) < 0.03), psi - kussner_exact(s)
    jones = 1 - 0.5 * np.exp(-0.13 * s) - 0.5 * np.exp(-s)
    near = (s >= 2) & (s <= 12)
    assert np.all(np.abs(psi - jones)[near] < 0.03), psi - jones
    assert fit.fit_error < 0.05


def test_gust_reference_point_shifts_phase_only():
    # the same gust referred to the leading edge (x0 = 0) arrives half a chord (k rad) earlier
    # at mid-chord: Q(x0 = 0) = exp(-i k) Q(x0 = b) exactly (a pure delay, linear aerodynamics)
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 3, 0), 1.0, 4, 6))
    plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    k = 0.7
    q_le = gust_columns(plunge, m, 0.3, [k], 0.5, x0=0.0, method="dlm")[0, 0]
    q_mid = gust_columns(plunge, m, 0.3, [k], 0.5, x0=0.5, method="dlm")[0, 0]
    assert q_le == pytest.approx(np.exp(-1j * k) * q_mid, rel=1e-12)


def test_steady_gust_is_an_incidence():
    # at k = 0 a gust angle W/U is a uniform incidence alpha = W/U (a nose-up plate has
    # w/U = -alpha in the DLM convention): same pressures, same lift
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.2, 2, 0), 0.6, 4, 6))
    plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    q = gust_columns(plunge, m, 0.5, [0.0], 0.5, method="dlm")[0, 0]
    cp = pressure_jump(m, 0.5, 0.0, 0.5, -np.ones(m.n))
    assert q.real == pytest.approx(np.sum(cp * m.area), rel=1e-12)
    assert q.real > 0 and abs(q.imag) < 1e-12 * q.real


def test_piston_gust_column_closed_form():
    # first-order piston theory (Lighthill 1953; Ashley & Zartarian 1956): DeltaCp = (4/M) W/U
    # exp(-i k (x - x0)/b) locally, so on a rectangular plate of chord c, span s (plunge row)
    # Q_hg = (4/M) s int_0^c exp(-i k (x - x0)/b) dx = (4/M) s b/(i k) (1 - exp(-i k c/b))
    # exp(i k x0 / b). 40 chordwise boxes resolve the delay to < 0.5 % at k <= 1.
    c, s, b, mach = 1.0, 0.5, 0.5, 3.0
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), c, (0, s, 0), c, 40, 2))
    plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    ks = np.array([0.1, 0.5, 1.0])
    q = gust_columns(plunge, m, mach, ks, b, x0=0.25, method="piston")[:, 0]
    want = 4 / mach * s * b / (1j * ks) * (1 - np.exp(-1j * ks * c / b)) * np.exp(1j * ks * 0.25 / b)
    assert np.all(np.abs(q / want - 1) < 5e-3), q / want


def test_table_and_errors():
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, 3, 4))
    plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    t = gust_table(plunge, m, [0.2, 0.4], [0.0, 0.3], 0.5, method="dlm")
    assert t.Qg.shape == (2, 2, 1)
    np.testing.assert_allclose(t.at(0.4), gust_columns(plunge, m, 0.4, [0.0, 0.3], 0.5,
                                                       method="dlm"), rtol=1e-12)
    with pytest.raises(ValueError, match="mach 0.3 is not in the gust table"):
        t.at(0.3)
    with pytest.raises(ValueError, match="x0 must be a finite"):
        gust_normalwash(np.zeros(2), 0.1, 0.5, x0=float("nan"))
    with pytest.raises(ValueError, match="b_ref"):
        gust_normalwash(np.zeros(2), 0.1, 0.0)
    with pytest.raises(ValueError, match="k must be"):
        gust_normalwash(np.zeros(2), -0.1, 0.5)
    with pytest.raises(ValueError, match="Qg must be"):
        GustGafTable([0.5], [0.0, 1.0], np.ones((1, 3, 1)), 0.5)


def test_one_solve_tables_match_the_separate_ones():
    # gust_aero_tables: the modal GAFs equal gaf_from_box_modes', the gust column
    # gust_columns', and a load row with the plunge mode's weights equals the plunge row
    from asekit.aero.gaf import gaf_from_box_modes
    from asekit.aero.gust import gust_aero_tables
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.3, 2, 0), 0.6, 4, 5))
    modes = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x),
                               lambda x, y: (-(x - 0.3), -1 + 0 * x)])
    ks = [0.0, 0.4]
    weights = np.column_stack([np.ones(m.n), m.load_point[:, 1]])
    t = gust_aero_tables(modes, m, 0.5, ks, 0.5, weights, x0=0.1, method="dlm")
    scale = np.abs(t.Q).max()
    assert np.abs(t.Q - gaf_from_box_modes(modes, m, 0.5, ks, 0.5)).max() < 1e-12 * scale
    assert np.abs(t.Qg - gust_columns(modes, m, 0.5, ks, 0.5, x0=0.1, method="dlm")).max() \
        < 1e-12 * scale
    assert np.abs(t.QL[:, 0] - t.Q[:, 0]).max() < 1e-12 * scale
    with pytest.raises(ValueError, match="load_weights must be"):
        gust_aero_tables(modes, m, 0.5, ks, 0.5, np.ones((3, 1)))


def test_mach_box_gust_column_through_the_same_interface():
    # the supersonic Mach box takes the gust normalwash through asekit.aero.methods.pressures
    # like the DLM: at k = 0 the gust is the incidence W/U (same lift as w/U = -1), and with k
    # the gust's delay lowers the plunge row's magnitude and lags it (a wave travelling over
    # the chord partly averages out, referred to the leading edge it arrives late)
    from asekit.aero.methods import pressures
    m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 1.0, 0), 1.0, 6, 4))
    plunge = analytic_modes(m, [lambda x, y: (1 + 0 * x, 0 * x)])
    q = gust_columns(plunge, m, 2.0, [0.0, 0.5], 0.5, method="supersonic")[:, 0]
    cp = pressures(m, 2.0, [0.0], 0.5, lambda kk: -np.ones((m.n, 1)), "supersonic")[0, :, 0]
    assert q[0].real == pytest.approx(np.sum(cp * m.area), rel=1e-10)
    assert q[0].real > 0 and abs(q[1]) < abs(q[0]) and np.angle(q[1]) < 0
