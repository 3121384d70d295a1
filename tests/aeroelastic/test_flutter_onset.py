"""Issue 11: flutter that must never go unreported.

A sweep that starts above the flutter speed, a single unstable airspeed, rounding-level
Re p > 0 at U -> 0, unsorted velocities, a k-iteration cut short, a time-domain window shorter
than a period. Reference speeds: the fin's p-k flutter at M 0.75 sea level (218.1 m/s, asekit's
own sweep from 100 m/s, tests/aeroelastic/test_flutter.py / reproduction chapter 3.3) and Nastran HA145B
(flutter of the second mode near 12,672 in/s, MSC Nastran Aeroelastic Analysis User's Guide,
Example HA145B, as quoted in tests/aeroelastic/test_flutter.py).
"""

import warnings

import numpy as np
import pytest
from property_targets import TWO_DOF, two_dof_coalescence

from asekit.aeroelastic.flutter import (
    FlutterConvergenceWarning,
    PkResult,
    RootLocusResult,
    TabulatedGaf,
    crossing_tolerance,
    first_of,
    growth_rate,
    match_point_table,
    matched_mach,
    pk_flutter,
    pk_instabilities,
    root_locus,
    root_locus_instabilities,
    simulate_free_response,
    time_domain_sweep,
)
from asekit.aeroelastic.statespace import modal_arrays
from asekit.io.op4 import load_ha145b
from asekit.rfa import roger_fit, roger_fit_database

HA145B_FLUTTER_SPEED = 12672.0      # in/s, Nastran HA145B (see module docstring)


@pytest.fixture(scope="module")
def fin(fin_modal, fin_gafs):
    """The fin (tests/conftest.py, via the case pipeline) at M 0.75: modal model, tabulated GAFs
    and their Roger fit with 4 lags."""
    return (fin_modal, fin_gafs.at(0.75),
            roger_fit_database(fin_gafs, 0.75, n_lags=4))


@pytest.fixture(scope="module")
def ha145b():
    case = load_ha145b()
    modal = modal_arrays(M=case.M, K=case.K, n_rigid=0)
    gaf = TabulatedGaf(case.k, case.Q, case.b_ref, mach=0.0)
    return case, modal, gaf, roger_fit(case.k, case.Q, case.b_ref, n_lags=4)


def _coalescence(c=2.0):
    """2-dof quasi-steady model of tests/aeroelastic/test_flutter.py (hand-derived flutter q_f)."""
    k1, k2, a, d = TWO_DOF
    q_f = np.sqrt((((k1 - k2) / 2) ** 2 + c ** 2 * (k1 + k2) / 2) / (-a * d))
    modal, gaf, fit = two_dof_coalescence(c)
    return modal, gaf, fit, np.sqrt(2 * q_f)          # rho = 1


# ---- sweeps that start above the flutter speed ------------------------------------------------
def test_fin_sweep_above_flutter_is_reported_by_all_three_methods(fin):
    """Issue reproducer: fin, sea level, M 0.75, sweep 250-460 m/s (flutter at ~218 m/s)."""
    modal, gaf, fit = fin
    U = np.linspace(250.0, 460.0, 22)
    res = pk_flutter(modal, gaf, 1.225, U)
    assert res.sigma[0].max() > 1.0                      # really unstable at 250 m/s
    fl = first_of(pk_instabilities(res, modal, gaf), "flutter")
    assert fl is not None and fl.at_first_point and fl.speed == 250.0
    assert "at or below 250" in fl.describe()
    rl = root_locus(modal, fit, 1.225, U)
    rl_f = first_of(root_locus_instabilities(rl, modal, fit), "flutter")
    assert rl_f is not None and rl_f.at_first_point and rl_f.speed == 250.0
    td = time_domain_sweep(modal, fit, 1.225, U[::7])
    assert td.at_first_point and td.onset_speed == 250.0
    assert "at or below 250" in td.describe()


