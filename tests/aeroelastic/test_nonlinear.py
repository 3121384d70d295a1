"""Tests of asekit.aeroelastic.nonlinear on a small model with a known flutter band.

The model: two oscillators, coordinate 1 a 5 Hz mode, coordinate 2 held only by the
connection spring (stiffness k = (2 pi 8 Hz)^2 per unit inertia), coupled by an antisymmetric
(circulatory, "aerodynamic") stiffness q * 150. With a connection stiffness kappa k the
frequencies coalesce and flutter for kappa in roughly (0.27, 0.51); below and above that band
the system is damped. So freeplay gives two LCOs per q: an unstable one at the lower edge and a
stable one at the upper edge, and none for q small enough that no stiffness flutters.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm

from asekit.aeroelastic.nonlinear import (
    ConnectedSystem,
    Connection,
    deadzone_gain,
    growth_rate,
    harmonic_balance,
    lco_curve,
    simulate,
    steady_oscillation,
)

K_CONN = (2 * math.pi * 8.0) ** 2


def toy(q=1.0):
    w1 = 2 * math.pi * 5.0
    K0 = np.array([[w1 ** 2, q * 150.0], [-q * 150.0, 0.0]])
    C = np.diag([2 * 0.02 * w1, 2 * 0.02 * 2 * math.pi * 5.0])
    A0 = np.zeros((4, 4))
    A0[:2, 2:] = np.eye(2)
    A0[2:, :2] = -K0
    A0[2:, 2:] = -C
    b = np.array([0.0, 0.0, 0.0, -1.0])        # the connection moment acts on coordinate 2
    c = np.array([0.0, 1.0, 0.0, 0.0])         # d = coordinate 2
    return ConnectedSystem(A0, b, c, velocity=q,
                           outputs={"x1": (np.array([1.0, 0, 0, 0]), np.zeros(0))})


# --------------------------------------------------------------------------------------------
# describing function
# --------------------------------------------------------------------------------------------
def first_harmonic(conn, a):
    """N(A) = (1 / (pi A)) int_0^{2 pi} f(A sin t) sin t dt, by quadrature (definition)."""
    t0 = math.asin(min(conn.freeplay / a, 1.0))
    kinks = [t0, math.pi - t0, math.pi + t0, 2 * math.pi - t0]      # the band edges
    val, _ = quad(lambda t: conn.moment(a * math.sin(t)) * math.sin(t), 0, 2 * math.pi,
                  points=kinks, limit=400, epsabs=1e-14, epsrel=1e-12)
    return val / (math.pi * a)


@pytest.mark.parametrize("k1", [0.0, 30.0])
@pytest.mark.parametrize("ratio", [1.01, 1.5, 3.0, 20.0])
def test_describing_function_is_the_first_harmonic(k1, ratio):
    conn = Connection(stiffness=120.0, freeplay=0.002, inner_stiffness=k1)
    a = ratio * conn.freeplay
    assert conn.describing_function(a) == pytest.approx(first_harmonic(conn, a), rel=1e-8)


def test_describing_function_limits_and_inverse():
    conn = Connection(stiffness=120.0, freeplay=0.002, inner_stiffness=10.0)
    # inside the band the stiffness is k1; far outside it tends to k as
    # k - (k - k1) 4 delta / (pi A)
    assert conn.describing_function(0.001) == pytest.approx(10.0)
    a = 1e4 * conn.freeplay
    assert conn.describing_function(a) == pytest.approx(120 - 110 * 4 / (math.pi * 1e4), rel=1e-6)
    assert deadzone_gain(0.0) == 1.0 and deadzone_gain(1.0) == pytest.approx(0.0, abs=1e-15)
    for n in (10.0, 50.0, 119.0):
        assert conn.describing_function(conn.amplitude_for(n)) == pytest.approx(n, rel=1e-10)


def test_region_laws_are_the_moment_and_continuous():
    conn = Connection(stiffness=100.0, freeplay=0.01, inner_stiffness=20.0, preload=0.004)
    d = np.linspace(-0.05, 0.05, 2001)
    f = conn.moment(d)
    for r in (-1, 0, 1):
        sel = np.array([conn.region_of(x) == r for x in d])
        kr, f0 = conn.region_law(r)
        np.testing.assert_allclose(f[sel], kr * d[sel] + f0, atol=1e-14)
    lo, hi = conn.breakpoints
    for e in (lo, hi):
        assert conn.moment(e - 1e-12) == pytest.approx(conn.moment(e + 1e-12), abs=1e-9)


# --------------------------------------------------------------------------------------------
# harmonic balance against time domain
# --------------------------------------------------------------------------------------------
def test_df_lco_matches_time_domain_on_the_stable_branch():
    """The issue's criterion: amplitude within 5 %, frequency within 2 %."""
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    hb = harmonic_balance(sysm, conn)
    st = hb.largest_stable()
    assert st is not None and len(hb.lcos) == 2 and not hb.lcos[0].stable
    x0 = np.zeros(4)
    x0[1] = 3 * st.amplitude
    sim = simulate(sysm, conn, x0, 20.0, n_out=40001)
    td = steady_oscillation(sim.t, sim.d)
    assert td.settled and td.kind == "lco"
    assert td.amplitude == pytest.approx(st.amplitude, rel=0.05)
    assert td.frequency_hz == pytest.approx(st.frequency_hz, rel=0.02)


