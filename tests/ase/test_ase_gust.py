"""The gust in the closed AEM1 and AEM2 loops, linear and power-limited (asekit.ase.gust)."""

import numpy as np
import pytest

from asekit.aeroelastic.gust import gust_state_space, one_minus_cosine
from asekit.ase.gust import closed_loop_gust, closed_loop_gust_response
from asekit.case import pipeline as P
from asekit.rfa.gust import gust_fit


def _gust_fit(fin_ase, scale=1.0):
    k = fin_ase.rfa.k
    n = fin_ase.modal.M.shape[0]
    qg = scale * np.outer(1 - 0.5j * k / (1j * k + 0.3), np.linspace(1.0, 0.2, n) * 1e-3)
    return gust_fit(k, qg, fin_ase.rfa.b_ref, lag_roots=fin_ase.rfa.lag_roots)


def test_loop_is_linear_in_the_gust_and_holds_the_fin(fin_ase):
    # the closed loop is linear in the gust (twice the gust column: twice the current), its
    # uncoupled part is the AEM1 loop of asekit.ase.loop (same poles plus the gust lags'
    # -(U/b) beta_n), and after the gust the fin returns to zero
    ss1 = gust_state_space(fin_ase.modal, fin_ase.rfa, _gust_fit(fin_ase), fin_ase.density,
                           fin_ase.velocity)
    ss2 = gust_state_space(fin_ase.modal, fin_ase.rfa, _gust_fit(fin_ase, 2.0),
                           fin_ase.density, fin_ase.velocity)
    _, ctl, _ = P.actuator_setup(fin_ase.case)
    loop1, loop2 = closed_loop_gust(fin_ase.model, ctl, ss1), closed_loop_gust(fin_ase.model,
                                                                               ctl, ss2)
    t = np.linspace(0.0, 0.5, 2001)
    w = one_minus_cosine(t, fin_ase.velocity, 5.0, 10.0)
    r1, r2 = closed_loop_gust_response(loop1, t, w), closed_loop_gust_response(loop2, t, w)
    peak = np.abs(r1["current"]).max()
    assert peak > 0
    np.testing.assert_allclose(r2["current"], 2 * r1["current"], atol=1e-9 * peak)
    assert abs(r1["theta"][-1]) < 1e-3 * np.abs(r1["theta"]).max()
    lags = -fin_ase.velocity / fin_ase.rfa.b_ref * np.asarray(fin_ase.rfa.lag_roots)
    poles = np.sort_complex(np.linalg.eigvals(loop1.A))
    n0 = loop1.A.shape[0] - lags.size
    base = np.sort_complex(np.concatenate([np.linalg.eigvals(loop1.A[:n0, :n0]), lags]))
    np.testing.assert_allclose(poles, base, rtol=1e-6)


def test_refuses_a_state_space_of_another_condition(fin_ase):
    ss = gust_state_space(fin_ase.modal, fin_ase.rfa, _gust_fit(fin_ase), fin_ase.density,
                          1.1 * fin_ase.velocity)
    _, ctl, _ = P.actuator_setup(fin_ase.case)
    with pytest.raises(ValueError, match="gust_ss must be the gust state space"):
        closed_loop_gust(fin_ase.model, ctl, ss)


# --- AEM2 and the power limits ---------------------------------------------------------------
def _loops(fin_ase, scale=1.0):
    from asekit.ase.gust import closed_loop_gust as clg
    ss = gust_state_space(fin_ase.modal, fin_ase.rfa, _gust_fit(fin_ase, scale),
                          fin_ase.density, fin_ase.velocity)
    _, ctl, _ = P.actuator_setup(fin_ase.case)
    return ctl, {t: clg(fin_ase.model, ctl, ss, t) for t in ("AEM1", "AEM2")}