def test_fin_sweep_from_below_still_gives_a_crossing(fin):
    modal, gaf, _ = fin
    res = pk_flutter(modal, gaf, 1.225, np.linspace(150.0, 300.0, 16))
    fl = first_of(pk_instabilities(res, modal, gaf), "flutter")
    assert not fl.at_first_point and 150.0 < fl.speed < 300.0
    assert fl.speed == pytest.approx(218.1, rel=0.01)      # asekit's own 100-460 m/s sweep


def test_fin_single_unstable_velocity(fin):
    modal, gaf, fit = fin
    fl = pk_instabilities(pk_flutter(modal, gaf, 1.225, [300.0]), modal, gaf)
    assert len(fl) >= 1 and fl[0].at_first_point and fl[0].kind == "flutter"
    rl = root_locus_instabilities(root_locus(modal, fit, 1.225, [300.0]))
    assert rl and rl[0].at_first_point
    # a single stable velocity reports nothing
    assert pk_instabilities(pk_flutter(modal, gaf, 1.225, [150.0]), modal, gaf) == []


def test_ha145b_sweep_above_flutter(ha145b):
    """Issue reproducer: HA145B swept 13,000-25,200 in/s misses the ~12,700 in/s flutter."""
    case, modal, gaf, fit = ha145b
    U = np.linspace(13000.0, 25200.0, 30)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlutterConvergenceWarning)
        res = pk_flutter(modal, gaf, case.rho, U)
    fl = first_of(pk_instabilities(res, modal, gaf), "flutter")
    assert fl.at_first_point and fl.mode == 1 and fl.speed == 13000.0
    assert HA145B_FLUTTER_SPEED < fl.speed                 # consistent: flutter is below U0
    rl_f = first_of(root_locus_instabilities(root_locus(modal, fit, case.rho, U), modal, fit),
                    "flutter")
    assert rl_f.at_first_point and rl_f.mode == 1
    td = time_domain_sweep(modal, fit, case.rho, [13000.0, 14000.0], t_end=3.0)
    assert td.at_first_point and td.onset_speed == 13000.0


def test_match_points_say_so(fin):
    modal, gaf, _ = fin
    # issue 30: the advice names the argument that takes it, every number with its unit
    with pytest.warns(RuntimeWarning, match=r"at or below 250 m/s.*, only a bound; velocities "
                                            r"starting below 250 m/s \(match_point_table's"):
        rows = match_point_table(modal, lambda mach: gaf, [0.75], [0.0],
                                 np.linspace(250.0, 460.0, 8))
    assert rows[0].at_first_point and "at or below 250" in rows[0].describe()
    with pytest.warns(RuntimeWarning, match="unstable at its first point"):
        assert matched_mach(rows, 0.0) is None


# ---- the crossing test's tolerance -------------------------------------------------------------
def test_rounding_level_positive_real_part_is_not_an_instability():
    """Re p = +4.7e-14 at U ~ 0 (rounding, undamped fin in the issue) with |p| ~ 900 1/s: not an
    instability at the first point; the real crossing later is still found."""
    U = np.array([1e-6, 100.0, 200.0, 300.0])
    w = 2 * np.pi * 140.0
    sig = np.array([4.7e-14, -5.0, -1.0, 3.0])
    p = (sig + 1j * w)[:, None]
    res = PkResult(velocities=U, p=p, k=np.zeros((4, 1)), vectors=np.ones((4, 1, 1), complex),
                   converged=np.ones((4, 1), bool), structural_frequencies_hz=np.array([140.0]),
                   density=1.0)
    assert 4.7e-14 < crossing_tolerance(p) < 1e-3
    inst = pk_instabilities(res, refine=False)
    assert len(inst) == 1 and not inst[0].at_first_point
    assert inst[0].speed == pytest.approx(200.0 + 100.0 * 1.0 / 4.0)
    rl = RootLocusResult(velocities=U, eigenvalues=p, elastic=p, max_real=p.real[:, 0],
                         density=1.0)
    inst = root_locus_instabilities(rl, refine=False)
    assert len(inst) == 1 and not inst[0].at_first_point