def test_krylov_bogoliubov_unstable_branch_separates_decay_from_lco():
    """Starting below the unstable LCO the motion decays into the band; above it, it grows to
    the stable LCO (the unstable branch is the threshold)."""
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    hb = harmonic_balance(sysm, conn)
    a_u = hb.lcos[0].amplitude
    x0 = np.zeros(4)
    x0[1] = 0.8 * a_u
    low = steady_oscillation(*_run(sysm, conn, x0), floor=conn.freeplay)
    assert low.kind == "decayed"
    x0[1] = 1.4 * a_u
    t, d = _run(sysm, conn, x0)
    high = steady_oscillation(t, d)
    assert high.kind == "lco" and high.amplitude > a_u


def _run(sysm, conn, x0, t_final=20.0):
    sim = simulate(sysm, conn, x0, t_final, n_out=40001)
    return sim.t, sim.d


def test_lco_amplitude_proportional_to_freeplay():
    sysm = toy(1.0)
    res = [harmonic_balance(sysm, Connection(K_CONN, freeplay=dl)) for dl in (0.001, 0.01, 0.1)]
    amps = np.array([[lc.amplitude for lc in r.lcos] for r in res])
    freqs = np.array([[lc.frequency_hz for lc in r.lcos] for r in res])
    np.testing.assert_allclose(amps[1] / amps[0], 10.0, rtol=1e-8)
    np.testing.assert_allclose(amps[2] / amps[0], 100.0, rtol=1e-8)
    np.testing.assert_allclose(freqs[1:], freqs[[0, 0]], rtol=1e-9)
    # the time domain too: the same motion scaled by delta
    x0 = np.zeros(4)
    sims = []
    for dl in (0.01, 0.02):
        x0[1] = 5 * dl
        sims.append(simulate(sysm, Connection(K_CONN, freeplay=dl), x0, 3.0, n_out=3001).d)
    np.testing.assert_allclose(sims[1], 2 * sims[0], atol=1e-6 * np.abs(sims[1]).max())


def test_no_lco_where_no_equivalent_stiffness_flutters():
    """An LCO needs A(N) unstable for some N in [k1, k]: at q where no connection stiffness
    flutters, harmonic balance finds none and the time domain decays from any amplitude."""
    q_lo = 0.2
    sysm = toy(q_lo)
    kap = np.linspace(0, 1, 201)
    assert max(growth_rate(sysm, kp * K_CONN)[0] for kp in kap) < 0
    conn = Connection(K_CONN, freeplay=0.01)
    hb = harmonic_balance(sysm, conn)
    assert hb.lcos == () and "no LCO found in" in hb.message
    x0 = np.zeros(4)
    x0[1] = 0.1
    out = steady_oscillation(*_run(sysm, conn, x0), floor=conn.freeplay)
    assert out.kind == "decayed"
    curve = lco_curve(toy, np.linspace(0.05, 0.5, 10), conn)
    onset = curve.onset_speed()
    # the onset is where the most unstable stiffness first flutters
    qs = np.linspace(0.05, 0.5, 10)
    first_unstable = next(q for q in qs
                          if max(growth_rate(toy(q), kp * K_CONN)[0] for kp in kap) > 0)
    assert onset == pytest.approx(first_unstable)


