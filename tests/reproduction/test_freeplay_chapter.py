"""The freeplay chapter (asekit.reproduction.freeplay): the reference fin's Ritz model with a
freeplay connection (FinFreeplayModel) against the linear fin and the ASE loops, its statics,
LCOs and time domain; the Conner et al. (1997) path following and its helpers.

asekit.aeroelastic.nonlinear and asekit.aeroelastic.typical_section themselves are tested on their own models in
tests/aeroelastic/test_nonlinear.py and tests/aeroelastic/test_typical_section.py (references there: [C97] Conner,
Tang, Dowell & Virgin, J. Fluids Struct. 11 (1997) 89-109; [T98] Tang, Dowell & Virgin,
J. Fluids Struct. 12 (1998) 839-858).
"""

import math

import numpy as np
import pytest

from asekit.aeroelastic.nonlinear import (
    Connection,
    growth_rate,
    harmonic_balance,
    steady_oscillation,
)
from asekit.aeroelastic.typical_section import conner_1997, flutter_speed, section_matrices

# --------------------------------------------------------------------------------------------
# the reference fin (FinFreeplayModel): FN2 Ritz basis, Mach 0.5, sea level
# --------------------------------------------------------------------------------------------
RHO0 = 1.225


@pytest.fixture(scope="module")
def fin_model():
    from asekit.reproduction.flutter import load_fin_gafs
    from asekit.reproduction.freeplay import fin_freeplay_model
    data, reason = load_fin_gafs()
    if data is None:
        pytest.skip(reason)
    return fin_freeplay_model(0.5, data)


def test_fin_ritz_model_reproduces_the_linear_fin(fin_model):
    """With the linear 120 N m/rad spring, the fin-alone Ritz model (rigid pitch + FN1 modes,
    theta_f free) has the FN1 frequencies (plus one local connection mode above 3 kHz) and the
    growth rates of the thesis's clamped-actuator model (FN2 s-set, Eq. 3.12)."""
    from asekit.aeroelastic.statespace import aeroelastic_matrices
    m = fin_model
    Kt = m.K_plate + m.k_s * np.outer(m.c, m.c)
    f = np.sort(np.sqrt(np.abs(np.linalg.eigvals(np.linalg.solve(m.M, Kt))))) / (2 * math.pi)
    np.testing.assert_allclose(f[:-1], m.modal.frequencies_hz[1:], rtol=1e-6)
    assert f[-1] > 3000.0
    for u in (150.0, 250.0):
        ref = np.max(np.linalg.eigvals(aeroelastic_matrices(m.modal, m.rfa, RHO0, u).A).real)
        new = growth_rate(m.fin_alone(RHO0, u), m.k_s)[0]
        assert new == pytest.approx(ref, rel=5e-3, abs=0.01)


def test_fin_aem1_loop_matches_the_ase_model(fin_model):
    """The AEM1 loop built through the connection has the aeroelastic roots of
    asekit.ase.loop.closed_loop (thesis FN2 formulation) near the 140 Hz flutter mode."""
    import control as ct

    from asekit.ase import loop as ase
    from asekit.servo.actuator import SYSTEM_3
    m = fin_model
    rows = {"fin_root_pitch": m.outputs["fin_root_pitch"]}
    for u in (180.0, 240.0):
        model = ase.build_model(m.modal, m.rfa, RHO0, u, rows)
        ref = ct.poles(ase.closed_loop(model, SYSTEM_3, "AEM1"))
        new = m.aem1(RHO0, u).eigenvalues(m.k_s)
        pick = lambda ev: ev[np.argmin(np.abs(np.abs(ev.imag) / (2 * math.pi) - 140.0))]  # noqa
        a, b = pick(ref), pick(new)
        assert abs(b.imag) == pytest.approx(abs(a.imag), rel=0.01)
        assert b.real == pytest.approx(a.real, abs=0.05 * abs(a.imag) * 0.02 + 1.0)


def test_fin_aem2_loop_matches_the_ase_model(fin_model):
    """AEM2 (PD on the fin-root pitch) through the connection: the same stability verdict
    and the same least-damped roots as asekit.ase.loop.closed_loop (the thesis finds the linear
    AEM2 loop unstable, Fig 79)."""
    import control as ct

    from asekit.ase import loop as ase
    from asekit.servo.actuator import SYSTEM_3
    m = fin_model
    rows = {"fin_root_pitch": m.outputs["fin_root_pitch"]}
    u = 0.5 * 340.294
    ref = ct.poles(ase.closed_loop(ase.build_model(m.modal, m.rfa, RHO0, u, rows), SYSTEM_3,
                                   "AEM2"))
    new = m.loop(RHO0, u, "AEM2").eigenvalues(m.k_s)
    r_ref = ref[np.argmax(ref.real)]
    r_new = new[np.argmax(new.real)]
    assert (r_ref.real > 0) == (r_new.real > 0)
    assert abs(r_new) == pytest.approx(abs(r_ref), rel=0.02)
    assert r_new.real == pytest.approx(r_ref.real, rel=0.05, abs=1.0)
    with pytest.raises(ValueError, match="topology"):
        m.loop(RHO0, u, "AEM3")


