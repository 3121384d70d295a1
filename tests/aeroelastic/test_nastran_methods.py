"""MSC Nastran's flutter methods (asekit.aeroelastic.nastran): K, KE, PK and PKNL.

References: MSC Nastran Aeroelastic Analysis User's Guide (Rodden and Johnson 1994), Eq. 2-120
(K method) and Eq. 2-124 (PK method); its Example HA145B (BAH wing, PK, Mach 0, sea level):
flutter of the second mode at about 12,672 in/s near 3.1 Hz (shared/benchmarks/bah_ha145b/
README.md, the same numbers as tests/aeroelastic/test_flutter.py). The one-degree-of-freedom
cases below are solved by hand (docs/nastran-flutter.md derives them)."""

import numpy as np
import pytest

from asekit.aero.gaf import TabulatedGaf
from asekit.aeroelastic import nastran as N
from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
from asekit.aeroelastic.methods import FLUTTER_METHODS
from asekit.aeroelastic.statespace import modal_arrays
from asekit.io.op4 import load_ha145b

HA145B_FLUTTER_SPEED = 12672.0      # in/s, MSC Example HA145B (see the module docstring)
HA145B_FLUTTER_FREQ = 3.1           # Hz


@pytest.fixture(scope="module")
def ha145b():
    c = load_ha145b()
    m = modal_arrays(M=c.M, K=c.K, n_rigid=0)
    gaf = TabulatedGaf(c.k, c.Q, c.b_ref, mach=0.0)
    return c, m, gaf


@pytest.fixture(scope="module")
def ha145b_pk(ha145b):
    """Nastran's PK on HA145B over the example's 4800-25200 in/s (69 velocities)."""
    c, m, gaf = ha145b
    return N.pk_method(m, gaf, c.rho, np.linspace(4800.0, 25200.0, 69))


def _flutter(found, mode=None):
    hits = [c for c in found if c.kind == "flutter" and not c.unstable_at_first_point
            and (mode is None or c.mode == mode)]
    return min(hits, key=lambda c: c.speed)


def test_ha145b_pk_against_nastran(ha145b_pk):
    """Nastran's PK on Nastran's own matrices: the published flutter point within 1 % in speed
    (the V grid is 300 in/s: the linear-in-g crossing is read as Nastran's user reads it)."""
    fl = _flutter(N.crossings(ha145b_pk))
    assert fl.mode == 1                                  # the second mode (0-based 1)
    assert fl.speed == pytest.approx(HA145B_FLUTTER_SPEED, rel=0.01)
    assert fl.frequency_hz == pytest.approx(HA145B_FLUTTER_FREQ, rel=0.02)
    assert not fl.unstable_at_first_point


def test_ha145b_k_ke_pk_agree_at_zero_damping(ha145b, ha145b_pk):
    """At g = 0 the K method's harmonic motion is the PK root's: the crossings coincide (to the
    interpolation of the tabulated curves, 0.3 %), and K and KE give the same eigenvalues."""
    c, m, gaf = ha145b
    pk = _flutter(N.crossings(ha145b_pk))
    ks = np.geomspace(0.02, 1.0, 200)
    k = N.k_method(m, gaf, c.rho, ks)
    ke = N.k_method(m, gaf, c.rho, ks, vectors=False)
    assert ke.vectors is None and k.vectors.shape == (200, 10, 10)
    np.testing.assert_allclose(np.sort_complex(ke.eigenvalue), np.sort_complex(k.eigenvalue),
                               rtol=1e-9)
    for res in (k, ke):
        fk = _flutter(N.crossings(res), mode=1)
        assert fk.speed == pytest.approx(pk.speed, rel=3e-3)
        assert fk.frequency_hz == pytest.approx(pk.frequency_hz, rel=3e-3)


def test_ha145b_nastran_pk_is_asekit_pk_equation(ha145b):
    """asekit's p-k solves the same equation (thesis Eq. 3.12 = MSC Eq. 2-124): the flutter
    mode's damping and frequency agree at every velocity to the k tolerances (EPS 1e-3 vs
    1e-7), and the crossing speeds within the linear interpolation of a 1200 in/s step."""
    c, m, gaf = ha145b
    U = np.linspace(4800.0, 25200.0, 18)
    ase = pk_flutter(m, gaf, c.rho, U, max_iter=200)
    tight = N.pk_method(m, gaf, c.rho, U, eps=1e-9)
    np.testing.assert_allclose(tight.damping_g[:, 1], ase.damping_g[:, 1], atol=2e-5)
    np.testing.assert_allclose(tight.frequency_hz[:, 1], ase.frequency_hz[:, 1], rtol=2e-5)
    # Nastran's default EPS = 1e-3 on k (absolute below k = 1: 2 % of k = 0.05 at 21,000
    # in/s) leaves up to 0.003 in g where the root is far unstable; 2e-4 where it is stable
    nas = N.pk_method(m, gaf, c.rho, U)
    stable = ase.damping_g[:, 1] < 0
    np.testing.assert_allclose(nas.damping_g[stable, 1], ase.damping_g[stable, 1], atol=2e-4)
    np.testing.assert_allclose(nas.damping_g[:, 1], ase.damping_g[:, 1], atol=4e-3)
    fa = [i for i in pk_instabilities(ase, m, gaf) if i.kind == "flutter"][0]
    assert _flutter(N.crossings(nas)).speed == pytest.approx(fa.speed, rel=5e-3)