def test_unbounded_above_the_linear_flutter_speed():
    """A system whose full-stiffness model flutters has no bounded LCO at large amplitude:
    harmonic balance flags it and the time domain diverges."""
    w1 = 2 * math.pi * 8.0
    sysm = toy(1.0)
    # move mode 1 so the full stiffness is inside the flutter band
    A0 = sysm.A0.copy()
    A0[2, 0] = -w1 ** 2
    s2 = ConnectedSystem(A0, sysm.b, sysm.c)
    assert growth_rate(s2, K_CONN)[0] > 0
    conn = Connection(K_CONN, freeplay=0.01)
    hb = harmonic_balance(s2, conn)
    assert hb.unbounded and "grow without bound" in hb.message
    x0 = np.zeros(4)
    x0[1] = 2 * hb.lcos[-1].amplitude          # beyond the (unstable) LCO
    sim = simulate(s2, conn, x0, 30.0, n_out=3001)
    assert sim.diverged
    assert steady_oscillation(sim.t, sim.d, diverged=sim.diverged).kind == "diverged"


def test_zero_freeplay_limit_is_the_linear_system():
    """delta -> 0: the piecewise integration converges to the exact linear solution
    x(t) = expm(A(k) t) x0 (error proportional to delta)."""
    sysm = toy(0.5)
    x0 = np.array([0.0, 0.02, 0.0, 0.0])
    t_end = 2.0
    exact = expm(sysm.state_matrix(K_CONN) * t_end) @ x0
    errs = []
    for dl in (1e-4, 1e-5, 0.0):
        sim = simulate(sysm, Connection(K_CONN, freeplay=dl), x0, t_end, n_out=3, rtol=1e-10,
                       atol=1e-14)
        assert not sim.diverged
        errs.append(np.max(np.abs(sim.x[:, -1] - exact)))
    assert errs[2] < 1e-8                      # linear connection: the integrator's own error
    assert errs[1] < 0.2 * errs[0]             # ~ proportional to delta
    assert errs[1] < 0.02 * np.max(np.abs(sysm.state_matrix(K_CONN) @ x0))   # 2 % of the rates


def test_switches_are_located_on_the_band_edges():
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01, preload=0.003)
    x0 = np.array([0.0, 0.04, 0.0, 0.0])
    sim = simulate(sysm, conn, x0, 5.0, n_out=501)
    lo, hi = conn.breakpoints
    dist = np.minimum(np.abs(sim.switch_d - lo), np.abs(sim.switch_d - hi))
    assert sim.switch_times.size > 10
    assert np.max(dist) < 1e-10 * conn.freeplay * 100


# --------------------------------------------------------------------------------------------
# bad input
# --------------------------------------------------------------------------------------------
def test_bad_connections_are_refused():
    with pytest.raises(ValueError, match="freeplay"):
        Connection(120.0, freeplay=-0.001)
    with pytest.raises(ValueError, match="preload"):
        Connection(120.0, freeplay=0.001, preload=0.002)
    with pytest.raises(ValueError, match="inner_stiffness"):
        Connection(120.0, freeplay=0.001, inner_stiffness=200.0)
    with pytest.raises(ValueError, match="stiffness"):
        Connection(0.0, freeplay=0.001)
    with pytest.raises(ValueError, match="preload = 0"):
        Connection(120.0, freeplay=0.001, preload=0.0005).describing_function(0.01)
    with pytest.raises(ValueError, match="equivalent_stiffness"):
        Connection(120.0, freeplay=0.001).amplitude_for(120.0)