def test_fin_band_is_statically_unstable_and_the_fin_rests_on_a_stop(fin_model):
    """The fin's aerodynamic hinge moment is de-centring (pressure centre ahead of the shaft):
    with zero stiffness in the band the rest position diverges statically, and below the
    linear flutter speed the stable states are the two offsets d = +-d_e against the stops,
    proportional to delta. The time domain settles there."""
    from asekit.aeroelastic.nonlinear import equilibria, simulate_exact
    m = fin_model
    s = m.fin_alone(RHO0, 200.0)
    assert growth_rate(s, 0.0)[2] > 0                       # a real root: static
    dl = math.radians(0.1)
    eq = equilibria(s, Connection(m.k_s, freeplay=dl))
    assert [e.region for e in eq] == [-1, 0, 1]
    assert eq[0].stable and eq[2].stable and not eq[1].stable
    eq2 = equilibria(s, Connection(m.k_s, freeplay=2 * dl))
    assert eq2[2].d == pytest.approx(2 * eq[2].d, rel=1e-10)
    x0 = np.zeros(s.n_states)
    x0[0] = 0.5 * dl
    sim = simulate_exact(s, Connection(m.k_s, freeplay=dl), x0, 3.0, step=1e-4)
    assert sim.d[-1] == pytest.approx(eq[2].d, rel=2e-3)


def test_fin_has_no_lco_below_linear_flutter_and_a_biased_one_above(fin_model):
    """Harmonic balance, symmetric and biased: no stable LCO at 150 and 200 m/s (below the
    linear flutter speed, where no equivalent stiffness in [0, k] flutters); just above it a
    stable LCO about the offset is born at zero amplitude (a Hopf bifurcation of the offset
    state), so the LCO onset is the linear flutter speed. The zero-stiffness fin does not
    flutter at all below 900 m/s."""
    from asekit.aeroelastic.nonlinear import biased_harmonic_balance
    from asekit.reproduction.freeplay import lco_onset, linear_flutter
    m = fin_model
    unit = Connection(m.k_s, freeplay=1.0)
    at = lambda u: m.fin_alone(RHO0, u)  # noqa: E731
    for u in (150.0, 200.0):
        s = at(u)
        assert max(growth_rate(s, kp * m.k_s)[0] for kp in np.linspace(0, 1, 41)) < 0
        assert harmonic_balance(s, unit).lcos == ()
        assert biased_harmonic_balance(s, unit) == ()
    uf, ff = linear_flutter(at, m.k_s, 50.0, 900.0)
    assert linear_flutter(at, 0.0, 20.0, 900.0) == (None, None)
    onset = lco_onset(m, "alone", RHO0, uf - 12.0, uf + 17.0)
    assert onset == pytest.approx(uf, abs=0.5)
    lc = biased_harmonic_balance(at(uf + 4.0), unit)
    assert len(lc) == 1 and lc[0].stable and lc[0].amplitude < 0.3 * lc[0].bias
    assert lc[0].frequency_hz == pytest.approx(ff, rel=0.02)


def test_fin_biased_df_against_time_domain(fin_model):
    """At 210 m/s (4 m/s above linear flutter) the event-located time domain settles on the
    biased LCO: bias and first-harmonic amplitude within 5 %, frequency within 2 % of the
    dual-input describing function."""
    from asekit.aeroelastic.nonlinear import biased_harmonic_balance
    from asekit.reproduction.freeplay import time_domain
    m = fin_model
    dl = math.radians(0.1)
    lc = biased_harmonic_balance(m.fin_alone(RHO0, 210.0), Connection(m.k_s, freeplay=dl))[0]
    sim = time_domain(m, "alone", RHO0, 210.0, delta_deg=0.1, t_final=4.0,
                      start=(lc.bias + lc.amplitude) / dl)
    # near the Hopf point the LCO attracts slowly: 2 % change per 30 cycles at 4 s
    td = steady_oscillation(sim.t, sim.d, n_cycles=30, rel_tol=0.02)
    assert td.settled, td.message
    assert td.bias == pytest.approx(lc.bias, rel=0.05)
    assert td.amplitude == pytest.approx(lc.amplitude, rel=0.05)
    assert td.frequency_hz == pytest.approx(lc.frequency_hz, rel=0.02)