def _one_dof(a=-2.0, c=-3.0, m=1.0, K=400.0, B=0.0, b=1.0):
    """One mode with Q(k) = a + i c k (quasi-steady: Q^R = a, Q^I / k = c, exact under the
    linear interpolation of the table)."""
    k = np.array([0.0, 1.0, 2.0])
    Q = (a + 1j * c * k)[:, None, None]
    return modal_arrays(M=[[m]], K=[[K]], C=[[B]]), TabulatedGaf(k, Q, b)


@pytest.mark.parametrize("V", [2.0, 6.0, 12.0])
def test_one_dof_pk_and_k_damping_by_hand(V):
    """One DOF, Q = a + i c k. PK (Eq. 2-124): m p^2 - rho b V c p / 2 + (K - q a) = 0, so
    Re p = rho b V c / (4m), (Im p)^2 = (K - q a)/m - (Re p)^2, g_PK = 2 Re p / Im p. K method
    (Eq. 2-120): omega^2 = (K - q a)/m, g_K = q c k / K at V = omega b / k. Their ratio tends
    to omega^2 m / K = 1 - q a / K: K's g multiplies the structural stiffness only."""
    a, c, mm, K, b, rho = -2.0, -3.0, 1.0, 400.0, 1.0, 1.0
    modal, gaf = _one_dof(a, c, mm, K, 0.0, b)
    q = 0.5 * rho * V ** 2
    re = rho * b * V * c / (4 * mm)
    im = np.sqrt((K - q * a) / mm - re ** 2)
    pk = N.pk_method(modal, gaf, rho, [V], eps=1e-10)
    assert pk.damping_g[0, 0] == pytest.approx(2 * re / im, rel=1e-8)
    assert pk.frequency_hz[0, 0] == pytest.approx(im / (2 * np.pi), rel=1e-8)
    # the K method at the k of its own harmonic solution at this V
    w = np.sqrt((K - q * a) / mm)
    kres = N.k_method(modal, gaf, rho, [w * b / V])
    assert kres.velocity[0, 0] == pytest.approx(V, rel=1e-10)
    g_k = q * c * (w * b / V) / K
    assert kres.damping_g[0, 0] == pytest.approx(g_k, rel=1e-10)
    # the two definitions differ by the stiffness ratio (first order in the damping)
    ratio = g_k / (2 * re / w)
    assert ratio == pytest.approx(mm * w ** 2 / K, rel=1e-10)


def test_k_method_structural_damping_moves_crossing_to_zero():
    """Viscous modal damping enters K as g_j = B_jj omega_j / K_jj (KDAMP = -1 form): with no
    aerodynamic damping (c = 0) the required g is -g_j at every k."""
    modal, gaf = _one_dof(a=0.0, c=0.0, B=0.4)                # omega 20 rad/s: g_s = 0.02
    res = N.k_method(modal, gaf, 1.0, [0.3, 1.0])
    np.testing.assert_allclose(res.damping_g[:, 0], -0.02, rtol=1e-12)


def test_pknl_matched_points_and_crossing():
    """PKNL: point i is (rho_i, M_i, V_i), each the PK root at that point alone; the crossing
    interpolated linearly in g between the bracketing points; a root unstable at point 1 is
    flagged. One DOF with aerodynamic anti-damping c > 0 and viscous damping B: g changes sign
    where rho b V c / 2 = B."""
    modal, gaf = _one_dof(a=0.0, c=2.0, B=1.0)
    dens, machs, vel = [0.2, 0.5, 1.0, 1.5], [0.3, 0.4, 0.5, 0.6], [1.0, 1.5, 2.0, 2.5]
    gafs = {}
    res = N.pknl_method(modal, lambda mach: gafs.setdefault(mach, gaf), dens, machs, vel)
    assert sorted(gafs) == machs                       # one Mach per point, no looping
    for i in range(4):
        one = N.pk_method(modal, gaf, dens[i], [vel[i]])
        assert res.damping_g[i, 0] == pytest.approx(one.damping_g[0, 0], rel=1e-9)
    g = res.damping_g[:, 0]
    assert g[1] < 0 < g[2]                            # rho V c / 2 = 1: between points 2, 3
    (x,) = N.crossings(res)
    t = -g[1] / (g[2] - g[1])
    assert x.speed == pytest.approx(1.5 + 0.5 * t) and x.index == 2
    assert x.density == pytest.approx(0.5 + 0.5 * t) and x.mach == pytest.approx(0.4 + 0.1 * t)
    assert not x.unstable_at_first_point
    (y,) = N.crossings(N.pknl_method(modal, lambda mach: gaf, dens[2:], machs[2:], vel[2:]))
    assert y.unstable_at_first_point and y.speed == 2.0