def test_amplitude_ranges_without_a_solution_say_so():
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    hb = harmonic_balance(sysm, conn, amplitude_range=(0.03, 0.5))   # above both LCOs
    assert hb.lcos == () and hb.message.startswith("no LCO found in [0.03, 0.5] rad")
    with pytest.raises(ValueError, match="amplitude_range"):
        harmonic_balance(sysm, conn, amplitude_range=(0.005, 0.5))   # below the band
    with pytest.raises(ValueError, match="amplitude_range"):
        harmonic_balance(sysm, conn, amplitude_range=(0.05, 0.02))
    with pytest.raises(ValueError, match="nonlinear"):
        harmonic_balance(sysm, Connection(K_CONN))


def test_never_settling_and_chattering_runs_are_reported():
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    x0 = np.array([0.0, 0.04, 0.0, 0.0])
    short = simulate(sysm, conn, x0, 0.3, n_out=301)
    res = steady_oscillation(short.t, short.d)
    assert res.kind == "not settled" and not res.settled
    assert np.isfinite(res.amplitude) and np.isfinite(res.frequency_hz)
    with pytest.raises(RuntimeError, match="region switches"):
        simulate(sysm, conn, x0, 20.0, max_switches=20)
    with pytest.raises(ValueError, match="x0"):
        simulate(sysm, conn, np.zeros(3), 1.0)
    with pytest.raises(ValueError, match="t_final"):
        simulate(sysm, conn, x0, -1.0)


def test_exact_propagation_equals_event_located_solve_ivp():
    """simulate_exact (matrix exponential per region, Brent on the exact d(tau)) and simulate
    (solve_ivp events) agree on the same switches and history."""
    from asekit.aeroelastic.nonlinear import simulate_exact
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01, inner_stiffness=50.0)
    x0 = np.array([0.01, 0.04, 0.0, 0.0])
    a = simulate(sysm, conn, x0, 3.0, n_out=3001, rtol=1e-10, atol=1e-13)
    b = simulate_exact(sysm, conn, x0, 3.0, step=1e-3)
    assert a.switch_times.size == b.switch_times.size > 20
    np.testing.assert_allclose(b.switch_times, a.switch_times, atol=1e-8)
    np.testing.assert_allclose(b.d, a.d, atol=1e-7 * conn.freeplay)
    with pytest.raises(ValueError, match="constant input"):
        simulate_exact(sysm, conn, x0, 1.0, u=lambda t: np.zeros(0))


def test_equilibria_of_a_destabilising_band():
    """A connection coordinate with a negative (de-centring) stiffness of its own: the rest
    position is unstable inside a freeplay band and two offset equilibria against the stops
    exist, d_e = k delta / (k - k_a), proportional to delta."""
    from asekit.aeroelastic.nonlinear import equilibria
    ka = 400.0                                     # de-centring stiffness, < k
    A0 = np.array([[0.0, 1.0], [ka, -2.0]])        # theta'' = ka theta - 2 theta' - f
    sysm = ConnectedSystem(A0, [0.0, -1.0], [1.0, 0.0])
    for dl in (0.01, 0.02):
        eq = equilibria(sysm, Connection(K_CONN, freeplay=dl))
        assert [e.region for e in eq] == [-1, 0, 1]
        assert not eq[1].stable and eq[0].stable and eq[2].stable
        assert eq[2].d == pytest.approx(K_CONN * dl / (K_CONN - ka), rel=1e-12)
        assert eq[0].d == pytest.approx(-eq[2].d, rel=1e-12)


