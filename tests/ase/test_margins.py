"""asekit.ase.margins: Nyquist-counted margins on loops whose closed-loop stability is known exactly.

References: closed-loop poles of first- and second-order loops in closed form (the roots of the
characteristic polynomial; Routh-Hurwitz for the cubic), the classic K/(s+1)^3 loop (phase
crossover at w = sqrt(3), |L| = K/8 there), and, for random loops, the eigenvalues of the
closed-loop state matrix A - k B C / (1 + k D) — an independent definition of stability that
does not use the Nyquist curve.
"""

import math

import control as ct
import numpy as np
import pytest

from asekit.ase.margins import nyquist_margins


def _eig_stable(sys, k):
    ss = ct.ss(sys)
    A, B, C, D = (np.asarray(m, float) for m in (ss.A, ss.B, ss.C, ss.D))
    acl = A - k * B @ C / (1.0 + k * D[0, 0])
    return bool(np.all(np.linalg.eigvals(acl).real < 0))


def test_first_order_unstable_loop_has_a_lower_gain_margin():
    # L = K/(s - a): closed-loop pole s = a - k K, stable iff k > a/K. K = 2a: lower GM = 1/2.
    a, K = 15.5, 31.0
    m = nyquist_margins(ct.tf([K], [1, -a]))
    assert m.open_loop_unstable and m.open_loop_unstable_poles == 1
    assert m.closed_loop_stable
    assert m.lower_gain_margin == pytest.approx(a / K, rel=1e-9)
    assert m.lower_gain_margin_db == pytest.approx(20 * math.log10(0.5), abs=1e-7)
    assert math.isinf(m.upper_gain_margin)
    # the crossing is at w = 0 (L(0) = -K/a), a phase crossover no Bode grid sees
    assert m.phase_crossovers_hz[0] == 0.0


def test_integrator_with_unstable_pole_and_lead():
    # L = K (s + z) / (s (s - a)): s^2 + (kK - a) s + kKz = 0, stable iff k > a/K (Routh).
    # Exercises the indentation around the origin together with P = 1.
    a, z, K = 2.0, 5.0, 8.0
    m = nyquist_margins(ct.tf([K, K * z], [1, -a, 0]))
    assert (m.open_loop_unstable_poles, m.origin_poles) == (1, 1)
    assert m.closed_loop_stable
    assert m.lower_gain_margin == pytest.approx(a / K, rel=1e-7)
    assert math.isinf(m.upper_gain_margin)


def test_classic_stable_cubic_upper_margin():
    # L = K/(s+1)^3, K = 2: phase crossover at w = sqrt(3) rad/s where |L| = K/8: upper GM 4
    # (Routh: stable iff k K < 8); stable down to zero gain.
    m = nyquist_margins(ct.tf([2.0], [1, 3, 3, 1]))
    assert not m.open_loop_unstable and m.closed_loop_stable
    assert m.lower_gain_margin == 0.0 and m.lower_gain_margin_db == -math.inf
    assert m.upper_gain_margin == pytest.approx(4.0, rel=1e-8)
    assert m.phase_crossovers_hz[0] == pytest.approx(math.sqrt(3) / (2 * math.pi), rel=1e-8)
    # and it agrees with python-control where python-control applies (stable open loop)
    gm, pm, *_ = ct.stability_margins(ct.tf([2.0], [1, 3, 3, 1]))
    assert m.upper_gain_margin == pytest.approx(gm, rel=1e-6)
    assert m.phase_margin_deg == pytest.approx(pm, abs=1e-5)


def test_unstable_nominal_loop_reports_no_margins():
    # L = -1/s: 1 - k/s, closed-loop pole +k: unstable for every k > 0
    m = nyquist_margins(ct.tf([-1.0], [1, 0]))
    assert m.closed_loop_unstable_poles == 1 and not m.closed_loop_stable
    assert m.lower_gain_margin is None and m.upper_gain_margin is None
    assert m.lower_gain_margin_db is None


def test_double_unstable_second_order():
    # L = K (s + 1)^2 / (s - 1)^2 (P = 2): (1 + k K) s^2 + 2 (k K - 1) s + (1 + k K) = 0,
    # stable iff k K > 1. K = 4: lower GM 1/4.
    K = 4.0
    m = nyquist_margins(ct.tf([K, 2 * K, K], [1, -2, 1]))
    assert m.open_loop_unstable_poles == 2 and m.closed_loop_stable
    assert m.lower_gain_margin == pytest.approx(0.25, rel=1e-7)


@pytest.mark.parametrize("seed", range(12))
def test_random_loops_agree_with_closed_loop_eigenvalues(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 7))
    sys = ct.rss(n, 1, 1, strictly_proper=bool(seed % 2))
    A = np.asarray(sys.A) + np.diag(rng.normal(0, 0.5, n))       # some unstable poles
    sys = ct.ss(A, sys.B, sys.C, sys.D)
    if np.any(np.abs(np.linalg.eigvals(A).real) < 1e-6):
        pytest.skip("pole on the imaginary axis")
    m = nyquist_margins(sys)
    edges = np.concatenate([[m.boundary_gains[0] / 10 if m.boundary_gains.size else 0.1],
                            m.boundary_gains,
                            [m.boundary_gains[-1] * 10 if m.boundary_gains.size else 10.0]])
    mids = np.sqrt(edges[:-1] * edges[1:]) if m.boundary_gains.size else np.array([0.1, 1, 10])
    for k in mids:
        if abs(1.0 + k * float(np.asarray(sys.D)[0, 0])) < 1e-6:
            continue
        assert m.stable_at(k) == _eig_stable(sys, k), (seed, k)


def test_bad_input():
    with pytest.raises(TypeError):
        nyquist_margins(np.ones(3))
    with pytest.raises(TypeError):
        nyquist_margins(ct.rss(2, 2, 2))
    with pytest.raises(ValueError, match="imaginary axis"):
        nyquist_margins(ct.tf([1.0], [1, 0, 4.0]))           # undamped poles at +-2j
    with pytest.raises(ValueError, match="at least one state"):
        nyquist_margins(ct.ss([], [], [], [[-2.0]]))
    with pytest.raises(ValueError, match="points_per_decade"):
        nyquist_margins(ct.tf([1.0], [1, 1]), points_per_decade=2)
    m = nyquist_margins(ct.tf([1.0], [1, 1]))
    with pytest.raises(ValueError, match="positive"):
        m.stable_at(-1.0)


def test_crossing_exactly_on_a_grid_point():
    # L = 8 (s + 5) / (s (s - 2)) crosses the real axis at w = sqrt(10) rad/s (Im L = 0 there:
    # Im[(40 + 8jw)(-w^2 + 2jw)] = 80 w - 8 w^3), a point of the default logspace grid, where
    # Im L is exactly 0 in floating point; the crossing must still be counted (Routh: stable).
    from asekit.ase.margins import _frequency_grid
    L = ct.tf([8.0, 40.0], [1.0, -2.0, 0.0])
    w = _frequency_grid(np.array([0.0, 2.0]), np.array([-5.0]), 400)
    assert np.any(w == math.sqrt(10.0))
    m = nyquist_margins(L)
    assert m.closed_loop_unstable_poles == 0
    assert m.lower_gain_margin == pytest.approx(2.0 / 8.0, rel=1e-9)   # k K > a
