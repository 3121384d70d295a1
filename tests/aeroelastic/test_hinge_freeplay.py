"""Freeplay in a control surface's hinge (asekit.aeroelastic.hinge_freeplay, issue 25): the
aileron wing (data/cases/aileron_wing.toml, coarsened: 4 x 8 plate elements, 8 x 8 boxes, Mach
0, sea level) with its 0.5 N m/rad hinge spring as the nonlinear connection."""

import math
import tomllib

import numpy as np
import pytest

from asekit.aero.gaf import build_gaf_database
from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
from asekit.aeroelastic.hinge_freeplay import (
    connected_flutter_speed,
    hinge_connected_system,
    hinge_connection,
    hinge_spring,
)
from asekit.aeroelastic.nonlinear import harmonic_balance, simulate_exact, steady_oscillation
from asekit.case import case_from_dict
from asekit.case import pipeline as P
from asekit.rfa.roger import roger_fit_database
from asekit.util.paths import CASES_DIR

RHO = 1.225
GAP = math.radians(0.5)           # freeplay half-width (rad)


@pytest.fixture(scope="module")
def wing():
    d = tomllib.loads((CASES_DIR / "aileron_wing.toml").read_text())
    d["panel"][0].update(n_chord=4, n_span=8)
    d["aero"]["boxes"] = [{"n_chord": 8, "n_span": 8}]
    d["aero"]["machs"] = [0.0]
    d["control_surface"][0].pop("actuator", None)
    case = case_from_dict(d)
    hm = P.control_surface_mesh(case)
    fm = P.control_surface_model(case)
    db = build_gaf_database(fm.box_modes, hm.mesh, (0.0,), P.reduced_frequencies(case),
                            case.aero.reference_semichord, 0, symmetric=True, progress=False)
    fit = roger_fit_database(db, 0.0, n_lags=4)
    h = fm.n_wing

    def at(u):
        return hinge_connected_system(fm.modal, fit, RHO, u, h)
    return fm, db.at(0.0), fit, h, at


def test_zero_gap_is_the_hinge_free_linear_flutter(wing):
    """With the hinge spring as a linear connection (zero gap) the connected system is the
    hinge-free aeroelastic state space; its flutter speed matches the p-k flutter of the same
    flap modal model and GAFs within 3 % (RFA vs p-k; measured 13.26 vs 13.04 m/s on the
    finer shipped mesh), the frequency within 3 %."""
    fm, gaf, fit, h, at = wing
    kh = hinge_spring(fm.modal, h)
    assert kh == pytest.approx(0.5)
    u_ss, f_ss = connected_flutter_speed(at, kh, 2.0, 40.0)
    res = pk_flutter(fm.modal, gaf, RHO, np.arange(2.0, 40.0, 0.25))
    inst = [i for i in pk_instabilities(res, fm.modal, gaf, RHO)
            if not i.at_first_point and i.frequency_hz > 0]
    pk = min(inst, key=lambda i: i.speed)
    assert u_ss == pytest.approx(pk.speed, rel=0.03)
    assert f_ss == pytest.approx(pk.frequency_hz, rel=0.03)
    # the connected system's A0 + k b c^T is the state matrix with the spring in K
    from asekit.aeroelastic.statespace import aeroelastic_matrices
    s = at(15.0)
    A_lin = aeroelastic_matrices(fm.modal, fit, RHO, 15.0).A
    assert np.allclose(s.state_matrix(kh), A_lin, rtol=1e-10, atol=1e-9 * np.abs(A_lin).max())


def test_describing_function_lco_band(wing):
    """Freeplay with no inner stiffness: the describing function N(A) spans [0, k_h), so a
    harmonic-balance LCO exists at every airspeed between the flutter speed with the hinge
    spring at zero (U_0) and at k_h (U_h, above which the oscillation is unbounded). Here the
    unbalanced aileron with no hinge spring is already unstable at 2 m/s (U_0 < 2 m/s: the LCO
    onset is below every speed tried). At an airspeed in the band the LCO's equivalent
    stiffness N(A) is the hinge stiffness whose linear flutter speed is that airspeed (within
    1 %), and the amplitude grows with airspeed."""
    fm, gaf, fit, h, at = wing
    kh = hinge_spring(fm.modal, h)
    conn = hinge_connection(fm.modal, h, GAP)
    with pytest.raises(ValueError, match="already unstable"):
        connected_flutter_speed(at, 0.0, 2.0, 40.0)
    uh, _ = connected_flutter_speed(at, kh, 2.0, 40.0)
    lo = harmonic_balance(at(2.0), conn)
    assert lo.inside_band_unstable and lo.largest_stable() is not None
    amps = []
    for u in np.linspace(2.0, uh, 6)[1:-1]:
        r = harmonic_balance(at(u), conn)
        lc = r.largest_stable()
        assert lc is not None and not r.unbounded
        k_eq = float(conn.describing_function(lc.amplitude))
        assert 0 < k_eq < kh
        uf, _ = connected_flutter_speed(at, k_eq, 0.5 * u, 40.0)
        assert uf == pytest.approx(u, rel=0.01)
        amps.append(lc.amplitude)
    assert np.all(np.diff(amps) > 0)
    assert harmonic_balance(at(1.05 * uh), conn).unbounded


def test_exact_simulation_matches_harmonic_balance(wing):
    """At an airspeed inside the LCO band the exact piecewise-linear time integration settles
    on an oscillation whose first-harmonic hinge amplitude is within 5 % of the harmonic
    balance's and its frequency within 5 % (measured at 0.8 U_h = 10.61 m/s, 0.5 deg gap:
    0.967 deg / 3.00 Hz against 0.976 deg / 3.02 Hz; the describing function keeps the first
    harmonic only)."""
    fm, gaf, fit, h, at = wing
    kh = hinge_spring(fm.modal, h)
    conn = hinge_connection(fm.modal, h, GAP)
    uh, _ = connected_flutter_speed(at, kh, 2.0, 40.0)
    u = 0.8 * uh
    s = at(u)
    lc = harmonic_balance(s, conn).largest_stable()
    x0 = np.zeros(s.n_states)
    x0[h] = 2 * GAP
    sim = simulate_exact(s, conn, x0, 30.0, step=2e-3)
    td = steady_oscillation(sim.t, sim.d, n_cycles=4, rel_tol=0.05)
    print(f"U = {u:.2f} m/s: harmonic balance {math.degrees(lc.amplitude):.4f} deg "
          f"{lc.frequency_hz:.3f} Hz, time domain {math.degrees(td.amplitude):.4f} deg "
          f"{td.frequency_hz:.3f} Hz ({td.kind})")
    assert td.kind == "lco"
    assert td.frequency_hz == pytest.approx(lc.frequency_hz, rel=0.05)
    assert td.amplitude == pytest.approx(lc.amplitude, rel=0.05)