def test_dual_input_df_reduces_to_the_single_input_one_and_to_the_law():
    from asekit.aeroelastic.nonlinear import dual_input_df
    conn = Connection(100.0, freeplay=0.01, inner_stiffness=10.0)
    for a in (0.005, 0.02, 0.3):
        f0, n1 = dual_input_df(conn, 0.0, a)
        assert f0 == pytest.approx(0.0, abs=1e-12)
        assert n1 == pytest.approx(conn.describing_function(a), rel=1e-12)
    # whole cycle on one linear piece: F0 = f(B), N1 = k
    f0, n1 = dual_input_df(conn, 0.05, 0.01)
    assert f0 == pytest.approx(float(conn.moment(0.05)), rel=1e-12) and n1 == pytest.approx(100.0)
    # against quadrature with a bias and a preload
    cp = Connection(100.0, freeplay=0.01, preload=0.004)
    B, A = 0.006, 0.015
    t0 = [math.asin(max(-1, min(1, (e - B) / A))) for e in cp.breakpoints]
    pts = sorted({x % (2 * math.pi) for t in t0 for x in (t, math.pi - t)})
    m0 = quad(lambda t: cp.moment(B + A * math.sin(t)), 0, 2 * math.pi, points=pts)[0]
    m1 = quad(lambda t: cp.moment(B + A * math.sin(t)) * math.sin(t), 0, 2 * math.pi,
              points=pts)[0]
    f0, n1 = dual_input_df(cp, B, A)
    assert f0 == pytest.approx(m0 / (2 * math.pi), rel=1e-9)
    assert n1 == pytest.approx(m1 / (math.pi * A), rel=1e-9)


# --------------------------------------------------------------------------------------------
# multi-harmonic balance
# --------------------------------------------------------------------------------------------
def test_multi_harmonic_balance_with_one_harmonic_is_the_describing_function():
    """With one harmonic and no bias, Eq. (4) is the describing-function balance
    D_1 = G(i omega) N(A) D_1: same amplitude and frequency as harmonic_balance (to the FFT
    sampling of the moment); more harmonics move the toy's stable LCO by under 1 % (its
    waveform is nearly harmonic) and agree with the time domain of the DF test above."""
    from asekit.aeroelastic.nonlinear import multi_harmonic_balance
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    st = harmonic_balance(sysm, conn).largest_stable()
    m1 = multi_harmonic_balance(sysm, conn, 1.1 * st.amplitude, 0.98 * st.frequency_hz,
                                n_harmonics=1, n_samples=4096)
    assert m1.converged
    assert m1.amplitude == pytest.approx(st.amplitude, rel=1e-5)
    assert m1.frequency_hz == pytest.approx(st.frequency_hz, rel=1e-6)
    assert abs(m1.bias) < 1e-9
    m9 = multi_harmonic_balance(sysm, conn, st.amplitude, st.frequency_hz, n_harmonics=9)
    assert m9.converged and m9.stable and abs(m9.trivial_multiplier - 1) < 0.01
    assert m9.amplitude == pytest.approx(st.amplitude, rel=0.01)
    # the unstable (lower) DF branch is unstable for the multi-harmonic balance too
    un = harmonic_balance(sysm, conn).lcos[0]
    mu = multi_harmonic_balance(sysm, conn, un.amplitude, un.frequency_hz, n_harmonics=9)
    assert mu.converged and not mu.stable


def test_multi_harmonic_balance_bad_input_and_no_lco():
    from asekit.aeroelastic.nonlinear import multi_harmonic_balance
    sysm = toy(1.0)
    conn = Connection(K_CONN, freeplay=0.01)
    for kw, name in (({"amplitude": -0.01}, "amplitude"), ({"frequency_hz": 0.0}, "frequency_hz"),
                     ({"n_harmonics": 0}, "n_harmonics"), ({"n_samples": 16}, "n_samples"),
                     ({"bias": math.nan}, "bias")):
        args = {"amplitude": 0.02, "frequency_hz": 6.0, **kw}
        with pytest.raises(ValueError, match=name):
            multi_harmonic_balance(sysm, conn, **args)
    with pytest.raises(ValueError, match="freeplay > 0"):
        multi_harmonic_balance(sysm, Connection(K_CONN), 0.02, 6.0)
    with pytest.raises(ValueError, match="harmonics_guess"):
        multi_harmonic_balance(sysm, conn, 0.02, 6.0, n_harmonics=3, harmonics_guess=[0, 0.02])
    with pytest.raises(TypeError, match="Connection"):
        multi_harmonic_balance(sysm, 1.0, 0.02, 6.0)
    # q = 0.3: no stiffness flutters, no LCO; a guess inside the band stays at rest
    quiet = multi_harmonic_balance(toy(0.3), conn, 0.005, 6.0, n_harmonics=3)
    assert not quiet.converged and quiet.message.startswith("no LCO found near")
    assert np.isfinite(quiet.amplitude)