def test_bad_input_names_the_field():
    modal, gaf = _one_dof()
    with pytest.raises(ValueError, match="PKNL needs equal-length"):
        N.pknl_method(modal, lambda m: gaf, [1.0, 1.0], [0.3], [1.0, 2.0])
    with pytest.raises(ValueError, match="FLUTTER EPS"):
        N.pk_method(modal, gaf, 1.0, [1.0], eps=0.0)
    with pytest.raises(ValueError, match="FLUTTER IMETH"):
        N.pk_method(modal, gaf, 1.0, [1.0], interpolation="X")
    with pytest.raises(ValueError, match="RFREQ"):
        N.k_method(modal, gaf, 1.0, [0.0, 0.1])
    with pytest.raises(ValueError, match="VEL"):
        N.pk_method(modal, gaf, 1.0, [0.0])


def test_negative_velocities_ask_for_vectors():
    """A negative FLFACT velocity: solved at |V|, its eigenvectors printed in the summary."""
    modal, gaf = _one_dof()
    res = N.pk_method(modal, gaf, 1.0, [-1.0, 2.0, -3.0])
    assert res.print_vectors.tolist() == [True, False, True]
    assert res.velocity[:, 0].tolist() == [1.0, 2.0, 3.0]
    text = N.flutter_summary(res)
    assert "EIGENVECTORS" in text and text.count("mode 1: +1.0000E+00") == 2


def test_imeth_s_equals_l_on_linear_tables():
    """IMETH = S (asekit: a cubic spline in k) reproduces a table that is linear in k exactly,
    so it gives IMETH = L's roots."""
    modal, gaf = _one_dof()
    a = N.pk_method(modal, gaf, 1.0, [2.0, 6.0], interpolation="L")
    b = N.pk_method(modal, gaf, 1.0, [2.0, 6.0], interpolation="S")
    np.testing.assert_allclose(a.eigenvalue, b.eigenvalue, rtol=1e-10)


def test_summary_has_nvalue_blocks(ha145b):
    c, m, gaf = ha145b
    res = N.pk_method(m, gaf, c.rho, [6000.0, 12000.0])
    text = N.flutter_summary(res, nvalue=3, velocity_unit="in/s")
    assert text.count("FLUTTER SUMMARY") == 3 and "METHOD = PK" in text
    assert len(text.splitlines()) == 3 * 4 + 2        # 3 x (title, head, 2 rows), 2 gaps


@pytest.mark.parametrize("name", ["nastran_pk", "k", "ke"])
def test_registry_entries_find_ha145b_flutter(ha145b, name):
    """Each registered Nastran method through the registry's interface: the HA145B flutter
    point within 1 % of the published one (tracked roots on the requested velocities)."""
    c, m, gaf = ha145b
    U = np.linspace(4800.0, 25200.0, 69)
    roots, found = FLUTTER_METHODS[name].solve(m, gaf, None, c.rho, U)
    assert roots.p.shape == (69, 10)
    fl = [i for i in found if i.kind == "flutter" and not i.at_first_point][0]
    assert fl.speed == pytest.approx(HA145B_FLUTTER_SPEED, rel=0.01) and fl.mode == 1


def test_ha145b_k_damping_is_pk_damping_times_frequency_ratio_squared(ha145b):
    """docs/nastran-flutter.md: away from g = 0, g_K / g_PK = (omega / omega_s)^2 to first order
    in the damping (K's g multiplies the structural stiffness only). On HA145B's modes 2-4
    (|g| < 0.07) at 4800-9600 in/s the measured ratio matches it within 1 % (measured:
    0.848-0.990 against 0.849-0.988); the K curve read at each V by linear interpolation."""
    c, m, gaf = ha145b
    fs = np.sqrt(np.diag(c.K) / np.diag(c.M)) / (2 * np.pi)          # diagonal modal matrices
    U = np.array([4800.0, 7200.0, 9600.0])
    pk = N.pk_method(m, gaf, c.rho, U)
    k = N.k_method(m, gaf, c.rho, np.geomspace(0.02, 1.0, 400))
    for j in (1, 2, 3):
        order = np.argsort(k.velocity[:, j])
        g_k = np.interp(U, k.velocity[order, j], k.damping_g[order, j])
        ratio = g_k / pk.damping_g[:, j]
        np.testing.assert_allclose(ratio, (pk.frequency_hz[:, j] / fs[j]) ** 2, rtol=0.01)
        assert np.all(ratio < 0.999)               # the airstream lowers these frequencies
