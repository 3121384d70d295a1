"""Gust input of the aeroelastic state space and 1-cos gust responses (asekit.aeroelastic.gust):
the state space against the frequency-domain equation it realises, and a plunging typical
section in a 1-cos gust against an independent frequency-domain solution with the exact
Theodorsen and Sears functions."""

import numpy as np
import pytest
from scipy.special import hankel2, j0, j1

from asekit.aeroelastic.gust import (
    gust_response,
    gust_state_space,
    load_histories,
    one_minus_cosine,
)
from asekit.aeroelastic.statespace import ModalArrays
from asekit.rfa.gust import gust_fit
from asekit.rfa.roger import roger_fit


def theodorsen(k):
    return hankel2(1, k) / (hankel2(1, k) + 1j * hankel2(0, k))


def sears_le(k):
    """Sears's function with the gust referred to the leading edge: S(k) e^{-ik}, S(k) =
    [J0 - i J1] C + i J1 (Sears 1941; Bisplinghoff, Ashley & Halfman 1955, Eq. 5-338)."""
    return ((j0(k) - 1j * j1(k)) * theodorsen(k) + 1j * j1(k)) * np.exp(-1j * k)


def _random_model(seed=3):
    rng = np.random.default_rng(seed)
    n = 3
    a = rng.normal(size=(n, n))
    M = a @ a.T + 3 * np.eye(n)
    K = np.diag([0.0, 400.0, 2500.0]) + 0.0
    C = np.diag([0.0, 0.5, 1.0])
    k = np.linspace(0.0, 1.5, 12)
    Q = rng.normal(size=(1, n, n)) + (1j * k[:, None, None]) * rng.normal(size=(1, n, n)) \
        + (1j * k[:, None, None]) ** 2 * 0.01 * rng.normal(size=(1, n, n))
    Qg = rng.normal(size=(1, n)) * (1 - 0.5j * k[:, None] / (1j * k[:, None] + 0.3))
    return ModalArrays(M, K, C, 1), k, Q, Qg


def test_state_space_realises_the_frequency_domain_equation():
    # The elastic response and hinge moment to a harmonic gust w_g e^{i omega t} from the state
    # space equal the solution of (-omega^2 M + i omega C + K - q Q~(k)) zeta = q Q~g(k) w/U
    # with zeta_c = 0 (actuator clamped), and T_hinge = row c of (q Q~ + omega^2 M - i omega C
    # - K) zeta + q Q~g,c w/U (Eqs. 2.44, 2.68-2.70), both fits evaluated at k = omega b/U.
    modal, k, Q, Qg = _random_model()
    b, rho, U = 0.3, 1.1, 40.0
    rfa = roger_fit(k, Q, b, n_lags=2)
    gfit = gust_fit(k, Qg, b, lag_roots=rfa.lag_roots)
    ss = gust_state_space(modal, rfa, gfit, rho, U)
    q = 0.5 * rho * U ** 2
    for omega in (3.0, 30.0, 90.0):
        kk = omega * b / U
        Qk, Qgk = rfa.evaluate(kk), gfit.evaluate(kk)
        Z = -omega ** 2 * modal.M + 1j * omega * modal.C + modal.K - q * Qk
        zeta_s = np.linalg.solve(Z[1:, 1:], q * Qgk[1:] / U)
        hinge = (-Z[0, 1:] @ zeta_s) + q * Qgk[0] / U
        u = np.array([1.0, 1j * omega, -omega ** 2])
        x = np.linalg.solve(1j * omega * np.eye(ss.n_states) - ss.A, ss.B_g @ u)
        assert np.allclose(x[:2], zeta_s, rtol=1e-9, atol=1e-12 * np.abs(zeta_s).max())
        got_h = ss.C_hinge @ x + ss.Dg_hinge @ u
        assert got_h[0] == pytest.approx(hinge, rel=1e-9)


def _plunge_section():
    # per unit span: semi-chord b = 0.5 m, mass 50 kg/m, plunge frequency 3 Hz, no damping;
    # sea level, U = 50 m/s (mass ratio m / (pi rho b^2) = 52)
    b, m, f = 0.5, 50.0, 3.0
    return b, ModalArrays(np.array([[m]]), np.array([[m * (2 * np.pi * f) ** 2]]),
                          np.zeros((1, 1)), 0)