def test_fin_aem1_command_step_with_freeplay(fin_model):
    """AEM1 with the connection freeplay: a 1 deg command step (u = theta_cmd). The
    transmission settles at the command less the droop of the PD under the hinge moment, and
    the fin settles at the transmission angle plus the connection offset of a static equilibrium
    (the fin leans on one stop)."""
    from asekit.aeroelastic.nonlinear import equilibria, simulate_exact
    m = fin_model
    s = m.aem1(RHO0, 150.0)
    conn = Connection(m.k_s, freeplay=math.radians(0.1))
    cmd = np.array([math.radians(1.0)])
    x0 = np.zeros(s.n_states)
    a = simulate_exact(s, conn, x0, 1.5, u=cmd, step=5e-5)
    eq = [e for e in equilibria(s, conn, u=cmd) if e.stable]
    assert eq, "a stable equilibrium under the command"
    end = a.x[:, -1]
    best = min(eq, key=lambda e: np.max(np.abs(e.x - end)))
    assert a.outputs["theta"][-1] == pytest.approx(best.x[0], rel=1e-3)
    assert a.d[-1] == pytest.approx(best.d, rel=3e-3)
    assert abs(a.outputs["theta"][-1] - cmd[0]) < 0.05 * cmd[0]
    assert abs(best.d) > conn.freeplay                    # on a stop


# --------------------------------------------------------------------------------------------
# Conner et al. (1997): path following
# --------------------------------------------------------------------------------------------
def _coupled_in_vacuo(sec):
    """In-vacuo coupled natural frequencies (rad/s, ascending) and mode shapes of a section
    (as tests/aeroelastic/test_typical_section.py)."""
    m = section_matrices(sec, 1.0)
    w2, phi = np.linalg.eig(np.linalg.solve(m.M_s, m.K_s))
    i = np.argsort(w2.real)
    return np.sqrt(w2.real[i]), phi.real[:, i]


PATH_SPEEDS = (4.0, 4.5, 5.0, 6.0, 7.0, 8.0, 8.5, 9.0, 9.5, 10.0, 10.5, 11.0, 11.5, 12.0, 12.5,
               13.0, 15.0, 17.5, 20.0, 22.0, 23.5, 24.0)


@pytest.fixture(scope="module")
def conner_path():
    from asekit.reproduction.freeplay import conner_path_following
    uf = flutter_speed(conner_1997(), 1.0, 60.0, 120)[0]
    return uf, conner_path_following(PATH_SPEEDS)


