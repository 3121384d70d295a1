"""Issue 23, "p-k batched": :func:`asekit.aeroelastic.flutter.pk_flutter_many` solves several
(GAF, density) sweeps of one modal model together, each k-iteration of every sweep's pending
roots one stacked eigen call. Its results must be those of :func:`pk_flutter` run sweep by
sweep, exactly (bit for bit): the batch changes how the eigenproblems are grouped, not what is
computed.

The model is the hand-derivable 2-dof coalescence case of test_flutter.py (M = I,
K = diag(100^2, 150^2), C = 2 I, Q = [[0, 1], [-2, 0]]): flutter where
q_f^2 (-a d) = ((k1 - k2)/2)^2 + c^2 (k1 + k2)/2, i.e. q_f = 4423.3 Pa at omega_f =
sqrt((k1 + k2)/2) (derived there from p = -c/2 +- sqrt(c^2/4 - lambda), lambda the eigenvalues
of K - q Q), plus a third, uncoupled mode. Two "Machs": the k-independent table (Mach 0) and
the same coupling scaled by Prandtl-Glauert's 1/sqrt(1 - M^2) at M 0.7 with a k-dependent
imaginary part (so that the interpolation in k matters); two densities.
"""

import numpy as np
import pytest
from scipy import optimize

from asekit.aeroelastic.flutter import (
    TabulatedGaf,
    _brent,
    first_of,
    pk_flutter,
    pk_flutter_many,
    pk_instabilities,
    pk_instabilities_many,
)
from asekit.aeroelastic.statespace import modal_arrays

K1, K2, K3, A, D, C = 100.0 ** 2, 150.0 ** 2, 260.0 ** 2, 1.0, -2.0, 2.0
#: flutter dynamic pressure of the Mach-0 table (formula above), Pa
Q_F = np.sqrt((((K1 - K2) / 2) ** 2 + C ** 2 * (K1 + K2) / 2) / (-A * D))
KS = np.array([0.0, 0.1, 0.3, 1.0])
VELOCITIES = np.arange(60.0, 150.0 + 1e-9, 3.0)        # m/s
DENSITIES = (1.0, 2.0)                                 # kg/m^3


def _model():
    M, K, Cm = np.eye(3), np.diag([K1, K2, K3]), C * np.eye(3)
    return modal_arrays(M=M, K=K, C=Cm, n_rigid=0)


def _gafs():
    Q = np.zeros((3, 3), complex)
    Q[0, 1], Q[1, 0] = A, D
    mach0 = TabulatedGaf(KS, np.array([Q] * KS.size), 1.0, mach=0.0)
    beta = 1.0 / np.sqrt(1.0 - 0.7 ** 2)
    damp = np.diag([-0.3, -0.2, -0.1]).astype(complex)
    Q7 = np.array([beta * (Q + 1j * k * damp) for k in KS])
    return [mach0, TabulatedGaf(KS, Q7, 1.0, mach=0.7)]