def test_undamped_root_locus_from_u_near_zero():
    """Undamped 2-dof case from U = 1e-9: structural roots on the imaginary axis (rounding may
    put them at +-1e-14); exactly one flutter crossing at the hand-derived U_f. (The grid avoids
    U_f itself: at the exact coalescence the double root's rounding is sqrt(eps) |p| ~ 1e-6.)"""
    modal, gaf, fit, U_f = _coalescence(c=0.0)
    U = np.r_[1e-9, np.linspace(0.2 * U_f, 1.5 * U_f, 12)]
    rl = root_locus(modal, fit, 1.0, U)
    inst = root_locus_instabilities(rl, modal, fit)
    assert [i.at_first_point for i in inst] == [False]
    assert inst[0].speed == pytest.approx(U_f, rel=1e-6)
    pk = pk_instabilities(pk_flutter(modal, gaf, 1.0, U), modal, gaf)
    assert pk and not any(i.at_first_point for i in pk)    # both tracked modes may report it
    assert all(i.speed == pytest.approx(U_f, rel=1e-6) for i in pk)


# ---- velocities, max_iter, window --------------------------------------------------------------
@pytest.mark.parametrize("U", [[30.0, 20.0, 10.0], [10.0, 30.0, 20.0], [10.0, 10.0, 20.0]])
def test_unsorted_velocities_refused_by_all_methods(U):
    modal, gaf, fit, _ = _coalescence()
    for call in (lambda: pk_flutter(modal, gaf, 1.0, U),
                 lambda: root_locus(modal, fit, 1.0, U),
                 lambda: time_domain_sweep(modal, fit, 1.0, U, coordinate=0, t_end=1.0)):
        with pytest.raises(ValueError, match="velocities must be strictly ascending"):
            call()


def test_max_iter_nonconvergence_warns_with_mode_and_speed():
    modal, gaf, _, U_f = _coalescence()
    gaf_k = TabulatedGaf(np.array([0.0, 0.5, 10.0]), np.array([gaf.Q[0], 2 * gaf.Q[0],
                                                               gaf.Q[0]]), 1.0)
    # issue 30: the speed with its unit; the advice names pk_flutter's max_iter (not a bare
    # "Raise max_iter": a case file has no such key)
    with pytest.warns(FlutterConvergenceWarning, match=r"within 1 iterations .* mode \d at "
                      r"U = [0-9.e+]+ m/s.*pk_flutter\(\.\.\., max_iter=N\)"):
        res = pk_flutter(modal, gaf_k, 1.0, [0.5 * U_f], max_iter=1)
    assert not res.converged.all()
    for bad in (0, -3):
        with pytest.raises(ValueError, match="max_iter"):
            pk_flutter(modal, gaf, 1.0, [10.0], max_iter=bad)
    with pytest.raises(TypeError, match="max_iter"):
        pk_flutter(modal, gaf, 1.0, [10.0], max_iter=2.5)


def test_time_domain_window_shorter_than_a_period_refused():
    modal, _, fit, U_f = _coalescence()
    period = 2 * np.pi / 100.0                        # slowest mode 100 rad/s
    with pytest.raises(ValueError, match="window .* shorter than a period"):
        time_domain_sweep(modal, fit, 1.0, [U_f], coordinate=0, t_end=1.0, window=1e-9)
    with pytest.raises(ValueError, match="t_end"):
        time_domain_sweep(modal, fit, 1.0, [U_f], coordinate=0, t_end=2 * period)
    t = np.linspace(0, 1, 101)
    with pytest.raises(ValueError, match="window"):
        growth_rate(t, np.sin(t), 1e-9)
    with pytest.raises(ValueError, match="max_step"):
        simulate_free_response(np.eye(2), np.ones(2), t_end=10.0, max_step=1e-9)