def test_plunging_section_in_a_one_minus_cosine_gust():
    # Plunge h (up) of a 2-D section: Q_hh(k) = 2 (pi k^2 - 2 pi i k C(k)) per unit span and q
    # (Theodorsen, NACA Rep. 496, 1935), gust column (front at the leading edge) Q_hg(k) =
    # 4 pi b S(k) e^{-ik} (Sears 1941). asekit: Roger fits of both (4 lags on k <= 2), the gust
    # state space, lsim. Independent reference: the same equation solved in the frequency
    # domain with the exact C(k) and S(k), h(omega) = q Q_hg W(omega)/U / (K - omega^2 m -
    # q Q_hh), inverse FFT (window 10 s; the response has decayed to 3e-5 of its peak at its
    # end). 1-cos gust, H = 10 m, U_ds = 5 m/s. Measured: peak 68.8 mm, asekit's 0.67 % above,
    # history within 1.7 % of the peak (the gust fit's error is 2.0 %, the modal fit's 0.07 %).
    b, modal = _plunge_section()
    rho, U, H, wds = 1.225, 50.0, 10.0, 5.0
    q = 0.5 * rho * U ** 2
    k = np.array([0.0, 0.025, 0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.65, 0.9, 1.25, 1.6, 2.0])
    kk = np.maximum(k, 1e-9)
    Qhh = (2 * (np.pi * kk ** 2 - 2j * np.pi * kk * theodorsen(kk)))[:, None, None]
    Qhh[0] = 0.0
    Qhg = (4 * np.pi * b * sears_le(kk))[:, None]
    rfa = roger_fit(k, Qhh, b, n_lags=4)
    gfit = gust_fit(k, Qhg, b, lag_roots=rfa.lag_roots)
    ss = gust_state_space(modal, rfa, gfit, rho, U)
    dt, T = 2e-3, 10.0
    t = np.arange(0.0, T, dt)
    w = one_minus_cosine(t, U, H, wds)
    h_ss = gust_response(ss, t, w).modal[:, 0]

    om = 2 * np.pi * np.fft.rfftfreq(t.size, dt)
    Wf = np.fft.rfft(w[0]) * dt
    kf = np.maximum(om * b / U, 1e-12)
    qhh = 2 * (np.pi * kf ** 2 - 2j * np.pi * kf * theodorsen(kf))
    qhg = 4 * np.pi * b * sears_le(kf)
    hf = q * qhg * Wf / U / (modal.K[0, 0] - om ** 2 * modal.M[0, 0] - q * qhh)
    hf[0] = q * 4 * np.pi * b * Wf[0] / U / modal.K[0, 0]
    h_ref = np.fft.irfft(hf, t.size) / dt
    peak = np.abs(h_ref).max()
    assert np.abs(h_ss).max() == pytest.approx(peak, rel=0.03)
    assert np.abs(h_ss - h_ref).max() < 0.03 * peak
    assert h_ss[np.argmax(np.abs(h_ss))] > 0                 # an upward gust lifts the section

    # force summation: the root shear = aerodynamic lift (its own Roger fit of the lift row
    # and the gust lift, same lags) + inertia -m h''; for this one-mode section it must equal
    # the spring force K h of the reference (equilibrium), within the same 3 % of the peak
    # (measured: within 1.7 % of the peak, peak +0.67 %, as the displacement)
    load_fit = gust_fit(k, np.hstack([Qhh[:, 0, :], Qhg]), b, lag_roots=rfa.lag_roots)
    shear = load_histories(gust_response(ss, t, w), load_fit, -modal.M)[:, 0]
    ref = modal.K[0, 0] * h_ref
    assert np.abs(shear - ref).max() < 0.03 * np.abs(ref).max()


def test_one_minus_cosine_profile_and_errors():
    t = np.linspace(0.0, 1.0, 1001)
    w = one_minus_cosine(t, 20.0, 5.0, 3.0, delay=0.1)
    assert w[0].max() == pytest.approx(3.0, rel=1e-5)
    assert t[np.argmax(w[0])] == pytest.approx(0.1 + 5.0 / 20.0, abs=1e-3)
    np.testing.assert_allclose(np.gradient(w[0], t)[200:300], w[1][200:300], rtol=1e-3,
                               atol=1e-3)
    assert np.all(w[:, t > 0.1 + 0.5 + 1e-9] == 0)
    with pytest.raises(ValueError, match="gradient_length"):
        one_minus_cosine(t, 20.0, 0.0, 3.0)
    b, modal = _plunge_section()
    k = np.linspace(0, 1, 6)
    rfa = roger_fit(k, np.ones((6, 1, 1)) + 0j, b, n_lags=1)
    with pytest.raises(ValueError, match="same reference semi-chord"):
        gust_state_space(modal, rfa, gust_fit(k, np.ones(6), 2 * b, n_lags=1), 1.0, 10.0)
    ss = gust_state_space(modal, rfa, gust_fit(k, np.ones(6), b, n_lags=1), 1.0, 10.0)
    with pytest.raises(ValueError, match="gust must be"):
        gust_response(ss, t, np.zeros((2, t.size)))


