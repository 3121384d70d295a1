"""The gust in the closed AEM1 loop (asekit.ase.gust)."""

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