def test_aem2_gust_loop_matches_the_loop_closed_by_hand(fin_ase):
    # Independent route: the loop opened at the voltage, x = (sI - F)^-1 (g V + G_open u_g),
    # closed in the frequency domain by the PD on the fin-root pitch theta_fb = D_r0 theta +
    # C_r z: V = -K_c (K_P + K_D s) theta_fb (its rate is s theta_fb, which carries the gust's
    # terms of z' without any algebra). The state-space loop must give the same current per
    # unit gust; without the gust feed-through k_gust (the AEM1 form of the rate) it does not.
    from asekit.ase.gust import closed_loop_gust_frequency_response
    from asekit.ase.loop import _loop_matrices
    ctl, loops = _loops(fin_ase)
    # (an algebraic identity: it holds whether or not this loop is stable; at M 0.5, sea level
    # the fin's AEM2 loop has a growing pole, so no time response is run on it here)
    lp = loops["AEM2"]
    assert not np.any(loops["AEM1"].k_gust)
    fb = np.zeros(lp.F.shape[0])
    fb[:len(_loop_matrices(fin_ase.model, ctl, 0.0, "AEM2")["fb_row"])] = \
        _loop_matrices(fin_ase.model, ctl, 0.0, "AEM2")["fb_row"]
    n = lp.F.shape[0]
    w = np.array([5.0, 200.0, 900.0, 3000.0])
    got = closed_loop_gust_frequency_response(lp, w)["current"]
    for wi, gi in zip(w, got):
        s = 1j * wi
        R = np.linalg.inv(s * np.eye(n) - lp.F)
        u = np.array([1.0, s, s * s])
        pd = -ctl.gain * (ctl.kp + ctl.kd * s)
        # theta_fb = fb R (g V + G u), V = pd theta_fb  ->  V = pd fb R G u / (1 - pd fb R g)
        V = pd * (fb @ R @ lp.G_open @ u) / (1 - pd * (fb @ R @ lp.g))
        x = R @ (lp.g * V + lp.G_open @ u)
        assert gi == pytest.approx(x[2], rel=1e-8)
    # the unforced loop is the AEM2 loop of asekit.ase.loop (plus the gust lags)
    base = _loop_matrices(fin_ase.model, ctl, 0.0, "AEM2")
    n0 = base["F"].shape[0]
    np.testing.assert_allclose(lp.A[:n0, :n0], base["F"] + np.outer(base["g"], base["k"]),
                               rtol=1e-12, atol=1e-12 * np.abs(lp.A).max())


@pytest.mark.parametrize("topology", ["AEM1"])
def test_far_limits_give_the_linear_response(fin_ase, topology, monkeypatch):
    # with a 1 kV supply and a 1 kA current limit no limit binds: the exact piecewise-affine
    # propagation must reproduce lsim's first-order-hold response (a different integrator).
    # NEAR_LIMIT = 2 makes every sample "near a limit", so the exact propagation runs from
    # t = 0 instead of the shortcut that keeps the linear states.
    import asekit.ase.gust as ag
    from asekit.ase.gust import limited_gust_response
    monkeypatch.setattr(ag, "NEAR_LIMIT", 2.0)
    from asekit.servo.simulate import PowerLimits
    _, loops = _loops(fin_ase)
    lp = loops[topology]
    t = np.linspace(0.0, 0.1, 801)
    w = one_minus_cosine(t, fin_ase.velocity, 2.0, 10.0)
    lin = closed_loop_gust_response(lp, t, w)
    act = fin_ase.model.actuator
    lim = limited_gust_response(lp, act, PowerLimits(1000.0, 1000.0), t, w)
    peak = np.abs(lin["current"]).max()
    assert not lim["saturated"] and peak > 0
    np.testing.assert_allclose(lim["current"], lin["current"], atol=1e-7 * peak)
    np.testing.assert_allclose(lim["voltage"], lin["voltage"],
                               atol=1e-7 * np.abs(lin["voltage"]).max())


def test_tight_limits_bound_the_voltage_and_the_current(fin_ase):
    # a current limit at half the linear loop's peak current: with the thesis's voltage clip
    # (|V| <= I_lim R, Eqs. 4.14-4.15) the applied voltage never exceeds I_lim R; with the
    # current regulator (time constant 1e-5 s) the current stays within the limit
    from asekit.ase.gust import limited_gust_response
    from asekit.servo.simulate import PowerLimits
    _, loops = _loops(fin_ase)
    lp = loops["AEM1"]
    t = np.linspace(0.0, 0.1, 801)
    w = one_minus_cosine(t, fin_ase.velocity, 2.0, 10.0)
    lin = closed_loop_gust_response(lp, t, w)
    i_lim = 0.5 * np.abs(lin["current"]).max()
    act = fin_ase.model.actuator
    r = act.motor.resistance
    clip = limited_gust_response(lp, act, PowerLimits(24.0, i_lim), t, w)
    assert clip["saturated"]
    assert np.abs(clip["voltage"]).max() <= min(i_lim * r, 24.0) * (1 + 1e-12)
    reg = limited_gust_response(lp, act, PowerLimits(1000.0, i_lim, "regulator", 1e-5), t, w)
    assert reg["saturated"]
    assert np.abs(reg["current"]).max() <= 1.01 * i_lim
    assert np.abs(reg["current"]).max() >= 0.99 * i_lim      # it does reach the limit