@pytest.mark.parametrize("spectrum", ["von_karman", "dryden"])
def test_turbulence_psd_integrates_to_the_variance(spectrum):
    # int_0^inf Phi d omega = sigma^2 (Hoblit 1988, Eqs. 2.7-2.8): von Karman's a = 1.339 is
    # the constant that makes it so (to the 4 digits of a)
    from scipy.integrate import quad

    from asekit.aeroelastic.gust import turbulence_psd
    U, L, s = 120.0, 762.0, 3.0
    x = quad(lambda w: float(turbulence_psd(w, U, L, s, spectrum)), 0, np.inf, limit=500)[0]
    assert x == pytest.approx(s ** 2, rel=1e-4)
    with pytest.raises(ValueError, match="spectrum must be"):
        turbulence_psd([1.0], U, L, s, "kaimal")


def test_plunging_section_in_von_karman_turbulence():
    # A-bar and N0 of the plunge of the section of test_plunging_section_in_a_one_minus_cosine
    # _gust in von Karman turbulence (L = 762 m), from asekit's gust state space (Roger fits)
    # against the exact frequency response with Theodorsen's C(k) and Sears's S(k), both
    # integrated over the same grid up to k = 2 (the fits' range). Measured: A-bar 0.01076 s
    # (m per m/s) against 0.01103 (-2.4 %: the gust fit's 2 % error at low k, where the von
    # Karman spectrum is largest), N0 0.776 Hz against 0.757 Hz (+2.4 %).
    from asekit.aeroelastic.gust import (
        gust_frequency_response,
        spectral_statistics,
        turbulence_psd,
    )
    b, modal = _plunge_section()
    rho, U = 1.225, 50.0
    q = 0.5 * rho * U ** 2
    k = np.array([0.0, 0.025, 0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.65, 0.9, 1.25, 1.6, 2.0])
    kk = np.maximum(k, 1e-9)
    Qhh = (2 * (np.pi * kk ** 2 - 2j * np.pi * kk * theodorsen(kk)))[:, None, None]
    Qhh[0] = 0.0
    rfa = roger_fit(k, Qhh, b, n_lags=4)
    gfit = gust_fit(k, (4 * np.pi * b * sears_le(kk))[:, None], b, lag_roots=rfa.lag_roots)
    ss = gust_state_space(modal, rfa, gfit, rho, U)
    w = np.linspace(1e-4, 2.0 * U / b, 4001)
    psd = turbulence_psd(w, U, 762.0, 1.0)
    got = spectral_statistics(w, gust_frequency_response(ss, w)["modal"][:, 0], psd)
    kw = w * b / U
    exact = q * 4 * np.pi * b * sears_le(kw) / U / (
        modal.K[0, 0] - w ** 2 * modal.M[0, 0] - q * 2 * (np.pi * kw ** 2
                                                         - 2j * np.pi * kw * theodorsen(kw)))
    ref = spectral_statistics(w, exact, psd)
    assert got["A_bar"] == pytest.approx(ref["A_bar"], rel=0.03)
    assert got["N0_per_s"] == pytest.approx(ref["N0_per_s"], rel=0.03)
    assert 0.3 < ref["N0_per_s"] < 3.0          # below the 3 Hz plunge: low-frequency gusts


def test_dryden_realisation_has_the_dryden_spectrum():
    # the shaping filter's output (seed 3, 20000 tau long) has the variance sigma^2 (standard
    # error of the estimate about 1 % for this length) and, by Welch's method averaged over
    # bands around the knee U / L, the Dryden PSD (MIL-F-8785C; Hoblit 1988). Measured:
    # variance +0.3 %, band means -3.8 % (0.2-0.4 rad/s), -3.9 % (0.8-1.2), +1.1 % (2.5-3.5);
    # single Welch bins scatter by about 9 % (120 segments), hence the band means.
    from scipy.signal import welch

    from asekit.aeroelastic.gust import dryden_realisation, turbulence_psd
    U, L, sigma, dt = 100.0, 100.0, 2.0, 0.01
    t = np.arange(0.0, 20000.0, dt)
    w = dryden_realisation(t, U, L, sigma, seed=3)[0]
    assert np.var(w) == pytest.approx(sigma ** 2, rel=0.05)
    f, p = welch(w, fs=1 / dt, nperseg=2 ** 14)
    omega, psd = 2 * np.pi * f, p / (2 * np.pi)              # one-sided per rad/s
    for lo, hi in ((0.2, 0.4), (0.8, 1.2), (2.5, 3.5)):
        band = (omega >= lo) & (omega <= hi)
        ratio = np.mean(psd[band] / turbulence_psd(omega[band], U, L, sigma, "dryden"))
        assert ratio == pytest.approx(1.0, abs=0.1), (lo, hi, ratio)
    assert np.array_equal(w, dryden_realisation(t, U, L, sigma, seed=3)[0])     # seeded