def _same_result(a, b):
    for name in ("velocities", "p", "k", "vectors", "converged", "path_velocities", "path_p",
                 "path_vectors", "path_converged", "modes", "structural_frequencies_hz"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert (a.density, a.mach, a.b_ref, a.forced_steps) == (b.density, b.mach, b.b_ref,
                                                            b.forced_steps)


@pytest.fixture(scope="module")
def sweeps():
    modal, gafs = _model(), _gafs()
    conditions = [(g, rho) for g in gafs for rho in DENSITIES]
    many = pk_flutter_many(modal, conditions, VELOCITIES)
    one = [pk_flutter(modal, g, rho, VELOCITIES) for g, rho in conditions]
    return modal, conditions, many, one


def test_batched_equals_sweep_by_sweep_exactly(sweeps):
    modal, conditions, many, one = sweeps
    assert len(many) == len(conditions) == 4
    for a, b in zip(many, one):
        _same_result(a, b)
    batched = pk_instabilities_many(many, modal, [g for g, _ in conditions])
    for (g, _), a, b, ia in zip(conditions, many, one, batched):
        ib = pk_instabilities(b, modal, g)
        assert ia and [_key(s) for s in ia] == [_key(s) for s in ib]
        assert [_key(s) for s in pk_instabilities(a, modal, g)] == [_key(s) for s in ib]


def _key(s):
    return (s.kind, s.mode, s.speed, s.frequency_hz, s.at_first_point, s.speed_tolerance)


def _run_brent(f, a, b, xtol):
    gen = _brent(a, b, xtol)
    x, calls = next(gen), 0
    try:
        while True:
            calls += 1
            x = gen.send(f(x))
    except StopIteration as stop:
        return stop.value, calls


@pytest.mark.parametrize("f, a, b", [
    (lambda x: x ** 3 - 2.0 * x - 5.0, 2.0, 3.0),          # Wallis's cubic, root 2.0945515
    (lambda x: np.cos(x) - x, 0.0, 1.0),
    (lambda x: np.exp(x) - 1e3, 0.0, 10.0),
    (lambda x: np.sign(x - 0.3) * abs(x - 0.3) ** 0.5, 0.0, 1.0),   # bisection steps
    (lambda x: np.tanh(50.0 * (x - 0.71)) - 0.2, 0.0, 1.0),
])
def test_generator_brent_is_scipy_brentq_step_for_step(f, a, b):
    """The lock-step refinement's Brent (a generator) returns scipy.optimize.brentq's root bit
    for bit, with the same number of evaluations, so that a batched refinement equals the
    one-sweep one; same-sign brackets give None (brentq: ValueError)."""
    for xtol in (1e-12, 1e-6, 1e-3):
        ref, info = optimize.brentq(f, a, b, xtol=xtol, full_output=True)
        root, calls = _run_brent(f, a, b, xtol)
        assert root == ref and calls == info.function_calls
    assert _run_brent(lambda x: x * x + 1.0, -1.0, 1.0, 1e-9)[0] is None


def test_batched_physics_first_point_and_hand_derived_flutter(sweeps):
    modal, conditions, many, _ = sweeps
    # Mach 0, rho 1: the hand-derived flutter speed U_f = sqrt(2 q_f / rho), 94.05 m/s
    fl = first_of(pk_instabilities(many[0], modal, conditions[0][0]), "flutter")
    assert fl is not None and not fl.at_first_point
    assert fl.speed == pytest.approx(np.sqrt(2 * Q_F / 1.0), rel=1e-6)
    assert fl.frequency_hz == pytest.approx(np.sqrt((K1 + K2) / 2) / (2 * np.pi), rel=1e-6)
    # Mach 0.7, rho 2: the Prandtl-Glauert factor 1.40 lowers q_f to 3160 Pa, U_f 56.2 m/s
    # without the (stabilising) damping term, 58-59 m/s with it: below the first airspeed
    # (60 m/s), so reported as flutter at or below U0, not dropped
    first = first_of(pk_instabilities(many[3], modal, conditions[3][0]))
    assert first is not None and first.at_first_point and first.kind == "flutter"
    assert first.speed == VELOCITIES[0]
    # the uncoupled third mode stays at its structural frequency, damped (Re p < 0)
    assert np.all(many[1].sigma[:, 2] < 0)


def test_batched_is_reproducible_and_order_free(sweeps):
    modal, conditions, many, _ = sweeps
    again = pk_flutter_many(modal, conditions[::-1], VELOCITIES)[::-1]
    for a, b in zip(many, again):
        _same_result(a, b)


def test_batched_tracks_selected_modes_like_pk_flutter(sweeps):
    modal, conditions, _, _ = sweeps
    many = pk_flutter_many(modal, conditions[:2], VELOCITIES[:8], modes=[1, 2])
    for (g, rho), a in zip(conditions[:2], many):
        _same_result(a, pk_flutter(modal, g, rho, VELOCITIES[:8], modes=[1, 2]))


@pytest.mark.parametrize("conditions, error, words", [
    ([], ValueError, "non-empty sequence of (gaf, density) pairs"),
    (5, TypeError, "conditions must be a sequence"),
    ("bad-density", ValueError, "conditions[1] density"),
    ("bad-gaf", TypeError, "conditions[0] gaf must be a TabulatedGaf"),
])
def test_batched_bad_conditions_are_named(conditions, error, words):
    modal, gafs = _model(), _gafs()
    if conditions == "bad-density":
        conditions = [(gafs[0], 1.0), (gafs[1], -1.0)]
    elif conditions == "bad-gaf":
        conditions = [(np.zeros((4, 3, 3)), 1.0)]
    with pytest.raises(error, match=None) as info:
        pk_flutter_many(modal, conditions, VELOCITIES)
    assert words in str(info.value)