def test_conner_lco_regimes_against_published_path_following(conner_path):
    """[C97] Sec. 11.2 (pp. 101-105) describes the numerical model's path following in
    increasing airspeed (U / U_f, U_f its own linear flutter speed; experiment in brackets):
    disturbances decay up to ~0.18 (0.23), then a discrete jump to a low-frequency LCO; simple
    low-frequency motion until ~0.35 (0.37); "from approximately 0.32 U_f to 0.44 U_f
    predominantly nonperiodic" (p. 102); periodic again from ~0.44 (0.48) as "a more complex
    low frequency limit cycle" (Fig. 10: "period-2 flap region", 0.49 U_f) with larger
    amplitudes in all three degrees of freedom; at ~0.50 (0.55) the jump to a stable
    high-frequency LCO with "a dramatic drop in the plunge amplitude", the flap amplitude
    jumping up; divergent flutter "within 2% of the linear boundary" (p. 105). [T98] Sec. 4.2.1:
    the low-frequency LCO is near the plunge natural frequency, the high-frequency one near the
    pitch natural frequency.

    asekit, same model (Jones' C(k), Table A.1, +-2.12 deg), the same procedure (path
    following from the flap resting on a band edge plus a plunge kick of delta b;
    asekit.reproduction.freeplay.conner_path_following), U_f = 24.03 m/s:
    rest at 0.166, LCO from 0.187 (published 0.18); simple period-one low-frequency LCO
    (4.6-4.9 Hz) up to 0.395 (published 0.35: +0.045); not period-one at 0.416 (repeats every
    4 cycles) and 0.437 (no repeat within 8); periodic again from 0.458 to 0.499 with two flap
    maxima a cycle and an offset (-0.3 delta) (published: periodic again from 0.44, "more
    complex"); the 10.6-11.4 Hz LCO from 0.520 (published 0.50: +0.02), plunge r.m.s. falling
    from 0.48 to 0.14 then 0.04 delta b, flap r.m.s. rising; bounded LCO up to 0.999 U_f
    (published: within 2 %). Not compared: the r.m.s. amplitude curves of Fig. 8 (figures only,
    not digitised)."""
    uf, pts = conner_path
    r = np.array([p.velocity / uf for p in pts])
    kind = [p.flap.kind for p in pts]
    f = np.array([p.flap.frequency_hz for p in pts])
    lco = np.array([k == "lco" for k in kind])
    # (i) onset from rest: bracket [last decayed, first LCO] within 0.025 of 0.18
    i_on = int(np.argmax(lco))
    assert i_on > 0 and all(k == "decayed" for k in kind[:i_on])
    assert r[i_on] - 0.18 <= 0.025 and 0.18 - r[i_on - 1] <= 0.025
    # (ii) end of the simple (period-one, one maximum a cycle) low-frequency LCO: 0.35 +- 0.05
    simple_low = [i for i, p in enumerate(pts)
                  if lco[i] and f[i] < 7.0 and p.period == 1 and abs(p.maxima_per_cycle - 1) < 0.1]
    assert simple_low == list(range(i_on, simple_low[-1] + 1))
    assert abs(r[simple_low[-1]] - 0.35) <= 0.05
    # (iii) a non-period-one window inside 0.32-0.44, then periodic "more complex" motion
    non_p1 = [i for i, p in enumerate(pts) if f[i] < 7.0 and lco[i] and p.period != 1]
    assert non_p1 and all(0.32 <= r[i] <= 0.44 for i in non_p1)
    complex_p = [i for i, p in enumerate(pts)
                 if f[i] < 7.0 and p.period == 1 and p.maxima_per_cycle > 1.5]
    assert complex_p and all(0.44 <= r[i] <= 0.50 for i in complex_p)
    last_low = pts[complex_p[-1]]
    assert last_low.flap_rms > pts[simple_low[-1]].flap_rms
    assert last_low.plunge_rms > pts[simple_low[-1]].plunge_rms
    # (iv) the jump to the high-frequency LCO: 0.50 +- 0.03, plunge drops, flap rises
    i_hi = int(np.argmax(f > 7.5))
    assert abs(r[i_hi] - 0.50) <= 0.03 and np.all(f[i_hi:] > 7.5)
    settled_hi = [p for p in pts[i_hi:] if p.flap.kind == "lco"]
    assert settled_hi[0].plunge_rms < last_low.plunge_rms / 5
    assert settled_hi[0].flap_rms > last_low.flap_rms
    # (v) bounded up to the linear flutter speed (published: divergence within 2 %)
    assert all(p.flap.kind == "lco" for p in pts if p.velocity / uf > 0.98)
    assert max(r[lco]) > 0.98
    # [T98]: low branch nearer the plunge, high branch nearer the pitch coupled frequency
    w, _ = _coupled_in_vacuo(conner_1997())
    fh, fa, fb = w / (2 * math.pi)
    low, high = f[lco & (f < 7.0)], f[lco & (f > 7.5)]
    assert np.all(np.abs(low - fh) < np.abs(low - fa))
    assert np.all(np.abs(high - fa) < np.minimum(np.abs(high - fh), np.abs(high - fb)))


def test_path_following_helpers():
    """repeat_period finds the period of a period-doubled signal (a 5 Hz sine plus a 2.5 Hz
    subharmonic repeats after 2 periods of 5 Hz, a pure sine after 1, an incommensurate sum
    never within 8); bad input is refused."""
    from asekit.reproduction.freeplay import conner_path_following, repeat_period
    t = np.arange(0.0, 10.0, 1e-3)
    assert repeat_period(t, np.sin(2 * math.pi * 5 * t), 5.0, 1.0) == 1
    assert repeat_period(t, np.sin(2 * math.pi * 5 * t) + 0.3 * np.sin(math.pi * 5 * t),
                         5.0, 1.0) == 2
    assert repeat_period(t, np.sin(2 * math.pi * 5 * t) + 0.3 * np.sin(2 * math.pi * 5 * t
                                                                        / math.sqrt(5)),
                         5.0, 1.0) is None
    with pytest.raises(ValueError, match="frequency_hz"):
        repeat_period(t, t, 0.0, 1.0)
    with pytest.raises(ValueError, match="velocities"):
        conner_path_following([5.0, 4.0])
